"""The registry of ttmanip's public API for the fuzzer (tests/test_api_fuzz.py).

Every public callable of ``ttmanip`` (functions of the package and its public submodules,
classes, their methods and properties) is found by :func:`public_callables`. The fuzzer calls
each one, drawing every argument from a strategy chosen by the *parameter's name* (``q``, ``T``,
``task``, ``duration``, ...; see ``tests/test_api_fuzz.py``), so a new public name is fuzzed by
default. :data:`API` lists every name once, with what the fuzzer needs beyond that:

- ``shape``: the documented result shape, from the drawn arguments (``n`` = joints of the robot,
  ``N`` = batch size of the first array argument, ``None`` for one item);
- ``may_be_inf``: the result may hold ±inf by definition (e.g. "inf where no limit");
- ``finite_part``: the part of the result that must be finite, when the rest is NaN by definition;
- ``receiver``: for methods, how to make the object (default: by class name, see the fuzzer);
- ``args``: per-parameter strategy names overriding the by-name choice;
- ``type_error``: messages of TypeErrors the call documents for a wrong *set* of arguments;
- ``os_error``: the call writes a file; an unwritable path is an ``OSError`` (Python's file error);
- ``skip_call``: why the entry is not called (a class without a Python constructor);
- ``record``: a plain parameter record (a dataclass checked where it is used, e.g. by ``Servo``),
  which may hold a boolean or complex array without refusing it.

``test_registry_covers_the_public_api`` fails when a public callable is missing here.
"""

from __future__ import annotations

import inspect
import types

import numpy as np
import ttmanip
import ttmanip.ball_fit
import ttmanip.ctl
import ttmanip.files

#: Submodules of ttmanip whose public names are part of the API (``ctl``, ``files`` and
#: ``ball_fit`` since issue 29's leftovers: the controller link and trajectory writer, the file
#: readers, and the ball calibration with its binding).
MODULES = ("ball", "dynamics", "motor", "robots", "traj", "ctl", "files", "ball_fit")


def _batched(*item):
    """Shape `item` ("n" = joints) for one input, (N, *item) for a batch of N."""

    def shape(n, N):
        one = tuple(n if d == "n" else d for d in item)
        return one if N is None else (N, *one)

    return shape


#: name -> options (see the module docstring). Keys are "name" for package functions,
#: "module.name" for submodule functions, "Class" for constructors, "Class.attr" for members.
API: dict[str, dict] = {
    # --- package functions
    "task_line": {},
    "track": {"args": {"task_trajectory": "task_trajectory", "base": "diffdrive_or_none"}},
    "wls_step": {"args": {"base": "diffdrive_or_none"}},
    # --- Robot
    "Robot": {"skip_call": "Robot() has no constructor; the factories below make robots"},
    "Robot.builtin": {"args": {"name": "robot_name"}},
    "Robot.builtin_names": {},
    "Robot.ready": {},
    "Robot.gravity_vector": {},
    "Robot.with_racket": {},
    "Robot.with_ready": {},
    "Robot.from_dh": {},
    "Robot.from_file": {},
    "Robot.from_toml": {},
    "Robot.from_urdf": {},
    "Robot.from_urdf_string": {},
    "Robot.acceleration_limits": {"may_be_inf": True},
    "Robot.velocity_limits": {"may_be_inf": True},
    "Robot.effort_limits": {"may_be_inf": True},
    "Robot.drive_effort_limits": {"may_be_inf": True},
    "Robot.effective_effort_limits": {"may_be_inf": True},
    "Robot.effort_limit_sources": {},
    "Robot.drive_velocity_limits": {"may_be_inf": True},
    "Robot.effective_velocity_limits": {"may_be_inf": True},
    "Robot.velocity_limit_sources": {},
    "Robot.effort_limits_at": {"shape": _batched("n"), "may_be_inf": True},
    "Robot.limits": {"may_be_inf": True},
    "Robot.analytic_ik": {},
    "Robot.armature": {},
    "Robot.base": {},
    "Robot.tool": {},
    "Robot.coriolis": {"shape": _batched("n")},
    "Robot.drives": {},
    "Robot.fk": {"shape": _batched(4, 4)},
    "Robot.fk_all": {"shape": _batched("n", 4, 4)},
    "Robot.jacobian": {"shape": _batched(6, "n")},
    "Robot.mass_matrix": {"shape": _batched("n", "n")},
    "Robot.gravity": {"shape": _batched("n")},
    "Robot.rnea": {"shape": _batched("n")},
    "Robot.inverse_dynamics": {"shape": _batched("n")},
    "Robot.forward_dynamics": {"shape": _batched("n")},
    "Robot.nonlinear_effects": {"shape": _batched("n")},
    "Robot.friction": {"shape": _batched("n")},
    "Robot.kinetic_energy": {},
    "Robot.potential_energy": {},
    "Robot.ik": {},
    # the batch form pads q (N, 4, n) with NaN past each pose's branch count (documented)
    "Robot.ik_all": {
        "args": {"limits": "flag"},
        "finite_part": lambda r: r[0][np.arange(4) < r[1][:, None]] if isinstance(r, tuple) else r,
    },
    "Robot.ik_nearest": {"args": {"limits": "flag"}},
    "Robot.joint_velocity": {"shape": _batched("n")},
    "Robot.joint_names": {},
    "Robot.joint_types": {},
    "Robot.masses": {},
    "Robot.n": {},
    "Robot.dof": {},
    "Robot.name": {},
    "Robot.simulate": {},
    "Robot.racket_angle_jacobian": {},
    "Robot.task_coordinates": {},
    "Robot.task_jacobian": {},
    "Robot.to_toml": {},
    "Robot.to_urdf": {},
    "Robot.torques": {},
    "Robot.with_base": {},
    "Robot.with_tool": {},
    "Robot.with_drives": {},
    "Robot.with_inertials": {},
    # --- hit pipeline (issue 12)
    "Hit": {"args": {"pose": "pose_or_junk", "twist": "array6", "t": "time"}},
    "Hit.from_normal": {},
    "Hit.centre": {},
    "Hit.normal": {},
    "Hit.velocity": {},
    "plan_hit": {"args": {"hit": "hit", "state": "state", "jerk": "jerk_or_none"}},
    "plan_hits": {"args": {"hits": "hits", "state": "state", "jerk": "jerk_or_none"}},
    "simulate": {
        "args": {
            "plan": "hit_plan",
            "setpoint_hz": "rate",
            "setpoint_rate": "rate",  # deprecated name of setpoint_hz
            "rate_hz": "rate",
            "rate": "rate",  # deprecated name of rate_hz
            "noise": "noise",
            "gravity": "flag",
        }
    },
    "HitPlan": {"skip_call": "made by plan_hit only"},
    **{
        f"HitPlan.{a}": {"may_be_inf": a in ("earliest_t_hit",)}
        for a in (
            "branches",
            "duration",
            "earliest_t_hit",
            "effort_ratio",
            "hit_pose",
            "hit_twist",
            "message",
            "ok",
            "peak_effort",
            "profile",
            "q_hit",
            "qd_hit",
            "ready",
            "requested_t_hit",
            "return_duration",
            "sigma_min",
            "start",
            "status",
            "t_hit",
            "tau",
            "tool_target",
            "trajectory",
            "violations",
        )
    },
    "HitPlan.robot_name": {},
    "HitPlan.made_for": {},  # robot drawn from all four: pairs of different robots (issue 29)
    "HitPlan.sample": {"args": {"rate_hz": "rate", "rate": "rate"}},
    "HitPlan.torques": {"args": {"rate_hz": "rate", "rate": "rate"}},
    "SimResult": {"skip_call": "made by simulate only"},
    "SimResult.summary": {},
    "SimResult.t": {},
    # --- drives (issue 10)
    "DriveSim": {
        "args": {"setpoint_hz": "rate", "setpoint_rate": "rate", "noise": "noise", "gravity": "flag"}
    },
    **{
        f"DriveSim.{a}": {}
        for a in (
            "current",
            "current_reference",
            "current_ref",
            "faults",
            "q",
            "qd",
            "t",
            "tick_hz",
            "tick_rate",
        )
    },
    "DriveSim.reset": {},
    "DriveSim.set_setpoint": {},
    "DriveSim.tick": {"args": {"n": "small_count"}},
    "DriveSim.run": {"args": {"t": "short_times"}},
    "motor.theta5_ripple_case": {},
    "motor.actuators": {},
    "motor.drive_line": {"skip_call": "formats an entry of motor.actuators"},
    "motor.theta5_figure": {"args": {"path": "out_path"}, "os_error": True},
    "motor.Loops.observer_bandwidth_hz": {},
    # --- ball rally (issue 13)
    # per-ball arrays hold NaN for balls that were not hit (racket and landing errors undefined)
    "rally": {
        "may_be_inf": True,
        "os_error": True,
        "args": {"n": "tiny_count", "drives": "tiny_count", "out": "out_dir", "chunk": "small_count"},
    },
    # --- design sweeps (issue 31); tests/test_sweep.py runs them (serial and on a LocalCluster)
    "sweep": {"skip_call": "starts a Dask cluster per call; tests/test_sweep.py checks it"},
    # --- ball (issue 13); positions after a flight ends at the net or the floor are NaN (documented)
    "ball.BallModel": {"args": {"name": "ball_model_name"}},
    "ball.BallModel.name": {},
    "ball.Estimate": {"skip_call": "a record made by ball.estimate"},
    **{f"ball.Estimate.{a}": {} for a in ("position", "spin", "velocity")},
    "ball.Table": {},
    **{f"ball.Table.{a}": {} for a in ("height", "length", "net_height", "net_overhang", "width")},
    "ball.Table.on_opponent_half": {},
    "ball.Table.outline": {},
    "ball.crossing": {"may_be_inf": True, "args": {"model": "ball_model_name"}},
    "ball.estimate": {"args": {"model": "ball_model_name"}},
    "ball.plan_return": {"args": {"model": "ball_model_name"}},
    "ball.predict": {"may_be_inf": True, "args": {"model": "ball_model_name"}},
    "ball.predict_batch": {"may_be_inf": True, "args": {"model": "ball_model_name"}},
    "ball.state": {},
    "ball.racket_impact": {"args": {"model": "ball_model_name"}},
    "ball.update": {"args": {"model": "ball_model_name"}},
    "ball.plan_correct": {"args": {"model": "ball_model_name"}},
    # --- IkResult (made by Robot.ik)
    "IkResult": {"skip_call": "made by Robot.ik only"},
    "IkResult.q": {},
    "IkResult.success": {},
    "IkResult.position_error": {},
    "IkResult.orientation_error": {},
    "IkResult.iterations": {},
    "IkResult.restarts": {},
    "IkResult.status": {},
    # --- DiffDrive
    "DiffDrive": {},
    "DiffDrive.body_velocity": {},
    "DiffDrive.integrate": {"shape": lambda n, N: (3,)},
    "DiffDrive.limit_step": {"shape": lambda n, N: (2,)},
    "DiffDrive.saturate": {"shape": lambda n, N: (2,)},
    "DiffDrive.wheel_speeds": {"shape": lambda n, N: (2,)},
    "DiffDrive.max_wheel_acceleration": {"may_be_inf": True},
    "DiffDrive.max_wheel_speed": {"may_be_inf": True},
    "DiffDrive.track": {},
    "DiffDrive.track_width": {},
    "DiffDrive.wheel_radius": {},
    # --- TrackResult (made by track)
    "TrackResult": {"skip_call": "made by track only"},
    **{
        f"TrackResult.{a}": {}
        for a in (
            "error",
            "joint_names",
            "margin",
            "message",
            "ok",
            "orientation_error",
            "position_error",
            "q",
            "qd",
            "qdot",
            "scale",
            "sigma_min",
            "status",
            "time",
            "x",
        )
    },
    # --- dynamics
    "dynamics.TorqueProfile": {"skip_call": "made by Robot.torques only"},
    **{
        f"dynamics.TorqueProfile.{a}": {}
        for a in ("current", "joint", "motor", "peak", "violations", "within_limits")
    },
    "dynamics.gantry6_example": {"args": {"samples": "small_count"}},
    "dynamics.torque_figure": {
        "args": {"path": "out_path_required", "profile": "torque_profile"},
        "os_error": True,
    },
    # --- motor
    "motor.DcMotor": {"record": True},
    "motor.Gearbox": {"record": True},
    "motor.Load": {"record": True},
    "motor.Loops": {},
    "motor.PowerStage": {"record": True},
    "motor.Response": {"skip_call": "made by Servo.step_response only"},
    "motor.Servo": {
        "args": {
            "motor": "dc_motor",
            "gearbox": "gearbox",
            "load": "load",
            "power_stage": "power_stage",
            "drive": "power_stage",  # deprecated name of power_stage
            "loops": "loops",
        }
    },
    "motor.plot": {"args": {"path": "out_path", "response": "response"}, "os_error": True},
    "motor.quintic": {},
    **{
        f"motor.{cls}.{a}": {}
        for cls, attrs in {
            "DcMotor": (
                "back_emf_constant",
                "coulomb_friction",
                "inductance",
                "resistance",
                "rotor_inertia",
                "torque_constant",
                "viscous_friction",
            ),
            "PowerStage": ("bus_voltage", "current_noise", "encoder_counts_per_rev", "max_duty"),
            "Gearbox": ("efficiency", "inertia", "ratio"),
            "Load": ("inertia", "viscous_friction"),
            "Loops": (
                "acceleration_feedforward",
                "anti_windup",
                "continuous_current",
                "current_bandwidth_hz",
                "current_hz",
                "emf_feedforward",
                "emf_filter_hz",
                "following_error_limit",
                "max_speed",
                "overcurrent_trip",
                "peak_current",
                "peak_duration",
                "position_hz",
                "position_ratio",
                "quick_stop_deceleration",
                "speed_hz",
                "speed_output_filter_hz",
                "speed_reference_filter_hz",
                "speed_symmetric_optimum",
                "speed_window",
                "velocity_feedforward",
            ),
            "Response": (),
            "Servo": (
                "follow",
                "follow_quintic",
                "params",
                "rates",
                "step_response",
                "track",
                "track_quintic",
                "tuning",
            ),
        }.items()
        for a in attrs
    },
    "motor.Response.overshoot": {"args": {"target": "time"}},
    "motor.Response.rise_time": {"args": {"target": "time"}, "may_be_inf": True},  # inf: never rises
    # --- robots
    **{f"robots.{f}": {} for f in ("arm4", "gantry6", "mobile8", "mobile8_start", "ur5")},
    "robots.builtin": {"args": {"name": "robot_name"}},
    # --- traj
    # arc's optional arguments come in documented combinations; a missing or mixed one is a
    # TypeError, Python's answer to a wrong set of arguments
    "traj.arc": {"type_error": ("duration is required", "give either")},
    "traj.cubic": {},
    "traj.line": {},
    "traj.minimal_duration": {},
    "traj.quintic": {},
    "traj.quintic_samples": {"args": {"n": "small_count"}},
    "traj.stroke": {"args": {"state": "state"}},
    "traj.via": {},
    "traj.CartesianTrajectory": {"skip_call": "made by traj.line / traj.arc only"},
    "traj.JointTrajectory": {"skip_call": "made by traj.cubic / quintic / via only"},
    "traj.Stroke": {"skip_call": "made by traj.stroke only"},
    **{
        f"traj.CartesianTrajectory.{a}": {}
        for a in ("arc_about", "arc_through", "check_limits", "duration", "line")
    },
    # rate_hz is required; hz, its deprecated name, makes it a keyword with a None default: a
    # missing or doubled rate is Python's TypeError
    **{
        f"traj.{c}.{a}": {"type_error": ("missing required argument", "given twice")}
        for c, a in (
            ("CartesianTrajectory", "sample_rate"),
            ("CartesianTrajectory", "to_joint"),
            ("JointTrajectory", "sample_rate"),
        )
    },
    "traj.CartesianTrajectory.sample": {"args": {"t": "time"}},
    **{
        f"traj.JointTrajectory.{a}": {}
        for a in (
            "check_limits",
            "coefficients",
            "dof",
            "duration",
            "knots",
            "peaks",
            "sample",
            "sample_uniform",
        )
    },
    "traj.JointTrajectory.jerk": {"args": {"t": "time"}},
    "traj.Stroke.feasible": {},
    "traj.Stroke.on_time": {},
    # --- the controller link and trajectory files (issue 19, 29)
    "ctl.Link": {"args": {"address": "address", "bind": "address"}},
    "ctl.Link.hit": {"args": {"hit": "hit", "id": "wire_int", "stroke": "wire_int"}},
    "ctl.Link.observation": {"args": {"id": "wire_int", "camera_time": "time", "position": "vector3"}},
    "ctl.Link.receive": {"args": {"timeout": "timeout"}},
    "ctl.Link.close": {},
    "ctl.write_trajectory": {"args": {"path": "out_csv", "tau_ff": "array_or_none"}, "os_error": True},
    "ctl.write_stroke": {"args": {"path": "out_csv", "rate_hz": "rate"}, "os_error": True},
    # --- the file readers (issue 29): a missing input file is Python's FileNotFoundError
    "files.read_limited": {
        "args": {"f": "binary_file", "what": "label", "limit": "byte_limit"},
        "type_error": ("f: expected a binary file",),
    },
    "files.read_text": {"args": {"path": "text_path", "what": "label"}, "os_error": True},
    "files.json_depth": {"args": {"text": "json_text"}},
    # integers are read as floats, so a 401-digit one is inf, and JSON's NaN is NaN (documented:
    # the caller checks finiteness)
    "files.load_json": {"args": {"text": "json_text_or_bytes", "what": "label"}, "may_be_inf": True},
    # --- the ball calibration on recorded flights (issue 28) and its binding
    "ball_fit.read_flights": {"args": {"path": "flights_path"}, "os_error": True},
    # std is NaN where a parameter is not identified (documented: table friction)
    "ball_fit.fit": {
        "args": {"path": "flights_path", "window": "window", "period": "period"},
        "os_error": True,
        "may_be_inf": True,
    },
}


def _members(prefix: str, cls: type) -> dict[str, object]:
    out = {}
    for a in dir(cls):
        if a.startswith("_"):
            continue
        out[f"{prefix}.{a}"] = inspect.getattr_static(cls, a)
    return out


def public_callables() -> dict[str, object]:
    """Every public callable of ttmanip: registry key -> the object (class, function, member)."""
    found: dict[str, object] = {}
    spaces = [("", ttmanip)] + [(f"{m}.", getattr(ttmanip, m)) for m in MODULES]
    for prefix, mod in spaces:
        for name in getattr(mod, "__all__", [n for n in dir(mod) if not n.startswith("_")]):
            v = getattr(mod, name)
            if isinstance(v, types.ModuleType):
                continue
            if inspect.isclass(v):
                if issubclass(v, BaseException):
                    continue
                found[f"{prefix}{name}"] = v
                found.update(_members(f"{prefix}{name}", v))
            elif callable(v):
                found[f"{prefix}{name}"] = v
    return found


# --- pickle and copy (issue 31)
#: Every public class -> the calls whose results must be equal on an object and on its pickled or
#: copied twin (besides every public property, which tests/test_pickle.py compares anyway).
#: ``test_every_class_has_a_pickle_probe`` fails when a public class is missing here.
_G6_Q = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
PICKLE_PROBES: dict[str, object] = {
    "Robot": lambda r: (
        r.fk(_G6_Q[: r.dof]),
        r.fk_all(_G6_Q[: r.dof]),
        r.jacobian(_G6_Q[: r.dof]),
        r.mass_matrix(_G6_Q[: r.dof]),
        r.rnea(_G6_Q[: r.dof], _G6_Q[: r.dof], _G6_Q[: r.dof]),
        r.ik(r.fk(_G6_Q[: r.dof])).q,
        r.to_toml(),
        r.to_urdf(),
    ),
    "Hit": lambda h: (h.pose, h.twist, h.t),
    "HitPlan": lambda p: (p.sample(500.0), p.torques(500.0), p.earliest_t_hit),
    "SimResult": lambda s: (s.summary(), s.arrays, s.racket_pose),
    "DriveSim": lambda s: (s.tick(40), s.q, s.qd, s.current, s.current_reference, s.t),
    "IkResult": lambda r: (r.q, r.status, bool(r)),
    "DiffDrive": lambda d: (d.wheel_speeds(0.3, 0.2), d.integrate([0.0, 0.0, 0.1], [1.0, 2.0], 0.5)),
    "TrackResult": lambda t: (len(t), t.q, t.qd, t.x, t.joint_names),
    "ball.BallModel": lambda m: ttmanip.ball.predict(
        ttmanip.ball.state([-1.0, 0.0, 0.3], [4.0, 0.0, 1.0], [0.0, 50.0, 0.0]), [0.1, 0.2], model=m
    ),
    "ball.Estimate": lambda e: (e.state, e.covariance, e.bounce_time, e.extra),
    "ball.Table": lambda t: t.on_opponent_half(0.5, 0.1),
    "dynamics.TorqueProfile": lambda p: (p.joint, p.motor, p.current, p.peak, p.violations),
    "motor.DcMotor": lambda m: ttmanip.motor.Servo(motor=m).tuning,
    "motor.PowerStage": lambda d: ttmanip.motor.Servo(power_stage=d).tuning,
    "motor.Gearbox": lambda g: ttmanip.motor.Servo(gearbox=g).tuning,
    "motor.Load": lambda load: ttmanip.motor.Servo(load=load).tuning,
    "motor.Loops": lambda lo: ttmanip.motor.Servo(loops=lo).tuning,
    "motor.Response": lambda r: (r.rise_time("position", 0.01), r.overshoot("position", 0.01)),
    "motor.Servo": lambda s: s.step_response("position", 0.01, 0.02),
    "motor.ServoSim": lambda s: (s.step("velocity", 1.0, 0.01), s.params, s.plant_params),
    "traj.CartesianTrajectory": lambda c: (c.sample(0.2), c.sample_rate(100.0)),
    "traj.JointTrajectory": lambda j: (j.sample(np.linspace(0.0, j.duration, 7)), j.coefficients, j.knots),
    "traj.Stroke": lambda s: (s.trajectory.sample(0.1), s.on_time, s.feasible),
    # a link pickles as its addresses and opens a socket of its own when unpickled
    "ctl.Link": lambda link: (link.address, link.bind),
}


def public_classes() -> dict[str, type]:
    """Every public class of ttmanip, its submodules and the extension ``ttmanip._ttmanip``
    (exceptions apart): registry key -> class. A class of the extension that the package does not
    re-export is keyed by the submodule that uses it (``motor.ServoSim``)."""
    found = {k: v for k, v in public_callables().items() if inspect.isclass(v)}
    known = {id(v) for v in found.values()}
    native = ttmanip._ttmanip
    for name in dir(native):
        v = getattr(native, name)
        if inspect.isclass(v) and not issubclass(v, BaseException) and id(v) not in known:
            homes = [m for m in MODULES if getattr(getattr(ttmanip, m), name, None) is v]
            found[f"{homes[0]}.{name}" if homes else f"_ttmanip.{name}"] = v
    return found


def public_exceptions() -> dict[str, type]:
    """Every public exception class of ttmanip and the extension: name -> class."""
    spaces = [ttmanip, ttmanip._ttmanip] + [getattr(ttmanip, m) for m in MODULES]
    return {
        f"{v.__module__}.{v.__qualname__}": v
        for mod in spaces
        for v in vars(mod).values()
        if inspect.isclass(v)
        and issubclass(v, BaseException)
        and not v.__name__.startswith("_")
        and v.__module__.startswith("ttmanip")
    }
