"""The controller's datagram format from Python (issue 26, ttcan::online::wire): what a camera
process or a notebook sends, byte for byte as the Rust core decodes it."""

from __future__ import annotations

import socket
import struct

import numpy as np
import pytest
import ttmanip
from ttmanip import _ttmanip as _t
from ttmanip.ctl import Link


def test_a_hit_datagram_is_the_documented_layout():
    hit = ttmanip.DEMO_HIT
    data = _t.wire_hit(7, 2, 12.5, hit.pose, hit.twist, 41, 3.25)
    assert len(data) == 184
    # header: magic, version, kind, seq, sent (docs/online.md), read with the standard library
    magic, version, kind, seq, sent = struct.unpack_from("<4sHHQd", data)
    assert (magic, version, kind, seq, sent) == (b"TTMW", _t.WIRE_VERSION, 1, 41, 3.25)
    hit_id, stroke, t_hit = struct.unpack_from("<IId", data, 24)
    assert (hit_id, stroke, t_hit) == (7, 2, 12.5)
    values = np.array(struct.unpack_from("<18d", data, 40))
    np.testing.assert_array_equal(values[:9].reshape(3, 3), hit.pose[:3, :3])
    np.testing.assert_array_equal(values[9:12], hit.pose[:3, 3])
    np.testing.assert_array_equal(values[12:], hit.twist)
    d = _t.wire_decode(data)
    assert d["kind"] == "hit" and d["id"] == 7 and d["stroke"] == 2 and d["seq"] == 41
    np.testing.assert_array_equal(d["centre"], hit.centre)


def test_malformed_datagrams_are_refused_saying_why():
    good = _t.wire_observation(3, 1.25, [-1.0, 0.2, 0.3], 1, 0.0)
    assert len(good) == 64 and _t.wire_decode(good)["position"] == [-1.0, 0.2, 0.3]
    cases = {
        good[:10]: "truncated",
        good[:-1]: "truncated",
        good + b"\0": "oversized",
        b"XXXX" + good[4:]: "magic",
        good[:4] + struct.pack("<H", 2) + good[6:]: "version",
        good[:6] + struct.pack("<H", 9) + good[8:]: "kind",
        good[:48] + struct.pack("<d", float("nan")) + good[56:]: "non-finite",
    }
    for data, words in cases.items():
        with pytest.raises(ttmanip.TtmanipError, match=words):
            _t.wire_decode(data)
    with pytest.raises(ttmanip.TtmanipError):
        _t.wire_observation(3, 1.25, [np.nan, 0, 0], 1, 0.0)


def test_a_link_sends_numbered_datagrams_over_udp():
    controller = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    controller.bind(("127.0.0.1", 0))
    controller.settimeout(2.0)
    with Link(controller.getsockname(), bind=("127.0.0.1", 0)) as link:
        link.hit(ttmanip.DEMO_HIT, t_hit=12.5, id=1)
        link.observation(5, 0.75, [0.1, 0.2, 0.3])
        first, back = controller.recvfrom(1024)
        second, _ = controller.recvfrom(1024)
        assert [_t.wire_decode(d)["seq"] for d in (first, second)] == [1, 2]
        assert _t.wire_decode(second)["kind"] == "observation"
        controller.sendto(first, back)  # any well-formed datagram comes back decoded
        assert link.receive(timeout=2.0)["kind"] == "hit"
        controller.sendto(b"junk", back)
        with pytest.raises(ttmanip.TtmanipError, match="truncated"):
            link.receive(timeout=2.0)
        assert link.receive(timeout=0.05) is None
    controller.close()
