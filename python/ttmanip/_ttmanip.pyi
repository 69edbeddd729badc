"""Type stubs of the native extension ``ttmanip._ttmanip`` (Rust, PyO3)."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

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

class ServoSim:
    """A simulated servo axis: ttcan's current/speed/position cascade on a DC motor plant (SI units)."""

    def __init__(
        self, params: dict[str, object] | None = None, plant: dict[str, object] | None = None
    ) -> None:
        """Controller from ``params`` (keys of ``defaults()``); plant: the same, overridden by ``plant``."""
    @staticmethod
    def defaults() -> dict[str, object]:
        """The reference axis: maxon RE 25 + GP 26 A 14:1, 24 V, 20/5/1 kHz loops."""
    @property
    def params(self) -> dict[str, object]:
        """The controller's parameters, SI units."""
    @property
    def plant_params(self) -> dict[str, object]:
        """The simulated actuator's parameters, SI units."""
    @property
    def tuning(self) -> dict[str, object]:
        """Per loop: kp, ki, crossover_hz, phase_margin_deg, bandwidth_hz; plus t_sigma (s)."""
    @property
    def rates(self) -> tuple[float, float, float]:
        """Current, speed and position loop rates, Hz."""
    def step(
        self, kind: str, amplitude: float, duration: float, external_torque: float = 0.0, seed: int = 7
    ) -> dict[str, object]:
        """Step response in 'current' (A), 'velocity' (rad/s) or 'position' (rad) mode."""
    def trajectory(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        settle: float = 0.0,
        external_torque: float = 0.0,
        seed: int = 7,
    ) -> dict[str, object]:
        """Tracks (q, qd, qdd) given at the position-loop rate, then holds the end for ``settle`` s."""

# --- trajectories (crates/ttkin-py/src/traj.rs) -------------------------------------------------

_F = NDArray[np.float64]

class JointTrajectory:
    """Joint-space trajectory: piecewise polynomials of degree ≤ 5 per joint (rad or m, s)."""

    @property
    def duration(self) -> float:
        """Duration (s)."""
    @property
    def dof(self) -> int:
        """Number of joints."""
    @property
    def knots(self) -> _F:
        """Segment boundaries (s), from 0 to the duration."""
    @property
    def coefficients(self) -> _F:
        """(segments, dof, 6) coefficients in ascending powers of the local time (s)."""
    def sample(self, t: float | ArrayLike) -> tuple[_F, _F, _F]:
        """(q, qd, qdd) at t: each (dof,) for a scalar t, (N, dof) for N times."""
    def jerk(self, t: float) -> _F:
        """Jerk (per s³) at t, (dof,)."""
    def sample_rate(self, hz: float) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) at a control rate, end time included."""
    def sample_uniform(self, n: int) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) at n ≥ 2 evenly spaced times."""
    def peaks(self, order: int) -> tuple[_F, _F]:
        """Exact signed peaks of velocity (1), acceleration (2) or jerk (3) and their times."""
    def check_limits(self, robot: Robot, jerk: ArrayLike | None = None) -> list[dict[str, Any]]:
        """Exact limit check: worst violation per joint and quantity; empty when all hold."""

class CartesianTrajectory:
    """Task-space trajectory: tool pose (4×4, base frame, m) along a line or an arc."""

    @staticmethod
    def line(t0: ArrayLike, t1: ArrayLike, duration: float, law: str = "quintic",
             blend: float = 0.25) -> CartesianTrajectory:
        """Straight line between two poses, slerp orientation."""
    @staticmethod
    def arc_through(t0: ArrayLike, via: ArrayLike, t1: ArrayLike, duration: float, law: str = "quintic",
                    blend: float = 0.25) -> CartesianTrajectory:
        """Circular arc from T0 through a point to T1, slerp orientation."""
    @staticmethod
    def arc_about(t0: ArrayLike, centre: ArrayLike, axis: ArrayLike, angle: float, duration: float,
                  law: str = "quintic", blend: float = 0.25) -> CartesianTrajectory:
        """Circular arc of T0 about an axis line; the tool turns with the arc."""
    @property
    def duration(self) -> float:
        """Duration (s)."""
    def sample(self, t: float) -> tuple[_F, _F, _F]:
        """(pose (4, 4), twist [v; ω] (6,), twist derivative (6,)), base frame."""
    def sample_rate(self, hz: float) -> tuple[_F, _F, _F, _F]:
        """(t (N,), poses (N, 4, 4), twists (N, 6), twist derivatives (N, 6))."""
    def to_joint(self, hz: float, q_start: ArrayLike,
                 ik: Callable[[_F, _F], ArrayLike]) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) by IK at every sample; raises naming the first unsolvable sample."""
    def check_limits(self, robot: Robot, ik: Callable[[_F, _F], ArrayLike], q_start: ArrayLike,
                     hz: float = 1000.0) -> list[dict[str, Any]]:
        """Sampled limit check through IK."""

def traj_cubic(q0: ArrayLike, q1: ArrayLike, duration: float, v0: ArrayLike | None = None,
               v1: ArrayLike | None = None) -> JointTrajectory: ...
def traj_quintic(q0: ArrayLike, q1: ArrayLike, duration: float, v0: ArrayLike | None = None,
                 v1: ArrayLike | None = None, a0: ArrayLike | None = None,
                 a1: ArrayLike | None = None) -> JointTrajectory: ...
def traj_quintic_samples(q0: ArrayLike, q1: ArrayLike, duration: float, n: int = 101,
                         v0: ArrayLike | None = None, v1: ArrayLike | None = None,
                         a0: ArrayLike | None = None,
                         a1: ArrayLike | None = None) -> tuple[_F, _F, _F, _F]: ...
def traj_via(points: ArrayLike, times: ArrayLike, kind: str = "cubic", velocities: ArrayLike | None = None,
             accelerations: ArrayLike | None = None, v_start: ArrayLike | None = None,
             v_end: ArrayLike | None = None) -> JointTrajectory: ...
def traj_minimal_duration(robot: Robot, q0: ArrayLike, q1: ArrayLike, kind: str = "quintic",
                          jerk: ArrayLike | None = None) -> float: ...
def traj_stroke(start: tuple[ArrayLike, ArrayLike, ArrayLike], hit: tuple[ArrayLike, ArrayLike, ArrayLike],
                t_hit: float, ready: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike,
                jerk: ArrayLike, lower: ArrayLike | None = None, upper: ArrayLike | None = None,
                return_duration: float | None = None
                ) -> tuple[JointTrajectory, float, float, list[dict[str, Any]]]: ...
