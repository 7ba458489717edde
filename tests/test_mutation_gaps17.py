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
def test_a_secant_counts_from_ten_percent_below_the_local_slope(factor, share, warned):
    """The local slope handed in as the law's is 1 / (1 - share) of the
    secant's (a factor linear in q: its secant is exact), so they differ by
    ``share`` of the local one: 0.09 keeps the law, 0.11 replaces it
    (SECANT_DISAGREE = 0.1, the documented figure since secant2)."""
    assert SECANT_DISAGREE == 0.1
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


@pytest.mark.parametrize("std_izz, clipped", [(2.0e-3, False), (5.2e-3, True), (11e-3, True)])
def test_a_secant_end_outside_the_bodys_tensors_is_brought_in_to_the_edge(factor, std_izz, clipped):
    """The secant's ends Izz = 0.020 +- 1.96 std with Ixx 0.014, Iyy 0.016:
    a tensor a body can have up to Izz = (Ixx + Iyy) / (1 - 1e-4) (the
    triangle inequality, the config's allowance) and above 0.  std 2 mm^2:
    0.0161 .. 0.0239, both ends physical, run there; std 5.2e-3 reaches
    0.0302 > 0.030 (the triangle), 11e-3 below 0 as well: since secant2 the
    ends are brought in to the edge of the physical set (runs only on
    physical tensors, never past them) and the pair is still checked (a
    flat body's estimate sits on that edge).  The secant (1.32x the local
    slope r J) is the larger: one warning, the law unchanged."""
    b = 8.0
    factor.abk = (0.0, 1.0, b)
    pb, law = _problem(1e-6, dr_dp=0.0)
    h = 1.96 * std_izz
    top = (IXX + IYY) / (1 - 1e-4)
    assert (P0 + h > top) is clipped
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], np.array([std_izz]))
    assert len(msgs) == 1 and not changed and law.dr_dp[0] == 0.0
    assert len(factor.calls) == 2 and min(factor.calls) > 0.0 and max(factor.calls) <= top * (1 + 1e-12)
    if not clipped:
        assert sorted(factor.calls) == pytest.approx([P0 - h, P0 + h], rel=1e-12)
    else:  # the upper end at the triangle's edge (bisection to 1e-6 of the reach)
        assert max(factor.calls) == pytest.approx(top, abs=2e-6 * h + 1e-9)


def test_only_the_measurements_with_a_nonlinear_law_are_checked(factor):
    """Two measurements of the same torsion: the first without a law (None)
    or with a law without dr_dp (a linear rung), the second with one: only
    the second is checked (its two runs) and changed."""
    factor.abk = (0.0, 1.0, 8.0)
    pb, law = _problem(1e-6, dr_dp=0.0)
    pb.measurements = pb.measurements * 2
    pb.linear_periods = lambda q: np.array([C * math.sqrt(q[0])] * 2)
    pb.jacobian = lambda q: np.array([[C / (2.0 * math.sqrt(q[0]))]] * 2)
    for first in (None, SimpleNamespace(dr_dp=None)):
        factor.calls.clear()
        msgs, changed = secant_check(pb, [P0], np.array([1.0, 1.0]), [first, law], np.array([1e-3]))
        assert len(msgs) == 1 and len(factor.calls) == 2 and not changed  # the secant 1.32x: the law stays


def test_a_pair_without_a_std_or_a_nonlinear_law_is_not_checked(factor):
    """No run where the unknown's std is 0 / NaN, or no law has dr_dp."""
    pb, law = _problem(1e-6, dr_dp=0.0)
    factor.abk = (0.0, 1.0, 8.0)
    for std in (np.array([0.0]), np.array([math.nan]), np.array([])):
        assert secant_check(pb, [P0], np.array([1.0]), [law], std) == ([], False)
    assert secant_check(pb, [P0], np.array([1.0]), [SimpleNamespace(dr_dp=None)], np.array([1e-3])) == ([], False)
    assert secant_check(pb, [P0], np.array([1.0]), None, np.array([1e-3])) == ([], False)
    assert factor.calls == []


# ---------------------------------------------------------------------------
# symmetry_check._reach_factor: the Runge-Kutta step's reach over the transverse rates
# ---------------------------------------------------------------------------

def _rotation_rates(omega, step):
    """(1, 2, 2) rates matrix A = D [[0, w], [-w, 0]] D^-1 (D = diag(step)):
    eigenvalues +-i w whatever the directions' units."""
    D = np.diag(step)
    return (D @ np.array([[0.0, omega], [-omega, 0.0]]) @ np.linalg.inv(D))[None]


@pytest.mark.parametrize("step, h", [((1e-3, 1e-3), 0.01), ((1e-3, 2.0), 0.01), ((5.0, 1e-4), 0.01),
                                     ((20.0, 20.0), 0.01), ((1e-3, 1e-3), 4.0)])
@pytest.mark.parametrize("wh, factor", [(0.3, 1.0), (0.45, 1.0), (1.5, 6.0), (4.0, 16.0)])
def test_the_reach_factor_brings_the_fastest_rate_to_half_the_reach(step, h, wh, factor):
    """RK4_REACH = 0.5: a grid whose step h has |lambda| h within it needs
    no refinement (factor 1; at 0.45 the Frobenius bound sqrt(2) w h = 0.64
    exceeds it but the eigenvalues do not); beyond it the step shrinks by
    2 |lambda| h / 0.5 (to half the reach: 6 at 1.5, 16 at 4).  Truth: the
    rates' eigenvalues +-i w, built in; the directions' units (step) must
    not matter (before round 17, `/ step -> * step` survived: in units of
    1e-3 the bound then passed every grid)."""
    from bifilar.analysis.symmetry_check import RK4_REACH, _reach_factor

    assert RK4_REACH == 0.5
    A = np.concatenate([_rotation_rates(0.1 / h, np.array(step)), _rotation_rates(wh / h, np.array(step)),
                        _rotation_rates(0.2 / h, np.array(step))])
    f = _reach_factor(A, np.array(step, float), h)
    assert f == pytest.approx(factor, rel=1e-9)
    assert wh / f <= RK4_REACH + 1e-12


@pytest.mark.parametrize("fast", [0, 2])
def test_the_reach_factor_reads_the_first_and_the_middle_rates(fast):
    """The eigenvalues are read of the first, the middle and the largest
    (Frobenius) of the matrices along the orbit (the documented rule): the
    fastest rotation (w h = 1.5: factor 6) first or in the middle of five,
    a nilpotent matrix (eigenvalues 0, the largest norm) last."""
    from bifilar.analysis.symmetry_check import _reach_factor

    h, step = 0.01, np.array([1e-3, 1e-3])
    A = [_rotation_rates(0.1 / h, step) for _ in range(4)] + [np.array([[[0.0, 50.0 / h], [0.0, 0.0]]])]
    A[fast] = _rotation_rates(1.5 / h, step)
    assert _reach_factor(np.concatenate(A), step, h) == pytest.approx(6.0, rel=1e-9)


# ---------------------------------------------------------------------------
# signal_frames: the lattice search, the step reading, the curvature, correction_std
# ---------------------------------------------------------------------------

FPS = 30.0


def _dropped_record(drops=(300, 520, 760, 1000, 1210), T=1.7, n_frames=1535, noise=5e-4, seed=4):
    """A 0.05 rad cosine of period T at 30 fps, white noise ``noise``, the
    frames ``drops`` (indices of the camera's frames) missing: (nominal
    times j dt, samples, the kept frames' true times)."""
    rng = np.random.default_rng(seed)
    tt = np.arange(n_frames) / FPS
    keep = np.ones(n_frames, bool)
    keep[list(drops)] = False
    y = 0.05 * np.cos(2 * np.pi * tt / T + 0.4) + noise * rng.standard_normal(n_frames)
    y = y[keep]
    return np.arange(y.size) / FPS, y, tt[keep]


def test_recover_frames_finds_the_true_frequency_and_each_drop():
    """Five frames dropped from a 1.7 s cosine: the fit on the nominal
    time base reads the frequency high by the drops' share (5 / 1555); the
    lattice's peak is at the true frequency within its width over a quarter
    step (1 / n of it: the search steps by a quarter of that); each sample's
    recovered time is its frame's true time except within the median's
    reach (a quarter cycle, 13 samples) of a drop; the lattice's strength
    at the noise's prediction exp(-2 pi^2 (sigma / (a w dt))^2) (constant
    amplitude), within 2 % (the third-difference noise estimate's error).
    The record is 1530 samples, 30 whole cycles: in 1555 samples (30.5
    cycles) the analytic signal's phase is off by over half a frame for
    ~25 samples past the half cycle dropped at the start, the count's zero
    is taken there, and the drop at sample 300 is not counted
    (docs/mutation.md "Round 17", found)."""
    from bifilar.estimation.signal_frames import recover_frames

    t, y, t_true = _dropped_record()
    f_nom = (1 / 1.7) * (1 + 5 / 1555)  # the nominal time base's frequency (no fit needed: the share is known)
    rec = recover_frames(t, y, f_nom)
    assert rec["resolved"] and rec["dropped"] == 5
    assert rec["frequency"] == pytest.approx(1 / 1.7, rel=1.0 / t.size)
    off = np.abs(rec["t"] - t_true) > 0.5 / FPS
    assert off.sum() <= 5 * 13, off.sum()
    assert rec["edge"] == 2 * (51 // 2)  # a cycle (W = 51): half the local mean's, half the analytic signal's
    h = 2 * np.pi / 1.7 / FPS
    pred = math.exp(-2 * np.pi ** 2 * (5e-4 / (0.05 * h)) ** 2)
    assert rec["lattice_expected"] == pytest.approx(pred, rel=0.02)
    assert rec["lattice"] >= 0.5 * pred and rec["lattice_at_fit"] < 0.2 * rec["lattice"]
    assert rec["rises"] == 5 and rec["falls"] == 0


def test_a_clean_record_has_no_drops_to_recover():
    """No frame missing: the lattice peaks at the fitted frequency, nothing
    is recovered (dropped 0, not resolved), the time base is the nominal."""
    from bifilar.estimation.signal_frames import recover_frames

    t, y, t_true = _dropped_record(drops=())
    rec = recover_frames(t, y, 1 / 1.7)
    assert rec["dropped"] == 0 and not rec["resolved"]
    np.testing.assert_allclose(rec["t"], t_true, atol=1e-12)


@pytest.mark.parametrize("per_cycle, cycles, searched", [(8, 4.3, True), (7, 30, False), (30, 3.9, False)])
def test_recover_frames_searches_from_eight_samples_a_cycle_and_four_cycles(per_cycle, cycles, searched):
    """The documented limits (MIN_SAMPLES_PER_CYCLE 8, four cycles and two samples: n >= 4 W + 2)."""
    from bifilar.estimation.signal_frames import recover_frames

    f = FPS / per_cycle
    n = int(cycles * per_cycle)
    t = np.arange(n) / FPS
    y = np.cos(2 * np.pi * f * t)
    assert (recover_frames(t, y, f) is not None) is searched


def test_the_curvature_of_a_poisson_staircase_is_a_standard_normal():
    """_curvature_z in standard errors of a staircase of drops at a
    constant rate: over 300 seeded staircases (20 drops at uniform places
    in 1500 samples, a Poisson process given its count) the z's mean is 0
    within 0.2 and their sd 1 within 0.15 (the sd of 300 normals' sd is
    0.04; the bridge's lumping onto 200 points is exact to ~1e-3); a
    frequency drifting with the amplitude (the count quadratic in time) is
    far beyond the gate's 2."""
    from bifilar.estimation.signal_frames import MAX_CURVATURE_Z, _curvature_z

    rng = np.random.default_rng(17)
    n, D = 1500, 20
    z = []
    for _ in range(300):
        places = rng.uniform(0, n, D)
        z.append(_curvature_z(np.searchsorted(np.sort(places), np.arange(n), side="right").astype(float)))
    z = np.array(z)
    assert abs(z.mean()) < 0.2 and 0.85 < z.std() < 1.15, (z.mean(), z.std())
    u = np.arange(n) / n
    assert _curvature_z(np.floor(10 * D * u * u)) > 3 * MAX_CURVATURE_Z  # 200 drops: z ~ sqrt(200) x 0.5


def _fit_bias(n, at):
    """The relative change of a least-squares line's slope through a phase
    of n samples (unit slope) stepped by one sample's phase at sample
    ``at``: the relative period error of a drop there (independent of the
    code: numpy's polyfit)."""
    j = np.arange(n, dtype=float)
    return np.polyfit(j, j + (j >= at), 1)[0] - 1.0


def test_correction_std_is_a_misplaced_and_a_missed_drops_fit_bias():
    """The two terms against least-squares fits of a stepped phase: a drop
    misplaced by the median's reach (a quarter cycle, W / 4 samples) moves
    the fitted period by at most 6 (W / 4) / n^2 of it (at the record's
    ends; polyfit's largest change over the places), sqrt(D) of it for D
    drops misplaced at random; a drop missed within ``edge`` samples of an
    end biases it by at most the bias of a step at ``edge`` (~6 edge / n^2)
    times the 2 edge D / n drops expected there (W = 0: the placement term
    alone is zero)."""
    from bifilar.estimation.signal_frames import correction_std

    n, W, T = 1200, 48, 1.7
    worst = max(abs(_fit_bias(n, j + W // 4) - _fit_bias(n, j)) for j in range(1, n - W // 4, 7))
    assert correction_std(T, n, 1, 0, W) / T == pytest.approx(worst, rel=0.03)
    assert correction_std(T, n, 9, 0, W) == pytest.approx(3 * correction_std(T, n, 1, 0, W), rel=1e-12)
    assert correction_std(T, n, 0, 0, W) == pytest.approx(correction_std(T, n, 1, 0, W), rel=1e-12)
    edge, D = 25, 12
    missed = 2 * edge * D / n * abs(_fit_bias(n, edge))
    assert correction_std(T, n, D, edge, 0) / T == pytest.approx(missed, rel=0.05)
    both = correction_std(T, n, D, edge, W)
    assert both == pytest.approx(math.hypot(correction_std(T, n, D, edge, 0), correction_std(T, n, D, 0, W)),
                                 rel=1e-12)
    assert correction_std(T, 0, 3, 2, W) == 0.0


def test_the_lattice_expected_weights_each_sample_by_its_squared_amplitude():
    """R_pred = sum w_j exp(-2 pi^2 (sigma / (a_j w dt))^2), w_j = a_j^2
    normalised: on a record decaying to a fifth of its start (a_j =
    0.05 exp(-t / tau)), the analytic envelope's weighted mean, to 3 %
    (the third-difference noise estimate and the analytic signal's own
    amplitude error near the ends; seeds 9 and 10 measured 1.2 %, 0.7 %).
    Unweighted the mean is 0.49, with the amplitudes cubed 0.74, against 0.68."""
    from bifilar.estimation.signal_frames import recover_frames

    T, n, sig = 1.7, 1530, 5e-4
    rng = np.random.default_rng(9)
    tt = np.arange(n) / FPS
    a = 0.05 * np.exp(-tt / (tt[-1] / math.log(5.0)))
    y = a * np.cos(2 * np.pi * tt / T + 0.4) + sig * rng.standard_normal(n)
    rec = recover_frames(tt, y, 1 / T)
    h = 2 * np.pi / T / FPS
    inner = slice(51, n - 51)  # the samples whose phase is read (a cycle at either end is not)
    w = a[inner] ** 2
    pred = float(np.sum(w * np.exp(-2 * np.pi ** 2 * (sig / (a[inner] * h)) ** 2)) / np.sum(w))
    flat = float(np.mean(np.exp(-2 * np.pi ** 2 * (sig / (a[inner] * h)) ** 2)))
    assert abs(pred - flat) > 0.1 * pred  # the weights matter on this record
    assert rec["lattice_expected"] == pytest.approx(pred, rel=0.03)


# ---------------------------------------------------------------------------
# signal_swing_rate: which combination a tone is, the swing's rate from it, decay_at_rate
# ---------------------------------------------------------------------------

F_T, F_S, F_O = 1.0, 0.3, 0.85  # Hz: the timed mode, the swing, another mode


@pytest.mark.parametrize("f_tone, power", [
    (abs(2 * F_S - F_T), 2), (abs(2 * F_S - F_T) * 1.019, 2), (abs(2 * F_S - F_T) * 1.021, None),
    (F_T + F_S, 1), (F_T - F_S, 1), (F_O + F_S, 1), (F_O - F_S, 1), ((F_O - F_S) * 0.981, 1),
    ((F_O - F_S) * 0.979, None), (2.0, None)])
def test_a_tones_combination_is_read_from_its_frequency_within_two_percent(f_tone, power):
    """The swing's power in the tone (module docstring): |2 f_s - f_t| is
    swing^2 x timed mode (2), |f_o +- f_s| swing x another mode or the
    timed one (1), within COMBO_TOL = 2 % of the tone's frequency; no
    combination of these frequencies lies within 5 % of another here."""
    from bifilar.estimation.signal_swing_rate import COMBO_TOL, _combination

    assert COMBO_TOL == 0.02
    assert _combination(f_tone, F_T, F_S, [F_O]) == power


def _rate_inputs(sigma_t, sigma_tone, f_tone, sd=0.004, sd_t=0.003, source=None, modes=True):
    fit = SimpleNamespace(modes=[{"sigma": sigma_t, "sigma_std": sd_t, "frequency": F_T}] if modes else [])
    tone = {"sigma": sigma_tone, "sigma_std": sd, "period": 1.0 / f_tone}
    if source:
        tone["source"] = source
    hm = SimpleNamespace(modes0=SimpleNamespace(modes=[SimpleNamespace(period=1 / F_T), SimpleNamespace(period=1 / F_S),
                                                       SimpleNamespace(period=1 / F_O)]))
    return SimpleNamespace(fit=fit), tone, hm


@pytest.mark.parametrize("f_tone, power", [(abs(2 * F_S - F_T), 2), (F_T + F_S, 1), (F_O - F_S, 1)])
def test_the_swings_rate_from_how_its_tone_is_made(f_tone, power):
    """A tone A_s^p A_o decays at p sigma_s + sigma_o (amplitudes
    exp(-sigma t)); the timed mode at sigma_t = sigma_o (the stated
    assumption): a swing decaying at 0.05 /s beside a timed mode at 0.02 /s
    makes a tone decaying at 0.12 /s (2 f_s - f_t) or 0.07 /s (f_o +- f_s),
    read back as 0.05.  Its std: the two fitted rates' in quadrature over
    p, and RATE_SHARE (0.3) of the rate beside it; a tone decaying slower
    than the timed mode gives a rate floored at 0 (a swing does not grow)."""
    from bifilar.estimation.signal_swing_rate import RATE_SHARE, tone_swing_rate

    assert RATE_SHARE == 0.3
    s_s, s_t = 0.05, 0.02
    m, tone, hm = _rate_inputs(s_t, power * s_s + s_t, f_tone)
    rate, std = tone_swing_rate(m, tone, hm, 1, 0)
    assert rate == pytest.approx(s_s, rel=1e-12)
    assert std == pytest.approx(math.hypot(math.hypot(0.004, 0.003) / power, 0.3 * s_s), rel=1e-12)
    m, tone, hm = _rate_inputs(s_t, s_t - 0.01, f_tone)
    rate, std = tone_swing_rate(m, tone, hm, 1, 0)
    assert rate == 0.0 and std == pytest.approx(math.hypot(math.hypot(0.004, 0.003) / power, 0.3 * 0.01 / power))


def test_a_tone_the_rate_cannot_be_read_from_gives_none():
    """None (the stated share's rule stays) without the timed mode's fit,
    without the tone's rate, or at a frequency no combination makes."""
    from bifilar.estimation.signal_swing_rate import tone_swing_rate

    m, tone, hm = _rate_inputs(0.02, 0.07, F_T + F_S, modes=False)
    assert tone_swing_rate(m, tone, hm, 1, 0) is None
    m, tone, hm = _rate_inputs(0.02, 0.07, F_T + F_S)
    del tone["sigma"]
    assert tone_swing_rate(m, tone, hm, 1, 0) is None
    m, tone, hm = _rate_inputs(0.02, 0.07, 2.0)
    assert tone_swing_rate(m, tone, hm, 1, 0) is None
    m, tone, hm = _rate_inputs(None, 0.07, F_T + F_S)
    assert tone_swing_rate(m, tone, hm, 1, 0) is None
    # the swing's own harmonic 2 f_s (swing^2, decaying at 2 sigma_s) is none of the combinations read: the swing
    # is not "another mode" beside itself (nor is the timed mode)
    m, tone, hm = _rate_inputs(0.02, 0.10, 2 * F_S)
    assert tone_swing_rate(m, tone, hm, 1, 0) is None


@pytest.mark.parametrize("rate", [0.0, 0.02, 0.1])
def test_decay_at_rate_is_the_kernel_weighted_rms_amplitude(rate):
    """Uniform weights over tau in [0, 30 s] on a fine grid: g^2 is the mean
    of exp(-2 rate tau), (1 - exp(-2 rate T)) / (2 rate T); g's relative std
    |d ln g / d rate| std, the derivative of that closed form by central
    differences (to 1e-3: the grid's rectangle rule and the difference)."""
    from bifilar.estimation.signal_swing_rate import decay_at_rate

    Tw, n, std = 30.0, 30001, 0.01
    t = 5.0 + np.linspace(0.0, Tw, n)  # a window that starts at 5 s: tau from its start

    def lng(r):
        x = 2 * r * Tw
        return 0.5 * math.log(-math.expm1(-x) / x) if x > 0 else 0.0

    g, s = decay_at_rate(t, np.ones(n), rate, std)
    assert g == pytest.approx(math.exp(lng(rate)), rel=1e-3)
    e = 1e-5
    dl = (lng(rate + e) - lng(max(rate - e, 0.0))) / (rate + e - max(rate - e, 0.0))
    assert s == pytest.approx(abs(dl) * std, rel=2e-3)


def test_a_residual_tones_rate_is_read_beside_the_fits_mismatch():
    """A single-mode fit's residuals: a tone at 0.7 Hz decaying at 0.08 /s
    beside a cubic-in-time mismatch at the fundamental (1 Hz, under the
    fit's envelope, the chirp a damped record leaves) and white noise: the
    tone's own rate is read to within 3 of its std (and the std below a
    tenth of the rate); the tone's damped cosine alone would take the
    mismatch into its envelope."""
    from bifilar.estimation.signal_swing_rate import residual_tone_rate

    rng = np.random.default_rng(21)
    t = np.arange(12.0, 52.0, 1 / 50.0)  # the window starts at 12 s: tau from there
    tau = t - 12.0
    w0, s0 = 2 * np.pi, 0.03
    mism = 2e-4 * np.exp(-s0 * tau) * (tau / 40.0) ** 3 * np.cos(w0 * tau + 0.3)
    r = 1e-3 * np.exp(-0.08 * tau) * np.cos(2 * np.pi * 0.7 * tau + 1.1) + mism + 2e-5 * rng.standard_normal(t.size)
    fit = SimpleNamespace(t_used=t, residuals=r, modes=[{"omega": w0, "sigma": s0}], std_inflation=1.0)
    sg, sd = residual_tone_rate(fit, 0.7, 0.05)
    assert abs(sg - 0.08) < 3 * sd and sd < 0.008, (sg, sd)


# ---------------------------------------------------------------------------
# elastic_rest: Hooke's law at the elastic rest, the loaded scene, the torsion on it
# ---------------------------------------------------------------------------

def test_the_loaded_bifilar_is_hookes_and_its_torsion_the_parallel_wire_law():
    """A level bifilar of vertical 2 m wires 0.8 m apart, 200 kg, EA 1e5 N:
    each wire carries m g / 2 = 981 N (vertical wires, the CoM under their
    middle), so by Hooke's law it hangs L (1 + m g / (2 EA)) = 2.01962 m and
    the body 19.62 mm lower than on rigid wires.  loaded_scene's wires are
    that long and stiff (no stiffness: nothing stretches them again), and
    the torsion on them is the parallel-wire law w^2 = m g r^2 / (Izz L')
    (r = 0.4 m: the linear restoring torque of two vertical wires, each
    tilted by r theta / L', carrying m g / 2), to 1e-9; on the unloaded
    lengths it would be 4.9e-3 short.  loaded_scenes keeps a batch's error
    entry's scene and shares one loaded scene per (scene, rest) pair."""
    from bifilar.analysis.elastic_rest import loaded_scene, loaded_scenes
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import scene_from_dict
    from test_estimation_audit16 import _heavy

    m, g, EA, L, r = 200.0, 9.81, 1.0e5, 2.0, 0.4
    sc = scene_from_dict(_heavy(2, m, EA), "h", warn=False)
    rigid = scene_from_dict(_heavy(2, m, None), "h", warn=False)
    rest, rest0 = rest_pose(sc), rest_pose(rigid)
    Lp = L * (1 + m * g / 2 / EA)
    np.testing.assert_allclose(rest.tensions, m * g / 2, rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(rest.wire_vectors, axis=1), Lp, rtol=1e-12)
    assert rest0.com[2] - rest.com[2] == pytest.approx(Lp - L, rel=1e-8)
    ls = loaded_scene(sc, rest)
    assert ls.stiffness is None and loaded_scene(rigid, rest0) is rigid
    np.testing.assert_allclose(ls.lengths, Lp, rtol=1e-12)
    w2 = m * g * r * r / (20.0 * Lp)
    T_law = 2 * np.pi / math.sqrt(w2)
    assert linear_modes(ls, rest_pose(ls)).get("torsion").period == pytest.approx(T_law, rel=1e-9)
    assert linear_modes(sc, rest).get("torsion").period == pytest.approx(T_law, rel=1e-9)
    # the elastic wires' own linear periods, matched to the modes by shape: the torsion's is the same (vertical
    # wires: it does not tilt them), the rest within half the strain 9.8e-3 (a coupling ~ strain x itself);
    # a mode matched to another shape would be off by the ratio of two different periods (>= 1.028 here)
    from bifilar.analysis.elastic_rest import elastic_period_ratios

    ms = linear_modes(sc, rest)
    ratio = elastic_period_ratios(sc, rest, ms)
    assert ratio[[md.label for md in ms.modes].index("torsion")] == pytest.approx(1.0, abs=1e-9)
    per = sorted(md.period for md in ms.modes if md.period)
    assert min(b / a for a, b in zip(per, per[1:])) > 1.02
    assert np.all(np.abs(ratio[np.isfinite(ratio)] - 1) < 5e-3), ratio
    err = ValueError("a batch's failed rest")
    out = loaded_scenes([sc, sc, sc, rigid], [rest, rest, err, rest0])
    assert out[0] is out[1] and out[0] is not sc and out[2] is sc and out[3] is rigid
    np.testing.assert_allclose(out[0].lengths, Lp, rtol=1e-12)


# ---------------------------------------------------------------------------
# point_symmetry: the sweep/plan point's warning of a symmetric run, its --periods
# ---------------------------------------------------------------------------

@pytest.fixture
def sym_stubs(monkeypatch):
    """symmetric_run_warnings with its runs and multiplier stood in: the
    rig symmetric, each short run sampled, the multiplier ``state.rho``."""
    import bifilar.analysis.batch as batch
    import bifilar.analysis.symmetry_check as sc

    state = SimpleNamespace(rho=2.0, short=0, syms=["C2"])
    monkeypatch.setattr(sc, "rig_symmetries", lambda scene, rest: state.syms)

    def short(*a, **k):
        state.short += 1
        return SimpleNamespace(t=np.zeros(3), y=np.zeros((3, 13)))

    monkeypatch.setattr(batch, "run_one", short)
    monkeypatch.setattr(sc, "run_multiplier",
                        lambda *a: (SimpleNamespace(names="the mirror y"), state.rho))
    return state


def _point_run(period=2.2):
    return SimpleNamespace(period=period, error=None, warnings=[])


@pytest.mark.parametrize("rho, periods, T_lin, T_run", [(4.0, 12.0, 2.0, 2.2), (7.33, 17.0, 3.0, 3.24),
                                                        (30.0, 6.0, 2.0, 1.9), (2.0, 40.0, 2.0, 2.0),
                                                        (2.0, 19.0, 2.0, 2.0), (2000.0, 4.0, 2.0, 2.0)])
def test_a_symmetric_points_periods_advice_is_the_longest_run_below_the_gate(sym_stubs, rho, periods, T_lin, T_run):
    """An offset grows by rho each period of the run (T_run s), and a run of
    N linear periods (T_lin s) lasts N T_lin / T_run of them: the warning
    comes where rho^(periods T_lin / T_run) reaches GROWTH_GATE (1e6) and
    names the largest N with rho^(N T_lin / T_run) below it (N >= 2: --periods
    takes 2 at least; else only the smaller amplitude).  Truth: the gate's
    definition, counted here."""
    import re

    from bifilar.analysis.symmetry_check import GROWTH_GATE
    from bifilar.studies.point_symmetry import symmetric_run_warnings

    assert GROWTH_GATE == 1e6
    sym_stubs.rho = rho
    ms = SimpleNamespace(get=lambda lab: SimpleNamespace(period=T_lin))
    run = _point_run(T_run)
    symmetric_run_warnings(None, None, ms, ["torsion"], 0.1, periods, 1e-10, [run])
    growth = rho ** (periods * T_lin / T_run)
    assert (len(run.warnings) == 1) is (growth >= GROWTH_GATE)
    if not run.warnings:
        return
    N = 0
    while rho ** ((N + 1) * T_lin / T_run) < GROWTH_GATE:
        N += 1
    got = re.findall(r"--periods (\d+)", run.warnings[0])
    assert got == ([str(N)] if N >= 2 else []), (N, run.warnings[0])
    assert f"{rho:.3g}" in run.warnings[0]


def test_short_runs_and_asymmetric_rigs_cost_nothing(sym_stubs):
    """At most SHORT_RUN_PERIODS (3) linear periods no run is made (the gate
    would need a multiplier of 100 a period: 100^3 = 1e6); a rig without
    symmetry neither; a run that timed no period or failed is skipped."""
    from bifilar.studies.point_symmetry import SHORT_RUN_PERIODS, symmetric_run_warnings

    assert SHORT_RUN_PERIODS == 3.0
    sym_stubs.rho = 1000.0
    ms = SimpleNamespace(get=lambda lab: SimpleNamespace(period=2.0))
    run = _point_run()
    symmetric_run_warnings(None, None, ms, ["torsion"], 0.1, 3.0, 1e-10, [run])
    assert sym_stubs.short == 0 and run.warnings == []
    symmetric_run_warnings(None, None, ms, ["torsion"], 0.1, 3.01, 1e-10, [run])
    assert sym_stubs.short == 1 and len(run.warnings) == 1
    sym_stubs.syms = []
    run = _point_run()
    symmetric_run_warnings(None, None, ms, ["torsion"], 0.1, 10.0, 1e-10, [run])
    assert sym_stubs.short == 1 and run.warnings == []
    sym_stubs.syms = ["C2"]
    runs = [SimpleNamespace(period=None, error=None, warnings=[]), SimpleNamespace(period=2.0, error="x", warnings=[])]
    symmetric_run_warnings(None, None, ms, ["a", "b"], 0.1, 10.0, 1e-10, runs)
    assert sym_stubs.short == 1 and all(r.warnings == [] for r in runs)


# ---------------------------------------------------------------------------
# shorthands.overlap_warnings: warned exactly where apply_params moves the path
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("short, value", [("length", 1.1), ("length_offset", 0.1), ("spacing", 0.45),
                                          ("ceiling_spacing", 0.45), ("height", 0.1)])
def test_a_path_is_warned_of_exactly_where_its_shorthand_moves_it(short, value):
    """Every coordinate of every attachment and anchor and every length of
    the drone config, set to a value off its own and swept beside one
    shorthand: warned iff apply_params' built config holds another value
    there (the truth: the edit itself, not the warning's table)."""
    from pathlib import Path

    from bifilar.config import read_yaml
    from bifilar.studies.shorthands import apply_params, get_path, overlap_warnings

    cfg = read_yaml(Path(__file__).resolve().parents[1] / "configs" / "drone_parallel.yaml")
    n = len(cfg["rig"]["lengths"])
    paths = [f"rig.lengths.{i}" for i in range(n)] + [f"rig.{key}.{i}.{c}" for key in ("attachments", "anchors")
                                                       for i in range(n) for c in range(3)]
    for path in paths:
        set_to = float(get_path(cfg, path)) + 0.0123
        built, _ = apply_params(cfg, {path: set_to, short: value})
        moved = abs(float(get_path(built, path)) - set_to) > 1e-9
        said = overlap_warnings([path, short])
        assert len(said) == int(moved), (path, short, moved, said)
