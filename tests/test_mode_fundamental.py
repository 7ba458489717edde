"""The fundamental of a mode in a simulated run (``bifilar.analysis.fundamental``):
the period and amplitude ``invert``'s nonlinear model gives a fitted record
(docs/invert.md, "Signal audit, session 10").

Checked on a motion without other oscillations, where the mean period
between crossings is exact (a symmetric bifilar's torsion stays on its own
one-degree-of-freedom manifold: its coordinate is periodic), and the
fundamental's amplitude is the first Fourier coefficient over whole periods
between those crossings, an independent formulation of it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.fundamental import mode_fundamental
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import scene_from_dict

SYMMETRIC = {"body": {"mass": 2.0, "inertia": {"principal": [0.05, 0.03, 0.07]}},
             "rig": {"anchors": [[0.2, 0.0, 1.0], [-0.2, 0.0, 1.0]], "attachments": [[0.2, 0.0, 0.0], [-0.2, 0.0, 0.0]],
                     "lengths": [1.0, 1.0]}}


@pytest.fixture(scope="module")
def torsion_run():
    scene = scene_from_dict(SYMMETRIC, warn=False)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    k = next(i for i, m in enumerate(ms.modes) if m.label == "torsion")
    A = 0.3  # rad: a large release, so the harmonics and the amplitude's shift are not negligible
    sim = simulate(scene, k + 1, A, 12, rest=rest, modes=ms, rtol=1e-11, samples_per_period=128, check=False)
    return rest, ms, k, A, sim


def test_the_fundamentals_period_is_the_crossings_one_without_other_oscillations(torsion_run):
    """Period within 1e-8 of the crossings' (measured 3e-10; the run's
    period error at rtol 1e-11 is ~1e-11), started 1e-4 off."""
    rest, ms, k, A, sim = torsion_run
    T, _ = mode_fundamental(sim.t, sim.y, rest, ms, k, sim.period)
    assert T == pytest.approx(sim.period, rel=1e-8)
    T2, _ = mode_fundamental(sim.t, sim.y, rest, ms, k, sim.period * (1 + 1e-4))
    assert T2 == pytest.approx(sim.period, rel=1e-8)


def test_the_fundamentals_amplitude_is_its_fourier_coefficient_not_the_release(torsion_run):
    """The first Fourier coefficient of the coordinate over the whole
    periods between the first and last crossings (a cubic spline of the
    samples, 4000 points a period): within 1e-7 relative (measured 1e-9).
    It is 1.0007 times the release here (the harmonics' share of the
    starting angle), so the release itself is off by far more than that."""
    rest, ms, k, A, sim = torsion_run
    _, a = mode_fundamental(sim.t, sim.y, rest, ms, k, sim.period)
    tc = sim.crossings
    n = len(tc) - 1
    tt = np.linspace(tc[0], tc[-1], 4000 * n, endpoint=False)
    yy = CubicSpline(sim.t, sim.coordinate)(tt)
    ph = 2 * np.pi * (tt - tc[0]) / sim.period
    fourier = math.hypot(2 * np.mean(yy * np.cos(ph)), 2 * np.mean(yy * np.sin(ph)))
    assert a == pytest.approx(fourier, rel=1e-7)
    assert abs(a / A - 1) > 1e-4  # the amplitude the correction carries r over is not nothing
