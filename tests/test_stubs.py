"""The hand-written stubs (_ttmanip.pyi) describe exactly what the extension exports."""

from __future__ import annotations

import ast
from pathlib import Path

import ttmanip
from ttmanip import _ttmanip

STUB = Path(ttmanip.__file__).with_name("_ttmanip.pyi")


def _stub_names() -> tuple[set[str], dict[str, set[str]]]:
    tree = ast.parse(STUB.read_text())
    functions, classes = set(), {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            functions.add(node.target.id)  # a module constant (MAX_RALLY_BALLS: int)
        elif isinstance(node, ast.ClassDef):
            classes[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
    return functions, classes


def test_every_export_and_method_has_a_stub():
    functions, classes = _stub_names()
    exported = {n for n in dir(_ttmanip) if not n.startswith("_")}
    assert exported == functions | set(classes), "stub and extension export different names"
    for name, methods in classes.items():
        runtime = {n for n in vars(getattr(_ttmanip, name)) if not n.startswith("__")}
        if issubclass(getattr(_ttmanip, name), BaseException):
            continue
        assert runtime == methods - {"__init__", "__len__", "__bool__"}, f"{name}: stub methods differ"
