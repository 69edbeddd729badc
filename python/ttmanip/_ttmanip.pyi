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

class NotConvergedError(TtmanipError):
    """A solver stopped before converging; the target may still be reachable."""

class NumericalError(TtmanipError):
    """A computation on finite inputs gave a non-finite result (overflow)."""

class InternalError(TtmanipError):
    """A bug inside ttmanip (a Rust panic caught at the boundary); please report it."""

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
        """A built-in robot: one of `Robot.builtin_names()` ("mobile8", "gantry6", "arm4", "ur5")."""
    @staticmethod
    def builtin_names() -> list[str]:
        """Names of the built-in robots, in the order of `ttkin::robots::NAMES`."""
    def to_urdf(self) -> str:
        """URDF text (links base_link, link0 … linkN, tool; link i is DH frame i)."""
    def to_toml(self) -> str:
        """Robot-file text (TOML, SI units)."""
    def with_tool(self, tool: ArrayLike) -> Robot:
        """The same robot with another tool transform (4×4)."""
    def with_base(self, base: ArrayLike) -> Robot:
        """The same robot with another base transform (4×4)."""
    @property
    def dof(self) -> int:
        """Number of joints (degrees of freedom)."""
    @property
    def n(self) -> int:
        """Deprecated name of ``dof``."""
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
    def with_racket(self, mount: ArrayLike) -> Robot:
        """The same robot carrying its racket at `mount` (racket frame in the tool frame, 4×4, m)."""
    def with_ready(self, q: ArrayLike) -> Robot:
        """The same robot with the ready (rest) configuration `q` (n,) in m or rad, within the limits."""
    @property
    def ready(self) -> NDArray[np.float64]:
        """(n,) ready (rest) configuration (m or rad): where strokes start and return to."""
    @property
    def gravity_vector(self) -> NDArray[np.float64]:
        """(3,) gravity in the base frame (m/s²): the default of every dynamics call on this robot."""
    @property
    def drive_effort_limits(self) -> NDArray[np.float64]:
        """(n,) drive peak torque G·k_t·I_peak·η (N or N·m; inf where the drive data lacks it)."""
    @property
    def effective_effort_limits(self) -> NDArray[np.float64]:
        """(n,) the smaller of effort_limits and drive_effort_limits: what the planners use at rest."""
    @property
    def effort_limit_sources(self) -> list[str]:
        """Which limit governs each joint at rest: "robot file", "drive peak current", "drive voltage"."""
    @property
    def drive_velocity_limits(self) -> NDArray[np.float64]:
        """(n,) the drive's largest speed min(ω_rated, 0.9·(0.95·U − R·I_cont)/k_t)/G (inf: no data)."""
    @property
    def effective_velocity_limits(self) -> NDArray[np.float64]:
        """(n,) the smaller of velocity_limits and drive_velocity_limits: what the planners use."""
    @property
    def velocity_limit_sources(self) -> list[str]:
        """Which limit governs each joint's speed: "robot file", "drive" or "none"."""
    def effort_limits_at(self, qd: ArrayLike) -> NDArray[np.float64]:
        """Effective effort limits at joint speeds qd: (n,) or (N, n); they fall with speed."""
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
    def task_jacobian(
        self, q: ArrayLike, task: str = "racket5", target: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """Task Jacobian (m, n) of "pose", "position" or "racket5" in residual coordinates (ė = −J_e q̇)."""
    def racket_angle_jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        """Jacobian (5, n) of the racket 5-vector [centre (m), polar, azimuth (rad)]: ẋ = J q̇."""
    def task_coordinates(self, q: ArrayLike, task: str = "racket5") -> NDArray[np.float64]:
        """Task coordinates of the tool pose: (3,) position, (6,) pose or (5,) racket 5-vector (m, rad)."""

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
    def ik(
        self,
        T: ArrayLike,
        q0: ArrayLike | None = None,
        task: str = "pose",
        *,
        method: str = "auto",
        position_tolerance: float = 1e-6,
        orientation_tolerance: float = 1e-6,
        max_iterations: int = 60,
        max_restarts: int = 500,
        time_budget: float | None = 1e-3,
        seed: int = 0,
        racket_offset: float | None = None,
        raise_on_failure: bool = False,
    ) -> IkResult:
        """IK of T (4, 4) or a batch (N, 4, 4); task "pose", "racket5" or "position".

        method "auto" uses the analytic nearest branch for task="pose" where the robot has one,
        else bounded Levenberg–Marquardt with restarts. An unreachable target gives
        success=False (UnreachableError only with raise_on_failure=True).
        """
    def ik_all(
        self, T: ArrayLike, limits: bool = False, hint: ArrayLike | None = None
    ) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Every analytic branch: (k, n) for T (4, 4); (q (N, 4, n) NaN-padded, count (N,)) for (N, 4, 4)."""
    def ik_nearest(self, T: ArrayLike, q: ArrayLike, limits: bool = True) -> NDArray[np.float64]:
        """The analytic branch nearest to q (revolute angles modulo 2π), within limits by default."""
    @property
    def analytic_ik(self) -> str | None:
        """ "gantry6" or "arm4" when the DH structure has a closed-form IK, else None."""
    def joint_velocity(
        self,
        q: ArrayLike,
        twist: ArrayLike,
        frame: str = "base",
        weights: ArrayLike | None = None,
        epsilon: float = 1e-3,
        lambda_max: float = 1e-2,
        info: bool = False,
        *,
        threshold: float | None = None,
        max_damping: float | None = None,
    ) -> NDArray[np.float64] | tuple[NDArray[np.float64], dict[str, float | bool]]:
        """q̇ (n,) for the tool twist [v; ω] (6,): J⁻¹V, weighted least-norm, or damped near singularities."""

class ServoSim:
    """A simulated servo axis: ttcan's current/speed/position cascade on a DC motor plant (SI units)."""

    def __init__(
        self, params: dict[str, object] | None = None, plant: dict[str, object] | None = None
    ) -> None:
        """Controller from ``params`` (nested entries of ``defaults()``, ``ttcan::AxisConfig``'s serde
        shape); plant: its ``model`` overridden by ``plant``."""
    @staticmethod
    def defaults() -> dict[str, object]:
        """The reference axis as a nested dict: maxon RE 25 + GP 26 A 14:1, 24 V, 20/5/1 kHz loops."""
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
    def follow(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        settle: float = 0.0,
        external_torque: float = 0.0,
        seed: int = 7,
    ) -> dict[str, object]:
        """Follows (q, qd, qdd) given at the position-loop rate from rest, then holds the end ``settle`` s."""

class DiffDrive:
    """Differential-drive base: wheel speeds (left, right) rad/s, body velocity (v m/s, ω rad/s)."""

    def __init__(
        self,
        wheel_radius: float,
        track_width: float | None = None,
        max_wheel_speed: float | None = None,
        max_wheel_acceleration: float | None = None,
        *,
        track: float | None = None,
    ) -> None:
        """``track`` is the deprecated name of ``track_width`` (m)."""
    @property
    def wheel_radius(self) -> float: ...
    @property
    def track_width(self) -> float: ...
    @property
    def track(self) -> float:
        """Deprecated name of ``track_width``."""
    @property
    def max_wheel_speed(self) -> float: ...
    @property
    def max_wheel_acceleration(self) -> float: ...
    def body_velocity(self, wheel_speeds: ArrayLike) -> tuple[float, float]:
        """(v m/s, ω rad/s) from wheel speeds (left, right) rad/s."""
    def wheel_speeds(self, v: float, omega: float) -> NDArray[np.float64]:
        """Wheel speeds (left, right) rad/s, shape (2,)."""
    def integrate(self, pose: ArrayLike, wheel_speeds: ArrayLike, duration: float) -> NDArray[np.float64]:
        """Pose (x, y, θ) after `duration` s at constant wheel speeds (exact arc), shape (3,)."""
    def saturate(self, wheel_speeds: ArrayLike) -> NDArray[np.float64]:
        """Wheel speeds scaled together to the speed limit, shape (2,)."""
    def limit_step(self, previous: ArrayLike, command: ArrayLike, dt: float) -> NDArray[np.float64]:
        """Wheel speeds reachable from `previous` toward `command` in `dt` s, shape (2,)."""

class TrackResult:
    """Arrays of a tracked motion, one row per control sample, and how it ended."""

    @property
    def time(self) -> NDArray[np.float64]: ...
    @property
    def q(self) -> NDArray[np.float64]: ...
    @property
    def qd(self) -> NDArray[np.float64]: ...
    @property
    def qdot(self) -> NDArray[np.float64]:
        """Deprecated name of ``qd``."""
    @property
    def x(self) -> NDArray[np.float64]: ...
    @property
    def error(self) -> NDArray[np.float64]: ...
    @property
    def position_error(self) -> NDArray[np.float64]: ...
    @property
    def orientation_error(self) -> NDArray[np.float64]: ...
    @property
    def margin(self) -> NDArray[np.float64]: ...
    @property
    def scale(self) -> NDArray[np.float64]: ...
    @property
    def sigma_min(self) -> NDArray[np.float64]: ...
    @property
    def status(self) -> str:
        """ "completed", "saturated" or "failed"."""
    @property
    def ok(self) -> bool: ...
    @property
    def message(self) -> str: ...
    @property
    def joint_names(self) -> list[str]: ...
    def __len__(self) -> int: ...

def wls_step(
    robot: Robot,
    q: ArrayLike,
    xdot: ArrayLike,
    task: str = "racket5",
    weights: str = "chan-dubey",
    lambda_max: float = 0.05,
    epsilon: float = 1e-3,
    qd_prev: ArrayLike | None = None,
    base: DiffDrive | None = None,
    mount: ArrayLike | None = None,
    *,
    damping: float | None = None,
    qdot_prev: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """One weighted least-norm step: inputs q̇ for task velocity `xdot` (residual coordinates)."""

def task_line(
    x0: ArrayLike, x1: ArrayLike, duration: float, rate_hz: float = 1000.0, task: str = "racket5"
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Samples and rates (N, dim) of a straight task line with the quintic time law."""

def track(
    robot: Robot,
    q0: ArrayLike,
    task_trajectory: ArrayLike,
    rate_hz: float = 1000.0,
    task: str = "racket5",
    velocities: ArrayLike | None = None,
    weights: str = "chan-dubey",
    gain: float | None = None,
    lambda_max: float = 0.05,
    epsilon: float = 1e-3,
    input_weights: ArrayLike | None = None,
    limit_gain: float = 0.0,
    manipulability_gain: float = 0.0,
    respect_limits: bool = True,
    max_error: float = 0.05,
    corrector: bool = True,
    base: DiffDrive | None = None,
    mount: ArrayLike | None = None,
    *,
    damping: float | None = None,
) -> TrackResult:
    """Closed-loop tracking of a task trajectory sampled at `rate_hz` (loop in Rust)."""

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

class IkResult:
    """Result of Robot.ik: scalars for one target, arrays for a batch."""

    @property
    def q(self) -> NDArray[np.float64]:
        """Joint values (m, rad): (n,) or (N, n)."""
    @property
    def success(self) -> bool | NDArray[np.bool_]:
        """True where both errors are within the tolerances."""
    @property
    def position_error(self) -> float | NDArray[np.float64]:
        """Position error (m)."""
    @property
    def orientation_error(self) -> float | NDArray[np.float64]:
        """Orientation error (rad)."""
    @property
    def iterations(self) -> int | NDArray[np.int64]:
        """LM steps (0 for an analytic solve)."""
    @property
    def restarts(self) -> int | NDArray[np.int64]:
        """Random restarts used."""
    @property
    def status(self) -> str | list[str]:
        """Outcome per target: "solved", "unreachable" (proven out of reach) or "not_converged"."""
    def __bool__(self) -> bool: ...

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
    def sample_rate(self, rate_hz: float | None = None, *, hz: float | None = None) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) at a control rate ``rate_hz`` (Hz, required), end time included; ``hz`` is
        its deprecated name."""
    def sample_uniform(self, n: int) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) at n ≥ 2 evenly spaced times."""
    def peaks(self, order: int) -> tuple[_F, _F]:
        """Exact signed peaks of velocity (1), acceleration (2) or jerk (3) and their times."""
    def check_limits(self, robot: Robot, jerk: ArrayLike | None = None) -> list[dict[str, Any]]:
        """Exact limit check: worst violation per joint and quantity; empty when all hold."""

class CartesianTrajectory:
    """Task-space trajectory: tool pose (4×4, base frame, m) along a line or an arc."""

    @staticmethod
    def line(
        t0: ArrayLike, t1: ArrayLike, duration: float, law: str = "quintic", blend: float = 0.25
    ) -> CartesianTrajectory:
        """Straight line between two poses, slerp orientation."""
    @staticmethod
    def arc_through(
        t0: ArrayLike,
        via: ArrayLike,
        t1: ArrayLike,
        duration: float,
        law: str = "quintic",
        blend: float = 0.25,
    ) -> CartesianTrajectory:
        """Circular arc from T0 through a point to T1, slerp orientation."""
    @staticmethod
    def arc_about(
        t0: ArrayLike,
        centre: ArrayLike,
        axis: ArrayLike,
        angle: float,
        duration: float,
        law: str = "quintic",
        blend: float = 0.25,
    ) -> CartesianTrajectory:
        """Circular arc of T0 about an axis line; the tool turns with the arc."""
    @property
    def duration(self) -> float:
        """Duration (s)."""
    def sample(self, t: float) -> tuple[_F, _F, _F]:
        """(pose (4, 4), twist [v; ω] (6,), twist derivative (6,)), base frame."""
    def sample_rate(self, rate_hz: float | None = None, *, hz: float | None = None) -> tuple[_F, _F, _F, _F]:
        """(t (N,), poses (N, 4, 4), twists (N, 6), twist derivatives (N, 6)) at ``rate_hz`` (Hz,
        required); ``hz`` is its deprecated name."""
    def to_joint(
        self,
        rate_hz: float | None = None,
        q_start: ArrayLike | None = None,
        ik: Callable[[_F, _F], ArrayLike] | None = None,
        *,
        hz: float | None = None,
    ) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) by IK at every sample at ``rate_hz`` (Hz); all three arguments required
        (``hz`` is the deprecated name of ``rate_hz``); raises naming the first unsolvable sample."""
    def check_limits(
        self,
        robot: Robot,
        ik: Callable[[_F, _F], ArrayLike],
        q_start: ArrayLike,
        rate_hz: float = 1000.0,
        *,
        hz: float | None = None,
    ) -> list[dict[str, Any]]:
        """Sampled limit check through IK at ``rate_hz`` (Hz; ``hz`` is its deprecated name)."""

def traj_cubic(
    q0: ArrayLike, q1: ArrayLike, duration: float, v0: ArrayLike | None = None, v1: ArrayLike | None = None
) -> JointTrajectory: ...
def traj_quintic(
    q0: ArrayLike,
    q1: ArrayLike,
    duration: float,
    v0: ArrayLike | None = None,
    v1: ArrayLike | None = None,
    a0: ArrayLike | None = None,
    a1: ArrayLike | None = None,
) -> JointTrajectory: ...
def traj_quintic_samples(
    q0: ArrayLike,
    q1: ArrayLike,
    duration: float,
    n: int = 101,
    v0: ArrayLike | None = None,
    v1: ArrayLike | None = None,
    a0: ArrayLike | None = None,
    a1: ArrayLike | None = None,
) -> tuple[_F, _F, _F, _F]: ...
def traj_via(
    points: ArrayLike,
    times: ArrayLike,
    kind: str = "cubic",
    velocities: ArrayLike | None = None,
    accelerations: ArrayLike | None = None,
    v_start: ArrayLike | None = None,
    v_end: ArrayLike | None = None,
) -> JointTrajectory: ...
def traj_minimal_duration(
    robot: Robot, q0: ArrayLike, q1: ArrayLike, kind: str = "quintic", jerk: ArrayLike | None = None
) -> float: ...
def traj_stroke(
    start: tuple[ArrayLike, ArrayLike, ArrayLike],
    hit: tuple[ArrayLike, ArrayLike, ArrayLike],
    t_hit: float,
    ready: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    jerk: ArrayLike,
    lower: ArrayLike | None = None,
    upper: ArrayLike | None = None,
    return_duration: float | None = None,
) -> tuple[JointTrajectory, float, float, list[dict[str, Any]]]: ...

# --- drives (issue 10): all axes of a robot through their cascades on its rigid-body dynamics ---

class DriveSim:
    """Every joint driven by its own current/speed/position cascade on the robot's shared
    rigid-body mechanics (gravity included), one current-loop period per tick (SI units)."""

    def __init__(
        self,
        robot: Robot,
        *,
        gravity: bool = True,
        setpoint_hz: float = 1000.0,
        noise: float | None = None,
        seed: int = 0,
        ideal_current: bool = False,
        setpoint_rate: float | None = None,
    ) -> None:
        """Drives from the robot file's drive section (``ttcan::coupled::axis_config_from_drive``);
        ``noise``: current-sense noise (A RMS, None: 5 mA); ``setpoint_hz``: cyclic setpoint rate
        (Hz) the drives interpolate (``setpoint_rate`` is its deprecated name); ``ideal_current``:
        winding current = reference. At q = 0."""
    def reset(self, q0: ArrayLike, qd0: ArrayLike | None = None) -> None:
        """Rebuilds the drives around (q0, qd0 or rest): time 0, every axis holding q0."""
    def set_setpoint(
        self,
        q: ArrayLike,
        qd: ArrayLike | None = None,
        qdd: ArrayLike | None = None,
        tau_ff: ArrayLike | None = None,
    ) -> None:
        """Joint-space setpoint (rad or m, per s, per s²) and joint-side torque feed-forward (N·m or N)."""
    def tick(self, n: int = 1) -> None:
        """Advances ``n`` current-loop periods."""
    @property
    def t(self) -> float:
        """Simulated time since the last reset, s."""
    @property
    def q(self) -> NDArray[np.float64]:
        """True joint positions, rad or m."""
    @property
    def qd(self) -> NDArray[np.float64]:
        """True joint speeds, rad/s or m/s."""
    @property
    def current(self) -> NDArray[np.float64]:
        """Winding currents, A."""
    @property
    def current_reference(self) -> NDArray[np.float64]:
        """Current references after limiting, A."""
    @property
    def current_ref(self) -> NDArray[np.float64]:
        """Deprecated name of `current_reference`."""
    @property
    def faults(self) -> list[str]:
        """Fault of each axis ("" when none)."""
    @property
    def tick_hz(self) -> float:
        """Current-loop (tick) rate, Hz."""
    @property
    def tick_rate(self) -> float:
        """Deprecated name of `tick_hz`."""
    def run(
        self,
        t: ArrayLike,
        q: ArrayLike,
        qd: ArrayLike,
        qdd: ArrayLike,
        tau_ff: ArrayLike | None = None,
    ) -> dict[str, Any]:
        """Runs a reference trajectory: t (K,); q, qd, q_ref, current, current_ref, torque (K, n); faults."""

def drive_theta5_case(setpoint_hz: float = 1000.0, *, setpoint_rate: float | None = None) -> dict[str, Any]:
    """Issue 10's θ5 case (gantry6 demo stroke on θ5, RE 25 + 14:1, 4096 counts): RMS numbers and
    traces (``setpoint_rate``, the deprecated name of ``setpoint_hz``, also as the result's key)."""

def actuators(robot: Robot) -> list[dict[str, Any]]:
    """Each joint's actuator from the robot file's drive section: joint, drive (as given),
    continuous_current, peak_current, max_speed, bus_voltage, encoder_counts, gear_ratio."""

def step_metrics(t: ArrayLike, y: ArrayLike, target: float) -> tuple[float, float]:
    """(10–90 % rise time in s, overshoot as a fraction of ``target``) of ``y`` sampled at ``t``."""

# -- hit pipeline (issue 12) ------------------------------------------------------------------
class HitPlan:
    """One planned hit: every intermediate product of ``ttkin::hit`` (SI units, base frame)."""

    @property
    def ok(self) -> bool:
        """True when the hit is on time and within every limit."""
    @property
    def status(self) -> str:
        """ok, too_early, unreachable, singular, hit_speed_limit, position_limit, effort_limit, no_stroke."""
    @property
    def message(self) -> str:
        """One line on what limited the plan ("" when ok)."""
    @property
    def q_hit(self) -> _F:
        """(n,) hit configuration (m, rad)."""
    @property
    def qd_hit(self) -> _F:
        """(n,) hit joint velocities."""
    @property
    def t_hit(self) -> float:
        """Planned hit time (s)."""
    @property
    def requested_t_hit(self) -> float:
        """Requested hit time (s)."""
    @property
    def earliest_t_hit(self) -> float:
        """Earliest feasible hit time (s)."""
    @property
    def profile(self) -> str:
        """Hit-leg profile: quintic or jerk."""
    @property
    def sigma_min(self) -> float:
        """Smallest singular value of the (task) Jacobian at the hit."""
    @property
    def branches(self) -> int:
        """IK branches within the limits."""
    @property
    def robot_name(self) -> str:
        """Name of the robot this plan was made for."""
    def made_for(self, robot: Robot) -> bool:
        """Whether this plan was made for ``robot`` (the same chain)."""
    @property
    def hit_pose(self) -> _F:
        """(4, 4) requested racket pose."""
    @property
    def hit_twist(self) -> _F:
        """(6,) requested racket-centre twist."""
    @property
    def tool_target(self) -> _F:
        """(4, 4) tool pose putting the racket at the hit pose."""
    @property
    def start(self) -> _F:
        """(n,) start configuration."""
    @property
    def ready(self) -> _F:
        """(n,) ready configuration."""
    @property
    def return_duration(self) -> float:
        """Return-leg duration (s)."""
    @property
    def duration(self) -> float:
        """Stroke duration (s)."""
    @property
    def peak_effort(self) -> _F:
        """(n,) largest |joint torque| over the stroke."""
    @property
    def effort_ratio(self) -> float:
        """Largest |τ(t)| / effective effort limit over every instant of the stroke."""
    @property
    def violations(self) -> list[dict[str, Any]]:
        """Kinematic limit violations."""
    @property
    def trajectory(self) -> JointTrajectory | None:
        """The stroke, None when none was planned."""
    def sample(self, rate_hz: float = 1000.0, *, rate: float | None = None) -> tuple[_F, _F, _F, _F]:
        """(t, q, qd, qdd) at ``rate_hz`` (Hz); ``rate`` is its deprecated name."""
    def torques(self, rate_hz: float = 1000.0, *, rate: float | None = None) -> _F:
        """(K, n) inverse-dynamics joint torques at ``rate_hz`` (Hz) samples (``rate``: deprecated)."""
    @property
    def tau(self) -> _F:
        """(K, n) joint torques at the 1 kHz samples."""

def hit_plan(
    robot: Robot,
    pose: ArrayLike,
    twist: ArrayLike,
    t: float,
    q: ArrayLike | None = None,
    qd: ArrayLike | None = None,
    qdd: ArrayLike | None = None,
    ready: ArrayLike | None = None,
    profile: str = "auto",
    task: str = "auto",
    jerk: ArrayLike | None = None,
    effort: bool = True,
) -> HitPlan: ...
def hit_plan_batch(
    robot: Robot,
    poses: ArrayLike,
    twists: ArrayLike,
    times: ArrayLike,
    q: ArrayLike | None = None,
    qd: ArrayLike | None = None,
    qdd: ArrayLike | None = None,
    ready: ArrayLike | None = None,
    profile: str = "auto",
    task: str = "auto",
    jerk: ArrayLike | None = None,
    effort: bool = True,
) -> list[HitPlan]: ...
def racket_frame(normal: ArrayLike, handle: ArrayLike | None = None) -> _F:
    """(3, 3) racket orientation (base axes): z along the face ``normal``, x (handle) near ``handle``."""

def racket_mount(robot: Robot) -> _F:
    """(4, 4) racket frame in the tool frame (m): where ``robot`` carries its racket."""

def racket_states(robot: Robot, q: ArrayLike, qd: ArrayLike) -> _F:
    """(N, 22) per joint state: racket pose (row-major 4×4, base frame, m), racket-centre twist (6,)."""

def hit_check(pose: ArrayLike, twist: ArrayLike, t: float) -> None: ...
def hit_stroke_profiles() -> list[str]:
    """The stroke profile names ``plan_hit(profile=...)`` accepts (``StrokeProfile::ALL``)."""

def hit_batch_check(robot: Robot, count: int) -> None: ...

# issue 29: the one array conversion, the rally's bound
def real_array(obj: ArrayLike, what: str) -> _F:
    """``obj`` as a float64 array of the same shape; complex, bool, string or object data is refused."""

MAX_RALLY_BALLS: int
BOUNCE_SPREAD: list[float]
EARTH_GRAVITY: list[float]

# issue 13: ball flight, estimation, prediction, hit planning, rally (ttkin::ball)
def ball_table() -> dict[str, float]: ...
def ball_table_check(table: dict[str, float]) -> None: ...
def ball_on_opponent_half(table: dict[str, float], x: float, y: float) -> bool: ...
def ball_table_outline(
    table: dict[str, float],
) -> dict[str, tuple[tuple[float, float, float], ...]]:
    """Polylines (x, y, z) (m, world) of the table: surface, centre_line, net."""

def ball_camera() -> dict[str, float]: ...
def ball_rally_config() -> dict[str, Any]:
    """``RallyConfig::default()``: camera, target (x, y), max_spin_rps, corkscrew, seed, paths,
    replan_period, max_window, correction_delay, second_correction, widen_correction, world (None)."""

def ball_placement() -> _F:
    """(4, 4) base frame of the rally's robot in the world (table) frame, m."""

def ball_placement_for(robot: Robot) -> _F | None:
    """(4, 4) base frame of ``robot`` in the world (table) frame where the rally places it, m;
    None for a robot the ball planner does not play (no analytic IK)."""

def ball_rally_observations(index: int, seed: int = 0, world: bool = False) -> dict[str, Any]: ...
def ball_rally_score(
    index: int,
    t_hit: float,
    t: ArrayLike,
    q: ArrayLike,
    qd: ArrayLike,
    seed: int = 0,
    world: bool = False,
) -> dict[str, Any]: ...
def ball_estimate(t: ArrayLike, p: ArrayLike, model: str = "default") -> dict[str, Any]: ...
def ball_predict(state: ArrayLike, times: ArrayLike, model: str = "default") -> dict[str, Any]: ...
def ball_predict_batch(states: ArrayLike, times: ArrayLike, model: str = "default") -> NDArray[np.float64]:
    """(N, K, 3) positions of N balls (``states`` (N, 10)) at ``times`` (K,); NaN after a terminal event."""

def ball_crossing(
    state: ArrayLike, point: ArrayLike, normal: ArrayLike, t_max: float = 2.0, model: str = "default"
) -> dict[str, Any]: ...
def ball_plan_return(
    robot: Robot, state: ArrayLike, now: float, target: ArrayLike, model: str = "default"
) -> dict[str, Any]: ...
def ball_fit(
    names: list[str],
    positions: list[ArrayLike],
    velocities: list[ArrayLike] | None = None,
    window: int = 20,
    period: float | None = None,
) -> dict[str, Any]: ...
def ball_racket_impact(
    state: ArrayLike, normal: ArrayLike, velocity: ArrayLike, model: str = "default"
) -> NDArray[np.float64]:
    """(10,) ball state just after the racket impact (``ttkin::ball::impact::RacketImpact``)."""

def ball_plan_correct(
    robot: Robot,
    state: ArrayLike,
    now: float,
    target: ArrayLike,
    state_new: ArrayLike,
    t_c: float,
    after_bounce: bool,
    model: str = "default",
) -> dict[str, Any]: ...
def ball_update(
    t: ArrayLike,
    p: ArrayLike,
    t_new: ArrayLike,
    p_new: ArrayLike,
    model: str = "default",
    bounce_spread: ArrayLike | None = None,
) -> dict[str, Any]: ...
def ball_rally(
    n: int,
    seed: int = 0,
    start: int = 0,
    target: tuple[float, float] = (0.9, 0.0),
    max_spin_rps: float = 40.0,
    paths: int = 5,
    world: bool = False,
    incoming: ArrayLike | None = None,
    drives: bool = False,
) -> dict[str, Any]: ...
def ball_rally_stats(
    in_reach: list[bool],
    returned: list[bool],
    reach: list[str],
    status: list[str],
    racket_error: ArrayLike,
    plan_time_us: ArrayLike,
    plan_wall_time_us: ArrayLike,
    correction_time_us: ArrayLike,
    landing_error: ArrayLike,
    velocity_error: ArrayLike,
) -> dict[str, Any]: ...

# issue 26: the controller's datagram format (ttcan::online::wire)
WIRE_VERSION: int
WIRE_MAX_LEN: int

def wire_hit(
    id: int, stroke: int, t_hit: float, pose: ArrayLike, twist: ArrayLike, seq: int, sent: float
) -> bytes: ...
def wire_observation(id: int, camera_time: float, position: ArrayLike, seq: int, sent: float) -> bytes: ...
def wire_decode(data: bytes) -> dict[str, Any]: ...
