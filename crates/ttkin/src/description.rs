//! The ttmanip robot file: a small TOML description of a serial chain (DH rows or URDF-style
//! origins, limits, inertias), read with serde.
//!
//! ```toml
//! name = "planar2"
//! convention = "standard"              # DH convention of the rows: "standard" or "modified"
//! units = { length = "mm", angle = "deg" }   # of DH rows, origins and position/speed limits
//! tool = { xyz = [0, 0, 50], rpy = [0, 0, 0] }
//! racket = { xyz = [0, 0, 150], rpy = [0, -90, 180] }   # racket frame in the tool frame (default: the tool frame)
//! ready = [0]                           # rest configuration, one value per joint (default: mid range)
//!
//! [[joint]]
//! name = "shoulder"
//! type = "revolute"                     # or "prismatic"
//! dh = { a = 300, alpha = 0, d = 0, theta = 0 }   # theta (revolute) or d (prismatic) is the offset at q = 0
//! limits = { lower = -170, upper = 170, velocity = 180 }
//! inertial = { mass = 1.2, com = [-0.15, 0, 0], inertia = [1e-3, 9e-3, 9e-3, 0, 0, 0] }  # always SI
//! ```
//! A joint may also carry its drive (SI units; see [`crate::joint::Drive`]):
//! `drive = { gear_ratio = 100, rotor_inertia = 1.2e-6, viscous = 0.05, coulomb = 0.2, torque_constant = 0.025 }`,
//! optionally with the motor's datasheet values (`resistance`, `inductance`, `nominal_current`,
//! `peak_current`, `max_motor_speed`, the five thermal values, `gear_efficiency`, `encoder_counts`,
//! `bus_voltage`; see `robots/gantry6.toml`).
//! A joint may give `origin = { xyz = [...], rpy = [...] }` and `axis = [x, y, z]` instead of `dh`.
//! Inertias are always SI: kg, m, kg·m² (ixx, iyy, izz, ixy, ixz, iyz) about the centre of mass
//! in link-frame axes. Unknown keys are errors, so a typo never passes silently.

use std::path::Path;

use nalgebra::{IsometryMatrix3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::inertial::Inertial;
use crate::joint::{Dh, DhConvention, Drive, Geometry, Joint, JointType, Limits};
use crate::transform::{from_xyz_rpy, to_xyz_rpy};

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    convention: Option<DhConvention>,
    #[serde(default)]
    units: Units,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    base: Option<PoseEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tool: Option<PoseEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    racket: Option<PoseEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ready: Option<Vec<f64>>,
    /// Gravity in the base frame (m/s², never scaled by `units`); (0, 0, −9.81) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gravity: Option<[f64; 3]>,
    joint: Vec<JointEntry>,
}

#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Units {
    #[serde(default)]
    length: LengthUnit,
    #[serde(default)]
    angle: AngleUnit,
}

#[derive(Debug, Default, Clone, Copy, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum LengthUnit {
    #[default]
    M,
    Mm,
}

#[derive(Debug, Default, Clone, Copy, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum AngleUnit {
    #[default]
    Rad,
    Deg,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseEntry {
    #[serde(default)]
    xyz: [f64; 3],
    #[serde(default)]
    rpy: [f64; 3],
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct DhEntry {
    #[serde(default)]
    a: f64,
    #[serde(default)]
    alpha: f64,
    #[serde(default)]
    d: f64,
    #[serde(default)]
    theta: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct InertialEntry {
    mass: f64,
    com: [f64; 3],
    inertia: [f64; 6],
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct JointEntry {
    name: String,
    #[serde(rename = "type")]
    kind: JointType,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    convention: Option<DhConvention>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dh: Option<DhEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    origin: Option<PoseEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    axis: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    limits: Option<Limits>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inertial: Option<InertialEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    drive: Option<Drive>,
}

impl Units {
    fn len(&self) -> f64 {
        match self.length {
            LengthUnit::M => 1.0,
            LengthUnit::Mm => 1e-3,
        }
    }
    fn ang(&self) -> f64 {
        match self.angle {
            AngleUnit::Rad => 1.0,
            AngleUnit::Deg => std::f64::consts::PI / 180.0,
        }
    }
    fn pose(&self, p: &PoseEntry) -> IsometryMatrix3<f64> {
        let (l, a) = (self.len(), self.ang());
        from_xyz_rpy(p.xyz.map(|v| v * l), p.rpy.map(|v| v * a))
    }
}

/// Reads a robot file from disk.
pub fn load(path: impl AsRef<Path>) -> Result<Chain> {
    let path = path.as_ref();
    let text = crate::budget::read_text(path)?;
    from_toml_str(&text, &path.display().to_string())
}

/// Parses a robot file from TOML text; `origin` names the text in error messages.
pub fn from_toml_str(text: &str, origin: &str) -> Result<Chain> {
    let file_err = |reason: String| Error::File {
        path: origin.to_string(),
        reason,
    };
    if text.len() as u64 > crate::budget::MAX_FILE_BYTES {
        return Err(file_err(format!(
            "{} bytes, more than the {} bytes (16 MiB) a robot file may be",
            text.len(),
            crate::budget::MAX_FILE_BYTES
        )));
    }
    let f: RobotFile = toml::from_str(text).map_err(|e| file_err(e.to_string()))?;
    let u = &f.units;
    let mut joints = Vec::with_capacity(f.joint.len());
    for e in &f.joint {
        let geometry = match (&e.dh, &e.origin) {
            (Some(dh), None) => {
                if e.axis.is_some() {
                    return Err(file_err(format!(
                        "joint '{}': 'axis' goes with 'origin', not with 'dh'",
                        e.name
                    )));
                }
                let conv = e.convention.or(f.convention).ok_or_else(|| {
                    file_err(format!(
                        "joint '{}': DH convention unknown; set convention = \"standard\" or \"modified\" at the top or on the joint",
                        e.name
                    ))
                })?;
                Geometry::Dh(
                    conv,
                    Dh {
                        a: dh.a * u.len(),
                        alpha: dh.alpha * u.ang(),
                        d: dh.d * u.len(),
                        theta: dh.theta * u.ang(),
                    },
                )
            }
            (None, Some(o)) => {
                let axis = Vector3::from(e.axis.unwrap_or([0.0, 0.0, 1.0]));
                if !(axis.norm() > 1e-12) {
                    return Err(file_err(format!("joint '{}': axis must be a non-zero vector", e.name)));
                }
                Geometry::Origin {
                    origin: u.pose(o),
                    axis: Unit::new_normalize(axis),
                }
            }
            _ => {
                return Err(file_err(format!(
                    "joint '{}': give exactly one of 'dh' or 'origin'",
                    e.name
                )))
            }
        };
        let mut j = Joint::new(e.name.clone(), e.kind, geometry)?;
        if let Some(l) = e.limits {
            let s = match e.kind {
                JointType::Revolute => u.ang(),
                JointType::Prismatic => u.len(),
            };
            j = j.with_limits(Limits {
                lower: l.lower * s,
                upper: l.upper * s,
                velocity: l.velocity.map(|v| v * s),
                acceleration: l.acceleration.map(|v| v * s),
                effort: l.effort,
            })?;
        }
        if let Some(i) = &e.inertial {
            j = j.with_inertial(Inertial::new(i.mass, i.com, i.inertia))?;
        }
        if let Some(d) = e.drive {
            j = j.with_drive(d)?;
        }
        joints.push(j);
    }
    let id = IsometryMatrix3::identity();
    let base = f.base.as_ref().map_or(id, |p| u.pose(p));
    let tool = f.tool.as_ref().map_or(id, |p| u.pose(p));
    let mut chain = Chain::new(f.name, joints, base, tool)?;
    if let Some(r) = &f.racket {
        chain = chain.with_racket(u.pose(r))?;
    }
    if let Some(q) = &f.ready {
        if q.len() != chain.dof() {
            return Err(file_err(format!(
                "ready: expected {} values (one per joint), got {}",
                chain.dof(),
                q.len()
            )));
        }
        let si: Vec<f64> = q
            .iter()
            .zip(chain.joints())
            .map(|(v, j)| match j.kind() {
                JointType::Revolute => v * u.ang(),
                JointType::Prismatic => v * u.len(),
            })
            .collect();
        chain = chain.with_ready(&si).map_err(|e| file_err(format!("ready: {e}")))?;
    }
    if let Some(g) = f.gravity {
        chain = chain.with_gravity(g).map_err(|e| file_err(format!("gravity: {e}")))?;
    }
    Ok(chain)
}

fn pose_entry(t: &IsometryMatrix3<f64>) -> Option<PoseEntry> {
    if *t == IsometryMatrix3::identity() {
        return None;
    }
    let (xyz, rpy) = to_xyz_rpy(t);
    Some(PoseEntry { xyz, rpy })
}

/// Writes a chain as a robot file (TOML, SI units: m, rad).
pub fn to_toml(chain: &Chain) -> String {
    let joint = chain
        .joints()
        .iter()
        .map(|j| {
            let (convention, dh, origin, axis) = match j.geometry() {
                Geometry::Dh(c, d) => (
                    Some(*c),
                    Some(DhEntry {
                        a: d.a,
                        alpha: d.alpha,
                        d: d.d,
                        theta: d.theta,
                    }),
                    None,
                    None,
                ),
                Geometry::Origin { origin, axis } => {
                    let (xyz, rpy) = to_xyz_rpy(origin);
                    (None, None, Some(PoseEntry { xyz, rpy }), Some([axis.x, axis.y, axis.z]))
                }
            };
            let l = j.limits();
            JointEntry {
                name: j.name().to_string(),
                kind: j.kind(),
                convention,
                dh,
                origin,
                axis,
                limits: (l.lower.is_finite() || l.upper.is_finite() || l.velocity.is_some()).then_some(*l),
                inertial: j.inertial().map(|i| InertialEntry {
                    mass: i.mass,
                    com: i.com.into(),
                    inertia: i.components(),
                }),
                drive: j.drive().copied(),
            }
        })
        .collect();
    let f = RobotFile {
        name: chain.name().to_string(),
        convention: None,
        units: Units::default(),
        base: pose_entry(chain.base()),
        tool: pose_entry(chain.tool()),
        racket: pose_entry(chain.racket()),
        ready: chain.has_ready().then(|| chain.ready()),
        gravity: (chain.gravity() != crate::dynamics::EARTH_GRAVITY).then(|| chain.gravity()),
        joint,
    };
    toml::to_string(&f).expect("a robot file of finite values always serialises")
}
