"""The demo command writes its figures and summary."""

from __future__ import annotations

import json

from ttmanip.cli import main


def test_demo_writes_figures_and_summary(tmp_path):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    for name in ("workspace_gantry6.png", "workspace_mobile8.png"):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 20_000
    summary = json.loads((tmp_path / "summary.json").read_text())
    for robot in ("gantry6", "mobile8"):
        assert len(summary[robot]["jacobian_singular_values_ref"]) == 6
        lo, hi = summary[robot]["workspace_min_m"], summary[robot]["workspace_max_m"]
        assert all(a < b for a, b in zip(lo, hi))
