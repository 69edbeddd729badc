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

    # --- dynamics (crates/ttkin-py/src/dynamics.rs); SI units, gravity in the base frame ---
    def rnea(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        gravity: ArrayLike | None = None,
        wrench: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Inverse dynamics (RNEA, armature, no friction): (n,) or (N, n) torques."""
    def inverse_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        gravity: ArrayLike | None = None,
        wrench: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """rnea plus joint friction: the torques the drives deliver."""
    def mass_matrix(self, q: ArrayLike) -> NDArray[np.float64]:
        """Joint-space mass matrix (CRBA, armature included): (n, n) or (N, n, n)."""
    def gravity(self, q: ArrayLike, gravity: ArrayLike | None = None) -> NDArray[np.float64]:
        """Gravity torques g(q): (n,) or (N, n)."""
    def coriolis(self, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
        """Coriolis and centrifugal torques C(q, qd)·qd: (n,) or (N, n)."""
    def nonlinear_effects(
        self, q: ArrayLike, qd: ArrayLike, gravity: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """h(q, qd) = C(q, qd)·qd + g(q): (n,) or (N, n)."""
    def forward_dynamics(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        tau: ArrayLike,
        gravity: ArrayLike | None = None,
        wrench: ArrayLike | None = None,
    ) -> NDArray[np.float64]:
        """Joint accelerations M⁻¹(τ − h + Jᵀw), no friction: (n,) or (N, n)."""
    def friction(self, qd: ArrayLike) -> NDArray[np.float64]:
        """Joint friction b·qd + f_c·sign(qd): (n,) or (N, n)."""
    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float:
        """½ qdᵀ M qd (J)."""
    def potential_energy(self, q: ArrayLike, gravity: ArrayLike | None = None) -> float:
        """−Σ m_i g·c_i (J)."""
    def simulate(
        self,
        q0: ArrayLike,
        qd0: ArrayLike,
        tau: ArrayLike,
        dt: float,
        gravity: ArrayLike | None = None,
        friction: bool = True,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Semi-implicit Euler under tau (N, n): (q, qd), each (N + 1, n)."""
    def torques(
        self,
        trajectory: object,
        qd: ArrayLike | None = None,
        qdd: ArrayLike | None = None,
        gravity: ArrayLike | None = None,
        wrench: ArrayLike | None = None,
    ) -> TorqueProfile:
        """Torque profile of (q, qd, qdd) (N, n) arrays, a tuple of them or an object with q, qd, qdd."""
    @property
    def armature(self) -> NDArray[np.float64]:
        """(n,) rotor inertia reflected to each joint, G²·J (kg·m² or kg)."""
    @property
    def masses(self) -> NDArray[np.float64]:
        """(n,) link masses (kg; NaN where unknown)."""
    @property
    def drives(self) -> list[dict[str, float | None] | None]:
        """Per joint: gear_ratio, rotor_inertia, viscous, coulomb, torque_constant (or None)."""
    def with_inertials(self, mass: ArrayLike, com: ArrayLike, inertia: ArrayLike) -> Robot:
        """The same robot with link inertias (n,) kg, (n, 3) m, (n, 3, 3) kg·m² about the com, link frames."""
    def with_drives(
        self,
        gear_ratio: ArrayLike,
        rotor_inertia: ArrayLike | None = None,
        viscous: ArrayLike | None = None,
        coulomb: ArrayLike | None = None,
        torque_constant: ArrayLike | None = None,
    ) -> Robot:
        """The same robot with drives, one value per joint."""

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

class TorqueProfile:
    """Torques along a planned motion (patent step S105)."""

    @property
    def joint(self) -> NDArray[np.float64]:
        """(N, n) joint torques, friction included (N·m or N)."""
    @property
    def motor(self) -> NDArray[np.float64]:
        """(N, n) motor torques τ/G (N·m)."""
    @property
    def current(self) -> NDArray[np.float64]:
        """(N, n) motor currents (A; NaN without torque constant)."""
    @property
    def peak(self) -> NDArray[np.float64]:
        """(n,) largest |joint torque|."""
    @property
    def within_limits(self) -> bool:
        """No sample exceeds an effort limit."""
    @property
    def violations(self) -> list[tuple[int, int, float, float]]:
        """(sample, joint, torque, limit) of every exceedance."""
