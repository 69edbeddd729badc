"""Motor control: one DC servo axis, its cascaded loops, simulation and plots.

The loops are ``ttcan``'s (Rust): current (PI, anti-windup, I²t, back-EMF feedforward, PWM duty),
speed (limit, reference filter, PI, output filter) and position (P with velocity and acceleration
feedforward, following-error monitoring), run at 20/5/1 kHz by default, on a simulated brushed DC
motor + gearbox + load + averaged H-bridge + quantising encoder + noisy current sense.

Everything is in SI units: ohm, henry, N·m/A, V·s/rad, kg·m², N·m·s/rad, N·m, V, A, Hz, s; positions
and speeds are at the output (joint) side of the gearbox. The defaults describe a maxon RE 25 (24 V)
with a GP 26 A 14:1 gearhead, a 1024-CPT encoder and a 1e-3 kg·m² load.

>>> from ttmanip import motor
>>> servo = motor.Servo()
>>> r = servo.step_response("current", 1.0, 0.01)
>>> bool(abs(r.current[-1] - 1.0) < 0.02)
True
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, fields
from os import PathLike
from typing import TYPE_CHECKING, Any

import numpy as np

from ._ttmanip import ServoSim, TtmanipError, actuators, drive_theta5_case, step_metrics

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "DcMotor",
    "Gearbox",
    "Load",
    "Loops",
    "PowerStage",
    "Response",
    "Servo",
    "actuators",
    "drive_line",
    "plot",
    "quintic",
    "theta5_figure",
    "theta5_ripple_case",
]

# The one axis schema is Rust's (``ttcan::AxisConfig``, serde): the dataclasses below take their
# defaults from it, ``Servo`` places their fields in it by name, and tests/test_motor.py checks
# that their fields and its entries agree.
_D = ServoSim.defaults()
_M = _D["model"]


@dataclass(frozen=True)
class DcMotor:
    """Brushed DC motor at its shaft (defaults: maxon RE 25, 24 V winding)."""

    resistance: float = _M["motor"]["resistance"]  # terminal resistance, Ω
    inductance: float = _M["motor"]["inductance"]  # terminal inductance, H
    torque_constant: float = _M["motor"]["torque_constant"]  # N·m/A
    back_emf_constant: float = _M["motor"]["back_emf_constant"]  # V·s/rad
    rotor_inertia: float = _M["motor"]["rotor_inertia"]  # kg·m²
    viscous_friction: float = _M["motor"]["viscous_friction"]  # N·m·s/rad
    coulomb_friction: float = _M["motor"]["coulomb_friction"]  # N·m


@dataclass(frozen=True)
class Gearbox:
    """Gearbox, ω_motor = ratio · ω_output (defaults: maxon GP 26 A 14:1)."""

    ratio: float = _M["gearbox"]["ratio"]  # motor turns per output turn
    efficiency: float = _M["gearbox"]["efficiency"]  # in (0, 1]
    inertia: float = _M["gearbox"]["inertia"]  # kg·m² at the motor shaft


@dataclass(frozen=True)
class Load:
    """Rigid load on the output shaft."""

    inertia: float = _M["load"]["inertia"]  # kg·m² about the output axis
    viscous_friction: float = _M["load"]["viscous_friction"]  # N·m·s/rad at the output


@dataclass(frozen=True)
class PowerStage:
    """Power stage (H-bridge on the DC bus) and the drive's sensors. Not a *drive*: in the
    glossary that is the joint's transmission (``ttkin::joint::Drive``)."""

    bus_voltage: float = _M["bus_voltage"]  # V
    max_duty: float = _M["max_duty"]  # largest |duty| in (0, 1]
    encoder_counts_per_rev: int = _M["encoder_counts_per_rev"]  # counts per motor turn (quadrature)
    current_noise: float = _M["current_noise"]  # current-sense noise standard deviation, A


def __getattr__(name: str):
    """``motor.Drive``: the deprecated name of :class:`PowerStage` (one release)."""
    if name == "Drive":
        warnings.warn(
            "motor.Drive is deprecated; use motor.PowerStage (a drive is the joint's transmission)",
            DeprecationWarning,
            stacklevel=2,
        )
        return PowerStage
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class Loops:
    """Loop rates, tuning targets, limits and switches of the cascade."""

    current_hz: float = _D["rates"]["current_hz"]  # current-loop (PWM) rate
    speed_hz: float = _D["rates"]["speed_hz"]  # must divide current_hz
    position_hz: float = _D["rates"]["position_hz"]  # must divide speed_hz
    current_bandwidth_hz: float = _D["tuning"]["current_bandwidth_hz"]  # ≤ current_hz / 6
    speed_symmetric_optimum: float = _D["tuning"]["speed_symmetric_optimum"]  # a ≥ 2
    speed_output_filter_hz: float = _D["tuning"]["speed_output_filter_hz"]
    position_ratio: float = _D["tuning"]["position_ratio"]  # speed crossover / position gain
    observer_bandwidth_hz: float = _D["tuning"]["observer_bandwidth_hz"]  # tracking observer
    speed_reference_filter_hz: float | None = _D["speed_reference_filter_hz"]  # None: 1/(2π a T_σ)
    continuous_current: float = _D["continuous_current"]  # A
    peak_current: float = _D["peak_current"]  # A
    overcurrent_trip: float = _D["overcurrent_trip"]  # A
    max_speed: float = _D["max_speed"]  # rad/s at the output
    following_error_limit: float = _D["following_error_limit"]  # rad
    quick_stop_deceleration: float = _D["quick_stop_deceleration"]  # rad/s²
    emf_filter_hz: float = _D["emf_filter_hz"]
    velocity_feedforward: bool = _D["velocity_feedforward"]
    acceleration_feedforward: bool = _D["acceleration_feedforward"]
    emf_feedforward: bool = _D["emf_feedforward"]
    anti_windup: bool = _D["anti_windup"]
    # Removed in issue 10 (kept one release, ignored with a DeprecationWarning): the speed is now
    # estimated by a tracking observer (``observer_bandwidth_hz``), and the I²t fold-back is replaced
    # by the thermal model.
    speed_window: int | None = None
    peak_duration: float | None = None

    def __post_init__(self) -> None:
        for name in ("speed_window", "peak_duration"):
            if getattr(self, name) is not None:
                warnings.warn(
                    f"Loops.{name} is deprecated and ignored: "
                    + (
                        "use observer_bandwidth_hz" if name == "speed_window" else "the thermal model derates"
                    ),
                    DeprecationWarning,
                    stacklevel=3,
                )


def _model(motor: DcMotor, gearbox: Gearbox, load: Load, power_stage: PowerStage) -> dict[str, Any]:
    """The parts as ``ttcan::MotorModel``'s entries (``ServoSim.defaults()["model"]``)."""
    return {"motor": asdict(motor), "gearbox": asdict(gearbox), "load": asdict(load), **asdict(power_stage)}


def _axis(loops: Loops) -> dict[str, Any]:
    """``loops`` as ``ttcan::AxisConfig``'s entries: each field goes to the section (``rates``,
    ``tuning``) of the Rust schema that holds its name, else to the top level."""
    out: dict[str, Any] = {"rates": {}, "tuning": {}}
    for name, value in asdict(loops).items():
        if name in ("speed_window", "peak_duration"):  # deprecated, ignored
            continue
        section = next((s for s in ("rates", "tuning") if name in _D[s]), None)
        (out[section] if section else out)[name] = value
    return out


# The flat plant keys of the previous release ("resistance", "gear_ratio", "load_inertia", ...) by
# the dataclass fields they name; they keep working one release with a DeprecationWarning.
_FLAT_PLANT = {
    **{f.name: ("motor", f.name) for f in fields(DcMotor)},
    **{f"gear_{f.name}": ("gearbox", f.name) for f in fields(Gearbox)},
    **{f"load_{f.name}": ("load", f.name) for f in fields(Load)},
}


def _plant_entries(plant: dict[str, Any]) -> dict[str, Any]:
    """A plant dict in ``ServoSim.defaults()["model"]``'s nested shape; flat keys are moved in."""
    out = {k: v for k, v in plant.items() if k not in _FLAT_PLANT}
    flat = [k for k in plant if k in _FLAT_PLANT]
    if flat:
        warnings.warn(
            f"flat plant keys ({', '.join(flat)}) are deprecated; use the nested form of "
            'Servo().params["model"], e.g. {"motor": {"resistance": ...}}',
            DeprecationWarning,
            stacklevel=3,
        )
    for k in flat:
        section, name = _FLAT_PLANT[k]
        out.setdefault(section, {})[name] = plant[k]
    return out


@dataclass(frozen=True)
class Response:
    """A simulated response, one sample per current-loop period (units as in the module doc)."""

    time: np.ndarray  # s
    current: np.ndarray  # true motor current, A
    current_reference: np.ndarray  # after limiting, A
    duty: np.ndarray  # in [-1, 1]
    speed: np.ndarray  # true output speed, rad/s
    speed_reference: np.ndarray  # after filtering and feedforward, rad/s
    position: np.ndarray  # true output position, rad
    position_reference: np.ndarray  # rad
    following_error: np.ndarray  # q_ref - q_measured at the last position step, rad
    state: np.ndarray  # 0 disabled, 1 enabled, 2 stopping, 3 faulted
    fault: str | None  # "OverCurrent", "FollowingError", ... or None

    @classmethod
    def _from_native(cls, d: dict[str, Any]) -> Response:
        return cls(**d)

    def rise_time(self, signal: str, target: float) -> float:
        """10 %–90 % rise time of ``signal`` (a field name) towards ``target``, s (inf if never);
        defined once, in Rust (``ttcan::sim::rise_time``)."""
        return step_metrics(self.time, self._signal(signal), _target(target))[0]

    def overshoot(self, signal: str, target: float) -> float:
        """Largest excursion of ``signal`` beyond ``target``, as a fraction of ``target``; defined
        once, in Rust (``ttcan::sim::overshoot``)."""
        return step_metrics(self.time, self._signal(signal), _target(target))[1]

    def _signal(self, signal: str) -> np.ndarray:
        """The array field named ``signal``; another name is a TtmanipError listing the fields."""
        fields = [f for f, v in vars(self).items() if isinstance(v, np.ndarray) and v.dtype.kind == "f"]
        if not isinstance(signal, str) or signal not in fields:
            raise TtmanipError(f"signal: expected one of {', '.join(fields)}, got {signal!r}")
        return getattr(self, signal)


def _target(target: float) -> float:
    """A step target: finite and non-zero (the ratios above divide by it)."""
    if not (np.isfinite(target) and target != 0.0):
        raise TtmanipError(f"target: expected a finite, non-zero value, got {target}")
    return float(target)


def _int_as_float(v, what: str):
    """A Python int as a float64, or a TtmanipError naming ``what`` when it is beyond float64's
    range (issue 29: not a bare OverflowError); anything else unchanged."""
    if isinstance(v, int) and not isinstance(v, bool):
        try:
            return float(v)
        except OverflowError:
            shown = str(v)[:20]
            raise TtmanipError(f"{what}: {shown}… is out of range; expected a float64") from None
    return v


def quintic(distance: float, duration: float, rate_hz: float, start: float = 0.0):
    """Rest-to-rest quintic sampled at ``rate_hz``: arrays (t, q, qd, qdd) in s, rad, rad/s, rad/s²
    (``ttmanip.traj``'s quintic, the one in Rust)."""
    distance, duration = _int_as_float(distance, "distance"), _int_as_float(duration, "duration")
    rate_hz, start = _int_as_float(rate_hz, "rate_hz"), _int_as_float(start, "start")
    if not (duration > 0 and rate_hz > 0 and np.isfinite(distance) and np.isfinite(start)):
        raise TtmanipError("quintic: need finite distance and start, duration > 0 and rate_hz > 0")
    if not duration * rate_hz <= 1e8:
        raise TtmanipError(f"quintic: duration × rate_hz = {duration * rate_hz:.3g} samples, at most 1e8")
    from . import traj

    t = np.arange(int(round(duration * rate_hz)) + 1) / rate_hz
    q, qd, qdd = traj.quintic([start], [start + distance], duration).sample(np.minimum(t, duration))
    return t, q[:, 0], qd[:, 0], qdd[:, 0]


class Servo:
    """One servo axis: the controller (built from ``motor``, ``gearbox``, ``load``,
    ``power_stage``, ``loops``) on a simulated actuator with the same parameters, or with ``plant``
    overriding some of them (e.g. ``plant=Load(inertia=2e-3)``) to see how the tuning copes with a
    model error. ``drive=`` is the deprecated name of ``power_stage=``."""

    def __init__(
        self,
        motor: DcMotor | None = None,
        gearbox: Gearbox | None = None,
        load: Load | None = None,
        power_stage: PowerStage | None = None,
        loops: Loops | None = None,
        plant: DcMotor | Gearbox | Load | PowerStage | dict[str, Any] | None = None,
        *,
        drive: PowerStage | None = None,
    ) -> None:
        if drive is not None:
            warnings.warn(
                "Servo(drive=...) is deprecated; use power_stage= (a PowerStage)",
                DeprecationWarning,
                stacklevel=2,
            )
            if power_stage is not None:
                raise TtmanipError("Servo: give power_stage= only (drive= is its deprecated name)")
            power_stage = drive
        parts = (motor or DcMotor(), gearbox or Gearbox(), load or Load(), power_stage or PowerStage())
        params = {"model": _model(*parts), **_axis(loops or Loops())}
        plant_params = None
        if isinstance(plant, dict):
            plant_params = _plant_entries(plant)
        elif plant is not None:
            plant_params = _model(*[plant if type(plant) is type(p) else p for p in parts])
        self._sim = ServoSim(params, plant_params)

    @property
    def tuning(self) -> dict[str, Any]:
        """Gains (kp, ki), crossover (Hz), phase margin (deg) and bandwidth (Hz) of each loop."""
        return self._sim.tuning

    @property
    def rates(self) -> tuple[float, float, float]:
        """Current, speed and position loop rates, Hz."""
        return self._sim.rates

    @property
    def params(self) -> dict[str, Any]:
        """The controller's parameters: ``ttcan::AxisConfig`` as a nested dict (``model`` with
        ``motor``, ``gearbox``, ``load``; ``rates``; ``tuning``; ``thermal``; ratings, limits, ...)."""
        return self._sim.params

    def step_response(
        self, kind: str, amplitude: float, duration: float, external_torque: float = 0.0, seed: int = 7
    ) -> Response:
        """Step of ``amplitude`` in 'current' (A), 'velocity' (rad/s) or 'position' (rad) mode."""
        return Response._from_native(self._sim.step(kind, amplitude, duration, external_torque, seed))

    def follow(
        self, q, qd, qdd, settle: float = 0.0, external_torque: float = 0.0, seed: int = 7
    ) -> Response:
        """Follows (q, qd, qdd) given at the position-loop rate from rest at q[0], then holds the end
        for ``settle`` s (``ttcan::Simulation::follow``)."""
        return Response._from_native(self._sim.follow(q, qd, qdd, settle, external_torque, seed))

    def follow_quintic(self, distance: float, duration: float, settle: float = 0.05) -> Response:
        """Follows a rest-to-rest quintic of ``distance`` rad in ``duration`` s from 0."""
        _, q, qd, qdd = quintic(distance, duration, self.rates[2])
        return self.follow(q, qd, qdd, settle=settle)

    def track(self, q, qd, qdd, settle: float = 0.0, external_torque: float = 0.0, seed: int = 7) -> Response:
        """Deprecated name of :meth:`follow` ("track" is CLIK tracking; see the glossary)."""
        warnings.warn("Servo.track is deprecated; use Servo.follow", DeprecationWarning, stacklevel=2)
        return self.follow(q, qd, qdd, settle, external_torque, seed)

    def track_quintic(self, distance: float, duration: float, settle: float = 0.05) -> Response:
        """Deprecated name of :meth:`follow_quintic`."""
        warnings.warn(
            "Servo.track_quintic is deprecated; use Servo.follow_quintic", DeprecationWarning, stacklevel=2
        )
        return self.follow_quintic(distance, duration, settle)

    def __repr__(self) -> str:
        return repr(self._sim)


def plot(response: Response, path: str | PathLike[str] | None = None, title: str | None = None) -> Figure:
    """Current, duty, speed and position (with references and following error) against time, in
    milliseconds. Uses the Agg canvas directly (no pyplot, no global backend change); writes a PNG
    when ``path`` is given and returns the figure."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if title is not None and not isinstance(title, str):
        raise TypeError(f"title: expected a str or None, got {type(title).__name__}")
    fig = Figure(figsize=(8, 9), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots(4, 1, sharex=True)
    t = response.time * 1e3
    ax[0].plot(t, response.current_reference, "--", label="reference")
    ax[0].plot(t, response.current, label="current")
    ax[0].set_ylabel("current (A)")
    ax[1].plot(t, response.duty, color="tab:purple")
    ax[1].set_ylabel("duty")
    ax[2].plot(t, response.speed_reference, "--", label="reference")
    ax[2].plot(t, response.speed, label="speed")
    ax[2].set_ylabel("speed (rad/s)")
    ax[3].plot(t, response.position_reference, "--", label="reference")
    ax[3].plot(t, response.position, label="position")
    ax[3].set_ylabel("position (rad)")
    err = ax[3].twinx()
    err.plot(t, response.following_error * 1e3, color="tab:red", lw=0.8, label="following error")
    err.set_ylabel("following error (mrad)", color="tab:red")
    ax[3].set_xlabel("time (ms)")
    for a in (ax[0], ax[2], ax[3]):
        a.legend(loc="best", fontsize="small")
    for a in ax:
        a.grid(True, alpha=0.3)
    if response.fault:
        stop = np.flatnonzero(response.state >= 2)
        if len(stop):
            for a in ax:
                a.axvline(t[stop[0]], color="k", lw=0.8, ls=":")
    fig.suptitle(title or (f"fault: {response.fault}" if response.fault else "servo response"))
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def drive_line(actuator: dict) -> str:
    """One line describing an entry of :func:`actuators`: the motor (k_t, R, L, rotor inertia), its
    ratings (continuous and peak current, largest joint speed), gear, encoder and bus."""
    d = actuator["drive"] or {}

    def value(key: str, fmt: str, scale: float = 1.0, unit: str = "") -> str:
        v = d.get(key)
        return "?" if v is None else f"{v * scale:{fmt}}{unit}"

    eta = d.get("gear_efficiency")
    return (
        f"motor k_t {value('torque_constant', '.4g')} N·m/A, R {value('resistance', '.4g')} Ω, "
        f"L {value('inductance', '.4g', 1e3)} mH, J {value('rotor_inertia', '.3g')} kg·m²; "
        f"{actuator['continuous_current']:.2f} A cont / {actuator['peak_current']:.2f} A peak, "
        f"max {actuator['max_speed']:.3g}; gear {actuator['gear_ratio']:g}"
        + ("" if eta is None else f" (η {eta:g})")
        + f", encoder {actuator['encoder_counts']}, bus {actuator['bus_voltage']:g} V"
    )


def theta5_ripple_case() -> dict[str, float]:
    """Issue 10's θ5 case (gantry6's demo stroke on θ5: maxon RE 25 + GP 26 A 14:1, 4096-count
    encoder, load 0.0148 kg·m²) computed in Rust (``ttcan::cases``), as the demo's ``summary.json``
    keys: ``drive_current_ripple_rms_a`` = RMS(i − i_ref) with 1 kHz setpoints and
    ``drive_current_ripple_250hz_rms_a`` = RMS(i − i_needed) with 250 Hz setpoints, both A, plus
    the largest following errors (rad)."""
    fast, slow = drive_theta5_case(1000.0), drive_theta5_case(250.0)
    return {
        "drive_current_ripple_rms_a": float(fast["current_ripple_rms"]),
        "drive_current_ripple_250hz_rms_a": float(slow["current_error_rms"]),
        "drive_theta5_following_error_rad": float(fast["max_following_error"]),
        "drive_theta5_following_error_250hz_rad": float(slow["max_following_error"]),
    }


def theta5_figure(path: str | PathLike[str] | None = None) -> Figure:
    """The θ5 case as a figure: current, its reference and the current the motion needs, with 1 kHz
    and 250 Hz setpoints, and the following error; writes a PNG when ``path`` is given."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 7), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots(3, 1, sharex=True)
    for a, rate in zip(ax[:2], (1000.0, 250.0), strict=False):
        c = drive_theta5_case(rate)
        t = c["t"] * 1e3
        a.plot(t, c["current_ref"], "--", lw=0.8, label="reference")
        a.plot(t, c["current"], lw=0.8, label="current")
        a.plot(t, c["current_needed"], ":", color="k", lw=1, label="needed by the motion")
        a.set_ylabel("current (A)")
        a.set_title(
            f"setpoints at {rate:.0f} Hz: RMS(i − i_ref) = {c['current_ripple_rms']:.4f} A, "
            f"RMS(i − i_needed) = {c['current_error_rms']:.4f} A",
            fontsize="small",
        )
        a.legend(loc="best", fontsize="small")
        ax[2].plot(t, (c["position_ref"] - c["position"]) * 1e3, lw=0.8, label=f"{rate:.0f} Hz setpoints")
    ax[2].set_ylabel("q_ref − q (mrad)")
    ax[2].set_xlabel("time (ms)")
    ax[2].legend(loc="best", fontsize="small")
    for a in ax:
        a.grid(True, alpha=0.3)
    fig.suptitle("gantry6 θ5 (RE 25 + 14:1, 4096 counts, 0.0148 kg·m²) with the tracking observer")
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
