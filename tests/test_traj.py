"""ttmanip.traj: boundary conditions, seed-001 values, via continuity, lines and arcs, limits, strokes."""

from __future__ import annotations

import json

import numpy as np
import pytest
import ttmanip
import ttmanip.traj as tt
from hypothesis import given, settings
from hypothesis import strategies as st

TOL = 1e-12


def rpy_pose(xyz, rpy) -> np.ndarray:
    """4×4 pose from a translation and R = Rz(yaw)·Ry(pitch)·Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    t = np.eye(4)
    t[:3, :3] = rz @ ry @ rx
    t[:3, 3] = xyz
    return t


def test_seed001_cubic_values():
    traj = tt.cubic([0.0, 0.0], [1.6, -1.6], 2.0)
    q, qd, qdd = traj.sample(np.array([0.5, 1.0, 1.5, 2.0]))
    np.testing.assert_allclose(q[:, 0], [0.25, 0.8, 1.35, 1.6], atol=TOL)
    np.testing.assert_allclose(qd[:, 0], [0.9, 1.2, 0.9, 0.0], atol=TOL)
    np.testing.assert_allclose(qdd[:, 0], [1.2, 0.0, -1.2, -2.4], atol=TOL)
    np.testing.assert_allclose(q[:, 1], -q[:, 0], atol=TOL)


vec8 = st.lists(st.floats(-2, 2), min_size=8, max_size=8).map(np.array)


@settings(max_examples=60, deadline=None)
@given(vec8, vec8, vec8, vec8, vec8, vec8, st.floats(0.5, 3.0))
def test_quintic_boundary_conditions(q0, q1, v0, v1, a0, a1, tf):
    traj = tt.quintic(q0, q1, tf, v0=v0, v1=v1, a0=a0, a1=a1)
    for t, want in ((0.0, (q0, v0, a0)), (tf, (q1, v1, a1))):
        for got, w in zip(traj.sample(t), want, strict=False):
            np.testing.assert_allclose(got, w, atol=TOL)


@settings(max_examples=60, deadline=None)
@given(vec8, vec8, vec8, vec8, st.floats(0.5, 3.0))
def test_cubic_boundary_conditions(q0, q1, v0, v1, tf):
    traj = tt.cubic(q0, q1, tf, v0=v0, v1=v1)
    q, qd, _ = traj.sample(0.0)
    np.testing.assert_allclose(q, q0, atol=TOL)
    np.testing.assert_allclose(qd, v0, atol=TOL)
    q, qd, _ = traj.sample(tf)
    np.testing.assert_allclose(q, q1, atol=TOL)
    np.testing.assert_allclose(qd, v1, atol=TOL)


def test_quintic_samples_equal_the_object_samples():
    q0, q1 = np.linspace(0, 1, 8), np.linspace(1, -1, 8)
    t, q, qd, qdd = tt.quintic_samples(q0, q1, 0.8, 101, v1=np.full(8, 0.5))
    traj = tt.quintic(q0, q1, 0.8, v1=np.full(8, 0.5))
    q2, qd2, qdd2 = traj.sample(t)
    assert t.shape == (101,) and q.shape == (101, 8)
    np.testing.assert_array_equal(q, q2)
    np.testing.assert_array_equal(qd, qd2)
    np.testing.assert_array_equal(qdd, qdd2)
    assert t[-1] == 0.8


def test_sample_rate_includes_the_end():
    traj = tt.quintic([0.0], [1.0], 0.105)
    t, q, qd, qdd = traj.sample_rate(100.0)
    assert len(t) == 12 and t[-1] == 0.105
    assert abs(q[-1, 0] - 1.0) < TOL


@pytest.mark.parametrize("kind,c2", [("cubic", False), ("spline", True), ("quintic", True)])
def test_via_continuity(kind, c2):
    points = np.array([[0.0, 1.0], [0.4, 0.8], [1.0, 0.2], [1.3, 0.9], [1.5, 1.4]])
    times = np.array([0.5, 1.0, 2.2, 2.7, 4.0])
    traj = tt.via(points, times, kind=kind)
    assert abs(traj.duration - 3.5) < TOL
    q, _, _ = traj.sample(times - times[0])
    np.testing.assert_allclose(q, points, atol=TOL)
    eps = 1e-9
    for tk in times[1:-1] - times[0]:
        before, after = traj.sample(tk - eps), traj.sample(tk + eps)
        assert np.abs(before[1] - after[1]).max() < 1e-7
        jump = np.abs(before[2] - after[2]).max()
        assert (jump < 1e-6) if c2 else (jump > 1e-3)


def test_line_and_arc_geometry():
    a, b = rpy_pose([0.4, -0.2, 0.9], [0.1, 0.2, 0.3]), rpy_pose([0.7, 0.3, 1.2], [-0.5, 0.4, 2.0])
    line = tt.line(a, b, 0.8, law="trapezoid")
    t, poses, twists, _ = line.sample_rate(250.0)
    d = poses[:, :3, 3] - a[:3, 3]
    u = (b[:3, 3] - a[:3, 3]) / np.linalg.norm(b[:3, 3] - a[:3, 3])
    assert np.abs(d - np.outer(d @ u, u)).max() < TOL
    np.testing.assert_allclose(poses[-1], b, atol=TOL)

    via_point = np.array([0.55, 0.1, 1.2])
    arc = tt.arc(a, b, 1.0, via=via_point)
    _, poses, _, _ = arc.sample_rate(500.0)
    p = poses[:, :3, 3]
    # Circumcentre of the three points and the plane normal.
    p0, p2 = a[:3, 3], b[:3, 3]
    x, y = via_point - p0, p2 - p0
    n = np.cross(x, y)
    c = p0 + np.cross(x @ x * y - y @ y * x, n) / (2 * n @ n)
    r = np.linalg.norm(p0 - c)
    assert np.abs(np.linalg.norm(p - c, axis=1) - r).max() < TOL
    assert np.abs((p - c) @ (n / np.linalg.norm(n))).max() < TOL

    about = tt.arc(a, duration=1.0, centre=[0.2, 0.1, 0.5], axis=[0, 0, 1], angle=1.0)
    pose, twist, _ = about.sample(0.5)
    assert abs(np.linalg.norm(pose[:2, 3] - [0.2, 0.1]) - np.linalg.norm(a[:2, 3] - [0.2, 0.1])) < TOL
    assert abs(pose[2, 3] - a[2, 3]) < TOL


def test_to_joint_with_a_python_ik_reproduces_the_poses():
    # x, y, z slides then a roll-pitch-yaw wrist: FK(q) = Trans(q0, q1, q2)·Rz(q3)·Ry(q4)·Rx(q5).
    def fk(q):
        return rpy_pose(q[:3], [q[5], q[4], q[3]])

    def ik(pose, seed):
        r = pose[:3, :3]
        if pose[0, 3] > 0.65:
            raise ttmanip.UnreachableError(f"x = {pose[0, 3]:.3f} m beyond the rail")
        yaw, pitch, roll = np.arctan2(r[1, 0], r[0, 0]), -np.arcsin(r[2, 0]), np.arctan2(r[2, 1], r[2, 2])
        return np.array([*pose[:3, 3], yaw, pitch, roll])

    a, b = rpy_pose([0.4, -0.2, 0.9], [0.1, 0.2, 0.3]), rpy_pose([0.6, 0.3, 1.2], [-0.5, 0.4, 1.0])
    line = tt.line(a, b, 0.5)
    t, q, qd, qdd = line.to_joint(500.0, np.zeros(6), ik)
    for i in range(0, len(t), 25):
        pose, twist, _ = line.sample(t[i])
        np.testing.assert_allclose(fk(q[i]), pose, atol=1e-12)
    far = tt.line(a, rpy_pose([0.9, 0.0, 0.9], [0, 0, 0]), 1.0)
    with pytest.raises(ttmanip.UnreachableError, match=r"^unreachable: sample \d+ at t = "):
        far.to_joint(100.0, np.zeros(6), ik)


def test_check_limits_finds_planted_violations():
    robot = ttmanip.robots.arm4()  # ±170° (joint 3: ±120°), 2 rad/s
    n = robot.dof
    slow = tt.quintic(np.zeros(n), [1.0, 0.5, 1.5, 0.3], 5.0)
    assert slow.check_limits(robot) == []
    fast = tt.quintic(np.zeros(n), [1.0, 0.5, 2.5, 0.3], 0.5)
    found = {(v["joint"], v["quantity"]) for v in fast.check_limits(robot)}
    peaks, _ = fast.peaks(1)
    expect_vel = {j for j in range(n) if abs(peaks[j]) > robot.velocity_limits[j]}
    assert expect_vel and {j for j, k in found if k == "velocity"} == expect_vel
    assert (2, "position") in found  # 2.5 rad > 120°


def test_minimal_duration_sits_at_the_limit():
    robot = ttmanip.robots.arm4()
    q0, q1 = np.zeros(4), np.array([1.0, -0.5, 0.8, 0.3])
    for kind in ("cubic", "quintic"):
        t = tt.minimal_duration(robot, q0, q1, kind=kind)
        traj = (tt.cubic if kind == "cubic" else tt.quintic)(q0, q1, t)
        vpk, _ = traj.peaks(1)
        ratio = np.abs(vpk) / robot.velocity_limits
        amax = robot.acceleration_limits
        if np.all(np.isfinite(amax)):
            apk, _ = traj.peaks(2)
            ratio = np.maximum(ratio, np.abs(apk) / amax)
        assert abs(ratio.max() - 1.0) < 1e-12


def test_stroke_on_time_and_adjusted():
    n = 4
    state = (np.zeros(n), np.array([0.2, 0, -0.1, 0]), np.array([0, 0.5, 0, 0]))
    q_hit, qd_hit = np.array([0.8, -0.4, 0.6, 1.0]), np.array([2.0, -1.0, 1.5, 3.0])
    kw = dict(velocity=np.full(n, 4.0), acceleration=np.full(n, 40.0), jerk=np.full(n, 800.0))
    s = tt.stroke(None, state, q_hit, qd_hit, 0.6, np.zeros(n), **kw)
    assert s.on_time and s.feasible
    q, qd, qdd = s.trajectory.sample(0.6)
    np.testing.assert_allclose(q, q_hit, atol=TOL)
    np.testing.assert_allclose(qd, qd_hit, atol=TOL)
    q, qd, _ = s.trajectory.sample(s.trajectory.duration)
    np.testing.assert_allclose(q, np.zeros(n), atol=TOL)
    np.testing.assert_allclose(qd, np.zeros(n), atol=TOL)

    late = tt.stroke(None, state, q_hit, qd_hit, 0.1, np.zeros(n), **kw)
    assert not late.on_time and late.t_hit > 0.1 and late.feasible
    shorter = tt.quintic(state[0], q_hit, late.t_hit * (1 - 1e-9), v0=state[1], v1=qd_hit, a0=state[2])
    robot_like = [abs(shorter.peaks(k)[0]).max() / lim for k, lim in ((1, 4.0), (2, 40.0), (3, 800.0))]
    assert max(robot_like) > 1.0


def test_stroke_binding_refuses_half_position_limits():
    """Position limits with only one side given are an error, not silently dropped (issue 30)."""
    from ttmanip import _ttmanip

    n, inf = 2, np.full(2, np.inf)
    start = hit = (np.zeros(n), np.zeros(n), np.zeros(n))
    with pytest.raises(ttmanip.TtmanipError, match="lower.*upper"):
        _ttmanip.traj_stroke(start, hit, 0.5, np.zeros(n), inf, inf, inf, np.full(n, -1.0), None, None)
    _ttmanip.traj_stroke(start, hit, 0.5, np.zeros(n), inf, inf, inf, np.full(n, -1.0), np.ones(n), None)


def test_bad_input():
    with pytest.raises(ttmanip.TtmanipError, match="duration"):
        tt.cubic([0.0], [1.0], 0.0)
    with pytest.raises(ttmanip.TtmanipError):
        tt.quintic([0.0], [1.0], -1.0)
    with pytest.raises(ttmanip.NonFiniteError):
        tt.quintic([0.0, np.nan], [1.0, 1.0], 1.0)
    with pytest.raises(ttmanip.ShapeError):
        tt.cubic([0.0, 1.0], [1.0], 1.0)
    with pytest.raises(ttmanip.ShapeError):
        tt.quintic([0.0, 1.0], [1.0, 2.0], 1.0, v0=[1.0])
    with pytest.raises(ttmanip.TtmanipError, match="strictly increasing"):
        tt.via([[0.0], [1.0], [2.0]], [0.0, 1.0, 1.0])
    with pytest.raises(ttmanip.ShapeError):
        tt.via([[0.0], [1.0]], [0.0, 1.0, 2.0])
    with pytest.raises(ttmanip.TtmanipError, match="outside"):
        tt.cubic([0.0], [1.0], 1.0).sample(2.0)
    with pytest.raises(ttmanip.TtmanipError, match="collinear"):
        tt.arc(np.eye(4), rpy_pose([2, 0, 0], [0, 0, 0]), 1.0, via=[1.0, 0, 0])
    with pytest.raises(ttmanip.TtmanipError, match="law"):
        tt.line(np.eye(4), np.eye(4), 1.0, law="sigmoid")


def test_seed001_experiment_writes_its_outputs(tmp_path):
    from ttmanip.experiments import seed001

    summary = seed001.run(tmp_path)
    assert summary["cubic_matches_readme_values"] is True
    data = json.loads((tmp_path / "summary.json").read_text())
    assert data["cubic"]["position"] == pytest.approx([0.25, 0.8, 1.35, 1.6], abs=1e-12)
    assert data["paper_speed_integral"]["trapezoid_rad"] == pytest.approx(3.0)
    assert (tmp_path / "seed001_motion.png").stat().st_size > 10_000
    assert "cannot all be matched" in (tmp_path / "seed001_table.md").read_text()


def test_stroke_with_robot_limits_reports_position_violations():
    robot = ttmanip.robots.arm4()  # ±170° (joint 3: ±120°), 2 rad/s, no acceleration limit
    q0 = np.zeros(4)
    ok = tt.stroke(robot, q0, [0.5, -0.3, 0.4, 0.2], [1.0, 0.0, -0.5, 0.5], 0.8, q0)
    assert ok.feasible and ok.on_time
    peaks, _ = ok.trajectory.peaks(1)
    assert np.all(np.abs(peaks) <= robot.velocity_limits * (1 + 1e-9))
    # Hitting at 2.0 rad on joint 3 (limit 120° ≈ 2.094 rad) at 1.9 rad/s overshoots the limit.
    over = tt.stroke(robot, q0, [0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 1.9, 0.0], 2.0, q0)
    assert not over.feasible
    assert {(v["joint"], v["quantity"]) for v in over.violations} == {(2, "position")}
