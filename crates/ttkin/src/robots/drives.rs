//! Catalogue-class drives of the built-in robots: motor, gearbox, encoder and bus of one joint as
//! a robot file's drive section carries them ([`Drive`], SI units, motor side).
//!
//! The values are typical datasheet values of the named motor families (maxon catalogue: RE 25,
//! RE 30, RE 40 pages; 400 W AC servo class: Yaskawa Σ-7 SGM7J-04 / Panasonic MINAS A6 MSMF04 as
//! a DC-equivalent motor, torque per ampere of the torque-producing current). They make sizing and
//! simulation plausible; check every value against the datasheet of the motor actually fitted
//! before driving hardware.

use std::f64::consts::PI;

use crate::joint::Drive;

/// rev/min → rad/s.
const RPM: f64 = 2.0 * PI / 60.0;

/// Joint-side friction of a drive: viscous b (N·m·s/rad or N·s/m) and Coulomb f_c (N·m or N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// Viscous coefficient b, joint side.
    pub viscous: f64,
    /// Coulomb level f_c, joint side.
    pub coulomb: f64,
}

/// A motor class's datasheet values, motor side, in the columns: rotor inertia (kg·m²), torque
/// constant (N·m/A), winding resistance (Ω) and inductance (H), nominal and peak current (A), top
/// speed (rpm), thermal resistances winding–housing and housing–ambient (K/W), thermal time
/// constants of winding and housing (s), winding temperature limit (°C), encoder counts per motor
/// turn, bus voltage (V).
type Datasheet = [f64; 14];

/// The motor of [`servo_400w`].
const SERVO_400W: Datasheet = [
    2.6e-5,
    0.45,
    2.3,
    6.0e-3,
    2.8,
    8.4,
    6000.0,
    1.2,
    3.4,
    60.0,
    1800.0,
    155.0,
    1_048_576.0,
    325.0,
];
/// The motor of [`maxon_re40`].
const MAXON_RE40: Datasheet = [
    1.34e-5, 60.3e-3, 1.16, 0.33e-3, 3.0, 9.0, 12_000.0, 1.93, 4.65, 41.6, 1120.0, 155.0, 4096.0, 48.0,
];
/// The motor of [`maxon_re30`].
const MAXON_RE30: Datasheet = [
    3.35e-6, 25.9e-3, 0.611, 0.119e-3, 3.44, 10.0, 12_000.0, 1.7, 6.0, 16.3, 714.0, 125.0, 4096.0, 24.0,
];
/// The motor of [`maxon_re25`].
const MAXON_RE25: Datasheet = [
    10.8e-7, 43.9e-3, 2.32, 0.238e-3, 1.2, 3.6, 14_000.0, 4.0, 13.2, 12.5, 700.0, 125.0, 4096.0, 24.0,
];

/// The drive of motor `m` behind a transmission of ratio `gear_ratio` (rad/rad or rad/m) and
/// `gear_efficiency`, with the joint-side `friction`.
fn fitted(m: &Datasheet, gear_ratio: f64, gear_efficiency: f64, friction: Friction) -> Drive {
    let [rotor_inertia, kt, r, l, i_nominal, i_peak, rpm, r_wh, r_ha, tau_w, tau_h, t_max, counts, u_bus] = *m;
    Drive {
        rotor_inertia,
        viscous: friction.viscous,
        coulomb: friction.coulomb,
        torque_constant: Some(kt),
        resistance: Some(r),
        inductance: Some(l),
        nominal_current: Some(i_nominal),
        peak_current: Some(i_peak),
        max_motor_speed: Some(rpm * RPM),
        thermal_resistance_winding_housing: Some(r_wh),
        thermal_resistance_housing_ambient: Some(r_ha),
        thermal_time_constant_winding: Some(tau_w),
        thermal_time_constant_housing: Some(tau_h),
        max_winding_temperature: Some(t_max),
        gear_efficiency: Some(gear_efficiency),
        encoder_counts: Some(counts as u32),
        bus_voltage: Some(u_bus),
        ..Drive::geared(gear_ratio)
    }
}

/// 400 W AC servo class (DC-equivalent), 325 V bus (rectified 230 V AC), 20-bit encoder, behind a
/// transmission of ratio `gear_ratio` (rad/rad or rad/m) and `gear_efficiency`: k_t 0.45 N·m/A
/// (1.27 N·m at 2.8 A rated), 8.4 A peak (drive limit, 3× rated), 2.3 Ω, 6 mH, rotor 2.6·10⁻⁵
/// kg·m², 6000 rpm, thermal 1.2 + 3.4 K/W, τ 60 s / 1800 s, 155 °C (class F).
pub fn servo_400w(gear_ratio: f64, gear_efficiency: f64, friction: Friction) -> Drive {
    fitted(&SERVO_400W, gear_ratio, gear_efficiency, friction)
}

/// maxon RE 40 class (Ø40 mm, graphite brushes, 150 W, 48 V winding), 48 V bus, 1024-CPT encoder
/// (4096 counts): k_t 60.3 mN·m/A, 3.0 A nominal, 9 A peak (drive limit), 1.16 Ω, 0.33 mH, rotor
/// 134 g·cm², 12 000 rpm, thermal 1.93 + 4.65 K/W, τ 41.6 s / 1120 s, 155 °C.
pub fn maxon_re40(gear_ratio: f64, gear_efficiency: f64, friction: Friction) -> Drive {
    fitted(&MAXON_RE40, gear_ratio, gear_efficiency, friction)
}

/// maxon RE 30 class (Ø30 mm, graphite brushes, 60 W, 24 V winding), 24 V bus, 1024-CPT encoder:
/// k_t 25.9 mN·m/A, 3.44 A nominal, 10 A peak (drive limit), 0.611 Ω, 0.119 mH, rotor
/// 33.5 g·cm², 12 000 rpm, thermal 1.7 + 6.0 K/W, τ 16.3 s / 714 s, 125 °C.
pub fn maxon_re30(gear_ratio: f64, gear_efficiency: f64, friction: Friction) -> Drive {
    fitted(&MAXON_RE30, gear_ratio, gear_efficiency, friction)
}

/// maxon RE 25 class (Ø25 mm, graphite brushes, 24 V winding), 24 V bus, 1024-CPT encoder: the
/// values of `ttcan`'s reference motor, k_t 43.9 mN·m/A, 1.2 A continuous, 3.6 A peak, 2.32 Ω,
/// 0.238 mH, rotor 10.8 g·cm², 14 000 rpm, thermal 4.0 + 13.2 K/W, τ 12.5 s / 700 s, 125 °C.
pub fn maxon_re25(gear_ratio: f64, gear_efficiency: f64, friction: Friction) -> Drive {
    fitted(&MAXON_RE25, gear_ratio, gear_efficiency, friction)
}

/// gantry6's drives, d1 … θ6: both belt axes a 400 W servo behind a 4:1 planetary on a Ø40 mm
/// pulley (G = 4/0.02 m = 200 rad/m, η 0.9); θ3, θ4 an RE 40 on a 50:1 three-stage planetary
/// (η 0.72); θ5 an RE 30 on 30:1 (η 0.75); θ6 an RE 25 on 30:1 (η 0.75). Joint friction as before
/// (estimates). Chosen so that the demo stroke with gravity passes `ttcan::sizing`.
pub fn gantry6() -> Vec<Drive> {
    let f = |viscous, coulomb| Friction { viscous, coulomb };
    vec![
        servo_400w(200.0, 0.9, f(20.0, 15.0)),
        servo_400w(200.0, 0.9, f(15.0, 10.0)),
        maxon_re40(50.0, 0.72, f(0.05, 0.3)),
        maxon_re40(50.0, 0.72, f(0.05, 0.3)),
        maxon_re30(30.0, 0.75, f(0.02, 0.1)),
        maxon_re25(30.0, 0.75, f(0.01, 0.05)),
    ]
}
