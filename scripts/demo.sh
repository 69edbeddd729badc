#!/usr/bin/env bash
# Sets up the project (scripts/setup.sh) and runs the demo of the pipeline; figures land in out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh
.venv/bin/ttmanip demo --out "${1:-out/demo}"
