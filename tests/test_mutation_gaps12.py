"""Mutation round 12 (docs/mutation.md, "Round 12"): tests that fail on a
mutant of session 11's code that the suite let through.  Each states the
truth it checks (an analytic result, an independent formulation, or the
documented rule on an input built for it); none reads its expected value
off the code under test.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import yaml

from test_dependent_wires_messages import SHIFTED, _gap_by_hand, scene_of

# ---------------------------------------------------------------------------
# estimation/slack_cause.py
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("last", ["1.1628", "1.1928"])
def test_a_slack_wires_gap_is_its_length_minus_the_span_of_its_ends(last):
    """``slack_gaps`` of the leaning table's wire 4 (slack by 1.13 mm, or
    31.1 mm with the wire 30 mm longer) is its length minus the distance
    between its anchor and attachment at the rest pose of the three other
    wires, written out by hand (``_gap_by_hand``: its own rest pose of the
    3-wire config and ``|com + R p - a|``); the same as the slack the rest
    pose's refusal states.  Only its derivatives reached a test before, and
    those are the same for ``+ anchor`` and for ``L + |d|`` (each input moves
    either the length or the span, by a unit vector's worth)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import SlackWireError
    from bifilar.estimation.slack_cause import slack_gaps

    text = SHIFTED.replace("LAST", last)
    scene = scene_of(text)
    gap, rp = slack_gaps(scene, [3])
    by_hand = _gap_by_hand(yaml.safe_load(text), 3)
    # two rest poses solved to ~1e-12 m: agreement to 1e-9 m
    assert gap.shape == (1,) and abs(gap[0] - by_hand) < 1e-9, (gap, by_hand)
    with pytest.raises(SlackWireError) as ei:
        rest_pose(scene)
    assert abs(ei.value.gaps[0] - by_hand) < 1e-9


def _lean_error():
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.errors import SlackWireError

    scene = scene_of(SHIFTED.replace("LAST", "1.1628"))
    with pytest.raises(SlackWireError) as ei:
        rest_pose(scene)
    return scene, ei.value


def test_the_within_note_quotes_the_slack_wires_own_sigma():
    """The note's standard uncertainty is that of the named wire's slack
    (wire 4, 0-based 3: its first-order std, checked against 300 sampled
    configs by test_dependent_wires_messages), 3.43 mm; wire 3's would be
    3.49 mm (``w - 1 -> w - 2`` passed: both lie within 3 sigma)."""
    from bifilar.estimation.slack_cause import slack_gap_sigmas, within_uncertainty

    scene, err = _lean_error()
    out = within_uncertainty(err, scene, {}, "here")
    m = re.search(r"wire 4's ([0-9.]+) mm against a standard uncertainty of ([0-9.]+) mm", out.message)
    assert m, out.message
    own = slack_gap_sigmas(scene, [3], {})[0] * 1000
    assert float(m.group(1)) == pytest.approx(err.gaps[0] * 1000, rel=5e-3)  # 3 significant digits
    assert float(m.group(2)) == pytest.approx(own, rel=5e-3)


@pytest.mark.parametrize("gaps", [[0.0], None, []])
def test_a_wire_without_a_positive_slack_is_never_put_down_to_the_inputs(gaps):
    """A wire straight at rest that carries no tension (the rest pose's
    refusal states its gap as 0) or an error without gaps is left as it is
    (the docstring: the note is for a *slack* wire).  ``or -> and`` and ``>
    -> >=`` passed: with gap 0 the note said 'wire 4's 0 mm ... within 3
    standard uncertainties', a slack that is not there."""
    from bifilar.errors import SlackWireError
    from bifilar.estimation.slack_cause import within_uncertainty

    scene, _ = _lean_error()
    err = SlackWireError([4], "wire 4 carries no tension at rest (0 N)", gaps=gaps)
    assert within_uncertainty(err, scene, {}, "here") is err


# ---------------------------------------------------------------------------
# estimation/solve.py: the gain of one unknown, and its warning
# ---------------------------------------------------------------------------


def _boat_problem(n: int, A: float = 1.0, T: float = 3.0):
    """The Solar Boat's swing-y timed ``n`` times (``T`` s +- 1 ms) at amplitude ``A`` (m), Ixx unknown."""
    from bifilar.config import load_scene
    from bifilar.estimation import measurements as mm
    from bifilar.estimation.problem import build_problem

    from conftest import CONFIGS

    cfg = CONFIGS / "solar_boat.yaml"
    sc = load_scene(cfg, unknown=("Ixx",))
    ms = [mm.Measurement("swing-y", T, 1e-3, "period", "--period", cycles=10, amplitude=A, std_given=True)
          for _ in range(n)]
    return build_problem(mm.MeasurementSet([mm.Hanging("ref", sc, np.eye(3), str(cfg))], ms), ["Ixx"])


BOAT_IXX = 83.14158854


def _full_slope_gain(pb, k: int, p0: float, r0: float, dr: float) -> float:
    """``d(T_lin r)/dp / (r dT_lin/dp)`` at ``p0`` for a factor linear in the unknown, ``r(p) = r0 + dr (p -
    p0)``: central differences of the product itself (step 1e-3 of p0: truncation ~1e-6 relative, rounding
    ~1e-13 / 1e-3), not the gain's formula ``1 + T_lin dr/dp / (r dT_lin/dp)``."""
    h = 1e-3 * p0
    Tp, Tm = (float(pb.linear_periods([p0 + s * h])[k]) for s in (1, -1))
    full = (Tp * (r0 + dr * h) - Tm * (r0 - dr * h)) / (2 * h)
    return full / (r0 * (Tp - Tm) / (2 * h))


def _law(dr):
    from types import SimpleNamespace

    return SimpleNamespace(dr_dp=None if dr is None else np.array([dr]))


def test_factor_gains_are_the_full_models_slope_over_the_linear_ones():
    """Per measurement: None without a law or without ``dr/dp`` (``or ->
    and`` on either passed: no test had a measurement without a law beside
    one with), else the slope of ``T_lin r`` over ``r``'s share of it."""
    from bifilar.estimation.solve import Estimate, factor_gains

    pb = _boat_problem(3)
    r0, dr = 1.02, 4e-4
    est = Estimate(np.array([BOAT_IXX]), "nonlinear", np.array([1.0, 1.0, r0]), laws=[None, _law(None), _law(dr)])
    g = factor_gains(pb, est)
    assert g[0] is None and g[1] is None
    from types import SimpleNamespace

    two = SimpleNamespace(unknowns=["Ixx", "Izz"], measurements=pb.measurements)  # several unknowns: no gain
    assert factor_gains(two, est) == [None] * 3
    ref = _full_slope_gain(pb, 2, BOAT_IXX, r0, dr)
    assert abs(ref - 1) > 0.1  # the factor's term is no rounding
    assert g[2] == pytest.approx(ref, rel=1e-4)  # pb.jacobian's own central step (1e-6): ~1e-6 relative


@pytest.mark.parametrize("g, warned", [(1.95, False), (2.05, True), (0.5, False), (-0.05, True)])
def test_the_gain_warning_starts_where_the_fixed_point_stops_contracting(g, warned):
    """The fixed point ``x -> T_lin^-1(T_meas / r(x))`` multiplies its error
    by ``1 - g`` per run (docs/invert.md): it contracts for ``0 < g < 2``
    and no longer from ``g = 2`` on (``|1 - g| >= 1``); at ``g <= 0`` the
    period turns back.  The warning must start at those analytic limits
    (``GAIN_RANGE``'s 2.0 -> 4.0 passed: the tests' gains were 1.7 and
    5.8).  The factor's ``dr/dp`` is set so that the full model's slope,
    by central differences of ``T_lin r``, gives ``g``."""
    from bifilar.estimation.answer_checks import monotonic_warnings
    from bifilar.estimation.solve import Estimate

    pb = _boat_problem(1)
    r0 = 1.02
    h = 1e-3 * BOAT_IXX
    dT = float(pb.linear_periods([BOAT_IXX + h])[0] - pb.linear_periods([BOAT_IXX - h])[0]) / (2 * h)
    dr = (g - 1) * r0 * dT / float(pb.linear_periods([BOAT_IXX])[0])
    assert _full_slope_gain(pb, 0, BOAT_IXX, r0, dr) == pytest.approx(g, abs=1e-4)
    est = Estimate(np.array([BOAT_IXX]), "nonlinear", np.array([r0]), laws=[_law(dr)])
    w = [x for x in monotonic_warnings(pb, est) if "need not be monotonic" in x]
    assert bool(w) is warned, (g, w)
    if warned and g <= 0:
        assert "falls as it grows" in w[0]


# ---------------------------------------------------------------------------
# studies/point_inputs.py: gravity's dr/dx bound
# ---------------------------------------------------------------------------


def test_gravity_adds_nothing_to_the_factor_inputs_bound():
    """The amplitude factor is a ratio of periods of one rigid pendulum, all
    of which scale as 1/sqrt(g): ``r`` does not depend on gravity (checked
    here: the boat's torsion at 0.3 rad, r at g and 1.2 g agree to 1e-9,
    the runs' own error ~1e-11), so a stated gravity uncertainty must add
    nothing to the point's bound on the inputs' factor terms (``_bound_scale``'s
    gravity 0.0 -> 1 was never run: no test stated one)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import simulate
    from bifilar.scene import scene_with

    from test_sweep_factor_inputs import SOLAR, _point

    bounds = []
    for sig in ({}, {"gravity": 1e-3}):
        _, scene, p = _point(SOLAR, {"spacing": 1.0, "length": 2.0}, components=["Izz"], sigma=sig)
        e = p["components"]["Izz"]
        bounds.append(e["amplitude_budget"]["input_factor_bound"] * e["sigma"])  # kg m^2 (stated relative)
    r = []
    for g in (scene.gravity, 1.2 * scene.gravity):
        s = scene_with(scene, gravity=g)
        r.append(simulate(s, "torsion", 0.3, 10, rtol=1e-10).period / linear_modes(s, rest_pose(s)).get("torsion").period)
    assert abs(r[0] - r[1]) < 1e-9 and abs(r[0] - 1) > 1e-3, r
    assert bounds[0] > 0 and bounds[1] == pytest.approx(bounds[0], rel=1e-9), bounds


def _full_scalar(monkeypatch, factor, xs=(80.0, 100.0, 110.0)):
    """``_solve_full_scalar`` on the boat's swing-y (Ixx, 1 ms timing) with the amplitude factor replaced by
    ``factor(x, T_lin(x))`` (regular runs without a period error, as a run whose error is unknown), the fixed
    point's iterates at ``xs``."""
    from types import SimpleNamespace

    from bifilar.estimation import solve

    pb = _boat_problem(1, T=2.97)

    def fake(pb_, k, p, rtol=1e-10, amplitude=None):
        x = float(p[0])
        return factor(x, float(pb_.linear_periods([x])[0])), SimpleNamespace(period_error=math.nan), 0.0

    # estimation/nonlinear_roots.py (where _solve_full_scalar moved) reads solve.measured_factor when called
    monkeypatch.setattr(solve, "measured_factor", fake)
    runs = {x: fake(pb, 0, np.array([x])) for x in xs}
    return pb, solve._solve_full_scalar(pb, np.array([xs[-1]]), 1e-10, runs)


def test_the_full_models_root_is_where_its_period_is_the_measured_one(monkeypatch):
    """A factor linear in Ixx chosen so that ``T_lin r`` equals the measured
    period at Ixx = 95 exactly: the root is 95 to Brent's 1e-9 of the scale."""
    T_meas, x_star = 2.97, 95.0
    pb = _boat_problem(1, T=T_meas)
    r_star = T_meas / float(pb.linear_periods([x_star])[0])
    _, out = _full_scalar(monkeypatch, lambda x, T_lin: r_star * (1 + 1e-3 * (x - x_star) / x_star))
    assert len(out) == 1 and abs(float(out[0][0][0]) - x_star) < 1e-6 * x_star, out
    assert out[0][1] == pytest.approx(r_star, rel=1e-9)


def test_a_period_that_jumps_across_the_measured_one_is_no_root(monkeypatch):
    """A factor whose ``T_lin r`` jumps from 1 % below the measured period
    to 1 % above it at Ixx = 95 (the timed coordinate of a beating mode
    passing from one mode to another): a sign change with no root, which
    must be refused naming the jump, not answered.  The tolerance on the
    full model's period is 1e-3 of its 1 ms std (``FULL_MAP_SHARE / std``
    -> 1 s, and ``max(errs, default=1)`` -> 10 s where no run has a period
    error, passed: no test had a jump)."""
    from bifilar.errors import InputError

    with pytest.raises(InputError) as ei:
        _full_scalar(monkeypatch, lambda x, T_lin: 2.97 / T_lin * (1 + 0.01 * math.copysign(1, x - 95.0)))
    assert ei.value.field == "--period" and "jumps across the measured one at Ixx = 95" in str(ei.value)
    # named once: the fallback search re-finds the jump the bracketing found ("at Ixx = 95, 95" before)
    assert "at Ixx = 95)" in str(ei.value), str(ei.value)


# ---------------------------------------------------------------------------
# analysis/equilibrium.py: tension_range on inclined dependent wires
# ---------------------------------------------------------------------------


def test_range_on_four_inclined_wires_through_one_point():
    """Four wires from attachments (+-0.3, +-0.2, 0) to anchors (+-0.15,
    +-0.1, 1) all point at (0, 0, 2), above the CoM: their moments about it
    vanish, so only the three force equations bind (dependent, rank 3).  By
    hand: x and y balance give T1 = T3, T2 = T4, z gives T1 + T2 = W |d| /
    2 with ``d = (0.15, 0.1, 1)`` per unit height, so each wire carries 0 ..
    W |d| / 2 = 49.84 N.  The session's tests had vertical wires only, whose
    horizontal force rows are zero (the rank reduction drops them): the
    weight's right-hand side with an x component (``b[0]`` 0 -> 1) passed."""
    from bifilar.analysis.equilibrium import rest_pose, tensions_determined
    from bifilar.analysis.wire_statics import tension_range
    from bifilar.config import scene_from_dict

    corners = [(1, 1), (-1, 1), (-1, -1), (1, -1)]
    anch = [[0.15 * x, 0.10 * y, 1.0] for x, y in corners]
    att = [[0.30 * x, 0.20 * y, 0.0] for x, y in corners]
    L = [float(np.linalg.norm(np.subtract(a, p))) for a, p in zip(anch, att)]
    cfg = {"name": "inclined", "body": {"mass": 10.0, "inertia": {"principal": [0.3, 0.5, 0.7]}},
           "rig": {"anchors": anch, "attachments": att, "lengths": L}}
    scene = scene_from_dict(cfg, "x", warn=False)
    rest = rest_pose(scene)
    assert not tensions_determined(scene, rest)
    W = scene.mass * scene.gravity
    hi = W * math.sqrt(0.15 ** 2 + 0.1 ** 2 + 1.0) / 2
    # the LP's feasibility tolerance ~1e-9 of W
    assert np.allclose(tension_range(scene, rest), [[0.0, hi]] * 4, rtol=0, atol=1e-7 * W)



# ---------------------------------------------------------------------------
# analysis/simulate.py: reachable_amplitude
# ---------------------------------------------------------------------------


def test_every_rotation_is_limited_to_half_a_turn_and_every_translation_in_metres():
    """The limit is pi rad for a mode whose dominant coordinate is a
    rotation (roll, pitch, torsion: no start is more than half a turn from
    rest) and a length (m) for a translation (swing, bounce), read here
    from the mode's label, not its index: the Solar Boat's roll is the
    first rotation (index 3), which ``>= 3 -> > 3`` and ``3 -> 4`` put among
    the translations (its limit 6 'm') and passed: the tests' rotations were
    torsions."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import reachable_amplitude
    from bifilar.config import load_scene

    from conftest import CONFIGS

    seen = set()
    for cfg in ("solar_boat.yaml", "thesis_lin2_pitch.yaml"):
        s = load_scene(CONFIGS / cfg, warn=False)
        for m in linear_modes(s, rest_pose(s)).modes:
            kind = m.label.split("-")[0]
            seen.add(kind)
            limit, unit = reachable_amplitude(s, m)
            if kind in ("roll", "pitch", "torsion"):
                assert (limit, unit) == (math.pi, "rad"), (cfg, m.label, limit, unit)
            else:
                assert kind in ("swing", "bounce") and unit == "m" and limit >= float(np.max(s.lengths)), (cfg, m.label)
    assert {"roll", "pitch", "torsion", "swing"} <= seen


def test_two_roots_of_the_full_model_are_both_found_ascending(monkeypatch):
    """``T_lin r - T_meas = T_meas k (x - 95)(105 - x)``: the fixed point's
    runs at 80, 100 and 110 change sign twice, and each interval is refined
    on its own (Brent between ``xs[i]`` and ``xs[i + 1]``; ``xs[i + 2]``
    passed, the tests' only root lying in the first of two intervals that
    both bracket it): the roots 95 and 105, ascending."""
    T_meas, k = 2.97, 1e-4
    _, out = _full_scalar(monkeypatch, lambda x, T_lin: T_meas / T_lin * (1 + k * (x - 95.0) * (105.0 - x)))
    assert [round(float(q[0][0]), 6) for q in out] == [95.0, 105.0]


# ---------------------------------------------------------------------------
# estimation/signal_models.py: the dominant mode by RMS amplitude
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("sigma", [0.0, 1e-14, 0.02, 0.6, 3.0])
def test_a_modes_rank_is_its_rms_amplitude_over_the_record(sigma):
    """``_mode_rank``'s amplitude is the RMS over the record ``[0, T_rec]``
    of an envelope ``A e^{-sigma t}`` (the phase averages the cosine's
    square to 1/2 in both modes alike), by trapezoid quadrature on 2e5
    points (error ``h^2 (2 sigma)^2 / 12`` <= 3e-8 relative): ``x = 2 sigma T_rec -> 4 sigma T_rec``
    passed (a transient at damping ratio 0.6 is small over the record
    either way)."""
    from bifilar.estimation.signal_models import _mode_rank

    A, T_rec, w = 0.3, 20.0, 2 * math.pi / 2.0
    t = np.linspace(0.0, T_rec, 200001)
    y2 = (A * np.exp(-sigma * t)) ** 2
    rms = math.sqrt(float(np.sum((y2[1:] + y2[:-1]) / 2 * np.diff(t))) / T_rec)
    few, key = _mode_rank(w, A, T_rec, sigma)
    assert few is False
    assert -key == pytest.approx(rms, rel=1e-7)


@pytest.mark.parametrize("left, settled", [(0.05, True), (0.2, False)])
def test_a_contracting_fixed_point_is_taken_when_what_is_left_is_under_a_tenth_of_the_std(left, settled):
    """Iterates ``x_n = x* + e c^n`` (c = 0.5) of a contraction: after
    ``x_2`` the error left is exactly the last step times ``c / (1 - c)``
    (the geometric series), here set to move the period by ``left`` of its
    1 ms std (``T_lin`` near-linear over the 1e-4 span: its curvature
    changes that by ~1e-4 relative).  Taken within a tenth of the std
    (``IRREGULAR_REFUSE_SHARE``), not beyond; a growing step is never
    taken.  (``len(pb.unknowns) != 1 -> == 1`` passed: the full model then
    solved each such case again, to the same answer.)"""
    from bifilar.estimation.solve import IRREGULAR_REFUSE_SHARE, _contracted

    assert IRREGULAR_REFUSE_SHARE == 0.1
    pb = _boat_problem(1)
    r, x_star, c = np.array([1.02]), 90.0, 0.5
    h = 1e-3 * x_star
    dT = float(pb.linear_periods([x_star + h])[0] - pb.linear_periods([x_star - h])[0]) / (2 * h)
    e = left * 1e-3 / (abs(dT) * r[0] * c ** 2)
    x = [np.array([x_star + e * c ** n]) for n in range(3)]
    assert _contracted(pb, [(x[0], x[1]), (x[1], x[2])], r) is settled
    assert _contracted(pb, [(x[2], x[1]), (x[1], x[0])], r) is False  # the steps grow
    assert _contracted(pb, [(x[0], x[1])], r) is False  # one step: no contraction measured


@pytest.mark.parametrize("cycles, few", [(1.5, True), (2.5, False), (40.0, False)])
def test_a_mode_with_fewer_than_two_cycles_in_the_record_ranks_last(cycles, few):
    """The first element of the key: fewer than ``MIN_CYCLES`` = 2 cycles
    of ``omega`` within the record (a slow swell fitted as a "mode"); the
    count is ``omega T_rec / 2 pi`` (``2 pi -> 3 pi`` and ``* -> /`` in it
    passed, the tests' modes having tens of cycles or under one)."""
    from bifilar.estimation.signal_models import _mode_rank

    T_rec = 30.0
    w = 2 * math.pi * cycles / T_rec
    assert _mode_rank(w, 0.1, T_rec, 0.01)[0] is few


# ---------------------------------------------------------------------------
# estimation/answer_checks.py: the envelope at the record's halves
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("sigma, kappa", [(0.02, 0.0), (0.02, 0.05), (0.0, 0.05)])
def test_the_halves_amplitudes_follow_the_fitted_decay_law(sigma, kappa):
    """The quadratic fit's envelope ``A0 e^{-sigma tau} / (1 + kappa E)``
    solves ``dA/dtau = -sigma A - (kappa / A0) A^2`` (viscous plus
    quadratic damping); integrated here numerically (DOP853, rtol 1e-12)
    to the middles of the record's halves, T/4 and 3T/4.  The tests'
    records were viscous (kappa 0), where the sign of ``E`` (dropped: passed)
    and the decay term's form do not show."""
    from types import SimpleNamespace

    from scipy.integrate import solve_ivp

    from bifilar.estimation.answer_checks import _half_amplitudes

    A0, T = 0.4, 60.0
    fit = SimpleNamespace(damping={"sigma": sigma, "kappa": kappa}, amplitude=-A0, t0=5.0, t1=5.0 + T)
    sol = solve_ivp(lambda t, A: -sigma * A - kappa / A0 * A ** 2, (0.0, T), [A0], method="DOP853",
                    t_eval=[T / 4, 3 * T / 4], rtol=1e-12, atol=1e-15)
    got = _half_amplitudes(fit)
    assert got is not None and np.allclose(got, sol.y[0], rtol=1e-9, atol=0), (got, sol.y[0])


def test_a_record_in_degrees_under_one_unit_is_refused_too(tmp_path):
    """The drone's torsion released at 0.9 degrees, recorded in degrees and
    read as rad (``--signal-quantity angle`` without ``--signal-scale``):
    its fitted amplitude is 0.9 'rad', below one signal unit, and must be
    checked as the 1.5-degree record of test_signal_audit11 is (the check
    runs for any positive amplitude; ``amplitude_period > 0 -> > 1``
    passed).  Exit 2 naming --signal-scale."""
    from click.testing import CliRunner

    from bifilar.cli import main

    from test_signal_audit11 import drone_torsion_in_degrees

    cfg, _, rec = drone_torsion_in_degrees(tmp_path, 0.9)
    r = CliRunner().invoke(main, ["invert", str(cfg), "--signal", f"torsion={rec}", "--signal-quantity", "angle",
                                  "--json"])
    assert r.exit_code == 2 and r.stdout == "", r.output
    assert "--signal-scale" in r.output and "contradicts the record" in r.output, r.output


def test_an_unsettled_fixed_point_with_regular_runs_is_refused_only_beyond_its_share():
    """mut12's gap: ``_refuse_unsettled``'s branch for regular runs (no check
    difference, ``seen`` 0) was reached by no test.  Its last step moved the
    model period by ``|T_lin(p) - T_lin(p_at)| r``; the refusal must come
    exactly when that exceeds ``IRREGULAR_REFUSE_SHARE`` of the period's
    std, name the measurement's field and say why (the factor changes with
    the unknowns as fast as the linear period: a resonance), and a step
    inside the share must pass.  ``T_lin`` is the boat's own (its linear
    periods at two Ixx), so the step size in Ixx is set from its slope
    ``dT_lin/dIxx`` by central differences."""
    from bifilar.errors import InputError
    from bifilar.estimation import solve

    pb = _boat_problem(1, T=2.97)
    m = pb.measurements[0]
    p0 = np.array([BOAT_IXX])
    h = 1e-3 * BOAT_IXX
    slope = float((pb.linear_periods(p0 + h)[0] - pb.linear_periods(p0 - h)[0]) / (2 * h))  # s per kg m^2
    r = np.array([1.0])
    step = solve.IRREGULAR_REFUSE_SHARE * m.std / abs(slope)  # the Ixx step that moves T_lin by the share
    solve._refuse_unsettled(pb, p0 + 0.9 * step, p0, r, [0.0], 6)  # inside: no refusal
    with pytest.raises(InputError) as ei:
        solve._refuse_unsettled(pb, p0 + 1.1 * step, p0, r, [0.0], 6)
    msg = str(ei.value)
    assert ei.value.field == "--period", ei.value.field
    assert "did not settle in 6 simulations" in msg and "release at a smaller amplitude" in msg, msg
    assert "changes with the unknowns about as fast as the linear period" in msg, msg
    # the step moved the period by 1.1 shares: the message's figure is that, to its one digit
    moved = 1.1 * solve.IRREGULAR_REFUSE_SHARE * m.std
    assert f"by {moved:.1g} s" in msg, msg


@pytest.mark.parametrize("irregular", [0.0, 1e-7])
def test_the_secant_abandons_a_step_whose_run_is_irregular(monkeypatch, irregular):
    """mut12's gap: no test made a secant step's run irregular (``irr > 0 ->
    > 1`` passed).  Two periods of the boat's swing-y, one unknown, the
    factor replaced by a constant 1 (so the fixed point's map is the linear
    solution ``x_lin`` whatever ``x``: the secant from two iterates lands on
    it in one step and the model periods then agree exactly).  A regular run
    settles there; a run with any check difference (1e-7 s, 1e-4 of the
    period's 1 ms std) is no smooth factor, and the secant must give up
    (None: refused by ``_refuse_unsettled``), not return that iterate."""
    from types import SimpleNamespace

    from bifilar.estimation import solve

    T = float(_boat_problem(1).linear_periods(np.array([BOAT_IXX]))[0])  # the boat's own linear period
    pb = _boat_problem(2, T=T)

    def fake(pb_, k, p, rtol=1e-10, amplitude=None):
        return 1.0, SimpleNamespace(period_error=0.0), irregular

    monkeypatch.setattr(solve, "measured_factor", fake)
    x_lin = float(solve.solve_linear(pb, solve._targets(pb, np.ones(2)), p0=np.array([BOAT_IXX]))[0])
    assert abs(x_lin - BOAT_IXX) < 1e-6 * BOAT_IXX  # the linear model's own answer
    steps = [(np.array([x_lin - 2.0]), np.array([x_lin])), (np.array([x_lin + 1.0]), np.array([x_lin]))]
    out = solve._settle_by_secant(pb, steps, 1e-10)
    if irregular:
        assert out is None
    else:
        assert out is not None and abs(float(out[0][0]) - x_lin) <= 1e-9 * x_lin, (out, x_lin)
