//! Differential-drive base (seed 000, formulas (3)–(12) corrected): wheel speeds ↔ body velocity,
//! the exact pose update for constant wheel speeds, odometry from encoder increments, wheel speed
//! and acceleration limits, and the seed's 4-wheel layout (2 driven wheels, 2 fixed followers).
//!
//! Conventions: wheel speeds are always ordered (left, right) in rad/s, positive when the wheel
//! drives the base forward; the body velocity is (v, ω) with v the forward speed of the axle
//! midpoint (m/s) and ω the yaw rate (rad/s, counter-clockwise positive); a pose is (x, y, θ) of the
//! axle midpoint in the world frame (m, m, rad). The wheel radius `r` and the turning radius v/ω
//! are different quantities (the seed writes both as R).
//!
//! Corrections to the seed (../shared/seeds/README.md): (3) ω = (v_R − v_L)/l, not (2v_R − v_L)/l;
//! (6) third row [r/l, −r/l]; (10) the rotation about the ICC has −sin in its (1, 2) entry; the
//! exact update for constant wheel speeds over δt, with no singularity at ω → 0 or in place, is
//! x' = x + vδt·sinc(ωδt/2)·cos(θ + ωδt/2), y' = y + vδt·sinc(ωδt/2)·sin(θ + ωδt/2), θ' = θ + ωδt;
//! (12) is replaced by the heading increment r(Δφ_R − Δφ_L)/l of the odometry.

use crate::error::{check_finite, check_positive, Error, Result};

/// sin(x)/x, exact at 0 and accurate to machine precision near it (m, rad independent).
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        let x2 = x * x;
        1.0 - x2 / 6.0 + x2 * x2 / 120.0
    } else {
        x.sin() / x
    }
}

/// Pose (x, y, θ) after moving for `dt` s at constant body velocity (`v` m/s, `omega` rad/s) from
/// `pose` (m, m, rad, world frame): the exact arc (straight line when ω = 0, turn in place when v = 0).
pub fn arc_step(pose: [f64; 3], v: f64, omega: f64, dt: f64) -> [f64; 3] {
    let dth = omega * dt;
    let ds = v * dt * sinc(0.5 * dth);
    let mid = pose[2] + 0.5 * dth;
    [pose[0] + ds * mid.cos(), pose[1] + ds * mid.sin(), pose[2] + dth]
}

/// A differential-drive base: two driven wheels on one axle, with optional wheel limits.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffDrive {
    wheel_radius: f64,
    track: f64,
    max_wheel_speed: f64,
    max_wheel_acceleration: f64,
}

impl DiffDrive {
    /// A base with wheel radius `wheel_radius` (m) and `track` (distance between the wheel
    /// contact points, m); no speed or acceleration limit.
    pub fn new(wheel_radius: f64, track: f64) -> Result<Self> {
        check_positive("wheel_radius", wheel_radius, "m")?;
        check_positive("track", track, "m")?;
        Ok(DiffDrive {
            wheel_radius,
            track,
            max_wheel_speed: f64::INFINITY,
            max_wheel_acceleration: f64::INFINITY,
        })
    }

    /// The same base with wheel speed (rad/s) and wheel acceleration (rad/s²) limits; pass
    /// `f64::INFINITY` for none.
    pub fn with_limits(mut self, max_wheel_speed: f64, max_wheel_acceleration: f64) -> Result<Self> {
        for (what, v) in [
            ("max_wheel_speed", max_wheel_speed),
            ("max_wheel_acceleration", max_wheel_acceleration),
        ] {
            if !(v > 0.0) {
                return Err(Error::invalid(what, format!("must be > 0 (or infinite), got {v}")));
            }
        }
        self.max_wheel_speed = max_wheel_speed;
        self.max_wheel_acceleration = max_wheel_acceleration;
        Ok(self)
    }

    /// Wheel radius (m).
    pub fn wheel_radius(&self) -> f64 {
        self.wheel_radius
    }

    /// Distance between the wheel contact points (m).
    pub fn track(&self) -> f64 {
        self.track
    }

    /// Wheel speed limit (rad/s, infinite when unlimited).
    pub fn max_wheel_speed(&self) -> f64 {
        self.max_wheel_speed
    }

    /// Wheel acceleration limit (rad/s², infinite when unlimited).
    pub fn max_wheel_acceleration(&self) -> f64 {
        self.max_wheel_acceleration
    }

    /// Body velocity (v m/s, ω rad/s) from wheel speeds (left, right) in rad/s:
    /// v = r(φ̇_L + φ̇_R)/2, ω = r(φ̇_R − φ̇_L)/l.
    pub fn body_velocity(&self, wheels: [f64; 2]) -> (f64, f64) {
        let (vl, vr) = (self.wheel_radius * wheels[0], self.wheel_radius * wheels[1]);
        (0.5 * (vl + vr), (vr - vl) / self.track)
    }

    /// Wheel speeds (left, right) in rad/s for a body velocity (v m/s, ω rad/s).
    pub fn wheel_speeds(&self, v: f64, omega: f64) -> [f64; 2] {
        let half = 0.5 * omega * self.track;
        [(v - half) / self.wheel_radius, (v + half) / self.wheel_radius]
    }

    /// Pose (x, y, θ) after `duration` s at constant wheel speeds (left, right) rad/s from `pose`
    /// (m, m, rad): the exact sinc update, no singularity when driving straight or spinning.
    pub fn integrate(&self, pose: [f64; 3], wheels: [f64; 2], duration: f64) -> [f64; 3] {
        let (v, w) = self.body_velocity(wheels);
        arc_step(pose, v, w, duration)
    }

    /// Checked [`DiffDrive::integrate`]: finite inputs and a duration ≥ 0 s.
    pub fn try_integrate(&self, pose: [f64; 3], wheels: [f64; 2], duration: f64) -> Result<[f64; 3]> {
        check_finite("pose", &pose)?;
        check_finite("wheel_speeds", &wheels)?;
        if !(duration >= 0.0 && duration.is_finite()) {
            return Err(Error::invalid(
                "duration",
                format!("must be finite and ≥ 0 s, got {duration}"),
            ));
        }
        Ok(self.integrate(pose, wheels, duration))
    }

    /// Largest box |v| ≤ v_max, |ω| ≤ ω_max (m/s, rad/s) inside the wheel speed limit: every body
    /// velocity in it keeps both wheels within `max_wheel_speed` (v_max = r·φ̇_max/2,
    /// ω_max = r·φ̇_max/l, half of the straight-line and in-place extremes).
    pub fn body_velocity_box(&self) -> (f64, f64) {
        let s = self.wheel_radius * self.max_wheel_speed;
        (0.5 * s, s / self.track)
    }

    /// Wheel speeds (left, right) rad/s scaled down together, if needed, to the speed limit; the
    /// common scale keeps the path curvature ω/v. Returns the speeds and the scale in (0, 1].
    pub fn saturate_speeds(&self, wheels: [f64; 2]) -> ([f64; 2], f64) {
        let peak = wheels[0].abs().max(wheels[1].abs());
        if peak <= self.max_wheel_speed {
            return (wheels, 1.0);
        }
        let s = self.max_wheel_speed / peak;
        ([wheels[0] * s, wheels[1] * s], s)
    }

    /// Wheel speeds (left, right) rad/s reachable from `previous` within `dt` s under the
    /// acceleration limit, moving toward `command` along the straight line in wheel-speed space
    /// (the change is scaled as a whole, so a curvature change is not distorted), then saturated.
    pub fn limit_step(&self, previous: [f64; 2], command: [f64; 2], dt: f64) -> [f64; 2] {
        let d = [command[0] - previous[0], command[1] - previous[1]];
        let peak = d[0].abs().max(d[1].abs());
        let max_d = self.max_wheel_acceleration * dt;
        let s = if peak > max_d { max_d / peak } else { 1.0 };
        self.saturate_speeds([previous[0] + s * d[0], previous[1] + s * d[1]]).0
    }

    /// [`DiffDrive::limit_step`] with the step checked: `dt` must be finite and ≥ 0 s.
    pub fn limit_step_checked(&self, previous: [f64; 2], command: [f64; 2], dt: f64) -> crate::error::Result<[f64; 2]> {
        if !(dt >= 0.0 && dt.is_finite()) {
            return Err(crate::error::Error::invalid(
                "dt",
                format!("must be finite and ≥ 0 s, got {dt}"),
            ));
        }
        Ok(self.limit_step(previous, command, dt))
    }
}

/// Dead-reckoning odometry: pose (x, y, θ) of the axle midpoint from wheel encoder increments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry {
    drive: DiffDrive,
    pose: [f64; 3],
    distance: f64,
}

impl Odometry {
    /// Odometry of `drive` starting at `pose` (m, m, rad, world frame).
    pub fn new(drive: DiffDrive, pose: [f64; 3]) -> Self {
        Odometry {
            drive,
            pose,
            distance: 0.0,
        }
    }

    /// Current pose estimate (x, y, θ), m, m, rad.
    pub fn pose(&self) -> [f64; 3] {
        self.pose
    }

    /// Path length travelled by the axle midpoint (m, signed: backward motion subtracts).
    pub fn distance(&self) -> f64 {
        self.distance
    }

    /// Adds one pair of wheel rotation increments (left, right) in rad since the last update; the
    /// wheels are assumed to turn at constant speed in between (exact arc). Heading changes by
    /// r(Δφ_R − Δφ_L)/l, the integral form of the seed's (12). Non-finite increments are rejected.
    pub fn update(&mut self, increments: [f64; 2]) -> Result<[f64; 3]> {
        check_finite("encoder increments", &increments)?;
        let (ds, dth) = self.drive.body_velocity(increments);
        self.pose = arc_step(self.pose, ds, dth, 1.0);
        self.distance += ds;
        Ok(self.pose)
    }
}

/// The seed's 4-wheel base: a driven axle (left, right) and a follower axle of fixed wheels
/// `wheelbase` m ahead of it, same track. Fixed followers roll at the speed of their contact point
/// along the body x axis and are dragged sideways by ω·wheelbase when the base turns, which is why
/// the seed's base drives only back and forth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourWheelBase {
    drive: DiffDrive,
    wheelbase: f64,
    follower_radius: f64,
}

impl FourWheelBase {
    /// A 4-wheel base from its driven axle, the axle distance (m) and the follower wheel radius (m).
    pub fn new(drive: DiffDrive, wheelbase: f64, follower_radius: f64) -> Result<Self> {
        check_positive("wheelbase", wheelbase, "m")?;
        check_positive("follower_radius", follower_radius, "m")?;
        Ok(FourWheelBase {
            drive,
            wheelbase,
            follower_radius,
        })
    }

    /// The driven axle.
    pub fn drive(&self) -> &DiffDrive {
        &self.drive
    }

    /// All four wheel speeds (rad/s) for a body velocity (v m/s, ω rad/s): driven left, driven
    /// right, follower left, follower right.
    pub fn wheel_speeds(&self, v: f64, omega: f64) -> [f64; 4] {
        let [dl, dr] = self.drive.wheel_speeds(v, omega);
        let half = 0.5 * omega * self.drive.track();
        [
            dl,
            dr,
            (v - half) / self.follower_radius,
            (v + half) / self.follower_radius,
        ]
    }

    /// Sideways slip speed of the follower wheels (m/s, body y) for a yaw rate ω (rad/s).
    pub fn follower_slip(&self, omega: f64) -> f64 {
        omega * self.wheelbase
    }
}
