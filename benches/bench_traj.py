"""Hitting strokes and quintic sampling from Python: ttmanip beside ruckig.

Same problems for both: an 8-joint arm at a random current state (q, q̇, q̈) must reach a hit state
(q_hit, q̇_hit, q̈_hit = 0) and then rest at a ready pose, under per-joint velocity, acceleration and
jerk limits.

- ttmanip plans each leg as one quintic per joint (the patent's step S104) and moves the hit time to
  the earliest feasible one (root bracketing on the duration, exact quintic extrema).
- ruckig (community version) plans the time-optimal jerk-limited trajectory of each leg.

A quintic is one fixed shape per joint, so its minimal duration is never below ruckig's time-optimal
one; the table shows by how much. "on time" asks whether a requested hit time of 0.5 s is kept
(ruckig: ``minimum_duration`` = 0.5 s and a result of exactly 0.5 s). Also timed: building an
8-joint quintic and sampling 101 points (numpy reference implementation beside the native call).

Run: ``.venv/bin/python benches/bench_traj.py`` (peer: ``pip install ruckig``).
"""

from __future__ import annotations

import numpy as np
import ttmanip.traj as tt
from timing import per_call_us

try:
    import ruckig
except ImportError:  # pragma: no cover - optional peer
    ruckig = None

DOF = 8
VMAX = np.full(DOF, 4.0)
AMAX = np.full(DOF, 40.0)
JMAX = np.full(DOF, 800.0)
T_REQUEST = 0.5


def problems(count: int, seed: int = 1) -> list[dict[str, np.ndarray]]:
    """Random hitting problems within the limits."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        out.append(
            {
                "q": rng.uniform(-0.5, 0.5, DOF),
                "qd": rng.uniform(-0.5, 0.5, DOF),
                "qdd": rng.uniform(-2.0, 2.0, DOF),
                "q_hit": rng.uniform(-1.0, 1.0, DOF),
                "qd_hit": rng.uniform(-2.5, 2.5, DOF),
                "ready": np.zeros(DOF),
            }
        )
    return out


def ttmanip_stroke(p: dict, t_hit: float) -> tt.Stroke:
    return tt.stroke(
        None,
        (p["q"], p["qd"], p["qdd"]),
        p["q_hit"],
        p["qd_hit"],
        t_hit,
        p["ready"],
        velocity=VMAX,
        acceleration=AMAX,
        jerk=JMAX,
    )


def ruckig_leg(start, target, minimum_duration: float | None = None):
    """(duration, result) of ruckig's time-optimal leg from ``start`` to ``target`` (q, qd, qdd)."""
    otg = ruckig.Ruckig(DOF)
    inp = ruckig.InputParameter(DOF)
    inp.current_position, inp.current_velocity, inp.current_acceleration = (list(x) for x in start)
    inp.target_position, inp.target_velocity, inp.target_acceleration = (list(x) for x in target)
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(VMAX), list(AMAX), list(JMAX)
    if minimum_duration is not None:
        inp.minimum_duration = minimum_duration
    traj = ruckig.Trajectory(DOF)
    result = otg.calculate(inp, traj)
    return traj.duration, result


def compare_strokes(count: int = 10) -> None:
    rows = []
    zeros = np.zeros(DOF)
    for i, p in enumerate(problems(count)):
        start = (p["q"], p["qd"], p["qdd"])
        hit = (p["q_hit"], p["qd_hit"], zeros)
        earliest = ttmanip_stroke(p, 1e-3)
        on_time = ttmanip_stroke(p, T_REQUEST)
        row = {
            "problem": i,
            "tt_hit": earliest.t_hit,
            "tt_back": earliest.return_duration,
            "tt_on_time": on_time.on_time and on_time.feasible,
            "tt_us": per_call_us(lambda p=p: ttmanip_stroke(p, 1e-3), number=50),
        }
        if ruckig is not None:
            t_hit, res = ruckig_leg(start, hit)
            t_back, _ = ruckig_leg(hit, (p["ready"], zeros, zeros))
            t_req, res_req = ruckig_leg(start, hit, T_REQUEST)
            row.update(
                {
                    "rk_hit": t_hit
                    if res == ruckig.Result.Working or res == ruckig.Result.Finished
                    else np.nan,
                    "rk_back": t_back,
                    "rk_on_time": abs(t_req - T_REQUEST) < 1e-9,
                    "rk_us": per_call_us(lambda s=start, h=hit: ruckig_leg(s, h), number=200)
                    + per_call_us(lambda h=hit, r=p["ready"]: ruckig_leg(h, (r, zeros, zeros)), number=200),
                }
            )
        rows.append(row)

    print(f"\nHitting strokes, {DOF} joints, |q̇| ≤ 4 rad/s, |q̈| ≤ 40 rad/s², |jerk| ≤ 800 rad/s³")
    print(
        "durations in s (hit leg / return leg); on time = requested t_hit = "
        f"{T_REQUEST} s kept within limits; planning time per stroke in µs"
    )
    head = f"{'#':>2} | {'ttmanip quintic':>17} | {'ruckig optimal':>17} | {'hit ratio':>9} | "
    head += f"{'on time tt/rk':>13} | {'µs tt':>7} | {'µs rk':>7}"
    print(head)
    print("-" * len(head))
    for r in rows:
        rk = f"{r['rk_hit']:.4f} / {r['rk_back']:.4f}" if "rk_hit" in r else "n/a"
        ratio = f"{r['tt_hit'] / r['rk_hit']:.3f}" if "rk_hit" in r else "n/a"
        rk_on = ("yes" if r.get("rk_on_time") else "no") if "rk_hit" in r else "n/a"
        on = f"{'yes' if r['tt_on_time'] else 'no':>3} / {rk_on}"
        rk_us = f"{r['rk_us']:7.1f}" if "rk_us" in r else "    n/a"
        print(
            f"{r['problem']:>2} | {r['tt_hit']:.4f} / {r['tt_back']:.4f} | {rk:>17} | {ratio:>9} | "
            f"{on:>13} | {r['tt_us']:7.1f} | {rk_us}"
        )
    if ruckig is not None:
        ratios = np.array([r["tt_hit"] / r["rk_hit"] for r in rows])
        print(
            f"quintic hit time / ruckig time-optimal: median {np.median(ratios):.3f}, "
            f"range {ratios.min():.3f}–{ratios.max():.3f}"
        )


def quintic_numpy(q0, q1, tf, n):
    """Reference: rest-to-rest quintic sampled with numpy (the ≈34 µs baseline of issue 5)."""
    t = np.linspace(0.0, tf, n)
    tau = (t / tf)[:, None]
    h = (q1 - q0)[None, :]
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    sd = 30 * tau**2 * (1 - tau) ** 2 / tf
    sdd = 60 * tau * (1 - tau) * (1 - 2 * tau) / tf**2
    return t, q0 + h * s, h * sd, h * sdd


def compare_sampling() -> None:
    q0, q1 = np.linspace(0.0, 1.0, DOF), np.linspace(1.0, -1.0, DOF)
    t, q, qd, qdd = tt.quintic_samples(q0, q1, 0.8, 101)
    tn, qn, qdn, qddn = quintic_numpy(q0, q1, 0.8, 101)
    assert np.abs(q - qn).max() < 1e-12 and np.abs(qdd - qddn).max() < 1e-10
    print("\nBuild an 8-joint quintic and sample 101 points (µs per call, median)")
    one_call = per_call_us(lambda: tt.quintic_samples(q0, q1, 0.8, 101), 20000)
    two_calls = per_call_us(lambda: tt.quintic(q0, q1, 0.8).sample_uniform(101), 20000)
    numpy_ref = per_call_us(lambda: quintic_numpy(q0, q1, 0.8, 101), 5000)
    print(f"  ttmanip.traj.quintic_samples     {one_call:7.2f}")
    print(f"  ttmanip quintic + sample_uniform {two_calls:7.2f}")
    print(f"  numpy closed form                {numpy_ref:7.2f}")
    if ruckig is not None:
        zeros = np.zeros(DOF)

        def rk():
            otg = ruckig.Ruckig(DOF)
            inp = ruckig.InputParameter(DOF)
            inp.current_position, inp.target_position = list(q0), list(q1)
            inp.current_velocity = inp.current_acceleration = list(zeros)
            inp.target_velocity = inp.target_acceleration = list(zeros)
            inp.max_velocity, inp.max_acceleration, inp.max_jerk = list(VMAX), list(AMAX), list(JMAX)
            traj = ruckig.Trajectory(DOF)
            otg.calculate(inp, traj)
            return [traj.at_time(ti) for ti in np.linspace(0.0, traj.duration, 101)]

        rk_us = per_call_us(rk, 500)
        print(f"  ruckig calculate + 101 at_time   {rk_us:7.2f}  (time-optimal, not a quintic)")


if __name__ == "__main__":
    compare_sampling()
    compare_strokes()
