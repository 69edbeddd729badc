"""The demo of the whole pipeline, with figures.

Writes into the output folder:
- ``kinematics/``: ``workspace_gantry6.png`` and ``workspace_mobile8.png``, reachable tool
  positions from 200,000 random configurations within the joint limits (batch FK in Rust), top and
  side views, with the robot drawn as a stick figure at a reference configuration;
- ``pipeline/``: seed 002's hit pipeline on gantry6 (hit parameters → analytic IK → J⁻¹V →
  quintic stroke → inverse dynamics → one joint driven by the cascaded motor loops), see
  :mod:`ttmanip.pipeline`;
- ``seed000/``, ``seed001/``: the seed documents' experiments (``ttmanip experiment NAME``);
- ``summary.json``: what each part measured.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import robots  # noqa: E402
from ._ttmanip import Robot  # noqa: E402


def random_configurations(robot: Robot, count: int, seed: int = 0) -> np.ndarray:
    """``count`` configurations drawn uniformly within the joint limits, shape (count, n)."""
    lim = robot.limits
    rng = np.random.default_rng(seed)
    return lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((count, robot.n))


def _stick(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Origins of the base and of every link frame, shape (n + 2, 3), with the tool point last."""
    frames = robot.fk_all(q)
    tool = robot.fk(q)
    return np.vstack([robot.base[:3, 3], frames[:, :3, 3], tool[:3, 3]])


def workspace_figure(robot: Robot, q_ref: np.ndarray, path: Path, count: int = 200_000) -> dict:
    """Plots the sampled workspace of ``robot`` (top and side views) and returns its statistics."""
    qs = random_configurations(robot, count)
    t0 = time.perf_counter()
    poses = robot.fk(qs)
    rate = count / (time.perf_counter() - t0)
    p = poses[:, :3, 3]
    stick = _stick(robot, q_ref)

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True)
    for ax, (i, j), title in zip(axes, [(0, 1), (0, 2)], ["top view (x–y)", "side view (x–z)"]):
        hb = ax.hexbin(p[:, i], p[:, j], gridsize=70, bins="log", cmap="viridis", mincnt=1)
        ax.plot(stick[:, i], stick[:, j], "o-", color="tab:red", lw=2, ms=4, label="robot at q_ref")
        ax.set_xlabel(f"{'xyz'[i]} [m]")
        ax.set_ylabel(f"{'xyz'[j]} [m]")
        ax.set_title(title)
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(loc="upper right")
        fig.colorbar(hb, ax=ax, label="configurations per cell")
    fig.suptitle(f"{robot.name}: tool positions of {count:,} random configurations within limits")
    fig.savefig(path, dpi=120)
    plt.close(fig)

    t_ref = robot.fk(q_ref)
    sv = np.linalg.svd(robot.jacobian(q_ref), compute_uv=False)
    return {
        "q_ref": q_ref.tolist(),
        "tool_pose_ref": t_ref.tolist(),
        "jacobian_singular_values_ref": sv.tolist(),
        "workspace_min_m": p.min(axis=0).tolist(),
        "workspace_max_m": p.max(axis=0).tolist(),
        "batch_fk_per_second": rate,
    }


def run(out: Path) -> dict:
    """Runs the demo, writes the figures and ``summary.json`` into ``out``, returns a short summary."""
    import importlib

    from . import pipeline

    out.mkdir(parents=True, exist_ok=True)
    kin = out / "kinematics"
    kin.mkdir(exist_ok=True)
    q_gantry = np.array([0.1, -0.2, 0.3, 0.4, 0.6, 0.0])
    results = {
        "kinematics": {
            "gantry6": workspace_figure(robots.gantry6(), q_gantry, kin / "workspace_gantry6.png"),
            "mobile8": workspace_figure(
                robots.mobile8(), robots.mobile8_start(), kin / "workspace_mobile8.png"
            ),
        },
        "pipeline": pipeline.run(out / "pipeline"),
    }
    for name in ("seed000", "seed001"):
        results[name] = importlib.import_module(f"ttmanip.experiments.{name}").run(out / name)
    (out / "summary.json").write_text(json.dumps(results, indent=2, default=str))
    hit = results["pipeline"]
    return {
        "output": str(out),
        "figures": sum(1 for _ in out.rglob("*.png")),
        "batch_fk_per_second_mobile8": round(results["kinematics"]["mobile8"]["batch_fk_per_second"]),
        "hit_pose_error_m": hit["hit_pose_error_m"],
        "hit_twist_error": hit["hit_twist_error"],
        "stroke_feasible": hit["stroke_feasible"],
        "seed000_max_tracking_error": results["seed000"].get("max_tracking_error"),
    }
