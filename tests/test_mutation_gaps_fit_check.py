"""Tests written to kill surviving mutants of the fit check
(``bifilar/estimation/fit_check.py``; see docs/mutation.md).  Truths: the
documented thresholds (docs/invert.md, "The fit check": ``max |z| <= 0.1``
for as many periods as unknowns, the chi-square 99.9 % quantile for more,
whose values are taken from a printed chi-square table), and the exact
period of a pendulum (the swing of a body on parallel wires: a translation
on a circle of radius L, ``T = 4 sqrt(L/g) K(sin^2(theta/2))``) -- never
output of the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ellipk

from bifilar.estimation import fit_check
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet

from test_fit_check_inputs import UNC, _closed_form, _ms, _plate, L

#: chi-square 99.9 % quantiles for 1, 2, 3 degrees of freedom (printed tables, e.g. Abramowitz & Stegun 26.8)
CHI2_999 = {1: 10.828, 2: 13.816, 3: 16.266}


def test_fit_statistics_is_the_documented_rule():
    """As many periods as unknowns: every |z| <= 0.1 (0.09 passes, 0.11
    fails; chi2 is still sum z^2).  More periods: chi2 = sum z^2 against
    its 99.9 % quantile with K - P degrees of freedom, 1 % either side of
    the table value.  A non-finite residual fails with an infinite chi2."""
    for K in (1, 2):
        ok, chi2, _ = fit_check.fit_statistics(np.full(K, 0.09), K)
        assert ok and chi2 == pytest.approx(K * 0.0081)
        assert not fit_check.fit_statistics(np.r_[np.full(K - 1, 0.0), -0.11], K)[0]
    for dof, q in CHI2_999.items():
        assert fit_check.chi2_limit(dof + 2, 2) == pytest.approx(q, abs=1e-3)
        for f, passes in ((0.99, True), (1.01, False)):
            z = np.full(dof + 1, math.sqrt(f * q / (dof + 1)))  # K = dof + 1 periods, P = 1 unknown
            ok, chi2, how = fit_check.fit_statistics(z, 1)
            assert ok is passes and chi2 == pytest.approx(f * q), (dof, f)
            assert f"{dof} degrees of freedom" in how
    ok, chi2, _ = fit_check.fit_statistics(np.array([0.0, np.nan, 0.0]), 1)
    assert not ok and chi2 == math.inf


def test_unstated_amplitude_variance_is_the_exact_pendulums_second_moment():
    """A swing timed at an unstated amplitude: releases uniform in 0 ..
    A_max = L sin 10 degrees (the sideways displacement) lengthen it by
    ``r(A) - 1``, so the second moment is ``T^2 E[(r(A) - 1)^2]`` with
    ``r`` the exact pendulum's factor, ``(2 / pi) K(sin^2(theta / 2))``,
    ``theta = asin(A / L)`` (the plate on vertical parallel wires swings
    along the attachment line as a pendulum of length L), the mean over
    ``A`` by Gauss-Legendre quadrature.  The quadratic rule's ``(T (r_max -
    1))^2 / 5`` is 0.7 % above it (``asin`` and the elliptic integral add
    an ``A^4`` term), outside the band; the amplitude law's two runs give
    it to 5e-5.  The torsion, timed at a stated amplitude, has none."""
    T_t, T_s = _closed_form(L)
    ms = MeasurementSet([Hanging("ref", _plate(), np.eye(3))],
                        [Measurement("torsion", T_t, 1e-3, "period", "--period", amplitude=0.0),
                         Measurement("swing-x", T_s, 1e-3, "period", "--period", amplitude=None)])
    res = invert(ms, solve_for=["Izz"], unc={**UNC, "timing": 1e-3}, ladder=False, method="linear")
    v = fit_check.unstated_amplitude_variance(res.problem, res.values)
    x, w = np.polynomial.legendre.leggauss(40)
    A = 0.5 * L * math.sin(math.radians(10.0)) * (x + 1)
    r = 2 / math.pi * ellipk(np.sin(np.arcsin(A / L) / 2) ** 2)
    assert v[0] == 0.0
    assert v[1] == pytest.approx(T_s ** 2 * 0.5 * float(w @ (r - 1) ** 2), rel=1e-4)


def test_inputs_explain_accepts_an_input_error_within_its_cost_and_refuses_one_beyond():
    """The plate's torsion and swing periods with both wires ``d`` longer
    than the config says (closed forms), against the answer for the
    written lengths; timing variance 1e-8 s^2.  The check's misfit is the
    least ``|dx / s|^2 + |res - dT|^2 / var`` over input errors ``dx``
    (the conditional mean minimises its linearisation), so:

    * at most that of the known explanation, both lengths ``d`` off: ``2
      (d / 1 mm)^2`` (1 mm std; the model term ~0);
    * at least ``(2 d)^2 / 6`` in units of the 1 mm std: the swing period
      ``2 pi sqrt(L / g)`` of vertical wires needs their mean vertical
      extent ``d`` longer, which only the two lengths and the anchors' and
      attachments' z move (to first order), 1 mm std each: six inputs
      whose changes sum to ``2 d``, Cauchy-Schwarz.

    1 mm: accepted at a limit of 2.0, refused at 0.6 (< 4/6); 10 mm: refused
    at 60 (< 400/6 = 66.7), accepted at 210 (200 plus 5 % for the model's
    curvature over 10 mm)."""
    T0 = np.array(_closed_form(L))
    res = invert(_ms(_plate(), T0, UNC["timing"]), solve_for=["Izz"], unc=UNC, ladder=False, method="linear")
    pb, p = res.problem, res.values
    base = fit_check.labelled_periods(pb, p)
    var = np.full(2, 1e-8)
    for d, below, above in ((1e-3, 0.6, 2.0), (1e-2, 60.0, 210.0)):
        r = np.array(_closed_form(L + d)) - base
        assert not fit_check.inputs_explain(pb, p, r, var, below), d
        assert fit_check.inputs_explain(pb, p, r, var, above), d


def test_an_exactly_determined_answer_is_accepted_within_two_sigma(monkeypatch):
    """One period, one unknown (the torsion's Izz), the inputs' covariance
    set to 0: the step to the exact fit in the metric of its covariance is
    ``z^2`` (``d = res / J``, covariance ``sigma^2 / J^2``), and an edge
    answer is accepted within EDGE_Z = 2 sigma (docs/invert.md): ``z`` =
    1.9 passes (the inputs, 1 mm, explain 0.19 ms easily), 2.1 does not."""
    T_t, _ = _closed_form(L)
    ms = MeasurementSet([Hanging("ref", _plate(), np.eye(3))],
                        [Measurement("torsion", T_t, UNC["timing"], "period", "--period", amplitude=0.0)])
    res = invert(ms, solve_for=["Izz"], unc=UNC, ladder=False, method="linear")
    monkeypatch.setattr(fit_check, "input_period_covariance", lambda pb_, p_, r_=None: np.zeros((1, 1)))
    for z, passes in ((1.9, True), (-1.9, True), (2.1, False), (-2.1, False)):
        ok, chi2_fit, dist, how = fit_check.input_fit_check(res.problem, res.values, np.array([z]),
                                                            amp_var=np.zeros(1))
        assert dist == pytest.approx(z * z, rel=1e-9) and chi2_fit == pytest.approx(0.0, abs=1e-12)
        assert ok is passes, z
        assert "<= 4 (1 degrees of freedom, 2 sigma)" in how, how
