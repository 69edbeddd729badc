"""ttmanip.ball: flight, estimation, prediction, crossing and hit planning (issue 13)."""

from __future__ import annotations

import numpy as np
import pytest
import ttmanip
from hypothesis import given, settings
from hypothesis import strategies as st
from ttmanip import ball

G = 9.81


@settings(max_examples=30, deadline=None)
@given(
    st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-2, 5)),  # stays above the floor for 0.3 s
    st.lists(st.floats(-300, 300), min_size=3, max_size=3),
)
def test_vacuum_flight_is_the_parabola(v, w):
    s = ball.state([0.0, 3.0, 1.0], v, w)  # beside the table: no contact for 0.3 s
    t = np.linspace(0.0, 0.3, 7)
    p = ball.predict(s, t, model="vacuum")
    exact = np.array([0.0, 3.0, 1.0]) + np.outer(t, v) + np.outer(0.5 * t**2, [0.0, 0.0, -G])
    np.testing.assert_allclose(p, exact, atol=1e-9)


@pytest.mark.parametrize(
    "model, e", [("default", 0.964), ("measured", 0.964), ("aero", 0.93), ("tt3d", 0.93)]
)
def test_bounce_reverses_normal_speed_with_restitution(model, e):
    # The default's restitution is measured (docs/ball.md, Calibration); the presets keep 0.93.
    s = ball.state([-0.5, 0.0, 0.3], [-2.0, 0.0, 0.0])
    _, events = ball.predict(s, [1.0], model=model, events=True)
    bounce = next(e for e in events if e["kind"] == "table")
    vz_before, vz_after = bounce["before"][6], bounce["after"][6]
    assert vz_after == pytest.approx(-e * vz_before, rel=1e-12)
    m, r = 0.0027, 0.02
    energy = lambda x: 0.5 * m * x[4:7] @ x[4:7] + 0.5 * (2 / 3 * m * r * r) * x[7:10] @ x[7:10]  # noqa: E731
    assert energy(bounce["after"]) < energy(bounce["before"])


def _observations(state, n=41, noise=0.002, seed=0):
    t = 0.02 + 0.005 * np.arange(n)
    p = ball.predict(state, t) + noise * np.random.default_rng(seed).standard_normal((n, 3))
    return t, p


def test_estimate_recovers_velocity_within_stated_error():
    # Stated: σ = 2 mm, 41 observations at 200 Hz, one 10 cm outlier → |Δv| < 0.15 m/s.
    s = ball.state([1.6, 0.1, 0.3], [-5.0, -0.3, 1.2], [0.0, -120.0, 40.0])
    t, p = _observations(s)
    p[7] += 0.1
    e = ball.estimate(t, p)
    v_true = _velocity_at(s, t[-1])
    assert np.linalg.norm(e.velocity - v_true) < 0.15
    assert e.outliers >= 1 and e.state[0] == t[-1]
    assert e.covariance.shape == (6, 6)


def _velocity_at(s, t):
    h = 1e-4
    p = ball.predict(s, [t - h, t + h])
    return (p[1] - p[0]) / (2 * h)


def test_estimate_bad_input_is_a_clear_error():
    s = ball.state([1.6, 0.0, 0.3], [-5.0, 0.0, 1.0])
    t, p = _observations(s, n=12)
    with pytest.raises(ttmanip.TtmanipError, match="too few"):
        ball.estimate(t[:3], p[:3])
    q = p.copy()
    q[:9, 1] = np.nan
    with pytest.raises(ttmanip.TtmanipError, match="too few"):
        ball.estimate(t, q)
    with pytest.raises(ttmanip.TtmanipError, match="p"):
        ball.estimate(t, p[:, :2])
    q = p.copy()
    q[2, 0] = np.nan
    assert ball.estimate(t, q).nonfinite == 1


def test_predict_batch_matches_single_predictions():
    states = np.array([ball.state([1.6, y, 0.3], [-5.0, 0.2 * y, 1.0]) for y in (-0.3, 0.0, 0.4)])
    t = np.linspace(0.0, 0.8, 9)
    batch = ball.predict_batch(states, t)
    assert batch.shape == (3, 9, 3)
    for k, s in enumerate(states):
        np.testing.assert_array_equal(batch[k], ball.predict(s, t))


def test_crossing_of_the_hitting_plane():
    s = ball.state([1.6, 0.1, 0.3], [-6.0, -0.2, 1.5], [0.0, 40.0, 0.0])
    c = ball.crossing(s, x=-1.6)
    assert c["outcome"] == "crossed" and c["bounces"] == ["table"]
    assert c["state"][1] == pytest.approx(-1.6, abs=1e-9)
    assert c["state"][4] < 0
    assert ball.crossing(ball.state([0.8, 0.0, 0.05], [-3.0, 0.0, 0.0]), x=-1.6)["outcome"] == "net"


def test_plan_return_gives_a_reachable_hit_and_rejects_targets_off_the_table():
    s = ball.state([1.6, 0.1, 0.3], [-6.0, -0.2, 1.5], [0.0, 40.0, 0.0])
    plan = ball.plan_return(s, 0.2, (0.9, 0.0))
    assert plan["status"] == "ok"
    robot = ttmanip.robots.gantry6()
    np.testing.assert_allclose(robot.fk(plan["q_hit"]), plan["pose"], atol=1e-9)
    assert plan["landing"][0] == pytest.approx(0.9, abs=1e-3)
    for target in [(2.0, 0.0), (-0.5, 0.0), (0.9, 1.0)]:
        with pytest.raises(ttmanip.TtmanipError, match="target"):
            ball.plan_return(s, 0.2, target)
    net = ball.state([0.8, 0.0, 0.05], [-3.0, 0.0, 0.0])
    assert ball.plan_return(net, 0.0)["status"] == "no_bounce"


def test_plan_return_plans_for_the_robot_given_and_refuses_one_it_cannot_plan_for():
    s = ball.state([1.6, 0.1, 0.3], [-6.0, -0.2, 1.5], [0.0, 40.0, 0.0])
    g6 = ttmanip.robots.gantry6()
    default = ball.plan_return(s, 0.2, (0.9, 0.0))
    given = ball.plan_return(s, 0.2, (0.9, 0.0), robot=g6)
    for key in ("q_hit", "qd_hit", "pose", "ready", "landing"):
        np.testing.assert_array_equal(given[key], default[key])
    # A gantry6 carrying its racket 5 cm further out along the tool z axis: the plan is made for
    # that robot (its forward kinematics puts its racket at the planned pose), not for gantry6.
    mount = np.eye(4)
    mount[2, 3] = 0.05
    moved = g6.with_racket(ttmanip.pipeline.racket_mount(g6) @ mount)
    other = ball.plan_return(s, 0.2, (0.9, 0.0), robot=moved)
    assert other["status"] == "ok"
    assert not np.allclose(other["ready"], default["ready"])
    fk = moved.fk(other["q_hit"]) @ ttmanip.pipeline.racket_mount(moved)
    np.testing.assert_allclose(fk, other["pose"], atol=1e-9)
    # ur5 has no analytic IK; arm4 has one but cannot reach the ready pose at the placement.
    cases = [(ttmanip.robots.ur5(), "analytic IK"), (ttmanip.robots.arm4(), "ready racket pose")]
    for robot, reason in cases:
        with pytest.raises(ttmanip.ModelError, match=f"{robot.name}.*{reason}"):
            ball.plan_return(s, 0.2, (0.9, 0.0), robot=robot)
        with pytest.raises(ttmanip.ModelError, match=reason):
            ball.plan_correct(s, 0.2, (0.9, 0.0), s, 0.25, False, robot=robot)


def test_the_table_is_the_cores_predicate_checks_and_outline():
    t = ball.Table()
    # the core's predicate (Table::on_opponent_half): the end line and side lines belong to it
    half_l, half_w = t.length / 2, t.width / 2
    assert t.on_opponent_half(half_l, half_w) and t.on_opponent_half(1e-9, 0.0)
    assert not t.on_opponent_half(0.0, 0.0) and not t.on_opponent_half(half_l + 1e-9, 0.0)
    assert not t.on_opponent_half(-0.5, 0.0) and not t.on_opponent_half(0.5, -half_w - 1e-9)
    small = ball.Table(length=2.0, width=1.0)
    assert small.on_opponent_half(1.0, 0.5) and not small.on_opponent_half(1.2, 0.0)
    with pytest.raises(ttmanip.TtmanipError, match="x"):
        t.on_opponent_half(np.nan, 0.0)
    # the core's checks (Table::validate): a net that does not overhang is a table, a flat one is not
    assert ball.Table(net_overhang=0.0).net_overhang == 0.0
    for field in ("length", "width", "height", "net_height"):
        with pytest.raises(ttmanip.TtmanipError, match=field):
            ball.Table(**{field: 0.0})
    with pytest.raises(ttmanip.TtmanipError, match="net_overhang"):
        ball.Table(net_overhang=-0.1)
    with pytest.raises(ttmanip.TtmanipError, match="length"):
        ball.Table(length="long")
    # the outline: closed loops on the surface's edges and the net's, from the given geometry
    o = small.outline()
    assert o["surface"].shape == (5, 3) and o["net"].shape == (5, 3) and o["centre_line"].shape == (2, 3)
    np.testing.assert_array_equal(o["surface"][0], o["surface"][-1])
    np.testing.assert_array_equal(np.abs(o["surface"][:4, :2]), np.tile([1.0, 0.5], (4, 1)))
    assert o["net"][:, 1].max() == 0.5 + small.net_overhang and o["net"][:, 2].max() == small.net_height
    assert (o["net"][:, 0] == 0).all()


def test_bad_state_and_model_are_errors():
    with pytest.raises(ttmanip.TtmanipError):
        ball.predict([np.nan] * 10, [0.1])
    with pytest.raises(ttmanip.TtmanipError):
        ball.predict(np.zeros(9), [0.1])
    with pytest.raises(ttmanip.TtmanipError, match="model"):
        ball.BallModel("unknown")
    with pytest.raises(ttmanip.TtmanipError, match="events"):
        ball.predict(np.zeros(10), [0.1], events=np.zeros(2))


def test_racket_impact_reverses_the_relative_normal_speed():
    # Head-on, no spin: the relative normal speed reverses with the rubber's restitution 0.85.
    s = ball.state([-1.8, 0.0, 0.2], [-5.0, 0.0, 0.0])
    out = ball.racket_impact(s, [1.0, 0.0, 0.0], [3.0, 0.0, 0.0])
    assert out[4] == pytest.approx(3.0 + 0.85 * 8.0, rel=1e-12)
    np.testing.assert_allclose(out[[0, 1, 2, 3, 5, 6, 7, 8, 9]], s[[0, 1, 2, 3, 5, 6, 7, 8, 9]], atol=1e-12)
    # Oblique with spin: the tangential impulse turns spin into speed and back (rolling cap).
    s2 = ball.state([-1.8, 0.0, 0.2], [-5.0, 1.0, 0.0], [0.0, 0.0, 100.0])
    out2 = ball.racket_impact(s2, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    assert out2[4] > 0 and out2[9] != 100.0
    with pytest.raises(ttmanip.TtmanipError, match="unit"):
        ball.racket_impact(s, [2.0, 0.0, 0.0], [0.0, 0.0, 0.0])


def test_update_through_the_bounce_follows_the_true_ball():
    s = ball.state([1.6, 0.1, 0.25], [-5.0, -0.2, 0.8], [0.0, 60.0, 0.0])
    t = 0.02 + 0.005 * np.arange(41)
    p = ball.predict(s, t)
    _, events = ball.predict(s, [1.0], events=True)
    tb = next(e for e in events if e["kind"] == "table")["before"][0]
    t_new = np.arange(t[-1] + 0.005, tb + 0.04, 0.005)
    p_new = ball.predict(s, t_new)
    up = ball.update(t, p, t_new, p_new)
    # (observations right at the bounce are not used)
    assert up["bounced"] and len(t_new) - 3 <= up["used"] <= len(t_new)
    assert t_new[-4] <= up["state"][0] <= t_new[-1]
    np.testing.assert_allclose(up["state"][1:4], ball.predict(s, [up["state"][0]])[0], atol=2e-3)
    assert np.asarray(up["covariance"]).shape == (9, 9)


def test_update_with_the_bounce_kick_follows_a_ball_that_bounces_off_the_model():
    # The true ball leaves the table (on the robot's half) 0.1 m/s faster in x than the model's
    # bounce says: the plain update (the model's bounce exactly) cannot follow it, the kick
    # (update_kick, the rally's correction) does; a ball that bounces as the model says keeps the
    # plain update (the χ² gate).
    s = ball.state([1.2, 0.1, 0.35], [-6.0, -0.2, 0.9], [0.0, 60.0, 0.0])
    t = 0.02 + 0.005 * np.arange(41)
    p = ball.predict(s, t)
    _, events = ball.predict(s, [1.0], events=True)
    bounce = next(e for e in events if e["kind"] == "table")
    assert bounce["before"][1] < 0  # on the robot's half
    after = np.array(bounce["after"], dtype=float)
    kicked = after.copy()
    kicked[4] += 0.1
    t_new = np.arange(t[-1] + 0.005, after[0] + 0.06, 0.005)
    before = t_new < after[0]
    p_new = np.vstack([ball.predict(s, t_new[before]), ball.predict(kicked, t_new[~before])])
    plain = ball.update(t, p, t_new, p_new)
    kick = ball.update(t, p, t_new, p_new, bounce_spread=ball.BOUNCE_SPREAD)
    ahead = kick["state"][0] + 0.03
    truth = ball.predict(kicked, [ahead])[0]
    err_plain = np.linalg.norm(ball.predict(plain["state"], [ahead])[0] - truth)
    err_kick = np.linalg.norm(ball.predict(kick["state"], [ahead])[0] - truth)
    assert kick["bounced"] and err_kick < 1e-4 < 5e-3 < err_plain, (err_kick, err_plain)
    assert kick["outliers"] == 0 and plain["outliers"] > 0
    # The model's own bounce: the gate keeps the plain update.
    p_model = ball.predict(s, t_new)
    a = ball.update(t, p, t_new, p_model)
    b = ball.update(t, p, t_new, p_model, bounce_spread=ball.BOUNCE_SPREAD)
    np.testing.assert_array_equal(a["state"], b["state"])
    for bad in ([0.3, 0.0, 0.05], [0.3, 0.3], [0.3, np.nan, 0.05]):
        with pytest.raises(ttmanip.TtmanipError, match="bounce_spread"):
            ball.update(t, p, t_new, p_new, bounce_spread=bad)


def test_plan_correct_replans_near_the_first_hit_from_the_moving_stroke():
    incoming = ttmanip.rally(8, seed=0)["results"]["incoming"]
    s = next(b for b in incoming if ball.plan_return(b, 0.23, [0.9, 0.0])["status"] == "ok")
    # The same ball, known better 80 ms into the stroke: the corrected hit is near the first.
    r = ball.plan_correct(s, 0.23, [0.9, 0.0], s, 0.31, False)
    assert r["first"]["status"] == "ok" and r["corrected"]["status"] == "ok"
    t1 = 0.23 + r["first"]["t_hit"]
    t2 = 0.31 + r["corrected"]["t_hit"]
    assert abs(t1 - t2) < 0.05
    np.testing.assert_allclose(r["corrected"]["landing"][:2], r["first"]["landing"][:2], atol=0.05)
    with pytest.raises(ttmanip.TtmanipError, match="now"):
        ball.plan_correct(s, 0.23, [0.9, 0.0], s, t1 - 0.01, False)
