"""Timing helpers shared by the Python benchmarks (run them as ``python benches/bench_*.py``)."""

from __future__ import annotations

import importlib
import timeit

import numpy as np


def per_call_us(fn, number: int = 20000, repeat: int = 7) -> float:
    """Median time of one call of ``fn`` in µs."""
    times = timeit.repeat(fn, number=number, repeat=repeat)
    return float(np.median(times)) / number * 1e6


def per_item_rate(fn, count: int, repeat: int = 5) -> float:
    """Items per second of a batch call over ``count`` items (best of ``repeat``)."""
    return count / min(timeit.repeat(fn, number=1, repeat=repeat))


def random_configurations(robot, count: int, seed: int = 0) -> np.ndarray:
    """(count, dof) configurations drawn uniformly within ``robot``'s joint limits (m, rad)."""
    lim = robot.limits
    rng = np.random.default_rng(seed)
    return lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((count, robot.dof))


def optional_peer(module: str):
    """The peer library ``module`` when it is installed, else None (its rows are skipped)."""
    try:
        return importlib.import_module(module)
    except ImportError:  # pragma: no cover - optional peer
        return None


def print_rows(rows: list[tuple[str, str, str]]) -> None:
    """Prints (robot, operation, result) rows as an aligned table."""
    width = max(len(r[1]) for r in rows)
    print(f"{'robot':8s}  {'operation':{width}s}  result")
    for robot, op, result in rows:
        print(f"{robot:8s}  {op:{width}s}  {result}")
