"""The ``ttmanip rally`` subcommand: a simulated rally against randomized incoming balls."""

from __future__ import annotations

import argparse
import json


def add_parser(sub) -> argparse.ArgumentParser:
    """Adds ``rally`` to the subparsers ``sub`` of the ``ttmanip`` command."""
    p = sub.add_parser("rally", help="simulate gantry6 returning randomized incoming balls")
    p.add_argument(
        "--n", type=int, default=None, help="number of balls (default 1000, or the rows of --balls)"
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", default="out/rally", help="output folder (default: out/rally)")
    p.add_argument(
        "--drives",
        type=int,
        default=20,
        help="in-reach balls also executed through the drive simulation (default 20)",
    )
    p.add_argument(
        "--world",
        choices=("model", "mismatch", "both"),
        default="model",
        help="the world the balls fly in: the planner's model (default), a mismatched one "
        "(per-ball constants and latency drawn around the model's), or both on the same balls "
        "(summary of the mismatched run with world_comparison)",
    )
    p.add_argument(
        "--balls",
        help="incoming balls from a file: one row per ball, t px py pz vx vy vz wx wy wz "
        "(s, m, m/s, rad/s, world frame; comma or space separated, # comments); --n defaults to its rows",
    )
    p.add_argument(
        "--execution",
        choices=("ideal", "drives"),
        default="ideal",
        help="strokes executed exactly (default) or through the coupled drive simulation",
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

    import numpy as np

    from . import TtmanipError
    from .files import read_text
    from .rally import rally

    incoming = None
    n = args.n if args.n is not None else 1000
    if args.balls:
        try:
            # read no further than 16 MiB (a device such as /dev/zero never ends), UTF-8 only
            text = read_text(args.balls, f"--balls {args.balls}").replace(",", " ")
            incoming = np.loadtxt(text.splitlines(), ndmin=2)
        except TtmanipError as e:
            print(f"ttmanip rally: {e}", file=sys.stderr)
            return 1  # bad input (ttmanip.cli.EXIT_BAD_INPUT)
        except (OSError, ValueError) as e:
            print(f"ttmanip rally: --balls {args.balls}: {e}", file=sys.stderr)
            return 1  # bad input (ttmanip.cli.EXIT_BAD_INPUT)
        if incoming.shape[1] != 10:
            print(
                f"ttmanip rally: --balls {args.balls}: rows must have 10 numbers "
                f"(t px py pz vx vy vz wx wy wz), got {incoming.shape[1]}",
                file=sys.stderr,
            )
            return 1  # bad input
        n = min(args.n, len(incoming)) if args.n is not None else len(incoming)
    try:
        summary = rally(
            n,
            args.seed,
            out=args.out,
            progress=True,
            drives=args.drives,
            world=args.world != "model",
            incoming=incoming,
            compare_world=args.world == "both",
            drive_execution=args.execution == "drives",
        )
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
