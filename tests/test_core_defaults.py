"""Issue 30: the Python package restates no default or name list the core has; each comes from
the core through a binding (``ball_rally_config``, ``hit_stroke_profiles``)."""

from __future__ import annotations

import inspect
import json
import subprocess
import sys

import ttmanip
from ttmanip import _ttmanip, ball, sweeps
from ttmanip.rally import rally


def test_rally_defaults_are_the_core_rally_config():
    core = _ttmanip.ball_rally_config()
    assert tuple(core["target"]) == (0.9, 0.0) and core["max_spin_rps"] == 40.0  # RallyConfig::default()
    assert core["world"] is None and core["camera"] == _ttmanip.ball_camera()
    sig = inspect.signature(rally).parameters
    assert sig["target"].default == tuple(core["target"])
    assert sig["max_spin_rps"].default == core["max_spin_rps"]
    assert inspect.signature(ball.plan_return).parameters["target"].default == tuple(core["target"])
    study = sweeps.STUDIES["rally"][0]
    assert (study["target_x"], study["target_y"], study["max_spin_rps"]) == (
        *core["target"],
        core["max_spin_rps"],
    )


def test_the_cli_takes_its_profile_names_from_the_core(tmp_path):
    names = _ttmanip.hit_stroke_profiles()
    assert names == ["auto", "quintic", "jerk"]  # StrokeProfile::ALL
    for name in names:  # every listed name is one plan_hit accepts
        robot = ttmanip.robots.gantry6()
        assert ttmanip.plan_hit(robot, ttmanip.DEMO_HIT, profile=name).status
    hit = {"centre": [0.35, -0.55, 0.05], "normal": [0.3, -1.0, -0.2], "velocity": [0.86, -2.87, -0.57]}
    hit["t"] = 0.55
    path = tmp_path / "hit.json"
    path.write_text(json.dumps({"robot": "gantry6", "profile": "bogus", "hits": [hit]}))
    r = subprocess.run(
        [sys.executable, "-m", "ttmanip.cli", "plan", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode != 0
    assert "profile: expected 'auto', 'quintic' or 'jerk', got 'bogus'" in r.stderr


def test_the_rally_place_of_a_robot_is_the_cores_fact_not_its_name():
    import numpy as np

    g6 = _ttmanip.Robot.builtin("gantry6")
    at_table = _ttmanip.ball_placement()
    assert np.array_equal(_ttmanip.ball_placement_for(g6), at_table)
    # the same model under another name is still the robot the rally plays
    renamed = _ttmanip.Robot.from_toml(g6.to_toml().replace('name = "gantry6"', 'name = "my_arm"'))
    assert renamed.name == "my_arm"
    assert np.array_equal(_ttmanip.ball_placement_for(renamed), at_table)
    for name in ("ur5", "mobile8"):  # no analytic IK: the ball planner does not play them
        assert _ttmanip.ball_placement_for(_ttmanip.Robot.builtin(name)) is None


def test_earth_gravity_is_the_cores():
    import numpy as np
    from ttmanip.dynamics import EARTH_GRAVITY

    assert list(EARTH_GRAVITY) == _ttmanip.EARTH_GRAVITY == [0.0, 0.0, -9.81]
    # a robot file without a gravity key gets the core's
    assert np.array_equal(_ttmanip.Robot.builtin("gantry6").gravity_vector, EARTH_GRAVITY)
