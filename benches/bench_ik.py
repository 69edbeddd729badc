"""Numeric IK from Python: ttmanip beside Robotics Toolbox, Pinocchio, ikpy and OptIK.

Targets are the FK of random configurations within the joint limits (reachable by construction);
every solver starts from the same fixed configuration and must reach the pose to 1e-6 m and
1e-6 rad within the joint limits, checked with ttmanip's FK whatever the solver claims. A solve
counts as a success only if it also finished within 1 ms. Prints success rate and median / p99
time per solver and case, plus ttmanip's batch throughput and the analytic gantry6 IK (every
branch) per pose.

Single start (issue 29): every solver from the same start (ur5's home, mobile8's start pose) with
no restart and no time limit (ttmanip ``max_restarts=0``, Robotics Toolbox ``slimit=1``,
Pinocchio's CLIK loop, which never restarts), on ``--single-count`` targets per seed: the basin of
one descent, "reached" counted alike for all.

Run: ``.venv/bin/python benches/bench_ik.py [--count 10000] [--peer-count 1000]``, peers from
``pip install roboticstoolbox-python pin ikpy optik-py``. Not part of CI. The peers get fewer
targets by default because the slow ones take seconds per hundred solves.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings

import numpy as np
import ttmanip
from timing import random_configurations

TOL = 1e-6
BUDGET = 1e-3


def rot_angle(r: np.ndarray) -> float:
    """Rotation angle of a rotation matrix (rad), robust near 0 and π."""
    v = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return float(np.arctan2(np.linalg.norm(v), 0.5 * (np.trace(r) - 1.0)))


def reached(robot: ttmanip.Robot, q, target: np.ndarray, task: str) -> bool:
    """True when FK(q) reaches `target` to TOL for `task` (pose or racket5)."""
    if q is None or not np.all(np.isfinite(q)):
        return False
    lim = robot.limits
    q = np.asarray(q, dtype=float)
    if np.any(q < lim[:, 0] - 1e-9) or np.any(q > lim[:, 1] + 1e-9):
        return False
    t = robot.fk(q)
    if task == "racket5":
        c = lambda m: m[:3, 3] + 0.15 * m[:3, 2]  # noqa: E731
        n, nt = t[:3, 0], target[:3, 0]
        ang = float(np.arctan2(np.linalg.norm(np.cross(n, nt)), n @ nt))
        return bool(np.linalg.norm(c(t) - c(target)) <= TOL and ang <= TOL)
    dp = np.linalg.norm(t[:3, 3] - target[:3, 3])
    return bool(dp <= TOL and rot_angle(t[:3, :3].T @ target[:3, :3]) <= TOL)


def run(label: str, solve, robot, targets, task) -> tuple[str, str, float, float, float, float]:
    """Times `solve(T) -> q` per target: (label, count, success %, reached %, median µs, p99 µs)."""
    times, ok, hit = [], 0, 0
    for t in targets:
        t0 = time.perf_counter()
        try:
            q = solve(t)
        except Exception:  # a peer raising on a hard target counts as a failure
            q = None
        dt = time.perf_counter() - t0
        times.append(dt)
        good = reached(robot, q, t, task)
        hit += good
        ok += dt <= BUDGET and good
    times = np.array(times) * 1e6
    n = len(targets)
    med, p99 = float(np.median(times)), float(np.percentile(times, 99))
    return label, f"{n}", 100.0 * ok / n, 100.0 * hit / n, med, p99


def peers(robot: ttmanip.Robot, q0: np.ndarray, urdf: str, single: bool = False):
    """(label, solve) for every installed peer; ``single``: one start, no restart, no time limit
    (Robotics Toolbox and Pinocchio only)."""
    out = []
    try:
        import roboticstoolbox as rtb
        from roboticstoolbox.models.URDF.URDFRobot import URDF_file

        links, rname, _ = URDF_file(urdf)
        ets = rtb.Robot(links, name=rname).ets(start="base_link", end="tool")

        def rtb_solve(t):
            sol = ets.ik_LM(t, q0=q0, ilimit=30, slimit=1 if single else 100, tol=1e-12, joint_limits=True)
            return sol.q if sol.success else None

        out.append(("rtb ETS ik_LM (C++)", rtb_solve))
    except ImportError:
        pass
    try:
        import pinocchio as pin

        model = pin.buildModelFromXML(robot.to_urdf())
        data = model.createData()
        fid = model.getFrameId("tool")

        def pin_clik(t):
            # Pinocchio's documented CLIK loop (damped pseudo-inverse, step 0.1), frame version.
            target = pin.SE3(t[:3, :3], t[:3, 3])
            q = q0.copy()
            for _ in range(1000):
                pin.framesForwardKinematics(model, data, q)
                i_md = data.oMf[fid].actInv(target)
                err = pin.log(i_md).vector
                if np.linalg.norm(err) < 1e-7:
                    return q
                jac = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
                jac = -pin.Jlog6(i_md.inverse()) @ jac
                v = -jac.T @ np.linalg.solve(jac @ jac.T + 1e-12 * np.eye(6), err)
                q = pin.integrate(model, q, v * 0.1)
            return None

        out.append(("pinocchio CLIK loop", pin_clik))
    except ImportError:
        pass
    if single:
        return out
    try:
        import ikpy.chain

        chain = ikpy.chain.Chain.from_urdf_file(urdf, base_elements=["base_link"])
        mask = [link.joint_type != "fixed" for link in chain.links]
        chain.active_links_mask = np.array(mask)
        full0 = np.zeros(len(chain.links))
        full0[np.array(mask)] = q0

        def ikpy_solve(t):
            q = chain.inverse_kinematics(t[:3, 3], t[:3, :3], orientation_mode="all", initial_position=full0)
            return np.asarray(q)[np.array(mask)]

        out.append(("ikpy", ikpy_solve))
    except ImportError:
        pass
    if "prismatic" in robot.joint_types:
        # optik's Jacobian is `todo!()` for prismatic joints: the panic aborts Python.
        out.append(("optik-py", None))
        return out
    try:
        from optik import Robot as OptikRobot
        from optik import SolverConfig

        orobot = OptikRobot.from_urdf_file(urdf, "base_link", "tool")
        orobot.set_parallelism(1)
        config = SolverConfig(max_time=BUDGET, tol_f=1e-14)

        def optik_solve(t):
            sol = orobot.ik(config, t, list(q0))
            return None if sol is None or sol[0] is None else np.asarray(sol[0])

        out.append(("optik-py", optik_solve))
    except ImportError:
        pass
    return out


def main() -> None:
    warnings.filterwarnings("ignore", module="ikpy")
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=10_000, help="targets for ttmanip")
    ap.add_argument("--peer-count", type=int, default=1_000, help="targets for each peer")
    ap.add_argument("--single-count", type=int, default=200, help="targets per seed, single start")
    ap.add_argument("--only-single", action="store_true", help="only the single-start case")
    args = ap.parse_args()
    ur5_start = np.array([0.0, -np.pi / 2, np.pi / 2, 0.0, np.pi / 2, 0.0])
    cases = [
        ("ur5", "pose", ur5_start),
        ("mobile8", "pose", ttmanip.robots.mobile8_start()),
        ("mobile8", "racket5", ttmanip.robots.mobile8_start()),
    ]
    rows = single_start(cases[:2], args.single_count)
    if args.only_single:
        return report(rows)
    for name, task, q0 in cases:
        robot = ttmanip.Robot.builtin(name)
        qs = random_configurations(robot, args.count)
        targets = robot.fk(qs)
        label = f"{name} {task}"

        def ours(t, robot=robot, q0=q0, task=task):
            return robot.ik(t, q0, task=task).q

        rows.append((label, *run("ttmanip ik", ours, robot, targets, task)))
        t0 = time.perf_counter()
        batch = robot.ik(targets, q0, task=task)
        rate = len(targets) / (time.perf_counter() - t0)
        succ = 100.0 * batch.success.mean()
        rows.append((label, "ttmanip ik batch", f"{len(targets)}", succ, succ, 1e6 / rate, float("nan")))
        if task != "pose":
            continue  # the peers have no racket task
        with tempfile.TemporaryDirectory() as tmp:
            urdf = os.path.join(tmp, f"{name}.urdf")
            with open(urdf, "w") as f:
                f.write(robot.to_urdf())
            for plabel, solve in peers(robot, q0, urdf):
                if solve is None:
                    nan = float("nan")
                    rows.append((label, f"{plabel} (unsupported)", "0", nan, nan, nan, nan))
                    continue
                rows.append((label, *run(plabel, solve, robot, targets[: args.peer_count], task)))
    gantry = ttmanip.robots.gantry6()
    ts = gantry.fk(random_configurations(gantry, 100_000, seed=1))
    gantry.ik_all(ts)
    t0 = time.perf_counter()
    _, count = gantry.ik_all(ts)
    per_pose = (time.perf_counter() - t0) / len(ts) * 1e6
    succ = 100.0 * (count > 0).mean()
    rows.append(("gantry6 ik_all", "analytic batch", f"{len(ts)}", succ, succ, per_pose, float("nan")))
    t1 = ts[0]
    t0 = time.perf_counter()
    for _ in range(10_000):
        gantry.ik_all(t1)
    single = (time.perf_counter() - t0) / 1e4 * 1e6
    rows.append(("gantry6 ik_all", "analytic single", "10000", 100.0, 100.0, single, float("nan")))

    report(rows)


def single_start(cases, count: int) -> list:
    """The single-start rows: each solver's basin from one start, two seeds of targets."""
    rows = []
    for name, task, q0 in cases:
        robot = ttmanip.Robot.builtin(name)
        for seed in (0, 1):
            targets = robot.fk(random_configurations(robot, count, seed=seed))
            label = f"{name} 1-start s{seed}"

            def ours(t, robot=robot, q0=q0, task=task):
                return robot.ik(t, q0, task=task, method="numeric", max_restarts=0, time_budget=None).q

            rows.append((label, *run("ttmanip ik", ours, robot, targets, task)))
            with tempfile.TemporaryDirectory() as tmp:
                urdf = os.path.join(tmp, f"{name}.urdf")
                with open(urdf, "w") as f:
                    f.write(robot.to_urdf())
                for plabel, solve in peers(robot, q0, urdf, single=True):
                    rows.append((label, *run(plabel, solve, robot, targets, task)))
    return rows


def report(rows) -> None:
    head = f"{'case':16s} {'solver':22s} {'targets':>8s} {'success%':>9s} {'reached%':>9s}"
    print(f"{head} {'median µs':>10s} {'p99 µs':>10s}")
    for case, solver, n, succ, hit, med, p99 in rows:
        print(f"{case:16s} {solver:22s} {n:>8s} {succ:9.2f} {hit:9.2f} {med:10.2f} {p99:10.2f}")
    print("success%: reached within 1 ms; reached%: reached at all (to 1e-6 m / rad, within limits).")
    print("Batch rows: time per target of one parallel call; success within the 1 ms budget each.")


if __name__ == "__main__":
    main()
