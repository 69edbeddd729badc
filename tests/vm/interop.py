"""VM test of issue 27: both interoperability directions with python-canopen on Linux vcan
(SocketCAN on both sides), run by tests/vm/guest.sh in a chroot on the host's filesystem (shared
read-only over 9p by scripts/vm/run.sh), with the host's Python and python-canopen.

    interop.py python-master IFACE BINDIR   # (a) python-canopen masters ttdrive-sim on IFACE
    interop.py ttctl-master IFACE BINDIR    # (b) ttctl masters a LocalNode from the vendor EDS
    interop.py online-hit IFACES BINDIR     # (c) issue 26: ttctl --online hit on ttdrive-sim,
                                            #     gantry6 on three vcans (IFACES a,b,c), a hit
                                            #     sent with ttmanip.ctl.Link over loopback UDP

Prints one line `RESULT ...` and exits 0 when every check of the scenario passed.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the shared scenarios

import canopen  # noqa: E402
import canopen_scenarios as sc  # noqa: E402


def python_master(iface: str, bindir: Path) -> str:
    drive = subprocess.Popen(
        [
            str(bindir / "ttdrive-sim"),
            "--channel",
            f"{iface}:5",
            "--period",
            "0.004",
            "--sync-timeout-ms",
            "1000",
            "--idle-exit",
            "3",
            "--duration",
            "200",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    time.sleep(0.5)
    net = canopen.Network()
    net.connect(interface="socketcan", channel=iface)
    try:
        r = sc.python_master(net)
    finally:
        net.disconnect()
    out = drive.communicate(timeout=60)[0]
    print(out)
    assert "node 5: state SwitchOnDisabled" in out, out
    error = abs(r["position"] - r["target"])
    return (
        f"segmented SDO both ways, abort codes, CiA 402 by SDO, PDOs remapped, CSP: final error "
        f"{error} increments, worst {r['worst']}, quick stop to Switch On Disabled"
    )


def ttctl_master(iface: str, bindir: Path) -> str:
    net = canopen.Network()
    net.connect(interface="socketcan", channel=iface)
    try:
        local, drive = sc.vendor_local_node(net)
        with tempfile.TemporaryDirectory() as d:
            stats = Path(d) / "stats.txt"
            p = subprocess.run(
                sc.ttctl_command(bindir / "ttctl", sc.ttctl_config(Path(d), iface), stats),
                capture_output=True,
                text=True,
                timeout=240,
            )
            out = p.stdout + p.stderr
            print(out)
            sc.check_ttctl_run(p.returncode, out, stats, local, drive)
            result = dict(line.split("=", 1) for line in stats.read_text().split())
    finally:
        net.disconnect()
    return (
        f"vendor EDS: identity checked, 0x1008 uploaded, string downloaded, PDOs remapped; motion "
        f"completed, {drive.syncs} SYNCs, max tracking error {result['max_tracking_error']}"
    )


def online_hit(ifaces: str, bindir: Path) -> str:
    """Issue 26 on real SocketCAN: ttctl --online hit drives six ttdrive-sim axes (gantry6) at the
    VM's 250 Hz; a hit sent with ttmanip.ctl.Link is accepted and executed, bad datagrams counted,
    then SIGINT: controlled stop, exit 0."""
    import signal
    import socket
    import struct

    import ttmanip
    from ttmanip.ctl import Link

    names = ifaces.split(",")
    lines = [
        'robot = "gantry6"',
        "joints = 6",
        "cycle_hz = 250",
        'mode = "csp"',
        "",
        "[watchdog]",
        "feedback_cycles = 100",
        "heartbeat_cycles = 1000",
        "sdo_cycles = 1000",
        "",
        "[online]",
        "silence_s = 30.0",
        "latency_budget_s = 0.5",
        "splice_lead_s = 0.1",
        "telemetry_decimation = 5",
        "",
    ]
    for c, name in enumerate(names):
        lines += ["[[channel]]", f'interface = "{name}"']
        for a in range(2):
            lines += ["[[channel.axis]]", f"node = {a + 1}", f"joint = {2 * c + a}"]
            lines += ["following_error_limit = 0.25"]
    drives = subprocess.Popen(
        [
            str(bindir / "ttdrive-sim"),
            *sum((["--channel", f"{n}:1,2"] for n in names), []),
            "--period",
            "0.004",
            "--sync-timeout-ms",
            "1000",
            "--idle-exit",
            "3",
            "--duration",
            "200",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    time.sleep(0.5)
    with tempfile.TemporaryDirectory() as d, Link(("127.0.0.1", 5005), bind=("127.0.0.1", 5006)) as link:
        cfg, stats = Path(d) / "online.toml", Path(d) / "stats.txt"
        cfg.write_text("\n".join(lines) + "\n")
        ctl = subprocess.Popen(
            [
                str(bindir / "ttctl"),
                "-c",
                str(cfg),
                "--online",
                "hit",
                "--listen",
                "127.0.0.1:5005",
                "--reply",
                "127.0.0.1:5006",
                "--max-seconds",
                "120",
                "--stats",
                str(stats),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        try:
            ready = ttmanip.Robot.builtin("gantry6").ready
            until, at_ready = time.monotonic() + 90, False
            while time.monotonic() < until and not at_ready:
                m = link.receive(timeout=0.5)
                at_ready = (
                    bool(m)
                    and m.get("kind") == "telemetry"
                    and all(abs(a - b) < 5e-3 for a, b in zip(m["q"][:6], ready, strict=True))
                )
            if not at_ready:
                raise RuntimeError("the robot did not reach the ready pose")
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            # a hit datagram cut to 64 bytes: version 1, kind 1, truncated
            s.sendto(b"TTMW" + struct.pack("<HH", 1, 1) + bytes(56), ("127.0.0.1", 5005))
            s.close()
            # As an upper computer does: a hit answered `TooEarly` (the emulated VM on a loaded
            # host can take most of a second to plan) is sent again for its earliest time plus a
            # margin; at most three tries, each counted by the controller.
            t_hit, status = time.monotonic() + 2.0, None
            for attempt in range(1, 4):
                link.hit(ttmanip.DEMO_HIT, t_hit=t_hit, id=attempt, stroke=1)
                status, until = None, time.monotonic() + 10
                while status is None and time.monotonic() < until:
                    m = link.receive(timeout=0.5)
                    if m and m.get("kind") == "status" and m.get("id") == attempt:
                        status = m
                if status is None or status["status"] != "TooEarly":
                    break
                t_hit = max(status["earliest_t_hit"], time.monotonic()) + 1.0 + status["planning_time"]
            time.sleep(3.0 + max(0.0, t_hit - time.monotonic()))
        finally:
            ctl.send_signal(signal.SIGINT)
            out = ctl.communicate(timeout=60)[0]
            drives.communicate(timeout=60)
        print(out)
        if status is None or status["status"] != "Accepted":
            raise RuntimeError(f"hit status {status}")
        if ctl.returncode != 0:
            raise RuntimeError(f"ttctl exit {ctl.returncode}")
        kv = dict(line.split("=", 1) for line in stats.read_text().split())
        if kv["online_truncated"] != "1" or kv["online_status_accepted"] != "1" or kv["fault"] != "none":
            raise RuntimeError(f"stats {kv}")
    return (
        f"hit accepted (planning {status['planning_time'] * 1e3:.1f} ms) and executed on "
        f"{len(names)} vcans at 250 Hz, truncated datagram counted, "
        f"latency p99 quiet {kv['latency_p99_us_quiet']} us / "
        f"planning {kv['latency_p99_us_planning']} us, deadline misses {kv['deadline_misses']}"
    )


if __name__ == "__main__":
    scenario, iface, bindir = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    run = {"python-master": python_master, "ttctl-master": ttctl_master, "online-hit": online_hit}[scenario]
    try:
        print("RESULT " + run(iface, bindir))
    except Exception as e:  # every failure is reported as the scenario's result
        print(f"RESULT {type(e).__name__}: {e}")
        sys.exit(1)
