"""Mutation round 29 (docs/mutation.md, "Round 29"): tests that kill the
surviving mutants of session 28's new and changed code (partner28/cross28's
named partner readings of several unknowns, camera28's leakage term in the
2nd harmonic's std).  Every expected value is worked out by hand or from the
documented rule, never taken from the code under test; each test's
docstring names the mutants it kills (ids of ``scripts/mutate.py``'s mutants
of the module at 20d7b8f).  ~2 s CPU."""

from __future__ import annotations

import math
import re
import types
from pathlib import Path

import numpy as np
import pytest

DRAWN = str(Path(__file__).resolve().parent / "data" / "audit27" / "a03_drawn.yaml")
T_TORSION, T_ROLL = 1.88117, 1.62931  # s: audit27 a03's truth periods (tests/test_partner28.py)


# ---------------------------------------------------------------------------
# estimation/crossing_partner.py (partner28, cross28)
# ---------------------------------------------------------------------------

def _one_unknown_scan():
    from bifilar.estimation import stated_inputs as sti
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.roots import ScalarScan
    from bifilar.estimation.uncertainty import default_uncertainty

    ms = sti.measurement_set(DRAWN, None, ["Izz"], {}, None, [("torsion", T_TORSION, 0.0005)], (), (),
                             {None: (0.05, None)})
    return ScalarScan(build_problem(ms, ["Izz"], default_uncertainty(ms.uncertainty)))


def test_a_stated_amplitude_without_a_reading_names_the_partner_and_no_value():
    """partner_hint's documented rule: with a stated amplitude (``exact``
    False) the value comes only from ``reading``; without one (inside a
    reading) the hint names the label and how to give the period, and
    stops there.  a03's gap 1.8745 .. 1.8840 s (tests/test_partner28.py)
    holds 1.8808 s.  Kills crossing_partner 22 (``not exact and reading is
    not None -> or``: calls None)."""
    from bifilar.estimation import crossing_partner as cp

    msg = cp.partner_hint(_one_unknown_scan(), 1.8808, exact=False, reading=None)
    assert msg.endswith(f"the period can be given under its label (--period swing-x={T_TORSION}+-0.0005)")
    assert "which" not in msg


def test_a_refusals_first_clause_is_cut_at_240_characters():
    """The quoted refusal: its first clause (up to the first ';'), white
    space folded, at most 240 characters (the docstring).  Kills
    crossing_partner 30 (``[:240] -> [:241]``)."""
    from bifilar.estimation import crossing_partner as cp

    assert cp._head("a  b\n c; d") == "a b c"
    assert cp._head("x" * 300 + "; more") == "x" * 240


def _two_unknowns():
    from bifilar.estimation import stated_inputs as sti
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.uncertainty import default_uncertainty

    ms = sti.measurement_set(DRAWN, None, ["Izz", "Ixx"], {}, None,
                             [("torsion", T_TORSION, 0.0005), ("roll", T_ROLL, 0.0005)], (), (), {})
    pb = build_problem(ms, ["Izz", "Ixx"], default_uncertainty(ms.uncertainty))
    assert list(pb.unknowns) == ["Ixx", "Izz"]
    return pb, np.array([0.0416, 0.1023])  # the best fit of tests/test_partner28.py's refusal (kg m^2)


def test_the_measurement_scanned_is_the_largest_finite_residual_not_a_nan():
    """surface_hint tries the measurement the refusal names, the largest
    normalised residual; a NaN residual is not a residual (numpy's nanargmax
    of the finite |z| with the NaN's below every one).  With z = (0.5, NaN)
    the torsion is the one named (its 1.88117 s lies in the Izz line's gap
    at the best fit, test_partner28), with (NaN, 0.5) the roll (in no gap:
    no hint).  Kills crossing_partner 32 (the fill ``-1.0 -> 1.0``: the NaN's
    roll then outranks |z| = 0.5 and the torsion's gap goes unnamed).
    (The fill ``-2.0``, 33, is equivalent: any negative fill is below every
    |z|.)"""
    from bifilar.estimation import crossing_partner as cp

    pb, p = _two_unknowns()
    T = [T_TORSION, T_ROLL]
    assert cp.surface_hint(pb, p, [0.5, np.nan], T).startswith(
        "; at the best fit no Izz gives the mode labelled 'torsion' 1.88117 s with Ixx = 0.0416 as there")
    assert cp.surface_hint(pb, p, [np.nan, 0.5], T) == ""


@pytest.mark.parametrize("rel, want", [
    # (signed distance of each line's gap from the best fit, in units of that line's admissible interval)
    ({"Ixx": -0.03, "Izz": 0.01}, "Izz"),
    ({"Ixx": 0.04, "Izz": 0.05}, "Ixx"),
])
def test_of_two_lines_with_a_gap_the_one_nearest_the_best_fit_relative_to_its_interval_is_named(
        monkeypatch, rel, want):
    """surface_hint's rule: of the unknowns' lines with a gap whose partner
    has a root, the gap nearest the best fit relative to the line's
    admissible interval ``(scan.a, scan.b)`` is named.  Both a03 lines
    (Ixx, Izz) are given a hand-placed gap (``_gap_partner`` replaced; the
    scans, their intervals and their no-root check are the real ones: neither
    line reaches 1.88117 s), at the relative distances ``rel``; the answer is
    the smaller ``|rel|``, by hand.  Case 1 kills crossing_partner 34
    (``0.5 * (xa + xb) -> 1.0 *``), 36 (``xa + xb -> xa - xb``), 37 (``- p[i]
    -> + p[i]``); case 2 (the absolute distances 1.25 : 1, the intervals
    1.56 : 1) kills 35 (``0.5 * -> 0.5 /``) and 38 (``/ (b - a) -> *``)."""
    from bifilar.estimation import crossing_partner as cp

    pb, p = _two_unknowns()
    best = dict(zip(pb.unknowns, p))
    seen = {}

    def placed(scan, target):
        w = scan.b - scan.a
        mid = best[scan.name] + rel[scan.name] * w
        seen[scan.name] = (scan.a, scan.b)
        return cp._Gap(mid - 1e-9, mid + 1e-9, 1.8745, 1.8840, ["swing-x"], {"swing-x": [mid]}, {"swing-x": None})

    monkeypatch.setattr(cp, "_gap_partner", placed)
    msg = cp.surface_hint(pb, p, [14.6, 0.1], [T_TORSION, T_ROLL])
    assert set(seen) == {"Ixx", "Izz"}  # both lines scanned, both with a gap
    assert msg.startswith(f"; at the best fit no {want} gives the mode labelled 'torsion' 1.88117 s"), msg



def test_several_unknowns_whose_partner_reading_is_refused_quote_its_first_clause():
    """_surface_message: where the partner reading of several unknowns is
    refused, the refusal says so and quotes that refusal's first clause
    (no value, and no ACROSS caution: there is no answer to distrust).  The
    a03 gap of tests/test_partner28.py's exchange-only test, its partner
    given a root on the line this time.  Kills crossing_partner 49 (the
    clause's ``+ -> -``: a TypeError), a line no test ran (uncovered)."""
    from bifilar.estimation import crossing_partner as cp

    pb, p = _two_unknowns()
    g = cp._Gap(0.1024, 0.1025, 1.8745, 1.8840, ["swing-x"], {"swing-x": [0.1011]}, {"swing-x": None})
    msg = cp._surface_message(pb, p, 0, "Izz", g, T_TORSION, lambda rl: (None, "--period: no tensor here; more"))
    assert msg.endswith(f"(--period swing-x={T_TORSION}+-0.0005); read so, they are refused as well "
                        "(--period: no tensor here)")
    assert cp.ACROSS not in msg


# ---------------------------------------------------------------------------
# estimation/signal_harmonic2.py (camera28)
# ---------------------------------------------------------------------------

def _three_mode_fit(order):
    """A hand-made three_mode fit over 3 s (3 periods of a 1 Hz dominant
    mode, so ``half = pi / 3 s`` is 1/6 of omega1): further modes at 0.38
    and 0.62 omega1, both 2nd harmonics (0.76, 1.24 omega1) within the 0.25
    band.  The 0.38 one's harmonic has the 0.62 mode within ``half`` of it
    (floor 0: a fitted mode models it, no leakage); the 0.62 one's has
    none (the noise floor and the leakage).  ``order``: which further mode
    comes first in the parameters.  Residuals: white noise and a 1.24
    omega1 term."""
    w1 = 2 * math.pi
    further = {"lo": [0.3, 0.2, 0.38 * w1, 0.05], "hi": [0.2, -0.1, 0.62 * w1, 0.05]}
    t = np.linspace(0.0, 3.0, 301)
    r = 0.01 * np.random.default_rng(3).standard_normal(t.size) + 0.05 * np.cos(1.24 * w1 * t + 0.7)
    p = np.array([0.0, 0.0, 1.0, 0.0, w1, 0.05] + further[order[0]] + further[order[1]])
    return types.SimpleNamespace(params=p, t_used=t, residuals=r, covariance=np.eye(p.size), _kind="three_mode",
                                 t0=0.0, t_ref=1.5, std_inflation=1.0, uncertainty={}, notes=[])


def test_the_harmonic_term_is_the_largest_over_the_further_modes_in_either_order():
    """second_harmonic_term is "the largest bias estimate over the further
    modes": a maximum over a set, so swapping the two further modes'
    parameter blocks (the same model, its Jacobian's columns permuted)
    leaves the term and the harmonic it names unchanged (to the lstsq's
    rounding, 1e-6 relative).  Of the two candidates here, the one without
    a leakage (floor 0) is not the largest.  Kills signal_harmonic2 100
    (the comparison's ``leak.get("leakage", 0.0) -> 1``: a candidate
    without a leakage then replaces a larger one found before it, so the
    term depends on the order)."""
    from bifilar.estimation import signal_harmonic2 as sh

    got = []
    for order in (("lo", "hi"), ("hi", "lo")):
        fit = _three_mode_fit(order)
        got.append((sh.second_harmonic_term(fit), fit.uncertainty["second_harmonic_fit"]))
    (a, ha), (b, hb) = got
    assert a > 0 and b == pytest.approx(a, rel=1e-6)
    assert ha["frequency"] == pytest.approx(1.24, rel=1e-12) == hb["frequency"]
    assert ha["floor"] == hb["floor"] == sh.NOISE_FLOOR


# ---------------------------------------------------------------------------
# estimation/second_order.py (fixed28: the stacked surrogates)
# ---------------------------------------------------------------------------

def test_an_input_whose_sigma_point_fails_on_either_side_alone_is_returned_as_failed(monkeypatch):
    """second_order returns "the keys whose sigma points cannot hang": an
    input fails when either of its two sigma points does.  Three inputs of
    one unknown: 'a' with its +sigma point unsolvable, 'b' its -sigma point,
    'c' both solved on an exactly linear response (p = p0 +- sqrt(3) c, the
    linear budget's contribution c = 2e-3: no 2nd order, so the linear budget
    itself comes back, identical).  ``_solve_points`` is replaced by that
    table (the sigma points' solves are not what is tested).  Kills
    second_order 221 (``or -> and``: 'a' and 'b' taken as solved, their None
    stacked) and 222 (the -1 side read as the +1 side: 'b' taken as solved)."""
    from bifilar.estimation import second_order as so
    from bifilar.estimation.uncertainty import LinearBudget

    p0, c = np.array([0.1]), 2e-3
    h = so.SIGMA_POINT
    table = {("a", 1): None, ("a", -1): p0 - h * c, ("b", 1): p0 + h * c, ("b", -1): None,
             ("c", 1): p0 + h * c, ("c", -1): p0 - h * c}
    monkeypatch.setattr(so, "_solve_points", lambda pb, ctx, p_hat, r_hat, points: {k: table[k] for k in points})
    ctx = types.SimpleNamespace(inputs=["a", "b", "c"], sigmas={"a": 1.0, "b": 1.0, "c": 1.0}, modes=[],
                                factor_shift={}, amplitude={}, cross=None, surrogate=None, nonlinear=None)
    contrib = {"a": np.array([1e-3]), "b": np.array([1e-3]), "c": np.array([c])}
    lin = LinearBudget(["Izz"], np.array([[sum(float(v[0]) ** 2 for v in contrib.values())]]), contrib)
    got, failed = so.second_order(types.SimpleNamespace(unknowns=["Izz"]), p0, None, ctx, lin)
    assert failed == ["a", "b"]
    assert got is lin and ctx.surrogate == {}



# ---------------------------------------------------------------------------
# estimation/budget.py (shift28: interval_95's hull of its two readings)
# ---------------------------------------------------------------------------

def test_the_unstated_amplitudes_term_keeps_its_sign_in_both_readings():
    """interval_95: "the unstated amplitude's term keeps its sign" (an
    assumed release distribution, independent of the inputs), in the
    mirrored reading and in the one as built alike.  One second-order input
    too small to matter (a = 1e-9, b = 0) beside an unstated amplitude's
    term ``D u``, u = U^2 with U uniform on (0, 1) (no law: the quadratic
    weight): the interval is then that term's own 2.5-97.5 % quantiles,
    ``D 0.025^2 .. D 0.975^2`` (0.000625 D .. 0.9506 D), all on D's side.
    The 20000 samples put U's 2.5 % point within ~4 % (its sampling std
    sqrt(0.025 0.975 / 20000) = 0.0011), so the lower end within 1e-3 D of
    0 and the upper within 1 %.  Kills budget 61 (``post + rest -> post -
    rest``: the as-built reading's term flipped, the lower end -0.95 D)."""
    from bifilar.estimation.budget import BudgetContext, interval_95
    from bifilar.estimation.uncertainty import LinearBudget, covariance_of

    A, B, D = np.array([1e-9]), np.array([0.0]), np.array([2e-3])
    contrib = {"com.z": A, "com.z (2nd order)": math.sqrt(2) * B, "amplitude[torsion]": D * math.sqrt(4 / 45)}
    budget = LinearBudget(["Izz"], covariance_of(contrib, 1), contrib)
    ctx = BudgetContext(["com.z"], {"com.z": 1.0}, np.ones((1, 1)), np.ones(1), [], [], [], [], [],
                        surrogate={"com.z": (A, B)}, amplitude={"torsion": D})
    lo, hi = interval_95(np.zeros(1), budget, ctx)[0]
    assert abs(lo - D[0] * 0.025 ** 2) < 1e-3 * D[0], lo
    assert hi == pytest.approx(D[0] * 0.975 ** 2, rel=0.01)


# ---------------------------------------------------------------------------
# studies/point_amplitude.py (runs28: the refining rerun's known starts)
# ---------------------------------------------------------------------------

def test_the_refining_rerun_takes_known_starts_only_where_both_sides_solved_them():
    """_known_starts' documented rule: the start poses where the point
    solved them already, None where it did not -- the point's own
    (``pre.starts``) or the law's (``law.starts``, a law planned without the
    point's runs) -- so that simulate_batch solves them.  Either one missing
    gives None, not a half-built list.  Kills point_amplitude 86 (the first
    ``or -> and``: ``pre.starts`` None read through)."""
    from bifilar.studies import point_amplitude as pa

    class Starts:  # a StartPoses stand-in that says when it is read
        def take(self, rows):
            raise AssertionError("read")

    rows = [(0, 3)]
    assert pa._known_starts(types.SimpleNamespace(starts=None, runs=[0]), types.SimpleNamespace(starts=Starts()),
                            rows) is None
    assert pa._known_starts(types.SimpleNamespace(starts=Starts(), runs=[0]), types.SimpleNamespace(starts=None),
                            rows) is None
    assert pa._known_starts(types.SimpleNamespace(starts=Starts(), runs=[1]), types.SimpleNamespace(starts=Starts()),
                            rows) is None  # mode 0's own run not among the point's runs


def test_the_second_order_std_counts_the_mean_offset_squared(monkeypatch):
    """The sigma-point check's variance (module docstring): each input's
    linear term ``a`` and 2nd-order term ``sqrt(2) b`` in quadrature, plus
    the mean offset ``(sum b)^2``: one input with ``a`` = 1.008923e-3 and
    ``b`` = 0.095e-3 (its sigma points ``p0 +- sqrt(3) a + 3 b``) against a
    linear contribution of 1e-3 gives ``a^2 + 3 b^2`` = 1.045e-6, a std
    1.02225e-3: 2.2 % above the linear one, past LINEAR_ENOUGH (2 %), with
    the offset 0.095 std under OFFSET_ENOUGH (0.1).  So the budget comes
    back second-order, with that std (by hand) and the offset as a term.
    ``_pair_terms`` (the cross terms, which need a real problem) is
    replaced by zeros.  Kills second_order 230 (``+ offset ** 2 -> -``: 1.027e-6,
    1.3 % above, and the linear budget comes back)."""
    from bifilar.estimation import second_order as so
    from bifilar.estimation.uncertainty import LinearBudget

    p0, a, b = np.array([0.1]), 1.008923e-3, 0.095e-3
    h = so.SIGMA_POINT
    table = {("c", 1): p0 + h * a + 3 * b, ("c", -1): p0 - h * a + 3 * b}
    monkeypatch.setattr(so, "_solve_points", lambda pb, ctx, p_hat, r_hat, points: {k: table[k] for k in points})
    monkeypatch.setattr(so, "_pair_terms", lambda pb, ctx, p_hat, r_hat, sol, contrib, std1: np.zeros(1))
    ctx = types.SimpleNamespace(inputs=["c"], sigmas={"c": 1.0}, modes=[], factor_shift={}, amplitude={},
                                cross=None, surrogate=None, nonlinear=None)
    lin = LinearBudget(["Izz"], np.array([[1e-6]]), {"c": np.array([1e-3])})
    got, failed = so.second_order(types.SimpleNamespace(unknowns=["Izz"]), p0, None, ctx, lin)
    assert failed == [] and got is not lin and list(ctx.surrogate) == ["c"]
    assert math.sqrt(got.covariance[0, 0]) == pytest.approx(math.sqrt(a * a + 3 * b * b), rel=1e-9)
    assert got.contributions["offset"][0] == pytest.approx(b, rel=1e-9)
