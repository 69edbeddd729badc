"""One weighted least-norm step and one whole tracked motion from Python: ttmanip beside the
Pinocchio + numpy version a user would write instead.

The peer computes the geometric Jacobian with Pinocchio, builds the same 5-D racket task Jacobian,
the Chan–Dubey weights and the weighted least-norm solve with numpy; both must agree (checked
before timing). Prints per-call times (µs, median of repeats) and the seed000 tracking time (ms).

Run: ``.venv/bin/python benches/bench_redundancy.py`` (peer: ``pip install pin``).
"""

from __future__ import annotations

import timeit

import numpy as np
import ttmanip
from timing import optional_peer, per_call_us
from ttmanip.experiments import seed000

pin = optional_peer("pinocchio")


def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def tangent_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u1 = np.cross(helper, n)
    u1 /= np.linalg.norm(u1)
    return u1, np.cross(n, u1)


def main() -> None:
    robot = ttmanip.robots.mobile8()
    q = seed000.Q_START.copy()
    xdot = np.array([0.1, 0.05, -0.08, 0.3, -0.2])
    lim = robot.limits
    rows = []
    ours = ttmanip.wls_step(robot, q, xdot, weights="chan-dubey", lambda_max=0.0)
    t_ours = per_call_us(lambda: ttmanip.wls_step(robot, q, xdot))
    rows.append(("ttmanip.wls_step (racket5, Chan–Dubey)", t_ours))

    if pin is not None:
        model = pin.buildModelFromXML(robot.to_urdf())
        data = model.createData()
        fid = model.getFrameId("tool")

        def peer() -> np.ndarray:
            j = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
            t = data.oMf[fid]
            r = t.rotation
            n = r[:, 0]
            jc = j[:3] - skew(0.15 * r[:, 2]) @ j[3:]
            u1, u2 = tangent_basis(n)
            jn = -np.vstack([u1, u2]) @ (skew(n) @ skew(n) @ j[3:])
            je = np.vstack([jc, jn])
            lo, hi = lim[:, 0], lim[:, 1]
            grad = (hi - lo) ** 2 * (2 * q - hi - lo) / (4 * (hi - q) ** 2 * (q - lo) ** 2)
            w = 1.0 + np.abs(grad)  # at rest: every joint counts as approaching its limit
            winv_jt = je.T / w[:, None]
            return winv_jt @ np.linalg.solve(je @ winv_jt, xdot)

        pin.framesForwardKinematics(model, data, q)
        assert np.allclose(peer(), ours, atol=1e-9), (peer(), ours)
        rows.append(("pinocchio jacobian + numpy WLS", per_call_us(peer, number=5000)))

    # the experiment's motion: FK along the quintic joint path to the nearest reachable target
    q_target, _ = seed000.nearest_reachable(robot)
    x, xd, _ = seed000.joint_path_task_trajectory(robot, q, q_target, 4.0, rate_hz=1000.0)
    t_track = min(timeit.repeat(lambda: ttmanip.track(robot, q, x, velocities=xd), number=5, repeat=5)) / 5
    rows.append(("ttmanip.track seed000 (4 s at 1 kHz, 4001 samples)", t_track * 1e6))

    width = max(len(r[0]) for r in rows)
    print(f"{'mobile8':10s} {'operation':{width}s}  time")
    for name, us in rows:
        value = f"{us / 1000:.2f} ms" if us > 1000 else f"{us:.2f} µs"
        print(f"{'mobile8':10s} {name:{width}s}  {value}")


if __name__ == "__main__":
    main()
