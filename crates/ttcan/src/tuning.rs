//! PI gains from motor parameters and target bandwidths, and the bandwidths and stability margins
//! that result, computed on the loop transfer functions (not quoted from rules of thumb).
//!
//! - Current loop, **discrete pole-zero cancellation**. The voltage-to-current plant with a duty held
//!   over one period T (back-EMF compensated) is exactly P(z) = ((1 − a)/R) / (z − a), a = e^{−RT/L}.
//!   The PI C(z) = Kp + Ki T/(z − 1) has its zero at 1 − Ki T/Kp; putting it on a gives the open loop
//!   b/(z − 1) with b = Kp (1 − a)/R, and the closed loop b/(z − (1 − b)): first order, no overshoot.
//!   b = 1 − e^{−ω_c T} places its pole where a continuous loop of bandwidth ω_c would have it, so
//!   Kp = R (1 − e^{−ω_c T})/(1 − a) and Ki = Kp (1 − a)/T (→ L ω_c and R ω_c as T → 0).
//! - Speed loop, **symmetric optimum** (Kessler). The plant seen by the speed PI is
//!   K_acc/s · 1/(1 + T_σ s), where T_σ lumps the small lags: the closed current loop 1/ω_c,i, the
//!   output filter T_f, the hold of the current reference T_s/2, the speed estimate and the current
//!   loop's hold T_c/2. The speed estimate is the tracking observer of [`crate::observer`]: with its
//!   acceleration input the current-to-estimate path is k_acc/s exactly, so it adds only its own
//!   period T_c; without it the PLL's low-frequency group delay 2/ω_o is added (ω_o its bandwidth).
//!   With a ≥ 2: Kp = 1/(a K_acc T_σ), T_i = a² T_σ,
//!   crossover 1/(a T_σ), phase margin atan((a² − 1)/(2a)) (36.9° for a = 2, 53.1° for a = 3).
//!   The reference low-pass 1/(1 + a T_σ s) takes the edge off the PI zero's overshoot.
//! - Position loop: P gain Kp = ω_c,speed / r (r = 4 by default), velocity and acceleration
//!   feedforward make the tracking independent of this gain to first order.
//!
//! - Quantisation ripple: the encoder's resolution Δ (rad per count) is a white position error of
//!   RMS Δ/√12 on every reading; through the observer it becomes a speed-estimate error of RMS
//!   Δω ([`crate::observer::TrackingObserver::speed_noise_rms`]) and through the speed gain a
//!   current-reference ripple Kp·Δω, reported as [`CascadeTuning::quantisation_ripple_rms`]. The
//!   axis refuses a configuration whose ripple exceeds a stated share of the continuous current.
//!
//! The reported margins are evaluated on the full loop models (discrete current loop; speed and
//! position loops with their filters and delays), by a logarithmic frequency sweep.

use crate::error::{at_least, positive, sixth_of_rate, Error, Result};
use crate::motor::MotorModel;
use crate::observer::TrackingObserver;
use nalgebra::Complex;
use std::f64::consts::PI;

/// Gains of one loop and what they achieve.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LoopReport {
    /// Proportional gain (V/A, A per rad/s, or 1/s for the position loop).
    pub kp: f64,
    /// Integral gain, 1/s times the unit of `kp` (0 for a P controller).
    pub ki: f64,
    /// Gain crossover frequency of the open loop, Hz.
    pub crossover_hz: f64,
    /// Phase margin at the crossover, degrees.
    pub phase_margin_deg: f64,
    /// Closed-loop −3 dB bandwidth, Hz.
    pub bandwidth_hz: f64,
}

/// Gains and reports of the whole cascade (serialised for reports: `current.kp`, …).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CascadeTuning {
    /// Current loop (V/A).
    pub current: LoopReport,
    /// Speed loop (A per output rad/s).
    pub speed: LoopReport,
    /// Position loop (1/s).
    pub position: LoopReport,
    /// Lumped small time constant T_σ of the speed loop, s.
    pub t_sigma: f64,
    /// Default speed reference filter cut-off 1/(2π a T_σ), Hz.
    pub speed_reference_filter_hz: f64,
    /// RMS of the speed estimate's error from encoder quantisation, output rad/s.
    pub speed_noise_rms: f64,
    /// RMS ripple that encoder quantisation puts on the current reference, Kp·Δω, A.
    pub quantisation_ripple_rms: f64,
}

/// Targets for [`tune_cascade`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TuningTargets {
    /// Current-loop closed-loop bandwidth, Hz (at most a sixth of the current-loop rate).
    pub current_bandwidth_hz: f64,
    /// Symmetric-optimum factor a (≥ 2; larger is slower and better damped).
    pub speed_symmetric_optimum: f64,
    /// Speed-loop output filter cut-off, Hz (may be infinite: no filter).
    pub speed_output_filter_hz: f64,
    /// Ratio of the speed-loop crossover to the position gain (≥ 2).
    pub position_ratio: f64,
    /// Bandwidth of the tracking observer that estimates position and speed, Hz (at most a sixth
    /// of the current-loop rate): higher follows unmodelled torques faster and lets more encoder
    /// quantisation through.
    pub observer_bandwidth_hz: f64,
    /// Feed the measured current × k_acc to the observer as its acceleration input (default on:
    /// a single axis with a matched model gets an estimate without lag, so the speed loop keeps
    /// its gain and a 30 Hz observer suffices). It trusts the axis' own model of its
    /// acceleration, which a joint inertially coupled to others does not have (their torques reach
    /// it through M⁻¹'s off-diagonal terms): on gantry6 with it on, θ4 and θ5 limit-cycle against
    /// each other at the current limit, so [`crate::coupled`] switches it off (PLL alone, 100 Hz).
    pub observer_acceleration_input: bool,
}

impl Default for TuningTargets {
    fn default() -> Self {
        TuningTargets {
            current_bandwidth_hz: 1000.0,
            speed_symmetric_optimum: 3.0,
            speed_output_filter_hz: 1000.0,
            position_ratio: 4.0,
            observer_bandwidth_hz: 30.0,
            observer_acceleration_input: true,
        }
    }
}

/// Current-loop gains by discrete pole-zero cancellation: (Kp V/A, Ki V/(A·s)).
pub fn current_gains(model: &MotorModel, period: f64, bandwidth_hz: f64) -> Result<(f64, f64)> {
    model.validate()?;
    positive("current loop period (s)", period)?;
    positive("current loop bandwidth (Hz)", bandwidth_hz)?;
    sixth_of_rate("current loop bandwidth (Hz)", bandwidth_hz, period)?;
    let m = &model.motor;
    let a = (-m.resistance * period / m.inductance).exp();
    let b = 1.0 - (-2.0 * PI * bandwidth_hz * period).exp();
    let kp = m.resistance * b / (1.0 - a);
    Ok((kp, kp * (1.0 - a) / period))
}

/// Tunes the three loops for `model` at the given loop periods (s) and reports what they achieve.
pub fn tune_cascade(model: &MotorModel, periods: [f64; 3], targets: &TuningTargets) -> Result<CascadeTuning> {
    let [tc, ts, tp] = periods;
    positive("speed loop period (s)", ts)?;
    positive("position loop period (s)", tp)?;
    let (kpc, kic) = current_gains(model, tc, targets.current_bandwidth_hz)?;
    let a_so = targets.speed_symmetric_optimum;
    at_least("speed symmetric optimum factor", a_so, 2.0)?;
    let f_out = targets.speed_output_filter_hz;
    if f_out.is_nan() || f_out <= 0.0 {
        return Err(Error::InvalidParameter {
            what: "speed output filter (Hz)".into(),
            value: f_out,
            reason: "must be > 0 (infinite: no filter)".into(),
        });
    }
    let k_acc = model.acceleration_per_amp();
    let observer = TrackingObserver::new(
        targets.observer_bandwidth_hz,
        tc,
        if targets.observer_acceleration_input {
            k_acc
        } else {
            0.0
        },
    )?;
    let r_pos = targets.position_ratio;
    at_least("position ratio", r_pos, 2.0)?;

    // Current loop, discrete.
    let m = &model.motor;
    let a = (-m.resistance * tc / m.inductance).exp();
    let plant_gain = (1.0 - a) / m.resistance;
    let current_open = |w: f64| {
        let z = Complex::from_polar(1.0, w * tc);
        let c = Complex::new(kpc, 0.0) + kic * tc / (z - 1.0);
        c * plant_gain / (z - a)
    };
    let current_margins = margins(&current_open, 1.0, PI / tc);

    // Speed loop, continuous with lumped delays.
    let w_ci = 2.0 * PI * targets.current_bandwidth_hz;
    let t_f = if f_out.is_infinite() {
        0.0
    } else {
        1.0 / (2.0 * PI * f_out)
    };
    let t_observer = if targets.observer_acceleration_input {
        tc
    } else {
        tc + 2.0 / (2.0 * PI * targets.observer_bandwidth_hz)
    };
    let t_d = 0.5 * ts + t_observer + 0.5 * tc;
    let t_sigma = 1.0 / w_ci + t_f + t_d;
    let kps = 1.0 / (a_so * k_acc * t_sigma);
    let ti = a_so * a_so * t_sigma;
    let kis = kps / ti;
    let jw = |w: f64| Complex::new(0.0, w);
    let speed_open = |w: f64| {
        let s = jw(w);
        let c = kps * (1.0 + 1.0 / (s * ti));
        let lags = (1.0 + s * t_f) * (1.0 + s / w_ci);
        c * k_acc / s / lags * Complex::from_polar(1.0, -w * t_d)
    };
    let speed_margins = margins(&speed_open, 0.1, PI / tc);

    // Position loop around the closed speed loop (with its reference filter).
    let w_cs = speed_margins.crossover_hz * 2.0 * PI;
    let kpp = w_cs / r_pos;
    let t_r = a_so * t_sigma;
    let position_open = |w: f64| {
        let s = jw(w);
        let l = speed_open(w);
        let closed_speed = l / (1.0 + l) / (1.0 + s * t_r);
        kpp / s * closed_speed * Complex::from_polar(1.0, -w * 0.5 * tp)
    };
    let position_margins = margins(&position_open, 0.01, PI / tc);
    let speed_noise_rms = observer.speed_noise_rms(model.radians_per_count() / 12f64.sqrt());

    Ok(CascadeTuning {
        current: current_margins.report(kpc, kic),
        speed: speed_margins.report(kps, kis),
        position: position_margins.report(kpp, 0.0),
        t_sigma,
        speed_reference_filter_hz: 1.0 / (2.0 * PI * t_r),
        speed_noise_rms,
        quantisation_ripple_rms: kps * speed_noise_rms,
    })
}

/// Crossover, phase margin and closed-loop bandwidth of an open loop L(jω), by a log sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Margins {
    crossover_hz: f64,
    phase_margin_deg: f64,
    bandwidth_hz: f64,
}

impl Margins {
    fn report(self, kp: f64, ki: f64) -> LoopReport {
        LoopReport {
            kp,
            ki,
            crossover_hz: self.crossover_hz,
            phase_margin_deg: self.phase_margin_deg,
            bandwidth_hz: self.bandwidth_hz,
        }
    }
}

fn margins(open: &dyn Fn(f64) -> Complex<f64>, w_lo: f64, w_hi: f64) -> Margins {
    const STEPS: usize = 4000;
    let ratio = (w_hi / w_lo).ln() / STEPS as f64;
    let mut crossover = f64::NAN;
    let mut pm = f64::NAN;
    let mut bandwidth = f64::NAN;
    let mut phase_prev = open(w_lo).arg();
    let mut phase = phase_prev;
    for k in 1..=STEPS {
        let w = w_lo * (ratio * k as f64).exp();
        let l = open(w);
        // Unwrap the phase along the sweep.
        let mut p = l.arg();
        while p - phase_prev > PI {
            p -= 2.0 * PI;
        }
        while p - phase_prev < -PI {
            p += 2.0 * PI;
        }
        phase += p - phase_prev;
        phase_prev = p;
        if crossover.is_nan() && l.norm() < 1.0 {
            crossover = w;
            pm = 180.0 + phase.to_degrees();
        }
        if bandwidth.is_nan() && (l / (1.0 + l)).norm() < std::f64::consts::FRAC_1_SQRT_2 {
            bandwidth = w;
        }
    }
    Margins {
        crossover_hz: crossover / (2.0 * PI),
        phase_margin_deg: pm,
        bandwidth_hz: bandwidth / (2.0 * PI),
    }
}
