"""The hardware-in-the-loop rally (issue 26 item 6): the rally's incoming balls played in real
time against a running ``ttctl`` in ball mode.

For each ball the simulated camera of the core (``_ttmanip.ball_rally_observations``: the rally's
serve, flight, rate, noise, outliers and time-stamp error for the same seed and ball) is streamed
over UDP with :class:`ttmanip.ctl.Link`, every observation sent at its exposure plus the camera's
latency on this host's monotonic clock (the camera clock; the header's send time is the same
clock, so the controller can relate its clock to it). The controller's telemetry (measured joint
states) and plan status come back; the racket is put where forward kinematics of the measured
joints puts it and the ball is scored by the rally's own scoring (``_ttmanip.ball_rally_score``).
The controller's clock is related to this host's by the smallest delay of its telemetry
(arrival − controller time), the same min filter the controller's ball brain uses.
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import numpy as np

from . import TtmanipError
from . import _ttmanip as _t
from .ctl import Link

__all__ = ["HilError", "find_ttctl", "play", "run"]


class HilError(TtmanipError):
    """The hardware-in-the-loop rally cannot run (no controller, no ball mode, no telemetry)."""


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class _Listener:
    """Collects the controller's datagrams on a thread: telemetry rows and status dicts, each
    with its arrival time on this host's monotonic clock."""

    def __init__(self, link: Link):
        self.link = link
        self.telemetry: list[tuple[float, float, np.ndarray, np.ndarray]] = []
        self.status: list[tuple[float, dict]] = []
        self.refused = 0
        # (controller time, fault bits) of every telemetry row with a fault bit set
        self.faults: list[tuple[float, int]] = []
        # what stopped the thread, if anything did (reported by :meth:`check`, never swallowed)
        self.error: BaseException | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                try:
                    d = self.link.receive(timeout=0.05)
                except TtmanipError:
                    self.refused += 1
                    continue
                if d is not None:
                    self._take(d)
        except BaseException as e:  # noqa: BLE001 - reported by check(), the run stops on it
            self.error = e

    def _take(self, d: dict) -> None:
        now = time.monotonic()
        if d["kind"] == "telemetry":
            if d["faults"]:
                self.faults.append((d["time"], int(d["faults"])))
            self.telemetry.append((now, d["time"], np.asarray(d["q"]), np.asarray(d["qd"])))
        elif d["kind"] == "status":
            self.status.append((now, d))

    def check(self) -> None:
        """Raises :class:`HilError` when the listener thread stopped on an exception."""
        if self.error is not None:
            raise HilError(f"the telemetry listener stopped: {self.error!r}") from self.error

    def fault_since(self, t: float) -> int:
        """The fault bits (bit j: joint j's channel stopped) of the telemetry from controller time
        ``t`` (s) on; 0: none."""
        bits = 0
        for tc, f in reversed(self.faults):
            if tc < t:
                break
            bits |= f
        return bits

    def offset(self) -> float:
        """This host's monotonic clock minus the controller's (s), smallest delay seen."""
        if not self.telemetry:
            raise HilError("no telemetry from the controller: is it running in ball mode with --reply here?")
        return min(a - c for a, c, _, _ in self.telemetry)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=1.0)


def _sleep_until(t: float) -> None:
    while True:
        dt = t - time.monotonic()
        if dt <= 0:
            return
        time.sleep(min(dt, 0.002) if dt > 0.003 else 0)


def play(
    link: Link, listener: _Listener, index: int, seed: int = 0, world: bool = False, settle: float = 0.6
) -> dict:
    """Plays ball ``index`` of the rally of ``seed`` against the controller behind ``link``:
    streams its observations in real time, waits ``settle`` s after the camera's last frame, and
    scores it from the measured joint states. Returns the ball's record (status, returned, hit
    time on the ball's clock, racket error, planning time, ...)."""
    cam = _t.ball_rally_observations(index, seed, world)
    ball_id = index + 1
    t0 = time.monotonic() + 0.02  # the opponent's hit, on the camera clock
    sends, due = [], []
    for e, stamp, p in zip(cam["exposures"], cam["times"], cam["positions"], strict=True):
        if not np.all(np.isfinite(p)):
            continue  # the ball is gone (past the floor or the net): no frame
        due.append(t0 + e + cam["latency"])
        _sleep_until(due[-1])
        sends.append(time.monotonic())
        link.observation(ball_id, t0 + stamp, p)
    _sleep_until(sends[-1] + settle)
    listener.check()
    offset = listener.offset()
    start, end = t0, sends[-1] + settle
    rows = [r for r in listener.telemetry if start <= r[1] + offset <= end]
    hits = [(a, s) for a, s in listener.status if start <= a <= end]
    accepted = [s for _, s in hits if s["status"] == "Accepted" and np.isfinite(s["t_hit"])]
    rec = {
        "index": index,
        "observations": len(sends),
        "send_jitter_ms": float(np.max(np.array(sends) - np.array(due)) * 1e3),
        "statuses": [s["status"] for _, s in hits],
        "planning_time_s": [s["planning_time"] for _, s in hits],
        "telemetry": len(rows),
    }
    # A controller that stopped (a drive fault) keeps sending telemetry with its fault bits: the
    # ball is lost to the fault, whatever the joints did.
    faults = listener.fault_since(start - offset)
    if faults:
        rec.update(status="fault", faults=faults, returned=False, contact=False)
        return rec
    if not rows:
        rec.update(status="no_telemetry", returned=False, contact=False)
        return rec
    if not accepted:
        rec.update(status="no_hit", returned=False, contact=False)
        return rec
    t_hit = accepted[-1]["t_hit"] + offset - t0
    t = np.array([r[1] + offset - t0 for r in rows])
    q = np.array([r[2] for r in rows])
    qd = np.array([r[3] for r in rows])
    sc = _t.ball_rally_score(index, t_hit, t, q, qd, seed, world)
    rec.update(
        status=sc["status"],
        returned=bool(sc["returned"]),
        contact=bool(sc["contact"]),
        racket_error=float(sc["racket_error"]),
        t_hit=float(t_hit),
        timeline={
            "t_obs": cam["times"].tolist(),
            "obs": cam["positions"].tolist(),
            "t": t.tolist(),
            "q": q.tolist(),
            # the ball leaving the racket [t, x, y, z] (s, m, world), when the racket met it
            "impact": None if sc["after"] is None else np.asarray(sc["after"])[:4].tolist(),
        },
    )
    return rec


def _checkout(start: Path) -> Path | None:
    """The ttmanip checkout holding ``start`` (its root: the workspace with ``crates/ttcan``), if any."""
    for d in (start, *start.parents):
        if (d / "crates" / "ttcan" / "Cargo.toml").is_file() and (d / "Cargo.toml").is_file():
            return d
    return None


def _checkouts() -> list[Path]:
    """The checkouts to look in: the working directory's, then the one this package was loaded
    from (a source or editable install; an installed wheel lives in site-packages, in none)."""
    out: list[Path] = []
    for start in (Path.cwd().resolve(), Path(__file__).resolve().parent):
        root = _checkout(start)
        if root is not None and root not in out:
            out.append(root)
    return out


def find_ttctl(binary: str | None = None) -> str:
    """The ``ttctl`` binary: ``binary`` when given, else ``ttctl`` on ``PATH``, else the release
    build of the checkout the working directory is in (``cargo build --release -p ttcan``:
    ``$CARGO_TARGET_DIR/release/ttctl`` or ``target/release/ttctl``), else of the checkout this
    package was loaded from. Raises :class:`HilError` saying what to build or give."""
    if binary is not None:
        exe = Path(binary)
        if not exe.is_file():
            raise HilError(f"--ttctl {binary}: no such file (build it with cargo build --release -p ttcan)")
        return str(exe)
    on_path = shutil.which("ttctl")
    if on_path is not None:
        return on_path
    roots = _checkouts()
    target = os.environ.get("CARGO_TARGET_DIR")
    for root in roots:
        for t in ([Path(target) if Path(target).is_absolute() else root / target] if target else []) + [
            root / "target"
        ]:
            exe = t / "release" / "ttctl"
            if exe.is_file():
                return str(exe)
    if roots:
        raise HilError(
            f"ttctl not built in the checkout {roots[0]}: run `cargo build --release -p ttcan` there "
            "(or give --ttctl PATH)"
        )
    raise HilError(
        "ttctl not found: it is not on PATH and the working directory is not in a ttmanip checkout "
        "(the wheel does not ship ttctl); build it in a checkout with `cargo build --release -p ttcan` "
        "and give --ttctl PATH/TO/target/release/ttctl, or run ttmanip hil from the checkout"
    )


def _ttctl_command(
    binary: str | None, config: str | None, port: int, reply: int, stats: Path, max_seconds: float
) -> list[str]:
    exe = find_ttctl(binary)
    # The default configuration of the checkout: from the working directory (the package may be
    # installed from the wheel, away from the repository), else in the checkouts found above.
    default = Path("tests") / "online" / "gantry6_hil.toml"
    if config is not None:
        cfg = config
    else:
        found = [r / default for r in _checkouts() if (r / default).exists()]
        cfg = str(default if default.exists() else (found[0] if found else default))
    if not Path(cfg).exists():
        raise HilError(f"ttctl configuration {cfg} not found: give --config PATH")
    return [
        exe,
        "-c",
        cfg,
        "--virtual-drives",
        "--online",
        "ball",
        "--listen",
        f"127.0.0.1:{port}",
        "--reply",
        f"127.0.0.1:{reply}",
        "--stats",
        str(stats),
        "--max-seconds",
        str(max_seconds),
    ]


def _stats(path: Path) -> dict:
    """ttctl's statistics file (key=value lines) as a dict, numbers as floats."""
    out = {}
    if path.exists():
        for line in path.read_text().splitlines():
            k, sep, v = line.partition("=")
            if sep:
                try:
                    out[k.strip()] = float(v)
                except ValueError:
                    out[k.strip()] = v.strip()
    return out


def _pct(a, p):
    return float(np.percentile(a, p)) if len(a) else float("nan")


def run(
    n: int,
    seed: int = 0,
    out: str | Path = "out/hil",
    connect: tuple[str, int] | None = None,
    ttctl: str | None = None,
    config: str | None = None,
    world: bool = False,
) -> dict:
    """Plays balls 0..``n`` of the rally of ``seed`` against ``ttctl`` (started here in ball mode
    with virtual drives unless ``connect`` gives a running one's address), plays the offline rally
    on the same balls, writes ``summary.json`` and the figure of one ball's timeline to ``out``,
    and returns the summary."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 1 <= n <= _t.MAX_RALLY_BALLS:
        raise HilError(f"--n: {n!r} balls, need an integer in 1..={_t.MAX_RALLY_BALLS} (the rally's balls)")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2**64:
        raise HilError(f"--seed: {seed!r}, need an integer in 0..2^64")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    reply = _free_port()
    proc = None
    if connect is None:
        port = _free_port()
        cmd = _ttctl_command(ttctl, config, port, reply, out / "ttctl_stats.txt", 30.0 + 2.0 * n)
        log = (out / "ttctl.log").open("w")
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        address = ("127.0.0.1", port)
    else:
        address = connect
    link = Link(address, bind=("127.0.0.1", reply))
    listener = _Listener(link)
    balls = []
    try:
        deadline = time.monotonic() + 10.0
        while not listener.telemetry:
            if proc is not None and proc.poll() is not None:
                raise HilError(f"ttctl exited with {proc.returncode}: see {out / 'ttctl.log'}")
            if time.monotonic() > deadline:
                raise HilError("no telemetry from the controller within 10 s")
            time.sleep(0.05)
        # The controller approaches its ready pose after enabling: the balls start once the
        # measured joints have been at rest for 0.2 s (the rally's robot waits at ready): each
        # joint within 1 mrad (or mm) over the window and no speed above 0.1 rad/s. The measured
        # speed comes from encoder counts (1e-5 per cycle = 0.01 per s), so a drive holding
        # position dithers by a count or two: exact zero speed is not a rest test.
        while True:
            rows = listener.telemetry[-200:]
            if len(rows) >= 200:
                q = np.array([r[2] for r in rows])
                qd = np.array([r[3] for r in rows])
                if float(np.max(np.ptp(q, axis=0))) < 1e-3 and float(np.max(np.abs(qd))) < 0.1:
                    break
            if proc is not None and proc.poll() is not None:
                raise HilError(f"ttctl exited with {proc.returncode}: see {out / 'ttctl.log'}")
            if time.monotonic() > deadline + 10.0:
                raise HilError("the controller did not come to rest at its ready pose within 20 s")
            time.sleep(0.05)
        for i in range(n):
            balls.append(play(link, listener, i, seed, world))
            if balls[-1]["status"] in ("no_telemetry", "fault"):
                break  # the controller stopped (see ttctl.log and its statistics' fault)
    finally:
        listener.stop()
        link.close()
        if proc is not None:
            proc.send_signal(2)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
    offline = _t.ball_rally(len(balls), seed=seed, world=world)
    returned = sum(b["returned"] for b in balls)
    played = len(balls)
    plan = [x for b in balls for x in b["planning_time_s"]]
    summary = {
        "n": n,
        "played": played,
        "seed": seed,
        "world": "mismatch" if world else "model",
        "returned": returned,
        "return_rate": returned / max(played, 1),
        "offline_returned": int(np.sum(offline["returned"])),
        "offline_return_rate": float(np.mean(offline["returned"])),
        "planning_time_ms": {"p50": _pct(plan, 50) * 1e3, "p99": _pct(plan, 99) * 1e3},
        "send_jitter_ms_max": max(b["send_jitter_ms"] for b in balls),
        "refused_datagrams": listener.refused,
        "statuses": {s: sum(b["status"] == s for b in balls) for s in {b["status"] for b in balls}},
    }
    st = _stats(out / "ttctl_stats.txt")
    summary["ttctl"] = st

    def stat(key: str, scale: float = 1.0) -> float:
        v = st.get(key)
        return float(v) * scale if isinstance(v, float) else float("nan")

    # Measured in the controller: the arrival of the datagram a stroke was decided on (the last
    # observation used) to the stroke's first cycle, the first changed setpoint.
    summary["decision_latency_ms"] = {
        p: stat(f"online_decision_latency_{p}_us", 1e-3) for p in ("p50", "p90", "p99", "max")
    }
    summary["decision_latency_ms"]["strokes"] = stat("online_decision_latency_count")
    summary["decision_latency_ms"]["over_2ms"] = stat("online_decision_latency_over_2ms")
    # Cycle wake-up latency and deadline misses, split by whether the planning thread planned.
    summary["cycle_latency_us"] = {p: stat(f"latency_{p}_us") for p in ("p50", "p99", "max")}
    summary["deadline_misses"] = {
        "all": stat("deadline_misses"),
        "quiet": stat("deadline_misses_quiet"),
        "planning": stat("deadline_misses_planning"),
        "cycles_quiet": stat("cycles_quiet"),
        "cycles_planning": stat("cycles_planning"),
        "latency_p99_us_quiet": stat("latency_p99_us_quiet"),
        "latency_p99_us_planning": stat("latency_p99_us_planning"),
    }
    summary["brain"] = {k[len("online_") :]: v for k, v in st.items() if k.startswith("online_ball")}
    # Why strokes were late (ready after their splice cycle), and the causes of those over 2 ms.
    summary["late_strokes"] = {
        k[len("online_") :]: v for k, v in st.items() if k.startswith(("online_late_", "online_over_2ms_"))
    }
    summary["offline_statuses"] = [str(x) for x in offline["status"]]
    summary["balls"] = [{k: v for k, v in b.items() if k != "timeline"} for b in balls]
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    _figure(out, balls)
    return summary


def _figure(out: Path, balls: list[dict]) -> None:
    """The timeline of the first ball that was hit: observations (those after the planned hit
    greyed: the simulator streams the recorded incoming flight to its end, the return is not
    observed), the hit time, where the ball left the racket, and the measured joint motion (FK
    of the measured joints is in the score)."""
    ball = next((b for b in balls if "timeline" in b), None)
    if ball is None:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tl = ball["timeline"]
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    obs = np.array(tl["obs"])
    t_obs = np.array(tl["t_obs"])
    before = t_obs <= ball["t_hit"]
    impact = tl.get("impact")
    for k, name in enumerate("xyz"):
        (line,) = ax[0].plot(t_obs[before], obs[before, k], ".", ms=2, label=f"observed {name}")
        ax[0].plot(t_obs[~before], obs[~before, k], ".", ms=1, color="0.75")
        if impact is not None:
            ax[0].plot(impact[0], impact[1 + k], "x", ms=8, mew=2, color=line.get_color())
    if np.any(~before):
        ax[0].plot([], [], ".", color="0.75", label="incoming flight after the hit (not seen)")
    if impact is not None:
        ax[0].plot([], [], "kx", label="ball leaving the racket")
    ax[0].axvline(ball["t_hit"], color="k", ls="--", label="planned hit")
    ax[0].set_ylabel("ball (m, world)")
    ax[0].legend(fontsize=7)
    q = np.array(tl["q"])
    if q.size:
        ax[1].plot(tl["t"], q)
    ax[1].axvline(ball["t_hit"], color="k", ls="--")
    ax[1].set_xlabel("s from the opponent's hit")
    ax[1].set_ylabel("measured joints")
    ax[0].set_title(f"ball {ball['index']}: {ball['status']}")
    fig.savefig(out / "timeline.png", dpi=100)
    plt.close(fig)
