"""A simulated rally: incoming balls, camera, estimation, hit planning, stroke, scoring.

The heavy loop runs in Rust (``ttkin::ball::rally``, parallel over balls); this module collects
the per-ball outcomes into ``summary.json`` and figures. What executes the stroke: the planned
quintic stroke itself, exactly (no drive simulation); see ``docs/ball.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from . import _ttmanip as _t

__all__ = ["rally"]

# The rally's defaults are the core's (`ttkin::ball::rally::RallyConfig::default()`), not restated.
_RALLY = _t.ball_rally_config()
_TARGET: tuple[float, float] = tuple(_RALLY["target"])


def _median(a: np.ndarray) -> float | None:
    a = a[np.isfinite(a)]
    return float(np.median(a)) if a.size else None


def _progress(done: int, total: int) -> None:
    width = 30
    k = int(width * done / max(total, 1))
    sys.stderr.write(f"\rrally [{'#' * k}{'.' * (width - k)}] {done}/{total}")
    if done >= total:
        sys.stderr.write("\n")
    sys.stderr.flush()


def rally(
    n: int = 1000,
    seed: int = 0,
    *,
    target: tuple[float, float] = _TARGET,
    max_spin_rps: float = _RALLY["max_spin_rps"],
    out: str | Path | None = None,
    progress: bool = False,
    chunk: int = 1000,
    drives: int = 0,
    world: bool = False,
    incoming: np.ndarray | None = None,
    compare_world: bool = False,
    drive_execution: bool = False,
) -> dict:
    """Plays ``n`` balls (deterministic in ``seed``); returns the summary (and writes
    ``summary.json`` and figures into ``out`` when given).

    Summary keys: ``balls``, ``in_reach``, ``out_of_reach``, ``returned``, ``return_rate``
    (returned / in_reach; in reach by the robot's geometry and joint limits alone, see
    ``ttkin::ball::reach``: a return is possible), ``reach`` (counts of the region's verdicts, in
    the order checked, every one present: ``no_bounce``, ``outside_volume``, ``no_return`` (no
    shot of the grid lands on the opponent's half), ``no_return_pose`` (no racket pose for a
    return shot within the joint position limits), ``return_speed`` (the joint velocities
    q̇ = J⁻¹·V of every such pose above their limits), ``too_early`` (not in the time left),
    ``in_reach``), ``returned_out_of_reach``,
    ``racket_error_m_median``,
    ``landing_error_m_median``, ``velocity_error_mps_median``, ``plan_time_us_median`` (per-ball
    planning in thread CPU time, from the parallel batch), ``plan_wall_time_us_median``,
    ``correction_time_us_median`` (the one correction after the bounce during the stroke: the
    estimate updated through the bounce and the re-plan, thread CPU time, over the balls that had
    one), ``statuses`` (counts of every outcome, in reach or not) and the stated simulation settings.

    ``drives`` > 0 also executes that many in-reach balls through the drives: the hit planned from
    the ball's true state (``ball.plan_return``) goes to ``plan_hit`` and ``simulate`` (coupled drive
    simulation on the rigid-body dynamics); ``drive_*`` keys report the racket's pose and velocity
    error at the hit against the plan, i.e. how far the exactly executed stroke of the rally is
    from a driven one (about 60 ms per ball, hence a subset).

    ``world=True`` plays every ball in a world the planner does not know (``ttkin::ball::rally::
    WorldSpread::measured``: per-ball drag, Magnus, restitution and friction drawn around the
    planner's measured constants within the spreads measured between the ball-gun groups, and a
    camera time-stamp error of up to ±3 ms); the balls themselves are the same as without.
    ``incoming`` (N, 10) gives the balls (``[t, p, v, w]`` at the opponent's hit, e.g. recorded
    shots; ``n`` ≤ N) instead of drawing them. ``compare_world=True`` plays the same balls in both
    worlds and adds ``world_comparison`` (return rates side by side) to the summary, whose other
    keys are those of the world asked for. ``drive_execution=True`` executes every planned stroke
    through the coupled drive simulation (``ttcan::coupled::execute``: a fresh simulation per
    stroke, inverse-dynamics feed-forward, setpoints at 1 kHz) instead of exactly; the racket meets
    the ball where the driven joints put it.
    """
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise _t.TtmanipError(f"n: must be a positive integer, got {n!r}")
    if n > _t.MAX_RALLY_BALLS:
        # Checked before the first chunk: the chunks would otherwise step around the binding's
        # limit (rally(10**12) ran for ever).
        raise _t.TtmanipError(f"n: at most {_t.MAX_RALLY_BALLS} balls per rally, got {n}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise _t.TtmanipError(f"seed: must be a non-negative integer, got {seed!r}")
    if not isinstance(chunk, (int, np.integer)) or isinstance(chunk, bool) or chunk < 1:
        raise _t.TtmanipError(f"chunk: must be a positive integer, got {chunk!r}")
    if not isinstance(drives, (int, np.integer)) or isinstance(drives, bool) or drives < 0:
        raise _t.TtmanipError(f"drives: must be a non-negative integer, got {drives!r}")
    for what, flag in (
        ("world", world),
        ("compare_world", compare_world),
        ("drive_execution", drive_execution),
    ):
        if not isinstance(flag, (bool, np.bool_)):
            raise _t.TtmanipError(f"{what}: must be True or False, got {flag!r}")
    if not isinstance(progress, (bool, np.bool_)):
        raise _t.TtmanipError(f"progress: must be True or False, got {progress!r}")
    try:
        target = tuple(float(v) for v in _t.real_array(target, "target").reshape(-1))
        spin = _t.real_array(max_spin_rps, "max_spin_rps").reshape(-1)
        if spin.size != 1:
            raise TypeError("max_spin_rps: one number")
        max_spin_rps = float(spin[0])
    except (TypeError, ValueError, OverflowError):
        raise _t.TtmanipError(
            f"target, max_spin_rps: expected (x, y) in m and a number in rev/s, got {target!r}, "
            f"{max_spin_rps!r}"
        ) from None
    if len(target) != 2:
        raise _t.TtmanipError(
            f"target: expected (x, y) on the opponent's half in m, got {len(target)} values"
        )
    if incoming is not None:
        try:
            # the bindings' one conversion: complex, boolean and string arrays are refused, not cast
            incoming = _t.real_array(incoming, "incoming")
        except (TypeError, ValueError):
            raise _t.TtmanipError(
                f"incoming: expected an (N, 10) array of ball states, got {incoming!r}"
            ) from None
        if incoming.ndim != 2 or incoming.shape[1] != 10 or len(incoming) < n:
            raise _t.TtmanipError(
                f"incoming: expected ({n}, 10) or more rows of [t, p, v, w], got shape {incoming.shape}"
            )
    comparison = None
    if compare_world:
        other = rally(
            n, seed, target=target, max_spin_rps=max_spin_rps, chunk=chunk, world=not world, incoming=incoming
        )
        comparison = other
    parts = []
    for start in range(0, n, chunk):
        m = min(chunk, n - start)
        parts.append(
            _t.ball_rally(
                m,
                int(seed),
                start,
                (float(target[0]), float(target[1])),
                float(max_spin_rps),
                5 if start == 0 else 0,
                bool(world),
                incoming,
                bool(drive_execution),
            )
        )
        if progress:
            _progress(start + m, n)
    res = {
        k: np.concatenate([np.asarray(p[k]) for p in parts])
        for k in parts[0]
        if k not in ("paths", "reach_names", "in_reach_definition")
    }
    # The extension gives the paths' serde form (lists of points); here as (K, 3) arrays.
    res["paths"] = [
        {
            **p,
            "ball": np.asarray(p["ball"], float).reshape(-1, 3),
            "racket": np.asarray(p["racket"], float).reshape(-1, 3),
        }
        for p in parts[0]["paths"]
    ]
    in_reach = res["in_reach"].astype(bool)
    returned = res["returned"].astype(bool) & in_reach
    stats = _t.ball_rally_stats(
        in_reach.tolist(),
        res["returned"].astype(bool).tolist(),
        res["reach"].tolist(),
        res["status"].tolist(),
        res["racket_error"],
        res["plan_time_us"],
        res["plan_wall_time_us"],
        res["correction_time_us"],
        res["landing_error"],
        res["velocity_error"],
    )
    summary = {
        "balls": stats["balls"],
        "seed": int(seed),
        "in_reach": stats["in_reach"],
        "out_of_reach": stats["out_of_reach"],
        "returned": stats["returned"],
        "return_rate": stats["return_rate"],
        "returned_out_of_reach": stats["returned_out_of_reach"],
        # every verdict of the region, counted (0 when none): the reasons a ball is out of reach
        "reach": dict(stats["reach"]),
        # the region's own sentence, written from its grids (ttkin::ball::reach::ReachRegion::definition)
        "in_reach_definition": parts[0]["in_reach_definition"],
        "racket_error_m_median": stats["racket_error_m_median"],
        "plan_time_us_median": stats["plan_time_us_median"],  # thread CPU time
        "plan_wall_time_us_median": stats["plan_wall_time_us_median"],
        # the one correction after the bounce (estimate updated through it, re-plan from the
        # stroke's state), during the stroke: thread CPU time, balls that had one
        "correction_time_us_median": stats["correction_time_us_median"],
        "landing_error_m_median": stats["landing_error_m_median"],
        "velocity_error_mps_median": stats["velocity_error_mps_median"],
        "statuses": stats["statuses"],
        "target": list(map(float, target)),
        "max_spin_rps": float(max_spin_rps),
        "camera": _camera_summary(),
        "stroke_execution": (
            "every stroke through the coupled drive simulation (ttcan::coupled::execute)"
            if drive_execution
            else "planned hit leg (quintic, else jerk-limited) executed exactly"
        )
        + "; drive_* keys: a subset through plan_hit + simulate (coupled drive simulation)",
        "world": "per-ball constants drawn around the planner's (WorldSpread::measured) and camera "
        "time-stamp error up to +-3 ms"
        if world
        else "the planner's model",
        "incoming": "given" if incoming is not None else "drawn (ttkin::ball::rally::serve)",
    }
    if comparison is not None:
        mine = "mismatched" if world else "matched"
        theirs = "matched" if world else "mismatched"
        keys = ("in_reach", "returned", "return_rate", "returned_out_of_reach")
        summary["world_comparison"] = {
            "balls": int(n),
            mine: {k: summary[k] for k in keys},
            theirs: {k: comparison[k] for k in keys},
            "same_balls": bool(np.array_equal(comparison["results"]["incoming"], res["incoming"])),
        }
    if drives > 0:
        summary.update(_drive_check(res, in_reach, int(drives)))
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        summary["figures"] = _figures(res, in_reach, returned, target, out)
        (out / "summary.json").write_text(json.dumps(summary, indent=2))
    summary["results"] = res
    return summary


def _camera_summary() -> dict:
    """The rally's camera as the summary reports it: the core's defaults
    (``ttkin::ball::rally::Camera::default``), with units in the keys."""
    c = _t.ball_camera()
    return {
        "rate_hz": c["rate_hz"],
        "latency_s": c["latency"],
        "noise_m": c["noise"],
        "outliers": c["outlier_rate"],
        "window_s": c["window"],
    }


def _drive_check(res: dict, in_reach: np.ndarray, count: int) -> dict:
    from . import ball, plan_hit, robots, simulate

    robot = robots.gantry6()
    pos, ang, vel, ok = [], [], [], 0
    for k in np.flatnonzero(in_reach)[:count]:
        d = ball.plan_return(res["incoming"][k], 0.23)
        if d["status"] != "ok":
            continue
        plan = plan_hit(robot, d["hit"], d["ready"])
        if not plan.ok:
            continue
        ok += 1
        sim = simulate(robot, plan)
        pos.append(sim.racket_position_error_m)
        ang.append(sim.racket_normal_error_deg)
        vel.append(sim.racket_velocity_error_mps)
    return {
        "drive_balls": ok,
        "drive_racket_position_error_m_median": _median(np.array(pos)),
        "drive_racket_normal_error_deg_median": _median(np.array(ang)),
        "drive_racket_velocity_error_mps_median": _median(np.array(vel)),
        "drive_racket_position_error_m_max": float(max(pos)) if pos else None,
    }


def _table(ax) -> None:
    """The table from above: its outline and the net (the core's ``Table::outline``)."""
    from .ball import Table

    o = Table().outline()
    ax.plot(o["surface"][:, 0], o["surface"][:, 1], "k-", lw=1)
    ax.plot(o["net"][:, 0], o["net"][:, 1], "k-", lw=2)


def _figures(res: dict, in_reach: np.ndarray, returned: np.ndarray, target, out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from . import robots
    from .ball import Table

    paths = []
    fig, ax = plt.subplots(figsize=(8, 5), constrained_layout=True)
    _table(ax)
    land = res["landing"]
    ok = np.isfinite(land[:, 0])
    ax.scatter(land[ok & returned, 0], land[ok & returned, 1], s=3, alpha=0.4, label="returned")
    bad = ok & ~returned & in_reach
    ax.scatter(land[bad, 0], land[bad, 1], s=6, color="C3", label="landed off the opponent's half")
    ax.plot(*target, "k+", ms=14, label="target")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (toward the opponent)")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("landing points of the returns (world frame, table from above)")
    paths.append(out / "rally_landing.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig = plt.figure(figsize=(9, 6), constrained_layout=True)
    ax = fig.add_subplot(projection="3d")
    outline = Table().outline()
    ax.add_collection3d(Poly3DCollection([outline["surface"][:4]], alpha=0.15, color="C2"))
    ax.plot(*outline["net"].T, "k-")
    # the gantry's travel: its d1 × d2 position limits along the prismatic axes (the Jacobian's
    # first two columns, base frame) from the base origin, placed in the world frame
    gantry = robots.gantry6()
    lim, axes = gantry.limits, gantry.jacobian(np.zeros(gantry.dof))[:3, :2]
    ends = ((0, 0), (1, 0), (1, 1), (0, 1), (0, 0))
    corners = [lim[0, a] * axes[:, 0] + lim[1, b] * axes[:, 1] for a, b in ends]
    travel = np.column_stack([corners, np.ones(5)]) @ _t.ball_placement().T
    ax.plot(*travel[:, :3].T, "k--", lw=1, label="gantry axes (d1 × d2)")
    for k, p in enumerate(res["paths"]):
        b, r = p["ball"], p["racket"]
        ax.plot(b[:, 0], b[:, 1], b[:, 2], color=f"C{k}", lw=1, label=f"ball {k}: {p['status']}")
        if len(r):
            ax.plot(r[:, 0], r[:, 1], r[:, 2], color=f"C{k}", lw=2, ls=":")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("ball flights (solid) and racket-centre paths (dotted)")
    ax.legend(fontsize=7)
    paths.append(out / "rally_trajectories.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    inc = res["incoming"]
    speed = np.linalg.norm(inc[:, 4:7], axis=1)
    spin = np.linalg.norm(inc[:, 7:10], axis=1) / (2 * np.pi)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for ax, x, name in ((axes[0], speed, "incoming speed [m/s]"), (axes[1], spin, "incoming spin [rev/s]")):
        edges = (
            np.linspace(x[in_reach].min(), x[in_reach].max(), 9) if in_reach.any() else np.linspace(0, 1, 9)
        )
        idx = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
        rate = [
            returned[in_reach & (idx == b)].sum() / max((in_reach & (idx == b)).sum(), 1)
            for b in range(len(edges) - 1)
        ]
        ax.bar(0.5 * (edges[:-1] + edges[1:]), rate, width=np.diff(edges) * 0.9)
        ax.set_ylim(0, 1.05)
        ax.set_xlabel(name)
        ax.set_ylabel("return rate (in reach)")
        ax.grid(alpha=0.3)
    paths.append(out / "rally_rate.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return [str(p) for p in paths]
