"""Cost of the robust Python boundary (issue 14): single-call ``fk`` and ``jacobian`` of mobile8
on an aligned C-contiguous float64 q (the zero-copy fast path), beside the copying paths
(unaligned, byte-swapped, strided, float32, list).

Compare two builds in one run: ``--baseline DIR`` names a directory holding another build of the
``ttmanip`` package (e.g. a copy of ``python/ttmanip`` with its ``.so`` from the commit before);
the two are measured in alternating subprocesses, several rounds, and the best of each compared.

``--icount`` adds what load cannot disturb: instructions per aligned ``fk`` and ``jacobian`` call,
counted by valgrind (callgrind) as the difference between a run of 20,000 calls and a run of none
(start-up cancels), with OpenBLAS on one thread (its idle worker threads would count too).

Run: ``.venv/bin/python benches/bench_boundary.py [--baseline DIR] [--rounds 6] [--icount]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def mobile8_case():
    """mobile8 and its aligned, C-contiguous float64 start configuration (m, rad)."""
    import ttmanip

    return ttmanip.Robot.builtin("mobile8"), ttmanip.robots.mobile8_start()


def measure() -> dict[str, float]:
    """Per-call µs of each case in this process (whichever ttmanip is importable)."""
    sys.path.insert(0, HERE)
    from timing import per_call_us

    robot, q = mobile8_case()
    out = {
        "fk aligned": per_call_us(lambda: robot.fk(q)),
        "jacobian aligned": per_call_us(lambda: robot.jacobian(q)),
    }
    buf = bytearray(8 * q.size + 1)
    unaligned = np.ndarray(q.shape, np.float64, buf, offset=1)
    unaligned[:] = q
    cases = {
        "unaligned": unaligned,
        "byte-swapped": q.astype(">f8"),
        "strided": np.repeat(q, 2)[::2],
        "float32": q.astype(np.float32),
        "list": q.tolist(),
    }
    for label, x in cases.items():
        try:
            out[f"fk {label}"] = per_call_us(lambda x=x: robot.fk(x), number=5000)
        except BaseException:  # the baseline refuses (or panics on, PanicException) some of these
            out[f"fk {label}"] = float("nan")
    return out


def run_child(pythonpath: str | None) -> dict[str, float]:
    env = dict(os.environ)
    if pythonpath:
        env["PYTHONPATH"] = pythonpath
    code = (
        f"import sys; sys.path.insert(0, {HERE!r}); import bench_boundary, json; "
        "print(json.dumps(bench_boundary.measure()))"
    )
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


ICOUNT_CHILD = f"""
import sys
sys.path.insert(0, {HERE!r})
from bench_boundary import mobile8_case
robot, q = mobile8_case()
f = getattr(robot, sys.argv[1])
f(q)
for _ in range(int(sys.argv[2])):
    f(q)
"""


def instructions_per_call(pythonpath: str | None, method: str, calls: int = 20000) -> float:
    """Instructions of one aligned ``robot.<method>(q)`` call of mobile8, counted by callgrind."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    if pythonpath:
        env["PYTHONPATH"] = pythonpath

    def total(n: int) -> int:
        cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable]
        res = subprocess.run(
            [*cmd, "-c", ICOUNT_CHILD, method, str(n)], env=env, capture_output=True, text=True, check=True
        )
        return int(res.stderr.split("Collected :")[1].split()[0])

    return (total(calls) - total(0)) / calls


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", help="directory holding another ttmanip package build")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--icount", action="store_true", help="also count instructions per call (valgrind)")
    args = ap.parse_args()
    builds = {"this build": None}
    if args.baseline:
        builds = {"baseline": args.baseline, "this build": None}
    runs: dict[str, list[dict[str, float]]] = {b: [] for b in builds}
    for _ in range(args.rounds):
        for label, path in builds.items():
            runs[label].append(run_child(path))
    keys = list(runs["this build"][0])
    # best of the rounds: on a shared machine the minimum is the least disturbed measurement
    med = {b: {k: float(np.min([r[k] for r in rs])) for k in keys} for b, rs in runs.items()}
    print(f"{'case':<22}" + "".join(f"{b:>14}" for b in builds) + ("     ratio" if args.baseline else ""))
    for k in keys:
        row = f"{k:<22}" + "".join(f"{med[b][k]:>11.3f} µs" for b in builds)
        if args.baseline:
            row += f"  {med['this build'][k] / med['baseline'][k]:>8.3f}"
        print(row)
    if args.icount:
        print(f"{'instructions per call':<22}" + "".join(f"{b:>14}" for b in builds))
        for method in ("fk", "jacobian"):
            counts = {b: instructions_per_call(path, method) for b, path in builds.items()}
            row = f"{method + ' aligned':<22}" + "".join(f"{counts[b]:>14.0f}" for b in builds)
            if args.baseline:
                row += f"  {counts['this build'] / counts['baseline']:>8.3f}"
            print(row)


if __name__ == "__main__":
    main()
