"""Cross-check against an independent implementation: Pinocchio loading our exported URDF."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import ttmanip
from conftest import BUILTINS, random_q


def pinocchio_model(robot: ttmanip.Robot):
    model = pin.buildModelFromXML(robot.to_urdf())
    assert model.nq == robot.dof, "every exported joint is a 1-DoF joint"
    return model, model.createData(), model.getFrameId("tool")


@pytest.mark.parametrize("name", BUILTINS)
def test_fk_and_jacobian_agree_with_pinocchio(name):
    robot = ttmanip.Robot.builtin(name)
    model, data, tool = pinocchio_model(robot)
    qs = random_q(robot, 1000, seed=11)
    fk = robot.fk(qs)
    jb = robot.jacobian(qs, frame="base")
    jt = robot.jacobian(qs, frame="tool")
    frames = robot.fk_all(qs)
    link_ids = [model.getFrameId(f"link{i + 1}") for i in range(robot.dof)]
    for k, q in enumerate(qs):
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(fk[k], data.oMf[tool].homogeneous, atol=1e-10)
        for i, fid in enumerate(link_ids):
            np.testing.assert_allclose(frames[k, i], data.oMf[fid].homogeneous, atol=1e-10)
        pin.computeJointJacobians(model, data, q)
        j_world = pin.getFrameJacobian(model, data, tool, pin.LOCAL_WORLD_ALIGNED)
        j_local = pin.getFrameJacobian(model, data, tool, pin.LOCAL)
        np.testing.assert_allclose(jb[k], j_world, atol=1e-10)
        np.testing.assert_allclose(jt[k], j_local, atol=1e-10)


@pytest.mark.parametrize("name", BUILTINS)
def test_exported_limits_reach_pinocchio(name):
    robot = ttmanip.Robot.builtin(name)
    model, _, _ = pinocchio_model(robot)
    np.testing.assert_allclose(model.lowerPositionLimit, robot.limits[:, 0])
    np.testing.assert_allclose(model.upperPositionLimit, robot.limits[:, 1])
    np.testing.assert_allclose(model.velocityLimit, robot.velocity_limits)
