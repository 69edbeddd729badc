"""The ``ttmanip ball`` subcommands: ``ttmanip ball fit DATA --out DIR`` (the ball model calibrated
on recorded flights, ``ttmanip.ball_fit``)."""

from __future__ import annotations

import argparse
import json


def add_parser(sub) -> argparse.ArgumentParser:
    """Adds ``ball`` (with ``fit``) to the subparsers ``sub`` of the ``ttmanip`` command."""
    p = sub.add_parser("ball", help="ball-model tools (fit: calibrate on recorded flights)")
    bsub = p.add_subparsers(dest="ball_command", required=True)
    f = bsub.add_parser(
        "fit",
        help="calibrate drag, Magnus, table restitution and friction on recorded flights",
        description="Fits the ball model to recorded flights (a zip or folder of JSON files "
        '{"ob": [[x,y,z,vx,vy,vz], ...]}), holds every fourth file (sorted by path) out and compares '
        "the held-out prediction error with published constants.\n\nexample:\n"
        "  ttmanip ball fit ../shared/data/ball/pam_ball_trajectories.zip --out out/ballfit",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    f.add_argument("data", help="zip file or folder of flight JSON files")
    f.add_argument("--out", default="out/ballfit", help="output folder (default: out/ballfit)")
    f.add_argument("--window", type=int, default=20, help="frames the prediction starts from (default 20)")
    f.add_argument("--period", type=float, help="frame period (s); estimated from the data when unset")
    f.set_defaults(func=run_fit)
    return p


def run_fit(args: argparse.Namespace) -> int:
    """Runs the calibration, writes summary.json and fit.png, prints the main numbers."""
    import sys

    from . import TtmanipError
    from .ball_fit import run

    try:
        s = run(args.data, args.out, window=args.window, period=args.period)
    except (TtmanipError, ValueError, FileNotFoundError) as e:
        print(f"ttmanip ball fit: {e}", file=sys.stderr)
        return 1  # bad input (ttmanip.cli.EXIT_BAD_INPUT)
    short = {
        "flights": s["flights"],
        "held_out_flights": s["held_out_flights"],
        "fit": {k: s["fit"][k] for k in ("globals", "std", "sigma_m", "median_flight_rms_m")},
        "held_out_median_rms_after_bounce_m": {
            m["name"]: m["median_after_bounce"] for m in s["prediction"]["models"]
        },
        "calibrated_le_best_published": s["prediction"]["calibrated_le_best_published"],
    }
    print(json.dumps(short, indent=2))
    print(f"wrote {args.out}/summary.json and {s['figure']}")
    return 0
