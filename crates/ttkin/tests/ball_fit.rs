//! The ball-model calibration (`ttkin::ball::fit`) on synthetic flights with known constants:
//! it recovers them within their reported uncertainty, the period and bounce-height estimators,
//! the split, and the prediction error's definition.

use ttkin::ball::fit::{
    bounce_level, calibrate, estimate_period, experiment, held_out, prediction_error, segment, Bounce, FitModel,
    FitOptions, Recording, SpinPrior,
};
use ttkin::ball::{BallModel, BallState};

fn truth() -> FitModel {
    FitModel {
        model: BallModel {
            k_drag: 0.125,
            k_magnus: 0.0018,
            table_restitution: 0.91,
            table_friction: 0.3,
            ..BallModel::default()
        },
        bounce: Bounce::Impulse,
        surface: -0.44,
        period: 0.0105,
    }
}

/// Gun-like flights: launched upward from y ≈ 3 m toward −y, one bounce, noise σ (m).
fn flights(n: usize, sigma: f64, seed: u64) -> Vec<Recording> {
    let mut rng = fastrand::Rng::with_seed(seed);
    let tm = truth();
    (0..n)
        .map(|i| {
            let s0 = BallState::new(
                0.0,
                [0.8 + 0.2 * rng.f64(), 3.0, 0.1 + 0.05 * rng.f64()],
                [0.4 * (rng.f64() - 0.5), -4.0 - rng.f64(), 2.0 + 0.8 * rng.f64()],
                [
                    40.0 * (rng.f64() - 0.5),
                    40.0 + 40.0 * rng.f64(),
                    20.0 * (rng.f64() - 0.5),
                ],
            );
            let frames = 100;
            let path = tm.path(&s0, frames, 0.001);
            let noise = |rng: &mut fastrand::Rng| {
                let u: f64 = rng.f64().max(1e-300);
                sigma * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * rng.f64()).cos()
            };
            let positions: Vec<[f64; 3]> = path
                .iter()
                .map(|p| [p.x + noise(&mut rng), p.y + noise(&mut rng), p.z + noise(&mut rng)])
                .collect();
            // Velocities by central differences of the exact path (the period estimator's input).
            let fine = tm.path(&s0, frames + 1, 0.001);
            let velocities: Vec<[f64; 3]> = (0..frames)
                .map(|k| {
                    let a = if k == 0 { fine[0] } else { fine[k - 1] };
                    let b = fine[k + 1];
                    let dt = if k == 0 { tm.period } else { 2.0 * tm.period };
                    ((b - a) / dt).into()
                })
                .collect();
            Recording {
                name: format!("f{i:02}"),
                positions,
                velocities,
            }
        })
        .collect()
}

#[test]
fn recovers_known_constants_within_reported_uncertainty() {
    let recs = flights(10, 0.002, 7);
    let level = bounce_level(&recs).unwrap();
    assert!(recs.iter().all(|r| segment(r, level, 0.05).is_some()));
    let tm = truth();
    let start = FitModel {
        model: BallModel {
            k_drag: 0.14,
            k_magnus: 0.0012,
            table_restitution: 0.95,
            ..tm.model
        },
        surface: level - 0.02 - 0.005,
        period: 0.0107,
        ..tm
    };
    // Friction fixed: with these spins every bounce rolls, so μ is not identified (tested below).
    let opts = FitOptions {
        free: [true, true, true, false, true, true],
        iterations: 20,
        step: 0.002,
        ..FitOptions::default()
    };
    let cal = calibrate(&recs, &start, &opts).unwrap();
    let want = [tm.model.k_drag, tm.model.k_magnus, 0.91, 0.3, tm.surface, tm.period];
    for j in [0, 1, 2, 4, 5] {
        let err = (cal.globals[j] - want[j]).abs();
        assert!(
            err <= 5.0 * cal.std[j] && cal.std[j].is_finite(),
            "global {j}: {} vs {} (std {})",
            cal.globals[j],
            want[j],
            cal.std[j]
        );
    }
    // Tight in absolute terms too: the recovery is not a wide error bar.
    assert!((cal.globals[0] - 0.125).abs() < 0.005);
    assert!((cal.globals[1] - 0.0018).abs() < 0.0004);
    assert!((cal.globals[2] - 0.91).abs() < 0.01);
    assert!((cal.sigma - 0.002).abs() < 0.0005, "sigma {}", cal.sigma);
    assert!(cal.std[3].is_nan());
    assert!(cal.flights.iter().all(|f| f.friction_to_roll < 0.3));
}

#[test]
fn friction_is_not_identified_when_bounces_roll_and_is_when_they_slide() {
    let recs = flights(6, 0.002, 3);
    let tm = truth();
    let opts = FitOptions {
        iterations: 15,
        ..FitOptions::default()
    };
    let cal = calibrate(&recs, &tm, &opts).unwrap();
    assert!(cal.std[3].is_nan(), "rolling bounces: μ has no column");
    // Low friction: the bounces slide and μ is estimated.
    let slide = FitModel {
        model: BallModel {
            table_friction: 0.08,
            ..tm.model
        },
        ..tm
    };
    let mut rng = fastrand::Rng::with_seed(5);
    let recs: Vec<Recording> = (0..6)
        .map(|i| {
            let s0 = BallState::new(0.0, [0.9, 3.0, 0.12], [0.1, -4.5 - rng.f64(), 2.4], [0.0, 50.0, 0.0]);
            Recording {
                name: format!("s{i}"),
                positions: slide.path(&s0, 90, 0.001).iter().map(|p| (*p).into()).collect(),
                velocities: Vec::new(),
            }
        })
        .collect();
    let start = FitModel {
        model: BallModel {
            table_friction: 0.12,
            ..tm.model
        },
        ..tm
    };
    let cal = calibrate(&recs, &start, &opts).unwrap();
    assert!((cal.globals[3] - 0.08).abs() < 0.005, "μ {}", cal.globals[3]);
    assert!(cal.std[3].is_finite());
}

#[test]
fn period_and_bounce_level_from_the_data() {
    let recs = flights(8, 0.0, 1);
    let p = estimate_period(&recs).unwrap();
    assert!((p - 0.0105).abs() < 2e-4, "period {p}");
    let level = bounce_level(&recs).unwrap();
    // The lowest frame lies above the contact height (surface + r), within one frame's travel.
    let contact = -0.44 + 0.02;
    assert!(level >= contact && level < contact + 0.04, "level {level}");
    let none = Recording {
        name: "x".into(),
        positions: vec![[0.0, 0.0, 1.0]; 10],
        velocities: Vec::new(),
    };
    assert!(estimate_period(std::slice::from_ref(&none)).is_err());
    assert!(bounce_level(&[none]).is_err());
}

#[test]
fn split_holds_out_every_fourth_name_in_sorted_order() {
    let names = ["d", "a", "c", "b", "h", "e", "g", "f"];
    let h = held_out(&names);
    let out: Vec<&str> = names.iter().zip(&h).filter(|(_, &x)| x).map(|(n, _)| *n).collect();
    assert_eq!(out, vec!["d", "h"]);
}

#[test]
fn prediction_error_is_zero_for_the_true_model_without_noise_and_grows_with_a_wrong_one() {
    let tm = truth();
    let s0 = BallState::new(0.0, [0.9, 3.0, 0.12], [0.0, -4.5, 2.4], [0.0, 50.0, 0.0]);
    let rec = Recording {
        name: "t".into(),
        positions: tm.path(&s0, 100, 0.001).iter().map(|p| (*p).into()).collect(),
        velocities: Vec::new(),
    };
    let level = bounce_level(std::slice::from_ref(&rec)).unwrap();
    // The spin lies along the flight (−y, the first flight axis): no Magnus force, seen only
    // through the bounce, so the prior carries it (in flight axes: −50 along the flight).
    let prior = SpinPrior {
        mean: [-50.0, 0.0, 0.0],
        std: [1.0, 10.0, 10.0],
    };
    let opts = FitOptions::default();
    let e = prediction_error(&rec, &tm, 25, level, &prior, &opts).unwrap();
    assert!(e.rms_after_bounce < 2e-3, "{e:?}");
    let wrong = FitModel {
        model: BallModel {
            table_restitution: 0.8,
            ..tm.model
        },
        ..tm
    };
    let e2 = prediction_error(&rec, &wrong, 25, level, &prior, &opts).unwrap();
    assert!(e2.rms_after_bounce > 10.0 * e.rms_after_bounce.max(1e-3));
    assert!(e2.max >= e2.rms && e2.max >= e2.rms_after_bounce);
    // With the along-flight spin's prior wrong the bounce is mispredicted even with the true model.
    let blind = SpinPrior {
        mean: [0.0; 3],
        std: [1.0, 10.0, 10.0],
    };
    let e3 = prediction_error(&rec, &tm, 25, level, &blind, &opts).unwrap();
    assert!(e3.rms_after_bounce > 0.05, "{e3:?}");
    // A window reaching the bounce is refused.
    assert!(prediction_error(&rec, &tm, 90, level, &prior, &opts).is_none());
}

/// The experiment's report (its serde form) has the documented records: globals keyed by name,
/// one record per fitted flight and per model, paths as rows of 3; the recordings come from
/// parallel columns, whose counts must agree.
#[test]
fn experiment_report_and_recordings_from_columns() {
    let recs = flights(8, 0.001, 3);
    let names: Vec<String> = recs.iter().map(|r| r.name.clone()).collect();
    let pos: Vec<Vec<[f64; 3]>> = recs.iter().map(|r| r.positions.clone()).collect();
    let again = Recording::from_columns(names.clone(), pos.clone(), None).unwrap();
    assert_eq!(again.len(), recs.len());
    assert_eq!(again[2].positions, recs[2].positions);
    assert!(again[2].velocities.is_empty());
    assert!(Recording::from_columns(names[..3].to_vec(), pos.clone(), None).is_err());
    assert!(Recording::from_columns(names.clone(), pos.clone(), Some(vec![Vec::new()])).is_err());
    let e = experiment(&recs, 20, None, &FitOptions::default()).unwrap();
    let v = toml::Value::try_from(&e).unwrap();
    let cal = &v["calibration"];
    assert_eq!(cal["globals"]["k_drag"].as_float(), Some(e.calibration.globals[0]));
    assert_eq!(cal["correlation"].as_array().unwrap().len(), 6);
    assert_eq!(cal["flights"].as_array().unwrap().len(), e.calibration.flights.len());
    assert_eq!(cal["flights"][0]["state"].as_array().unwrap().len(), 10);
    let comps = v["comparisons"].as_array().unwrap();
    assert_eq!(comps.len(), e.comparisons.len());
    assert_eq!(comps[0]["name"].as_str(), Some(e.comparisons[0].name.as_str()));
    let err = &comps[0]["errors"][0];
    assert_eq!(err["index"].as_integer(), Some(e.comparisons[0].errors[0].0 as i64));
    assert_eq!(err["path"][0].as_array().unwrap().len(), 3);
}

/// Issue 29: a frame period no camera has (1e300 s ran for hours) and a window no flight can use
/// are refused; a period far from the data's (twice the true one: the ball then rolls on the
/// plane for most of a flight, which bounced without end before) ends in a plain fit.
#[test]
fn experiment_refuses_unusable_periods_and_windows_and_ends_with_a_wrong_period() {
    let recs = flights(8, 0.001, 3);
    let opts = FitOptions::default();
    for p in [1e300, 0.5, 1e-9, -0.01, f64::NAN] {
        let e = experiment(&recs, 20, Some(p), &opts).unwrap_err().to_string();
        assert!(e.starts_with("period:") && e.contains("camera frame period"), "{e}");
    }
    let e = experiment(&recs, 4, None, &opts).unwrap_err().to_string();
    assert!(e.starts_with("window:") && e.contains("at least 5"), "{e}");
    let period = truth().period;
    assert!(experiment(&recs, 20, Some(2.0 * period), &opts).is_ok());
}
