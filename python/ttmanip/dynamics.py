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

Units are SI (N·m, N, kg·m², m/s²). ``gravity`` is a base-frame vector, default
:data:`EARTH_GRAVITY`; ``wrench`` is [fx, fy, fz, mx, my, mz] applied *to* the tool by the
environment, in tool-frame axes, moment about the tool point. Inertias and drives come from the
robot file (``inertial``, ``drive``) or URDF (``<inertial>``, ``<dynamics damping friction>``), or
``robot.with_inertials`` / ``robot.with_drives``.
"""

from __future__ import annotations

import numpy as np

from ._ttmanip import TorqueProfile

__all__ = ["EARTH_GRAVITY", "MOBILE8_GRAVITY", "TorqueProfile"]

#: Standard gravity in a z-up base frame, m/s².
EARTH_GRAVITY = np.array([0.0, 0.0, -9.81])

#: Gravity for ``robots.mobile8()`` in its base frame (Table 1's frame 0), m/s²: joint 1 moves the
#: base along z0, horizontally, and the waist joint 2 turns about x0, so x0 is up (our reading of
#: seed 000, which does not say it explicitly).
MOBILE8_GRAVITY = np.array([-9.81, 0.0, 0.0])
