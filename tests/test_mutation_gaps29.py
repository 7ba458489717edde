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
