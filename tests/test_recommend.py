"""The recommendation rule (bifilar/studies/recommend.py) on hand-worked
tables of made-up points: which point `sweep` recommends (assess) and
`plan` answers (choose), both by one rule.  The expected answers are worked
out by hand in each test's comment from the rule as documented
(README "sweep"; ranking.rank_order): the smallest objective (the target's
relative sigma, else the worst of the components measurable somewhere)
among the points that meet every limit; a point whose dependent wires may
carry more than --max-tension yields to one without that within
ranking.EQUAL_REL (2 %) of its objective; a point whose body reaches the
ceiling or whose wires cross at rest goes after every clean one."""

from __future__ import annotations

import pytest

from bifilar.studies.recommend import (add_point_remedies, assess, cautioned, choose, identifiability,
                                       reference_point)
from bifilar.studies.settings import Constraints


def pt(x, sig, peak=10.0, range_peak=None, depth=1.5, sep=0.2, valid=True, **flags):
    """A point at parameter ``spacing = x`` whose components have the relative sigmas ``sig``
    ({comp: rel or None: not identifiable}), peak tension ``peak`` N (``range_peak``: what statics lets a
    dependent wire reach, N), depth ``depth`` m and mode separation ``sep``."""
    comps = {c: {"rel_sigma": r, "identifiable": r is not None, "mode": "torsion" if c == "Izz" else "swing",
                 "sigma": None if r is None else r * 0.1} for c, r in sig.items()}
    t = {"peak": peak, "range_peak": range_peak}
    if range_peak is not None:
        t.update(range=[[0.0, range_peak * 0.8]], range_peak_wire=1)
    return {"params": {"spacing": x}, "valid": valid, "components": comps, "tension": t, "depth": {"max": depth},
            "separation": sep, **flags}


def test_smallest_worst_component_among_the_feasible_points():
    # worst of (Ixx, Izz): P0 1.0 %, P1 0.8 %, P2 0.7 % but its peak 120 N breaks --max-tension 100:
    # P1 recommended, then P0; P2 infeasible, unranked
    pts = [pt(1.0, {"Ixx": 0.010, "Izz": 0.005}), pt(2.0, {"Ixx": 0.006, "Izz": 0.008}),
           pt(3.0, {"Ixx": 0.007, "Izz": 0.006}, peak=120.0)]
    doc = assess(pts, Constraints(max_tension=100.0), None)
    assert doc["best"] == 1 and doc["ranking"] == [1, 0]
    assert [p["rank"] for p in pts] == [2, 1, None] and [p["feasible"] for p in pts] == [True, True, False]
    assert pts[2]["violations"] == ["peak tension 120 N > 100 N"]
    assert doc["objective"] == pytest.approx(0.008) and doc["params"] == {"spacing": 2.0}
    assert (doc["n_valid"], doc["n_feasible"]) == (3, 2) and doc["measurable"] == ["Ixx", "Izz"]
    assert doc["why"][0] == ("lowest predicted uncertainty of the worst measurable component: Izz +- 0.8 % "
                             "(from the torsion mode)")
    # the target Ixx alone: P1 0.6 % < P0 1.0 %; Izz alone: P0 0.5 % < P1 0.8 %
    assert assess(pts, Constraints(max_tension=100.0), "Ixx")["best"] == 1
    assert assess(pts, Constraints(max_tension=100.0), "Izz")["best"] == 0
    # no limit: P2 (worst 0.7 %) is best
    assert assess(pts, Constraints(), None)["best"] == 2


def test_a_component_no_point_measures_does_not_block_the_others():
    # Iyy identifiable nowhere: left out of the objective (worst of Ixx, Izz: P0 1.2 %, P1 0.9 %) and named
    pts = [pt(1.0, {"Ixx": 0.012, "Iyy": None, "Izz": 0.004}), pt(2.0, {"Ixx": 0.009, "Iyy": None, "Izz": 0.003})]
    doc = assess(pts, Constraints(), None)
    assert doc["best"] == 1 and doc["measurable"] == ["Ixx", "Izz"] and doc["not_measurable"] == ["Iyy"]
    assert doc["target"] == "worst relative of Ixx, Izz"
    assert doc["identifiability"]["Iyy"] == {"identifiable": False, "from_modes": {}, "mode": "swing", "remedy": None,
                                             "rel_sigma": None, "set_aside": None, "marginal": None}
    # the target Iyy: no point gives it, nothing recommended, --target named
    doc = assess(pts, Constraints(), "Iyy")
    assert doc["best"] is None and doc["binding"] == "--target"


@pytest.mark.parametrize("scale, best", [(0.98, 0), (1.0, 0), (1.02, 2)])
def test_a_component_whose_best_sigma_is_above_the_threshold_is_set_aside(scale, best):
    # Iyy's best relative sigma over the range is P0's, scale x USEFUL_REL (50 %); P1 gives it 90 %, P2 none.
    # Within the threshold (0.98 x, and exactly at it: "exceeds" is strict) Iyy counts: the worst components
    # are P0 49-50 %, P1 90 %, P2 inf (no Iyy), P0 recommended.  Above it (1.02 x: 51 %) Iyy is set aside and
    # the worst of Ixx, Izz decides: P0 10 %, P1 5 %, P2 2 %, P2 recommended.  The threshold applied to Iyy's
    # worst point (90 %) would set it aside in every case, the comparison inverted only in the first two.
    from bifilar.studies.ranking import USEFUL_REL

    rel = scale * USEFUL_REL
    pts = [pt(1.0, {"Ixx": 0.10, "Iyy": rel, "Izz": 0.10}), pt(2.0, {"Ixx": 0.05, "Iyy": 0.90, "Izz": 0.05}),
           pt(3.0, {"Ixx": 0.02, "Iyy": None, "Izz": 0.02})]
    doc = assess(pts, Constraints(), None)
    assert doc["best"] == best, doc
    aside = doc["set_aside"]
    if best == 0:
        assert aside == [] and doc["measurable"] == ["Ixx", "Iyy", "Izz"] and doc["objective"] == rel
        assert doc["identifiability"]["Iyy"]["set_aside"] is None
    else:
        assert doc["measurable"] == ["Ixx", "Izz"] and doc["not_measurable"] == [] and doc["objective"] == 0.02
        assert [(a["component"], a["best_rel_sigma"], a["params"]) for a in aside] == [("Iyy", rel, {"spacing": 1.0})]
        assert aside[0]["reason"] == (
            "Iyy is not measurable in this range: its smallest uncertainty is +- 51 % (at spacing = 1), above the "
            "50 % a measurement must beat to say more than a guess; it is left out of the ranking: leave Iyy out "
            "of --component, add --hangings, or rank by it with --target Iyy")
        assert doc["identifiability"]["Iyy"]["set_aside"] == aside[0] and doc["identifiability"]["Iyy"]["identifiable"]
        from rich.console import Console

        from bifilar.cli.cmd_sweep import render_identifiability

        con = Console(record=True, width=400)
        render_identifiability(con, doc["identifiability"])  # the table's lines (sweep and plan)
        assert con.export_text().splitlines()[1] == "  Iyy: set aside: " + aside[0]["reason"].split(": ", 1)[1]
        # plan answers by the same rule (choose, on the components the search found measurable)
        assert choose([pts[1], pts[2]], Constraints(), None, doc["measurable"])[0]["params"] == {"spacing": 3.0}
    # a target is ranked by itself, never set aside: Iyy P0 (scale x 50 %) before P1 (90 %)
    doc = assess(pts, Constraints(), "Iyy")
    assert doc["best"] == 0 and doc["set_aside"] == []
    # every component set aside (--component Iyy alone): nothing recommended, --component named with the reason
    only = [pt(x, {"Iyy": p["components"]["Iyy"]["rel_sigma"]}) for x, p in zip((1.0, 2.0, 3.0), pts)]
    doc = assess(only, Constraints(), None)
    if best == 0:
        assert doc["best"] == 0
    else:
        assert doc["best"] is None and doc["binding"] == "--component"
        assert doc["reason"] == "no component is measurable in this range: " + aside[0]["reason"]


@pytest.mark.parametrize("rival, best", [(0.0101, 1), (0.0103, 0)])
def test_a_cautioned_point_yields_within_two_percent(rival, best):
    # P0 1.00 % but a dependent wire may reach 49 N under --max-tension 40 (its model split peaks at 30 N);
    # P1 uncautioned at 1.01 % (1 % worse: within EQUAL_REL, P1 first, P0 'preferred over') or 1.03 % (3 %:
    # the figures tell them apart, P0 first)
    pts = [pt(1.0, {"Izz": 0.0100}, peak=30.0, range_peak=49.0), pt(2.0, {"Izz": rival}, peak=30.0)]
    c = Constraints(max_tension=40.0)
    assert cautioned(c)(pts[0]) and not cautioned(c)(pts[1])
    doc = assess(pts, c, "Izz")
    assert doc["best"] == best and all(p["feasible"] for p in pts)
    opt, over, why = choose(pts, c, "Izz", ["Izz"])  # plan's optimum: the same rule
    assert opt["params"] == pts[best]["params"] and opt["objective"] == pytest.approx(pts[best]["components"]
                                                                                      ["Izz"]["rel_sigma"])
    if best == 1:
        assert over == [{"params": {"spacing": 1.0}, "objective": 0.01, "reason": "tension_range_caution"}]
        assert why.startswith("preferred to spacing = 1, whose predicted uncertainty is 0.99 % lower")  # 1 - 1/1.01
        assert doc["preferred_over"][0]["index"] == 0
    else:
        assert over == [] and why is None


def test_a_point_whose_body_reaches_the_ceiling_goes_after_every_clean_one():
    # P0 0.5 % with its body through the ceiling at rest, P1 0.9 %, P2 0.7 % (wires cross): the clean
    # point first (P1), then the clashing ones by objective (P0 0.5 %, P2 0.7 %)
    pts = [pt(1.0, {"Izz": 0.005}, ceiling_clash=True), pt(2.0, {"Izz": 0.009}), pt(3.0, {"Izz": 0.007},
                                                                                  wires_cross=True)]
    doc = assess(pts, Constraints(), "Izz")
    assert doc["ranking"] == [1, 0, 2]
    opt, over, why = choose(pts, Constraints(), "Izz", ["Izz"])
    assert opt["params"] == {"spacing": 2.0}
    assert [o["reason"] for o in over] == ["ceiling_clash", "wires_cross"]


def test_equal_objectives_tie_on_the_other_components_then_the_parameters():
    # worst component 1.0 % at both; the other component 0.4 % at P1 against 0.6 % at P0: P1 first.
    # All equal: the smaller parameter first
    pts = [pt(1.0, {"Ixx": 0.010, "Izz": 0.006}), pt(2.0, {"Ixx": 0.010, "Izz": 0.004})]
    assert assess(pts, Constraints(), None)["ranking"] == [1, 0]
    pts = [pt(2.0, {"Izz": 0.010}), pt(1.0, {"Izz": 0.010})]
    assert assess(pts, Constraints(), None)["ranking"] == [1, 0]


def test_no_feasible_point_names_the_binding_limit():
    # peaks 120 and 150 N under --max-tension 100: the lowest found is 120 N
    pts = [pt(1.0, {"Izz": 0.01}, peak=150.0), pt(2.0, {"Izz": 0.02}, peak=120.0)]
    doc = assess(pts, Constraints(max_tension=100.0), None)
    assert doc["best"] is None and doc["binding"] == "--max-tension"
    assert doc["reason"] == "no configuration meets --max-tension 100 N: the lowest peak tension found is 120 N"


def test_remedies_are_evaluated_at_the_recommended_or_first_valid_point():
    pts = [pt(1.0, {"Izz": 0.01}, valid=False), pt(2.0, {"Izz": 0.02}), pt(3.0, {"Izz": 0.03})]
    assert reference_point({"best": 2}, pts) is pts[2]
    assert reference_point({"best": None}, pts) is pts[1]
    assert reference_point({}, [pts[0]]) is None
    doc = {"identifiability": {"Izz": identifiability("Izz", pts[1], True)}}
    before = repr(doc)
    add_point_remedies(doc, [], pts[1], {}, "x", None)  # nothing to remedy: nothing evaluated or added
    add_point_remedies(doc, ["Izz"], None, {}, "x", None)  # no point to evaluate at
    assert repr(doc) == before
