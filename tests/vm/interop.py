"""VM test of issue 27: both interoperability directions with python-canopen on Linux vcan
(SocketCAN on both sides), run by tests/vm/guest.sh in a chroot on the host's filesystem (shared
read-only over 9p by scripts/vm/run.sh), with the host's Python and python-canopen.

    interop.py python-master IFACE BINDIR   # (a) python-canopen masters ttdrive-sim on IFACE
    interop.py ttctl-master IFACE BINDIR    # (b) ttctl masters a LocalNode from the vendor EDS

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
        [str(bindir / "ttdrive-sim"), "--channel", f"{iface}:5", "--period", "0.004",
         "--sync-timeout-ms", "1000", "--idle-exit", "3", "--duration", "200"],
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
    return (f"segmented SDO both ways, abort codes, CiA 402 by SDO, PDOs remapped, CSP: final error "
            f"{error} increments, worst {r['worst']}, quick stop to Switch On Disabled")


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
    return (f"vendor EDS: identity checked, 0x1008 uploaded, string downloaded, PDOs remapped; motion "
            f"completed, {drive.syncs} SYNCs, max tracking error {result['max_tracking_error']}")


if __name__ == "__main__":
    scenario, iface, bindir = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    run = {"python-master": python_master, "ttctl-master": ttctl_master}[scenario]
    try:
        print("RESULT " + run(iface, bindir))
    except Exception as e:  # every failure is reported as the scenario's result
        print(f"RESULT {type(e).__name__}: {e}")
        sys.exit(1)
