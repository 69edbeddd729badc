"""Before/after in one run: a git revision and the working tree built side by side, compared.

Builds ``REV`` (checked out as a detached git worktree under ``/tmp``) and this checkout's working
tree (or ``--after REV2``) with the same cargo and the same profiles, then, alternating the two
builds so that the machine's load falls on both alike:

- the rally's counts (``crates/ttkin/examples/rally_stats``: balls in reach, returned, the
  in-reach failures by status, the planning CPU median) on each seed (default 0, 1, 2; 2000 balls);
- the criterion benchmarks of ``ttkin`` and ``ttcan`` (every ``[[bench]]`` target both builds
  have; each bench binary run once per build, the median of its samples from criterion's
  ``estimates.json``, each build writing to its own ``CRITERION_HOME``).

It prints one Markdown table (``--out FILE`` also writes it), with the revisions, the rustc
version and the load average at the start and end; a row whose rally counts differ is marked.
The rally counts are deterministic (seeded, fixed chunks), so any difference is a change of
behaviour; the bench medians are wall times on a shared machine (compare them with the load).

Run: ``.venv/bin/python benches/before_after.py 0057ae6 [--balls 2000] [--seeds 0 1 2]
[--bench kinematics ...] [--quick]``. Each side builds in its own target directory
(``--target-dir``/before, /after, or /worktree for this checkout's working tree, default under
this checkout's ``target/before-after``; kept between runs, so a second run rebuilds only what
changed): one directory shared by both sides
gave the second side the first side's binaries, because cargo names a workspace member's
artifacts by its path relative to the workspace root (the same in both checkouts) and judges them
fresh by file times (the second checkout's files are older than the first side's build). A side
whose ``rally_stats`` is byte-identical to the other's although their sources differ stops the
script. The ``/tmp`` worktrees and copies are removed at the end unless ``--keep``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
RALLY_LINE = re.compile(
    r"balls (\d+) seed (\d+): in reach (\d+), returned (\d+) -> return rate ([0-9.]+) %, "
    r"returned out of reach (\d+)"
)
FAILURES_LINE = re.compile(r"in-reach failures (\{.*\})")
CPU_LINE = re.compile(r"plan CPU time median ([0-9.]+) us")


def _run(cmd: list[str], cwd: Path, env: dict | None = None) -> str:
    """Runs ``cmd`` in ``cwd`` and returns its stdout; stops the script with its stderr on failure."""
    p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"failed ({p.returncode}): {' '.join(cmd)} in {cwd}\n{p.stderr[-4000:]}")
    return p.stdout


def _git(*args: str) -> str:
    """Output of git in this checkout, stripped."""
    return _run(["git", *args], REPO).strip()


def _checkout(rev: str, scratch: Path) -> Path:
    """A detached worktree of ``rev`` under ``scratch`` (the revision's files, nothing built)."""
    sha = _git("rev-parse", "--verify", f"{rev}^{{commit}}")
    path = scratch / f"tree-{sha[:10]}"
    _run(["git", "worktree", "add", "--detach", "--force", str(path), sha], REPO)
    return path


def _executables(tree: Path, cargo_args: list[str], target_dir: Path, kind: str) -> dict[str, str]:
    """Builds in ``tree`` and returns {target name: executable} of the artifacts of ``kind``."""
    env = dict(os.environ, CARGO_TARGET_DIR=str(target_dir))
    out = _run(["cargo", *cargo_args, "--message-format=json-render-diagnostics"], tree, env)
    found = {}
    for line in out.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") == "compiler-artifact" and msg.get("executable"):
            if kind in msg["target"]["kind"]:
                found[msg["target"]["name"]] = msg["executable"]
    return found


def _build(side: str, tree: Path, target_dir: Path, copies: Path, benches: bool) -> dict:
    """rally_stats and (with ``benches``) every bench binary of one side, copied out of the shared
    target directory."""
    t0 = time.monotonic()
    dest = copies / side
    dest.mkdir(parents=True, exist_ok=True)
    exes = {}
    rally = _executables(
        tree, ["build", "--release", "-p", "ttkin", "--example", "rally_stats"], target_dir, "example"
    )
    bench_args = ["bench", "-p", "ttkin", "-p", "ttcan", "--benches", "--no-run"]
    found = _executables(tree, bench_args, target_dir, "bench") if benches else {}
    for name, exe in [("rally_stats", rally["rally_stats"]), *sorted(found.items())]:
        exes[name] = dest / name
        shutil.copy2(exe, exes[name])
    built = ", ".join(sorted(found)) or "no benches"
    print(f"[{side}] built in {time.monotonic() - t0:.0f} s: {built}", file=sys.stderr)
    return exes


def _target_name(side: str, tree: Path) -> str:
    """The target folder of a side: the working tree builds in ``worktree`` (cargo's own freshness
    rules hold: one source folder per target folder); a detached checkout, made afresh by each run
    (its files newer than any earlier build there), in ``before`` or ``after``."""
    return "worktree" if tree == REPO else side


def _check_distinct(a, exes: dict) -> None:
    """Stops the script when both sides' ``rally_stats`` are the same file although the sources
    they were built from differ (a stale build taken for the other side's)."""
    digest = {side: hashlib.sha256(e["rally_stats"].read_bytes()).hexdigest() for side, e in exes.items()}
    if digest["before"] != digest["after"]:
        return
    paths = ["crates", "Cargo.toml", "Cargo.lock"]
    revs = [a.rev, a.after] if a.after else [a.rev]
    same = subprocess.run(["git", "diff", "--quiet", *revs, "--", *paths], cwd=REPO).returncode == 0
    if not same:
        sys.exit("before and after built to the same rally_stats although their sources differ")


def _bench_crate(tree: Path, name: str) -> Path:
    """The crate folder whose benches/ holds bench ``name`` (criterion benches may read files there)."""
    for crate in ("ttkin", "ttcan"):
        if (tree / "crates" / crate / "benches" / f"{name}.rs").exists():
            return tree / "crates" / crate
    return tree


def _rally(exe: Path, balls: int, seed: int) -> dict:
    """rally_stats' counts on ``balls`` balls of ``seed``."""
    out = _run([str(exe), str(balls), str(seed)], exe.parent)
    m = RALLY_LINE.search(out)
    if not m:
        sys.exit(f"{exe}: no counts line in its output:\n{out[-2000:]}")
    f = FAILURES_LINE.search(out)
    c = CPU_LINE.search(out)
    return {
        "in_reach": int(m.group(3)),
        "returned": int(m.group(4)),
        "rate": float(m.group(5)),
        "returned_out": int(m.group(6)),
        "failures": f.group(1) if f else "?",
        "cpu_us": float(c.group(1)) if c else float("nan"),
    }


def _criterion(exe: Path, cwd: Path, home: Path, quick: bool) -> None:
    """Runs one criterion bench binary, its results under ``home``."""
    args = [str(exe), "--bench", "--noplot"]
    if quick:
        args += ["--warm-up-time", "1", "--measurement-time", "2"]
    _run(args, cwd, dict(os.environ, CRITERION_HOME=str(home)))


def _medians(home: Path) -> dict[str, float]:
    """{benchmark id: median ns} of every benchmark criterion wrote under ``home``."""
    out = {}
    for bench in home.rglob("new/benchmark.json"):
        full_id = json.loads(bench.read_text())["full_id"]
        est = json.loads((bench.parent / "estimates.json").read_text())
        out[full_id] = est["median"]["point_estimate"]
    return out


def _ns(v: float | None) -> str:
    """A duration in ns as the table shows it (µs or ms above 10 000 ns)."""
    if v is None:
        return "—"
    if v >= 1e7:
        return f"{v / 1e6:,.2f} ms"
    if v >= 1e4:
        return f"{v / 1e3:,.2f} µs"
    return f"{v:,.1f} ns"


def _describe(tree: Path, rev: str | None) -> str:
    """The revision of a side: its sha and subject, or the working tree's HEAD and whether it is dirty."""
    if rev is not None:
        return _git("log", "-1", "--format=%h %s", rev)[:100]
    dirty = _run(["git", "status", "--porcelain", "--untracked-files=no"], tree).strip()
    head = _run(["git", "log", "-1", "--format=%h %s"], tree).strip()[:90]
    return f"working tree at {head}" + (" (with uncommitted changes)" if dirty else "")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="the 'before' git revision (e.g. 0057ae6)")
    ap.add_argument("--after", help="an 'after' revision instead of the working tree")
    ap.add_argument("--balls", type=int, default=2000, help="balls per seed (default 2000)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="rally seeds (default 0 1 2)")
    ap.add_argument("--bench", nargs="*", help="only these bench targets (default: all of both builds)")
    ap.add_argument("--no-bench", action="store_true", help="rally counts only")
    ap.add_argument("--quick", action="store_true", help="criterion warm-up 1 s, measurement 2 s")
    ap.add_argument(
        "--target-dir",
        type=Path,
        default=REPO / "target" / "before-after",
        help="cargo target dirs go in its subfolders before/ and after/",
    )
    ap.add_argument("--out", type=Path, help="also write the table to this file")
    ap.add_argument("--keep", action="store_true", help="keep the /tmp worktrees and copies")
    a = ap.parse_args()
    if a.balls < 1:
        ap.error(f"--balls: expected at least 1 ball, got {a.balls}")

    # a SIGTERM (e.g. a killed run) still removes the /tmp worktrees (the `finally` below)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit("terminated"))
    load0 = os.getloadavg()
    scratch = Path(tempfile.mkdtemp(prefix="ttmanip-before-after-"))
    trees = {"before": _checkout(a.rev, scratch)}
    trees["after"] = _checkout(a.after, scratch) if a.after else REPO
    try:
        exes = {
            side: _build(side, tree, a.target_dir / _target_name(side, tree), scratch / "bin", not a.no_bench)
            for side, tree in trees.items()
        }
        _check_distinct(a, exes)
        rally = {}
        for seed in a.seeds:
            for side in ("before", "after"):
                t0 = time.monotonic()
                rally[side, seed] = _rally(exes[side]["rally_stats"], a.balls, seed)
                print(f"[{side}] rally seed {seed}: {time.monotonic() - t0:.0f} s", file=sys.stderr)
        medians = {"before": {}, "after": {}}
        if not a.no_bench:
            names = sorted((set(exes["before"]) | set(exes["after"])) - {"rally_stats"})
            for name in [n for n in names if not a.bench or n in a.bench]:
                for side in ("before", "after"):
                    if name not in exes[side]:
                        continue
                    home = scratch / "criterion" / side
                    _criterion(exes[side][name], _bench_crate(trees[side], name), home, a.quick)
                    print(f"[{side}] bench {name} done", file=sys.stderr)
            medians = {side: _medians(scratch / "criterion" / side) for side in ("before", "after")}
        load1 = os.getloadavg()
        table = _table(a, trees, rally, medians, load0, load1)
    finally:
        if not a.keep:
            for tree in trees.values():
                if tree != REPO:
                    subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=REPO, check=False)
            shutil.rmtree(scratch, ignore_errors=True)
    print(table)
    if a.out:
        a.out.write_text(table)


def _table(a, trees, rally, medians, load0, load1) -> str:
    """The Markdown report: revisions, rally counts, bench medians."""
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    lines = [
        f"before: `{_describe(trees['before'], a.rev)}`  ",
        f"after: `{_describe(trees['after'], a.after)}`  ",
        f"{rustc}; load average (1/5/15 min) {load0[0]:.1f}/{load0[1]:.1f}/{load0[2]:.1f} at the start, "
        f"{load1[0]:.1f}/{load1[1]:.1f}/{load1[2]:.1f} at the end; {os.cpu_count()} CPUs",
        "",
        f"Rally (`rally_stats {a.balls} SEED`): in reach, returned (return rate), returned out of reach, "
        "in-reach failures by status, planning CPU median.",
        "",
        "| seed | build | in reach | returned | rate | returned out of reach | in-reach failures "
        "| plan CPU median |",
        "| ---: | --- | ---: | ---: | ---: | ---: | --- | ---: |",
    ]
    for seed in a.seeds:
        b, f = rally["before", seed], rally["after", seed]
        same = all(b[k] == f[k] for k in ("in_reach", "returned", "returned_out", "failures"))
        for side, r in (("before", b), ("after", f)):
            mark = "" if same or side == "before" else " **≠**"
            lines.append(
                f"| {seed} | {side}{mark} | {r['in_reach']} | {r['returned']} | {r['rate']:.2f} % | "
                f"{r['returned_out']} | `{r['failures']}` | {r['cpu_us']:.0f} µs |"
            )
    if medians["before"] or medians["after"]:
        lines += [
            "",
            "Criterion medians" + (" (warm-up 1 s, measurement 2 s)" if a.quick else "") + ":",
            "",
            "| benchmark | before | after | after / before |",
            "| --- | ---: | ---: | ---: |",
        ]
        for bid in sorted(set(medians["before"]) | set(medians["after"])):
            b, f = medians["before"].get(bid), medians["after"].get(bid)
            ratio = f"{f / b:.2f}" if b and f else "—"
            lines.append(f"| `{bid}` | {_ns(b)} | {_ns(f)} | {ratio} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
