"""Issue 29: no input crashes, hangs or lies. Every example of the issue, each standing for a class
(work bounded before it starts, clocks that stop, parsers without limits, validation by entry
point, results that do not match their inputs, lenient files, binaries, messages). A case that
could kill the interpreter or run unbounded runs in a subprocess with a time and memory cap
(``capped``): an abort, a segfault, a hang or a traceback fails it."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest
import ttmanip
import ttmanip.ctl
from ttmanip import TtmanipError
from ttmanip.pipeline import racket_frame

#: Per case: seconds and address space (bytes) a capped case may use.
CAP_SECONDS = 60
CAP_BYTES = 3 << 30


def _limits():
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def _interactive():
    """The caps, and SIGINT at its default as in a terminal: a test run in the background (``&``
    or ``nohup``) starts its children with SIGINT ignored, and Python then installs no Ctrl-C
    handler, which is right for such a process but not what these tests are about."""
    _limits()
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def capped(code: str, timeout: float = CAP_SECONDS) -> subprocess.CompletedProcess:
    """Runs ``code`` in a fresh interpreter under the caps; returns it (failing on a hang)."""
    try:
        return subprocess.run(
            [sys.executable, "-c", textwrap.dedent(code)],
            capture_output=True,
            text=True,
            timeout=timeout,
            preexec_fn=_limits,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"hung for more than {timeout} s:\n{code}")


def refused(code: str, *fragments: str) -> str:
    """``code`` (which calls something that must be refused) raises a TtmanipError naming
    ``fragments``: no abort, segfault, hang or other exception."""
    wrapped = f"""
import ttmanip, numpy as np
try:
{textwrap.indent(textwrap.dedent(code), "    ")}
except ttmanip.TtmanipError as e:
    print("REFUSED", type(e).__name__, e)
else:
    print("ACCEPTED")
"""
    r = capped(wrapped)
    assert r.returncode == 0, f"exit {r.returncode}\n{r.stderr[-2000:]}"
    assert "REFUSED" in r.stdout, r.stdout + r.stderr
    for f in fragments:
        assert f in r.stdout, r.stdout
    return r.stdout


# -- 1. work bounded before it starts -----------------------------------------------------------


def test_sampling_is_bounded_in_bytes_before_allocating():
    refused(
        """
plan = ttmanip.plan_hit(ttmanip.robots.gantry6(), ttmanip.DEMO_HIT)
plan.sample(0.99e8 / plan.duration)
""",
        "hz",
        "bytes",
    )


def test_servo_runs_are_bounded_before_allocating():
    refused("ttmanip.motor.Servo().step_response('current', 1.0, 1e4)", "duration")
    refused("ttmanip.motor.Servo().step_response('current', 1.0, 1e300)", "duration")


def test_estimation_window_is_bounded():
    refused(
        """
t = np.array([0.0, 1.0, 2.0, 3.0, 1e6])
p = np.column_stack([t * 0.0, t * 0.0, t * 0.0 + 1.0])
ttmanip.ball.estimate(t, p)
""",
        "t",
    )


def test_ball_flights_are_bounded_in_steps():
    refused("ttmanip.ball.predict(ttmanip.ball.state([0, 0, 1e3], [0, 0, 0]), [1e7])", "steps")


def test_batch_results_are_bounded_in_bytes_before_allocating():
    # 1e5 balls × 1e5 times × 3 floats is 240 GB: refused, not an aborted allocation.
    refused(
        """
s = np.tile(ttmanip.ball.state([-1, 0, 0.3], [4, 0, 1]), (100000, 1))
ttmanip.ball.predict_batch(s, np.linspace(0.0, 0.1, 100000))
""",
        "result of shape (100000, 100000, 3)",
    )


def test_a_batch_of_hits_is_bounded_in_bytes_before_it_is_stacked_or_planned():
    # 10⁷ hits: plan_hits stacked 1.19 GiB of poses, then planned for hours; now refused at
    # once, saying how many hits one call may take (the binding checks its arrays alike)
    out = refused(
        "ttmanip.plan_hits(ttmanip.robots.gantry6(), [ttmanip.DEMO_HIT] * 10**7)",
        "hits: 10000000 hits",
        "512 MiB",
        "split the batch into calls of at most",
    )
    most = int(out.split("at most ")[-1].split()[0])
    assert 100_000 <= most < 10**7, out
    refused(
        """
n = 10**7
poses = np.broadcast_to(np.eye(4), (n, 4, 4))
ttmanip._ttmanip.hit_plan_batch(ttmanip.robots.gantry6(), poses, np.zeros((n, 6)), np.full(n, 0.5))
""",
        "split the batch",
    )


def test_rally_n_is_checked_before_the_first_chunk():
    with pytest.raises(TtmanipError, match="at most"):
        ttmanip.rally(10**12)


def test_a_long_rally_stops_on_ctrl_c():
    _stops_on_ctrl_c(
        "import ttmanip",
        "ttmanip._ttmanip.ball_rally",
        "ttmanip._ttmanip.ball_rally(100000, 0, 0)",  # minutes of work
    )


# -- 2. clocks that stop ------------------------------------------------------------------------


@pytest.mark.parametrize("t0", [1e15, 1e17])
def test_flights_far_from_t0_are_refused(t0):
    refused(
        f"ttmanip.ball.predict(ttmanip.ball.state([0, 0, 1], [1, 0, 0], t={t0}), [{t0} + 1e3])",
        "nearer origin",
    )


def test_drive_runs_far_from_t0_or_too_long_are_refused():
    refused(
        """
sim = ttmanip.DriveSim(ttmanip.robots.gantry6())
z = np.zeros((2, 6))
sim.run(np.array([0.0, 1e15]), z, z, z)
""",
        "nearer origin",
    )
    refused(
        """
sim = ttmanip.DriveSim(ttmanip.robots.gantry6())
z = np.zeros((2, 6))
sim.run(np.array([0.0, 1e4]), z, z, z)
""",
        "ticks",
    )


# -- 3. parsers with limits ---------------------------------------------------------------------


def test_deep_and_huge_urdf_are_refused(tmp_path):
    deep = tmp_path / "deep.urdf"
    deep.write_text("<robot name='r'>" + "<a>" * 20000 + "</a>" * 20000 + "</robot>")
    refused(f"ttmanip.Robot.from_urdf({str(deep)!r}, 'a', 'b')", "nested")


def test_cli_reads_no_further_than_the_limit():
    r = subprocess.run(
        [sys.executable, "-m", "ttmanip.cli", "plan", "/dev/zero"],
        capture_output=True,
        text=True,
        timeout=CAP_SECONDS,
        preexec_fn=_limits,
    )
    assert r.returncode == 1 and "16 MiB" in r.stderr and "Traceback" not in r.stderr, r.stderr


@pytest.mark.parametrize(
    "text, fragment",
    [
        (
            '{"robot": "gantry6", "hits": [{"centre": [1' + "0" * 400 + ', 0, 0], "normal": [0, -1, 0], '
            '"velocity": [0, -1, 0], "t": 0.3}]}',
            "finite",
        ),
        (b'{"robot": "gantry6\xff"}', "UTF-8"),
        ("[" * 100000 + "]" * 100000, "nested"),
    ],
)
def test_hit_files_with_huge_ints_bad_bytes_or_deep_nesting_are_one_line_errors(tmp_path, text, fragment):
    path = tmp_path / "hit.json"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    r = subprocess.run(
        [sys.executable, "-m", "ttmanip.cli", "plan", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=CAP_SECONDS,
        preexec_fn=_limits,
    )
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr and fragment in r.stderr, r.stderr


# -- 4. one validation everywhere ---------------------------------------------------------------


@pytest.mark.parametrize("bad", [np.array([0.3, -1.0, -0.2], dtype=complex), np.array([True, False, True])])
def test_complex_and_bool_arrays_are_refused_everywhere(bad):
    with pytest.raises(ttmanip.ShapeError):
        ttmanip.Hit.from_normal([0.35, -0.55, 0.05], bad, [0.86, -2.87, -0.57], 0.35)
    with pytest.raises(ttmanip.ShapeError):
        ttmanip.Hit(np.eye(4).astype(bad.dtype), np.zeros(6), 0.3)
    with pytest.raises(ttmanip.ShapeError):
        ttmanip.ball.state(bad, [1, 0, 0])
    with pytest.raises(TtmanipError):
        ttmanip.ctl.write_trajectory(
            "/tmp/never.csv", [0.0, 1.0], np.stack([bad[:2], bad[:2]]), np.zeros((2, 2)), np.zeros((2, 2))
        )


def test_racket_frame_of_huge_vectors_is_a_rotation():
    r = racket_frame([1e300, -1e300, 1e300])
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-12) and abs(np.linalg.det(r) - 1) < 1e-12


# -- 5. results that match their inputs ---------------------------------------------------------


def test_a_plan_is_simulated_only_on_its_robot():
    plan = ttmanip.plan_hit(ttmanip.robots.gantry6(), ttmanip.DEMO_HIT)
    with pytest.raises(TtmanipError, match="made for robot 'gantry6'"):
        ttmanip.simulate(ttmanip.robots.ur5(), plan)
    with pytest.raises(TtmanipError, match="made for robot"):
        ttmanip.simulate(ttmanip.robots.mobile8(), plan)
    assert plan.made_for(ttmanip.robots.gantry6())


def test_hit_times_beyond_the_longest_stroke_are_refused_at_the_hit():
    with pytest.raises(TtmanipError, match="hit.t: the hit time must be at most .* got 1e300 s$"):
        ttmanip.Hit(ttmanip.DEMO_HIT.pose, ttmanip.DEMO_HIT.twist, 1e300)


def test_drive_setpoints_beyond_the_joint_limits_are_refused():
    # a setpoint of 1e300 was taken (the axis then ran into its following-error fault)
    robot = ttmanip.robots.gantry6()
    sim = ttmanip.DriveSim(robot)
    with pytest.raises(ttmanip.ModelError, match=r"^q\[3\] = 1e300: outside joint 'theta4' position limits"):
        sim.set_setpoint([0.0, 0.0, 0.0, 1e300, 0.0, 0.0])
    with pytest.raises(ttmanip.ModelError, match=r"^qd\[0\] = -5: over joint 'd1' velocity limit 3 m/s"):
        sim.set_setpoint(np.zeros(6), qd=[-5.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    # a run is checked whole before its first tick: nothing ran
    t = np.linspace(0.0, 0.01, 11)
    q = np.zeros((11, 6))
    q[5, 2] = 1e300
    before = sim.t
    with pytest.raises(ttmanip.ModelError, match=r"^q\[5, 2\] = 1e300: outside joint 'theta3'"):
        sim.run(t, q, np.zeros_like(q), np.zeros_like(q))
    assert sim.t == before
    # at the limits (a stroke sampled at its limit), within the margin: taken
    lim = robot.limits
    sim.set_setpoint(lim[:, 1] + 5e-7, qd=robot.velocity_limits)
    sim.set_setpoint(lim[:, 0], qd=-robot.velocity_limits * (1 + 5e-7))
    with pytest.raises(ttmanip.ModelError, match=r"^q\[0\]"):
        sim.set_setpoint(lim[:, 1] + 2e-6)


def test_an_overflowing_motor_model_is_refused_not_simulated_as_nan():
    refused(
        """
s = ttmanip.motor.Servo(ttmanip.motor.DcMotor(inductance=1e-300))
s.step_response('current', 1.0, 0.01)
""",
        "inductance",
    )


def test_unphysical_ball_speeds_are_refused():
    with pytest.raises(TtmanipError, match="velocity"):
        ttmanip.ball.predict(ttmanip.ball.state([0, 0, 1], [1e200, 0, 0]), [0.1])


# -- 6. hit files as strict as robot files ------------------------------------------------------

GOOD = {
    "centre": [0.35, -0.55, 0.05],
    "normal": [0.3, -1.0, -0.2],
    "velocity": [0.86, -2.87, -0.57],
    "t": 0.35,
}


@pytest.mark.parametrize(
    "data, key",
    [
        ({"robot": "gantry6", "hits": [GOOD], "redy": [0] * 6}, "redy"),
        ({"robot": "gantry6", "hits": [GOOD], "profle": "jerk"}, "profle"),
        ({"robot": "gantry6", "hits": [GOOD], "state": {"q": [0] * 6, "qdot": [0] * 6}}, "state.qdot"),
        ({"robot": "gantry6", "hits": [{**GOOD, "center": [0, 0, 0]}]}, "center"),
        ({"robot": "gantry6", **GOOD, "profle": "jerk"}, "profle"),
    ],
)
def test_unknown_keys_in_hit_files_are_refused(tmp_path, data, key):
    from ttmanip import cli

    path = tmp_path / "hit.json"
    path.write_text(json.dumps(data))
    with pytest.raises(cli.CliError, match=key):
        cli.read_hit_file(str(path))


# -- 7. binaries: checked arguments and one set of exit codes -----------------------------------


def _binary(name: str) -> str | None:
    from conftest import built_binary

    return built_binary(name)


@pytest.mark.parametrize(
    "binary, args, fragment",
    [
        ("ttctl", ["--demo", "--amplitude", "nan", "--check"], "--amplitude"),
        ("ttctl", ["--demo", "--max-seconds=-1", "--check"], "--max-seconds"),
        ("ttctl", ["--no-such-option"], ""),
        ("ttdrive-sim", ["--channel", "vcan0:1", "--duration", "nan"], "--duration"),
        ("ttdrive-sim", ["--channel", "vcan0:1,1"], "node 1 given twice"),
        ("ttdrive-sim", ["--channel", "vcan0:1", "--channel", "vcan0:2"], "interface given twice"),
        ("ttdrive-sim", ["--bogus"], ""),
    ],
)
def test_binaries_refuse_bad_arguments_with_exit_1(binary, args, fragment):
    exe = _binary(binary)
    if exe is None:
        pytest.skip(f"{binary} is not built (cargo build -p ttcan)")
    r = subprocess.run([exe, *args], capture_output=True, text=True, timeout=CAP_SECONDS, preexec_fn=_limits)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert fragment in r.stderr, r.stderr


def test_cli_usage_errors_exit_1_and_help_0():
    from ttmanip import cli

    assert cli.main(["--no-such-option"]) == 1
    assert cli.main(["fk"]) == 1


# -- 8. messages that name the right thing ------------------------------------------------------


def test_a_plan_for_another_robot_names_the_plan_not_q0():
    plan = ttmanip.plan_hit(ttmanip.robots.gantry6(), ttmanip.DEMO_HIT)
    with pytest.raises(TtmanipError) as e:
        ttmanip.simulate(ttmanip.robots.mobile8(), plan)
    assert str(e.value).startswith("plan:") and "q0" not in str(e.value)


# -- 1b. long calls stop on Ctrl-C (issue 29: every call that can run longer than ~0.5 s) --------


#: The child of a Ctrl-C test: ``SETUP`` runs, a profile hook reports when ``TARGET`` (a binding)
#: is entered ("started") and how it ends ("ended c_return": it finished; "ended c_exception": it
#: raised, here KeyboardInterrupt: it stopped before finishing), then ``CALL`` runs and ``AFTER``
#: runs once it is interrupted.
CTRL_C_CHILD = """
import sys
{setup}
TARGET = {target}


def _hook(frame, event, arg):
    if event in ("c_call", "c_return", "c_exception") and (
        arg is TARGET or (type(arg) is type(TARGET) and arg == TARGET)
    ):
        print("started" if event == "c_call" else f"ended {{event}}", flush=True)


sys.setprofile(_hook)
try:
    {call}
except KeyboardInterrupt:
    sys.setprofile(None)
    print("interrupted", flush=True)
{after}
    sys.exit(130)
sys.setprofile(None)
print("finished", flush=True)
"""


def _stops_on_ctrl_c(
    setup: str, target: str, call: str, after: str = "", timeout: float = 900.0, cli: bool = False
) -> str:
    """Runs ``call`` in a fresh capped interpreter and sends it SIGINT once the binding ``target``
    has started its work (a readiness line from a profile hook, so a loaded machine cannot send
    it early); the binding must end by raising KeyboardInterrupt (``c_exception``: it stopped
    before finishing, not after) and the process exit 130. No timing is asserted: the timeout
    (generous under any load) only catches a call that ignores the signal and runs on. Returns
    the child's stdout (``after`` may print what it checks). ``cli``: ``call`` is the ``ttmanip``
    command line, which handles the interrupt itself: one line on stderr, no traceback."""
    import tempfile

    code = CTRL_C_CHILD.format(
        setup=textwrap.dedent(setup),
        target=target,
        call=call,
        after=textwrap.indent(textwrap.dedent(after), "    "),
    )
    lines: list[str] = []
    started = threading.Event()
    with tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            preexec_fn=_interactive,
        )

        def read():
            for line in p.stdout:
                lines.append(line.strip())
                if line.strip() == "started":
                    started.set()
            started.set()  # the child ended without starting the work: fail below

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        try:
            if not started.wait(timeout):
                pytest.fail(f"{target} did not start within {timeout} s")
            time.sleep(0.2)
            p.send_signal(signal.SIGINT)
            p.wait(timeout)
        except subprocess.TimeoutExpired:
            pytest.fail(f"{target} went on for {timeout} s after Ctrl-C: {lines}")
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
            reader.join(10)
            err.seek(0)
            stderr = err.read()
    out = "\n".join(lines)
    assert "started" in lines, f"{target} was never called:\n{out}\n{stderr[-3000:]}"
    assert "finished" not in lines and "ended c_return" not in lines, (
        f"the work ended before Ctrl-C: make it longer\n{out}"
    )
    assert "ended c_exception" in lines, f"{out}\n{stderr[-3000:]}"
    if cli:
        assert "ttmanip: interrupted" in stderr and "Traceback" not in stderr, stderr[-3000:]
    else:
        assert "interrupted" in lines, f"{out}\n{stderr[-3000:]}"
    assert p.returncode == 130, (p.returncode, out, stderr[-3000:])
    return out


CLI = "import sys\nfrom ttmanip import _ttmanip\nfrom ttmanip.cli import main"


def test_planning_a_file_of_100000_hits_stops_on_ctrl_c(tmp_path):
    rng = np.random.default_rng(0)
    hit = ttmanip.DEMO_HIT
    centres = np.round(hit.centre + rng.uniform(-0.15, 0.15, (100_000, 3)), 3).tolist()
    normal, velocity = (
        np.round(hit.normal, 4).tolist(),
        np.round(3.0 * hit.normal, 4).tolist(),
    )  # within 16 MiB
    hits = [{"centre": c, "normal": normal, "velocity": velocity, "t": 0.5} for c in centres]
    (tmp_path / "hits.json").write_text(json.dumps({"robot": "gantry6", "hits": hits}, separators=(",", ":")))
    out = tmp_path / "out"
    call = f"sys.exit(main(['plan', {str(tmp_path / 'hits.json')!r}, '--out', {str(out)!r}]))"
    _stops_on_ctrl_c(CLI, "_ttmanip.hit_plan_batch", call, cli=True)
    assert not (out / "plan.json").exists()


def test_a_sweep_of_20000_values_stops_on_ctrl_c(tmp_path):
    out = tmp_path / "sweep"
    args = ["sweep", "hits", "--param", "speed=2:6:20000", "--scheduler", "serial", "--out", str(out)]
    _stops_on_ctrl_c(CLI, "_ttmanip.hit_plan_batch", f"sys.exit(main({args!r}))", cli=True)
    assert not (out / "sweep.csv").exists()


def test_an_ik_batch_stops_on_ctrl_c():
    _stops_on_ctrl_c(
        """
        import numpy as np, ttmanip
        ur5 = ttmanip.robots.ur5()
        rng = np.random.default_rng(0)
        lim = np.clip(ur5.limits, -3.0, 3.0)
        T = np.tile(ur5.fk(lim[:, 0] + (lim[:, 1] - lim[:, 0]) * rng.random((4000, 6))), (50, 1, 1))
        """,
        "ur5.ik",
        'ur5.ik(T, np.zeros(6), method="numeric", time_budget=None)',  # 200 000 targets
    )


def test_a_servo_run_stops_on_ctrl_c():
    _stops_on_ctrl_c(
        "import ttmanip\nservo = ttmanip.motor.Servo()",
        "servo._sim.step",
        'servo.step_response("position", 0.1, 300.0)',
    )


DRIVE_SIM = """
import pickle
import numpy as np, ttmanip
robot = ttmanip.robots.mobile8()
sim = ttmanip.DriveSim(robot)
z = np.zeros((2, robot.dof))
q0 = ttmanip.robots.mobile8_start()
sim.reset(q0)
"""
#: The interrupted simulation stayed usable: it stopped within the run, and a pickle replays the
#: interrupted run to the same tick.
DRIVE_SIM_AFTER = """
print("t", sim.t, flush=True)
copy = pickle.loads(pickle.dumps(sim))
print("same", bool(np.array_equal(copy.q, sim.q)) and copy.t == sim.t, flush=True)
sim.tick(10)
"""


def test_a_drive_run_stops_on_ctrl_c():
    # 49 s: 980 000 ticks at 20 kHz, under the 10⁶ a run may take
    out = _stops_on_ctrl_c(
        DRIVE_SIM, "sim.run", "sim.run(np.array([0.0, 49.0]), np.tile(q0, (2, 1)), z, z)", DRIVE_SIM_AFTER
    )
    t = float(out.split("t ")[-1].split()[0])
    assert 0.0 < t < 49.0 and "same True" in out, out


def test_drive_ticks_stop_on_ctrl_c():
    out = _stops_on_ctrl_c(DRIVE_SIM, "sim.tick", "sim.tick(980_000)", DRIVE_SIM_AFTER)
    t = float(out.split("t ")[-1].split()[0])
    assert 0.0 < t < 49.0 and "same True" in out, out


#: A ball high up with a strong spin: the Magnus force keeps it flying for the whole 10⁸-step
#: horizon (about 10 s of work).
HIGH_BALL = "import ttmanip\ns = ttmanip.ball.state([0.0, 0.0, 1e4], [900.0, 0.0, 0.0], [0.0, 1e5, 0.0])"


def test_a_single_ball_flight_stops_on_ctrl_c():
    _stops_on_ctrl_c(HIGH_BALL, "ttmanip._ttmanip.ball_predict", "ttmanip.ball.predict(s, [1.9e5])")


# -- 8. messages: a huge Python int names its argument (every binding argument, by #[guarded]) ----


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda p, r: p.sample(10**400), "rate_hz"),
        (lambda p, r: r.ik(r.fk(np.zeros(r.dof)), max_iterations=10**400), "max_iterations"),
        (lambda p, r: r.ik(r.fk(np.zeros(r.dof)), seed=-(2**130)), "seed"),
        (lambda p, r: ttmanip.motor.Servo().step_response("current", 1.0, 2**1024), "duration"),
        (lambda p, r: ttmanip.DriveSim(r).tick(10**40), "n"),
    ],
)
def test_huge_python_ints_name_their_argument_and_range(call, name):
    r = ttmanip.robots.gantry6()
    p = ttmanip.plan_hit(r, ttmanip.DEMO_HIT)
    pattern = rf"^{name}: .* is out of range; expected (a real number|an integer)"
    with pytest.raises(TtmanipError, match=pattern):
        call(p, r)


def test_a_plane_crossing_search_stops_on_ctrl_c():
    # a plane below the floor, never reached: the spin keeps the ball up
    _stops_on_ctrl_c(
        HIGH_BALL,
        "ttmanip._ttmanip.ball_crossing",
        "ttmanip.ball.crossing(s, t_max=1.9e5, point=[0.0, 0.0, -5.0], normal=[0.0, 0.0, 1.0])",
    )


# -- issue 29, second sweep (h29): escapes found by a new user's sweep of the newer API -----------


def _cli(*args, timeout: float = CAP_SECONDS) -> subprocess.CompletedProcess:
    """``ttmanip ARGS`` in a capped subprocess (a hang fails the test)."""
    try:
        return subprocess.run(
            [sys.executable, "-m", "ttmanip.cli", *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout,
            preexec_fn=_limits,
            cwd="/tmp",
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"hung for more than {timeout} s: ttmanip {args}")


def _bad_input(r: subprocess.CompletedProcess, *fragments: str) -> None:
    """Exit 1 (bad input) with a one-line message naming ``fragments``, no traceback."""
    assert r.returncode == 1, (r.returncode, r.stderr[-2000:])
    assert "Traceback" not in r.stderr, r.stderr[-3000:]
    for f in fragments:
        assert f in r.stderr, r.stderr


def _flights(folder, rows: str) -> None:
    folder.mkdir()
    for i in range(4):
        (folder / f"{i}.json").write_text('{"ob": [' + ",".join([rows] * 30) + "]}")


def test_ball_fit_reads_flights_within_limits(tmp_path):
    import zipfile

    # a zip bomb: 20 MiB of spaces inflate from a few kB; refused before it is inflated whole
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z, z.open("a.json", "w") as f:
        f.write(b'{"ob": [[0, 0, 0] ')
        for _ in range(20):
            f.write(b" " * (1 << 20))
        f.write(b"]}")
    _bad_input(_cli("ball", "fit", bomb, "--out", tmp_path / "o"), "a.json", "16 MiB")
    deep = tmp_path / "deep"
    deep.mkdir()
    (deep / "a.json").write_text('{"ob": ' + "[" * 100000 + "]" * 100000 + "}")
    _bad_input(_cli("ball", "fit", deep, "--out", tmp_path / "o"), "nested 100001 deep")
    _flights(tmp_path / "bigint", "[1" + "0" * 400 + ", 0, 1]")
    _bad_input(_cli("ball", "fit", tmp_path / "bigint", "--out", tmp_path / "o"))
    _flights(tmp_path / "bools", "[true, false, true]")
    _bad_input(_cli("ball", "fit", tmp_path / "bools", "--out", tmp_path / "o"), "ob")
    from ttmanip import ball_fit

    with pytest.raises(TtmanipError, match="16 MiB"):
        ball_fit.read_flights(bomb)


def test_rally_balls_and_telemetry_files_are_read_within_limits(tmp_path):
    _bad_input(_cli("rally", "--balls", "/dev/zero", "--out", tmp_path / "r"), "16 MiB")
    _bad_input(_cli("telemetry", "/dev/zero", "--rerun", tmp_path / "t.rrd"), "16 MiB")
    bad = tmp_path / "tele.csv"
    bad.write_text("channel,t,latency_us\nvcan0,abc,1\n")
    _bad_input(_cli("telemetry", bad, "--rerun", tmp_path / "t.rrd"), "line 2", "abc")
    bad.write_bytes(b"channel,t,latency_us\nvcan0,1\xff,1\n")
    _bad_input(_cli("telemetry", bad, "--rerun", tmp_path / "t.rrd"), "UTF-8")


def test_rally_incoming_balls_of_complex_or_bool_dtype_are_refused():
    inc = np.tile([0, -1.5, 0, 0.3, 4, 0, 1, 0, 0, 0.0], (3, 1))
    for bad in (inc.astype(complex), inc.astype(bool)):
        with pytest.raises(TtmanipError, match="incoming"):
            ttmanip.rally(3, incoming=bad)


def test_link_addresses_and_wire_times_are_checked():
    with pytest.raises(TtmanipError, match="address: the port"):
        ttmanip.ctl.Link(("127.0.0.1", 99999))
    with pytest.raises(TtmanipError, match="address"):
        ttmanip.ctl.Link("127.0.0.1:5005")
    h = ttmanip.DEMO_HIT
    # a NaN time encoded, and the controller dropped the datagram without an answer
    with pytest.raises(ttmanip.NonFiniteError, match="t_hit"):
        ttmanip._ttmanip.wire_hit(1, 0, float("nan"), h.pose, h.twist, 1, 0.0)
    with pytest.raises(ttmanip.NonFiniteError, match="camera_time"):
        ttmanip._ttmanip.wire_observation(1, float("inf"), [0.0, 0.0, 1.0], 1, 0.0)


def test_hil_arguments_are_checked_before_a_controller_starts(tmp_path):
    _bad_input(_cli("hil", "--n", "1", "--connect", "127.0.0.1:99999", "--out", tmp_path / "h"), "--connect")
    r = _cli("hil", "--n", str(10**12), "--ttctl", "/nonexistent/ttctl", "--out", tmp_path / "h")
    _bad_input(r, "--n")
    _bad_input(_cli("hil", "--n", "1", "--seed", "-1", "--out", tmp_path / "h"), "--seed")


def test_cli_ik_prints_only_branches_within_the_joint_limits():
    # d2 = 4.9 m on a ±0.6 m axis was printed with exit 0
    _bad_input(_cli("ik", "gantry6", "--centre", "5,0,0", "--normal", "0,-1,0"), "reach", "d2")
    _bad_input(_cli("ik", "gantry6", "--centre", "1e300,0,0", "--normal", "0,-1,0"), "reach")


def test_the_ball_speed_in_a_refusal_is_the_speed_given():
    with pytest.raises(TtmanipError, match=r"‖velocity‖ = 1e200 m/s"):
        ttmanip.ball.predict(ttmanip.ball.state([0, 0, 1], [1e200, 0, 0]), [0.1])


def test_a_tampered_drive_sim_pickle_is_checked_and_its_replay_stops_on_ctrl_c():
    sim = ttmanip.DriveSim(ttmanip.robots.gantry6())
    sim.tick(10)
    f, (state,) = sim.__reduce__()
    chain, options, period, journal = state
    with pytest.raises(TtmanipError, match="setpoint_period"):
        f((chain, options, float("nan"), journal))
    # 10¹⁵ ticks in the journal: hours of replay, stopped by Ctrl-C (it ignored the signal)
    _stops_on_ctrl_c(
        """
        import ttmanip
        f, ((chain, options, period, journal),) = ttmanip.DriveSim(ttmanip.robots.gantry6()).__reduce__()
        """,
        "f",
        'f((chain, options, period, {"reset": None, "calls": [{"Tick": 10**15}]}))',
    )


CTL_AXES = '[[channel]]\ninterface = "vcan0"\n[[channel.axis]]\nnode = 1\njoint = 0\n'


@pytest.mark.parametrize(
    ("config", "trajectory", "extra", "fragment"),
    [
        # joint = 10¹² aborted `ttctl --demo` (a demo motion of 10¹² joints allocated)
        (
            '[[channel]]\ninterface = "vcan0"\n[[channel.axis]]\nnode = 1\njoint = 1000000000000\n',
            None,
            ["--demo"],
            "joint",
        ),
        ("approach_s = 1e300\n" + CTL_AXES, None, [], "approach_s"),
        (CTL_AXES + 'device_file = "/dev/zero"\n', None, [], "16 MiB"),
        # an axis beyond the file's joints held still while the motion "completed"
        (
            CTL_AXES + "[[channel.axis]]\nnode = 2\njoint = 1\n",
            "0,0,0.1,0,0\n1,0.1,0.1,0,0\n",
            [],
            "follows joint 1",
        ),
        # targets beyond the drive's 32-bit integers faulted at the first cycle
        (CTL_AXES, "0,1e300,0,0,0\n1,1e300,0,0,0\n", [], "position"),
        # a position jump its velocity column does not show, and a subnormal time step: the
        # drives refused them at run time (a target step beyond their limit), --check passed them
        (CTL_AXES, "0,0,0,0,0\n0.001,0,0,0,0\n0.002,0.5,0,0,0\n", [], "line 4: q1 moves by 5e-1 from line 3"),
        (CTL_AXES, "0,0,0,0,0\n5e-324,0,0,0,0\n", [], "line 3: t steps by 5e-324 s"),
        # times too coarse for the cycle: at 1e17 s float64 times are 16 s apart
        (CTL_AXES, "1e17,0,0,0,0\n1.0000000000001e17,0,0,0,0\n", [], "nearer origin"),
    ],
)
def test_ttctl_checks_configurations_and_trajectories_before_running(
    tmp_path, config, trajectory, extra, fragment
):
    exe = _binary("ttctl")
    if exe is None:
        pytest.skip("ttctl is not built (cargo build -p ttcan)")
    cfg = tmp_path / "ctl.toml"
    cfg.write_text(config)
    args = [exe, "--config", str(cfg), "--check", *extra]
    if trajectory is not None:
        (tmp_path / "t.csv").write_text("t,q1,qd1,qdd1,tau1\n" + trajectory)
        args += ["--trajectory", str(tmp_path / "t.csv")]
    r = subprocess.run(args, capture_output=True, text=True, timeout=CAP_SECONDS, preexec_fn=_limits)
    assert r.returncode == 1, (r.returncode, r.stderr[-2000:])
    assert fragment in r.stderr and "panicked" not in r.stderr, r.stderr


def test_ttdrive_sim_refuses_a_sync_period_it_cannot_step():
    exe = _binary("ttdrive-sim")
    if exe is None:
        pytest.skip("ttdrive-sim is not built (cargo build -p ttcan)")
    for period in ("1e300", "1e-300"):
        r = subprocess.run(
            [exe, "--channel", "stdio:1", "--period", period, "--duration", "1"],
            capture_output=True,
            text=True,
            timeout=CAP_SECONDS,
            preexec_fn=_limits,
            input="",
        )
        assert r.returncode == 1 and "--period" in r.stderr, (r.returncode, r.stderr)


def test_a_copy_of_a_huge_broadcast_view_is_refused_before_it_is_made():
    # np.broadcast_to costs 0 bytes; the float64 copy the binding needs would take 48 GB
    r = ttmanip.robots.gantry6()
    q = np.broadcast_to(np.zeros(6, dtype=np.float32), (10**9, 6))
    with pytest.raises(TtmanipError, match=r"asks for 6\.0+e9 items of 8 bytes.*512 MiB"):
        r.fk(q)
