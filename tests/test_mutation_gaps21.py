"""Mutation round 21 (docs/mutation.md, "Round 21"): tests that kill the
surviving mutants of session 21's new code -- birge.py, parts_prior.py,
close_modes.py, local_fits.py, the soft clipping of signal_clip.py,
phase_lean, fit_window and kernel_values.py.  Every expected value comes
from a definition worked by hand, a closed form or an independent
formulation, never from the code's own output."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.estimation.birge import birge_factor, widen_timing
from bifilar.estimation.uncertainty import LinearBudget

# ---------------------------------------------------------------- birge


def _fit(chi2, dof, passed=True, with_inputs=None):
    return {"passed": passed, "chi2": chi2, "dof": dof, "chi2_with_inputs": with_inputs}


def test_birge_factor_divides_chi2_by_its_degrees_of_freedom():
    """``B = sqrt(chi2 / dof)``: chi2 8 on 2 dof is 2 (chi2 x dof would give 4), 27 on 3 is 3; a fit
    check without a dof count has none (the documented ``dof > 0``): 1."""
    assert birge_factor(_fit(8.0, 2)) == pytest.approx(2.0, rel=1e-15)
    assert birge_factor(_fit(27.0, 3)) == pytest.approx(3.0, rel=1e-15)
    assert birge_factor({"passed": True, "chi2": 9.0, "chi2_with_inputs": None}) == 1.0
    assert birge_factor(_fit(9.0, 1, passed=False)) == 1.0
    assert birge_factor(_fit(math.nan, 1)) == 1.0


def _budget():
    """Izz (kg m^2) with two timing terms and one length term: contributions c_j, sigmas s_j written out."""
    contrib = {"timing[torsion]": np.array([3e-3]), "timing[roll]": np.array([-1e-3]), "length.1": np.array([2e-3])}
    cov = sum(np.outer(c, c) for c in contrib.values())
    return LinearBudget(["Izz"], cov, contrib, {"timing[torsion]": 1e-3, "timing[roll]": 2e-3, "length.1": 5e-4})


def test_widening_by_a_factor_between_one_and_two_scales_the_timing_sigmas_only():
    """A factor 1.5 (above 1: widened) multiplies each timing term's contribution and its stated sigma by
    1.5 and leaves the length's; the variance is the length's plus 1.5^2 the timing's (9 + 1 + 4 in
    1e-6 units -> 2.25 x 10 + 4)."""
    w = widen_timing(_budget(), 1.5)
    assert w.covariance[0, 0] == pytest.approx((2.25 * 10 + 4) * 1e-6, rel=1e-12)
    assert w.sigmas == pytest.approx({"timing[torsion]": 1.5e-3, "timing[roll]": 3e-3, "length.1": 5e-4}, rel=1e-12)
    assert w.contributions["length.1"][0] == 2e-3
    b = _budget()
    assert widen_timing(b, 1.0) is b and widen_timing(b, 0.5) is b
