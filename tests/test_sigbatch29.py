"""sigbatch29: a one-process sweep evaluates its points in chunks whose
sigma points (rest poses and modes) and runs' start poses are each solved
in one batch (bifilar.analysis.shared_batch).  A point's figures must not
depend on what shares its batch: each point of a sweep equals the same
point evaluated alone, field by field, to the bit (the exact comparison
is the only tolerance that proves it), and the shared batches must
actually have answered (else the equality would prove nothing)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from bifilar.analysis import shared_batch as sb
from bifilar.config import read_yaml
from bifilar.jsonable import to_jsonable
from bifilar.studies import sweep as sw

ROOT = Path(__file__).resolve().parents[1]
BOAT = ROOT / "configs" / "solar_boat.yaml"
TRIFILAR = ROOT / "configs" / "trifilar_kth.yaml"
DRONE = ROOT / "configs" / "drone_parallel.yaml"
#: a 30 g part whose CoM is 5 mm under its attachments: sigma points that turn, from near (per point)
DRONEPART = ROOT / "tests" / "data" / "audit24" / "c04_dronepart.yaml"


def _first_difference(a, b, path="point"):
    """The path of the first field where ``a`` and ``b`` differ (floats by
    their bits, NaN equal to NaN), or None."""
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            return f"{path} keys {sorted(set(a) ^ set(b))}"
        for k in a:
            d = _first_difference(a[k], b[k], f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            return f"{path} length {len(a)} != {len(b)}"
        for n, (x, y) in enumerate(zip(a, b)):
            d = _first_difference(x, y, f"{path}[{n}]")
            if d:
                return d
        return None
    if isinstance(a, float) and isinstance(b, float):
        same = (math.isnan(a) and math.isnan(b)) or np.float64(a).tobytes() == np.float64(b).tobytes()
        return None if same else f"{path}: {a!r} != {b!r}"
    return None if (type(a) is type(b) and a == b) else f"{path}: {a!r} != {b!r}"


def _counted(monkeypatch):
    """{kind: [requests, answered]} of the shared solvers, counted as they run."""
    seen = {k: [0, 0] for k in sb.SOLVERS}
    for kind, real in list(sb.SOLVERS.items()):
        def wrapped(reqs, _real=real, _kind=kind):
            out = _real(reqs)
            seen[_kind][0] += len(reqs)
            seen[_kind][1] += sum(a is not None for a in out)
            return out
        monkeypatch.setitem(sb.SOLVERS, kind, wrapped)
    return seen


def _sweep_and_alone(path: Path, grid: list[dict], monkeypatch, **over):
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    if over:
        import dataclasses

        st = dataclasses.replace(st, **over)
    seen = _counted(monkeypatch)
    swept = sw.run_sweep(cfg, str(path), grid, st)
    monkeypatch.undo()
    alone = [sw.evaluate_point(cfg, str(path), p, st) for p in grid]
    for p, a, b in zip(grid, swept, alone):
        d = _first_difference(to_jsonable(a), to_jsonable(b))
        assert d is None, f"{p}: {d}"
        assert json.dumps(to_jsonable(a)) == json.dumps(to_jsonable(b))
    return swept, seen


def test_boat_sweep_points_are_each_point_alone_to_the_bit(monkeypatch):
    # six boat points of the issue-14 grid, one chunk; the amplitude swept too (start poses of other amplitudes
    # in the same batch)
    grid = [{"spacing": s, "length": L} for s in (1.0, 2.5, 4.0) for L in (2.0, 5.0)]
    grid += [{"spacing": 3.0, "amplitude": 0.3}]
    swept, seen = _sweep_and_alone(BOAT, grid, monkeypatch)
    assert all(p["valid"] for p in swept)
    # every point's sigma points and start poses came from the shared batches (one request each)
    assert seen["sigma points"] == [len(grid), len(grid)]
    assert seen["start poses"] == [len(grid), len(grid)]


def test_second_order_sigmas_from_a_shared_batch(monkeypatch):
    # the drone's honest sigmas are second order (its sigma points, and their pairs' corners, set the printed
    # figure: the boat's stay within 2 % of the linear one, so the boat alone would not see a wrong sigma point)
    from bifilar.estimation import honest

    real, moved = honest.honest_stds, []

    def rec(*a, **k):
        out = real(*a, **k)
        moved.extend(o != fb for o, fb in zip(out, k["fallbacks"]))
        return out

    monkeypatch.setattr(honest, "honest_stds", rec)
    grid = [{}, {"length": 0.8}, {"length": 1.2}]
    cfg = read_yaml(DRONE)
    st = sw.resolve_settings(cfg)
    sw.evaluate_point(cfg, str(DRONE), grid[0], st)
    assert any(moved)
    monkeypatch.undo()
    swept, seen = _sweep_and_alone(DRONE, grid, monkeypatch)
    assert all(p["valid"] for p in swept)
    assert seen["sigma points"][1] == seen["sigma points"][0] > len(grid)  # the pairs' corners shared too


def test_trifilar_and_a_reversed_chunk(monkeypatch):
    # three wires; the same points in another order (other neighbours in the batch) give the same figures
    grid = [{"length": L} for L in (1.0, 1.6, 2.2)]
    a, seen = _sweep_and_alone(TRIFILAR, grid, monkeypatch)
    assert seen["sigma points"][1] == len(grid) and seen["start poses"][1] == len(grid)
    b, _ = _sweep_and_alone(TRIFILAR, grid[::-1], monkeypatch)
    assert json.dumps(to_jsonable(a)) == json.dumps(to_jsonable(b[::-1]))


def test_turning_sigma_points_keep_their_own_batch(monkeypatch):
    # the drone part's sigma points include scenes not accepted from the start pose (their pose comes from the
    # point's own rest pose, `near`): those requests are answered None and each point solves its own batch
    grid = [{"spacing": 0.06}, {"spacing": 0.05}, {"length": 0.4}]
    swept, seen = _sweep_and_alone(DRONEPART, grid, monkeypatch)
    assert all(p["valid"] for p in swept)
    assert seen["sigma points"][0] >= len(grid) and seen["sigma points"][1] == 0
    assert seen["start poses"] == [len(grid), len(grid)]


def _sigma_requests(path: Path, params: dict) -> list:
    """The sigma-point scenes (and the base pose ``near``) of one point's own batches, as it makes them."""
    from bifilar.analysis import batch

    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    got, real = [], batch.rest_poses

    def rec(scenes, guess=None, **k):
        if k.get("near") is not None:
            got.append((list(scenes), k["near"]))
        return real(scenes, guess, **k)

    batch.rest_poses = rec
    try:
        sw.evaluate_point(cfg, str(path), params, st)
    finally:
        batch.rest_poses = real
    return got


def test_a_partly_shared_sigma_batch_answers_each_request_as_its_own():
    # a boat point's request beside the drone part's (same wire count, one batch): the boat's rows answered, the
    # same bytes as its own batch; the drone part's (a scene that turns) None
    from bifilar.analysis.batch import modes_batch, rest_poses

    boat = _sigma_requests(BOAT, {"spacing": 3.0})[0]
    part = _sigma_requests(DRONEPART, {})[0]
    out = sb._sigma_points([boat[0], part[0], boat[0][:5]])
    assert out[1] is None and out[0] is not None and out[2] is not None
    geo = []
    own = rest_poses(boat[0], boat[1], errors="return", geometry=geo, near=boat[1], defer=True)
    own_ms = modes_batch(boat[0], own, lazy=True, geometry=geo[0])
    for ans in (out[0], out[2]):  # (the second: the first five scenes, zip stops there)
        for r, r2, m, m2 in zip(own, ans[0], own_ms, ans[1]):
            for f in ("com", "R", "tensions"):
                assert np.asarray(getattr(r, f)).tobytes() == np.asarray(getattr(r2, f)).tobytes()
            for f in ("periods", "shapes", "mass_matrix", "basis"):
                assert np.asarray(getattr(m, f)).tobytes() == np.asarray(getattr(m2, f)).tobytes()
    assert len(out[2][0]) == 5


def test_run_together_order_errors_and_outside():
    assert sb.shared("sigma points", []) is None  # outside run_together: the caller's own batch
    done = []
    vals = sb.run_together([lambda i=i: i * i for i in range(5)], on_done=lambda i, v: done.append((i, v)))
    assert vals == [0, 1, 4, 9, 16] and sorted(done) == [(i, i * i) for i in range(5)]

    def boom():
        raise KeyboardInterrupt

    def parks():
        return sb.shared("start poses", None)  # parks; never answered: run_together stops it

    with pytest.raises(KeyboardInterrupt):
        sb.run_together([parks, boom, parks])


def test_interrupted_chunked_sweep_resumes_to_the_same_points(tmp_path):
    # stop_after inside what would be one chunk: exactly that many points journaled, the resumed sweep the same
    cfg = read_yaml(BOAT)
    st = sw.resolve_settings(cfg)
    grid = [{"spacing": s} for s in (1.0, 2.0, 3.0, 4.0)]
    j = tmp_path / "s.partial.jsonl"
    with pytest.raises(sw.SweepInterrupted) as e:
        sw.run_sweep(cfg, str(BOAT), grid, st, journal=j, stop_after=3)
    assert e.value.done == 3 and len(sw.read_journal(j, sw.fingerprint(cfg, st))) == 3
    resumed = sw.run_sweep(cfg, str(BOAT), grid, st, journal=j, resume=True)
    whole = sw.run_sweep(cfg, str(BOAT), grid, st)
    assert json.dumps(to_jsonable(resumed)) == json.dumps(to_jsonable(whole))


def test_workers_evaluate_chunks_to_the_same_points():
    # --workers 2: each task a chunk of points evaluated together (8 points: chunks of 2 on two workers), the same
    # figures as the one-process sweep and as a chunk evaluated here
    cfg = read_yaml(BOAT)
    st = sw.resolve_settings(cfg)
    grid = [{"spacing": s, "length": L} for s in (1.0, 2.0, 3.0, 4.0) for L in (2.0, 5.0)]
    one = sw.run_sweep(cfg, str(BOAT), grid, st)
    two = sw.run_sweep(cfg, str(BOAT), grid, st, workers=2)
    assert json.dumps(to_jsonable(one)) == json.dumps(to_jsonable(two))
    chunk = sw._evaluate_chunk(cfg, str(BOAT), grid[2:5], st)
    assert json.dumps(to_jsonable(chunk)) == json.dumps(to_jsonable(one[2:5]))
