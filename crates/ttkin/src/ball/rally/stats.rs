//! A rally's statistics: counts of the balls in reach and returned, the region's verdicts and the
//! planner's statuses, and the medians of the per-ball errors and times ([`RallyStats`]), from
//! the outcome columns of one or several runs ([`OutcomeColumns`], [`Outcomes::stats`]).

use std::collections::BTreeMap;

use super::score::Outcomes;
use crate::ball::reach::Reachability;
use crate::error::{Error, Result};

/// The per-ball outcome columns the statistics read (one entry per ball, all of one length).
#[derive(Debug, Clone, Copy)]
pub struct OutcomeColumns<'a> {
    /// Whether each ball is in reach.
    pub in_reach: &'a [bool],
    /// Whether each ball was returned (landed on the opponent's half).
    pub returned: &'a [bool],
    /// The region's verdict per ball (one of [`Reachability::NAMES`]).
    pub reach: &'a [&'a str],
    /// The planner's status per ball ("ok", …, or "estimate: …").
    pub status: &'a [&'a str],
    /// Contact point's distance from the racket centre (m; NaN without contact).
    pub racket_error: &'a [f64],
    /// Planning time (µs of thread CPU time).
    pub plan_time_us: &'a [f64],
    /// Planning time (µs wall clock).
    pub plan_wall_time_us: &'a [f64],
    /// Correction time after the bounce (µs of thread CPU time; NaN without one).
    pub correction_time_us: &'a [f64],
    /// Landing point's distance from the target (m; NaN without landing).
    pub landing_error: &'a [f64],
    /// Error of the estimated velocity (m/s).
    pub velocity_error: &'a [f64],
}

/// A rally's statistics (counts and medians; a median is `None` when no ball has a finite value).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RallyStats {
    /// Balls played.
    pub balls: usize,
    /// Balls in reach (a return is possible, [`crate::ball::reach`]).
    pub in_reach: usize,
    /// Balls out of reach.
    pub out_of_reach: usize,
    /// Balls in reach that were returned.
    pub returned: usize,
    /// Returned / in reach (`None` without a ball in reach).
    pub return_rate: Option<f64>,
    /// Balls returned although out of reach (should stay 0: the region is a necessary condition).
    pub returned_out_of_reach: usize,
    /// Count of every region verdict, in the order of [`Reachability::NAMES`] (0 when none).
    pub reach: Vec<(&'static str, usize)>,
    /// Count of every "verdict/status" pair (the status up to its first ':'), sorted by key.
    pub statuses: BTreeMap<String, usize>,
    /// Median contact distance from the racket centre over the balls in reach (m).
    pub racket_error_m_median: Option<f64>,
    /// Median planning time (µs thread CPU time).
    pub plan_time_us_median: Option<f64>,
    /// Median planning time (µs wall clock).
    pub plan_wall_time_us_median: Option<f64>,
    /// Median correction time over the balls that had one (µs thread CPU time).
    pub correction_time_us_median: Option<f64>,
    /// Median landing error over the returned balls (m).
    pub landing_error_m_median: Option<f64>,
    /// Median error of the estimated velocity (m/s).
    pub velocity_error_mps_median: Option<f64>,
}

/// Median of the finite values of `a` picked by `keep` (mean of the two middle ones for an even
/// count), `None` when there are none.
fn median(a: &[f64], keep: impl Fn(usize) -> bool) -> Option<f64> {
    let mut v: Vec<f64> = a
        .iter()
        .enumerate()
        .filter(|&(k, x)| keep(k) && x.is_finite())
        .map(|(_, &x)| x)
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    Some(if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    })
}

impl RallyStats {
    /// The statistics of the outcome columns `c`; [`Error::InvalidArgument`] when the columns differ
    /// in length or a verdict is not one of [`Reachability::NAMES`].
    pub fn new(c: &OutcomeColumns<'_>) -> Result<Self> {
        let n = c.in_reach.len();
        let lengths = [
            ("returned", c.returned.len()),
            ("reach", c.reach.len()),
            ("status", c.status.len()),
            ("racket_error", c.racket_error.len()),
            ("plan_time_us", c.plan_time_us.len()),
            ("plan_wall_time_us", c.plan_wall_time_us.len()),
            ("correction_time_us", c.correction_time_us.len()),
            ("landing_error", c.landing_error.len()),
            ("velocity_error", c.velocity_error.len()),
        ];
        if let Some((name, len)) = lengths.iter().find(|(_, len)| *len != n) {
            return Err(Error::invalid(
                *name,
                format!("{len} values, but in_reach has {n}: give one value per ball in every column"),
            ));
        }
        let mut reach: Vec<(&'static str, usize)> = Reachability::NAMES.iter().map(|&k| (k, 0)).collect();
        let mut statuses = BTreeMap::new();
        for (r, s) in c.reach.iter().zip(c.status) {
            let Some(slot) = reach.iter_mut().find(|(k, _)| k == r) else {
                return Err(Error::invalid(
                    "reach",
                    format!("unknown verdict '{r}'; expected one of {:?}", Reachability::NAMES),
                ));
            };
            slot.1 += 1;
            let status = s.split(':').next().unwrap_or_default();
            *statuses.entry(format!("{r}/{status}")).or_insert(0) += 1;
        }
        let in_reach = c.in_reach.iter().filter(|&&b| b).count();
        let returned_in = |k: usize| c.returned[k] && c.in_reach[k];
        let returned = (0..n).filter(|&k| returned_in(k)).count();
        Ok(RallyStats {
            balls: n,
            in_reach,
            out_of_reach: n - in_reach,
            returned,
            return_rate: (in_reach > 0).then(|| returned as f64 / in_reach as f64),
            returned_out_of_reach: (0..n).filter(|&k| c.returned[k] && !c.in_reach[k]).count(),
            reach,
            statuses,
            racket_error_m_median: median(c.racket_error, |k| c.in_reach[k]),
            plan_time_us_median: median(c.plan_time_us, |_| true),
            plan_wall_time_us_median: median(c.plan_wall_time_us, |_| true),
            correction_time_us_median: median(c.correction_time_us, |_| true),
            landing_error_m_median: median(c.landing_error, returned_in),
            velocity_error_mps_median: median(c.velocity_error, |_| true),
        })
    }
}

impl Outcomes {
    /// The statistics of these outcomes ([`RallyStats::new`] of their columns).
    pub fn stats(&self) -> Result<RallyStats> {
        let status: Vec<&str> = self.status.iter().map(String::as_str).collect();
        let c = OutcomeColumns {
            in_reach: &self.in_reach,
            returned: &self.returned,
            reach: &self.reach,
            status: &status,
            racket_error: &self.racket_error,
            plan_time_us: &self.plan_time_us,
            plan_wall_time_us: &self.plan_wall_time_us,
            correction_time_us: &self.correction_time_us,
            landing_error: &self.landing_error,
            velocity_error: &self.velocity_error,
        };
        RallyStats::new(&c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn columns<'a>(
        in_reach: &'a [bool],
        returned: &'a [bool],
        reach: &'a [&'a str],
        status: &'a [&'a str],
        x: &'a [f64],
    ) -> OutcomeColumns<'a> {
        OutcomeColumns {
            in_reach,
            returned,
            reach,
            status,
            racket_error: x,
            plan_time_us: x,
            plan_wall_time_us: x,
            correction_time_us: x,
            landing_error: x,
            velocity_error: x,
        }
    }

    #[test]
    fn counts_rates_and_medians_over_the_right_balls() {
        let in_reach = [true, true, true, false];
        let returned = [true, false, true, true];
        let reach = ["in_reach", "in_reach", "in_reach", "no_bounce"];
        let status = ["ok", "estimate: too few", "ok", "no_bounce"];
        let x = [1.0, f64::NAN, 4.0, 100.0];
        let s = RallyStats::new(&columns(&in_reach, &returned, &reach, &status, &x)).unwrap();
        assert_eq!((s.balls, s.in_reach, s.out_of_reach, s.returned), (4, 3, 1, 2));
        assert_eq!(s.returned_out_of_reach, 1);
        assert_eq!(s.return_rate, Some(2.0 / 3.0));
        // every verdict listed, in the region's order
        assert_eq!(s.reach.len(), Reachability::NAMES.len());
        assert_eq!(s.reach[0], ("no_bounce", 1));
        assert_eq!(s.reach.last(), Some(&("in_reach", 3)));
        let keys: Vec<_> = s.statuses.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        assert_eq!(
            keys,
            [("in_reach/estimate", 1), ("in_reach/ok", 2), ("no_bounce/no_bounce", 1)]
        );
        // NaN skipped; in reach only (1, 4); returned and in reach (1, 4); all (1, 4, 100)
        assert_eq!(s.racket_error_m_median, Some(2.5));
        assert_eq!(s.landing_error_m_median, Some(2.5));
        assert_eq!(s.plan_time_us_median, Some(4.0));
    }

    #[test]
    fn no_ball_in_reach_gives_no_rate_and_bad_columns_an_error() {
        let s = RallyStats::new(&columns(&[false], &[false], &["too_early"], &["ok"], &[f64::NAN])).unwrap();
        assert_eq!(
            (s.return_rate, s.racket_error_m_median, s.plan_time_us_median),
            (None, None, None)
        );
        let e = RallyStats::new(&columns(&[false, true], &[false], &["too_early"], &["ok"], &[1.0])).unwrap_err();
        assert!(e.to_string().contains("returned"), "{e}");
        let e = RallyStats::new(&columns(&[false], &[false], &["far"], &["ok"], &[1.0])).unwrap_err();
        assert!(e.to_string().contains("unknown verdict 'far'"), "{e}");
    }
}
