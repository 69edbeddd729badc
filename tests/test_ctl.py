"""ttmanip.ctl: the trajectory file for ttctl round-trips and refuses malformed input."""

import numpy as np
import pytest
import ttmanip
from ttmanip import ctl


def test_round_trip_of_a_two_joint_trajectory(tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    q = np.column_stack([np.sin(t), np.cos(t)])
    qd = np.column_stack([np.cos(t), -np.sin(t)])
    qdd = -q
    tau = 0.1 * q
    p = ctl.write_trajectory(tmp_path / "a.csv", t, q, qd, qdd, tau)
    lines = p.read_text().splitlines()
    assert lines[0].startswith("# ttctl trajectory v1")
    assert lines[1] == "t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2"
    data = np.loadtxt(p, delimiter=",", skiprows=2)
    np.testing.assert_allclose(data, np.column_stack([t, q, qd, qdd, tau]), rtol=1e-8, atol=1e-12)


def test_one_joint_vectors_and_default_torque(tmp_path):
    t = [0.0, 0.5, 1.0]
    p = ctl.write_trajectory(tmp_path / "b.csv", t, [0, 1, 2], [2, 2, 2], [0, 0, 0])
    data = np.loadtxt(p, delimiter=",", skiprows=2)
    assert data.shape == (3, 5)
    assert np.all(data[:, 4] == 0.0)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(t=[0.0, 0.0, 1.0]), "t"),
        (dict(t=[0.0]), "t"),
        (dict(q=np.zeros((3, 3))), "q"),
        (dict(qd=[[np.nan, 0], [0, 0], [0, 0]]), "qd"),
        (dict(tau_ff=np.zeros((2, 2))), "tau_ff"),
        (dict(qdd="x"), "qdd"),
    ],
)
def test_malformed_input_is_a_ttmanip_error_naming_the_argument(tmp_path, kwargs, word):
    args = dict(t=[0.0, 0.5, 1.0], q=np.zeros((3, 2)), qd=np.zeros((3, 2)), qdd=np.zeros((3, 2)))
    args.update(kwargs)
    with pytest.raises(ttmanip.TtmanipError, match=word):
        ctl.write_trajectory(tmp_path / "c.csv", **args)


def test_gantry6_stroke_file_is_written(tmp_path):
    p = ctl.write_stroke(tmp_path / "stroke.csv")
    data = np.loadtxt(p, delimiter=",", skiprows=2)
    assert data.shape[1] == 1 + 4 * 6
    assert np.all(np.diff(data[:, 0]) > 0)
    # velocity column consistent with the positions (finite differences)
    fd = np.gradient(data[:, 1:7], data[:, 0], axis=0)
    assert np.max(np.abs(fd[5:-5] - data[5:-5, 7:13])) < 0.05 * max(1.0, np.max(np.abs(data[:, 7:13])))
