"""Forward kinematics and Jacobians from Python: shapes, identities, finite differences."""

from __future__ import annotations

import numpy as np
import pytest
import ttmanip
from conftest import BUILTINS, random_q
from hypothesis import given, settings
from hypothesis import strategies as st


def numeric_jacobian(robot: ttmanip.Robot, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central differences of fk: linear velocity of the tool point and ω from Ṙ Rᵀ (base axes)."""
    t0 = robot.fk(q)
    jac = np.zeros((6, robot.dof))
    for i in range(robot.dof):
        dq = np.zeros(robot.dof)
        dq[i] = h
        tp, tm = robot.fk(q + dq), robot.fk(q - dq)
        jac[:3, i] = (tp[:3, 3] - tm[:3, 3]) / (2 * h)
        w = (tp[:3, :3] - tm[:3, :3]) / (2 * h) @ t0[:3, :3].T
        jac[3:, i] = [w[2, 1], w[0, 2], w[1, 0]]
    return jac


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(BUILTINS), seed=st.integers(0, 2**32 - 1))
def test_jacobian_matches_central_differences(name, seed):
    robot = ttmanip.Robot.builtin(name)
    q = random_q(robot, 1, seed)[0]
    jn = numeric_jacobian(robot, q)
    np.testing.assert_allclose(robot.jacobian(q), jn, atol=1e-8)
    r = robot.fk(q)[:3, :3]
    tool = robot.jacobian(q, frame="tool")
    np.testing.assert_allclose(tool[:3], r.T @ jn[:3], atol=1e-8)
    np.testing.assert_allclose(tool[3:], r.T @ jn[3:], atol=1e-8)


def test_shapes_single_and_batch(robot):
    n = robot.dof
    q = random_q(robot, 7)
    assert robot.fk(q[0]).shape == (4, 4)
    assert robot.fk(q).shape == (7, 4, 4)
    assert robot.fk_all(q[0]).shape == (n, 4, 4)
    assert robot.fk_all(q).shape == (7, n, 4, 4)
    assert robot.jacobian(q[0]).shape == (6, n)
    assert robot.jacobian(q, frame="tool").shape == (7, 6, n)
    assert robot.limits.shape == (n, 2)
    assert np.all(robot.limits[:, 0] < robot.limits[:, 1])


def test_batch_equals_single_calls(robot):
    q = random_q(robot, 1000, seed=3)
    fk = robot.fk(q)
    jac = robot.jacobian(q)
    frames = robot.fk_all(q)
    for k in (0, 255, 256, 999):
        np.testing.assert_array_equal(fk[k], robot.fk(q[k]))
        np.testing.assert_array_equal(jac[k], robot.jacobian(q[k]))
        np.testing.assert_array_equal(frames[k], robot.fk_all(q[k]))


def test_tool_pose_is_last_link_frame_times_tool(robot):
    tool = np.eye(4)
    tool[:3, 3] = [0.01, -0.02, 0.15]
    r = robot.with_tool(tool)
    q = random_q(r, 5, seed=1)
    np.testing.assert_allclose(r.fk(q), r.fk_all(q)[:, -1] @ tool, atol=1e-14)
    np.testing.assert_allclose(r.tool, tool)


def test_poses_are_rigid(robot):
    t = robot.fk(random_q(robot, 200, seed=2))
    rot = t[:, :3, :3]
    np.testing.assert_allclose(
        rot @ rot.transpose(0, 2, 1), np.broadcast_to(np.eye(3), rot.shape), atol=1e-13
    )
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-13)
    np.testing.assert_array_equal(t[:, 3], np.broadcast_to([0, 0, 0, 1.0], (200, 4)))


def test_fk_ignores_limits():
    robot = ttmanip.robots.gantry6()
    q = robot.limits[:, 1] + 5.0
    assert np.all(np.isfinite(robot.fk(q)))
    assert np.all(np.isfinite(robot.jacobian(q)))


def test_integer_and_list_inputs_are_converted():
    robot = ttmanip.robots.ur5()
    q = [0, 1, 0, -1, 0, 1]
    np.testing.assert_array_equal(robot.fk(q), robot.fk(np.array(q, dtype=float)))
    np.testing.assert_array_equal(robot.fk(np.array(q, dtype=np.int32)), robot.fk(np.array(q, dtype=float)))
    strided = np.zeros((6, 2))
    strided[:, 0] = q
    np.testing.assert_array_equal(robot.fk(strided[:, 0]), robot.fk(q))


def test_standard_and_modified_dh_describe_the_same_robot():
    # UR5 in standard DH, then rewritten in the modified convention: (a, alpha) move one row down
    # and the last ones become the tool transform.
    d = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
    a = [0, -0.425, -0.39225, 0, 0, 0]
    alpha = [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0]
    standard = ttmanip.Robot.from_dh(a=a, alpha=alpha, d=d, theta=np.zeros(6), convention="standard")
    modified = ttmanip.Robot.from_dh(
        a=[0, *a[:-1]], alpha=[0, *alpha[:-1]], d=d, theta=np.zeros(6), convention="modified"
    )
    q = random_q(ttmanip.robots.ur5(), 100, seed=5)
    np.testing.assert_allclose(standard.fk(q), modified.fk(q), atol=1e-14)
    np.testing.assert_allclose(standard.jacobian(q), modified.jacobian(q), atol=1e-14)
    np.testing.assert_allclose(standard.fk(q), ttmanip.robots.ur5().fk(q), atol=1e-14)


def test_gantry6_matches_the_seed_closed_form():
    robot = ttmanip.robots.gantry6()
    l1, l2, l3, l4 = 0.10, 0.05, 0.30, 0.15
    q = random_q(robot, 500, seed=9)
    d1, d2, t3, t4, t5 = q[:, 0], q[:, 1], q[:, 2], q[:, 3], q[:, 4]
    s45, c45 = np.sin(t4 + t5), np.cos(t4 + t5)
    a = np.stack([np.sin(t3) * s45, -np.cos(t3) * s45, -c45], axis=1)
    reach = l3 * np.cos(t4) + l4 * s45
    p = np.stack(
        [
            d2 - l2 * np.cos(t3) + np.sin(t3) * reach,
            -d1 - l2 * np.sin(t3) - np.cos(t3) * reach,
            l1 + l3 * np.sin(t4) - l4 * c45,
        ],
        axis=1,
    )
    t = robot.fk(q)
    np.testing.assert_allclose(t[:, :3, 2], a, atol=1e-13)
    np.testing.assert_allclose(t[:, :3, 3], p, atol=1e-13)


@pytest.mark.parametrize(
    ("q", "exc", "words"),
    [
        ([0.0] * 5, ttmanip.ShapeError, "expected shape (6,) or (N, 6)"),
        (np.zeros((3, 7)), ttmanip.ShapeError, "got (3, 7)"),
        (np.zeros((2, 3, 6)), ttmanip.ShapeError, "got (2, 3, 6)"),
        ([0, 0, float("nan"), 0, 0, 0], ttmanip.NonFiniteError, "element 2 is NaN"),
        (np.full((4, 6), np.inf), ttmanip.NonFiniteError, "inf"),
        ("abc", ttmanip.ShapeError, "array of real numbers"),
        ([[0, 1], [2]], ttmanip.ShapeError, "array of real numbers"),
        (np.zeros(6, dtype=complex), ttmanip.ShapeError, "array of real numbers"),
        (None, ttmanip.ShapeError, "array of real numbers"),
        (np.array([True] * 6), ttmanip.ShapeError, "dtype bool"),
    ],
)
def test_bad_configurations_raise_clear_errors(q, exc, words):
    robot = ttmanip.robots.gantry6()
    for call in (robot.fk, robot.fk_all, robot.jacobian):
        with pytest.raises(exc) as info:
            call(q)
        assert words in str(info.value)
        assert isinstance(info.value, ttmanip.TtmanipError)
        assert isinstance(info.value, ValueError)


def test_bad_frame_name():
    with pytest.raises(ttmanip.TtmanipError, match="'base' or 'tool'"):
        ttmanip.robots.ur5().jacobian(np.zeros(6), frame="world-ish")


def test_from_dh_validates_its_arguments():
    ok = dict(a=[0.1, 0.2], alpha=[0, 0], d=[0, 0], theta=[0, 0])
    robot = ttmanip.Robot.from_dh(**ok, types="RP", limits=[[-1, 1], [0, 0.5]], name="two")
    assert robot.joint_types == ["revolute", "prismatic"]
    assert robot.name == "two"
    with pytest.raises(ttmanip.ShapeError, match="alpha: expected shape"):
        ttmanip.Robot.from_dh(**{**ok, "alpha": [0.0]})
    with pytest.raises(ttmanip.ShapeError, match="types: expected 2"):
        ttmanip.Robot.from_dh(**ok, types="R")
    with pytest.raises(ttmanip.TtmanipError, match="unknown joint type 'x'"):
        ttmanip.Robot.from_dh(**ok, types="RX")
    with pytest.raises(ttmanip.TtmanipError, match="convention"):
        ttmanip.Robot.from_dh(**ok, convention="dh")
    with pytest.raises(ttmanip.ModelError, match="lower ≤ upper"):
        ttmanip.Robot.from_dh(**ok, limits=[[1, -1], [0, 1]])
    with pytest.raises(ttmanip.NonFiniteError):
        ttmanip.Robot.from_dh(**{**ok, "d": [0, np.nan]})
    skewed = np.eye(4)
    skewed[0, 1] = 0.1
    with pytest.raises(ttmanip.TtmanipError, match="not orthonormal"):
        ttmanip.Robot.from_dh(**ok, tool=skewed)
    bottom = np.eye(4)
    bottom[3, 0] = 1.0
    with pytest.raises(ttmanip.TtmanipError, match="bottom row"):
        ttmanip.Robot.from_dh(**ok, base=bottom)
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    with pytest.raises(ttmanip.TtmanipError, match="reflection"):
        ttmanip.Robot.from_dh(**ok, base=mirror)
