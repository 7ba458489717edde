"""Reductions along a short axis of a long record, by columns.

numpy reduces the last axis of a (k, m) array (or the first of a C-ordered
(k, m) array) with one inner-loop call per row when m is small: ~50 ns a
row, so a 13 000-sample record's max over 8 box corners or min over 2 wires
costs ~0.8-2.5 ms, while m element-wise passes over its columns cost ~10 us
each.  These give the same values bit for bit: a max or min is exact in any
order, and a sum is taken in numpy's order for fewer than 8 terms,
((a0 + a1) + a2) + ... (docs/design.md, "Session 14, perf16";
tests/test_rowwise.py).  Beside the layers: imports numpy only.
"""

from __future__ import annotations

import numpy as np


def row_max(M: np.ndarray) -> np.ndarray:
    """``np.max(M, axis=-1)`` of a 2-D array (k, m), m >= 1, by columns.
    (A NaN propagates as there.)"""
    M = np.asarray(M)
    out = np.array(M[:, 0], dtype=float)
    for j in range(1, M.shape[1]):
        np.maximum(out, M[:, j], out=out)
    return out


def column_extremes(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(``T.min(axis=0)``, ``T.max(axis=0)``) of a 2-D array (k, n), k >= 1,
    column by column."""
    T = np.asarray(T)
    return (np.array([T[:, i].min() for i in range(T.shape[1])], dtype=float),
            np.array([T[:, i].max() for i in range(T.shape[1])], dtype=float))


def row_sum(cols) -> np.ndarray:
    """``np.sum(M, axis=-1)`` of the array whose last-axis entries are the
    arrays ``cols`` (fewer than 8 of them: numpy's order, left to right)."""
    if len(cols) >= 8:
        raise ValueError("row_sum follows numpy's order only for fewer than 8 terms")
    out = cols[0]
    for c in cols[1:]:
        out = out + c
    return out
