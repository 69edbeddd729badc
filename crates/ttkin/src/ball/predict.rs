//! Prediction of a ball's flight from a state: positions at given times through bounces, and the
//! crossing of a hitting plane; batches over many balls run in parallel (rayon).

use super::flight::{BallState, Event, EventKind, Flight, Plane};
use crate::error::{Error, Result};
use rayon::prelude::*;

/// Positions at the requested times and what happened on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// Ball centre (m, world) at each requested time; NaN after a terminal event.
    pub positions: Vec<[f64; 3]>,
    /// Every event met up to the last requested time (bounces, net, floor).
    pub events: Vec<Event>,
    /// The terminal event (net or floor) that ended the flight, if any.
    pub end: Option<EventKind>,
}

/// Checks that `times` are finite, non-decreasing and not before `t0` (s).
fn check_times(times: &[f64], t0: f64) -> Result<()> {
    for (i, &t) in times.iter().enumerate() {
        if !t.is_finite() {
            return Err(Error::NonFinite {
                what: "times".into(),
                index: i,
                value: t,
            });
        }
        if t < t0 - 1e-12 {
            return Err(Error::invalid(
                "times",
                format!("times[{i}] = {t} s lies before the state's time {t0} s (prediction runs forward)"),
            ));
        }
        if i > 0 && t < times[i - 1] {
            return Err(Error::invalid(
                "times",
                format!("must be non-decreasing; times[{i}] = {t} < times[{}]", i - 1),
            ));
        }
    }
    Ok(())
}

/// Positions of the ball from `state` at `times` (s, non-decreasing, ≥ state.t), through bounces.
pub fn predict(flight: &Flight, state: &BallState, times: &[f64]) -> Result<Prediction> {
    predict_until(flight, state, times, &|| false)
}

/// [`predict`] that ends early with [`crate::budget::stopped`]'s error when `stop()` turns true
/// (polled every [`crate::budget::STOP_POLL_STEPS`] integration steps).
pub fn predict_until(
    flight: &Flight,
    state: &BallState,
    times: &[f64],
    stop: crate::budget::Stop<'_>,
) -> Result<Prediction> {
    flight.validate()?;
    state.validate("state")?;
    check_times(times, state.t)?;
    if let Some(&last) = times.last() {
        flight.check_span("times", state, last)?;
    }
    let mut cur = *state;
    let mut events = Vec::new();
    let mut end = None;
    let mut positions = Vec::with_capacity(times.len());
    for &t in times {
        while end.is_none() && cur.t < t {
            let (next, ev) = flight.advance_until(&cur, t, None, stop);
            if ev.is_none() && next.t < t {
                // stopped by the caller (or a clock that no longer advances, which the span check
                // above refuses)
                return Err(if stop() {
                    crate::budget::stopped("times")
                } else {
                    Error::invalid("times", "the clock no longer advances at this time")
                });
            }
            cur = next;
            if let Some(e) = ev {
                events.push(e);
                if e.kind.terminal() {
                    end = Some(e.kind);
                }
            }
        }
        positions.push(if end.is_some() { [f64::NAN; 3] } else { cur.p.into() });
    }
    Ok(Prediction { positions, events, end })
}

/// How a flight toward a plane ended.
#[derive(Debug, Clone, PartialEq)]
pub enum CrossingOutcome {
    /// The ball crossed the plane; the state there and the bounces before.
    Crossed {
        /// State at the crossing (time, position, velocity, spin).
        state: BallState,
        /// Bounces (table, edge) before the crossing.
        bounces: Vec<Event>,
    },
    /// The flight ended at the net or the floor before the crossing.
    Ended(Event),
    /// No crossing before `t_max`.
    Timeout,
}

/// The default search horizon (s) of a crossing: longer than any flight across the table.
pub const CROSSING_HORIZON: f64 = 2.0;

/// Where and when the ball from `state` crosses `plane` (from its positive to negative side),
/// searching up to `t_max` (s).
pub fn crossing(flight: &Flight, state: &BallState, plane: &Plane, t_max: f64) -> Result<CrossingOutcome> {
    crossing_until(flight, state, plane, t_max, &|| false)
}

/// [`crossing`] that ends early with [`crate::budget::stopped`]'s error when `stop()` turns true
/// (polled every [`crate::budget::STOP_POLL_STEPS`] integration steps).
pub fn crossing_until(
    flight: &Flight,
    state: &BallState,
    plane: &Plane,
    t_max: f64,
    stop: crate::budget::Stop<'_>,
) -> Result<CrossingOutcome> {
    flight.validate()?;
    state.validate("state")?;
    if !t_max.is_finite() {
        return Err(Error::NonFinite {
            what: "t_max".into(),
            index: 0,
            value: t_max,
        });
    }
    flight.check_span("t_max", state, t_max)?;
    let (end, events) = flight.run_until(state, t_max, Some(plane), stop);
    if end.t < t_max
        && events
            .last()
            .is_none_or(|e| !(e.kind.terminal() || e.kind == EventKind::Plane))
        && stop()
    {
        return Err(crate::budget::stopped("t_max"));
    }
    let mut bounces = Vec::new();
    for e in events {
        match e.kind {
            EventKind::Plane => {
                return Ok(CrossingOutcome::Crossed {
                    state: e.before,
                    bounces,
                })
            }
            EventKind::Net | EventKind::Floor => return Ok(CrossingOutcome::Ended(e)),
            _ => bounces.push(e),
        }
    }
    Ok(CrossingOutcome::Timeout)
}

/// [`predict`] for many balls in parallel, one result per state.
pub fn predict_batch(flight: &Flight, states: &[BallState], times: &[f64]) -> Vec<Result<Prediction>> {
    states.par_iter().map(|s| predict(flight, s, times)).collect()
}

/// [`predict`] for many balls in parallel, written into `out` (N × K × 3 for N `states` and K
/// `times`, row-major; NaN after a terminal event), each ball's error naming it (`states[i]`);
/// `stop()` is polled before each ball (a caller's cancellation) and ends the batch with an error.
pub fn predict_batch_into(
    flight: &Flight,
    states: &[BallState],
    times: &[f64],
    out: &mut [f64],
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<()> {
    let k = times.len();
    if out.len() != states.len() * 3 * k {
        return Err(Error::shape(
            "out",
            format!("{} values", states.len() * 3 * k),
            out.len(),
        ));
    }
    out.par_chunks_mut((3 * k).max(1))
        .zip(states.par_iter())
        .enumerate()
        .try_for_each(|(i, (o, s))| {
            if stop() {
                return Err(Error::invalid("states", "prediction stopped"));
            }
            // one long flight stops too (issue 29), not only between balls
            let pred = predict_until(flight, s, times, stop)
                .map_err(|e| Error::invalid(format!("states[{i}]"), e.to_string()))?;
            for (dst, p) in o.chunks_exact_mut(3).zip(&pred.positions) {
                dst.copy_from_slice(p);
            }
            Ok(())
        })
}

/// [`crossing`] for many balls in parallel, one result per state.
pub fn crossing_batch(
    flight: &Flight,
    states: &[BallState],
    plane: &Plane,
    t_max: f64,
) -> Vec<Result<CrossingOutcome>> {
    states.par_iter().map(|s| crossing(flight, s, plane, t_max)).collect()
}

#[cfg(test)]
mod stop_tests {
    use super::*;
    use crate::ball::model::BallModel;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A flight asked to stop ends with the stop's error after one poll's worth of steps; one
    /// never asked is `predict`, bit for bit.
    #[test]
    fn predict_until_stops_on_request_and_is_predict_otherwise() {
        let f = Flight::new(BallModel::default());
        let s = BallState::new(0.0, [0.0, 0.0, 1e4], [900.0, 0.0, 0.0], [0.0, 1e5, 0.0]);
        let polls = AtomicU64::new(0);
        let err = predict_until(&f, &s, &[100.0], &|| polls.fetch_add(1, Ordering::Relaxed) >= 2).unwrap_err();
        assert!(err.to_string().contains("stopped by the caller"), "{err}");
        // three polls in the flight (the third stops it), one more to tell a stop from a stalled clock
        assert_eq!(polls.load(Ordering::Relaxed), 4);
        let plane = Plane {
            point: nalgebra::Vector3::new(0.0, 0.0, -5.0),
            normal: nalgebra::Vector3::new(0.0, 0.0, 1.0),
        };
        let err = crossing_until(&f, &s, &plane, 100.0, &|| true).unwrap_err();
        assert!(err.to_string().contains("stopped by the caller"), "{err}");
        assert_eq!(
            crossing(&f, &s, &plane, 3.0).unwrap(),
            crossing_until(&f, &s, &plane, 3.0, &|| false).unwrap()
        );
        let times = [0.5, 1.0, 7.0];
        assert_eq!(
            predict(&f, &s, &times).unwrap(),
            predict_until(&f, &s, &times, &|| false).unwrap()
        );
    }
}
