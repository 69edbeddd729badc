"""The built wheel is one abi3 wheel, installs into a clean virtual environment and runs
``ttmanip demo`` there. CI builds the wheel in ``scripts/setup.sh`` (``dist/``); elsewhere set
``TTMANIP_WHEEL`` to a wheel's path, or build one with ``maturin build --release --out dist``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _wheel() -> Path | None:
    env = os.environ.get("TTMANIP_WHEEL")
    if env:
        return Path(env)
    wheels = sorted((ROOT / "dist").glob("ttmanip-*.whl"), key=lambda p: p.stat().st_mtime)
    return wheels[-1] if wheels else None


@pytest.mark.wheel
def test_wheel_is_abi3_and_runs_the_demo_in_a_clean_venv(tmp_path):
    wheel = _wheel()
    if wheel is None:
        pytest.skip("no wheel built: run scripts/setup.sh or `maturin build --release --out dist` first")
    assert wheel.exists(), wheel
    assert "-cp310-abi3-" in wheel.name, f"{wheel.name} is not a single abi3 wheel for CPython ≥ 3.10"
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    py = env_dir / "bin" / "python"
    subprocess.run([py, "-m", "pip", "install", "--quiet", str(wheel)], check=True, timeout=900)
    out = tmp_path / "demo"
    exe = env_dir / "bin" / "ttmanip"
    r = subprocess.run(
        [exe, "demo", "--no-workspace", "--out", out],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["racket_position_error_m"] <= 1e-3
    assert summary["racket_normal_error_deg"] <= 0.5
    assert summary["racket_velocity_error_rel"] <= 0.02
    # The clean environment imports the installed package, not this checkout.
    r = subprocess.run(
        [py, "-c", "import ttmanip; print(ttmanip.__file__)"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=True,
    )
    assert str(env_dir) in r.stdout, r.stdout
    assert sys.executable != str(py)
