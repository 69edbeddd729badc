"""Mobile manipulation from Python: diff-drive base, task Jacobians, WLS steps, CLIK tracking and
the seed000 experiment."""

from __future__ import annotations

import json

import numpy as np
import pytest
import ttmanip
from conftest import random_q
from ttmanip.experiments import seed000

Q_START = seed000.Q_START


@pytest.fixture(scope="module")
def mobile8() -> ttmanip.Robot:
    return ttmanip.robots.mobile8()


def test_diff_drive_body_velocity_and_wheel_speeds_are_the_corrected_formulas():
    base = ttmanip.DiffDrive(wheel_radius=0.075, track_width=0.42)
    v, w = base.body_velocity([2.0, 6.0])  # (left, right) rad/s
    assert v == pytest.approx(0.075 * (2.0 + 6.0) / 2)
    assert w == pytest.approx(0.075 * (6.0 - 2.0) / 0.42)  # (v_R − v_L)/l, not (2v_R − v_L)/l
    np.testing.assert_allclose(base.wheel_speeds(v, w), [2.0, 6.0], rtol=1e-14)


def test_diff_drive_integrate_matches_numerical_integration_and_special_cases():
    base = ttmanip.DiffDrive(wheel_radius=0.1, track_width=0.5)
    pose0 = np.array([0.3, -0.2, 0.7])
    wheels = np.array([3.0, 4.5])
    v, w = base.body_velocity(wheels)
    # midpoint-rule integration of the unicycle ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω (θ is linear in t)
    steps = 200_000
    h = 1.3 / steps
    th = pose0[2] + w * h * (np.arange(steps) + 0.5)
    p = pose0 + np.array([v * h * np.cos(th).sum(), v * h * np.sin(th).sum(), w * 1.3])
    np.testing.assert_allclose(base.integrate(pose0, wheels, 1.3), p, atol=1e-10)
    # spinning in place does not move the axle midpoint; straight driving does not turn
    spin = base.integrate(pose0, [-2.0, 2.0], 0.9)
    np.testing.assert_allclose(spin[:2], pose0[:2], atol=1e-15)
    straight = base.integrate(pose0, [2.0, 2.0], 0.9)
    assert straight[2] == pose0[2]


def test_diff_drive_limits_and_bad_input():
    base = ttmanip.DiffDrive(
        wheel_radius=0.1, track_width=0.5, max_wheel_speed=10.0, max_wheel_acceleration=20.0
    )
    np.testing.assert_allclose(base.saturate([20.0, 10.0]), [10.0, 5.0])
    np.testing.assert_allclose(base.limit_step([0.0, 0.0], [5.0, 2.0], 0.1), [2.0, 0.8])
    with pytest.raises(ttmanip.TtmanipError, match="wheel_radius"):
        ttmanip.DiffDrive(wheel_radius=-0.1, track_width=0.5)
    with pytest.raises(ttmanip.ShapeError):
        base.body_velocity([1.0, 2.0, 3.0])
    with pytest.raises(ttmanip.NonFiniteError):
        base.integrate([0.0, np.nan, 0.0], [1.0, 1.0], 1.0)
    with pytest.raises(ttmanip.TtmanipError, match="duration"):
        base.integrate([0.0, 0.0, 0.0], [1.0, 1.0], -1.0)


@pytest.mark.parametrize("task", ["position", "pose", "racket5"])
def test_task_jacobian_matches_finite_differences(mobile8, task):
    h = 1e-6
    for q in random_q(mobile8, 5, seed=3):
        je = mobile8.task_jacobian(q, task=task)
        assert je.shape == ({"position": 3, "pose": 6, "racket5": 5}[task], 8)
        fd = np.empty((6, 8))
        for k in range(8):
            dq = np.zeros(8)
            dq[k] = h
            tp, tm = mobile8.fk(q + dq), mobile8.fk(q - dq)
            r = tp[:3, :3] @ tm[:3, :3].T
            w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / (4 * h)
            if task == "racket5":
                cp = tp[:3, 3] + 0.15 * tp[:3, 2]
                cm = tm[:3, 3] + 0.15 * tm[:3, 2]
                fd[:3, k] = (cp - cm) / (2 * h)
                ndot = (tp[:3, 0] - tm[:3, 0]) / (2 * h)
                fd[3:, k] = [np.linalg.norm(ndot), 0.0, 0.0]
            else:
                fd[:3, k] = (tp[:3, 3] - tm[:3, 3]) / (2 * h)
                fd[3:, k] = w
        if task == "racket5":
            np.testing.assert_allclose(je[:3], fd[:3], atol=1e-8)
            # normal rows: the rate of the face normal in the tangent plane, |ṅ| per joint
            np.testing.assert_allclose(np.linalg.norm(je[3:], axis=0), fd[3], atol=1e-8)
        else:
            np.testing.assert_allclose(je, fd[: je.shape[0]], atol=1e-8)


@pytest.mark.parametrize("task", ["pose", "position", "racket5"])
def test_task_batches_are_one_call_equal_to_the_rows(mobile8, task):
    # (N, n) in one core call (ttkin::task::Task::*_batch) equals N single calls, bit for bit.
    q = random_q(mobile8, 300, seed=4)
    x = mobile8.task_coordinates(q, task)
    j = mobile8.task_jacobian(q, task)
    target = mobile8.fk(q[0])
    jt = mobile8.task_jacobian(q, task, target)
    assert x.shape == (300, len(x[0])) and j.shape == (300, len(x[0]), mobile8.dof)
    for k in (0, 1, 257, 299):
        np.testing.assert_array_equal(x[k], mobile8.task_coordinates(q[k], task))
        np.testing.assert_array_equal(j[k], mobile8.task_jacobian(q[k], task))
        np.testing.assert_array_equal(jt[k], mobile8.task_jacobian(q[k], task, target))
    if task == "racket5":
        ja = mobile8.racket_angle_jacobian(q)
        assert ja.shape == (300, 5, mobile8.dof)
        for k in (0, 299):
            np.testing.assert_array_equal(ja[k], mobile8.racket_angle_jacobian(q[k]))
    bad = q[:3].copy()
    bad[1, 2] = np.nan
    with pytest.raises(ttmanip.NonFiniteError, match="q"):
        mobile8.task_coordinates(bad, task)
    with pytest.raises(ttmanip.ShapeError, match="q"):
        mobile8.task_jacobian(q[:, :3], task)


def test_wls_step_realises_the_task_velocity(mobile8):
    rng = np.random.default_rng(1)
    for q in random_q(mobile8, 20, seed=5):
        xdot = rng.uniform(-0.5, 0.5, 5)
        je = mobile8.task_jacobian(q)
        if np.linalg.svd(je, compute_uv=False)[-1] < 1e-2:
            continue
        for weights in ("chan-dubey", "none"):
            qd = ttmanip.wls_step(mobile8, q, xdot, task="racket5", weights=weights, lambda_max=0.0)
            np.testing.assert_allclose(je @ qd, xdot, atol=1e-10)
    # unweighted and undamped is the minimum-norm solution: the Moore–Penrose pseudo-inverse
    q = Q_START
    xdot = np.array([0.1, -0.05, 0.02, 0.3, 0.1])
    qd = ttmanip.wls_step(mobile8, q, xdot, weights="none", lambda_max=0.0)
    np.testing.assert_allclose(qd, np.linalg.pinv(mobile8.task_jacobian(q)) @ xdot, atol=1e-10)


def test_chan_dubey_weights_slow_a_joint_near_its_limit(mobile8):
    q = Q_START.copy()
    lo, hi = mobile8.limits[4]
    q[4] = hi - 0.02  # joint 5 close to its upper limit
    xdot = np.array([0.1, 0.1, 0.0, 0.0, 0.0])
    free = ttmanip.wls_step(mobile8, q, xdot, weights="none", lambda_max=0.0)
    toward = np.sign(free)  # last motion toward the limit where the unweighted one goes there
    weighted = ttmanip.wls_step(mobile8, q, xdot, weights="chan-dubey", lambda_max=0.0, qd_prev=toward)
    if free[4] > 0:
        assert abs(weighted[4]) < 0.1 * abs(free[4])


def test_wls_step_bad_input(mobile8):
    with pytest.raises(ttmanip.TtmanipError, match="task"):
        ttmanip.wls_step(mobile8, Q_START, np.zeros(5), task="racket6")
    with pytest.raises(ttmanip.TtmanipError, match="weights"):
        ttmanip.wls_step(mobile8, Q_START, np.zeros(5), weights="inverse")
    with pytest.raises(ttmanip.ShapeError, match="xdot"):
        ttmanip.wls_step(mobile8, Q_START, np.zeros(6), task="racket5")
    with pytest.raises(ttmanip.NonFiniteError):
        ttmanip.wls_step(mobile8, np.full(8, np.nan), np.zeros(5))
    with pytest.raises(ttmanip.TtmanipError, match="damping"):
        ttmanip.wls_step(mobile8, Q_START, np.zeros(5), lambda_max=-1.0)


def test_track_returns_plot_ready_arrays(mobile8):
    x0 = mobile8.task_coordinates(Q_START)
    x, xdot = ttmanip.task_line(x0, x0 + [0.02, 0.03, -0.01, 0.05, -0.05], 1.0, rate_hz=500.0)
    assert x.shape == (501, 5) and xdot.shape == (501, 5)
    res = ttmanip.track(mobile8, Q_START, x, rate_hz=500.0, velocities=xdot)
    assert res.status == "completed" and res.ok
    assert len(res) == 501
    assert res.time.shape == (501,) and res.q.shape == (501, 8) and res.qd.shape == (501, 8)
    assert res.x.shape == (501, 5) and res.margin.shape == (501, 8)
    np.testing.assert_allclose(res.time[-1], 1.0)
    np.testing.assert_allclose(res.x[-1], x[-1], atol=1e-8)
    assert res.error.max() < 1e-6
    # without given velocities (finite differences of the samples) it tracks as well
    res2 = ttmanip.track(mobile8, Q_START, x, rate_hz=500.0)
    assert res2.error.max() < 1e-5


def test_track_reports_an_unreachable_motion_instead_of_garbage(mobile8):
    x0 = mobile8.task_coordinates(Q_START)
    x, xdot = ttmanip.task_line(x0, seed000.X4_SEED, 4.0)
    res = ttmanip.track(mobile8, Q_START, x, velocities=xdot)
    assert res.status in ("saturated", "failed")
    assert not res.ok
    assert res.message
    assert np.isfinite(res.q).all()
    assert (res.margin >= 0.0).all()


def test_track_bad_input(mobile8):
    x0 = mobile8.task_coordinates(Q_START)
    x, _ = ttmanip.task_line(x0, x0 + 0.01, 0.5)
    with pytest.raises(ttmanip.ShapeError, match="task_trajectory"):
        ttmanip.track(mobile8, Q_START, x[:, :3])
    with pytest.raises(ttmanip.ShapeError, match="q0"):
        ttmanip.track(mobile8, Q_START[:5], x)
    bad = x.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ttmanip.NonFiniteError):
        ttmanip.track(mobile8, Q_START, bad)
    outside = Q_START.copy()
    outside[4] = 6.0
    with pytest.raises(ttmanip.TtmanipError, match="outside its limits"):
        ttmanip.track(mobile8, outside, x)
    with pytest.raises(ttmanip.TtmanipError, match="rate_hz"):
        ttmanip.track(mobile8, Q_START, x, rate_hz=0.0)


def test_track_on_a_diff_drive_base_keeps_the_wheels_within_limits():
    arm = ttmanip.robots.ur5()
    base = ttmanip.DiffDrive(wheel_radius=0.075, track_width=0.42, max_wheel_speed=20.0)
    mount = np.eye(4)
    mount[:3, 3] = [0.1, 0.0, 0.3]
    q0 = np.array([0.0, 0.0, 0.2, 0.3, -1.2, 1.4, -0.8, 1.2, 0.4])
    pose = mount @ arm.fk(q0[3:])
    c, s = np.cos(0.2), np.sin(0.2)
    p0 = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ pose[:3, 3]
    x, xdot = ttmanip.task_line(p0, p0 + [0.4, -0.2, 0.05], 2.0, rate_hz=500.0, task="position")
    res = ttmanip.track(
        arm,
        q0,
        x,
        rate_hz=500.0,
        task="position",
        velocities=xdot,
        base=base,
        mount=mount,
        input_weights=[10.0, 10.0, 1, 1, 1, 1, 1, 1],
    )
    assert res.ok, res.message
    assert res.q.shape == (1001, 9) and res.qd.shape == (1001, 8)
    assert res.error.max() < 1e-6
    wheels = np.array([base.wheel_speeds(v, w) for v, w in res.qd[:, :2]])
    assert np.abs(wheels).max() <= 20.0 + 1e-9


@pytest.fixture(scope="module")
def seed000_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("seed000")
    return out, seed000.run(out)


def test_seed000_experiment(seed000_run):
    tmp_path, summary = seed000_run
    for name in (
        "fig08_joint_positions.png",
        "fig09_joint_speeds.png",
        "fig10_tracking_error.png",
        "fig_unweighted_comparison.png",
        "weighted.csv",
        "unweighted.csv",
        "summary.json",
    ):
        assert (tmp_path / name).stat().st_size > 0, name
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert on_disk["max_tracking_error"] == summary["max_tracking_error"]
    assert summary["max_tracking_error"] <= 1e-6
    assert summary["reached"] is True
    assert summary["min_limit_margin"] > 0.0
    assert summary["joints_beyond_limits"] is False
    assert summary["max_joint_speed"] <= 3.0
    # every sample of the weighted motion lies within the limits, read back from the CSV
    data = np.loadtxt(tmp_path / "weighted.csv", delimiter=",", skiprows=1)
    q = data[:, 1:9]
    lim = ttmanip.robots.mobile8().limits
    assert (q >= lim[:, 0]).all() and (q <= lim[:, 1]).all()
    np.testing.assert_allclose(data[-1, 17:22], summary["target"], atol=1e-6)
    # on this motion the unweighted pseudo-inverse comes closer to a limit (j2) than the weighted one
    w, u = summary["min_limit_margin_per_joint"], summary["unweighted"]["min_limit_margin_per_joint"]
    assert min(u[1:]) < min(w[1:]) - 0.05
    # and on the straight task line to 15 % of x(4) it crosses a limit where the weighted one does not
    assert summary["line15"]["unweighted"]["min_limit_margin"] < 0.0
    assert summary["line15"]["unweighted"]["joints_crossing_limits"]
    assert summary["line15"]["weighted_min_limit_margin"] > 0.0
    assert summary["line15"]["weighted_max_tracking_error"] <= 1e-6


def test_seed000_target_is_reachable_and_the_nearest_found(seed000_run, mobile8):
    tmp_path, summary = seed000_run
    q_t = np.array(summary["target_q"])
    target = np.array(summary["target"])
    # reachable: FK of the target configuration reproduces the target, within the margins
    np.testing.assert_allclose(mobile8.task_coordinates(q_t), target, atol=1e-12)
    lo, hi = seed000.margin_box(mobile8)
    assert (q_t >= lo).all() and (q_t <= hi).all()
    assert seed000.task_sigma_min(mobile8, q_t) >= seed000.SIGMA_MARGIN
    # and reached: FK of the final tracked configuration reproduces it
    data = np.loadtxt(tmp_path / "weighted.csv", delimiter=",", skiprows=1)
    c, n = seed000.racket_centre_normal(mobile8, data[-1, 1:9])
    c_t, n_t = seed000.racket_centre_normal(mobile8, q_t)
    assert np.linalg.norm(c - c_t) < 1e-6 and np.linalg.norm(n - n_t) < 1e-6
    # nearer to x(4) than the old target (15 % of the straight task line), under the metric
    d_t = seed000.distance_of_coordinates(target)
    assert d_t == pytest.approx(summary["target_distance_to_x4"], abs=1e-12)
    old = np.asarray(summary["x0"]) + 0.15 * (seed000.X4_SEED - np.asarray(summary["x0"]))
    assert d_t < seed000.distance_of_coordinates(old) - 0.1
    # no sampled reachable pose is nearer: 100k random configurations within the same margins,
    # and 100k within the bare joint limits (no singularity margin either)
    rng = np.random.default_rng(12345)
    q = lo + rng.random((100_000, 8)) * (hi - lo)
    d = seed000.distance_to_x4(*seed000.racket_centre_normal(mobile8, q))
    admissible = seed000.task_sigma_min(mobile8, q) >= seed000.SIGMA_MARGIN
    assert admissible.sum() > 50_000
    assert d[admissible].min() > d_t
    lim = mobile8.limits
    q = lim[:, 0] + rng.random((100_000, 8)) * (lim[:, 1] - lim[:, 0])
    assert seed000.distance_to_x4(*seed000.racket_centre_normal(mobile8, q)).min() > d_t
    # the distance is the documented metric
    c4, n4 = seed000.x4_centre_normal()
    np.testing.assert_allclose(seed000.distance_to_x4(c4, n4), 0.0, atol=1e-15)
    assert seed000.distance_to_x4(c4 + [0.1, 0.0, 0.0], n4) == pytest.approx(0.1)
    assert seed000.distance_to_x4(c4, -n4) == pytest.approx(seed000.NORMAL_WEIGHT * np.pi)


def test_seed000_joint_path_task_rates_are_the_derivative_of_the_samples(mobile8):
    q1 = Q_START + np.array([0.1, 0.2, -0.1, 0.1, 0.2, -0.2, 0.1, 0.1])
    x, xdot, qp = seed000.joint_path_task_trajectory(mobile8, Q_START, q1, duration=1.0, rate_hz=1000.0)
    np.testing.assert_allclose(qp[[0, -1]], [Q_START, q1], atol=1e-15)
    np.testing.assert_allclose(x[0], mobile8.task_coordinates(Q_START), atol=1e-12)
    np.testing.assert_allclose(x[-1], mobile8.task_coordinates(q1), atol=1e-12)
    central = (x[2:] - x[:-2]) / 2e-3
    np.testing.assert_allclose(xdot[1:-1], central, atol=1e-5)
    np.testing.assert_allclose(xdot[[0, -1]], 0.0, atol=1e-15)


def test_wls_step_at_a_singular_configuration():
    ur5 = ttmanip.robots.ur5()
    q = np.array([0.3, -1.2, 1.4, -0.8, 0.0, 0.4])  # wrist singularity (q5 = 0)
    xdot = np.array([0.0, 0.0, 0.0, 0.3, 0.2, 0.1])
    with pytest.raises(ttmanip.SingularError, match="damping"):
        ttmanip.wls_step(ur5, q, xdot, task="pose", weights="none", lambda_max=0.0)
    qd = ttmanip.wls_step(ur5, q, xdot, task="pose", weights="none", lambda_max=0.05, epsilon=0.05)
    assert np.isfinite(qd).all() and np.abs(qd).max() < 20.0
