//! The cheap bounds that let the hit planner skip exact extrema: they contain the exact values,
//! and the bounded limit ratio is the exact one whenever it matters.

use proptest::prelude::*;
use ttkin::traj::duration::{quintic_limit_ratio, quintic_limit_ratio_above, quintic_limit_ratio_below};
use ttkin::traj::{poly, JointState, JointTrajectory, KinematicLimits};

fn vecs(n: usize, r: f64) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-r..r, n)
}

fn state(q: Vec<f64>, qd: Vec<f64>, qdd: Vec<f64>) -> JointState {
    JointState { q, qd, qdd }
}

/// Start (moving, accelerating) and end (moving, no acceleration) states of a 6-joint quintic
/// inside and around the limits of [`limits`].
fn stroke_ends() -> impl Strategy<Value = (JointState, JointState)> {
    (vecs(6, 2.0), vecs(6, 2.0), vecs(6, 3.0), vecs(6, 3.0), vecs(6, 5.0))
        .prop_map(|(q0, q1, v0, v1, a0)| (state(q0, v0, a0), state(q1, v1, vec![0.0; 6])))
}

/// The 6-joint velocity, acceleration and jerk limits the ratio tests use.
fn limits() -> KinematicLimits {
    KinematicLimits::new(&[2.0; 6], &[20.0; 6], &[400.0; 6]).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn bounds_contain_the_exact_range(c in vecs(6, 50.0), tf in 0.01..3.0f64) {
        let c: poly::Coeffs = c.try_into().unwrap();
        let ((_, lo), (_, hi)) = poly::min_max(&c, tf);
        let (blo, bhi) = poly::bounds(&c, tf);
        prop_assert!(blo <= lo && bhi >= hi, "bounds [{blo}, {bhi}] miss range [{lo}, {hi}]");
        let (_, peak) = poly::max_abs(&c, tf);
        prop_assert!(poly::bound_abs(&c, tf) >= peak.abs());
    }

    #[test]
    fn joint_position_bounds_contain_the_exact_range(
        q0 in vecs(3, 2.0), q1 in vecs(3, 2.0), v0 in vecs(3, 3.0), v1 in vecs(3, 3.0), t in 0.05..2.0f64,
    ) {
        let traj = JointTrajectory::quintic_between(
            &state(q0, v0, vec![0.0; 3]),
            &state(q1, v1, vec![0.0; 3]),
            t,
        )
        .unwrap();
        let exact = traj.position_range();
        for (j, (lo, hi)) in exact.iter().enumerate() {
            let (blo, bhi) = traj.joint_position_bounds(j);
            prop_assert!(blo <= lo.value && bhi >= hi.value);
            prop_assert_eq!((lo.value, hi.value), {
                let (l, h) = traj.joint_position_range(j);
                (l.value, h.value)
            });
        }
    }

    #[test]
    fn ratio_above_is_the_exact_ratio_when_it_exceeds_the_floor(
        (s, e) in stroke_ends(), t in 0.05..2.0f64, floor in 0.0..3.0f64,
    ) {
        let lim = limits();
        let exact = quintic_limit_ratio(&s, &e, t, &lim);
        let above = quintic_limit_ratio_above(&s, &e, t, &lim, floor);
        if exact > floor {
            prop_assert_eq!(above.to_bits(), exact.to_bits());
        } else {
            prop_assert!(above <= floor, "{above} above the floor {floor} while the exact ratio is {exact}");
        }
    }

    #[test]
    fn ratio_below_is_the_exact_ratio_when_it_is_under_the_ceiling(
        (s, e) in stroke_ends(), t in 0.05..2.0f64, ceiling in 0.0..3.0f64,
    ) {
        let lim = limits();
        let exact = quintic_limit_ratio(&s, &e, t, &lim);
        let below = quintic_limit_ratio_below(&s, &e, t, &lim, ceiling);
        if exact < ceiling {
            prop_assert_eq!(below.to_bits(), exact.to_bits());
        } else {
            prop_assert!(below >= ceiling && below <= exact, "{below} for the ceiling {ceiling}, exact {exact}");
        }
    }
}
