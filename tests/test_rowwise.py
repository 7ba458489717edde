"""Session 14, perf16: the reductions over a short axis taken by columns
(bifilar/rowwise.py) give the bits of the numpy reductions they replace,
where those ran row by row on a long record (docs/design.md, "Session 14,
perf16"): the support function's max over a box's corners, the lowest
point's quaternion norm and max over the attachments, the samples' energy,
the record's tension extremes.  Each reference is the replaced expression,
written out here as it was."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from bifilar.analysis import batch_health as bh
from bifilar.rowwise import column_extremes, row_max, row_sum

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from test_kernel import SCENES, _random_states  # noqa: E402


def test_row_helpers_are_numpys_reductions_bit_for_bit():
    rng = np.random.default_rng(14)
    for m in (1, 2, 3, 4, 7, 8):
        M = rng.normal(size=(3001, m)) * 10.0 ** rng.integers(-8, 8, size=(3001, m))
        M[17, 0] = np.nan  # NaN propagates as in np.max / np.min
        M[40, -1] = np.inf
        assert np.array_equal(row_max(M), np.max(M, axis=-1), equal_nan=True)
        lo, hi = column_extremes(M)
        assert np.array_equal(lo, M.min(axis=0), equal_nan=True)
        assert np.array_equal(hi, M.max(axis=0), equal_nan=True)
        if m < 8:  # numpy's order for fewer than 8 terms (a reordered sum differs in many rows)
            assert np.array_equal(row_sum([M[:, j] for j in range(m)]), np.sum(M, axis=-1), equal_nan=True)
    with pytest.raises(ValueError):
        row_sum([np.zeros(2)] * 8)


def _old_fold(scene, z, q) -> float:
    """LowestPoint's one-scene fold as it was before session 14."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    qw, qx, qy, qz = q.T
    down = -np.stack([2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)], -1)
    att = np.broadcast_to(scene.attachments, (len(z),) + scene.attachments.shape)
    h = np.maximum(np.max(np.einsum("rnk,rk->rn", att, down), axis=1), 0.0)
    if scene.support is not None:
        h = np.maximum(h, np.asarray(scene.support(down), float))
    return float(np.min(z - h))


@pytest.mark.parametrize("name, scene", SCENES, ids=[s[0] for s in SCENES])
def test_lowest_point_and_energy_are_the_replaced_expressions(name, scene):
    """The fold's lowest point and the samples' energy on random states near
    the hanging pose (full inertia tensors among them: the einsum path),
    bit for bit against the expressions they replace."""
    Y = _random_states(scene, np.random.default_rng(9), 3000)
    low = bh.LowestPoint([scene], np.zeros((1, 3)))
    low.add(np.zeros(len(Y), int), Y[:, 2], Y[:, 3:7])
    assert low.z[0] == _old_fold(scene, Y[:, 2], Y[:, 3:7])
    for Bn in (1, 3):  # one scene (component rows (k,)) and a batch (rows (k, B))
        Yb = np.repeat(Y[:, None, :], Bn, axis=1) * (1.0 + 0.01 * np.arange(Bn))[None, :, None]
        inertia = np.repeat(np.asarray(scene.inertia, float)[None], Bn, axis=0)
        obs = bh.Health(Bn, scene.n_wires, np.zeros((13, Bn)), np.full(Bn, scene.mass), np.full(Bn, scene.gravity),
                        inertia, np.ones((scene.n_wires, Bn)), "continue", None, None, np.ones(Bn))
        comps = list(np.ascontiguousarray(np.moveaxis(Yb, -1, 0)))
        if Bn == 1:
            comps = [c[:, 0] for c in comps]
        v, w = Yb[:, :, 7:10], Yb[:, :, 10:13]
        old = (0.5 * obs.mass * np.sum(v * v, -1) + 0.5 * np.sum(w * np.einsum("bij,kbj->kbi", inertia, w), -1)
               + obs.mass * obs.grav * Yb[:, :, 2])
        assert np.array_equal(bh._sample_energy(obs, Yb, comps), old)


def test_refine_at_local_extrema_is_the_whole_refinement():
    """A long record's tension extremes refined from the parabolas of its
    local extrema only: the values of the parabolas through every sample
    (NaN-masked samples and flat stretches among them; the refined minimum's
    time where there is one)."""
    rng = np.random.default_rng(2)
    for trial in range(40):
        K, n, B = int(rng.integers(bh.REFINE_SUBSET, 2000)), int(rng.integers(1, 4)), int(rng.integers(1, 3))
        t = np.cumsum(rng.random((K, B)) + 0.01, axis=0)
        T = np.sin(t[None] * rng.random((n, 1, B)) * 3) + 0.01 * rng.normal(size=(n, K, B))
        if trial % 3 == 0:
            T[:, rng.integers(0, K, 20), :] = np.nan
        if trial % 5 == 0:
            T[:, 100:110] = 1.0
        fast = bh.refine_extremes(t, T)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(bh, "REFINE_SUBSET", 10**9)  # every sample's parabola, as before
            every = bh.refine_extremes(t, T)
        assert np.array_equal(fast[0], every[0]) and np.array_equal(fast[2], every[2])
        found = np.isfinite(fast[0])
        assert np.array_equal(fast[1][found], every[1][found])
