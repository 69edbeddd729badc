//! The winding/housing thermal model (issue 10): steady state against the datasheet relation,
//! time constants, derating monotone and continuous, bad constants rejected naming the field.

use proptest::prelude::*;
use ttcan::thermal::{ThermalModel, ThermalState, COPPER_ALPHA};

#[test]
fn the_continuous_current_holds_the_winding_at_its_largest_temperature() {
    let m = ThermalModel::maxon_re25();
    let i = m.continuous_current(2.32);
    let mut s = ThermalState::new(&m, 2.32).unwrap();
    for _ in 0..200_000 {
        s.step(i, 0.05); // 10 000 s: many housing time constants
    }
    println!(
        "continuous current {i:.3} A → winding {:.2} °C",
        s.winding_temperature()
    );
    assert!((s.winding_temperature() - m.max_winding_temperature).abs() < 0.05);
    // Steady state: housing = ambient + P R_ha, winding = housing + P R_wh, P = R(T_w) i².
    let p = 2.32 * (1.0 + COPPER_ALPHA * (s.winding_temperature() - 25.0)) * i * i;
    assert!((s.housing_temperature() - (25.0 + p * m.housing_ambient_resistance)).abs() < 0.05);
}

#[test]
fn the_winding_heats_with_its_own_time_constant_first() {
    // A current step: after τ_w the winding has covered ≈ 63 % of its rise over the (still cold)
    // housing; the housing has barely moved.
    let m = ThermalModel::maxon_re25();
    let mut s = ThermalState::new(&m, 2.32).unwrap();
    let i = 2.0;
    let dt = 1e-3;
    for _ in 0..(m.winding_time_constant / dt) as usize {
        s.step(i, dt);
    }
    let rise = s.winding_temperature() - s.housing_temperature();
    let p = 2.32 * i * i;
    let full = p * m.winding_housing_resistance;
    assert!(rise > 0.55 * full && rise < 0.75 * full, "rise {rise} K of {full} K");
    assert!(s.housing_temperature() - 25.0 < 0.1 * (s.winding_temperature() - 25.0));
}

proptest! {
    #[test]
    fn derating_is_monotone_and_continuous(t1 in 20.0f64..140.0, dt in 0.0f64..5.0) {
        let m = ThermalModel::maxon_re25();
        let mut a = ThermalState::new(&m, 2.32).unwrap();
        let mut b = a;
        a.set_temperatures(t1, 40.0);
        b.set_temperatures(t1 + dt, 40.0);
        let (la, lb) = (a.limit(3.6, 1.2), b.limit(3.6, 1.2));
        prop_assert!(lb <= la + 1e-12);
        // Lipschitz: at most (3.6 − 1.2)/20 A per K in the band, 1.2/10 above it.
        prop_assert!(la - lb <= 0.121 * dt + 1e-12);
        prop_assert!((0.0..=3.6).contains(&la));
    }
}

#[test]
fn missing_or_bad_thermal_constants_are_rejected_naming_the_field() {
    type Case = (fn(&mut ThermalModel), &'static str);
    let cases: [Case; 5] = [
        (|m| m.winding_time_constant = 0.0, "thermal time constant winding"),
        (|m| m.housing_time_constant = f64::NAN, "thermal time constant housing"),
        (
            |m| m.winding_housing_resistance = -1.0,
            "thermal resistance winding-housing",
        ),
        (
            |m| m.housing_ambient_resistance = 0.0,
            "thermal resistance housing-ambient",
        ),
        (|m| m.max_winding_temperature = 30.0, "max winding temperature"),
    ];
    for (f, name) in cases {
        let mut m = ThermalModel::maxon_re25();
        f(&mut m);
        let e = ThermalState::new(&m, 2.32).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
        let mut c = ttcan::AxisConfig::new(ttcan::MotorModel::maxon_re25_gp26());
        c.thermal = m;
        let e = ttcan::Axis::new(&c).unwrap_err().to_string();
        assert!(e.contains(name), "axis: {e}");
    }
}
