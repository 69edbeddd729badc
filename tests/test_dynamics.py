"""Dynamics from Python: RNEA, mass matrix and forward dynamics against Pinocchio (our exported URDF
with the rotor armature set on the Pinocchio model) for every built-in robot and random inertias;
the identities between them; the torque profile; bad input."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
import ttmanip
from conftest import BUILTINS, random_q
from ttmanip.dynamics import EARTH_GRAVITY, MOBILE8_GRAVITY

TOL = 1e-9


def pinocchio_model(robot: ttmanip.Robot, gravity=None):
    """Pinocchio's model of `robot` with `gravity` (m/s², base frame; default: the robot's own, which
    its rnea uses by default: mobile8's base frame has x up)."""
    model = pin.buildModelFromXML(robot.to_urdf())
    assert model.nq == robot.dof
    model.armature = robot.armature
    gravity = robot.gravity_vector if gravity is None else gravity
    model.gravity = pin.Motion(np.array(gravity, dtype=float), np.zeros(3))
    return model, model.createData()


def random_inertias(robot: ttmanip.Robot, seed: int):
    """(mass, com, inertia) of random physical links: triangle-valid principal moments, random axes."""
    rng = np.random.default_rng(seed)
    n = robot.dof
    mass = rng.uniform(0.1, 5.0, n)
    com = rng.uniform(-0.2, 0.2, (n, 3))
    inertia = np.empty((n, 3, 3))
    for i in range(n):
        s = rng.uniform(1e-3, 0.05, 3)
        moments = np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
        rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        inertia[i] = rot @ np.diag(moments) @ rot.T
    return mass, com, inertia


def randomised(name: str, seed: int) -> ttmanip.Robot:
    robot = ttmanip.Robot.builtin(name).with_inertials(*random_inertias(ttmanip.Robot.builtin(name), seed))
    rng = np.random.default_rng(seed + 1)
    n = robot.dof
    return robot.with_drives(
        rng.uniform(1.0, 120.0, n), rotor_inertia=rng.uniform(0.0, 1e-4, n), viscous=rng.uniform(0, 1, n)
    )


def states(robot: ttmanip.Robot, count: int, seed: int):
    rng = np.random.default_rng(seed)
    q = random_q(robot, count, seed=seed)
    return q, rng.uniform(-2, 2, q.shape), rng.uniform(-5, 5, q.shape)


def robots_under_test():
    for name in BUILTINS:
        yield pytest.param(lambda name=name: ttmanip.Robot.builtin(name), id=name)
        for seed in (1, 2):
            yield pytest.param(lambda name=name, seed=seed: randomised(name, seed), id=f"{name}-random{seed}")


@pytest.mark.parametrize("make", list(robots_under_test()))
def test_rnea_mass_matrix_and_forward_dynamics_agree_with_pinocchio(make):
    robot = make()
    gravity = (0.3, -1.2, -9.81)
    model, data = pinocchio_model(robot, gravity)
    q, qd, qdd = states(robot, 50, seed=3)
    tau = robot.rnea(q, qd, qdd, gravity=gravity)
    mass = robot.mass_matrix(q)
    acc = robot.forward_dynamics(q, qd, tau, gravity=gravity)
    grav = robot.gravity(q, gravity=gravity)
    h = robot.nonlinear_effects(q, qd, gravity=gravity)
    for k in range(len(q)):
        scale = 1.0 + np.abs(tau[k]).max()
        np.testing.assert_allclose(
            tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k]), rtol=0, atol=TOL * scale
        )
        m_pin = pin.crba(model, data, q[k])
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        np.testing.assert_allclose(mass[k], m_pin, rtol=0, atol=TOL * (1.0 + np.abs(m_pin).max()))
        a_pin = pin.aba(model, data, q[k], qd[k], tau[k])
        np.testing.assert_allclose(acc[k], a_pin, rtol=0, atol=TOL * (1.0 + np.abs(a_pin).max()))
        np.testing.assert_allclose(acc[k], qdd[k], rtol=0, atol=1e-8)
        g_pin = pin.computeGeneralizedGravity(model, data, q[k])
        np.testing.assert_allclose(grav[k], g_pin, rtol=0, atol=TOL * (1.0 + np.abs(g_pin).max()))
        h_pin = pin.nonLinearEffects(model, data, q[k], qd[k])
        np.testing.assert_allclose(h[k], h_pin, rtol=0, atol=TOL * (1.0 + np.abs(h_pin).max()))
    # single-configuration calls give the batch rows
    np.testing.assert_array_equal(robot.rnea(q[7], qd[7], qdd[7], gravity=gravity), tau[7])
    np.testing.assert_array_equal(robot.mass_matrix(q[7]), mass[7])


@pytest.mark.parametrize("name", BUILTINS)
def test_tool_wrench_agrees_with_pinocchio_external_force(name):
    robot = ttmanip.Robot.builtin(name)
    model, data = pinocchio_model(robot)
    q, qd, qdd = states(robot, 10, seed=5)
    wrench = np.array([3.0, -2.0, 5.0, 0.4, 0.1, -0.3])  # on the tool, tool axes, about the tool point
    tool = model.getFrameId("tool")
    parent = model.frames[tool].parentJoint
    placement = model.frames[tool].placement  # tool frame in the last joint's frame
    for k in range(len(q)):
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        fext[parent] = placement.act(pin.Force(wrench[:3], wrench[3:]))
        expected = pin.rnea(model, data, q[k], qd[k], qdd[k], fext)
        np.testing.assert_allclose(robot.rnea(q[k], qd[k], qdd[k], wrench=wrench), expected, atol=1e-9)


@pytest.mark.parametrize("name", BUILTINS)
def test_identities_and_energy(name):
    robot = ttmanip.Robot.builtin(name)
    q, qd, qdd = states(robot, 20, seed=8)
    tau = robot.rnea(q, qd, qdd)
    mass = robot.mass_matrix(q)
    h = robot.nonlinear_effects(q, qd)
    np.testing.assert_allclose(tau, np.einsum("kij,kj->ki", mass, qdd) + h, atol=1e-9)
    np.testing.assert_allclose(h, robot.coriolis(q, qd) + robot.gravity(q), atol=1e-9)
    for k in range(len(q)):
        assert np.all(np.linalg.eigvalsh(mass[k]) > 0)
        np.testing.assert_allclose(
            robot.kinetic_energy(q[k], qd[k]), 0.5 * qd[k] @ mass[k] @ qd[k], rtol=1e-12
        )
    np.testing.assert_allclose(robot.inverse_dynamics(q, qd, qdd), tau + robot.friction(qd), atol=1e-12)


def test_simulation_conserves_energy_without_torque_or_friction():
    robot = ttmanip.robots.ur5()
    q0 = np.array([0.1, -1.0, 1.2, -0.5, 0.6, 0.0])
    qd0 = np.array([0.5, -0.3, 0.2, 0.8, -0.4, 1.0])
    energy0 = robot.kinetic_energy(q0, qd0) + robot.potential_energy(q0)
    drifts = []
    for dt in (2e-4, 1e-4):
        steps = int(round(0.5 / dt))
        qs, qds = robot.simulate(q0, qd0, np.zeros((steps, robot.dof)), dt, friction=False)
        assert qs.shape == (steps + 1, robot.dof)
        pairs = zip(qs[::50], qds[::50], strict=True)
        e = [robot.kinetic_energy(a, b) + robot.potential_energy(a) for a, b in pairs]
        drifts.append(np.abs(np.array(e) - energy0).max())
    # first-order integrator: halving the step halves the energy error, which stays small
    assert 0.4 < drifts[1] / drifts[0] < 0.6, drifts
    assert drifts[0] < 0.05 * abs(energy0) + 0.05, drifts


def test_torque_profile_of_a_planned_motion():
    robot = ttmanip.robots.gantry6()
    t = np.linspace(0.0, 1.0, 101)[:, None]
    q0, q1 = np.zeros(robot.dof), np.array([0.3, -0.2, 1.0, 0.5, -0.8, 1.5])
    s = 10 * t**3 - 15 * t**4 + 6 * t**5  # rest-to-rest quintic over 1 s
    sd = 30 * t**2 - 60 * t**3 + 30 * t**4
    sdd = 60 * t - 180 * t**2 + 120 * t**3
    q, qd, qdd = q0 + s * (q1 - q0), sd * (q1 - q0), sdd * (q1 - q0)
    profile = robot.torques(q, qd, qdd)
    assert profile.joint.shape == (101, robot.dof)
    np.testing.assert_allclose(profile.joint, robot.inverse_dynamics(q, qd, qdd), atol=1e-12)
    gear = np.array([d["gear_ratio"] for d in robot.drives])
    kt = np.array([d["torque_constant"] for d in robot.drives])
    np.testing.assert_allclose(profile.motor, profile.joint / gear, rtol=1e-14)
    np.testing.assert_allclose(profile.current, profile.motor / kt, rtol=1e-14)
    np.testing.assert_allclose(profile.peak, np.abs(profile.joint).max(axis=0))
    assert profile.within_limits and profile.violations == []
    # the same motion 8× faster needs 64× the inertial torques: some joints exceed their effort limits
    fast = robot.torques((q, 8 * qd, 64 * qdd))
    assert not fast.within_limits
    # Against the effective limits at the sample's speed (the robot file's or the drive's).
    limits = robot.effort_limits_at(8 * np.asarray(qd))
    for sample, joint, torque, limit in fast.violations:
        assert abs(torque) > limit == limits[sample, joint] <= robot.effort_limits[joint]
        assert fast.joint[sample, joint] == torque

    class Trajectory:
        pass

    traj = Trajectory()
    traj.q, traj.qd, traj.qdd = q, qd, qdd
    np.testing.assert_array_equal(robot.torques(traj).joint, profile.joint)
    named = SimpleNamespace(position=q, velocity=qd, acceleration=qdd)
    np.testing.assert_array_equal(robot.torques(named).joint, profile.joint)
    with pytest.raises(ttmanip.TtmanipError, match="attributes"):
        robot.torques(SimpleNamespace(q=q))


def test_missing_inertia_names_the_link():
    robot = ttmanip.Robot.from_dh([0.3, 0.2], [0, 0], [0, 0], [0, 0])
    with pytest.raises(ttmanip.ModelError, match=r"joint1.*link1.*no inertial"):
        robot.rnea([0, 0], [0, 0], [0, 0])


def test_bad_input_is_a_clear_error():
    robot = ttmanip.robots.arm4()
    n = robot.dof
    mass, com, inertia = random_inertias(robot, 0)
    bad = inertia.copy()
    bad[2] = np.diag([1.0, 0.1, 0.1])
    with pytest.raises(ttmanip.ModelError, match="triangle"):
        robot.with_inertials(mass, com, bad)
    bad[2] = np.diag([1.0, 1.0, -0.5])
    with pytest.raises(ttmanip.ModelError, match="positive definite"):
        robot.with_inertials(mass, com, bad)
    with pytest.raises(ttmanip.NonFiniteError):
        robot.with_inertials(np.full(n, np.nan), com, inertia)
    with pytest.raises(ttmanip.ModelError, match="gear ratio"):
        robot.with_drives(np.zeros(n))
    with pytest.raises(ttmanip.NonFiniteError):
        robot.rnea([0, 0, np.nan, 0], np.zeros(n), np.zeros(n))
    with pytest.raises(ttmanip.ShapeError):
        robot.rnea(np.zeros(n), np.zeros(n + 1), np.zeros(n))
    with pytest.raises(ttmanip.ShapeError):
        robot.rnea(np.zeros((3, n)), np.zeros((2, n)), np.zeros((3, n)))
    with pytest.raises(ttmanip.ShapeError):
        robot.rnea(np.zeros(n), np.zeros(n), np.zeros(n), gravity=[0, -9.81])
    with pytest.raises(ttmanip.NonFiniteError):
        robot.forward_dynamics(np.zeros(n), np.zeros(n), np.zeros(n), wrench=[0, 0, np.inf, 0, 0, 0])
    with pytest.raises(ttmanip.TtmanipError):
        robot.simulate(np.zeros(n), np.zeros(n), np.zeros((3, n)), dt=-1e-3)
    with pytest.raises(ttmanip.TtmanipError):
        robot.torques(np.zeros((3, n)), np.zeros((3, n)))


def test_robot_file_and_urdf_carry_inertias_and_drives():
    robot = ttmanip.robots.mobile8()
    back = ttmanip.Robot.from_toml(robot.to_toml())
    q, qd, qdd = states(robot, 5, seed=9)
    np.testing.assert_array_equal(back.armature, robot.armature)
    assert back.drives == robot.drives
    np.testing.assert_allclose(
        back.inverse_dynamics(q, qd, qdd), robot.inverse_dynamics(q, qd, qdd), atol=1e-12
    )
    urdf = ttmanip.Robot.from_urdf_string(robot.to_urdf(), "base_link", "tool")
    # URDF keeps masses, inertias and friction (<dynamics damping friction>), not the rotor inertia
    # and not the gravity (URDF has no field for it: the loaded robot has the default, base -z)
    np.testing.assert_array_equal(urdf.gravity_vector, [0.0, 0.0, -9.81])
    g = robot.gravity_vector
    np.testing.assert_allclose(
        urdf.inverse_dynamics(q, qd, 0 * qdd, gravity=g), robot.inverse_dynamics(q, qd, 0 * qdd), atol=1e-9
    )
    model = pin.buildModelFromXML(robot.to_urdf())
    np.testing.assert_allclose(model.damping, [d["viscous"] for d in robot.drives])
    np.testing.assert_allclose(model.friction, [d["coulomb"] for d in robot.drives])


def test_torque_figure_is_written(tmp_path):
    robot = ttmanip.robots.arm4()
    q, qd, qdd = states(robot, 30, seed=2)
    path = tmp_path / "torques.png"
    ttmanip.dynamics.torque_figure(robot, np.linspace(0, 1, 30), robot.torques(q, qd, qdd), path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    gantry, t, profile = ttmanip.dynamics.gantry6_example()
    assert profile.within_limits and profile.joint.shape == (len(t), gantry.dof)


@pytest.mark.parametrize("name", BUILTINS)
def test_default_gravity_is_the_robots_and_agrees_with_pinocchio(name):
    # Gravity is a fact of the robot in its base frame (robot file `gravity`): mobile8's base
    # frame has x up. Every default uses it: rnea, the static torques, DriveSim.
    robot = ttmanip.Robot.builtin(name)
    expected = MOBILE8_GRAVITY if name == "mobile8" else EARTH_GRAVITY
    np.testing.assert_array_equal(robot.gravity_vector, expected)
    model, data = pinocchio_model(robot, robot.gravity_vector)
    q, qd, qdd = states(robot, 10, seed=5)
    tau = robot.rnea(q, qd, qdd)
    grav = robot.gravity(q)
    for k in range(len(q)):
        np.testing.assert_allclose(tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k]), rtol=0, atol=1e-8)
        g_pin = pin.computeGeneralizedGravity(model, data, q[k])
        np.testing.assert_allclose(grav[k], g_pin, rtol=0, atol=1e-8)
    # The comparison could fail: the gravity torques are not zero, and Pinocchio with any other
    # gravity (the other robots' default, or none) gives other torques.
    assert np.abs(grav).max() > 0.1
    other = (0.0, 0.0, -9.81) if name == "mobile8" else (-9.81, 0.0, 0.0)
    for g in (other, (0.0, 0.0, 0.0)):
        model_g, data_g = pinocchio_model(robot, g)
        g_other = np.array([pin.computeGeneralizedGravity(model_g, data_g, qk) for qk in q])
        assert np.abs(grav - g_other).max() > 0.1, g
    # A renamed copy from its file keeps its gravity: nothing is decided by the name.
    copy = ttmanip.Robot.from_toml(robot.to_toml().replace(f'name = "{name}"', 'name = "copy"', 1))
    np.testing.assert_array_equal(copy.gravity_vector, expected)
