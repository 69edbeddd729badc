"""Design studies on Dask (issue 31): ``ttmanip.sweep(...)`` and ``ttmanip sweep``.

A study evaluates many trials at each point of a design (a grid or random points over named
parameters). The trials of a point are cut into chunks; one chunk is one Dask task (seconds of
work), so a sweep spreads over every worker of a ``LocalCluster`` (default) or of any running Dask
scheduler (``scheduler="tcp://host:8786"``). Every task draws its random numbers from its own seed,
``SeedSequence([seed, point, chunk])`` (the rally: balls by index), and the per-point numbers are
summed in task order, so the same sweep gives identical numbers on any number of workers, and
with ``scheduler="serial"`` (no Dask, in this process).

Studies (all maths in Rust; this module only makes inputs and counts outcomes):

- ``hits``: gantry6 with its base moved by ``base_x``, ``base_y`` (m, base frame) and drives
  ``drive_scale`` times as capable (velocity, acceleration and effort limits), random hits
  around the demo hit (centre ± 0.15 m, face normal ± 0.2, time 0.3–0.6 s) with racket speed
  ``speed`` (m/s, ± 10 %); rate = share of ``plan_hits`` plans that are ok.
- ``rally``: the simulated rally (``ttmanip.rally``) with return target ``target_x``, ``target_y``
  (m) and incoming spin up to ``max_spin_rps``; rate = returned / in reach.

Dask is the optional extra ``ttmanip[sweep]`` (``dask``, ``distributed``); results are a CSV (and
a Parquet file when ``pyarrow`` is installed) and a matplotlib figure. See ``docs/sweep.md``.
"""

from __future__ import annotations

import csv
import itertools
import sys
import time
from pathlib import Path

import numpy as np

from . import _ttmanip as _t

__all__ = ["sweep", "STUDIES"]

_RALLY = _t.ball_rally_config()  # the rally study's defaults: RallyConfig::default()'s

#: Study name -> (its parameters with their defaults, trials per point by default, trials per task).
STUDIES: dict[str, tuple[dict[str, float], int, int]] = {
    "hits": ({"base_x": 0.0, "base_y": 0.0, "speed": 3.0, "drive_scale": 1.0}, 10000, 10000),
    "rally": (
        {
            "target_x": _RALLY["target"][0],
            "target_y": _RALLY["target"][1],
            "max_spin_rps": _RALLY["max_spin_rps"],
        },
        400,
        200,
    ),
}


#: Units of the study parameters, for the figure's axes.
UNITS = {
    "base_x": "m",
    "base_y": "m",
    "speed": "m/s",
    "drive_scale": "×",
    "target_x": "m",
    "target_y": "m",
    "max_spin_rps": "rev/s",
}


def _scaled_drives(robot, scale: float):
    """``robot`` with drives ``scale`` times as capable: its robot file with every joint's velocity,
    acceleration and effort limit multiplied by ``scale`` (> 0)."""
    import re

    from . import Robot

    if not (np.isfinite(scale) and scale > 0):
        raise _t.TtmanipError(f"drive_scale: expected a finite factor > 0, got {scale}")

    def times(m: re.Match) -> str:
        return f"{m[1]} = {float(m[2]) * scale!r}"

    return Robot.from_toml(re.sub(r"(?m)^(velocity|acceleration|effort) = (\S+)$", times, robot.to_toml()))


def _hits_task(p: dict[str, float], count: int, seed: list[int]) -> dict[str, float]:
    """One chunk of the ``hits`` study: ``count`` random hits planned for the moved gantry6."""
    from . import Hit, plan_hits, robots
    from .pipeline import DEMO_HIT

    rng = np.random.default_rng(np.random.SeedSequence(seed))
    robot = robots.gantry6()
    if p["drive_scale"] != 1.0:
        robot = _scaled_drives(robot, p["drive_scale"])
    shift = np.eye(4)
    shift[:2, 3] = p["base_x"], p["base_y"]
    robot = robot.with_base(shift @ robot.base)
    centres = DEMO_HIT.centre + rng.uniform(-0.15, 0.15, (count, 3))
    normals = DEMO_HIT.normal + rng.uniform(-0.2, 0.2, (count, 3))
    speeds = p["speed"] * rng.uniform(0.9, 1.1, count)
    times = rng.uniform(0.3, 0.6, count)
    hits = [
        Hit.from_normal(c, nrm, s * nrm / np.linalg.norm(nrm), t)
        for c, nrm, s, t in zip(centres, normals, speeds, times, strict=True)
    ]
    plans = plan_hits(robot, hits)
    ok = [pl.ok for pl in plans]
    return {
        "trials": count,
        "ok": int(sum(ok)),
        "unreachable": sum(pl.status == "unreachable" for pl in plans),
        "too_early": sum(pl.status == "too_early" for pl in plans),
        "hit_speed_limit": sum(pl.status == "hit_speed_limit" for pl in plans),
        "effort_ratio_sum": float(sum(pl.effort_ratio for pl, k in zip(plans, ok, strict=True) if k)),
    }


def _rally_task(p: dict[str, float], count: int, seed: list[int], start: int) -> dict[str, float]:
    """One chunk of the ``rally`` study: balls ``start`` .. ``start + count`` of the rally."""
    r = _t.ball_rally(count, seed[0], start, (p["target_x"], p["target_y"]), p["max_spin_rps"], 0)
    in_reach = np.asarray(r["in_reach"]).astype(bool)
    returned = np.asarray(r["returned"]).astype(bool) & in_reach
    return {"trials": count, "in_reach": int(in_reach.sum()), "ok": int(returned.sum())}


def _task(study: str, point: dict[str, float], count: int, seed: int, index: int, chunk: int, first: int):
    """The task a worker runs: chunk ``chunk`` (trials ``first`` ..) of design point ``index``."""
    if study == "hits":
        return _hits_task(point, count, [seed, index, chunk])
    return _rally_task(point, count, [seed], first)


def design_points(
    params: dict[str, object], design: str = "grid", points: int = 8, seed: int = 0, study: str = "hits"
) -> list[dict[str, float]]:
    """The design: a grid over the listed values of each parameter (``{"speed": [2, 4]}``), or
    ``points`` random points drawn uniformly in the ``(low, high)`` range of each; parameters not
    given keep the study's default."""
    if study not in STUDIES:
        raise _t.TtmanipError(f"study: expected one of {sorted(STUDIES)}, got {study!r}")
    defaults = STUDIES[study][0]
    unknown = sorted(set(params) - set(defaults))
    if unknown:
        raise _t.TtmanipError(
            f"params: {unknown[0]!r} is not a parameter of '{study}' (expected {sorted(defaults)})"
        )
    if design == "grid":
        names = list(params)
        values = []
        for k in names:
            v = np.atleast_1d(np.asarray(params[k], dtype=float))
            if v.ndim != 1 or v.size == 0 or not np.isfinite(v).all():
                raise _t.TtmanipError(f"params[{k!r}]: expected a non-empty list of finite numbers")
            values.append(v)
        return [
            {**defaults, **dict(zip(names, map(float, combo), strict=True))}
            for combo in itertools.product(*values)
        ]
    if design == "random":
        if not isinstance(points, int) or points < 1:
            raise _t.TtmanipError(f"points: expected a positive integer, got {points!r}")
        rng = np.random.default_rng(np.random.SeedSequence([seed, 0x5EED]))
        ranges = {}
        for k, v in params.items():
            lo_hi = np.asarray(v, dtype=float)
            if lo_hi.shape != (2,) or not np.isfinite(lo_hi).all() or lo_hi[0] > lo_hi[1]:
                raise _t.TtmanipError(f"params[{k!r}]: a random design needs a (low, high) range, got {v!r}")
            ranges[k] = lo_hi
        draws = {k: rng.uniform(lo, hi, points) for k, (lo, hi) in ranges.items()}
        return [{**defaults, **{k: float(d[i]) for k, d in draws.items()}} for i in range(points)]
    raise _t.TtmanipError(f"design: expected 'grid' or 'random', got {design!r}")


def _progress(done: int, total: int, t0: float) -> None:
    width = 30
    k = width * done // max(total, 1)
    sys.stderr.write(
        f"\rsweep [{'#' * k}{'.' * (width - k)}] {done}/{total} tasks {time.perf_counter() - t0:6.1f} s"
    )
    if done >= total:
        sys.stderr.write("\n")
    sys.stderr.flush()


def _client(scheduler, workers: int):
    """A Dask client: on the scheduler at ``scheduler`` (an address), or on a new LocalCluster of
    ``workers`` single-threaded worker processes (one Rust thread each: RAYON_NUM_THREADS=1)."""
    try:
        import distributed
    except ImportError:
        raise _t.TtmanipError(
            "sweep: Dask is not installed; pip install 'ttmanip[sweep]' (or use scheduler='serial')"
        ) from None
    if scheduler is not None:
        return distributed.Client(scheduler), None
    cluster = distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env={"RAYON_NUM_THREADS": "1"},
    )
    return distributed.Client(cluster), cluster


def sweep(
    study: str = "hits",
    params: dict[str, object] | None = None,
    *,
    design: str = "grid",
    points: int = 8,
    n: int | None = None,
    chunk: int | None = None,
    seed: int = 0,
    scheduler: str | None = None,
    workers: int = 2,
    out: str | Path | None = None,
    progress: bool = False,
) -> dict:
    """Runs a design study as Dask tasks; returns ``{"rows": [...], "files": {...}, "tasks",
    "workers", "wall_s"}``, one row per design point (its parameters, ``trials``, ``ok``,
    ``rate`` and the study's counts).

    ``study``: ``"hits"`` or ``"rally"`` (module doc); ``params``: parameter -> values (grid) or
    (low, high) (``design="random"``, ``points`` points); ``n`` trials per point in chunks of
    ``chunk`` (one task each); ``scheduler``: None for a LocalCluster of ``workers`` processes, a
    Dask scheduler address (``"tcp://host:8786"``), or ``"serial"`` (this process, no Dask);
    ``out``: a directory for ``sweep.csv`` (+ ``sweep.parquet`` with pyarrow) and ``sweep.png``.
    """
    if study not in STUDIES:
        raise _t.TtmanipError(f"study: expected one of {sorted(STUDIES)}, got {study!r}")
    _, n_default, chunk_default = STUDIES[study]
    n = n_default if n is None else n
    chunk = chunk_default if chunk is None else chunk
    for what, v in (("n", n), ("chunk", chunk), ("workers", workers)):
        if not isinstance(v, int | np.integer) or isinstance(v, bool) or v < 1:
            raise _t.TtmanipError(f"{what}: expected a positive integer, got {v!r}")
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or seed < 0:
        raise _t.TtmanipError(f"seed: expected a non-negative integer, got {seed!r}")
    pts = design_points(params or {}, design, points, int(seed), study)
    tasks = [
        (study, p, min(chunk, n - first), int(seed), i, c, first)
        for i, p in enumerate(pts)
        for c, first in enumerate(range(0, n, chunk))
    ]
    t0 = time.perf_counter()
    results: list[dict | None] = [None] * len(tasks)
    if scheduler == "serial":
        used = 1
        for k, args in enumerate(tasks):
            results[k] = _task(*args)
            if progress:
                _progress(k + 1, len(tasks), t0)
    else:
        import distributed

        client, cluster = _client(scheduler, workers)
        t0 = time.perf_counter()  # the cluster is up: wall_s is the work's time
        futures = []
        try:
            used = len(client.scheduler_info()["workers"])
            for k, args in enumerate(tasks):
                futures.append(client.submit(_task, *args, pure=False, key=f"ttmanip-sweep-{k}"))
            index = {f.key: k for k, f in enumerate(futures)}
            for done, f in enumerate(distributed.as_completed(futures), start=1):
                results[index[f.key]] = f.result()
                if progress:
                    _progress(done, len(tasks), t0)
        except BaseException:
            # Ctrl-C (or a failed task): the tasks still queued are dropped at once, so that the
            # cluster closes without running them (20 000 points queued minutes of work)
            if futures:
                client.cancel(futures)
            raise
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    wall = time.perf_counter() - t0
    rows = []
    for i, p in enumerate(pts):
        total: dict[str, float] = {}
        for (_, _, _, _, j, _, _), r in zip(tasks, results, strict=True):
            if j == i:  # summed in task order: the same numbers on any number of workers
                for k, v in r.items():
                    total[k] = total.get(k, 0) + v
        base = total.get("in_reach", total["trials"])
        rows.append({**p, **total, "rate": total["ok"] / base if base else float("nan")})
    files = _write(rows, study, Path(out)) if out is not None else {}
    return {"rows": rows, "files": files, "tasks": len(tasks), "workers": used, "wall_s": wall}


def _write(rows: list[dict], study: str, out: Path) -> dict[str, str]:
    """sweep.csv (+ sweep.parquet with pyarrow) and sweep.png in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    files = {"csv": str(out / "sweep.csv")}
    with open(files["csv"], "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: repr(v) if isinstance(v, float) else v for k, v in r.items()})
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        pass
    else:
        files["parquet"] = str(out / "sweep.parquet")
        pq.write_table(pa.table({k: [r[k] for r in rows] for k in rows[0]}), files["parquet"])
    files["figure"] = str(out / "sweep.png")
    figure(rows, study, files["figure"])
    return files


def figure(rows: list[dict], study: str, path: str | Path) -> Path:
    """The rate over the design. A grid: a heat map over the two most varied parameters, one panel
    per value of a third (up to 4 panels; the mean over any further one); one parameter: a line;
    a random design: markers coloured by rate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [k for k in STUDIES[study][0] if len({r[k] for r in rows}) > 1]
    names.sort(key=lambda k: -len({r[k] for r in rows}))
    label = "return rate (in reach)" if study == "rally" else "share of ok plans"
    title = f"ttmanip sweep: {study}, {len(rows)} points, {rows[0]['trials']} trials each"
    values = [sorted({r[k] for r in rows}) for k in names]
    is_grid = int(np.prod([len(v) for v in values])) == len(rows) if names else False
    panels = values[2][:4] if is_grid and len(names) >= 3 else [None]
    fig, axes = plt.subplots(
        1, len(panels), figsize=(1.0 + 5.0 * len(panels), 4.6), squeeze=False, constrained_layout=True
    )
    for ax, panel in zip(axes[0], panels, strict=True):
        sel = [r for r in rows if panel is None or r[names[2]] == panel]
        rate = np.array([r["rate"] for r in sel])
        if len(names) >= 2 and is_grid:
            xs, ys = values[0], values[1]
            grid = np.full((len(ys), len(xs)), np.nan)
            for y_i, y in enumerate(ys):
                for x_i, x in enumerate(xs):
                    grid[y_i, x_i] = np.mean(
                        [r["rate"] for r in sel if r[names[0]] == x and r[names[1]] == y]
                    )
                    v = grid[y_i, x_i]
                    ax.text(
                        x, y, f"{v:.2f}", ha="center", va="center", fontsize=9, color="k" if v > 0.6 else "w"
                    )
            im = ax.pcolormesh(xs, ys, grid, shading="nearest", vmin=0, vmax=1, cmap="viridis")
        elif len(names) >= 2:
            im = ax.scatter(
                [r[names[0]] for r in sel], [r[names[1]] for r in sel], c=rate, vmin=0, vmax=1, s=80
            )
        elif names:
            order = np.argsort([r[names[0]] for r in sel])
            ax.plot(np.array([r[names[0]] for r in sel])[order], rate[order], "o-")
            ax.set_ylim(0, 1.05)
        else:
            ax.bar([0], [rate.mean()])
        if names:
            ax.set_xlabel(f"{names[0]} [{UNITS[names[0]]}]")
        ax.set_ylabel(f"{names[1]} [{UNITS[names[1]]}]" if len(names) >= 2 else label)
        if panel is not None:
            ax.set_title(f"{names[2]} = {panel:g} {UNITS[names[2]]}")
    if len(names) >= 2:
        fig.colorbar(im, ax=axes[0].tolist(), label=label)
    fig.suptitle(title)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
