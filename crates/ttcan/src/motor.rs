//! Plant models for simulation: brushed DC motor, gearbox, load, averaged H-bridge, encoder and
//! current sensor, discretised exactly for a duty cycle held over one PWM/current-loop period.
//!
//! Continuous model (motor shaft, SI units), state x = [i (A), ω_m (rad/s), θ_m (rad)]:
//!
//! ```text
//! L di/dt    = u − R i − Ke ω_m                    u = d · V_bus (averaged H-bridge, |d| ≤ d_max)
//! J dω_m/dt  = Kt i − b ω_m − τ_d                  J = J_rotor + J_gear + J_load / (η N²)
//! dθ_m/dt    = ω_m                                 b = b_motor + b_load / (η N²)
//! ```
//!
//! τ_d collects the Coulomb friction and the external load torque reflected to the motor shaft; it is
//! held constant over a step (its sign changes are handled by a stick/slip rule). With u and τ_d held,
//! the linear part is integrated exactly: x⁺ = Φ x + Γ [u, τ_d]ᵀ with Φ = e^{Ah} and
//! Γ = ∫₀ʰ e^{As} ds B, both read off the exponential of the augmented matrix [[A, B], [0, 0]]·h.
//! The electrical time constant L/R (0.1 ms for the RE 25) is shorter than a few control periods, so
//! an explicit Euler step at 20 kHz would be visibly wrong; this one is exact for the averaged bridge.
//!
//! Not modelled: PWM ripple and dead time, inductance saturation, winding temperature, gear backlash
//! and compliance, power-flow-dependent gear efficiency for the inertia (η divides the reflected load
//! inertia, as in maxon's own sizing rules).

use crate::error::{in_range, non_negative, positive, Result};
use crate::noise::Gaussian;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use ttkin::joint::Drive;
use ttkin::robots::drives::Friction;

/// No joint-side friction: the catalogue drives below are read for their motor values only.
pub(crate) const NO_JOINT_FRICTION: Friction = Friction {
    viscous: 0.0,
    coulomb: 0.0,
};

/// A datasheet value `what` of a drive, or the error that it is missing.
fn datasheet(what: &str, value: Option<f64>) -> Result<f64> {
    value.ok_or_else(|| crate::Error::InvalidParameter {
        what: format!("motor {what}"),
        value: f64::NAN,
        reason: "missing from the drive's datasheet".into(),
    })
}

/// Brushed DC motor parameters, SI units, motor shaft.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DcMotor {
    /// Terminal resistance, Ω.
    pub resistance: f64,
    /// Terminal inductance, H.
    pub inductance: f64,
    /// Torque constant, N·m/A.
    pub torque_constant: f64,
    /// Back-EMF constant, V·s/rad (equals the torque constant in SI units for an ideal motor).
    pub back_emf_constant: f64,
    /// Rotor inertia, kg·m².
    pub rotor_inertia: f64,
    /// Viscous friction, N·m·s/rad at the motor shaft.
    pub viscous_friction: f64,
    /// Coulomb (dry) friction, N·m at the motor shaft (also the static breakaway torque).
    pub coulomb_friction: f64,
}

impl DcMotor {
    /// maxon RE 25 (Ø25 mm, graphite brushes, 24 V winding), nominal catalogue values.
    ///
    /// R = 2.32 Ω, L = 0.238 mH, kM = 43.9 mN·m/A (speed constant 218 rpm/V, so Ke = kM in SI),
    /// rotor inertia 10.8 g·cm²; no-load current ≈ 25 mA at ≈ 5200 rpm, split here into 0.6 mN·m
    /// Coulomb and 1e-6 N·m·s/rad viscous friction. These are the values this crate was designed
    /// and tested with; check them against the current maxon datasheet before driving hardware.
    pub fn maxon_re25() -> Self {
        // The datasheet values are the RE 25 class drive's of the built-in robots (one source);
        // the no-load friction split is this model's own (the drive's friction is joint-side).
        let drive = ttkin::robots::drives::maxon_re25(1.0, 1.0, NO_JOINT_FRICTION);
        DcMotor {
            viscous_friction: 1.0e-6,
            coulomb_friction: 0.6e-3,
            ..DcMotor::from_drive(&drive).expect("the RE 25 class drive carries its datasheet")
        }
    }

    /// The motor of a joint's drive (`ttkin::joint::Drive`'s datasheet values, motor side):
    /// resistance, inductance, torque constant (= back-EMF constant in SI units) and rotor
    /// inertia, no friction (a drive's friction is joint-side). A value the drive lacks is an
    /// error naming it.
    pub fn from_drive(drive: &Drive) -> Result<Self> {
        let kt = datasheet("torque constant (N·m/A)", drive.torque_constant)?;
        Ok(DcMotor {
            resistance: datasheet("resistance (Ω)", drive.resistance)?,
            inductance: datasheet("inductance (H)", drive.inductance)?,
            torque_constant: kt,
            back_emf_constant: kt,
            rotor_inertia: drive.rotor_inertia,
            viscous_friction: 0.0,
            coulomb_friction: 0.0,
        })
    }

    /// Checks that every parameter is physical (positive R, L, Kt, Ke, inertia; non-negative friction).
    pub fn validate(&self) -> Result<()> {
        positive("motor resistance (Ω)", self.resistance)?;
        positive("motor inductance (H)", self.inductance)?;
        positive("motor torque constant (N·m/A)", self.torque_constant)?;
        positive("motor back-EMF constant (V·s/rad)", self.back_emf_constant)?;
        positive("motor rotor inertia (kg·m²)", self.rotor_inertia)?;
        non_negative("motor viscous friction (N·m·s/rad)", self.viscous_friction)?;
        non_negative("motor Coulomb friction (N·m)", self.coulomb_friction)?;
        Ok(())
    }

    /// Electrical time constant L/R, s.
    pub fn electrical_time_constant(&self) -> f64 {
        self.inductance / self.resistance
    }
}

/// Gearbox between the motor shaft and the joint (output), ω_motor = ratio · ω_output.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gearbox {
    /// Reduction ratio N (motor turns per output turn), > 0; 1 for a direct drive.
    pub ratio: f64,
    /// Efficiency η in (0, 1].
    pub efficiency: f64,
    /// Gearbox inertia seen at the motor shaft, kg·m².
    pub inertia: f64,
}

impl Gearbox {
    /// maxon GP 26 A planetary gearhead, 14:1 (two stages), 81 % efficiency, 0.4 g·cm² (catalogue values).
    pub fn maxon_gp26a_14() -> Self {
        Gearbox {
            ratio: 14.0,
            efficiency: 0.81,
            inertia: 0.4e-7,
        }
    }

    /// Checks ratio > 0, efficiency in (0, 1], inertia ≥ 0.
    pub fn validate(&self) -> Result<()> {
        positive("gear ratio", self.ratio)?;
        in_range("gear efficiency", self.efficiency, 0.0, 1.0)?;
        non_negative("gear inertia (kg·m²)", self.inertia)?;
        Ok(())
    }
}

/// Rigid load on the output shaft (a robot link about its joint axis).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Load {
    /// Load inertia about the output axis, kg·m².
    pub inertia: f64,
    /// Viscous friction at the output, N·m·s/rad.
    pub viscous_friction: f64,
}

impl Load {
    /// Checks inertia ≥ 0 and friction ≥ 0.
    pub fn validate(&self) -> Result<()> {
        non_negative("load inertia (kg·m²)", self.inertia)?;
        non_negative("load viscous friction (N·m·s/rad)", self.viscous_friction)?;
        Ok(())
    }
}

/// Everything the simulator and the controller need to know about one actuator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorModel {
    /// The motor.
    pub motor: DcMotor,
    /// The gearbox.
    pub gearbox: Gearbox,
    /// The load on the output shaft.
    pub load: Load,
    /// H-bridge supply voltage, V.
    pub bus_voltage: f64,
    /// Largest usable duty cycle magnitude in (0, 1] (bootstrap and current-sense windows).
    pub max_duty: f64,
    /// Encoder counts per motor revolution (after quadrature decoding), ≥ 4.
    pub encoder_counts_per_rev: u32,
    /// Standard deviation of the current-sense noise, A (simulation only).
    pub current_noise: f64,
}

/// Standard deviation of the simulated current-sense noise of a drive whose data names none, A:
/// 5 mA, about one LSB of a 12-bit current ADC over a ±10 A range (20 A / 4096 ≈ 4.9 mA).
pub const DEFAULT_CURRENT_NOISE: f64 = 0.005;

impl MotorModel {
    /// maxon RE 25 + GP 26 A 14:1 + 1024-CPT encoder (4096 counts/rev), 24 V bus, 1e-3 kg·m² load.
    pub fn maxon_re25_gp26() -> Self {
        let gearbox = Gearbox::maxon_gp26a_14();
        // bus and encoder from the RE 25 class drive of the built-in robots (one source)
        let drive = ttkin::robots::drives::maxon_re25(gearbox.ratio, gearbox.efficiency, NO_JOINT_FRICTION);
        MotorModel {
            motor: DcMotor::maxon_re25(),
            gearbox,
            load: Load {
                inertia: 1.0e-3,
                viscous_friction: 0.0,
            },
            bus_voltage: drive.bus_voltage.expect("the RE 25 class drive names its bus"),
            max_duty: 0.95,
            encoder_counts_per_rev: drive.encoder_counts.expect("the RE 25 class drive names its encoder"),
            current_noise: DEFAULT_CURRENT_NOISE,
        }
    }

    /// Checks every parameter; the error names the first non-physical one.
    pub fn validate(&self) -> Result<()> {
        self.motor.validate()?;
        self.gearbox.validate()?;
        self.load.validate()?;
        positive("bus voltage (V)", self.bus_voltage)?;
        in_range("max duty", self.max_duty, 0.0, 1.0)?;
        if self.encoder_counts_per_rev < 4 {
            return Err(crate::Error::InvalidParameter {
                what: "encoder counts per revolution".into(),
                value: self.encoder_counts_per_rev as f64,
                reason: "must be >= 4".into(),
            });
        }
        non_negative("current noise (A)", self.current_noise)?;
        Ok(())
    }

    /// Total inertia reflected to the motor shaft, kg·m²: J_rotor + J_gear + J_load/(η N²).
    pub fn motor_side_inertia(&self) -> f64 {
        let n = self.gearbox.ratio;
        self.motor.rotor_inertia + self.gearbox.inertia + self.load.inertia / (self.gearbox.efficiency * n * n)
    }

    /// Total viscous friction reflected to the motor shaft, N·m·s/rad.
    pub fn motor_side_viscous(&self) -> f64 {
        let n = self.gearbox.ratio;
        self.motor.viscous_friction + self.load.viscous_friction / (self.gearbox.efficiency * n * n)
    }

    /// Output acceleration per ampere, rad/s²/A: Kt / (J_motor_side · N).
    pub fn acceleration_per_amp(&self) -> f64 {
        self.motor.torque_constant / (self.motor_side_inertia() * self.gearbox.ratio)
    }

    /// Output angle per encoder count, rad.
    pub fn radians_per_count(&self) -> f64 {
        2.0 * PI / (self.encoder_counts_per_rev as f64 * self.gearbox.ratio)
    }

    /// Largest voltage the bridge can apply, V.
    pub fn max_voltage(&self) -> f64 {
        self.bus_voltage * self.max_duty
    }
}

/// What the drive electronics read in one sample: the things a real drive has, nothing else.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement {
    /// Measured motor current, A.
    pub current: f64,
    /// Encoder position, counts (motor shaft, after quadrature), any origin.
    pub encoder_counts: i64,
    /// Measured DC-bus voltage, V; `None` when the drive does not measure it (the nominal bus
    /// voltage is then assumed and the bus monitors are off).
    pub bus_voltage: Option<f64>,
}

/// Simulated actuator: state plus the exact discretisation for one step of `dt` seconds.
#[derive(Debug, Clone)]
pub struct Plant {
    model: MotorModel,
    dt: f64,
    phi: SMatrix<f64, 3, 3>,
    gamma: SMatrix<f64, 3, 2>,
    /// Current decay over one step with the rotor stuck (ω = 0): e^{−R dt / L}.
    stuck_decay: f64,
    state: SVector<f64, 3>,
    external_torque: f64,
    encoder_offset: i64,
    current_offset: f64,
    bus_voltage: f64,
    rng: Gaussian,
}

impl Plant {
    /// Builds the plant at rest (i = 0, ω = 0, θ = 0) for steps of `dt` seconds.
    pub fn new(model: &MotorModel, dt: f64) -> Result<Self> {
        model.validate()?;
        positive("plant time step (s)", dt)?;
        let (phi, gamma) = discretise(model, dt);
        if !(phi.iter().chain(gamma.iter()).all(|v| v.is_finite())) {
            // Rates such as R/L·dt = 1e296 (an inductance of 1e-300 H) overflow the exact step:
            // refused here rather than simulated as NaN currents.
            return Err(crate::Error::InvalidParameter {
                what: "motor inductance (H)".into(),
                value: model.motor.inductance,
                reason: format!(
                    "the exact step of {dt} s overflows (R/L·dt = {:e}, K/J·dt = {:e}): parameters this                      far apart cannot be simulated",
                    model.motor.resistance / model.motor.inductance * dt,
                    model.motor.torque_constant / model.motor_side_inertia() * dt
                ),
            });
        }
        Ok(Plant {
            model: *model,
            dt,
            phi,
            gamma,
            stuck_decay: (-model.motor.resistance * dt / model.motor.inductance).exp(),
            state: SVector::zeros(),
            external_torque: 0.0,
            encoder_offset: 0,
            current_offset: 0.0,
            bus_voltage: model.bus_voltage,
            rng: Gaussian::new(0x5eed_0007),
        })
    }

    /// Changes the load inertia about the output axis (kg·m², e.g. the joint's diagonal entry of a
    /// robot's mass matrix at the present configuration) and re-discretises; no allocation.
    /// Returns false and changes nothing for a negative or non-finite value.
    pub fn set_load_inertia(&mut self, inertia: f64) -> bool {
        if !(inertia.is_finite() && inertia >= 0.0) {
            return false;
        }
        self.model.load.inertia = inertia;
        (self.phi, self.gamma) = discretise(&self.model, self.dt);
        true
    }

    /// The model this plant simulates.
    pub fn model(&self) -> &MotorModel {
        &self.model
    }

    /// Step length, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Sets the external torque acting on the output shaft (gravity, contact, ...), N·m, positive
    /// in the direction of positive output rotation.
    pub fn set_external_torque(&mut self, torque: f64) {
        self.external_torque = if torque.is_finite() { torque } else { 0.0 };
    }

    /// Sets the output position (rad) and speed (rad/s), keeping the current; for initial conditions.
    pub fn set_output_state(&mut self, position: f64, speed: f64) {
        let n = self.model.gearbox.ratio;
        if position.is_finite() && speed.is_finite() {
            self.state[2] = position * n;
            self.state[1] = speed * n;
        }
    }

    /// Seeds the current-sense noise generator.
    pub fn seed_noise(&mut self, seed: u64) {
        self.rng = Gaussian::new(seed);
    }

    /// Fault injection: adds `counts` to every later encoder reading (a glitch, a lost index).
    pub fn inject_encoder_jump(&mut self, counts: i64) {
        self.encoder_offset = self.encoder_offset.saturating_add(counts);
    }

    /// Fault injection: adds `amps` to every later current reading (a shorted winding as seen by
    /// the current sense); 0 removes it.
    pub fn set_current_sense_offset(&mut self, amps: f64) {
        self.current_offset = if amps.is_finite() { amps } else { 0.0 };
    }

    /// True motor current, A.
    pub fn current(&self) -> f64 {
        self.state[0]
    }

    /// True output speed, rad/s.
    pub fn output_speed(&self) -> f64 {
        self.state[1] / self.model.gearbox.ratio
    }

    /// True output position, rad.
    pub fn output_position(&self) -> f64 {
        self.state[2] / self.model.gearbox.ratio
    }

    /// True motor speed, rad/s.
    pub fn motor_speed(&self) -> f64 {
        self.state[1]
    }

    /// What the drive reads now: noisy current, quantised encoder counts.
    pub fn measure(&mut self) -> Measurement {
        let noise = if self.model.current_noise > 0.0 {
            self.model.current_noise * self.rng.normal()
        } else {
            0.0
        };
        let counts = (self.state[2] * self.model.encoder_counts_per_rev as f64 / (2.0 * PI)).floor();
        // Saturating float-to-int conversion: no overflow even for absurd angles.
        Measurement {
            current: self.state[0] + noise + self.current_offset,
            encoder_counts: (counts as i64).saturating_add(self.encoder_offset),
            bus_voltage: Some(self.bus_voltage),
        }
    }

    /// Fault injection: the DC-bus voltage from now on, V (a sagging supply, regeneration).
    pub fn set_bus_voltage(&mut self, volts: f64) {
        if volts.is_finite() && volts >= 0.0 {
            self.bus_voltage = volts;
        }
    }

    /// Advances one step with the bridge switched off: an open winding. The free-wheeling diodes
    /// apply −V_bus·sign(i) while current flows (or while the back-EMF exceeds the bus); when the
    /// current reaches zero it stays there and the motor coasts.
    pub fn step_open(&mut self) {
        let i = self.state[0];
        let emf = self.model.motor.back_emf_constant * self.state[1];
        if i == 0.0 && emf.abs() <= self.bus_voltage {
            // No current: the voltage across the open winding balances the back-EMF.
            self.step_voltage(emf);
            self.state[0] = 0.0;
            return;
        }
        let dir = if i != 0.0 { i.signum() } else { -emf.signum() };
        self.step_voltage(-dir * self.bus_voltage);
        if self.state[0] * dir < 0.0 {
            self.state[0] = 0.0;
        }
    }

    /// Advances one step with the bridge duty `duty` (clamped to ±max_duty; NaN counts as 0),
    /// applied to the present bus voltage.
    pub fn step(&mut self, duty: f64) {
        let d = if duty.is_finite() {
            duty.clamp(-self.model.max_duty, self.model.max_duty)
        } else {
            0.0
        };
        self.step_voltage(d * self.bus_voltage);
    }

    fn step_voltage(&mut self, u: f64) {
        let m = &self.model.motor;
        let n = self.model.gearbox.ratio;
        let eta = self.model.gearbox.efficiency;
        let omega = self.state[1];
        // External torque at the motor shaft: the gearbox loses power in whichever direction it flows.
        let t_ext = self.external_torque / n;
        let t_ext = if t_ext * omega > 0.0 { t_ext * eta } else { t_ext / eta };
        let tc = m.coulomb_friction;
        if omega == 0.0 {
            let drive = m.torque_constant * self.state[0] + t_ext;
            if drive.abs() <= tc {
                // Stuck: friction balances the drive torque; only the current moves.
                let a = self.stuck_decay;
                self.state[0] = a * self.state[0] + (1.0 - a) * u / m.resistance;
                return;
            }
            let dir = drive.signum();
            self.advance(u, tc * dir - t_ext);
            if tc > 0.0 && self.state[1] * dir < 0.0 {
                self.state[1] = 0.0;
            }
        } else {
            let dir = omega.signum();
            self.advance(u, tc * dir - t_ext);
            if tc > 0.0 && self.state[1] * dir < 0.0 {
                // The speed crossed zero inside the step: stick at zero (the next step decides).
                self.state[1] = 0.0;
            }
        }
    }

    fn advance(&mut self, u: f64, tau_d: f64) {
        self.state = self.phi * self.state + self.gamma * SVector::<f64, 2>::new(u, tau_d);
    }
}

/// Φ = e^{A dt} and Γ = ∫₀^dt e^{As} ds B, read off the exponential of [[A, B], [0, 0]]·dt.
fn discretise(model: &MotorModel, dt: f64) -> (SMatrix<f64, 3, 3>, SMatrix<f64, 3, 2>) {
    let m = &model.motor;
    let j = model.motor_side_inertia();
    let b = model.motor_side_viscous();
    let mut aug = SMatrix::<f64, 5, 5>::zeros();
    aug[(0, 0)] = -m.resistance / m.inductance;
    aug[(0, 1)] = -m.back_emf_constant / m.inductance;
    aug[(1, 0)] = m.torque_constant / j;
    aug[(1, 1)] = -b / j;
    aug[(2, 1)] = 1.0;
    aug[(0, 3)] = 1.0 / m.inductance;
    aug[(1, 4)] = -1.0 / j;
    let e = (aug * dt).exp();
    (
        e.fixed_view::<3, 3>(0, 0).into_owned(),
        e.fixed_view::<3, 2>(0, 3).into_owned(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_re25_model_reads_the_catalogue_drive_and_keeps_its_values() {
        let m = MotorModel::maxon_re25_gp26();
        let d = &m.motor;
        // the values this crate was designed and tested with (module doc of DcMotor::maxon_re25)
        assert_eq!(
            (
                d.resistance,
                d.inductance,
                d.torque_constant,
                d.back_emf_constant,
                d.rotor_inertia
            ),
            (2.32, 0.238e-3, 43.9e-3, 43.9e-3, 10.8e-7)
        );
        assert_eq!((d.viscous_friction, d.coulomb_friction), (1.0e-6, 0.6e-3));
        assert_eq!(
            (m.gearbox.ratio, m.gearbox.efficiency, m.gearbox.inertia),
            (14.0, 0.81, 0.4e-7)
        );
        assert_eq!((m.bus_voltage, m.encoder_counts_per_rev), (24.0, 4096));
        m.validate().unwrap();
    }

    #[test]
    fn a_drive_without_its_datasheet_names_the_missing_value() {
        let e = DcMotor::from_drive(&Drive::geared(10.0)).unwrap_err().to_string();
        assert!(e.contains("torque constant") && e.contains("missing"), "{e}");
    }
}
