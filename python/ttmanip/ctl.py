"""Joint trajectory files for the embedded controller ``ttctl`` (crates/ttcan/src/bin/ttctl.rs).

The file is CSV, SI units, one row per sample: ``t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun`` after a
``# ttctl trajectory v1`` comment line; ``t`` strictly increasing. ``ttctl --trajectory FILE``
follows it (CSP targets ``q``, torque offset 0x60B2 from ``tau``).

``python -m ttmanip.ctl OUT.csv`` writes the gantry6 hitting stroke of ``ttmanip.pipeline``'s
default hit request (the one the VM test runs).

:class:`Link` speaks the controller's datagram format (``ttcan::online::wire``, ``docs/online.md``)
over UDP: hits and ball observations out, plan status and telemetry back.
"""

from __future__ import annotations

import itertools
import socket
import sys
import time
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from . import TtmanipError
from . import _ttmanip as _t

__all__ = ["Link", "write_trajectory", "write_stroke"]


class TrajectoryFileError(TtmanipError, ValueError):
    """A trajectory handed to :func:`write_trajectory` is malformed."""


def _real(name: str, a: ArrayLike) -> np.ndarray:
    """``a`` as float64 by the bindings' one conversion (complex, bool, string data refused)."""
    try:
        return _t.real_array(a, name)
    except (TypeError, ValueError) as e:
        raise TrajectoryFileError(f"{name}: not an array of real numbers ({e})") from None


def _matrix(name: str, a: ArrayLike, k: int, n: int | None) -> np.ndarray:
    m = _real(name, a)
    if m.ndim == 1 and n in (None, 1) and m.shape[0] == k:
        m = m[:, None]
    if m.ndim != 2 or m.shape[0] != k or (n is not None and m.shape[1] != n):
        want = f"({k}, {'n' if n is None else n})"
        raise TrajectoryFileError(f"{name}: shape {m.shape}, expected {want}")
    if not np.all(np.isfinite(m)):
        raise TrajectoryFileError(f"{name}: contains NaN or infinite values")
    return m


def write_trajectory(
    path: str | Path,
    t: ArrayLike,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    tau_ff: ArrayLike | None = None,
) -> Path:
    """Writes a joint trajectory for ``ttctl``: times ``t`` (K,) s strictly increasing, positions
    ``q``, velocities ``qd``, accelerations ``qdd`` and torque feed-forward ``tau_ff`` (K, n) in
    SI (rad or m, N·m or N; ``tau_ff`` zero when omitted). Returns the path."""
    tt = _real("t", t).reshape(-1)
    k = tt.shape[0]
    if k < 2:
        raise TrajectoryFileError(f"t: {k} samples, a trajectory needs at least 2")
    if not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0.0):
        raise TrajectoryFileError("t: must be finite and strictly increasing")
    qm = _matrix("q", q, k, None)
    n = qm.shape[1]
    qdm = _matrix("qd", qd, k, n)
    qddm = _matrix("qdd", qdd, k, n)
    taum = np.zeros_like(qm) if tau_ff is None else _matrix("tau_ff", tau_ff, k, n)
    head = ["t"] + [f"{c}{j + 1}" for c in ("q", "qd", "qdd", "tau") for j in range(n)]
    data = np.column_stack([tt, qm, qdm, qddm, taum])
    p = Path(path)
    with p.open("w", encoding="ascii") as f:
        f.write("# ttctl trajectory v1\n")
        f.write(",".join(head) + "\n")
        np.savetxt(f, data, delimiter=",", fmt="%.9g")
    return p


def write_stroke(path: str | Path, rate_hz: float = 1000.0) -> Path:
    """Plans the gantry6 hitting stroke of the demo hit ``ttmanip.DEMO_HIT`` (start → hit →
    ready) and writes it with :func:`write_trajectory` (no torque feed-forward: the virtual
    drives of ``ttdrive-sim`` carry their motor model's load, not the robot's)."""
    from . import pipeline, robots

    try:
        rate = float(rate_hz)
    except (TypeError, ValueError, OverflowError):
        rate = float("nan")  # a huge int (10**400) or a non-number: refused below, named
    if isinstance(rate_hz, bool) or not (np.isfinite(rate) and rate > 0):
        shown = f"an integer of {len(str(rate_hz))} digits" if isinstance(rate_hz, int) else repr(rate_hz)
        raise TtmanipError(f"rate_hz: expected a sample rate > 0 Hz, got {shown}")
    robot = robots.gantry6()
    plan = pipeline.plan_hit(robot, pipeline.DEMO_HIT, raise_on_failure=True)
    t, q, qd, qdd = plan.sample(rate)
    return write_trajectory(path, t, q, qd, qdd)


#: Longest wait of :meth:`Link.receive`, s (about 11 days; ``None`` waits without end).
MAX_RECEIVE_TIMEOUT = 1e6


def _address(name: str, address) -> tuple[str, int]:
    """``address`` as (host, port), the port an integer in 0..=65535; otherwise a TtmanipError
    naming ``name`` (the socket's own ``OverflowError`` named neither)."""
    try:
        host, port = address
    except (TypeError, ValueError):
        raise TtmanipError(f"{name}: expected (host, port), got {address!r}") from None
    if not isinstance(host, str):
        raise TtmanipError(f"{name}: the host must be a string, got {host!r}")
    if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= port <= 65535:
        raise TtmanipError(f"{name}: the port must be an integer in 0..=65535, got {port!r}")
    return host, int(port)


class Link:
    """A UDP link to a controller at ``address`` (host, port): sends hits and ball observations in
    the controller's datagram format (version ``_ttmanip.WIRE_VERSION``), numbered by one sequence
    counter, and receives its status and telemetry datagrams as dicts. ::

        link = ttmanip.ctl.Link(("192.168.1.20", 5005))
        link.hit(ttmanip.DEMO_HIT, t_hit=12.5, id=1)
        print(link.receive(timeout=0.5))     # {'kind': 'status', 'id': 1, 'status': 'Accepted', ...}
    """

    def __init__(self, address: tuple[str, int], bind: tuple[str, int] = ("", 0)):
        self.address = _address("address", address)
        #: The local (host, port) the socket was asked to bind (port 0: any free port).
        self.bind = _address("bind", bind)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._sock.bind(self.bind)
        except BaseException:
            self._sock.close()
            raise
        self._seq = itertools.count(1)

    def __reduce__(self):
        # A socket does not pickle: a copy is a new link to the same controller, with a socket
        # of its own bound as this one was asked to be (issue 31: every public class pickles).
        return (Link, (self.address, self.bind))

    def hit(self, hit, t_hit: float, id: int, stroke: int = 0) -> bytes:
        """Sends ``hit`` (a :class:`ttmanip.Hit`: racket pose and twist) for the hit time ``t_hit``
        (s, controller clock); a newer hit with the same ``stroke`` replaces an older one."""
        from .pipeline import Hit

        if not isinstance(hit, Hit):
            raise TtmanipError(f"hit: expected a ttmanip.Hit, got {type(hit).__name__}")
        data = _t.wire_hit(id, stroke, t_hit, hit.pose, hit.twist, next(self._seq), time.monotonic())
        self._open()
        self._sock.sendto(data, self.address)
        return data

    def observation(self, id: int, camera_time: float, position: ArrayLike) -> bytes:
        """Sends one camera observation of ball ``id``: its centre ``position`` (m, world frame)
        at ``camera_time`` (s, camera clock)."""
        data = _t.wire_observation(id, camera_time, position, next(self._seq), time.monotonic())
        self._open()
        self._sock.sendto(data, self.address)
        return data

    def receive(self, timeout: float | None = None) -> dict | None:
        """The next datagram from the controller, decoded (``None`` after ``timeout`` s, a real
        number in [0, 1e6]; ``None``: wait for one); a malformed one raises
        :class:`ttmanip.TtmanipError` saying why."""
        if timeout is not None:
            # the socket's own errors (ValueError for NaN or < 0, OverflowError for 1e300 or
            # 10**400) named no argument
            if isinstance(timeout, bool) or not isinstance(timeout, (int, float, np.integer, np.floating)):
                raise TypeError(
                    f"timeout: expected a number of seconds or None, got {type(timeout).__name__}"
                )
            if not 0.0 <= timeout <= MAX_RECEIVE_TIMEOUT:
                raise TtmanipError(
                    f"timeout: expected seconds in [0, {MAX_RECEIVE_TIMEOUT:g}] or None, got {timeout!r}"
                )
            timeout = float(timeout)
        self._open()
        self._sock.settimeout(timeout)
        try:
            data, _ = self._sock.recvfrom(_t.WIRE_MAX_LEN + 1)
        except TimeoutError:
            return None
        return _t.wire_decode(data)

    def close(self) -> None:
        """Closes the socket (the link sends and receives no more)."""
        self._sock.close()

    def _open(self) -> None:
        # a closed socket's own error was "[Errno 9] Bad file descriptor"
        if self._sock.fileno() < 0:
            raise TtmanipError("link: closed; make a new ttmanip.ctl.Link to talk to the controller")

    def __enter__(self) -> Link:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


if __name__ == "__main__":  # pragma: no cover - exercised by scripts/vm/build.sh
    if len(sys.argv) != 2:
        sys.exit("usage: python -m ttmanip.ctl OUT.csv")
    print(write_stroke(sys.argv[1]))
