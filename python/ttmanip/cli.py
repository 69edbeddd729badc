"""The ``ttmanip`` command line: the hit pipeline, the seed experiments, kinematics and robot files.

Every subcommand takes ``--out DIR`` and writes its products there (PNG, CSV, JSON). Exit status,
shared with ``ttctl`` and ``ttdrive-sim``: 0 done; 1 bad input (usage error, bad file, unwritable
folder, bad value, missing or unknown key), with one line ``ttmanip: error: KEY: problem``; 2 not
done (a hit that cannot be planned, a simulated run that faulted); 130 interrupted by Ctrl-C
(every long call stops within about a second).

examples:
  ttmanip demo --out out/demo
  ttmanip experiment seed002 --out out/seed002
  ttmanip fk gantry6 --q 0.1,0,0.2,0.3,0.4,0.5
  ttmanip ik gantry6 --centre 0.35,-0.55,0.05 --normal 0.3,-1,-0.2
  ttmanip plan hit.json --out out/plan
  ttmanip simulate hit.json --out out/sim --noise 0.01
  ttmanip export gantry6 --out out/robots
  ttmanip info mobile8
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from .files import MAX_FILE_BYTES as MAX_HIT_FILE_BYTES
from .files import MAX_JSON_DEPTH, json_depth
from .robots import NAMES as ROBOTS

__all__ = ["CliError", "Progress", "build_parser", "main", "read_hit_file"]

EXPERIMENTS = ("seed000", "seed001", "seed002")

HIT_FILE_HELP = """hit file (JSON):
  {"robot": "gantry6", "hits": [{"centre": [x, y, z], "normal": [nx, ny, nz],
                                 "velocity": [vx, vy, vz], "t": 0.35}]}
in m, m/s, s (base frame). A hit may instead give "pose" (4x4) and "twist" (6); optional per
hit: "omega" (rad/s), "handle"; optional top level: "units" ({"length": "m", "time": "s",
"angle": "rad"}), "state" ({"q": [...], "qd": [...]}), "ready" ([...]), "profile" ("auto",
"quintic", "jerk"). A single hit may stand at the top level instead of "hits". Unknown keys
are refused (as in robot files); at most 16 MiB, UTF-8, nested at most 64 deep."""

#: Exit statuses shared with ``ttctl`` and ``ttdrive-sim`` (``ttcan::runtime::exit``).
EXIT_SUCCESS, EXIT_BAD_INPUT, EXIT_NOT_DONE = 0, 1, 2
#: Exit status after Ctrl-C: 128 + SIGINT, as a shell reports a command the signal ended.
EXIT_INTERRUPTED = 130

#: Largest hit file read (bytes) and deepest JSON nesting accepted.


class CliError(Exception):
    """A user error: printed as one line, no traceback."""


class Progress:
    """A small progress bar on stderr: ``[#####-----] 3/6 label  1.2 s``."""

    def __init__(self, total: int, width: int = 24) -> None:
        self.total, self.width, self.done, self.t0 = max(total, 1), width, 0, time.perf_counter()

    def __call__(self, label: str) -> None:
        self.done = min(self.done + 1, self.total)
        filled = self.width * self.done // self.total
        bar = "#" * filled + "-" * (self.width - filled)
        elapsed = time.perf_counter() - self.t0
        sys.stderr.write(f"\r[{bar}] {self.done}/{self.total} {label:<12s} {elapsed:5.1f} s")
        sys.stderr.flush()

    def close(self) -> None:
        sys.stderr.write("\n")
        sys.stderr.flush()


def _out_dir(path: str) -> Path:
    """``--out``: created if needed and checked to be writable."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".ttmanip-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise CliError(f"--out: cannot write to '{out}': {e.strerror or e}") from e
    return out


def _numbers(text: str, what: str, count: int | None = None) -> np.ndarray:
    try:
        values = np.array([float(v) for v in text.replace(" ", "").split(",") if v != ""])
    except ValueError as e:
        raise CliError(f"{what}: expected comma-separated numbers, got '{text}'") from e
    if count is not None and values.size != count:
        raise CliError(f"{what}: expected {count} numbers, got {values.size}")
    if not np.isfinite(values).all():
        raise CliError(f"{what}: every value must be finite, got '{text}'")
    return values


def _robot(name: str):
    from . import Robot

    try:
        return Robot.builtin(name)
    except Exception as e:  # noqa: BLE001 - the binding's message names the problem
        raise CliError(f"robot: {e}") from e


def _write_json(path: Path, data) -> Path:
    path.write_text(json.dumps(data, indent=2, default=lambda o: np.asarray(o).tolist()))
    return path


def _print_summary(summary: dict, keys=None) -> None:
    for key, value in summary.items():
        if keys is None or key in keys:
            print(f"{key}: {value}")


# -- hit files ---------------------------------------------------------------------------------

_UNITS = {"length": "m", "time": "s", "angle": "rad"}


def _vector(entry: dict, key: str, where: str, count: int, required: bool = True):
    from . import TtmanipError
    from .pipeline import _array

    if key not in entry:
        if required:
            raise CliError(f"{where}.{key}: missing key")
        return None
    try:
        return _array(entry[key], (4, 4) if count == 16 else (count,), f"{where}.{key}", flat=True)
    except TtmanipError as e:
        raise CliError(str(e)) from e


def _hit(entry, where: str):
    from . import Hit, TtmanipError

    if not isinstance(entry, dict):
        raise CliError(f"{where}: expected an object with centre/normal/velocity/t, got {entry!r}")
    allowed = {"centre", "center", "normal", "velocity", "t", "omega", "handle", "pose", "twist"}
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise CliError(f"{where}.{unknown[0]}: unknown key (expected one of {sorted(allowed)})")
    if "centre" in entry and "center" in entry:
        raise CliError(f"{where}.center: give the centre once ('centre' or 'center', not both)")
    if "pose" in entry:
        extra = sorted(set(entry) & {"centre", "center", "normal", "velocity", "omega", "handle"})
        if extra:
            raise CliError(
                f"{where}.{extra[0]}: a hit gives 'pose' and 'twist' or centre/normal/velocity, not both"
            )
    elif "twist" in entry:
        raise CliError(f"{where}.twist: goes with 'pose' (give centre/normal/velocity otherwise)")
    if "t" not in entry:
        raise CliError(f"{where}.t: missing key (hit time in s)")
    t = entry["t"]
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not np.isfinite(t) or t <= 0:
        raise CliError(f"{where}.t: expected a hit time > 0 s, got {t!r}")
    try:
        if "pose" in entry:
            return Hit(_vector(entry, "pose", where, 16), _vector(entry, "twist", where, 6), float(t))
        if "center" in entry and "centre" not in entry:
            entry = {**entry, "centre": entry["center"]}
        centre = _vector(entry, "centre", where, 3)
        normal = _vector(entry, "normal", where, 3)
        velocity = _vector(entry, "velocity", where, 3)
        omega = _vector(entry, "omega", where, 3, required=False)
        handle = _vector(entry, "handle", where, 3, required=False)
        try:
            # the core checks the normal (nonzero) and the handle; its message names the argument
            return Hit.from_normal(centre, normal, velocity, float(t), omega=omega, handle=handle)
        except TtmanipError as e:
            raise CliError(f"{where}.{e}") from e
    except TtmanipError as e:
        raise CliError(f"{where}: {e}") from e


def _ttmanip_profiles() -> list[str]:
    """The stroke profile names of the core (``ttkin::hit::StrokeProfile::ALL``)."""
    from . import _ttmanip

    return _ttmanip.hit_stroke_profiles()


def read_hit_file(path: str) -> dict:
    """Reads and checks a hit file (see ``--help``): ``{"robot", "hits", "state", "ready", "profile"}``."""
    p = Path(path)
    if p.suffix.lower() in (".yaml", ".yml"):
        raise CliError(f"{path}: YAML hit files need PyYAML, which ttmanip does not depend on; use JSON")
    try:
        # Read no further than the limit: a device such as /dev/zero never ends.
        with p.open("rb") as f:
            raw = f.read(MAX_HIT_FILE_BYTES + 1)
    except OSError as e:
        raise CliError(f"{path}: cannot read the hit file: {e.strerror or e}") from e
    if len(raw) > MAX_HIT_FILE_BYTES:
        raise CliError(f"{path}: larger than {MAX_HIT_FILE_BYTES} bytes (16 MiB), the most a hit file may be")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise CliError(f"{path}: not UTF-8 text: invalid byte at offset {e.start}") from None
    depth = json_depth(text)
    if depth > MAX_JSON_DEPTH:
        raise CliError(f"{path}: JSON nested {depth} deep, at most {MAX_JSON_DEPTH}")
    try:
        # Integers as floats: a 401-digit integer is inf (refused as non-finite), not a traceback.
        data = json.loads(text, parse_int=float)
    except json.JSONDecodeError as e:
        raise CliError(f"{path}: not valid JSON (line {e.lineno}, column {e.colno}: {e.msg})") from e
    except (ValueError, RecursionError) as e:
        raise CliError(f"{path}: not a readable JSON hit file ({e})") from None
    if not isinstance(data, dict):
        raise CliError(f"{path}: expected a JSON object at the top level")
    top = {"robot", "units", "state", "ready", "profile"}
    hit_keys = {"centre", "center", "normal", "velocity", "t", "omega", "handle", "pose", "twist"}
    allowed = top | ({"hits"} if "hits" in data else hit_keys)
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise CliError(f"{unknown[0]}: unknown key (expected one of {sorted(allowed)})")
    units = data.get("units", {})
    if not isinstance(units, dict):
        raise CliError(f"units: expected an object like {_UNITS}, got {units!r}")
    for key, value in units.items():
        if key not in _UNITS:
            raise CliError(f"units.{key}: unknown unit kind (expected one of {sorted(_UNITS)})")
        if value != _UNITS[key]:
            raise CliError(f"units.{key}: only '{_UNITS[key]}' (SI) is accepted, got '{value}'")
    robot_name = data.get("robot", "gantry6")
    if not isinstance(robot_name, str) or robot_name not in ROBOTS:
        raise CliError(f"robot: unknown robot '{robot_name}' (expected one of {list(ROBOTS)})")
    if "hits" in data:
        entries = data["hits"]
        if not isinstance(entries, list) or not entries:
            raise CliError("hits: expected a non-empty list of hits")
        hits = [_hit(e, f"hits[{i}]") for i, e in enumerate(entries)]
    else:
        hits = [
            _hit(
                {k: v for k, v in data.items() if k not in ("robot", "units", "state", "ready", "profile")},
                "hit",
            )
        ]
    robot = _robot(robot_name)
    state = None
    if "state" in data:
        s = data["state"]
        if not isinstance(s, dict) or "q" not in s:
            raise CliError("state.q: missing key (the start configuration)")
        unknown = sorted(set(s) - {"q", "qd", "qdd"})
        if unknown:
            raise CliError(f"state.{unknown[0]}: unknown key (expected 'q', 'qd', 'qdd')")
        state = {k: _vector(s, k, "state", robot.dof) for k in ("q", "qd", "qdd") if k in s}
    ready = _vector(data, "ready", "file", robot.dof, required=False)
    profile = data.get("profile", "auto")
    profiles = _ttmanip_profiles()
    if profile not in profiles:
        names = ", ".join(repr(p) for p in profiles[:-1]) + f" or {profiles[-1]!r}"
        raise CliError(f"profile: expected {names}, got {profile!r}")
    return {"robot": robot, "hits": hits, "state": state, "ready": ready, "profile": profile}


def _plans(spec: dict):
    from . import plan_hits

    return plan_hits(spec["robot"], spec["hits"], spec["state"], ready=spec["ready"], profile=spec["profile"])


def _fail_unplanned(plans) -> int:
    bad = [(i, p) for i, p in enumerate(plans) if not p.ok]
    if not bad:
        return 0
    i, p = bad[0]
    more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
    print(f"ttmanip: error: hits[{i}]: {p.status}: {p.message}{more}", file=sys.stderr)
    return EXIT_NOT_DONE


# -- subcommands -------------------------------------------------------------------------------


def _demo(args: argparse.Namespace) -> int:
    from .demo import run

    out = _out_dir(args.out)
    bar = Progress(8 if not args.no_workspace else 7)
    try:
        summary = run(out, progress=bar, workspace=not args.no_workspace, rerun=args.rerun)
    finally:
        bar.close()
    _print_summary(
        summary,
        (
            "status",
            "t_hit",
            "profile",
            "racket_position_error_m",
            "racket_normal_error_deg",
            "racket_velocity_error_mps",
            "racket_velocity_error_rel",
            "faults",
        ),
    )
    print(
        f"mobile8: {summary['mobile8']['status']}, racket error "
        f"{summary['mobile8'].get('racket_position_error_m', float('nan')):.2e} m"
    )
    print(f"wrote {out / 'summary.json'}")
    if "rerun" in summary:
        print(f"wrote {summary['rerun']} (open it with: rerun {summary['rerun']})")
    return 0


def _experiment(args: argparse.Namespace) -> int:
    out = _out_dir(args.out)
    module = importlib.import_module(f"ttmanip.experiments.{args.name}")
    bar = Progress(1)
    try:
        summary = module.run(out)
        bar(args.name)
    finally:
        bar.close()
    for key, value in summary.items():
        if not isinstance(value, (list, dict)):
            print(f"{key}: {value}")
    print(f"wrote {out}")
    return 0


def _fk(args: argparse.Namespace) -> int:
    robot = _robot(args.robot)
    q = _numbers(args.q, "--q", robot.dof)
    pose = robot.fk(q)
    np.set_printoptions(precision=6, suppress=True)
    print(pose)
    if args.out:
        out = _out_dir(args.out)
        _write_json(out / "fk.json", {"robot": robot.name, "q": q, "pose": pose})
        print(f"wrote {out / 'fk.json'}")
    return 0


def _ik(args: argparse.Namespace) -> int:
    from . import Hit, TtmanipError, UnreachableError

    robot = _robot(args.robot)
    centre = _numbers(args.centre, "--centre", 3)
    normal = _numbers(args.normal, "--normal", 3)
    try:
        hit = Hit.from_normal(centre, normal, np.zeros(3), 1.0)
        # within the joint limits: a branch with d2 = 4.9 m on a ±0.6 m axis is not in reach
        # (before issue 29's sweep it was printed with exit 0)
        branches = robot.ik_all(hit.pose, limits=True)
    except UnreachableError as e:
        raise CliError(
            f"--centre: the racket pose at {centre.tolist()} is outside {robot.name}'s reach: {e}"
        ) from e
    except TtmanipError as e:
        raise CliError(f"--centre/--normal: {e}") from e
    ok = np.isfinite(branches).all(axis=1)
    if not ok.any():
        raise CliError(f"--centre: the racket pose at {centre.tolist()} is outside {robot.name}'s reach")
    np.set_printoptions(precision=6, suppress=True)
    print(branches[ok])
    if args.out:
        out = _out_dir(args.out)
        _write_json(out / "ik.json", {"robot": robot.name, "pose": hit.pose, "branches": branches[ok]})
        np.savetxt(out / "ik.csv", branches[ok], delimiter=",", header=",".join(robot.joint_names))
        print(f"wrote {out / 'ik.json'}")
    return 0


def _plan_summary(p) -> dict:
    return {
        "status": p.status,
        "message": p.message,
        "t_hit": p.t_hit,
        "t_hit_requested": p.requested_t_hit,
        "earliest_t_hit": p.earliest_t_hit,
        "profile": p.profile,
        "q_hit": p.q_hit,
        "qd_hit": p.qd_hit,
        "duration": p.duration,
        "peak_effort": p.peak_effort,
        "violations": p.violations,
    }


def _plan(args: argparse.Namespace) -> int:
    from . import plots
    from .demo import write_csv

    spec = read_hit_file(args.file)
    out = _out_dir(args.out)
    robot = spec["robot"]
    bar = Progress(len(spec["hits"]) + 1)
    try:
        plans = _plans(spec)
        bar("plan")
        for i, p in enumerate(plans):
            if p.trajectory is not None:
                t, q, qd, qdd = p.sample(1000.0)
                tau = p.torques(1000.0)
                write_csv(out / f"hit{i}_plan.csv", {"t": t, "q": q, "qd": qd, "qdd": qdd, "tau": tau})
                plots.joint_figure(robot, t, q, qd, qdd, tau, out / f"hit{i}_joints.png", t_hit=p.t_hit)
            bar(f"hit {i}")
    finally:
        bar.close()
    _write_json(out / "plan.json", {"robot": robot.name, "plans": [_plan_summary(p) for p in plans]})
    for i, p in enumerate(plans):
        print(f"hits[{i}]: {p.status}, t_hit {p.t_hit:.4f} s ({p.profile})")
    print(f"wrote {out / 'plan.json'}")
    return _fail_unplanned(plans)


def _simulate(args: argparse.Namespace) -> int:
    from .demo import run_hit

    spec = read_hit_file(args.file)
    out = _out_dir(args.out)
    if args.setpoint_rate is not None:  # the deprecated spelling of --setpoint-hz (one release)
        print("ttmanip: warning: --setpoint-rate is deprecated; use --setpoint-hz", file=sys.stderr)
        if args.setpoint_hz is not None:
            raise CliError("--setpoint-hz: given twice (once by its deprecated name --setpoint-rate)")
        args.setpoint_hz = args.setpoint_rate
    if args.setpoint_hz is not None and not args.setpoint_hz > 0:
        raise CliError(f"--setpoint-hz: expected a rate > 0 Hz, got {args.setpoint_hz}")
    if args.noise is not None and not args.noise >= 0:
        raise CliError(f"--noise: expected a current-sense noise >= 0 A, got {args.noise}")
    results = []
    bar = Progress(4 * len(spec["hits"]))
    rec = None
    if args.rerun:
        from .viz import Recording

        rec = Recording(args.rerun, "ttmanip-simulate")
    t0 = 0.0
    # A robot the rally plays (the core decides: its structure, whatever its name) stands at its
    # rally place by the table.
    from . import _ttmanip

    at_table = _ttmanip.ball_placement_for(spec["robot"])
    try:
        for i, hit in enumerate(spec["hits"]):
            results.append(
                run_hit(
                    spec["robot"],
                    hit,
                    out,
                    f"hit{i}",
                    gif=args.gif,
                    state=spec["state"],
                    noise=args.noise,
                    setpoint_hz=args.setpoint_hz,
                    progress=bar,
                    recording=rec,
                    t0=t0,
                    world_from_base=at_table,
                )
            )
            t0 += (results[-1].get("stroke_duration") or 0.0) + 0.5  # the hits one after the other
    finally:
        bar.close()
        if rec is not None:
            print(f"wrote {rec.close()}")
    _write_json(out / "summary.json", {"robot": spec["robot"].name, "hits": results})
    for i, r in enumerate(results):
        err = r.get("racket_position_error_m", float("nan"))
        print(
            f"hits[{i}]: {r['status']}, racket centre error {err:.3e} m, normal "
            f"{r.get('racket_normal_error_deg', float('nan')):.3f}°, velocity "
            f"{r.get('racket_velocity_error_mps', float('nan')):.4f} m/s"
        )
    print(f"wrote {out / 'summary.json'}")
    bad = [(i, r) for i, r in enumerate(results) if not r["ok"]]
    if bad:
        i, r = bad[0]
        print(f"ttmanip: error: hits[{i}]: {r['status']}: {r['message']}", file=sys.stderr)
        return EXIT_NOT_DONE
    return 0


def _actuators(robot):
    """Each joint's actuator from the robot's drive sections, or None when a joint has none."""
    from . import motor
    from ._ttmanip import ModelError

    try:
        return motor.actuators(robot)
    except ModelError:
        return None


def _info(args: argparse.Namespace) -> int:
    from .motor import drive_line

    robot = _robot(args.robot)
    print(robot)
    rows = []
    drives = _actuators(robot)
    drive_peak, effective = robot.drive_effort_limits, robot.effective_effort_limits
    sources = robot.effort_limit_sources
    drive_v, effective_v = robot.drive_velocity_limits, robot.effective_velocity_limits
    v_sources = robot.velocity_limit_sources
    columns = zip(robot.joint_names, robot.joint_types, robot.limits, strict=True)
    for j, (name, kind, (lo, hi)) in enumerate(columns):
        v, a, e = robot.velocity_limits[j], robot.acceleration_limits[j], robot.effort_limits[j]
        d, eff, src = drive_peak[j], effective[j], sources[j]
        dv, ev, vsrc = drive_v[j], effective_v[j], v_sources[j]
        print(
            f"  {name:10s} {kind:9s} [{lo: .4f}, {hi: .4f}]  v {v:g}  drive speed {dv:.4g}"
            f"  -> {ev:.4g} ({vsrc} governs)  a {a:g}  effort {e:g}"
            f"  drive peak {d:.4g}  -> {eff:.4g} ({src} governs)"
        )
        if drives is not None:
            print(f"  {'':10s} drive: {drive_line(drives[j])}")
        rows.append(
            {
                "name": name,
                "type": kind,
                "lower": lo,
                "upper": hi,
                "velocity": v,
                "drive_velocity": dv,
                "effective_velocity": ev,
                "velocity_source": vsrc,
                "acceleration": a,
                "effort": e,
                "drive_effort": d,
                "effective_effort": eff,
                "effort_source": src,
                "drive": None if drives is None else drives[j],
            }
        )
    if args.out:
        out = _out_dir(args.out)
        _write_json(out / "info.json", {"robot": robot.name, "joints": rows})
        print(f"wrote {out / 'info.json'}")
    return 0


def _export(args: argparse.Namespace) -> int:
    robot = _robot(args.robot)
    out = Path(args.out)
    header = (
        f"# Built-in robot {args.robot} of ttmanip, written by `ttmanip export {args.robot}`; SI units.\n"
        "# tests/test_robot_files.py checks that this file and the built-in model agree.\n"
    )
    if out.suffix and out.suffix not in (".urdf", ".toml"):
        raise CliError(f"--out: expected a folder or a file ending in .urdf or .toml, got '{out}'")
    if out.suffix in (".urdf", ".toml"):
        _out_dir(str(out.parent) if str(out.parent) else ".")
        targets = [out]
    else:
        out = _out_dir(args.out)
        targets = [out / f"{args.robot}.urdf", out / f"{args.robot}.toml"]
    for path in targets:
        try:
            path.write_text(robot.to_urdf() if path.suffix == ".urdf" else header + robot.to_toml())
        except OSError as e:
            raise CliError(f"--out: cannot write '{path}': {e.strerror or e}") from e
        print(f"wrote {path}")
    return 0


def _telemetry(args: argparse.Namespace) -> int:
    from .viz import record_telemetry

    print(f"wrote {record_telemetry(args.file, args.rerun)}")
    return 0


def _arg(*flags: str, **options) -> tuple[tuple[str, ...], dict]:
    """One argument of a subcommand: the flags and options of ``add_argument``."""
    return flags, options


def _command(sub, name: str, func, help: str, description: str, *arguments) -> argparse.ArgumentParser:
    """Adds subcommand ``name`` running ``func``, with its help, description and arguments."""
    parser = sub.add_parser(
        name, help=help, description=description, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    for flags, options in arguments:
        parser.add_argument(*flags, **options)
    parser.set_defaults(func=func)
    return parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``ttmanip`` command."""
    parser = argparse.ArgumentParser(
        prog="ttmanip", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = parser.add_subparsers(dest="command", required=True)

    _command(
        sub,
        "demo",
        _demo,
        "plan and simulate a gantry6 hit on every axis, write the figures",
        "Plans seed 002's demo hit on gantry6, simulates it through every "
        "axis's drive with gravity, then a mobile8 racket hit; writes figures, CSV and "
        "summary.json.\n\nexample:\n  ttmanip demo --out out/demo",
        _arg("--out", default="out/demo", help="output folder (default: out/demo)"),
        _arg("--no-workspace", action="store_true", help="skip the workspace figures"),
        _arg("--rerun", metavar="FILE.rrd", help="also write a Rerun recording (needs ttmanip[viz])"),
    )
    _command(
        sub,
        "experiment",
        _experiment,
        "reproduce a seed document's experiment",
        "Runs a seed experiment and writes every product.\n\nexample:\n"
        "  ttmanip experiment seed002 --out out/seed002",
        _arg("name", choices=EXPERIMENTS),
        _arg("--out", required=True, help="output folder"),
    )
    _command(
        sub,
        "fk",
        _fk,
        "tool pose of a built-in robot at a configuration",
        "Prints the 4x4 tool pose (base frame, m).\n\nexample:\n"
        "  ttmanip fk gantry6 --q 0.1,0,0.2,0.3,0.4,0.5 --out out/fk",
        _arg("robot", choices=ROBOTS),
        _arg("--q", required=True, help="joint values, comma-separated (m, rad)"),
        _arg("--out", help="output folder for fk.json"),
    )
    _command(
        sub,
        "ik",
        _ik,
        "every IK branch for a racket centre and face normal",
        "Prints every analytic IK branch reaching the racket pose within the joint limits.\n\nexample:\n"
        "  ttmanip ik gantry6 --centre 0.35,-0.55,0.05 --normal 0.3,-1,-0.2",
        _arg("robot", choices=ROBOTS),
        _arg("--centre", required=True, help="racket centre x,y,z (m, base frame)"),
        _arg("--normal", required=True, help="face normal nx,ny,nz (base axes)"),
        _arg("--out", help="output folder for ik.json and ik.csv"),
    )
    _command(
        sub,
        "plan",
        _plan,
        "plan the hits of a JSON hit file",
        HIT_FILE_HELP + "\n\nexample:\n  ttmanip plan hit.json --out out/plan",
        _arg("file", help="hit file (.json)"),
        _arg("--out", default="out/plan", help="output folder (default: out/plan)"),
    )
    _command(
        sub,
        "simulate",
        _simulate,
        "plan and simulate the hits of a JSON hit file on the drives",
        HIT_FILE_HELP + "\n\nexample:\n  ttmanip simulate hit.json --out out/sim",
        _arg("file", help="hit file (.json)"),
        _arg("--out", default="out/simulate", help="output folder (default: out/simulate)"),
        _arg("--noise", type=float, help="current-sense noise (A, DriveSim's default if unset)"),
        _arg("--setpoint-hz", type=float, help="setpoint rate to the drives (Hz, DriveSim's default: 1000)"),
        _arg("--setpoint-rate", type=float, help=argparse.SUPPRESS),  # deprecated name of --setpoint-hz
        _arg("--gif", action="store_true", help="also write a GIF of each stroke"),
        _arg("--rerun", metavar="FILE.rrd", help="also write a Rerun recording (needs ttmanip[viz])"),
    )

    _command(
        sub,
        "info",
        _info,
        "print a built-in robot's joints and limits",
        "example:\n  ttmanip info gantry6 --out out/info",
        _arg("robot", choices=ROBOTS),
        _arg("--out", help="output folder for info.json"),
    )

    _command(
        sub,
        "export",
        _export,
        "write a built-in robot as URDF and as a ttmanip robot file",
        "--out is a folder (both files) or a file ending in .urdf or .toml."
        "\n\nexample:\n  ttmanip export gantry6 --out out/robots",
        _arg("robot", choices=ROBOTS),
        _arg("--out", required=True, help="output folder, or a file ending in .urdf or .toml"),
    )

    from . import rally_cli  # issue 13

    rally_cli.add_parser(sub)
    from . import ball_cli  # issue 28

    ball_cli.add_parser(sub)
    from . import sweep_cli  # issue 31

    sweep_cli.add_parser(sub)
    from . import hil_cli  # issue 26

    hil_cli.add_parser(sub)
    _command(
        sub,
        "telemetry",
        _telemetry,
        "convert a ttctl telemetry CSV to a Rerun recording",
        "Writes q, q_ref and current of every axis and the cycle latency of every channel as "
        "time series (needs ttmanip[viz]).\n\nexample:\n  ttmanip telemetry tele.csv --rerun tele.rrd",
        _arg("file", help="telemetry CSV written by ttctl --telemetry"),
        _arg("--rerun", metavar="FILE.rrd", required=True, help="the recording to write"),
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ttmanip`` command: user errors become one line on stderr."""
    from . import TtmanipError

    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:
        # argparse exits 2 on a usage error; here 2 means "not done": a usage error is bad input.
        return EXIT_BAD_INPUT if e.code not in (0, None) else EXIT_SUCCESS
    try:
        return args.func(args)
    except (CliError, TtmanipError) as e:
        print(f"ttmanip: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:
        print(f"ttmanip: error: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # every long call stops on Ctrl-C (the bindings poll for it while they work): one line,
        # no traceback, the shell's status for a command SIGINT ended
        print("\nttmanip: interrupted (Ctrl-C): stopped before the end", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    raise SystemExit(main())
