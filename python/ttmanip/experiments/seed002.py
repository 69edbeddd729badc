"""Seed 002's experiment: the gantry patent's pipeline S101–S106 on a documented set of hits.

The hit parameters (:data:`HITS`, base frame of gantry6, m, m/s, s) are five racket poses in front
of the robot: the demo hit, a forehand further out, a low backhand, a high smash and a slow push;
each with a racket speed along its face normal. For every hit the experiment writes each
intermediate product of the patent's steps into ``hitK/``:

- ``s101_hit.json``: racket pose (4×4) and twist;
- ``s102_ik.json``: every analytic IK branch, the one nearest the ready pose within the limits;
- ``s103_velocity.json``: the Jacobian at the hit, q̇ = J⁻¹V, σ_min;
- ``s104_quintic.csv`` and ``s104_jerk.csv``: the patent's quintic stroke and the jerk-limited one
  (t, q, q̇, q̈), with ``s104_strokes.json`` (hit times, earliest feasible, profile used);
- ``s105_torques.csv``: inverse-dynamics torques (friction included) of the planned stroke;
- ``s106_drives.csv``: the stroke executed by every axis's drive with gravity (q, q̇, current),
  and the racket errors at the hit in ``summary.json``;
- ``joints.png``, ``racket.png`` for every hit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .. import plots, robots
from ..demo import write_csv
from ..pipeline import Hit, plan_hit, simulate

__all__ = ["HITS", "hits", "run"]


def _along(normal, speed):
    n = np.asarray(normal, float)
    return speed * n / np.linalg.norm(n)


#: The documented hit set: (name, centre m, face normal, racket speed m/s along the normal, hit time s).
HITS = (
    ("demo", (0.35, -0.55, 0.05), (0.3, -1.0, -0.2), 3.0, 0.35),
    ("forehand_wide", (0.25, -0.45, 0.0), (0.5, -1.0, 0.0), 2.5, 0.45),
    ("backhand_low", (-0.2, -0.5, -0.1), (-0.3, -1.0, 0.2), 2.0, 0.5),
    ("smash_high", (0.1, -0.45, 0.1), (0.0, -1.0, -0.5), 3.5, 0.5),
    ("push_slow", (0.0, -0.35, 0.0), (0.0, -1.0, 0.3), 1.0, 0.6),
)


def hits() -> list[tuple[str, Hit]]:
    """The documented hits as :class:`ttmanip.Hit` objects."""
    return [(name, Hit.from_normal(c, n, _along(n, s), t)) for name, c, n, s, t in HITS]


def _dump(path: Path, data) -> None:
    path.write_text(json.dumps(data, indent=2, default=lambda o: np.asarray(o).tolist()))


def run(out_dir: str | Path) -> dict:
    """Runs S101–S106 on every hit of :data:`HITS`, writes every product; returns the summary."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    robot = robots.gantry6()
    results = {}
    for k, (name, hit) in enumerate(hits()):
        d = out / f"hit{k}_{name}"
        d.mkdir(exist_ok=True)
        _dump(d / "s101_hit.json", {"pose": hit.pose, "twist": hit.twist, "t": hit.t})
        plan = plan_hit(robot, hit)
        quintic = plan_hit(robot, hit, profile="quintic")
        jerk = plan_hit(robot, hit, profile="jerk")
        branches = robot.ik_all(hit.pose)
        _dump(
            d / "s102_ik.json",
            {
                "branches": branches[np.isfinite(branches).all(axis=1)],
                "nearest_within_limits": plan.q_hit,
                "ready": plan.ready,
            },
        )
        entry = {"status": plan.status, "message": plan.message}
        if plan.trajectory is None:
            results[name] = entry
            continue
        _dump(
            d / "s103_velocity.json",
            {"jacobian": robot.jacobian(plan.q_hit), "qd_hit": plan.qd_hit, "sigma_min": plan.sigma_min},
        )
        for label, p in (("quintic", quintic), ("jerk", jerk)):
            if p.trajectory is not None:
                t, q, qd, qdd = p.sample(1000.0)
                write_csv(d / f"s104_{label}.csv", {"t": t, "q": q, "qd": qd, "qdd": qdd})
        _dump(
            d / "s104_strokes.json",
            {
                "requested_t_hit": hit.t,
                "planned": {"profile": plan.profile, "t_hit": plan.t_hit, "status": plan.status},
                "quintic": {
                    "t_hit": quintic.t_hit,
                    "status": quintic.status,
                    "earliest": quintic.earliest_t_hit,
                },
                "jerk": {"t_hit": jerk.t_hit, "status": jerk.status, "earliest": jerk.earliest_t_hit},
            },
        )
        t, q, qd, qdd = plan.sample(1000.0)
        tau = plan.torques(1000.0)
        write_csv(d / "s105_torques.csv", {"t": t, "tau": tau})
        sim = simulate(robot, plan)
        ex = sim.arrays
        write_csv(
            d / "s106_drives.csv", {"t": ex["t"], "q": ex["q"], "qd": ex["qd"], "current": ex["current"]}
        )
        plots.hit_figures(
            robot,
            plan,
            sim,
            (t, q, qd, qdd, tau),
            d / "joints.png",
            d / "racket.png",
            title=f"seed 002, hit '{name}': S104 stroke, S105 torques, S106 drives",
        )
        entry.update(
            {
                "t_hit": plan.t_hit,
                "profile": plan.profile,
                "quintic_t_hit": quintic.t_hit,
                "jerk_t_hit": jerk.t_hit,
                "peak_torques": np.abs(tau).max(axis=0).tolist(),
                **sim.summary(),
            }
        )
        results[name] = entry
    summary = {
        "hits": {name: {"centre": c, "normal": n, "speed_mps": s, "t_hit_s": t} for name, c, n, s, t in HITS},
        "results": results,
        "all_within_acceptance": all(
            r.get("racket_position_error_m", 1.0) <= 1e-3
            and r.get("racket_normal_error_deg", 9.0) <= 0.5
            and r.get("racket_velocity_error_rel", 1.0) <= 0.02
            for r in results.values()
        ),
        # Drive faults (e.g. a following-error trip) are the drive layer's verdict; listed, not hidden.
        "drive_faults": {name: [f for f in r.get("faults", []) if f] for name, r in results.items()},
    }
    _dump(out / "summary.json", summary)
    return summary
