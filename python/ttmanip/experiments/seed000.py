"""Seed 000's simulation: joint-limit avoidance of the 8-joint mobile manipulator by weighted
least norm (Chan–Dubey weights from the joint-limit criterion (21)), redone with the corrected
mathematics and closed-loop tracking (CLIK at 1 kHz, loop in Rust).

Model: Table 1 read literally (``ttmanip.robots.mobile8``: modified DH, joint 1 prismatic, lengths
mm → m), start q = [0.26 m, 200°, 90°, 80°, 250°, 105°, 180°, 135°]. Task: the 5-D racket task
[centre (m), polar, azimuth (rad)] of the racket centre 0.15 m along z8 and of the face normal
(tool x axis).

Target. Our FK gives x(0) = [0.325, 0.134, 0.507, 1.271, 0.772], not the paper's x(0) (the paper's
⁰T₈ cannot be reproduced from Table 1, see ../shared/seeds/README.md). The seed's
x(4) = [0.5501, 1.0647, 0.3998, 0.4699, 1.0528] is out of reach of the literal model: its racket
centre lies 1.20 m from the axis of the prismatic joint 1 (which moves along the base z axis and so
cannot bring it closer), while the arm from joint 2 to the racket centre spans at most
0.068 + 0.156 + 0.325 + 0.15 ≈ 0.70 m. We move to the reachable racket pose *nearest* to x(4):

- Distance to x(4) (:func:`distance_to_x4`): ``|c − c₄| + NORMAL_WEIGHT · ∠(n, n₄)`` with the
  racket centres c (m), the face normals n and ``NORMAL_WEIGHT`` = 0.1 m/rad (1° of normal error
  counts as 1.7 mm of centre error). At the optimum the normal matches n₄ to < 1e-3°, so the
  lexicographic rule (nearest centre, then nearest normal) picks the same pose.
- Reachable, with margins (:func:`nearest_reachable`): every joint at least ``LIMIT_MARGIN``
  (0.02 m for the prismatic joint, 5° for the revolute ones) inside its limits, and the smallest
  singular value of the 5 × 8 racket task Jacobian at least ``SIGMA_MARGIN`` = 0.05 (half its value
  0.0998 at the start): the nearest centre is reached by stretching the arm toward x(4), i.e. at a
  singularity, which the margin keeps away from. Found by SciPy's SLSQP within the shrunken
  box (a quadratic penalty on the σ_min margin; the gradient from the core's task and geometric
  Jacobians), started from the start configuration and from the 20 nearest of 20,000 random
  in-box configurations; the tests check that no one of 100,000 random configurations obeying the same
  margins is nearer. Without the singularity margin the nearest distance is about 5.6 mm smaller.
- Time law: the racket coordinates of FK along the quintic (rest-to-rest) joint-space path from
  the start to that configuration, 4 s, with their exact rates ẋ = J_x q̇ — reachable at every
  sample by construction (a straight task-space line toward x(4) turns singular at ~18 % of the
  way, the previous version of this experiment stopped at 15 % of it). The CLIK tracker does not
  follow that joint path: weighted least norm with Chan–Dubey weights chooses its own joint
  motion for the task path.

The unweighted comparison runs the same task path with the plain pseudo-inverse and nothing
keeping the joints inside their limits. On this motion it comes closer to a limit than the
weighted solution (joint j2) but crosses none; the figure therefore also shows the straight
task-space line to 15 % of the way toward x(4) (the previous target), on which the unweighted
solution drives joint j5 past its limit while the weighted one stays inside.

Writes into ``out_dir``: ``fig08_joint_positions.png``, ``fig09_joint_speeds.png``,
``fig10_tracking_error.png``, ``fig_unweighted_comparison.png``, ``weighted.csv``,
``unweighted.csv`` and ``summary.json``.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .. import Robot, robots, traj  # noqa: E402
from ..mobile import TrackResult, task_line, track  # noqa: E402

#: The seed's start configuration (m, rad): mobile8's ready configuration, from the robot's data.
Q_START = robots.mobile8_start()
#: The seed's printed x(4): racket centre (m), polar and azimuth of the face normal (rad).
X4_SEED = np.array([0.5501, 1.0647, 0.3998, 0.4699, 1.0528])
#: The previous target: this fraction of the straight task-space line toward x(4) (comparison only).
LINE_FRACTION = 0.15
DURATION = 4.0
RATE_HZ = 1000.0
#: Arm span from joint 2 to the racket centre (m): d2 + d4 + d5 + racket offset of Table 1.
ARM_SPAN = 0.068 + 0.156 + 0.325 + 0.15
#: Weight of the face-normal angle in the distance to x(4) (m/rad).
NORMAL_WEIGHT = 0.1
#: Margin kept from the joint limits by the target: m for the prismatic joint, rad for the others.
LIMIT_MARGIN = (0.02, np.radians(5.0))
#: Smallest singular value of the racket task Jacobian the target keeps (the start has 0.0998).
SIGMA_MARGIN = 0.05


def x4_centre_normal() -> tuple[np.ndarray, np.ndarray]:
    """The seed's x(4) as racket centre (m) and unit face normal."""
    polar, azimuth = X4_SEED[3], X4_SEED[4]
    n = np.array([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)])
    return X4_SEED[:3].copy(), n


def _normal(polar: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """Unit face normals from racket task angles (rad)."""
    sp = np.sin(polar)
    return np.stack([sp * np.cos(azimuth), sp * np.sin(azimuth), np.cos(polar)], axis=-1)


def _task_rows(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The core's racket task coordinates of q (n,) or (N, n): one batched call
    (``Robot.task_coordinates``, ``ttkin::task::Task::coordinates_batch``)."""
    return robot.task_coordinates(q, "racket5")


def racket_centre_normal(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Racket centres (m) and face normals in the base frame for q (n,) or (N, n): the core's
    racket task (the robot's racket mount, ``Robot.task_coordinates``)."""
    x = _task_rows(robot, q)
    return x[..., :3], _normal(x[..., 3], x[..., 4])


def distance_to_x4(c: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The distance to the seed's x(4): |c − c₄| (m) + NORMAL_WEIGHT · angle(n, n₄) (rad)."""
    c4, n4 = x4_centre_normal()
    angle = np.arctan2(np.linalg.norm(np.cross(n, n4), axis=-1), n @ n4)
    return np.linalg.norm(c - c4, axis=-1) + NORMAL_WEIGHT * angle


def distance_of_coordinates(x: np.ndarray) -> float:
    """:func:`distance_to_x4` of racket task coordinates [centre (m), polar, azimuth (rad)]."""
    n = np.array([np.sin(x[3]) * np.cos(x[4]), np.sin(x[3]) * np.sin(x[4]), np.cos(x[3])])
    return float(distance_to_x4(np.asarray(x[:3]), n))


def task_sigma_min(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Smallest singular value of the racket5 task Jacobian (``Robot.task_jacobian``) for q (n,)
    or (N, n)."""
    jacobians = robot.task_jacobian(q, "racket5")  # one batched call for (N, n)
    return np.linalg.svd(jacobians, compute_uv=False)[..., -1]


def margin_box(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Joint limits shrunk by ``LIMIT_MARGIN`` (m or rad), lower and upper (n,)."""
    margin = np.array([LIMIT_MARGIN[0] if k == "prismatic" else LIMIT_MARGIN[1] for k in robot.joint_types])
    return robot.limits[:, 0] + margin, robot.limits[:, 1] - margin


#: Smoothing of the normal angle at 0 in the optimiser's objective (rad²): changes it by < 1e-5 m.
_ANGLE_SMOOTHING = 1e-10
#: Weight of the quadratic penalty on the σ_min margin in the optimiser's objective.
_SIGMA_PENALTY = 1e4
#: Step of the central differences of the task Jacobian for the gradient of σ_min (rad or m).
_SIGMA_STEP = 1e-7


def _sigma_min_gradient(robot: Robot, q: np.ndarray) -> tuple[float, np.ndarray]:
    """σ_min of the racket5 task Jacobian J(q) and its gradient (n,): dσ/dq_k = uᵀ (∂J/∂q_k) v with
    the singular vectors u, v of σ_min (a simple singular value), ∂J/∂q_k by central differences of
    the core's task Jacobian."""
    u_all, s, vt = np.linalg.svd(robot.task_jacobian(q, "racket5"), full_matrices=False)
    u, v = u_all[:, -1], vt[-1]
    grad = np.empty(len(q))
    for k in range(len(q)):
        dq = np.zeros(len(q))
        dq[k] = _SIGMA_STEP
        dj = robot.task_jacobian(q + dq, "racket5") - robot.task_jacobian(q - dq, "racket5")
        grad[k] = u @ dj @ v / (2.0 * _SIGMA_STEP)
    return float(s[-1]), grad


def _objective(robot: Robot, q: np.ndarray) -> tuple[float, np.ndarray]:
    """The optimiser's objective and its gradient (n,) at q: the distance to x(4) with the normal
    angle smoothed at 0, plus a quadratic penalty on the σ_min margin (ends just above it). The
    gradient comes from the core's Jacobians: the centre rows of the racket task Jacobian (ċ = J_c
    q̇) and the angular rows of the geometric Jacobian (ṅ = ω × n, so the angle θ to n₄ changes as
    θ̇ = −ωᵀ(n × n₄)/sin θ)."""
    x = robot.task_coordinates(q, "racket5")
    c4, n4 = x4_centre_normal()
    dc = x[:3] - c4
    centre = float(np.linalg.norm(dc))
    grad = dc / centre @ robot.task_jacobian(q, "racket5")[:3]
    n = _normal(x[3], x[4])
    axis = np.cross(n, n4)
    sin_angle = float(np.linalg.norm(axis))
    angle = float(np.arctan2(sin_angle, n @ n4))
    root = np.sqrt(angle * angle + _ANGLE_SMOOTHING)
    if sin_angle > 0.0:
        angle_rate = -(axis / sin_angle) @ robot.jacobian(q)[3:]
        grad = grad + NORMAL_WEIGHT * (angle / root) * angle_rate
    value = centre + NORMAL_WEIGHT * (root - np.sqrt(_ANGLE_SMOOTHING))
    short = SIGMA_MARGIN + 1e-4 - task_sigma_min(robot, q)
    if short > 0.0:
        _, dsigma = _sigma_min_gradient(robot, q)
        value += _SIGMA_PENALTY * short * short
        grad = grad - 2.0 * _SIGMA_PENALTY * short * dsigma
    return value, grad


def _local_minimum(robot: Robot, q0: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Local minimum of :func:`_objective` within the box [lo, hi] from q0: SciPy's SLSQP with the
    box as bounds and the objective's gradient from the core's Jacobians (L-BFGS-B finds the same
    minimum, but its BLAS calls for an 8-vector cost milliseconds each on a loaded machine)."""
    try:
        from scipy.optimize import minimize
    except ImportError:  # pragma: no cover - the experiments extra is installed with the tests
        raise ImportError(
            "seed000 finds its target with SciPy's optimiser: pip install 'ttmanip[experiments]'"
        ) from None
    result = minimize(
        lambda q: _objective(robot, q),
        np.clip(q0, lo, hi),
        jac=True,
        method="SLSQP",
        bounds=list(zip(lo, hi, strict=True)),
        options={"maxiter": 400, "ftol": 1e-12},
    )
    return np.clip(result.x, lo, hi)


def nearest_reachable(
    robot: Robot, samples: int = 20_000, starts: int = 20, seed: int = 0
) -> tuple[np.ndarray, float]:
    """The configuration (n,) whose racket pose is nearest to x(4) under :func:`distance_to_x4`
    within the margins (``LIMIT_MARGIN``, ``SIGMA_MARGIN``), and that distance: a local minimum
    (:func:`_local_minimum`) from the start and from each of the ``starts`` nearest of ``samples``
    random configurations (see module doc)."""
    lo, hi = margin_box(robot)
    rng = np.random.default_rng(seed)
    q = lo + rng.random((samples, robot.dof)) * (hi - lo)
    d = distance_to_x4(*racket_centre_normal(robot, q))
    d = np.where(task_sigma_min(robot, q) >= SIGMA_MARGIN, d, np.inf)
    best, best_d = None, np.inf
    for q0 in [np.clip(Q_START, lo, hi), *q[np.argsort(d)[:starts]]]:
        qs = _local_minimum(robot, q0, lo, hi)
        if task_sigma_min(robot, qs) < SIGMA_MARGIN:
            continue  # the penalty left it a hair inside the margin: not admissible
        ds = float(distance_to_x4(*racket_centre_normal(robot, qs)))
        if ds < best_d:
            best, best_d = qs, ds
    if best is None:
        raise RuntimeError("no admissible configuration found")
    return best, best_d


def joint_path_task_trajectory(
    robot: Robot, q0: np.ndarray, q1: np.ndarray, duration: float = DURATION, rate_hz: float = RATE_HZ
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Racket task samples x (N, 5) and exact rates ẋ (N, 5) along the quintic joint path
    q0 → q1, and that path (N, n); azimuth unwrapped."""
    count = int(round(duration * rate_hz)) + 1
    q, qd, _ = traj.quintic(q0, q1, duration).sample(np.linspace(0.0, duration, count))
    # the rates of the racket coordinates from the core's Jacobian of them (ẋ = J q̇; the racket
    # task Jacobian's angle rows are residual coordinates, not the angles' rates)
    x = _task_rows(robot, q)
    xdot = np.einsum("kij,kj->ki", robot.racket_angle_jacobian(q), qd)  # one batched call
    x[:, 4] = np.unwrap(x[:, 4])
    return x, xdot, q


def _run(robot: Robot, x: np.ndarray, xdot: np.ndarray, weighted: bool) -> tuple[TrackResult, float]:
    start = time.perf_counter()
    if weighted:
        result = track(robot, Q_START, x, rate_hz=RATE_HZ, velocities=xdot, weights="chan-dubey")
    else:
        # The plain pseudo-inverse, with nothing keeping the joints inside their limits.
        result = track(
            robot, Q_START, x, rate_hz=RATE_HZ, velocities=xdot, weights="none", respect_limits=False
        )
    return result, time.perf_counter() - start


def _display(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Joint values for plotting: m for prismatic joints, degrees for revolute ones."""
    out = np.array(q, dtype=float, copy=True)
    units = []
    for i, kind in enumerate(robot.joint_types):
        if kind == "revolute":
            out[..., i] = np.degrees(out[..., i])
            units.append("°")
        else:
            units.append("m")
    return out, units


def _joint_grid(robot: Robot):
    fig, axes = plt.subplots(2, 4, figsize=(13, 6), sharex=True)
    return fig, axes.ravel()


def _fig_joints(
    robot: Robot, time: np.ndarray, values: np.ndarray, what: str, units, limits, path: Path, title
):
    """One panel a joint of ``values`` (display units) against ``time`` with the dashed limit
    lines ``limits(i)`` gives for joint i (pairs (value, label or None)); ``title`` as text."""
    fig, axes = _joint_grid(robot)
    for i, ax in enumerate(axes):
        ax.plot(time, values[:, i], color="C0", label="weighted (Chan–Dubey)")
        for value, label in limits(i):
            ax.axhline(value, color="C3", ls="--", lw=1, label=label)
        ax.set_title(robot.joint_names[i])
        ax.set_ylabel(f"{what} ({units[i]})")
        if i >= 4:
            ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _fig_positions(robot: Robot, res: TrackResult, path: Path) -> None:
    q, units = _display(robot, res.q)
    lim, _ = _display(robot, robot.limits.T)
    _fig_joints(
        robot,
        res.time,
        q,
        "position",
        units,
        lambda i: [(lim[0, i], "joint limits"), (lim[1, i], None)],
        path,
        "Fig. 8: joint positions of the weighted least-norm motion, with joint limits",
    )


def _fig_speeds(robot: Robot, res: TrackResult, path: Path) -> None:
    qd, _ = _display(robot, res.qd)
    vmax, _ = _display(robot, robot.velocity_limits)
    units = ["m/s" if k == "prismatic" else "°/s" for k in robot.joint_types]

    def limits(i):
        near = np.isfinite(vmax[i]) and np.abs(qd[:, i]).max() > 0.5 * vmax[i]
        return [(vmax[i], "speed limit"), (-vmax[i], None)] if near else []

    reached = bool((np.abs(qd) >= vmax - 1e-9).any())
    _fig_joints(
        robot,
        res.time,
        qd,
        "speed",
        units,
        limits,
        path,
        f"Fig. 9: joint speeds (limits {vmax[0]:.1f} m/s and {vmax[1]:.0f} °/s "
        + ("reached at some samples)" if reached else "never reached)"),
    )


def _fig_error(res: TrackResult, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8, 4.5))
    floor = 1e-17
    ax.semilogy(res.time, np.maximum(res.position_error, floor), label="racket centre position error (m)")
    ax.semilogy(res.time, np.maximum(res.orientation_error, floor), label="face normal direction error (rad)")
    ax.axhline(1e-3, color="C3", ls="--", lw=1, label="paper's reported error (1e-3)")
    ax.axhline(1e-6, color="C2", ls=":", lw=1, label="our acceptance bound (1e-6)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("tracking error (m or rad, log scale)")
    ax.set_title("Fig. 10: main-task tracking error (CLIK at 1 kHz)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _comparison_row(robot: Robot, w: TrackResult, u: TrackResult, axes, what: str) -> None:
    worst = int(np.argmin(u.margin.min(axis=0)))
    qw, units = _display(robot, w.q)
    qu, _ = _display(robot, u.q)
    lim, _ = _display(robot, robot.limits.T)
    a, b = axes
    a.plot(w.time, qw[:, worst], color="C0", label="weighted (Chan–Dubey)")
    a.plot(u.time, qu[:, worst], color="C1", label="unweighted pseudo-inverse")
    a.axhline(lim[0, worst], color="C3", ls="--", lw=1, label="joint limits")
    a.axhline(lim[1, worst], color="C3", ls="--", lw=1)
    a.set_xlabel("time (s)")
    a.set_ylabel(f"{robot.joint_names[worst]} position ({units[worst]})")
    name = robot.joint_names[worst]
    a.set_title(f"{what}: joint {name}, the one the unweighted solution drives furthest", fontsize=9)
    a.grid(alpha=0.3)
    a.legend(fontsize=8)
    b.plot(w.time, w.margin.min(axis=1), color="C0", label="weighted (Chan–Dubey)")
    b.plot(u.time, u.margin.min(axis=1), color="C1", label="unweighted pseudo-inverse")
    b.axhline(0.0, color="C3", ls="--", lw=1, label="a joint at its limit")
    b.set_xlabel("time (s)")
    b.set_ylabel("smallest distance to a limit (rad or m)")
    b.set_title(f"{what}: smallest joint-limit margin over all joints", fontsize=9)
    b.grid(alpha=0.3)
    b.legend(fontsize=8)


def _fig_comparison(
    robot: Robot, w: TrackResult, u: TrackResult, lw: TrackResult, lu: TrackResult, path: Path
) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(13, 9))
    _comparison_row(robot, w, u, axes[0], "motion to the nearest reachable target")
    _comparison_row(robot, lw, lu, axes[1], f"straight task line, {LINE_FRACTION:.0%} toward x(4)")
    fig.suptitle("Same 5-D motions, weighted vs unweighted least norm")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _csv(robot: Robot, res: TrackResult, x_target: np.ndarray, path: Path) -> None:
    names = robot.joint_names
    cols = (
        ["time_s"]
        + [f"q_{n}" for n in names]
        + [f"qdot_{n}" for n in names]
        + ["x_cx_m", "x_cy_m", "x_cz_m", "x_polar_rad", "x_azimuth_rad"]
        + ["xd_cx_m", "xd_cy_m", "xd_cz_m", "xd_polar_rad", "xd_azimuth_rad"]
        + ["error", "position_error_m", "orientation_error_rad"]
        + [f"margin_{n}" for n in names]
    )
    n = len(res)
    data = np.column_stack(
        [
            res.time,
            res.q,
            res.qd,
            res.x,
            x_target[:n],
            res.error,
            res.position_error,
            res.orientation_error,
            res.margin,
        ]
    )
    np.savetxt(path, data, delimiter=",", header=",".join(cols), comments="", fmt="%.12e")


def _unweighted_summary(robot: Robot, u: TrackResult, seconds: float) -> dict:
    margin = u.margin
    return {
        "status": u.status,
        "max_tracking_error": float(u.error.max()),
        "min_limit_margin": float(margin.min()),
        "min_limit_margin_joint": robot.joint_names[int(np.argmin(margin.min(axis=0)))],
        "min_limit_margin_per_joint": margin.min(axis=0).tolist(),
        "joints_crossing_limits": [
            n for n, m in zip(robot.joint_names, margin.min(axis=0), strict=True) if m < 0.0
        ],
        "track_call_seconds": seconds,
    }


def run(out_dir: str | Path) -> dict:
    """Runs the experiment, writes figures, CSV arrays and ``summary.json``; returns the summary."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    robot = robots.mobile8()
    x0 = robot.task_coordinates(Q_START, task="racket5")
    q_target, target_distance = nearest_reachable(robot)
    x, xdot, _ = joint_path_task_trajectory(robot, Q_START, q_target)
    target = x[-1]

    weighted, t_weighted = _run(robot, x, xdot, weighted=True)
    unweighted, t_unweighted = _run(robot, x, xdot, weighted=False)
    # the previous target: a straight task line part of the way toward x(4) (comparison only)
    line_target = x0 + LINE_FRACTION * (X4_SEED - x0)
    xl, xdl = task_line(x0, line_target, DURATION, rate_hz=RATE_HZ, task="racket5")
    line_w, _ = _run(robot, xl, xdl, weighted=True)
    line_u, t_line_u = _run(robot, xl, xdl, weighted=False)

    _fig_positions(robot, weighted, out / "fig08_joint_positions.png")
    _fig_speeds(robot, weighted, out / "fig09_joint_speeds.png")
    _fig_error(weighted, out / "fig10_tracking_error.png")
    _fig_comparison(robot, weighted, unweighted, line_w, line_u, out / "fig_unweighted_comparison.png")
    _csv(robot, weighted, x, out / "weighted.csv")
    _csv(robot, unweighted, x, out / "unweighted.csv")

    margin_w = weighted.margin
    final_error = float(weighted.error[-1])
    c4, _ = x4_centre_normal()
    c_t, n_t = racket_centre_normal(robot, q_target)
    _, n4 = x4_centre_normal()
    summary = {
        "robot": "mobile8 (seed 000 Table 1, literal)",
        "task": "racket5: centre 0.15 m along z8 (m), polar and azimuth of the face normal (rad)",
        "q_start": Q_START.tolist(),
        "x0": x0.tolist(),
        "x4_seed": X4_SEED.tolist(),
        "target": target.tolist(),
        "target_q": q_target.tolist(),
        "target_distance_to_x4": target_distance,
        "target_centre_distance_m": float(np.linalg.norm(c_t - c4)),
        "target_normal_angle_rad": float(np.arctan2(np.linalg.norm(np.cross(n_t, n4)), n_t @ n4)),
        "target_sigma_min": float(task_sigma_min(robot, q_target)),
        "distance_metric": f"|c - c4| (m) + {NORMAL_WEIGHT} m/rad * angle(n, n4)",
        "target_margins": {
            "joint_limits_prismatic_m": LIMIT_MARGIN[0],
            "joint_limits_revolute_rad": float(LIMIT_MARGIN[1]),
            "task_jacobian_sigma_min": SIGMA_MARGIN,
        },
        "line15_target": line_target.tolist(),
        "line15_distance_to_x4": distance_of_coordinates(line_target),
        "target_reason": (
            f"x4_seed's racket centre is {float(np.hypot(X4_SEED[0], X4_SEED[1])):.2f} m from the axis "
            f"of prismatic joint 1 and the arm spans at most {ARM_SPAN:.2f} m: out of reach. The target "
            "is the reachable racket pose nearest to x4_seed under distance_metric, with target_margins "
            "from the joint limits and from the singularity (SLSQP from 21 starts); the task path is FK "
            "along a quintic joint path to it, reachable at every sample"
        ),
        "duration_s": DURATION,
        "rate_hz": RATE_HZ,
        "status": weighted.status,
        "message": weighted.message,
        "reached": bool(weighted.ok and final_error <= 1e-6),
        "final_error": final_error,
        "max_tracking_error": float(weighted.error.max()),
        "max_position_error_m": float(weighted.position_error.max()),
        "max_orientation_error_rad": float(weighted.orientation_error.max()),
        "min_limit_margin": float(margin_w.min()),
        "min_limit_margin_joint": robot.joint_names[int(np.argmin(margin_w.min(axis=0)))],
        "min_limit_margin_per_joint": margin_w.min(axis=0).tolist(),
        "min_task_sigma_min": float(weighted.sigma_min.min()),
        "max_joint_speed": float(np.abs(weighted.qd).max()),
        "max_joint_speed_per_joint": np.abs(weighted.qd).max(axis=0).tolist(),
        "joints_beyond_limits": bool((margin_w < 0.0).any()),
        "track_call_seconds": t_weighted,
        "unweighted": _unweighted_summary(robot, unweighted, t_unweighted),
        "line15": {
            "weighted_min_limit_margin": float(line_w.margin.min()),
            "weighted_max_tracking_error": float(line_w.error.max()),
            "unweighted": _unweighted_summary(robot, line_u, t_line_u),
        },
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
