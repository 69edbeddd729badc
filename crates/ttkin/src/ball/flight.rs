//! Ball flight: fixed-step RK4 on the model of [`super::model`] with event detection.
//!
//! After every step (or at `m` evenly spaced times of it, [`Flight::advance_sampled`]) the guards
//! are evaluated: distance to the table top minus the radius, the same for the net, height above
//! the floor, and optionally a user plane (first by squared distances, no square root; the exact
//! values only when one may have fired). When one falls to ≤ 0, the event time is located by
//! bisection on the step's cubic Hermite interpolant of the position (from p and v at both ends;
//! its error is h⁴·|p⁗|/384 ≈ 1e-12 m at 2 ms) between the last sample where none fired and the
//! first where one did, 30 halvings (2e-12 s at 2 ms), and the state just before the contact is
//! one RK4 step from the start of the step to there (stepped back until every armed guard is > 0
//! on that state). Guards are sampled, not swept, with one addition for the two thin bodies,
//! thinner than a ball's travel between samples (the net: 2 mm + 40 mm across for the centre, 21
//! m/s at 2 ms, 4.2 m/s at 10 ms; the table top: 25 mm + 40 mm): where the interpolant crosses the
//! net's plane x = 0 or the surface's plane z = 0 between two samples, the guards are evaluated
//! there too. A body passed between samples otherwise (a table edge grazed at speed) has no event. Table (surface) and edge contacts bounce ([`super::contact::impulse`]) and the flight
//! goes on; net and floor contacts end it; a plane crossing is reported. RK4's global error is
//! O(h⁴): at the default 2 ms step a 1 s flight is within 1e-6 m of a 0.05 ms reference (tested).

use super::contact::{floor_distance, impulse, net_distance, table_distance};
use super::model::{BallModel, Table};
use crate::error::{Error, Result};
use nalgebra::Vector3;

/// Ball state at time `t` (s): position `p` (m), velocity `v` (m/s), spin `w` (rad/s), world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallState {
    /// Time (s).
    pub t: f64,
    /// Centre position (m, world).
    pub p: Vector3<f64>,
    /// Velocity (m/s, world).
    pub v: Vector3<f64>,
    /// Spin (rad/s, world axes).
    pub w: Vector3<f64>,
}

impl BallState {
    /// A state from arrays: time (s), position (m), velocity (m/s), spin (rad/s).
    pub fn new(t: f64, p: [f64; 3], v: [f64; 3], w: [f64; 3]) -> Self {
        BallState {
            t,
            p: p.into(),
            v: v.into(),
            w: w.into(),
        }
    }

    /// The state as [t, px, py, pz, vx, vy, vz, wx, wy, wz] (s, m, m/s, rad/s, world).
    pub fn to_array(&self) -> [f64; 10] {
        let (p, v, w) = (&self.p, &self.v, &self.w);
        [self.t, p.x, p.y, p.z, v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// The state of a [`Self::to_array`] row (the first 10 values of `row`).
    pub fn from_row(row: &[f64]) -> Self {
        let r = |i: usize| [row[i], row[i + 1], row[i + 2]];
        BallState::new(row[0], r(1), r(4), r(7))
    }

    /// The states of consecutive [`Self::to_array`] rows (`data.len() / 10` of them).
    pub fn from_rows(data: &[f64]) -> Vec<Self> {
        data.chunks_exact(10).map(Self::from_row).collect()
    }

    /// The rows ([`Self::to_array`]) of `states`, concatenated.
    pub fn rows(states: &[BallState]) -> Vec<f64> {
        states.iter().flat_map(Self::to_array).collect()
    }

    /// Checks that every component is finite and within the ball's physical range
    /// ([`MAX_POSITION`], [`MAX_SPEED`], [`MAX_SPIN`]: beyond them the drag and Magnus terms
    /// overflow or the flight is not a table-tennis ball's); `what` names the argument.
    pub fn validate(&self, what: &str) -> Result<()> {
        self.validate_finite(what)?;
        for (part, v, max, unit) in [
            ("position", &self.p, MAX_POSITION, "m"),
            ("velocity", &self.v, MAX_SPEED, "m/s"),
            ("spin", &self.w, MAX_SPIN, "rad/s"),
        ] {
            // scaled by the largest component: ‖(1e200, 0, 0)‖ is 1e200, not the inf of x² + y² + z²
            let big = v.amax();
            let norm = if big > 0.0 { big * (v / big).norm() } else { 0.0 };
            if !(norm <= max) {
                return Err(Error::invalid(
                    what,
                    format!("‖{part}‖ = {norm:e} {unit}, at most {max:e} {unit} for a ball"),
                ));
            }
        }
        Ok(())
    }

    /// Checks that every component is finite; `what` names the argument.
    fn validate_finite(&self, what: &str) -> Result<()> {
        let all = [self.t]
            .into_iter()
            .chain(self.p.iter().copied())
            .chain(self.v.iter().copied())
            .chain(self.w.iter().copied());
        for (i, x) in all.enumerate() {
            if !x.is_finite() {
                return Err(Error::NonFinite {
                    what: what.to_string(),
                    index: i,
                    value: x,
                });
            }
        }
        Ok(())
    }
}

/// Largest distance of a ball from the world origin (m) a flight accepts.
pub const MAX_POSITION: f64 = 1e4;
/// Largest ball speed (m/s) a flight accepts (the fastest smash is about 35 m/s).
pub const MAX_SPEED: f64 = 1e3;
/// Largest ball spin (rad/s) a flight accepts (a strong loop is about 1000 rad/s).
pub const MAX_SPIN: f64 = 1e5;

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// Bounce on the playing surface.
    Table,
    /// Contact with an edge or side of the table top (bounce with a non-vertical normal).
    Edge,
    /// Contact with the net (ends the flight).
    Net,
    /// Reached the floor (ends the flight).
    Floor,
    /// Crossed the user plane from its positive to its negative side.
    Plane,
}

impl EventKind {
    /// Short lower-case name ("table", "edge", "net", "floor", "plane").
    pub fn name(&self) -> &'static str {
        match self {
            EventKind::Table => "table",
            EventKind::Edge => "edge",
            EventKind::Net => "net",
            EventKind::Floor => "floor",
            EventKind::Plane => "plane",
        }
    }

    /// Whether the flight ends at this event.
    pub fn terminal(&self) -> bool {
        matches!(self, EventKind::Net | EventKind::Floor)
    }
}

/// An event: its kind, the state just before and just after (equal except for bounces).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// What happened.
    pub kind: EventKind,
    /// State at the contact, before the impulse.
    pub before: BallState,
    /// State after the impulse (same as `before` for non-bouncing events).
    pub after: BallState,
}

impl Event {
    /// The kinds' names ([`EventKind::name`]) of `events`, in order.
    pub fn names(events: &[Event]) -> Vec<&'static str> {
        events.iter().map(|e| e.kind.name()).collect()
    }
}

/// An event's serde form: `kind` (its name) and the states `before` and `after` as
/// [`BallState::to_array`] rows.
impl serde::Serialize for Event {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Event", 3)?;
        st.serialize_field("kind", self.kind.name())?;
        st.serialize_field("before", &self.before.to_array())?;
        st.serialize_field("after", &self.after.to_array())?;
        st.end()
    }
}

/// A plane n·(p − point) = 0 (world); crossing means n·(p − point) goes from > 0 to ≤ 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point on the plane (m, world).
    pub point: Vector3<f64>,
    /// Unit normal (world), pointing to the side the ball comes from.
    pub normal: Vector3<f64>,
}

impl Plane {
    /// The plane through `point` (m, world) with normal along `normal` (any length, normalised
    /// here); an error for a non-finite point or a zero or non-finite normal.
    pub fn new(point: [f64; 3], normal: [f64; 3]) -> Result<Self> {
        let (point, normal) = (Vector3::from(point), Vector3::from(normal));
        let norm = normal.norm();
        if !(norm > 1e-12 && norm.is_finite()) {
            return Err(Error::invalid("normal", "must be a non-zero vector"));
        }
        if !point.iter().all(|x| x.is_finite()) {
            return Err(Error::invalid("point", "must be finite"));
        }
        Ok(Plane {
            point,
            normal: normal / norm,
        })
    }

    /// Signed distance (m) of `p` to the plane.
    pub fn distance(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(&(p - self.point))
    }
}

/// The flight integrator: model, table and step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flight {
    /// Ball and air model.
    pub model: BallModel,
    /// Table geometry.
    pub table: Table,
    /// RK4 step (s), default 2 ms.
    pub step: f64,
}

impl Default for Flight {
    fn default() -> Self {
        Flight {
            model: BallModel::default(),
            table: Table::default(),
            step: 0.002,
        }
    }
}

/// Guard values of a state: (table, net, floor, plane); an event fires when one becomes ≤ 0.
#[derive(Clone, Copy)]
struct Guards([f64; 4]);

impl Flight {
    /// Flight with `model` on the ITTF table and the default 2 ms step.
    pub fn new(model: BallModel) -> Self {
        Flight {
            model,
            ..Flight::default()
        }
    }

    /// Checks model, table and step.
    pub fn validate(&self) -> Result<()> {
        self.model.validate()?;
        self.table.validate()?;
        if !(self.step > 0.0 && self.step <= 0.05) {
            return Err(Error::invalid(
                "step",
                format!("must lie in (0, 0.05] s, got {}", self.step),
            ));
        }
        Ok(())
    }

    /// Checks that a flight from `s` up to the time `t_end` (s) is bounded work: its clock advances
    /// by this flight's step at both ends ([`crate::budget::check_clock`]) and it takes at most
    /// [`crate::budget::MAX_STEPS`] steps. `what` names the argument that sets `t_end`.
    pub fn check_span(&self, what: &str, s: &BallState, t_end: f64) -> Result<()> {
        crate::budget::check_clock("state.t", s.t, self.step)?;
        crate::budget::check_clock(what, t_end, self.step)?;
        crate::budget::check_steps(what, (t_end - s.t).max(0.0), self.step)?;
        Ok(())
    }

    /// One RK4 step of length `h` (s) without events (spin constant).
    pub fn rk4(&self, s: &BallState, h: f64) -> BallState {
        let m = &self.model;
        let w = s.w;
        let a1 = m.acceleration(&s.v, &w);
        let v2 = s.v + 0.5 * h * a1;
        let a2 = m.acceleration(&v2, &w);
        let v3 = s.v + 0.5 * h * a2;
        let a3 = m.acceleration(&v3, &w);
        let v4 = s.v + h * a3;
        let a4 = m.acceleration(&v4, &w);
        BallState {
            t: s.t + h,
            p: s.p + h / 6.0 * (s.v + 2.0 * v2 + 2.0 * v3 + v4),
            v: s.v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            w,
        }
    }

    fn guards(&self, p: &Vector3<f64>, plane: Option<&Plane>) -> Guards {
        let r = self.model.radius;
        Guards([
            table_distance(&self.table, p).0 - r,
            net_distance(&self.table, p).0 - r,
            floor_distance(&self.table, &self.model, p),
            plane.map_or(f64::INFINITY, |pl| pl.distance(p)),
        ])
    }

    /// Whether an armed guard may be ≤ 0 at `p`: squared distances to the table top and the net
    /// against (r + 1 nm)², no square root. False means no guard fired; true asks for [`Self::guards`].
    fn may_fire(&self, armed: &[bool; 4], p: &Vector3<f64>, plane: Option<&Plane>) -> bool {
        let t = &self.table;
        let reach = self.model.radius + 1e-9;
        let reach2 = reach * reach;
        let (hl, hw) = (t.half_length(), t.half_width());
        let outside = |x: f64, lo: f64, hi: f64| {
            let d = x - x.clamp(lo, hi);
            d * d
        };
        let table2 = outside(p.x, -hl, hl) + outside(p.y, -hw, hw) + outside(p.z, -t.thickness, 0.0);
        let half = hw + t.net_overhang;
        let net2 = outside(p.x, -0.001, 0.001) + outside(p.y, -half, half) + outside(p.z, 0.0, t.net_height);
        (armed[0] && table2 <= reach2)
            || (armed[1] && net2 <= reach2)
            || (armed[2] && floor_distance(t, &self.model, p) <= 1e-9)
            || (armed[3] && plane.is_some_and(|pl| pl.distance(p) <= 1e-9))
    }

    /// Integrates from `s` up to time `t_end` (s) or the first event, whichever comes first.
    /// Returns the state reached (after the bounce impulse at a table or edge event) and the event.
    /// Guards already ≤ 0 at `s` are ignored (e.g. a ball resting on a plane it just crossed).
    pub fn advance(&self, s: &BallState, t_end: f64, plane: Option<&Plane>) -> (BallState, Option<Event>) {
        self.advance_sampled(s, t_end, plane, 1)
    }

    /// [`Flight::advance`] with the guards evaluated at `samples` evenly spaced times of every
    /// step (m ≥ 1; the last at the step's end, the others on the step's cubic Hermite
    /// interpolant of the position, error h⁴·|p⁗|/384) instead of at its end only: a long step
    /// with the guard resolution of a short one. With m = 1 it is `advance`. The net's plane is
    /// checked where the ball crosses it (module doc).
    pub fn advance_sampled(
        &self,
        s: &BallState,
        t_end: f64,
        plane: Option<&Plane>,
        samples: usize,
    ) -> (BallState, Option<Event>) {
        self.advance_guarded(s, t_end, plane, samples, true)
    }

    /// [`Flight::advance_sampled`], the net guard armed only with `net` (without it, no net event;
    /// table, floor and plane as there): for a prediction that flies on through a net clip.
    pub(crate) fn advance_guarded(
        &self,
        s: &BallState,
        t_end: f64,
        plane: Option<&Plane>,
        samples: usize,
        net: bool,
    ) -> (BallState, Option<Event>) {
        self.advance_stoppable(s, t_end, plane, samples, net, &|| false)
    }

    /// [`Flight::advance`] that also returns, without an event and before `t_end`, when `stop()`
    /// turns true (polled every [`crate::budget::STOP_POLL_STEPS`] steps): a caller's
    /// cancellation. Until then the steps are those of `advance`.
    pub fn advance_until(
        &self,
        s: &BallState,
        t_end: f64,
        plane: Option<&Plane>,
        stop: crate::budget::Stop<'_>,
    ) -> (BallState, Option<Event>) {
        self.advance_stoppable(s, t_end, plane, 1, true, stop)
    }

    /// [`Flight::advance_guarded`] with a stop check (see [`Flight::advance_until`]).
    fn advance_stoppable(
        &self,
        s: &BallState,
        t_end: f64,
        plane: Option<&Plane>,
        samples: usize,
        net: bool,
        stop: crate::budget::Stop<'_>,
    ) -> (BallState, Option<Event>) {
        let samples = samples.max(1);
        let mut cur = *s;
        // Every guard is > 0 where none may fire (the cheap test has a 1e-9 m margin): the exact
        // guards only near a surface.
        let mut armed: [bool; 4] = if self.may_fire(&[true; 4], &cur.p, plane) {
            let g0 = self.guards(&cur.p, plane);
            std::array::from_fn(|k| g0.0[k] > 0.0)
        } else {
            [true; 4]
        };
        armed[1] &= net;
        let mut steps = 0u64;
        while cur.t < t_end {
            steps += 1;
            if steps.is_multiple_of(crate::budget::STOP_POLL_STEPS) && stop() {
                return (cur, None);
            }
            let h = self.step.min(t_end - cur.t);
            let next = self.rk4(&cur, h);
            if !(next.t > cur.t) {
                // The clock no longer advances (|t| so large that t + h == t; the entry points
                // refuse such times, see `check_span`): stop rather than loop for ever.
                return (cur, None);
            }
            let (mut lo, mut p_lo) = (0.0, cur.p);
            for j in 1..=samples {
                let (tau, p) = if j == samples {
                    (h, next.p)
                } else {
                    let tau = h * j as f64 / samples as f64;
                    (tau, hermite(&cur, &next, tau))
                };
                // Through the net's plane x = 0 or the table's surface z = 0 between two samples:
                // the guards also where the interpolant crosses it (linear in that coordinate
                // between the samples), so that the net and the table top, thinner than the
                // travel between samples, are not passed.
                let mut crossings = [(0, 1), (2, 0)].map(|(axis, guard)| {
                    let (a, b) = (p_lo[axis], p[axis]);
                    (armed[guard] && (a < 0.0) != (b < 0.0)).then(|| lo + (tau - lo) * (a / (a - b)).clamp(0.0, 1.0))
                });
                if crossings[1] < crossings[0] && crossings[1].is_some() {
                    crossings.swap(0, 1);
                }
                for cross in crossings.into_iter().flatten().filter(|&c| c > lo) {
                    let pc = hermite(&cur, &next, cross);
                    if self.may_fire(&armed, &pc, plane) {
                        if let Some(k) = fired(&armed, &self.guards(&pc, plane)) {
                            let (before, hit_k) = self.locate(&cur, &next, (lo, cross), &armed, plane, k);
                            return (self.apply(&before, hit_k), Some(self.event(before, hit_k)));
                        }
                    }
                }
                p_lo = p;
                if self.may_fire(&armed, &p, plane) {
                    if let Some(k) = fired(&armed, &self.guards(&p, plane)) {
                        let (before, hit_k) = self.locate(&cur, &next, (lo, tau), &armed, plane, k);
                        return (self.apply(&before, hit_k), Some(self.event(before, hit_k)));
                    }
                }
                lo = tau;
            }
            cur = next;
        }
        (cur, None)
    }

    /// The state just before guard `k` (or an earlier one) fires in the step `cur` → `next`
    /// between the times `bracket` (s after `cur`; none fired at the first, `k` at the second),
    /// and which guard fired: bisection on the cubic Hermite interpolant of the position, then one
    /// RK4 step from `cur`, stepped back until every armed guard is > 0 on it.
    fn locate(
        &self,
        cur: &BallState,
        next: &BallState,
        bracket: (f64, f64),
        armed: &[bool; 4],
        plane: Option<&Plane>,
        k: usize,
    ) -> (BallState, usize) {
        let hermite = |tau: f64| hermite(cur, next, tau);
        // lo keeps every armed guard > 0 on the interpolant, hi has one ≤ 0.
        let (mut lo, mut hi) = bracket;
        let mut hit_k = k;
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            match fired(armed, &self.guards(&hermite(mid), plane)) {
                Some(kk) => {
                    hi = mid;
                    hit_k = kk;
                }
                None => lo = mid,
            }
        }
        let mut back = hi - lo;
        loop {
            if lo <= 0.0 {
                return (*cur, hit_k);
            }
            let before = self.rk4(cur, lo);
            match fired(armed, &self.guards(&before.p, plane)) {
                None => return (before, hit_k),
                Some(kk) => {
                    hit_k = kk;
                    lo -= back;
                    back *= 2.0;
                }
            }
        }
    }

    fn event(&self, before: BallState, k: usize) -> Event {
        let kind = match k {
            0 => {
                let (_, n) = table_distance(&self.table, &before.p);
                if n.z > 0.999_999 {
                    EventKind::Table
                } else {
                    EventKind::Edge
                }
            }
            1 => EventKind::Net,
            2 => EventKind::Floor,
            _ => EventKind::Plane,
        };
        Event {
            kind,
            before,
            after: self.apply(&before, k),
        }
    }

    fn apply(&self, s: &BallState, k: usize) -> BallState {
        if k != 0 {
            return *s;
        }
        let (_, n) = table_distance(&self.table, &s.p);
        let m = &self.model;
        let (dv, dw) = impulse(m, &s.v, &s.w, &n, m.table_restitution, m.table_friction);
        BallState {
            v: s.v + dv,
            w: s.w + dw,
            ..*s
        }
    }

    /// Integrates from `s` to `t_end` (s) through bounces, collecting the events, until `t_end`,
    /// a terminal event (net, floor) or a plane crossing. Returns the final state and the events.
    pub fn run(&self, s: &BallState, t_end: f64, plane: Option<&Plane>) -> (BallState, Vec<Event>) {
        self.run_until(s, t_end, plane, &|| false)
    }

    /// [`Flight::run`] that also ends, before `t_end` and without a further event, when `stop()`
    /// turns true (a caller's cancellation, see [`Flight::advance_until`]).
    pub fn run_until(
        &self,
        s: &BallState,
        t_end: f64,
        plane: Option<&Plane>,
        stop: crate::budget::Stop<'_>,
    ) -> (BallState, Vec<Event>) {
        let mut cur = *s;
        let mut events = Vec::new();
        // Each bounce loses energy; 64 events bound a flight of any practical length.
        while cur.t < t_end && events.len() < 64 {
            let (next, ev) = self.advance_until(&cur, t_end, plane, stop);
            cur = next;
            match ev {
                Some(e) => {
                    events.push(e);
                    if e.kind.terminal() || e.kind == EventKind::Plane {
                        break;
                    }
                }
                None => break,
            }
        }
        (cur, events)
    }
}

/// Position (m) at `tau` s after `cur` on the cubic Hermite interpolant of the step `cur` →
/// `next` (positions and velocities at both ends).
pub(crate) fn hermite(cur: &BallState, next: &BallState, tau: f64) -> Vector3<f64> {
    let h = next.t - cur.t;
    let s = tau / h;
    let (s2, s3) = (s * s, s * s * s);
    cur.p * (2.0 * s3 - 3.0 * s2 + 1.0)
        + cur.v * (h * (s3 - 2.0 * s2 + s))
        + next.p * (3.0 * s2 - 2.0 * s3)
        + next.v * (h * (s3 - s2))
}

/// The first armed guard that is ≤ 0 (the most negative when several are).
fn fired(armed: &[bool; 4], g: &Guards) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (k, (&on, &v)) in armed.iter().zip(g.0.iter()).enumerate() {
        if on && v <= 0.0 && best.is_none_or(|(_, b)| v < b) {
            best = Some((k, v));
        }
    }
    best.map(|(k, _)| k)
}
