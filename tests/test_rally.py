"""ttmanip.rally and the ``ttmanip rally`` command (issue 13)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import ttmanip
from ttmanip import cli

KEYS = (
    "balls",
    "in_reach",
    "returned",
    "return_rate",
    "racket_error_m_median",
    "plan_time_us_median",
    "landing_error_m_median",
)


REACH = (
    "no_bounce",
    "outside_volume",
    "no_return",
    "no_return_pose",
    "return_speed",
    "too_early",
    "in_reach",
)


def test_rally_summary_and_determinism():
    a = ttmanip.rally(40, seed=3)
    for k in KEYS:
        assert k in a
    assert a["balls"] == 40 and a["in_reach"] + a["out_of_reach"] == 40
    assert 0.0 <= a["return_rate"] <= 1.0
    assert a["returned"] <= a["in_reach"]
    # The reachable region's verdicts cover every ball; "in_reach" is the only one counted in reach.
    assert sum(a["reach"].values()) == 40 and a["reach"].get("in_reach", 0) == a["in_reach"]
    # Every reason is reported, in the order checked, with 0 when no ball has it.
    assert list(a["reach"]) == list(REACH)
    b = ttmanip.rally(40, seed=3)
    assert a["returned"] == b["returned"] and a["statuses"] == b["statuses"]


def test_rally_bad_arguments():
    with pytest.raises(ttmanip.TtmanipError, match="n"):
        ttmanip.rally(0)
    with pytest.raises(ttmanip.TtmanipError, match="seed"):
        ttmanip.rally(5, seed=-1)
    with pytest.raises(ttmanip.TtmanipError, match="target"):
        ttmanip.rally(5, target=(3.0, 0.0))
    # found by the 10,000-example fuzzer campaign: an array for a flag
    with pytest.raises(ttmanip.TtmanipError, match="progress"):
        ttmanip.rally(5, progress=np.zeros((0, 8)))


def test_rally_cli_writes_summary_and_figures(tmp_path, capsys):
    out = tmp_path / "rally"
    assert cli.main(["rally", "--n", "30", "--seed", "1", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    for k in KEYS:
        assert k in summary
    assert list(summary["reach"]) == list(REACH) and sum(summary["reach"].values()) == 30
    for f in summary["figures"]:
        assert (tmp_path / f).exists() or __import__("pathlib").Path(f).exists()
    assert cli.main(["rally", "--n", "0", "--out", str(out)]) == 1


def test_planned_hits_executed_through_the_drives_stay_on_the_plan():
    s = ttmanip.rally(30, seed=3, drives=3)
    assert s["drive_balls"] >= 1
    assert s["drive_racket_position_error_m_max"] < 0.005  # the racket is 7.5 cm in radius


def test_mismatched_world_on_the_same_balls_and_balls_from_a_file(tmp_path, capsys):
    # issue 28: the world's physics drawn per ball around the planner's model, on the same balls.
    s = ttmanip.rally(60, seed=2, compare_world=True, world=True)
    c = s["world_comparison"]
    assert c["same_balls"] and c["balls"] == 60
    assert set(c) >= {"matched", "mismatched"}
    assert c["mismatched"]["returned"] == s["returned"]
    assert s["world"].startswith("per-ball")
    # Replaying the drawn balls from a file: the same incoming states.
    rows = s["results"]["incoming"][:25]
    f = tmp_path / "balls.csv"
    np.savetxt(f, rows, delimiter=",", header="t,px,py,pz,vx,vy,vz,wx,wy,wz")
    out = tmp_path / "r"
    assert cli.main(["rally", "--balls", str(f), "--out", str(out), "--drives", "0"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["balls"] == 25 and summary["incoming"] == "given"
    g = ttmanip.rally(25, seed=2, incoming=rows)
    np.testing.assert_array_equal(g["results"]["incoming"], rows)
    with pytest.raises(ttmanip.TtmanipError, match="incoming"):
        ttmanip.rally(5, incoming=np.zeros((3, 10)))
    (tmp_path / "bad.csv").write_text("1 2 3\n")
    assert cli.main(["rally", "--balls", str(tmp_path / "bad.csv"), "--out", str(out)]) == 1
    capsys.readouterr()


def test_the_summary_reports_the_cores_camera():
    """The summary's camera is ``ttkin::ball::rally::Camera::default()``, not a copy of it."""
    from ttmanip import _ttmanip
    from ttmanip.rally import _camera_summary

    core = _ttmanip.ball_camera()
    assert set(core) == {"rate_hz", "latency", "noise", "outlier_rate", "outlier_size", "start", "window"}
    assert _camera_summary() == {
        "rate_hz": core["rate_hz"],
        "latency_s": core["latency"],
        "noise_m": core["noise"],
        "outliers": core["outlier_rate"],
        "window_s": core["window"],
    }
    # the values the summary printed before it read them from the core (unchanged)
    before = {"rate_hz": 200.0, "latency_s": 0.010, "noise_m": 0.002, "outliers": 0.02, "window_s": 0.20}
    assert _camera_summary() == before


def test_the_summary_statistics_are_the_cores_over_every_chunk():
    """The counts and medians come from ``ttkin::ball::rally::RallyStats`` over the columns of all
    chunks: the same as one chunk, and the same as counted here from the per-ball columns."""
    from ttmanip import _ttmanip

    a = ttmanip.rally(30, seed=1, chunk=7)
    b = ttmanip.rally(30, seed=1)
    for k in ("in_reach", "returned", "return_rate", "reach", "statuses", "landing_error_m_median"):
        assert a[k] == b[k], k
    res = a["results"]
    in_reach = res["in_reach"].astype(bool)
    returned = res["returned"].astype(bool) & in_reach
    assert a["in_reach"] == in_reach.sum() and a["returned"] == returned.sum()
    assert a["return_rate"] == pytest.approx(returned.sum() / in_reach.sum(), rel=1e-15)
    assert a["returned_out_of_reach"] == (res["returned"].astype(bool) & ~in_reach).sum()
    landing = res["landing_error"][returned]
    assert a["landing_error_m_median"] == pytest.approx(np.median(landing[np.isfinite(landing)]), rel=1e-15)
    racket = res["racket_error"][in_reach]
    assert a["racket_error_m_median"] == pytest.approx(np.median(racket[np.isfinite(racket)]), rel=1e-15)
    keys = [f"{r}/{str(s).split(':')[0]}" for r, s in zip(res["reach"], res["status"], strict=True)]
    assert a["statuses"] == {k: keys.count(k) for k in sorted(set(keys))}
    # bad columns are a typed error that names the column
    with pytest.raises(ttmanip.TtmanipError, match="returned"):
        _ttmanip.ball_rally_stats([True], [], ["in_reach"], ["ok"], *[np.zeros(1)] * 6)
    with pytest.raises(ttmanip.TtmanipError, match="unknown verdict"):
        _ttmanip.ball_rally_stats([True], [True], ["far"], ["ok"], *[np.zeros(1)] * 6)


def test_the_summary_states_the_cores_in_reach_definition():
    """``in_reach_definition`` is the region's own sentence (``ReachRegion::definition``, written
    from its grids), the same text the summary printed when it restated the constants."""
    s = ttmanip.rally(3, seed=0)
    before = (
        "a return is possible: after its bounce on the robot's half the true "
        "flight has a point in the hitting volume where a shot of a fixed grid (drag-free parabola "
        "to x in {0.4, 0.8, 1.2} m, y in {-0.5, 0, 0.5} m in 0.45 to 1.05 s) with the racket of the "
        "impact model lands on the opponent's half in the real flight model, a racket pose for it "
        "(roll 0, +-30, +-60 deg) has IK within the joint position limits, q_dot = J^-1 V is within "
        "the velocity limits and the joints' minimum time from rest at the ready configuration is "
        "at most the time left (ttkin::ball::reach); independent of the planner"
    )
    assert s["in_reach_definition"] == before
    assert "in_reach_definition" not in s["results"]
