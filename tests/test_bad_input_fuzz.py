"""Random malformed input to every array-taking Robot method: a result or a TtmanipError, never a
crash, a panic or another exception type."""

from __future__ import annotations

import numpy as np
import ttmanip
from hypothesis import given, settings
from hypothesis import strategies as st

ROBOTS = {name: ttmanip.Robot.builtin(name) for name in ("mobile8", "gantry6", "arm4", "ur5")}

values = st.sampled_from([0.0, 1.0, -2.5, 1e300, -1e-300, np.nan, np.inf, -np.inf, 3.0e5])
# random shapes, and the shapes the methods accept (so that values, not only shapes, are exercised)
shapes = st.one_of(
    st.lists(st.integers(0, 9), min_size=0, max_size=3).map(tuple),
    st.sampled_from([(8,), (6,), (4,), (3, 8), (2, 6), (5, 4), (4, 4), (2, 4, 4), (0, 6), (0, 4, 4)]),
)


@st.composite
def arrays(draw):
    shape = draw(shapes)
    size = int(np.prod(shape)) if shape else 1
    data = draw(st.lists(values, min_size=size, max_size=size))
    kind = draw(st.sampled_from(["float", "int", "list", "bool", "object"]))
    a = np.array(data, dtype=float).reshape(shape)
    if kind == "int":
        return np.clip(np.nan_to_num(a), -7, 7).astype(np.int64)
    if kind == "list":
        return a.tolist()
    if kind == "bool":
        return a > 0
    if kind == "object":
        return a.astype(object)
    return a


def call(name: str, method: str, args: list):
    robot = ROBOTS[name]
    try:
        getattr(robot, method)(*args)
    except ttmanip.TtmanipError:
        pass


@settings(max_examples=400, deadline=None)
@given(
    name=st.sampled_from(sorted(ROBOTS)),
    method=st.sampled_from(["fk", "fk_all", "jacobian", "mass_matrix", "gravity", "task_jacobian"]),
    a=arrays(),
)
def test_one_array_methods(name, method, a):
    call(name, method, [a])


@settings(max_examples=300, deadline=None)
@given(
    name=st.sampled_from(sorted(ROBOTS)),
    method=st.sampled_from(["rnea", "inverse_dynamics", "forward_dynamics"]),
    a=arrays(),
    b=arrays(),
    c=arrays(),
)
def test_three_array_methods(name, method, a, b, c):
    call(name, method, [a, b, c])


@settings(max_examples=300, deadline=None)
@given(name=st.sampled_from(sorted(ROBOTS)), t=arrays(), q=arrays())
def test_ik_and_joint_velocity(name, t, q):
    call(name, "ik", [t])
    call(name, "ik_all", [t])
    call(name, "joint_velocity", [q, t])
