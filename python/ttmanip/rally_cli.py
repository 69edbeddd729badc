"""The ``ttmanip rally`` subcommand: a simulated rally against randomized incoming balls."""

from __future__ import annotations

import argparse
import json


def add_parser(sub) -> argparse.ArgumentParser:
    """Adds ``rally`` to the subparsers ``sub`` of the ``ttmanip`` command."""
    p = sub.add_parser("rally", help="simulate gantry6 returning randomized incoming balls")
    p.add_argument("--n", type=int, default=1000, help="number of balls (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", default="out/rally", help="output folder (default: out/rally)")
    p.add_argument(
        "--drives",
        type=int,
        default=20,
        help="in-reach balls also executed through the drive simulation (default 20)",
    )
    p.add_argument(
        "--rerun",
        metavar="FILE.rrd",
        help="also a Rerun recording of the first 10 balls (needs ttmanip[viz])",
    )
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Runs the rally, writes ``summary.json`` and figures, prints the summary."""
    import sys

    from . import TtmanipError
    from .rally import rally

    try:
        summary = rally(args.n, args.seed, out=args.out, progress=True, drives=args.drives)
    except TtmanipError as e:
        print(f"ttmanip rally: {e}", file=sys.stderr)
        return 1  # bad input (ttmanip.cli.EXIT_BAD_INPUT)
    if args.rerun:
        from .viz import record_rally

        print(f"wrote {record_rally(args.rerun, summary)}", file=sys.stderr)
    summary.pop("results")
    print(json.dumps({k: v for k, v in summary.items() if k != "figures"}, indent=2))
    print(f"wrote {args.out}/summary.json")
    return 0
