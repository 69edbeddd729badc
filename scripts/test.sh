#!/usr/bin/env bash
# Sets up the project (scripts/setup.sh) and runs every check and test: formatting and lints,
# the Rust tests of the workspace, the Python tests against the installed wheel, and the CAN
# scenarios in a QEMU VM. Each step prints its start time and the run ends with a table of the
# steps' wall times (also when a step fails), so a CI log shows where the time went.
#
# Two cores' worth of work: the release builds (the wheel, then ttctl/ttdrive-sim; their fat-LTO
# codegen runs on one core for minutes) run in the background beside the debug builds (clippy,
# rustdoc, the test binaries); cargo locks target/release and target/debug separately. The timed
# tests (cargo test's online controller, the pytest tests marked `serial`, the VM) run with nothing
# of this script beside them.
set -euo pipefail
cd "$(dirname "$0")/.."

STEP_TIMES=()
STEP_NAME=""
STEP_START=$SECONDS
BG_PID=""
# step NAME: ends the step running (recording its wall time) and starts NAME
step() {
    if [ -n "$STEP_NAME" ]; then
        STEP_TIMES+=("$(printf '%6d s  %s' $((SECONDS - STEP_START)) "$STEP_NAME")")
    fi
    STEP_NAME=$1
    STEP_START=$SECONDS
    [ -z "$STEP_NAME" ] || echo "== $STEP_NAME ($(date -u +%H:%M:%S) UTC)"
}
on_exit() {
    local rc=$?
    if [ -n "$BG_PID" ] && kill -0 "$BG_PID" 2>/dev/null; then
        kill -- -"$BG_PID" 2>/dev/null || true # its own process group (setsid): cargo, maturin, pip
        echo "== stopped the background release builds; their log: target/ci-release.log"
        tail -n 40 target/ci-release.log || true
    fi
    [ -z "$STEP_NAME" ] || STEP_TIMES+=("$(printf '%6d s  %s%s' $((SECONDS - STEP_START)) "$STEP_NAME" \
        "$([ $rc -eq 0 ] || echo ' (FAILED)')")")
    echo "== step wall times (load $(cut -d' ' -f1-3 /proc/loadavg))"
    printf '%s\n' "${STEP_TIMES[@]}"
    printf '%6d s  total (exit %d)\n' "$SECONDS" "$rc"
}
trap on_exit EXIT

# The debug builds (clippy, cargo test, the test binaries) keep line tables (backtraces with file
# and line) but not full debug info: the test binaries link in a fraction of the time.
export CARGO_PROFILE_DEV_DEBUG="${CARGO_PROFILE_DEV_DEBUG:-line-tables-only}"
# On CI the property tests run a fixed, reproducible set of cases (proptest seed here, hypothesis
# profile in tests/conftest.py); elsewhere they draw new cases every run.
if [ "${CI:-}" = "true" ]; then
    export PROPTEST_RNG_SEED="${PROPTEST_RNG_SEED:-20261124}"
fi

step "setup and release binaries (background) | fmt, clippy, rustdoc, test binaries"
mkdir -p target
# One release build of ttctl and ttdrive-sim (the release profile, as shipped) for the HIL test
# ($TTCTL), the Python tests that run the binaries and the VM (scripts/vm/build.sh finds it built).
setsid bash -c 'set -e; s=$SECONDS
    bash scripts/setup.sh
    echo "ci: setup (venv, release wheel): $((SECONDS - s)) s"; s=$SECONDS
    cargo build --release --quiet -p ttcan --bin ttctl --bin ttdrive-sim
    echo "ci: cargo build --release ttctl ttdrive-sim: $((SECONDS - s)) s"' \
    > target/ci-release.log 2>&1 < /dev/null &
BG_PID=$!
t=$SECONDS
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
echo "ci: fmt, clippy: $((SECONDS - t)) s"; t=$SECONDS
RUSTDOCFLAGS="-D warnings" cargo doc --quiet --no-deps -p ttkin -p ttcan
echo "ci: rustdoc: $((SECONDS - t)) s"; t=$SECONDS
cargo test --quiet --no-run
echo "ci: cargo test --no-run: $((SECONDS - t)) s"
rc=0
wait "$BG_PID" || rc=$?
BG_PID=""
cat target/ci-release.log
[ $rc -eq 0 ] || { echo "ci: setup / release build failed (exit $rc)"; exit $rc; }

step "ruff"
.venv/bin/ruff check python tests benches
.venv/bin/ruff format --check python tests benches

step "cargo test (runs)"
cargo test --quiet

# Two pytest runs: the tests marked `serial` (real time: a controller's cycles against the clock)
# alone, everything else on two workers (pytest-xdist, a whole file per worker); --durations lists
# the slowest in the log. Binaries: the timed ttctl runs (HIL rally, online link) take the release
# build ($TTCTL); the others the debug builds of cargo test, debug assertions and overflow checks on
# ($TTCAN_BIN_DIR for tests/conftest.py built_binary; test_canopen_interop's default).
export TTCTL="$PWD/target/release/ttctl"
export TTCAN_BIN_DIR="$PWD/target/debug"
step "pytest (parallel, 2 workers)"
.venv/bin/python -m pytest -q -n 2 --dist loadfile -m "not serial" --durations=15 tests
step "pytest (serial: real-time tests)"
.venv/bin/python -m pytest -q -p no:xdist -m serial --durations=10 tests

step "VM build: CiA 402 over real Linux SocketCAN (QEMU/TCG; scripts/vm, tests/vm)"
bash scripts/vm/build.sh
step "VM run"
bash scripts/vm/run.sh
step ""
