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
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ttmanip`` command."""
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
