"""The ball model calibrated on the measured flights (issue 28, item 3): ``ttmanip ball fit``.

Reads ``../shared/data/ball/pam_ball_trajectories.zip`` relative to the repository root (CI has
``../shared`` beside the clone; ``TTMANIP_BALL_DATA`` overrides the path, e.g. in a worktree).
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest
from ttmanip import ball_fit
from ttmanip.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(
    os.environ.get(
        "TTMANIP_BALL_DATA", ROOT.parent / "shared" / "data" / "ball" / "pam_ball_trajectories.zip"
    )
)


@pytest.fixture(scope="module")
def summary(tmp_path_factory):
    if not DATA.exists():
        pytest.fail(
            f"measured flights not found at {DATA}: put ../shared beside the clone or set TTMANIP_BALL_DATA"
        )
    out = tmp_path_factory.mktemp("ballfit")
    assert main(["ball", "fit", str(DATA), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    s["_out"] = out
    return s


def test_split_and_data(summary):
    assert summary["flights"] == 291
    assert summary["held_out_flights"] == 72 and summary["training_flights"] == 219
    names = sorted(n for n in zipfile.ZipFile(DATA).namelist() if n.endswith(".json"))
    assert summary["held_out_names"] == names[3::4]
    # The frame period and the bounce height come from the data (README: about 10.8 ms, z ≈ −0.44).
    assert 0.0095 < summary["period_estimate_s"] < 0.0115
    assert -0.46 < summary["bounce_level_m"] < -0.40


def test_fit_has_finite_uncertainty_and_small_residual(summary):
    f = summary["fit"]
    g, sd = f["globals"], f["std"]
    for k in ("k_drag", "k_magnus", "table_restitution", "surface", "period"):
        assert np.isfinite(sd[k]) and 0 < sd[k] < 0.05 * abs(g[k]), (k, g[k], sd[k])
    assert 0.08 < g["k_drag"] < 0.2
    assert 0.0 < g["k_magnus"] < 0.004
    assert 0.8 < g["table_restitution"] <= 1.0
    assert f["median_flight_rms_m"] < 0.02
    # Friction: every training bounce rolls at the fitted value, so μ is not identified (NaN std).
    if not np.isfinite(sd["table_friction"]):
        assert f["friction_to_roll_percentiles"][2] <= g["table_friction"] + 1e-9


def test_calibrated_beats_the_best_published_constants_on_held_out_flights(summary):
    p = summary["prediction"]
    models = {m["name"]: m for m in p["models"]}
    assert p["models"][0]["name"] == "calibrated"
    assert {"mpi_linear", "muelling", "tt3d"} <= set(models)
    n = {m["flights"] for m in p["models"]}
    assert len(n) == 1 and n.pop() >= 60, "every model on the same held-out flights"
    best = min(m["median_after_bounce"] for k, m in models.items() if k != "calibrated")
    assert models["calibrated"]["median_after_bounce"] <= best
    assert p["calibrated_le_best_published"]
    assert (summary["_out"] / "fit.png").stat().st_size > 10_000


def test_reader_errors_say_what_to_fix(tmp_path):
    with pytest.raises(FileNotFoundError, match="not a folder or a zip"):
        ball_fit.read_flights(tmp_path / "missing.zip")
    (tmp_path / "a.json").write_text('{"ob": [[1, 2]]}')
    with pytest.raises(ValueError, match="at least 10 rows"):
        ball_fit.read_flights(tmp_path)
    (tmp_path / "a.json").write_text("[]")
    with pytest.raises(ValueError, match="'ob'"):
        ball_fit.read_flights(tmp_path)
    assert main(["ball", "fit", str(tmp_path / "nothing"), "--out", str(tmp_path / "o")]) == 1
