"""Mutation round 20 (docs/mutation.md, "Round 20"): tests that kill the
surviving mutants of design_noise.py, signal_quantisation.py,
signal_wrap.py and signal_crossings.py.  Every expected value comes from
the physics, a hand computation or an independent formulation, never from
the code's own output."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.estimation.design_noise import (DILUTION_MAX, corrected_normal_equations, correction_std,
                                             design_noise, undetermined_by_noise, variance_rse)
from bifilar.estimation.from_tensions import COMPONENTS

# ---------------------------------------------------------------- design_noise

#: the symmetric index pair of each component (independent of the config's table)
_PAIR = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


def _column_noise(d: np.ndarray, comp: str) -> np.ndarray:
    """The noise of component ``comp``'s column, written out by hand: the
    column is ``E alpha`` with ``E`` the symmetric unit matrix of the pair,
    so a diagonal component carries ``d_i`` in row ``i`` and an off-diagonal
    one ``d_j`` in row ``i`` and ``d_i`` in row ``j``.  ``d`` (n, 3)."""
    i, j = _PAIR[comp]
    out = np.zeros_like(d)
    out[:, i] = d[:, j]
    out[:, j] = d[:, i]
    return out


_C = np.array([[2.0, 0.3, -0.5], [0.3, 1.0, 0.2], [-0.5, 0.2, 3.0]])  # (rad/s^2)^2, positive definite


def test_design_noise_is_the_covariance_of_the_columns_noise_by_hand():
    """``S_jl = E[(E_j d) . (E_l d)]``: Ixx with Ixx is ``C_xx``; Ixy with
    itself ``C_xx + C_yy`` (its column has ``d_y`` in row x and ``d_x`` in
    row y); Ixx with Ixy ``C_xy`` (only row x overlaps: ``d_x d_y``); Ixy
    with Ixz ``C_yz`` (row x: ``d_y d_z``); Ixx with Iyy 0."""
    S = design_noise(_C)
    ix = {c: COMPONENTS.index(c) for c in COMPONENTS}
    assert S.shape == (6, 6)
    assert S[ix["Ixx"], ix["Ixx"]] == pytest.approx(2.0)
    assert S[ix["Izz"], ix["Izz"]] == pytest.approx(3.0)
    assert S[ix["Ixy"], ix["Ixy"]] == pytest.approx(3.0)
    assert S[ix["Ixz"], ix["Ixz"]] == pytest.approx(5.0)
    assert S[ix["Iyz"], ix["Iyz"]] == pytest.approx(4.0)
    assert S[ix["Ixx"], ix["Ixy"]] == pytest.approx(0.3)
    assert S[ix["Ixy"], ix["Ixz"]] == pytest.approx(0.2)
    assert S[ix["Ixy"], ix["Iyz"]] == pytest.approx(-0.5)
    assert S[ix["Ixx"], ix["Iyy"]] == pytest.approx(0.0, abs=1e-15)
    assert np.allclose(S, S.T)


def test_design_noise_matches_a_sampled_covariance_of_the_columns():
    """Independent formulation: draw ``d ~ N(0, C)``, build each column's
    noise by hand and average the products; 400 000 draws put the sampled
    entries within ~0.02 of the exact ones (entries of size 1-5, the
    standard error of a product's mean ~sqrt(2 * 25 / 4e5) ~ 0.011)."""
    rng = np.random.default_rng(20)
    d = rng.multivariate_normal(np.zeros(3), _C, size=400_000)
    cols = [_column_noise(d, c) for c in COMPONENTS]
    sampled = np.array([[np.mean(np.sum(a * b, axis=1)) for b in cols] for a in cols])
    assert np.allclose(design_noise(_C), sampled, atol=0.05)


def _eiv_problem(seed: int, k: int, fixed: bool):
    """Errors in the variables of Euler's equations (a stand-in: the design's
    exact columns random and O(1), each sample three rows): the noisy design
    ``A = A0 + D`` with each column's noise ``E_j d`` (``d ~ N(0, C)`` per
    sample), the torque exact.  With held components ``f``, ``b = tau - A_f
    x_f`` so its noise ``-D_f x_f`` correlates with the solved columns'."""
    rng = np.random.default_rng(seed)
    comps = ("Ixx", "Iyy", "Izz") if fixed else COMPONENTS
    held = ["Ixy", "Ixz", "Iyz"] if fixed else []
    x_all = {"Ixx": 2.0, "Iyy": 1.5, "Izz": 3.0, "Ixy": 1.2, "Ixz": -0.9, "Iyz": 0.8}
    A0 = {c: rng.standard_normal(3 * k) for c in COMPONENTS}
    d = rng.multivariate_normal(np.zeros(3), 0.3 * _C, size=k)
    A = {c: A0[c] + _column_noise(d, c).reshape(-1) for c in COMPONENTS}
    tau = sum(A0[c] * x_all[c] for c in COMPONENTS)
    xf = np.array([x_all[c] for c in held])
    b = tau - sum((A[c] * x_all[c] for c in held), np.zeros(3 * k))
    return comps, held, xf, np.column_stack([A[c] for c in comps]), b, np.array([x_all[c] for c in comps])


@pytest.mark.parametrize("fixed", [False, True])
def test_corrected_normal_equations_remove_the_dilution(fixed):
    """The classical errors-in-variables correction: with noise power ~0.3-1.5
    of the columns' 1, plain least squares lie ~25-45 % off; the corrected
    estimate (in scaled unknowns ``x scale``, scale not 1) lands within 1.5 %
    of the truth with three held components, 4 % with all six solved (k =
    40 000 samples; over seeds 7-10 its error was at most 0.5 % / 1.3 %).
    With held components the ``S_cf`` term matters: left out, or divided by
    the scale twice too few (``* scale``), the solved diagonal is 4-6 % off."""
    k = 40_000
    comps, held, xf, A, b, truth = _eiv_problem(7, k, fixed)
    scale = np.linspace(0.5, 2.0, len(comps))
    noise = design_noise(0.3 * _C)
    xs, S_cc, offset = corrected_normal_equations(A / scale, b, scale, noise, comps, held, xf, k)
    x = xs / scale
    plain = np.linalg.lstsq(A, b, rcond=None)[0]
    assert np.max(np.abs(plain - truth) / np.abs(truth)) > 0.2  # the dilution exists
    assert np.max(np.abs(x - truth) / np.abs(truth)) < (0.015 if fixed else 0.04), (x, truth)
    ic = [COMPONENTS.index(c) for c in comps]
    assert np.allclose(S_cc, noise[np.ix_(ic, ic)] / np.outer(scale, scale))


def test_corrected_scores_sum_to_zero_at_the_estimate():
    """The offset's defining property (docstring): the samples' scores
    ``As_k^T r_k + offset`` sum to zero at the estimate, i.e. ``As^T (b -
    As x) + k offset = 0`` -- an identity of the corrected equations, on a
    small problem with held components and a non-unit scale."""
    k = 50
    comps, held, xf, A, b, _ = _eiv_problem(3, k, True)
    scale = np.array([0.7, 1.3, 2.1])
    As = A / scale
    xs, _, offset = corrected_normal_equations(As, b, scale, design_noise(0.3 * _C), comps, held, xf, k)
    total = As.T @ (b - As @ xs) + k * offset
    assert np.allclose(total, 0.0, atol=1e-9 * np.abs(As.T @ b).max())


def test_correction_std_is_the_correction_times_the_noise_estimates_rse():
    assert np.allclose(correction_std([2.0, -1.0], [1.5, -1.2], 0.1), [0.05, 0.02])
    assert np.allclose(correction_std([1.0], [1.5], 0.2), [0.1])


def test_a_component_is_undetermined_past_half_its_columns_power():
    """``k S_jj`` above ``DILUTION_MAX`` (0.5) of the column's own scaled power
    1 leaves the component undetermined; at or below it (a positive
    definite corrected matrix) it is kept."""
    assert DILUTION_MAX == 0.5
    N = np.diag([1.0, 2.0, 3.0])
    assert list(undetermined_by_noise([0.45, 0.55, 0.5], N)) == [False, True, False]
    assert not undetermined_by_noise([0.1, 0.2, 0.3], N).any()


def test_a_corrected_matrix_not_positive_definite_leaves_every_component_undetermined():
    """The corrected normal matrix must be positive definite: a zero or
    negative eigenvalue of its symmetric part, or a non-finite entry, marks
    all.  A non-symmetric but positive definite matrix (symmetric part
    diag(1, 1)) is fine."""
    low = [0.1, 0.1]
    assert undetermined_by_noise(low, np.diag([1.0, 0.0])).all()
    assert undetermined_by_noise(low, np.diag([1.0, -1e-3])).all()
    assert undetermined_by_noise(low, np.array([[1.0, np.nan], [0.0, 1.0]])).all()
    assert undetermined_by_noise(low, np.array([[1.0, np.inf], [0.0, 1.0]])).all()
    assert not undetermined_by_noise(low, np.array([[1.0, 0.8], [-0.8, 1.0]])).any()
    assert not undetermined_by_noise(low, np.array([[1.0, 1.5], [0.1, 1.0]])).any()  # sym part eig 0.2, 1.8


def test_variance_rse_is_that_of_a_normal_samples_variance():
    """The sample variance of ``n`` independent N(0, 1) residuals (known mean)
    is chi^2_n / n: its relative std is ``sqrt(2 / n)`` -- 0.2 at n = 50,
    and checked against 20 000 sampled variances of 50; fewer than one
    residual counts as one."""
    assert variance_rse(50.0) == pytest.approx(0.2)
    assert variance_rse(2.0) == pytest.approx(1.0)
    assert variance_rse(0.5) == pytest.approx(math.sqrt(2.0))
    assert variance_rse(0.0) == pytest.approx(math.sqrt(2.0))
    rng = np.random.default_rng(5)
    v = np.mean(rng.standard_normal((20_000, 50)) ** 2, axis=1)
    assert np.std(v) == pytest.approx(variance_rse(50), rel=0.03)


# ---------------------------------------------------------------- signal_wrap

from bifilar.estimation.signal_wrap import MAX_STEP_TURNS, unwrap_record  # noqa: E402


def test_a_heading_sampled_exactly_eight_times_a_turn_is_unwrapped():
    """"Sampled at least 8 times a turn of its own motion" includes 8: a
    heading in degrees turning by exactly 45 deg (= MAX_STEP_TURNS x 360, a
    float-exact step) a sample, wrapped at +-180, is put back (the step is
    not larger than an eighth of a turn)."""
    assert MAX_STEP_TURNS * 360.0 == 45.0
    y, w = unwrap_record(np.array([90.0, 135.0, 180.0, -135.0, -90.0]))
    assert w is not None and "+-180" in w
    assert np.array_equal(y, [90.0, 135.0, 180.0, 225.0, 270.0])


def test_an_atan2_record_holding_both_plus_and_minus_pi_spans_exactly_one_turn_and_is_unwrapped():
    """atan2 returns +pi or -pi at the wrap itself depending on the sign of
    the zero (``atan2(+-0.0, -1)``): a record oscillating across the wrap
    can hold both, spanning exactly one turn, which "at most one turn"
    admits.  Unwrapped: 3, pi, 2 pi - 3, pi, 3 (steps 0.14 rad)."""
    y = np.array([3.0, math.atan2(0.0, -1.0), -3.0, math.atan2(-0.0, -1.0), 3.0])
    assert np.ptp(y) == 2 * math.pi
    out, w = unwrap_record(y)
    assert w is not None and "+-pi" in w
    assert np.allclose(out, [3.0, math.pi, 2 * math.pi - 3.0, math.pi, 3.0], atol=1e-12)


def test_a_degree_heading_holding_both_plus_and_minus_180_is_unwrapped():
    """The same in degrees: 170, 180, -170, -180, 170 spans exactly 360 and
    unwraps to 170, 180, 190, 180, 170 (2 pi is tried first: its span is
    exceeded)."""
    out, w = unwrap_record(np.array([170.0, 180.0, -170.0, -180.0, 170.0]))
    assert w is not None and "+-180" in w
    assert np.allclose(out, [170.0, 180.0, 190.0, 180.0, 170.0], atol=1e-12)


# ---------------------------------------------------------------- signal_crossings

from bifilar.estimation.signal_crossings import period_from_crossings  # noqa: E402


def _gapped_sine(t_end: float, gap: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """``sin(2 pi t)`` (period 1 s, upward zero crossings at whole seconds,
    downward at halves) sampled at 200 Hz from 0.6 s, its amplitude 0.01
    (inside a 0.1 hysteresis band: no crossing) over ``gap``, which starts
    and ends at a trough (t = k + 0.75) so no crossing is half made."""
    t = np.arange(0.6, t_end, 0.005)
    env = np.where((t > gap[0]) & (t < gap[1]), 0.01, 1.0)
    return t, env * np.sin(2 * math.pi * t)


def test_two_complete_periods_between_lost_crossings_are_enough():
    """Crossings up 1, 2, 5 and down 1.5, 2.5 (three cycles lost in the band
    between 2.75 and 4.75 s): the rough period is the median of the
    same-direction intervals 1, 3, 1 = 1 s, so exactly two intervals are one
    cycle (2 - 1 and 2.5 - 1.5): "at least two full periods" holds and the
    period is the sine's 1 s (the pooled line through cycle numbers 0, 1, 4
    and 0.5, 1.5), the mean interval 1 s."""
    t, y = _gapped_sine(5.2, (2.75, 4.75))
    cp = period_from_crossings(t, y, level=0.0, hysteresis=0.1)
    assert np.allclose(cp.up_times, [1.0, 2.0, 5.0], atol=1e-4)
    assert np.allclose(cp.down_times, [1.5, 2.5], atol=1e-4)
    assert cp.n_periods == 2
    assert cp.period == pytest.approx(1.0, abs=1e-4)
    assert cp.mean_period == pytest.approx(1.0, abs=1e-4)



# ---------------------------------------------------------------- signal_quantisation

from bifilar.estimation.signal_models import _model  # noqa: E402
from bifilar.estimation.signal_quantisation import _turned  # noqa: E402

#: parameters of each model kind: offset, drift, then per oscillation (a, b,
#: omega rad/s, sigma 1/s) -- quadratic (a, b, omega, kappa, sigma), chirp
#: (a, b, omega, sigma, beta, beta2) and further damped cosines
_KINDS = {
    "viscous": [0.1, 0.01, 0.3, -0.2, 3.3, 0.02],
    "two_mode": [0.1, 0.01, 0.3, -0.2, 3.3, 0.02, 0.05, 0.04, 5.1, 0.03],
    "three_mode": [0.1, 0.01, 0.3, -0.2, 3.3, 0.02, 0.05, 0.04, 5.1, 0.03, -0.02, 0.03, 7.7, 0.01],
    "quadratic": [0.1, 0.01, 0.3, -0.2, 3.3, 0.5, 0.02],
    "chirp": [0.1, 0.01, 0.3, -0.2, 3.3, 0.02, 0.1, 0.01, 0.05, 0.04, 5.1, 0.03],
    "chirp+2": [0.1, 0.01, 0.3, -0.2, 3.3, 0.02, 0.1, 0.01, 0.05, 0.04, 5.1, 0.03, -0.02, 0.03, 7.7, 0.01],
}


@pytest.mark.parametrize("name", sorted(_KINDS))
def test_turning_every_oscillation_by_half_a_turn_negates_it(name):
    """``_turned`` shifts every oscillation's phase by ``dphi``: ``a cos th +
    b sin th -> a cos(th - dphi) + b sin(th - dphi)`` (the rotation of each
    (a, b) pair), so at ``dphi = pi`` the model less its line is negated and
    at ``2 pi`` unchanged, for every oscillation of every kind (the second
    and third modes, the chirp's extra damped cosine included); the line
    (offset, drift) and the frequencies and dampings are untouched."""
    p = np.array(_KINDS[name])
    kind = name.split("+")[0]  # "chirp+2": a chirp with two further damped cosines
    t = np.linspace(0.0, 6.0, 301)
    line = p[0] + p[1] * (t - 3.0)
    osc = _model(kind, p, t, 0.0, 3.0) - line
    half = _turned(p, kind, math.pi)
    assert np.allclose(_model(kind, half, t, 0.0, 3.0) - line, -osc, atol=1e-12)
    assert np.allclose(_turned(p, kind, 2 * math.pi), p, atol=1e-12)
    moved = [i for i in range(p.size) if not math.isclose(half[i], p[i], abs_tol=1e-15)]
    pairs = {"quadratic": [2], "chirp": list(range(8, p.size, 4)) + [2]}.get(kind, list(range(2, p.size, 4)))
    assert moved == sorted([i for j in pairs for i in (j, j + 1)])


def test_a_quarter_turn_makes_the_cosine_a_sine():
    """``dphi = pi / 2``: ``a cos th + b sin th -> a sin th - b cos th``, i.e.
    ``(a, b) -> (-b, a)``."""
    p = np.array(_KINDS["viscous"])
    q = _turned(p, "viscous", math.pi / 2)
    assert np.allclose(q, [0.1, 0.01, 0.2, 0.3, 3.3, 0.02], atol=1e-15)


STEP = 5e-4  # rad, the encoder's step (not 1: the copies' offsets are divided by it)


def _resting_record():
    """A cosine of 15 steps of 0.5 mrad resting on level 0 (an encoder zeroed
    at rest), 30 fps for 40 s, rounded to whole steps; its viscous fit; its levels;
    and the fit in level indices that the rest rule makes (the same call)
    with its offsets' miss ``d`` from the nearest level at both ends."""
    from bifilar.estimation.signal_checks import quantisation_levels
    from bifilar.estimation.signal_windows import _fit_window

    t = np.arange(0.0, 40.0, 1.0 / 30.0)
    y = STEP * np.round(15.0 * np.exp(-t / 200.0) * np.cos(2 * math.pi * t / 1.7 + 0.4))
    fit, _ = _fit_window(t, y, "viscous", True, None, (), "BIC")
    lev = quantisation_levels(y)
    fk, _ = _fit_window(t, lev.index(y), "viscous", True, fit.frequency, (), "BIC")
    p = fk.params
    d = p[0] + p[1] * (np.array([t[0], t[-1]]) - fk.t_ref) - np.round(p[0])
    return t, y, fit, lev, fk, d


def _ends_with_chi2(d: np.ndarray, target: float, step: float) -> np.ndarray:
    """10 copies' end offsets [y] whose covariance (``e^T e / m``, in steps)
    is ``diag(a^2, b^2) / 2`` -- five rows ``(+-a, 0)``, five ``(0, +-b)`` --
    with ``a, b`` chosen so that ``d^T C^-1 d = 2 d0^2 / a^2 + 2 d1^2 / b^2``
    is ``target`` (half from each end)."""
    a, b = (math.sqrt(4.0 * di ** 2 / target) for di in d)
    rows = [(a, 0.0), (-a, 0.0)] * 2 + [(a, 0.0)] + [(0.0, b), (0.0, -b)] * 2 + [(0.0, -b)]
    return np.array(rows) * step


@pytest.mark.parametrize("share, rests", [(0.9, True), (1.1, False)])
def test_a_record_rests_on_a_level_within_the_99_percent_chi2_of_its_copies_offsets(share, rests):
    """The rest rule by hand: the offsets at both ends minus the nearest
    level, ``d`` (steps), against the copies' offset covariance ``C``:
    rests when ``d^T C^-1 d`` is within chi^2_2's 99 % quantile (9.21).  At
    0.9 x that it rests -- the returned parameters are the index fit's with
    the offset on the level and no drift, and its time origins -- at 1.1 x
    it does not.  Ten copies are enough."""
    from scipy import stats

    from bifilar.estimation.signal_quantisation import REST_LEVEL_CHI2, _rest_on_level

    t, y, fit, lev, fk, d = _resting_record()
    assert np.all(np.abs(d) > 0) and np.all(np.abs(d) < 0.1)  # the fit misses the level a little
    assert REST_LEVEL_CHI2 == 0.99
    ends = _ends_with_chi2(d, share * stats.chi2.ppf(0.99, 2), STEP)
    out = _rest_on_level(fit, t, y, lev, ends, True, "BIC")
    assert (out is not None) is rests
    if rests:
        p, ref = out
        assert p[0] == np.round(fk.params[0]) and p[1] == 0.0
        assert np.allclose(p[2:], fk.params[2:])
        assert ref == (fk.t0, fk.t_ref)


@pytest.mark.parametrize("share, rests", [(0.9, True), (1.1, False)])
def test_without_drift_the_rest_rule_is_chi2_1_on_the_first_offset(share, rests):
    """Without drift the two ends are one offset: ``d0^2 / C00`` against
    chi^2_1's 99 % quantile (6.63); the second end's column is ignored (b
    tiny here would make the two-end chi^2 huge)."""
    from scipy import stats

    from bifilar.estimation.signal_quantisation import _rest_on_level
    from bifilar.estimation.signal_windows import _fit_window

    t, y, fit, lev, _, _ = _resting_record()
    fk, _ = _fit_window(t, lev.index(y), "viscous", False, fit.frequency, (), "BIC")
    d0 = fk.params[0] + fk.params[1] * (t[0] - fk.t_ref) - np.round(fk.params[0])
    a = math.sqrt(d0 ** 2 / (share * stats.chi2.ppf(0.99, 1)))  # C00 = a^2 with rows +-a
    ends = np.array([(a, 1e-9), (-a, -1e-9)] * 5) * STEP
    out = _rest_on_level(fit, t, y, lev, ends, False, "BIC")
    assert (out is not None) is rests


def test_fewer_than_ten_copies_do_not_decide_a_rest():
    from bifilar.estimation.signal_quantisation import _rest_on_level

    t, y, fit, lev, _, d = _resting_record()
    ends = _ends_with_chi2(d, 1.0, STEP)  # well within the quantile
    assert _rest_on_level(fit, t, y, lev, ends, True, "BIC") is not None
    assert _rest_on_level(fit, t, y, lev, ends[:9], True, "BIC") is None
