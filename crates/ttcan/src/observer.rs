//! Position and speed estimation: a tracking observer (a phase-locked loop on the encoder position)
//! run at the current-loop rate, with the measured current × k_acc as its acceleration input.
//!
//! ODrive and moteus estimate speed with a PLL on the encoder; Beckhoff AX5000 and Kollmorgen
//! drives add the commanded (here: measured) torque as an acceleration feed-forward. Per period T:
//!
//! ```text
//! predict   a = â + b̂,  θ⁻ = θ̂ + ω̂ T + ½ a T²,  ω⁻ = ω̂ + a T,    â = k_acc · i_measured
//! correct   e = θ_enc − θ⁻,  θ̂ = θ⁻ + l₁ e,  ω̂ = ω⁻ + l₂ e,  b̂ = b̂ + l₃ e
//! ```
//!
//! b̂ is the acceleration the model misses (friction, load torque, inertia error; rad/s²): without
//! it a constant friction current would bias ω̂ by 2â/ω_o. The error dynamics e⁺ = (I − L H) F e
//! are similar to F − (F L) H, whose characteristic polynomial in u = z − 1 is
//! u³ + k₁u² + (T k₂ + T² k₃/2) u + T² k₃ with K = F L. All three poles at p = e^{−ω_o T}
//! (bandwidth ω_o), c = 1 − p: k₁ = 3c, k₃ = c³/T², k₂ = (3c² − c³/2)/T, hence
//! l₁ = 1 − p³, l₂ = (3c² − 3c³/2)/T, l₃ = c³/T² (the continuous 3ω_o, 3ω_o², ω_o³ as T → 0).
//!
//! With the acceleration input and a matched model the current-to-speed-estimate path is exactly
//! k_acc/s (the observer is a complementary filter: encoder below ω_o, model above), so the speed
//! loop sees no estimator lag; the PLL corrects only what the model lacks (friction, load torque,
//! inertia error). The encoder's quantisation (uniform, σ = Δ/√12 for Δ rad per count) reaches the
//! speed estimate low-pass filtered: [`TrackingObserver::speed_noise_rms`] gives the RMS.

use crate::error::{finite, non_negative, positive, sixth_of_rate, Result};

/// Tracking observer of the output position (rad) and speed (rad/s) of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingObserver {
    period: f64,
    l_position: f64,
    l_speed: f64,
    l_bias: f64,
    acceleration_per_amp: f64,
    position: f64,
    speed: f64,
    bias: f64,
    innovation: f64,
}

impl TrackingObserver {
    /// Observer of bandwidth `bandwidth_hz` (> 0, below a sixth of the rate) stepped every `period`
    /// s; `acceleration_per_amp` (output rad/s² per A, ≥ 0; 0 switches the acceleration input off).
    pub fn new(bandwidth_hz: f64, period: f64, acceleration_per_amp: f64) -> Result<Self> {
        positive("observer bandwidth (Hz)", bandwidth_hz)?;
        positive("observer period (s)", period)?;
        non_negative("observer acceleration per amp (rad/s²/A)", acceleration_per_amp)?;
        sixth_of_rate("observer bandwidth (Hz)", bandwidth_hz, period)?;
        let p = (-2.0 * std::f64::consts::PI * bandwidth_hz * period).exp();
        let c = 1.0 - p;
        Ok(TrackingObserver {
            period,
            l_position: 1.0 - p * p * p,
            l_speed: (3.0 * c * c - 1.5 * c * c * c) / period,
            l_bias: c * c * c / (period * period),
            acceleration_per_amp,
            position: 0.0,
            speed: 0.0,
            bias: 0.0,
            innovation: 0.0,
        })
    }

    /// Sets the estimate (bumpless start), rad and rad/s.
    pub fn reset(&mut self, position: f64, speed: f64) {
        self.position = position;
        self.speed = speed;
        self.bias = 0.0;
        self.innovation = 0.0;
    }

    /// Prediction only (no encoder this period), with the measured current `current` (A).
    #[inline]
    pub fn predict(&mut self, current: f64) {
        let t = self.period;
        let a = self.acceleration_per_amp * current + self.bias;
        self.position += self.speed * t + 0.5 * a * t * t;
        self.speed += a * t;
    }

    /// One period: predict with the measured current (A), correct with the encoder position (rad).
    #[inline]
    pub fn step(&mut self, encoder_position: f64, current: f64) {
        self.predict(current);
        let e = encoder_position - self.position;
        self.innovation = e;
        self.position += self.l_position * e;
        self.speed += self.l_speed * e;
        self.bias += self.l_bias * e;
    }

    /// Estimated output position, rad.
    #[inline]
    pub fn position(&self) -> f64 {
        self.position
    }

    /// Estimated output speed, rad/s.
    #[inline]
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Estimated unmodelled acceleration (friction, load), rad/s².
    pub fn acceleration_bias(&self) -> f64 {
        self.bias
    }

    /// Last innovation θ_enc − θ⁻ (encoder minus prediction), rad.
    pub fn innovation(&self) -> f64 {
        self.innovation
    }

    /// Correction gains (l₁, l₂ in 1/s, l₃ in 1/s²).
    pub fn gains(&self) -> (f64, f64, f64) {
        (self.l_position, self.l_speed, self.l_bias)
    }

    /// RMS of the speed estimate's error (rad/s) caused by a white position error of RMS
    /// `position_rms` rad on every encoder reading (quantisation: Δ/√12): `position_rms`·‖h‖₂, h the
    /// impulse response from the encoder reading to ω̂, summed until it has decayed.
    pub fn speed_noise_rms(&self, position_rms: f64) -> f64 {
        let (l1, l2, l3, t) = (self.l_position, self.l_speed, self.l_bias, self.period);
        // Estimate driven by one unit impulse on the measurement at k = 0 (true state zero).
        let (mut th, mut om, mut b) = (l1, l2, l3);
        let mut sum = om * om;
        let p = (1.0 - l1).cbrt();
        let steps = (80.0 / (1.0 - p).max(1e-9)).min(1e7) as usize;
        for _ in 0..steps {
            let tp = th + om * t + 0.5 * b * t * t;
            let op = om + b * t;
            let e = -tp;
            th = tp + l1 * e;
            om = op + l2 * e;
            b += l3 * e;
            sum += om * om;
        }
        finite("speed noise", position_rms * sum.sqrt()).unwrap_or(f64::INFINITY)
    }
}
