//! The calibration: Levenberg–Marquardt over the globals and every flight's nuisance at once,
//! the globals' step from the Schur complement of the block-arrow normal matrix, three robust
//! rounds, and the globals' covariance.

use super::problem::{fit_nuisance, flight_axes, huber, start, state_of, Mat6, Mat9, Mat96, Problem, Vec6, Vec9};
use super::segments::{bounce_level, median, segment};
use super::{Bounce, Calibration, FitModel, FitOptions, FlightFit, Recording, SpinPrior};
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, Vector3};
use rayon::prelude::*;

/// Fits the globals (those `opts.free` says; the others as in `initial`) and every flight's
/// nuisance to `recordings` (see the module doc). `initial.bounce` must be [`Bounce::Impulse`].
pub fn calibrate(recordings: &[Recording], initial: &FitModel, opts: &FitOptions) -> Result<Calibration> {
    if initial.bounce != Bounce::Impulse {
        return Err(Error::invalid(
            "initial",
            "the calibration fits the impulse bounce; give Bounce::Impulse",
        ));
    }
    initial.model.validate()?;
    if !(initial.period > 0.0 && initial.period.is_finite() && initial.surface.is_finite()) {
        return Err(Error::invalid("initial", "period must be > 0 and surface finite"));
    }
    let level = bounce_level(recordings)?;
    let segs: Vec<(usize, (usize, usize))> = recordings
        .iter()
        .enumerate()
        .filter_map(|(i, r)| segment(r, level, opts.bounce_band).map(|s| (i, s)))
        .collect();
    if segs.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no flight has a usable segment with a bounce",
        ));
    }
    let mut fm = *initial;
    let mut problems: Vec<Problem> = segs
        .iter()
        .map(|&(i, (end, _))| {
            let r = &recordings[i];
            Problem {
                obs: &r.positions[..end],
                weights: vec![1.0; end],
                x: start(r, fm.period),
                spin_mean: Vector3::zeros(),
                prior_axes: nalgebra::Matrix3::identity(),
                prior_std: Vector3::repeat(opts.spin_prior),
            }
        })
        .collect();
    problems.par_iter_mut().for_each(|pb| {
        fit_nuisance(&fm, pb, opts);
    });
    let free: Vec<usize> = (0..6).filter(|&j| opts.free[j]).collect();
    let nf = free.len();
    let mut iterations = 0;
    let mut sigma = f64::NAN;
    let mut s_final = DMatrix::<f64>::zeros(nf, nf);
    for round in 0..3 {
        if round > 0 {
            // Huber weights from the current residuals.
            let norms: Vec<Vec<f64>> = problems
                .par_iter()
                .map(|pb| {
                    let path = fm.path(&state_of(&pb.x), pb.obs.len(), opts.step);
                    path.iter()
                        .zip(pb.obs)
                        .map(|(p, o)| (p - Vector3::from(*o)).norm())
                        .collect()
                })
                .collect();
            let mut all: Vec<f64> = norms.iter().flatten().copied().collect();
            let c = 3.0 * median(&mut all);
            for (pb, n) in problems.iter_mut().zip(&norms) {
                pb.weights = huber(n, c);
            }
        }
        let mut lambda = 1e-3;
        let total =
            |fm: &FitModel, probs: &[Problem]| -> f64 { probs.par_iter().map(|pb| pb.cost(fm, &pb.x, opts)).sum() };
        let mut cost = total(&fm, &problems);
        for _ in 0..opts.iterations {
            iterations += 1;
            // Per flight: r, A, B → U, W, g_x; the globals' V and g.
            let blocks: Vec<(Mat9, Mat96, Vec9, Mat6, Vec6)> = problems
                .par_iter()
                .map(|pb| {
                    let (r, a, b) = pb.linearise(&fm, opts, true);
                    let at = a.transpose();
                    let bt = b.transpose();
                    let u = Mat9::from_iterator((&at * &a).iter().copied());
                    let w = Mat96::from_iterator((&at * &b).iter().copied());
                    let gx = Vec9::from_iterator((&at * &r).iter().copied());
                    let v = Mat6::from_iterator((&bt * &b).iter().copied());
                    let gg = Vec6::from_iterator((&bt * &r).iter().copied());
                    (u, w, gx, v, gg)
                })
                .collect();
            let schur = |lam: f64| -> Option<(DMatrix<f64>, DVector<f64>, Vec<Mat9>)> {
                let mut v = Mat6::zeros();
                let mut gg = Vec6::zeros();
                for bl in &blocks {
                    v += bl.3;
                    gg += bl.4;
                }
                let mut s = DMatrix::zeros(nf, nf);
                let mut rhs = DVector::zeros(nf);
                for (a, &ja) in free.iter().enumerate() {
                    rhs[a] = gg[ja];
                    for (b, &jb) in free.iter().enumerate() {
                        s[(a, b)] = v[(ja, jb)];
                    }
                    s[(a, a)] += lam * v[(ja, ja)].max(1e-30);
                }
                let mut inv = Vec::with_capacity(blocks.len());
                for (u, w, gx, _, _) in &blocks {
                    let mut ud = *u;
                    for j in 0..9 {
                        ud[(j, j)] += lam * u[(j, j)].max(1e-12);
                    }
                    let ui = ud.try_inverse()?;
                    let wt_ui = w.transpose() * ui;
                    let m = wt_ui * w;
                    let q = wt_ui * gx;
                    for (a, &ja) in free.iter().enumerate() {
                        rhs[a] -= q[ja];
                        for (b, &jb) in free.iter().enumerate() {
                            s[(a, b)] -= m[(ja, jb)];
                        }
                    }
                    inv.push(ui);
                }
                Some((s, rhs, inv))
            };
            let mut improved = false;
            for _ in 0..12 {
                let Some((s, rhs, inv)) = schur(lambda) else {
                    lambda *= 10.0;
                    continue;
                };
                let Some(ch) = s.clone().cholesky() else {
                    lambda *= 10.0;
                    continue;
                };
                let dg = -ch.solve(&rhs);
                let mut g = fm.globals();
                let mut dgf = Vec6::zeros();
                for (a, &ja) in free.iter().enumerate() {
                    g[ja] += dg[a];
                    dgf[ja] = dg[a];
                }
                let trial = fm.with_globals(&g);
                let xs: Vec<Vec9> = blocks
                    .iter()
                    .zip(&inv)
                    .zip(&problems)
                    .map(|(((_, w, gx, _, _), ui), pb)| pb.x - ui * (gx + w * dgf))
                    .collect();
                let c: f64 = problems
                    .par_iter()
                    .zip(&xs)
                    .map(|(pb, x)| pb.cost(&trial, x, opts))
                    .sum();
                if c < cost {
                    let rel = (cost - c) / cost.max(1e-300);
                    fm = trial;
                    for (pb, x) in problems.iter_mut().zip(xs) {
                        pb.x = x;
                    }
                    cost = c;
                    lambda = (lambda * 0.3).max(1e-9);
                    improved = rel > 1e-9;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        // The undamped Schur complement at the solution, for the covariance.
        if let Some(s) = schur_at(&fm, &problems, opts, &free) {
            s_final = s;
        }
        let n_res: usize = problems.iter().map(|pb| 3 * pb.obs.len()).sum();
        let n_par = 9 * problems.len() + nf;
        sigma = (cost / (n_res.saturating_sub(n_par)).max(1) as f64).sqrt();
    }
    // Parameters whose column vanishes (μ when every bounce rolls) are not identified: the
    // covariance of the others, theirs NaN.
    let scale = (0..nf).map(|a| s_final[(a, a)]).fold(0.0, f64::max);
    let ident: Vec<usize> = (0..nf).filter(|&a| s_final[(a, a)] > 1e-12 * scale).collect();
    let sub = DMatrix::from_fn(ident.len(), ident.len(), |a, b| s_final[(ident[a], ident[b])]);
    let mut std = [f64::NAN; 6];
    let mut correlation = [[f64::NAN; 6]; 6];
    if let Some(ch) = sub.cholesky() {
        let cov = ch.inverse() * (sigma * sigma);
        for (a, &ia) in ident.iter().enumerate() {
            std[free[ia]] = cov[(a, a)].sqrt();
        }
        for (a, &ia) in ident.iter().enumerate() {
            for (b, &ib) in ident.iter().enumerate() {
                correlation[free[ia]][free[ib]] = cov[(a, b)] / (std[free[ia]] * std[free[ib]]);
            }
        }
    }
    let flights: Vec<FlightFit> = problems
        .par_iter()
        .zip(&segs)
        .map(|(pb, &(i, (end, b)))| {
            let mut roll = f64::NAN;
            let m = fm.model;
            let path = fm.path_with(&state_of(&pb.x), end, opts.step, &mut |b| {
                if roll.is_nan() {
                    let kappa = 1.0 + m.mass * m.radius * m.radius / m.inertia();
                    let slip = Vector3::new(b.v.x, b.v.y, 0.0) + b.w.cross(&(-m.radius * Vector3::z()));
                    roll = slip.norm() / kappa / ((1.0 + m.table_restitution) * b.v.z.abs());
                }
            });
            let ss: f64 = path
                .iter()
                .zip(pb.obs)
                .map(|(p, o)| (p - Vector3::from(*o)).norm_squared())
                .sum();
            FlightFit {
                index: i,
                state: state_of(&pb.x),
                frames: end,
                bounce_frame: b,
                rms: (ss / end as f64).sqrt(),
                friction_to_roll: roll,
            }
        })
        .collect();
    let observations: usize = flights.iter().map(|f| f.frames).sum();
    let rms = (flights.iter().map(|f| f.rms * f.rms * f.frames as f64).sum::<f64>() / observations as f64).sqrt();
    let local: Vec<Vector3<f64>> = flights
        .iter()
        .map(|f| flight_axes(&f.state.v).transpose() * f.state.w)
        .collect();
    let nfl = local.len() as f64;
    let mean = local.iter().sum::<Vector3<f64>>() / nfl;
    let var = local
        .iter()
        .map(|w| (w - mean).component_mul(&(w - mean)))
        .sum::<Vector3<f64>>()
        / (nfl - 1.0).max(1.0);
    Ok(Calibration {
        spin: SpinPrior {
            mean: mean.into(),
            std: var.map(|v| v.sqrt().max(1.0)).into(),
        },
        fit: fm,
        globals: fm.globals(),
        std,
        correlation,
        sigma,
        rms,
        flights,
        iterations,
        observations,
    })
}

/// The undamped Schur complement of the globals at the current solution.
fn schur_at(fm: &FitModel, problems: &[Problem], opts: &FitOptions, free: &[usize]) -> Option<DMatrix<f64>> {
    let nf = free.len();
    let parts: Vec<Option<DMatrix<f64>>> = problems
        .par_iter()
        .map(|pb| {
            let (_, a, b) = pb.linearise(fm, opts, true);
            let at = a.transpose();
            let u = &at * &a;
            let w = &at * &b;
            let v = b.transpose() * &b;
            let ui = u.try_inverse()?;
            Some(v - w.transpose() * ui * w)
        })
        .collect();
    let mut s = DMatrix::zeros(nf, nf);
    for p in parts {
        let p = p?;
        for (a, &ja) in free.iter().enumerate() {
            for (b, &jb) in free.iter().enumerate() {
                s[(a, b)] += p[(ja, jb)];
            }
        }
    }
    Some(s)
}
