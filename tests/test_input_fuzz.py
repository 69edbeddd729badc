"""File and command-line fuzzers (issue 29): robot files (TOML, URDF), hit files (JSON) and
trajectory files (CSV) mutated at random, and random arguments to ``ttmanip``, ``ttctl`` and
``ttdrive-sim``. Every case runs under a time and memory cap: a case that hangs, aborts, segfaults
or ends in a traceback fails.

- Files: one subprocess per kind reads all its mutated files in turn (each read under a
  ``faulthandler`` timer of ``CASE_SECONDS``, the process under ``RLIMIT_AS``); a read must give a
  robot (whose FK is finite), a checked hit file, or a ``TtmanipError`` / ``CliError`` naming the
  problem. Trajectory files go to ``ttctl --check --trajectory``: exit 0 or 1, never a signal.
- Arguments: each command line is its own subprocess; the exit status must be 0, 1 (bad input) or
  2 (not done), with no traceback.

CI runs a fixed seed and a small budget (``TTMANIP_INPUT_FUZZ_CASES``, 24 per kind, seconds); a
longer campaign: ``TTMANIP_INPUT_FUZZ_CASES=2000 TTMANIP_INPUT_FUZZ_SEED=$RANDOM pytest
tests/test_input_fuzz.py``.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import ttmanip

CASES = int(os.environ.get("TTMANIP_INPUT_FUZZ_CASES", "24"))
SEED = int(os.environ.get("TTMANIP_INPUT_FUZZ_SEED", "29"))
CASE_SECONDS = 20
CAP_BYTES = 3 << 30
ROOT = Path(__file__).resolve().parents[1]

NUMBERS = [
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "5e-324",
    "-1",
    "0",
    "1e17",
    "1" + "0" * 400,
    "-0.0",
    "1e-300",
    "1000000000000",
]
JSON_NUMBERS = [
    "NaN",
    "Infinity",
    "-Infinity",
    "1e308",
    "-1e308",
    "5e-324",
    "-1",
    "0",
    "1e17",
    "1" + "0" * 400,
]


def _limits():
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def run(cmd: list[str], timeout: float, stdin: str | None = None) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout, preexec_fn=_limits, input=stdin, cwd="/tmp"
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"hung for more than {timeout} s: {cmd}")


# -------------------------------------------------------------------------------- mutations


def mutate(text: str, rng: random.Random, numbers: list[str]) -> str | bytes:
    """One random mutation of ``text``: a number replaced by an extreme, a line dropped or doubled,
    a key misspelt, a byte flipped, nesting added, the text truncated or blown up."""
    kind = rng.randrange(9)
    lines = text.splitlines()
    if kind == 0:  # a number replaced by an extreme
        import re

        nums = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text))
        if nums:
            m = rng.choice(nums)
            return text[: m.start()] + rng.choice(numbers) + text[m.end() :]
    if kind == 1 and lines:  # a line dropped
        del lines[rng.randrange(len(lines))]
        return "\n".join(lines)
    if kind == 2 and lines:  # a line doubled
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
        return "\n".join(lines)
    if kind == 3:  # a key or word misspelt
        import re

        words = list(re.finditer(r"[a-z_]{3,}", text))
        if words:
            m = rng.choice(words)
            w = m.group()
            k = rng.randrange(len(w))
            return text[: m.start()] + w[:k] + w[k + 1 :] + text[m.end() :]
    if kind == 4:  # a byte flipped (possibly not UTF-8)
        b = bytearray(text.encode())
        if b:
            b[rng.randrange(len(b))] = rng.randrange(256)
        return bytes(b)
    if kind == 5:  # truncated
        return text[: rng.randrange(len(text) + 1)]
    if kind == 6:  # nesting
        depth = rng.choice([10, 100, 10000, 100000])
        return rng.choice(["[" * depth + "]" * depth, "{" * depth, "<a>" * depth + "</a>" * depth]) + text
    if kind == 7:  # blown up: many copies of a line
        if lines:
            i = rng.randrange(len(lines))
            lines[i:i] = [lines[i]] * rng.choice([100, 5000])
            return "\n".join(lines)
    return text + rng.choice(["\n\x00", "\nzzz = 1\n", "\n<bogus/>", "\n,,,\n", ""])


def read_all(kind: str, paths: list[Path]) -> subprocess.CompletedProcess:
    """Reads every file of ``paths`` as ``kind`` in one capped interpreter; prints a line per file."""
    code = f"""
import faulthandler, json, os, sys
import numpy as np
import ttmanip
from ttmanip import cli
paths = {[str(p) for p in paths]!r}
for p in paths:
    faulthandler.dump_traceback_later({CASE_SECONDS}, exit=True)
    try:
        if {kind!r} == "toml":
            r = ttmanip.Robot.from_file(p)
        elif {kind!r} == "flight":
            from ttmanip import ball_fit
            r = ball_fit.read_flights(os.path.dirname(p))
        elif {kind!r} == "urdf":
            text = open(p, "rb").read().decode("utf-8", "replace")
            r = ttmanip.Robot.from_urdf_string(text, "base_link", "tool")
        else:
            r = cli.read_hit_file(p)
        if {kind!r} in ("toml", "urdf"):
            pose = r.fk(np.zeros(r.dof))
            assert np.isfinite(pose).all(), p
        print("ok", p, flush=True)
    except (ttmanip.TtmanipError, cli.CliError) as e:
        print("refused", p, type(e).__name__, " ".join(str(e).split())[:160], flush=True)
    faulthandler.cancel_dump_traceback_later()
print("END", flush=True)
"""
    return run([sys.executable, "-c", textwrap.dedent(code)], timeout=CASE_SECONDS * (len(paths) + 2))


def sources(kind: str) -> list[str]:
    arm4, m8 = ttmanip.robots.arm4(), ttmanip.robots.mobile8()
    if kind == "toml":
        return [arm4.to_toml(), m8.to_toml(), (ROOT / "robots" / "gantry6.toml").read_text()]
    if kind == "urdf":
        return [arm4.to_urdf(), m8.to_urdf()]
    hit = {
        "robot": "gantry6",
        "units": {"length": "m", "time": "s"},
        "state": {"q": [0.0] * 6},
        "profile": "auto",
        "hits": [
            {
                "centre": [0.35, -0.55, 0.05],
                "normal": [0.3, -1.0, -0.2],
                "velocity": [0.86, -2.87, -0.57],
                "t": 0.35,
            }
        ],
    }
    if kind == "flight":
        t = [0.004 * k for k in range(30)]
        return [
            json.dumps({"ob": [[-1.2 + 4 * x, 0.1 * x, 0.3 + 1.5 * x - 4.9 * x * x, 4, 0.1, 1.5] for x in t]})
        ]
    return [json.dumps(hit, indent=1)]


@pytest.mark.parametrize("kind", ["toml", "urdf", "json", "flight"])
def test_mutated_files_are_read_or_refused_never_crash_or_hang(kind, tmp_path):
    rng = random.Random(f"{SEED}-{kind}")
    paths = []
    for i in range(CASES):
        text = mutate(rng.choice(sources(kind)), rng, JSON_NUMBERS if kind in ("json", "flight") else NUMBERS)
        p = tmp_path / f"case{i}.{kind}"
        if kind == "flight":  # one flight per folder (ball_fit.read_flights reads a folder)
            (tmp_path / f"case{i}").mkdir()
            p = tmp_path / f"case{i}" / "a.json"
        (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
        paths.append(p)
    r = read_all(kind, paths)
    assert r.returncode == 0 and r.stdout.rstrip().endswith("END"), (
        f"exit {r.returncode}; last case: {r.stdout.strip().splitlines()[-1:]} {r.stderr[-3000:]}"
    )
    assert r.stdout.count("\n") == len(paths) + 1


def test_mutated_trajectory_files_are_checked_by_ttctl(tmp_path):
    exe = _binary("ttctl")
    if exe is None:
        pytest.skip("ttctl is not built (cargo build -p ttcan)")
    import numpy as np
    from ttmanip.ctl import write_trajectory

    t = np.linspace(0.0, 0.2, 21)
    q = np.column_stack([0.1 * t, -0.2 * t])
    good = tmp_path / "good.csv"
    write_trajectory(good, t, q, np.zeros_like(q), np.zeros_like(q))
    cfg = tmp_path / "ctl.toml"
    cfg.write_text(
        '[[channel]]\ninterface = "vcan0"\n[[channel.axis]]\nnode = 1\njoint = 0\n[[channel.axis]]\n'
        "node = 2\njoint = 1\n"
    )
    rng = random.Random(f"{SEED}-csv")
    for i in range(CASES):
        text = mutate(good.read_text(), rng, NUMBERS)
        p = tmp_path / f"case{i}.csv"
        (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
        r = run([exe, "--config", str(cfg), "--trajectory", str(p), "--check"], timeout=CASE_SECONDS)
        assert r.returncode in (0, 1), (i, r.returncode, r.stderr[-2000:])
    r = run([exe, "--config", str(cfg), "--trajectory", "/dev/zero", "--check"], timeout=CASE_SECONDS)
    assert r.returncode == 1 and "16 MiB" in r.stderr, r.stderr


def test_mutated_controller_configurations_are_checked_by_ttctl(tmp_path):
    exe = _binary("ttctl")
    if exe is None:
        pytest.skip("ttctl is not built (cargo build -p ttcan)")
    rng = random.Random(f"{SEED}-ctl")
    sources = [
        (ROOT / "tests" / "online" / "gantry6_hil.toml").read_text(),
        (ROOT / "tests" / "vm" / "vcan.toml").read_text(),
    ]
    for i in range(CASES):
        text = mutate(rng.choice(sources), rng, NUMBERS)
        p = tmp_path / f"case{i}.toml"
        (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
        # --demo sizes its motion by the largest joint index (joint = 10^12 aborted it)
        r = run([exe, "--config", str(p), "--demo", "--check"], timeout=CASE_SECONDS)
        assert r.returncode in (0, 1), (i, r.returncode, r.stderr[-2000:])
        assert "panicked" not in r.stderr, (i, r.stderr[-2000:])


# -------------------------------------------------------------------------------- arguments


def _binary(name: str) -> str | None:
    from conftest import built_binary

    return built_binary(name)


def _value(rng: random.Random) -> str:
    return rng.choice(NUMBERS + ["abc", "", "0.5", "3", "1,2,3", "0.1,0,0.2,0.3,0.4,0.5", "-5", "1e3"])


TTMANIP = [
    ["fk", "{robot}", "--q", "{v}"],
    ["ik", "{robot}", "--centre", "{v}", "--normal", "{v}"],
    ["info", "{robot}"],
    ["plan", "{path}", "--out", "{out}"],
    ["rally", "--n", "{v}", "--seed", "{v}", "--out", "{out}"],
    ["export", "{robot}", "--out", "{out}"],
    ["ball", "fit", "{path}", "--window", "{v}", "--out", "{out}"],
    ["rally", "--balls", "{path}", "--n", "2", "--drives", "0", "--out", "{out}"],
    ["telemetry", "{path}", "--rerun", "{out}.rrd"],
    ["hil", "--n", "{v}", "--seed", "{v}", "--connect", "127.0.0.1:{v}", "--out", "{out}"],
    ["hil", "--n", "{v}", "--seed", "{v}", "--ttctl", "/nonexistent/ttctl", "--out", "{out}"],
    ["ik", "{robot}", "--centre", "{v}", "--normal", "0,-1,0"],
    ["{v}"],
]
TTCTL = [
    ["--demo", "--check", "--amplitude", "{v}"],
    ["--demo", "--check", "--max-seconds={v}"],
    ["--config", "{path}", "--check"],
    ["--config", "{path}", "--demo", "--check"],
    ["--{v}"],
]
TTDRIVE = [
    ["--channel", "vcan9:{v}", "--duration", "{v}", "--idle-exit", "0.1"],
    ["--channel", "{v}:1", "--period", "{v}", "--duration", "0.1"],
    ["--channel", "vcan9:1", "--fail", "emcy:vcan9:{v}@{v}", "--duration", "0.1"],
]


def _command(template: list[str], rng: random.Random, tmp: Path) -> list[str]:
    return [
        a.format(
            robot=rng.choice(["gantry6", "mobile8", "arm4", "ur5", "r2d2"]),
            v=_value(rng),
            path=rng.choice(["/dev/zero", "/nonexistent.json", str(tmp / "x.json"), "/etc/passwd"]),
            out=str(tmp / "out"),
        )
        for a in template
    ]


@pytest.mark.parametrize("program", ["ttmanip", "ttctl", "ttdrive-sim"])
def test_random_command_lines_exit_0_1_or_2_without_traceback(program, tmp_path):
    rng = random.Random(f"{SEED}-{program}")
    if program == "ttmanip":
        prefix, templates = [sys.executable, "-m", "ttmanip.cli"], TTMANIP
    else:
        exe = _binary(program)
        if exe is None:
            pytest.skip(f"{program} is not built (cargo build -p ttcan)")
        prefix, templates = [exe], TTCTL if program == "ttctl" else TTDRIVE
    (tmp_path / "x.json").write_text('{"robot": "gantry6", "t": 0.3}')
    for _ in range(max(4, CASES // 3)):
        cmd = prefix + _command(rng.choice(templates), rng, tmp_path)
        if "rally" in cmd:
            n = cmd[cmd.index("--n") + 1]
            if n.isdigit() and int(n) > 3:
                cmd[cmd.index("--n") + 1] = "3"  # a real rally is minutes of work, not a fuzz case
        r = run(cmd, timeout=120)
        assert r.returncode in (0, 1, 2), (cmd, r.returncode, r.stderr[-2000:])
        assert "Traceback" not in r.stderr and "panicked" not in r.stderr, (cmd, r.stderr[-3000:])
