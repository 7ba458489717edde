"""The Birge factor: timing stds widened where the periods scatter more
than they state.

An overdetermined fit that passes its check on the timing alone (chi-square
below its 99.9 % quantile, :mod:`bifilar.estimation.fit_check`) may still
have ``chi2 / dof > 1``: the periods disagree more than their stated timing
stds allow, which a mistyped or mis-timed period does (one of two torsion
timings 0.1 % off at 1 ms).  The budget, built on the stated stds, then
undercovers (the 95 % interval covered the truth in 76 % of such draws, 26 %
for a 0.2 % typo; docs/design.md, "Fit check and interval honesty, session
20").  As in the Particle Data Group's practice (R. T. Birge, Phys. Rev. 40,
207 (1932)), the timing terms of the budget are scaled by
``B = sqrt(chi2 / dof)`` where it exceeds 1: the scatter the data show
stands in for the stated std.  Not applied where the fit needed the
measured inputs' uncertainty (its misfit is then the inputs', which the
budget carries) or has no degrees of freedom.  Dimensionless; the budget's
contributions in the unknowns' SI units.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .uncertainty import LinearBudget, covariance_of, group_of


def birge_factor(fit: dict) -> float:
    """``sqrt(chi2 / dof)`` of the fit check ``fit`` (``chi2``, ``dof``,
    ``chi2_with_inputs``: :func:`bifilar.estimation.invert._fit_check`'s
    dict) where it exceeds 1 for a fit that passed on the timing alone
    with ``dof`` > 0, else 1.0."""
    dof, chi2 = fit.get("dof", 0), fit.get("chi2", math.nan)
    if not fit.get("passed") or dof <= 0 or fit.get("chi2_with_inputs") is not None or not math.isfinite(chi2):
        return 1.0
    return max(1.0, math.sqrt(chi2 / dof))


def timing_scale(res) -> float:
    """The factor an inversion result ``res`` widened its timing terms by:
    its fit check's ``birge_factor`` (1.0 where it has none).  The Monte
    Carlo (:func:`~bifilar.estimation.montecarlo.draw_monte_carlo`) draws
    each period with this times its stated std, so that it checks the
    widened budget."""
    fit = getattr(res, "fit", None) or {}
    return float(fit.get("birge_factor", 1.0))


def widen_timing(budget: LinearBudget, factor: float) -> LinearBudget:
    """``budget`` with each timing contribution (group ``timing``) times
    ``factor`` and the covariance summed again; the same budget where
    ``factor`` is 1."""
    if not factor > 1.0:
        return budget
    contrib = {n: (np.asarray(c, float) * factor if group_of(n) == "timing" else c)
               for n, c in budget.contributions.items()}
    sigmas = {n: (s * factor if group_of(n) == "timing" else s) for n, s in budget.sigmas.items()}
    cov = covariance_of(contrib, len(budget.names))
    return replace(budget, covariance=cov, contributions=contrib, sigmas=sigmas)


def widen_std(budget: LinearBudget, std, factor: float) -> np.ndarray:
    """(P,) the std ``std`` (SI, e.g. a budget's linear std before its
    second-order terms) with the timing variance of ``budget`` widened by
    ``factor`` as :func:`widen_timing` widens it: ``sqrt(std^2 + (factor^2
    - 1) v_t)``, ``v_t`` the sum of the timing contributions' squares;
    ``std`` where ``factor`` is 1."""
    std = np.asarray(std, float)
    if not factor > 1.0:
        return std
    v_t = sum((np.asarray(c, float) ** 2 for n, c in budget.contributions.items() if group_of(n) == "timing"),
              np.zeros_like(std))
    return np.sqrt(std ** 2 + (factor ** 2 - 1.0) * v_t)


def birge_note(factor: float, fit: dict) -> str:
    """The stderr line of a Birge factor above 1."""
    return (f"the measured periods scatter more than their stated timing stds (chi2 {fit['chi2']:.3g} for "
            f"{fit['dof']} degree{'s' if fit['dof'] > 1 else ''} of freedom): the timing terms of the budget are "
            f"widened by the Birge factor sqrt(chi2/dof) = {factor:.3g}; check the periods for a typo or a "
            "timing on another mode")
