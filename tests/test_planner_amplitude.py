"""The planner's sigma with the stated amplitude's own uncertainty
(docs/design.md, "Closed-loop check of the planner"): a user times the
period at the release amplitude the sweep assumes and states it to
``invert --amplitude A`` (10 % relative uncertainty by default); the sweep's
sigma must be the std invert then prints, and the spread of such
experiments."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.simulate import simulate
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import DEFAULT_CYCLES, Hanging, Measurement, MeasurementSet
from bifilar.estimation.uncertainty import DEFAULT_AMPLITUDE_REL
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS, measured_scene
from test_amplitude_law import without_input_factor_terms

SOLAR = CONFIGS / "solar_boat.yaml"


def _point(path, params, **settings):
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, **settings)
    p = sw.evaluate_point(cfg, str(path), params, st)
    assert p["valid"], p["error"]
    scene = scene_from_dict(apply_params(cfg, params, str(path))[0], warn=False)
    return st, scene, p


def _invert(scene, mode, period, comp, unc, amplitude, cycles=None, rtol=1e-10):
    """``bifilar invert CONFIG --period MODE=PERIOD+-TIMING --amplitude A --solve-for COMP`` (auto method:
    the nonlinear rung with an amplitude, the linear one with ``--amplitude 0``); ``cycles`` the period's
    (None: invert's default), ``rtol`` its runs'."""
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(mode, period, unc["timing"], "period", "--period", amplitude=amplitude,
                                     cycles=DEFAULT_CYCLES if cycles is None else cycles)])
    ms.uncertainty = dict(unc)
    return invert(ms, solve_for=[comp], ladder=False, rtol=rtol)


@pytest.mark.parametrize("amplitude", [0.05, 0.3])
def test_sweep_sigma_is_the_std_invert_prints_with_the_amplitude_stated(amplitude):
    # the Solar Boat's recommended point (docs/design.md), Izz from torsion: the user times the period the
    # body shows at the sweep's amplitude (simulated over invert's 10 cycles at rtol 1e-10) and states the
    # amplitude.  invert's std then carries the amplitude's 10 % (2 % more std at 0.05, 7x at 0.3); the sweep
    # gave the small-amplitude figure (invert --amplitude 0), 2 % and 86 % low.  The sweep's amplitude factor
    # comes from its own 3-period run at rtol 1e-8: 1e-6 relative measured, band 2e-5
    st, scene, p = _point(SOLAR, {"spacing": 2.5, "length": 2.0}, components=["Izz"], amplitude=amplitude)
    e = p["components"]["Izz"]
    T = simulate(scene, e["mode"], amplitude, 10, rtol=1e-10).period
    res = _invert(scene, e["mode"], T, "Izz", st.unc, amplitude)
    assert res.method == "nonlinear"
    assert res.value("Izz") == pytest.approx(e["value"], rel=1e-9)
    # at 0.05 the sweep leaves the inputs' factor terms out (input_factor_terms false: their bound, 5 %
    # here, is under FACTOR_INPUT_ENOUGH): invert's std with them taken out; with them invert's std is 1 -
    # 2e-4 of the sweep's, within that bound.  At 0.3 the sweep measures them (dr/dx): invert's std
    ab = e["amplitude_budget"]
    if amplitude < 0.1:
        assert ab["input_factor_terms"] is False
        assert e["sigma"] == pytest.approx(without_input_factor_terms(res, "Izz"), rel=2e-5)
        assert abs(res.sigma("Izz") / e["sigma"] - 1) <= ab["input_factor_bound"]
    else:
        assert ab["input_factor_terms"] is True
    assert e["sigma"] == pytest.approx(res.sigma("Izz"), rel=1e-3 if amplitude < 0.1 else 1e-4)
    assert ab["budgeted"] and ab["amplitude"] == amplitude and ab["relative_std"] == DEFAULT_AMPLITUDE_REL
    # the small-amplitude figure kept beside it is what `--amplitude 0` prints for the linear period
    small = _invert(scene, e["mode"], e["period"], "Izz", st.unc, 0.0)
    assert ab["sigma_small_amplitude"] == pytest.approx(small.sigma("Izz"), rel=1e-6)
    assert e["sigma"] > ab["sigma_small_amplitude"] * (1.01 if amplitude < 0.1 else 5)
    # the amplitude's own contribution, as invert lists it (proportional to r - 1 = 8.6e-4 at 0.05, which
    # the two runs give to 2.5e-5 relative)
    amp = [v for k, v in res.budget.contributions.items() if k.startswith("amplitude[")]
    assert len(amp) == 1 and ab["contribution"] == pytest.approx(abs(float(amp[0][0])), rel=1e-4)
    assert e["shares"]["amplitude"] == pytest.approx((ab["contribution"] / e["sigma"]) ** 2, rel=1e-3)


def test_without_a_nonlinear_run_the_sigma_says_it_is_for_a_small_amplitude():
    # --no-tensions: no run gives the amplitude factor, so the sigma is invert's at --amplitude 0 and the
    # point says that the amplitude is not budgeted
    st, scene, p = _point(SOLAR, {"spacing": 2.5, "length": 2.0}, components=["Izz"], tensions=False)
    e = p["components"]["Izz"]
    ab = e["amplitude_budget"]
    assert not ab["budgeted"] and ab["contribution"] is None and "--amplitude 0" in ab["note"]
    assert ab["sigma_small_amplitude"] == e["sigma"]
    small = _invert(scene, e["mode"], e["period"], "Izz", st.unc, 0.0)
    assert e["sigma"] == pytest.approx(small.sigma("Izz"), rel=1e-6)


@pytest.mark.slow
def test_spread_of_experiments_released_at_an_uncertain_amplitude():
    # `sweep configs/solar_boat.yaml --param spacing=1:4:7 --param length=2:5:4 --amplitude 0.3` recommends
    # spacing 1, length 2 (at 0.05: spacing 2.5, length 2; the amplitude's term penalises the modes whose
    # period lengthens most with amplitude).  There Iyy is timed from pitch, where the amplitude makes 79 %
    # of the variance: the old sigma (small amplitude) was 0.46 of the one with it.  The experiment: the
    # release amplitude drawn about the stated 0.3 with its 10 %, the experimenter's inputs from their
    # stds, the period the true body shows at the drawn amplitude (nonlinear, 10 cycles) timed with 1 ms,
    # inverted with --amplitude 0.3.  30 draws: the sample sd is within +-13 % (1 sd) of the truth; band 3.5 sd
    # (0.46).  Test economy, session 15 (was 40 draws, 26 s of the suite's CPU, nearly all invert's nonlinear
    # solves): the bug guarded, the small-amplitude sigma (0.46 of the true one), makes sd / sigma 2.17 x
    # s / s_true, a false pass needs s / s_true < 0.673, chi^2_29 < 13.1: P = 4.8e-3 (40 draws: 4.4e-4); the
    # false alarm of a right sigma stays 4.4e-4 (two chi^2 tails beyond the band).  This seed: sd / sigma
    # 0.84 (1.8 of its standard errors below 1, the band 3.5), the mean 1.9 standard errors below the value.
    # Test economy, session 16: each draw is cheaper, the draws and bands unchanged.  The period is timed over
    # 5 cycles (was 10) and invert's runs are at rtol 1e-8 (was 1e-10): on the first 6 draws the estimates moved
    # by 8e-5 - 6.4e-4 of the sigma (rtol alone: 2e-6) and invert's std by < 5e-4 of itself, so the seed's
    # figures above and the power arithmetic stand; an invert 0.61 -> 0.26 s of CPU (the test ~19 -> ~9 s)
    st, scene, p = _point(SOLAR, {"spacing": 1.0, "length": 2.0}, components=["Iyy"], amplitude=0.3)
    e = p["components"]["Iyy"]
    assert e["mode"] == "pitch"
    n = 30
    rng = np.random.default_rng(7)
    amps = 0.3 * (1 + DEFAULT_AMPLITUDE_REL * rng.standard_normal(n))
    runs = simulate_batch([scene] * n, mode=e["mode"], amplitude=list(amps), periods=5, rtol=1e-10)
    est = []
    for run in runs:
        T = run.period + rng.normal(0, st.unc["timing"])
        est.append(_invert(measured_scene(scene, rng, st.unc), e["mode"], T, "Iyy", st.unc, 0.3, cycles=5,
                           rtol=1e-8).value("Iyy"))
    sd = np.std(est, ddof=1)
    band = 3.5 / math.sqrt(2 * (n - 1))
    assert abs(sd / e["sigma"] - 1) < band, sd / e["sigma"]
    assert abs(np.mean(est) - e["value"]) < 3.5 * e["sigma"] / math.sqrt(n)
    assert e["amplitude_budget"]["sigma_small_amplitude"] < 0.5 * e["sigma"]


def _cli(*args) -> dict:
    from click.testing import CliRunner

    from bifilar.cli import main

    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.stderr
    return json.loads(r.stdout)


def test_recommendation_says_what_an_unstated_amplitude_costs_and_how_to_invert(tmp_path):
    # the boat at its recommended point (one point swept): the advice's invert options, run on the point's
    # config, print the sweep's sigma (the period written to 6 digits: 1e-4); without --amplitude invert
    # budgets a 0-10 degree release and prints ~5.5x that for Izz (docs/design.md: 5.7x the small-amplitude
    # sigma).  The old sweep said nothing about the amplitude
    point = tmp_path / "point.yaml"
    doc = _cli("sweep", SOLAR, "--param", "spacing=2.5", "--param", "length=2", "--component", "Izz",
               "--write-config", point, "--json")
    adv = doc["recommendation"]["amplitude_advice"]
    e = doc["points"][0]["components"]["Izz"]
    assert adv["budgeted"] and adv["amplitude"] == 0.05 and "--amplitude 0.05" in adv["text"]
    row = adv["components"]["Izz"]
    assert row["sigma"] == e["sigma"] and row["mode"] == "torsion"
    inv = _cli("invert", point, *row["invert_options"].split(), "--json")
    # (invert adds the inputs' factor terms, which the sweep's sigma leaves out: -2e-4 here)
    assert inv["inertia"]["Izz"]["std"] == pytest.approx(e["sigma"], rel=1e-3)
    assert inv["inertia"]["Izz"]["value"] == pytest.approx(e["value"], rel=1e-5)
    unstated = row["invert_options"].replace(" --amplitude 0.05", "").replace(f"{row['period']:.6g}", f"{e['period']:.9g}")
    inv = _cli("invert", point, *unstated.split(), "--json")
    assert row["std_unstated"] == pytest.approx(inv["inertia"]["Izz"]["std"], rel=1e-6)
    assert 5 < row["ratio_unstated"] < 6.5 and f"{row['ratio_unstated']:.2g} times the sigma" in adv["text"]


def test_multi_hanging_plan_states_the_amplitude_and_its_sigma_is_invert_s(tmp_path):
    # `plan --hangings --write-measurements` on the KTH trifilar at amplitude 0.3: the measurements file
    # gives each period at the planned amplitude with that amplitude (it gave amplitude 0 and the linear
    # periods), and invert --measurements of it prints the plan's joint sigma, which counts the amplitude's
    # 10 % (1.5-1.6x the sigmas planned at 0.05) and, since session 12, the amplitude factor's derivative in
    # each measured input (dr/dx) as invert measures it: without them invert's std was 1.065 (Ixx), 1.033
    # (Iyy), 1.0009 (Izz) of the plan's; with them 1.0002, 0.9996, 1.00006.  Band 0.5 %: what is left is the
    # plan's dr/dx from its 3-period runs at rtol 1e-8 against invert's 10 cycles at 1e-10, invert's
    # second-order std against the plan's linear one and the periods written to 9 digits (4.5e-4 at most
    # here), 13x below the gap the old plan left on Ixx
    # Test economy, session 23: the point is swept alone (`sweep --param spacing=0.8 ... --hangings`), not
    # searched (`plan --param spacing=0.8:1.6`, 20 points, each with its hangings plan at 0.3: 7.5 of the
    # test's 11 s of CPU; the sweep 3.0 s).  0.8 is the plan's optimum there, and the multi-hanging plan of
    # a point is one function for both commands (cli/cmd_sweep.multi_hanging): its sigmas came out
    # bit-identical and the written file byte-identical but for its header's command name.  `plan --hangings
    # --write-measurements` itself stays covered by tests/test_plan_hangings_separation.py.  The plan's joint
    # sigma without its dr/dx columns (hangings.plan_hangings's finish(X) taking C0) fails the band below
    # (checked, session 23)
    out = tmp_path / "measurements.yaml"
    doc = _cli("sweep", CONFIGS / "trifilar_kth.yaml", "--param", "spacing=0.8", "--min-separation", 0,
               "--hangings", "--amplitude", 0.3, "--write-measurements", out, "--json")
    mh = doc["recommendation"]["multi_hanging"]
    written = read_yaml(out)
    assert all(m["amplitude"] == 0.3 for h in written["hangings"] for m in h["measurements"])
    assert all(m["period_at_amplitude"] > m["period"] for m in mh["measurements"])
    inv = _cli("invert", "--measurements", out, "--json")
    for comp, a in mh["accuracy"].items():
        assert inv["inertia"][comp]["std"] == pytest.approx(a["sigma"], rel=5e-3), comp
    # it times swings (no bound holds on their dr/dx): measured, and said so
    assert mh["input_factor_terms"] is True and all(b == 0.0 for b in mh["input_factor_bound"].values())
    # and the written (planned) periods give back the config's tensor (test_closure's planned-hangings closure,
    # merged here in session 15: it ran the same plan at 0.05, 9 s of CPU): one hanging identifies only Izz,
    # the plan's several identify all it lists, and every component is within one std of the config's inertia,
    # its 95 % interval holding it (noise-free periods: the estimate is the truth up to the periods' 9 digits)
    from bifilar.config import load_scene

    truth = np.asarray(load_scene(CONFIGS / "trifilar_kth.yaml", warn=False).inertia)
    idx = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
    assert len(mh["hangings"]) > 1 and not mh["not_identified"]
    assert sorted(inv["inertia"]) == sorted(mh["components"]) and not inv.get("ambiguous")
    for comp, v in inv["inertia"].items():
        true = truth[idx[comp]]
        assert abs(v["value"] - true) <= v["std"] and v["interval_95"][0] <= true <= v["interval_95"][1], (comp, v)


def test_multi_hanging_plan_leaves_out_dr_dx_only_within_its_bound(tmp_path):
    # the session-11 audit's unequal trifilar at spacing 0.48, length 1.2 (three torsions, no swing) at the
    # default 0.05: the bound on what the inputs' dr/dx terms change each joint sigma is 3.4-3.7 %, under
    # FACTOR_INPUT_ENOUGH, so no run; invert --measurements of the written file (which measures them)
    # differs from the plan's sigmas by 1-2e-4, inside the bound (a bound of 0, or terms dropped where they
    # matter, fails it)
    from bifilar.studies.point_inputs import FACTOR_INPUT_ENOUGH

    from test_closed_loop_audit11 import TRIFILAR_UNEQUAL

    cfg, out = tmp_path / "tri.yaml", tmp_path / "M.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    doc = _cli("sweep", cfg, "--param", "spacing=0.48", "--param", "length=1.2", "--component", "Izz", "--component",
               "Ixx", "--component", "Iyy", "--hangings", "--write-measurements", out, "--json")
    mh = doc["recommendation"]["multi_hanging"]
    assert {m["mode"] for m in mh["measurements"]} == {"torsion"} and mh["input_factor_terms"] is False
    inv = _cli("invert", "--measurements", out, "--json")
    for comp, a in mh["accuracy"].items():
        bound = mh["input_factor_bound"][comp]
        assert 0 < bound <= FACTOR_INPUT_ENOUGH
        assert abs(inv["inertia"][comp]["std"] / a["sigma"] - 1) <= bound, comp


def test_plan_at_a_large_amplitude_searches_the_sigma_with_the_amplitude():
    # the boat at amplitude 0.3: the amplitude's term moves the optimum.  A search ranking only the
    # small-amplitude sigmas (its local screens without nonlinear runs) ends where the plan at 0.05 does,
    # spacing 1.29, length 2.64, whose worst sigma at 0.3 is 0.897 %; searching the full sigma finds
    # spacing 0.97, length 2.63 at 0.790 %
    from bifilar.studies.plan import plan

    cfg = read_yaml(SOLAR)
    st = sw.resolve_settings(cfg, amplitude=0.3)
    res = plan(cfg, str(SOLAR), [("spacing", 0.5, 4.0), ("length", 2.0, 5.0)], st, sw.resolve_constraints(cfg), None)
    small_opt = sw.evaluate_point(cfg, str(SOLAR), {"spacing": 1.2875, "length": 2.6375}, st)
    assert res.best["objective"] < 0.95 * sw.objective(small_opt, None, None)
    # and its answer is a full point: the sigma with the amplitude's term, the small-amplitude one beside it
    assert all(e["amplitude_budget"]["budgeted"] for e in res.best["components"].values())


def test_multi_hanging_plan_counts_a_stated_gravity_uncertainty_as_invert_does(tmp_path):
    # `--sigma gravity=0.003` (relative): the multi-hanging plan's joint sigma left g out (its inputs are the
    # rig's and the body's), while invert --measurements of the file it writes (which states the 0.003)
    # budgets it: invert's std was 1.26-1.30x the plan's on the session-11 audit's unequal trifilar.  g
    # enters every period exactly as g^-1/2 (t' = sqrt(g) t removes it from the equations of motion), one
    # column shared by all hangings; now within 1e-4 (the same 1-2e-4 the file's other inputs leave,
    # test above), a band of 1 %, 26x below the old gap
    from test_closed_loop_audit11 import TRIFILAR_UNEQUAL

    cfg, out = tmp_path / "tri.yaml", tmp_path / "M.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    doc = _cli("sweep", cfg, "--param", "spacing=0.48", "--param", "length=1.2", "--component", "Izz", "--component",
               "Ixx", "--component", "Iyy", "--hangings", "--sigma", "gravity=0.003", "--write-measurements", out,
               "--json")
    mh = doc["recommendation"]["multi_hanging"]
    assert read_yaml(out)["uncertainty"]["gravity"] == 0.003
    inv = _cli("invert", "--measurements", out, "--json")
    for comp, a in mh["accuracy"].items():
        assert inv["inertia"][comp]["std"] == pytest.approx(a["sigma"], rel=1e-2), comp
