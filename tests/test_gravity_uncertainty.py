"""A stated uncertainty of gravity (``--uncertainty gravity=S``, relative;
docs/invert.md's table, default 0) is in invert's budget.  It was accepted
and drawn by the Monte Carlo, but the budget's inputs left g out, so the
printed std and interval ignored it (found with the amplitude factor's
Monte Carlo, session 9)."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet

from conftest import trapezoid

UNC = {"length": 1e-3, "position": 1e-3, "mass": 1e-3, "com": 2e-3, "timing": 1e-3}


@pytest.mark.parametrize("mode, comp", [("torsion", "Izz"), ("pitch", "Iyy")])
def test_gravity_term_is_a_period_change_of_half_its_relative_std(mode, comp):
    # every linear period of a wire-hung rigid body scales as 1 / sqrt(g) (all its stiffness is m g
    # times geometry), so a relative error s of g acts on the estimate as a period error T s / 2 does:
    # the gravity term is the timing term times (T s / 2) / sigma_T.  Forward differences: ~1e-6
    s = trapezoid(h=0.3)
    T = float(linear_modes(s, rest_pose(s)).get(mode).period)
    ms = MeasurementSet([Hanging("ref", s, np.eye(3))], [Measurement(mode, T, 1e-3, "period", "--period",
                                                                      amplitude=0.0)])
    res = invert(ms, method="linear", solve_for=[comp], unc={**UNC, "gravity": 2e-3}, ladder=False)
    c = res.budget.contributions
    assert abs(c["gravity"][0]) == pytest.approx(abs(c[f"timing[{mode}]"][0]) * T * (2e-3 / 2) / 1e-3, rel=1e-4)
    assert res.budget.grouped(0)["gravity"][1] == pytest.approx(abs(c["gravity"][0]), rel=1e-12)
    known = invert(ms, method="linear", solve_for=[comp], unc={**UNC, "gravity": 0.0}, ladder=False)
    assert "gravity" not in known.budget.contributions
    assert res.sigma(comp) == pytest.approx(np.hypot(known.sigma(comp), c["gravity"][0]), rel=1e-6)
