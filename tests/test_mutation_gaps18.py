"""Mutation round 18 (docs/mutation.md, "Round 18"): tests that kill the
surviving mutants of session 18's new code, each against a truth computed
another way (a closed form, a documented rule written out with its edge
bracketed at 0.9 / 1.1, a record built with a known fault), never against
the code's own output.  All cheap: stand-in runs, noise-free records."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.analysis import run_accuracy as ra
from bifilar.errors import IntegrationError

# ---------------------------------------------------------------------------
# run_accuracy: FAR_FROM_LINEAR, far_from_linear and the check it sends a run to
# ---------------------------------------------------------------------------
#
# A stand-in run (the attributes check_period reads) and a stand-in `again`
# recording how it was asked; the truths are the documented rule (a period
# more than 20 % from the linear one; a check by DOP853 at rtol / 100, not
# below MIN_RTOL; 1.1 x the difference plus twice the check's own bound,
# kept only where it exceeds the model's bound).


def _run(period, linear=1.0, spread=0.0, error=1e-9, rtol=1e-10):
    return SimpleNamespace(period=period, linear_period=linear, period_std=spread * (period or 0.0), crossings=[],
                           rtol=rtol, method="LSODA", period_error=error, warnings=[], period_check=None)


@pytest.mark.parametrize("ratio, far", [(1.0 + 0.9 * ra.FAR_FROM_LINEAR, False), (1.0 + 1.1 * ra.FAR_FROM_LINEAR, True),
                                        (1.0 - 0.9 * ra.FAR_FROM_LINEAR, False),
                                        (1.0 - 1.1 * ra.FAR_FROM_LINEAR, True)])
def test_a_period_is_far_from_linear_beyond_a_fifth_either_way(ratio, far):
    """The documented 0.2 of the linear period, either side (a period can
    also be shorter: a stiffening), at 0.9 / 1.1 of the edge, on a linear
    period of 2.5 s (not 1: a relative rule)."""
    assert ra.FAR_FROM_LINEAR == 0.2
    assert ra.far_from_linear(_run(2.5 * ratio, linear=2.5)) is far
    assert ra.needs_period_check(_run(2.5 * ratio, linear=2.5)) is far  # a clean run (no spread): only this rule


def test_a_run_without_a_period_or_a_linear_one_is_not_far():
    for r in (_run(None), _run(3.0, linear=None), _run(3.0, linear=0.0)):
        assert ra.far_from_linear(r) is False


class _Again:
    """A check run returning ``period`` with its own bound ``own`` (or
    raising / timing nothing), recording each call's arguments."""

    def __init__(self, period, own=0.0, fail=False):
        self.period, self.own, self.fail, self.calls = period, own, fail, []

    def __call__(self, method, rtol, atol):
        self.calls.append((method, rtol, atol))
        if self.fail:
            raise IntegrationError("stand-in failure")
        return SimpleNamespace(period=self.period, period_error=self.own, method=method, rtol=rtol)


@pytest.mark.parametrize("rtol, expect", [(1e-10, 1e-12), (1e-13, ra.MIN_RTOL)])
def test_a_far_run_is_checked_by_dop853_at_a_hundredth_of_its_rtol(rtol, expect):
    """T / T_lin = 2.5, single cycles that agree: one DOP853 run at rtol /
    100 (never below MIN_RTOL), atol over the same 100; the period's error
    becomes 1.1 x the difference + 2 x the check's own bound, with one
    warning."""
    r = _run(2.5, error=1e-9, rtol=rtol)
    again = _Again(2.5 + 4e-8, own=3e-10)
    ra.check_period(r, again, "LSODA", np.array([2e-9, 4e-9]))
    assert len(again.calls) == 1
    method, rt, atol = again.calls[0]
    assert method == "DOP853" and rt == pytest.approx(expect, rel=1e-12)
    assert np.allclose(atol, [2e-11, 4e-11], rtol=1e-12)
    assert r.period_error == pytest.approx(1.1 * 4e-8 + 2 * 3e-10, rel=1e-6)
    assert r.period_check["difference"] == pytest.approx(4e-8, rel=1e-6)
    assert r.period_check["model_bound"] == 1e-9
    assert len(r.warnings) == 1 and "150%" in r.warnings[0]  # 2.5 / 1 - 1, as a percentage


@pytest.mark.parametrize("own", [None, math.inf, math.nan])
def test_a_far_runs_check_without_its_own_bound_adds_only_the_difference(own):
    """A check run whose own bound is not established counts as exact:
    the error becomes 1.1 x the difference alone."""
    r = _run(2.5, error=1e-9)
    ra.check_period(r, _Again(2.5 + 4e-8, own=own), "LSODA", None)
    assert r.period_error == pytest.approx(1.1 * 4e-8, rel=1e-6)


def test_a_far_runs_check_within_its_bound_changes_nothing():
    """1.1 x 5e-10 + 2 x 1e-10 = 7.5e-10 < the model's 1e-9: the bound
    stands, no warning (a regular far run the error model bounds)."""
    r = _run(2.5, error=1e-9)
    ra.check_period(r, _Again(2.5 + 5e-10, own=1e-10), "LSODA", None)
    assert r.period_error == 1e-9 and r.warnings == [] and r.period_check["difference"] == pytest.approx(5e-10)


def test_a_far_runs_check_that_fails_or_times_nothing_says_so_and_keeps_the_bound():
    for again, word in ((_Again(None, fail=True), "failed"), (_Again(None), "timed no period")):
        r = _run(0.7, error=1e-9)
        ra.check_period(r, again, "LSODA", None)
        assert again.calls[0][2] is None  # atol scaled: None passed on
        assert r.period_error == 1e-9 and r.period_check is None
        assert len(r.warnings) == 1 and word in r.warnings[0] and "30%" in r.warnings[0]


def test_a_spread_run_takes_the_irregular_check_not_the_far_one():
    """A far run whose single cycles also spread (beyond IRREGULAR_SPREAD)
    is checked as before: the run's own method at rtol / 100, the
    difference itself (no 1.1 x, no check bound) as the error."""
    r = _run(2.5, spread=1e-3, error=1e-9)
    again = _Again(2.5 + 4e-8, own=3e-10)
    ra.check_period(r, again, "LSODA", np.array([3e-9]))
    assert again.calls[0][0] == "LSODA" and again.calls[0][1] == pytest.approx(1e-12, rel=1e-12)
    assert np.allclose(again.calls[0][2], [3e-11], rtol=1e-12)
    assert r.period_error == pytest.approx(4e-8, rel=1e-6)


# ---------------------------------------------------------------------------
# signal_start: the one-period windows and the held start's first rule
# ---------------------------------------------------------------------------
#
# Over a window of exactly one period on a uniform grid (T / dt a whole
# number) the columns 1, cos, sin are orthogonal, so the least-squares level
# is the window's plain mean and the amplitude that of the record's own
# cosine: an independent formulation of local_sinusoids' cumulative-sum solve.

from bifilar.estimation.signal_start import (FIRE_SHARE, MARGIN_PERIODS, STEPS, held_end, held_start,  # noqa: E402
                                             local_sinusoids)


def test_a_windows_level_is_its_mean_and_its_amplitude_the_cosines():
    """y = 0.3 + 0.4 t + 1.7 cos(w t + 0.4) at 25 samples a period, 6
    periods: a window of 25 samples every 25 // 8 = 3, its level the mean
    of its samples and its amplitude the samples' projection on cos and sin
    (the drift adds a sine component of its own, so not 1.7 exactly)."""
    T, n_per = 2.0, 25
    dt = T / n_per
    t = 1.0 + np.arange(6 * n_per) * dt
    w = 2 * math.pi / T
    y = 0.3 + 0.4 * t + 1.7 * np.cos(w * t + 0.4)
    ts, tm, c, A = local_sinusoids(t, y, T)
    starts = np.arange(0, t.size - n_per + 1, n_per // STEPS)
    assert np.array_equal(ts, t[starts]) and np.array_equal(tm, t[starts + n_per // 2])
    means = np.array([y[i:i + n_per].mean() for i in starts])
    assert np.allclose(c, means, rtol=0, atol=1e-9)
    # the amplitude: the window's samples projected on cos and sin (orthogonal, each of norm n / 2)
    tc = t - t[0]
    amp = [math.hypot(2 / n_per * np.dot(y[i:i + n_per], np.cos(w * tc[i:i + n_per])),
                      2 / n_per * np.dot(y[i:i + n_per], np.sin(w * tc[i:i + n_per]))) for i in starts]
    assert np.allclose(A, amp, rtol=1e-9)


@pytest.mark.parametrize("n_per, n, ok", [(4, 8, True), (4, 7, False), (8, 16, True), (8, 15, False)])
def test_windows_need_two_periods_of_samples(n_per, n, ok):
    """None when the record is shorter than two periods (documented); at
    exactly two, and at 4 samples a period (enough for three unknowns), the
    windows' levels are the means (a pure cosine about 0.25: all 0.25)."""
    T = 1.0
    t = np.arange(n) * (T / n_per)
    y = 0.25 + np.cos(2 * math.pi * t / T + 0.3)
    out = local_sinusoids(t, y, T)
    assert (out is not None) is ok
    if ok:
        assert np.allclose(out[2], 0.25, atol=1e-12) and np.allclose(out[3], 1.0, rtol=1e-12)
        # a window every m / 8 samples, at least every sample: n - m + 1 windows at 4 samples a period
        assert out[0].size == (n - n_per + 1 if n_per < STEPS else (n - n_per) // (n_per // STEPS) + 1)


def _held_record(d, hold=1.0, T=2.0, fs=50.0, cycles=20):
    """Held at level ``d`` for ``hold`` periods, then a unit cosine about 0
    (noise-free): the first window's level lies exactly ``d`` off the free
    part's line (0) in units of the largest amplitude (1)."""
    t = np.arange(0.0, (hold + cycles) * T, 1 / fs)
    y = np.cos(2 * math.pi * (t - hold * T) / T)
    y[t < hold * T] = d
    return t, y


@pytest.mark.parametrize("share, fires", [(0.9, False), (1.1, True)])
def test_a_hold_counts_from_fire_share_of_the_amplitude_off_the_line(share, fires):
    """The documented first rule (FIRE_SHARE = 0.15): a one-period hold at
    0.9 / 1.1 of it.  Where it fires, the deviation is the hold's level
    (exact: a whole-period window of a unit cosine has level 0 and
    amplitude 1), the free part begins within the period before the
    hold's end, and the fit MARGIN_PERIODS (0.5) later."""
    assert FIRE_SHARE == 0.15 and MARGIN_PERIODS == 0.5
    T = 2.0
    d = share * FIRE_SHARE
    t, y = _held_record(d, T=T)
    h = held_start(t, y, T)
    assert (h is not None) is fires
    if fires:
        assert h["deviation"] == pytest.approx(d, rel=1e-9)
        assert T - T <= h["t_free"] <= T  # the hold ends at t = T
        assert h["t_start"] == pytest.approx(h["t_free"] + 0.5 * T, rel=1e-12)
        assert h["rest_deviation"] < 1e-9


def test_a_held_end_is_the_held_start_of_the_record_reversed():
    """The record of the previous test run backwards (a free cosine, then
    the body held at 0.5 for a period): held_end reads it as held, the last
    free window ending where the reversed start's first free window begins
    (times negated), and the fit's end MARGIN_PERIODS before it."""
    T = 2.0
    t, y = _held_record(0.5, T=T)
    start = held_start(t, y, T)
    tr = t[-1] - t[::-1]  # the same grid, reversed in time
    e = held_end(tr, y[::-1], T)
    assert e is not None and e["how"] == "held"
    assert e["t_held"] == pytest.approx(t[-1] - start["t_free"], abs=1e-9)
    assert e["t_stop"] == pytest.approx(e["t_held"] - 0.5 * T, abs=1e-9)
    assert e["deviation"] == pytest.approx(0.5, rel=1e-9)


# ---------------------------------------------------------------------------
# slope_check (secant2): the ends brought in to the physical edge, the halvings
# ---------------------------------------------------------------------------
#
# Round 17's stand-in problem (tests/test_mutation_gaps17.py): one unknown Izz
# of a diagonal tensor (Ixx 0.014, Iyy 0.016), T_lin = c sqrt(Izz), the factor
# r = 1 + b (Izz - p0) run through the code's own _secant (monkeypatched), here
# with runs that fail beyond a stated distance from the estimate.

from bifilar.errors import BifilarError  # noqa: E402
from bifilar.estimation import slope_check  # noqa: E402
from bifilar.estimation.slope_check import SECANT_HALVINGS, SECANT_REACH, secant_check  # noqa: E402

from test_mutation_gaps17 import C, IXX, IYY, P0, _problem, _r  # noqa: E402


@pytest.fixture
def runs(monkeypatch):
    """The stand-in factor with trend ``b``; a run farther than ``reach``
    from P0 fails (a BifilarError, as a run that cannot be made)."""
    state = SimpleNamespace(b=8.0, reach=math.inf, calls=[], failed=[])

    def fake(pb, k, q, rtol):
        x = float(q[0])
        if abs(x - P0) > state.reach:
            state.failed.append(x)
            raise BifilarError("stand-in run failed")
        state.calls.append(x)
        return _r(x, 0.0, 1.0, state.b)

    monkeypatch.setattr(slope_check, "_unchecked_factor", fake)
    return state


def test_only_the_end_outside_the_tensors_is_brought_in(runs):
    """std 5.2e-3: P0 + 1.96 std = 0.0302 passes the triangle's edge
    (Ixx + Iyy) / (1 - 1e-4), P0 - 1.96 std = 0.0098 does not: the upper end
    at the edge, the lower one where the reach puts it (each side clipped on
    its own), and the warning gives the reach in std either side."""
    std = 5.2e-3
    h = SECANT_REACH * std
    top = (IXX + IYY) / (1 - 1e-4)
    pb, law = _problem(1e-6, dr_dp=0.0)
    msgs, _ = secant_check(pb, [P0], np.array([1.0]), [law], np.array([std]))
    assert sorted(runs.calls) == pytest.approx([P0 - h, top], abs=2e-6 * h)
    assert len(msgs) == 1 and f"-{SECANT_REACH:.3g} .. +{(top - P0) / std:.3g} std" in msgs[0], msgs
    assert "no physical inertia tensor" in msgs[0]
    # both ends inside (std 2e-3: 0.0161 .. 0.0239): the full interval, named as such
    runs.calls.clear()
    msgs, _ = secant_check(pb, [P0], np.array([1.0]), [law], np.array([2e-3]))
    assert len(runs.calls) == 2 and len(msgs) == 1
    assert "over the estimate's 95 % interval (" in msgs[0] and " std of the estimate" not in msgs[0], msgs


def test_a_reach_less_than_a_quarter_physical_is_not_run(runs):
    """Izz = 0.020 between 0 and the triangle's edge 0.030: with std 0.04
    the reach +-1.96 std = 0.078 keeps at most 0.030 of its 0.157 width
    physical, under a quarter (0.039): no run, one warning saying so; with
    std 0.018 (0.030 of 0.071, over a quarter) the clipped ends are run."""
    pb, law = _problem(1e-6, dr_dp=0.0)
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], np.array([0.04]))
    assert runs.calls == [] and not changed
    assert len(msgs) == 1 and "less than a quarter of it is a physical tensor" in msgs[0], msgs
    msgs, _ = secant_check(pb, [P0], np.array([1.0]), [law], np.array([0.018]))
    assert len(runs.calls) == 2 and "could not be checked" not in msgs[0]


def test_a_failed_run_halves_the_reach_up_to_twice(runs):
    """Runs fail beyond 0.3 h of the estimate: the secant is taken over +-h,
    then +-h / 2 (both fail), then +-h / 4 (SECANT_HALVINGS = 2), where it
    is the closed form (T(p + h/4) - T(p - h/4)) / (h / 2); the warning names
    the reach, +-0.49 std, and the failure."""
    assert SECANT_HALVINGS == 2
    std = 2.0e-3
    h = SECANT_REACH * std
    runs.reach = 0.3 * h
    pb, law = _problem(1e-6, dr_dp=0.0)
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], np.array([std]))
    assert runs.calls == pytest.approx([P0 + h / 4, P0 - h / 4], rel=1e-12)
    assert len(runs.failed) == 2  # the first end of each of the two wider tries
    T = [C * math.sqrt(q) * _r(q, 0.0, 1.0, runs.b) for q in (P0 + h / 4, P0 - h / 4)]
    sec = (T[0] - T[1]) / (h / 2)
    assert len(msgs) == 1 and f"({sec:.3g} s per unit)" in msgs[0] and "-0.49 .. +0.49 std" in msgs[0], msgs
    assert "a run at its end failed" in msgs[0] and not changed  # the secant the larger: the law stays


def test_a_slope_whose_runs_fail_within_a_quarter_of_the_reach_is_left_unchecked(runs):
    """Runs fail beyond 0.2 h: +-h, +-h/2, +-h/4 all fail, and an eighth is
    less than the quarter the check asks: one warning that the slope could
    not be checked, no law changed, no further run."""
    std = 2.0e-3
    runs.reach = 0.2 * SECANT_REACH * std
    pb, law = _problem(1e-6, dr_dp=0.0)
    msgs, changed = secant_check(pb, [P0], np.array([1.0]), [law], np.array([std]))
    assert runs.calls == [] and len(runs.failed) == 3
    assert len(msgs) == 1 and "could not be checked" in msgs[0] and "a run at its end failed" in msgs[0]
    assert not changed and law.dr_dp[0] == 0.0


# ---------------------------------------------------------------------------
# signal_wrap: the eighth of a turn; config/yaml_safe: only plain scalars
# ---------------------------------------------------------------------------

from bifilar.estimation.signal_wrap import MAX_STEP_TURNS, unwrap_record  # noqa: E402


@pytest.mark.parametrize("share, unwrapped", [(0.9, True), (1.1, False)])
def test_a_wrapped_angle_is_put_back_only_where_its_steps_stay_within_an_eighth_of_a_turn(share, unwrapped):
    """A heading turning steadily by 0.9 / 1.1 x MAX_STEP_TURNS (1/8) of a
    turn a sample, wrapped by atan2 into +-pi over 3/4 of a turn (within one
    turn: the other two conditions hold): below the eighth it is the
    steady rotation again (up to whole turns), above it is left alone."""
    assert MAX_STEP_TURNS == 0.125
    step = share * MAX_STEP_TURNS * 2 * math.pi
    k = np.arange(int(0.75 * 2 * math.pi / step) + 1)
    true = 2.5 + step * k  # crosses pi once
    wrapped = np.angle(np.exp(1j * true))
    assert np.abs(np.diff(wrapped)).max() > math.pi
    y, w = unwrap_record(wrapped)
    assert (w is not None) is unwrapped
    if unwrapped:
        assert np.allclose(y, true, atol=1e-12)
    else:
        assert np.array_equal(y, wrapped)


def test_a_record_spanning_more_than_a_turn_is_no_wrapped_angle():
    """A heading turning steadily from -1/4 to 5/4 of a turn, a turn taken
    off once as it passes one turn: its steps would unwrap within an eighth
    of a turn, but it spans 1.25 turns, which no atan2 angle does: left as
    it is (documented: the values span at most one turn)."""
    true = 2 * math.pi * np.linspace(-0.25, 1.25, 61)
    y = np.where(true > 2 * math.pi, true - 2 * math.pi, true)
    assert np.ptp(y) > 2 * math.pi and np.abs(np.diff(y)).max() > math.pi
    out, w = unwrap_record(y)
    assert w is None and np.array_equal(out, y)


def test_three_samples_across_the_wrap_are_unwrapped():
    """The rule holds from three samples (two steps): 3.0, -3.0, 3.0 rad
    is 3.0, 2 pi - 3.0, 3.0 (steps 0.28 rad, within an eighth of a turn)."""
    y, w = unwrap_record(np.array([3.0, -3.0, 3.0]))
    assert w is not None and np.allclose(y, [3.0, 2 * math.pi - 3.0, 3.0], atol=1e-12)


def test_an_explicitly_tagged_quoted_number_keeps_its_tag():
    """Only a plain scalar is retagged (the docstring): ``!!int "010"`` and
    ``!!float "1:30"`` ask for YAML 1.1's number explicitly, and are read
    as PyYAML's safe_load reads them (8, 90.0), while the same text plain
    stays text."""
    import yaml

    from bifilar.config import parse_yaml

    text = 'a: !!int "010"\nb: !!float "1:30"\nc: 010\n'
    d = parse_yaml(text)
    ref = yaml.safe_load(text)
    assert d["a"] == ref["a"] == 8 and d["b"] == ref["b"] == 90.0
    assert d["c"] == "010"


# ---------------------------------------------------------------------------
# signal_repeats: the resolution's share of a difference's noise
# ---------------------------------------------------------------------------

from bifilar.estimation.signal_repeats import repeated_samples  # noqa: E402


def test_repeats_in_a_quantised_noise_free_record_are_found_at_their_frames():
    """A cosine of 150 steps of q = 1 mrad, rounded to q (no other noise),
    30 fps, period 1.7 s: five frames written twice where the steps either
    side are 10-18 q.  Two independent roundings differ by a noise of
    variance 2 q^2 / 12 = q^2 / 6 (the documented s): with it the repeats
    stand ~6 s from chance and are found, each where it was put; the
    record without them shows none."""
    FS, T, q = 30.0, 1.7, 1e-3
    t = np.arange(0.0, 30 * T, 1 / FS)
    y = np.round(150 * np.cos(2 * np.pi * t / T + 0.4)) * q
    d = np.diff(y)
    fast = np.nonzero((np.abs(d[:-1]) > 10 * q) & (np.abs(d[1:]) > 10 * q) & (np.sign(d[:-1]) == np.sign(d[1:])))[0] + 1
    frames = np.sort(np.random.default_rng(1).choice(fast[10:-10], 5, replace=False))
    cnt = np.zeros(t.size, int)
    cnt[frames] = 1
    idx, _ = repeated_samples(np.repeat(y, 1 + cnt))
    assert np.array_equal(idx, frames + np.arange(5) + 1)
    assert repeated_samples(y)[0].size == 0


# ---------------------------------------------------------------------------
# period_specs.fit_record: every line kept, in order
# ---------------------------------------------------------------------------


def test_fit_record_keeps_the_readers_the_time_bases_and_the_held_starts_lines(tmp_path):
    """A heading without its time column at 30 fps, wrapped at +-pi (the
    reader's line), with six frames written twice (the time base's) and
    held for 1.5 s before the release (the held start's): the period is the
    cosine's 1.7 s within 3 std, and meta's warnings hold the three lines
    once each, in that order (none lost when the next is appended)."""
    from bifilar.estimation.period_specs import fit_record

    from test_signal_repeats import FS, T, _record

    y, _ = _record(seed=3)
    hold = y[0] + 5e-4 * np.random.default_rng(7).standard_normal(int(1.5 * FS))
    yw = np.angle(np.exp(1j * (math.pi - 0.02 + np.r_[hold, y])))
    p = tmp_path / "heading.csv"
    np.savetxt(p, yw, header="heading", comments="", fmt="%.10g")
    _, _, fit, meta, tbw, held = fit_record(p, sample_rate=FS)
    assert abs(float(fit.period) - T) < 3 * float(fit.std)
    w = meta["warnings"]
    assert len(w) == 3 and "wrapped at +-pi" in w[0] and w[1] == tbw and w[2] == held, w
    assert "6 repeated frames" in tbw and "not a free oscillation before" in held
    assert meta["time_base"]["repeated_frames"] == 6


# ---------------------------------------------------------------------------
# factor_inputs (eaunc): gravity and mass derived through the strain m g / EA
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("stiff", [True, False])
def test_mass_and_gravity_slopes_follow_the_strain_and_the_scaling(stiff):
    """A stand-in amplitude factor r = 1 + a I / (m L^2) + c m g / EA (one
    wire of length L; the strain term only where EA is stated), written
    out: dr/dL = -2 a I / (m L^3), dr/ds = -c m g / EA (EA -> EA (1 + s)),
    and analytically dr/dm = -a I / (m^2 L^2) + c g / EA, dr/dg = c m / EA;
    without EA, dr/dg = 0 (g only scales time).  derive_factor_routes must
    give those from the measured dr/dL and dr/ds."""
    from bifilar.estimation.factor_inputs import derive_factor_routes

    a, c, I, m, g, L, EA = 0.3, 40.0, 0.05, 2.0, 9.81, 1.2, 5e4
    cc = c if stiff else 0.0
    scene = SimpleNamespace(n_wires=1, mass=m, gravity=g, lengths=np.array([L]),
                            stiffness=np.array([EA]) if stiff else None)
    dx = {"length.1": -2 * a * I / (m * L**3)}
    if stiff:
        dx["stiffness"] = -cc * m * g / EA
    derive_factor_routes(dx, {"mass": "scaling", "gravity": "gravity"}, scene, np.eye(3))
    assert dx["mass"] == pytest.approx(-a * I / (m**2 * L**2) + cc * g / EA, rel=1e-12)
    assert dx["gravity"] == pytest.approx(cc * m / EA, rel=1e-12, abs=0.0)
