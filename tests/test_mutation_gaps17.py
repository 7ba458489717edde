"""Mutation round 17 (docs/mutation.md, "Round 17"): tests that kill the
surviving mutants of session 17's new code, each against a truth computed
another way (an analytic value, another formulation, a documented
threshold written out), never against the code's own output."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation import slope_check
from bifilar.estimation.slope_check import SECANT_DISAGREE, SECANT_REACH, SECANT_SIGNIFICANT, secant_check


# ---------------------------------------------------------------------------
# slope_check.secant_check: the secant, its two gates, the admissible ends
# ---------------------------------------------------------------------------
#
# A stand-in problem with one unknown (Izz of a diagonal tensor, kg m^2) whose
# full-model period is written out: T(q) = T_lin(q) r(q), T_lin = c sqrt(q)
# (a torsion's period goes as the root of its inertia), and the amplitude
# factor r(q) = 1 + a sin(k (q - p0)) + b (q - p0) (the wiggle of audit17 row
# B3 and a smooth trend).  Its secant over +-h is then a closed form; the
# stand-in runs the code's own _secant through its factor (monkeypatched).

IXX, IYY = 0.014, 0.016
P0, C = 0.020, 12.0


def _r(q, a, k, b):
    return 1.0 + a * math.sin(k * (q - P0)) + b * (q - P0)


def _T(q, a, k, b):
    return C * math.sqrt(q) * _r(q, a, k, b)


def _problem(std_timing, a=0.0, k=1.0, b=0.0, dr_dp=None, name="Izz"):
    """(problem, law): the law's dr_dp the given one (default: the factor's
    true local derivative at P0)."""
    true_dr = a * k + b
    pb = SimpleNamespace(
        unknowns=[name],
        measurements=[SimpleNamespace(hanging=0, label="torsion", std=std_timing, amplitude=0.1)],
        models=[SimpleNamespace(hanging=SimpleNamespace(name="h"),
                                inertia_ref=lambda v: np.diag([IXX, IYY, v[0]]))],
        values=lambda q: np.asarray(q, float),
        linear_periods=lambda q: np.array([C * math.sqrt(q[0])]),
        jacobian=lambda q: np.array([[C / (2.0 * math.sqrt(q[0]))]]),
        calls=[])
    law = SimpleNamespace(dr_dp=np.array([true_dr if dr_dp is None else dr_dp], float))
    return pb, law


@pytest.fixture
def factor(monkeypatch):
    """The stand-in's amplitude factor r(q) through the code's runs (the
    parameters set per test in ``factor.abk``; each run recorded)."""
    state = SimpleNamespace(abk=(0.0, 1.0, 0.0), calls=[])

    def fake(pb, k, q, rtol):
        state.calls.append(float(q[0]))
        a, kk, b = state.abk
        return _r(float(q[0]), a, kk, b)

    monkeypatch.setattr(slope_check, "_unchecked_factor", fake)
    return state


def _full_slope(law, a, k, b, q=P0):
    """The law's full-model slope r J + T_lin dr/dp at q (s per kg m^2)."""
    return _r(q, a, k, b) * C / (2 * math.sqrt(q)) + C * math.sqrt(q) * float(law.dr_dp[0])


def test_the_secant_replaces_a_local_slope_taken_on_a_wiggle(factor):
    """Over +-1.96 std the wiggle sin(k x) averages out: the secant is the
    closed form (T(p + h) - T(p - h)) / 2h, and the law's full slope becomes
    it exactly (the budget's gain then follows it).  Truth: the formula
    evaluated here, not the code's _secant."""
    a, k, b = 0.02, 1500.0, 0.5
    factor.abk = (a, k, b)
    std = np.array([1.2e-3])
    pb, law = _problem(1e-4, a, k, b)
    loc = _full_slope(law, a, k, b)
    h = 1.96 * std[0]
    sec = (_T(P0 + h, a, k, b) - _T(P0 - h, a, k, b)) / (2 * h)
    assert abs(sec) < 0.5 * abs(loc)  # the case: the local slope is the wiggle's, the secant the trend's
    msgs, changed = secant_check(pb, [P0], np.array([_r(P0, a, k, b)]), [law], std)
    assert changed and len(msgs) == 1
    assert _full_slope(law, a, k, b) == pytest.approx(sec, rel=1e-9)
    # the runs were made at the estimate +- 1.96 std, no wider, no narrower
    assert sorted(factor.calls) == pytest.approx([P0 - h, P0 + h], rel=1e-12)


@pytest.mark.parametrize("share, warned", [(SECANT_DISAGREE - 0.01, False), (SECANT_DISAGREE + 0.01, True)])
def test_a_secant_counts_from_twenty_percent_below_the_local_slope(factor, share, warned):
    """The local slope handed in as the law's is 1 / (1 - share) of the
    secant's (a factor linear in q: its secant is exact), so they differ by
    ``share`` of the local one: 0.19 keeps the law, 0.21 replaces it
    (SECANT_DISAGREE = 0.2, the documented figure)."""
    assert SECANT_DISAGREE == 0.2
    b = 2.0
    factor.abk = (0.0, 1.0, b)
    T_lin, J = C * math.sqrt(P0), C / (2 * math.sqrt(P0))
    std = np.array([1e-3])
    h = SECANT_REACH * std[0]
    sec = (_T(P0 + h, 0, 1, b) - _T(P0 - h, 0, 1, b)) / (2 * h)
    loc = sec / (1.0 - share)
    pb, law = _problem(1e-6, dr_dp=(loc - J) / T_lin)  # a timing std far below the difference: not the gate
    before = law.dr_dp.copy()
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], std)
    assert changed is warned and len(msgs) == int(warned)
    if warned:
        assert _full_slope(law, 0, 1, b) == pytest.approx(sec, rel=1e-9)
    else:
        assert law.dr_dp[0] == before[0]


@pytest.mark.parametrize("ratio, warned", [(0.9, False), (1.1, True)])
def test_a_difference_counts_only_where_it_moves_the_period_by_a_tenth_of_the_timing_std(factor, ratio, warned):
    """The secant half the local slope; the timing std set so that the
    difference over the reach, |sec - loc| h, is 0.9 / 1.1 of
    SECANT_SIGNIFICANT (0.1) of it."""
    assert SECANT_SIGNIFICANT == 0.1
    b = 2.0
    factor.abk = (0.0, 1.0, b)
    T_lin, J = C * math.sqrt(P0), C / (2 * math.sqrt(P0))
    std = np.array([1e-3])
    h = 1.96 * std[0]
    sec = (_T(P0 + h, 0, 1, b) - _T(P0 - h, 0, 1, b)) / (2 * h)
    loc = 2.0 * sec
    timing = abs(sec - loc) * h / (ratio * 0.1)
    pb, law = _problem(timing, dr_dp=(loc - J) / T_lin)
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], std)
    assert changed is warned and len(msgs) == int(warned)


@pytest.mark.parametrize("ratio, runs", [(0.9, 0), (1.1, 2)])
def test_no_runs_where_no_smaller_secant_could_matter(factor, ratio, runs):
    """A secant between 0 and the local slope differs from it by less than
    |loc|, so where 2 |loc| h is within a tenth of the timing std no smaller
    secant can pass the gate and the two runs are not made (the documented
    shortcut): 0.9 of that edge no run, 1.1 of it the two."""
    factor.abk = (0.0, 1.0, 0.0)
    T_lin, J = C * math.sqrt(P0), C / (2 * math.sqrt(P0))
    std = np.array([1e-3])
    h = 1.96 * std[0]
    loc = J  # the law's dr_dp 0: the local slope is r J
    pb, law = _problem(2.0 * abs(loc) * h / (ratio * 0.1), dr_dp=0.0)
    secant_check(pb, [P0], np.array([1.0]), [law], std)
    assert len(factor.calls) == runs


def test_a_larger_secant_warns_and_leaves_the_law(factor):
    """A secant larger than the local slope: the local one already gives
    the larger std, the law stays as it is (changed False) but the warning
    is said."""
    b = 8.0
    factor.abk = (0.0, 1.0, b)
    std = np.array([1e-3])
    pb, law = _problem(1e-6, dr_dp=0.0)  # the local slope r J only, the secant adds T_lin b
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], std)
    assert not changed and len(msgs) == 1 and law.dr_dp[0] == 0.0


@pytest.mark.parametrize("std_izz, checked", [(2.0e-3, True), (5.2e-3, False), (11e-3, False)])
def test_a_secant_end_outside_the_bodys_tensors_leaves_the_pair_unchecked(factor, std_izz, checked):
    """The secant's ends Izz = 0.020 +- 1.96 std with Ixx 0.014, Iyy 0.016:
    a tensor a body can have up to Izz = (Ixx + Iyy) / (1 - 1e-4) (the
    triangle inequality, the config's allowance) and above 0.  std 2 mm^2:
    0.0161 .. 0.0239, both ends physical, checked; std 5.2e-3 reaches 0.0302 >
    0.030 (the triangle); 11e-3 reaches below 0 as well: no secant, no
    warning, the law unchanged."""
    b = 8.0  # the secant 1.32x the local slope r J
    factor.abk = (0.0, 1.0, b)
    pb, law = _problem(1e-6, dr_dp=0.0)
    hi = P0 + 1.96 * std_izz
    assert (hi <= (IXX + IYY) * (1 - 1e-4)) is checked
    msgs, _ = secant_check(pb, [P0], np.array([1.0]), [law], np.array([std_izz]))
    assert (len(msgs) == 1) is checked
    if not checked:
        assert law.dr_dp[0] == 0.0


def test_a_pair_without_a_std_or_a_nonlinear_law_is_not_checked(factor):
    """No run where the unknown's std is 0 / NaN, or no law has dr_dp."""
    pb, law = _problem(1e-6, dr_dp=0.0)
    factor.abk = (0.0, 1.0, 8.0)
    for std in (np.array([0.0]), np.array([math.nan]), np.array([])):
        assert secant_check(pb, [P0], np.array([1.0]), [law], std) == ([], False)
    assert secant_check(pb, [P0], np.array([1.0]), [SimpleNamespace(dr_dp=None)], np.array([1e-3])) == ([], False)
    assert secant_check(pb, [P0], np.array([1.0]), None, np.array([1e-3])) == ([], False)
    assert factor.calls == []
