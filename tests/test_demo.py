"""``ttmanip demo`` plans and simulates a gantry6 hit on every axis, writes its figures and a
summary whose racket errors at the hit meet the acceptance limits."""

from __future__ import annotations

import json

from ttmanip.cli import main


def test_demo_writes_figures_and_summary(tmp_path):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "gantry6_errors.png").read_bytes().startswith(b"\x89PNG")
    for name in (
        "gantry6_joints.png",
        "gantry6_racket.png",
        "mobile8_joints.png",
        "kinematics/workspace_gantry6.png",
        "kinematics/workspace_mobile8.png",
    ):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 20_000, name
    assert (tmp_path / "gantry6_stroke.gif").read_bytes().startswith(b"GIF8")
    assert (tmp_path / "gantry6_plan.csv").exists() and (tmp_path / "gantry6_sim.csv").exists()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["faults"] == [""] * 6
    assert summary["racket_position_error_m"] <= 1e-3
    assert summary["racket_normal_error_deg"] <= 0.5
    assert summary["racket_velocity_error_rel"] <= 0.02
    assert summary["mobile8"]["status"] == "ok"
    # issue 10: the θ5 case (RE 25 + 14:1, 4096 counts) without current chatter
    assert summary["drive_current_ripple_rms_a"] <= 0.03
    assert summary["drive_current_ripple_250hz_rms_a"] <= 0.06
    assert (tmp_path / "drive_theta5.png").is_file()
