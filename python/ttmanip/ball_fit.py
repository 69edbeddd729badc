"""The ball model calibrated on recorded flights: ``ttmanip ball fit DATA --out DIR``.

Reads flights (a zip of JSON files or a folder of them, each ``{"ob": [[x, y, z, vx, vy, vz],
...]}``, one row per camera frame) and runs ``ttkin::ball::fit::experiment``: the frame period and
the bounce height from the data, every fourth file (sorted by path) held out, the fit on the rest,
and the held-out prediction error of the calibrated model and of published constants in the same
run. Writes ``summary.json`` and ``fit.png``. See ``docs/ball.md`` (Calibration).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from . import _ttmanip as _t
from .files import MAX_TOTAL_BYTES, load_json, read_limited

__all__ = ["fit", "read_flights"]


def _parse(name: str, text: str | bytes) -> tuple[np.ndarray, np.ndarray | None]:
    data = load_json(text, name)
    if not isinstance(data, dict) or "ob" not in data:
        raise _t.TtmanipError(f"{name}: expected a JSON object with 'ob': rows of x,y,z[,vx,vy,vz]")
    try:
        # real numbers only: true/false or strings in the rows are refused, not cast
        ob = _t.real_array(data["ob"], f"{name}: ob")
    except (TypeError, ValueError) as e:
        raise _t.TtmanipError(f"{name}: 'ob' must be rows of 3 or 6 numbers ({e})") from None
    if ob.ndim != 2 or ob.shape[1] not in (3, 6) or len(ob) < 10:
        raise _t.TtmanipError(
            f"{name}: 'ob' must be at least 10 rows of 3 or 6 numbers, got shape {ob.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(ob).all(axis=1))
    if bad.size:
        # JSON's NaN and Infinity, or a 401-digit integer read as inf: a position that is no number
        raise _t.TtmanipError(f"{name}: 'ob' row {bad[0]} is not finite: {ob[bad[0]].tolist()}")
    return ob[:, :3].copy(), (ob[:, 3:6].copy() if ob.shape[1] == 6 else None)


def _items(p: Path) -> list[tuple[str, bytes]]:
    """The ``*.json`` members of the folder or zip ``p``, each read within
    :data:`ttmanip.files.MAX_FILE_BYTES` and all within :data:`ttmanip.files.MAX_TOTAL_BYTES` (a zip
    bomb is refused before it is inflated: the sizes are checked as the members are read)."""
    items: list[tuple[str, bytes]] = []
    total = 0

    def add(name: str, raw: bytes) -> None:
        nonlocal total
        total += len(raw)
        if total > MAX_TOTAL_BYTES:
            raise _t.TtmanipError(
                f"{p}: the flights add up to more than {MAX_TOTAL_BYTES} bytes (512 MiB), "
                "the most read at once"
            )
        items.append((name, raw))

    if p.is_dir():
        for f in sorted(p.rglob("*.json")):
            name = str(f.relative_to(p))
            with f.open("rb") as fh:
                add(name, read_limited(fh, name))
    elif p.is_file() and zipfile.is_zipfile(p):
        with zipfile.ZipFile(p) as z:
            for n in sorted(z.namelist()):
                if n.endswith(".json"):
                    with z.open(n) as fh:
                        add(n, read_limited(fh, n))
    else:
        raise FileNotFoundError(f"{p}: not a folder or a zip file of flights")
    return items


def read_flights(path: str | Path) -> tuple[list[str], list[np.ndarray], list[np.ndarray | None]]:
    """Flights from a zip or a folder of ``*.json`` (searched recursively), sorted by path: names,
    positions (N, 3) m, tracker velocities (N, 3) m/s or None. A file over 16 MiB, flights over
    512 MiB in all, JSON that is not UTF-8 or nested over 64 deep, or rows that are not finite
    numbers are refused with a :class:`ttmanip.TtmanipError` naming the file."""
    p = Path(path)
    items = _items(p)
    if not items:
        raise _t.TtmanipError(f"{path}: no .json flights found")
    names, pos, vel = [], [], []
    for name, text in sorted(items):
        pp, vv = _parse(name, text)
        names.append(name)
        pos.append(pp)
        vel.append(vv)
    return names, pos, vel


def fit(path: str | Path, window: int = 20, period: float | None = None) -> dict:
    """The calibration experiment on the flights at ``path`` (see the module doc): a dict with
    ``calibration`` (globals, std, correlation, per-flight fits), ``comparisons`` (held-out
    prediction errors per model, calibrated first) and the data's ``period_estimate`` and
    ``bounce_level``; ``names`` lists the flights."""
    names, pos, vel = read_flights(path)
    velocities = vel if all(v is not None for v in vel) else None
    res = _t.ball_fit(names, pos, velocities, window=window, period=period)
    res["names"] = names
    return res


def _summary(res: dict, data: str) -> dict:
    cal = res["calibration"]
    held = res["held_out"]
    comps = []
    for c in res["comparisons"]:
        d = {k: v for k, v in c.items() if k != "errors"}
        d["flights"] = len(c["errors"])
        comps.append(d)
    best = min((c for c in comps if c["name"] != "calibrated"), key=lambda c: c["median_after_bounce"])
    roll = np.array([f["friction_to_roll"] for f in cal["flights"]])
    return {
        "data": data,
        "flights": len(res["names"]),
        "training_flights": int(len(held) - sum(held)),
        "held_out_flights": int(sum(held)),
        "held_out_rule": "files sorted by path, every fourth (positions 3, 7, 11, ...) held out",
        "held_out_names": [n for n, h in zip(res["names"], held, strict=True) if h],
        "unusable": [res["names"][i] for i in res["unusable"]],
        "period_estimate_s": res["period_estimate"],
        "bounce_level_m": res["bounce_level"],
        "fit": {
            "globals": cal["globals"],
            "std": cal["std"],
            "correlation": np.asarray(cal["correlation"]).round(3).tolist(),
            "sigma_m": cal["sigma"],
            "rms_m": cal["rms"],
            "median_flight_rms_m": float(np.median([f["rms"] for f in cal["flights"]])),
            "iterations": cal["iterations"],
            "frames": cal["observations"],
            "spin_prior_mean_rad_s": cal["spin_mean"],
            "spin_prior_std_rad_s": cal["spin_std"],
            "friction_to_roll_percentiles": np.nanpercentile(roll, [50, 90, 100]).tolist(),
        },
        "prediction": {
            "window_frames": res["window"],
            "metric": "state (position, velocity, spin with the training flights' spin prior) fitted on "
            "the first window frames with the model's constants fixed; RMS distance between predicted "
            "and observed positions over the frames after the bounce, median over held-out flights",
            "models": comps,
            "best_published": best["name"],
            "calibrated_le_best_published": comps[0]["median_after_bounce"] <= best["median_after_bounce"],
        },
    }


def _figure(res: dict, out: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    comps = res["comparisons"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    data = [[e["rms_after_bounce"] * 100 for e in c["errors"]] for c in comps]
    a1.boxplot(data, showfliers=False)
    a1.set_xticks(range(1, len(comps) + 1), [c["name"] for c in comps], rotation=30, ha="right")
    a1.set_ylabel("held-out RMS error after the bounce (cm)")
    a1.set_title(f"prediction from the first {res['window']} frames ({len(data[0])} held-out flights)")
    cal = comps[0]["errors"]
    k = int(np.argsort([e["rms_after_bounce"] for e in cal])[len(cal) // 2]) if cal else 0
    if cal:
        idx = cal[k]["index"]
        names = res["names"]
        obs = res["_positions"][idx]
        a2.plot(obs[:, 1], obs[:, 2], "k.", ms=3, label="observed")
        best = min(comps[1:], key=lambda c: c["median_after_bounce"])
        for c, style in ((comps[0], "C0-"), (best, "C3--")):
            e = next((e for e in c["errors"] if e["index"] == idx), None)
            if e is not None:
                path = np.asarray(e["path"])
                a2.plot(
                    path[:, 1],
                    path[:, 2],
                    style,
                    label=f"{c['name']} ({e['rms_after_bounce'] * 100:.1f} cm)",
                )
        a2.axvline(obs[cal[k]["window"] - 1, 1], color="grey", lw=0.8, ls=":")
        a2.set_xlabel("y (m, recording frame)")
        a2.set_ylabel("z (m)")
        a2.set_title(f"median held-out flight: {names[idx]}")
        a2.legend(fontsize=8)
    path = out / "fit.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def run(data: str, out: str, window: int = 20, period: float | None = None) -> dict:
    """Runs the calibration on ``data``, writes ``summary.json`` and ``fit.png`` into ``out``;
    returns the summary."""
    names, pos, vel = read_flights(data)
    velocities = vel if all(v is not None for v in vel) else None
    res = _t.ball_fit(names, pos, velocities, window=window, period=period)
    res["names"] = names
    res["_positions"] = pos
    o = Path(out)
    o.mkdir(parents=True, exist_ok=True)
    summary = _summary(res, str(data))
    summary["figure"] = _figure(res, o)
    (o / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
