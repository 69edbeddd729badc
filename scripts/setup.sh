#!/usr/bin/env bash
# Sets up everything ttmanip needs on a fresh machine: a virtual environment in .venv with the
# Python dependencies, and the ttmanip wheel built from this checkout (Rust, release) and installed.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet "maturin>=1.5,<2"

rm -rf dist
.venv/bin/maturin build --release --quiet --out dist --interpreter .venv/bin/python
wheel=$(ls dist/ttmanip-*.whl)
.venv/bin/python -m pip install --quiet --force-reinstall --no-deps "$wheel"
.venv/bin/python -m pip install --quiet "${wheel}[test]"
