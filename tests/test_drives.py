"""ttmanip.DriveSim (issue 10): every joint of gantry6 through its drive cascade on the robot's
rigid-body dynamics, tick by tick and as a whole-trajectory run."""

from __future__ import annotations

import numpy as np
import pytest
import ttmanip
from ttmanip import motor, robots


def _stroke(robot, rate=1000.0):
    ready = np.array([0.0, 0.0, 0.0, 0.6, 0.6, 0.0])
    t = np.arange(0.0, 0.4 + 1e-12, 1.0 / rate)
    s = np.clip(t / 0.4, 0.0, 1.0)[:, None]
    h = np.array([0.05, -0.05, 0.2, 0.3, -0.3, 0.2])
    q = ready + h * s**3 * (10 - 15 * s + 6 * s**2)
    qd = h / 0.4 * 30 * s**2 * (1 - s) ** 2
    qdd = h / 0.4**2 * 60 * s * (1 - s) * (1 - 2 * s)
    return t, q, qd, qdd


def test_run_returns_the_documented_arrays_and_tracks_with_feedforward():
    robot = robots.gantry6()
    sim = ttmanip.DriveSim(robot, setpoint_hz=1000.0, seed=1)
    t, q, qd, qdd = _stroke(robot)
    sim.reset(q[0])
    tau = robot.inverse_dynamics(q, qd, qdd)
    out = sim.run(t, q, qd, qdd, tau_ff=tau)
    k = len(out["t"])
    assert k == round(0.4 * sim.tick_hz) + 1
    for key in ("q", "qd", "q_ref", "current", "current_ref", "torque"):
        assert out[key].shape == (k, 6), key
    assert out["faults"] == [""] * 6
    assert np.abs(out["q"] - out["q_ref"]).max() < 2e-3


def test_tick_by_tick_holds_against_gravity_and_reports_state():
    robot = robots.gantry6()
    sim = ttmanip.DriveSim(robot)
    q0 = np.array([0.0, 0.0, 0.0, 0.6, 0.6, 0.0])
    sim.reset(q0)
    g = robot.gravity(q0)  # the host's gravity feed-forward (without it θ5 sags past its limit)
    for _ in range(200):  # 0.2 s of 1 kHz setpoints
        sim.set_setpoint(q0, tau_ff=g)
        sim.tick(20)
    assert sim.t == pytest.approx(0.2 + 1.0 / sim.tick_hz, abs=1e-9)
    assert np.abs(sim.q - q0).max() < 1e-3
    assert sim.current.shape == sim.current_reference.shape == (6,)
    assert sim.faults == [""] * 6


def test_lost_setpoints_stop_every_axis_with_a_named_fault():
    robot = robots.gantry6()
    sim = ttmanip.DriveSim(robot)
    q0 = np.array([0.0, 0.0, 0.0, 0.6, 0.6, 0.0])
    sim.reset(q0)
    sim.set_setpoint(q0)
    sim.tick(2000)  # 100 ms without a setpoint
    assert sim.faults == ["SetpointsLost"] * 6


def test_bad_input_raises_ttmanip_errors():
    robot = robots.gantry6()
    with pytest.raises(ttmanip.TtmanipError, match="setpoint_hz"):
        ttmanip.DriveSim(robot, setpoint_hz=0.0)
    sim = ttmanip.DriveSim(robot)
    with pytest.raises(ttmanip.TtmanipError):
        sim.set_setpoint([0.0, 1.0])
    t, q, qd, qdd = _stroke(robot)
    with pytest.raises(ttmanip.TtmanipError):
        sim.run(t, q[:, :3], qd, qdd)
    q_bad = q.copy()
    q_bad[3, 2] = np.nan
    with pytest.raises(ttmanip.TtmanipError):
        sim.run(t, q_bad, qd, qdd)


def test_theta5_ripple_case_meets_issue_10():
    r = motor.theta5_ripple_case()
    assert r["drive_current_ripple_rms_a"] <= 0.03
    assert r["drive_current_ripple_250hz_rms_a"] <= 0.06


def test_removed_loop_fields_warn_and_are_ignored():
    with pytest.warns(DeprecationWarning, match="observer_bandwidth_hz"):
        loops = motor.Loops(speed_window=4)
    with pytest.warns(DeprecationWarning, match="thermal"):
        motor.Loops(peak_duration=1.0)
    r = motor.Servo(loops=loops).step_response("current", 1.0, 0.01)
    assert abs(r.current[-1] - 1.0) < 0.02
