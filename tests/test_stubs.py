"""The hand-written stubs (_ttmanip.pyi) describe exactly what the extension exports."""

from __future__ import annotations

import ast
import inspect
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


def _stub_signatures() -> dict[str, ast.FunctionDef]:
    """Every function of the stub by its runtime path (`name` or `Class.name`)."""
    tree = ast.parse(STUB.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = node
        elif isinstance(node, ast.ClassDef):
            for f in node.body:
                if isinstance(f, ast.FunctionDef):
                    out[f"{node.name}.{f.name}"] = f
    return out


_UNKNOWN = object()


def _stub_params(f: ast.FunctionDef) -> list[tuple[str, str, object]]:
    """(name, kind, default) of a stub function's parameters; default `_UNKNOWN` when it is not a
    literal, None's own `None` when absent is marked by kind."""
    a = f.args
    out = []
    positional = [*a.posonlyargs, *a.args]
    defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
    for p, d in zip(positional, defaults, strict=True):
        out.append((p.arg, "positional", _literal(d)))
    if a.vararg:
        out.append((a.vararg.arg, "*", inspect.Parameter.empty))
    for p, d in zip(a.kwonlyargs, a.kw_defaults, strict=True):
        out.append((p.arg, "keyword", _literal(d)))
    if a.kwarg:
        out.append((a.kwarg.arg, "**", inspect.Parameter.empty))
    return out


def _literal(node: ast.expr | None) -> object:
    if node is None:
        return inspect.Parameter.empty
    try:
        return ast.literal_eval(node)
    except ValueError:
        return _UNKNOWN


def _runtime_params(obj) -> list[tuple[str, str, object]] | None:
    try:
        sig = inspect.signature(obj)
    except (ValueError, TypeError):
        return None
    kinds = {
        inspect.Parameter.POSITIONAL_ONLY: "positional",
        inspect.Parameter.POSITIONAL_OR_KEYWORD: "positional",
        inspect.Parameter.KEYWORD_ONLY: "keyword",
        inspect.Parameter.VAR_POSITIONAL: "*",
        inspect.Parameter.VAR_KEYWORD: "**",
    }
    return [(p.name, kinds[p.kind], p.default) for p in sig.parameters.values()]


def _signature_mismatches(stub: dict[str, ast.FunctionDef], runtime_of) -> list[str]:
    """Where the stub's parameters (names, kinds, presence of a default, literal defaults) differ
    from the runtime's. A runtime default shown as `...` comes from the core (a `Default` or a
    constant, not visible from Python): the stub must give one, any value."""
    bad = []
    for path, f in sorted(stub.items()):
        rt = runtime_of(path)
        if rt is None:
            continue
        st = [p for p in _stub_params(f) if p[0] != "self" and p[0] != "cls"]
        rt = [p for p in rt if p[0] not in ("self", "cls")]
        if [(n, k) for n, k, _ in st] != [(n, k) for n, k, _ in rt]:
            bad.append(
                f"{path}: parameters {[(n, k) for n, k, _ in st]} != runtime {[(n, k) for n, k, _ in rt]}"
            )
            continue
        for (n, _, sd), (_, _, rd) in zip(st, rt, strict=True):
            if (sd is inspect.Parameter.empty) != (rd is inspect.Parameter.empty):
                bad.append(f"{path}({n}): default in one and not the other")
            elif rd is not inspect.Parameter.empty and rd is not Ellipsis and sd is not _UNKNOWN and sd != rd:
                bad.append(f"{path}({n}): stub default {sd!r} != runtime {rd!r}")
    return bad


def _runtime_of(path: str):
    obj = _ttmanip
    for part in path.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    if path.split(".")[-1].startswith("__") and path.split(".")[-1] != "__init__":
        return None
    if path.endswith(".__init__"):
        obj = getattr(_ttmanip, path.split(".")[0])
    return _runtime_params(obj)


def test_stub_signatures_match_the_runtime():
    stub = _stub_signatures()
    checked = [p for p in stub if _runtime_of(p) is not None]
    assert len(checked) >= 100, f"only {len(checked)} signatures readable at run time"
    bad = _signature_mismatches(stub, _runtime_of)
    assert not bad, "stub and runtime signatures differ:\n" + "\n".join(bad)
    # A planted stub with a renamed parameter and a wrong default is found.
    planted = ast.parse(
        "def ball_predict(state, times, model='other'): ...\ndef ball_estimate(t, q, model='default'): ..."
    )
    found = _signature_mismatches({f.name: f for f in planted.body}, _runtime_of)
    assert any("ball_predict(model)" in b for b in found) and any(
        b.startswith("ball_estimate:") for b in found
    ), found
