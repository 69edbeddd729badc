"""The hit pipeline from Python: plans meet the hit exactly, the jerk-limited stroke is as fast as
Python ``ruckig`` on the same limits, every sampled trajectory respects every limit, the drives
execute the demo hit within the acceptance errors, and bad input is a TtmanipError."""

from __future__ import annotations

import numpy as np
import pytest
import ruckig
import ttmanip
from ttmanip import robots
from ttmanip.pipeline import racket_states

GANTRY = robots.gantry6()
JERK_PER_ACCELERATION = 200.0  # the planner's default jerk limit: 200 × the acceleration limit


def random_hits(count: int, seed: int = 0, t: float = 0.01) -> list[ttmanip.Hit]:
    """The documented distribution of random gantry6 hits: racket centre uniform in
    x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2], z ∈ [−0.15, 0.15] m; face normal (sin a, −cos a·cos b, sin b)
    with a, b uniform in [−0.7, 0.7] rad (within ≈ 40° of −y); racket speed uniform in 1–4 m/s along
    the normal; hit time ``t`` (0.01 s: earlier than feasible, so the plan is the time-optimal one)."""
    rng = np.random.default_rng(seed)
    hits = []
    for _ in range(count):
        c = rng.uniform([-0.3, -0.6, -0.15], [0.3, -0.2, 0.15])
        a, b = rng.uniform(-0.7, 0.7, 2)
        n = np.array([np.sin(a), -np.cos(a) * np.cos(b), np.sin(b)])
        n /= np.linalg.norm(n)
        hits.append(ttmanip.Hit.from_normal(c, n, rng.uniform(1.0, 4.0) * n, t))
    return hits


def racket_at(robot, plan):
    """Racket pose and centre velocity of the planned stroke at its hit time."""
    q, qd, _ = plan.trajectory.sample(plan.t_hit)
    poses, _, _, v = racket_states(robot, q, qd)
    return poses[0], v[0]


def test_demo_hit_is_met_exactly_on_time():
    plan = ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT)
    assert plan.ok and plan.status == "ok" and plan.t_hit == pytest.approx(0.55, abs=0)
    pose, v = racket_at(GANTRY, plan)
    np.testing.assert_allclose(pose, ttmanip.DEMO_HIT.pose, atol=1e-9)
    np.testing.assert_allclose(v, ttmanip.DEMO_HIT.velocity, atol=1e-8)
    assert 0.25 < plan.earliest_t_hit < 0.55
    assert plan.violations == []
    t, q, qd, qdd = plan.sample(1000.0)
    assert plan.tau.shape == q.shape
    np.testing.assert_allclose(q[-1], plan.ready, atol=1e-8)


def test_too_early_hit_is_a_status_and_raises_only_on_request():
    hit = ttmanip.Hit(ttmanip.DEMO_HIT.pose, ttmanip.DEMO_HIT.twist, 0.05)
    plan = ttmanip.plan_hit(GANTRY, hit)
    assert not plan.ok and plan.status == "too_early"
    assert plan.t_hit == pytest.approx(plan.earliest_t_hit) and plan.t_hit > 0.05
    with pytest.raises(ttmanip.HitError, match="too_early"):
        ttmanip.plan_hit(GANTRY, hit, raise_on_failure=True)
    far = ttmanip.Hit.from_normal([0.3, -0.5, 2.0], [0, -1, 0], [0, -3, 0], 0.5)
    plan = ttmanip.plan_hit(GANTRY, far)
    assert plan.status == "unreachable" and plan.trajectory is None
    with pytest.raises(ttmanip.TtmanipError, match="no stroke"):
        plan.sample(1000.0)


def test_batch_equals_single_calls():
    hits = random_hits(20, seed=3, t=0.4)
    batch = ttmanip.plan_hits(GANTRY, hits)
    for h, b in zip(hits, batch, strict=False):
        s = ttmanip.plan_hit(GANTRY, h)
        assert (s.status, s.profile) == (b.status, b.profile)
        np.testing.assert_array_equal([s.t_hit, *s.q_hit], [b.t_hit, *b.q_hit])


def _ruckig_duration(plan, v, a, j) -> float:
    inp = ruckig.InputParameter(6)
    inp.current_position = list(plan.start)
    inp.current_velocity = [0.0] * 6
    inp.current_acceleration = [0.0] * 6
    inp.target_position = list(plan.q_hit)
    inp.target_velocity = list(plan.qd_hit)
    inp.target_acceleration = [0.0] * 6
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(v), list(a), list(j)
    traj = ruckig.Trajectory(6)
    result = ruckig.Ruckig(6).calculate(inp, traj)
    assert result in (ruckig.Result.Working, ruckig.Result.Finished)
    return traj.duration


def _sampled_within_limits(robot, plan, j) -> None:
    t, q, qd, qdd = plan.sample(1000.0)
    lim = np.asarray(robot.limits)
    tol = 1e-9
    assert (q >= lim[:, 0] - tol).all() and (q <= lim[:, 1] + tol).all()
    assert (np.abs(qd) <= robot.velocity_limits * (1 + tol)).all()
    assert (np.abs(qdd) <= robot.acceleration_limits * (1 + tol)).all()
    # Jerk: exact per-segment values of the piecewise polynomial.
    values, _ = plan.trajectory.peaks(3)
    assert (np.abs(values) <= j * (1 + tol)).all()
    assert (np.abs(plan.tau) <= robot.effort_limits * (1 + 1e-6)).all() or plan.effort_ratio <= 1.0


def test_jerk_limited_stroke_matches_python_ruckig_on_1000_reachable_hits():
    v, a = GANTRY.velocity_limits, GANTRY.acceleration_limits
    j = JERK_PER_ACCELERATION * a
    reachable, ratios = [], []
    seed = 0
    while len(reachable) < 1000:
        for plan in ttmanip.plan_hits(GANTRY, random_hits(400, seed=seed), profile="jerk", effort=False):
            if plan.status in ("ok", "too_early") and len(reachable) < 1000:
                reachable.append(plan)
        seed += 1
    for plan in reachable:
        ratios.append(plan.t_hit / _ruckig_duration(plan, v, a, j))
    ratios = np.array(ratios)
    # The same time-optimal problem: the hit time is within 1.02× of ruckig's (and never shorter).
    assert ratios.max() <= 1.02, (ratios.max(), np.argmax(ratios))
    assert ratios.min() >= 1 - 1e-9
    for plan in reachable[:200]:
        _sampled_within_limits(GANTRY, plan, j)


def test_every_sampled_stroke_respects_every_limit_with_effort_checks():
    j = JERK_PER_ACCELERATION * GANTRY.acceleration_limits
    for plan in ttmanip.plan_hits(GANTRY, random_hits(200, seed=11, t=0.3)):
        if plan.status in ("ok", "too_early"):
            _sampled_within_limits(GANTRY, plan, j)
            assert plan.effort_ratio <= 1.0


def test_demo_hit_on_the_drives_meets_the_acceptance_errors():
    plan = ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT)
    sim = ttmanip.simulate(GANTRY, plan)
    assert sim.faults == [""] * 6
    assert sim.racket_position_error_m <= 1e-3
    assert sim.racket_normal_error_deg <= 0.5
    assert sim.racket_velocity_error_rel <= 0.02
    k = sim.arrays["q"].shape[0]
    assert sim.racket_centre.shape == (k, 3) and sim.racket_pose.shape == (k, 4, 4)


def test_mobile8_racket_task_hit_is_planned_and_simulated():
    from ttmanip.demo import mobile8_hit

    robot = robots.mobile8()
    hit = mobile8_hit()
    plan = ttmanip.plan_hit(robot, hit)
    assert plan.ok, plan.message
    pose, v = racket_at(robot, plan)
    np.testing.assert_allclose(pose[:3, 3], hit.centre, atol=1e-6)
    np.testing.assert_allclose(pose[:3, 2], hit.normal, atol=1e-6)
    np.testing.assert_allclose(v, hit.velocity, atol=1e-6)
    sim = ttmanip.simulate(robot, plan)
    assert sim.arrays["q"].shape[1] == 8
    assert np.isfinite(sim.racket_position_error_m)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: ttmanip.Hit(np.eye(3), np.zeros(6), 0.3), "hit.pose"),
        (lambda: ttmanip.Hit(np.eye(4), np.zeros(5), 0.3), "hit.twist"),
        (lambda: ttmanip.Hit(np.eye(4), np.zeros(6), -1.0), "hit.t"),
        (lambda: ttmanip.Hit(np.eye(4), np.zeros(6), "soon"), "hit.t"),
        (lambda: ttmanip.Hit.from_normal([0, 0, 0], [0, 0, 0], [0, 0, 0], 0.3), "normal"),
        (lambda: ttmanip.Hit.from_normal([np.nan, 0, 0], [0, 0, 1], [0, 0, 0], 0.3), "centre"),
        (lambda: ttmanip.plan_hit(GANTRY, "hit"), "hit"),
        (lambda: ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT, [0.0] * 5), "state.q"),
        (lambda: ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT, profile="fast"), "profile"),
        (lambda: ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT, task="racket6"), "task: expected 'auto'"),
        (lambda: ttmanip.plan_hits(GANTRY, [ttmanip.DEMO_HIT], task="Pose"), "task: expected 'auto'"),
        (lambda: ttmanip.plan_hit(GANTRY, ttmanip.DEMO_HIT, ready=[0.0]), "ready"),
        (
            lambda: (
                ttmanip.Hit(np.diag([2.0, 1, 1, 1]), np.zeros(6), 0.3)
                and ttmanip.plan_hit(GANTRY, ttmanip.Hit(np.diag([2.0, 1, 1, 1]), np.zeros(6), 0.3))
            ),
            "hit.pose",
        ),
    ],
)
def test_bad_input_is_a_ttmanip_error_naming_the_argument(make, match):
    with pytest.raises(ttmanip.TtmanipError, match=match):
        make()


def test_pipeline_modules_export_only_their_api():
    import inspect

    from ttmanip import cli, demo, pipeline, plots
    from ttmanip.experiments import seed002

    for module in (pipeline, plots, demo, cli, seed002):
        assert all(hasattr(module, name) for name in module.__all__), module.__name__
        leaked = {"np", "json", "dataclass", "field", "Any", "Path", "plt", "matplotlib", "annotations"}
        assert not leaked & set(module.__all__), module.__name__
        own = {
            n
            for n, v in vars(module).items()
            if inspect.isfunction(v) and v.__module__ == module.__name__ and not n.startswith("_")
        }
        assert own <= set(module.__all__), (module.__name__, own - set(module.__all__))


@pytest.mark.parametrize("name", ["gantry6", "mobile8"])
def test_racket_states_match_fk_and_the_jacobian(name):
    """The racket states come from ttkin::hit::racket; checked here against FK, the Jacobian and
    the mount (v_centre = v_tool + ω × lever), and the centre velocity against a finite difference."""
    robot = robots.builtin(name)
    rng = np.random.default_rng(3)
    lo, hi = robot.limits.T
    q = rng.uniform(np.maximum(lo, -3), np.minimum(hi, 3), (20, robot.dof))
    qd = rng.normal(size=(20, robot.dof))
    poses, centres, normals, v = racket_states(robot, q, qd)
    mount = ttmanip.pipeline.racket_mount(robot)
    tool = robot.fk(q)
    np.testing.assert_allclose(poses, tool @ mount, atol=1e-14)
    twist = np.einsum("kij,kj->ki", robot.jacobian(q), qd)
    lever = np.einsum("kij,j->ki", tool[:, :3, :3], mount[:3, 3])
    np.testing.assert_allclose(v, twist[:, :3] + np.cross(twist[:, 3:], lever), atol=1e-12)
    h = 1e-6
    ahead = racket_states(robot, q + h * qd, qd)[1]
    behind = racket_states(robot, q - h * qd, qd)[1]
    np.testing.assert_allclose(v, (ahead - behind) / (2 * h), atol=1e-6)
    np.testing.assert_array_equal(normals, poses[:, :3, 2])
    with pytest.raises(ttmanip.ShapeError, match="qd"):
        racket_states(robot, q, qd[:3])
