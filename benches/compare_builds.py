"""Two builds of ttmanip side by side, in one run: the ttmanip rows of the Python benches.

The cases are those of ``bench_kinematics``, ``bench_dynamics``, ``bench_ik``, ``bench_traj`` and
``bench_redundancy`` (the peers left out), written only with calls that both builds have, so that
an older build (e.g. the wheel of an issue's base commit, unpacked to a directory) runs them
unchanged. ``bench_boundary.py --baseline DIR`` compares the boundary cases the same way;
``bench_pipeline`` has no older counterpart (the hit pipeline is newer than the base).

Each round measures every case once in a fresh subprocess per build, alternating baseline and
this build; the table shows the best round of each (on a shared machine the minimum is the
least disturbed measurement) and the ratio this build / baseline (below 1: faster). Every value
is µs per call or per item.

Run: ``.venv/bin/python benches/compare_builds.py --baseline DIR [--rounds 3]`` where ``DIR``
holds another build's ``ttmanip`` package (``pip install --no-deps --target DIR wheel.whl``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import timeit

import numpy as np
import ttmanip
import ttmanip.traj as tt
from bench_traj import T_REQUEST, problems, ttmanip_stroke
from timing import per_call_us

HERE = os.path.dirname(os.path.abspath(__file__))


def _dof(robot) -> int:
    """Joint count under either name (``dof`` now, ``n`` in older builds)."""
    return robot.dof if hasattr(robot, "dof") else robot.n


def _configurations(robot, count: int, seed: int = 0) -> np.ndarray:
    """(count, dof) configurations uniform within the joint limits (``timing.random_configurations``)."""
    lim = robot.limits
    rng = np.random.default_rng(seed)
    return lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((count, _dof(robot)))


def _robot(name: str, count: int):
    """The built-in robot ``name`` and ``count`` configurations within its limits."""
    robot = ttmanip.Robot.builtin(name)
    return robot, _configurations(robot, count)


def _batch_us(fn, count: int, repeat: int = 3) -> float:
    """Best time of one batch call over ``count`` items, µs per item."""
    return min(timeit.repeat(fn, number=1, repeat=repeat)) / count * 1e6


def _loop_us(fn, items) -> float:
    """Median over the items of one call each, µs (``bench_ik``'s per-target figure)."""
    times = []
    for x in items:
        t0 = timeit.default_timer()
        fn(x)
        times.append(timeit.default_timer() - t0)
    return float(np.median(times)) * 1e6


def kinematics(out: dict[str, float]) -> None:
    """``bench_kinematics``: single fk and jacobian, batch fk (100,000 configurations)."""
    for name in ("mobile8", "ur5"):
        _kinematics_of(name, out)


def _kinematics_of(name: str, out: dict[str, float]) -> None:

    robot, qs = _robot(name, 100_000)
    q = qs[0].copy()
    out[f"{name} fk"] = per_call_us(lambda: robot.fk(q))
    out[f"{name} jacobian"] = per_call_us(lambda: robot.jacobian(q))
    out[f"{name} fk batch (per config)"] = _batch_us(lambda: robot.fk(qs), len(qs))


def dynamics(out: dict[str, float]) -> None:
    """``bench_dynamics``: single rnea, mass matrix, forward dynamics; batch rnea (200,000)."""
    for name in ("mobile8", "ur5"):
        _dynamics_of(name, out)


def _dynamics_of(name: str, out: dict[str, float]) -> None:

    robot, qs = _robot(name, 200_000)
    rng = np.random.default_rng(1)
    qds, qdds = rng.uniform(-1, 1, qs.shape), rng.uniform(-1, 1, qs.shape)
    q, qd, qdd = qs[0].copy(), qds[0].copy(), qdds[0].copy()
    tau = robot.rnea(q, qd, qdd)
    out[f"{name} rnea"] = per_call_us(lambda: robot.rnea(q, qd, qdd))
    out[f"{name} mass_matrix"] = per_call_us(lambda: robot.mass_matrix(q))
    out[f"{name} forward_dynamics"] = per_call_us(lambda: robot.forward_dynamics(q, qd, tau))
    out[f"{name} rnea batch (per sample)"] = _batch_us(lambda: robot.rnea(qs, qds, qdds), len(qs))


def ik(out: dict[str, float]) -> None:
    """``bench_ik``: numeric ik per target (median of 1,000) and batched (10,000); gantry6 ik_all."""

    ur5_start = np.array([0.0, -np.pi / 2, np.pi / 2, 0.0, np.pi / 2, 0.0])
    _ik_of("ur5", "pose", ur5_start, out)
    _ik_of("mobile8", "pose", ttmanip.robots.mobile8_start(), out)
    _ik_of("mobile8", "racket5", ttmanip.robots.mobile8_start(), out)
    gantry = ttmanip.robots.gantry6()
    ts = gantry.fk(_configurations(gantry, 100_000, seed=1))
    out["gantry6 ik_all batch (per pose)"] = _batch_us(lambda: gantry.ik_all(ts), len(ts))
    out["gantry6 ik_all single"] = _batch_us(lambda: [gantry.ik_all(ts[0]) for _ in range(10_000)], 10_000)


def _ik_of(name: str, task: str, q0: np.ndarray, out: dict[str, float]) -> None:

    robot, qs = _robot(name, 10_000)
    targets = robot.fk(qs)
    out[f"{name} {task} ik"] = _loop_us(lambda t: robot.ik(t, q0, task=task), targets[:1000])
    out[f"{name} {task} ik batch (per target)"] = _batch_us(
        lambda: robot.ik(targets, q0, task=task), len(targets), repeat=1
    )


def traj(out: dict[str, float]) -> None:
    """``bench_traj``: an 8-joint quintic sampled at 101 points; hitting strokes (20 problems)."""

    q0, q1 = np.linspace(0.0, 1.0, 8), np.linspace(1.0, -1.0, 8)
    out["quintic_samples 8 joints x 101"] = per_call_us(lambda: tt.quintic_samples(q0, q1, 0.8, 101))
    out["quintic + sample_uniform 101"] = per_call_us(lambda: tt.quintic(q0, q1, 0.8).sample_uniform(101))

    ps = problems(20)
    out["stroke 8 joints (per problem)"] = min(
        _loop_us(lambda p: ttmanip_stroke(p, T_REQUEST), ps) for _ in range(5)
    )


def redundancy(out: dict[str, float]) -> None:
    """``bench_redundancy``: one wls_step of mobile8; tracking seed 000's 4 s motion at 1 kHz."""
    from ttmanip.experiments import seed000

    robot = ttmanip.robots.mobile8()
    q = seed000.Q_START.copy()
    xdot = np.array([0.1, 0.05, -0.08, 0.3, -0.2])
    out["mobile8 wls_step"] = per_call_us(lambda: ttmanip.wls_step(robot, q, xdot))
    q_target, _ = seed000.nearest_reachable(robot)
    x, xd, _ = seed000.joint_path_task_trajectory(robot, q, q_target, 4.0, rate_hz=1000.0)
    track = min(timeit.repeat(lambda: ttmanip.track(robot, q, x, velocities=xd), number=5, repeat=5)) / 5
    out["mobile8 track seed000 (4001 samples)"] = track * 1e6


GROUPS = {"kinematics": kinematics, "dynamics": dynamics, "ik": ik, "traj": traj, "redundancy": redundancy}


def measure(groups: list[str]) -> dict[str, float]:
    """Every case of ``groups`` in this process (whichever ttmanip is importable), µs."""
    sys.path.insert(0, HERE)
    out: dict[str, float] = {}
    for g in groups:
        GROUPS[g](out)
    return out


def run_child(pythonpath: str | None, groups: list[str]) -> dict[str, float]:
    """``measure(groups)`` in a fresh interpreter with ``pythonpath`` in front (None: this build)."""
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    code = (
        f"import sys, json, warnings; warnings.simplefilter('ignore'); sys.path.insert(0, {HERE!r}); "
        f"import compare_builds; print(json.dumps(compare_builds.measure({groups!r})))"
    )
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="directory holding another ttmanip package build")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--groups", default=",".join(GROUPS), help=f"comma-separated subset of {list(GROUPS)}")
    args = ap.parse_args()
    groups = [g for g in args.groups.split(",") if g]
    builds = {"baseline": args.baseline, "this build": None}
    runs: dict[str, list[dict[str, float]]] = {b: [] for b in builds}
    load_before = os.getloadavg()[0]
    for _ in range(args.rounds):
        for label, path in builds.items():
            runs[label].append(run_child(path, groups))
    best = {b: {k: min(r[k] for r in rs) for k in rs[0]} for b, rs in runs.items()}
    width = max(len(k) for k in best["this build"])
    load = f"{load_before:.2f} before, {os.getloadavg()[0]:.2f} after"
    print(f"load average (1 min) {load}; {os.cpu_count()} cores; {args.rounds} rounds, best of each")
    print(f"| {'case (µs)':<{width}} | {'baseline':>10} | {'this build':>10} | {'ratio':>6} |")
    print(f"|{'-' * (width + 2)}|{'-' * 12}|{'-' * 12}|{'-' * 8}|")
    for k, v in best["this build"].items():
        b = best["baseline"].get(k, float("nan"))
        print(f"| {k:<{width}} | {b:>10.3f} | {v:>10.3f} | {v / b:>6.3f} |")


if __name__ == "__main__":
    main()
