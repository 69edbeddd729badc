"""Rerun recordings (issue 31): ``--rerun`` on demo, simulate and rally, ``ttmanip telemetry``;
each recording is read back with Rerun's own reader (``rerun.chunk.RrdReader``) and its entity
paths and values are checked against the run's own outputs."""

from __future__ import annotations

import csv
import json

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr  # the viz extra, part of the test extra
import ttmanip
from ttmanip.cli import main
from ttmanip.viz import WORLD_FROM_GANTRY6


def read(path) -> dict[str, dict[str, list]]:
    """entity path -> column -> values over all its chunks (rows in time order per column)."""
    out: dict[str, dict[str, list]] = {}
    for chunk in rr.chunk.RrdReader(path).stream().to_chunks():
        batch = chunk.to_record_batch()
        cols = out.setdefault(chunk.entity_path, {})
        for name in batch.schema.names:
            col = batch.column(name)
            if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
                col = col.cast(pa.int64())  # ns
            cols.setdefault(name, []).extend(col.to_pylist())
    return out


def seconds(values) -> np.ndarray:
    """Timeline values (ns) in s."""
    return np.array(values, dtype=float) / 1e9


def scalars(rec, entity) -> tuple[np.ndarray, np.ndarray]:
    c = rec[entity]
    order = np.argsort(seconds(c["time"]), kind="stable")
    return seconds(c["time"])[order], np.array([v[0] for v in c["Scalars:scalars"]])[order]


def read_csv(path) -> dict[str, np.ndarray]:
    with open(path) as f:
        rows = list(csv.reader(f))
    return {k: np.array([float(r[i]) for r in rows[1:]]) for i, k in enumerate(rows[0])}


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--out", str(out), "--no-workspace", "--rerun", str(out / "demo.rrd")]) == 0
    return out, read(out / "demo.rrd")


def test_demo_recording_has_the_scene(demo):
    out, rec = demo
    g6 = ttmanip.robots.gantry6()
    names = [*g6.joint_names, "tool"]
    expected = {"/world", "/world/table", "/world/net", "/world/gantry6", "/world/gantry6/skeleton"}
    expected |= {f"/world/gantry6/links/{n}" for n in names}
    expected |= {"/world/gantry6/racket", "/world/gantry6/racket/blade", "/world/gantry6/hit"}
    expected |= {f"/joints/{k}/{n}" for k in ("q", "q_ref", "torque", "current") for n in g6.joint_names}
    expected |= {"/mobile8", "/mobile8/racket", "/mobile8/skeleton"}
    assert expected <= set(rec), sorted(expected - set(rec))
    table = ttmanip.ball.Table()
    half = rec["/world/table"]["Boxes3D:half_sizes"][0][0]
    np.testing.assert_allclose(half, [table.length / 2, table.width / 2, 0.015], rtol=1e-6)
    base = rec["/world/gantry6"]
    np.testing.assert_allclose(base["Transform3D:translation"][0][0], WORLD_FROM_GANTRY6[:3, 3], atol=1e-7)


def test_demo_joint_series_are_the_simulated_ones(demo):
    out, rec = demo
    g6 = ttmanip.robots.gantry6()
    sim = read_csv(out / "gantry6_sim.csv")
    for j, name in enumerate(g6.joint_names):
        t, q = scalars(rec, f"/joints/q/{name}")
        np.testing.assert_array_equal(t.round(6), sim["t"].round(6))  # the timeline is in ns
        np.testing.assert_array_equal(q, sim[f"q[{j}]"])  # float64 scalars: exact
        _, tau = scalars(rec, f"/joints/torque/{name}")
        np.testing.assert_array_equal(tau, sim[f"torque[{j}]"])
        _, current = scalars(rec, f"/joints/current/{name}")
        np.testing.assert_array_equal(current, sim[f"current[{j}]"])


def test_demo_link_frames_are_fk_of_the_simulated_joints(demo):
    out, rec = demo
    g6 = ttmanip.robots.gantry6()
    sim = read_csv(out / "gantry6_sim.csv")
    q = np.column_stack([sim[f"q[{j}]"] for j in range(g6.dof)])
    tool = rec["/world/gantry6/links/tool"]
    t = seconds(tool["time"])
    assert 100 <= len(t) <= 300  # decimated 3-D frames; the scalars keep every sample
    idx = np.searchsorted(sim["t"].round(9), t.round(9))
    fk = g6.fk(q[idx])
    np.testing.assert_allclose(np.array(tool["Transform3D:translation"])[:, 0], fk[:, :3, 3], atol=1e-6)
    np.testing.assert_allclose(
        np.array(tool["Transform3D:mat3x3"])[:, 0].reshape(-1, 3, 3),
        fk[:, :3, :3].transpose(0, 2, 1),
        atol=1e-6,
    )  # Rerun stores 3x3 matrices column-major
    frames = g6.fk_all(q[idx])
    d2 = rec["/world/gantry6/links/d2"]
    np.testing.assert_allclose(np.array(d2["Transform3D:translation"])[:, 0], frames[:, 1, :3, 3], atol=1e-6)
    summary = json.loads((out / "summary.json").read_text())
    hit = rec["/world/gantry6/hit"]["Points3D:positions"][0][0]
    np.testing.assert_allclose(hit, np.array(summary["hit_pose"])[:3, 3], atol=1e-6)


@pytest.fixture(scope="module")
def rally(tmp_path_factory):
    out = tmp_path_factory.mktemp("rally")
    code = main(["rally", "--n", "10", "--drives", "0", "--out", str(out), "--rerun", str(out / "rally.rrd")])
    assert code == 0
    return ttmanip.rally(10, 0), read(out / "rally.rrd")


def test_rally_recording_has_ten_balls_and_the_strokes(rally):
    summary, rec = rally
    for k in range(10):
        assert f"/world/ball{k}" in rec and f"/world/ball{k}/predicted" in rec
    for entity in ("/world/table", "/world/net", "/world/gantry6/links/tool", "/world/gantry6/racket"):
        assert entity in rec, entity
    assert "/joints/q/d1" in rec and "/joints/torque/theta5" in rec
    # the balls' positions are the flight model's, from each ball's incoming state
    incoming = summary["results"]["incoming"][3]
    ball = rec["/world/ball3"]
    t = seconds(ball["time"])
    p = np.array([row[0] for row in ball["Points3D:positions"]])
    offset = 3 * 1.5
    expected = ttmanip.ball.predict(incoming, incoming[0] + (t - offset))
    np.testing.assert_allclose(p, expected, atol=2e-6)  # positions are stored as float32


def test_telemetry_converts(tmp_path, capsys):
    path = tmp_path / "tele.csv"
    header = "channel,cycle,t,phase,latency_us" + "".join(f",q_ref{a},q{a},current{a}" for a in range(2))
    rows = [
        f"can0,{k},{k * 0.001:.4f},run,{10 + k:.1f},{0.1 * k:.6f},{0.1 * k - 0.01:.6f},{0.5:.4f},0,0,0"
        for k in range(5)
    ]
    path.write_text("\n".join([header, *rows]) + "\n")
    assert main(["telemetry", str(path), "--rerun", str(tmp_path / "tele.rrd")]) == 0
    rec = read(tmp_path / "tele.rrd")
    t, q = scalars(rec, "/telemetry/can0/axis0/q")
    np.testing.assert_allclose(t, np.arange(5) * 0.001, atol=1e-9)
    np.testing.assert_array_equal(q, np.round([0.1 * k - 0.01 for k in range(5)], 6))
    _, lat = scalars(rec, "/telemetry/can0/latency_us")
    np.testing.assert_array_equal(lat, 10.0 + np.arange(5))
    assert "/telemetry/can0/axis1/current" in rec
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    assert main(["telemetry", str(bad), "--rerun", str(tmp_path / "x.rrd")]) == 2
    assert "not a ttctl telemetry CSV" in capsys.readouterr().err


def test_snapshot_draws_a_frame_from_the_recording(demo, tmp_path):
    from ttmanip.viz import snapshot

    out, _ = demo
    png = snapshot(out / "demo.rrd", 0.35, tmp_path / "frame.png")
    assert png.stat().st_size > 20_000


def test_rally_ball_meets_the_planned_hit_point(rally):
    summary, rec = rally
    incoming = summary["results"]["incoming"][0]
    d = ttmanip.ball.plan_return(incoming, 0.23)
    assert d["status"] == "ok"
    t_hit = 0.23 + d["t_hit"]  # ball 0 starts at 0 s on the timeline
    hit = rec["/world/gantry6/hit"]
    first = int(np.argmin(seconds(hit["time"])))  # ball 0's stroke is the first logged
    centre = np.r_[np.array(hit["Points3D:positions"][first][0]), 1.0]
    world = (WORLD_FROM_GANTRY6 @ centre)[:3]
    ball = ttmanip.ball.predict(incoming, [t_hit])[0]
    # the ball touches the racket face at the hit: centres one ball radius (20 mm) apart, which
    # also checks WORLD_FROM_GANTRY6 against the rally's own placement (float32 storage: 1e-6 m)
    assert abs(np.linalg.norm(ball - world) - 0.020) < 1e-5, (ball, world)
