"""Exact feasibility and one truth for what a joint can do (issue 28, items 1–2): no ``ok`` hit
plan exceeds a position, velocity, acceleration, jerk or effort limit at any instant of a 10 kHz
sample; ``effort_ratio`` is the dense-sampled peak; gantry6's effective effort limits are within
what its drives deliver; ``ok`` plans track within the documented racket bound in the coupled
drive simulation."""

from __future__ import annotations

import numpy as np
import ttmanip
from ttmanip import robots

GANTRY = robots.gantry6()
JERK_PER_ACCELERATION = 200.0  # the planner's default jerk limit: 200 × the acceleration limit
RATE = 1e4  # the dense check's sample rate, Hz
#: The documented racket bound of the coupled simulation (docs/simulate.md): centre error (m),
#: face-normal error (°), relative racket-speed error.
RACKET_BOUND = (1e-3, 0.5, 0.02)


def random_problem(rng: np.random.Generator):
    """One random gantry6 hit drawn in joint space (the issue's form: the racket pose and twist of
    a configuration q moving at q̇, `Hit(fk(q), J(q)·q̇, t)`), half of them from a moving start
    (position, velocity and acceleration near the ready pose), with the profile "auto" (quintic or
    jerk-limited, whichever meets the time), "jerk" or "quintic"."""
    lo, hi = GANTRY.limits.T
    q = rng.uniform(np.maximum(lo, -2.0) * 0.8, np.minimum(hi, 2.0) * 0.8)
    qd = rng.uniform(-0.6, 0.6, 6) * GANTRY.velocity_limits
    t = rng.uniform(0.25, 0.9)
    hit = ttmanip.Hit(GANTRY.fk(q), GANTRY.jacobian(q) @ qd, t)
    ready = np.array([0.0, 0.0, 0.0, 0.6, 0.6, 0.0])
    if rng.random() < 0.5:
        state = None
    else:
        state = (
            ready + rng.uniform(-0.3, 0.3, 6),
            rng.uniform(-0.3, 0.3, 6) * GANTRY.velocity_limits,
            rng.uniform(-0.2, 0.2, 6) * GANTRY.acceleration_limits,
        )
    profile = ("auto", "auto", "jerk", "quintic")[rng.integers(4)]
    return hit, state, profile


def dense_excess(plan) -> dict[str, float]:
    """The largest ratio of each quantity to its limit over a 10 kHz sample of the stroke
    (position: the largest excess over the range in m or rad, 0 inside; jerk from differences
    of the sampled accelerations, a mean over each sample step, never above the true peak).
    "effort_knots" adds the stroke's knots and both sides of every zero crossing of a joint's
    speed to the instants: a jerk-limited leg's torque has a kink where its jerk switches, and
    the Coulomb friction steps where a speed crosses zero, and a peak there falls between 10 kHz
    samples by up to |dτ/dt|·50 µs (6e-3 of the limit seen)."""
    t, q, qd, qdd = plan.sample(RATE)
    tau = plan.torques(RATE)
    traj = plan.trajectory
    # Where a joint's speed crosses zero the Coulomb friction steps: the supremum is a one-sided
    # limit the samples step over. The crossings, bisected to 1e-8 s, evaluated 1e-8 s beyond either side.
    k, j = np.nonzero(np.sign(qd[:-1]) * np.sign(qd[1:]) < 0)
    lo, hi = t[k], t[k + 1]
    for _ in range(24):
        mid = 0.5 * (lo + hi)
        same = np.sign(traj.sample(mid)[1][np.arange(len(k)), j]) == np.sign(qd[k, j])
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    side = np.concatenate([lo - 1e-8, hi + 1e-8]).clip(0.0, traj.duration)
    times = np.concatenate([traj.knots, side])
    kq, kqd, kqdd = traj.sample(times)
    ktau = GANTRY.inverse_dynamics(kq, kqd, kqdd)
    at_knots = float(np.max(np.abs(ktau) / GANTRY.effort_limits_at(kqd)))
    lo, hi = GANTRY.limits.T
    jerk = np.diff(qdd, axis=0) * RATE
    j_lim = JERK_PER_ACCELERATION * GANTRY.acceleration_limits
    return {
        "position": float(np.max(np.maximum(q - hi, lo - q))),
        "velocity": float(np.max(np.abs(qd) / GANTRY.velocity_limits)),
        "acceleration": float(np.max(np.abs(qdd) / GANTRY.acceleration_limits)),
        "jerk": float(np.max(np.abs(jerk) / j_lim)),
        "effort": float(np.max(np.abs(tau) / GANTRY.effort_limits_at(qd))),
        "effort_knots": max(float(np.max(np.abs(tau) / GANTRY.effort_limits_at(qd))), at_knots),
    }


def plans(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        hit, state, profile = random_problem(rng)
        yield ttmanip.plan_hit(GANTRY, hit, state, profile=profile), state is not None


def test_no_feasible_plan_exceeds_a_limit_at_10_khz_and_effort_ratio_is_the_dense_peak_with_knots():
    """Every `ok` or `too_early` plan (a stroke the planner calls feasible, on time or late) of
    1,000 random hits (moving starts and both profiles) is within every limit at every 10 kHz
    sample, and every plan's `effort_ratio` is within 1e-3 of the peak of a *dense sample
    including knots*: the 10 kHz instants plus the stroke's knots and both sides of every zero
    crossing of a joint's speed. That is the sense in which issue 28's "effort_ratio equals the
    dense-sampled peak within 1e-3" holds: a plain 10 kHz sample steps over the peak by more than
    1e-3 on some plans (a jerk switch's kink, a Coulomb step at q̇ = 0; counted and printed), and
    the certified ratio is the true peak, not the sample's."""
    ok, moving, jerk_legs, worst_gap, stepped_over = 0, 0, 0, 0.0, 0
    for plan, moved in plans(1000, seed=28):
        if plan.trajectory is None:
            continue
        e = dense_excess(plan)
        # The certified peak: a value the stroke takes, within 1e-3 of the 10 kHz sample with
        # the knots, and never below it by more than the planner's tolerance (1e-4).
        gap = plan.effort_ratio - e["effort_knots"]
        stepped_over += e["effort_knots"] - e["effort"] > 1e-3
        worst_gap = max(worst_gap, abs(gap))
        assert -1.1e-4 <= gap <= 1e-3, (plan, plan.effort_ratio, e)
        if plan.status not in ("ok", "too_early"):
            continue
        ok += 1
        moving += moved
        jerk_legs += plan.profile == "jerk"
        assert e["position"] <= 1e-9, (plan, e)
        for name in ("velocity", "acceleration", "jerk", "effort"):
            assert e[name] <= 1 + 1e-9, (plan, name, e)
        assert plan.effort_ratio <= 1.0 + 1e-9
    # Enough of every kind of ok plan for the claim to mean something.
    assert ok >= 300 and moving >= 100 and jerk_legs >= 40 and ok - jerk_legs >= 50, (ok, moving, jerk_legs)
    assert worst_gap <= 1e-3, worst_gap
    print(f"{ok} feasible plans ({jerk_legs} jerk-limited, {moving} from a moving start); effort_ratio")
    print(f"within {worst_gap:.1e} of the dense peak; {stepped_over} peaks between the 10 kHz samples")


# The catalogue values of gantry6's drives (docs/drives.md, crates/ttkin/src/robots/drives.rs),
# one column per joint after the transpose: gear ratio G, torque constant k_t (N·m/A), peak
# current (A), gear efficiency η, bus voltage U (V), winding resistance R (Ω), nominal current
# I_nom (A), rated motor speed (rpm).
GANTRY_DRIVES = np.array(
    [
        [200, 0.45, 8.4, 0.9, 325, 2.3, 2.8, 6000],
        [200, 0.45, 8.4, 0.9, 325, 2.3, 2.8, 6000],
        [50, 60.3e-3, 9, 0.72, 48, 1.16, 3.0, 12000],
        [50, 60.3e-3, 9, 0.72, 48, 1.16, 3.0, 12000],
        [30, 25.9e-3, 10, 0.75, 24, 0.611, 3.44, 12000],
        [30, 43.9e-3, 3.6, 0.75, 24, 2.32, 1.2, 14000],
    ]
).T


def test_issue_example_is_not_ok_with_an_effort_above_its_limit():
    q = np.array([-0.3205, -0.2153, 0.7574, 1.3635, 2.3812, 1.0477])
    qd = np.array([0.0023, 0.8334, 2.1938, -4.7879, -3.9945, -9.3762])
    plan = ttmanip.plan_hit(GANTRY, ttmanip.Hit(GANTRY.fk(q), GANTRY.jacobian(q) @ qd, 0.7864))
    e = dense_excess(plan)
    assert abs(plan.effort_ratio - e["effort"]) <= 1e-3
    assert plan.status != "ok" or e["effort"] <= 1 + 1e-9, (plan.status, e)


def test_gantry6_effective_effort_limits_are_within_its_drives():
    g, kt, i_peak, eta, u_bus, r, _, _ = GANTRY_DRIVES
    peak = g * kt * i_peak * eta
    np.testing.assert_allclose(GANTRY.drive_effort_limits, peak, rtol=1e-12)
    eff = GANTRY.effective_effort_limits
    assert (eff <= peak * (1 + 1e-12)).all() and (eff <= GANTRY.effort_limits).all()
    np.testing.assert_allclose(eff, np.minimum(GANTRY.effort_limits, peak), rtol=1e-12)
    # θ3–θ6 are limited by their drives, the belt axes by the robot file.
    assert GANTRY.effort_limit_sources == ["robot file"] * 2 + ["drive peak current"] * 4
    # The bus voltage lowers the limit with speed: none left at θ6's no-load speed U/(k_e·G).
    no_load = u_bus[5] / (kt[5] * g[5])
    qd = np.zeros(6)
    qd[5] = 1.001 * no_load
    assert GANTRY.effort_limits_at(qd)[5] == 0.0
    many = np.outer(np.linspace(0, 1, 5), GANTRY.velocity_limits)
    limits = GANTRY.effort_limits_at(many)
    voltage = g * kt * eta * np.maximum(u_bus - kt * g * np.abs(many), 0.0) / r
    np.testing.assert_allclose(limits, np.minimum(eff, voltage), rtol=1e-12)
    assert limits.shape == (5, 6) and (np.diff(limits, axis=0) <= 0).all()


def test_info_shows_which_effort_limit_governs(capsys):
    from ttmanip.cli import main

    assert main(["info", "gantry6"]) == 0
    out = capsys.readouterr().out
    assert "drive peak current governs" in out and "robot file governs" in out


def test_gantry6_effective_velocity_limits_are_within_its_drives():
    # The drive's largest speed min(ω_rated, 0.9·(0.95·U − R·I_nom)/k_t)/G (ttkin::speed, also
    # ttcan::actuator's speed clamp).
    g, kt, _, _, u_bus, r, i_nom, rpm = GANTRY_DRIVES
    drive = np.minimum(rpm * np.pi / 30, 0.9 * (0.95 * u_bus - r * i_nom) / kt) / g
    np.testing.assert_allclose(GANTRY.drive_velocity_limits, drive, rtol=1e-12)
    eff = GANTRY.effective_velocity_limits
    np.testing.assert_allclose(eff, np.minimum(GANTRY.velocity_limits, drive), rtol=1e-12)
    # θ6's RE 25 on 24 V behind 30:1 reaches ≈ 13.6 rad/s, below the file's 20 rad/s.
    assert 13 < eff[5] < 14 and GANTRY.velocity_limit_sources[5] == "drive"
    assert GANTRY.velocity_limit_sources[:5] == ["robot file"] * 5


def test_info_shows_which_velocity_limit_governs(capsys):
    from ttmanip.cli import main

    assert main(["info", "gantry6"]) == 0
    out = capsys.readouterr().out
    assert "(drive governs)" in out and "13.6" in out


def test_ok_plans_track_within_the_racket_bound_in_the_coupled_simulation():
    checked, worst = 0, np.zeros(3)
    rng = np.random.default_rng(7)
    while checked < 100:
        hit, state, profile = random_problem(rng)
        plan = ttmanip.plan_hit(GANTRY, hit, state, profile=profile)
        if plan.status != "ok":
            continue
        sim = ttmanip.simulate(GANTRY, plan)
        errors = np.array(
            [sim.racket_position_error_m, sim.racket_normal_error_deg, sim.racket_velocity_error_rel]
        )
        worst = np.maximum(worst, errors)
        assert sim.faults == [""] * 6, (checked, sim.faults)
        assert (errors <= RACKET_BOUND).all(), (checked, errors)
        checked += 1
    assert checked == 100
    print(f"worst of 100 ok plans: {1e3 * worst[0]:.3f} mm, {worst[1]:.4f} deg, {100 * worst[2]:.3f} %")
