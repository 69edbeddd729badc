//! Built-in robots of the seed documents (`../shared/seeds/README.md`) and a UR5 for comparison.
//!
//! Every model is a plain [`Chain`]; the same data is also written out as robot files under
//! `robots/` of the repository and can be exported as URDF.

use std::f64::consts::PI;

use nalgebra::{IsometryMatrix3, Matrix3, Vector3};

use crate::chain::Chain;
use crate::error::Result;
use crate::inertial::Inertial;
use crate::joint::{Dh, DhConvention, Drive, Joint, Limits};

pub mod drives;

const DEG: f64 = PI / 180.0;

fn dh(a: f64, alpha: f64, d: f64, theta: f64) -> Dh {
    Dh { a, alpha, d, theta }
}

fn limits(lower: f64, upper: f64, velocity: f64, acceleration: f64, effort: f64) -> Limits {
    Limits {
        lower,
        upper,
        velocity: Some(velocity),
        acceleration: Some(acceleration),
        effort: Some(effort),
    }
}

/// Lengths of the gantry robot of seed 002 (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GantryLengths {
    /// Offset of joint 3 along its axis.
    pub l1: f64,
    /// Offset of joint 5 along its axis.
    pub l2: f64,
    /// Link length between joints 4 and 5 (a_4 of the modified DH table).
    pub l3: f64,
    /// Offset of joint 6 (racket) along its axis.
    pub l4: f64,
}

impl Default for GantryLengths {
    /// The documented defaults 0.10, 0.05, 0.30, 0.15 m (the patent gives no lengths).
    fn default() -> Self {
        GantryLengths {
            l1: 0.10,
            l2: 0.05,
            l3: 0.30,
            l4: 0.15,
        }
    }
}

/// Seed 000, Table 1, read literally: a mobile table-tennis manipulator, modified (Craig) DH,
/// θ_i = offset_i + q_i, lengths mm → m. Joint 1 is prismatic (the base rolling back and forth on
/// fixed wheels, θ1 = 90° fixed); joints 2–8 are revolute with offsets 0°, 180°, 180°, 90°, 180°,
/// 180°, 90°.
///
/// The seed gives no joint limits. Ours are centred near the seed's start configuration
/// q = [0.26 m, 200°, 90°, 80°, 250°, 105°, 180°, 135°] with a range of 170°–180° per revolute joint
/// (narrow enough that limit avoidance matters, as in the seed's experiment) and 0–0.8 m of base
/// travel. Speeds: 0.5 m/s for the base, 3 rad/s for the arm, typical of small geared DC motors.
/// Joint 5's range is 145°–325° (first chosen as 160°–340°, shifted by −15° for the seed000
/// experiment): the unweighted pseudo-inverse then drives joint 5 past its upper limit on the
/// experiment's motion while the Chan–Dubey weighted solution stays inside, which is the contrast
/// the seed's experiment is about.
/// The printed ⁰T₈ of the seed cannot be reproduced from Table 1 (see the seeds README): this is
/// Table 1, not the paper's matrix.
///
/// Inertias and drives are documented estimates (the seed gives none): a 12 kg wheeled base,
/// aluminium-tube arm links with lumped motors and a 0.18 kg racket centred 0.15 m along z8.
pub fn mobile8() -> Chain {
    let m = DhConvention::Modified;
    // (alpha_{i-1} deg, a_{i-1} mm, d_i mm, theta_i deg)
    let rows = [
        (0.0, 0.0, 0.0, 90.0),
        (90.0, 0.0, 68.0, 0.0),
        (90.0, 0.0, 5.0, 180.0),
        (90.0, 0.0, 156.0, 180.0),
        (90.0, 0.0, 325.0, 90.0),
        (90.0, 0.0, -5.0, 180.0),
        (0.0, 1.2, 0.0, 180.0),
        (90.0, 0.0, 0.0, 90.0),
    ];
    // (lower, upper) in deg for joints 2..8
    let lim_deg = [
        (110.0, 290.0),
        (0.0, 180.0),
        (-10.0, 170.0),
        (145.0, 325.0),
        (15.0, 195.0),
        (90.0, 270.0),
        (45.0, 225.0),
    ];
    let mut joints = Vec::with_capacity(8);
    for (i, &(alpha, a, d, theta)) in rows.iter().enumerate() {
        let row = dh(a * 1e-3, alpha * DEG, d * 1e-3, theta * DEG);
        let name = format!("j{}", i + 1);
        let j = if i == 0 {
            Joint::prismatic(name, m, row).and_then(|j| j.with_limits(limits(0.0, 0.8, 0.5, 1.0, 200.0)))
        } else {
            let (lo, hi) = lim_deg[i - 1];
            Joint::revolute(name, m, row).and_then(|j| j.with_limits(limits(lo * DEG, hi * DEG, 3.0, 15.0, 20.0)))
        };
        joints.push(j.expect("built-in mobile8 joint is valid"));
    }
    Chain::new(
        "mobile8",
        joints,
        IsometryMatrix3::identity(),
        IsometryMatrix3::identity(),
    )
    .and_then(mobile8_dynamics)
    .and_then(|c| c.with_racket(crate::hit::RacketMount::seed000().in_tool))
    .and_then(|c| c.with_ready(&mobile8_start()))
    .and_then(|c| c.with_gravity(MOBILE8_GRAVITY))
    .expect("built-in mobile8 is valid")
}

/// Gravity for mobile8 in its base frame (Table 1's frame 0), m/s². Joint 1 moves the base along
/// z0, horizontally ("back and forth on fixed wheels"), so z0 cannot be vertical; joint 2, the
/// waist, turns about x0 and sits 68 mm along its own axis above the base: x0 is up. The seed
/// does not say so explicitly: this is our reading, mobile8's [`Chain::gravity`] (robot-file key
/// `gravity`), so every default (RNEA, hit planner, coupled simulation) uses it.
pub const MOBILE8_GRAVITY: [f64; 3] = [-9.81, 0.0, 0.0];

/// The start configuration of seed 000's experiment: [0.26 m, 200°, 90°, 80°, 250°, 105°, 180°, 135°].
pub fn mobile8_start() -> [f64; 8] {
    [
        0.26,
        200.0 * DEG,
        90.0 * DEG,
        80.0 * DEG,
        250.0 * DEG,
        105.0 * DEG,
        180.0 * DEG,
        135.0 * DEG,
    ]
}

/// Seed 002: the 6-joint gantry table-tennis robot with the default lengths.
pub fn gantry6() -> Chain {
    gantry6_with(GantryLengths::default()).expect("built-in gantry6 is valid")
}

/// Seed 002 with chosen lengths. Modified DH rows (α_{i−1}, a_{i−1}, θ_i, d_i):
/// (90°, 0, 90°, d1), (90°, 0, 90°, d2), (90°, 0, θ3, L1), (90°, 0, θ4, 0), (0, L3, θ5, L2),
/// (90°, 0, θ6, L4). Joint order d1, d2 (linear axes along −y and +x of the base), θ3..θ6.
/// Strokes ±1.0 m and ±0.6 m (d1 force 600 N: its axis moves every carriage, ≈ 17 kg at 20 m/s²); wrist joints ±180°, θ4 within ±90° (the upper arm stays below its
/// shoulder, one σ2 branch of the IK). Inertias and drives are documented estimates (8 kg and
/// 4 kg carriages, aluminium-tube wrist links with lumped motors, a 0.18 kg racket at the tool).
pub fn gantry6_with(l: GantryLengths) -> Result<Chain> {
    let m = DhConvention::Modified;
    let a90 = 90.0 * DEG;
    let joints = vec![
        Joint::prismatic("d1", m, dh(0.0, a90, 0.0, a90))?.with_limits(limits(-1.0, 1.0, 3.0, 20.0, 600.0))?,
        Joint::prismatic("d2", m, dh(0.0, a90, 0.0, a90))?.with_limits(limits(-0.6, 0.6, 3.0, 20.0, 200.0))?,
        Joint::revolute("theta3", m, dh(0.0, a90, l.l1, 0.0))?.with_limits(limits(-PI, PI, 10.0, 100.0, 30.0))?,
        Joint::revolute("theta4", m, dh(0.0, a90, 0.0, 0.0))?.with_limits(limits(
            -PI / 2.0,
            PI / 2.0,
            10.0,
            100.0,
            30.0,
        ))?,
        Joint::revolute("theta5", m, dh(l.l3, 0.0, l.l2, 0.0))?.with_limits(limits(-PI, PI, 15.0, 150.0, 15.0))?,
        Joint::revolute("theta6", m, dh(0.0, a90, l.l4, 0.0))?.with_limits(limits(-PI, PI, 20.0, 200.0, 5.0))?,
    ];
    Chain::new(
        "gantry6",
        joints,
        IsometryMatrix3::identity(),
        IsometryMatrix3::identity(),
    )
    .and_then(gantry6_dynamics)
    .and_then(|c| c.with_ready(&GANTRY6_READY))
}

/// gantry6's ready pose (m, rad): carriages centred, θ4 = θ5 = 0.6 rad, the racket face up in
/// front of the robot.
pub const GANTRY6_READY: [f64; 6] = [0.0, 0.0, 0.0, 0.6, 0.6, 0.0];

/// Lengths of the 4-DOF arm of seed 001 (m). The seed prints no values; these are documented
/// choices of a small desktop arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arm4Lengths {
    /// Height of joint 2 above joint 1 (d1).
    pub d1: f64,
    /// Length of link 1 (a1), joint 1 → joint 2.
    pub a1: f64,
    /// Length of link 2 (a2), joint 2 → joint 3.
    pub a2: f64,
    /// Wrist-to-tool offset along the last axis (d4).
    pub d4: f64,
}

impl Default for Arm4Lengths {
    /// d1 = 0.30, a1 = 0.25, a2 = 0.20, d4 = 0.10 m.
    fn default() -> Self {
        Arm4Lengths {
            d1: 0.30,
            a1: 0.25,
            a2: 0.20,
            d4: 0.10,
        }
    }
}

/// Seed 001: the 4-DOF arm in standard DH rows (θ, d, a, α): (θ1, d1, a1, 0), (θ2, 0, a2, 90°),
/// (θ3, 0, 0, 90°), (θ4, d4, 0, 0); joints 1 and 2 parallel and vertical (the structure for which
/// the seed's IK fragments hold). Limits ±170° (joint 3: ±120°), 2 rad/s. Inertias and drives are
/// documented estimates (aluminium-tube links with lumped motors, a 0.18 kg racket at the tool).
pub fn arm4() -> Chain {
    arm4_with(Arm4Lengths::default()).expect("built-in arm4 is valid")
}

/// Seed 001's arm with chosen lengths.
pub fn arm4_with(l: Arm4Lengths) -> Result<Chain> {
    let s = DhConvention::Standard;
    let lim = |deg: f64| limits(-deg * DEG, deg * DEG, 2.0, 10.0, 10.0);
    let joints = vec![
        Joint::revolute("theta1", s, dh(l.a1, 0.0, l.d1, 0.0))?.with_limits(lim(170.0))?,
        Joint::revolute("theta2", s, dh(l.a2, 90.0 * DEG, 0.0, 0.0))?.with_limits(lim(170.0))?,
        Joint::revolute("theta3", s, dh(0.0, 90.0 * DEG, 0.0, 0.0))?.with_limits(lim(120.0))?,
        Joint::revolute("theta4", s, dh(0.0, 0.0, l.d4, 0.0))?.with_limits(lim(170.0))?,
    ];
    Chain::new("arm4", joints, IsometryMatrix3::identity(), IsometryMatrix3::identity()).and_then(arm4_dynamics)
}

/// Universal Robots UR5 (CB3), standard DH with the nominal values of the vendor's DH table:
/// d1 = 0.089159, a2 = −0.425, a3 = −0.39225, d4 = 0.10915, d5 = 0.09465, d6 = 0.0823 m,
/// α = (90°, 0, 0, 90°, −90°, 0). Limits ±360°, 180°/s, efforts 150/150/150/28/28/28 N·m.
/// Link masses and centres of mass as published by Universal Robots; inertia tensors and drives
/// are cylinder and harmonic-drive estimates.
pub fn ur5() -> Chain {
    let s = DhConvention::Standard;
    let rows = [
        dh(0.0, PI / 2.0, 0.089159, 0.0),
        dh(-0.425, 0.0, 0.0, 0.0),
        dh(-0.39225, 0.0, 0.0, 0.0),
        dh(0.0, PI / 2.0, 0.10915, 0.0),
        dh(0.0, -PI / 2.0, 0.09465, 0.0),
        dh(0.0, 0.0, 0.0823, 0.0),
    ];
    let names = [
        "shoulder_pan",
        "shoulder_lift",
        "elbow",
        "wrist_1",
        "wrist_2",
        "wrist_3",
    ];
    let efforts = [150.0, 150.0, 150.0, 28.0, 28.0, 28.0];
    let joints = rows
        .iter()
        .zip(names)
        .zip(efforts)
        .map(|((row, name), effort)| {
            Joint::revolute(name, s, *row)
                .and_then(|j| j.with_limits(limits(-2.0 * PI, 2.0 * PI, PI, 8.0, effort)))
                .expect("built-in ur5 joint is valid")
        })
        .collect();
    Chain::new("ur5", joints, IsometryMatrix3::identity(), IsometryMatrix3::identity())
        .and_then(ur5_dynamics)
        .expect("built-in ur5 is valid")
}

/// A built-in robot by name: `mobile8`, `gantry6`, `arm4` or `ur5`.
pub fn by_name(name: &str) -> Result<Chain> {
    match name {
        "mobile8" => Ok(mobile8()),
        "gantry6" => Ok(gantry6()),
        "arm4" => Ok(arm4()),
        "ur5" => Ok(ur5()),
        other => Err(crate::error::Error::invalid(
            "robot",
            format!("unknown built-in robot '{other}'; choose one of {}", NAMES.join(", ")),
        )),
    }
}

/// Names of the built-in robots ([`by_name`]).
pub const NAMES: [&str; 4] = ["mobile8", "gantry6", "arm4", "ur5"];

// ---------------------------------------------------------------------------------------------
// Inertial and drive estimates of the built-in robots.
//
// None of the seeds gives masses or inertias. Except for the UR5 (published masses and centres of
// mass), the values below are CAD-like estimates: aluminium (ρ = 2700 kg/m³) tubes between the
// joints, the stator of joint i + 1 as a lumped body on link i at joint i + 1, carriages as solid
// aluminium-and-steel blocks, and a 0.18 kg table-tennis racket on the last link. Drives are
// typical small geared DC motors / servo motors with harmonic or planetary gears. They make the
// dynamics plausible (torques of the right order against the effort limits), not identified.
// ---------------------------------------------------------------------------------------------

/// Linear density of a 40 × 2 mm aluminium tube, kg/m: 2700·π·(0.020² − 0.018²).
const TUBE_40X2: f64 = 2700.0 * PI * (0.020 * 0.020 - 0.018 * 0.018);
/// Mass of the racket (blade, rubbers and handle), kg.
pub const RACKET_MASS: f64 = 0.18;
/// Radius of the disc that stands in for the racket blade, m.
const RACKET_RADIUS: f64 = 0.075;

/// Solid cylinder of `mass` kg and `radius` m whose axis runs from `a` to `b` (m, link frame).
fn cylinder(mass: f64, a: Vector3<f64>, b: Vector3<f64>, radius: f64) -> Inertial {
    let d = b - a;
    let len = d.norm();
    let axis = if len > 1e-9 { d / len } else { Vector3::z() };
    let i_axis = 0.5 * mass * radius * radius;
    let i_perp = mass * (3.0 * radius * radius + len * len) / 12.0;
    Inertial {
        mass,
        com: (a + b) * 0.5,
        inertia: Matrix3::identity() * i_perp + axis * axis.transpose() * (i_axis - i_perp),
    }
}

/// Solid sphere of `mass` kg and `radius` m centred at `at` (m, link frame): a lumped motor.
fn lump(mass: f64, at: Vector3<f64>, radius: f64) -> Inertial {
    Inertial {
        mass,
        com: at,
        inertia: Matrix3::identity() * (0.4 * mass * radius * radius),
    }
}

/// Solid block of `mass` kg with edges `size` (m, link-frame axes) centred at `at`: a carriage.
fn block(mass: f64, at: Vector3<f64>, size: [f64; 3]) -> Inertial {
    let [x, y, z] = size.map(|s| s * s);
    Inertial {
        mass,
        com: at,
        inertia: Matrix3::from_diagonal(&Vector3::new(y + z, x + z, x + y)) * (mass / 12.0),
    }
}

/// The racket: a 0.18 kg disc of radius 75 mm centred at `at` (m, link frame) whose face normal
/// is the link's x axis (seed 000: the face normal is n = x of the last frame).
fn racket(at: Vector3<f64>) -> Inertial {
    let r2 = RACKET_RADIUS * RACKET_RADIUS;
    Inertial {
        mass: RACKET_MASS,
        com: at,
        inertia: Matrix3::from_diagonal(&Vector3::new(0.5, 0.25, 0.25)) * (RACKET_MASS * r2),
    }
}

/// Origin of joint i's axis frame and of the next joint (or of the tool point for the last link),
/// both in link frame i.
fn link_ends(chain: &Chain, i: usize) -> (Vector3<f64>, Vector3<f64>) {
    let joints = chain.joints();
    let own = joints[i].post().inverse().translation.vector;
    let next = match joints.get(i + 1) {
        Some(j) => j.pre().translation.vector,
        None => chain.tool().translation.vector,
    };
    (own, next)
}

/// CAD-like estimate of an arm link i: a tube of `kg_per_m` and `radius` from its joint to the
/// next joint, a 50 g bracket at its joint and the `next_motor` kg stator lumped at the next joint.
fn tube_link(chain: &Chain, i: usize, kg_per_m: f64, radius: f64, next_motor: f64) -> Inertial {
    let (own, next) = link_ends(chain, i);
    let mut body = lump(0.05, own, radius);
    let len = (next - own).norm();
    if len > 1e-6 {
        body = body.combine(&cylinder(kg_per_m * len, own, next, radius));
    }
    if next_motor > 0.0 {
        body = body.combine(&lump(next_motor, next, 0.03));
    }
    body
}

/// The same chain with the given link inertias and drives (kinematics unchanged).
fn with_dynamics(chain: Chain, links: Vec<Inertial>, drives: Vec<Drive>) -> Result<Chain> {
    let joints = chain
        .joints()
        .iter()
        .zip(links)
        .zip(drives)
        .map(|((j, l), d)| j.clone().with_inertial(l)?.with_drive(d))
        .collect::<Result<Vec<_>>>()?;
    chain.with_joints(joints, *chain.base(), *chain.tool())
}

/// A drive from (gear ratio, rotor inertia kg·m², viscous, Coulomb, torque constant N·m/A).
fn drive(gear_ratio: f64, rotor_inertia: f64, viscous: f64, coulomb: f64, torque_constant: f64) -> Drive {
    Drive {
        gear_ratio,
        rotor_inertia,
        viscous,
        coulomb,
        torque_constant: Some(torque_constant),
        ..Drive::geared(gear_ratio)
    }
}

/// mobile8 inertias (estimates): link 1 is the wheeled base, a 12 kg block 0.40 × 0.30 × 0.15 m
/// (frame, battery, the motor of joint 2); links 2–8 are 40 × 2 mm aluminium tubes (0.64 kg/m)
/// carrying the stators of joints 3–8 (0.5, 0.5, 0.35, 0.35, 0.25, 0.25 kg); link 8 carries the
/// 0.18 kg racket centred 0.15 m along z8 (the seed's racket centre). Drives: base wheels of
/// 50 mm radius behind a 20:1 gear (G = 400 rad/m), arm joints 100:1 with 3·10⁻⁶ kg·m² rotors.
fn mobile8_dynamics(chain: Chain) -> Result<Chain> {
    let mut links = vec![block(12.0, Vector3::zeros(), [0.40, 0.30, 0.15])];
    let stators = [0.5, 0.5, 0.35, 0.35, 0.25, 0.25, 0.0];
    for (i, &m) in stators.iter().enumerate() {
        links.push(tube_link(&chain, i + 1, TUBE_40X2, 0.02, m));
    }
    links[7] = links[7].combine(&racket(Vector3::new(0.0, 0.0, 0.15)));
    let mut drives = vec![drive(400.0, 2.0e-5, 5.0, 10.0, 0.05)];
    drives.extend(std::iter::repeat_n(drive(100.0, 3.0e-6, 0.02, 0.1, 0.03), 7));
    with_dynamics(chain, links, drives)
}

/// gantry6 inertias (estimates): the d1 carriage (with the d2 axis) 8 kg and the d2 carriage
/// 4 kg, solid blocks; links 3–6 are 40 × 2 mm aluminium tubes with the stators of joints 4–6
/// (0.8, 0.6, 0.3 kg) lumped at the next joint; the 0.18 kg racket is centred at the tool point.
/// Drives: catalogue-class motors with full datasheet values, see [`drives::gantry6`].
fn gantry6_dynamics(chain: Chain) -> Result<Chain> {
    let links = vec![
        block(8.0, Vector3::zeros(), [0.30, 0.20, 0.10]),
        block(4.0, Vector3::zeros(), [0.20, 0.15, 0.08]),
        tube_link(&chain, 2, TUBE_40X2, 0.02, 0.8),
        tube_link(&chain, 3, TUBE_40X2, 0.02, 0.6),
        tube_link(&chain, 4, TUBE_40X2, 0.02, 0.3),
        tube_link(&chain, 5, TUBE_40X2, 0.02, 0.0).combine(&racket(chain.tool().translation.vector)),
    ];
    let drives = drives::gantry6();
    with_dynamics(chain, links, drives)
}

/// arm4 inertias (estimates): 40 × 2 mm aluminium tubes between the joints, the stators of
/// joints 2–4 (0.6, 0.4, 0.3 kg) lumped at the next joint, the 0.18 kg racket at the tool point.
/// Drives: 100:1 gears, 2·10⁻⁶ kg·m² rotors.
fn arm4_dynamics(chain: Chain) -> Result<Chain> {
    let stators = [0.6, 0.4, 0.3, 0.0];
    let mut links: Vec<Inertial> = (0..4)
        .map(|i| tube_link(&chain, i, TUBE_40X2, 0.02, stators[i]))
        .collect();
    links[3] = links[3].combine(&racket(chain.tool().translation.vector));
    let drives = vec![drive(100.0, 2.0e-6, 0.02, 0.1, 0.03); 4];
    with_dynamics(chain, links, drives)
}

/// UR5 inertias: the masses (3.7, 8.393, 2.33, 1.219, 1.219, 0.1879 kg) and centres of mass in the
/// DH link frames published by Universal Robots with its DH table; UR publishes no tensors, so
/// the rotational inertia about each centre of mass is that of a solid cylinder of the link's mass
/// along the link (radius 60 mm for links 1–3, 45 mm for the wrist), as the vendor's ROS
/// description also does. Drives (estimates): 101:1 harmonic gears, rotors of 4·10⁻⁵ kg·m²
/// (shoulder, elbow) and 1.1·10⁻⁵ kg·m² (wrist).
fn ur5_dynamics(chain: Chain) -> Result<Chain> {
    let masses = [3.7, 8.393, 2.33, 1.219, 1.219, 0.1879];
    let coms = [
        [0.0, -0.02561, 0.00193],
        [0.2125, 0.0, 0.11336],
        [0.15, 0.0, 0.0265],
        [0.0, -0.0018, 0.01634],
        [0.0, 0.0018, 0.01634],
        [0.0, 0.0, -0.001159],
    ];
    let radii = [0.06, 0.06, 0.06, 0.045, 0.045, 0.045];
    let links = (0..6)
        .map(|i| {
            let (own, next) = link_ends(&chain, i);
            let shape = cylinder(masses[i], own, next, radii[i]);
            Inertial {
                com: Vector3::from(coms[i]),
                ..shape
            }
        })
        .collect();
    let big = drive(101.0, 4.0e-5, 0.5, 2.0, 0.13);
    let small = drive(101.0, 1.1e-5, 0.2, 0.8, 0.09);
    let drives = vec![big, big, big, small, small, small];
    with_dynamics(chain, links, drives)
}
