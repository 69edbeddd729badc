//! Cyclic position setpoints as a CANopen drive receives them (CiA 402 cyclic synchronous position
//! with an interpolation time period, object 0x60C2): interpolation at the speed-loop rate and the
//! setpoint-age watchdog.
//!
//! Each setpoint carries (q, q̇, q̈). On arrival the interpolator joins the previous setpoint to the
//! new one by the quintic with both ends' position, velocity and acceleration
//! ([`ttkin::traj::poly::quintic`], the same polynomial the planner uses) over one setpoint period
//! T_sp, and the speed-loop ticks read it at τ = time since arrival. A quintic reference is thus
//! reproduced exactly, with a delay of one period: the host sends each setpoint T_sp ahead of the
//! instant it describes (as CiA 402 hosts do with a known interpolation time). When a period
//! passes without a setpoint the reference stops at the last setpoint with zero velocity and
//! acceleration feed-forward (nothing moves on a stale setpoint); after `max_missed` periods the
//! watchdog reports the setpoints lost (the axis then quick-stops).

use ttkin::traj::poly::{eval3, quintic, Coeffs};

/// Interpolator and age watchdog for cyclic position setpoints (rad, rad/s, rad/s² at the output).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SetpointInterpolator {
    period: f64,
    max_missed: u32,
    segment: Coeffs,
    last: [f64; 3],
    age: f64,
    started: bool,
}

impl SetpointInterpolator {
    /// Interpolator for setpoints every `period` s (> 0, checked by the caller) that reports them
    /// lost after `max_missed` (≥ 1) whole periods without one.
    pub fn new(period: f64, max_missed: u32) -> Self {
        SetpointInterpolator {
            period,
            max_missed: max_missed.max(1),
            segment: [0.0; 6],
            last: [0.0; 3],
            age: 0.0,
            started: false,
        }
    }

    /// Restarts at rest at `q`: the next setpoint is reached from there.
    pub fn reset(&mut self, q: f64) {
        self.last = [q, 0.0, 0.0];
        self.segment = [q, 0.0, 0.0, 0.0, 0.0, 0.0];
        self.age = 0.0;
        self.started = false;
    }

    /// A new setpoint arrived: the segment from the previous one to it starts now.
    #[inline]
    pub fn push(&mut self, q: f64, qd: f64, qdd: f64) {
        let [q0, v0, a0] = if self.age < self.period && self.started {
            // Early setpoint: start from where the running segment is now.
            eval3(&self.segment, self.age)
        } else {
            self.last
        };
        self.segment = quintic(q0, v0, a0, q, qd, qdd, self.period);
        self.last = [q, qd, qdd];
        self.age = 0.0;
        self.started = true;
    }

    /// Reference for the speed-loop period of `hold` s that starts now: the position at its start
    /// (where the measurement is), the velocity and acceleration at its middle (the speed loop
    /// holds its output over the period, so the mean speed it produces is the one asked for at
    /// the middle; sampling them at the start would lag the motion by hold/2).
    #[inline]
    pub fn sample(&self, hold: f64) -> [f64; 3] {
        if self.age <= self.period {
            let [q, _, _] = eval3(&self.segment, self.age);
            let [_, qd, qdd] = eval3(&self.segment, (self.age + 0.5 * hold).min(self.period));
            [q, qd, qdd]
        } else {
            [self.last[0], 0.0, 0.0]
        }
    }

    /// Advances the clock by `dt` s (every current-loop period, after the control step).
    #[inline]
    pub fn advance(&mut self, dt: f64) {
        self.age += dt;
    }

    /// True once `max_missed` setpoints in a row are overdue (by half a period, the jitter allowance).
    #[inline]
    pub fn lost(&self) -> bool {
        self.started && self.age > (self.max_missed as f64 + 0.5) * self.period
    }

    /// Time since the last setpoint, s.
    pub fn age(&self) -> f64 {
        self.age
    }

    /// Setpoint period, s.
    pub fn period(&self) -> f64 {
        self.period
    }
}
