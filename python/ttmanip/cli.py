"""The ``ttmanip`` command line: demos and the seed experiments, each writing figures to a folder."""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

EXPERIMENTS = ("seed000", "seed001")


def _demo(args: argparse.Namespace) -> int:
    from .demo import run

    summary = run(Path(args.out))
    for key, value in summary.items():
        print(f"{key}: {value}")
    return 0


def _experiment(args: argparse.Namespace) -> int:
    try:
        module = importlib.import_module(f"ttmanip.experiments.{args.name}")
    except ModuleNotFoundError:
        print(f"ttmanip: experiment '{args.name}' is not available in this build", file=sys.stderr)
        return 2
    summary = module.run(Path(args.out))
    for key, value in summary.items():
        print(f"{key}: {value}")
    return 0


def _info(args: argparse.Namespace) -> int:
    from . import Robot

    robot = Robot.builtin(args.robot)
    print(robot)
    for name, kind, (lo, hi) in zip(robot.joint_names, robot.joint_types, robot.limits):
        print(f"  {name:14s} {kind:9s} [{lo: .4f}, {hi: .4f}]")
    return 0


def _export(args: argparse.Namespace) -> int:
    from . import Robot

    robot = Robot.builtin(args.robot)
    out = Path(args.out)
    if out.suffix == ".urdf":
        out.write_text(robot.to_urdf())
    elif out.suffix == ".toml":
        header = (
            f"# Built-in robot {args.robot} of ttmanip, written by `ttmanip export {args.robot}`; SI units.\n"
            "# tests/test_robot_files.py checks that this file and the built-in model agree.\n"
        )
        out.write_text(header + robot.to_toml())
    else:
        print("ttmanip: --out must end in .urdf or .toml", file=sys.stderr)
        return 2
    print(f"wrote {out}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``ttmanip`` command."""
    parser = argparse.ArgumentParser(prog="ttmanip", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser("demo", help="run the pipeline demo and write its figures")
    demo.add_argument("--out", default="out/demo", help="output folder (default: out/demo)")
    demo.set_defaults(func=_demo)

    exp = sub.add_parser("experiment", help="reproduce a seed document's experiment")
    exp.add_argument("name", choices=EXPERIMENTS)
    exp.add_argument("--out", required=True, help="output folder")
    exp.set_defaults(func=_experiment)

    info = sub.add_parser("info", help="print a built-in robot's joints and limits")
    info.add_argument("robot", choices=("mobile8", "gantry6", "arm4", "ur5"))
    info.set_defaults(func=_info)

    export = sub.add_parser("export", help="write a built-in robot as URDF or as a ttmanip robot file")
    export.add_argument("robot", choices=("mobile8", "gantry6", "arm4", "ur5"))
    export.add_argument("--out", required=True, help="file ending in .urdf or .toml")
    export.set_defaults(func=_export)

    from . import rally_cli  # issue 13

    rally_cli.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ttmanip`` command."""
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
