//! Built-in robots of the seed documents (`../shared/seeds/README.md`) and a UR5 for comparison.
//!
//! Every model is a plain [`Chain`]; the same data is also written out as robot files under
//! `robots/` of the repository and can be exported as URDF.

use std::f64::consts::PI;

use nalgebra::IsometryMatrix3;

use crate::chain::Chain;
use crate::error::Result;
use crate::joint::{Dh, DhConvention, Joint, Limits};

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
    .expect("built-in mobile8 is valid")
}

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
/// Strokes ±1.0 m and ±0.6 m; wrist joints ±180°, θ4 within ±90° (the upper arm stays below its
/// shoulder, one σ2 branch of the IK).
pub fn gantry6_with(l: GantryLengths) -> Result<Chain> {
    let m = DhConvention::Modified;
    let a90 = 90.0 * DEG;
    let joints = vec![
        Joint::prismatic("d1", m, dh(0.0, a90, 0.0, a90))?.with_limits(limits(-1.0, 1.0, 3.0, 20.0, 300.0))?,
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
}

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
/// the seed's IK fragments hold). Limits ±170° (joint 3: ±120°), 2 rad/s.
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
    Chain::new("arm4", joints, IsometryMatrix3::identity(), IsometryMatrix3::identity())
}

/// Universal Robots UR5 (CB3), standard DH with the nominal values of the vendor's DH table:
/// d1 = 0.089159, a2 = −0.425, a3 = −0.39225, d4 = 0.10915, d5 = 0.09465, d6 = 0.0823 m,
/// α = (90°, 0, 0, 90°, −90°, 0). Limits ±360°, 180°/s, efforts 150/150/150/28/28/28 N·m.
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
    Chain::new("ur5", joints, IsometryMatrix3::identity(), IsometryMatrix3::identity()).expect("built-in ur5 is valid")
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
            format!("unknown built-in robot '{other}'; choose mobile8, gantry6, arm4 or ur5"),
        )),
    }
}
