//! URDF import of a serial chain between two links, and URDF export of any chain, through the
//! `urdf-rs` crate.
//!
//! Export writes one URDF link per DH frame (`link1` … `linkN`), so frame i of a tool that loads
//! the file is exactly our link frame i: `base_link` —(fixed: base)→ `link0` —(joint 1)→ `link1` …
//! `linkN` —(fixed: tool)→ `tool`. URDF 1.0 carries no acceleration limits, so they are not exported. A standard-DH joint moves before its fixed part, so it gets an
//! extra `<joint name>_axis` link between the moving joint and a fixed joint to its DH frame.
//!
//! A joint's drive travels as `<dynamics damping="viscous" friction="Coulomb"/>` (joint side);
//! URDF has no field for the gear ratio, rotor inertia or torque constant, so those live only in
//! the robot file (an imported joint with damping or friction gets a unit gear ratio).

use std::collections::HashMap;

use nalgebra::{IsometryMatrix3, Unit, Vector3};

use crate::budget::{MAX_URDF_JOINTS, MAX_XML_DEPTH};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::inertial::Inertial;
use crate::joint::{DhConvention, Drive, Geometry, Joint, JointType, Limits};
use crate::transform::{from_xyz_rpy, to_xyz_rpy};

/// Name of the base link in exported URDF.
pub const BASE_LINK: &str = "base_link";
/// Name of the tool link in exported URDF.
pub const TOOL_LINK: &str = "tool";

/// Reads the serial chain from `base_link` to `tip_link` of a URDF file.
pub fn load(path: impl AsRef<std::path::Path>, base_link: &str, tip_link: &str) -> Result<Chain> {
    let text = crate::budget::read_text(path.as_ref())?;
    from_urdf_str(&text, base_link, tip_link)
}

fn pose(p: &urdf_rs::Pose) -> IsometryMatrix3<f64> {
    from_xyz_rpy(p.xyz.0, p.rpy.0)
}

/// The link's inertia in its frame; None for a massless link (URDF's default: mass 0). A
/// negative or non-finite mass or a non-physical inertia is refused, as the robot-file reader
/// refuses it.
fn link_inertial(link: &urdf_rs::Link) -> Result<Option<Inertial>> {
    let i = &link.inertial;
    let t = &i.inertia;
    let values = [i.mass.value, t.ixx, t.iyy, t.izz, t.ixy, t.ixz, t.iyz];
    if i.mass.value == 0.0 && values.iter().all(|v| v.is_finite()) {
        // A massless link (URDF's default, and common for frames such as `world` or `tool`).
        return Ok(None);
    }
    let local = Inertial::new(i.mass.value, [0.0; 3], [t.ixx, t.iyy, t.izz, t.ixy, t.ixz, t.iyz]);
    local.validate(&link.name).map_err(|e| Error::Urdf(e.to_string()))?;
    let origin = pose(&i.origin);
    check_pose(&format!("inertial origin of link '{}'", link.name), &origin)?;
    Ok(Some(local.transformed(&origin)))
}

/// Checks that a pose read from the URDF is finite (xyz and rpy).
fn check_pose(what: &str, t: &IsometryMatrix3<f64>) -> Result<()> {
    let v = t.translation.vector;
    crate::error::check_finite(what, &[v.x, v.y, v.z]).map_err(|e| Error::Urdf(e.to_string()))?;
    crate::error::check_finite(what, t.rotation.matrix().as_slice()).map_err(|e| Error::Urdf(e.to_string()))
}

/// Checks the XML's element nesting before it is parsed: at most [`MAX_XML_DEPTH`] levels (the
/// parser recurses once a level, and a document nested thousands deep would overflow the stack).
/// Comments, CDATA, declarations and quoted attribute values are skipped.
fn check_xml_depth(text: &str) -> Result<()> {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    let (mut i, mut depth) = (0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") || rest.starts_with(b"</") {
            depth = depth.saturating_sub(usize::from(rest.starts_with(b"</")));
            i = skip_to(i + 2, b">");
        } else {
            // An opening tag: to its '>' outside quotes; "/>" closes it at once.
            let mut j = i + 1;
            let mut quote = None;
            while j < b.len() {
                match (quote, b[j]) {
                    (None, q @ (b'"' | b'\'')) => quote = Some(q),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if !(j > 0 && j < b.len() && b[j - 1] == b'/') {
                depth += 1;
                if depth > MAX_XML_DEPTH {
                    return Err(Error::Urdf(format!(
                        "elements nested more than {MAX_XML_DEPTH} deep (a URDF is 4 deep): not a robot description"
                    )));
                }
            }
            i = j + 1;
        }
    }
    Ok(())
}

fn add_body(acc: &mut Option<Inertial>, body: Option<Inertial>) {
    if let Some(b) = body {
        *acc = Some(match acc {
            Some(a) => a.combine(&b),
            None => b,
        });
    }
}

/// Each link's parent joint, after checking that the joints make the links a tree (URDF's rule):
/// every joint joins two declared links, no link has two parent joints, and no chain of joints
/// comes back to where it started (a loop such as a → b and b → a).
fn parent_joints<'a>(
    robot: &'a urdf_rs::Robot,
    links: &HashMap<&str, &urdf_rs::Link>,
) -> Result<HashMap<&'a str, &'a urdf_rs::Joint>> {
    let mut by_child: HashMap<&str, &urdf_rs::Joint> = HashMap::new();
    let mut names = std::collections::HashSet::new();
    for j in &robot.joints {
        if !names.insert(j.name.as_str()) {
            return Err(Error::Urdf(format!(
                "two joints are named '{}': joint names must be unique",
                j.name
            )));
        }
        for end in [&j.parent.link, &j.child.link] {
            if !links.contains_key(end.as_str()) {
                return Err(Error::Urdf(format!(
                    "joint '{}' refers to an undeclared link '{end}'",
                    j.name
                )));
            }
        }
        if let Some(other) = by_child.insert(j.child.link.as_str(), j) {
            return Err(Error::Urdf(format!(
                "link '{}' has two parent joints, '{}' and '{}': a URDF's links must form a tree",
                j.child.link, other.name, j.name
            )));
        }
    }
    // With one parent per link, walking up from any link either ends at a root or repeats a link:
    // a loop. Each link is walked once (linear time): a walk stops at a link an earlier walk
    // already proved to lead to a root.
    let mut rooted: std::collections::HashSet<&str> = std::collections::HashSet::new();
    let mut starts: Vec<&str> = by_child.keys().copied().collect();
    starts.sort_unstable();
    for start in starts {
        let mut link = start;
        let mut walk = vec![link];
        let mut on_walk: std::collections::HashSet<&str> = std::collections::HashSet::from([link]);
        while let Some(j) = by_child.get(link) {
            if rooted.contains(link) {
                break;
            }
            link = j.parent.link.as_str();
            walk.push(link);
            if !on_walk.insert(link) {
                let first = walk.iter().position(|&l| l == link).unwrap_or(0);
                return Err(Error::Urdf(format!(
                    "joints form a loop ({}): a URDF's links must form a tree",
                    walk[first..].iter().rev().copied().collect::<Vec<_>>().join(" → ")
                )));
            }
        }
        rooted.extend(walk);
    }
    Ok(by_child)
}

/// Parses URDF text and extracts the serial chain from `base_link` to `tip_link`.
///
/// Fixed joints on the path are folded into the next moving joint's origin (or into the tool
/// transform after the last one); the inertias of links fixed to a moving link are lumped into it.
/// Links that hang off the path are ignored. Continuous joints become unbounded revolute joints.
pub fn from_urdf_str(text: &str, base_link: &str, tip_link: &str) -> Result<Chain> {
    if text.len() as u64 > crate::budget::MAX_FILE_BYTES {
        return Err(Error::Urdf(format!(
            "{} bytes, more than the {} bytes (16 MiB) a URDF may be",
            text.len(),
            crate::budget::MAX_FILE_BYTES
        )));
    }
    check_xml_depth(text)?;
    let joints_declared = text.matches("<joint").count();
    if joints_declared > MAX_URDF_JOINTS {
        return Err(Error::Urdf(format!(
            "{joints_declared} joints, more than the {MAX_URDF_JOINTS} a URDF may declare"
        )));
    }
    let robot = urdf_rs::read_from_string(text).map_err(|e| Error::Urdf(format!("cannot parse: {e}")))?;
    let mut links: HashMap<&str, &urdf_rs::Link> = HashMap::new();
    for l in &robot.links {
        if links.insert(l.name.as_str(), l).is_some() {
            return Err(Error::Urdf(format!(
                "two links are named '{}': link names must be unique",
                l.name
            )));
        }
    }
    for name in [base_link, tip_link] {
        if !links.contains_key(name) {
            let mut known: Vec<&str> = links.keys().copied().collect();
            known.sort_unstable();
            return Err(Error::Urdf(format!(
                "no link named '{name}'; links are: {}",
                known.join(", ")
            )));
        }
    }
    let by_child = parent_joints(&robot, &links)?;
    // Walk up from the tip to the base (it ends: `parent_joints` proved the links form a tree).
    let mut path = Vec::new();
    let mut link = tip_link;
    while link != base_link {
        match by_child.get(link) {
            Some(j) => {
                path.push(*j);
                link = j.parent.link.as_str();
            }
            None => {
                return Err(Error::Urdf(format!(
                    "links '{base_link}' and '{tip_link}' are not connected: '{tip_link}' does not descend from '{base_link}'"
                )))
            }
        }
    }
    path.reverse();
    let mut joints: Vec<Joint> = Vec::new();
    let mut pending = IsometryMatrix3::identity();
    let mut body: Option<Inertial> = None;
    for uj in path {
        let origin = pose(&uj.origin);
        check_pose(&format!("origin of joint '{}'", uj.name), &origin)?;
        let kind = match uj.joint_type {
            urdf_rs::JointType::Fixed => {
                pending *= origin;
                if !joints.is_empty() {
                    let child = match links.get(uj.child.link.as_str()) {
                        Some(l) => link_inertial(l)?,
                        None => None,
                    };
                    add_body(&mut body, child.map(|i| i.transformed(&pending)));
                }
                continue;
            }
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointType::Revolute,
            urdf_rs::JointType::Prismatic => JointType::Prismatic,
            ref other => {
                return Err(Error::Urdf(format!(
                "joint '{}' is {other:?}: a serial chain holds only revolute, continuous, prismatic and fixed joints",
                uj.name
            )))
            }
        };
        if uj.mimic.is_some() {
            return Err(Error::Urdf(format!(
                "joint '{}' mimics another joint: not a serial chain of independent joints",
                uj.name
            )));
        }
        if let Some(prev) = joints.last_mut() {
            if let Some(b) = body.take() {
                *prev = prev.clone().with_inertial(b)?;
            }
        }
        let axis = Vector3::from(uj.axis.xyz.0);
        if !(axis.norm() > 1e-12) {
            return Err(Error::Urdf(format!("joint '{}' has a zero axis", uj.name)));
        }
        let mut j = Joint::new(
            uj.name.clone(),
            kind,
            Geometry::Origin {
                origin: pending * origin,
                axis: Unit::new_normalize(axis),
            },
        )
        .map_err(|e| Error::Urdf(e.to_string()))?;
        let l = &uj.limit;
        // URDF's <limit> defaults every value to 0; lower = upper = 0 (or a continuous joint)
        // means no position limits, and a rate of 0 means none given. What the robot-file reader
        // refuses is refused here too: lower > upper, a negative or non-finite value.
        let bad = |what: &str, v: f64| {
            Error::Urdf(format!(
                "joint '{}': limit {what} = {v}: must be finite{}",
                uj.name,
                if what == "lower" || what == "upper" {
                    ""
                } else {
                    " and ≥ 0"
                }
            ))
        };
        for (what, v) in [("lower", l.lower), ("upper", l.upper)] {
            if !v.is_finite() {
                return Err(bad(what, v));
            }
        }
        for (what, v) in [("velocity", l.velocity), ("effort", l.effort)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(what, v));
            }
        }
        // urdf-rs reads a missing acceleration as +inf (none).
        if !(l.acceleration >= 0.0) {
            return Err(bad("acceleration", l.acceleration));
        }
        if uj.joint_type != urdf_rs::JointType::Continuous && l.lower > l.upper {
            return Err(Error::Urdf(format!(
                "joint '{}': limit lower = {} is above upper = {}",
                uj.name, l.lower, l.upper
            )));
        }
        let bounded = uj.joint_type != urdf_rs::JointType::Continuous && l.lower < l.upper;
        let positive = |v: f64| (v.is_finite() && v > 0.0).then_some(v);
        j = j
            .with_limits(Limits {
                lower: if bounded { l.lower } else { f64::NEG_INFINITY },
                upper: if bounded { l.upper } else { f64::INFINITY },
                velocity: positive(l.velocity),
                acceleration: positive(l.acceleration),
                effort: positive(l.effort),
            })
            .map_err(|e| Error::Urdf(e.to_string()))?;
        if let Some(d) = &uj.dynamics {
            if d.damping != 0.0 || d.friction != 0.0 {
                // URDF has no gear ratio or rotor inertia: a unit ratio carries the friction alone.
                let drive = Drive {
                    viscous: d.damping,
                    coulomb: d.friction,
                    ..Drive::geared(1.0)
                };
                j = j.with_drive(drive).map_err(|e| Error::Urdf(e.to_string()))?;
            }
        }
        joints.push(j);
        pending = IsometryMatrix3::identity();
        body = match links.get(uj.child.link.as_str()) {
            Some(l) => link_inertial(l)?,
            None => None,
        };
    }
    if joints.is_empty() {
        return Err(Error::Urdf(format!(
            "no revolute or prismatic joint between '{base_link}' and '{tip_link}'"
        )));
    }
    if let (Some(b), Some(last)) = (body, joints.last_mut()) {
        *last = last.clone().with_inertial(b)?;
    }
    Chain::new(robot.name.clone(), joints, IsometryMatrix3::identity(), pending)
}

fn urdf_pose(t: &IsometryMatrix3<f64>) -> urdf_rs::Pose {
    let (xyz, rpy) = to_xyz_rpy(t);
    urdf_rs::Pose {
        xyz: urdf_rs::Vec3(xyz),
        rpy: urdf_rs::Vec3(rpy),
    }
}

fn urdf_link(name: &str, inertial: Option<&Inertial>) -> urdf_rs::Link {
    let inertial = inertial.map_or_else(urdf_rs::Inertial::default, |i| {
        let [ixx, iyy, izz, ixy, ixz, iyz] = i.components();
        urdf_rs::Inertial {
            origin: urdf_rs::Pose {
                xyz: urdf_rs::Vec3(i.com.into()),
                rpy: urdf_rs::Vec3([0.0; 3]),
            },
            mass: urdf_rs::Mass { value: i.mass },
            inertia: urdf_rs::Inertia {
                ixx,
                ixy,
                ixz,
                iyy,
                iyz,
                izz,
            },
        }
    });
    urdf_rs::Link {
        name: name.to_string(),
        inertial,
        visual: vec![],
        collision: vec![],
    }
}

fn fixed_joint(name: &str, parent: &str, child: &str, t: &IsometryMatrix3<f64>) -> urdf_rs::Joint {
    urdf_rs::Joint {
        name: name.to_string(),
        joint_type: urdf_rs::JointType::Fixed,
        origin: urdf_pose(t),
        parent: urdf_rs::LinkName {
            link: parent.to_string(),
        },
        child: urdf_rs::LinkName {
            link: child.to_string(),
        },
        axis: urdf_rs::Axis::default(),
        limit: urdf_rs::JointLimit::default(),
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    }
}

/// Writes any chain as URDF text (see the module doc for the link names).
pub fn to_urdf_string(chain: &Chain) -> String {
    let mut links = vec![urdf_link(BASE_LINK, None), urdf_link("link0", None)];
    let mut joints = vec![fixed_joint("base_joint", BASE_LINK, "link0", chain.base())];
    for (i, j) in chain.joints().iter().enumerate() {
        let parent = format!("link{i}");
        let child = format!("link{}", i + 1);
        let (origin, axis, post) = match j.geometry() {
            Geometry::Origin { origin, axis } => (*origin, axis.into_inner(), None),
            Geometry::Dh(DhConvention::Modified, _) => (*j.pre(), Vector3::z(), None),
            Geometry::Dh(DhConvention::Standard, _) => (*j.pre(), Vector3::z(), Some(*j.post())),
        };
        let moving_child = if post.is_some() {
            format!("{}_axis", j.name())
        } else {
            child.clone()
        };
        let l = j.limits();
        let unbounded = !(l.lower.is_finite() && l.upper.is_finite());
        let joint_type = match (j.kind(), unbounded) {
            (JointType::Revolute, true) => urdf_rs::JointType::Continuous,
            (JointType::Revolute, false) => urdf_rs::JointType::Revolute,
            (JointType::Prismatic, _) => urdf_rs::JointType::Prismatic,
        };
        joints.push(urdf_rs::Joint {
            name: j.name().to_string(),
            joint_type,
            origin: urdf_pose(&origin),
            parent: urdf_rs::LinkName { link: parent },
            child: urdf_rs::LinkName {
                link: moving_child.clone(),
            },
            axis: urdf_rs::Axis {
                xyz: urdf_rs::Vec3(axis.into()),
            },
            limit: urdf_rs::JointLimit {
                lower: l.lower,
                upper: l.upper,
                // URDF requires both attributes; 0 stands for "not given" (read back as no limit).
                effort: l.effort.unwrap_or(0.0),
                velocity: l.velocity.unwrap_or(0.0),
                acceleration: f64::INFINITY,
                deceleration: f64::INFINITY,
                jerk: f64::INFINITY,
            },
            calibration: None,
            dynamics: j.drive().map(|d| urdf_rs::Dynamics {
                damping: d.viscous,
                friction: d.coulomb,
            }),
            mimic: None,
            safety_controller: None,
        });
        if let Some(post) = post {
            links.push(urdf_link(&moving_child, None));
            joints.push(fixed_joint(&format!("{}_dh", j.name()), &moving_child, &child, &post));
        }
        links.push(urdf_link(&child, j.inertial()));
    }
    let n = chain.dof();
    links.push(urdf_link(TOOL_LINK, None));
    joints.push(fixed_joint("tool_joint", &format!("link{n}"), TOOL_LINK, chain.tool()));
    let robot = urdf_rs::Robot {
        name: chain.name().to_string(),
        version: None,
        links,
        joints,
        materials: vec![],
    };
    urdf_rs::write_to_string(&robot).expect("a chain of finite values always serialises as URDF")
}
