"""The demo command runs the whole pipeline and writes its figures and summary."""

from __future__ import annotations

import json

from ttmanip.cli import main


def test_demo_writes_figures_and_summary(tmp_path):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    for name in (
        "kinematics/workspace_gantry6.png",
        "kinematics/workspace_mobile8.png",
        "pipeline/stroke_joints.png",
        "pipeline/stroke_torques.png",
    ):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 20_000, name
    summary = json.loads((tmp_path / "summary.json").read_text())
    for robot in ("gantry6", "mobile8"):
        kin = summary["kinematics"][robot]
        assert len(kin["jacobian_singular_values_ref"]) == 6
        assert all(a < b for a, b in zip(kin["workspace_min_m"], kin["workspace_max_m"]))
    hit = summary["pipeline"]
    # the planned stroke puts the racket at the requested pose with the requested twist at t_hit
    assert hit["hit_pose_error_m"] < 1e-9
    assert hit["hit_twist_error"] < 1e-9
    assert hit["stroke_feasible"]
    assert hit["driven_joint_fault"] is None
    assert summary["seed000"]["max_tracking_error"] <= 1e-6
