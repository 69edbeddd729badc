"""The API reference (issue 31): every public name has a docstring, and pdoc builds the reference
from them without a warning (scripts/docs.sh, the same build a user runs)."""

from __future__ import annotations

import inspect
import subprocess
import sys
from pathlib import Path

import ttmanip
from api_registry import MODULES, public_callables, public_classes

ROOT = Path(__file__).resolve().parent.parent


def _doc(obj) -> str:
    """The object's own docstring ("" when missing; a dataclass's generated signature is missing)."""
    if isinstance(obj, staticmethod | classmethod):
        obj = obj.__func__
    if isinstance(obj, property):
        obj = obj.fget
    doc = (getattr(obj, "__doc__", None) or "").strip()
    if inspect.isclass(obj) and doc.startswith(f"{obj.__name__}("):
        return ""  # dataclasses write their signature when the class has no docstring
    return doc


def test_every_public_name_has_a_docstring():
    names = {**public_callables(), **public_classes()}
    names.update({m: getattr(ttmanip, m) for m in MODULES})
    names["ttmanip"] = ttmanip
    names["sweeps"] = ttmanip.sweeps
    documented = (property, staticmethod, classmethod, type(ttmanip))
    missing = sorted(
        k
        for k, v in names.items()
        if (callable(v) or isinstance(v, documented) or inspect.isdatadescriptor(v)) and not _doc(v)
    )
    assert missing == [], f"public names without a docstring: {missing}"


def test_api_reference_builds_without_warnings(tmp_path):
    r = subprocess.run(
        ["bash", str(ROOT / "scripts" / "docs.sh"), str(tmp_path)],
        capture_output=True,
        text=True,
        env={"PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin"},
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert "warn" not in r.stderr.lower(), r.stderr[-3000:]
    index = (tmp_path / "ttmanip.html").read_text()
    for name in ("Robot", "plan_hits", "sweep", "HitPlan"):
        assert name in index
    assert (tmp_path / "ttmanip" / "sweeps.html").exists()
