#!/usr/bin/env bash
# Sets up the project (scripts/setup.sh) and runs every check and test: formatting and lints,
# the Rust tests of the workspace, and the Python tests against the installed wheel.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh

# On CI the property tests run a fixed, reproducible set of cases (proptest seed here, hypothesis
# profile in tests/conftest.py); elsewhere they draw new cases every run.
if [ "${CI:-}" = "true" ]; then
    export PROPTEST_RNG_SEED="${PROPTEST_RNG_SEED:-20261124}"
fi

echo "== cargo fmt / clippy / ruff / rustdoc"
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
.venv/bin/ruff check python tests benches
.venv/bin/ruff format --check python tests benches
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps -p ttkin -p ttcan

echo "== cargo test"
cargo test --quiet

echo "== pytest"
.venv/bin/python -m pytest -q tests

echo "== VM: CiA 402 over real Linux SocketCAN (QEMU/TCG; scripts/vm, tests/vm)"
bash scripts/vm/build.sh
bash scripts/vm/run.sh
