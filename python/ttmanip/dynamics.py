"""Rigid-body dynamics of a :class:`ttmanip.Robot` (Rust core ``ttkin::dynamics``).

The algorithms are methods of the robot, single configuration (n,) or batch (N, n):

- ``robot.rnea(q, qd, qdd, gravity=None, wrench=None)``: inverse dynamics (recursive Newton–Euler),
  rigid bodies plus rotor armature, no friction; ``robot.inverse_dynamics`` adds joint friction.
- ``robot.mass_matrix(q)`` (composite rigid body algorithm), ``robot.gravity(q)``,
  ``robot.coriolis(q, qd)``, ``robot.nonlinear_effects(q, qd)``.
- ``robot.forward_dynamics(q, qd, tau)``: joint accelerations, Cholesky solve of M.
- ``robot.simulate(q0, qd0, tau, dt)``: semi-implicit Euler integration.
- ``robot.torques(q, qd, qdd)`` or ``robot.torques(trajectory)``: a :class:`TorqueProfile` with
  joint torques (friction included), motor torques through the gear ratio, currents through the
  torque constant, and the effort-limit check.

Units are SI (N·m, N, kg·m², m/s²). ``gravity`` is a base-frame vector, default the robot's
own ``robot.gravity_vector`` (robot-file key ``gravity``: :data:`EARTH_GRAVITY` unless the file
says otherwise, :data:`MOBILE8_GRAVITY` for mobile8); ``wrench`` is [fx, fy, fz, mx, my, mz]
applied *to* the tool by the environment, in tool-frame axes, moment about the tool point.
Inertias and drives come from the robot file (``inertial``, ``drive``) or URDF (``<inertial>``,
``<dynamics damping friction>``), or
``robot.with_inertials`` / ``robot.with_drives``.
"""

from __future__ import annotations

import numpy as np

from . import _ttmanip
from ._ttmanip import Robot, ShapeError, TorqueProfile, TtmanipError, real_array

__all__ = ["EARTH_GRAVITY", "MOBILE8_GRAVITY", "TorqueProfile", "gantry6_example", "torque_figure"]

#: Standard gravity in a z-up base frame, m/s² (the core's ``ttkin::dynamics::EARTH_GRAVITY``).
EARTH_GRAVITY = np.array(_ttmanip.EARTH_GRAVITY)

#: Gravity for ``robots.mobile8()`` in its base frame (Table 1's frame 0), m/s²: joint 1 moves the
#: base along z0, horizontally, and the waist joint 2 turns about x0, so x0 is up (our reading of
#: seed 000, which does not say it explicitly). The robot's own fact (``Robot.gravity_vector``), read here.
MOBILE8_GRAVITY = Robot.builtin("mobile8").gravity_vector


def torque_figure(robot, t, profile: TorqueProfile, path) -> None:
    """Saves a figure of a torque profile: joint torques against time with the effort limits
    (dashed) and the motor currents, one panel per joint. ``t`` holds the N sample times (s)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = real_array(t, "t")  # the bindings' one conversion: complex and bool refused
    n = robot.dof
    if t.shape != (profile.joint.shape[0],) or profile.joint.shape[1] != n:
        raise ShapeError(
            f"t: expected shape ({profile.joint.shape[0]},) matching the profile of "
            f"{profile.joint.shape[1]} joints for this {n}-joint robot, got {t.shape}"
        )
    fig, axes = plt.subplots(n, 2, figsize=(10, 1.8 * n), sharex=True, squeeze=False)
    limits = robot.effective_effort_limits  # the robot file's or the drive's, whichever is smaller
    for i, name in enumerate(robot.joint_names):
        unit = "N" if robot.joint_types[i] == "prismatic" else "N·m"
        ax = axes[i, 0]
        ax.plot(t, profile.joint[:, i], color="C0")
        if np.isfinite(limits[i]):
            for sign in (-1, 1):
                ax.axhline(sign * limits[i], color="C3", ls="--", lw=0.8)
        ax.set_ylabel(f"{name} [{unit}]")
        axes[i, 1].plot(t, profile.current[:, i], color="C2")
        axes[i, 1].set_ylabel(f"{name} [A]")
    axes[0, 0].set_title("joint torque (dashed: effort limit)")
    axes[0, 1].set_title("motor current")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{robot.name}: torque profile, within limits: {profile.within_limits}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def gantry6_example(duration: float = 0.5, samples: int = 201):
    """The patent's step S105 on gantry6: a rest-to-rest quintic from q = 0 to
    [0.3 m, −0.2 m, 1.0, 0.5, −0.8, 1.5 rad] in ``duration`` s; returns (robot, t, profile)."""
    from . import robots, traj

    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 2 <= samples <= 10**8:
        raise TtmanipError(f"samples: expected an integer in 2..=100000000, got {samples!r}")
    try:
        duration = float(duration)
    except OverflowError:  # a Python int beyond float64 (issue 29: named, not a bare OverflowError)
        shown = str(duration)[:20]
        raise TtmanipError(f"duration: {shown}… is out of range; expected a real number (float64)") from None
    robot = robots.gantry6()
    t = np.linspace(0.0, duration, samples)
    q1 = np.array([0.3, -0.2, 1.0, 0.5, -0.8, 1.5])
    q, qd, qdd = traj.quintic(np.zeros(robot.dof), q1, duration).sample(t)
    return robot, t, robot.torques(q, qd, qdd)


if __name__ == "__main__":  # python -m ttmanip.dynamics OUT.png
    import sys

    robot, t, profile = gantry6_example()
    out = sys.argv[1] if len(sys.argv) > 1 else "torques_gantry6.png"
    torque_figure(robot, t, profile, out)
    print(f"wrote {out}: {profile}")
