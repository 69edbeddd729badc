"""ttmanip: the motion stack for table-tennis robots.

Rust core (``ttkin``) behind a thin Python layer. Units are SI everywhere: metres, radians,
seconds; poses are 4×4 homogeneous matrices in the robot's base frame.

>>> import ttmanip
>>> robot = ttmanip.robots.gantry6()
>>> robot.fk([0.1, 0.0, 0.2, 0.3, 0.4, 0.5]).shape
(4, 4)
"""

from . import ball, dynamics, motor, robots, traj
from ._ttmanip import (  # issue 14: overflow, caught panics
    DriveSim,
    IkResult,
    InternalError,
    ModelError,
    NonFiniteError,
    NotConvergedError,
    NumericalError,
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
from .sweeps import sweep  # issue 31

__all__ = [
    "DEMO_HIT",
    "DiffDrive",
    "DriveSim",
    "Hit",
    "HitError",
    "HitPlan",
    "IkResult",
    "InternalError",
    "ModelError",
    "NonFiniteError",
    "NotConvergedError",
    "NumericalError",
    "Robot",
    "RobotFileError",
    "ShapeError",
    "SimResult",
    "SingularError",
    "TrackResult",
    "TtmanipError",
    "UnreachableError",
    "ball",
    "dynamics",
    "motor",
    "plan_hit",
    "plan_hits",
    "rally",
    "robots",
    "simulate",
    "sweep",
    "task_line",
    "track",
    "traj",
    "wls_step",
]

__version__ = "0.1.0"
