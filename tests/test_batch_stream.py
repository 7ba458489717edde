"""Bounded memory in long batches (issue 14): the lowest point as a running
minimum, batches run in chunks, and ``health=False`` on the DOP853 engine."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis import batch as bt
from bifilar.analysis.batch_health import LowestPoint
from bifilar.config import scene_from_dict
from bifilar.rotations import quat_to_matrix
from bifilar.scene import lowest_point_z
from conftest import trapezoid


def _box_scene(dims, shift=0.0):
    """A trapezoid whose body is a bounding box (a support function of its own)."""
    s = trapezoid(h=0.5)
    cfg = {"body": {"mass": 100.0, "inertia": {"principal": [100, 50, 150]},
                    "bounding_box": {"min": [-d / 2 for d in dims], "max": [d / 2 for d in dims]}},
           "rig": {"anchors": s.anchors.tolist(), "attachments": (s.attachments + [0, shift, 0]).tolist(),
                   "lengths": s.lengths.tolist()}}
    return scene_from_dict(cfg)


def test_running_minimum_equals_the_direct_minimum():
    """Folded every 7 rows (many folds, scenes interleaved) or once at the end,
    the running minimum is the minimum of lowest_point_z over each scene's states."""
    a = _box_scene([1.0, 5.0, 0.2])
    scenes = [a, a.with_changes(lengths=a.lengths * 1.01), _box_scene([2.0, 4.0, 1.0], 0.1), trapezoid(h=0.3)]
    assert scenes[3].support is None and scenes[0].support is scenes[1].support
    rng = np.random.default_rng(5)
    com0 = rng.normal(size=(4, 3))
    chunks = []
    for _ in range(20):
        idx = rng.integers(0, 4, 9)
        y = np.zeros((13, 9))
        y[:3] = 0.1 * rng.normal(size=(3, 9))
        y[3:7] = rng.normal(size=(4, 9))  # any quaternion (normalised inside)
        chunks.append((idx, y))
    small, big = LowestPoint(scenes, com0, limit=7), LowestPoint(scenes, com0, limit=10**9)
    for idx, y in chunks:
        small.add_states(idx, y)
        big.add_states(idx, y)
    for b, sc in enumerate(scenes):
        rows = [(y[:, idx == b]) for idx, y in chunks]
        Y = np.concatenate(rows, axis=1)
        direct = np.min(lowest_point_z(sc, Y[:3].T + com0[b], quat_to_matrix(Y[3:7].T)))
        assert small.z[b] == pytest.approx(direct, abs=1e-14)
        assert big.z[b] == pytest.approx(direct, abs=1e-14)


def _scenes(k):
    return [trapezoid(l1=5.0, l2=5.0 - 0.01 * j, h=0.3 + 0.02 * j) for j in range(k)]


def test_chunked_batch_gives_each_scene_its_own_result(monkeypatch):
    """Per-scene step control: a scene's DOP853 run does not depend on its batch
    neighbours, so chunks of 4 give the same figures as one batch (rounding).
    SMALL_BATCH lowered to 2 so that every chunk takes the vectorised engine."""
    monkeypatch.setattr(bt, "SMALL_BATCH", 2)
    scenes = _scenes(6)
    whole = bt.simulate_batch(scenes, "torsion", 0.05, 2.2, rtol=1e-8, method="dop853")
    monkeypatch.setattr(bt, "CHUNK", 4)
    seen = []
    parts = bt.simulate_batch(scenes, "torsion", 0.05, 2.2, rtol=1e-8, method="dop853",
                              progress=lambda d, t: seen.append(d / t))
    assert seen and max(seen) == pytest.approx(1.0) and np.all(np.diff(seen) >= -1e-12)
    for a, b in zip(whole, parts):
        assert b.period == pytest.approx(a.period, rel=1e-13)
        assert b.lowest_z_min == pytest.approx(a.lowest_z_min, abs=1e-13)
        assert b.energy_drift == pytest.approx(a.energy_drift, rel=1e-6, abs=1e-15)
        np.testing.assert_allclose(b.tension_min, a.tension_min, rtol=1e-12)


@pytest.mark.parametrize("k", [1, 3])
def test_health_false_reports_no_health_and_the_same_period(k, monkeypatch):
    """health=False (both DOP853 paths: one scene on floats, a vectorised batch,
    SMALL_BATCH lowered to 2 to get it cheaply): the same steps, so the same
    period; health figures NaN, not a made-up 0."""
    monkeypatch.setattr(bt, "SMALL_BATCH", 2)
    scenes = _scenes(k)
    on = bt.simulate_batch(scenes, "torsion", 0.05, 2.2, rtol=1e-8, method="dop853")
    off = bt.simulate_batch(scenes, "torsion", 0.05, 2.2, rtol=1e-8, method="dop853", health=False)
    for a, b in zip(on, off):
        assert b.period == a.period
        assert np.isfinite(a.energy_drift) and np.isfinite(a.lowest_z_min)
        assert np.isnan(b.max_constraint_violation) and np.isnan(b.energy_drift) and np.isnan(b.lowest_z_min)
        assert np.all(np.isnan(b.tension_min)) and np.all(np.isnan(b.tension_max))
