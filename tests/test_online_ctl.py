"""ttctl's online hit mode driven from Python through ttmanip.ctl.Link: gantry6 on in-process
virtual drives (ttctl --virtual-drives, no CAN), bad datagrams of every class counted and dropped
with the robot's state unchanged, a hit accepted and executed, a plan every 50 ms with the cycle
latency reported quiet and planning side by side."""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import time

import numpy as np
import pytest
import ttmanip
from conftest import built_binary
from ttmanip import _ttmanip as _t
from ttmanip.ctl import Link

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(ROOT, "tests", "online", "gantry6.toml")

# real time: ttctl's cycles and planning latency against the clock (scripts/test.sh runs it alone)
pytestmark = pytest.mark.serial


def _free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


# joint band (rad or m) the virtual drives hunt in at rest: a few encoder counts
HUNT = 3e-4


def _telemetry(link: Link, timeout: float) -> list[dict]:
    out, until = [], time.monotonic() + timeout
    while time.monotonic() < until:
        m = link.receive(timeout=0.05)
        if m is not None:
            out.append(m)
    return out


def test_bad_input_hits_and_planning_load_through_link(tmp_path):
    # timed like the HIL rally: $TTCTL when set (scripts/test.sh: the release build), else the newest
    ttctl = os.environ.get("TTCTL") or built_binary("ttctl")
    if ttctl is None:
        pytest.skip("ttctl is not built (cargo build -p ttcan)")
    port = _free_port()
    stats = tmp_path / "stats.txt"
    with Link(("127.0.0.1", port), bind=("127.0.0.1", 0)) as link:
        reply = link._sock.getsockname()
        proc = subprocess.Popen(
            [
                ttctl,
                "-c",
                CONFIG,
                "--virtual-drives",
                "--online",
                "hit",
                "--listen",
                f"127.0.0.1:{port}",
                "--reply",
                f"{reply[0]}:{reply[1]}",
                "--max-seconds",
                "90",  # ended by SIGINT below; on a loaded machine the steps take tens of seconds
                "--stats",
                str(stats),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        try:
            ready = ttmanip.Robot.builtin("gantry6").ready
            until = time.monotonic() + 20
            at_ready = False
            while time.monotonic() < until and not at_ready:
                tel = [m for m in _telemetry(link, 0.2) if m.get("kind") == "telemetry"]
                at_ready = bool(tel) and np.allclose(np.asarray(tel[-1]["q"])[:6], ready, atol=2e-3)
            assert at_ready, "the robot did not reach the ready pose"
            # settled: the approach's motion has died out. At rest the virtual drives hunt by a few
            # encoder counts (their position loop's integral against Coulomb friction: steps of
            # about 8e-5 every few hundred ms, each joint at its own phase), so "at rest" is a band
            # of HUNT around the window's mean, not a constant; any stroke moves by far more.
            # (Its own deadline: a loaded machine may take most of the first one to reach ready,
            # and a 0.2 s window may bring no telemetry at all.)
            settled, before = False, None
            until = time.monotonic() + 20
            while time.monotonic() < until and not settled:
                tel = [m for m in _telemetry(link, 0.2) if m.get("kind") == "telemetry"]
                q = np.asarray([m["q"][:6] for m in tel])
                settled = len(q) > 1 and np.ptp(q, axis=0).max() < HUNT
                before = q.mean(axis=0) if settled else before
            assert settled, "the robot did not settle at ready"
            now = time.monotonic()
            hit = ttmanip.DEMO_HIT
            past = _t.wire_hit(7, 7, now - 0.1, hit.pose, hit.twist, 100, now)
            sock, to = link._sock, ("127.0.0.1", port)
            bad = {
                "truncated": past[:60],
                "oversized": past + b"\0" * 8,
                "unknown_version": past[:4] + struct.pack("<H", 9) + past[6:],
                "malformed": b"XXXX" + past[4:],
                "non_finite": past[:112] + struct.pack("<d", float("nan")) + past[120:],
            }
            sock.sendto(past, to)  # through the screen, answered `rejected` (in the past)
            sock.sendto(past, to)  # duplicate
            sock.sendto(_t.wire_hit(8, 8, now + 1, hit.pose, hit.twist, 99, now), to)  # out of order
            sock.sendto(_t.wire_hit(9, 9, now + 1, hit.pose, hit.twist, 101, now - 1.0), to)  # stale
            for data in bad.values():
                sock.sendto(data, to)
            got = _telemetry(link, 0.5)
            statuses = [m for m in got if m.get("kind") == "status"]
            assert [(s["id"], s["status"]) for s in statuses] == [(7, "Rejected")], statuses
            after = np.asarray([m["q"][:6] for m in got if m.get("kind") == "telemetry"])
            assert len(after) > 1 and np.abs(after - before).max() < HUNT, (before, after)
            # a hit, accepted
            link._seq = iter(range(1000, 10**9))
            link.hit(hit, t_hit=time.monotonic() + 0.8, id=20, stroke=20)
            got = _telemetry(link, 1.5)
            # (a second status `OutOfStep` when a stall left the channels apart near the hit)
            statuses = [m for m in got if m.get("kind") == "status" and m["status"] != "OutOfStep"]
            assert [(s["id"], s["status"]) for s in statuses] == [(20, "Accepted")], statuses
            # a plan every 50 ms: one stroke, replaced again and again
            t_hit = time.monotonic() + 2.5
            for k in range(20):
                link.hit(hit, t_hit=t_hit, id=100 + k, stroke=99)
                time.sleep(0.05)
            got = _telemetry(link, 2.0)
            answered = {s["id"] for s in got if s.get("kind") == "status"}
            assert answered == set(range(100, 120)), answered
        finally:
            proc.send_signal(signal.SIGINT)
            out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, out
    kv = dict(line.split("=", 1) for line in stats.read_text().split())
    for name in bad:
        assert int(kv[f"online_{name}"]) == 1, (name, kv)
    assert int(kv["online_duplicate"]) == 1 and int(kv["online_out_of_order"]) == 1
    assert int(kv["online_stale"]) == 1
    assert int(kv["online_status_accepted"]) >= 2
    assert int(kv["cycles_planning"]) > 0 and int(kv["cycles_quiet"]) > 0
    print(
        "latency p99 quiet {} µs / planning {} µs; deadline misses quiet {} / planning {}".format(
            kv["latency_p99_us_quiet"],
            kv["latency_p99_us_planning"],
            kv["deadline_misses_quiet"],
            kv["deadline_misses_planning"],
        )
    )
