"""Pickle and copy of every public class (issue 31).

Each public class (found by ``api_registry.public_classes``, so a new class cannot be forgotten)
gets a sample object; it goes through ``pickle`` (every protocol from 2), ``copy.copy`` and
``copy.deepcopy``, and the twin must give *equal results*: every public property and the calls of
``api_registry.PICKLE_PROBES`` are compared exactly (arrays bit for bit, NaN equal to NaN).
Robots and hit plans also travel to a ``ProcessPoolExecutor`` and to a Dask ``LocalCluster``
running ``plan_hits``, and the plans that come back equal the local ones.
"""

from __future__ import annotations

import concurrent.futures
import copy
import dataclasses
import inspect
import multiprocessing
import pickle
import warnings

import numpy as np
import pytest
import ttmanip
from api_registry import PICKLE_PROBES, public_classes, public_exceptions
from hypothesis import given, settings
from hypothesis import strategies as st
from test_api_fuzz import sample_objects

PROTOCOLS = range(2, pickle.HIGHEST_PROTOCOL + 1)


def _samples() -> dict[str, list[object]]:
    """Registry key -> sample objects (several where the state has more than one shape)."""
    out = {k: [v] for k, v in sample_objects().items()}
    out["Robot"] = [ttmanip.Robot.builtin(n) for n in ("gantry6", "mobile8", "arm4", "ur5")]
    g6 = out["Robot"][0]
    urdf = ttmanip.Robot.from_urdf_string(g6.to_urdf(), "base_link", "tool")  # origin/axis joints
    out["Robot"].append(urdf.with_base(g6.fk(np.full(6, 0.3))).with_tool(g6.fk(np.full(6, -0.2))))
    ran = ttmanip.DriveSim(g6, noise=0.01, seed=3)  # a simulator mid-run: the journal replays it
    ran.set_setpoint(np.full(6, 0.01), tau_ff=np.full(6, 0.1))
    ran.tick(25)
    ran.tick(5)
    reset = ttmanip.DriveSim(g6, gravity=False, setpoint_hz=500.0)
    reset.reset(np.full(6, 0.2), np.full(6, 0.01))
    t = np.linspace(0.0, 0.01, 11)
    q = np.full((11, 6), 0.2)
    reset.run(t, q, np.zeros_like(q), np.zeros_like(q))
    failed = ttmanip.DriveSim(g6)  # a run that failed is journaled and replays alike
    with pytest.raises(ttmanip.TtmanipError):
        failed.run(t[::-1], q, np.zeros_like(q), np.zeros_like(q))
    failed.tick(7)
    out["DriveSim"] += [ran, reset, failed]
    out["IkResult"].append(g6.ik(np.array([g6.fk(np.full(6, 0.1)), g6.fk(np.full(6, 0.2))])))
    unreachable = ttmanip.Hit.from_normal([5.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.3)
    out["HitPlan"].append(ttmanip.plan_hit(g6, unreachable))  # no stroke: NaNs and None
    out["motor.ServoSim"] = [ttmanip.motor.Servo()._sim]
    return out


SAMPLES = _samples()


def _same(a, b, where: str = "", depth: int = 0) -> None:
    """Asserts that a and b are equal, exactly: arrays bit for bit (NaN equals NaN)."""
    assert type(a) is type(b), f"{where}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, f"{where}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"
        if a.dtype == object:
            for i, (x, y) in enumerate(zip(a.ravel(), b.ravel(), strict=True)):
                _same(x, y, f"{where}[{i}]", depth + 1)
        else:
            assert np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"), where
    elif isinstance(a, float | np.floating):
        assert a == b or (np.isnan(a) and np.isnan(b)), f"{where}: {a} vs {b}"
    elif isinstance(a, dict):
        assert sorted(map(str, a)) == sorted(map(str, b)), where  # Robot.drives: a HashMap's order
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]", depth + 1)
    elif isinstance(a, list | tuple):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{where}[{i}]", depth + 1)
    elif a is None or isinstance(a, str | bytes | bool | int | np.integer | np.bool_):
        assert a == b, f"{where}: {a!r} vs {b!r}"
    elif depth < 3:
        _same(_properties(a), _properties(b), f"{where}.", depth + 1)


def _properties(obj) -> dict[str, object]:
    """Every public property or field of obj: name -> value, or (exception type, message)."""
    out = {}
    for name in dir(type(obj)) + list(getattr(obj, "__dict__", {})):
        if name.startswith("_") or name in out:
            continue
        static = inspect.getattr_static(obj, name)
        if (
            callable(static)
            and not dataclasses.is_dataclass(obj)
            or isinstance(static, classmethod | staticmethod)
        ):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                value = getattr(obj, name)
        except Exception as e:  # both twins must fail alike
            value = (type(e), str(e))
        if not callable(value) or isinstance(value, type):
            out[name] = value
    return out


def _probe(probe, obj):
    """probe(obj), or (exception type, message) when it raises: the twin must raise alike."""
    try:
        return probe(obj)
    except Exception as e:
        return (type(e), str(e))


def _twins(obj) -> list[tuple[str, object]]:
    """obj through every pickle protocol, copy.copy and copy.deepcopy."""
    out = [(f"pickle protocol {p}", pickle.loads(pickle.dumps(obj, protocol=p))) for p in PROTOCOLS]
    return out + [("copy.copy", copy.copy(obj)), ("copy.deepcopy", copy.deepcopy(obj))]


def test_every_class_has_a_pickle_probe_and_a_sample():
    classes = public_classes()
    assert sorted(set(classes) - set(PICKLE_PROBES)) == [], "add these classes to api_registry.PICKLE_PROBES"
    assert sorted(set(classes) - set(SAMPLES)) == [], "add a sample of these classes to tests/test_pickle.py"
    assert sorted(set(PICKLE_PROBES) - set(classes)) == [], "PICKLE_PROBES names classes that are gone"


@pytest.mark.parametrize("key", sorted(public_classes()))
def test_round_trip_gives_equal_results(key):
    probe = PICKLE_PROBES[key]
    for i, obj in enumerate(SAMPLES[key]):
        assert isinstance(obj, public_classes()[key])
        twins = _twins(obj)  # before the probe: a probe may advance a simulator
        expected = (_properties(obj), _probe(probe, obj))
        for how, twin in twins:
            assert type(twin) is type(obj), how
            _same(expected, (_properties(twin), _probe(probe, twin)), f"{key} sample {i} via {how}")


_EXTENSION_CLASSES = sorted(
    k
    for k, c in public_classes().items()
    if c.__module__ in ("ttmanip", "ttmanip._ttmanip") and c.__reduce__ is not object.__reduce__
)


@pytest.mark.parametrize("key", _EXTENSION_CLASSES)
def test_each_extension_class_reduces_through_its_own_unpickler(key):
    """One mechanism (``ttkin_py::pickle::pickled!``): every class of the extension reduces to
    ``(_unpickle_<class>, (state,))``, a function of the extension that takes that state back and
    refuses a state of another shape with an error naming the class."""
    for obj in SAMPLES[key]:
        restore, args = obj.__reduce__()
        assert restore.__module__ == "ttmanip._ttmanip" and restore.__name__.startswith("_unpickle_")
        assert getattr(ttmanip._ttmanip, restore.__name__) is restore and len(args) == 1
        assert type(restore(args[0])) is type(obj)
        cls = type(obj).__name__
        with pytest.raises(ttmanip.TtmanipError, match=f"unpickle {cls}: not a state of this version"):
            restore({"not": "a state"})


def test_every_unpickler_belongs_to_one_class():
    unpicklers = {n for n in dir(ttmanip._ttmanip) if n.startswith("_unpickle_")}
    used = {SAMPLES[k][0].__reduce__()[0].__name__ for k in _EXTENSION_CLASSES}
    assert used == unpicklers and len(used) == len(_EXTENSION_CLASSES)


@pytest.mark.parametrize("name", sorted(public_exceptions()))
def test_exceptions_pickle(name):
    cls = public_exceptions()[name]
    e = cls("q: expected shape (6,), got (5,)")
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is cls and back.args == e.args


def test_a_robot_pickle_is_its_serde_state_not_a_file():
    r = SAMPLES["Robot"][-1]
    restore, (state,) = r.__reduce__()
    assert restore is ttmanip._ttmanip._unpickle_robot
    assert isinstance(state, dict) and state["name"] == r.name and len(state["joints"]) == r.dof
    with pytest.raises(ttmanip.TtmanipError, match="unpickle Robot: not a state of this version"):
        restore({"name": "x"})


def _hits() -> list[ttmanip.Hit]:
    c = np.array([0.35, -0.55, 0.05])
    return [
        ttmanip.Hit.from_normal(c + [dx, 0.0, dz], [0.3, -1.0, -0.2], [0.6, -2.0, -0.4], 0.4 + 0.05 * k)
        for k, (dx, dz) in enumerate([(0.0, 0.0), (0.05, 0.0), (0.0, 0.05), (-0.05, 0.02)])
    ]


def _plans_equal(local, remote) -> None:
    assert len(local) == len(remote)
    for i, (a, b) in enumerate(zip(local, remote, strict=True)):
        probe = PICKLE_PROBES["HitPlan"]
        _same((_properties(a), _probe(probe, a)), (_properties(b), _probe(probe, b)), f"plan {i}")
    assert sum(p.ok for p in local) >= 2, [p.status for p in local]


def test_plan_hits_in_a_process_pool():
    robot = ttmanip.robots.gantry6()
    hits = _hits()
    local = ttmanip.plan_hits(robot, hits)
    ctx = multiprocessing.get_context("spawn")  # nothing inherited: everything travels by pickle
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=ctx) as pool:
        remote = list(pool.map(ttmanip.plan_hits, [robot, robot], [hits[:2], hits[2:]]))
    _plans_equal(local, remote[0] + remote[1])


def test_plan_hits_on_a_dask_local_cluster():
    import distributed  # the sweep extra, part of the test extra

    robot = ttmanip.robots.gantry6()
    hits = _hits()
    local = ttmanip.plan_hits(robot, hits)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote_robot = client.scatter(robot, broadcast=True)
        futures = [
            client.submit(ttmanip.plan_hits, remote_robot, hits[k : k + 2], pure=False) for k in (0, 2)
        ]
        remote = client.gather(futures)
    _plans_equal(local, remote[0] + remote[1])


@settings(max_examples=40, deadline=None)
@given(
    st.integers(1, 7).flatmap(
        lambda n: st.tuples(
            *[
                st.lists(st.floats(-2.0, 2.0, allow_subnormal=False), min_size=n, max_size=n)
                for _ in range(5)
            ],
            st.text("RP", min_size=n, max_size=n),
            st.sampled_from(["standard", "modified"]),
        )
    )
)
def test_any_dh_robot_round_trips_bit_for_bit(params):
    a, alpha, d, theta, q, types, convention = params
    robot = ttmanip.Robot.from_dh(a, alpha, d, theta, types=types, convention=convention)
    twin = pickle.loads(pickle.dumps(robot))
    assert twin.to_toml() == robot.to_toml()
    np.testing.assert_array_equal(twin.fk_all(q), robot.fk_all(q))
    np.testing.assert_array_equal(twin.jacobian(q), robot.jacobian(q))
