"""The Python boundary (issue 14): every case of the issue, each failing before the fix.

Layouts: any array numpy can hand over gives the result of the aligned C-contiguous float64 one.
Panics: become ``InternalError`` (a ``TtmanipError``), never ``PanicException``. Arguments: named
as typed. Overflow: ``NumericalError`` naming the call. Rotations: float32 accepted to its
precision. Empty batches: empty results. URDF: loops refused.
"""

from __future__ import annotations

import numpy as np
import pytest
import ttmanip
from ttmanip import _ttmanip

G6 = ttmanip.Robot.builtin("gantry6")
M8 = ttmanip.Robot.builtin("mobile8")
Q6 = np.array([0.1, -0.05, 0.3, 0.4, -0.5, 0.2])
Q8 = ttmanip.robots.mobile8_start()


def unaligned(a: np.ndarray) -> np.ndarray:
    """The issue's reproduction: the same values in a buffer at an odd offset."""
    a = np.asarray(a, dtype=float)
    buf = bytearray(a.nbytes + 1)
    u = np.ndarray(a.shape, np.float64, buf, offset=1)
    u[...] = a
    assert not u.flags.aligned and u.flags.c_contiguous
    return u


def swapped(a):
    return np.asarray(a, dtype=float).astype(">f8")


def strided(a):
    a = np.asarray(a, dtype=float)
    return np.repeat(a[..., None], 2, axis=-1)[..., 0]


def fortran(a):
    return np.asfortranarray(np.asarray(a, dtype=float))


def readonly(a):
    b = np.array(a, dtype=float)
    b.flags.writeable = False
    return b


LAYOUTS = [unaligned, swapped, strided, fortran, readonly]

T6 = G6.fk(Q6)
CALLS = {
    "fk": lambda f: G6.fk(f(Q6)),
    "fk batch": lambda f: G6.fk(f(np.array([Q6, 2 * Q6]))),
    "fk_all": lambda f: G6.fk_all(f(Q6)),
    "jacobian": lambda f: G6.jacobian(f(Q6)),
    "task_jacobian": lambda f: M8.task_jacobian(f(Q8)),
    "ik": lambda f: G6.ik(f(T6)).q,
    "ik_all": lambda f: G6.ik_all(f(T6)),
    "ik_nearest": lambda f: G6.ik_nearest(f(T6), f(Q6)),
    "joint_velocity": lambda f: G6.joint_velocity(f(Q6), f(np.arange(6.0) * 0.1)),
    "rnea": lambda f: G6.rnea(f(Q6), f(Q6), f(Q6)),
    "inverse_dynamics": lambda f: G6.inverse_dynamics(f(Q6), f(Q6), f(Q6)),
    "forward_dynamics": lambda f: G6.forward_dynamics(f(Q6), f(Q6), f(Q6)),
    "mass_matrix": lambda f: G6.mass_matrix(f(Q6)),
    "gravity": lambda f: G6.gravity(f(Q6)),
    "coriolis": lambda f: G6.coriolis(f(Q6), f(Q6)),
    "friction": lambda f: G6.friction(f(Q6)),
    "kinetic_energy": lambda f: G6.kinetic_energy(f(Q6), f(Q6)),
    "potential_energy": lambda f: G6.potential_energy(f(Q6)),
    "DiffDrive.body_velocity": lambda f: ttmanip.DiffDrive(0.1, 0.5).body_velocity(f([1.0, 2.0])),
    "DiffDrive.integrate": lambda f: ttmanip.DiffDrive(0.1, 0.5).integrate(
        f([0.0, 0.0, 0.1]), f([1.0, 2.0]), 0.1
    ),
    "wls_step": lambda f: ttmanip.wls_step(M8, f(Q8), f(np.full(5, 0.01))),
    "task_line": lambda f: ttmanip.task_line(f(np.zeros(5)), f(np.full(5, 0.1)), 0.1, rate_hz=100.0),
    "track": lambda f: (
        ttmanip.track(
            M8,
            f(Q8),
            f(
                ttmanip.task_line(
                    M8.task_coordinates(Q8), M8.task_coordinates(Q8) + 0.01, 0.05, rate_hz=200.0
                )[0]
            ),
            rate_hz=200.0,
        ).q
    ),
}


def same(a, b):
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b)
        for x, y in zip(a, b, strict=False):
            same(x, y)
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda f: f.__name__)
@pytest.mark.parametrize("call", sorted(CALLS))
def test_every_layout_gives_the_contiguous_result(call, layout):
    """Unaligned (the issue's panic), byte-swapped, strided, Fortran and read-only inputs."""
    reference = CALLS[call](lambda a: np.ascontiguousarray(a, dtype=float))
    same(CALLS[call](layout), reference)


def test_the_issue_reproduction_no_longer_panics():
    b = bytearray(49)
    u = np.ndarray((6,), np.float64, b, offset=1)
    u[:] = 0.1
    np.testing.assert_array_equal(ttmanip.robots.gantry6().fk(u), G6.fk(np.full(6, 0.1)))


def test_float32_and_int_inputs_equal_their_float64_values():
    q32 = Q6.astype(np.float32)
    np.testing.assert_array_equal(G6.fk(q32), G6.fk(q32.astype(np.float64)))
    np.testing.assert_array_equal(
        G6.jacobian(np.array([0, 0, 1, 1, 0, 0])), G6.jacobian(np.array([0.0, 0, 1, 1, 0, 0]))
    )


def test_a_panic_becomes_internal_error_not_panic_exception():
    with pytest.raises(ttmanip.InternalError, match="boom") as e:
        _ttmanip._panic_for_test("boom")
    assert isinstance(e.value, ttmanip.TtmanipError) and isinstance(e.value, Exception)
    _ttmanip._panic_for_test("")  # no panic, no error


def test_every_binding_block_is_guarded():
    """One line per #[pymethods] block / #[pyfunction]: the guard cannot be forgotten silently."""
    import pathlib

    src = pathlib.Path(__file__).resolve().parents[1] / "crates" / "ttkin-py" / "src"
    for path in sorted(src.glob("*.rs")):
        lines = path.read_text().splitlines()
        for i, line in enumerate(lines):
            if line.strip() in ("#[pymethods]", "#[pyfunction]"):
                assert lines[i - 1].strip() == "#[ttkin_py_guard::guarded]", (
                    f"{path.name}:{i + 1} not guarded"
                )


# ---------------------------------------------------------------- unreachable: a status


def unreachable_pose():
    t = np.eye(4)
    t[:3, 3] = [5.0, 5.0, 5.0]
    return t


def test_analytic_ik_of_an_unreachable_pose_is_a_status():
    r = G6.ik(unreachable_pose(), method="analytic")
    assert r.success is False and r.status == "unreachable"
    with pytest.raises(ttmanip.UnreachableError):
        G6.ik(unreachable_pose(), method="analytic", raise_on_failure=True)


def test_one_unreachable_pose_does_not_fail_the_batch():
    r = G6.ik(np.array([unreachable_pose(), T6]), method="analytic")
    assert list(r.success) == [False, True] and r.status == ["unreachable", "solved"]
    np.testing.assert_allclose(G6.fk(r.q[1]), T6, atol=1e-9)


# ---------------------------------------------------------------- arguments named, none ignored


def family_pose():
    """A gantry pose on the s45 = 0 family, where the hint picks θ3."""
    q = Q6.copy()
    q[3], q[4] = 0.7, -0.7
    return G6.fk(q)


def test_ik_all_batch_uses_the_hint():
    t = family_pose()
    hint = np.array([0.0, 0.0, 0.9, 0.0, 0.0, 0.0])
    single = G6.ik_all(t, hint=hint)
    q, count = G6.ik_all(np.array([t, t]), hint=hint)
    assert list(count) == [len(single)] * 2
    np.testing.assert_allclose(q[0, : len(single)], single, atol=1e-12)
    plain, _ = G6.ik_all(np.array([t, t]))
    assert not np.allclose(plain[0, : len(single)], single), "the hint must change the branches here"
    with pytest.raises(ttmanip.NonFiniteError, match="hint"):
        G6.ik_all(np.array([t, t]), hint=np.full(6, np.nan))


@pytest.mark.parametrize(
    "kw",
    [
        {"epsilon": np.inf},
        {"lambda_max": np.inf},
        {"epsilon": np.inf, "lambda_max": np.inf},
        {"lambda_max": -1.0},
        {"epsilon": 0.0},
        {"epsilon": np.nan},
    ],
)
def test_joint_velocity_refuses_meaningless_thresholds(kw):
    """One check, the core's: epsilon finite and > 0, lambda_max finite and ≥ 0 (the binding's own
    epsilon ≥ 0 check, which disagreed with the core's > 0, is gone: issue 30)."""
    name = next(iter(kw))
    with pytest.raises(ttmanip.TtmanipError, match=name):
        G6.joint_velocity(Q6, np.ones(6), **kw)


def test_wls_step_outside_the_joint_limits_is_refused():
    q = Q8.copy()
    q[2] = M8.limits[2, 1] + 0.5
    with pytest.raises(ttmanip.TtmanipError, match=r"q\[2\].*outside its joint limits"):
        ttmanip.wls_step(M8, q, np.full(5, 0.01))
    ttmanip.wls_step(M8, q, np.full(5, 0.01), weights="none")  # no limit weights: a plain step


def test_undamped_wls_step_at_a_stretched_arm_singularity_raises():
    # A 3R arm (yaw, then two pitch links of 1 m), fully stretched: no velocity along the arm.
    arm = ttmanip.Robot.from_dh([0.0, 1.0, 1.0], [np.pi / 2, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    q = np.zeros(3)
    with pytest.raises(ttmanip.SingularError):
        ttmanip.wls_step(arm, q, np.array([0.1, 0.0, 0.0]), task="position", lambda_max=0.0)
    step = ttmanip.wls_step(arm, q, np.array([0.1, 0.0, 0.0]), task="position", lambda_max=0.05)
    assert np.isfinite(step).all()


@pytest.mark.parametrize("name", ["max_iterations", "max_restarts", "seed"])
def test_negative_counts_are_ttmanip_errors_naming_the_argument(name):
    with pytest.raises(ttmanip.TtmanipError, match=name):
        G6.ik(T6, method="numeric", **{name: -1})


def test_float_arguments_are_named_as_typed():
    with pytest.raises(ttmanip.NonFiniteError, match="racket_offset"):
        M8.ik(M8.fk(Q8), task="racket5", racket_offset=np.nan)
    with pytest.raises(ttmanip.TtmanipError, match=r"torque_constant\[4\]"):
        G6.with_drives(np.full(6, 10.0), torque_constant=[1, 1, 1, 1, np.inf, 1])


# ---------------------------------------------------------------- finite in, finite out


@pytest.mark.parametrize(
    "call",
    [
        lambda v: G6.rnea(Q6, np.full(6, v), np.zeros(6)),
        lambda v: G6.inverse_dynamics(Q6, np.full(6, v), np.zeros(6)),
        lambda v: G6.forward_dynamics(Q6, np.full(6, v), np.zeros(6)),
        lambda v: G6.coriolis(Q6, np.full(6, v)),
        lambda v: G6.nonlinear_effects(Q6, np.full(6, v)),
        lambda v: G6.rnea(np.array([Q6]), np.full((1, 6), v), np.zeros((1, 6))),
    ],
    ids=["rnea", "inverse_dynamics", "forward_dynamics", "coriolis", "nonlinear_effects", "rnea batch"],
)
@pytest.mark.parametrize("speed", [1e160, 1e200, 1e300])
def test_overflow_is_a_numerical_error_not_nan(call, speed):
    with pytest.raises(ttmanip.NumericalError, match="not finite"):
        call(speed)


def test_wheel_speeds_overflow_names_the_call():
    with pytest.raises(ttmanip.NumericalError, match="DiffDrive.wheel_speeds"):
        ttmanip.DiffDrive(0.1, 0.5).wheel_speeds(1e308, 1e308)


# ---------------------------------------------------------------- rotations and empty batches


def test_float32_rotation_is_accepted_to_its_precision():
    t32 = T6.astype(np.float32)
    r = np.asarray(t32[:3, :3], dtype=float)
    assert np.abs(r.T @ r - np.eye(3)).max() > 1e-9  # the old test refused it
    res = G6.ik(t32)
    assert res.success
    np.testing.assert_allclose(G6.fk(res.q), T6, atol=1e-6)
    res_b = G6.ik(np.array([t32, t32]))
    assert list(res_b.success) == [True, True]
    q, count = G6.ik_all(np.array([t32, t32]))
    assert list(count) == [len(G6.ik_all(t32))] * 2


def test_float32_tolerance_is_not_a_blank_cheque():
    bad = T6.astype(np.float32)
    bad[0, 0] += 1e-3
    with pytest.raises(ttmanip.TtmanipError, match="orthonormal"):
        G6.ik(bad)
    near = T6.copy()
    near[0, 0] += 1e-8  # float64 keeps the 1e-9 test
    with pytest.raises(ttmanip.TtmanipError, match="orthonormal"):
        G6.ik(near)


@pytest.mark.parametrize(
    "call, shape",
    [
        (lambda: G6.fk(np.zeros((0, 6))), (0, 4, 4)),
        (lambda: G6.fk_all(np.zeros((0, 6))), (0, 6, 4, 4)),
        (lambda: G6.jacobian(np.zeros((0, 6))), (0, 6, 6)),
        (lambda: G6.mass_matrix(np.zeros((0, 6))), (0, 6, 6)),
        (lambda: G6.gravity(np.zeros((0, 6))), (0, 6)),
        (lambda: G6.rnea(np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 6))), (0, 6)),
        (lambda: G6.forward_dynamics(np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 6))), (0, 6)),
        (lambda: G6.ik(np.zeros((0, 4, 4))).q, (0, 6)),
        (lambda: G6.ik_all(np.zeros((0, 4, 4)))[0], (0, 4, 6)),
        (lambda: ttmanip.traj.cubic(np.zeros(6), np.ones(6), 1.0).sample(np.zeros(0))[0], (0, 6)),
    ],
)
def test_an_empty_batch_gives_an_empty_result(call, shape):
    assert call().shape == shape


# ---------------------------------------------------------------- small arrays copied, large borrowed


@pytest.mark.parametrize("rows", [1, 42, 43, 100])
def test_copied_and_borrowed_inputs_give_the_same_results(rows):
    """Arrays of at most 256 values are copied when read, larger ones borrowed (gantry6: 42 rows
    are 252 values, 43 are 258): a batch on either side equals the rows one at a time, and the
    caller's arrays are left as they were."""
    rng = np.random.default_rng(rows)
    q, qd, qdd = (rng.uniform(-0.5, 0.5, (rows, 6)) for _ in range(3))
    before = [a.copy() for a in (q, qd, qdd)]
    tau = G6.rnea(q, qd, qdd)
    poses = G6.fk(q)
    for k in range(rows):
        assert np.array_equal(tau[k], G6.rnea(q[k], qd[k], qdd[k]))
        assert np.array_equal(poses[k], G6.fk(q[k]))
    for a, b in zip((q, qd, qdd), before, strict=True):
        assert np.array_equal(a, b)


# ---------------------------------------------------------------- files


def test_a_urdf_whose_joints_form_a_loop_is_refused():
    joint = (
        '<joint name="{0}" type="revolute"><parent link="{1}"/><child link="{2}"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )
    text = (
        '<robot name="r"><link name="a"/><link name="b"/>'
        + joint.format("ab", "a", "b")
        + joint.format("ba", "b", "a")
        + "</robot>"
    )
    with pytest.raises(ttmanip.RobotFileError, match="loop"):
        ttmanip.Robot.from_urdf_string(text, "a", "b")
