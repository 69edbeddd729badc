"""``ttmanip demo``: the whole hit pipeline on gantry6, planned and executed by every axis's drive.

Seed 002's pipeline (hit parameters → analytic IK → J⁻¹V → stroke → inverse dynamics → drives)
for :data:`ttmanip.DEMO_HIT`, simulated with gravity through ``ttmanip.DriveSim`` (setpoints at
1 kHz), then seed 000's mobile8 with a 5-D racket hit. Writes into the output folder:

- ``summary.json``: the errors at the hit (``racket_position_error_m``,
  ``racket_normal_error_deg``, ``racket_velocity_error_mps``), the plan and the drive faults;
- ``gantry6_joints.png`` (q, q̇, q̈, τ, current per joint with limits), ``gantry6_racket.png``
  (racket path in 3-D, table, robot at the hit), ``gantry6_errors.png``, ``gantry6_stroke.gif``;
- ``gantry6_plan.csv`` (planned t, q, q̇, q̈, τ) and ``gantry6_sim.csv`` (executed t, q, q̇, current);
- ``mobile8_joints.png``, ``mobile8_racket.png`` and ``mobile8_*.csv`` for the mobile manipulator;
- ``kinematics/workspace_*.png``: sampled workspaces of both robots.
"""

from __future__ import annotations

import csv
import json
import time
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import _ttmanip as _t  # noqa: E402
from . import motor, plots, robots  # noqa: E402
from ._ttmanip import Robot  # noqa: E402
from .pipeline import DEMO_HIT, Hit, plan_hit, racket_states, simulate  # noqa: E402

__all__ = ["mobile8_hit", "random_configurations", "run", "run_hit", "workspace_figure", "write_csv"]


def random_configurations(robot: Robot, count: int, seed: int = 0) -> np.ndarray:
    """``count`` configurations drawn uniformly within the joint limits, shape (count, n)."""
    lim = robot.limits
    rng = np.random.default_rng(seed)
    return lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((count, robot.dof))


def workspace_figure(robot: Robot, q_ref: np.ndarray, path: Path, count: int = 100_000) -> dict:
    """Plots the sampled workspace of ``robot`` (top and side views) and returns its statistics."""
    qs = random_configurations(robot, count)
    t0 = time.perf_counter()
    poses = robot.fk(qs)
    rate = count / (time.perf_counter() - t0)
    p = poses[:, :3, 3]
    stick = plots.robot_points(robot, q_ref)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True)
    for ax, (i, j), title in zip(axes, [(0, 1), (0, 2)], ["top view (x–y)", "side view (x–z)"], strict=False):
        hb = ax.hexbin(p[:, i], p[:, j], gridsize=70, bins="log", cmap="viridis", mincnt=1)
        ax.plot(stick[:, i], stick[:, j], "o-", color="tab:red", lw=2, ms=4, label="robot at q_ref")
        ax.set_xlabel(f"{'xyz'[i]} [m]")
        ax.set_ylabel(f"{'xyz'[j]} [m]")
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(loc="upper right")
        fig.colorbar(hb, ax=ax, label="configurations per cell")
    fig.suptitle(f"{robot.name}: tool positions of {count:,} random configurations within limits")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return {
        "q_ref": np.asarray(q_ref).tolist(),
        "workspace_min_m": p.min(axis=0).tolist(),
        "workspace_max_m": p.max(axis=0).tolist(),
        "batch_fk_per_second": rate,
    }


def write_csv(path: Path, columns: dict) -> Path:
    """Writes equal-length columns (1-D arrays, or 2-D arrays split into ``name[j]``) as CSV."""
    names, data = [], []
    for name, arr in columns.items():
        a = np.asarray(arr, float)
        if a.ndim == 1:
            names.append(name)
            data.append(a)
        else:
            for j in range(a.shape[1]):
                names.append(f"{name}[{j}]")
                data.append(a[:, j])
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        w.writerows(np.column_stack(data).tolist())
    return Path(path)


def run_hit(
    robot: Robot,
    hit: Hit,
    out: Path,
    prefix: str,
    *,
    gif: bool = True,
    state=None,
    noise=None,
    setpoint_hz: float | None = None,
    progress=None,
    recording=None,
    t0: float = 0.0,
    world_from_base=None,
    setpoint_rate: float | None = None,
) -> dict:
    """Plans and simulates ``hit`` on ``robot``; writes figures and CSVs named ``prefix_*`` into
    ``out``; returns the JSON-ready summary. With ``recording`` (a ``ttmanip.viz.Recording``) the
    simulated stroke is also logged there from ``t0`` (s) on its timeline. ``setpoint_hz``: the
    drives' setpoint rate (Hz; None: ``DriveSim``'s default); ``setpoint_rate``, its deprecated
    name, warns."""
    if setpoint_rate is not None:
        warnings.warn(
            "run_hit(setpoint_rate=...) is deprecated; use setpoint_hz=...", DeprecationWarning, stacklevel=2
        )
        setpoint_hz = setpoint_rate
    step = progress or (lambda _msg: None)
    step("plan")
    plan = plan_hit(robot, hit, state)
    summary = {
        "robot": robot.name,
        "status": plan.status,
        "message": plan.message,
        "ok": plan.ok,
        "t_hit_requested": plan.requested_t_hit,
        "t_hit": plan.t_hit,
        "earliest_t_hit": plan.earliest_t_hit,
        "profile": plan.profile,
        "q_hit": plan.q_hit.tolist(),
        "qd_hit": plan.qd_hit.tolist(),
        "sigma_min": plan.sigma_min,
        "ik_branches": plan.branches,
        "hit_pose": plan.hit_pose.tolist(),
        "hit_twist": plan.hit_twist.tolist(),
    }
    if plan.trajectory is None:
        return summary
    t, q, qd, qdd = plan.sample(1000.0)
    tau = plan.torques(1000.0)
    write_csv(out / f"{prefix}_plan.csv", {"t": t, "q": q, "qd": qd, "qdd": qdd, "tau": tau})
    step("simulate")
    sim = simulate(robot, plan, setpoint_hz=setpoint_hz, noise=noise)
    ex = sim.arrays
    write_csv(
        out / f"{prefix}_sim.csv",
        {"t": ex["t"], "q": ex["q"], "qd": ex["qd"], "current": ex["current"], "torque": ex["torque"]},
    )
    if recording is not None:
        from . import viz

        viz.record_hit(recording, robot, plan, sim, t0=t0, world_from_base=world_from_base)
    step("figures")
    figures = [
        *plots.hit_figures(
            robot, plan, sim, (t, q, qd, qdd, tau), out / f"{prefix}_joints.png", out / f"{prefix}_racket.png"
        ),
        plots.error_figure(sim.summary(), out / f"{prefix}_errors.png"),
    ]
    if gif:
        figures.append(
            plots.animation(
                robot,
                np.asarray(ex["t"]),
                np.asarray(ex["q"]),
                sim.racket_centre,
                out / f"{prefix}_stroke.gif",
            )
        )
    summary.update(sim.summary())
    summary.update(
        {
            "peak_torques": np.abs(tau).max(axis=0).tolist(),
            "effort_limits": np.asarray(robot.effort_limits).tolist(),
            "effective_effort_limits": np.asarray(robot.effective_effort_limits).tolist(),
            "stroke_duration": plan.duration,
            "figures": [str(p) for p in figures],
        }
    )
    return summary


def mobile8_hit() -> Hit:
    """Seed 000's robot: a 5-D racket hit 8.3 cm from the racket's start pose (centre offset
    (0.02, −0.04, −0.07) m, same face normal), centre moving at (−0.29, 0.19, 0.25) m/s at 1.5 s; the
    rotation about the normal is free."""
    robot = robots.mobile8()
    q0 = robots.mobile8_start()
    _, c, n, _ = racket_states(robot, q0, np.zeros(robot.dof))
    return Hit.from_normal(c[0] + [0.02, -0.04, -0.07], n[0], [-0.29, 0.19, 0.25], 1.5)


def run(out: Path, progress=None, workspace: bool = True, rerun: str | Path | None = None) -> dict:
    """Runs the demo, writes the figures, CSVs and ``summary.json`` into ``out``; returns the summary.
    ``rerun``: also a Rerun recording (.rrd) of both strokes (``ttmanip.viz``)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    step = progress or (lambda _msg: None)
    rec = None
    if rerun is not None:
        from . import viz

        rec = viz.Recording(rerun, "ttmanip-demo")
    # gantry6 stands where the rally places it (ttkin::ball::reach::Placement::default)
    at_table = _t.ball_placement()
    summary = run_hit(
        robots.gantry6(), DEMO_HIT, out, "gantry6", progress=step, recording=rec, world_from_base=at_table
    )
    summary["mobile8"] = run_hit(
        robots.mobile8(), mobile8_hit(), out, "mobile8", gif=False, progress=step, recording=rec
    )
    if rec is not None:
        summary["rerun"] = str(rec.close())
    step("drive: θ5 case")
    summary.update(motor.theta5_ripple_case())  # issue 10's current-chatter case
    motor.theta5_figure(out / "drive_theta5.png")
    if workspace:
        step("workspaces")
        kin = out / "kinematics"
        kin.mkdir(exist_ok=True)
        summary["kinematics"] = {
            "gantry6": workspace_figure(
                robots.gantry6(), np.array([0.1, -0.2, 0.3, 0.4, 0.6, 0.0]), kin / "workspace_gantry6.png"
            ),
            "mobile8": workspace_figure(
                robots.mobile8(), robots.mobile8_start(), kin / "workspace_mobile8.png"
            ),
        }
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=str))
    return summary
