"""ARCHITECTURE.md stays true: every module and file it names exists, and the Rust sources have no
import cycle between files."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "ARCHITECTURE.md"
CRATE_DIRS = {"ttkin": "crates/ttkin", "ttcan": "crates/ttcan", "ttkin_py": "crates/ttkin-py"}
PY_PACKAGE = "python/ttmanip"


def _backticked() -> list[str]:
    return re.findall(r"`([^`\s]+)`", PAGE.read_text())


def _module_file(crate_dir: Path, parts: list[str]) -> Path | None:
    """The file of module `parts` (a::b) under crate_dir/src, or None."""
    base = crate_dir / "src"
    for k in range(len(parts), 0, -1):
        # A path may end in an item (a type or function) after the module: try shorter prefixes
        # only when the remainder names no module file.
        stem = base.joinpath(*parts[:k])
        for candidate in (stem.with_suffix(".rs"), stem / "mod.rs"):
            if candidate.is_file():
                return (
                    candidate
                    if k == len(parts)
                    else (candidate if _names_item(candidate, parts[k:]) else None)
                )
    return None


def _names_item(file: Path, rest: list[str]) -> bool:
    """True when `rest` (one name) is an item defined in `file` (pub struct/enum/fn/trait/const/mod)."""
    if len(rest) != 1:
        return False
    name = re.escape(rest[0])
    pattern = rf"pub(\([^)]*\))?\s+(struct|enum|fn|trait|const|type|mod|use)\s+[^;{{]*\b{name}\b"
    return re.search(pattern, file.read_text()) is not None


def _rust_paths() -> list[str]:
    return [p for p in _backticked() if re.fullmatch(r"(ttkin|ttcan|ttkin_py)(::\w+)+", p)]


def _file_paths() -> list[str]:
    return [
        p.rstrip("/")
        for p in _backticked()
        if re.fullmatch(r"(crates|python|tests|benches|scripts|robots|docs)/[\w./*-]+", p) and "*" not in p
    ]


def test_the_page_exists_and_names_modules():
    assert PAGE.is_file()
    assert len(_rust_paths()) >= 30, "the code map should name the modules it describes"


def test_every_rust_module_named_exists():
    missing = []
    for path in _rust_paths():
        crate, *parts = path.split("::")
        if _module_file(ROOT / CRATE_DIRS[crate], parts) is None:
            missing.append(path)
    assert not missing, f"ARCHITECTURE.md names modules that do not exist: {missing}"


def test_every_file_named_exists():
    missing = [p for p in _file_paths() if not (ROOT / p).exists()]
    assert not missing, f"ARCHITECTURE.md names files that do not exist: {missing}"


def test_every_python_module_named_exists():
    missing = []
    for path in _backticked():
        if re.fullmatch(r"ttmanip(\.\w+)+", path):
            parts = path.split(".")[1:]
            stem = ROOT / PY_PACKAGE / Path(*parts)
            files = (stem.with_suffix(".py"), stem.with_suffix(".pyi"), stem / "__init__.py")
            if not any(f.is_file() for f in files):
                # ttmanip.<module>.<name>: the module (or package) must exist and define the name.
                parent = ROOT / PY_PACKAGE / Path(*parts[:-1])
                mod = next(
                    (f for f in (parent.with_suffix(".py"), parent / "__init__.py") if f.is_file()), None
                )
                if mod is None or not re.search(rf"\b{re.escape(parts[-1])}\b", mod.read_text()):
                    missing.append(path)
    assert not missing, f"ARCHITECTURE.md names Python modules that do not exist: {missing}"


def _module_of(src: Path, file: Path) -> tuple[str, ...]:
    rel = file.relative_to(src).with_suffix("")
    parts = rel.parts
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def _imports(src: Path, file: Path, modules: set[tuple[str, ...]]) -> set[tuple[str, ...]]:
    """Modules (of this crate) that `file` uses through `crate::` or `super::`."""
    me = _module_of(src, file)
    is_mod_file = file.name in ("mod.rs", "lib.rs")
    text = re.sub(r"//[^\n]*", "", file.read_text())
    text = text.split("#[cfg(test)]")[0]
    out = set()
    for m in re.finditer(r"\b((?:crate|super)(?:::\w+)+)", text):
        segs = m.group(1).split("::")
        if segs[0] == "crate":
            base: tuple[str, ...] = ()
            rest = segs[1:]
        else:
            base = me if is_mod_file else me[:-1]
            rest = segs[1:]
            while rest and rest[0] == "super":
                base, rest = base[:-1], rest[1:]
        # The longest prefix that is a module of this crate.
        target = None
        for k in range(len(rest), 0, -1):
            if base + tuple(rest[:k]) in modules:
                target = base + tuple(rest[:k])
                break
        if target is None and base in modules:
            target = base
        if (
            target is not None
            and target != me
            and not _is_ancestor(target, me)
            and not _is_ancestor(me, target)
        ):
            out.add(target)
    return out


def _is_ancestor(a: tuple[str, ...], b: tuple[str, ...]) -> bool:
    return len(a) < len(b) and b[: len(a)] == a


def _cycle(graph: dict[tuple[str, ...], set[tuple[str, ...]]]) -> list[tuple[str, ...]] | None:
    state: dict[tuple[str, ...], int] = {}
    stack: list[tuple[str, ...]] = []

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in graph.get(u, ()):
            if state.get(v) == 1:
                return stack[stack.index(v) :] + [v]
            if v not in state:
                found = visit(v)
                if found:
                    return found
        stack.pop()
        state[u] = 2
        return None

    for u in graph:
        if u not in state:
            found = visit(u)
            if found:
                return found
    return None


CRATES = ["ttkin", "ttkin-py", "ttcan"]


@pytest.mark.parametrize("crate", CRATES)
def test_no_import_cycle_between_files(crate):
    """A parent module re-exporting its children is not a cycle (edges to ancestors and
    descendants are ignored); any other loop of `use crate::`/`super::` between files is."""
    src = ROOT / "crates" / crate / "src"
    files = [f for f in src.rglob("*.rs") if "bin" not in f.relative_to(src).parts]
    modules = {_module_of(src, f) for f in files}
    graph = {_module_of(src, f): _imports(src, f, modules) for f in files}
    cycle = _cycle(graph)
    assert cycle is None, f"{crate}: import cycle {' -> '.join('::'.join(m) or 'lib' for m in cycle)}"


def test_the_cycle_finder_finds_a_planted_cycle():
    graph = {("a",): {("b",)}, ("b",): {("c",)}, ("c",): {("a",)}, ("d",): set()}
    assert _cycle(graph) is not None
    assert _cycle({("a",): {("b",)}, ("b",): set()}) is None


# ---------------------------------------------------------------------------------------------
# Invariants (issue 30): each check is a function of its inputs, run on the tree and on a planted
# violation so that it is shown to fail.

RUST_CRATES = {
    "ttkin": "crates/ttkin",
    "ttcan": "crates/ttcan",
    "ttkin_py": "crates/ttkin-py",
    "ttkin_py_guard": "crates/ttkin-py-guard",
}


def _source_modules() -> list[tuple[str, str]]:
    """(module path, file) of every source module: Rust files under crates/*/src and Python files
    of the package. Crate roots, package roots and unit-test files (`tests.rs`) are their parent's."""
    out = []
    for crate, d in RUST_CRATES.items():
        src = ROOT / d / "src"
        for f in sorted(src.rglob("*.rs")):
            rel = f.relative_to(src).with_suffix("").parts
            if rel[-1] in ("lib", "main") or rel[-1] == "tests":
                continue
            if rel[-1] == "mod":
                rel = rel[:-1]
            out.append(("::".join((crate, *rel)), str(f.relative_to(ROOT))))
    for f in sorted((ROOT / PY_PACKAGE).rglob("*.py")):
        rel = f.relative_to(ROOT / "python").with_suffix("").parts
        if rel[-1] == "__init__":
            rel = rel[:-1]
        if len(rel) > 1:
            out.append((".".join(rel), str(f.relative_to(ROOT))))
    return out


def _unnamed(modules: list[tuple[str, str]], page: str) -> list[str]:
    names = set(re.findall(r"`([^`\s]+)`", page))
    return [m for m, f in modules if m not in names and f not in names]


def test_every_source_module_is_named():
    page = PAGE.read_text()
    missing = _unnamed(_source_modules(), page)
    assert not missing, f"modules without their line in ARCHITECTURE.md's code map: {missing}"
    # A module added without its line is found.
    planted = [*_source_modules(), ("ttkin::brand_new", "crates/ttkin/src/brand_new.rs")]
    assert _unnamed(planted, page) == ["ttkin::brand_new"]


FORBIDDEN_IN_TTKIN = {
    # Python
    "pyo3",
    "pyo3-ffi",
    "pyo3-build-config",
    "numpy",
    "pythonize",
    # buses and devices
    "socketcan",
    "embedded-can",
    "neli",
    "nix",
    # the crates above it
    "ttcan",
    "ttkin-py",
}


def _metadata() -> dict:
    import json
    import subprocess

    out = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--manifest-path", str(ROOT / "Cargo.toml")],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def _normal_closure(meta: dict, root_name: str) -> set[str]:
    """Names of the packages `root_name` depends on at build or run time (not dev-dependencies),
    transitively, from `cargo metadata`'s resolve graph."""
    by_id = {p["id"]: p["name"] for p in meta["packages"]}
    nodes = {n["id"]: n for n in meta["resolve"]["nodes"]}
    root = next(i for i, name in by_id.items() if name == root_name and i in nodes)
    seen, todo = set(), [root]
    while todo:
        for dep in nodes[todo.pop()]["deps"]:
            if any(k["kind"] in (None, "build") for k in dep["dep_kinds"]) and dep["pkg"] not in seen:
                seen.add(dep["pkg"])
                todo.append(dep["pkg"])
    return {by_id[i] for i in seen}


def test_ttkin_has_no_bus_no_python_and_no_unsafe():
    meta = _metadata()
    bad = _normal_closure(meta, "ttkin") & FORBIDDEN_IN_TTKIN
    assert not bad, f"ttkin (maths) depends on {sorted(bad)}: a bus, Python or a crate above it"
    assert not (_normal_closure(meta, "ttcan") & {"pyo3", "numpy", "ttkin-py"}), "ttcan knows no Python"
    lib = (ROOT / "crates/ttkin/src/lib.rs").read_text()
    assert "#![forbid(unsafe_code)]" in lib
    # The check finds a planted dependency of ttkin on socketcan.
    ttkin_id = next(p["id"] for p in meta["packages"] if p["name"] == "ttkin")
    sock = {"id": "socketcan-planted", "name": "socketcan"}
    planted = {
        "packages": [*meta["packages"], sock],
        "resolve": {
            "nodes": [
                {**n, "deps": [*n["deps"], {"pkg": sock["id"], "dep_kinds": [{"kind": None}]}]}
                if n["id"] == ttkin_id
                else n
                for n in meta["resolve"]["nodes"]
            ]
            + [{"id": sock["id"], "deps": []}]
        },
    }
    assert "socketcan" in _normal_closure(planted, "ttkin")


def _builtin_names() -> list[str]:
    text = (ROOT / "crates/ttkin/src/robots.rs").read_text()
    m = re.search(r"pub const NAMES: \[&str; \d+\] = \[([^\]]*)\]", text)
    assert m, "ttkin::robots::NAMES lists the built-in robots"
    return re.findall(r'"(\w+)"', m.group(1))


def _name_matches(text: str, names: list[str], rust: bool) -> list[str]:
    """Lines of `text` (comments and Rust unit tests dropped) that decide something by comparing
    with a built-in robot's name: a match arm `"gantry6" =>` or a comparison `== "gantry6"`."""
    if rust:
        text = text.split("#[cfg(test)]")[0]
        text = re.sub(r"//[^\n]*", "", text)
    else:
        text = re.sub(r"#[^\n]*", "", text)
    alt = "|".join(map(re.escape, names))
    lit = rf"[\"']({alt})[\"']"
    pat = rf"{lit}\s*(=>|==|!=|\|)|(==|!=)\s*{lit}|\bin\s*[(\[{{][^)\]}}]*{lit}"
    return [line.strip() for line in text.splitlines() if re.search(pat, line)]


def test_no_robot_name_match_outside_the_robots_room():
    """Robot facts (racket mount, ready pose, analytic IK) are data on the robot or found from its
    structure; only the robots' room (`ttkin::robots`, `ttmanip.robots`) maps names to robots."""
    names = _builtin_names()
    rooms = {ROOT / "crates/ttkin/src/robots.rs", ROOT / PY_PACKAGE / "robots.py"}
    found = []
    for f in [*ROOT.glob("crates/*/src/**/*.rs"), *(ROOT / PY_PACKAGE).rglob("*.py")]:
        if f in rooms or "robots" in f.relative_to(ROOT).parts[:-1]:
            continue
        for line in _name_matches(f.read_text(), names, rust=f.suffix == ".rs"):
            found.append(f"{f.relative_to(ROOT)}: {line}")
    assert not found, "decisions by robot name outside the robots' room:\n" + "\n".join(found)
    # The check finds the pattern it forbids.
    planted = (
        'fn ready(c: &Chain) -> f64 {\n    match c.name() {\n        "gantry6" => 0.6,\n'
        "        _ => 0.0,\n    }\n}"
    )
    assert _name_matches(planted, names, rust=True) == ['"gantry6" => 0.6,']
    assert _name_matches("if robot.name == 'mobile8':\n    pass", names, rust=False)
    assert _name_matches("if name in ('ur5', 'arm4'):", names, rust=False)
    assert not _name_matches('summary["gantry6"] = run(robots.gantry6())  # gantry6 ==', names, rust=False)


# The binding crate converts only (issue 30 item 6): a binding reads its arguments, calls one core
# function and converts the result. Structural check on crates/ttkin-py/src: loops over data
# (`for … in`, `while`, `loop`, iterators, chunks, zips) are allowed only in the conversion helpers,
# and signature defaults are never numeric literals (a default comes from the core's `Default` or
# constant, e.g. `t_max = CROSSING_HORIZON`). The loops still in the bindings are listed below by
# function with their count, a ratchet: a new loop, or one more in a listed function, fails; a loop
# removed must come off the list (so it only shrinks).

BINDING_SRC = ROOT / "crates/ttkin-py/src"
CONVERSION_HELPERS = {"convert.rs", "errors.rs", "interrupt.rs", "pickle.rs", "args.rs", "guard.rs", "lib.rs"}
_LOOP = re.compile(
    r"\bfor\s+[\w(), &]+\s+in\b|\bwhile\b|\bloop\s*\{|\.(?:par_)?iter(?:_mut)?\(\)|\.into_(?:par_)?iter\(\)"
    r"|\.(?:par_)?chunks(?:_exact)?(?:_mut)?\(|\.zip\("
)
_FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?fn\s+(\w+)")
_SIGNATURE = re.compile(r"#\[pyo3\(signature\s*=\s*\((.*?)\)\)\]", re.S)
_NUMERIC_DEFAULT = re.compile(r"\b(\w+)\s*=\s*(-?\d[\w.]*)")

# Known loops left in the bindings (file::function -> count), each a debt of issue 30 item 3:
# none left (moved into the core or into the conversion helpers); an entry may only be removed.
BINDING_LOOP_DEBTS: dict[str, int] = {}

# Known numeric literal defaults left in binding signatures (file -> the `name=value` texts): none.
BINDING_DEFAULT_DEBTS: dict[str, list[str]] = {}


def _code(line: str) -> str:
    """`line` without string contents and comments."""
    return re.sub(r'"(?:[^"\\]|\\.)*"', '""', line).split("//")[0]


def _binding_loops(name: str, text: str) -> dict[str, int]:
    """Loops over data per function (`file::fn` -> count) in binding file `name`; unit tests off."""
    out: dict[str, int] = {}
    fn = "<top>"
    for line in text.splitlines():
        if line.startswith("#[cfg(test)]"):
            break
        m = _FN.match(line)
        if m:
            fn = m.group(1)
        n = len(_LOOP.findall(_code(line)))
        if n:
            key = f"{name}::{fn}"
            out[key] = out.get(key, 0) + n
    return out


def _binding_defaults(text: str) -> list[str]:
    return [f"{a}={b}" for sig in _SIGNATURE.findall(text) for a, b in _NUMERIC_DEFAULT.findall(sig)]


def _binding_files() -> dict[str, str]:
    files = sorted(BINDING_SRC.rglob("*.rs"))
    return {
        f.relative_to(BINDING_SRC).as_posix(): f.read_text()
        for f in files
        if f.relative_to(BINDING_SRC).as_posix() not in CONVERSION_HELPERS
    }


def _binding_violations(files: dict[str, str]) -> list[str]:
    """What the bindings hold beyond the listed debts: loops over data, numeric literal defaults."""
    bad = []
    loops: dict[str, int] = {}
    for name, text in files.items():
        loops.update(_binding_loops(name, text))
        extra = list(_binding_defaults(text))
        for d in BINDING_DEFAULT_DEBTS.get(name, []):
            if d in extra:
                extra.remove(d)
        bad += [f"{name}: literal default {d} (take it from the core)" for d in extra]
    for key, n in sorted(loops.items()):
        if n > BINDING_LOOP_DEBTS.get(key, 0):
            bad.append(f"{key}: {n} loops over data (listed: {BINDING_LOOP_DEBTS.get(key, 0)})")
    return bad


def test_bindings_convert_only():
    files = _binding_files()
    bad = _binding_violations(files)
    assert not bad, "the bindings must convert only (ARCHITECTURE.md, crates/ttkin-py):\n" + "\n".join(bad)
    # The ratchet is tight: every listed debt is still there, at its count.
    loops: dict[str, int] = {}
    for name, text in files.items():
        loops.update(_binding_loops(name, text))
    stale = {k: n for k, n in BINDING_LOOP_DEBTS.items() if loops.get(k, 0) != n}
    assert not stale, f"loops removed: lower or drop their BINDING_LOOP_DEBTS entries {stale}"
    for name, debts in BINDING_DEFAULT_DEBTS.items():
        assert sorted(_binding_defaults(files[name])) == sorted(debts), (
            f"{name}: update BINDING_DEFAULT_DEBTS"
        )


def test_the_binding_check_finds_a_planted_loop_and_default():
    files = _binding_files()
    planted = dict(files)
    planted["ball/mod.rs"] = files["ball/mod.rs"] + (
        "\nfn ball_speeds(py: Python<'_>, states: &[BallState]) -> Vec<f64> {\n"
        "    let mut out = Vec::new();\n"
        "    for s in states {\n"
        "        out.push(s.v.norm());\n"
        "    }\n"
        "    out\n}\n"
    )
    assert _binding_violations(planted) == ["ball/mod.rs::ball_speeds: 1 loops over data (listed: 0)"]
    planted = dict(files)
    planted["traj.rs"] = files["traj.rs"] + '\n#[pyo3(signature = (q, step = 0.001, name = "x"))]\n'
    assert _binding_violations(planted) == ["traj.rs: literal default step=0.001 (take it from the core)"]
