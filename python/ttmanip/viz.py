"""3D recordings with Rerun (issue 31): ``--rerun FILE.rrd`` on ``ttmanip demo``, ``simulate`` and
``rally``, and ``ttmanip telemetry`` for ``ttctl`` telemetry files.

A recording holds, on one timeline ``time`` (s):

- ``world/table``, ``world/net`` — the ITTF table (surface at z = 0, ``ttmanip.ball.Table``);
- ``world/<robot>`` — the robot's base frame in the world; under it ``links/<joint>`` (each link
  frame, a transform from ``Robot.fk_all``), ``links/tool``, ``skeleton`` (the simple link
  geometry: a thick polyline through the base, every link origin and the tool),
  ``racket`` (the racket frame with a blade) and ``hit`` (the planned racket centre at the hit);
- ``world/ball`` (the ball) and ``world/ball/predicted`` (its predicted path);
- ``joints/<quantity>/<joint>`` — joint positions, references, torques and currents as scalars.

All positions come from Rust (FK, the flight model, the drive simulation); this module only
lays them out. Rerun is the optional extra ``ttmanip[viz]`` (``rerun-sdk``).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from . import _ttmanip as _t

__all__ = ["Recording", "WORLD_FROM_GANTRY6", "record_hit", "record_rally", "record_telemetry", "snapshot"]

#: gantry6's base frame in the world (table) frame of the rally (4×4, m): origin (−2.0, 0, 0.15) m,
#: yaw 90°, read from the Rust core (``ttkin::ball::reach::Placement::default``).
WORLD_FROM_GANTRY6 = _t.ball_placement()
_MAX_FRAMES = 300  # 3D frames per stroke (the scalars keep every sample)


def _rerun():
    try:
        import rerun as rr
    except ImportError:
        raise _t.TtmanipError(
            "--rerun: Rerun is not installed; pip install 'ttmanip[viz]' (the rerun-sdk package)"
        ) from None
    return rr


class Recording:
    """A Rerun recording written to ``path`` (.rrd): open it with ``rerun FILE.rrd``."""

    def __init__(self, path: str | Path, name: str = "ttmanip") -> None:
        rr = self.rr = _rerun()
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.rec = rr.RecordingStream(name, recording_id=f"{name}-{self.path.stem}")
        self.rec.save(str(self.path))
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)

    def layout(self, robot, quantities: tuple[str, ...] = ("q", "current")) -> None:
        """The viewer's layout (a Rerun blueprint): the 3-D world on the left, ``robot``'s joint
        ``quantities`` as plots on the right, the timeline below."""
        import rerun.blueprint as rrb

        plots = [
            rrb.TimeSeriesView(
                origin=f"/joints/{k}",
                contents=[f"/joints/{k}/{n}" for n in robot.joint_names],
                name=f"{robot.name} joints: {k}",
            )
            for k in quantities
        ]
        self.rec.send_blueprint(
            rrb.Blueprint(
                rrb.Horizontal(
                    rrb.Spatial3DView(
                        origin="/world",
                        name="world",
                        # looking at the robot's end of the table from the side, over the net
                        eye_controls=rrb.EyeControls3D(
                            position=[0.2, -1.9, 1.0], look_target=[-1.3, 0.1, 0.1], eye_up=[0.0, 0.0, 1.0]
                        ),
                    ),
                    rrb.Vertical(*plots),
                    column_shares=[3, 2],
                ),
                rrb.TimePanel(timeline="time"),
                collapse_panels=True,
            )
        )

    def close(self) -> Path:
        """Flushes and closes the file; returns its path."""
        self.rec.flush()
        self.rec.disconnect()
        return self.path

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _columns(self, entity: str, t, columns) -> None:
        rr = self.rr
        rr.send_columns(
            entity,
            indexes=[rr.TimeColumn("time", duration=np.asarray(t, dtype=float))],
            columns=columns,
            recording=self.rec,
        )

    def table(self, table=None) -> None:
        """The table top and the net (static): the boxes around ``ttmanip.ball.Table.outline()``
        (the core's ``Table::outline``, default ITTF), the top drawn 3 cm thick below the surface
        and the net 4 mm thick."""
        from .ball import Table

        rr, outline = self.rr, (table or Table()).outline()
        for entity, loop, pad, color in (
            ("world/table", outline["surface"], [0.0, 0.0, 0.015], [20, 70, 140]),
            ("world/net", outline["net"], [0.002, 0.0, 0.0], [230, 230, 230]),
        ):
            lo, hi = loop.min(axis=0), loop.max(axis=0)
            centre = (lo + hi) / 2 - [0.0, 0.0, pad[2]]  # the top's slab lies below the surface
            self.rec.log(
                entity,
                rr.Boxes3D(
                    centers=[centre], half_sizes=[(hi - lo) / 2 + pad], colors=[color], fill_mode="solid"
                ),
                static=True,
            )

    def robot(
        self,
        root: str,
        robot,
        t,
        q,
        *,
        world_from_base=None,
        scalars: dict[str, np.ndarray] | None = None,
    ) -> None:
        """The robot at ``q`` (K, n) over ``t`` (K,) under entity ``root``: link frames, skeleton,
        and the time series ``scalars`` (quantity -> (K, n) array) under ``joints/``."""
        rr = self.rr
        t, q = np.asarray(t, dtype=float), np.asarray(q, dtype=float)
        base = np.eye(4) if world_from_base is None else np.asarray(world_from_base, dtype=float)
        self.rec.log(root, rr.Transform3D(translation=base[:3, 3], mat3x3=base[:3, :3]), static=True)
        pick = np.unique(np.linspace(0, len(t) - 1, min(len(t), _MAX_FRAMES)).round().astype(int))
        frames = robot.fk_all(q[pick])  # (K', n, 4, 4), base frame
        tool = robot.fk(q[pick])  # (K', 4, 4)
        names = [*robot.joint_names, "tool"]
        for j, name in enumerate(names):
            f = frames[:, j] if j < robot.dof else tool
            self._columns(
                f"{root}/links/{name}",
                t[pick],
                rr.Transform3D.columns(translation=f[:, :3, 3], mat3x3=f[:, :3, :3]),
            )
            self.rec.log(f"{root}/links/{name}", rr.TransformAxes3D(0.08), static=True)
        origin = robot.base[:3, 3]
        for k, i in enumerate(pick):
            self.rec.set_time("time", duration=float(t[i]))
            pts = np.vstack([origin, frames[k, :, :3, 3], tool[k, :3, 3]])
            self.rec.log(f"{root}/skeleton", rr.LineStrips3D([pts], radii=0.02, colors=[[240, 160, 40]]))
        self.rec.reset_time()
        for quantity, values in (scalars or {"q": q}).items():
            values = np.asarray(values, dtype=float)
            for j, name in enumerate(robot.joint_names):
                self._columns(f"joints/{quantity}/{name}", t, rr.Scalars.columns(scalars=values[:, j]))

    def racket(self, root: str, t, poses, hit_centre=None) -> None:
        """The racket frame ``poses`` (K, 4, 4, parent frame of ``root``) over ``t`` with a blade,
        and the planned hit centre (from ``t[0]`` on: each stroke shows its own)."""
        rr = self.rr
        t, poses = np.asarray(t, dtype=float), np.asarray(poses, dtype=float)
        pick = np.unique(np.linspace(0, len(t) - 1, min(len(t), _MAX_FRAMES)).round().astype(int))
        self._columns(
            f"{root}/racket",
            t[pick],
            rr.Transform3D.columns(translation=poses[pick, :3, 3], mat3x3=poses[pick, :3, :3]),
        )
        self.rec.log(
            f"{root}/racket/blade",
            rr.Ellipsoids3D(half_sizes=[[0.08, 0.075, 0.006]], colors=[[200, 30, 30]], fill_mode="solid"),
            static=True,
        )
        if hit_centre is not None:
            self.rec.set_time("time", duration=float(t[0]))
            self.rec.log(f"{root}/hit", rr.Points3D([hit_centre], radii=0.025, colors=[[255, 220, 0]]))
            self.rec.reset_time()

    def ball(self, t, positions, predicted=None, *, entity: str = "world/ball") -> None:
        """The ball at ``positions`` (K, 3, world) over ``t``; ``predicted`` (M, 3) its predicted
        path, logged at ``t[0]``."""
        rr = self.rr
        t, p = np.asarray(t, dtype=float), np.asarray(positions, dtype=float)
        ok = np.isfinite(p).all(axis=1)
        self._columns(
            entity, t[ok], rr.Points3D.columns(positions=p[ok]).partition(np.ones(ok.sum(), dtype=int))
        )
        self.rec.log(entity, rr.Points3D.from_fields(radii=0.02, colors=[[255, 140, 0]]), static=True)
        if predicted is not None:
            pr = np.asarray(predicted, dtype=float)
            pr = pr[np.isfinite(pr).all(axis=1)]
            self.rec.set_time("time", duration=float(t[0]))
            self.rec.log(f"{entity}/predicted", rr.LineStrips3D([pr], radii=0.004, colors=[[255, 200, 120]]))
            self.rec.reset_time()


def record_hit(rec: Recording, robot, plan, sim, *, t0: float = 0.0, world_from_base=None) -> None:
    """A planned and simulated hit (``plan_hit`` + ``simulate``) from ``t0`` (s) on the timeline:
    the robot from the simulated joint positions, the racket, the hit point, q / q_ref / torque /
    current. With ``world_from_base`` (4×4, e.g. :data:`WORLD_FROM_GANTRY6`) the robot stands
    there by the table (``world/<name>``); without, it stands alone (``<name>``, base at the origin)."""
    at_table = world_from_base is not None
    if at_table:
        rec.table()
        rec.layout(robot, ("q", "current"))
    root = f"world/{robot.name}" if at_table else robot.name
    a = sim.arrays
    t = t0 + np.asarray(a["t"], dtype=float)
    scalars = {k: a[k] for k in ("q", "q_ref", "torque", "current") if k in a}
    base = np.asarray(world_from_base, dtype=float) if at_table else None
    rec.robot(root, robot, t, a["q"], world_from_base=base, scalars=scalars)
    rec.racket(root, t, sim.racket_pose, plan.hit_pose[:3, 3])


def record_rally(path: str | Path, summary: dict, balls: int = 10) -> Path:
    """The first ``balls`` balls of a rally (``ttmanip.rally``'s summary), one after the other on
    the timeline: each ball's flight from its incoming state and its predicted path, and gantry6's
    stroke for the return planned from the ball's true state (``ball.plan_return`` +
    ``plan_hit``, as the rally's drive check does)."""
    from . import ball, plan_hit, robots
    from .pipeline import racket_states

    res = summary["results"]
    robot = robots.gantry6()
    with Recording(path, "ttmanip-rally") as rec:
        rec.table()
        rec.layout(robot, ("q", "torque"))
        offset = 0.0
        for k in range(min(balls, len(res["incoming"]))):
            state = np.asarray(res["incoming"][k], dtype=float)
            times = state[0] + np.arange(0.0, 1.2, 0.005)
            flight = ball.predict(state, times)
            rec.ball(offset + times - state[0], flight, predicted=flight[::4], entity=f"world/ball{k}")
            now = 0.23
            d = ball.plan_return(state, now)
            if d["status"] == "ok":
                plan = plan_hit(robot, d["hit"], d["ready"])
                if plan.trajectory is not None:
                    t, q, _, _ = plan.sample(500.0)
                    tau = plan.torques(500.0)
                    root = "world/gantry6"
                    rec.robot(
                        root,
                        robot,
                        offset + now + t,
                        q,
                        world_from_base=WORLD_FROM_GANTRY6,
                        scalars={"q": q, "torque": tau},
                    )
                    poses = racket_states(robot, q, np.zeros_like(q))[0]
                    rec.racket(root, offset + now + t, poses, plan.hit_pose[:3, 3])
            offset += 1.5
    return Path(path)


def record_telemetry(telemetry: str | Path, path: str | Path) -> Path:
    """A ``ttctl`` telemetry CSV (one row per channel and cycle) as a recording: per channel and
    axis ``telemetry/<channel>/axis<a>/{q, q_ref, current}`` and the cycle ``latency_us``."""
    import io

    from .files import read_text

    # within 16 MiB and UTF-8 (a device such as /dev/zero never ends): a one-line error, no hang
    rows = list(csv.DictReader(io.StringIO(read_text(telemetry, f"telemetry: {telemetry}"), newline="")))
    if not rows or "channel" not in rows[0] or "t" not in rows[0] or "latency_us" not in rows[0]:
        raise _t.TtmanipError(
            f"telemetry: '{telemetry}' is not a ttctl telemetry CSV (no channel,t,latency_us header)"
        )

    def number(row: dict, key: str) -> float:
        try:
            return float(row[key])
        except (TypeError, ValueError):
            line = rows.index(row) + 2
            raise _t.TtmanipError(
                f"telemetry: {telemetry}: line {line}, column {key}: not a number: {row[key]!r}"
            ) from None

    with Recording(path, "ttmanip-telemetry") as rec:
        for channel in dict.fromkeys(r["channel"] for r in rows):
            sel = [r for r in rows if r["channel"] == channel]
            t = np.array([number(r, "t") for r in sel])
            rec._columns(
                f"telemetry/{channel}/latency_us",
                t,
                rec.rr.Scalars.columns(scalars=[number(r, "latency_us") for r in sel]),
            )
            a = 0
            while f"q{a}" in sel[0]:
                for quantity in ("q", "q_ref", "current"):
                    v = np.array([number(r, f"{quantity}{a}") for r in sel])
                    rec._columns(
                        f"telemetry/{channel}/axis{a}/{quantity}", t, rec.rr.Scalars.columns(scalars=v)
                    )
                a += 1
    return Path(path)


def snapshot(recording: str | Path, t: float, path: str | Path, *, title: str = "") -> Path:
    """A matplotlib 3-D picture of a recording at time ``t`` (s), drawn from the logged data read
    back with Rerun's reader: table, net, robot skeletons, racket centres, hit points, balls. A
    stand-in for a viewer screenshot where no viewer can run (no display, no GPU)."""
    rr = _rerun()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pyarrow as pa

    data: dict[str, dict[str, list]] = {}
    for chunk in rr.chunk.RrdReader(str(recording)).stream().to_chunks():
        batch = chunk.to_record_batch()
        cols = data.setdefault(chunk.entity_path, {})
        for name in batch.schema.names:
            col = batch.column(name)
            if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
                col = col.cast(pa.int64())
            cols.setdefault(name, []).extend(col.to_pylist())

    def at(entity: str, column: str):
        """The latest value of ``column`` at or before t (static values have no time)."""
        c = data.get(entity, {})
        if column not in c:
            return None
        if "time" not in c:
            return c[column][-1]
        times = np.array(c["time"], dtype=float) / 1e9
        before = np.flatnonzero(times <= t + 1e-12)
        return None if before.size == 0 else c[column][before[np.argmax(times[before])]]

    def world_from(entity: str) -> np.ndarray:
        """The entity's parent chain of Transform3D (static or at t), composed into the world."""
        parts = entity.strip("/").split("/")
        m = np.eye(4)
        for k in range(1, len(parts) + 1):
            e = "/" + "/".join(parts[:k])
            tr, rot = at(e, "Transform3D:translation"), at(e, "Transform3D:mat3x3")
            if tr is not None:
                step = np.eye(4)
                step[:3, 3] = tr[0]
                if rot is not None:
                    step[:3, :3] = np.array(rot[0]).reshape(3, 3).T  # stored column-major
                m = m @ step
        return m

    fig = plt.figure(figsize=(8, 6), constrained_layout=True)
    ax = fig.add_subplot(projection="3d")
    half = at("/world/table", "Boxes3D:half_sizes")
    if half is not None:
        hx, hy, _ = half[0]
        xs, ys = np.meshgrid([-hx, min(hx, 0.3)], [-hy, hy])  # drawn up to the figure's edge
        ax.plot_surface(xs, ys, np.zeros_like(xs), color="#1f4e8c", alpha=0.5)
        net = at("/world/net", "Boxes3D:half_sizes")
        if net is not None:
            _, ny, nz = net[0]
            ax.plot_surface(np.zeros((2, 2)), *np.meshgrid([-ny, ny], [0, 2 * nz]), color="0.85", alpha=0.7)
    for entity in sorted(e for e in data if e.startswith("/world/") and e.endswith("/skeleton")):
        strips = at(entity, "LineStrips3D:strips")
        if strips:
            m = world_from(entity.rsplit("/", 1)[0])
            p = np.array(strips[0], dtype=float) @ m[:3, :3].T + m[:3, 3]
            ax.plot(*p.T, "-o", color="#f0a028", lw=4, ms=4, label=entity.split("/")[-2] + " links")
    for entity in sorted(e for e in data if e.startswith("/world/") and e.endswith("/racket")):
        if at(entity, "Transform3D:translation") is not None:
            m = world_from(entity)
            u = np.linspace(0, 2 * np.pi, 40)
            blade = np.c_[0.08 * np.cos(u), 0.075 * np.sin(u), 0 * u] @ m[:3, :3].T + m[:3, 3]
            ax.plot(*blade.T, color="#c81e1e", lw=2, label="racket")
            c = data[entity]
            times = np.array(c["time"], dtype=float) / 1e9
            past = np.array([row[0] for row in c["Transform3D:translation"]], dtype=float)[times <= t]
            base = world_from(entity.rsplit("/", 1)[0])
            trail = past[np.argsort(times[times <= t])] @ base[:3, :3].T + base[:3, 3]
            ax.plot(*trail.T, ":", color="#c81e1e", lw=1, label="racket path so far")
    for entity in sorted(e for e in data if e.startswith("/world/") and e.endswith("/hit")):
        hit = at(entity, "Points3D:positions")
        if hit is not None:
            m = world_from(entity.rsplit("/", 1)[0])
            p = np.array(hit[0], dtype=float) @ m[:3, :3].T + m[:3, 3]
            ax.scatter(*p.T, color="gold", s=60, edgecolor="k", label="planned hit point")
    for entity in sorted(e for e in data if e.startswith("/world/ball") and e.count("/") == 2):
        p = at(entity, "Points3D:positions")
        if p is not None:
            ax.scatter(
                *np.array(p, dtype=float).T, color="white", edgecolor="k", s=45, label="ball", zorder=5
            )
        pr = at(entity + "/predicted", "LineStrips3D:strips")
        if pr:
            ax.plot(
                *np.array(pr[0], dtype=float).T, color="orange", lw=1, alpha=0.8, label="predicted flight"
            )
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    limits = np.array([[-2.6, 0.3], [-0.9, 0.9], [-0.1, 0.6]])  # the robot's end of the table, m
    # (the table is drawn up to x = 0.3 m, matplotlib does not clip surfaces)
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_zlim(*limits[2])
    ax.set_box_aspect(np.diff(limits, axis=1).ravel())  # equal scale on every axis
    ax.view_init(elev=25, azim=-55)
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    ax.legend(unique.values(), unique.keys(), loc="upper left", fontsize=8)
    ax.set_title(title or f"{Path(recording).name} at t = {t:.3f} s (drawn from the recording's data)")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
