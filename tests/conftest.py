"""Shared fixtures: the built-in robots and random configurations within their limits."""

from __future__ import annotations

import os

import numpy as np
import pytest
import ttmanip
from hypothesis import settings

# CI runs a fixed, reproducible set of property-test cases (scripts/test.sh sets CI=true);
# elsewhere hypothesis draws new cases every run.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if os.environ.get("CI") == "true":
    settings.load_profile("ci")

BUILTINS = ("mobile8", "gantry6", "arm4", "ur5")


def random_q(robot: ttmanip.Robot, count: int, seed: int = 0) -> np.ndarray:
    """(count, n) configurations uniformly within the joint limits."""
    lim = robot.limits
    rng = np.random.default_rng(seed)
    return lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((count, robot.dof))


@pytest.fixture(params=BUILTINS)
def robot(request) -> ttmanip.Robot:
    return ttmanip.Robot.builtin(request.param)


def built_binary(name: str) -> str | None:
    """The ttcan binary ``name`` in $TTCAN_BIN_DIR when set (scripts/test.sh picks the build per
    run), else the newest build (target/release or target/debug), or None. The newest, not the
    first found: a stale release build must not stand in for a fresh debug one."""
    import os

    chosen = os.environ.get("TTCAN_BIN_DIR")
    if chosen:
        path = os.path.join(chosen, name)
        return path if os.path.exists(path) else None
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    found = [os.path.join(root, "target", p, name) for p in ("release", "debug")]
    found = [p for p in found if os.path.exists(p)]
    return max(found, key=os.path.getmtime) if found else None
