"""Built-in robots of the seed documents (see ``../shared/seeds/README.md``) and a UR5.

Each function returns a fresh :class:`ttmanip.Robot`; the model data lives in the Rust core
(``ttkin::robots``), where every choice the seeds leave open (lengths, limits) is documented.
"""

from __future__ import annotations

import numpy as np

from ._ttmanip import Robot

__all__ = ["NAMES", "arm4", "builtin", "gantry6", "mobile8", "mobile8_start", "ur5"]

#: Names of the built-in robots (``ttkin::robots::NAMES``).
NAMES: tuple[str, ...] = tuple(Robot.builtin_names())


def builtin(name: str) -> Robot:
    """The built-in robot called ``name`` (one of :data:`NAMES`)."""
    return Robot.builtin(name)


def mobile8() -> Robot:
    """Seed 000, Table 1 read literally: 1 prismatic base joint + 7 revolute joints, modified DH."""
    return Robot.builtin("mobile8")


def mobile8_start() -> np.ndarray:
    """Seed 000's start configuration [0.26 m, 200°, 90°, 80°, 250°, 105°, 180°, 135°] in m and rad:
    mobile8's ready configuration (``mobile8().ready``)."""
    return mobile8().ready


def gantry6() -> Robot:
    """Seed 002's gantry robot: linear axes d1, d2 then θ3..θ6, modified DH, L = 0.10/0.05/0.30/0.15 m."""
    return Robot.builtin("gantry6")


def arm4() -> Robot:
    """Seed 001's 4-DOF arm (standard DH, joints 1 and 2 parallel and vertical)."""
    return Robot.builtin("arm4")


def ur5() -> Robot:
    """Universal Robots UR5 with the vendor's nominal standard-DH parameters."""
    return Robot.builtin("ur5")
