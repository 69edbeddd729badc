"""ttmanip: the motion stack for table-tennis robots.

Rust core (``ttkin``) behind a thin Python layer. Units are SI everywhere: metres, radians,
seconds; poses are 4×4 homogeneous matrices in the robot's base frame.

>>> import ttmanip
>>> robot = ttmanip.robots.gantry6()
>>> robot.fk([0.1, 0.0, 0.2, 0.3, 0.4, 0.5]).shape
(4, 4)
"""

from . import motor, robots
from ._ttmanip import (
    ModelError,
    NonFiniteError,
    Robot,
    RobotFileError,
    ShapeError,
    SingularError,
    TtmanipError,
    UnreachableError,
)

__all__ = [
    "ModelError",
    "NonFiniteError",
    "Robot",
    "RobotFileError",
    "ShapeError",
    "SingularError",
    "TtmanipError",
    "UnreachableError",
    "motor",
    "robots",
]

__version__ = "0.1.0"
