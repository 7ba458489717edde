"""Mutation round 13 (docs/mutation.md, "Round 13"): tests that fail on a
mutant of session 12's code that the suite let through.  Each states the
truth it checks (an analytic result, an independent formulation, or the
documented rule on an input built for it); none reads its expected value
off the code under test.
"""

from __future__ import annotations

import dataclasses
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

# ---------------------------------------------------------------------------
# models/maximal.py: _inline_single_use
# ---------------------------------------------------------------------------


def test_a_temporary_is_inlined_when_its_operand_is_reassigned_only_after_its_use():
    """``a = x*y`` read once by ``b``, and ``x`` assigned again in the
    statement right after ``b``: ``x*y`` moved into ``b`` still reads the
    old ``x``, as the source did, so the pass moves it (``untouched``'s
    ``i < k < j`` with ``j`` one past the last use; ``k <= j`` kept it, a
    lost inlining the bit-identity tests cannot see).  ``b`` then reads
    ``x`` and the output reads ``b`` after ``x = 1.0``: ``b`` stays
    (the expected source written by hand)."""
    from bifilar.models import maximal as mx

    body, out = mx._inline_single_use(["a = x*y", "b = a*2.0", "x = 1.0"], ["b", "x"])
    assert body == ["b = (x*y)*2.0", "x = 1.0"] and out == ["b", "x"]


# ---------------------------------------------------------------------------
# estimation/signal_swing.py: record_tones
# ---------------------------------------------------------------------------


def _fit(amps, omegas, stds=None, n=1000, noise=1e-4, inflation=1.5, span=30.0):
    modes = [{"amplitude": a, "omega": w, **({} if stds is None else {"std": s})}
             for a, w, s in zip(amps, omegas, stds or [None] * len(amps))]
    return SimpleNamespace(modes=modes, n_samples=n, noise_std=noise, std_inflation=inflation, t0=1.0, t1=1.0 + span)


def test_a_records_tones_are_angle_ratios_above_five_stds_with_two_cycles():
    """``record_tones`` by hand on a fit built for it: the std of a fitted
    sinusoid's amplitude in white noise is ``noise sqrt(2 / N)`` (least
    squares of a sine on N samples), times the fit's serial inflation
    (1.5 here); a tone is kept above 5 of those and with two cycles in the
    30 s record (``omega T >= 4 pi``), strongest first.  A rate record of
    the same motion (theta = sum a_i sin(w_i t): the rate's amplitudes are
    a_i w_i) gives the same angle-equivalent ratios a_i / a0, its std
    scaled alike; read as an angle record it would be w_i / w0 off."""
    from bifilar.estimation.signal_swing import record_tones

    a = [0.1, 3e-3, 6e-4, 1e-5, 5e-3]  # rad: the dominant, two tones, one under 5 std, one too slow
    w = [3.1, 2.45, -4.0, 2.0, 0.3]  # rad/s (a fit may return a negative omega); 0.3 x 30 s < 4 pi
    s_amp = 1e-4 * math.sqrt(2.0 / 1000) * 1.5  # 6.7e-6: the 1e-5 tone is 1.5 of it
    want = [{"period": 2 * math.pi / 2.45, "ratio": 3e-3 / 0.1}, {"period": 2 * math.pi / 4.0, "ratio": 6e-4 / 0.1}]
    angle = SimpleNamespace(fit=_fit(a, w, stds=[0.0, 2e-3, 4e-3, 0.0, 0.0]), details={"quantity": "angle"})
    rate = SimpleNamespace(fit=_fit([ai * abs(wi) for ai, wi in zip(a, w)], w), details={"quantity": "rate"})
    got_a, got_r = record_tones(angle), record_tones(rate)
    assert len(got_a) == len(got_r) == 2
    for g, wt in zip(got_a, want):
        assert g["period"] == pytest.approx(wt["period"], rel=1e-14)
        assert g["ratio"] == pytest.approx(wt["ratio"], rel=1e-14)
        assert g["ratio_std"] == pytest.approx(s_amp / 0.1, rel=1e-14)
    assert [g["period_std"] for g in got_a] == [2e-3, 4e-3]
    for g, wt, wi in zip(got_r, want, (2.45, 4.0)):
        assert g["ratio"] == pytest.approx(wt["ratio"], rel=1e-14)  # angle-equivalent
        assert g["ratio_std"] == pytest.approx(1e-4 * math.sqrt(2.0 / 1000) * 1.5 / (0.1 * 3.1) * 3.1 / wi, rel=1e-14)
    # an unstated serial factor counts as 1; no fit, or a fit of one mode, has no tones
    one = SimpleNamespace(fit=_fit(a, w, inflation=None), details={})
    assert record_tones(one)[0]["ratio_std"] == pytest.approx(1e-4 * math.sqrt(2.0 / 1000) / 0.1, rel=1e-14)
    assert record_tones(SimpleNamespace(fit=None, details={})) == []
    assert record_tones(SimpleNamespace(fit=SimpleNamespace(modes=None), details={})) == []


# ---------------------------------------------------------------------------
# analysis/clearance.py
# ---------------------------------------------------------------------------


def _rig(anchors, attachments, lengths, box_top=None):
    from bifilar.config import scene_from_dict

    body = {"mass": 2.0, "inertia": {"principal": [0.05, 0.06, 0.08]}}
    if box_top is not None:
        body["bounding_box"] = {"min": [-0.1, -0.1, -0.1], "max": [0.1, 0.1, box_top]}
    return scene_from_dict({"gravity": 9.81, "body": body,
                            "rig": {"anchors": anchors, "attachments": attachments, "lengths": lengths}}, warn=False)


@pytest.mark.parametrize("L", [0.5, 2.0])
def test_the_ceiling_tolerance_is_a_share_of_the_longest_wire(L):
    """The documented rule: the body at rest may reach ``CEILING_TOL`` times
    the longest wire above the highest anchor (the rest pose's rounding)
    before the warning.  A box whose top lies 0.5 and 1.5 of that above
    the ceiling (the pose given: the CoM on the ceiling's level minus the
    box's reach, level), on wires of 0.5 and 2 m: silent, then warned
    (``+ -> -`` on the ceiling warned a box that only touches it; ``* -> /``
    put the 2 m rig's allowance at a quarter of the stated one, 0.5 m's at
    four times)."""
    from bifilar.analysis.clearance import CEILING_TOL, ceiling_warning

    sc = _rig([[-0.2, 0, L], [0.2, 0, L]], [[-0.2, 0, 0.0], [0.2, 0, 0.0]], [L, L], box_top=0.25)
    tol = CEILING_TOL * L
    for share, warned in ((0.0, False), (0.5, False), (1.5, True)):
        rest = SimpleNamespace(com=np.array([0.0, 0.0, L - 0.25 + share * tol]), R=np.eye(3))
        w = ceiling_warning(sc, rest)
        assert (w is not None) == warned, (share, w)


def _x_rig(a=0.3, b=0.2, H=1.0, L=1.0, dy=0.0, shared=None):
    """Four wires of length L: on each side y = +-b two wires from x = -+a at
    the ceiling (z = H) to x = +-a on the body, crossing in an X; wire 2
    moved by ``dy`` in y at both ends (parallel planes ``dy`` apart).  The
    pose is given: level, the CoM under the centre at the wires' drop
    h = sqrt(L^2 - 4 a^2) (each spans 2a).  ``shared``: wire 2 vertical, 0.5 mm
    outside wire 1's anchor (``"anchor"``) or attachment (``"attachment"``)
    (a common end is refused by the config), so the two come closest at
    that end and spread from it."""
    anchors = [[-a, b, H], [a, b + dy, H], [-a, -b, H], [a, -b, H]]
    att = [[a, b, 0.0], [-a, b + dy, 0.0], [a, -b, 0.0], [-a, -b, 0.0]]
    h = math.sqrt(L * L - 4 * a * a)
    if shared == "anchor":
        anchors[1] = [-a - 5e-4, b, H]
        att[1] = [-a - 5e-4, b, 0.0]
    elif shared == "attachment":
        att[1] = [a + 5e-4, b, 0.0]
        anchors[1] = [a + 5e-4, b, H]
    lengths = [L] * 4
    if shared:  # wire 2 vertical
        lengths[1] = h
    return _rig(anchors, att, lengths), SimpleNamespace(com=np.array([0.0, 0.0, H - h]), R=np.eye(3)), H - h / 2


def test_crossing_wires_are_named_with_where_they_meet():
    """Two X's of wires (1-2 and 3-4), each pair meeting at the middle of
    its wires by symmetry, z = H - h/2 = 0.6 m (h = 0.8 m): both pairs
    named, 'meeting' (closer than 1e-6 m), at that height.  Wire 2 moved
    0.5 mm sideways (parallel planes): '0.5 mm apart' at the same height;
    1.5 mm: beyond the 1 mm contact distance, only 3-4 named.  Wires that
    come closest at an end (anchors or attachment points 0.5 mm apart, the
    wires spreading from there: s = 0 or 1) are not a crossing: not named."""
    from bifilar.analysis.clearance import crossing_warning

    sc, rest, zc = _x_rig()
    assert zc == pytest.approx(0.6, abs=1e-15)
    w = crossing_warning(sc, rest)
    assert w is not None and "wires 1 and 2 (meeting at z = 0.6 m)" in w and "wires 3 and 4 (meeting at z = 0.6 m)" in w
    assert len(re.findall(r"wires \d and \d", w)) == 2 and "(meeting at z = 0.6 m) cross: " in w, w
    sc, rest, _ = _x_rig(dy=5e-4)
    w = crossing_warning(sc, rest)
    assert "wires 1 and 2 (0.5 mm apart at z = 0.6 m)" in w and "wires 3 and 4 (meeting" in w, w
    sc, rest, _ = _x_rig(dy=1.5e-3)
    w = crossing_warning(sc, rest)
    assert "wires 1 and 2" not in w and "wires 3 and 4 (meeting" in w, w
    for end in ("anchor", "attachment"):
        sc, rest, _ = _x_rig(shared=end)
        w = crossing_warning(sc, rest)
        assert "wires 1 and 2" not in w and "wires 3 and 4 (meeting" in w, (end, w)


def test_wires_side_by_side_along_their_length_are_named():
    """A fourth wire hung 0.5 mm beside wire 1, parallel (a doubled wire),
    and once attached 0.1 mm higher on the body (1e-4 shorter: the ends' gaps are
    0.5 mm and ~0.51 mm at the rest pose, the segments skew): the two touch
    along their whole length (the distance between points at the same
    share of each is linear in the share, so at most its ends' 0.5 mm).
    Their closest points lay at an end (s = 0 for exactly parallel
    segments, clipped to an end for the skew pair) and the check, which
    leaves out wires closest at an end, said nothing; now named, with the
    distance.  The pair at 1.5 mm stays silent."""
    from bifilar.analysis.clearance import clearance_warnings

    a, b = 0.3, 0.2
    for dx, dz, named in ((5e-4, 0.0, True), (5e-4, 1e-4, True), (1.5e-3, 0.0, False)):
        sc = _rig([[-a, b, 1.0], [a, b, 1.0], [0.0, -b, 1.0], [-a + dx, b, 1.0]],
                  [[-a, b, 0.0], [a, b, 0.0], [0.0, -b, 0.0], [-a + dx, b, dz]], [1.0, 1.0, 1.0, 1.0 - dz])
        w = clearance_warnings(sc)
        if named:
            assert len(w) == 1 and re.search(r"wires 1 and 4 \(side by side, at most 0\.5\d? mm apart along their whole "
                                            r"length\)", w[0]) and " touch or cross: " in w[0], w
        else:
            assert w == [], w


def test_segment_distance_of_parallel_segments_and_beyond_an_end():
    """Two cases the random draws of test_forward_audit12 did not reach:
    exactly parallel segments (a e - b^2 = 0 in floating point: two
    vertical 1 m segments 1 m apart, distance 1: the branch that starts
    from an end), and lines whose closest points lie beyond the first
    segment's end (the x axis' 0 .. 1 against a segment along y at x = 2,
    z = 1: the lines meet their closest at s = 2; the segments' closest
    points are p1 = (1, 0, 0) and (2, 0, 1), sqrt 2 apart; an unclipped
    s = 2 gave 1; in the other order t = 2, and an unclipped t gave 1)."""
    from bifilar.analysis.clearance import segment_distance

    d, s, t = segment_distance([0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 1])
    assert d == pytest.approx(1.0, abs=1e-15) and 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
    d, s, t = segment_distance([0, 0, 0], [1, 0, 0], [2, -1, 1], [2, 1, 1])
    assert d == pytest.approx(math.sqrt(2.0), abs=1e-15) and s == 1.0 and t == pytest.approx(0.5, abs=1e-15)
    # the same pair in the other order: now the second line's closest point lies beyond its end (t = 2)
    d, s, t = segment_distance([2, -1, 1], [2, 1, 1], [0, 0, 0], [1, 0, 0])
    assert d == pytest.approx(math.sqrt(2.0), abs=1e-15) and t == 1.0 and s == pytest.approx(0.5, abs=1e-15)


# ---------------------------------------------------------------------------
# studies/point.py: statics_range
# ---------------------------------------------------------------------------


def test_the_range_peak_is_each_wires_greatest_share_of_the_peak_wrench_by_hand():
    """rankfix's rule (session 13; it replaced the per-wire ratio this test
    first pinned) on a split built for it: the table of four equal vertical
    wires at the rectangle's corners (each 0 .. m g / 2 at rest by statics,
    test_tension_range_limit), the model's split m g / 4 on wires 1-3 and
    1e-7 m g on wire 4, the runs' peaks 1.1, 1.2, 1.05 and 50 times those.
    By hand: the corners' one self-stress is N = (1, -1, 1, -1) (sum,
    x- and y-moments zero), so a split of the peaks' wrench is T + t N with
    every entry >= 0, and wire k's greatest share is T_k plus the least
    peak among the two wires of the other sign: wire 2's 0.3 + 0.2625 =
    0.5625 m g is the largest (above the rest's m g / 2).  With every peak
    tiny each share is tiny and the rest's top m g / 2 stands."""
    import dataclasses

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.studies.point import statics_range

    from test_dependent_wires_messages import CORNERS, scene_of, vertical

    sc = scene_of(vertical(CORNERS, [1.0] * 4))
    mg = sc.mass * sc.gravity
    rest = rest_pose(sc)
    T0 = np.array([mg / 4] * 3 + [1e-7 * mg])
    peak = T0 * [1.1, 1.2, 1.05, 50.0]
    got = statics_range(sc, dataclasses.replace(rest, tensions=T0), peak)
    assert np.allclose(got["range"], [[0.0, mg / 2]] * 4, rtol=1e-9, atol=1e-9 * mg)
    N = np.array([1, -1, 1, -1])
    by_hand = [peak[k] + min(peak[j] for j in range(4) if N[j] == -N[k]) for k in range(4)]
    assert by_hand[1] == pytest.approx(0.5625 * mg)
    assert got["range_peak"] == pytest.approx(max(max(by_hand), mg / 2), rel=1e-9) and got["range_peak_wire"] == 2
    tiny = np.full(4, 1e-7 * mg)
    got = statics_range(sc, dataclasses.replace(rest, tensions=tiny), tiny * 3.0)
    assert got["range_peak"] == pytest.approx(mg / 2, rel=1e-9)


# ---------------------------------------------------------------------------
# analysis/simulate.py: two_mode_state
# ---------------------------------------------------------------------------


def test_a_second_mode_without_stiffness_or_amplitude_starts_nothing():
    """A neutral mode (``period`` None: zero stiffness) has no oscillation
    whose velocity at rest the release could give, and an amplitude 0
    gives none: the start is :func:`initial_state`'s, the first mode held
    at its amplitude with zero velocity (``or -> and`` divided by the
    neutral mode's missing period)."""
    import dataclasses

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import initial_state, two_mode_state

    from test_forward_audit12 import bifilar

    sc = bifilar(1.2, [0.012, 0.013, 0.022], 0.15, 0.15, 0.03, 1.2, anchor_z=1.23)
    rest = rest_pose(sc)
    ms = linear_modes(sc, rest)
    tor, sw = ms.get("torsion"), ms.get("swing-y")
    y_ref = initial_state(sc, rest, tor, 0.1)
    assert np.array_equal(two_mode_state(sc, rest, tor, 0.1, dataclasses.replace(sw, period=None), 0.03), y_ref)
    assert np.array_equal(two_mode_state(sc, rest, tor, 0.1, sw, 0.0), y_ref)
    assert not np.array_equal(two_mode_state(sc, rest, tor, 0.1, sw, 0.03), y_ref)


# ---------------------------------------------------------------------------
# analysis/run_accuracy.py: the crossings' part of period_accuracy
# ---------------------------------------------------------------------------


def test_a_crossing_error_that_could_not_be_estimated_leaves_the_bound_unknown():
    """``crossing`` NaN (too few samples, a crossing the samples do not
    show: crossing_period_error) leaves the bound not established (NaN;
    simhealth, session 13: it counted as 0 before, a bound stated without
    its crossings' part), and a finite crossing part adds to it as is (1e-9
    s on top of the 1e-8-relative run's bound; ``else 0.0 -> 1`` put a
    whole second on every NaN)."""
    from bifilar.analysis.run_accuracy import period_accuracy

    base, _ = period_accuracy(2.0, "LSODA", 1e-9)
    assert np.isfinite(base)
    assert np.isnan(period_accuracy(2.0, "LSODA", 1e-9, crossing=float("nan"))[0])
    assert period_accuracy(2.0, "LSODA", 1e-9, crossing=1e-9)[0] == pytest.approx(base + 1e-9, rel=1e-12)


# ---------------------------------------------------------------------------
# studies/hangings_inputs.py: is_swing
# ---------------------------------------------------------------------------


def test_a_swing_is_told_by_its_kinetic_energy_not_by_its_largest_entry():
    """The quadcopter-like bifilar (CoM 3 cm below the wires' attachment
    line): its swing-y's largest shape entry is the roll (a rotation, the
    amplitude's unit rad) while its kinetic energy is mostly y translation,
    a swing; its roll's is mostly rotation about x (index 3), no swing
    (``< 3 -> <= 3`` took the roll for a swing, whose dr/dx then has no
    bound)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.studies.hangings_inputs import is_swing

    from test_forward_audit12 import bifilar

    sc = bifilar(1.2, [0.012, 0.013, 0.022], 0.15, 0.15, 0.03, 1.2, anchor_z=1.23)
    ms = linear_modes(sc, rest_pose(sc))
    got = {m.label: is_swing(m) for m in ms.modes}
    assert got == {"swing-x": True, "swing-y": True, "torsion": False, "roll": False}
    sy = ms.get("swing-y")
    assert sy.dominant >= 3 and float(np.sum(sy.energy_share[:3])) > 0.5  # the case the rule is for


def test_the_joint_fits_input_columns_are_each_hangings_own_block_then_the_shared_ones():
    """``keyed`` on maps built for it: hangings 0 and 2 of three candidates
    used (rows (0, 0), (0, 1), (2, 0)), each with its own inputs (2 and 1
    columns) and 2 shared ones.  The layout written by hand: a
    block-diagonal of ``raw @ M_own`` per hanging, the shared columns
    ``raw @ M_sh`` summed in the last two, and with ``absolute`` the maps'
    absolute values (a bound).  A block shifted by a row or a column (the
    offsets' ``0 -> 1``) moves an input's term onto another period or input."""
    from bifilar.studies.hangings_inputs import keyed

    rng = np.random.default_rng(13)
    maps = [(["a", "b", "c"], rng.normal(size=(3, 2)), rng.normal(size=(3, 2))),
            (["a"], rng.normal(size=(1, 4)), rng.normal(size=(1, 2))),
            (["a", "d"], rng.normal(size=(2, 1)), rng.normal(size=(2, 2)))]
    raw = {0: rng.normal(size=(2, 3)), 2: rng.normal(size=(1, 2))}
    rows = [(0, 0), (0, 1), (2, 0)]
    for absolute, f in ((False, lambda M: M), (True, np.abs)):
        want = np.block([[raw[0] @ f(maps[0][1]), np.zeros((2, 1)), raw[0] @ f(maps[0][2])],
                         [np.zeros((1, 2)), raw[2] @ f(maps[2][1]), raw[2] @ f(maps[2][2])]])
        got = keyed(maps, rows, raw, absolute=absolute)
        assert got.shape == (3, 5) and np.allclose(got, want, rtol=1e-14, atol=1e-14), (absolute, got - want)


# ---------------------------------------------------------------------------
# studies/ranking.py: tension_range_caution
# ---------------------------------------------------------------------------


def test_the_caution_quotes_the_range_of_the_wire_that_reaches_the_top():
    """A point built for it: four dependent wires with distinct statics
    ranges at rest (0 .. 10, 1 .. 20, 2 .. 30, 3 .. 40 N), the model's
    split peaking at 30 N, the range's peak 45 N on wire 2 in the runs,
    the limit 35 N between them: the caution names wire 2 and its own rest
    range, 1 .. 20 N (the symmetric table of test_tension_range_limit has
    one range for every wire, so a neighbour's was quoted unseen)."""
    from bifilar.studies.ranking import tension_range_caution
    from bifilar.studies.settings import Constraints

    point = {"tension": {"peak": 30.0, "range_peak": 45.0, "range_peak_wire": 2,
                         "range": np.array([[0.0, 10.0], [1.0, 20.0], [2.0, 30.0], [3.0, 40.0]])}}
    w = tension_range_caution(point, Constraints(max_tension=35.0))
    assert "wire 2 may carry 1 .. 20 N at rest and up to 45 N in the runs" in w, w


def _harmonic_record():
    """sin t + 0.2 sin(7 t + 0.3) on 23.7 samples per fundamental period
    (~3.4 per cycle of the harmonic), its upward crossings located on the
    samples, and the true ones by brentq on the function itself."""
    from scipy.optimize import brentq

    from bifilar import integrators as itg

    def sig(t):
        return np.sin(t) + 0.2 * np.sin(7 * t + 0.3)

    dt = 2 * np.pi / 23.7  # not a whole number per period: the crossings' errors differ (they would cancel)
    t = 0.7 + np.arange(0, 40, dt)  # not from 0: the spacing is t[1] - t[0]
    c = sig(t)
    _, tx, k = itg.sampled_crossings(c[:, None], dt)
    tx = tx + t[0]  # (times from the first sample)
    true = np.array([brentq(sig, t[j], t[j + 1], xtol=1e-15) for j in k])
    return t, c, tx, true


def test_the_mean_periods_crossing_error_covers_the_true_one():
    """crossing_period_error against the analytic signal: the mean period
    (last - first crossing over the cycles between) from the sampled
    crossings is off the true crossings' by at most the two end crossings'
    errors over the cycles; the estimate covers that and is no looser than
    50x the end crossings' true errors (each estimate is 2-4x its own
    error, test_forward_audit12).  Fewer than two crossings: 0 (no mean
    period); fewer than 9 samples: NaN (no stencil); a crossing the samples
    do not show (placed where the signal falls): NaN."""
    from bifilar.analysis.run_accuracy import crossing_period_error

    t, c, tx, true = _harmonic_record()
    n = len(tx) - 1
    err_mean = abs((tx[-1] - tx[0]) - (true[-1] - true[0])) / n
    ends = (abs(tx[0] - true[0]) + abs(tx[-1] - true[-1])) / n
    est = crossing_period_error(t, c, tx)
    assert n >= 5 and 0 < ends and err_mean <= est <= 50 * ends + 1e-13, (err_mean, ends, est)
    # the estimate is per cycle: the same end crossings over fewer cycles between them
    sub = np.r_[tx[0], tx[1:-1][:1], tx[-1]]
    assert crossing_period_error(t, c, sub) == pytest.approx(est * n / 2, rel=1e-12)
    assert crossing_period_error(t, c, tx[[0, -1]]) == pytest.approx(est * n, rel=1e-12)  # two: one period
    assert crossing_period_error(t, c, tx[:1]) == 0.0
    # 9 samples are the fewest with a stencil of 8 and one shifted: a value (two crossings of a sine at 4.4
    # samples a period); 8: NaN
    from bifilar import integrators as itg

    t9 = 3.0 + np.arange(9.0)
    c9 = np.sin(2 * np.pi * (t9 - 3.3) / 4.4)
    _, x9, k9 = itg.sampled_crossings(c9[:, None], 1.0)
    assert len(x9) == 2 and k9[0] == 0  # the first crossing between samples 0 and 1: its stencils shift right only
    assert np.all(np.isfinite(itg.crossing_interpolation_error(c9, k9, 1.0)))
    assert np.isfinite(crossing_period_error(t9, c9, x9 + t9[0]))
    assert math.isnan(crossing_period_error(t[:8], c[:8], tx[:2]))
    down = t[int(np.argmax(np.diff(np.sign(c)) < 0))]  # a sample just before a downward crossing
    assert math.isnan(crossing_period_error(t, c, np.r_[tx[0], down]))


# ---------------------------------------------------------------------------
# scene.py: the body's lowest and highest points
# ---------------------------------------------------------------------------


def test_lowest_and_highest_points_of_a_box_by_hand():
    """A box from (-0.1, -0.1, -0.1) to (0.1, 0.1, 0.25) m in body axes with
    its CoM at z = 0.5 m: level, it reaches from 0.4 to 0.75 m; turned by 90
    degrees about x (body y up), from 0.4 to 0.6 m.  Without a shape the
    body reaches at least its CoM and its attachments (z 0 in body axes):
    both at 0.5 m level.  (The tests before checked inequalities only:
    ``lowest_point_z``'s sign scaled to -2 put the lowest point 4 h below
    the CoM, the support function being positively homogeneous.)"""
    from bifilar.scene import highest_point_z, lowest_point_z

    sc = _rig([[-0.2, 0, 1.0], [0.2, 0, 1.0]], [[-0.2, 0, 0.0], [0.2, 0, 0.0]], [0.5, 0.5], box_top=0.25)
    com = np.array([0.0, 0.0, 0.5])
    Rx = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # body y -> world z
    assert float(lowest_point_z(sc, com, np.eye(3))) == pytest.approx(0.4, abs=1e-15)
    assert float(highest_point_z(sc, com, np.eye(3))) == pytest.approx(0.75, abs=1e-15)
    assert float(lowest_point_z(sc, com, Rx)) == pytest.approx(0.4, abs=1e-15)
    assert float(highest_point_z(sc, com, Rx)) == pytest.approx(0.6, abs=1e-15)
    bare = _rig([[-0.2, 0, 1.0], [0.2, 0, 1.0]], [[-0.2, 0, 0.0], [0.2, 0, 0.0]], [0.5, 0.5])
    assert float(lowest_point_z(bare, com, np.eye(3))) == pytest.approx(0.5, abs=1e-15)
    assert float(highest_point_z(bare, com, np.eye(3))) == pytest.approx(0.5, abs=1e-15)


# ---------------------------------------------------------------------------
# studies/hangings.py: gravity_column
# ---------------------------------------------------------------------------


def test_gs_column_is_the_periods_derivative_in_g_times_its_std():
    """g's column against central differences of the linear periods over g
    (the rest pose and modes of the same rig at g (1 +- 1e-5)): each period
    falls as g^-1/2, so dT/dg s_g < 0 (the column's sign dropped passed:
    one column's sign does not change a sigma, but it is the derivative's);
    none stated (``--sigma gravity=0``): no column."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.studies.hangings import gravity_column

    def periods(g):
        sc = _rig([[-0.2, 0, 1.0], [0.2, 0, 1.0]], [[-0.15, 0, 0.05], [0.15, 0, 0.05]], [1.0, 1.0])
        sc = dataclasses.replace(sc, gravity=g)
        return sc, np.array([m.period for m in linear_modes(sc, rest_pose(sc)).modes])

    g, eps = 9.81, 1e-5
    sc, T = periods(g)
    dT = (periods(g * (1 + eps))[1] - periods(g * (1 - eps))[1]) / (2 * eps * g)
    h = SimpleNamespace(scene=sc, sens=SimpleNamespace(periods=T))
    col = gravity_column(h, {"gravity": 0.003})
    assert col.shape == (len(T), 1) and np.all(col < 0)
    # central differences: truncation ~eps^2, rounding ~1e-16 / eps of T: 1e-9 relative is ample
    assert np.allclose(col[:, 0], dT * 0.003 * g, rtol=1e-8, atol=0)
    assert gravity_column(h, {"gravity": 0.0}).shape == (len(T), 0)
