"""Trajectory generation: joint polynomials, via points, task-space lines and arcs, hitting strokes.

The maths lives in the Rust core (``ttkin::traj``); these functions convert arguments and return
the native trajectory objects. Units are SI: joint values in rad (revolute) or m (prismatic),
time in s, poses 4×4 in the robot's base frame.

Joint-space results are :class:`JointTrajectory` objects with ``duration``, ``sample(t)`` →
``(q, qd, qdd)``, ``sample_rate(rate_hz)`` → ``(t, q, qd, qdd)`` and ``check_limits(robot)`` (exact
peaks, not sampled). Task-space results are :class:`CartesianTrajectory` objects whose
``sample(t)`` gives ``(pose, twist, twist_dot)``.

>>> import ttmanip.traj as tt
>>> traj = tt.cubic([0.0], [1.6], 2.0)
>>> [round(float(x[0]), 6) for x in traj.sample(0.5)]
[0.25, 0.9, 1.2]
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._ttmanip import (
    CartesianTrajectory,
    JointTrajectory,
    Robot,
    ShapeError,
    TtmanipError,
    real_array,
    traj_cubic,
    traj_minimal_duration,
    traj_quintic,
    traj_quintic_samples,
    traj_stroke,
    traj_via,
)

__all__ = [
    "CartesianTrajectory",
    "JointTrajectory",
    "Stroke",
    "arc",
    "cubic",
    "line",
    "minimal_duration",
    "quintic",
    "quintic_samples",
    "stroke",
    "via",
]


# Joint polynomials and via points are the native functions themselves (their signatures and
# docs: ``_ttmanip.pyi`` and ``crates/ttkin-py/src/traj.rs``); nothing to convert here.
cubic = traj_cubic
quintic = traj_quintic
quintic_samples = traj_quintic_samples
via = traj_via


def line(
    T0: ArrayLike, T1: ArrayLike, duration: float, law: str = "quintic", blend: float = 0.25
) -> CartesianTrajectory:
    """Straight-line tool motion from pose ``T0`` to ``T1`` (4×4) with slerp orientation.

    ``law``: ``"cubic"``, ``"quintic"`` or ``"trapezoid"`` (``blend``: fraction of the duration
    spent accelerating, in (0, 0.5]).
    """
    return CartesianTrajectory.line(T0, T1, duration, law, blend)


def arc(
    T0: ArrayLike,
    T1: ArrayLike | None = None,
    duration: float | None = None,
    *,
    via: ArrayLike | None = None,
    centre: ArrayLike | None = None,
    axis: ArrayLike | None = None,
    angle: float | None = None,
    law: str = "quintic",
    blend: float = 0.25,
) -> CartesianTrajectory:
    """Circular-arc tool motion, either through three points or about an axis.

    ``arc(T0, T1, duration, via=p)``: from pose T0 through point p (3,) to pose T1, slerp orientation.
    ``arc(T0, duration=d, centre=c, axis=k, angle=a)``: rotate pose T0 about the line through c
    along k by a rad (right-handed); the tool turns with the arc.
    """
    if duration is None:
        raise TypeError("arc: duration is required")
    if via is not None:
        if T1 is None or centre is not None or axis is not None or angle is not None:
            raise TypeError("arc: give either (T1, via) or (centre, axis, angle)")
        return CartesianTrajectory.arc_through(T0, via, T1, duration, law, blend)
    if centre is None or axis is None or angle is None or T1 is not None:
        raise TypeError("arc: give either (T1, via) or (centre, axis, angle)")
    return CartesianTrajectory.arc_about(T0, centre, axis, angle, duration, law, blend)


minimal_duration = traj_minimal_duration


@dataclass(frozen=True)
class Stroke:
    """A planned hitting stroke: hit leg then return leg, time 0 = now."""

    trajectory: JointTrajectory
    t_hit: float
    requested_t_hit: float
    return_duration: float
    violations: list[dict[str, Any]] = field(default_factory=list)

    @property
    def on_time(self) -> bool:
        """Whether the requested hit time was kept."""
        return self.t_hit == self.requested_t_hit

    @property
    def feasible(self) -> bool:
        """Whether every limit holds (position limits included)."""
        return not self.violations


def _float_array(x: Any, what: str) -> np.ndarray:
    """``x`` as a float array; ragged or non-numeric data is a ShapeError naming ``what``."""
    try:
        # The bindings' one conversion: complex, bool, string and object data are refused.
        return real_array(x, what)
    except (TypeError, OverflowError) as e:
        raise ShapeError(f"{what}: expected an array of real numbers ({e})") from None


def joint_state_parts(state: Any) -> dict:
    """The one reading of a joint state argument (``stroke``, ``plan_hit``, ``plan_hits``): q, qd
    and qdd as given (unconverted; the bindings check them), from None (``{}``), a mapping with
    keys q, qd, qdd (any other key is refused), an object with attributes q, qd, qdd, a tuple
    or list (q,), (q, qd) or (q, qd, qdd), or q alone."""
    if state is None:
        return {}
    if isinstance(state, Mapping):
        unknown = set(state) - {"q", "qd", "qdd"}
        if unknown:
            raise TtmanipError(f"state: unknown keys {sorted(unknown)}; use 'q', 'qd', 'qdd'")
        if "q" not in state:
            raise TtmanipError("state: missing key 'q'")
        return {k: state[k] for k in ("q", "qd", "qdd") if k in state}
    if hasattr(state, "q"):
        parts = {k: getattr(state, k, None) for k in ("q", "qd", "qdd")}
        return {k: v for k, v in parts.items() if v is not None}
    if isinstance(state, (tuple, list)) and state and np.ndim(state[0]) >= 1:
        if not 1 <= len(state) <= 3:
            raise TtmanipError(f"state: expected (q,), (q, qd) or (q, qd, qdd), got {len(state)} items")
        return dict(zip(("q", "qd", "qdd"), state, strict=False))
    return {"q": state}


def _state(state: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, qd, qdd) as float arrays from :func:`joint_state_parts` (qd, qdd zero when not given)."""
    parts = joint_state_parts(state)
    if "q" not in parts:
        raise TtmanipError("state: expected q (n,), (q, qd[, qdd]) or a mapping with 'q'")
    q = _float_array(parts["q"], "state" if state is parts["q"] else "state.q")
    if q.ndim != 1:
        raise ShapeError(f"state: expected q of shape (n,), got shape {q.shape}")
    zero = np.zeros_like(q)
    qd = zero if parts.get("qd") is None else _float_array(parts["qd"], "state.qd")
    qdd = zero if parts.get("qdd") is None else _float_array(parts["qdd"], "state.qdd")
    return q, qd, qdd


def stroke(
    robot: Robot | None,
    state: Any,
    q_hit: ArrayLike,
    qd_hit: ArrayLike,
    t_hit: float,
    ready: ArrayLike,
    qdd_hit: ArrayLike | None = None,
    *,
    velocity: ArrayLike | None = None,
    acceleration: ArrayLike | None = None,
    jerk: ArrayLike | None = None,
    return_duration: float | None = None,
) -> Stroke:
    """Plans a hitting stroke with quintics (the patent's step S104).

    From ``state`` — ``(q, qd, qdd)``, a mapping or object with ``q``/``qd``/``qdd``, or just
    ``q`` at rest — reach ``(q_hit, qd_hit, qdd_hit)`` (acceleration zero by default) at ``t_hit``
    s, then rest at ``ready``. Limits: the robot's velocity, acceleration and position limits,
    overridden by ``velocity``/``acceleration``; ``jerk`` optional (inf otherwise). When t_hit is
    infeasible the earliest feasible later hit time is used (root bracketing on the duration with
    exact quintic extrema); the return leg takes its minimal feasible duration unless given.
    """
    q0, qd0, qdd0 = _state(state)
    n = q0.shape[0]
    inf = np.full(n, np.inf)
    lower = upper = None
    if robot is not None:
        vel, acc = robot.velocity_limits, robot.acceleration_limits
        lim = robot.limits
        lower, upper = lim[:, 0].copy(), lim[:, 1].copy()
    else:
        vel, acc = inf, inf
    vel = vel if velocity is None else _float_array(velocity, "velocity")
    acc = acc if acceleration is None else _float_array(acceleration, "acceleration")
    jrk = inf if jerk is None else _float_array(jerk, "jerk")
    q_hit = _float_array(q_hit, "q_hit")
    hit = (
        q_hit,
        _float_array(qd_hit, "qd_hit"),
        np.zeros_like(q_hit) if qdd_hit is None else _float_array(qdd_hit, "qdd_hit"),
    )
    traj, t, back, violations = traj_stroke(
        (q0, qd0, qdd0), hit, t_hit, ready, vel, acc, jrk, lower, upper, return_duration
    )
    return Stroke(traj, t, float(t_hit), back, violations)


def check_cartesian_limits(
    traj: CartesianTrajectory,
    robot: Robot,
    ik: Callable,
    q_start: ArrayLike,
    rate_hz: float = 1000.0,
    *,
    hz: float | None = None,
) -> list[dict[str, Any]]:
    """Limit check of a task-space trajectory through IK sampled at ``rate_hz`` (finite
    differences); ``hz`` is its deprecated name.

    Returns the worst violation per joint and quantity (position, velocity, acceleration) as
    dicts like :meth:`JointTrajectory.check_limits`; unlike it, values are sampled, not exact.
    """
    if hz is not None:
        warnings.warn(
            "check_cartesian_limits(hz=...) is deprecated; use rate_hz=...", DeprecationWarning, stacklevel=2
        )
        rate_hz = hz
    return traj.check_limits(robot, ik, q_start, rate_hz)
