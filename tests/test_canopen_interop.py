"""Issue 27: the project's CANopen code against python-canopen, a stack no one here wrote.

No VM and no vcan needed: `ttdrive-sim` and `ttctl` run with the interface `stdio` (frames as
`CAN <id>#<hex>` lines, `ttcan::bus::stdio`) and a bridge thread carries their frames to and
from python-can's in-process `virtual` bus, where python-canopen sits.

The scenarios are in tests/canopen_scenarios.py (the VM test runs them on vcan too):

(a) python-canopen as master: reads and writes `ttdrive-sim` by SDO (segmented upload of 0x1008,
    segmented download of a string, the abort codes of a block transfer and of bad writes), walks
    the CiA 402 state machine by SDO from Switch On Disabled right after boot-up, remaps both PDOs
    by SDO, runs a CSP motion with SYNC and ends with a quick stop.
(b) `ttctl` as master: configures a drive emulated on python-canopen's `LocalNode`, built from a
    vendor CiA 402 device file whose default mapping differs from the project's, from that file
    (identity checked, segmented upload of 0x1008, segmented download of a string, PDOs remapped),
    and runs the demo motion on it to completion.
"""

from __future__ import annotations

import os
import subprocess
import threading
import uuid
from pathlib import Path

import can
import canopen
import canopen_scenarios as sc
import pytest

ROOT = sc.ROOT

# real time: SYNC-driven motions through a bridge thread (scripts/test.sh runs these alone)
pytestmark = pytest.mark.serial


@pytest.fixture(scope="module")
def bins() -> Path:
    """Directory of the `ttctl` and `ttdrive-sim` binaries ($TTCAN_BIN_DIR, else target/debug,
    built there by cargo when missing)."""
    d = Path(os.environ.get("TTCAN_BIN_DIR", ROOT / "target" / "debug"))
    if not ((d / "ttctl").exists() and (d / "ttdrive-sim").exists()):
        subprocess.run(
            ["cargo", "build", "--quiet", "-p", "ttcan", "--bin", "ttctl", "--bin", "ttdrive-sim"],
            cwd=ROOT,
            check=True,
        )
        d = ROOT / "target" / "debug"
    return d


class Bridge:
    """Runs a ttcan binary on the interface `stdio` and carries its frames to and from a
    python-can virtual bus channel; keeps its other output lines."""

    def __init__(self, args: list[str], channel: str):
        self.bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
        self.proc = subprocess.Popen(
            args,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            bufsize=1,
        )
        self.lines: list[str] = []
        self.frames_out = 0
        self.running = True
        self.threads = [
            threading.Thread(target=self._from_process, daemon=True),
            threading.Thread(target=self._to_process, daemon=True),
        ]
        for t in self.threads:
            t.start()

    def _from_process(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            line = line.rstrip("\n")
            if line.startswith("CAN "):
                ident, data = line[4:].split("#")
                self.bus.send(
                    can.Message(arbitration_id=int(ident, 16), data=bytes.fromhex(data), is_extended_id=False)
                )
                self.frames_out += 1
            else:
                self.lines.append(line)

    def _to_process(self) -> None:
        assert self.proc.stdin is not None
        while self.running:
            msg = self.bus.recv(0.05)
            if msg is None or msg.is_error_frame or msg.is_extended_id or msg.is_remote_frame:
                continue
            try:
                self.proc.stdin.write(f"CAN {msg.arbitration_id:03X}#{msg.data.hex().upper()}\n")
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError, OSError):
                return

    def wait(self, timeout: float) -> int:
        rc = self.proc.wait(timeout)
        self.threads[0].join(2)
        return rc

    def close(self) -> None:
        """Closes the process' input (a ttdrive-sim then prints its drives' states and exits)."""
        self.running = False
        self.threads[1].join(2)
        if self.proc.stdin is not None:
            try:
                self.proc.stdin.close()
            except BrokenPipeError:  # the process has already ended
                pass
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.terminate()
            self.proc.wait(10)
        self.threads[0].join(2)
        self.bus.shutdown()

    def output(self) -> str:
        return "\n".join(self.lines)


def test_python_canopen_master_drives_ttdrive_sim(bins: Path) -> None:
    channel = f"ttmanip-{uuid.uuid4().hex}"
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    drive = Bridge(
        [
            str(bins / "ttdrive-sim"),
            "--channel",
            "stdio:5",
            "--period",
            "0.004",
            "--sync-timeout-ms",
            "1000",
            "--idle-exit",
            "5",
            "--duration",
            "120",
        ],
        channel,
    )
    try:
        sc.python_master(net)
    finally:
        net.disconnect()
        drive.close()
    out = drive.output()
    assert "node 5: state SwitchOnDisabled" in out, out


def test_ttctl_configures_a_local_node_from_its_vendor_device_file(bins: Path, tmp_path: Path) -> None:
    channel = f"ttmanip-{uuid.uuid4().hex}"
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    local, drive = sc.vendor_local_node(net)
    stats = tmp_path / "stats.txt"
    ctl = Bridge(sc.ttctl_command(bins / "ttctl", sc.ttctl_config(tmp_path, "stdio"), stats), channel)
    try:
        rc = ctl.wait(120)
    finally:
        ctl.close()
        net.disconnect()
    print(ctl.output())
    sc.check_ttctl_run(rc, ctl.output(), stats, local, drive)
