"""Design sweeps on Dask (issue 31): the same numbers serially and on a 2-worker LocalCluster,
the table and the figure, the CLI, bad input."""

from __future__ import annotations

import csv

import pytest
import ttmanip
from ttmanip.cli import main
from ttmanip.sweeps import design_points

GRID = {"base_x": [-0.2, 0.2], "speed": [2.0, 5.0]}


@pytest.fixture(scope="module")
def serial():
    return ttmanip.sweep("hits", GRID, n=24, chunk=8, seed=3, scheduler="serial")


def test_two_workers_give_the_serial_numbers(serial, tmp_path):
    dask = ttmanip.sweep("hits", GRID, n=24, chunk=8, seed=3, workers=2, out=tmp_path)
    assert dask["workers"] == 2 and dask["tasks"] == 4 * 3
    assert dask["rows"] == serial["rows"]  # exactly: counts and float sums alike
    rows = list(csv.DictReader(open(dask["files"]["csv"])))
    assert len(rows) == 4 and [float(r["rate"]) for r in rows] == [r["rate"] for r in serial["rows"]]
    assert (tmp_path / "sweep.png").stat().st_size > 10_000


def test_rows_are_counts_of_the_study(serial):
    assert [(r["base_x"], r["speed"]) for r in serial["rows"]] == [
        (-0.2, 2.0),
        (-0.2, 5.0),
        (0.2, 2.0),
        (0.2, 5.0),
    ]
    for r in serial["rows"]:
        assert r["trials"] == 24 and 0 <= r["ok"] <= 24 and r["rate"] == r["ok"] / 24
        assert r["base_y"] == 0.0  # the default
    # the rates differ across the design (the study sees the parameters)
    assert len({r["ok"] for r in serial["rows"]}) > 1


def test_chunking_does_not_change_the_rally_numbers():
    a = ttmanip.sweep("rally", {"max_spin_rps": [0.0, 50.0]}, n=30, chunk=30, scheduler="serial")
    b = ttmanip.sweep("rally", {"max_spin_rps": [0.0, 50.0]}, n=30, chunk=7, scheduler="serial")
    assert a["rows"] == b["rows"] and b["tasks"] == 2 * 5
    one = ttmanip.rally(30, 0, max_spin_rps=50.0)
    assert a["rows"][1]["ok"] == one["returned"]
    assert a["rows"][1]["in_reach"] == one["in_reach"]


def test_random_design_is_seeded():
    a = design_points({"speed": (1.0, 6.0), "base_y": (-0.1, 0.1)}, "random", 5, seed=1)
    b = design_points({"speed": (1.0, 6.0), "base_y": (-0.1, 0.1)}, "random", 5, seed=1)
    assert a == b and len(a) == 5 and all(1.0 <= p["speed"] <= 6.0 for p in a)
    assert a != design_points({"speed": (1.0, 6.0), "base_y": (-0.1, 0.1)}, "random", 5, seed=2)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"study": "nope"}, "study: expected one of"),
        ({"params": {"speeed": [1.0]}}, "'speeed' is not a parameter of 'hits'"),
        ({"params": {"speed": []}}, "non-empty list"),
        ({"params": {"speed": [1.0]}, "design": "random"}, r"\(low, high\) range"),
        ({"design": "latin"}, "design: expected 'grid' or 'random'"),
        ({"n": 0}, "n: expected a positive integer"),
        ({"chunk": 1.5}, "chunk: expected a positive integer"),
        ({"seed": -1}, "seed: expected a non-negative integer"),
    ],
)
def test_bad_input_says_what_to_fix(kwargs, message):
    with pytest.raises(ttmanip.TtmanipError, match=message):
        ttmanip.sweep(**{"scheduler": "serial", **kwargs})


def test_cli_sweep(tmp_path, capsys):
    out = tmp_path / "s"
    code = main(
        [
            "sweep",
            "hits",
            "--param",
            "speed=2:5:2",
            "--n",
            "8",
            "--chunk",
            "4",
            "--scheduler",
            "serial",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    text = capsys.readouterr()
    assert "4 tasks on 1 workers" in text.out and "sweep [" in text.err
    assert (out / "sweep.csv").exists() and (out / "sweep.png").exists()
    assert main(["sweep", "hits", "--param", "speed", "--scheduler", "serial"]) == 2
    assert "expected NAME=VALUES" in capsys.readouterr().err
    assert main(["sweep", "hits", "--random", "3", "--param", "speed=1,2", "--scheduler", "serial"]) == 2
    assert "expected low:high" in capsys.readouterr().err


def test_a_running_scheduler_by_address(serial):
    import distributed  # the sweep extra, part of the test extra

    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None
    ) as c:
        remote = ttmanip.sweep("hits", GRID, n=24, chunk=8, seed=3, scheduler=c.scheduler_address)
        assert remote["workers"] == 1 and remote["rows"] == serial["rows"]
        assert c.scheduler_address.startswith("tcp://")


def test_drive_scale_scales_the_limits_and_helps_fast_hits():
    from ttmanip.sweeps import _scaled_drives

    g6 = ttmanip.robots.gantry6()
    big = _scaled_drives(g6, 1.5)
    for limits in ("velocity_limits", "acceleration_limits", "effort_limits"):
        assert (getattr(big, limits) == 1.5 * getattr(g6, limits)).all(), limits
    assert (big.limits == g6.limits).all()
    r = ttmanip.sweep("hits", {"speed": [4.0], "drive_scale": [1.0, 1.5]}, n=40, chunk=20, scheduler="serial")
    weak, strong = r["rows"]
    assert strong["ok"] > weak["ok"] and weak["hit_speed_limit"] > strong["hit_speed_limit"]
    with pytest.raises(ttmanip.TtmanipError, match="drive_scale: expected a finite factor > 0"):
        ttmanip.sweep("hits", {"drive_scale": [0.0]}, n=2, scheduler="serial")
