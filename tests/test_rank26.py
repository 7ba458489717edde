"""The sweep / plan ranking's gaps rank25 left (docs/design.md, "rank26,
session 26"): a set-aside component's mode and the separation guard, its
advice, the reason quoted in the binding message, and the components ranked
or set aside close to the 50 % line.

The real points are audit24's c04 (a 30 g part on a bifilar) on screens, as
tests/test_sweep_audit24.py evaluates them (linear sigmas: the same ranking
code); the others are hand-made, as that file and
tests/test_mutation_gaps25.py build them.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bifilar.studies import sweep as sw
from bifilar.studies.ranking import USEFUL_REL, binding_constraint, marginal, point_separation
from bifilar.studies.recommend import remedy_clause, unmeasured

DATA = Path(__file__).parent / "data" / "audit24"


@pytest.fixture(scope="module")
def c04():
    """c04 at spacing 0.04 (Iyy from a swing 1.2 % from the other swing, +- 1490 %)
    and 0.06 (wires vertical: no Iyy): screens, --no-tensions."""
    from bifilar.config import read_yaml

    path = str(DATA / "c04_dronepart.yaml")
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, tensions=False)
    return cfg, path, st, sw.run_sweep(cfg, path, [{"spacing": v} for v in (0.04, 0.06)], st, screen=True)


def _gap(p, comps):
    """The smallest |T_k - T_j| / T_k over the modes k of ``comps`` at point ``p`` and every other mode j,
    worked out from the point's periods (not from the figures the guard reads)."""
    T = p["periods"]
    ks = {p["components"][c]["mode"] for c in comps if p["components"][c].get("mode")}
    return min(abs(T[k] - T[j]) / T[k] for k in ks for j in T if j != k)


def test_the_guard_leaves_out_the_mode_only_a_set_aside_component_needs(c04):
    """Item 1.  Iyy is set aside (best 1490 % > 50 %), so nobody times its
    swing: the guard is over Ixx's roll and Izz's torsion only, and 0.04,
    ruled out for Iyy's swing (1.18 % < 2 %), is feasible (guard 5.4 %).
    Fails with the guard over every component's mode (main), in the sweep's
    assessment or in plan's search penalty."""
    _, _, _, pts = c04
    rec = sw.assess(pts, sw.Constraints(min_separation=0.02), None)
    assert rec["measurable"] == ["Ixx", "Izz"] and [a["component"] for a in rec["set_aside"]] == ["Iyy"]
    for p in pts:
        assert p["guard_separation"] == pytest.approx(_gap(p, ["Ixx", "Izz"]), rel=1e-12)
    assert [p["feasible"] for p in pts] == [True, True], [p["violations"] for p in pts]
    # the old guard's figure (every timed mode, Iyy's swing included) is below the limit at 0.04
    assert _gap(pts[0], ["Ixx", "Iyy", "Izz"]) < 0.02 < pts[0]["guard_separation"]
    # the ranking is the measurable components' worst, unchanged: 0.06 first by a hair (Ixx 42.9 % everywhere)
    assert rec["params"] == {"spacing": 0.06} and rec["separation"] == pytest.approx(_gap(pts[1], ["Ixx", "Izz"]))
    # plan's search penalty counts the same modes: no excess at 0.04 with the ranked components, a penalty with all
    from bifilar.studies.plan import _penalty

    c = sw.Constraints(min_separation=0.02)
    ob = sum(pts[0]["components"][k]["rel_sigma"] ** 16 for k in ("Ixx", "Izz")) ** (1 / 16)  # its 16-norm
    assert _penalty(pts[0], c, None, ["Ixx", "Izz"]) == pytest.approx(ob, rel=1e-12)
    assert _penalty(pts[0], c, None, None) > 2 * _penalty(pts[0], c, None, ["Ixx", "Izz"])


def _point(x, comps):
    """A hand-made point: ``comps`` {name: (rel_sigma, mode, its separation)}."""
    return {"params": {"spacing": x}, "valid": True, "error": None,
            "components": {k: {"identifiable": True, "rel_sigma": r, "mode": m, "separation": s,
                               "shares": {"timing": 1.0}} for k, (r, m, s) in comps.items()},
            "separation": min(s for _, _, s in comps.values()),
            "tension": {"rest": [1.0], "peak": 1.0, "min": [0.5], "max": [1.0], "slack": False, "slack_wires": []},
            "depth": {"rest": 1.0, "max": 1.0}}


def test_a_mode_a_ranked_component_shares_with_a_set_aside_one_stays_guarded():
    """Item 1's other half: Ixx and the set-aside Iyy (90 %, 80 %) from one
    swing 1 % from another mode: the swing is timed for Ixx, so both points
    break --min-separation 0.02 and the message gives 1 %; with Ixx from the
    roll (5 %) and only Iyy on the close swing, both are feasible.  Fails
    with the guard over every mode, and where it drops every mode a
    set-aside component is estimated from."""
    c = sw.Constraints(min_separation=0.02)
    shared = [_point(x, {"Ixx": (0.1, "swing", 0.01), "Iyy": (r, "swing", 0.01), "Izz": (0.05, "torsion", 0.3)})
              for x, r in ((1.0, 0.9), (2.0, 0.8))]
    rec = sw.assess(shared, c, None)
    assert rec["measurable"] == ["Ixx", "Izz"] and rec["n_feasible"] == 0, rec
    assert rec["reason"] == "no configuration meets --min-separation 0.02: the best mode separation found is 0.01"
    own = [_point(x, {"Ixx": (0.1, "roll", 0.05), "Iyy": (r, "swing", 0.01), "Izz": (0.05, "torsion", 0.3)})
           for x, r in ((1.0, 0.9), (2.0, 0.8))]
    rec = sw.assess(own, c, None)
    assert rec["n_feasible"] == 2 and rec["separation"] == 0.05, rec
    assert point_separation(own[0]) == 0.01 and point_separation(own[0], ["Ixx", "Izz"]) == 0.05


def test_the_binding_message_quotes_the_points_reason_as_the_table_cuts_it():
    """Item 3: json25's points (the middle one meets every limit, Izz without a
    sigma); the message quotes that point's own reason, without "the
    uncertainty cannot be given", cut at 160 characters with "..." as the
    sweep table's note is: the dependent-wire text (592 characters) and the
    knife edge's whole (short) one; a point not identifiable quotes its
    ``reason``.  Fails without the quote or with another cut."""
    from bifilar.estimation.inversion_result import std_unavailable_text

    c = sw.Constraints(min_separation=0.02)
    long_ = std_unavailable_text(["rig.anchors.0.x"], "--sigma KEY=VALUE", True)
    for entry, quoted in (
            ({"sigma_unavailable": long_}, long_.removeprefix("the uncertainty cannot be given")[:157].rstrip() + "..."),
            ({"sigma_unavailable": "mode 'torsion' at 2.5 rad runs 3 x its linear period: no sigma"},
             ": mode 'torsion' at 2.5 rad runs 3 x its linear period: no sigma"),
            ({"reason": "no mode's period depends on Izz (max |d ln T / d ln Izz| = 1.0e-12)"},
             ": no mode's period depends on Izz (max |d ln T / d ln Izz| = 1.0e-12)")):
        pts = [_point(0.04, {"Ixx": (0.004, "roll", 0.0118), "Izz": (0.003, "torsion", 0.5)}),
               _point(0.06, {"Ixx": (0.004, "roll", 0.299), "Izz": (math.inf, "torsion", 0.5)}),
               _point(0.08, {"Ixx": (0.004, "roll", 0.0033), "Izz": (0.003, "torsion", 0.5)})]
        pts[1]["components"]["Izz"].update(entry)
        flag, msg = binding_constraint(pts, c, None, ["Ixx", "Izz"])
        assert flag == "--min-separation"
        assert msg.endswith(f"give no uncertainty for Izz (e.g. at spacing = 0.06; Izz{quoted}): leave Izz out of "
                            "--component, or add --hangings"), msg
    assert len(quoted) < 160 and len(long_) > 500


def _best(**rels):
    return {"params": {"spacing": 1.0}, "components": {k: {"rel_sigma": v} for k, v in rels.items()}}


def test_a_component_ranked_or_set_aside_near_the_line_is_marginal():
    """Item 4: within 20 % of the 50 % line (40-60 %, ends included): a ranked
    component by its figure at the recommended point (c11's plan: Iyy 49.3 %
    there), a set-aside one by its best.  Ranked: 0.399 no, 0.4 and 0.493
    yes, the target never; set aside: 0.6 yes, 0.601 no.  Fails with a band
    of 10 % or a strict end (either side)."""
    aside = [{"component": "Ixz", "best_rel_sigma": 0.6, "params": {"spacing": 2.0}},
             {"component": "Iyz", "best_rel_sigma": 0.601, "params": {"spacing": 3.0}}]
    best = _best(Ixx=0.399, Iyy=0.493, Izz=0.4, Ixy=0.45)
    m = marginal(best, ["Ixx", "Iyy", "Izz", "Ixy"], aside, target="Ixy")
    assert [(e["component"], e["ranked"], e["rel_sigma"], e["params"]) for e in m] == [
        ("Iyy", True, 0.493, {"spacing": 1.0}), ("Izz", True, 0.4, {"spacing": 1.0}),
        ("Ixz", False, 0.6, {"spacing": 2.0})]
    assert m[0]["reason"].startswith("Iyy is marginal: its uncertainty at the recommended point, +- 49.3 %, is within "
                                     "20 % of the 50 % line")
    assert "(at spacing = 2)" in m[2]["reason"] and "--target Ixz" in m[2]["reason"]
    # in the sweep's document, beside an unchanged ranking: Iyy's best is 0.3 elsewhere, 0.45 at the best point
    pts = [_point(x, {"Ixx": (0.1, "roll", 0.5), "Iyy": (r, "swing", 0.5)}) for x, r in ((1.0, 0.45), (2.0, 0.3))]
    pts[1]["components"]["Ixx"]["rel_sigma"] = 0.5
    rec = sw.assess(pts, sw.Constraints(), None)
    assert rec["best"] == 0 and rec["measurable"] == ["Ixx", "Iyy"] and rec["set_aside"] == []
    assert [e["component"] for e in rec["marginal"]] == ["Iyy"] and rec["marginal"][0]["rel_sigma"] == 0.45
    assert rec["identifiability"]["Iyy"]["marginal"] == rec["marginal"][0]
    assert rec["identifiability"]["Ixx"]["marginal"] is None


def test_a_set_aside_component_gets_the_advice_a_non_identifiable_one_gets(c04):
    """Item 2: the components the point cannot measure in its own hanging (their
    remedies and the multi-hanging plan at the point, which the CLI starts
    for them) are the non-identifiable and the set-aside ones.  c04's Iyy
    (set aside) at the recommended spacing 0.06: the remedies find the body
    turned 90 deg about x, whose torsion measures it (+- 3.3 %), and the
    line says so; a set-aside component whose best remedy stays above 50 %
    is told that no change tried measures it.  Fails with unmeasured() as
    on main (non-identifiable only)."""
    cfg, path, st, pts = c04
    rec = sw.assess(pts, sw.Constraints(min_separation=0.02), None)
    assert unmeasured(rec) == ["Iyy"] and rec["not_measurable"] == []
    from bifilar.studies.recommend import add_point_remedies

    add_point_remedies(rec, unmeasured(rec), pts[rec["best"]], cfg, path, st)
    e = rec["identifiability"]["Iyy"]
    r = e["remedy"]
    assert r["kind"] == "hanging" and r["mode"] == "torsion" and r["rel_sigma"] < 0.05, r
    assert remedy_clause(e) == f"; remedy: {r['text']}"
    worse = {**e, "remedy": {**r, "rel_sigma": 1.01 * USEFUL_REL, "text": "T"}}
    assert remedy_clause(worse) == "; none of the changes tried measures it to 50 % (the best: T)"
    # a non-identifiable one keeps its words; a set-aside one whose remedies were not looked for gets none
    assert remedy_clause({"identifiable": False, "remedy": None}) == "; the model found no remedy among the changes tried"
    assert remedy_clause({"identifiable": True, "set_aside": {"component": "Iyy"}, "remedy": None}) == ""
    doc = {"identifiability": {"Ixx": {"identifiable": True, "set_aside": None},
                               "Iyy": {"identifiable": True, "set_aside": {"component": "Iyy"}},
                               "Izz": {"identifiable": False, "set_aside": None}}}
    assert unmeasured(doc) == ["Iyy", "Izz"]


def test_the_multi_hanging_plan_cautions_where_the_points_sigma_is_second_order(c04):
    """The plan the set-aside advice starts has linear sigmas (hangings.py has
    no second-order check): c04's full point at 0.06 gives Izz +- 25.1 %,
    98.2 % of its variance second order, 3.34 % linear, and the plan 3.34 %.
    The caution names the component with the largest factor
    1 / sqrt(1 - second_order share): 0.17 gives 1.098 (no caution, the
    limit 1.1), 0.18 gives 1.104; a component the plan does not predict is
    passed over.  hangings_at_point gives it for its point.  Fails without
    the call or with the share taken as the linear part."""
    from bifilar.studies.point_hangings import LINEAR_CAUTION, hangings_at_point, linear_caution

    def pt(**shares):
        return {"components": {c: {"rel_sigma": 0.25, "shares": {"timing": 1 - s, "second_order": s}}
                               for c, s in shares.items()}}

    doc = {"accuracy": {"Ixx": {}, "Izz": {}}}
    assert linear_caution(pt(Izz=0.17), doc, "P") is None and 1 / math.sqrt(0.83) < LINEAR_CAUTION
    w = linear_caution(pt(Ixx=0.18, Izz=0.9823, Iyy=0.999), doc, "P")
    assert w.startswith("P: the multi-hanging plan's sigmas are linear") and "98.2 % of Izz's variance" in w, w
    assert w.endswith(f"+- 25 % against +- {25 * math.sqrt(1 - 0.9823):.3g} % linear (7.52x); the plan's figures "
                      "can be as optimistic"), w
    assert "Ixx's variance" in linear_caution(pt(Ixx=0.18, Iyy=0.9823), doc, "P")
    cfg, path, st, _ = c04
    ph = hangings_at_point(cfg, path, {"spacing": 0.06}, st, sw.Constraints(min_separation=0.02), 0.1, None,
                           "bifilar plan", point=pt(Izz=0.9823))
    assert "Izz" in ph.document["accuracy"]
    assert ph.warnings == [linear_caution(pt(Izz=0.9823), ph.document, "the planned point")]


def test_with_hangings_the_target_line_names_every_component_the_joint_figure_covers():
    """rank25's left item 4: with --hangings the points are ranked by the
    multi-hanging plan's sigma, the worst of every component (a set-aside
    one too), but the document's target read "worst relative of" the
    measurable ones.  Iyy set aside (90 / 80 %), the plan's figures 2 % and
    1 %: point 1 ranked first, the target names Ixx, Iyy, Izz by the plan
    and Iyy's set-aside reason no longer offers --hangings as the way out;
    without --hangings both stay.  Fails with the old label and without
    ranking.aside_under_hangings."""
    from bifilar.studies.recommend import target_label

    pts = [_point(x, {"Ixx": (0.1, "roll", 0.5), "Iyy": (r, "swing", 0.5), "Izz": (0.05, "torsion", 0.3)})
           for x, r in ((1.0, 0.9), (2.0, 0.8))]
    rec = sw.assess(pts, sw.Constraints(min_separation=0.02), None, hangings=lambda ps: [0.02, 0.01][:len(ps)])
    assert rec["best"] == 1 and rec["measurable"] == ["Ixx", "Izz"]
    assert rec["target"] == "worst relative of Ixx, Iyy, Izz by the multi-hanging plan", rec["target"]
    (a,) = rec["set_aside"]  # nor is --hangings named as the way out: it is given
    assert a["reason"].endswith("(at spacing = 2), above the 50 % a measurement must beat to say more than a guess; it "
                                "is left out of the point's own figure, but --hangings ranks by the multi-hanging "
                                "plan's joint sigma, which includes it"), a["reason"]
    assert rec["identifiability"]["Iyy"]["set_aside"] == a
    own = sw.assess(pts, sw.Constraints(), None)
    assert own["target"] == "worst relative of Ixx, Izz" and "add --hangings" in own["set_aside"][0]["reason"]
    assert target_label("Iyy", ["Ixx"], ["Ixx", "Iyy"], True) == "Iyy"
