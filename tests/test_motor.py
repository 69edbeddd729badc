"""ttmanip.motor: building a servo axis, simulating its responses, plotting, and bad input."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest
import ttmanip
from ttmanip import motor


@pytest.fixture(scope="module")
def servo() -> motor.Servo:
    return motor.Servo()


def test_defaults_are_the_documented_maxon_re25_axis():
    m, g = motor.DcMotor(), motor.Gearbox()
    assert (m.resistance, m.inductance, m.torque_constant) == (2.32, 0.238e-3, 43.9e-3)
    assert m.rotor_inertia == pytest.approx(10.8e-7)
    assert (g.ratio, g.efficiency) == (14.0, 0.81)
    assert motor.PowerStage().encoder_counts_per_rev == 4096


def test_dataclasses_are_the_rust_axis_schema():
    # One schema (ttcan::AxisConfig, serde): every dataclass field is an entry of it with the same
    # default, and an entry of the Rust schema that no dataclass exposes is listed here on purpose.
    params = motor.Servo().params
    model = params["model"]
    parts = {
        motor.DcMotor: model["motor"],
        motor.Gearbox: model["gearbox"],
        motor.Load: model["load"],
        motor.PowerStage: {k: v for k, v in model.items() if not isinstance(v, dict)},
    }
    for cls, entries in parts.items():
        assert asdict(cls()) == entries, cls.__name__
    loops = {k: v for k, v in asdict(motor.Loops()).items() if k not in ("speed_window", "peak_duration")}
    rust = {**params["rates"], **params["tuning"], **{k: v for k, v in params.items() if k not in SECTIONS}}
    assert loops == {k: rust[k] for k in loops}
    assert set(rust) - set(loops) == NOT_IN_LOOPS


SECTIONS = {"model", "rates", "tuning"}
NOT_IN_LOOPS = {
    "observer_acceleration_input",
    "thermal",
    "max_quantisation_ripple_share",
    "setpoint_period",
    "setpoint_max_missed",
    "following_error_per_speed",
    "overspeed_limit",
    "position_limits",
    "bus_overvoltage",
    "bus_undervoltage",
    "holding_brake",
}


def test_params_are_nested_and_changes_reach_their_entry():
    servo = motor.Servo(gearbox=motor.Gearbox(ratio=10.0), loops=motor.Loops(position_hz=500.0))
    assert servo.params["model"]["gearbox"]["ratio"] == 10.0
    assert servo.params["rates"] == {"current_hz": 20000.0, "speed_hz": 5000.0, "position_hz": 500.0}
    assert servo.rates == (20000.0, 5000.0, 500.0)


def test_a_bad_entry_is_named_by_its_path():
    with pytest.raises(ttmanip.TtmanipError, match=r"motor\.no_such"):
        motor.Servo(plant={"motor": {"no_such": 1.0}})
    with pytest.raises(ttmanip.TtmanipError, match=r"gearbox\.ratio"):
        motor.Servo(plant={"gearbox": {"ratio": "fourteen"}})
    with pytest.raises(ttmanip.TtmanipError, match=r"rates"):
        motor.Servo(loops=motor.Loops(speed_hz=6000.0))


def test_tuning_reports_designed_bandwidths(servo):
    t = servo.tuning
    assert servo.rates == (20000.0, 5000.0, 1000.0)
    assert t["current"]["bandwidth_hz"] == pytest.approx(1000.0, rel=0.05)
    assert t["current"]["phase_margin_deg"] > 75
    assert t["speed"]["phase_margin_deg"] == pytest.approx(53.1, abs=5)
    assert t["position"]["phase_margin_deg"] > 45
    # Discrete pole-zero cancellation: a = e^{-RT/L}, b = 1 - e^{-ω_c T}, Kp = R b/(1 - a), Ki = R b/T
    # (→ L ω_c and R ω_c for T → 0; at ω_c T = 0.31 the discrete values are 8 % and -14 % off).
    period, wc = 1 / 20000, 2 * np.pi * 1000
    a, b = np.exp(-2.32 * period / 0.238e-3), 1 - np.exp(-wc * period)
    assert t["current"]["kp"] == pytest.approx(2.32 * b / (1 - a), rel=1e-12)
    assert t["current"]["ki"] == pytest.approx(2.32 * b / period, rel=1e-12)
    assert t["current"]["kp"] == pytest.approx(0.238e-3 * wc, rel=0.1)


def test_current_step_response(servo):
    r = servo.step_response("current", 1.0, 0.02)
    n = len(r.time)
    assert n == 400
    for name in ("current", "current_reference", "duty", "speed", "position", "following_error"):
        a = getattr(r, name)
        assert isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (n,)
    assert r.fault is None and r.state[-1] == 1
    designed = np.log(9) / (2 * np.pi * 1000)
    assert r.rise_time("current", 1.0) == pytest.approx(designed, rel=0.2)
    assert r.overshoot("current", 1.0) < 0.05
    assert np.mean(r.current[-100:]) == pytest.approx(1.0, abs=0.003)
    assert np.all(np.abs(r.duty) <= 1.0)


def test_velocity_step_settles(servo):
    r = servo.step_response("velocity", 20.0, 0.1)
    assert r.overshoot("speed", 20.0) < 0.05
    assert np.mean(r.speed[-200:]) == pytest.approx(20.0, abs=0.1)


def test_quintic_tracking_with_and_without_feedforward():
    t, q, qd, qdd = motor.quintic(3.0, 0.3, 1000.0)
    assert q[0] == 0 and q[-1] == pytest.approx(3.0) and qd[-1] == pytest.approx(0.0)
    with_ff = motor.Servo().follow(q, qd, qdd, settle=0.05)
    no_ff = motor.Loops(velocity_feedforward=False, acceleration_feedforward=False, following_error_limit=1.0)
    without_ff = motor.Servo(loops=no_ff).follow(q, qd, qdd, settle=0.05)
    e_with = np.max(np.abs(with_ff.following_error))
    e_without = np.max(np.abs(without_ff.following_error))
    assert e_with < 2e-3
    assert e_without > 5e-2
    assert with_ff.position[-1] == pytest.approx(3.0, abs=1e-3)


def test_model_error_in_the_plant_is_tolerated():
    r = motor.Servo(plant=motor.Load(inertia=2e-3)).follow_quintic(2.0, 0.3)
    assert r.fault is None
    assert np.max(np.abs(r.following_error)) < 0.02


def test_too_fast_reference_trips_following_error_and_stops(servo):
    # A ramp at 40 rad/s for an axis limited to 30 rad/s.
    t = np.arange(100) / 1000.0
    r = servo.follow(40.0 * t, np.full(100, 40.0), np.zeros(100), settle=0.4)
    assert r.fault == "FollowingError"
    assert 2 in r.state and r.state[-1] == 3
    assert np.all(r.duty[r.state == 3] == 0.0)
    assert abs(r.speed[-1]) < 0.5


def test_plot_writes_a_png(servo, tmp_path):
    r = servo.step_response("velocity", 10.0, 0.05)
    path = tmp_path / "step.png"
    fig = motor.plot(r, path, title="velocity step")
    assert path.stat().st_size > 10_000
    assert len(fig.axes) == 5  # four panels and the following-error twin axis


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"motor": motor.DcMotor(resistance=-2.32)}, ttmanip.ModelError),
        ({"load": motor.Load(inertia=-1.0)}, ttmanip.ModelError),
        ({"motor": motor.DcMotor(rotor_inertia=0.0)}, ttmanip.ModelError),
        ({"motor": motor.DcMotor(inductance=float("nan"))}, ttmanip.NonFiniteError),
        ({"loops": motor.Loops(speed_hz=6000.0)}, ttmanip.TtmanipError),
        ({"loops": motor.Loops(peak_current=0.5)}, ttmanip.ModelError),
        ({"loops": motor.Loops(observer_bandwidth_hz=0.0)}, ttmanip.ModelError),
        ({"plant": {"motor": {"resistance": 0.0}}}, ttmanip.ModelError),
        ({"plant": {"no_such_parameter": 1.0}}, ttmanip.TtmanipError),
        ({"plant": {"gearbox": {"ratio": "14"}}}, ttmanip.TtmanipError),
        ({"loops": motor.Loops(anti_windup="no")}, ttmanip.TtmanipError),
    ],
)
def test_bad_parameters_are_rejected_when_built(kwargs, error):
    with pytest.raises(error) as info:
        motor.Servo(**kwargs)
    assert isinstance(info.value, ValueError)


def test_bad_references_are_rejected_before_simulating(servo):
    with pytest.raises(ttmanip.NonFiniteError):
        servo.step_response("current", float("nan"), 0.01)
    with pytest.raises(ttmanip.TtmanipError, match="kind"):
        servo.step_response("torque", 1.0, 0.01)
    with pytest.raises(ttmanip.TtmanipError):
        servo.step_response("current", 1.0, -1.0)
    q = np.zeros(10)
    with pytest.raises(ttmanip.NonFiniteError, match=r"qd\[3\]"):
        servo.follow(q, np.where(np.arange(10) == 3, np.inf, 0.0), q)
    with pytest.raises(ttmanip.ShapeError):
        servo.follow(q, q[:5], q)
    with pytest.raises(ttmanip.ShapeError):
        servo.follow(np.zeros((2, 5)), q, q)
