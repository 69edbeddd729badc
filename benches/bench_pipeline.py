"""The hit pipeline from Python: ``ttmanip.plan_hits`` beside a hand-made Pinocchio + ruckig one.

Same hits for both (gantry6, the documented distribution of ``tests/test_pipeline.py``: racket
centre uniform in x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2], z ∈ [−0.15, 0.15] m, face normal within
≈ 40° of −y, 1–4 m/s along the normal) at a hit time of 0.6 s, from rest at the ready pose.

What one plan includes (both pipelines): IK of the racket pose (ttmanip: analytic, nearest branch
within the limits; hand-made: Pinocchio damped Gauss–Newton from the ready pose), joint velocities
q̇ = J⁻¹V, the stroke (ttmanip: quintic on time within the limits, else jerk-limited; hand-made:
ruckig for the hit leg with the hit time as minimum duration and for the return leg), and
inverse-dynamics torques at 12 instants per leg against the effort limits (ttmanip: with friction;
hand-made: ``pin.rnea``). Sampling at 1 kHz is excluded from both. ttmanip's figure is per hit of a
1,000-hit batch (parallel in Rust on every core, GIL released: wall time of the call / 1,000, and
the CPU time of all threads / 1,000, which load from other processes hardly changes); the
hand-made one is per hit of a Python loop. Both run alternately in the same process, three
rounds; the load average and thread count are printed first.

Run: ``.venv/bin/python benches/bench_pipeline.py`` (peers: ``pip install pin ruckig``).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
import ttmanip
from ttmanip import robots

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_pipeline import random_hits  # noqa: E402

try:
    import pinocchio as pin
    import ruckig
except ImportError:  # pragma: no cover - optional peers
    pin = ruckig = None

T_HIT = 0.6
POINTS = 12


def ttmanip_per_hit_us(robot, hits, repeat: int = 5) -> tuple[float, float, dict]:
    """Best wall time and the CPU time of that call (all threads) per hit (µs), status counts."""
    best, cpu = np.inf, np.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        plans = ttmanip.plan_hits(robot, hits)
        t1, c1 = time.perf_counter(), time.process_time()
        if t1 - t0 < best:
            best, cpu = t1 - t0, c1 - c0
    statuses: dict = {}
    for p in plans:
        statuses[p.status] = statuses.get(p.status, 0) + 1
    return best / len(hits) * 1e6, cpu / len(hits) * 1e6, statuses


class HandMade:
    """IK (Pinocchio Gauss–Newton), J⁻¹V, ruckig strokes, pin.rnea torques."""

    def __init__(self, robot):
        self.robot = robot
        self.model = pin.buildModelFromXML(robot.to_urdf())
        self.data = self.model.createData()
        self.tool = self.model.getFrameId("tool")
        self.ready = np.array([0.0, 0.0, 0.0, 0.6, 0.6, 0.0])
        self.v, self.a = robot.velocity_limits, robot.acceleration_limits
        self.j = 200.0 * self.a
        self.effort = robot.effort_limits
        self.otg = ruckig.Ruckig(6)

    def ik(self, pose):
        target = pin.SE3(pose[:3, :3], pose[:3, 3])
        q = self.ready.copy()
        for _ in range(100):
            pin.framesForwardKinematics(self.model, self.data, q)
            err = pin.log6(self.data.oMf[self.tool].actInv(target)).vector
            if np.linalg.norm(err) < 1e-10:
                return q, True
            jac = pin.computeFrameJacobian(self.model, self.data, q, self.tool, pin.LOCAL)
            q = q + np.linalg.solve(jac.T @ jac + 1e-9 * np.eye(6), jac.T @ err)
        return q, False

    def leg(self, q0, v0, q1, v1, minimum=None):
        inp = ruckig.InputParameter(6)
        inp.current_position, inp.current_velocity, inp.current_acceleration = list(q0), list(v0), [0.0] * 6
        inp.target_position, inp.target_velocity, inp.target_acceleration = list(q1), list(v1), [0.0] * 6
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(self.v), list(self.a), list(self.j)
        if minimum is not None:
            inp.minimum_duration = minimum
        traj = ruckig.Trajectory(6)
        self.otg.calculate(inp, traj)
        return traj

    def plan(self, hit):
        q, ok = self.ik(hit.pose)
        if not ok:
            return None
        jac = pin.computeFrameJacobian(self.model, self.data, q, self.tool, pin.LOCAL_WORLD_ALIGNED)
        qd = np.linalg.solve(jac, hit.twist)
        if (np.abs(qd) > self.v).any():
            return None
        legs = [self.leg(self.ready, np.zeros(6), q, qd, T_HIT), self.leg(q, qd, self.ready, np.zeros(6))]
        worst = 0.0
        for traj in legs:
            for t in np.linspace(0.0, traj.duration, POINTS):
                p, v, a = traj.at_time(t)
                tau = pin.rnea(self.model, self.data, np.array(p), np.array(v), np.array(a))
                worst = max(worst, float(np.max(np.abs(tau) / self.effort)))
        return legs, worst

    def per_hit_us(self, hits, repeat: int = 3) -> float:
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            for h in hits:
                self.plan(h)
            best = min(best, time.perf_counter() - t0)
        return best / len(hits) * 1e6


def main(rounds: int = 3) -> None:
    robot = robots.gantry6()
    hits = random_hits(1000, seed=5, t=T_HIT)
    ttmanip.plan_hits(robot, hits[:10])  # warm-up
    threads = os.environ.get("RAYON_NUM_THREADS") or str(os.cpu_count())
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"load average {load}; {os.cpu_count()} cores; plan_hits on {threads} threads")
    hand = HandMade(robot) if pin is not None else None
    for r in range(rounds):
        us, cpu, statuses = ttmanip_per_hit_us(robot, hits)
        line = f"round {r + 1}: ttmanip.plan_hits, gantry6, 1000 hits at {T_HIT} s: {us:.1f} µs per hit"
        print(f"{line} (wall / N; CPU {cpu:.1f} µs per hit, all threads)  {statuses}")
        if hand is None:
            print("hand-made Pinocchio + ruckig: skipped (pip install pin ruckig)")
        else:
            print(
                f"round {r + 1}: hand-made Pinocchio + ruckig, same hits (Python loop, 300): "
                f"{hand.per_hit_us(hits[:300]):.1f} µs per hit"
            )


if __name__ == "__main__":
    main()
