"""Type stubs of the native extension ``ttmanip._ttmanip`` (Rust, PyO3)."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

class TtmanipError(ValueError):
    """Base of every ttmanip error."""

class ShapeError(TtmanipError):
    """An array has the wrong length, shape or dtype."""

class NonFiniteError(TtmanipError):
    """An input holds NaN or an infinity."""

class ModelError(TtmanipError):
    """A robot model is inconsistent or non-physical."""

class RobotFileError(TtmanipError):
    """A robot file or URDF cannot be read."""

class UnreachableError(TtmanipError):
    """A target is outside the robot's reach."""

class SingularError(TtmanipError):
    """A configuration is singular for the request."""

class Robot:
    """A serial robot arm: joints from base to tool (m, rad, s). Immutable."""

    @staticmethod
    def from_dh(
        a: ArrayLike,
        alpha: ArrayLike,
        d: ArrayLike,
        theta: ArrayLike,
        types: str | Sequence[str] | None = None,
        convention: str = "standard",
        limits: ArrayLike | None = None,
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        name: str = "robot",
        names: Sequence[str] | None = None,
    ) -> Robot:
        """Robot from DH parameters (m, rad); theta/d hold the joint offsets at q = 0."""
    @staticmethod
    def from_file(path: str | os.PathLike[str]) -> Robot:
        """Robot from a ttmanip robot file (TOML)."""
    @staticmethod
    def from_toml(text: str) -> Robot:
        """Robot from robot-file text (TOML)."""
    @staticmethod
    def from_urdf(path: str | os.PathLike[str], base_link: str, tip_link: str) -> Robot:
        """Robot from the serial chain between two links of a URDF file."""
    @staticmethod
    def from_urdf_string(text: str, base_link: str, tip_link: str) -> Robot:
        """Robot from URDF text."""
    @staticmethod
    def builtin(name: str) -> Robot:
        """A built-in robot: "mobile8", "gantry6", "arm4" or "ur5"."""
    def to_urdf(self) -> str:
        """URDF text (links base_link, link0 … linkN, tool; link i is DH frame i)."""
    def to_toml(self) -> str:
        """Robot-file text (TOML, SI units)."""
    def with_tool(self, tool: ArrayLike) -> Robot:
        """The same robot with another tool transform (4×4)."""
    def with_base(self, base: ArrayLike) -> Robot:
        """The same robot with another base transform (4×4)."""
    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def name(self) -> str:
        """Robot name."""
    @property
    def joint_names(self) -> list[str]:
        """Joint names, base to tool."""
    @property
    def joint_types(self) -> list[str]:
        """ "revolute" or "prismatic" per joint."""
    @property
    def limits(self) -> NDArray[np.float64]:
        """(n, 2) lower and upper position limits (m or rad)."""
    @property
    def velocity_limits(self) -> NDArray[np.float64]:
        """(n,) speed limits (m/s or rad/s; inf where none)."""
    @property
    def acceleration_limits(self) -> NDArray[np.float64]:
        """(n,) acceleration limits (m/s² or rad/s²; inf where none)."""
    @property
    def effort_limits(self) -> NDArray[np.float64]:
        """(n,) effort limits (N or N·m; inf where none)."""
    @property
    def base(self) -> NDArray[np.float64]:
        """Base frame → frame 0 (4×4)."""
    @property
    def tool(self) -> NDArray[np.float64]:
        """Last link frame → tool frame (4×4)."""
    def fk(self, q: ArrayLike) -> NDArray[np.float64]:
        """Tool pose in the base frame: (4, 4) for q (n,), (N, 4, 4) for (N, n)."""
    def fk_all(self, q: ArrayLike) -> NDArray[np.float64]:
        """Every link frame in the base frame: (n, 4, 4) or (N, n, 4, 4)."""
    def jacobian(self, q: ArrayLike, frame: str = "base") -> NDArray[np.float64]:
        """Geometric Jacobian [v; ω] of the tool point: (6, n) or (N, 6, n)."""
