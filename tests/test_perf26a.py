"""Session 26, perf26a: a sweep point's start poses and runs without work
repeated on known values; each shortcut against the path it replaces, bit for
bit (docs/performance.md, "Session 26, perf26a")."""

from __future__ import annotations

import numpy as np


def _bits(a) -> np.ndarray:
    return np.ascontiguousarray(a, float).view(np.int64)


def test_quat_to_matrix_stacked_equals_the_entry_by_entry_path(monkeypatch):
    # 9 .. 256 quaternions (a start-pose solve's 9-row batches and its 108-row Hessian poses) take the entries'
    # products from one outer product; against the entry-by-entry numpy path (_FEW = _STACKED = 0: all it was
    # for these sizes): the same bits over random, tiny, huge and nearly identity quaternions in every shape
    # it takes, and the same NaN / inf for zero or non-finite ones
    from bifilar import rotations
    from bifilar.rotations import quat_to_matrix

    def entry_by_entry(q):
        with monkeypatch.context() as m:
            m.setattr(rotations, "_FEW", 0)
            m.setattr(rotations, "_STACKED", 0)
            return quat_to_matrix(q)

    rng = np.random.default_rng(26)
    n = 0
    for shape in ((9, 4), (20, 4), (108, 4), (256, 4), (3, 5, 4)):
        for scale in (1e-150, 1e-3, 1.0, 1e3, 1e150):
            for _ in range(8):
                q = rng.normal(size=shape) * scale
                q[rng.uniform(size=shape[:-1]) < 0.3, 1:] *= 1e-9  # nearly identity rows
                got = quat_to_matrix(q)
                assert got.shape == shape[:-1] + (3, 3)
                assert np.array_equal(_bits(got), _bits(entry_by_entry(q)))
                n += 1
    with np.errstate(all="ignore"):
        bad = rng.normal(size=(12, 4))
        bad[0], bad[1, 0], bad[2, 3], bad[3, 1] = 0.0, np.nan, np.inf, -np.inf
        assert np.array_equal(quat_to_matrix(bad), entry_by_entry(bad), equal_nan=True)
    assert n == 200
