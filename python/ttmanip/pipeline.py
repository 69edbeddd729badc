"""The hit pipeline of seed 002 (the gantry patent), end to end on ``robots.gantry6()``.

S101 hit parameters: racket pose (tool frame, base frame, m) and racket twist at the hit time;
S102 analytic IK: every branch, then the one nearest the ready pose within the joint limits;
S103 joint velocities q̇ = J⁻¹V (singularity-checked);
S104 a quintic hitting stroke from the ready pose to (q, q̇) at t_hit and back to rest;
S105 joint torques by inverse dynamics, motor torques and currents through the drives;
S106 one joint driven by the cascaded motor loops of ``ttmanip.motor`` along its planned motion.

:func:`run` writes the figures and a ``summary.json`` with the checks that matter: the planned
racket pose and velocity at t_hit against the request, limits, torques, following error.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import robots
from ._ttmanip import Robot

__all__ = ["HitRequest", "plan_hit", "run"]


def racket_frame(normal: np.ndarray, up_hint: np.ndarray) -> np.ndarray:
    """Rotation (3×3) whose z axis is the racket-face ``normal`` and whose x axis is as close as
    possible to ``up_hint`` (the handle direction)."""
    z = np.asarray(normal, float) / np.linalg.norm(normal)
    x = np.asarray(up_hint, float) - z * np.dot(up_hint, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


@dataclass(frozen=True)
class HitRequest:
    """Hit parameters (S101): where the racket is, how it faces, how fast it moves, and when."""

    position: tuple[float, float, float] = (0.35, -0.55, 0.05)  # tool origin, base frame, m
    normal: tuple[float, float, float] = (0.3, -1.0, -0.2)  # racket-face normal (tool z), base axes
    speed: float = 3.0  # racket speed along the normal at the hit, m/s
    t_hit: float = 0.30  # s from now
    ready: tuple[float, ...] = (0.0, 0.0, 0.0, 0.6, 0.6, 0.0)  # rest configuration (m, rad)
    handle_hint: tuple[float, float, float] = field(default=(0.0, 0.0, 1.0))

    def pose(self) -> np.ndarray:
        """The hit pose (4×4, base frame)."""
        t = np.eye(4)
        t[:3, :3] = racket_frame(np.array(self.normal), np.array(self.handle_hint))
        t[:3, 3] = self.position
        return t

    def twist(self) -> np.ndarray:
        """The racket twist at the hit [v (m/s); ω (rad/s)], base axes: pure translation along the normal."""
        z = np.asarray(self.normal, float) / np.linalg.norm(self.normal)
        return np.r_[self.speed * z, 0.0, 0.0, 0.0]


def plan_hit(robot: Robot, request: HitRequest, rate_hz: float = 1000.0) -> dict:
    """Runs S102–S105 and returns every intermediate result (arrays in SI units)."""
    from . import traj

    target = request.pose()
    ready = np.asarray(request.ready, float)
    branches = robot.ik_all(target)  # S102: every mathematical branch
    q_hit = robot.ik_nearest(target, ready)  # nearest branch within the limits
    qd_hit, info = robot.joint_velocity(q_hit, request.twist(), info=True)  # S103
    if info["singular"]:
        raise RuntimeError(f"hit configuration is singular (σ_min = {info['sigma_min']:.2e})")
    stroke = traj.stroke(robot, ready, q_hit, qd_hit, request.t_hit, ready)  # S104
    t, q, qd, qdd = stroke.trajectory.sample_rate(rate_hz)
    profile = robot.torques(q, qd, qdd)  # S105
    return {
        "target": target,
        "branches": branches,
        "q_hit": q_hit,
        "qd_hit": qd_hit,
        "sigma_min": info["sigma_min"],
        "stroke": stroke,
        "t": t,
        "q": q,
        "qd": qd,
        "qdd": qdd,
        "profile": profile,
    }


def _drive_joint(robot: Robot, plan: dict, joint: int):
    """S106: the motor cascade of ``ttmanip.motor`` drives ``joint`` along its planned motion, with
    the joint's mean reflected inertia from the mass matrix as its load."""
    from . import motor

    servo0 = motor.Servo()
    rate = servo0.rates[2]
    t = np.arange(0.0, plan["stroke"].trajectory.duration, 1.0 / rate)
    q, qd, qdd = plan["stroke"].trajectory.sample(t)
    inertia = float(np.mean(robot.mass_matrix(q[:: max(1, len(t) // 50)])[:, joint, joint]))
    servo = motor.Servo(load=motor.Load(inertia=inertia))
    response = servo.track(q[:, joint] - q[0, joint], qd[:, joint], qdd[:, joint], settle=0.05)
    return servo, response, inertia


def _figures(robot: Robot, plan: dict, response, joint: int, out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from . import motor
    from .dynamics import torque_figure

    t, q, qd = plan["t"], plan["q"], plan["qd"]
    t_hit = plan["stroke"].t_hit
    names = robot.joint_names
    units = ["m" if k == "prismatic" else "rad" for k in robot.joint_types]
    paths = []

    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, constrained_layout=True)
    for i, name in enumerate(names):
        axes[0].plot(t, q[:, i], label=f"{name} [{units[i]}]")
        axes[1].plot(t, qd[:, i], label=f"{name} [{units[i]}/s]")
    for ax in axes:
        ax.axvline(t_hit, color="k", ls=":", lw=1)
        ax.grid(alpha=0.3)
        ax.legend(ncol=3, fontsize=8)
    axes[0].set_ylabel("position")
    axes[1].set_ylabel("velocity")
    axes[1].set_xlabel("t [s]  (dotted: hit)")
    axes[0].set_title("gantry6 hitting stroke (S104): ready → hit (q, q̇) → ready")
    paths.append(out / "stroke_joints.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    poses = robot.fk(q)
    p = poses[:, :3, 3]
    k = int(np.argmin(np.abs(t - t_hit)))
    v = robot.jacobian(q[k])[:3] @ qd[k]
    fig = plt.figure(figsize=(7, 6), constrained_layout=True)
    ax = fig.add_subplot(projection="3d")
    ax.plot(p[:, 0], p[:, 1], p[:, 2], color="C0", label="racket path")
    ax.scatter(*plan["target"][:3, 3], color="C3", s=40, label="hit point")
    ax.quiver(*p[k], *(0.1 * v), color="C3", label="racket velocity ×0.1 s")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.legend()
    ax.set_title("racket (tool) path in the base frame")
    paths.append(out / "stroke_racket.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    paths.append(out / "stroke_torques.png")
    torque_figure(robot, t, plan["profile"], paths[-1])

    paths.append(out / f"drive_{names[joint]}.png")
    motor.plot(response, paths[-1], title=f"S106: {names[joint]} driven by the cascaded loops")
    return [str(p) for p in paths]


def run(out: Path, request: HitRequest | None = None, joint: int = 4) -> dict:
    """Runs the whole pipeline on gantry6, writes figures and ``summary.json`` into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    request = request or HitRequest()
    robot = robots.gantry6()
    plan = plan_hit(robot, request)
    stroke = plan["stroke"]
    q_at, qd_at, _ = stroke.trajectory.sample(stroke.t_hit)
    pose_at = robot.fk(q_at)
    twist_at = robot.jacobian(q_at) @ qd_at
    servo, response, inertia = _drive_joint(robot, plan, joint)
    figures = _figures(robot, plan, response, joint, out)
    following = np.abs(response.following_error)
    summary = {
        "hit_pose": plan["target"].tolist(),
        "ik_branches": int(np.isfinite(plan["branches"]).all(axis=1).sum()),
        "q_hit": plan["q_hit"].tolist(),
        "qd_hit": plan["qd_hit"].tolist(),
        "sigma_min_at_hit": plan["sigma_min"],
        "t_hit_requested": stroke.requested_t_hit,
        "t_hit": stroke.t_hit,
        "stroke_duration": stroke.trajectory.duration,
        "stroke_feasible": stroke.feasible,
        "hit_pose_error_m": float(np.abs(pose_at - plan["target"]).max()),
        "hit_twist_error": float(np.abs(twist_at - request.twist()).max()),
        "peak_torques": plan["profile"].peak.tolist(),
        "torques_within_limits": plan["profile"].within_limits,
        "driven_joint": robot.joint_names[joint],
        "driven_joint_load_inertia": inertia,
        "driven_joint_max_following_error_rad": float(following.max()),
        "driven_joint_fault": response.fault,
        "figures": figures,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    return summary
