"""The API fuzzer (issue 14): random calls to every public callable of ttmanip.

Each example picks a registry entry (tests/api_registry.py), makes the receiver for a method,
and draws every argument from a strategy chosen by the parameter's name: arrays of random shape
(mostly the shapes the call accepts), dtype (float64/32/16, int, uint), byte order, alignment
(buffers at an odd offset), strides, Fortran order, read-only, or a list; values finite, huge
(1e160–1e308), magnitudes across the whole double range (10^k, k in −308..308), subnormals,
absolute times far from zero (1e9–1e17 s), NaN, ±inf, empty; boolean and complex arrays (which
must be refused); integers huge (2^64, 10^30) and negative; robots and objects (a plan, a robot)
drawn independently, so that pairs from different robots meet. The call must either

- return a result whose floating arrays are float64, of the documented shape (``shape`` in the
  registry), and finite whenever every input was finite (unless ``may_be_inf``); or
- raise a ``ttmanip.TtmanipError`` subclass. Anything else (another exception, PyO3's
  ``PanicException`` — a ``BaseException`` — or a silent NaN) fails the test.

A call that hangs ends the run: ``faulthandler`` dumps the stacks and exits after
``TTMANIP_FUZZ_CALL_SECONDS`` (120 s) of one call, so a hang is a failure, not a stuck CI job.

CI (``CI=true``) runs a fixed, derandomized set of examples (``ci`` profile in conftest.py);
``TTMANIP_FUZZ_EXAMPLES=10000`` runs a long local campaign.
"""

from __future__ import annotations

import faulthandler
import functools
import inspect
import math
import os
import tempfile

import numpy as np
import pytest
import ttmanip
from api_registry import API, public_callables
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

EXAMPLES = int(os.environ.get("TTMANIP_FUZZ_EXAMPLES", "600"))
ROBOT_NAMES = ("mobile8", "gantry6", "arm4", "ur5")
TMP = tempfile.mkdtemp(prefix="ttmanip-fuzz-")

# ---------------------------------------------------------------- values and array layouts

SPECIAL = [
    np.nan,
    np.inf,
    -np.inf,
    1e300,
    -1e300,
    1e160,
    -1e200,
    1e-300,
    0.0,
    -0.0,
    1.7976931348623157e308,  # the largest double
    -1e308,
    5e-324,  # the smallest subnormal
    -2.5e-320,
    2.2250738585072014e-308,  # the smallest normal
    1e9,  # absolute times: Unix epoch ...
    1.7e9,
    1e15,  # ... and times where a millisecond step is lost in rounding
    1e17,
]
CALL_SECONDS = float(os.environ.get("TTMANIP_FUZZ_CALL_SECONDS", "120"))
finite_special = [v for v in SPECIAL if math.isfinite(v)]


class Draw:
    """Draws arguments and remembers whether every drawn number was finite."""

    def __init__(self, data):
        self.data = data
        self.finite = True
        self.loose = False  # a value of possibly the wrong Python type was drawn
        self.refuse = False  # a boolean or complex array was drawn: the call must refuse it

    def __call__(self, strategy):
        return self.data.draw(strategy)

    def value(self) -> float:
        """A float: mostly ordinary, sometimes huge, tiny, NaN or infinite."""
        kind = self(st.integers(0, 10))
        if kind < 6:
            v = self(st.floats(-3.0, 3.0, allow_nan=False))
        elif kind < 8:
            v = self(st.sampled_from(finite_special))
        elif kind < 9:  # a magnitude anywhere in the double range
            v = self(st.sampled_from([1.0, -1.0])) * 10.0 ** self(st.integers(-308, 308))
        else:
            v = self(st.sampled_from(SPECIAL))
        self.finite &= math.isfinite(v)
        return v

    def values(self, shape) -> np.ndarray:
        size = int(np.prod(shape)) if shape else 1
        mode = self(st.integers(0, 9))
        if mode < 6:  # ordinary values, the call goes deep
            a = self(st.lists(st.floats(-1.5, 1.5, allow_nan=False), min_size=size, max_size=size))
        else:  # a few special values planted
            a = [self(st.floats(-1.5, 1.5, allow_nan=False)) for _ in range(min(size, 3))] + [0.5] * max(
                0, size - 3
            )
            for _ in range(self(st.integers(1, 3)) if size else 0):
                a[self(st.integers(0, size - 1))] = self(st.sampled_from(SPECIAL))
        arr = np.array(a, dtype=float).reshape(shape)
        self.finite &= bool(np.isfinite(arr).all())
        return arr

    def layout(self, a: np.ndarray):
        """The same values handed over in a random memory layout, dtype or container."""
        how = self(
            st.sampled_from(
                [
                    "plain",
                    "plain",
                    "unaligned",
                    "swapped",
                    "strided",
                    "fortran",
                    "readonly",
                    "float32",
                    "int",
                    "list",
                    "bool",
                    "complex",
                ]
            )
        )
        if how in ("bool", "complex"):
            # docs/boundary.md: arrays of them are refused, never cast (a 0-d one becomes a numpy
            # scalar, which converts to a float as Python's bool does)
            self.refuse |= np.ndim(a) > 0
            return np.asarray(a) > 0.0 if how == "bool" else np.asarray(a).astype(complex)
        if how == "unaligned":
            buf = bytearray(a.nbytes + 1)
            u = np.ndarray(a.shape, np.float64, buf, offset=1)
            u[...] = a
            return u
        if how == "swapped":
            return a.astype(a.dtype.newbyteorder(">" if a.dtype.byteorder != ">" else "<"))
        if how == "strided":
            big = np.repeat(a[..., None], 2, axis=-1) if a.ndim else a
            return big[..., 0] if a.ndim else big
        if how == "fortran":
            return np.asfortranarray(a)
        if how == "readonly":
            b = a.copy()
            b.flags.writeable = False
            return b
        if how == "float32":
            with np.errstate(over="ignore"):
                b = a.astype(np.float32)
            self.finite &= bool(np.isfinite(b).all())
            return b
        if how == "int":
            b = np.clip(np.nan_to_num(a), -5, 5).astype(np.int64)
            return b
        if how == "list":
            return a.tolist()
        return a

    def array(self, shapes) -> object:
        """An array of one of `shapes` (or a random shape), in a random layout."""
        if self(st.integers(0, 9)) < 8 and shapes:
            shape = self(st.sampled_from(shapes))
        else:
            shape = tuple(self(st.lists(st.integers(0, 7), max_size=3)))
        return self.layout(self.values(shape))


# ---------------------------------------------------------------- receivers and fixtures


@functools.cache
def robot(name: str) -> ttmanip.Robot:
    return ttmanip.Robot.builtin(name)


def pose_of(d: Draw, r: ttmanip.Robot):
    """A reachable pose of `r` (FK of a configuration within limits), in a random layout."""
    lim = np.clip(r.limits, -3.0, 3.0)
    u = np.array(d(st.lists(st.floats(0.0, 1.0), min_size=r.dof, max_size=r.dof)))
    return r.fk(lim[:, 0] + (lim[:, 1] - lim[:, 0]) * u)


def poses(d: Draw, r: ttmanip.Robot):
    kind = d(st.integers(0, 9))
    if kind < 5:
        return d.layout(pose_of(d, r))
    if kind < 7:
        count = d(st.integers(0, 3))
        return d.layout(np.array([pose_of(d, r) for _ in range(count)]).reshape(count, 4, 4))
    return d.array([(4, 4), (2, 4, 4), (0, 4, 4)])


@functools.cache
def _demo_estimate():
    t = np.linspace(0.0, 0.2, 21)
    p = np.column_stack([-1.0 - 4.0 * t, 0.1 * t, 0.3 + 1.0 * t - 4.905 * t**2])
    return ttmanip.ball.estimate(t, p)


@functools.cache
def _demo_plan():
    return ttmanip.plan_hit(robot("gantry6"), ttmanip.DEMO_HIT)


@functools.cache
def _demo_sim():
    return ttmanip.simulate(robot("gantry6"), _demo_plan())


def sample_objects() -> dict[str, object]:
    """One object of each public class that the API makes (receivers of methods)."""
    m8, g6 = robot("mobile8"), robot("gantry6")
    q0 = ttmanip.robots.mobile8_start()
    x0 = m8.task_coordinates(q0)
    x, xd = ttmanip.task_line(x0, x0 + 0.01, 0.05, rate_hz=200.0)
    tr = ttmanip.track(m8, q0, x, rate_hz=200.0, velocities=xd)
    n = g6.dof
    qg = np.full(n, 0.1)
    prof = g6.torques(np.zeros((3, n)), np.zeros((3, n)), np.zeros((3, n)))
    servo = ttmanip.motor.Servo()
    return {
        "IkResult": g6.ik(g6.fk(qg)),
        "DiffDrive": ttmanip.DiffDrive(0.1, 0.5, 2.0, 5.0),
        "TrackResult": tr,
        "dynamics.TorqueProfile": prof,
        "motor.DcMotor": ttmanip.motor.DcMotor(),
        "motor.PowerStage": ttmanip.motor.PowerStage(),
        "motor.Gearbox": ttmanip.motor.Gearbox(),
        "motor.Load": ttmanip.motor.Load(),
        "motor.Loops": ttmanip.motor.Loops(),
        "motor.Servo": servo,
        "motor.Response": servo.step_response("position", 0.01, 0.05),
        "traj.JointTrajectory": ttmanip.traj.cubic(np.zeros(n), qg, 0.5),
        "traj.CartesianTrajectory": ttmanip.traj.line(g6.fk(np.zeros(n)), g6.fk(qg), 0.5),
        "DriveSim": ttmanip.DriveSim(g6),
        "Hit": ttmanip.DEMO_HIT,
        "ball.BallModel": ttmanip.ball.BallModel(),
        "ball.Table": ttmanip.ball.Table(),
        "ball.Estimate": _demo_estimate(),
        "HitPlan": _demo_plan(),
        "SimResult": _demo_sim(),
        "ctl.Link": _link(),
        "traj.Stroke": ttmanip.traj.stroke(
            None, (qg, np.zeros(n), np.zeros(n)), qg + 0.1, np.zeros(n), 0.6, qg
        ),
    }


# ---------------------------------------------------------------- arguments by parameter name

CHOICES = {
    "task": ["pose", "racket5", "position", "rpy", ""],
    "frame": ["base", "tool", "world", "nope"],
    "method": ["auto", "numeric", "analytic", "lm"],
    "convention": ["standard", "modified", "craig", "x"],
    "kind": ["cubic", "quintic", "linear", "trapezoid", "bogus", "current", "velocity", "position"],
    "law": ["quintic", "cubic", "trapezoid", "linear", "bogus"],
    "weights": ["chan-dubey", "none", "identity", "bogus"],
    "types": ["R", "P", "RRRRRR", "PRRRRRRR", "PPRRRR", "RRRR", "X"],
    "robot_name": list(ROBOT_NAMES) + ["r2d2", ""],
    "name": ["robot", "", "x" * 300],
    "title": [None, "", "a title"],
    "signal": ["position", "velocity", "current", "time", "nope"],
}
INTS = {"max_iterations", "max_restarts", "seed", "samples", "n", "steps", "count"}
BOOLS = {"info", "raise_on_failure", "respect_limits", "corrector", "friction", "gravity_on", "strict"}
POSE_NAMES = {"T", "T0", "T1", "base", "tool", "mount", "target", "pose"}
ARRAY_NAMES = set(
    "q qd qdd q0 q1 q_hit qd_hit qdd_hit ready twist xdot x0 x1 gravity wheel_speeds hint t times points "
    "velocities accelerations v0 v1 a0 a1 v_start v_end mass com inertia gear_ratio rotor_inertia viscous "
    "coulomb torque_constant limits a alpha d theta velocity acceleration jerk qdot_prev qd_prev centre axis "
    "via tau torques input_weights".split()
)
FLOAT_NAMES = set(
    "duration rate_hz hz dt damping epsilon lambda_max threshold max_damping time_budget position_tolerance "
    "orientation_tolerance gain limit_gain manipulability_gain max_error t_hit return_duration v omega "
    "angle blend distance start wheel_radius track track_width max_wheel_speed max_wheel_acceleration "
    "racket_offset amplitude settle external_torque".split()
)
PATH_NAMES = {"path", "file"}
#: Python ints beyond every scalar type of the bindings (float64, i128, u64) and negative ones:
#: each must be refused with a TtmanipError naming the argument, never PyO3's OverflowError.
HUGE_INTS = [10**400, -(10**400), 2**1024, 2**128, -(2**127) - 1, -(2**64), -1]


def small_count(d: Draw, _ctx):
    return d(st.integers(-2, 50))


def out_path(d: Draw, _ctx):
    return d(st.sampled_from([None, os.path.join(TMP, "out.png"), "/nonexistent-dir/out.png"]))


def out_path_required(d: Draw, _ctx):
    return d(st.sampled_from([os.path.join(TMP, "out.png"), "/nonexistent-dir/out.png"]))


def task_trajectory(d: Draw, ctx):
    """(N, dim) task samples: a short line near the start pose of mobile8 or random values."""
    if d(st.booleans()):
        x0 = robot("mobile8").task_coordinates(ttmanip.robots.mobile8_start())
        x, _ = ttmanip.task_line(x0, x0 + d(st.floats(-0.05, 0.05)), 0.02, rate_hz=200.0)
        return d.layout(x)
    n = d(st.sampled_from([0, 1, 3]))
    return d.array([(n, 5), (n, 6), (n, 3)])


def torque_profile(d: Draw, _ctx):
    return sample_objects()["dynamics.TorqueProfile"]


def flag(d: Draw, _ctx):
    return d(st.booleans())


def diffdrive_or_none(d: Draw, _ctx):
    return d(st.sampled_from([None, sample_objects()["DiffDrive"]]))


def sample_of(name):
    """The sample object `name` (or None): parameters that take one of ttmanip's objects."""
    return lambda d, _ctx: d(st.sampled_from([None, sample_objects()[name]]))


def state(d: Draw, ctx):
    """A joint state: q, (q, qd) or (q, qd, qdd), or random."""
    k = d(st.integers(0, 3))
    if k == 0:
        return d.array([(ctx["n"],)])
    return tuple(d.array([(ctx["n"],)]) for _ in range(k))


def tiny_count(d: Draw, _ctx):
    return d(st.integers(-1, 3))


def rate(d: Draw, _ctx):
    return d(
        st.one_of(
            st.sampled_from([1000.0, 250.0, 0.0, -1.0, float("nan"), float("inf"), 1e-300]),
            st.floats(1.0, 5e3),
        )
    )


def noise(d: Draw, _ctx):
    return d(st.sampled_from([None, 0.0, 0.005, -1.0, float("nan"), float("inf")]))


def short_times(d: Draw, ctx):
    """Reference sample times: a short increasing grid, or random arrays (huge or non-finite)."""
    if d(st.booleans()):
        return np.linspace(0.0, d(st.floats(0.001, 0.05)), 3)
    return d.array([(3,), (0,), (2, 2)])


def out_dir(d: Draw, _ctx):
    return d(st.sampled_from([None, "/nonexistent-dir/rally"]))


def hit(d: Draw, ctx):
    return d(st.sampled_from([ttmanip.DEMO_HIT, None, 1.0]))


def hits(d: Draw, ctx):
    return d(st.sampled_from([[ttmanip.DEMO_HIT] * 2, [], [None], ttmanip.DEMO_HIT]))


def hit_plan(d: Draw, ctx):
    return d(st.sampled_from([_demo_plan(), None]))


def jerk_or_none(d: Draw, ctx):
    return None if d(st.booleans()) else d.array([(ctx["n"],), (3,)])


def array6(d: Draw, ctx):
    return d.array([(6,), (3,), (2, 6)])


def pose_or_junk(d: Draw, ctx):
    return poses(d, ctx["robot"]) if d(st.booleans()) else d.array([(4, 4), (3, 3)])


# -- the controller link, trajectory files, file readers and ball calibration (issue 29)


@functools.cache
def _link():
    return ttmanip.ctl.Link(("127.0.0.1", 9))  # the discard port: nothing answers


def address(d: Draw, _ctx):
    return d(
        st.sampled_from(
            [
                ("127.0.0.1", 9),
                ("", 0),
                ("127.0.0.1", 0),
                ("localhost", 65536),
                ("127.0.0.1", -1),
                ("127.0.0.1", 10**400),
                ("127.0.0.1", 1e300),
                ("127.0.0.1", float("nan")),
                ("127.0.0.1", True),
                ("127.0.0.1",),
                (1.0, 5),
                "ab",
                None,
                np.array([1.0, 2.0]),
            ]
        )
    )


def wire_int(d: Draw, _ctx):
    return d(st.one_of(st.integers(-3, 10), st.sampled_from([2**32, 2**64, -(2**63) - 1, *HUGE_INTS])))


def timeout(d: Draw, _ctx):
    return d(st.sampled_from([0.0, 0.001, 5e-324, -1.0, float("nan"), float("inf"), 1e300, *HUGE_INTS]))


def out_csv(d: Draw, _ctx):
    return d(st.sampled_from([os.path.join(TMP, "trajectory.csv"), "/nonexistent-dir/trajectory.csv"]))


def array_or_none(d: Draw, ctx):
    return None if d(st.booleans()) else d.array([(2, ctx["n"]), (ctx["n"],), (3, ctx["n"])])


def binary_file(d: Draw, _ctx):
    import io

    contents = [b"", b'{"ob": [[1, 2, 3]]}', b"\xff\xfe\x00", b"x" * 100, b"[" * 70 + b"]" * 70]
    return d(st.one_of(st.sampled_from(contents).map(io.BytesIO), st.sampled_from([None, "a.json", 1.0])))


def byte_limit(d: Draw, _ctx):
    return d(st.sampled_from([-1, 0, 5, 16 << 20, (512 << 20) + 1, 2**64, 1.5, True, *HUGE_INTS]))


def label(d: Draw, _ctx):
    return d(st.sampled_from(["a.json", "", "x" * 300, None]))


JSON_TEXTS = [
    "",
    "{}",
    '{"ob": [[1, 2, 3], [4, 5, 6]]}',
    "[" * 64 + "]" * 64,
    "[" * 65 + "]" * 65,
    "[" * 100000,
    '{"a": 1e400}',
    "1" * 401,
    "NaN",
    '"\\ud800"',
    '{"a": "[[[["}',
    "garbage",
]


def json_text(d: Draw, _ctx):
    return d(st.sampled_from(JSON_TEXTS))


def json_text_or_bytes(d: Draw, _ctx):
    text = d(st.sampled_from(JSON_TEXTS))
    return d(st.sampled_from([text, text.encode(), b"\xff" + text.encode()]))


@functools.cache
def _files() -> dict[str, str]:
    """Files and folders the readers are called on: valid synthetic flights (a folder and a zip),
    a folder of malformed ones, an empty folder, a non-UTF-8 file, a folder given as a file."""
    import json
    import zipfile

    out = {}
    rng = np.random.default_rng(29)
    good = os.path.join(TMP, "flights")
    os.makedirs(good, exist_ok=True)
    t = np.arange(40) * 0.0108  # 40 frames of the recorded data's 10.8 ms
    for i in range(8):
        s = ttmanip.ball.state(
            [-1.3, rng.uniform(-0.2, 0.2), 0.25],
            [2.5 + rng.uniform(-0.3, 0.3), 0.0, 1.0],
            [0.0, rng.uniform(-40, 40), 0.0],
        )
        p = ttmanip.ball.predict(s, t)  # short of the net: every frame finite
        rows = np.column_stack([p, np.gradient(p, t, axis=0)])
        with open(os.path.join(good, f"{i}.json"), "w") as f:
            json.dump({"ob": rows.tolist()}, f)
    out["folder"] = good
    out["zip"] = os.path.join(TMP, "flights.zip")
    with zipfile.ZipFile(out["zip"], "w") as z:
        for i in range(8):
            z.write(os.path.join(good, f"{i}.json"), f"{i}.json")
    bad = os.path.join(TMP, "bad-flights")
    os.makedirs(bad, exist_ok=True)
    for i, text in enumerate(['{"ob": [[1, 2]]}', '{"ob": [[true, 1, 2]]}', "[" * 100, '{"ob": "x"}']):
        with open(os.path.join(bad, f"{i}.json"), "w") as f:
            f.write(text)
    out["bad"] = bad
    out["empty"] = os.path.join(TMP, "no-flights")
    os.makedirs(out["empty"], exist_ok=True)
    out["binary"] = os.path.join(TMP, "binary.json")
    with open(out["binary"], "wb") as f:
        f.write(b'{"ob": \xff}')
    out["one"] = os.path.join(good, "0.json")
    return out


def flights_path(d: Draw, _ctx):
    f = _files()
    return d(st.sampled_from([f["folder"], f["zip"], f["bad"], f["empty"], f["one"], "/nonexistent/flights"]))


def text_path(d: Draw, _ctx):
    f = _files()
    return d(st.sampled_from([f["one"], f["binary"], f["folder"], "/dev/zero", "/nonexistent/x.json"]))


def window(d: Draw, _ctx):
    return d(st.sampled_from([-1, 0, 1, 3, 20, 10**6, 2**64, 1.5, *HUGE_INTS]))


def period(d: Draw, _ctx):
    return None if d(st.booleans()) else d.value()


SPECIAL_STRATEGIES = {
    "address": address,
    "wire_int": wire_int,
    "timeout": timeout,
    "out_csv": out_csv,
    "array_or_none": array_or_none,
    "binary_file": binary_file,
    "byte_limit": byte_limit,
    "label": label,
    "json_text": json_text,
    "json_text_or_bytes": json_text_or_bytes,
    "flights_path": flights_path,
    "text_path": text_path,
    "window": window,
    "period": period,
    "vector3": lambda d, _ctx: d.array([(3,), (2,), (2, 3)]),
    "ball_model_name": lambda d, _ctx: d(
        st.sampled_from(["default", "muelling", "mpi", "tt3d", "vacuum", "bogus"])
    ),
    "tiny_count": tiny_count,
    "rate": rate,
    "noise": noise,
    "short_times": short_times,
    "out_dir": out_dir,
    "hit": hit,
    "hits": hits,
    "hit_plan": hit_plan,
    "jerk_or_none": jerk_or_none,
    "array6": array6,
    "pose_or_junk": pose_or_junk,
    "flag": flag,
    "time": lambda d, _ctx: d.value(),
    "diffdrive_or_none": diffdrive_or_none,
    "state": state,
    "dc_motor": sample_of("motor.DcMotor"),
    "gearbox": sample_of("motor.Gearbox"),
    "load": sample_of("motor.Load"),
    "power_stage": sample_of("motor.PowerStage"),
    "loops": sample_of("motor.Loops"),
    "response": lambda d, _ctx: sample_objects()["motor.Response"],
    "small_count": small_count,
    "out_path": out_path,
    "out_path_required": out_path_required,
    "task_trajectory": task_trajectory,
    "torque_profile": torque_profile,
    "robot_name": lambda d, ctx: d(st.sampled_from(CHOICES["robot_name"])),
}


def argument(d: Draw, pname: str, ctx: dict, override: str | None, default=inspect.Parameter.empty):
    """A value for parameter `pname` (ctx: the robot of the call, its joint count n)."""
    if override:
        return SPECIAL_STRATEGIES[override](d, ctx)
    n = ctx["n"]
    shapes = [(n,), (2, n), (0, n), (3,), (6,), (5,), (2,), (n, 2), (4, 4), ()]
    if pname in ARRAY_NAMES:
        return None if default is None and d(st.integers(0, 4)) == 0 else d.array(shapes)
    if pname in FLOAT_NAMES:
        if d(st.integers(0, 19)) == 0:  # a Python int beyond float64 (issue 29: named, not OverflowError)
            d.finite = False
            return d(st.sampled_from(HUGE_INTS))
        return None if default is None and d(st.integers(0, 4)) == 0 else d.value()
    if pname == "robot":
        extra = [None] if default is None else []
        return d(st.sampled_from([robot(r) for r in ROBOT_NAMES] + extra))
    if pname in POSE_NAMES:
        return poses(d, ctx["robot"])
    if pname in CHOICES and d(st.integers(0, 9)) < 8:
        return d(st.sampled_from(CHOICES[pname]))
    if pname in INTS:
        return d(
            st.one_of(
                st.integers(-3, 40),
                st.sampled_from([-(2**40), 2**64, 0, 10**30, -(10**30), 2**126, *HUGE_INTS]),
            )
        )
    if pname in BOOLS:
        return d(st.booleans())
    if pname in PATH_NAMES:
        return d(st.sampled_from(["/nonexistent/robot.toml", os.path.join(TMP, "garbage.toml")]))
    if pname in ("text",):
        return d(st.sampled_from(["", "garbage", "<robot", robot("arm4").to_toml(), robot("arm4").to_urdf()]))
    if pname in ("base_link", "tip_link"):
        return d(st.sampled_from(["base_link", "tool", "link0", "link3", "nope"]))
    # a parameter the tables above do not know: numbers, arrays or None, and so possibly of the
    # wrong Python type (a TypeError is then the right answer)
    d.loose = True
    kind = d(st.integers(0, 9))
    if kind < 3:
        return d.value()
    if kind < 4:
        return None
    return d.array(shapes)


# ---------------------------------------------------------------- the call and the verdict


def arrays_in(result, depth=0):
    """Every numpy array (and float) reachable in a result."""
    if depth > 3:
        return
    if isinstance(result, np.ndarray):
        yield result
    elif isinstance(result, float):
        yield np.array(result)
    elif isinstance(result, (tuple, list)):
        for r in result:
            yield from arrays_in(r, depth + 1)
    elif isinstance(result, dict):
        for r in result.values():
            yield from arrays_in(r, depth + 1)


def parameters(fn) -> list[inspect.Parameter]:
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return []
    return [
        p
        for p in sig.parameters.values()
        if p.name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    ]


def resolve(key: str):
    """The object a registry key names (module attribute path)."""
    obj = ttmanip
    for part in key.split("."):
        obj = getattr(obj, part)
    return obj


def make_call(d: Draw, key: str, static):
    """(callable, or None for an attribute read; receiver; attribute; args; kwargs; ctx)."""
    spec = API.get(key, {})
    ctx_robot = robot(d(st.sampled_from(ROBOT_NAMES)))
    ctx = {"robot": ctx_robot, "n": ctx_robot.dof}
    owner, _, attr = key.rpartition(".")
    receiver = None
    owner_obj = resolve(owner) if owner else ttmanip
    if inspect.isclass(owner_obj) and not isinstance(static, (staticmethod, classmethod)):
        receiver = ctx_robot if owner == "Robot" else sample_objects()[owner]
        member = getattr(receiver, attr)
        target = member if callable(member) else None
    else:
        target = resolve(key)
    args, kwargs = [], {}
    if target is not None:
        for p in parameters(target):
            if p.default is not p.empty and d(st.integers(0, 9)) < 4:
                continue
            v = argument(d, p.name, ctx, spec.get("args", {}).get(p.name), p.default)
            if p.kind == p.POSITIONAL_ONLY:
                args.append(v)
            else:
                kwargs[p.name] = v
    return target, receiver, attr, args, kwargs, ctx


def check(key: str, result, d: Draw, kwargs: dict, ctx: dict):
    spec = API.get(key, {})
    if "finite_part" in spec:
        result = spec["finite_part"](result)
    for a in arrays_in(result):
        if a.dtype.kind == "f":
            assert a.dtype == np.float64, f"{key}: float result of dtype {a.dtype}, documented float64"
            if d.finite and not spec.get("may_be_inf"):
                assert np.isfinite(a).all(), f"{key}: non-finite result {a!r} for finite inputs {kwargs!r}"
    shape = spec.get("shape")
    if shape is not None:
        first = next((v for v in kwargs.values() if isinstance(v, (np.ndarray, list))), None)
        batch = np.asarray(first).shape[0] if first is not None and np.asarray(first).ndim >= 2 else None
        n = getattr(ctx.get("receiver"), "dof", ctx["n"])
        assert isinstance(result, np.ndarray), f"{key}: expected an array, got {type(result)}"
        assert result.shape == shape(n, batch), f"{key}: shape {result.shape}, documented {shape(n, batch)}"


def run_one(d: Draw, key: str, obj):
    spec = API.get(key, {})
    if "skip_call" in spec:
        return
    target, receiver, attr, args, kwargs, ctx = make_call(d, key, obj)
    ctx["receiver"] = receiver
    faulthandler.dump_traceback_later(CALL_SECONDS, exit=True)  # a hang ends the run, with stacks
    try:
        if target is None:
            result = getattr(receiver, attr)
        else:
            result = target(*args, **kwargs)
    except ttmanip.TtmanipError:
        return
    except BaseException as e:  # noqa: BLE001 - the point: nothing else may escape
        if isinstance(e, KeyboardInterrupt):
            raise
        if isinstance(e, TypeError) and d.loose:
            return  # a value of the wrong Python type for a parameter the tables do not know
        if isinstance(e, OSError) and spec.get("os_error"):
            return  # an unwritable output path (see the registry)
        if isinstance(e, TypeError) and any(m in str(e) for m in spec.get("type_error", ())):
            return  # a documented TypeError (see the registry)
        raise AssertionError(
            f"{key}({args!r}, {kwargs!r}) raised {type(e).__module__}.{type(e).__name__}: {e}"
        ) from e
    finally:
        faulthandler.cancel_dump_traceback_later()
    # (a loose parameter or a record's field may be stored and checked later)
    if d.refuse and not d.loose and not spec.get("record"):
        raise AssertionError(f"{key}({args!r}, {kwargs!r}) accepted a boolean or complex array")
    check(key, result, d, kwargs, ctx)


CALLABLES = public_callables()


def test_registry_covers_the_public_api():
    missing = sorted(set(CALLABLES) - set(API))
    assert not missing, f"public callables missing from tests/api_registry.py: {missing}"
    stale = sorted(set(API) - set(CALLABLES))
    assert not stale, f"registry entries that are not public callables (any more): {stale}"


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
)
@given(data=st.data(), key=st.sampled_from(sorted(CALLABLES)))
def test_fuzz_every_public_callable(data, key):
    run_one(Draw(data), key, CALLABLES[key])


@pytest.mark.parametrize("key", sorted(k for k in CALLABLES if "skip_call" not in API.get(k, {})))
def test_each_callable_survives_a_few_calls(key):
    """Every entry gets some calls of its own, whatever the random choice of keys above."""

    @settings(
        max_examples=8,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        phases=[Phase.explicit, Phase.generate],
    )
    @given(data=st.data())
    def inner(data):
        run_one(Draw(data), key, CALLABLES[key])

    inner()


def is_scalar_parameter(p: inspect.Parameter) -> bool:
    """A parameter that takes a number: by name, or by its numeric default."""
    if p.name in FLOAT_NAMES or p.name in INTS:
        return True
    return isinstance(p.default, (int, float)) and not isinstance(p.default, bool)


def run_huge_int(d: Draw, key: str, obj):
    """One call of `key` with a huge or negative Python int for one of its scalar parameters."""
    spec = API.get(key, {})
    target, receiver, attr, args, kwargs, ctx = make_call(d, key, obj)
    if target is None:
        return
    scalars = [p for p in parameters(target) if is_scalar_parameter(p) and p.kind != p.POSITIONAL_ONLY]
    if not scalars:
        return
    p = d(st.sampled_from(scalars))
    value = d(st.sampled_from(HUGE_INTS))
    kwargs[p.name] = value
    faulthandler.dump_traceback_later(CALL_SECONDS, exit=True)
    try:
        target(*args, **kwargs)
    except ttmanip.TtmanipError as e:
        # a refusal of the huge int names its argument and the accepted range
        if "is out of range; expected" in str(e):
            # (another int argument, e.g. a negative id, may be the one refused first)
            huge = [k for k, v in kwargs.items() if isinstance(v, int) and not isinstance(v, bool)]
            assert any(f"{k}: " in str(e) for k in huge), f"{key}({p.name}={value}): {e}"
    except BaseException as e:  # noqa: BLE001 - the point: nothing else may escape
        if isinstance(e, KeyboardInterrupt):
            raise
        if isinstance(e, TypeError) and (d.loose or any(m in str(e) for m in spec.get("type_error", ()))):
            return
        if isinstance(e, OSError) and spec.get("os_error"):
            return
        kind = f"{type(e).__module__}.{type(e).__name__}"
        raise AssertionError(f"{key}({args!r}, {{..., {p.name!r}: {value}}}) raised {kind}: {e}") from e
    finally:
        faulthandler.cancel_dump_traceback_later()


@pytest.mark.parametrize("key", sorted(k for k in CALLABLES if "skip_call" not in API.get(k, {})))
def test_huge_and_negative_ints_are_named(key):
    """Every scalar parameter of every callable, given a Python int out of every binding type's
    range (10**400, 2**1024, 2**128, -2**64, -1): a TtmanipError naming it, never a bare
    OverflowError (issue 29, class 8)."""

    @settings(
        max_examples=12,
        deadline=None,
        suppress_health_check=list(HealthCheck),
        derandomize=True,
        phases=[Phase.explicit, Phase.generate],
    )
    @given(data=st.data())
    def inner(data):
        run_huge_int(Draw(data), key, CALLABLES[key])

    inner()
