"""Robot files (TOML) and URDF: round trips, and clear errors for bad files."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
import ttmanip
from conftest import BUILTINS, random_q
from ttmanip.pipeline import racket_mount


@pytest.mark.parametrize("name", BUILTINS)
def test_urdf_round_trip_keeps_fk_and_limits(name, tmp_path):
    robot = ttmanip.Robot.builtin(name)
    path = tmp_path / f"{name}.urdf"
    path.write_text(robot.to_urdf())
    back = ttmanip.Robot.from_urdf(path, "base_link", "tool")
    assert back.dof == robot.dof
    assert back.joint_names == robot.joint_names
    q = random_q(robot, 300, seed=4)
    np.testing.assert_allclose(back.fk(q), robot.fk(q), atol=1e-12)
    np.testing.assert_allclose(back.jacobian(q), robot.jacobian(q), atol=1e-12)
    np.testing.assert_allclose(back.limits, robot.limits)
    np.testing.assert_allclose(back.velocity_limits, robot.velocity_limits)
    # and a second export of the imported robot is read the same way again
    again = ttmanip.Robot.from_urdf_string(back.to_urdf(), "base_link", "tool")
    np.testing.assert_allclose(again.fk(q), robot.fk(q), atol=1e-12)


@pytest.mark.parametrize("name", BUILTINS)
def test_robot_file_round_trip(name, tmp_path):
    robot = ttmanip.Robot.builtin(name)
    path = tmp_path / f"{name}.toml"
    path.write_text(robot.to_toml())
    back = ttmanip.Robot.from_file(path)
    q = random_q(robot, 300, seed=6)
    np.testing.assert_array_equal(back.fk(q), robot.fk(q))
    np.testing.assert_array_equal(back.limits, robot.limits)


def test_robot_file_in_seed_units_matches_builtin():
    # Seed 000 Table 1 typed as printed (mm, degrees) gives the built-in mobile8.
    rows = [
        (0, 0, 0, 90),
        (90, 0, 68, 0),
        (90, 0, 5, 180),
        (90, 0, 156, 180),
        (90, 0, 325, 90),
        (90, 0, -5, 180),
        (0, 1.2, 0, 180),
        (90, 0, 0, 90),
    ]
    text = 'name = "table1"\nconvention = "modified"\nunits = { length = "mm", angle = "deg" }\n'
    for i, (alpha, a, d, theta) in enumerate(rows):
        kind = "prismatic" if i == 0 else "revolute"
        text += f'[[joint]]\nname = "j{i + 1}"\ntype = "{kind}"\n'
        text += f"dh = {{ a = {a}, alpha = {alpha}, d = {d}, theta = {theta} }}\n"
    robot = ttmanip.Robot.from_toml(text)
    ref = ttmanip.robots.mobile8()
    q = random_q(ref, 100)
    # units apply to the description; the joint variable q is always SI (m for the prismatic joint)
    np.testing.assert_allclose(robot.fk(q), ref.fk(q), atol=1e-14)


URDF_HEAD = '<?xml version="1.0"?>\n<robot name="t">\n'


def _urdf(body: str) -> str:
    return URDF_HEAD + textwrap.dedent(body) + "</robot>\n"


def test_urdf_import_folds_fixed_joints_and_general_axes():
    text = _urdf(
        """
        <link name="world"/><link name="a"/><link name="b"/><link name="c"/><link name="tip"/>
        <joint name="mount" type="fixed"><parent link="world"/><child link="a"/>
          <origin xyz="0 0 0.5" rpy="0 0 0.3"/></joint>
        <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
          <origin xyz="0.1 0 0" rpy="0.2 0 0"/><axis xyz="0 1 1"/>
          <limit lower="-1" upper="1" effort="10" velocity="2"/></joint>
        <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/>
          <origin xyz="0 0.2 0" rpy="0 0.4 0"/><axis xyz="1 0 0"/>
          <limit lower="0" upper="0.3" effort="10" velocity="1"/></joint>
        <joint name="flange" type="fixed"><parent link="c"/><child link="tip"/>
          <origin xyz="0 0 0.05" rpy="0 0 0"/></joint>
        """
    )
    robot = ttmanip.Robot.from_urdf_string(text, "world", "tip")
    assert robot.dof == 2 and robot.joint_types == ["revolute", "prismatic"]

    def rot(axis, angle):
        axis = np.asarray(axis, float) / np.linalg.norm(axis)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k

    def tf(r=None, p=(0, 0, 0)):
        t = np.eye(4)
        t[:3, :3], t[:3, 3] = np.eye(3) if r is None else r, p
        return t

    q = np.array([0.7, 0.12])
    expected = (
        tf(rot([0, 0, 1], 0.3), [0, 0, 0.5])
        @ tf(rot([1, 0, 0], 0.2), [0.1, 0, 0])
        @ tf(rot([0, 1, 1], q[0]))
        @ tf(rot([0, 1, 0], 0.4), [0, 0.2, 0])
        @ tf(p=np.array([1.0, 0, 0]) * q[1])
        @ tf(p=[0, 0, 0.05])
    )
    np.testing.assert_allclose(robot.fk(q), expected, atol=1e-14)


@pytest.mark.parametrize(
    ("body", "base", "tip", "words"),
    [
        ('<link name="a"/><link name="b"/>', "a", "b", "not connected"),
        ('<link name="a"/>', "a", "nope", "no link named 'nope'"),
        (
            '<link name="a"/><link name="b"/><joint name="free" type="floating">'
            '<parent link="a"/><child link="b"/></joint>',
            "a",
            "b",
            "Floating",
        ),
        (
            '<link name="a"/><link name="b"/><joint name="slide" type="planar">'
            '<parent link="a"/><child link="b"/></joint>',
            "a",
            "b",
            "Planar",
        ),
        (
            '<link name="a"/><link name="b"/><joint name="weld" type="fixed">'
            '<parent link="a"/><child link="b"/></joint>',
            "a",
            "b",
            "no revolute or prismatic joint",
        ),
    ],
)
def test_bad_urdf_raises_robot_file_error(body, base, tip, words):
    with pytest.raises(ttmanip.RobotFileError, match=words):
        ttmanip.Robot.from_urdf_string(_urdf(body), base, tip)


def test_malformed_xml_and_missing_files(tmp_path):
    with pytest.raises(ttmanip.RobotFileError, match="cannot parse"):
        ttmanip.Robot.from_urdf_string("<robot><link", "a", "b")
    with pytest.raises(ttmanip.RobotFileError, match="No such file"):
        ttmanip.Robot.from_urdf(tmp_path / "missing.urdf", "a", "b")
    with pytest.raises(ttmanip.RobotFileError, match="No such file"):
        ttmanip.Robot.from_file(tmp_path / "missing.toml")
    with pytest.raises(ttmanip.RobotFileError, match="from_urdf"):
        ttmanip.Robot.from_file(tmp_path / "robot.urdf")


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ('name = "x"\n[[joint]]\nname = "a"\ntype = "revolute"\n', "exactly one of 'dh' or 'origin'"),
        ('name = "x"\n[[joint]]\nname = "a"\ntype = "revolute"\ndh = { a = 1 }\n', "DH convention unknown"),
        ('name = "x"\n[[joint]]\nname = "a"\ntype = "hinge"\n', "unknown variant"),
        (
            'name = "x"\nconvention = "standard"\n[[joint]]\nname = "a"\ntype = "revolute"\n'
            "dh = { a = 1, b = 2 }\n",
            "unknown field",
        ),
        ('name = "x"\njoint = []\n', "no joint"),
        (
            'name = "x"\nconvention = "standard"\n[[joint]]\nname = "a"\ntype = "revolute"\ndh = {}\n'
            "limits = { lower = 1, upper = 0 }\n",
            "lower ≤ upper",
        ),
        (
            'name = "x"\nconvention = "standard"\n[[joint]]\nname = "a"\ntype = "revolute"\ndh = {}\n'
            "inertial = { mass = -1, com = [0, 0, 0], inertia = [1, 1, 1, 0, 0, 0] }\n",
            "mass must be > 0",
        ),
        (
            'name = "x"\nconvention = "standard"\n[[joint]]\nname = "a"\ntype = "revolute"\ndh = {}\n'
            "inertial = { mass = 1, com = [0, 0, 0], inertia = [1, 1, 3, 0, 0, 0] }\n",
            "triangle inequality",
        ),
        ("this is not toml", "expected"),
    ],
)
def test_bad_robot_files_raise_clear_errors(text, words):
    with pytest.raises(ttmanip.TtmanipError, match=words):
        ttmanip.Robot.from_toml(text)


@pytest.mark.parametrize("name", BUILTINS)
def test_repository_robot_files_match_the_builtins(name):
    """robots/NAME.{toml,urdf} are what `ttmanip export` writes today (regenerate them if not)."""
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent / "robots"
    robot = ttmanip.Robot.builtin(name)
    toml_text = "".join(
        line
        for line in (root / f"{name}.toml").read_text().splitlines(keepends=True)
        if not line.startswith("#")
    )
    assert toml_text == robot.to_toml(), (
        f"robots/{name}.toml is stale: ttmanip export {name} --out robots/{name}.toml"
    )
    assert (root / f"{name}.urdf").read_text() == robot.to_urdf()
    from_file = ttmanip.Robot.from_file(root / f"{name}.toml")
    q = random_q(robot, 50)
    np.testing.assert_array_equal(from_file.fk(q), robot.fk(q))


def test_cli_export_and_info(tmp_path, capsys):
    from ttmanip.cli import main

    assert main(["export", "arm4", "--out", str(tmp_path / "arm4.urdf")]) == 0
    back = ttmanip.Robot.from_urdf(tmp_path / "arm4.urdf", "base_link", "tool")
    np.testing.assert_allclose(
        back.fk([0.1, 0.2, 0.3, 0.4]), ttmanip.robots.arm4().fk([0.1, 0.2, 0.3, 0.4]), atol=1e-12
    )
    assert main(["export", "arm4", "--out", str(tmp_path / "arm4.json")]) == 1
    assert main(["info", "gantry6"]) == 0
    assert "theta6" in capsys.readouterr().out


def test_urdf_round_trip_of_a_robot_without_any_limits():
    # no position, speed or effort limits: continuous/prismatic joints whose <limit> says "not given"
    arm = ttmanip.Robot.from_dh(
        a=[0, 0.3, 0.25], alpha=[np.pi / 2, 0, 0], d=[0.2, 0, 0], theta=[0, 0, 0], types="RPR"
    )
    back = ttmanip.Robot.from_urdf_string(arm.to_urdf(), "base_link", "tool")
    q = np.array([0.3, 0.1, -0.7])
    np.testing.assert_allclose(back.fk(q), arm.fk(q), atol=1e-14)
    assert np.all(np.isinf(back.limits)) and np.all(np.isinf(back.velocity_limits))
    assert np.all(np.isinf(back.effort_limits))


def test_racket_mount_and_ready_pose_are_data_of_the_robot(tmp_path):
    """Issue 30: what a robot carries is read from its file, never looked up by its name."""
    m8 = ttmanip.robots.mobile8()
    np.testing.assert_array_equal(m8.ready, ttmanip.robots.mobile8_start())
    np.testing.assert_array_equal(ttmanip.robots.gantry6().ready, [0, 0, 0, 0.6, 0.6, 0])
    renamed = ttmanip.Robot.from_toml(m8.to_toml().replace('name = "mobile8"', 'name = "copy"', 1))
    assert renamed.name == "copy"
    np.testing.assert_allclose(racket_mount(renamed), racket_mount(m8), atol=1e-15)
    np.testing.assert_array_equal(renamed.ready, m8.ready)
    # URDF carries neither: the tool frame and the mid range, until the robot is given them.
    from_urdf = ttmanip.Robot.from_urdf_string(m8.to_urdf(), "base_link", "tool")
    np.testing.assert_array_equal(racket_mount(from_urdf), np.eye(4))
    again = from_urdf.with_racket(racket_mount(m8)).with_ready(m8.ready)
    np.testing.assert_array_equal(racket_mount(again), racket_mount(m8))
    np.testing.assert_array_equal(again.ready, m8.ready)
    lo, hi = m8.limits.T
    with pytest.raises(ttmanip.TtmanipError, match="ready"):
        m8.with_ready(np.where(np.isfinite(hi), hi + 1.0, 0.0))
    with pytest.raises(ttmanip.ShapeError, match="q"):
        m8.with_ready([0.0, 1.0])
    assert ttmanip.robots.NAMES == ("mobile8", "gantry6", "arm4", "ur5")
    assert all(ttmanip.robots.builtin(n).name == n for n in ttmanip.robots.NAMES)
