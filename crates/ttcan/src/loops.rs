//! The three nested loops of seed 000 §2.1 (its Figs 2–4), each one step at its own rate, allocation
//! free, with all coefficients computed when the loop is built.
//!
//! - [`CurrentLoop`]: reference limited to the present current limit (peak, derated by the
//!   axis' thermal model, [`crate::thermal`]); PI against the measured current (anti-windup by conditional integration),
//!   optional back-EMF feedforward; output as a duty cycle, saturated to the bridge voltage.
//! - [`SpeedLoop`]: reference limited and low-pass filtered; PI; output low-pass filtered (the seed's
//!   two filters); gives the current reference. Feedforward enters after the reference filter.
//! - [`PositionLoop`]: P on the position error plus velocity and acceleration feedforward (the
//!   acceleration through inertia and torque constant to a current), with following-error monitoring.
//!
//! Units: output (joint) side, rad, rad/s, rad/s²; currents in A; voltages in V.

/// First-order low-pass y ← y + α (x − y), α = 1 − e^{−2π f_c T}: the exact step response of
/// 1/(1 + s/(2π f_c)) sampled every T. An infinite cut-off passes the input through (α = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowPass {
    alpha: f64,
    y: f64,
}

impl LowPass {
    /// Filter with cut-off `cutoff_hz` (> 0, may be infinite) sampled every `period` seconds.
    pub fn new(cutoff_hz: f64, period: f64) -> Self {
        let alpha = if cutoff_hz.is_infinite() {
            1.0
        } else {
            1.0 - (-2.0 * std::f64::consts::PI * cutoff_hz * period).exp()
        };
        LowPass { alpha, y: 0.0 }
    }

    /// Filters one sample.
    #[inline]
    pub fn step(&mut self, x: f64) -> f64 {
        self.y += self.alpha * (x - self.y);
        self.y
    }

    /// Sets the filter state (bumpless start).
    pub fn reset(&mut self, y: f64) {
        self.y = y;
    }

    /// Current output.
    pub fn output(&self) -> f64 {
        self.y
    }
}

/// Discrete PI u = Kp e + I, I ← I + Ki T e, with conditional-integration anti-windup: while the
/// output is saturated the integrator only integrates errors that pull it out of saturation, and
/// it stays inside the output range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pi {
    kp: f64,
    ki_t: f64,
    integral: f64,
    anti_windup: bool,
}

impl Pi {
    /// PI with proportional gain `kp`, integral gain `ki` (1/s times the units of `kp`), period `period` s.
    pub fn new(kp: f64, ki: f64, period: f64, anti_windup: bool) -> Self {
        Pi {
            kp,
            ki_t: ki * period,
            integral: 0.0,
            anti_windup,
        }
    }

    /// One step: output for `error`, saturated to [lo, hi] (lo ≤ hi).
    #[inline]
    pub fn step(&mut self, error: f64, lo: f64, hi: f64) -> f64 {
        let unsat = self.kp * error + self.integral;
        let out = unsat.max(lo).min(hi);
        if self.anti_windup {
            // Integrate unless saturated and the error pushes further into saturation.
            if out == unsat || error * (unsat - out) < 0.0 {
                self.integral += self.ki_t * error;
            }
            self.integral = self.integral.max(lo).min(hi);
        } else {
            self.integral += self.ki_t * error;
        }
        out
    }

    /// Sets the integrator (bumpless transfer).
    pub fn reset(&mut self, integral: f64) {
        self.integral = integral;
    }

    /// Integrator state.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Proportional gain.
    pub fn kp(&self) -> f64 {
        self.kp
    }

    /// Integral gain, 1/s times the units of `kp`.
    pub fn ki(&self, period: f64) -> f64 {
        self.ki_t / period
    }
}

/// Current loop: limit (set by the axis from the thermal model) → PI (+ back-EMF feedforward) →
/// duty cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurrentLoop {
    pi: Pi,
    bus_voltage: f64,
    max_voltage: f64,
    emf_per_output_speed: f64,
    peak: f64,
    limit: f64,
    reference: f64,
    voltage: f64,
}

impl CurrentLoop {
    /// Builds the loop; `emf_per_output_speed` (V per output rad/s) is 0 to switch the back-EMF
    /// feedforward off; the current limit starts at `peak` (A).
    pub fn new(pi: Pi, bus_voltage: f64, max_voltage: f64, emf_per_output_speed: f64, peak: f64) -> Self {
        CurrentLoop {
            pi,
            bus_voltage,
            max_voltage,
            emf_per_output_speed,
            peak,
            limit: peak,
            reference: 0.0,
            voltage: 0.0,
        }
    }

    /// Sets the measured bus voltage (V, > 0): the duty is the commanded voltage divided by it, and
    /// the usable voltage scales with it (max voltage × measured / nominal).
    #[inline]
    pub fn set_bus_voltage(&mut self, volts: f64) {
        if volts > 0.0 && volts.is_finite() {
            self.max_voltage *= volts / self.bus_voltage;
            self.bus_voltage = volts;
        }
    }

    /// Sets the current limit (A), at most the peak current (the thermal derating of the axis).
    #[inline]
    pub fn set_limit(&mut self, limit: f64) {
        self.limit = if limit.is_finite() {
            limit.clamp(0.0, self.peak)
        } else {
            0.0
        };
    }

    /// Present current limit, A.
    #[inline]
    pub fn limit(&self) -> f64 {
        self.limit
    }

    /// One step: reference (A), measured current (A), estimated output speed (rad/s) → duty in [−1, 1].
    #[inline]
    pub fn step(&mut self, reference: f64, measured: f64, output_speed: f64) -> f64 {
        let lim = self.limit;
        let r = reference.max(-lim).min(lim);
        self.reference = r;
        let ff = self.emf_per_output_speed * output_speed;
        let v = ff
            + self
                .pi
                .step(r - measured, -self.max_voltage - ff, self.max_voltage - ff);
        self.voltage = v;
        v / self.bus_voltage
    }

    /// Zeroes the integrator and the held values.
    pub fn reset(&mut self) {
        self.pi.reset(0.0);
        self.reference = 0.0;
        self.voltage = 0.0;
    }

    /// Last limited current reference, A.
    pub fn reference(&self) -> f64 {
        self.reference
    }

    /// Last commanded voltage, V.
    pub fn voltage(&self) -> f64 {
        self.voltage
    }

    /// The PI controller.
    pub fn pi(&self) -> &Pi {
        &self.pi
    }
}

/// Speed loop: limit → low-pass → (+ velocity feedforward) → PI → low-pass → current reference (A).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLoop {
    pi: Pi,
    max_speed: f64,
    reference_filter: LowPass,
    output_filter: LowPass,
    reference: f64,
}

impl SpeedLoop {
    /// Builds the loop; speeds in output rad/s, `max_speed` > 0.
    pub fn new(pi: Pi, max_speed: f64, reference_filter: LowPass, output_filter: LowPass) -> Self {
        SpeedLoop {
            pi,
            max_speed,
            reference_filter,
            output_filter,
            reference: 0.0,
        }
    }

    /// One step: commanded speed (filtered), feedforward speed (not filtered), measured speed, all
    /// rad/s at the output, and the current available to the PI (A) → current reference (A).
    #[inline]
    pub fn step(&mut self, command: f64, feedforward: f64, measured: f64, lo: f64, hi: f64) -> f64 {
        let c = command.max(-self.max_speed).min(self.max_speed);
        let r = (self.reference_filter.step(c) + feedforward)
            .max(-self.max_speed)
            .min(self.max_speed);
        self.reference = r;
        let u = self.pi.step(r - measured, lo, hi);
        self.output_filter.step(u)
    }

    /// Bumpless restart: filters at `speed` and `current`, integrator at `current`.
    pub fn reset(&mut self, speed: f64, current: f64) {
        self.reference_filter.reset(speed);
        self.output_filter.reset(current);
        self.pi.reset(current);
        self.reference = speed;
    }

    /// Last speed reference after limiting, filtering and feedforward, rad/s.
    pub fn reference(&self) -> f64 {
        self.reference
    }

    /// The PI controller.
    pub fn pi(&self) -> &Pi {
        &self.pi
    }
}

/// What the position loop hands to the speed loop.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PositionOutput {
    /// Speed command from the position error, rad/s (goes through the speed reference filter).
    pub speed_command: f64,
    /// Velocity feedforward, rad/s (added after the speed reference filter).
    pub speed_feedforward: f64,
    /// Acceleration feedforward as a current, A (added to the speed loop's output).
    pub current_feedforward: f64,
    /// Position error q_ref − q, rad.
    pub following_error: f64,
}

/// Position loop: P on the error with velocity and acceleration feedforward.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionLoop {
    kp: f64,
    amps_per_acceleration: f64,
    velocity_feedforward: bool,
    acceleration_feedforward: bool,
}

impl PositionLoop {
    /// `kp` in 1/s; `amps_per_acceleration` = 1 / (output rad/s² per A).
    pub fn new(
        kp: f64,
        amps_per_acceleration: f64,
        velocity_feedforward: bool,
        acceleration_feedforward: bool,
    ) -> Self {
        PositionLoop {
            kp,
            amps_per_acceleration,
            velocity_feedforward,
            acceleration_feedforward,
        }
    }

    /// One step: reference position, velocity, acceleration and measured position (rad, rad/s, rad/s²).
    #[inline]
    pub fn step(&self, q_ref: f64, qd_ref: f64, qdd_ref: f64, q: f64) -> PositionOutput {
        let e = q_ref - q;
        PositionOutput {
            speed_command: self.kp * e,
            speed_feedforward: if self.velocity_feedforward { qd_ref } else { 0.0 },
            current_feedforward: if self.acceleration_feedforward {
                qdd_ref * self.amps_per_acceleration
            } else {
                0.0
            },
            following_error: e,
        }
    }

    /// Proportional gain, 1/s.
    pub fn kp(&self) -> f64 {
        self.kp
    }
}
