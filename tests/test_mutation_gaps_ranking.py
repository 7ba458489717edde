"""Tests written to kill surviving mutants of the ranking and recommendation
of a sweep's points (``bifilar/studies/ranking.py``; see docs/mutation.md).

Hand-made points (the dicts of :func:`bifilar.studies.point.evaluate_point`,
only the fields the ranking reads), each case's answer worked out by hand
from the documented rules: a limit binds when no point meets it, else the
one whose removal frees the most points; the others are named as also
limiting; an invalid point's violation is its reason; a recommended point's
reasons quote the limits it meets.
"""

from __future__ import annotations

from bifilar.studies import sweep as sw
from bifilar.studies.ranking import binding_constraint, pareto_front, violations, why_invalid


def _point(obj=0.01, peak=100.0, depth=1.0, sep=0.2, x=0.0, comps=None):
    return {"params": {"x": x}, "valid": True, "error": None,
            "components": comps or {"Izz": {"identifiable": True, "rel_sigma": obj, "mode": "torsion",
                                            "shares": {"timing": 0.7, "length": 0.3}}},
            "separation": sep,
            "tension": {"rest": [1.0], "peak": peak, "min": [0.5], "max": [peak], "slack": False, "slack_wires": []},
            "depth": {"rest": depth, "max": depth}}


def test_the_binding_limit_is_the_one_whose_removal_frees_the_most_points():
    """Every limit is met by some point, so none binds alone: the binding one
    is the limit whose removal frees the most points.  Two points break only
    the tension limit (100 N) and one only the depth limit (2 m): without
    the tension limit two points become feasible, without the depth limit
    one -- the tension limit binds, and the depth limit also limits.  With
    the counts the other way round the depth limit binds."""
    c = sw.Constraints(max_tension=100.0, max_depth=2.0)
    pts = [_point(peak=200.0, x=1), _point(peak=250.0, x=2), _point(peak=50.0, depth=3.0, x=3)]
    flag, msg = binding_constraint(pts, c, None)
    assert flag == "--max-tension", msg
    assert "lowest peak tension found is 50 N" in msg and msg.endswith("(also limiting: --max-depth)"), msg
    pts = [_point(peak=200.0, x=1), _point(peak=50.0, depth=3.0, x=2), _point(peak=60.0, depth=2.5, x=3)]
    flag, msg = binding_constraint(pts, c, None)
    assert flag == "--max-depth", msg
    assert "smallest depth found is 1 m" in msg and msg.endswith("(also limiting: --max-tension)"), msg
    rec = sw.assess(pts, c, None)
    assert rec["best"] is None and rec["binding"] == "--max-depth"


def test_a_limit_no_point_meets_binds_and_names_the_best_value_found():
    """The separation limit 30 % is met by no point (20 % and 25 %): it
    binds whatever the counts, with the best separation found, 0.25; the
    tension limit, broken by one point only, also limits."""
    c = sw.Constraints(max_tension=100.0, min_separation=0.3)
    pts = [_point(sep=0.2, peak=200.0, x=1), _point(sep=0.25, x=2)]
    flag, msg = binding_constraint(pts, c, None)
    assert flag == "--min-separation", msg
    assert "best mode separation found is 0.25" in msg and msg.endswith("(also limiting: --max-tension)"), msg


def test_an_invalid_points_violation_is_its_reason():
    """A point that cannot hang breaks 'valid' with its own reason, which
    the sweep lists among the point's violations."""
    bad = {"params": {"x": 1.0}, "valid": False, "error": "rig.lengths: wires 1 and 2 cannot reach"}
    assert violations(bad, sw.Constraints()) == [("valid", "rig.lengths: wires 1 and 2 cannot reach")]
    pts = [bad, _point(x=2.0)]
    rec = sw.assess(pts, sw.Constraints(), None)
    assert rec["best"] == 1 and pts[0]["violations"] == ["rig.lengths: wires 1 and 2 cannot reach"]
    assert violations({"valid": False}, sw.Constraints()) == [("valid", "invalid")]


def test_nothing_identifiable_anywhere_says_no_component():
    """Valid points where no component is identifiable from any mode (no
    target given): no recommendation, the binding option is --target and the
    reason says that no component is identifiable."""
    comps = {"Ixx": {"identifiable": False, "rel_sigma": None, "mode": None}}
    pts = [_point(comps=comps, x=1), _point(comps=comps, x=2)]
    rec = sw.assess(pts, sw.Constraints(), None)
    assert rec["best"] is None and rec["binding"] == "--target"
    assert rec["reason"] == "no component is identifiable from any mode anywhere in the range", rec["reason"]
    assert rec["not_measurable"] == ["Ixx"] and rec["measurable"] == []


def test_the_recommended_points_reasons_quote_the_limits_it_meets():
    """The reasons of a recommended point: its worst component's relative
    sigma in % and the mode, its largest variance share, the separation
    with the required minimum, the peak tension and the depth, each with the
    limit it meets."""
    c = sw.Constraints(max_tension=350.0, max_depth=2.5, min_separation=0.1)
    pts = [_point(obj=0.02, peak=120.0, depth=1.5, sep=0.2, x=1), _point(obj=0.05, x=2)]
    rec = sw.assess(pts, c, None)
    assert rec["best"] == 0
    why = rec["why"]
    assert why[0].endswith("Izz +- 2 % (from the torsion mode)"), why
    assert why[1] == "its variance is 70 % timing", why
    assert why[2] == "mode separation 20 % (smallest gap between a timed mode and any other), >= 10 % required", why
    assert why[3] == "peak wire tension 120 N (<= 350 N)" and why[4] == "needs 1.5 m below the ceiling (<= 2.5 m)", why


def test_one_reason_for_every_invalid_point_is_quoted_without_other_reasons():
    """docs/errors.md's form: three invalid points whose reasons differ
    only in their numbers are one reason, quoted at the first point with the
    count, and no "other reason(s)" clause follows (there is none); a
    fourth, differently worded reason adds "(1 other reason(s) ...)"."""
    pts = [{"params": {"length": L}, "valid": False,
            "error": f"rig.lengths: wires 1 and 2 cannot reach: {L} + {L} m"} for L in (0.5, 0.6, 0.7)]
    assert why_invalid(pts) == ("the most common reason (3 of 3 points, e.g. at length = 0.5): "
                                "rig.lengths: wires 1 and 2 cannot reach: 0.5 + 0.5 m")
    pts.append({"params": {"length": 0.8}, "valid": False, "error": "every wire slack at rest"})
    assert why_invalid(pts).endswith("0.5 + 0.5 m (1 other reason(s) for the rest)")


def test_no_valid_point_binds_the_range_with_the_most_common_reason():
    """No point can hang: the range itself (--param) binds, with the most
    common reason of the invalid points."""
    pts = [{"params": {"length": L}, "valid": False, "error": f"wires 1 and 2 cannot reach: {L} m"} for L in (0.5, 0.6)]
    flag, msg = binding_constraint(pts, sw.Constraints(max_tension=10.0), None)
    assert flag == "--param"
    assert msg == ("no valid configuration in the range: the most common reason (2 of 2 points, e.g. at "
                   "length = 0.5): wires 1 and 2 cannot reach: 0.5 m"), msg


def test_no_point_with_the_available_lengths_binds_and_lists_them():
    c = sw.Constraints(lengths_available=(1.0, 1.5))
    pts = [dict(_point(x=1), lengths=[1.2, 1.2]), dict(_point(x=2), lengths=[1.0, 1.6])]
    flag, msg = binding_constraint(pts, c, None)
    assert flag == "--lengths-available"
    assert msg == "no configuration uses only the available wire lengths 1, 1.5", msg
    pts.append(dict(_point(x=3), lengths=[1.5, 1.0 + 1.5e-6]))  # beyond the documented 1e-6 m
    assert sw.assess(pts, c, None)["best"] is None
    pts.append(dict(_point(x=4), lengths=[1.5, 1.0 + 5e-7]))  # within it
    assert sw.assess(pts, c, None)["best"] == 3


def test_pareto_front_is_the_points_no_other_dominates():
    """(peak tension, objective) front: a point is left out when another has
    a lower or equal tension and a lower or equal objective, one of them
    strictly -- so of two points with the same objective only the one at the
    lower tension is on it.  Without the nonlinear runs (no peak tension)
    the front is empty."""
    pts = [_point(obj=0.02, peak=100.0, x=1), _point(obj=0.02, peak=200.0, x=2), _point(obj=0.01, peak=300.0, x=3)]
    assert pareto_front(pts, None) == [0, 2]
    for p in pts:
        p["tension"]["peak"] = None
    assert pareto_front(pts, None) == []
    assert sw.assess(pts, sw.Constraints(), None)["pareto_front"] == []


def test_the_objective_names_only_the_measurable_components():
    """Without a target the objective is the worst of the measurable
    components: Izz here; Ixx, identifiable nowhere, is not in it."""
    comps = {"Izz": {"identifiable": True, "rel_sigma": 0.01, "mode": "torsion"},
             "Ixx": {"identifiable": False, "rel_sigma": None, "mode": None}}
    rec = sw.assess([_point(comps=comps, x=1)], sw.Constraints(), None)
    assert rec["target"] == "worst relative of Izz" and rec["not_measurable"] == ["Ixx"], rec["target"]
    assert rec["best"] == 0 and rec["objective"] == 0.01


def test_every_point_slack_binds_the_amplitude():
    pts = [_point(x=1), _point(x=2)]
    for p in pts:
        p["tension"].update(slack=True, slack_wires=[1])
    flag, msg = binding_constraint(pts, sw.Constraints(), None)
    assert (flag, msg) == ("--amplitude", "every configuration lets a wire go slack during the excitation; "
                                          "reduce --amplitude")
