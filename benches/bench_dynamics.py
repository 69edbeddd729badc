"""Dynamics from Python: ttmanip beside Pinocchio on the same exported URDF (armature set).

Checks that both agree, then prints per-call times (µs, median of repeats) of RNEA, mass matrix
and forward dynamics for one configuration, and the batch RNEA throughput.

Run: ``.venv/bin/python benches/bench_dynamics.py`` (peer: ``pip install pin``).
"""

from __future__ import annotations

import timeit

import numpy as np
import ttmanip
from timing import optional_peer, per_call_us, print_rows, random_configurations

pin = optional_peer("pinocchio")


def bench_robot(name: str, batch: int) -> list[tuple[str, str, str]]:
    robot = ttmanip.Robot.builtin(name)
    qs = random_configurations(robot, batch)
    rng = np.random.default_rng(1)
    qds = rng.uniform(-1, 1, qs.shape)
    qdds = rng.uniform(-1, 1, qs.shape)
    q, qd, qdd = qs[0].copy(), qds[0].copy(), qdds[0].copy()
    tau = robot.rnea(q, qd, qdd)
    rows = [
        (name, "ttmanip rnea", f"{per_call_us(lambda: robot.rnea(q, qd, qdd)):.2f} µs"),
        (name, "ttmanip mass_matrix", f"{per_call_us(lambda: robot.mass_matrix(q)):.2f} µs"),
        (
            name,
            "ttmanip forward_dynamics",
            f"{per_call_us(lambda: robot.forward_dynamics(q, qd, tau)):.2f} µs",
        ),
    ]
    best = min(timeit.repeat(lambda: robot.rnea(qs, qds, qdds), number=1, repeat=3))
    rows.append((name, "ttmanip rnea batch", f"{batch / best / 1e6:.2f} M/s"))
    if pin is not None:
        model = pin.buildModelFromXML(robot.to_urdf())
        model.armature = robot.armature
        data = model.createData()
        assert np.allclose(pin.rnea(model, data, q, qd, qdd), tau, atol=1e-9)
        rows += [
            (name, "pinocchio rnea", f"{per_call_us(lambda: pin.rnea(model, data, q, qd, qdd)):.2f} µs"),
            (name, "pinocchio crba", f"{per_call_us(lambda: pin.crba(model, data, q)):.2f} µs"),
            (name, "pinocchio aba", f"{per_call_us(lambda: pin.aba(model, data, q, qd, tau)):.2f} µs"),
        ]
    return rows


def main() -> None:
    rows = []
    for name in ("mobile8", "ur5"):
        rows += bench_robot(name, 200_000)
    print_rows(rows)


if __name__ == "__main__":
    main()
