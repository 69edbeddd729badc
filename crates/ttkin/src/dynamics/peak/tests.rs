use super::recursion::Work;
use super::*;
use crate::traj::JointState;

#[test]
fn generic_recursion_on_f64_is_inverse_dynamics_without_coulomb() {
    for chain in [crate::robots::gantry6(), crate::robots::ur5(), crate::robots::mobile8()] {
        let dy = Dynamics::new(&chain).unwrap();
        let n = dy.dof();
        let mut data = DynamicsData::new(&dy);
        let mut w = Work::<f64>::new(n);
        let mut rng = fastrand::Rng::with_seed(2);
        let g = Vector3::new(0.3, -0.2, -9.81);
        for _ in 0..200 {
            let v = |rng: &mut fastrand::Rng, s: f64| (0..n).map(|_| s * (2.0 * rng.f64() - 1.0)).collect::<Vec<f64>>();
            let (q, qd, qdd) = (v(&mut rng, 2.0), v(&mut rng, 3.0), v(&mut rng, 20.0));
            let mut out = vec![0.0; n];
            dy.rnea_smooth(&mut w, &q, &qd, &qdd, &g, &mut out);
            let want = dy.inverse_dynamics_unchecked(&mut data, &q, &qd, &qdd, &g).clone();
            for j in 0..n {
                let coulomb = dy.drives[j].map_or(0.0, |d| d.coulomb * sign(qd[j]));
                let w = want[j] - coulomb;
                assert!(
                    (out[j] - w).abs() <= 1e-10 * (1.0 + w.abs()),
                    "{}: {out:?} vs {want:?}",
                    chain.name()
                );
            }
        }
    }
}

#[test]
fn shift_moves_the_origin() {
    let c = [0.3, -1.0, 2.0, 0.5, -0.7, 0.2];
    let s = shift(&c, 0.37);
    for tau in [0.0, 0.1, 0.5] {
        assert!((poly::value(&s, tau) - poly::value(&c, 0.37 + tau)).abs() < 1e-12);
    }
}

/// Dense reference: the largest ratio at `k` + 1 evenly spaced instants.
fn dense(dy: &Dynamics, traj: &JointTrajectory, lim: &EffortLimits, k: usize) -> f64 {
    let mut data = DynamicsData::new(dy);
    let n = dy.dof();
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let g = Vector3::new(0.0, 0.0, -9.81);
    let mut best: f64 = 0.0;
    for i in 0..=k {
        let t = traj.duration() * i as f64 / k as f64;
        traj.sample_unchecked(t, &mut q, &mut qd, &mut qdd);
        let tau = dy.inverse_dynamics_unchecked(&mut data, &q, &qd, &qdd, &g);
        for j in 0..n {
            best = best.max(ratio(tau[j].abs(), lim.at(j, qd[j])));
        }
    }
    best
}

#[test]
fn refined_peak_brackets_a_dense_sample_of_random_strokes() {
    let chain = crate::robots::gantry6();
    let dy = Dynamics::new(&chain).unwrap();
    let lim = EffortLimits::of(&chain);
    let kl =
        crate::traj::limits::KinematicLimits::from_chain(&chain, Some(&[200.0, 200.0, 2000.0, 2000.0, 3000.0, 4000.0]))
            .unwrap();
    let mut data = DynamicsData::new(&dy);
    let mut rng = fastrand::Rng::with_seed(9);
    let g = Vector3::new(0.0, 0.0, -9.81);
    let (mut evaluations, mut decisions) = (Vec::new(), Vec::new());
    for k in 0..24 {
        let r = |rng: &mut fastrand::Rng, s: f64| (0..6).map(|_| s * (2.0 * rng.f64() - 1.0)).collect::<Vec<f64>>();
        let start = JointState {
            q: r(&mut rng, 0.5),
            qd: r(&mut rng, 1.5),
            qdd: r(&mut rng, 5.0),
        };
        let end = JointState {
            q: r(&mut rng, 0.8),
            qd: r(&mut rng, 3.0),
            qdd: vec![0.0; 6],
        };
        let traj = if k % 2 == 0 {
            JointTrajectory::quintic_unchecked(&start, &end, 0.4 + 0.4 * rng.f64())
        } else {
            crate::traj::jerk::jerk_limited(
                &start,
                &end,
                &kl,
                Some(0.4 + 0.4 * rng.f64()),
                crate::traj::jerk::PositionLimits::Ignore,
            )
            .unwrap()
            .trajectory
        };
        let peak = dy.effort_peak(&mut data, &traj, &lim, &g, PeakStop::refine(1e-4));
        let reference = dense(&dy, &traj, &lim, 10_000);
        if !reference.is_finite() {
            // Faster than a drive's no-load speed somewhere: no torque left there.
            assert_eq!(peak.bound, f64::INFINITY);
            continue;
        }
        evaluations.push(peak.evaluations);
        assert!(peak.ratio <= peak.bound, "{k}: {peak:?}");
        assert!(
            reference <= peak.bound * (1.0 + 1e-9),
            "{k}: dense {reference} above bound {}",
            peak.bound
        );
        assert!(
            peak.bound - peak.ratio <= 1e-4 + 1e-12,
            "{k}: gap {}",
            peak.bound - peak.ratio
        );
        // A dense sample misses a peak at a kink (jerk switch, Coulomb step) by up to
        // |dτ/dt|·h/2: 1e-3 is the acceptance of issue 28.
        assert!(
            (peak.ratio - reference).abs() <= 1e-3,
            "{k}: {} vs dense {reference}",
            peak.ratio
        );
        let decide = dy.effort_peak(&mut data, &traj, &lim, &g, PeakStop::decide(1.0, 1e-3));
        decisions.push(decide.evaluations);
        if decide.bound <= 1.0 {
            assert!(
                reference <= 1.0 + 1e-9,
                "{k}: called within the limits, dense {reference}"
            );
        }
        assert!(decide.ratio <= reference + 1e-9 || decide.ratio <= peak.bound, "{k}");
    }
    evaluations.sort();
    decisions.sort();
    println!(
        "interval evaluations per decision: median {}, max {}",
        decisions[decisions.len() / 2],
        decisions[decisions.len() - 1]
    );
    println!(
        "interval evaluations per refined peak: median {}, max {}",
        evaluations[evaluations.len() / 2],
        evaluations[evaluations.len() - 1]
    );
    assert!(evaluations.len() >= 16);
}
