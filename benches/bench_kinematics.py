"""Forward kinematics and Jacobians from Python: ttmanip beside Pinocchio and Robotics Toolbox.

All three load the same robot (ttmanip's exported URDF), evaluate the same configurations, and
must agree (checked before timing). Prints a table of per-call times (µs, median of repeats) and
batch FK throughput (configurations per second).

Run: ``.venv/bin/python benches/bench_kinematics.py`` (peers: ``pip install pin roboticstoolbox-python``).
"""

from __future__ import annotations

import os
import tempfile

import numpy as np
import ttmanip
from timing import optional_peer, per_call_us, per_item_rate, print_rows, random_configurations

pin = optional_peer("pinocchio")
try:
    import roboticstoolbox as rtb
    from roboticstoolbox.models.URDF.URDFRobot import URDF_file
except ImportError:  # pragma: no cover - optional peer
    rtb = None


def bench_robot(name: str, batch: int) -> list[tuple[str, str, str]]:
    robot = ttmanip.Robot.builtin(name)
    qs = random_configurations(robot, batch)
    q = qs[0].copy()
    rows = []
    t_ref = robot.fk(q)
    j_ref = robot.jacobian(q)

    rows.append((name, "ttmanip fk", f"{per_call_us(lambda: robot.fk(q)):.2f} µs"))
    rows.append((name, "ttmanip jacobian", f"{per_call_us(lambda: robot.jacobian(q)):.2f} µs"))
    robot.fk(qs)
    rows.append((name, "ttmanip fk batch", f"{per_item_rate(lambda: robot.fk(qs), batch) / 1e6:.2f} M/s"))

    if pin is not None:
        model = pin.buildModelFromXML(robot.to_urdf())
        data = model.createData()
        fid = model.getFrameId("tool")
        pin.framesForwardKinematics(model, data, q)
        assert np.allclose(data.oMf[fid].homogeneous, t_ref, atol=1e-10)
        assert np.allclose(
            pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED), j_ref, atol=1e-10
        )

        def pin_fk():
            pin.framesForwardKinematics(model, data, q)
            return data.oMf[fid].homogeneous

        def pin_jac():
            return pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)

        def pin_loop():
            out = np.empty((batch, 4, 4))
            for k in range(batch):
                pin.framesForwardKinematics(model, data, qs[k])
                out[k] = data.oMf[fid].homogeneous
            return out

        rows.append((name, "pinocchio fk (4×4)", f"{per_call_us(pin_fk):.2f} µs"))
        rows.append((name, "pinocchio jacobian", f"{per_call_us(pin_jac):.2f} µs"))
        rows.append((name, "pinocchio fk loop", f"{per_item_rate(pin_loop, batch, repeat=1) / 1e6:.2f} M/s"))

    if rtb is not None:
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, f"{name}.urdf")
            with open(path, "w") as f:
                f.write(robot.to_urdf())
            links, rname, _ = URDF_file(path)
            r = rtb.Robot(links, name=rname)
        ets = r.ets(start="base_link", end="tool")
        assert np.allclose(ets.eval(q), t_ref, atol=1e-10)
        assert np.allclose(ets.jacob0(q), j_ref, atol=1e-10)
        rows.append((name, "rtb ETS eval (C++)", f"{per_call_us(lambda: ets.eval(q)):.2f} µs"))
        rows.append((name, "rtb ETS jacob0 (C++)", f"{per_call_us(lambda: ets.jacob0(q)):.2f} µs"))
        small = qs[: min(batch, 50000)]
        rows.append(
            (
                name,
                "rtb ETS eval vectorised",
                f"{per_item_rate(lambda: ets.eval(small), len(small), 3) / 1e6:.2f} M/s",
            )
        )
    return rows


def main() -> None:
    batch = 1_000_000
    rows = []
    for name in ("gantry6", "mobile8", "ur5"):
        rows += bench_robot(name, batch)
    print_rows(rows)


if __name__ == "__main__":
    main()
