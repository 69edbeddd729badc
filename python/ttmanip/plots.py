"""Figures of a planned and simulated hit: joint curves with their limits, the racket path in 3-D
with the table and the robot at the hit, the errors at the hit, and a GIF of the stroke.

Every function writes one file and returns its path. The table (ITTF: 2.74 × 1.525 m, surface
0.76 m above the floor, net 0.1525 m high) is placed in the robot's base frame by
:data:`TABLE_PLACEMENT` (documented choice: the robot stands behind the table's near end line).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import _ttmanip  # noqa: E402
from .ball import Table  # noqa: E402

__all__ = [
    "TABLE",
    "TABLE_PLACEMENT",
    "animation",
    "error_figure",
    "hit_figures",
    "joint_figure",
    "racket_figure",
    "robot_points",
]

#: Table dimensions (m): length, width, surface height above the floor, net height (the Rust
#: core's table, ``ttmanip.ball.Table``).
_T = Table()
TABLE = {"length": _T.length, "width": _T.width, "height": _T.height, "net": _T.net_height}

#: Where the table sits in the robot's base frame (m): the centre of its near end line and the
#: height of its surface; the table extends along −y (towards the opponent).
TABLE_PLACEMENT = {"near_end_centre": (0.0, -0.3), "surface_z": -0.25}


def robot_points(robot, q) -> np.ndarray:
    """Base origin, every link frame origin and the tool point (n + 2, 3) at ``q`` (base frame)."""
    q = _ttmanip.real_array(q, "q")  # the bindings' one conversion: complex and bool refused
    frames = robot.fk_all(q)
    return np.vstack([robot.base[:3, 3], frames[:, :3, 3], robot.fk(q)[:3, 3]])


def _limits(robot):
    lim = np.asarray(robot.limits, float)
    return lim[:, 0], lim[:, 1]


def _named(robot, attr, n):
    v = getattr(robot, attr, None)
    return np.full(n, np.nan) if v is None else np.asarray(v, float)


def joint_figure(
    robot, t, q, qd, qdd, tau, path, *, current=None, t_hit=None, executed=None, title: str = ""
) -> Path:
    """Per joint (columns): position, velocity, acceleration, torque and (if given) current
    against time, with the limits as dashed red lines; ``executed`` (dict with ``t``, ``q``,
    ``qd``) overlays the simulated motion."""
    n = q.shape[1]
    rows = 5 if current is not None else 4
    fig, axes = plt.subplots(
        rows, n, figsize=(2.6 * n + 1, 1.9 * rows + 1), sharex=True, constrained_layout=True, squeeze=False
    )
    lower, upper = _limits(robot)
    vmax = _named(robot, "velocity_limits", n)
    amax = _named(robot, "acceleration_limits", n)
    emax = _named(robot, "effective_effort_limits", n)  # what the planners use (at rest)
    kinds = list(robot.joint_types)
    for j in range(n):
        u = "m" if kinds[j] == "prismatic" else "rad"
        f = "N" if kinds[j] == "prismatic" else "N·m"
        data = [
            (q, f"q [{u}]", (lower[j], upper[j])),
            (qd, f"q̇ [{u}/s]", (-vmax[j], vmax[j])),
            (qdd, f"q̈ [{u}/s²]", (-amax[j], amax[j])),
            (tau, f"τ [{f}]", (-emax[j], emax[j])),
        ]
        if current is not None:
            data.append((current, "i [A]", (np.nan, np.nan)))
        for r, (arr, label, (lo, hi)) in enumerate(data):
            ax = axes[r, j]
            ax.plot(
                t if arr is not current else executed["t"],
                arr[:, j],
                lw=1.2,
                color="C0",
                label="planned" if arr is not current else "executed",
            )
            if executed is not None and r < 2:
                key = "q" if r == 0 else "qd"
                ax.plot(executed["t"], executed[key][:, j], lw=0.9, ls="--", color="C1", label="executed")
            for b in (lo, hi):
                if np.isfinite(b):
                    ax.axhline(b, color="C3", ls="--", lw=0.9)
            if t_hit is not None:
                ax.axvline(t_hit, color="k", ls=":", lw=0.9)
            ax.grid(alpha=0.3)
            if j == 0:
                ax.set_ylabel(label)
            if r == 0:
                ax.set_title(robot.joint_names[j])
        axes[-1, j].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(title or f"{robot.name}: hitting stroke (dashed red: limits, dotted: hit)")
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _table_outline() -> dict[str, np.ndarray]:
    """The core's table outline (``Table::outline``: surface, centre line, net; m) moved from the
    world frame into the figures' frame by :data:`TABLE_PLACEMENT`: world x (toward the opponent)
    along −y from the near end line's centre, world y along +x, the surface at ``surface_z``."""
    x0, y0 = TABLE_PLACEMENT["near_end_centre"]
    z = TABLE_PLACEMENT["surface_z"]
    world = _T.outline()
    near = world["surface"][:, 0].min()  # the near end line's x (world)
    return {k: np.column_stack([x0 + p[:, 1], y0 - (p[:, 0] - near), z + p[:, 2]]) for k, p in world.items()}


def _draw_table(ax) -> None:
    o = _table_outline()
    ax.plot(*o["surface"].T, color="darkgreen", lw=1.5, label="table")
    ax.plot(*o["centre_line"].T, color="white", lw=0.8)
    ax.plot(*o["net"].T, color="gray", lw=1.2, label="net")


def _frame(ax, points: np.ndarray) -> None:
    """Axis limits spanning ``points`` and the near half of the table up to the net, equal scale."""
    o = _table_outline()
    y_net = o["net"][0, 1]
    near_half = o["surface"][o["surface"][:, 1] >= y_net]
    allp = np.vstack([points, near_half, o["net"]])
    lo, hi = allp.min(axis=0) - 0.05, allp.max(axis=0) + 0.05
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo)


def racket_figure(
    robot, centre, normal, q_hit, hit_pose, path, *, planned_centre=None, velocity=None
) -> Path:
    """The racket-centre path in 3-D (executed and planned), the table and net, the robot as a
    stick figure at the hit configuration, the face normal and the velocity at the hit."""
    fig = plt.figure(figsize=(8, 6.5), constrained_layout=True)
    ax = fig.add_subplot(projection="3d")
    _draw_table(ax)
    if planned_centre is not None:
        ax.plot(*planned_centre.T, color="C0", lw=1.0, ls="--", label="planned racket centre")
    ax.plot(*centre.T, color="C1", lw=1.4, label="racket centre")
    pts = robot_points(robot, q_hit)
    ax.plot(*pts.T, "o-", color="C3", lw=2.0, ms=3, label="robot at the hit")
    c = hit_pose[:3, 3]
    ax.scatter(*c, color="k", s=30, label="hit point")
    ax.quiver(*c, *(0.15 * hit_pose[:3, 2]), color="k", lw=1.2, label="face normal (0.15 m)")
    if velocity is not None:
        ax.quiver(*c, *(0.05 * velocity), color="C2", lw=1.2, label="velocity × 0.05 s")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    _frame(ax, np.vstack([centre, pts]))
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title(f"{robot.name}: racket path, base frame")
    path = Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def hit_figures(robot, plan, sim, samples, joints_path, racket_path, *, title: str = "") -> list[Path]:
    """The joint figure and the racket figure of one planned and simulated hit: ``samples`` are
    the plan's ``(t, q, qd, qdd, tau)`` (1 kHz), ``sim`` its :class:`ttmanip.SimResult` (the
    executed motion and drive currents overlaid)."""
    from .pipeline import racket_states

    t, q, qd, qdd, tau = samples
    ex = {k: np.asarray(v) for k, v in sim.arrays.items() if k in ("t", "q", "qd", "current")}
    return [
        joint_figure(
            robot,
            t,
            q,
            qd,
            qdd,
            tau,
            joints_path,
            current=ex["current"],
            t_hit=plan.t_hit,
            executed={"t": ex["t"], "q": ex["q"], "qd": ex["qd"]},
            title=title,
        ),
        racket_figure(
            robot,
            sim.racket_centre,
            sim.racket_normal,
            plan.q_hit,
            plan.hit_pose,
            racket_path,
            planned_centre=racket_states(robot, q, qd)[1],
            velocity=plan.hit_twist[:3],
        ),
    ]


def error_figure(errors: dict, path, thresholds: dict | None = None) -> Path:
    """Bar chart of the errors at the hit, each against its acceptance threshold."""
    thresholds = thresholds or {
        "racket_position_error_m": 1e-3,
        "racket_normal_error_deg": 0.5,
        "racket_velocity_error_rel": 0.02,
    }
    labels = {
        "racket_position_error_m": "centre [mm]",
        "racket_normal_error_deg": "normal [°]",
        "racket_velocity_error_rel": "velocity [%]",
    }
    scale = {
        "racket_position_error_m": 1e3,
        "racket_normal_error_deg": 1.0,
        "racket_velocity_error_rel": 100.0,
    }
    keys = list(thresholds)
    fig, ax = plt.subplots(figsize=(6, 3.5), constrained_layout=True)
    vals = [errors[k] * scale[k] for k in keys]
    lims = [thresholds[k] * scale[k] for k in keys]
    x = np.arange(len(keys))
    colors = ["C0" if v <= m else "C3" for v, m in zip(vals, lims, strict=True)]
    ax.bar(x, vals, color=colors, label="simulated")
    ax.scatter(x, lims, marker="_", s=900, color="k", label="acceptance limit")
    ax.set_xticks(x, [labels[k] for k in keys])
    ax.set_yscale("log")
    ax.legend()
    ax.set_title("racket errors at the hit (drives, gravity)")
    path = Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def animation(robot, t, q, centre, path, *, frames: int = 30, fps: int = 15) -> Path:
    """A small GIF of the stroke: the robot stick figure and the racket path drawn so far."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    idx = np.linspace(0, len(t) - 1, frames).round().astype(int)
    sticks = [robot_points(robot, q[i]) for i in idx]
    fig = plt.figure(figsize=(4.5, 4), dpi=70)
    ax = fig.add_subplot(projection="3d")
    _draw_table(ax)
    _frame(ax, np.vstack([centre, *sticks]))
    (arm,) = ax.plot([], [], [], "o-", color="C3", lw=2, ms=3)
    (trail,) = ax.plot([], [], [], color="C1", lw=1)
    label = ax.set_title("")

    def draw(k):
        s = sticks[k]
        arm.set_data_3d(s[:, 0], s[:, 1], s[:, 2])
        c = centre[: idx[k] + 1]
        trail.set_data_3d(c[:, 0], c[:, 1], c[:, 2])
        label.set_text(f"{robot.name}  t = {t[idx[k]]:.3f} s")
        return arm, trail, label

    anim = FuncAnimation(fig, draw, frames=len(idx), blit=False)
    path = Path(path)
    anim.save(path, writer=PillowWriter(fps=fps))
    plt.close(fig)
    return path
