"""``invert`` on four elastic wires (docs/design.md "elastic25, session 25"
and "inv25, session 25"): the sweep point's drawn-rig rule on invert's own
config.

audit24's c07 (a plate on four vertical 1.2 m wires on a 0.4 m square, here
not flat, principal moments 0.03 / 0.045 / 0.06 kg m^2, so that Izz lies
off its triangle limit) with EA 2 kN.  At the 1 mm default stds a drawn
config's splay of ~1e-3 rad put a fourth wire direction at the model's old
held-direction cut-off (17 % of drawn configs held it; closed loop, 200
draws: the answers scattered 26x the sigma), and ``invert`` printed a std
1.034x the sweep's sigma; session 25 gave none and the sweep's reason
(session 26's stretch rule holds no direction differently there: the std
is kept, tests/test_elastic26.py; the refusal is tested at EA 20 kN, where
drawn configs leave a wire slack).  With
the points stated to 0.1 mm and the lengths to 2.5 mm no drawn config comes
near the cut-off and 2 % leave a wire slack: the std is kept, the planner's
linear sigma (closed loops there: invert's std 1.003-1.004x the sigma, the
answered scatter 0.951x), and a note gives the slack's share, checked
against the exact rests of drawn configs (session 26b: before, against a
hand model of the tensions, linear, which understates the tail that EA's
10 % std fattens).
"""

from __future__ import annotations

import math
import re

import numpy as np

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.studies import sweep as sw
from conftest import ROOT

QUAD = ROOT / "tests" / "data" / "audit24" / "c07_quad.yaml"
FINE = {"position": 1e-4, "length": 2.5e-3}  # m


def _config():
    cfg = read_yaml(QUAD)
    cfg["body"]["inertia"]["principal"] = [0.03, 0.045, 0.06]
    cfg["rig"]["stiffness"] = 2000.0
    return cfg


def _invert(cfg, unc):
    """``invert`` of the config's own linear torsion period (timing 1 ms, small amplitude)."""
    scene = scene_from_dict(cfg, warn=False)
    T = linear_modes(scene, rest_pose(scene)).get("torsion").period
    ms = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                        [Measurement("torsion", T, 1e-3, "period", "--period", amplitude=0.0, cycles=10)])
    return invert(ms, solve_for=["Izz"], unc=unc, ladder=False)


def test_invert_on_four_elastic_wires_gives_the_sweep_points_refusal_or_its_sigma():
    cfg = _config()
    cfg["rig"]["stiffness"] = 20000.0  # the 1 mm defaults: 74 % of drawn configs leave a wire slack
    res = _invert(cfg, None)
    assert math.isnan(res.sigma("Izz")) and np.all(np.isnan(res.interval))
    assert res.std_unavailable.startswith("the uncertainty cannot be given on these four or five elastic wires")
    assert "leave a wire slack" in res.std_unavailable  # (EA 2 kN at 1 mm was refused for the held directions
    # until session 26; elastic26's rule holds none differently there: its closed loop 1.07x, tests/test_elastic26)
    assert res.std_unavailable in res.warnings and math.isnan(res.to_json()["inertia"]["Izz"]["std"])  # null
    cfg["rig"]["stiffness"] = 2000.0
    # the points and lengths stated finely: the std kept, the sweep point's sigma
    cfg["uncertainty"] = dict(FINE)
    res = _invert(cfg, FINE)
    p = sw.evaluate_point(cfg, "x.yaml", {}, sw.resolve_settings(cfg, tensions=False, components=["Izz"]),
                          screen=True)
    assert p["valid"] and p["drawn_rig"]["p_near"] == 0, p
    assert res.std_unavailable is None
    # invert's linear budget against the planner's: the same terms by other finite differences (budget.py
    # LINEAR_ENOUGH's reason: ~1e-6 apart); 1e-3 is far inside the 3 % a refused or widened std would move
    assert abs(res.sigma("Izz") / p["components"]["Izz"]["sigma"] - 1) < 1e-3
    # the slack note: its share against the exact rests of 200,000 configs drawn from the same stds
    # (scripts/elastic_slack_check.py, seeds 3 and 5: 4597 slack, 0.02299, binomial std 3.4e-4; the linear
    # tensions of the same draws 0.02108, the hand model's 2 Phi(-(m g / 4) / (k s_e / 2)) 0.0187: EA's 10 %
    # std scales the lengths' warp, docs/design.md "elastic26b").  3 stds of the two counts (100,000 draws
    # here) and the note's 3 significant figures: 2.3e-3; the linear figure (0.0202) lies 2.8e-3 off
    exact = 4597 / 199_999
    note = [n for n in res.notes if "leave a wire slack in" in n]
    assert len(note) == 1, res.notes
    got = float(re.search(r"slack in ([0-9.e+-]+) %", note[0]).group(1)) / 100
    sd = math.sqrt(exact * (1 - exact) * (1 / 199_999 + 1 / 1e5))
    assert abs(got - exact) < 3 * sd + 5e-4, (got, exact)


def test_the_refusals_shares_read_as_percentages_near_all_configs():
    """A drawn-rig share near 1 printed '1e+02 %' (a pentagon of EA 2 kN at 1 mm: 99.8 % near the cut-off)."""
    from bifilar.estimation.elastic_split import DrawnRigRisks, sigma_refusal

    r = DrawnRigRisks(p_slack=0.9995, p_held=0.56, p_near=0.998, p_model=1.0, tension_sd=np.array([9.0, 1.0]),
                      tensions=np.array([4.9, 4.9]), held=3)
    text = sigma_refusal(r)
    assert "in 56 % of the configs" in text and "in 99.8 %)" in text and "so 100 % of the configs" in text, text


def test_a_refusal_near_the_cut_off_only_does_not_say_zero_percent_cross_it():
    """test_elastic25's pentagon at 0.1 mm: no drawn config crossed the held-direction cut-off, 0.3 % came
    within its factor 10; the reason read 'in 0 % of the configs ... the model holds another number'."""
    from bifilar.estimation.elastic_split import DrawnRigRisks, near_hold_refusal, sigma_refusal

    r = DrawnRigRisks(p_slack=0.0, p_held=0.0, p_near=0.003, p_model=0.0, tension_sd=np.array([1.0, 1.0]),
                      tensions=np.array([4.9, 4.9]), held=3)
    assert sigma_refusal(r) is None  # twin26: near the rule only, each component by its mode's bias
    text = near_hold_refusal(r, "Izz", 2e-3, 1e-2)  # a bias of 0.2 sigma
    assert "in 0.3 % of the configs" in text and "comes within a factor 10 of holding" in text, text
    assert "in 0 %" not in text and "none of the configs drawn crossed it" in text, text
    assert "moves Izz by 0.002" in text and "0.2 of its sigma" in text, text


def test_draws_that_cannot_be_made_refuse_the_sigma(monkeypatch):
    """Where a neighbour's rest pose is not found the drawn-config check used to return None, and the point's
    and invert's own figures (the lower bounds the check exists to catch) stood unchecked; now the sigma is
    refused with that reason."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.config import scene_from_dict
    from bifilar.errors import BifilarError
    from bifilar.estimation import elastic_split as es

    cfg = {"body": {"mass": 2.0, "inertia": {"principal": [0.03, 0.045, 0.06]}},
           "rig": {"anchors": [[0.2, 0.2, 1.2], [-0.2, 0.2, 1.2], [-0.2, -0.2, 1.2], [0.2, -0.2, 1.2]],
                   "attachments": [[0.2, 0.2, 0.01], [-0.2, 0.2, 0.01], [-0.2, -0.2, 0.01], [0.2, -0.2, 0.01]],
                   "lengths": [1.2] * 4, "stiffness": 2000.0}}
    scene = scene_from_dict(cfg, warn=False)
    rest = rest_pose(scene)

    def fail(*a, **k):
        raise BifilarError("no rest pose near the neighbour's")

    monkeypatch.setattr(es, "drawn_rig_risks", fail)
    risks = es.risks_or_none(scene, rest, {})
    assert risks is not None and risks.failed == "no rest pose near the neighbour's"
    text = es.sigma_refusal(risks)
    assert text is not None and "could not be drawn (no rest pose near the neighbour's)" in text
    assert es.slack_note(risks) is None
    refusal, notes = es.hangings_check([("ref", scene, rest)], {}, {})
    assert refusal == text and notes == []
    res = {}
    assert es.point_risks(res, scene, rest, {})[1] == text and res["drawn_rig"] == {"failed": risks.failed}
