"""ttmanip: the motion stack for table-tennis robots.

Rust core (``ttkin``) behind a thin Python layer. Units are SI everywhere: metres, radians,
seconds; poses are 4×4 homogeneous matrices in the robot's base frame.

>>> import ttmanip
>>> robot = ttmanip.robots.gantry6()
>>> robot.fk([0.1, 0.0, 0.2, 0.3, 0.4, 0.5]).shape
(4, 4)
"""

from . import (
    ball,  # issue 13
    dynamics,
    motor,
    robots,
    traj,
)
from ._ttmanip import (
    DriveSim,
    IkResult,
    ModelError,
    NonFiniteError,
    Robot,
    RobotFileError,
    ShapeError,
    SingularError,
    TtmanipError,
    UnreachableError,
)
from .mobile import DiffDrive, TrackResult, task_line, track, wls_step
from .pipeline import DEMO_HIT, Hit, HitError, HitPlan, SimResult, plan_hit, plan_hits, simulate
from .rally import rally  # issue 13

__all__ = [
    "DiffDrive",
    "DriveSim",
    "IkResult",
    "ModelError",
    "NonFiniteError",
    "Robot",
    "RobotFileError",
    "ShapeError",
    "SingularError",
    "TrackResult",
    "TtmanipError",
    "UnreachableError",
    "dynamics",
    "motor",
    "robots",
    "traj",
    "task_line",
    "track",
    "wls_step",
    "ball",
    "rally",
    # hit pipeline (issue 12)
    "DEMO_HIT",
    "Hit",
    "HitError",
    "HitPlan",
    "SimResult",
    "plan_hit",
    "plan_hits",
    "simulate",
]

__version__ = "0.1.0"
