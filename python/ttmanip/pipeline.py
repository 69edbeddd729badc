"""The hit pipeline: hit parameters → IK → joint velocities → stroke → torques → drives.

The maths is Rust (``ttkin::hit``); this module is the user-facing layer:

- :class:`Hit`: racket pose (4×4, racket frame in the robot's base frame, m), racket-centre twist
  ``[v; ω]`` (base axes, m/s, rad/s) and hit time (s from now). The racket frame has its origin at
  the racket centre and its z axis along the face normal (:func:`Hit.from_normal`);
- :func:`plan_hit` / :func:`plan_hits`: a :class:`HitPlan` per hit (status instead of an
  exception for an infeasible request, unless ``raise_on_failure``);
- :func:`simulate`: the plan executed by every axis's drive cascade and motor model on the
  robot's rigid-body dynamics with gravity (``ttmanip.DriveSim``), with the racket's pose and
  velocity over time and its errors at the hit.

>>> import numpy as np, ttmanip
>>> robot = ttmanip.robots.gantry6()
>>> plan = ttmanip.plan_hit(robot, ttmanip.DEMO_HIT)
>>> plan.ok, plan.status, round(plan.t_hit, 3)
(True, 'ok', 0.35)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _ttmanip
from ._ttmanip import HitPlan, Robot, ShapeError, TtmanipError
from .traj import joint_state_parts

__all__ = [
    "DEMO_HIT",
    "Hit",
    "HitError",
    "HitPlan",
    "SimResult",
    "plan_hit",
    "plan_hits",
    "racket_frame",
    "racket_mount",
    "racket_states",
    "simulate",
]


class HitError(TtmanipError):
    """A hit plan did not come out on time within every limit (``raise_on_failure=True``)."""


def racket_frame(normal, handle=None) -> np.ndarray:
    """(3, 3) racket orientation (base axes): z along the face ``normal``, x (the handle) as close
    as possible to ``handle`` (base +z by default)."""
    return _ttmanip.racket_frame(normal, handle)


def racket_mount(robot: Robot) -> np.ndarray:
    """(4, 4) racket frame in ``robot``'s tool frame (m): identity for gantry6, centre 0.15 m along
    tool z with the face normal along tool x for mobile8."""
    return _ttmanip.racket_mount(robot)


def _array(value: Any, shape: tuple[int, ...], what: str, flat: bool = False) -> np.ndarray:
    """``value`` as a read-only finite float array of ``shape`` (``flat``: any array of as many
    numbers, reshaped); :class:`ShapeError` or :class:`NonFiniteError` naming ``what`` otherwise."""
    expected = f"{int(np.prod(shape))} numbers" if flat else f"numbers of shape {shape}"
    try:
        # The bindings' one conversion: complex, bool, string and object data are refused.
        a = _ttmanip.real_array(value, what)
    except TypeError as e:
        raise ShapeError(f"{what}: expected {expected}, got {value!r}") from e
    if flat:
        if a.size != np.prod(shape):
            raise ShapeError(f"{what}: expected {expected}, got {a.size}")
        a = a.reshape(shape)
    if a.shape != shape:
        raise ShapeError(f"{what}: expected shape {shape}, got {a.shape}")
    if not np.isfinite(a).all():
        raise _ttmanip.NonFiniteError(f"{what}: every value must be finite, got {a.tolist()}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Hit:
    """Hit parameters: ``pose`` (4×4 racket pose, base frame, m), ``twist`` (6,) racket-centre
    ``[v (m/s); ω (rad/s)]`` in base axes, ``t`` hit time (s from now, > 0)."""

    pose: np.ndarray
    twist: np.ndarray
    t: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "pose", _array(self.pose, (4, 4), "hit.pose"))
        object.__setattr__(self, "twist", _array(self.twist, (6,), "hit.twist"))
        try:
            t = float(self.t)
        except (TypeError, ValueError, OverflowError) as e:
            raise TtmanipError(f"hit.t: expected a time in s, got {self.t!r}") from e
        if not (np.isfinite(t) and t > 0.0):
            raise TtmanipError(f"hit.t: the hit time must be finite and > 0 s, got {t}")
        # The planner's own check (rigid pose, hit time within the longest stroke), at construction.
        _ttmanip.hit_check(self.pose, self.twist, t)
        object.__setattr__(self, "t", t)

    @classmethod
    def from_normal(cls, centre, normal, velocity, t, omega=None, handle=None) -> Hit:
        """A hit from the racket ``centre`` (m), face ``normal`` (any length), centre ``velocity``
        (m/s), hit time ``t`` (s) and angular velocity ``omega`` (rad/s, zero by default), all in
        base axes; the handle points as close as possible to ``handle`` (base +z by default)."""
        c = _array(centre, (3,), "centre")
        v = _array(velocity, (3,), "velocity")
        w = np.zeros(3) if omega is None else _array(omega, (3,), "omega")
        pose = np.eye(4)
        pose[:3, :3] = racket_frame(_array(normal, (3,), "normal"), handle)
        pose[:3, 3] = c
        return cls(pose, np.r_[v, w], t)

    @property
    def centre(self) -> np.ndarray:
        """Racket centre (3,), m, base frame."""
        return self.pose[:3, 3]

    @property
    def normal(self) -> np.ndarray:
        """Unit face normal (3,), base axes."""
        return self.pose[:3, 2]

    @property
    def velocity(self) -> np.ndarray:
        """Racket-centre velocity (3,), m/s, base axes."""
        return self.twist[:3]


#: Seed 002's demo hit on gantry6: centre (0.35, −0.55, 0.05) m, face normal (0.3, −1, −0.2),
#: 3 m/s along the normal, at 0.55 s (the earliest within gantry6's drives is 0.503 s, a quintic;
#: the 0.35 s of before issue 28 needs 1.3× θ3's drive peak torque, which the sampled effort
#: check missed).
DEMO_HIT = Hit.from_normal(
    [0.35, -0.55, 0.05],
    [0.3, -1.0, -0.2],
    3.0 * np.array([0.3, -1.0, -0.2]) / np.linalg.norm([0.3, -1.0, -0.2]),
    0.55,
)


def _keywords(robot: Robot, state, ready, profile: str, task: str, jerk, effort: bool) -> dict:
    """The keywords :func:`plan_hit` and :func:`plan_hits` pass on to the planner."""
    return dict(ready=ready, profile=profile, task=task, jerk=jerk, effort=effort, **joint_state_parts(state))


def _check_hit(hit) -> Hit:
    if not isinstance(hit, Hit):
        raise TtmanipError(f"hit: expected a ttmanip.Hit, got {type(hit).__name__}")
    return hit


def plan_hit(
    robot: Robot,
    hit: Hit,
    state=None,
    *,
    ready=None,
    profile: str = "auto",
    task: str = "auto",
    jerk=None,
    effort: bool = True,
    raise_on_failure: bool = False,
) -> HitPlan:
    """Plans ``hit`` from ``state`` (at rest at ``ready`` when None; q, (q, qd[, qdd]) or a dict)
    back to rest at ``ready`` (default: the start, or the robot's ready pose).

    ``profile``: ``"auto"`` (quintic when on time within the limits, else jerk-limited),
    ``"quintic"`` or ``"jerk"``; ``task``: ``"auto"`` (6-D pose, or the 5-D racket task for a
    redundant robot), ``"pose"`` or ``"racket5"``; ``jerk``: jerk limits (n,), default 200 × the
    acceleration limits; ``effort``: check the torques (inverse dynamics with friction and gravity
    at 12 instants per leg) against the effort limits and move the hit later until they hold.
    An infeasible hit gives a plan with ``ok`` False and a ``status``; with ``raise_on_failure``
    it raises :class:`HitError` instead.
    """
    hit = _check_hit(hit)
    plan = _ttmanip.hit_plan(
        robot,
        hit.pose,
        hit.twist,
        hit.t,
        **_keywords(robot, state, ready, profile, task, jerk, effort),
    )
    if raise_on_failure and not plan.ok:
        raise HitError(f"hit: {plan.status}: {plan.message}")
    return plan


def plan_hits(
    robot: Robot,
    hits,
    state=None,
    *,
    ready=None,
    profile: str = "auto",
    task: str = "auto",
    jerk=None,
    effort: bool = True,
    raise_on_failure: bool = False,
) -> list[HitPlan]:
    """:func:`plan_hit` for a sequence of hits from the same state, planned in parallel in Rust.

    The plans of one call are bounded in bytes (512 MiB, ``ttkin::budget::MAX_BYTES``): a list
    too long for that (about 2·10⁵ hits on a 6-joint robot) is refused before planning starts, and
    a batch whose plans outgrow it (jerk-limited strokes are larger) ends with an error; both say
    how many hits a call may take. Ctrl-C stops the batch within one hit per thread."""
    if isinstance(hits, Hit) or not isinstance(hits, (list, tuple)):
        raise TtmanipError(
            f"hits: expected a list or tuple of ttmanip.Hit, got {type(hits).__name__} (one hit: plan_hit)"
        )
    # The plans' bytes bounded before anything is stacked (10⁷ hits stacked 1.19 GiB of poses).
    _ttmanip.hit_batch_check(robot, len(hits))
    hits = [_check_hit(h) for h in hits]
    # An empty list still has its other arguments checked (by the planner, on no hits).
    poses = np.stack([h.pose for h in hits]) if hits else np.zeros((0, 4, 4))
    twists = np.stack([h.twist for h in hits]) if hits else np.zeros((0, 6))
    times = np.array([h.t for h in hits])
    plans = _ttmanip.hit_plan_batch(
        robot,
        poses,
        twists,
        times,
        **_keywords(robot, state, ready, profile, task, jerk, effort),
    )
    if raise_on_failure:
        for i, p in enumerate(plans):
            if not p.ok:
                raise HitError(f"hits[{i}]: {p.status}: {p.message}")
    return plans


def racket_states(robot: Robot, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, ...]:
    """Racket poses (K, 4, 4), centres (K, 3), normals (K, 3) and centre velocities (K, 3), base
    frame, for joint states ``q``, ``qd`` (K, n)."""
    states = _ttmanip.racket_states(robot, np.atleast_2d(q), np.atleast_2d(qd))  # ttkin::hit::racket
    poses = states[:, :16].reshape(-1, 4, 4)
    return poses, poses[:, :3, 3], poses[:, :3, 2], states[:, 16:19]


@dataclass
class SimResult:
    """A plan executed by the drives: ``DriveSim.run`` arrays, the racket over time and its errors
    at the hit (racket centre m, face normal degrees, centre velocity m/s and relative)."""

    plan: HitPlan
    arrays: dict
    racket_pose: np.ndarray
    racket_centre: np.ndarray
    racket_normal: np.ndarray
    racket_velocity: np.ndarray
    racket_position_error_m: float
    racket_normal_error_deg: float
    racket_velocity_error_mps: float
    racket_velocity_error_rel: float
    hit_index: int
    faults: list = field(default_factory=list)

    def __getitem__(self, key: str) -> np.ndarray:
        return self.arrays[key]

    @property
    def t(self) -> np.ndarray:
        """Sample times (K,), s."""
        return self.arrays["t"]

    def summary(self) -> dict:
        """The errors at the hit and the drive faults, JSON-ready."""
        return {
            "racket_position_error_m": self.racket_position_error_m,
            "racket_normal_error_deg": self.racket_normal_error_deg,
            "racket_velocity_error_mps": self.racket_velocity_error_mps,
            "racket_velocity_error_rel": self.racket_velocity_error_rel,
            "faults": self.faults,
        }


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    c = np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b))
    s = np.linalg.norm(np.cross(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(np.degrees(np.arctan2(s, c)))


def simulate(
    robot: Robot,
    plan: HitPlan,
    *,
    setpoint_hz: float | None = None,
    noise=None,
    seed: int = 0,
    rate_hz: float = 1000.0,
    gravity: bool = True,
    rate: float | None = None,
    setpoint_rate: float | None = None,
) -> SimResult:
    """Executes ``plan`` on ``ttmanip.DriveSim``: the stroke sampled at ``rate_hz`` with its
    inverse-dynamics torques as feed-forward, setpoints handed to every axis's drive at
    ``setpoint_hz`` Hz (None: ``DriveSim``'s default, 1 kHz), optional sensor ``noise`` (see
    ``DriveSim``), gravity on. Returns the executed states, currents, the racket over time and
    its errors at the hit. ``rate`` and ``setpoint_rate`` are the deprecated names of ``rate_hz``
    and ``setpoint_hz``."""
    from ._ttmanip import DriveSim

    if rate is not None:
        warnings.warn("simulate(rate=...) is deprecated; use rate_hz=...", DeprecationWarning, stacklevel=2)
        rate_hz = rate
    if setpoint_rate is not None:
        warnings.warn(
            "simulate(setpoint_rate=...) is deprecated; use setpoint_hz=...", DeprecationWarning, stacklevel=2
        )
        setpoint_hz = setpoint_rate

    if not isinstance(plan, HitPlan):
        raise TtmanipError(f"plan: expected a ttmanip.HitPlan, got {type(plan).__name__}")
    if not plan.made_for(robot):
        raise TtmanipError(
            f"plan: made for robot '{plan.robot_name}' ({len(plan.start)} joints), not for "
            f"'{robot.name}' ({robot.dof} joints): plan the hit for the robot you simulate"
        )
    if plan.trajectory is None:
        raise HitError(f"plan: nothing to simulate (status '{plan.status}': {plan.message})")
    t, q, qd, qdd = plan.sample(rate_hz)
    tau = plan.torques(rate_hz)
    rates = {} if setpoint_hz is None else {"setpoint_hz": setpoint_hz}
    sim = DriveSim(robot, gravity=gravity, noise=noise, seed=seed, **rates)
    sim.reset(q[0], qd[0])
    arrays = sim.run(t, q, qd, qdd, tau_ff=tau)
    te = np.asarray(arrays["t"])
    qe = np.asarray(arrays["q"])
    qde = np.asarray(arrays["qd"])
    poses, centre, normal, vel = racket_states(robot, qe, qde)
    # The executed state at the hit time, interpolated between the two samples around it.
    q_hit = np.array([np.interp(plan.t_hit, te, qe[:, j]) for j in range(qe.shape[1])])
    qd_hit = np.array([np.interp(plan.t_hit, te, qde[:, j]) for j in range(qde.shape[1])])
    _, c_hit, n_hit, v_hit = racket_states(robot, q_hit, qd_hit)
    v_want = np.asarray(plan.hit_twist[:3])
    dv = float(np.linalg.norm(v_hit[0] - v_want))
    return SimResult(
        plan=plan,
        arrays=arrays,
        racket_pose=poses,
        racket_centre=centre,
        racket_normal=normal,
        racket_velocity=vel,
        racket_position_error_m=float(np.linalg.norm(c_hit[0] - plan.hit_pose[:3, 3])),
        racket_normal_error_deg=_angle_deg(n_hit[0], plan.hit_pose[:3, 2]),
        racket_velocity_error_mps=dv,
        racket_velocity_error_rel=dv / max(float(np.linalg.norm(v_want)), 1e-12),
        hit_index=int(np.argmin(np.abs(te - plan.t_hit))),
        faults=list(arrays.get("faults", [])),
    )
