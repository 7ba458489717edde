"""Tests that kill mutants the rest of the suite let survive (docs/mutation.md).

Each test names the mutant(s) it kills: module, line's code and the change.
Every expected value comes from an independent truth (a hand-solved
static, an analytic formula, a textbook quantile), never from the code
under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.analysis.tensions import general_tensions, symmetric_tension

G = 9.81


# ---------------------------------------------------------------------------
# bifilar/analysis/tensions.py
# ---------------------------------------------------------------------------

def test_symmetric_tension_takes_theta2_from_wire_1():
    """Kills tensions.py ``cos2 = units[:, 0, 2]`` -> ``units[:, 1, 2]``.

    The documented convention: theta2 is wire 1's angle to the vertical.
    With wire 1 vertical and wire 2 at 60 deg (mirror symmetry broken on
    purpose), F_t = m (g + a_z) / (2 cos 0) = m (g + a_z) / 2 by hand."""
    k = 3
    u = np.zeros((k, 2, 3))
    u[:, 0] = [0.0, 0.0, 1.0]
    u[:, 1] = [math.sin(math.pi / 3), 0.0, math.cos(math.pi / 3)]
    az = np.array([-0.5, 0.0, 0.7])
    m = 2.0
    np.testing.assert_allclose(symmetric_tension(m, G, az, u), m * (G + az) / 2, rtol=1e-14)


def test_general_tensions_residual_is_per_sample_force_imbalance():
    """Kills tensions.py ``np.linalg.norm(..., axis=-1)`` -> ``axis=-2`` (the
    residual normed over time instead of per sample; the existing test only
    checks a consistent system, whose residual is ~0 either way).

    Two vertical wires cannot balance a horizontal acceleration a_x: by
    hand the least-squares tensions carry the vertical load m g (split
    equally, the minimum-norm solution) and the residual at each sample is
    the unbalanced horizontal force m |a_x|."""
    k = 4  # != 3, so a wrongly shaped residual cannot broadcast
    u = np.zeros((k, 2, 3))
    u[:, :, 2] = 1.0
    ax = np.array([0.3, -1.2, 0.0, 2.5])
    accel = np.column_stack([ax, np.zeros(k), np.zeros(k)])
    m = 3.0
    F, res = general_tensions(m, G, accel, u)
    assert res.shape == (k,)
    np.testing.assert_allclose(res, m * np.abs(ax), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(F, m * G / 2, rtol=1e-12)
