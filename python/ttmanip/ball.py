"""Table-tennis ball: flight model, estimation from observations, prediction, hit planning.

Thin layer over ``ttkin::ball`` (Rust). World frame: origin at the centre of the table's playing
surface, x along the table toward the opponent (the robot stands behind the end line x = −1.37 m),
z up, y = z × x; metres, m/s, rad/s, seconds. A ball state is the (10,) array
``[t, px, py, pz, vx, vy, vz, wx, wy, wz]``. See ``docs/ball.md``.

>>> import numpy as np
>>> from ttmanip import ball
>>> s = ball.state([1.6, 0.0, 0.3], [-5.0, 0.0, 1.0])
>>> ball.predict(s, [0.1, 0.2]).shape
(2, 3)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _ttmanip as _t
from . import robots
from ._ttmanip import Robot

__all__ = [
    "BallModel",
    "Estimate",
    "Table",
    "crossing",
    "estimate",
    "plan_correct",
    "plan_return",
    "predict",
    "predict_batch",
    "racket_impact",
    "state",
    "update",
]

MODELS = ("default", "measured", "aero", "muelling", "mpi", "tt3d", "vacuum")

_TABLE = _t.ball_table()  # ttkin::ball::model::Table::default(), the one source of the numbers
_RALLY_TARGET = tuple(_t.ball_rally_config()["target"])  # RallyConfig::default()'s landing target


@dataclass(frozen=True)
class BallModel:
    """A named flight model: a = g − k_d·|v|·v + k_m·(ω × v).

    ``default`` (= ``measured``): fitted on the measured flights of the MPI PAM setup
    (``ttmanip ball fit``, docs/ball.md): k_d = 0.1229 /m, k_m = 0.00159, table restitution
    0.964, friction 0.25. Presets (table restitution 0.93, friction 0.25): ``aero`` (the previous
    default, ρ = 1.184 kg/m³, C_D = 0.5, C_L = rω/|v| → k_d = 0.1377 /m, k_m = 0.00551),
    ``muelling`` (k_d 0.1414, k_m 0.001), ``mpi`` (0.129, 0.00807), ``tt3d`` (0.141, 0.0018),
    ``vacuum`` (no air). Ball 2.7 g, 40 mm.
    """

    name: str = "default"

    def __post_init__(self) -> None:
        if self.name not in MODELS:
            raise _t.TtmanipError(f"model: unknown ball model {self.name!r}; expected one of {MODELS}")


@dataclass(frozen=True)
class Table:
    """ITTF table geometry (m) in the world frame: surface at z = 0, centred at the origin; the
    defaults are the Rust core's (``ttkin::ball::model::Table``: 2.74 × 1.525 m, 0.76 m high, net
    0.1525 m high and overhanging as much)."""

    length: float = _TABLE["length"]
    width: float = _TABLE["width"]
    height: float = _TABLE["height"]
    net_height: float = _TABLE["net_height"]
    net_overhang: float = _TABLE["net_overhang"]

    def __post_init__(self):
        _t.ball_table_check(self._core())  # the core's checks (Table::validate)

    def _core(self) -> dict[str, float]:
        """The fields as the core's ``Table`` reads them (floats, m)."""
        return {f.name: _finite_scalar(getattr(self, f.name), f.name) for f in fields(self)}

    def on_opponent_half(self, x: float, y: float) -> bool:
        """Whether (x, y) (m, world) lies on the opponent's half of the surface (the core's
        ``Table::on_opponent_half``)."""
        return _t.ball_on_opponent_half(self._core(), _finite_scalar(x, "x"), _finite_scalar(y, "y"))

    def outline(self) -> dict[str, NDArray[np.float64]]:
        """The outline to draw (m, world; the core's ``Table::outline``): ``surface`` and ``net``
        (5, 3) closed loops (the net in the plane x = 0, overhang included) and ``centre_line``
        (2, 3)."""
        return {k: np.asarray(v, float) for k, v in _t.ball_table_outline(self._core()).items()}


def _finite_scalar(v, what: str, positive: bool = False) -> float:
    """A finite real number (> 0 when ``positive``), else a TtmanipError naming ``what``."""
    try:
        f = float(v)
    except (TypeError, ValueError, OverflowError):
        raise _t.TtmanipError(f"{what}: expected a real number, got {type(v).__name__}") from None
    if not np.isfinite(f) or (positive and not f > 0.0):
        raise _t.TtmanipError(f"{what}: expected a finite{' positive' if positive else ''} number, got {v!r}")
    return f


@dataclass(frozen=True)
class Estimate:
    """A fitted ball state with its uncertainty (see ``ttkin::ball::estimate``)."""

    state: NDArray[np.float64]  # (10,) at the last usable observation
    covariance: NDArray[np.float64]  # (6, 6) of [p; v]
    spin_std: float
    spin_fitted: bool
    sigma: float
    used: int
    outliers: int
    nonfinite: int
    bounce_time: float | None
    segment: str
    extra: dict = field(default_factory=dict)

    @property
    def position(self) -> NDArray[np.float64]:
        """Position (m, world) at ``state[0]``."""
        return self.state[1:4]

    @property
    def velocity(self) -> NDArray[np.float64]:
        """Velocity (m/s, world) at ``state[0]``."""
        return self.state[4:7]

    @property
    def spin(self) -> NDArray[np.float64]:
        """Spin (rad/s, world), the part perpendicular to the velocity."""
        return self.state[7:10]


def _model(model: BallModel | str) -> str:
    return model.name if isinstance(model, BallModel) else BallModel(model).name


def _robot(robot: Robot | None) -> Robot:
    """The robot the ball planner plans for: ``robot``, or gantry6 when None."""
    return robots.gantry6() if robot is None else robot


def state(p: ArrayLike, v: ArrayLike, w: ArrayLike = (0.0, 0.0, 0.0), t: float = 0.0) -> NDArray[np.float64]:
    """A ball state (10,) from position (m), velocity (m/s), spin (rad/s) and time (s)."""
    parts = [np.array([_finite_scalar(t, "t")])]
    for name, value in (("p", p), ("v", v), ("w", w)):
        try:
            # The bindings' one conversion: complex, bool, string and object data are refused.
            a = _t.real_array(value, name)
        except TypeError:
            raise _t.TtmanipError(f"{name}: expected 3 real numbers, got {type(value).__name__}") from None
        if a.shape != (3,) or not np.isfinite(a).all():
            raise _t.TtmanipError(f"{name}: expected 3 finite numbers, got shape {a.shape}: {value!r}")
        parts.append(a)
    return np.concatenate(parts)


def estimate(t: ArrayLike, p: ArrayLike, model: BallModel | str = "default") -> Estimate:
    """Fits a ball state to observed positions ``p`` (N, 3) at times ``t`` (N,).

    Robust to outliers (Huber weights, rejection beyond 6σ), NaN rows (dropped and counted) and a
    bounce inside the window. Too few observations raise ``TtmanipError``.
    """
    d = _t.ball_estimate(t, p, _model(model))
    return Estimate(**d)


def predict(state: ArrayLike, times: ArrayLike, model: BallModel | str = "default", events: bool = False):
    """Positions (len(times), 3) of the ball from ``state`` at ``times`` (s, non-decreasing), through
    bounces; NaN after the net or the floor. With ``events=True`` also the list of events."""
    if not isinstance(events, (bool, np.bool_)):
        raise _t.TtmanipError(f"events: must be True or False, got {events!r}")
    d = _t.ball_predict(state, times, _model(model))
    if not events:
        return d["positions"]
    # The extension gives the events' serde form (states as lists); here as (10,) arrays.
    evs = [{**e, "before": np.asarray(e["before"]), "after": np.asarray(e["after"])} for e in d["events"]]
    return d["positions"], evs


def predict_batch(
    states: ArrayLike, times: ArrayLike, model: BallModel | str = "default"
) -> NDArray[np.float64]:
    """Positions (N, K, 3) of N balls ``states`` (N, 10) at ``times`` (K,), in parallel."""
    return _t.ball_predict_batch(states, times, _model(model))


def crossing(
    state: ArrayLike,
    x: float | None = None,
    *,
    point: ArrayLike | None = None,
    normal: ArrayLike | None = None,
    t_max: float = 2.0,
    model: BallModel | str = "default",
) -> dict:
    """Where, when and how fast the ball crosses a hitting plane.

    ``x``: the plane x = const (crossed toward the robot, −x); or a general plane through ``point``
    with ``normal`` (crossed from the normal's side). Returns ``{"outcome": "crossed", "state",
    "bounces"}``, or outcome ``"net"``/``"floor"`` (flight ended first) or ``"timeout"``.
    """
    if x is not None:
        point, normal = (float(x), 0.0, 0.0), (1.0, 0.0, 0.0)
    if point is None or normal is None:
        raise _t.TtmanipError("crossing: give x or both point and normal")
    return _t.ball_crossing(state, point, normal, t_max, _model(model))


def plan_return(
    state: ArrayLike,
    now: float,
    target: ArrayLike = _RALLY_TARGET,
    model: BallModel | str = "default",
    robot: Robot | None = None,
):
    """Plans ``robot``'s return (default gantry6) of the ball ``state`` for a stroke starting at
    rest at time ``now`` (s).

    The robot needs analytic IK and must reach the ready racket pose from the rally's placement
    (``ttkin::ball::hitplan::ReturnPlanner::new``); another robot raises ``ModelError``.

    Returns a dict with ``status`` ("ok", "no_bounce", "out_of_reach", "no_return",
    "infeasible") and, when ok, ``hit`` (a ``ttmanip.Hit`` when the pipeline module provides it, else the dict
    with ``pose`` (4×4, racket frame in the base frame), ``twist`` (6,), ``t_hit`` (s from now)),
    ``q_hit``, ``qd_hit``, ``v_out``, ``normal``, ``racket_velocity``, ``margin``, ``landing``.
    A target off the opponent's half raises ``TtmanipError``.
    """
    d = _t.ball_plan_return(_robot(robot), state, float(now), target, _model(model))
    if d["status"] == "ok":
        from . import pipeline

        hit_cls = getattr(pipeline, "Hit", None)
        d["hit"] = (
            hit_cls(d["pose"], d["twist"], d["t_hit"])
            if hit_cls is not None
            else {
                "pose": d["pose"],
                "twist": d["twist"],
                "t": d["t_hit"],
            }
        )
    return d


def racket_impact(
    state: ArrayLike, normal: ArrayLike, velocity: ArrayLike, model: BallModel | str = "default"
) -> NDArray[np.float64]:
    """The racket impact model: the ball ``state`` (10,) just before, the racket's unit face
    ``normal`` (3,) and its face velocity (3,, m/s) at the contact (world frame) in; the ball state
    (10,) just after out (``ttkin::ball::impact::RacketImpact``: restitution 0.85, friction 0.9
    with the rolling cap, Nakashima's impulse relative to the racket)."""
    return _t.ball_racket_impact(state, normal, velocity, _model(model))


def racket_hit(
    state: ArrayLike, normal: ArrayLike, velocity: ArrayLike, model: BallModel | str = "default"
) -> NDArray[np.float64]:
    """Deprecated name of :func:`racket_impact` (a *hit* is the robot's request, see the glossary)."""
    warnings.warn("ball.racket_hit is deprecated; use ball.racket_impact", DeprecationWarning, stacklevel=2)
    return racket_impact(state, normal, velocity, model)


BOUNCE_SPREAD: tuple[float, float, float] = tuple(_t.BOUNCE_SPREAD)
"""The rally's prior spread (m/s, world x, y, z) of the ball's own bounce kick (``update``)."""


def update(
    t: ArrayLike,
    p: ArrayLike,
    t_new: ArrayLike,
    p_new: ArrayLike,
    model: BallModel | str = "default",
    bounce_spread: ArrayLike | None = None,
) -> dict:
    """The estimate of observations ``p`` (N, 3) at ``t`` (N,) updated with later observations
    ``p_new`` (M, 3) at ``t_new`` (M,), through a bounce between them (``ttkin::ball::update``):
    ``state`` (10,) at the last new observation, ``at_prior`` (10,), ``covariance`` (9, 9) of
    [p; v; ω] at the prior's time, ``used``, ``outliers``, ``bounced``.

    ``bounce_spread`` (3,) (m/s, each > 0; e.g. :data:`BOUNCE_SPREAD`): the ball's own bounce, as
    the rally's correction makes it (``update_kick``): a velocity kick at the bounce is fitted
    with that prior spread and kept only when the observations after the bounce call for it (a
    χ² gate). None: the plain update, the model's bounce exactly."""
    return _t.ball_update(t, p, t_new, p_new, _model(model), bounce_spread)


def plan_correct(
    state: ArrayLike,
    now: float,
    target: ArrayLike,
    state_new: ArrayLike,
    t_c: float,
    after_bounce: bool,
    model: BallModel | str = "default",
    robot: Robot | None = None,
) -> dict:
    """The correction of a planned hit, as the rally makes it after the bounce: ``robot``'s
    (default gantry6, as :func:`plan_return`) return of ``state`` planned for a stroke from rest
    at ``now`` (s) landing at ``target`` (x, y, m),
    then, that stroke under way, planned again at ``t_c`` (s) for the ball ``state_new`` (e.g.
    :func:`update`'s state; ``after_bounce`` when past its bounce) near the first hit
    (``ReturnPlanner::plan_near`` from the stroke's joint state at ``t_c``). Returns ``first`` and
    ``corrected``, plan dicts as :func:`plan_return`'s (``status`` and the hit's items)."""
    if not isinstance(after_bounce, (bool, np.bool_)):
        raise _t.TtmanipError(f"after_bounce: must be True or False, got {after_bounce!r}")
    now = _finite_scalar(now, "now")
    t_c = _finite_scalar(t_c, "t_c")
    return _t.ball_plan_correct(
        _robot(robot), state, now, target, state_new, t_c, bool(after_bounce), _model(model)
    )
