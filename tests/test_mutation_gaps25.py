"""Mutation round 25 (docs/mutation.md, "Round 25"): tests that kill the
surviving mutants of session 24's new code (sigma24's rest poses from the
base pose, readers24's cycle count and parameter layout, audit24's shares,
binding message and elastic statics).  Every expected value is worked out
by hand or by an independent formulation, never taken from the code under
test; each test's docstring names the mutants it kills."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from test_sigma_rest import _counting, _ring

DATA = Path(__file__).parent / "data" / "audit24"


# ---------------------------------------------------------------------------
# sensitivity.grouped_shares: the second-order group (audit24)
# ---------------------------------------------------------------------------

def _budget():
    """A hand-made linear budget: contributions 3 (timing) and 4 (length.1)
    kg m^2, so its variance is 25 and its shares 9/25 and 16/25."""
    from bifilar.estimation.sensitivity import Budget

    return Budget("Izz", "torsion", 5.0, {"timing": 3.0, "length.1": 4.0},
                  {"timing": 9 / 25, "length.1": 16 / 25}, 1.0, 2.0)


PLAIN = {"timing": 9 / 25, "lengths": 16 / 25}


@pytest.mark.parametrize("sigma", [None, math.nan, math.inf, -1.0, 0.0])
def test_grouped_shares_without_a_usable_sigma_are_the_linear_ones(sigma):
    """No sigma, or one that is not a positive finite std: the linear shares
    grouped, no ``second_order`` (kills the guard's ``or -> and`` twice: a
    nan or inf sigma then scaled every share to nan or 0)."""
    from bifilar.estimation.sensitivity import grouped_shares

    assert grouped_shares(_budget(), sigma) == pytest.approx(PLAIN, abs=1e-15)


@pytest.mark.parametrize("ratio2, second", [
    (1.0201, False),     # sigma 1 % above the linear std: within LINEAR_ENOUGH (kills + -> -, lin * -> /)
    (1.05, True),        # 2.47 % above: between (1.02)^2 and (1.02)^3 (kills ** 2 -> ** 3)
    (1.21, True),        # 10 % above: below 2 x 1.02 (kills ** -> *)
    (4.0, True),         # twice the linear std (kills sigma * sigma -> sigma / sigma)
])
def test_grouped_shares_split_off_the_second_order_part_beyond_two_percent(ratio2, second):
    """sigma^2 = ratio2 x the linear variance 25: where sigma exceeds the
    linear std by more than LINEAR_ENOUGH = 2 % (sigma^2 > 1.0404 x 25) the
    linear shares are scaled by 25 / sigma^2 and ``second_order`` is
    1 - 25 / sigma^2; else the linear shares as they are.  The same with the
    linear variance passed (``linear_var``) instead of the contributions'."""
    from bifilar.estimation.sensitivity import Budget, grouped_shares

    sigma = math.sqrt(25.0 * ratio2)
    part = 1.0 / ratio2
    want = {"timing": 9 / 25 * part, "lengths": 16 / 25 * part, "second_order": 1.0 - part} if second else PLAIN
    assert grouped_shares(_budget(), sigma) == pytest.approx(want, rel=1e-12, abs=1e-15)
    b = _budget()
    no_terms = Budget(b.component, b.mode, b.value_sigma, {}, b.shares, b.dI_dT, b.rel_sensitivity)
    assert grouped_shares(no_terms, sigma, 25.0) == pytest.approx(want, rel=1e-12, abs=1e-15)


def test_grouped_shares_at_exactly_two_percent_are_the_linear_ones():
    """sigma exactly (1 + LINEAR_ENOUGH) x the linear std 1 (sigma^2 and
    (1.02)^2 are the same double): not *more* than 2 %, so the linear shares
    (kills the threshold's ``<= -> <``)."""
    from bifilar.estimation.second_order import LINEAR_ENOUGH
    from bifilar.estimation.sensitivity import grouped_shares

    assert LINEAR_ENOUGH == 0.02
    assert grouped_shares(_budget(), 1.0 + 0.02, 1.0) == pytest.approx(PLAIN, abs=1e-15)


def test_a_stated_amplitudes_shares_carry_the_small_amplitude_second_order_excess():
    """Row S13 of audit24 (a 1 kg bifilar, wires 1 m and 0.2 m apart, the
    CoM 1 cm below the attachments) with the sweep's stated amplitude: the
    printed sigma is the stated-amplitude one, sd, and its second-order part
    is the small-amplitude budget's excess over its linear variance, carried
    unchanged: ``second_order`` = (sd0^2 - I^2 lin) / sd^2, with sd0 the
    small-amplitude sigma the point reports and lin the linear relative
    variance by hand (test_sweep_audit24's: mass (0.1 %)^2, lengths
    2 (0.5 mm / 1 m)^2, anchors and attachments 4 (1 mm / 0.2 m)^2, timing
    (2 ms / T)^2); the anchors' share I^2 2 (5e-3)^2 / sd^2 (to 1e-3: the
    amplitude's factor gain 1.00015 and its own 1e-5 share).  Kills the
    seven mutants of point_amplitude's ``lin_var`` (each moves
    second_order by 0.25 or more, or drops it)."""
    from bifilar.config import read_yaml
    from bifilar.studies import sweep as sw

    path = str(DATA / "c13_shallow.yaml")
    cfg = read_yaml(path)
    p = sw.evaluate_point(cfg, path, {}, sw.resolve_settings(cfg, tensions=True, components=["Izz"]))
    e = p["components"]["Izz"]
    ab = e["amplitude_budget"]
    assert ab["budgeted"], ab
    I, sd, sd0 = 0.012, e["sigma"], ab["sigma_small_amplitude"]
    lin = 1e-6 + 2 * (0.5e-3) ** 2 + 4 * (5e-3) ** 2 + (2e-3 / e["period"]) ** 2
    sh = e["shares"]
    assert sh["second_order"] == pytest.approx((sd0 ** 2 - I * I * lin) / sd ** 2, rel=1e-3), sh
    assert sh["anchors"] == pytest.approx(I * I * 2 * (5e-3) ** 2 / sd ** 2, rel=1e-3), sh
    assert sum(sh.values()) == pytest.approx(1.0, abs=1e-12)


# ---------------------------------------------------------------------------
# ranking.binding_constraint's message (audit24)
# ---------------------------------------------------------------------------

def _point(x, sep, comps, notes=None):
    """A hand-made point (the fields the ranking reads), as
    tests/test_sweep_audit24.py builds them."""
    return {"params": {"spacing": x}, "valid": True, "error": None,
            "components": {k: {"identifiable": True, "rel_sigma": v, "mode": "m", "shares": {"timing": 1.0},
                               **({"sigma_unavailable": notes[k]} if notes and k in notes else {})}
                           for k, v in comps.items()},
            "separation": sep,
            "tension": {"rest": [1.0], "peak": 1.0, "min": [0.5], "max": [1.0], "slack": False, "slack_wires": []},
            "depth": {"rest": 1.0, "max": 1.0}}


def test_a_binding_message_never_names_an_empty_list_of_components():
    """Every point's components have a small sigma except one point whose
    Izz sigma is infinite (a stated amplitude whose range reaches the half
    turn: point_amplitude sets it to inf, not None) and which meets every
    limit; the other two break --min-separation 0.02.  Whatever the policy
    for that point (named or not), the message must not claim a point gives
    "no uncertainty for" nothing: kills ``not meet or not miss -> and``
    (which appended "...give no uncertainty for : leave  out of
    --component")."""
    from bifilar.studies.ranking import binding_constraint
    from bifilar.studies.settings import Constraints

    c = Constraints(min_separation=0.02)
    pts = [_point(0.04, 0.0118, {"Ixx": 0.004, "Izz": 0.003}),
           _point(0.06, 0.299, {"Ixx": 0.004, "Izz": math.inf}, {"Izz": "the amplitude range reaches the half turn"}),
           _point(0.08, 0.0033, {"Ixx": 0.004, "Izz": 0.003})]
    flag, msg = binding_constraint(pts, c, None, ["Ixx", "Izz"])
    assert flag == "--min-separation"
    assert "for :" not in msg and "leave  out" not in msg, msg
    assert msg.startswith("no configuration") and "the best mode separation found is 0.0118" in msg, msg


# ---------------------------------------------------------------------------
# batch_rest.rest_poses(..., near=): the Newton run from the base pose (sigma24)
# ---------------------------------------------------------------------------

def _turned(phase: float):
    """tests/test_sigma_rest.py's trifilar with its attachments turned by
    ``phase`` (rad) about the vertical from the anchors: it hangs turned by
    about -phase, beyond the 0.5 rad the start's Newton end may be taken at."""
    from bifilar.config import scene_from_dict

    return scene_from_dict({"gravity": 9.81, "body": {"mass": 2.0, "inertia": {"principal": [0.3, 0.25, 0.4]}},
                            "rig": {"anchors": _ring(0.5, 0.0, 0.0), "attachments": _ring(0.4, 0.05, phase),
                                    "lengths": [1.0, 1.1, 0.9]}}, warn=False)


def _turn(Ra, Rb) -> float:
    from bifilar.rotations import matrix_to_rotvec

    return float(np.linalg.norm(matrix_to_rotvec(np.asarray(Ra) @ np.asarray(Rb).T)))


def test_near_takes_a_newton_end_within_its_turn_limit_and_searches_beyond_it(monkeypatch):
    """The base turned by -1.0 rad, scenes by -1.04 and -1.07: their rest
    poses (rest_pose, independent) are 0.04 and 0.07 rad from the base's.
    NEAR_MAX_TURN = 0.05: the first is taken from the Newton run from the
    base pose (no search), the second goes to rest_pose (one search); both
    are rest_pose's pose to 1e-12.  Kills NEAR_MAX_TURN 0.05 -> 0.1 and the
    half-angle's ``/ 2 -> * 2`` (both take the 0.07 one) and ``2 -> 3``
    (which refuses the 0.04 one: its limit 0.033)."""
    import bifilar.analysis.batch_rest as br
    from bifilar.analysis.equilibrium import rest_pose

    rb = rest_pose(_turned(-1.0))
    near_ok, far = _turned(-1.04), _turned(-1.07)
    refs = [rest_pose(near_ok), rest_pose(far)]
    assert _turn(refs[0].R, rb.R) == pytest.approx(0.04, abs=2e-3)
    assert _turn(refs[1].R, rb.R) == pytest.approx(0.07, abs=2e-3)
    assert br.NEAR_MAX_TURN == 0.05
    calls = _counting(monkeypatch)
    got = br.rest_poses([near_ok, far], errors="return", near=rb)
    assert calls == [far]
    for pose, ref in zip(got, refs):
        assert np.max(np.abs(pose.com - ref.com)) <= 1e-12 and np.max(np.abs(pose.R - ref.R)) <= 1e-12


def test_near_leaves_a_pose_beyond_the_start_box_to_rest_poses_refusal():
    """The base turned by -1.55 rad hangs (1.574 rad from the start, its
    rotation vector inside the 90-degree box); the scene turned by -1.58
    would hang 0.03 rad farther, beyond the box, which rest_pose refuses
    ("cannot hang within 90 degrees of its start orientation").  The
    Newton run from the base pose reaches that turned pose, within
    NEAR_MAX_TURN of the base, so only the start-box check keeps it from
    being taken: the verdict must be rest_pose's refusal.  Kills the
    trace's index and sign mutants of that check (each makes the turned
    pose's cosine positive: taken)."""
    import bifilar.analysis.batch_rest as br
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import UnstableRestError

    rb = rest_pose(_turned(-1.55))
    s = _turned(-1.58)
    with pytest.raises(UnstableRestError, match="within 90 degrees"):
        rest_pose(s)
    got = br.rest_poses([s], errors="return", near=rb)[0]
    assert isinstance(got, UnstableRestError) and "within 90 degrees" in got.message, got


# ---------------------------------------------------------------------------
# signal_crossings: the cycle count against an independent frequency (readers24)
# ---------------------------------------------------------------------------

def _sine(t_end: float, period: float = 1.0, gaps=()):
    """``sin(2 pi t / period)`` at 200 samples a period from 0.6 periods,
    its amplitude 0.01 over each gap (in periods, peak to peak), as
    tests/test_readers24.py's records: upward crossings at whole periods,
    downward at halves."""
    t = np.arange(0.6, t_end, 0.005)
    env = np.ones_like(t)
    for a, b in gaps:
        env[(t > a) & (t < b)] = 0.01
    return t * period, env * np.sin(2 * math.pi * t)


def test_crossings_are_refused_past_one_lost_cycle_against_the_given_frequency():
    """A clean 1 s sine from 0.6 to 8.2 s: the crossings' period is 1 s and
    their span 7 s (up at 1 ... 8 s), so against a given frequency f they
    "lost" (f - 1) x 7 cycles: 0.9 is accepted, 1.5 refused (MAX_LOST_CYCLES
    = 1), the message counting 7.0 cycles against 7 f.  Kills
    MAX_LOST_CYCLES 1 -> 2 and the span's ``max - min -> max + min`` (a span
    of 9 s makes the 0.9 lost cycles 1.16)."""
    from bifilar.estimation.signal import SignalError
    from bifilar.estimation.signal_crossings import MAX_LOST_CYCLES, period_from_crossings

    assert MAX_LOST_CYCLES == 1.0
    t, y = _sine(8.2)
    cp = period_from_crossings(t, y, level=0.0, hysteresis=0.1, frequency=1.0 + 0.9 / 7.0)
    assert cp.period == pytest.approx(1.0, abs=1e-6)
    with pytest.raises(SignalError, match="cycles lost inside the hysteresis band") as e:
        period_from_crossings(t, y, level=0.0, hysteresis=0.1, frequency=1.0 + 1.5 / 7.0)
    assert "count 7.0 cycles in 7 s" in e.value.message and "the fit's frequency" in e.value.message, e.value.message


def test_a_fast_record_that_lost_most_cycles_is_refused_too():
    """readers24's two-thirds record (up crossings 1, 2, 5, 8 and down 1.5,
    4.5, 7.5 periods: median interval 3 periods) at a period of 0.5 s: the
    refusal does not depend on the period's size (kills ``period > 0 ->
    period > 1``, which skipped the count for periods under 1 s).  The
    spectral peak sees the 2 Hz cycles under the band."""
    from bifilar.estimation.signal import SignalError
    from bifilar.estimation.signal_crossings import period_from_crossings

    t, y = _sine(8.2, 0.5, [(2.25, 4.25), (5.25, 7.25)])
    with pytest.raises(SignalError, match="cycles lost inside the hysteresis band") as e:
        period_from_crossings(t, y, level=0.0, hysteresis=0.1)
    assert "spectral peak at 2 Hz" in e.value.message or "spectral peak at 1.99" in e.value.message, e.value.message


# ---------------------------------------------------------------------------
# signal_result: a chirp's other oscillations through further_modes (readers24)
# ---------------------------------------------------------------------------

def test_a_chirps_other_oscillation_is_reported_with_its_own_amplitude_and_phase():
    """A chirp record (1 Hz, amplitude 0.1, beta 0.3) carrying a second
    damped cosine a2 = 0.01, b2 = -0.005 at 0.47 Hz, sigma2 0.01 / s (the
    coupled swing signal_law fits beside the law), white noise 1e-4, 30 s
    at 50 Hz, fitted from its true parameters.  The result's second mode
    has the cosine's amplitude hypot(a2, b2) = 0.01118, phase atan2(-b2, a2)
    = 0.4636 rad, period 1 / 0.47 s and decay 0.01 / s (tolerances ~10x the
    least-squares stds, ~1e-5 in amplitude).  Kills ``mode(i, i + 1, ...)
    -> i - 1`` (its b read from beta2: amplitude 0.0100, phase 0.02)."""
    from bifilar.estimation.signal_models import _model, _solve
    from bifilar.estimation.signal_result import _build

    t = np.arange(0.0, 30.0, 0.02)
    t0, tm = float(t[0]), float(0.5 * (t[0] + t[-1]))
    a2, b2, f2, s2 = 0.01, -0.005, 0.47, 0.01
    p = np.array([0.0, 0.0, 0.1, 0.02, 2 * math.pi, 0.02, 0.3, 0.0, a2, b2, 2 * math.pi * f2, s2])
    y = _model("chirp", p, t, t0, tm) + np.random.default_rng(25).normal(0.0, 1e-4, t.size)
    fit = _build(_solve("chirp", t, y, t0, tm, p), t, y, "chirp", [])
    assert len(fit.modes) == 2
    other = fit.modes[1]
    assert other["amplitude"] == pytest.approx(math.hypot(a2, b2), abs=1e-4)
    assert other["phase"] == pytest.approx(math.atan2(-b2, a2), abs=1e-2)
    assert other["period"] == pytest.approx(1 / f2, rel=1e-3)
    assert other["sigma"] == pytest.approx(s2, abs=1e-3)


def test_a_batch_newton_end_at_an_unstable_equilibrium_is_rest_poses_refusal():
    """A trifilar whose wires spread upwards across y (anchors 2 m apart,
    attachments 0.1 m: the wires' virtual pivot lies below the attachments)
    and hang parallel along x (1.2 m apart), the CoM 0.1 m above the
    attachment plane: the upright pose balances but tips over about the x
    axis only, and rest_pose refuses it (UnstableRestError).  The batch's
    Newton from the start pose ends at that balance, its reduced stiffness
    with exactly one negative eigenvalue (measured -0.99, 2.87 and 17.9
    in its reduced coordinates): the check must look at the smallest and
    send the scene to rest_pose for the same refusal.  Kills ``ev[:, 0] -> ev[:, 1]`` (which
    passed the CoM 0.2 m up, whose two negative eigenvalues either index
    sees)."""
    import bifilar.analysis.batch_rest as br
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.config import scene_from_dict
    from bifilar.errors import UnstableRestError

    att = [[0.6, 0.05, -0.1], [-0.6, 0.05, -0.1], [0.0, -0.05, -0.1]]
    anc = [[0.6, 1.0, 1.0], [-0.6, 1.0, 1.0], [0.0, -1.0, 1.0]]
    s = scene_from_dict({"body": {"mass": 2.0, "inertia": {"principal": [0.05, 0.2, 0.22]}},
                         "rig": {"anchors": anc, "attachments": att,
                                 "lengths": np.linalg.norm(np.subtract(anc, att), axis=1).tolist()}}, warn=False)
    with pytest.raises(UnstableRestError):
        rest_pose(s)
    got = br.rest_poses([s], errors="return")[0]
    assert isinstance(got, UnstableRestError), got
