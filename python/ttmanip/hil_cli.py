"""The ``ttmanip hil`` subcommand: the rally's balls in real time against a running ``ttctl``."""

from __future__ import annotations

import argparse
import json


def add_parser(sub) -> argparse.ArgumentParser:
    """Adds ``hil`` to the subparsers ``sub`` of the ``ttmanip`` command."""
    p = sub.add_parser(
        "hil",
        help="hardware-in-the-loop rally: the rally's balls streamed to ttctl in ball mode",
        description="Plays the rally's incoming balls (same seed, same balls) in real time against "
        "ttctl in ball mode (started here with virtual drives unless --connect), scores them from "
        "the measured joint states as the rally does, and reports the return rate beside the "
        "offline rally's.\n\nexample:\n  ttmanip hil --n 20 --out out/hil",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--n", type=int, default=20, help="number of balls (default 20)")
    p.add_argument("--seed", type=int, default=0, help="the rally's random seed (default 0)")
    p.add_argument("--out", default="out/hil", help="output folder (default: out/hil)")
    p.add_argument("--connect", metavar="HOST:PORT", help="a running ttctl's ball-mode address")
    p.add_argument(
        "--ttctl",
        metavar="PATH",
        help="the ttctl binary (default: on PATH, else target/release/ttctl of the checkout)",
    )
    p.add_argument(
        "--config", metavar="PATH", help="ttctl configuration (default: tests/online/gantry6_hil.toml)"
    )
    p.add_argument(
        "--world",
        choices=("model", "mismatch"),
        default="model",
        help="the world the balls fly in (as ttmanip rally --world)",
    )
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Runs the HIL rally, writes summary.json and the timeline figure, prints the summary."""
    from .hil import HilError
    from .hil import run as hil_run

    connect = None
    if args.connect:
        host, _, port = args.connect.rpartition(":")
        if not host or not port.isdigit() or int(port) > 65535:
            raise HilError(f"--connect: {args.connect!r} is not HOST:PORT (a port in 0..=65535)")
        connect = (host, int(port))
    summary = hil_run(
        args.n,
        seed=args.seed,
        out=args.out,
        connect=connect,
        ttctl=args.ttctl,
        config=args.config,
        world=args.world == "mismatch",
    )
    print(json.dumps(summary, indent=2))
    return 0
