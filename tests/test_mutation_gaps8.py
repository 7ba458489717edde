"""Tests written to kill surviving mutants of round 8 (docs/mutation.md,
"Round 8"): the crossing period (``bifilar/estimation/signal_crossings.py``),
the linear modes (``bifilar/analysis/modes.py``), the config checks
(``bifilar/config/plausibility.py``, ``fields.py``, ``inertia.py``), the
timing advice (``bifilar/studies/timing.py``) and the stop handling
(``bifilar/interrupts.py``).

Truths: hand-worked cases (every expected number is worked out in the
comments), closed forms (the two-wire bifilar torsion period, the
stopwatch and Cramer-Rao formulas of the module docstrings), invariance
to the unit of time, and known noise levels -- never output of the code
under test pasted in.  Each test runs in well under 2 s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.estimation.signal_crossings import _crossing_time, period_from_crossings
from bifilar.estimation.signal_io import SignalError

# ---------------------------------------------------------------------------
# signal_crossings.py: where one crossing lies
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("ds,expected", [
    # t = 0, 1, 2; line through (-1, 0.2, 1): slope ((-1)(-1) + (1)(1)) / 2 = 1 about t_mean = 1,
    # mean 0.2 / 3: zero at 1 - 0.2 / 3 = 0.9333 (between t0 and t1; linear interpolation of the
    # sign change would say 1 / 1.2 = 0.8333)
    ([-1.0, 0.2, 1.0], 1.0 - 0.2 / 3),
    # (-1, -0.2, 1): slope 1, mean -0.2 / 3: zero at 1.0667 (between t1 and t2; interpolation 1.1667)
    ([-1.0, -0.2, 1.0], 1.0 + 0.2 / 3),
    # t = 0..3, (-1, -0.2, 0.6, 1): slope (1.5 + 0.1 + 0.3 + 1.5) / 5 = 0.68 about 1.5, mean 0.1:
    # zero at 1.5 - 0.1 / 0.68 = 1.35294 (interpolation 1.25)
    ([-1.0, -0.2, 0.6, 1.0], 1.5 - 0.1 / 0.68),
    # the same samples negated (a falling crossing): the line's zero does not move
    ([1.0, 0.2, -0.6, -1.0], 1.5 - 0.1 / 0.68),
])
def test_crossing_time_is_the_zero_of_the_least_squares_line(ds, expected):
    ts = np.arange(len(ds), dtype=float)
    assert _crossing_time(ts, np.asarray(ds), 0, len(ds) - 1) == pytest.approx(expected, abs=1e-12)
    # the same in another unit of time and origin (t -> 100 + 0.01 t)
    assert _crossing_time(100 + 0.01 * ts, np.asarray(ds), 0, len(ds) - 1) == pytest.approx(
        100 + 0.01 * expected, abs=1e-10)


@pytest.mark.parametrize("ds,expected", [
    ([-0.3, 0.2], 1.0 + 0.3 * 0.5 / 0.5),  # t = 1, 1.5: 0.3 of the 0.5 rise, 1.3
    ([0.2, -0.3], 1.0 + 0.2 * 0.5 / 0.5),  # falling: 1.2
])
def test_crossing_time_of_two_samples_is_linear_interpolation(ds, expected):
    assert _crossing_time(np.array([1.0, 1.5]), np.asarray(ds), 0, 1) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("ds,k,expected", [
    # 8 samples, middle 3.5; the least-squares line crosses at t = 9.1 (outside 0..7): fall back on
    # the sign changes 0-1, 2-3, 6-7; nearest the middle 2-3 (1.5 away): 2 + 0.31 / 0.45
    ([-0.6, 0.38, 0.31, -0.14, -0.37, -0.48, -0.46, 0.58], 2, 2 + 0.31 / 0.45),
    # 9 samples, middle 4; the line crosses at 10.7; sign changes 0-1, 2-3, 3-4, 4-5, 7-8: the
    # middle one 4-5: 4 + 0.1 / 0.5
    ([-0.6, 0.3, 0.2, -0.1, 0.1, -0.4, -0.4, -0.4, 0.5], 4, 4 + 0.1 / 0.5),
])
def test_crossing_time_falls_back_on_the_sign_change_nearest_the_middle(ds, k, expected):
    ds = np.asarray(ds)
    ts = np.arange(ds.size, dtype=float)
    slope, icpt = np.polyfit(ts, ds, 1)
    assert not 0 <= -icpt / slope <= ts[-1]  # (the premise: the line's zero is outside the bracket)
    assert ds[k] * ds[k + 1] < 0
    assert _crossing_time(ts, ds, 0, ds.size - 1) == pytest.approx(expected, abs=1e-12)


def test_a_line_falling_through_a_rising_crossing_is_not_trusted():
    """Band +-1; the samples rise from -1.01 to 1.01 but wander inside the band, high early and
    low late: the least-squares slope, (8.08 - 12) / 60, is negative (its zero, 4.85, lies inside
    the bracket).  A line falling through a rising crossing is no crossing's line: the sign
    change nearest the middle (4 -> 5) is interpolated instead, 4 + 0.5 / 1.5."""
    ds = np.array([-1.01, 1.0, 1.0, 1.0, 0.5, -1.0, -1.0, -1.0, 1.01])
    ts = np.arange(ds.size, dtype=float)
    slope, icpt = np.polyfit(ts, ds, 1)
    assert slope < 0 and 0 <= -icpt / slope <= ts[-1]  # (the premise)
    assert _crossing_time(ts, ds, 0, ds.size - 1) == pytest.approx(4 + 0.5 / 1.5, abs=1e-12)


# ---------------------------------------------------------------------------
# signal_crossings.py: the period
# ---------------------------------------------------------------------------


def _sine_with_spikes(scale=1.0):
    """sin(2 pi t / 1.25) sampled every 1 ms for 20 s, noise 1e-3, with a spike of -2 over 3
    samples at every peak and +2 at every trough (each crosses the level twice, down and back
    up: an even burst, a glitch), the last one at 19.6875 s after the last real crossing
    (19.375 s); times in units of ``scale`` s."""
    T, dt = 1.25, 0.001
    t = np.arange(0, 20, dt)
    y = np.sin(2 * np.pi * t / T) + 1e-3 * np.random.default_rng(0).standard_normal(t.size)
    for k in range(16):
        for tp, s in ((T / 4 + k * T, -2.0), (3 * T / 4 + k * T, 2.0)):
            if tp < 20:
                i = int(round(tp / dt))
                y[i:i + 3] += s
    return t / scale, y


@pytest.mark.parametrize("scale", [1.0, 1e-3, 1e2])
def test_spikes_away_from_the_level_are_dropped_in_any_unit_of_time(scale):
    """Real crossings: ups at 1.25, 2.5, ..., 18.75 (15; t = 0 starts on the level), downs at
    0.625, ..., 19.375 (16): 14 + 15 same-direction intervals of 1.25 s.  The spikes' pairs of
    crossings (1.5 ms apart, far below 0.2 x the 0.625 s median spacing) are glitches.  The rule
    has no time scale of its own: the same record in ms or in units of 100 s gives the same
    crossings."""
    t, y = _sine_with_spikes(scale)
    cr = period_from_crossings(t, y)
    assert cr.up_times.size == 15 and cr.down_times.size == 16 and cr.n_periods == 29
    assert cr.period == pytest.approx(1.25 / scale, rel=1e-5)
    assert cr.mean_period == pytest.approx(1.25 / scale, rel=1e-5)
    assert cr.frequency == pytest.approx(scale / 1.25, rel=1e-5)  # Hz
    assert cr.down_times[-1] == pytest.approx(19.375 / scale, rel=1e-5)


def test_default_hysteresis_is_three_times_the_white_noise_level():
    """The documented default band: 3 x the white-noise standard deviation (here known: 0.01)."""
    rng = np.random.default_rng(3)
    t = np.arange(0, 20, 0.001)
    y = np.sin(2 * np.pi * t / 1.25) + 0.01 * rng.standard_normal(t.size)
    cr = period_from_crossings(t, y)
    # the robust estimate from 20 000 second differences: ~1 % scatter; the sine adds
    # (2 pi / 1.25)^2 1e-6 = 2.5e-5 to differences of std 0.01 sqrt(6): negligible
    assert cr.hysteresis == pytest.approx(3 * 0.01, rel=0.05)


@pytest.mark.parametrize("t0,t1,ups,downs", [
    (0.1, 2.6, [1.0, 2.0], [0.5, 1.5, 2.5]),  # sin(2 pi t): 2 ups, 3 downs
    (0.6, 3.1, [1.0, 2.0, 3.0], [1.5, 2.5]),  # 3 ups, 2 downs
    # the record ends 2 ms after its last crossing, at the first sample beyond the band
    # (sin(2 pi 0.002) = 0.0126 > 0.01)
    (0.1, 2.5025, [1.0, 2.0], [0.5, 1.5, 2.5]),
])
def test_five_crossings_are_two_full_periods(t0, t1, ups, downs):
    """The documented minimum: two full periods, i.e. five crossings, at least two each way
    (3 same-direction intervals of 1 s here)."""
    t = np.arange(t0, t1, 0.001)
    cr = period_from_crossings(t, np.sin(2 * np.pi * t), level=0.0, hysteresis=0.01)
    assert cr.up_times == pytest.approx(ups, abs=1e-9) and cr.down_times == pytest.approx(downs, abs=1e-9)
    assert cr.period == pytest.approx(1.0, abs=1e-9) and cr.n_periods == 3
    assert cr.frequency == pytest.approx(1.0, abs=1e-9)


def test_four_crossings_are_refused():
    """0.1 .. 2.2 s of sin(2 pi t): ups at 1, 2, downs at 0.5, 1.5 -- one and a half periods."""
    t = np.arange(0.1, 2.2, 0.001)
    with pytest.raises(SignalError) as e:
        period_from_crossings(t, np.sin(2 * np.pi * t), level=0.0, hysteresis=0.01)
    assert e.value.field == "signal" and "only 4 crossings" in str(e.value)


# ---------------------------------------------------------------------------
# modes.py
# ---------------------------------------------------------------------------

G = 9.81


def _bifilar(mass=2.0, inertia=(0.1, 0.15, 0.2), half_sep=0.5, length=1.5):
    """Two vertical wires of ``length`` m, ``2 half_sep`` m apart along y, attached 0.1 m above
    the CoM of a body of ``mass`` kg and principal moments ``inertia`` kg m^2."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.config import scene_from_dict

    r = half_sep
    scene = scene_from_dict({
        "gravity": G,
        "body": {"mass": mass, "inertia": {"principal": list(inertia)}},
        "rig": {"anchors": [[0, -r, 0], [0, r, 0]], "attachments": [[0, -r, 0.1], [0, r, 0.1]],
                "lengths": [length, length]}}, warn=False)
    return scene, rest_pose(scene)


def test_bifilar_modes_are_the_closed_forms_found_by_label_prefix_and_index():
    """Torsion T = 2 pi sqrt(I L / (m g r^2)); the sideways swing in the wires' plane is a
    parallelogram (the body translates): T = 2 pi sqrt(L / g).  Labels by prefix and 1-based
    index; the default mode is the torsion."""
    from bifilar.analysis.modes import linear_modes
    from bifilar.errors import InputError

    m, Izz, r, L = 2.0, 0.2, 0.5, 1.5
    ms = linear_modes(*_bifilar(m, (0.1, 0.15, Izz), r, L))
    assert len(ms.modes) == 4  # 6 - 2 wires
    tors = ms.get("tors")  # a unique prefix
    assert tors.label == "torsion" and tors.period == pytest.approx(2 * math.pi * math.sqrt(Izz * L / (m * G * r * r)),
                                                                    rel=1e-9)
    assert tors.dominant == 5 and tors.shape[5] == pytest.approx(1.0) and tors.energy_share[5] == pytest.approx(1.0)
    assert ms.get("swing-y").period == pytest.approx(2 * math.pi * math.sqrt(L / G), rel=1e-9)
    periods = [md.period for md in ms.modes]
    assert periods == sorted(periods, reverse=True)  # slowest first
    for k in range(1, 5):
        assert ms.get(k) is ms.modes[k - 1] and ms.get(str(k)) is ms.modes[k - 1]
    for bad in (0, 5, "swing", "bounce"):  # out of range, ambiguous prefix (swing-x, swing-y), absent
        with pytest.raises(KeyError):
            ms.get(bad)
    assert ms.pick(None) is tors
    with pytest.raises(InputError) as e:
        ms.pick("swing", option="--measure")
    assert e.value.field == "--measure"
    for md in ms.modes:  # shapes scaled to a largest component of +1, shares summing to 1
        assert np.max(np.abs(md.shape)) == pytest.approx(1.0) and md.shape[md.dominant] == pytest.approx(1.0)
        assert md.energy_share.sum() == pytest.approx(1.0)


def test_without_a_torsion_the_default_mode_is_the_slowest():
    from bifilar.analysis.modes import ModeSet, linear_modes

    ms = linear_modes(*_bifilar())
    rest = ModeSet([md for md in ms.modes if md.label != "torsion"], ms.mass_matrix, ms.basis)
    assert rest.pick(None) is rest.modes[0] and rest.modes[0].label == "swing-x"


def test_a_modes_description_names_its_two_main_components_over_one_percent():
    from bifilar.analysis.modes import Mode

    def desc(share):
        return Mode("m", 1.0, 1.0, np.eye(6)[0], np.asarray(share, float), 0).description

    assert desc([0.5, 0.3, 0.2, 0, 0, 0]) == "x 50%, y 30%"  # the two largest, not the third
    assert desc([0, 0, 0, 0.05, 0, 0.95]) == "rz 95%, rx 5%"
    assert desc([0.995, 0.005, 0, 0, 0, 0]) == "x 100%"  # 0.5 % is no main component


def test_degenerate_clusters_are_runs_of_two_or_more_within_rel_of_the_scale():
    """Neighbours within rel x scale of a run's first member; a lone eigenvalue is no cluster."""
    from bifilar.analysis.modes import degenerate_clusters

    w2 = np.array([1.0, 2.0, 2.0 + 0.5e-3, 2.0 + 0.9e-3, 3.0, 4.0, 4.0 + 2e-3])
    assert degenerate_clusters(w2, scale=1.0, rel=1e-3) == [(1, 4)]  # 4 + 2e-3 is 2e-3 away
    assert degenerate_clusters(w2, scale=10.0, rel=1e-3) == [(1, 4), (5, 7)]
    assert degenerate_clusters(np.array([1.0, 2.0, 3.0]), scale=3.0) == []


def _diag_problem(w2):
    """K y = w M y with M = I and K = diag(w2): Y = I, and each eigenvalue's resolution is
    DEGENERATE_RTOL |y|^T |K| |y| = DEGENERATE_RTOL w."""
    w2 = np.asarray(w2, float)
    return w2, np.eye(w2.size), np.diag(w2)


@pytest.mark.parametrize("d,plain_batch,plain_one", [
    (5.0, True, True),  # split by 5 resolutions of the pair: apart, with the batch's margin of 2
    (1.5, False, True),  # apart (> 1 resolution) but within twice it: the batch declines
    (0.5, False, False),  # within the resolution: one degenerate cluster
])
def test_plain_order_is_eigenvalues_apart_by_twice_their_resolution(d, plain_batch, plain_one):
    """Eigenvalues 1, 2, 2 + d x (the pair's resolution, DEGENERATE_RTOL x 2): written in units of
    the constant, whose value is a tuning choice."""
    from bifilar.analysis.modes import DEGENERATE_RTOL, _plain_one, plain_order

    gap = d * DEGENERATE_RTOL * 2.0
    w2, Y, K = _diag_problem([1.0, 2.0, 2.0 + gap])
    assert bool(plain_order(w2[None], Y[None], K[None])[0]) is plain_batch
    assert _plain_one(w2, Y, K) is plain_one
    # two modes only (a 4-wire rig): the same rule for its pair
    w2, Y, K = _diag_problem([2.0, 2.0 + gap])
    assert bool(plain_order(w2[None], Y[None], K[None])[0]) is plain_batch
    # one mode (a 5-wire rig): nothing to cluster, positive: plain
    w2, Y, K = _diag_problem([2.0])
    assert plain_order(w2[None], Y[None], K[None])[0] and _plain_one(w2, Y, K)


def test_mode_set_without_a_stiffness_resolves_relative_to_the_largest_eigenvalue():
    """Without K, one resolution DEGENERATE_RTOL x max |omega^2| for all: translations of a 2 kg
    body with omega^2 = 1, 1 + 0.1 R x 100 and 100 (R = DEGENERATE_RTOL): the first two are one
    cluster (identical periods, the mean's), the third apart."""
    from bifilar.analysis.modes import DEGENERATE_RTOL, mode_set

    m = 2.0
    N = np.eye(6)[:, :3]  # x, y, z translations
    M = np.diag([m, m, m, 1.0, 1.0, 1.0])
    Y = np.eye(3) / math.sqrt(m)  # M-normalised: Y^T N^T M N Y = I
    w2 = np.array([1.0, 1.0 + 0.1 * DEGENERATE_RTOL * 100.0, 100.0])
    ms = mode_set(N, Y, w2, m, M)
    P = sorted(md.period for md in ms.modes)
    assert P[1] == P[2] == pytest.approx(2 * math.pi / math.sqrt(w2[:2].mean()), rel=1e-15)
    assert P[0] == pytest.approx(2 * math.pi / 10.0, rel=1e-12)
    assert [md.label for md in ms.modes] == ["swing-x", "swing-y", "bounce"]


@pytest.mark.parametrize("f,neutral", [(0.1, True), (10.0, False)])
def test_an_eigenvalue_below_neutral_rtol_of_the_largest_has_no_period(f, neutral):
    """omega^2 = f x NEUTRAL_RTOL x 100 beside 1 and 100 (each resolved to DEGENERATE_RTOL of
    itself, K = diag): below the threshold it is neutral (no period, listed last), above it has
    its period 2 pi / omega."""
    from bifilar.analysis.modes import NEUTRAL_RTOL, mode_set, mode_sets

    m = 2.0
    N = np.eye(6)[:, :3]
    M = np.diag([m, m, m, 1.0, 1.0, 1.0])
    w2 = np.array([f * NEUTRAL_RTOL * 100.0, 1.0, 100.0])
    ms = mode_set(N, np.eye(3) / math.sqrt(m), w2, m, M, K=np.diag(w2) * m)
    # the batch's mode_sets decide the same for a batch of one
    (batch,) = mode_sets(N[None], (np.eye(3) / math.sqrt(m))[None], w2[None], np.array([m]), M[None],
                         (np.diag(w2) * m)[None])
    for s in (ms, batch):
        if neutral:
            assert s.modes[-1].period is None and s.modes[-1].label == "swing-x"
        else:
            assert s.modes[0].period == pytest.approx(2 * math.pi / math.sqrt(w2[0]), rel=1e-12)


@pytest.mark.parametrize("w2", [[-1.0, 2.0, 3.0], [0.0, 2.0, 3.0], [1e-14, 2.0, 3.0]])
def test_a_negative_or_neutral_eigenvalue_is_never_plain(w2):
    from bifilar.analysis.modes import _plain_one, plain_order

    w2, Y, K = _diag_problem(w2)
    assert not plain_order(w2[None], Y[None], K[None])[0]
    assert not _plain_one(w2, Y, K)


def test_plain_order_takes_each_pairs_own_resolution():
    """A stiff mode (1e4) mixed with a soft one (1) by a 45 degree rotation: the soft mode's
    resolution 1e-10 |y|^T |K| |y| is ~1e-6 (the rotated stiffness's terms), far above 1e-10 of
    its eigenvalue.  The pair 2, 2 + 1e-8 of two unmixed modes (resolution 2e-10 each) is apart:
    the soft mode's coarse resolution is not theirs."""
    from bifilar.analysis.modes import eigh_generalized, plain_order

    c = math.sqrt(0.5)
    Q = np.eye(4)
    Q[np.ix_([0, 3], [0, 3])] = [[c, -c], [c, c]]
    K = Q @ np.diag([1.0, 2.0, 2.0 + 1e-8, 1e4]) @ Q.T
    w2, Y = eigh_generalized(K, np.eye(4))
    assert w2 == pytest.approx([1.0, 2.0, 2.0 + 1e-8, 1e4], rel=1e-9)
    res = 1e-10 * np.einsum("ik,ij,jk->k", np.abs(Y), np.abs(K), np.abs(Y))
    assert res[0] > 1e-7 and res[1] < 1e-9  # (the premise)
    assert plain_order(w2[None], Y[None], K[None])[0]


def test_crossing_period_std_is_the_pooled_regressions_standard_error():
    """t = a + T n (+ delta for downward crossings): by Frisch-Waugh the slope is the pooled
    within-direction regression, T = Sxy / Sxx with each direction centred on its own means, and
    its standard error sqrt(RSS / (N - 3) / Sxx) (three parameters).  Cycle numbers by hand:
    every crossing of this record is found, so they run 0, 1, 2, ... each way."""
    rng = np.random.default_rng(11)
    t = np.arange(0, 20, 0.002)
    y = np.sin(2 * np.pi * t / 1.3 + 0.4) + 0.05 * rng.standard_normal(t.size)
    cr = period_from_crossings(t, y)
    sxx = sxy = rss = 0.0
    n_all = 0
    for times in (cr.up_times, cr.down_times):
        assert np.all(np.abs(np.diff(times) - 1.3) < 0.1)  # no crossing lost or doubled
        n = np.arange(times.size, dtype=float)
        dn, dt = n - n.mean(), times - times.mean()
        sxx += dn @ dn
        sxy += dn @ dt
        n_all += times.size
    T = sxy / sxx
    for times in (cr.up_times, cr.down_times):
        n = np.arange(times.size, dtype=float)
        r = (times - times.mean()) - T * (n - n.mean())
        rss += r @ r
    assert cr.period == pytest.approx(T, rel=1e-12)
    assert cr.std == pytest.approx(math.sqrt(rss / (n_all - 3) / sxx), rel=1e-9)
    assert cr.n_periods == n_all - 2 and cr.periods.size == n_all - 2
    assert cr.scatter == pytest.approx(np.std(np.r_[np.diff(cr.up_times), np.diff(cr.down_times)], ddof=1), rel=1e-12)


# ---------------------------------------------------------------------------
# config/plausibility.py: the documented rules, each side of each threshold
# ---------------------------------------------------------------------------


def _warnings(anchors=((0, -0.5, 0), (0, 0.5, 0)), attachments=((0, -0.5, 0.1), (0, 0.5, 0.1)),
              lengths=(1.5, 1.5), mass=2.0, k=None, principal=(0.1, 0.1, 0.2), box=None, gravity=9.81,
              parts=None):
    """plausibility_warnings of a bifilar config; ``k``: principal moments m k^2 (0.6, 0.6, 1)
    (the largest moment m k^2, so the radius of gyration is k)."""
    from bifilar.config import scene_from_dict
    from bifilar.config.plausibility import plausibility_warnings

    if k is not None:
        principal = (0.6 * mass * k * k, 0.6 * mass * k * k, mass * k * k)
    body = {"mass": mass, "inertia": {"principal": list(principal)}} if parts is None else {"parts": parts}
    if box is not None:  # +-box, or (min, max) corners
        lo, hi = box if isinstance(box, tuple) else ([-box] * 3, [box] * 3)
        body["bounding_box"] = {"min": list(lo), "max": list(hi)}
    cfg = {"gravity": gravity, "body": body,
           "rig": {"anchors": [list(a) for a in anchors], "attachments": [list(p) for p in attachments],
                   "lengths": list(lengths)}}
    return plausibility_warnings(scene_from_dict(cfg, warn=False))


def test_wires_over_a_kilometre_warn_and_name_the_longest():
    wide = ((0, -10, 0), (0, 10, 0))  # anchors 20 m apart: not the millimetre rule (spans under 10 m)
    assert _warnings(anchors=wide, lengths=(999.0, 999.0)) == []
    w = _warnings(anchors=wide, lengths=(1001.0, 1002.0))
    assert len(w) == 1 and w[0].startswith("rig.lengths.1 = 1002 m is implausibly long")


def test_lengths_in_millimetres_need_every_wire_long_in_a_small_rig():
    """Every wire over 100 m while anchors and attachments span under 10 m."""
    assert "millimetres" in _warnings(anchors=((0, -4.5, 0), (0, 4.5, 0)), lengths=(101.0, 101.0))[0]
    assert _warnings(anchors=((0, -5.5, 0), (0, 5.5, 0)), lengths=(101.0, 101.0)) == []  # 11 m span
    # not every wire over 100 m: no millimetres (every wire over 20 m in a 1 m rig reads as centimetres, session 19)
    w = _warnings(lengths=(99.0, 101.0))
    assert not any("millimetres" in x for x in w) and len(w) == 1 and "centimetres" in w[0]


def test_the_documented_bounds_themselves_are_plausible():
    """"Longer than", "heavier than", "less than", "outside": the bounds are not flagged."""
    assert _warnings(anchors=((0, -5.0, 0), (0, 5.0, 0)), lengths=(101.0, 101.0)) == []  # spans exactly 10 m
    # exactly 100 m wires in a 1 m rig: not millimetres (they read as centimetres, the rule of 20 m, session 19)
    assert not any("millimetres" in x for x in _warnings(lengths=(100.0, 100.0)))
    assert _warnings(anchors=((0, -10, 0), (0, 10, 0)), lengths=(1000.0, 1000.0)) == []
    assert _warnings(mass=1e5, k=0.5) == []


def test_a_wide_body_is_no_millimetre_rig():
    """Anchors span 9 m but the attachments 12 m (x): not 'everything under 10 m'."""
    w = _warnings(anchors=((-4.5, 0, 0), (4.5, 0, 0)), attachments=((-6, 0, 0.1), (6, 0, 0.1)),
                  lengths=(101.0, 101.0), k=1.0)
    assert w == []


@pytest.mark.parametrize("g,n", [(1.0, 0), (30.0, 0), (0.99, 1), (30.1, 1), (981.0, 1)])
def test_gravity_from_one_to_thirty_is_plausible(g, n):
    assert len(_warnings(gravity=g)) == n


@pytest.mark.parametrize("k,n", [(0.9, 0), (1.1, 1)])
def test_a_known_shape_bounds_the_radius_of_gyration_by_twice_its_reach(k, n):
    """Bounding box +-0.5 m (reach h = 0.5 m along each body axis): k > 2 h = 1 m warns."""
    w = _warnings(k=k, box=0.5)
    assert len(w) == n and all("does not fit a body reaching 0.5 m" in x for x in w)


@pytest.mark.parametrize("k,n", [(0.02, 0), (0.015, 1), (14.0, 0), (16.0, 1)])
def test_attachments_alone_bound_the_radius_of_gyration_thirty_fold_either_way(k, n):
    """Attachments reaching 0.5 m (along y), no shape: warn when k > 30 x 0.5 = 15 m or
    k < 0.5 / 30 = 0.0167 m.  1000 kg: the mass rule (k > 10 m (m / 1 kg)^(1/3) = 100 m) is quiet."""
    w = _warnings(k=k, mass=1000.0)
    assert len(w) == n and all("(attachments)" in x for x in w)


@pytest.mark.parametrize("reach,n", [(0.09, 0), (0.11, 1)])
def test_attachments_beyond_ten_times_the_shape_warn(reach, n):
    """A 1 cm box: attachments up to 10 cm from the CoM are plausible, beyond are not."""
    att = ((0, -reach, 0.0), (0, reach, 0.0))
    w = _warnings(attachments=att, anchors=((0, -reach, 1.0), (0, reach, 1.0)), box=0.01, k=0.05)
    assert [x for x in w if x.startswith("rig.attachments reach")] == w and len(w) == n


# ---------------------------------------------------------------------------
# studies/timing.py: the module docstring's rules, worked by hand
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("sep,N", [
    (None, 10), (math.inf, 10),  # no other mode: the usual ten
    (0.0, 50), (-0.1, 50), (math.nan, 50),  # no separation: the most
    (0.5, 10), (0.05, 20), (1 / 30, 30), (0.01, 50),  # ceil(1 / s) within 10 .. 50
    (1 / 30.5, 31),
])
def test_cycles_per_trial_span_a_beat_within_ten_to_fifty(sep, N):
    from bifilar.studies.timing import cycles_per_trial

    assert cycles_per_trial(sep) == N


def test_stopwatch_and_sensor_sigmas_are_the_documented_formulas():
    """sigma_T = reaction / (N sqrt(n)); the sensor: Kay's bound var(w) = 12 / (eta M^3) for the
    frequency in radians per sample, eta = A^2 / (2 sigma^2) = 1 / (2 noise^2), w = 2 pi dt / T."""
    from bifilar.studies.timing import sensor_sigma, stopwatch_sigma

    assert stopwatch_sigma(0.1, 10, 4) == pytest.approx(0.1 / 20, rel=1e-12)
    assert stopwatch_sigma(0.2, 25, 1) == pytest.approx(0.008, rel=1e-12)
    T, noise, rate, N = 3.0, 0.01, 100.0, 10
    M, dt = rate * N * T, 1 / rate  # 3000 samples
    sd_w_per_sample = math.sqrt(12 / (M ** 3 / (2 * noise ** 2)))
    sd_T = T ** 2 / (2 * math.pi) * sd_w_per_sample / dt  # T = 2 pi / w: dT = T^2 dw / (2 pi)
    for n in (1, 4, 9):
        assert sensor_sigma(T, noise, rate, N, n) == pytest.approx(sd_T / math.sqrt(n), rel=1e-12)


@pytest.mark.parametrize("target,n", [(0.01, 1), (0.005, 4), (0.004, 7), (0.0025, 16)])
def test_trials_are_the_fewest_reaching_the_target(target, n):
    """One 10-cycle stopwatch trial: 0.1 / 10 = 0.01 s; n trials 0.01 / sqrt(n): the target 0.005
    needs exactly 4 (the ratio squared, 4, not rounded up to 5), 0.004 needs 6.25 -> 7."""
    from bifilar.studies.timing import advice

    row = advice(2.0, None, target, reaction=0.1)
    sw = row["stopwatch"]
    assert row["cycles_per_trial"] == 10 and sw["trials"] == n
    assert sw["sigma"] == pytest.approx(0.01 / math.sqrt(n), rel=1e-12)
    assert sw["time_s"] == pytest.approx(n * 10 * 2.0, rel=1e-12)  # n trials of 10 cycles of 2 s


def test_sensor_records_are_the_fewest_reaching_the_target():
    from bifilar.studies.timing import advice, sensor_sigma

    one = sensor_sigma(2.0, 0.01, 100.0, 10, 1)
    row = advice(2.0, None, one / 3, reaction=0.1, sensor=(0.01, 100.0))  # (1 / (1/3))^2 = 9 records
    se = row["sensor"]
    assert (se["noise"], se["rate"], se["records"]) == (0.01, 100.0, 9)
    assert se["sigma"] == pytest.approx(one / 3, rel=1e-12) and se["time_s"] == pytest.approx(9 * 10 * 2.0)


def test_an_exact_timing_target_is_reported_as_such():
    from bifilar.studies.timing import advice, describe

    row = advice(2.0, None, 0.0, sensor=(0.01, 100.0))
    assert row["stopwatch"]["trials"] == 0 and row["stopwatch"]["sigma"] is None
    assert row["sensor"]["records"] == 0 and row["sensor"]["sigma"] is None
    row["mode"], row["components"] = "torsion", ["Izz"]
    assert describe(row) == "torsion (T = 2 s): the plan assumes exact timing (timing = 0)"


def test_the_timing_line_quotes_minutes_and_milliseconds():
    from bifilar.studies.timing import advice, describe

    row = {"mode": "torsion", "components": ["Izz", "Ixx"],
           **advice(3.0, 0.05, 0.001, reaction=0.1, sensor=(0.01, 100.0))}
    # 20 cycles (sep 0.05); 0.1 / 20 = 5 ms a trial: 25 trials, 25 x 20 x 3 s = 25 min, +-1 ms
    assert describe(row).startswith(
        "torsion (T = 3 s, for Izz, Ixx): time 20 cycles per trial; stopwatch (+-0.1 s a trial): 25 trials "
        "(~25 min) for +-1 ms a period; sensor: 1 record(s) of 20 cycles (+-")


def test_how_to_time_separates_each_timed_mode_from_its_nearest_finite_neighbour():
    """Modes 2.0, 1.9, 1.0 s and a neutral one: torsion (2.0) is |2.0 - 1.9| / 2.0 = 5 % from its
    nearest -> 20 cycles; the 1.0 s mode, relative to its own period, |1.0 - 1.9| / 1.0 = 0.9 -> 10.
    Only identifiable components with a mode are timed, each mode once."""
    from bifilar.studies.timing import how_to_time

    point = {"periods": {"torsion": 2.0, "swing": 1.9, "pitch": 1.0, "bounce": None},
             "components": {"Izz": {"identifiable": True, "mode": "torsion"},
                            "Ixx": {"identifiable": True, "mode": "pitch"},
                            "Iyy": {"identifiable": True, "mode": "pitch"},
                            "Ixy": {"identifiable": False, "mode": "swing"},
                            "Ixz": {"identifiable": True, "mode": None}}}
    rows = {r["mode"]: r for r in how_to_time(point, 0.01, reaction=0.1)}
    assert set(rows) == {"torsion", "pitch"}
    assert rows["torsion"]["separation"] == pytest.approx(0.05, rel=1e-12) and rows["torsion"]["cycles_per_trial"] == 20
    assert rows["pitch"]["separation"] == pytest.approx(0.9, rel=1e-12) and rows["pitch"]["cycles_per_trial"] == 10
    assert rows["pitch"]["components"] == ["Ixx", "Iyy"] and rows["torsion"]["period"] == 2.0


@pytest.mark.parametrize("text,ok", [("0.01,100", (0.01, 100.0)), ("1e-3, 2e3", (1e-3, 2e3)), ("2,0.5", (2.0, 0.5)),
                                     (None, None)])
def test_sensor_spec_parses(text, ok):
    from bifilar.studies.timing import parse_sensor

    assert parse_sensor(text) == ok


@pytest.mark.parametrize("text", ["0.01", "0.01,100,3", "a,b", "0,100", "0.01,0", "-0.01,100", "inf,100", "0.01,nan"])
def test_bad_sensor_specs_name_the_option(text):
    from bifilar.errors import InputError
    from bifilar.studies.timing import parse_sensor

    with pytest.raises(InputError) as e:
        parse_sensor(text)
    assert e.value.field == "--sensor"


@pytest.mark.parametrize("r", [0.0, -0.1, math.inf, math.nan])
def test_the_reaction_sigma_must_be_positive_and_finite(r):
    from bifilar.errors import InputError
    from bifilar.studies.timing import check_reaction

    with pytest.raises(InputError) as e:
        check_reaction(r)
    assert e.value.field == "--stopwatch"
    assert check_reaction(0.25) == 0.25


# ---------------------------------------------------------------------------
# interrupts.py
# ---------------------------------------------------------------------------


def _chain(depth, last):
    """An exception whose __context__ chain reaches ``last`` after ``depth`` links."""
    exc = last
    for k in range(depth):
        try:
            try:
                raise exc
            except BaseException:
                raise ValueError(k)
        except ValueError as e:
            exc = e
    return exc


def test_is_terminated_follows_causes_contexts_and_the_flag():
    from bifilar.interrupts import Terminated, is_terminated

    assert is_terminated(Terminated()) and not is_terminated(KeyboardInterrupt())
    assert is_terminated(_chain(5, Terminated())) and not is_terminated(_chain(5, KeyboardInterrupt()))
    try:  # raised *from* a SIGTERM
        raise RuntimeError("wrapped") from Terminated()
    except RuntimeError as e:
        assert is_terminated(e)
    flagged = KeyboardInterrupt()
    flagged.terminated = True  # re-raised under another type, marked
    assert is_terminated(flagged) and is_terminated(_chain(3, flagged))
    a, b = ValueError("a"), ValueError("b")  # a cycle of contexts ends, False
    a.__context__, b.__context__ = b, a
    assert not is_terminated(a)


def test_the_last_stop_signalled_is_the_one_raised_again():
    import signal

    from bifilar import interrupts

    with interrupts.stop_handlers():
        for sig in (signal.SIGINT, signal.SIGTERM):
            with pytest.raises(KeyboardInterrupt):
                interrupts._on_signal(sig, None)
        assert interrupts.stop_requested() is interrupts.Terminated
        with pytest.raises(interrupts.Terminated):
            interrupts.raise_if_stop_requested()
    assert interrupts.stop_requested() is None


def test_stop_handlers_outside_the_main_thread_change_nothing():
    import signal
    import threading

    from bifilar import interrupts

    before = signal.getsignal(signal.SIGINT)
    seen = []

    def run():
        with interrupts.stop_handlers():
            seen.append(signal.getsignal(signal.SIGINT))

    th = threading.Thread(target=run)
    th.start()
    th.join()
    assert seen == [before]


def test_a_bodys_reach_counts_the_negative_axes_too():
    """A box from -0.5 to +0.01 m along each axis: it reaches 0.5 m (along -x, -y, -z).  Its radius
    of gyration 0.9 m is within 2 x 0.5; attachments 1 m out are within 10 x 0.5.  Reading only
    the positive axes (0.2 m with the attachments at y = +-0.2; 0.01 m for the shape alone) would
    flag both."""
    box = ([-0.5] * 3, [0.01] * 3)
    assert _warnings(anchors=((0, -0.2, 0), (0, 0.2, 0)), attachments=((-0.3, -0.2, 0), (-0.3, 0.2, 0)),
                     k=0.9, box=box) == []
    assert _warnings(anchors=((0, -1, 0), (0, 1, 0)), attachments=((0, -1, 0), (0, 1, 0)), k=0.5, box=box) == []


def test_attachments_beyond_the_parts_name_the_parts():
    """One 2 cm cube part (reach 0.01 m) hung from points 0.5 m out: 50 x its reach."""
    part = [{"shape": "box", "mass": 2.0, "size": [0.02, 0.02, 0.02], "position": [0, 0, 0]}]
    w = _warnings(attachments=((0, -0.5, 0), (0, 0.5, 0)), parts=part)
    assert w == ["rig.attachments reach 0.5 m from the centre of mass along a body axis, but the body "
                 "(body.parts) only 0.01 m; are the rig's coordinates in other units (cm, mm)?"]


# ---------------------------------------------------------------------------
# config/fields.py: limits, scales, geometry -- each side of each documented bound
# ---------------------------------------------------------------------------


def _pts(x):
    """Points given as a tuple of tuples as a YAML list of lists; anything else as it is."""
    return [list(a) for a in x] if isinstance(x, tuple) else x


def _errors(anchors=((0, -0.5, 0), (0, 0.5, 0)), attachments=((0, -0.5, 0.1), (0, 0.5, 0.1)),
            lengths=(1.5, 1.5), body=None, **top):
    """(field, message) of every problem scene_from_dict finds in a bifilar-like config."""
    from bifilar.config import scene_from_dict
    from bifilar.errors import InputError

    cfg = {"body": body or {"mass": 2.0, "inertia": {"principal": [0.1, 0.1, 0.2]}},
           "rig": {"anchors": _pts(anchors), "attachments": _pts(attachments), "lengths": list(lengths)}, **top}
    try:
        scene_from_dict(cfg, warn=False)
    except InputError as e:
        return [(x.field, x.message) for x in getattr(e, "errors", [e])]
    return []


def test_wires_differing_over_ten_thousand_fold_are_refused():
    wide = ((0, -2.0, 0), (0, 2.0, 0))
    assert _errors(anchors=wide, lengths=(1.0, 1e4)) == []  # exactly 1e4: accepted
    assert _errors(anchors=wide, lengths=(1.0, 10001.0)) == [
        ("rig.lengths", "wire 2 (10001 m) is more than 10000 times longer than wire 1 (1 m); check the units")]


@pytest.mark.parametrize("key,other", [("anchors", "attachments"), ("attachments", "anchors")])
def test_a_rig_over_ten_thousand_times_its_longest_wire_is_refused(key, other):
    """Wires of 1 mm: points spanning 10 m are within 1e4 x; 12 m are not (the other points 1 mm
    apart; that the wires cannot reach is another error)."""
    def cfg(half):
        pts = {key: ((0, -half, 0), (0, half, 0)), other: ((0, -5e-4, 0), (0, 5e-4, 0))}
        return _errors(lengths=(1e-3, 1e-3), **pts)

    assert not any("times the longest wire" in m for _, m in cfg(5.0))
    assert cfg(6.0)[0] == (f"rig.{key}", "span 12 m, more than 10000 times the longest wire (0.001 m); "
                                         "check the units")


@pytest.mark.parametrize("key", ["anchors", "attachments"])
def test_points_closer_than_a_billionth_of_the_rig_coincide(key):
    """The rig's size here is the 1.5 m wires: 1e-9 x 1.5 m.  1e-9 m apart is one point,
    3e-9 m apart are two."""
    other = "attachments" if key == "anchors" else "anchors"
    far = ((0, -0.5, 0), (0, 0.5, 0))
    for gap, n in ((1e-9, 1), (3e-9, 0)):
        errs = _errors(lengths=(1.5, 1.5), **{key: ((0, 0, 0), (0, gap, 0)), other: far})
        hits = [e for e in errs if "coincides" in e[1]]
        assert len(hits) == n
        if n:
            assert hits[0][0] == f"rig.{key}.1" and hits[0][1].startswith(f"coincides with rig.{key}.0")


@pytest.mark.parametrize("far", ["anchors", "attachments"])
def test_two_wires_must_reach_across_the_farther_pair(far):
    """Points 4 m apart on one side, 1 m on the other: 1.5 + 1.5 + 1 = 4 m just reaches (a straight
    line); 1.4 + 1.5 + 1 = 3.9 m does not, by 0.1 m."""
    near = "attachments" if far == "anchors" else "anchors"
    pts = {far: ((0, -2, 0), (0, 2, 0)), near: ((0, -0.5, 0), (0, 0.5, 0))}
    assert not any("cannot reach" in m for _, m in _errors(lengths=(1.5, 1.5), **pts))
    assert _errors(lengths=(1.4, 1.5), **pts) == [(
        "rig.lengths", f"wires 1 and 2 cannot reach: {far} 1 and 2 are 4 m apart but {near} 1 m apart plus wires "
                       f"1.4 + 1.5 m only span 3.9 m; lengthen them by 0.1 m in total or move the {far} closer")]


def test_three_attachments_on_one_line_are_refused_and_a_millimetre_off_it_is_not():
    anchors = ((-0.5, 0, 0), (0.5, 0, 0), (0, 0.5, 0))
    line = _errors(anchors=anchors, attachments=((-0.5, 0, 0), (0.5, 0, 0), (0, 0, 0)), lengths=(1, 1, 1))
    assert line == [("rig.attachments", "all 3 attachments lie on one line: the body could spin freely about it; "
                                        "move one off the line")]
    assert _errors(anchors=anchors, attachments=((-0.5, 0, 0), (0.5, 0, 0), (0, 1e-3, 0)), lengths=(1, 1, 1)) == []
    # the tolerance is relative to the rig's size: a 1 mm rig with a point 1e-7 m (1e-4 of it)
    # off the line is no line
    small = tuple(tuple(1e-3 * x for x in a) for a in anchors)
    assert _errors(anchors=small, attachments=((-5e-4, 0, 0), (5e-4, 0, 0), (0, 1e-7, 0)),
                   lengths=(1e-3, 1e-3, 1e-3)) == []


@pytest.mark.parametrize("field,value,message", [
    ("gravity", 1e4, None), ("gravity", 1e-3, None),  # the documented bounds themselves
    ("gravity", 1.1e4, "must be at most 10000 m/s^2 in magnitude, got 11000.0"),
    ("gravity", 5e-4, "must be at least 0.001 m/s^2, got 0.0005"),
    ("gravity", 0, "must be positive, got 0"),
    # readers19: a YAML boolean (`yes`) is named as one, not as Python's `bool True`
    ("gravity", True, "must be a number, got a YAML boolean (True: yes/no, on/off and true/false are read so); "
                      "write the number"),
    ("gravity", "9.81", "must be a number, got str '9.81' (a number in quotes is text; remove the quotes)"),
    ("gravity", "fast", "must be a number, got str 'fast'"),
    ("gravity", 10 ** 400, "must be finite, got an integer with 401 digits"),
    ("gravity", float("inf"), "must be finite, got inf"),
])
def test_a_number_is_checked_against_its_documented_limits(field, value, message):
    errs = _errors(**{field: value})
    assert errs == ([] if message is None else [(field, message)])


@pytest.mark.parametrize("length,message", [
    (1e-4, None), (1e5, None), (0.9e-4, "must be at least 0.0001 m, got 9e-05"),
    (1.1e5, "must be at most 100000 m in magnitude, got 110000.0")])
def test_wire_lengths_from_a_tenth_of_a_millimetre_to_a_hundred_kilometres(length, message):
    """Two wires of ``length`` m hung from anchors exactly above their attachments, 2 h apart
    (h = the length, at most 0.5 m: the points have limits of their own)."""
    h = min(length, 0.5)
    a = p = ((0, -h, 0), (0, h, 0))
    errs = _errors(anchors=a, attachments=p, lengths=(length, length))
    assert errs == ([] if message is None else [("rig.lengths.0", message), ("rig.lengths.1", message)])


@pytest.mark.parametrize("mass,message", [
    (1e-6, None), (1e9, None),
    (9e-7, "must be at least 1e-06 kg, got 9e-07"), (2e9, "must be at most 1e+09 kg in magnitude, got 2000000000.0")])
def test_the_mass_limits_are_one_milligram_to_a_megatonne(mass, message):
    k2 = 0.05  # k = 0.22 m: the inertia scales with the mass
    errs = _errors(body={"mass": mass, "inertia": {"principal": [k2 * mass, k2 * mass, 1.5 * k2 * mass]}})
    assert errs == ([] if message is None else [("body.mass", message)])


@pytest.mark.parametrize("key,shown", [
    ("a.b", "'a.b'"), ("with space", "'with space'"), ("x" * 40, "x" * 40),
    ("x" * 41, "'" + "x" * 41 + "'"), ("y" * 58, "'" + "y" * 58 + "'"), ("x" * 70, "'" + "x" * 56 + "...")])
def test_an_unknown_key_is_named_on_one_unambiguous_line(key, shown):
    """Keys with dots, blanks or over 40 characters are quoted; a path element is at most 60
    characters (57 and '...'; 60 are shown whole)."""
    body = {"mass": 2.0, "inertia": {"principal": [0.1, 0.1, 0.2]}, key: 1}
    errs = _errors(body=body)
    assert len(errs) == 1 and errs[0][0] == f"body.{shown}" and errs[0][1].startswith("unknown key")


# ---------------------------------------------------------------------------
# config/inertia.py
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("spec,names", [
    ({"principal": [1.0, 2.0, None]}, ["Izz"]),
    ({"principal": [None, 2.0, 3.0]}, ["Ixx"]),
    ({"tensor": [[1, 0, 0], [0, 2, 0], [0, 0, None]]}, ["Izz"]),
    ({"tensor": [[1, None, 0], [0, 2, 0], [0, 0, 3]]}, ["Ixy"]),  # either entry of a product
    ({"tensor": [[1, 0, 0], [0, 2, 0], [None, 0, 3]]}, ["Ixz"]),
    ({"tensor": [[None, 0, 0], [0, 2, None], [0, 0, 3]]}, ["Ixx", "Iyz"]),
    ({"tensor": [[1, 0], [0, 2]]}, []), ({"principal": "x"}, []), ("x", []),
    ({"principal": [1.0, None]}, ["Iyy"]),  # a short list: its own entries only (refused later)
])
def test_null_components_are_the_ones_marked_null(spec, names):
    from bifilar.config.inertia import null_components

    assert null_components({"body": {"inertia": spec}}) == names
    assert null_components({"body": {}}) == [] and null_components(None) == []


def test_unknown_components_get_placeholders_and_only_invert_accepts_them():
    """An unknown moment starts at the mean of the known ones, an unknown product at 0."""
    from bifilar.config import scene_from_dict

    def cfg(inertia):
        return {"body": {"mass": 2.0, "inertia": inertia},
                "rig": {"anchors": [[0, -0.5, 0], [0, 0.5, 0]], "attachments": [[0, -0.5, 0.1], [0, 0.5, 0.1]],
                        "lengths": [1.5, 1.5]}}

    from bifilar.errors import InputError

    with pytest.raises(InputError) as e:
        scene_from_dict(cfg({"principal": [0.1, None]}), warn=False, unknown=("Iyy",))
    assert (e.value.field, e.value.message) == (
        "body.inertia.principal", "must be a list of 3 numbers (or null for an unknown one), got a list of 2 item(s)")
    s = scene_from_dict(cfg({"principal": [0.1, 0.2, None]}), warn=False, unknown=("Izz",))
    assert s.inertia == pytest.approx(np.diag([0.1, 0.2, 0.15]), abs=1e-15)
    s = scene_from_dict(cfg({"tensor": [[0.1, None, 0.01], [None, 0.2, 0.0], [0.01, 0.0, None]]}), warn=False,
                        unknown=("Ixy", "Izz"))
    assert s.inertia == pytest.approx(np.array([[0.1, 0.0, 0.01], [0.0, 0.2, 0.0], [0.01, 0.0, 0.15]]), abs=1e-15)
    assert _errors(body={"mass": 2.0, "inertia": {"principal": [0.1, 0.2, None]}}) == [
        ("body.inertia", "Izz is null (unknown): only `bifilar invert` accepts an unknown component (it solves for "
                         "it); give its value")]


@pytest.mark.parametrize("inertia,message", [
    ({"principal": [0.1, 0.1, 0.2], "tensor": [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.2]]},
     "give exactly one of 'tensor' (3x3) or 'principal' ([I1, I2, I3]), got tensor and principal"),
    ({}, "give exactly one of 'tensor' (3x3) or 'principal' ([I1, I2, I3]), got neither"),
])
def test_exactly_one_form_of_the_inertia(inertia, message):
    assert _errors(body={"mass": 2.0, "inertia": inertia}) == [("body.inertia", message)]


def test_symmetry_is_checked_to_a_billionth_of_the_largest_entry():
    def tensor(eps):
        return {"mass": 2.0, "inertia": {"tensor": [[0.2, 0.01 + eps, 0], [0.01, 0.2, 0], [0, 0, 0.3]]}}

    assert _errors(body=tensor(0.3 * 0.5e-9)) == []  # 0.5e-9 of the largest entry, 0.3
    assert _errors(body=tensor(0.3 * 2e-9)) == [(
        "body.inertia.tensor", "inertia tensor must be symmetric; row 0, column 1 is 0.01 but row 1, column 0 is 0.01")]


def test_an_asymmetric_tensor_is_one_error_even_when_its_lower_half_is_indefinite():
    """[[0.2, 0.5], [0.4, 0.2]] (and 0.3): not symmetric -- the one problem reported; its lower
    half, [[0.2, 0.4], [0.4, 0.2]], has a moment -0.2, which is no second problem of the input."""
    errs = _errors(body={"mass": 2.0, "inertia": {"tensor": [[0.2, 0.5, 0], [0.4, 0.2, 0], [0, 0, 0.3]]}})
    assert errs == [("body.inertia.tensor",
                     "inertia tensor must be symmetric; row 0, column 1 is 0.5 but row 1, column 0 is 0.4")]


def test_the_radius_of_gyration_must_lie_between_a_micrometre_and_a_hundred_kilometres():
    """1 kg with moments 1e-13 .. 1.5e-13 kg m^2: k = sqrt(1e-13) = 3.16e-7 m < 1e-6 m;
    4e-13 .. 6e-13 (k >= 6.3e-7) still, 1e-12 .. 1.5e-12 (k >= 1e-6) accepted."""
    def body(s):
        return {"mass": 1.0, "inertia": {"principal": [s, s, 1.5 * s]}}

    assert _errors(body=body(1e-13)) == [(
        "body.inertia", "radius of gyration sqrt(I/m) = 3.16e-07 m is outside 1e-06 .. 100000 m (principal moments "
                        "[1e-13, 1e-13, 1.5e-13] kg m^2, mass 1 kg): are the units kg and m?")]
    assert len(_errors(body=body(4e-13))) == 1
    assert _errors(body=body(1.0001e-12)) == []
    # the upper bound: k_max = sqrt(1.5 I / m) > 1e5 m
    assert _errors(body=body(6e9)) == []  # k_max = 9.5e4 m
    assert "radius of gyration sqrt(I/m) = 1.22e+05 m" in _errors(body=body(1e10))[0][1]


@pytest.mark.parametrize("value,message", [
    ([], "must be a non-empty list of [x, y, z] points, got a list of 0 item(s)"),
    ("ab", "must be a non-empty list of [x, y, z] points, got str 'ab'"),
    ([[0, 0, 0]] * 101, "must list one [x, y, z] point per wire (at most 5), got 101 items"),
])
def test_the_points_must_be_a_list_of_points(value, message):
    errs = _errors(anchors=value)
    assert ("rig.anchors", message) in errs


@pytest.mark.parametrize("wide,close", [("anchors", "attachments"), ("attachments", "anchors")])
def test_the_coincidence_tolerance_scales_with_the_rigs_largest_extent(wide, close):
    """One pair of points 20 m apart along x (the rig's size; wires 10.5 m): the other pair 1.5e-8 m
    apart is within 1e-9 x 20 m, one point; 3e-8 m apart, two."""
    for gap, n in ((1.5e-8, 1), (3e-8, 0)):
        errs = _errors(lengths=(10.5, 10.5), **{wide: ((-10, 0, 0), (10, 0, 0)), close: ((0, 0, 0), (gap, 0, 0))})
        assert len([e for e in errs if e[0] == f"rig.{close}.1" and "coincides" in e[1]]) == n


def test_the_default_stopwatch_is_the_hand_timed_trial_invert_assumes():
    """0.1 s a trial (module docstring), the same as invert's default trial-time sigma."""
    from bifilar.estimation.uncertainty import DEFAULT_TRIAL_TIME_SIGMA
    from bifilar.studies.timing import advice

    row = advice(2.0, None, 0.005)
    assert row["stopwatch"]["reaction_sigma"] == DEFAULT_TRIAL_TIME_SIGMA == 0.1
    assert row["stopwatch"]["trials"] == 4  # (0.1 / 10 / 0.005)^2


@pytest.mark.parametrize("inertia,unknown,field,message", [
    ({"principal": [0.1, -0.2, None]}, ("Izz",), "body.inertia.principal.1", "must be positive, got -0.2"),
    ({"tensor": [[0.1, 0, 0], [0, -0.2, 0], [0, 0, None]]}, ("Izz",), "body.inertia.tensor.1.1",
     "must be positive, got -0.2"),
    ({"tensor": [[0.1, "a", 0], [0.0, 0.2, 0], [0, 0, None]]}, ("Izz",), "body.inertia.tensor.0.1",
     "must be a number, got str 'a'"),
])
def test_a_bad_known_component_beside_an_unknown_is_named_by_its_path(inertia, unknown, field, message):
    """Known moments must be positive numbers, known products numbers (either sign)."""
    from bifilar.config import scene_from_dict
    from bifilar.errors import InputError

    cfg = {"body": {"mass": 2.0, "inertia": inertia},
           "rig": {"anchors": [[0, -0.5, 0], [0, 0.5, 0]], "attachments": [[0, -0.5, 0.1], [0, 0.5, 0.1]],
                   "lengths": [1.5, 1.5]}}
    with pytest.raises(InputError) as e:
        scene_from_dict(cfg, warn=False, unknown=unknown)
    # that one problem alone (no follow-up error about a tensor built with a placeholder for it)
    assert [(x.field, x.message) for x in getattr(e.value, "errors", [e.value])] == [(field, message)]
    cfg["body"]["inertia"] = {"tensor": [[0.1, -0.01, 0], [-0.01, 0.2, 0], [0, 0, None]]}  # a negative product
    assert scene_from_dict(cfg, warn=False, unknown=unknown).inertia[0, 1] == -0.01
