"""The two interoperability scenarios of issue 27 with python-canopen, shared by the fast test
(tests/test_canopen_interop.py: python-can's virtual bus bridged to the binaries' `stdio`
interface) and the VM test (tests/vm/interop.py: Linux vcan, SocketCAN on both sides).

(a) python-canopen as master of `ttdrive-sim` ([`python_master`]); (b) `ttctl` as master of a drive
emulated on python-canopen's LocalNode built from a vendor device file whose default mapping
differs from the project's ([`EmulatedDrive`], [`ttctl_config`], [`check_ttctl_run`]).
"""

from __future__ import annotations

import math
import struct
import threading
import time
from pathlib import Path

import canopen

ROOT = Path(__file__).resolve().parents[1]
EDS = ROOT / "crates" / "ttcan" / "devices" / "ttdrive-sim.eds"
VENDOR_EDS = ROOT / "crates" / "ttcan" / "tests" / "data" / "vendor-402.eds"


def abort_code(f) -> int:
    """The SDO abort code `f()` raises."""
    try:
        f()
    except canopen.SdoAbortedError as e:
        return e.code
    raise AssertionError(f"{f} was not aborted")


def python_master(net: canopen.Network) -> dict:
    """Scenario (a) on a connected network with `ttdrive-sim` node 5 on it; returns measures."""
    node = canopen.RemoteNode(5, str(EDS))
    net.add_node(node)
    # reset communication and wait for the boot-up message (listening before the command: the
    # drive may answer before python-canopen's wait_for_bootup starts waiting)
    booted = threading.Event()
    net.subscribe(0x705, lambda can_id, data, timestamp: data[:1] == b"\x00" and booted.set())
    node.nmt.send_command(0x82)
    assert booted.wait(10), "no boot-up message"
    node.sdo.RESPONSE_TIMEOUT = 2.0

    # SDO: segmented upload (33 bytes) and download (42 bytes), read back
    assert node.sdo[0x1008].raw == "ttdrive-sim virtual CiA 402 drive"
    label = "left shoulder, pitch axis (python-canopen)"
    node.sdo[0x2000].raw = label
    assert node.sdo[0x2000].raw == label
    assert node.sdo[0x1018][2].raw == 0x74740402
    assert node.sdo[0x6502].raw & 0x380 == 0x380  # CSP, CSV, CST

    def block_upload() -> None:
        with node.sdo.open(0x1008, 0, "rb", block_transfer=True) as f:
            f.read()

    assert abort_code(block_upload) == 0x05040001  # block transfer: command specifier not supported
    assert abort_code(lambda: setattr(node.sdo[0x6041], "raw", 0)) == 0x06010002  # read-only
    assert abort_code(lambda: setattr(node.sdo[0x6060], "raw", 1)) == 0x06090030  # mode 1 not supported
    assert abort_code(lambda: node.sdo.upload(0x2345, 0)) == 0x06020000
    assert abort_code(lambda: node.sdo.download(0x6040, 0, b"\x06")) == 0x06070010  # 1 byte for 2

    # CiA 402 by SDO: Switch On Disabled right after boot-up, before any SYNC or NMT Start
    def state() -> int:
        return node.sdo[0x6041].raw & 0x6F

    assert state() & 0x4F == 0x40
    for cw, want in [
        (0x06, 0x21),
        (0x07, 0x23),
        (0x0F, 0x27),
        (0x07, 0x23),
        (0x00, 0x40),
        (0x06, 0x21),
        (0x07, 0x23),
        (0x0F, 0x27),
    ]:
        node.sdo[0x6040].raw = cw
        got = state() if want != 0x40 else state() & 0x4F
        assert got == want, f"controlword {cw:#x}: statusword state bits {got:#x}, expected {want:#x}"

    # remap both PDOs by SDO (python-canopen's save: invalidate, count 0, entries, count, revalidate)
    node.rpdo.read()
    node.tpdo.read()
    node.rpdo[1].clear()
    node.rpdo[1].add_variable(0x6040)
    node.rpdo[1].add_variable(0x607A)
    node.rpdo[1].trans_type = 1
    node.rpdo[1].enabled = True
    node.tpdo[1].clear()
    node.tpdo[1].add_variable(0x6041)
    node.tpdo[1].add_variable(0x6064)
    node.tpdo[1].add_variable(0x6061)
    node.tpdo[1].trans_type = 1
    node.tpdo[1].enabled = True
    node.rpdo.save()
    node.tpdo.save()
    assert [node.sdo[0x1600][k].raw for k in range(3)] == [2, 0x60400010, 0x607A0020]
    assert [node.sdo[0x1A00][k].raw for k in range(4)] == [3, 0x60410010, 0x60640020, 0x60610008]
    # CiA 301: the mapping of a valid PDO cannot change
    assert abort_code(lambda: setattr(node.sdo[0x1600][0], "raw", 0)) == 0x06010000

    # CSP with SYNC: 0.2 rad (20000 increments) in 1 s, 4 ms period
    q0 = node.sdo[0x6064].raw
    node.rpdo[1]["Controlword"].raw = 0x0F
    node.rpdo[1]["Target position"].raw = q0
    node.nmt.state = "OPERATIONAL"
    amplitude, n, period = 20000, 250, 0.004
    worst = 0
    for k in range(n + 100):
        target = q0 + int(round(amplitude * 0.5 * (1 - math.cos(math.pi * min(k, n) / n))))
        node.rpdo[1]["Target position"].raw = target
        node.rpdo[1].transmit()
        net.sync.transmit()
        time.sleep(period)
        if k > 10 and node.tpdo[1].is_received:
            worst = max(worst, abs(node.tpdo[1]["Position actual value"].raw - target))
    # (no pause without SYNC here: the drive's SYNC watchdog would rightly fault it)
    position = node.tpdo[1]["Position actual value"].raw
    assert abs(position - (q0 + amplitude)) < 300, (position, q0 + amplitude)  # 3 mrad
    assert node.tpdo[1]["Statusword"].raw & 0x6F == 0x27
    assert worst < 2000, worst  # 20 mrad, the TPDO answering the SYNC before the target's
    # quick stop by SDO: Quick Stop Active, the drive's stop ramp over SYNCs, Switch On Disabled
    node.sdo[0x6040].raw = 0x02
    for _ in range(200):
        net.sync.transmit()
        time.sleep(period)
        if state() & 0x4F == 0x40:
            break
    assert state() & 0x4F == 0x40, (hex(node.sdo[0x6041].raw), [hex(e.code) for e in node.emcy.log])
    return {"position": position, "target": q0 + amplitude, "worst": worst}


class EmulatedDrive:
    """A CiA 402 drive on python-canopen's LocalNode: python-canopen serves its SDOs from the
    vendor device file's dictionary; this class adds NMT (boot-up after a reset, defaults of the
    communication area restored), the state machine on the controlword, RPDO1 and a TPDO1 sent at
    every SYNC with whatever mapping the dictionary holds, and an ideal position loop."""

    SW = {"SOD": 0x40, "RTSO": 0x21, "SO": 0x23, "OE": 0x27, "QSA": 0x07}

    def __init__(self, net: canopen.Network, local: canopen.LocalNode):
        self.net, self.local, self.id = net, local, local.id
        self.state, self.operational, self.syncs, self.last_cw = "SOD", False, 0, 0
        self.pending: bytes | None = None
        self.position = 12345
        self.lock = threading.Lock()
        net.subscribe(0x000, self.on_nmt)
        net.subscribe(0x080, self.on_sync)
        net.subscribe(0x200 + self.id, self.on_rpdo)
        self.publish()

    def publish(self) -> None:
        sw = self.SW[self.state] | (0x10 if self.state != "SOD" else 0) | 0x200
        self.local.set_data(0x6041, 0, struct.pack("<H", sw))
        self.local.set_data(0x6064, 0, struct.pack("<i", self.position))
        self.local.set_data(0x6061, 0, self.local.get_data(0x6060, 0))

    def on_nmt(self, can_id, data, timestamp) -> None:
        cmd, node = data[0], data[1]
        if node not in (0, self.id):
            return
        with self.lock:
            if cmd in (0x81, 0x82):
                for index in list(self.local.data_store):
                    if index < 0x2000 or cmd == 0x81:
                        del self.local.data_store[index]
                self.local.nmt.stop_heartbeat()
                self.state, self.operational, self.pending = "SOD", False, None
                self.publish()
                self.local.nmt.send_command(0x82)  # sends the boot-up message
                self.local.nmt.send_command(0x80)  # pre-operational
            elif cmd == 0x01:
                self.operational = True
            elif cmd in (0x02, 0x80):
                self.operational = False

    def on_rpdo(self, can_id, data, timestamp) -> None:
        cob = struct.unpack("<I", self.local.get_data(0x1400, 1))[0]
        if self.operational and not cob & 0x80000000 and cob & 0x7FF == can_id:
            self.pending = bytes(data)

    def controlword(self, cw: int) -> None:
        s = self.state
        if not cw & 0x02:
            s = "SOD"
        elif s == "OE" and not cw & 0x04:
            s = "QSA"
        elif s == "QSA":
            pass
        elif not cw & 0x04:
            s = "SOD"
        elif cw & 0x0F == 0x06 and s in ("SOD", "SO", "OE"):
            s = "RTSO"
        elif cw & 0x0F == 0x07 and s in ("RTSO", "OE"):
            s = "SO"
        elif cw & 0x0F == 0x0F and s in ("RTSO", "SO"):
            s = "SO" if s == "RTSO" else "OE"
        self.state, self.last_cw = s, cw

    def mapping(self, index: int) -> list[tuple[int, int, int]]:
        n = struct.unpack("<B", self.local.get_data(index, 0))[0]
        words = [struct.unpack("<I", self.local.get_data(index, k))[0] for k in range(1, n + 1)]
        return [(w >> 16, (w >> 8) & 0xFF, w & 0xFF) for w in words]

    def on_sync(self, can_id, data, timestamp) -> None:
        with self.lock:
            if not self.operational:
                return
            self.syncs += 1
            cob = struct.unpack("<I", self.local.get_data(0x1800, 1))[0]
            if not cob & 0x80000000:
                self.publish()
                entries = self.mapping(0x1A00)
                payload = b"".join(self.local.get_data(i, s)[: bits // 8] for i, s, bits in entries)
                self.net.send_message(cob & 0x7FF, payload)
            if self.pending is not None:
                data, self.pending, offset = self.pending, None, 0
                for i, s, bits in self.mapping(0x1600):
                    self.local.set_data(i, s, data[offset : offset + bits // 8])
                    offset += bits // 8
                self.controlword(struct.unpack("<H", self.local.get_data(0x6040, 0))[0])
            if self.state == "QSA":
                self.state = "SOD"  # the stop ramp of an ideal drive ends at once
            if self.state == "OE":
                self.position = struct.unpack("<i", self.local.get_data(0x607A, 0))[0]
            self.publish()


def ttctl_config(directory: Path, interface: str) -> Path:
    """The ttctl configuration of scenario (b): node 5 on `interface`, the vendor device file, a
    string in the SDO initialisation list, 100 Hz, the demo motion on joint 0."""
    config = directory / "ctl.toml"
    config.write_text(
        f"""cycle_hz = 100
approach_s = 0.2
[watchdog]
feedback_cycles = 50
heartbeat_cycles = 1000
sdo_cycles = 100
enable_cycles = 1000
stop_cycles = 300
[[channel]]
interface = "{interface}"
[[channel.axis]]
node = 5
joint = 0
following_error_limit = 0.5
device_file = "{VENDOR_EDS}"
sdo = [{{ index = 0x2001, value = "ttmanip axis 0: shoulder pitch" }}]
"""
    )
    return config


def ttctl_command(ttctl: Path, config: Path, stats: Path) -> list[str]:
    """The ttctl command line of scenario (b)."""
    return [
        str(ttctl),
        "--config",
        str(config),
        "--demo",
        "--amplitude",
        "0.05",
        "--stats",
        str(stats),
        "--max-seconds",
        "60",
    ]


def check_ttctl_run(rc: int, out: str, stats: Path, local: canopen.LocalNode, drive: EmulatedDrive) -> None:
    """The checks of scenario (b) once ttctl has ended."""
    assert rc == 0, out
    result = dict(line.split("=", 1) for line in stats.read_text().split())
    assert result["completed"] == "1" and result["fault"] == "none", result
    # ttctl read the device file: its mapping line, the name it uploaded (segmented)
    assert "node 5: " in out and "RPDO1 [0x607a:0 0x60b2:0 0x6040:0] 8 B" in out, out
    assert 'device name (0x1008) "Example Servo 402"' in out, out
    # and configured the LocalNode: remapped to the project's PDOs, the vendor's others invalidated
    assert drive.mapping(0x1600) == [(0x607A, 0, 32), (0x60B2, 0, 16), (0x6040, 0, 16)]
    assert drive.mapping(0x1A00) == [(0x6064, 0, 32), (0x6078, 0, 16), (0x6041, 0, 16)]
    for comm in (0x1401, 0x1801):
        assert local.sdo[comm][1].raw & 0x80000000, hex(local.sdo[comm][1].raw)
    assert local.sdo[0x1400][2].raw == 1 and local.sdo[0x1800][2].raw == 1  # synchronous
    assert (local.sdo[0x60C2][1].raw, local.sdo[0x60C2][2].raw) == (1, -2)  # 1 · 10⁻² s = the cycle
    assert local.sdo[0x1017].raw == 100
    assert local.sdo[0x2001].raw == "ttmanip axis 0: shoulder pitch"  # segmented download by ttcan
    assert drive.syncs > 200 and drive.state == "SOD", (drive.syncs, drive.state)


def vendor_local_node(net: canopen.Network) -> tuple[canopen.LocalNode, EmulatedDrive]:
    """Node 5 emulated on a LocalNode from the vendor device file, on `net`."""
    local = canopen.LocalNode(5, canopen.import_od(str(VENDOR_EDS), 5))
    net.add_node(local)
    drive = EmulatedDrive(net, local)
    # the vendor's own default mapping, before ttctl
    assert drive.mapping(0x1600) == [(0x6040, 0, 16), (0x6060, 0, 8)]
    return local, drive
