"""The ``ttmanip`` command in a subprocess: every subcommand writes its products, ``--help`` has
examples, and user errors exit non-zero with one line naming the key and the problem."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HIT = {
    "robot": "gantry6",
    "units": {"length": "m", "time": "s"},
    "hits": [
        {
            "centre": [0.35, -0.55, 0.05],
            "normal": [0.3, -1.0, -0.2],
            "velocity": [0.86, -2.87, -0.57],
            "t": 0.55,
        }
    ],
}


def ttmanip(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "ttmanip.cli", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )


def write(tmp_path, data, name="hit.json"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def one_line_error(r, *fragments):
    assert r.returncode != 0, r.stdout
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("ttmanip: error:")]
    assert len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr
    for f in fragments:
        assert f in lines[0], lines[0]


def test_help_has_examples_for_every_subcommand():
    r = ttmanip("--help")
    assert r.returncode == 0 and "examples:" in r.stdout
    for sub in ("demo", "experiment", "fk", "ik", "plan", "simulate", "export", "info"):
        r = ttmanip(sub, "--help")
        assert r.returncode == 0 and "example" in r.stdout, sub


def test_plan_writes_json_csv_png(tmp_path):
    r = ttmanip("plan", write(tmp_path, HIT), "--out", tmp_path / "out")
    assert r.returncode == 0, r.stderr
    plan = json.loads((tmp_path / "out" / "plan.json").read_text())
    assert plan["plans"][0]["status"] == "ok"
    assert (tmp_path / "out" / "hit0_plan.csv").stat().st_size > 1000
    assert (tmp_path / "out" / "hit0_joints.png").read_bytes().startswith(b"\x89PNG")


def test_simulate_writes_the_errors_at_the_hit(tmp_path):
    r = ttmanip("simulate", write(tmp_path, HIT), "--out", tmp_path / "out")
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "out" / "summary.json").read_text())["hits"][0]
    assert s["racket_position_error_m"] <= 1e-3 and s["racket_normal_error_deg"] <= 0.5
    assert s["racket_velocity_error_rel"] <= 0.02
    assert (tmp_path / "out" / "hit0_sim.csv").exists() and (tmp_path / "out" / "hit0_racket.png").exists()


def test_fk_ik_info_export(tmp_path):
    r = ttmanip("fk", "gantry6", "--q", "0.1,0,0.2,0.3,0.4,0.5", "--out", tmp_path / "fk")
    assert r.returncode == 0 and json.loads((tmp_path / "fk" / "fk.json").read_text())["pose"]
    r = ttmanip(
        "ik", "gantry6", "--centre", "0.35,-0.55,0.05", "--normal", "0.3,-1,-0.2", "--out", tmp_path / "ik"
    )
    assert r.returncode == 0, r.stderr
    assert len(json.loads((tmp_path / "ik" / "ik.json").read_text())["branches"]) >= 1
    r = ttmanip("info", "mobile8", "--out", tmp_path / "info")
    assert r.returncode == 0 and len(json.loads((tmp_path / "info" / "info.json").read_text())["joints"]) == 8
    r = ttmanip("export", "gantry6", "--out", tmp_path / "robots")
    assert r.returncode == 0
    assert (tmp_path / "robots" / "gantry6.urdf").exists() and (tmp_path / "robots" / "gantry6.toml").exists()


@pytest.mark.parametrize(
    "content, fragments",
    [
        ("{not json", ["not valid JSON"]),
        (
            {"hits": [{"normal": [0, -1, 0], "velocity": [0, -3, 0], "t": 0.3}]},
            ["hits[0].centre", "missing key"],
        ),
        (
            {"hits": [{"centre": [0, -0.5, 0], "normal": [0, -1, 0], "velocity": [0, -3, 0]}]},
            ["hits[0].t", "missing"],
        ),
        (
            {"hits": [{"centre": [0, -0.5], "normal": [0, -1, 0], "velocity": [0, -3, 0], "t": 0.3}]},
            ["hits[0].centre", "expected 3 numbers"],
        ),
        (
            {"hits": [{"centre": [0, -0.5, 0], "normal": [0, -1, 0], "velocity": [0, -3, 0], "t": -1}]},
            ["hits[0].t", "> 0"],
        ),
        (
            {"hits": [{"centre": [0, -0.5, 0], "normal": [0, 0, 0], "velocity": [0, -3, 0], "t": 0.3}]},
            ["hits[0].normal", "nonzero"],
        ),
        ({**HIT, "units": {"length": "mm"}}, ["units.length", "'m'"]),
        ({**HIT, "robot": "r2d2"}, ["robot", "r2d2"]),
        (
            {
                "hits": [
                    {
                        "centre": [0, -0.5, 0],
                        "normal": [0, -1, 0],
                        "velocity": [0, -3, 0],
                        "t": 0.3,
                        "speed": 3,
                    }
                ]
            },
            ["hits[0].speed", "unknown key"],
        ),
        ({"hits": []}, ["hits", "non-empty"]),
        ({**HIT, "state": {"qd": [0] * 6}}, ["state.q", "missing"]),
    ],
)
def test_bad_hit_files_name_the_key(tmp_path, content, fragments):
    r = ttmanip("plan", write(tmp_path, content), "--out", tmp_path / "out")
    one_line_error(r, *fragments)


def test_unreachable_hit_exits_nonzero_naming_the_hit(tmp_path):
    far = {
        "hits": [
            HIT["hits"][0],
            {"centre": [0.3, -0.5, 2.0], "normal": [0, -1, 0], "velocity": [0, -3, 0], "t": 0.5},
        ]
    }
    r = ttmanip("plan", write(tmp_path, far), "--out", tmp_path / "out")
    assert r.returncode == 2  # not done (bad input is 1)
    one_line_error(r, "hits[1]", "unreachable")


def test_other_user_errors_are_one_line(tmp_path):
    one_line_error(
        ttmanip("plan", tmp_path / "missing.json", "--out", tmp_path / "o"), "missing.json", "cannot read"
    )
    one_line_error(ttmanip("plan", write(tmp_path, "a: 1", "hit.yaml"), "--out", tmp_path / "o"), "YAML")
    one_line_error(ttmanip("fk", "gantry6", "--q", "1,2,x"), "--q", "numbers")
    one_line_error(ttmanip("fk", "gantry6", "--q", "1,2"), "--q", "6 numbers")
    one_line_error(ttmanip("ik", "gantry6", "--centre", "0,0,5", "--normal", "0,-1,0"), "--centre", "reach")
    blocker = tmp_path / "file"
    blocker.write_text("")
    one_line_error(ttmanip("plan", write(tmp_path, HIT), "--out", blocker / "sub"), "--out", "cannot write")
    if os.geteuid() != 0:  # root can write anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        one_line_error(ttmanip("info", "gantry6", "--out", ro / "x"), "--out")


def test_info_prints_each_joints_motor_ratings_and_gear():
    r = ttmanip("info", "gantry6")
    assert r.returncode == 0
    lines = [ln for ln in r.stdout.splitlines() if "drive: motor k_t" in ln]
    assert len(lines) == 6
    # d1: the 400 W servo of robots/gantry6.toml, θ5: the RE 30 on 30:1
    assert "2.80 A cont / 8.40 A peak" in lines[0] and "gear 200 (η 0.9)" in lines[0]
    assert "k_t 0.0259 N·m/A" in lines[4] and "gear 30" in lines[4]
