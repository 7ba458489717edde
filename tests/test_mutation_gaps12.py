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


def _boat_problem(n: int, A: float = 1.0):
    """The Solar Boat's swing-y timed ``n`` times at amplitude ``A`` (m), Ixx unknown."""
    from bifilar.config import load_scene
    from bifilar.estimation import measurements as mm
    from bifilar.estimation.problem import build_problem

    from conftest import CONFIGS

    cfg = CONFIGS / "solar_boat.yaml"
    sc = load_scene(cfg, unknown=("Ixx",))
    ms = [mm.Measurement("swing-y", 3.0, 1e-3, "period", "--period", cycles=10, amplitude=A, std_given=True)
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
