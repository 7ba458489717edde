"""Closed-loop checks of the planner (docs/design.md, "Closed-loop check of
the planner, session 6"): do the experiment a sweep point describes -- draw
the experimenter's inputs from their declared stds, time the period, invert
as a user would -- and compare with what the sweep predicted; and the
recommendation logic on points whose figures tie or cannot be given."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import read_yaml, scene_from_dict
from bifilar.errors import InputError, UnstableRestError
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.sensitivity import perturb
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS, ROOT, measured_scene

PLATE = CONFIGS / "thesis_plate_rest.yaml"
SOLAR = CONFIGS / "solar_boat.yaml"


def _point(path, params, **settings):
    cfg = read_yaml(path)
    p = sw.evaluate_point(cfg, str(path), params, sw.resolve_settings(cfg, **settings))
    assert p["valid"], p["error"]
    scene = scene_from_dict(apply_params(cfg, params, str(path))[0], warn=False)
    return cfg, scene, p


def _invert(scene, mode, period, comp, unc):
    """``bifilar invert CONFIG --period MODE=PERIOD+-TIMING --amplitude 0 --solve-for COMP``."""
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(mode, period, unc["timing"], "period", "--period", amplitude=0.0)])
    ms.uncertainty = dict(unc)
    return invert(ms, method="linear", solve_for=[comp], ladder=False)


def test_knife_edge_point_gives_no_sigma_as_invert_gives_no_std():
    # the thesis plate's CoM lies on its attachment line.  The sweep used to leave the inputs without a
    # derivative (attachment x, com x) out and print Izz +- 0.18 % at the point it recommended; invert at
    # that very config gives no std, and the experiment shows why: with an experimenter's CoM 2 mm (one
    # std) off the line sideways the model cannot hang the plate as it hangs (it turns by 90 degrees)
    params = {"spacing": 2.0, "length": 4.5}
    cfg, scene, p = _point(PLATE, params, tensions=False)
    for c in ("Ixx", "Izz"):
        e = p["components"][c]
        assert e["identifiable"] and e["sigma"] is None and e["rel_sigma"] is None, c
        assert all(n in e["sigma_unavailable"] for n in ("attachment.1.x", "attachment.2.x", "com.x")), c
    unc = sw.resolve_settings(cfg).unc
    res = _invert(scene, "torsion", p["periods"]["torsion"], "Izz", unc)
    assert res.value("Izz") == pytest.approx(scene.inertia[2, 2], rel=1e-9)
    assert res.std_unavailable and math.isnan(res.sigma("Izz"))
    # (the rest pose of that config turns the plate by 90 degrees, which is refused as turning over)
    with pytest.raises(UnstableRestError, match="turn about it by 90 degrees"):
        rest_pose(perturb(scene, "com.x", unc["com"]))
    # the sweep ranks no point then and says why (not "no component is identifiable")
    rec = sw.assess([p], sw.resolve_constraints(cfg), None)
    assert rec["best"] is None and rec["binding"] == "--param"
    assert "cannot be given" in rec["reason"] and "identifiable" not in rec["reason"]
    # stated exact, those inputs leave an exact budget that invert reproduces
    exact = {"position": 0.0, "com": 0.0}
    cfg, scene, p = _point(PLATE, params, tensions=False, sigma=exact)
    unc = {**unc, **exact}
    res = _invert(scene, "torsion", p["periods"]["torsion"], "Izz", unc)
    assert res.sigma("Izz") == pytest.approx(p["components"]["Izz"]["sigma"], rel=1e-6)


def test_dependent_wires_without_a_sigma_are_not_called_unidentifiable():
    # four vertical wires on a square: one wire's length has no derivative (rigid dependent wires), so
    # Izz's torsion period measures it but no sigma can be given; the sweep said "no component is
    # identifiable from any mode anywhere in the range" (flag --target)
    cfg = {"body": {"mass": 10.0, "inertia": {"principal": [0.5, 0.8, 1.2]}},
           "rig": {"anchors": [[-0.3, -0.3, 0.0], [0.3, -0.3, 0.0], [0.3, 0.3, 0.0], [-0.3, 0.3, 0.0]],
                   "attachments": [[-0.3, -0.3, 0.05], [0.3, -0.3, 0.05], [0.3, 0.3, 0.05], [-0.3, 0.3, 0.05]],
                   "lengths": [1.5, 1.5, 1.5, 1.5]}}
    p = sw.evaluate_point(cfg, "square", {}, sw.resolve_settings(cfg, tensions=False))
    e = p["components"]["Izz"]
    assert e["identifiable"] and e["sigma"] is None and "length.1" in e["sigma_unavailable"]
    rec = sw.assess([p], sw.resolve_constraints(cfg), None)
    assert rec["best"] is None and rec["binding"] == "--param"
    assert "Izz" in rec["reason"] and "length.1" in rec["reason"] and "identifiable" not in rec["reason"]


def _fake(obj, x):
    return {"params": {"length_offset": x}, "valid": True, "error": None,
            "components": {"Izz": {"identifiable": True, "rel_sigma": obj, "mode": "torsion"}},
            "separation": 0.5, "tension": {"rest": [1.0], "peak": 2.0, "min": [0.5], "max": [2.0], "slack": False,
                                            "slack_wires": []}, "depth": {"rest": 1.0, "max": 1.0}}


@pytest.mark.parametrize("ulps", [0, 1, -1])
def test_ties_go_to_the_parameters_not_to_the_grid_order_or_the_last_bits(ulps):
    # mirror images (length_offset -0.1 and 0.1 of a symmetric rig) have one objective up to rounding
    # (6e-14 relative measured on the shallow box of docs/design.md); the recommendation and the ranks
    # must not follow the order of the grid nor the last bits
    a = 0.0123
    b = a
    for _ in range(abs(ulps)):
        b = math.nextafter(b, math.inf if ulps > 0 else -math.inf)
    for order in ((-0.1, 0.1), (0.1, -0.1)):
        pts = [_fake(a if x < 0 else b, x) for x in order]
        rec = sw.assess(pts, sw.Constraints(), None)
        assert rec["params"] == {"length_offset": -0.1}, (order, ulps)
        assert {p["params"]["length_offset"]: p["rank"] for p in pts} == {-0.1: 1, 0.1: 2}
    # a real difference still ranks
    pts = [_fake(a * (1 + 1e-6), -0.1), _fake(a, 0.1)]
    assert sw.assess(pts, sw.Constraints(), None)["params"] == {"length_offset": 0.1}


def test_recommended_point_sigma_is_the_spread_of_the_experiment():
    # the Solar Boat's recommended point of `sweep --param spacing=1:4:7 --param length=2:5:4`: the
    # experimenter's inputs drawn from their stds (every length, anchor and attachment coordinate,
    # the mass and the CoM), the period timed with the 1 ms the sweep assumes, inverted as a user
    # would (--amplitude 0: the sigma is for a stated small amplitude).  120 draws: the sample sd is
    # within +-6.5 % (1 sd) of the truth; the band is 3.5 sd.  200-400 draws of every component of the
    # boat, the drone and the trifilar: docs/design.md
    cfg, scene, p = _point(SOLAR, {"spacing": 2.5, "length": 2.0}, tensions=False, components=["Izz"])
    e = p["components"]["Izz"]
    unc = sw.resolve_settings(cfg).unc
    T = linear_modes(scene, rest_pose(scene)).get(e["mode"]).period
    rng = np.random.default_rng(2026)
    est, std = [], []
    for _ in range(120):
        res = _invert(measured_scene(scene, rng, unc), e["mode"], T + rng.normal(0, unc["timing"]), "Izz", unc)
        est.append(res.value("Izz"))
        std.append(res.sigma("Izz"))
    ratio = np.std(est, ddof=1) / e["sigma"]
    assert 0.77 < ratio < 1.23, ratio
    assert abs(np.mean(est) - e["value"]) < 3.5 * e["sigma"] / np.sqrt(len(est))
    # and the std invert prints for each draw is the sweep's (within the draws' own spread of it)
    assert np.median(std) == pytest.approx(e["sigma"], rel=0.03)


def test_multi_hanging_plan_of_a_knife_edge_gives_no_sigma():
    # the hangings planned at a knife-edge point: a timed period with an input without a derivative and
    # a nonzero sigma gives no joint sigma (it was the budget without those inputs); stated exact, it does
    from bifilar.studies.hangings import plan_hangings

    cfg = read_yaml(PLATE)
    params = {"spacing": 2.5}
    for sigma, given in ((None, False), ({"position": 0.0, "com": 0.0}, True)):
        st = sw.resolve_settings(cfg, tensions=False, sigma=sigma)
        doc = plan_hangings(cfg, str(PLATE), params, st, list(st.components), 0.02).to_json()
        assert doc["not_identified"] == []
        assert all((a["sigma"] is not None and math.isfinite(a["sigma"])) == given
                   for a in doc["accuracy"].values()), doc["accuracy"]
        assert (doc["sigma_unavailable"] is None) == given
        if not given:
            assert "com.x" in doc["sigma_unavailable"]


def test_flat_body_estimates_beyond_the_physical_limit_are_predicted():
    # the KTH trifilar table is flat (Izz = Ixx + Iyy): its torsion estimate of Izz sits on the triangle
    # limit with the other components as given, so about half the experiments time a period no physical
    # Izz reproduces (invert gives the limit, or refuses beyond EDGE_Z timing sigmas).  The sweep printed
    # a symmetric sigma and nothing else; it now predicts both fractions and warns.  Closed loop: 80
    # draws of the experimenter's inputs and timing (binomial sd <= 5.6 %; band 4.5 sd)
    params = {"spacing": 1.5, "length": 1.2}
    cfg, scene, p = _point(CONFIGS / "trifilar_kth.yaml", params, tensions=False, components=["Izz"])
    e = p["components"]["Izz"]
    assert 0.4 < e["p_unphysical"] < 0.5 and 0 < e["p_refused"] < e["p_unphysical"]
    assert e["physical_interval"][1] == pytest.approx(scene.inertia[0, 0] + scene.inertia[1, 1], rel=2e-4)
    assert "flat body" in e["physical_limit"] and "refuses" in e["physical_limit"]
    unc = sw.resolve_settings(cfg).unc
    T = p["periods"]["torsion"]
    rng = np.random.default_rng(11)
    edge = refused = 0
    n = 80
    for _ in range(n):
        try:
            res = _invert(measured_scene(scene, rng, unc), "torsion", T + rng.normal(0, unc["timing"]), "Izz", unc)
        except InputError as exc:
            assert "no physical Izz" in str(exc)
            refused += 1
            continue
        edge += any("edge of the physical set" in w for w in res.warnings)
    assert abs((edge + refused) / n - e["p_unphysical"]) < 0.25
    assert abs(refused / n - e["p_refused"]) < 0.15
    # a body well inside its physical set: nothing to say (the boat's recommended point)
    _, _, p = _point(SOLAR, {"spacing": 2.5, "length": 2.0}, tensions=False)
    assert all(c["p_unphysical"] < 1e-6 and "physical_limit" not in c for c in p["components"].values())


def test_sweep_table_says_why_a_knife_edge_point_is_not_ranked():
    # the plate hung at its CoM (height 0: a knife edge) and 0.3 m above it: the second is recommended,
    # the first's row says why it has no rank; the flat plate's components all sit on a triangle limit
    # with the others as given, which the recommended point's warnings say
    from click.testing import CliRunner

    from bifilar.cli import main

    r = CliRunner().invoke(main, ["sweep", str(PLATE), "--param", "height=0,0.3", "--no-tensions"])
    assert r.exit_code == 0, r.stderr
    text = " ".join(r.stdout.split())
    assert "0: no uncertainty for Ixx, Izz: these inputs have no derivative here (the scene is degenerate: a neutral " \
        "mode" in text
    assert "recommended: point 1: height = 0.3" in text
    assert "Izz: the config's value 260.417 kg m^2 lies" in " ".join(r.stderr.split())
    assert " ".join(r.stderr.split()).count("a flat body sits on it") == 3


def test_sweep_table_gives_an_elastic_refusal_its_own_reason(tmp_path):
    # four elastic wires at the default 1 mm stds (elastic25): the point's sigma is refused because drawn configs
    # leave a wire slack or hold another wire direction; the table's note gave the knife edge's words for every
    # refusal ("an input has no derivative here (the CoM on the attachment line, or dependent wires)") before
    import yaml
    from click.testing import CliRunner

    from bifilar.cli import main

    cfg = yaml.safe_load((ROOT / "tests" / "data" / "audit24" / "c07_quad.yaml").read_text())
    cfg["rig"]["stiffness"] = 20000.0
    path = tmp_path / "quad.yaml"
    path.write_text(yaml.safe_dump(cfg))
    r = CliRunner().invoke(main, ["sweep", str(path), "--param", "length=1.2", "--no-tensions", "--component", "Izz"])
    assert r.exit_code in (0, 2), r.output
    text = " ".join(r.stdout.split())
    assert "0: no uncertainty for Izz on these four or five elastic wires" in text, text
    assert "no derivative" not in text
