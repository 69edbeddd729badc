#!/usr/bin/env bash
# Builds the API reference of the Python package with pdoc into docs/api/ (or $1): the package,
# each public module and the extension ttmanip._ttmanip, from their docstrings. Fails on any
# warning (pdoc reports unresolvable annotations, links or sources as Python warnings).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/api}
.venv/bin/python - "$out" <<'PY'
import sys
import warnings
from pathlib import Path

import pdoc
import pdoc.render

import ttmanip

out = Path(sys.argv[1])
# every module of the package but the command-line front ends (docs/cli.md) and the seed scripts
modules = ["ttmanip", "ttmanip._ttmanip"] + sorted(
    f"ttmanip.{p.stem}"
    for p in Path(ttmanip.__file__).parent.glob("*.py")
    if not p.stem.startswith("_")
    and p.stem not in ("cli", "rally_cli", "sweep_cli")
    and p.stem not in ttmanip.__all__  # pdoc walks these from ttmanip
)
pdoc.render.configure(docformat="restructuredtext", footer_text="ttmanip API reference")
with warnings.catch_warnings():
    warnings.simplefilter("error")
    pdoc.pdoc(*modules, output_directory=out)
print(f"wrote {out}/index.html ({len(modules)} modules)")
PY
