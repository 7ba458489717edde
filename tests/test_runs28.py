"""Session 28 (runs28): the sweep's own work per point, against the path it
replaces, bit for bit (docs/design.md, "runs28, session 28"):

* ``jsonable.to_jsonable``'s dispatch on the exact types of a point's values
  (float, dict, list, bool, str, None) against the isinstance chain it
  was before (copied here), on random nested documents of every type the
  package hands it (numpy scalars and arrays, subclasses of float, int,
  dict and str, an IntEnum, tuples, NaN, infinities, signed zeros) and on
  a real sweep point: the same output, value, type and bits, everywhere;
* a law's ``dr/dI`` run again at a tighter rtol
  (``point_amplitude._refine_dr_dI``) from the start poses the point
  solved already (``_known_starts``) against solving them again: the
  points' JSON bit for bit, and each start taken against ``start_poses``
  of that row alone (two Solar Boat points whose refined mode is the
  first and the second of the point's runs).
"""

from __future__ import annotations

import enum
import json
import math
import os
import random
from collections import OrderedDict

import numpy as np

import pytest

from bifilar.jsonable import to_jsonable


def _old_to_jsonable(x):
    """``to_jsonable`` as it was before session 28."""
    if isinstance(x, dict):
        return {str(k): _old_to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_old_to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _old_to_jsonable(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return x if math.isfinite(x) else None
    return x


class _F(float):
    pass


class _I(int):
    pass


class _S(str):
    pass


class _D(dict):
    pass


class _E(enum.IntEnum):
    A = 1


def _same(a, b, path="doc"):
    """Exact equality of two converted documents: types, keys, bits."""
    assert type(a) is type(b), (path, type(a), type(b))
    if isinstance(a, dict):
        assert list(a) == list(b), path
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (u, v) in enumerate(zip(a, b)):
            _same(u, v, f"{path}[{i}]")
    elif isinstance(a, float):
        assert a.hex() == b.hex(), (path, a, b)  # -0.0 and 0.0 apart
    else:
        assert a is b or a == b, (path, a, b)


_FLOATS = [0.0, -0.0, 1.5, -2.25e-300, 5e-324, 1e308, math.inf, -math.inf, math.nan]


def _leaf(rng: random.Random):
    f = rng.choice(_FLOATS + [rng.uniform(-1e3, 1e3)])
    return rng.choice([
        f, _F(f), np.float64(f), np.float32(f if math.isfinite(f) and abs(f) < 1e30 else math.nan), np.float16(1.5),
        rng.randint(-5, 5), _I(3), np.int64(7), np.int8(-2), np.uint32(9),
        True, False, np.bool_(True), np.bool_(False),
        "text", _S("sub"), None, _E.A,
        np.array([f, 1.0, -0.0]), np.array([[1, 2], [3, 4]]), np.array([True, False]), np.zeros(0),
        np.float64(f).item(), complex(1, 2)])


def _doc(rng: random.Random, depth: int = 0):
    if depth > 3 or rng.random() < 0.3:
        return _leaf(rng)
    kind = rng.choice(["dict", "list", "tuple", "subdict", "ordered"])
    items = [_doc(rng, depth + 1) for _ in range(rng.randint(0, 5))]
    if kind == "list":
        return items
    if kind == "tuple":
        return tuple(items)
    keys = [rng.choice(["a", "b", 1, 2.5, None, True, ("t", 1), _S("k")]) for _ in items]
    pairs = list(zip(keys, items))
    return {"dict": dict, "subdict": _D, "ordered": OrderedDict}[kind](pairs)


def test_to_jsonable_dispatch_is_the_old_rule_bit_for_bit():
    rng = random.Random(28)
    for _ in range(3000):
        d = _doc(rng)
        _same(to_jsonable(d), _old_to_jsonable(d))


def test_to_jsonable_of_a_sweep_point_is_the_old_rule_and_its_json():
    """A real point's dict (numpy-laden, as ``evaluate_point`` builds it
    before converting) converts to the same document and the same JSON text."""
    from bifilar.config import read_yaml
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    from conftest import CONFIGS

    cfg = read_yaml(CONFIGS / "thesis_plate_rest.yaml")
    st = sw.resolve_settings(cfg, tensions=False)
    seen = []
    real = pt._plain

    def keep(x):
        seen.append(x)
        return real(x)

    pt._plain = keep
    try:
        sw.evaluate_point(cfg, "thesis_plate_rest.yaml", {"spacing": 2.0}, st)
    finally:
        pt._plain = real
    raw = seen[-1]
    assert raw["valid"] is True

    def kinds(x):
        if isinstance(x, dict):
            return set().union({type(x)}, *map(kinds, x.values()))
        if isinstance(x, (list, tuple)):
            return set().union({type(x)}, *map(kinds, x))
        return {type(x)}

    assert kinds(raw) & {np.ndarray, np.float64}  # the dict before conversion: numpy inside
    new, old = to_jsonable(raw), _old_to_jsonable(raw)
    _same(new, old)
    assert json.dumps(new, allow_nan=False) == json.dumps(old, allow_nan=False)


def _fields(sp):
    from bifilar.analysis.start_pose import StartPoses

    return [np.asarray(getattr(sp, f)).tobytes() for f in StartPoses.__dataclass_fields__]


@pytest.mark.parametrize("params", [{"spacing": 3.5, "length": 5.0}, {"spacing": 4.0, "length": 2.0}])
def test_refine_starts_where_the_point_started_bit_for_bit(params):
    from bifilar.analysis.start_pose import start_poses
    from bifilar.config import read_yaml
    from bifilar.studies import point_amplitude as pa
    from bifilar.studies import sweep as sw

    from conftest import CONFIGS

    cfg = read_yaml(CONFIGS / "solar_boat.yaml")
    st = sw.resolve_settings(cfg)
    real = pa._known_starts
    seen = []

    def keep(pre, law, rows):
        sp = real(pre, law, rows)
        seen.append((pre, law, rows, sp))
        return sp

    pa._known_starts = keep
    try:
        taken = json.dumps(sw.evaluate_point(cfg, "solar_boat.yaml", params, st))
        pa._known_starts = lambda pre, law, rows: None  # the path before: simulate_batch solves them again
        solved = json.dumps(sw.evaluate_point(cfg, "solar_boat.yaml", params, st))
    finally:
        pa._known_starts = real
    assert len(seen) == 1 and seen[0][3] is not None  # the point refines a law, from the starts it has
    assert taken == solved
    pre, law, rows, sp = seen[0]
    assert len(sp.feasible) == 2 * len(rows)
    for i, (k, j) in enumerate(rows):  # each row against its own solve (scene, rest, mode, amplitude)
        label = pre.labels[k]
        alone = start_poses([pre.scene, law.scenes[j]], [pre.rest, pre.rest],
                            [pre.ms.modes[k], law.mode_sets[j].get(label)], pre.amplitude)
        assert _fields(sp.take([2 * i, 2 * i + 1])) == _fields(alone)


def test_bench_grid_points_counts_the_refining_points():
    """``bench_sweep.py --grid-points`` (the split of the whole sweep's CPU a
    point, docs/performance.md): its points with a third call of the
    batched engine are exactly those whose law's ``dr/dI`` was run again
    (counted here independently, by ``_refine_dr_dI``'s start poses), and
    the engine is given back unwrapped."""
    import sys
    from pathlib import Path

    import bifilar.analysis.batch as batch
    from bifilar.studies import point_amplitude as pa

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    had = os.environ.get("BIFILAR_NATIVE")
    try:
        import bench_sweep  # (sets BIFILAR_NATIVE=sync where unset: not left to the tests after this one)
    finally:
        if had is None:
            os.environ.pop("BIFILAR_NATIVE", None)
        else:
            os.environ["BIFILAR_NATIVE"] = had

    real_batch, real_known = batch.simulate_batch, pa._known_starts
    refined = []
    pa._known_starts = lambda pre, law, rows: refined.append(len(rows)) or real_known(pre, law, rows)
    try:
        r = bench_sweep.bench_grid_points(1)
    finally:
        pa._known_starts = real_known
    assert batch.simulate_batch is real_batch
    assert r["grid_points"] == 28 and len(r["grid_point_cpu_s"]) == 28
    by = r["grid_by_engine_calls"]
    assert set(by) <= {"2", "3"} and sum(v["points"] for v in by.values()) == 28
    # the warm-up and the one timed round each refine the same points (the default point refines none), each
    # twice since sigbatch29: its points alone and the whole sweep by run_sweep
    assert len(refined) == 4 * by.get("3", {"points": 0})["points"] and by["3"]["points"] > 0
    assert 0 < r["json_cpu_s_a_point"] < r["default_point_cpu_s"]
