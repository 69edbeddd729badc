"""The ``ttmanip sweep`` subcommand: a design study on Dask (``ttmanip.sweeps``)."""

from __future__ import annotations

import argparse

EXAMPLE = """examples:
  ttmanip sweep hits --param base_x=-0.3:0.3:5 --param speed=2,4,6 --out out/sweep
  ttmanip sweep rally --random 12 --param max_spin_rps=0:60 --param target_x=0.4:1.2 --n 200
  ttmanip sweep hits --param speed=2,6 --scheduler tcp://10.0.0.5:8786

--param NAME=v1,v2,...   grid values;  NAME=low:high:count  evenly spaced grid values;
--param NAME=low:high    a range for --random.
Parameters: hits: base_x, base_y (m), speed (m/s), drive_scale (x the joints' velocity,
acceleration and effort limits); rally: target_x, target_y (m), max_spin_rps (rev/s)."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Adds ``sweep`` to the subparsers ``sub`` of the ``ttmanip`` command."""
    from .sweeps import STUDIES

    p = sub.add_parser(
        "sweep",
        help="a grid or random design study as Dask tasks (needs ttmanip[sweep])",
        description="Runs a design study over named parameters as Dask tasks: a LocalCluster by "
        "default, or the Dask scheduler at --scheduler. Writes sweep.csv (+ sweep.parquet with "
        "pyarrow) and sweep.png; identical numbers on any number of workers.\n\n" + EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("study", choices=sorted(STUDIES), help="what to evaluate at each point")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUES", help="a design parameter")
    p.add_argument(
        "--random", type=int, metavar="POINTS", help="random design of POINTS points (default: grid)"
    )
    p.add_argument("--n", type=int, help="trials per point (study default)")
    p.add_argument("--chunk", type=int, help="trials per task (study default)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes (default 2)")
    p.add_argument("--scheduler", help="a running Dask scheduler (tcp://host:8786), or 'serial' (no Dask)")
    p.add_argument("--out", default="out/sweep", help="output folder (default: out/sweep)")
    p.set_defaults(func=run)
    return p


def _param(text: str, random: bool):
    """NAME=v1,v2 | NAME=low:high:count (grid) | NAME=low:high (random) -> (name, values)."""
    from .cli import CliError

    name, sep, spec = text.partition("=")
    if not sep or not name:
        raise CliError(f"--param: expected NAME=VALUES, got '{text}'")
    try:
        if ":" in spec:
            parts = [float(v) for v in spec.split(":")]
            if random and len(parts) == 2:
                return name, parts
            if not random and len(parts) == 3 and parts[2] >= 1 and parts[2] == int(parts[2]):
                import numpy as np

                return name, list(np.linspace(parts[0], parts[1], int(parts[2])))
            raise ValueError
        if random:
            raise ValueError
        return name, [float(v) for v in spec.split(",")]
    except ValueError:
        want = "low:high" if random else "v1,v2,... or low:high:count"
        raise CliError(f"--param {name}: expected {want}, got '{spec}'") from None


def run(args: argparse.Namespace) -> int:
    """Runs the sweep with a progress bar, writes the table and the figure, prints the rows."""
    from .sweeps import sweep

    params = dict(_param(t, args.random is not None) for t in args.param)
    result = sweep(
        args.study,
        params,
        design="random" if args.random is not None else "grid",
        points=args.random or 8,
        n=args.n,
        chunk=args.chunk,
        seed=args.seed,
        scheduler=args.scheduler,
        workers=args.workers,
        out=args.out,
        progress=True,
    )
    names = list(result["rows"][0])
    print("  ".join(f"{k:>12s}" for k in names))
    for r in result["rows"]:
        print("  ".join(f"{v:12.4g}" if isinstance(v, float) else f"{v:>12}" for v in r.values()))
    print(f"{result['tasks']} tasks on {result['workers']} workers in {result['wall_s']:.1f} s")
    for f in result["files"].values():
        print(f"wrote {f}")
    return 0
