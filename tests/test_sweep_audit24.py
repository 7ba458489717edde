"""Sweep and plan audit, session 24 (docs/design.md, "Sweep and plan audit,
session 24"): the figures and messages of ``sweep`` / ``plan`` on rigs
nobody here wrote.

Hand-made points (the dicts of :func:`bifilar.studies.point.evaluate_point`,
only the fields the ranking reads), as tests/test_mutation_gaps_ranking.py
builds them; each answer worked out from the documented rule.
"""

from __future__ import annotations

from bifilar.studies import sweep as sw
from bifilar.studies.ranking import binding_constraint


def _point(x, sep, comps):
    return {"params": {"spacing": x}, "valid": True, "error": None,
            "components": {k: {"identifiable": v is not None, "rel_sigma": v, "mode": "m" if v else None,
                               "shares": {"timing": 1.0}} for k, v in comps.items()},
            "separation": sep,
            "tension": {"rest": [1.0], "peak": 1.0, "min": [0.5], "max": [1.0], "slack": False, "slack_wires": []},
            "depth": {"rest": 1.0, "max": 1.0}}


def test_a_point_meeting_every_limit_without_a_component_is_named():
    """The 30 g part of row S4 on a bifilar: Iyy has a sigma only where the
    wires lean (its swing then 0.3-1.2 % from the other swing, below the 2 %
    guard); the vertical point meets every limit but has no Iyy.  The
    binding message said "no configuration meets --min-separation 0.02",
    false of the vertical point the same document marks feasible; it now
    narrows the claim to the points that measure Ixx, Iyy, Izz and names
    the point and the way out.  Where every point measures every component
    the message is unchanged (the second case)."""
    c = sw.Constraints(min_separation=0.02)
    pts = [_point(0.04, 0.0118, {"Ixx": 0.43, "Iyy": 14.9, "Izz": 0.25}),
           _point(0.06, 0.299, {"Ixx": 0.43, "Iyy": None, "Izz": 0.25}),
           _point(0.08, 0.0033, {"Ixx": 0.43, "Iyy": 27.3, "Izz": 0.25})]
    flag, msg = binding_constraint(pts, c, None, ["Ixx", "Iyy", "Izz"])
    assert flag == "--min-separation", msg
    assert msg.startswith("no configuration that measures Ixx, Iyy, Izz meets --min-separation 0.02: "
                          "the best mode separation found is 0.0118"), msg
    assert msg.endswith("; 1 point(s) meet every limit but give no uncertainty for Iyy (e.g. at spacing = 0.06): "
                        "leave Iyy out of --component, or add --hangings"), msg
    rec = sw.assess(pts, c, None)
    assert rec["best"] is None and rec["n_feasible"] == 1 and rec["reason"] == msg
    flag, msg = binding_constraint(pts[::2], c, None, ["Ixx", "Iyy", "Izz"])
    assert msg == "no configuration meets --min-separation 0.02: the best mode separation found is 0.0118", msg
