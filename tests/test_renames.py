"""Renamed Python names (see the glossary of ARCHITECTURE.md) keep working, warn, and agree with
their new names; IK statuses tell unreachable from not converged."""

from __future__ import annotations

import numpy as np
import pytest
import ttmanip


def test_robot_n_is_a_deprecated_dof():
    robot = ttmanip.robots.ur5()
    with pytest.warns(DeprecationWarning, match=r"Robot\.n is deprecated; use Robot\.dof"):
        n = robot.n
    assert n == robot.dof == 6


def test_drive_sim_current_ref_is_a_deprecated_current_reference():
    sim = ttmanip.DriveSim(ttmanip.robots.gantry6())
    sim.tick(40)
    message = r"DriveSim\.current_ref is deprecated; use DriveSim\.current_reference"
    with pytest.warns(DeprecationWarning, match=message):
        old = sim.current_ref
    np.testing.assert_array_equal(old, sim.current_reference)


def test_diff_drive_track_is_a_deprecated_track_width():
    with pytest.warns(DeprecationWarning, match="track_width"):
        old = ttmanip.DiffDrive(wheel_radius=0.1, track=0.5)
    new = ttmanip.DiffDrive(wheel_radius=0.1, track_width=0.5)
    assert new.track_width == 0.5
    with pytest.warns(DeprecationWarning, match=r"DiffDrive\.track is deprecated"):
        assert old.track == new.track_width
    np.testing.assert_array_equal(old.wheel_speeds(0.3, 0.2), new.wheel_speeds(0.3, 0.2))
    with pytest.raises(ttmanip.TtmanipError, match="track_width"):
        ttmanip.DiffDrive(wheel_radius=0.1)


def test_track_result_qdot_is_a_deprecated_qd():
    from ttmanip.experiments import seed000

    robot = ttmanip.robots.mobile8()
    q0 = seed000.Q_START
    x0 = robot.task_coordinates(q0)
    x, xdot = ttmanip.task_line(x0, x0 + np.array([0.01, 0, 0, 0, 0]), 0.1)
    res = ttmanip.track(robot, q0, x, velocities=xdot)
    with pytest.warns(DeprecationWarning, match=r"TrackResult\.qdot"):
        old = res.qdot
    np.testing.assert_array_equal(old, res.qd)


def test_damping_keywords_are_deprecated_epsilon_and_lambda_max():
    gantry = ttmanip.robots.gantry6()
    q = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    twist = np.array([0.1, 0.0, 0.2, 0.0, 0.1, 0.0])
    new = gantry.joint_velocity(q, twist, epsilon=0.5, lambda_max=0.3)
    with pytest.warns(DeprecationWarning, match=r"\(threshold=\.\.\.\) is deprecated; use epsilon"):
        with pytest.warns(DeprecationWarning, match=r"max_damping=\.\.\.\) is deprecated; use lambda_max"):
            old = gantry.joint_velocity(q, twist, threshold=0.5, max_damping=0.3)
    np.testing.assert_array_equal(old, new)
    # the damped result differs from the default one: the keywords are used, not dropped
    assert np.abs(new - gantry.joint_velocity(q, twist)).max() > 1e-6
    robot = ttmanip.robots.mobile8()
    from ttmanip.experiments import seed000

    xdot, prev = np.array([0.01, 0.0, 0.02, 0.0, 0.01]), np.full(8, 0.01)
    new = ttmanip.wls_step(robot, seed000.Q_START, xdot, lambda_max=0.2, epsilon=0.3, qd_prev=prev)
    with pytest.warns(DeprecationWarning, match=r"wls_step\(damping=\.\.\.\) is deprecated; use lambda_max"):
        with pytest.warns(DeprecationWarning, match=r"\(qdot_prev=\.\.\.\) is deprecated; use qd_prev"):
            old = ttmanip.wls_step(robot, seed000.Q_START, xdot, damping=0.2, epsilon=0.3, qdot_prev=prev)
    np.testing.assert_array_equal(old, new)
    x0 = robot.task_coordinates(seed000.Q_START)
    x, xd = ttmanip.task_line(x0, x0 + np.array([0.01, 0, 0, 0, 0]), 0.1)
    new = ttmanip.track(robot, seed000.Q_START, x, velocities=xd, lambda_max=0.0)
    with pytest.warns(DeprecationWarning, match=r"track\(damping=\.\.\.\) is deprecated; use lambda_max"):
        old = ttmanip.track(robot, seed000.Q_START, x, velocities=xd, damping=0.0)
    np.testing.assert_array_equal(old.q, new.q)


def test_ik_status_tells_unreachable_from_not_converged():
    robot = ttmanip.robots.ur5()
    reachable = robot.fk(np.array([0.3, -0.9, 1.1, -0.4, 0.8, 0.2]))
    far = np.eye(4)
    far[0, 3] = 5.0
    batch = robot.ik(np.stack([reachable, far, reachable]), time_budget=None, max_restarts=20)
    assert batch.status == ["solved", "unreachable", "solved"]
    assert list(batch.success) == [True, False, True]
    starved = dict(q0=[-2.0, 1.0, -1.0, 2.0, -2.0, 2.0], method="numeric", max_iterations=1, max_restarts=0)
    result = robot.ik(reachable, time_budget=None, **starved)
    assert result.status == "not_converged" and not result.success
    with pytest.raises(ttmanip.NotConvergedError):
        robot.ik(reachable, time_budget=None, raise_on_failure=True, **starved)
    with pytest.raises(ttmanip.UnreachableError):
        robot.ik(far, time_budget=None, max_restarts=3, raise_on_failure=True)
    assert not issubclass(ttmanip.NotConvergedError, ttmanip.UnreachableError)


def test_callback_exception_keeps_its_type():
    line = ttmanip.traj.line(np.eye(4), np.eye(4) @ np.diag([1.0, 1, 1, 1]), 0.1)

    class Boom(RuntimeError):
        pass

    def ik(pose, seed):
        raise Boom("from the user's callback")

    with pytest.raises(Boom, match="user's callback"):
        line.to_joint(100.0, np.zeros(6), ik)

    def unreachable(pose, seed):
        raise ttmanip.UnreachableError("beyond the rail")

    with pytest.raises(ttmanip.UnreachableError, match=r"^unreachable: sample 0 at t = ") as info:
        line.to_joint(100.0, np.zeros(6), unreachable)
    assert isinstance(info.value.__cause__, ttmanip.UnreachableError)
    assert "beyond the rail" in str(info.value.__cause__)


def test_servo_track_is_a_deprecated_follow():
    from ttmanip import motor

    servo = motor.Servo()
    _, q, qd, qdd = motor.quintic(0.5, 0.05, 1000.0)
    new = servo.follow(q, qd, qdd, settle=0.01)
    with pytest.warns(DeprecationWarning, match=r"Servo\.track is deprecated; use Servo\.follow"):
        old = servo.track(q, qd, qdd, settle=0.01)
    np.testing.assert_array_equal(old.position, new.position)
    with pytest.warns(DeprecationWarning, match=r"Servo\.follow_quintic"):
        old = servo.track_quintic(0.5, 0.05)
    np.testing.assert_array_equal(old.current, servo.follow_quintic(0.5, 0.05).current)


def test_flat_plant_keys_are_deprecated_nested_entries():
    from ttmanip import motor

    with pytest.warns(DeprecationWarning, match="gear_ratio, load_inertia"):
        old = motor.Servo(plant={"gear_ratio": 12.0, "load_inertia": 2e-3, "bus_voltage": 30.0})
    new = motor.Servo(plant={"gearbox": {"ratio": 12.0}, "load": {"inertia": 2e-3}, "bus_voltage": 30.0})
    assert old._sim.plant_params == new._sim.plant_params
    assert new._sim.plant_params["gearbox"]["ratio"] == 12.0
    np.testing.assert_array_equal(
        old.step_response("velocity", 5.0, 0.01).speed, new.step_response("velocity", 5.0, 0.01).speed
    )


def test_reprs_print_the_current_names():
    """Issue 30: a repr shows the names to type today, not the deprecated ones."""
    import warnings

    robot = ttmanip.robots.ur5()
    assert repr(robot) == "Robot('ur5', dof=6, joints='RRRRRR')"
    drive = ttmanip.DiffDrive(
        wheel_radius=0.1, track_width=0.5, max_wheel_speed=3.0, max_wheel_acceleration=6.0
    )
    assert "track_width=0.5" in repr(drive) and "track=" not in repr(drive)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the repr evaluates without a deprecated keyword
        again = eval(repr(drive), {"DiffDrive": ttmanip.DiffDrive})  # noqa: S307 - our own repr
    assert repr(again) == repr(drive)


def test_ball_racket_hit_is_a_deprecated_racket_impact():
    """Issue 30: `Racket` named the robot's racket mount and the ball's impact model; the impact
    model is now `racket_impact` (Rust `RacketImpact`), the mount `racket_mount` (`RacketMount`)."""
    from ttmanip import ball

    s = ball.state([0.0, 0.0, 0.3], [-3.0, 0.5, 0.2], [0.0, 10.0, 0.0])
    new = ball.racket_impact(s, [1.0, 0.0, 0.0], [2.0, 0.0, 0.0])
    with pytest.warns(DeprecationWarning, match=r"ball\.racket_hit is deprecated; use ball\.racket_impact"):
        old = ball.racket_hit(s, [1.0, 0.0, 0.0], [2.0, 0.0, 0.0])
    np.testing.assert_array_equal(old, new)
    assert new[4] > 0.0  # the ball leaves along the normal: the call did the impact
    assert "racket_hit" not in ball.__all__


def test_motor_drive_is_a_deprecated_power_stage():
    """Issue 30: a *drive* is the joint's transmission (``ttkin::joint::Drive``); the H-bridge and
    sensors of ``ttmanip.motor`` are its ``PowerStage``."""
    from ttmanip import motor

    with pytest.warns(DeprecationWarning, match=r"motor\.Drive is deprecated; use motor\.PowerStage"):
        old_cls = motor.Drive
    assert old_cls is motor.PowerStage and "Drive" not in motor.__all__
    stage = motor.PowerStage(bus_voltage=28.0)
    new = motor.Servo(power_stage=stage)
    with pytest.warns(DeprecationWarning, match=r"Servo\(drive=\.\.\.\) is deprecated; use power_stage="):
        old = motor.Servo(drive=stage)
    assert old.params == new.params and new.params["model"]["bus_voltage"] == 28.0
    with pytest.warns(DeprecationWarning), pytest.raises(ttmanip.TtmanipError, match="power_stage"):
        motor.Servo(power_stage=stage, drive=stage)
    with pytest.raises(AttributeError, match="no attribute 'Dirve'"):
        motor.Dirve  # noqa: B018 - the module's __getattr__ still refuses unknown names


def test_rate_and_hz_keywords_are_deprecated_rate_hz():
    """Issue 30: a sampling rate in Hz is ``rate_hz`` everywhere; ``hz=`` and ``rate=`` warn."""
    robot = ttmanip.robots.gantry6()
    q0, q1 = np.zeros(6), np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    quintic = ttmanip.traj.quintic(q0, q1, 0.2)
    new = quintic.sample_rate(rate_hz=250.0)
    assert len(new[0]) == 51  # 0.2 s at 250 Hz, end included: the rate is used
    with pytest.warns(DeprecationWarning, match=r"JointTrajectory\.sample_rate\(hz=\.\.\.\) is deprecated"):
        old = quintic.sample_rate(hz=250.0)
    for a, b in zip(old, new, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(quintic.sample_rate(250.0)[1], new[1])  # positional unchanged
    with pytest.raises(TypeError, match="missing required argument 'rate_hz'"):
        quintic.sample_rate()
    with pytest.raises(TypeError, match="given twice"):
        quintic.sample_rate(250.0, hz=250.0)

    pose = robot.fk(q1)
    shifted = pose.copy()
    shifted[2, 3] += 0.02
    line = ttmanip.traj.line(pose, shifted, 0.1)
    assert len(line.sample_rate(rate_hz=100.0)[0]) == 11
    with pytest.warns(DeprecationWarning, match=r"CartesianTrajectory\.sample_rate\(hz=\.\.\.\)"):
        assert len(line.sample_rate(hz=100.0)[0]) == 11
    new = line.to_joint(100.0, q1, robot.ik_nearest)
    with pytest.warns(DeprecationWarning, match=r"CartesianTrajectory\.to_joint\(hz=\.\.\.\)"):
        old = line.to_joint(hz=100.0, q_start=q1, ik=robot.ik_nearest)
    np.testing.assert_array_equal(old[1], new[1])
    with pytest.raises(TypeError, match="missing required argument 'ik'"):
        line.to_joint(100.0, q1)
    with pytest.warns(DeprecationWarning, match=r"check_limits\(hz=\.\.\.\) is deprecated; use rate_hz"):
        assert line.check_limits(robot, robot.ik_nearest, q1, hz=100.0) == line.check_limits(
            robot, robot.ik_nearest, q1, rate_hz=100.0
        )
    with pytest.warns(DeprecationWarning, match=r"check_cartesian_limits\(hz=\.\.\.\) is deprecated"):
        ttmanip.traj.check_cartesian_limits(line, robot, robot.ik_nearest, q1, hz=100.0)

    plan = ttmanip._ttmanip.hit_plan(robot, robot.fk(robot.ready), np.array([1.0, 0.0, 0.5, 0, 0, 0]), 0.4)
    assert plan.ok
    assert len(plan.sample(rate_hz=500.0)[0]) < len(plan.sample()[0])  # 500 Hz against 1 kHz
    with pytest.warns(DeprecationWarning, match=r"HitPlan\.sample\(rate=\.\.\.\) is deprecated; use rate_hz"):
        np.testing.assert_array_equal(plan.sample(rate=500.0)[1], plan.sample(rate_hz=500.0)[1])
    with pytest.warns(DeprecationWarning, match=r"HitPlan\.torques\(rate=\.\.\.\)"):
        np.testing.assert_array_equal(plan.torques(rate=500.0), plan.torques(rate_hz=500.0))


def test_simulate_rate_is_a_deprecated_rate_hz():
    robot = ttmanip.robots.gantry6()
    plan = ttmanip._ttmanip.hit_plan(robot, robot.fk(robot.ready), np.array([1.0, 0.0, 0.5, 0, 0, 0]), 0.4)
    new = ttmanip.simulate(robot, plan, rate_hz=500.0)
    with pytest.warns(DeprecationWarning, match=r"simulate\(rate=\.\.\.\) is deprecated; use rate_hz"):
        old = ttmanip.simulate(robot, plan, rate=500.0)
    np.testing.assert_array_equal(old.arrays["q"], new.arrays["q"])


def test_setpoint_rate_and_tick_rate_are_deprecated_setpoint_hz_and_tick_hz():
    """Issue 30: a rate of one named thing in Hz is ``<thing>_hz`` (the glossary's rule):
    ``setpoint_rate`` and ``tick_rate`` warn and give what ``setpoint_hz`` and ``tick_hz`` give."""
    robot = ttmanip.robots.gantry6()
    new = ttmanip.DriveSim(robot, setpoint_hz=500.0)
    with pytest.warns(DeprecationWarning, match=r"DriveSim\(setpoint_rate=\.\.\.\) is deprecated"):
        old = ttmanip.DriveSim(robot, setpoint_rate=500.0)
    with pytest.warns(DeprecationWarning, match=r"DriveSim\.tick_rate is deprecated; use DriveSim\.tick_hz"):
        assert old.tick_rate == new.tick_hz == 20000.0
    q0 = np.full(6, 0.05)
    for sim in (old, new):
        sim.reset(q0)
        sim.set_setpoint(q0 + 0.01)
        sim.tick(100)
    np.testing.assert_array_equal(old.q, new.q)
    with pytest.warns(DeprecationWarning), pytest.raises(ttmanip.TtmanipError, match="setpoint_hz"):
        ttmanip.DriveSim(robot, setpoint_rate=0.0)  # the value is checked under its new name

    case = ttmanip._ttmanip.drive_theta5_case(setpoint_hz=250.0)
    with pytest.warns(DeprecationWarning, match=r"drive_theta5_case\(setpoint_rate=\.\.\.\) is deprecated"):
        old_case = ttmanip._ttmanip.drive_theta5_case(setpoint_rate=250.0)
    assert case["setpoint_hz"] == case["setpoint_rate"] == old_case["setpoint_hz"] == 250.0
    assert case["max_following_error"] == old_case["max_following_error"]

    plan = ttmanip._ttmanip.hit_plan(robot, robot.fk(robot.ready), np.array([1.0, 0.0, 0.5, 0, 0, 0]), 0.4)
    new = ttmanip.simulate(robot, plan, setpoint_hz=500.0)
    with pytest.warns(DeprecationWarning, match=r"simulate\(setpoint_rate=\.\.\.\) is deprecated"):
        old = ttmanip.simulate(robot, plan, setpoint_rate=500.0)
    np.testing.assert_array_equal(old.arrays["q"], new.arrays["q"])
    default = ttmanip.simulate(robot, plan)  # None: DriveSim's default, 1 kHz
    assert not np.array_equal(default.arrays["current"], new.arrays["current"])


def test_the_cli_setpoint_rate_flag_is_a_deprecated_setpoint_hz(tmp_path):
    import json
    import subprocess
    import sys

    hit = tmp_path / "hit.json"
    one = {
        "centre": [0.35, -0.55, 0.05],
        "normal": [0.3, -1.0, -0.2],
        "velocity": [0.86, -2.87, -0.57],
        "t": 0.55,
    }
    hit.write_text(json.dumps({"robot": "gantry6", "hits": [one]}))

    def cli(*args):
        return subprocess.run(
            [sys.executable, "-m", "ttmanip.cli", "simulate", str(hit), "--out", str(tmp_path / "o"), *args],
            capture_output=True,
            text=True,
            timeout=600,
        )

    r = cli("--setpoint-rate", "0")  # refused before any work, under the new name
    assert r.returncode != 0
    assert "--setpoint-rate is deprecated; use --setpoint-hz" in r.stderr
    assert "--setpoint-hz: expected a rate > 0 Hz, got 0.0" in r.stderr
    r = cli("--setpoint-rate", "500", "--setpoint-hz", "500")
    assert r.returncode != 0 and "given twice" in r.stderr
    r = cli("--setpoint-hz", "-1")
    assert r.returncode != 0 and "--setpoint-hz: expected a rate > 0 Hz" in r.stderr
    assert "deprecated" not in r.stderr
    assert "--setpoint-rate" not in cli("--help").stdout  # the old flag is not advertised
