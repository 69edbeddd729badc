"""The hand-written stubs (_ttmanip.pyi) describe exactly what the extension exports."""

from __future__ import annotations

import ast
import inspect
from collections.abc import Callable
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


# --- return annotations against the runtime (issue 30, scope 3) ---------------------------------
#
# Every function, method and property of the stub is called once on small inputs (the built-in
# robots, a short trajectory, two rally balls) and its result is checked against the stub's return
# annotation: the type, the element types of lists, tuples and dicts, the dtype of arrays. A stub
# entry without a call here fails the test unless it is listed in `_NOT_CALLED` with the reason.

_NOT_CALLED: dict[str, str] = {}


def _conforms(value, ann: ast.expr, names: dict) -> bool:
    """Whether `value` is of the stub annotation `ann` (an AST): unions, None, builtins, the
    extension's classes, `NDArray[dtype]` (by dtype), `list[X]`, `tuple[X, ...]`, `tuple[A, B]`,
    `dict[K, V]` (every element checked), `Any` and `object`. An int conforms to `float` (PEP 484)."""
    import numpy as np

    if isinstance(ann, ast.BinOp) and isinstance(ann.op, ast.BitOr):
        return _conforms(value, ann.left, names) or _conforms(value, ann.right, names)
    if isinstance(ann, ast.Constant) and ann.value is None:
        return value is None
    if isinstance(ann, ast.Name) and ann.id in names:  # a stub alias (`_F = NDArray[np.float64]`)
        return _conforms(value, names[ann.id], names)
    if isinstance(ann, ast.Name):
        simple = {
            "float": lambda v: isinstance(v, float) or (isinstance(v, int) and not isinstance(v, bool)),
            "int": lambda v: isinstance(v, int) and not isinstance(v, bool),
            "bool": lambda v: isinstance(v, bool),
            "str": lambda v: isinstance(v, str),
            "bytes": lambda v: isinstance(v, bytes),
            "Any": lambda v: True,
            "object": lambda v: True,
        }
        if ann.id in simple:
            return simple[ann.id](value)
        cls = getattr(_ttmanip, ann.id, None)
        assert isinstance(cls, type), f"unknown annotation name {ann.id}"
        return isinstance(value, cls)
    if isinstance(ann, ast.Subscript):
        outer = ast.unparse(ann.value)
        args = ann.slice.elts if isinstance(ann.slice, ast.Tuple) else [ann.slice]
        if outer == "NDArray":
            dtypes = {"np.float64": np.float64, "np.int64": np.int64, "np.bool_": np.bool_}
            dtype = dtypes[ast.unparse(args[0])]
            return isinstance(value, np.ndarray) and value.dtype == dtype
        if outer == "list":
            return isinstance(value, list) and all(_conforms(v, args[0], names) for v in value)
        if outer == "dict":
            return isinstance(value, dict) and all(
                _conforms(k, args[0], names) and _conforms(v, args[1], names) for k, v in value.items()
            )
        if outer == "tuple":
            if not isinstance(value, tuple):
                return False
            if len(args) == 2 and isinstance(args[1], ast.Constant) and args[1].value is Ellipsis:
                return all(_conforms(v, args[0], names) for v in value)
            pairs = zip(value, args, strict=False)
            return len(value) == len(args) and all(_conforms(v, a, names) for v, a in pairs)
    raise AssertionError(f"annotation not understood by the check: {ast.unparse(ann)}")


def _stub_aliases() -> dict[str, ast.expr]:
    """Module-level aliases of the stub (`_F = NDArray[np.float64]`)."""
    tree = ast.parse(STUB.read_text())
    return {
        n.targets[0].id: n.value
        for n in tree.body
        if isinstance(n, ast.Assign) and len(n.targets) == 1 and isinstance(n.targets[0], ast.Name)
    }


def _returned(tmp: Path) -> dict[str, Callable[[], object]]:
    """One call of every stub entry (by its path `name` or `Class.name`), on small inputs; files
    go to the folder `tmp`."""
    import numpy as np

    t = _ttmanip
    g6, ur5, arm4, m8 = (t.Robot.builtin(n) for n in ("gantry6", "ur5", "arm4", "mobile8"))
    q6 = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    qu = np.array([0.3, -0.9, 1.1, -0.4, 0.8, 0.2])
    q8 = m8.ready
    pose = ur5.fk(qu)
    dd = t.DiffDrive(0.1, 0.5, 3.0, 6.0)
    quintic = t.traj_quintic(np.zeros(6), q6, 0.5)
    pose6 = g6.fk(q6)
    line = t.CartesianTrajectory.line(pose6, pose6 @ _shifted(0.02), 0.2)
    x0 = m8.task_coordinates(q8)
    xs, xds = t.task_line(x0, x0 + np.array([0.01, 0, 0, 0, 0]), 0.05)
    tracked = t.track(m8, q8, xs, velocities=xds)
    samples = quintic.sample_rate(1000.0)
    fast = t.traj_quintic(np.zeros(6), q6 * 3, 0.1)
    profile = g6.torques(fast.sample_rate(1000.0)[1:])  # over the effort limits: violations listed
    ik = ur5.ik(pose, time_budget=None)
    ik_batch = ur5.ik(np.stack([pose, pose]), time_budget=None)
    hit_pose = g6.fk(g6.ready)
    plan = t.hit_plan(g6, hit_pose, np.array([1.0, 0.0, 0.5, 0, 0, 0]), 0.4)
    late = t.hit_plan(g6, g6.fk(q6), np.array([6.0, 0.0, 3.0, 0, 0, 0]), 0.05, effort=False)
    sim = t.DriveSim(g6)
    servo = t.ServoSim()
    s0 = np.array([0.0, -1.2, 0.0, 1.0, 4.0, 0.1, 0.5, 0.0, 0.0, 0.0])  # t, p, v, w (table at 0.76 m)
    times = np.linspace(0.0, 0.3, 31)
    obs_t = np.linspace(0.0, 0.1, 21)
    obs_p = t.ball_predict(s0, obs_t)["positions"]
    later_t = np.linspace(0.35, 0.45, 11)
    later_p = t.ball_predict(s0, later_t)["positions"]
    observed = t.ball_rally_observations(0)
    t_stroke = np.linspace(0.0, 0.2, 21)
    rally = t.ball_rally(2, paths=1)
    long = np.linspace(0.0, 0.6, 61)
    starts = [s0 + np.r_[0, 0, 0.05 * k, 0, 0, 0, 0, 0, 0, 0] for k in range(4)]
    flights = [t.ball_predict(s, long)["positions"] for s in starts]  # each with a bounce
    wire = t.wire_observation(1, 0.5, np.array([0.1, 0.2, 0.3]), 7, 0.5)
    dh = {"a": [0.0, 0.3], "alpha": [0.0, 0.0], "d": [0.0, 0.0], "theta": [0.0, 0.0]}
    calls = {
        # Robot
        "Robot.from_dh": lambda: t.Robot.from_dh(**dh),
        "Robot.from_file": lambda: t.Robot.from_file(_written(tmp / "ur5.toml", ur5.to_toml())),
        "Robot.from_toml": lambda: t.Robot.from_toml(ur5.to_toml()),
        "Robot.from_urdf": lambda: t.Robot.from_urdf(
            _written(tmp / "ur5.urdf", ur5.to_urdf()), "base_link", "tool"
        ),
        "Robot.from_urdf_string": lambda: t.Robot.from_urdf_string(ur5.to_urdf(), "base_link", "tool"),
        "Robot.builtin": lambda: t.Robot.builtin("arm4"),
        "Robot.builtin_names": t.Robot.builtin_names,
        "Robot.to_urdf": ur5.to_urdf,
        "Robot.to_toml": ur5.to_toml,
        "Robot.with_tool": lambda: ur5.with_tool(np.eye(4)),
        "Robot.with_base": lambda: ur5.with_base(np.eye(4)),
        "Robot.n": lambda: _quiet(lambda: ur5.n),
        "Robot.with_racket": lambda: g6.with_racket(np.eye(4)),
        "Robot.with_ready": lambda: g6.with_ready(g6.ready),
        "Robot.effort_limits_at": lambda: g6.effort_limits_at(np.zeros(6)),
        "Robot.fk": lambda: ur5.fk(qu),
        "Robot.fk_all": lambda: ur5.fk_all(qu),
        "Robot.jacobian": lambda: ur5.jacobian(qu),
        "Robot.task_jacobian": lambda: m8.task_jacobian(q8),
        "Robot.racket_angle_jacobian": lambda: m8.racket_angle_jacobian(q8),
        "Robot.task_coordinates": lambda: m8.task_coordinates(q8),
        "Robot.rnea": lambda: g6.rnea(q6, q6, q6),
        "Robot.inverse_dynamics": lambda: g6.inverse_dynamics(q6, q6, q6),
        "Robot.mass_matrix": lambda: g6.mass_matrix(q6),
        "Robot.gravity": lambda: g6.gravity(q6),
        "Robot.coriolis": lambda: g6.coriolis(q6, q6),
        "Robot.nonlinear_effects": lambda: g6.nonlinear_effects(q6, q6),
        "Robot.forward_dynamics": lambda: g6.forward_dynamics(q6, q6, np.zeros(6)),
        "Robot.friction": lambda: g6.friction(q6),
        "Robot.kinetic_energy": lambda: g6.kinetic_energy(q6, q6),
        "Robot.potential_energy": lambda: g6.potential_energy(q6),
        "Robot.simulate": lambda: g6.simulate(q6, np.zeros(6), np.zeros((3, 6)), 1e-3),
        "Robot.torques": lambda: g6.torques(samples[1:]),
        "Robot.with_inertials": lambda: arm4.with_inertials(
            np.ones(arm4.dof), np.zeros((arm4.dof, 3)), np.tile(np.eye(3) * 1e-2, (arm4.dof, 1, 1))
        ),
        "Robot.with_drives": lambda: arm4.with_drives(np.full(arm4.dof, 10.0)),
        "Robot.ik": lambda: ik,
        "Robot.ik_all": lambda: g6.ik_all(pose6),
        "Robot.ik_nearest": lambda: g6.ik_nearest(pose6, q6),
        "Robot.joint_velocity": lambda: g6.joint_velocity(q6, np.full(6, 0.1)),
        # ServoSim
        "ServoSim.__init__": lambda: None,
        "ServoSim.defaults": t.ServoSim.defaults,
        "ServoSim.step": lambda: servo.step("current", 1.0, 0.002),
        "ServoSim.follow": lambda: servo.follow(np.zeros(3), np.zeros(3), np.zeros(3)),
        # DiffDrive
        "DiffDrive.__init__": lambda: None,
        "DiffDrive.track": lambda: _quiet(lambda: dd.track),
        "DiffDrive.body_velocity": lambda: dd.body_velocity([1.0, 2.0]),
        "DiffDrive.wheel_speeds": lambda: dd.wheel_speeds(0.3, 0.2),
        "DiffDrive.integrate": lambda: dd.integrate([0.0, 0.0, 0.1], [1.0, 2.0], 0.5),
        "DiffDrive.saturate": lambda: dd.saturate([10.0, 20.0]),
        "DiffDrive.limit_step": lambda: dd.limit_step([0.0, 0.0], [1.0, 2.0], 0.01),
        # TrackResult, mobile
        "TrackResult.qdot": lambda: _quiet(lambda: tracked.qdot),
        "TrackResult.__len__": lambda: len(tracked),
        "wls_step": lambda: t.wls_step(m8, q8, np.full(5, 0.01)),
        "task_line": lambda: (xs, xds),
        "track": lambda: tracked,
        # IkResult (a batch: the scalar forms are the union's other half)
        "IkResult.__bool__": lambda: bool(ik),
        # JointTrajectory
        "JointTrajectory.sample": lambda: quintic.sample(0.1),
        "JointTrajectory.jerk": lambda: quintic.jerk(0.1),
        "JointTrajectory.sample_rate": lambda: samples,
        "JointTrajectory.sample_uniform": lambda: quintic.sample_uniform(5),
        "JointTrajectory.peaks": lambda: quintic.peaks(1),
        "JointTrajectory.check_limits": lambda: t.traj_quintic(np.zeros(6), q6 * 10, 0.05).check_limits(g6),
        # CartesianTrajectory
        "CartesianTrajectory.line": lambda: line,
        "CartesianTrajectory.arc_through": lambda: t.CartesianTrajectory.arc_through(
            pose6, (pose6 @ _shifted(0.01))[:3, 3] + [0, 0.01, 0], pose6 @ _shifted(0.02), 0.2
        ),
        "CartesianTrajectory.arc_about": lambda: t.CartesianTrajectory.arc_about(
            pose6, pose6[:3, 3] + [0.05, 0, 0], [0, 0, 1.0], 0.3, 0.2
        ),
        "CartesianTrajectory.sample": lambda: line.sample(0.1),
        "CartesianTrajectory.sample_rate": lambda: line.sample_rate(100.0),
        "CartesianTrajectory.to_joint": lambda: line.to_joint(100.0, q6, g6.ik_nearest),
        "CartesianTrajectory.check_limits": lambda: line.check_limits(g6, g6.ik_nearest, q6),
        "traj_cubic": lambda: t.traj_cubic(np.zeros(2), np.ones(2), 1.0),
        "traj_quintic": lambda: quintic,
        "traj_quintic_samples": lambda: t.traj_quintic_samples(np.zeros(2), np.ones(2), 1.0, n=5),
        "traj_via": lambda: t.traj_via(np.array([[0.0], [1.0], [0.5]]), np.array([0.0, 1.0, 2.0])),
        "traj_minimal_duration": lambda: t.traj_minimal_duration(g6, np.zeros(6), q6),
        "traj_stroke": lambda: t.traj_stroke(
            (np.zeros(1), np.zeros(1), np.zeros(1)),
            (np.ones(1), np.ones(1), np.zeros(1)),
            0.5,
            np.zeros(1),
            np.full(1, 10.0),
            np.full(1, 100.0),
            np.full(1, 5000.0),
        ),
        # DriveSim
        "DriveSim.__init__": lambda: None,
        "DriveSim.reset": lambda: sim.reset(np.zeros(6)),
        "DriveSim.set_setpoint": lambda: sim.set_setpoint(np.zeros(6)),
        "DriveSim.tick": lambda: sim.tick(2),
        "DriveSim.current_ref": lambda: _quiet(lambda: sim.current_ref),
        "DriveSim.run": lambda: sim.run(samples[0][:20], *(s[:20] for s in samples[1:])),
        "drive_theta5_case": t.drive_theta5_case,
        "actuators": lambda: t.actuators(g6),
        "step_metrics": lambda: t.step_metrics(np.linspace(0, 1, 11), np.linspace(0, 1.2, 11), 1.0),
        # hits
        "HitPlan.made_for": lambda: plan.made_for(g6),
        "HitPlan.sample": lambda: plan.sample(500.0),
        "HitPlan.torques": lambda: plan.torques(500.0),
        "HitPlan.tau": lambda: plan.tau,  # a plan without a stroke (`late`) raises here
        "hit_plan": lambda: plan,
        "hit_plan_batch": lambda: t.hit_plan_batch(
            g6, np.stack([hit_pose, hit_pose]), np.tile([1.0, 0.0, 0.5, 0, 0, 0], (2, 1)), [0.4, 0.5]
        ),
        "hit_batch_check": lambda: t.hit_batch_check(g6, 2),
        "racket_frame": lambda: t.racket_frame(np.array([1.0, 0.0, 0.0])),
        "racket_mount": lambda: t.racket_mount(m8),
        "racket_states": lambda: t.racket_states(g6, np.stack([q6, q6]), np.zeros((2, 6))),
        "hit_check": lambda: t.hit_check(hit_pose, np.zeros(6), 0.3),
        "real_array": lambda: t.real_array([1, 2], "x"),
        "MAX_RALLY_BALLS": lambda: t.MAX_RALLY_BALLS,
        "BOUNCE_SPREAD": lambda: t.BOUNCE_SPREAD,
        "EARTH_GRAVITY": lambda: t.EARTH_GRAVITY,
        # ball
        "ball_table": t.ball_table,
        "ball_camera": t.ball_camera,
        "ball_rally_config": t.ball_rally_config,
        "hit_stroke_profiles": t.hit_stroke_profiles,
        "ball_table_check": lambda: t.ball_table_check(t.ball_table()),
        "ball_on_opponent_half": lambda: t.ball_on_opponent_half(t.ball_table(), 0.9, 0.1),
        "ball_table_outline": lambda: t.ball_table_outline(t.ball_table()),
        "ball_placement": t.ball_placement,
        "ball_placement_for": lambda: _Each(t.ball_placement_for(r) for r in (g6, ur5)),
        "ball_rally_observations": lambda: observed,
        "ball_rally_score": lambda: t.ball_rally_score(
            0, 0.1, t_stroke, np.tile(g6.ready, (21, 1)), np.zeros((21, 6))
        ),
        "ball_estimate": lambda: t.ball_estimate(obs_t, obs_p),
        "ball_predict": lambda: t.ball_predict(s0, times),
        "ball_predict_batch": lambda: t.ball_predict_batch(np.stack([s0, s0]), times),
        "ball_crossing": lambda: t.ball_crossing(s0, np.array([-0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])),
        "ball_plan_return": lambda: t.ball_plan_return(g6, observed["incoming"], 0.1, observed["target"]),
        "ball_fit": lambda: t.ball_fit([f"f{k}" for k in range(4)], flights, period=0.01),
        "ball_racket_impact": lambda: t.ball_racket_impact(s0, np.array([0.0, -1.0, 0.0]), np.zeros(3)),
        "ball_plan_correct": lambda: t.ball_plan_correct(
            g6, observed["incoming"], 0.1, observed["target"], observed["incoming"], 0.2, False
        ),
        "ball_update": lambda: t.ball_update(obs_t, obs_p, later_t, later_p),
        "ball_rally": lambda: rally,
        "ball_rally_stats": lambda: t.ball_rally_stats(
            [True, False],
            [True, False],
            ["in_reach", "no_bounce"],
            ["ok", "out_of_reach"],
            *(np.array([1.0, np.nan]) for _ in range(6)),
        ),
        # wire
        "WIRE_VERSION": lambda: t.WIRE_VERSION,
        "WIRE_MAX_LEN": lambda: t.WIRE_MAX_LEN,
        "wire_hit": lambda: t.wire_hit(1, 2, 0.3, np.eye(4), np.zeros(6), 7, 0.1),
        "wire_observation": lambda: wire,
        "wire_decode": lambda: t.wire_decode(wire),
    }
    # Properties and argument-free methods: read on one instance of each class.
    instances = {
        "Robot": (ur5, g6, m8), "ServoSim": (servo,), "DiffDrive": (dd,), "TrackResult": (tracked,),
        "TorqueProfile": (profile, g6.torques(samples[1:])), "IkResult": (ik, ik_batch),
        "JointTrajectory": (quintic,), "CartesianTrajectory": (line,), "DriveSim": (sim,),
        "HitPlan": (plan, late),
    }  # fmt: skip
    for path, f in _stub_signatures().items():
        cls, _, attr = path.rpartition(".")
        if path in calls or cls not in instances or not _is_property(f):
            continue
        calls[path] = lambda objs=instances[cls], attr=attr: _Each(getattr(o, attr) for o in objs)
    return calls


class _Each(tuple):
    """Values of one stub entry on several instances (a scalar and a batch, with and without
    violations, ...): each must be of the annotation."""


def _written(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _shifted(dz: float):
    import numpy as np

    m = np.eye(4)
    m[2, 3] = dz
    return m


def _quiet(f):
    """A deprecated name's value, its DeprecationWarning expected and swallowed."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return f()


def _is_property(f: ast.FunctionDef) -> bool:
    return any(isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list)


def _return_mismatches(
    stub: dict[str, ast.FunctionDef], returned: dict[str, Callable[[], object]]
) -> list[str]:
    """Where a returned value is not of its stub entry's return annotation, or an entry has no call."""
    aliases = _stub_aliases()
    bad = []
    for path, f in sorted(stub.items()):
        if path in _NOT_CALLED or f.name in ("__init__",) or f.returns is None:
            continue
        if path not in returned:
            bad.append(f"{path}: no call in _returned() (add one, or list it in _NOT_CALLED with why)")
            continue
        value = returned[path]()
        values = value if isinstance(value, _Each) else (value,)
        shapes = _doc_shapes(ast.get_docstring(f) or "")
        for v in values:
            if not _conforms(v, f.returns, aliases):
                shown = type(v).__name__ + (f"[{v.dtype}]" if hasattr(v, "dtype") else "")
                bad.append(f"{path}: returned {shown} {_preview(v)}, stub says {ast.unparse(f.returns)}")
            elif shapes and hasattr(v, "shape") and not any(_fits(v.shape, s) for s in shapes):
                shown = ", ".join(f"({', '.join(s)}{',' if len(s) == 1 else ''})" for s in shapes)
                bad.append(f"{path}: returned an array of shape {v.shape}, its docstring says {shown}")
    return bad


# Words that stand for an array dimension in the stub's docstrings ("(N, n)", "(K, dof)").
_DIMS = {"N", "n", "K", "M", "k", "m", "dof", "segments"}


def _doc_shapes(doc: str) -> list[tuple[str, ...]]:
    """The array shapes a docstring names: "(n,)", "(N, 4, 4)", "4×4"; units such as "(m, rad)"
    are not shapes (a shape's words are dimensions or numbers)."""
    import re

    out = []
    for m in re.finditer(r"\(([^()]*)\)", doc):
        body = m.group(1).strip()
        parts = [p.strip() for p in body.split(",")]
        if parts and parts[-1] == "" and len(parts) == 2:  # "(n,)"
            parts = parts[:1]
        elif len(parts) < 2:
            continue
        if all(p.isdigit() or p in _DIMS for p in parts):
            out.append(tuple(parts))
    out += [(a, b) for a, b in re.findall(r"(\d)×(\d)", doc)]
    return out


def _fits(shape: tuple[int, ...], doc: tuple[str, ...]) -> bool:
    """Whether an array shape is of a docstring's shape: same rank, numbers equal."""
    same = zip(shape, doc, strict=False)
    return len(shape) == len(doc) and all(not d.isdigit() or int(d) == s for s, d in same)


def _preview(v) -> str:
    text = repr(v)
    return text if len(text) <= 120 else text[:117] + "..."


def _stub_entries() -> dict[str, ast.FunctionDef]:
    """Every function and method of the stub, and each module constant as an argument-free entry."""
    out = _stub_signatures()
    for node in ast.parse(STUB.read_text()).body:
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            f = ast.parse(f"def {node.target.id}() -> {ast.unparse(node.annotation)}: ...").body[0]
            out[node.target.id] = f
    return out


def test_stub_return_types_match_the_runtime(tmp_path):
    stub = _stub_entries()
    returned = _returned(tmp_path)
    called = [p for p in stub if p in returned]
    assert len(called) >= 200, f"only {len(called)} stub entries called"
    bad = _return_mismatches(stub, returned)
    assert not bad, "stub return annotations differ from what the runtime returns:\n" + "\n".join(bad)
    # Planted stale entries are found: a violation list declared as tuples (it is dicts), a dict
    # of the wrong value type, a list of the wrong class, and an array of the wrong documented shape.
    planted = ast.parse(
        "class JointTrajectory:\n"
        "    def check_limits(self) -> list[tuple[int, int, float, float]]: ...\n"
        "class HitPlan:\n"
        "    @property\n"
        "    def hit_pose(self) -> _F:\n"
        "        '(6,) requested racket-centre twist.'\n"
        "def ball_table() -> dict[str, str]: ...\n"
        "def hit_plan_batch() -> list[Robot]: ...\n"
    )
    entries = {
        "JointTrajectory.check_limits": planted.body[0].body[0],
        "HitPlan.hit_pose": planted.body[1].body[0],
        "ball_table": planted.body[2],
        "hit_plan_batch": planted.body[3],
    }
    found = _return_mismatches(entries, returned)
    assert sorted({b.split(":")[0] for b in found}) == sorted(entries), found
