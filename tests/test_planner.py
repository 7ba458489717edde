"""The planner answers the experimenter's questions (issue 12): which
components a rig can measure and the remedy for the others, swept
measurement uncertainties, the rig to build written as a config that
reproduces the planned periods, one mode-separation guard, instant refusal
of impossible limits, the body as `modes` sees it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.config import read_yaml, scene_from_dict
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import ParamSpec

from conftest import CONFIGS, trapezoid

PLATE = CONFIGS / "thesis_plate_rest.yaml"
SOLAR = CONFIGS / "solar_boat.yaml"


def run(args):
    r = CliRunner().invoke(main, args)
    return r.exit_code, r.stdout, r.stderr


#: attachment x and com x have no derivative on the thesis plate (CoM on the attachment line): stated exact
KNIFE_EXACT = ["--sigma", "position=0", "--sigma", "com=0"]


def parallel_plate():
    """The thesis plate on parallel wires 5 m apart."""
    cfg = read_yaml(PLATE)
    cfg["rig"]["anchors"] = [[0.0, -2.5, 0.0], [0.0, 2.5, 0.0]]
    return cfg


def test_plate_sweep_recommends_the_measurable_components_and_names_iyy_remedy():
    # the thesis plate with its CoM on the attachment line: the pitch about that line is neutral, so no
    # period depends on Iyy anywhere in the range; Ixx and Izz must still get a recommendation
    # (attachment x and com x, which have no derivative at this knife edge, stated exact: else no sigma)
    code, out, err = run(["sweep", str(PLATE), "--param", "spacing=1,2.5", "--no-tensions", "--json"] + KNIFE_EXACT)
    assert code == 0, err
    doc = json.loads(out)
    rec = doc["recommendation"]
    assert rec["best"] is not None and rec["measurable"] == ["Ixx", "Izz"] and rec["not_measurable"] == ["Iyy"]
    best = doc["points"][rec["best"]]
    assert rec["objective"] == max(best["components"][c]["rel_sigma"] for c in ("Ixx", "Izz"))
    rig = rec["rig"]  # the rig to build: the wire angle follows from anchors, attachments and lengths
    sc = scene_from_dict(read_yaml(PLATE))
    drop = np.sqrt(np.asarray(rig["lengths"]) ** 2 - (5.0 - best["params"]["spacing"] / 2) ** 2)
    np.testing.assert_allclose(np.tan(np.radians(rig["wire_angles_deg"])) * drop,
                               5.0 - best["params"]["spacing"] / 2, rtol=1e-9)
    assert rig["anchors"] == sc.anchors.tolist()
    iyy = rec["identifiability"]["Iyy"]
    assert not iyy["identifiable"] and iyy["remedy"] is not None and 0 < iyy["remedy"]["rel_sigma"] < 0.05
    # independent route for one alternative: the plate turned 90 deg about x hangs with body y vertical, so
    # the reference Iyy is the turned body's Izz, which the sweep itself estimates from the torsion
    turned = [a for a in iyy["alternatives"] if a["change"].get("hanging") == "turned 90 deg about x"]
    assert turned and turned[0]["mode"] == "torsion"
    c2 = read_yaml(PLATE)
    c2["rig"]["attachments"] = best["rig"]["attachments"]
    c2["rig"]["anchors"] = best["rig"]["anchors"]
    c2["body"] = {"mass": 100.0, "inertia": {"principal": [208.3333333333, 260.4166666667, 52.0833333333]}}
    p = sw.evaluate_point(c2, "t", {}, sw.resolve_settings(c2, tensions=False, sigma={"position": 0.0, "com": 0.0}))
    assert turned[0]["rel_sigma"] == pytest.approx(p["components"]["Izz"]["rel_sigma"], rel=1e-6)


def test_swept_timing_uncertainty_changes_the_predicted_sigma_as_sigma_flag_does():
    cfg = parallel_plate()
    values = (0.0, 0.003, 0.03)
    knife = {"position": 0.0, "com": 0.0}  # no derivative at this knife edge: stated exact, else no sigma
    pts = sw.run_sweep(cfg, "t", sw.build_grid([ParamSpec("uncertainty.timing", values)]),
                       sw.resolve_settings(cfg, components=["Izz"], tensions=False, sigma=knife))
    rel = [p["components"]["Izz"]["rel_sigma"] for p in pts]
    # the timing term adds in quadrature: rel^2 = rel_0^2 + (t (dI/dT) / I)^2 with (dI/I)/(dT/T) = rel_sens
    e = pts[0]["components"]["Izz"]
    for t, r in zip(values, rel):
        assert r == pytest.approx(math.hypot(rel[0], t * e["rel_sensitivity_period"] / e["period"]), rel=1e-9)
        flag = sw.evaluate_point(cfg, "t", {}, sw.resolve_settings(cfg, components=["Izz"], tensions=False,
                                                                    sigma={**knife, "timing": t}))
        assert r == pytest.approx(flag["components"]["Izz"]["rel_sigma"], rel=1e-12)
    assert rel[2] > 5 * rel[1]


@pytest.mark.parametrize("args,field,words", [
    (["--param", "uncertainty.timing=-0.001,0.01"], "--param", "must not be negative"),
    (["--param", "uncertainty.timming=0.01"], "--param", "uncertainty.KEY"),
    (["--param", "plan.amplitude=0.1"], "--param", "not sweep parameters"),
    (["--param", "uncertainty.timing=0.01", "--sigma", "timing=0.1"], "--sigma", "both"),
    (["--param", "spacing=1:4:4", "--max-tension", "400"], "--max-tension", "static load"),
])
def test_bad_sweep_inputs_are_refused_before_any_work(args, field, words):
    code, out, err = run(["sweep", str(PLATE), "--no-tensions"] + args) if "--max-tension" not in args else \
        run(["sweep", str(PLATE)] + args)
    assert code == 2 and out == "", err
    assert err.startswith(f"error: {field}") and words in err, err


def test_plan_refuses_a_tension_below_the_static_load_at_once():
    sc = scene_from_dict(read_yaml(SOLAR))
    load = sc.mass * sc.gravity / 2
    code, out, err = run(["plan", str(SOLAR), "--param", "spacing=3:4.8", "--max-tension", f"{0.99 * load:.6g}"])
    assert code == 2 and "static load" in err and f"{load:.4g}" in err, err


def test_plan_zip_keeps_wires_parallel_and_writes_a_config_and_a_measurements_file_that_reproduce_it(tmp_path):
    cfg = parallel_plate()
    src = tmp_path / "plate.yaml"
    src.write_text(yaml.safe_dump(cfg))
    out_cfg, meas = tmp_path / "planned.yaml", tmp_path / "measurements.yaml"
    code, out, err = run(["plan", str(src), "--zip", "--param", "spacing=2:5", "--param", "ceiling_spacing=2:5",
                          "--no-tensions", "--write-config", str(out_cfg), "--write-measurements", str(meas), "--json"]
                         + KNIFE_EXACT)
    assert code == 0, err
    doc = json.loads(out)
    opt = doc["optimum"]
    p = opt["params"]
    assert p["spacing"] == pytest.approx(p["ceiling_spacing"], rel=1e-12)
    np.testing.assert_allclose(opt["rig"]["wire_angles_deg"], 0.0, atol=1e-6)
    # parallel wires: only Izz on this hanging; Ixx and Iyy get remedies and the multi-hanging plan
    assert [c for c, e in doc["identifiability"].items() if e["identifiable"]] == ["Izz"]
    assert doc["identifiability"]["Iyy"]["remedy"] is not None
    code, mout, err = run(["modes", str(out_cfg), "--json"])
    assert code == 0, err
    modes = {m["label"]: m["period"] for m in json.loads(mout)["modes"]}
    for label, T in opt["periods"].items():
        if T is not None:
            assert modes[label] == pytest.approx(T, rel=1e-9), label
    written = read_yaml(out_cfg)
    np.testing.assert_allclose(written["rig"]["anchors"], opt["rig"]["anchors"], rtol=1e-12)
    np.testing.assert_allclose(written["rig"]["attachments"], opt["rig"]["attachments"], rtol=1e-12)
    mh = doc["multi_hanging"]
    assert mh["not_identified"] == [] and len(mh["hangings"]) >= 2
    code, out, err = run(["invert", "--measurements", str(meas), "--json"])
    assert code == 0, err
    idoc = json.loads(out)
    inv = idoc["inertia"]
    for c, a in mh["accuracy"].items():
        # the planned periods are those of the prior: invert must give the prior back
        assert inv[c]["value"] == pytest.approx(a["value"], rel=1e-6), c
        # this plate's CoM lies on its attachment line (a knife edge: a 1 mm sideways error tips it);
        # the plan states attachment x and com x exact (KNIFE_EXACT) and writes that into the file, so
        # invert's std exists and is the plan's (the sigma round trip on a rig that is not a knife edge:
        # test_multi_hanging_plan_uncertainty_matches_a_monte_carlo_of_the_planned_experiment)
        assert inv[c]["std"] == pytest.approx(a["sigma"], rel=1e-6), c
    assert idoc["std_unavailable"] is None


def test_separation_guard_is_the_smallest_gap_of_any_timed_mode():
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes

    cfg = read_yaml(CONFIGS / "thesis_lin2_pitch.yaml")
    p = sw.evaluate_point(cfg, "t", {}, sw.resolve_settings(cfg, tensions=False))
    sc = scene_from_dict(cfg)
    T = {m.label: m.period for m in linear_modes(sc, rest_pose(sc)).modes}
    timed = {e["mode"] for e in p["components"].values() if e["identifiable"]}
    expect = min(abs(T[k] - T[j]) / T[k] for k in timed for j in T if j != k and T[j])
    assert p["separation"] == pytest.approx(expect, rel=1e-9)
    # the default guard (2 %) refuses this point; --min-separation 0 switches it off
    rec = sw.assess([p], sw.resolve_constraints(cfg), None)
    assert rec["best"] is None and rec["binding"] == "--min-separation"
    assert sw.assess([p], sw.resolve_constraints(cfg, min_separation=0), None)["best"] == 0


def test_modes_prints_the_body_built_from_parts():
    cfg = read_yaml(SOLAR)
    parts_mass = sum(float(d["mass"]) for d in cfg["body"]["parts"])
    code, out, err = run(["modes", str(SOLAR), "--json"])
    assert code == 0, err
    body = json.loads(out)["body"]
    assert body["mass"] == pytest.approx(parts_mass, rel=1e-12) and body["built_from"] == "parts"
    I = np.array(body["inertia"])
    np.testing.assert_allclose(np.linalg.eigvalsh(I), body["principal_moments"], rtol=1e-12)
    code, text, _ = run(["modes", str(SOLAR)])
    assert "CoM in the parts' build frame" in text and "principal moments" in text


def test_sensor_timing_bound_matches_a_least_squares_fit_of_noisy_records():
    # the Cramer-Rao bound of how_to_time's sensor model against the scatter of an independent
    # least-squares sinusoid fit of simulated records (white noise, known sample rate)
    from scipy.optimize import least_squares

    from bifilar.studies.timing import sensor_sigma

    T, noise, rate, N = 2.0, 0.05, 50.0, 4
    t = np.arange(0, N * T, 1 / rate)
    rng = np.random.default_rng(7)
    est = []
    for _ in range(300):
        y = np.sin(2 * np.pi * t / T + 0.3) + noise * rng.standard_normal(t.size)
        r = least_squares(lambda p: p[0] * np.sin(2 * np.pi * t / p[1] + p[2]) + p[3] - y, [1.0, T * 1.001, 0.3, 0.0],
                          x_scale=[1, 1e-3, 1, 1], xtol=1e-14, ftol=1e-14, gtol=1e-14)
        est.append(r.x[1])
    # 300 draws: the sample std is within ~12 % (3 sigma) of the true one
    assert np.std(est, ddof=1) == pytest.approx(sensor_sigma(T, noise, rate, N, 1), rel=0.15)


def test_stopwatch_advice_reaches_the_target_with_the_fewest_trials_and_respects_the_separation():
    from bifilar.studies.timing import MAX_CYCLES, MIN_CYCLES, how_to_time, stopwatch_sigma

    cfg = read_yaml(PLATE)
    p = sw.evaluate_point(cfg, "t", {"spacing": 2.0}, sw.resolve_settings(cfg, tensions=False))
    for target in (1e-3, 5e-3):
        rows = how_to_time(p, target, reaction=0.1)
        assert {r["mode"] for r in rows} == {p["components"][c]["mode"] for c in ("Ixx", "Izz")}
        for r in rows:
            N, n = r["cycles_per_trial"], r["stopwatch"]["trials"]
            # a whole beat with the nearest mode, within the usual 10 .. 50 cycles
            assert N == min(MAX_CYCLES, max(MIN_CYCLES, math.ceil(1 / r["separation"]))), r
            assert stopwatch_sigma(0.1, N, n) <= target * (1 + 1e-12)
            assert n == 1 or stopwatch_sigma(0.1, N, n - 1) > target


# --------------------------------------------------------------------------
# multi-hanging plans


def monte_carlo_of_plan(hp, n, rng, offset):
    """Re-run the planned experiment n times: the true body differs from the prior by ``offset`` (relative,
    per component), every hanging's measured inputs are off by draws of their uncertainty, each period
    has the timing error; the periods are exact linear periods of the perturbed hangings, and the
    estimate is invert's Gauss-Newton fit (timing-weighted; two steps, exact model periods) of the prior scenes."""
    from dataclasses import replace

    from bifilar.estimation.sensitivity import measured_inputs, periods_of
    from bifilar.estimation.uncertainty import draw_deltas, perturb_many
    from bifilar.studies.hangings import _rows, joint_covariance
    from bifilar.studies.settings import _IDX

    comps = hp.components
    I0 = hp.hangings[0].scene.inertia.copy()

    def tensor(theta):
        I = I0.copy()
        for c, v in zip(comps, theta):
            i, j = _IDX[c]
            I[i, j] = I[j, i] = v
        return I

    idx = [[next(k for k, m in enumerate(h.sens.modes.modes) if m.label == mm["mode"])
            for mm in hp.measurements if mm["hanging"] == h.name] for h in hp.hangings]
    blocks = []
    for h, ks in zip(hp.hangings, idx):
        J, Sx, Js, _ = _rows(h, comps, hp.unc)
        blocks.append((J[ks], Sx[np.ix_(ks, ks)], Js[ks]))
    C, rank, _ = joint_covariance(blocks, hp.unc["timing"])
    J = np.vstack([b[0] for b in blocks])
    G = np.linalg.solve(J.T @ J, J.T)  # invert's step: least squares weighted by the (equal) timing variances
    theta0 = np.array([hp.values[c] for c in comps])
    theta_true = theta0 * (1 + offset)
    I_true = tensor(theta_true)

    def model(theta, scenes):
        return np.concatenate([periods_of(replace(sc, inertia=h.R @ tensor(theta) @ h.R.T), h.sens.modes,
                                          h.sens.rest)[ks] for h, sc, ks in zip(hp.hangings, scenes, idx)])

    nominal = [h.scene for h in hp.hangings]
    est = []
    shared = ("mass", "com.x", "com.y", "com.z")
    for _ in range(n):
        meas = []
        # the body's own inputs err once for every hanging (one weighing; one
        # CoM, reference body axes, d_h = R d_ref), and so do the one rig's wire
        # lengths and anchors (the plan's default rig model, shared); the
        # attachments once per hanging (other body points)
        body = draw_deltas(hp.hangings[0].scene, list(shared), rng, hp.unc)
        d_ref = np.array([body["com.x"], body["com.y"], body["com.z"]])
        sc0 = hp.hangings[0].scene
        rig = draw_deltas(sc0, [x for x in measured_inputs(sc0) if x.startswith(("length", "anchor"))], rng, hp.unc)
        for h, ks in zip(hp.hangings, idx):
            deltas = draw_deltas(h.scene, [x for x in measured_inputs(h.scene) if x.startswith("attachment")], rng,
                                 hp.unc)
            deltas.update(rig)
            deltas.update({"mass": body["mass"], **dict(zip(("com.x", "com.y", "com.z"), h.R @ d_ref))})
            true_sc = perturb_many(replace(h.scene, inertia=h.R @ I_true @ h.R.T), deltas)
            T = periods_of(true_sc, h.sens.modes, h.sens.rest)[ks]
            meas.append(T + hp.unc["timing"] * rng.standard_normal(len(ks)))
        y = np.concatenate(meas)
        theta = theta0.copy()
        for _ in range(2):
            theta = theta + G @ (y - model(theta, nominal))
        est.append(theta)
    return np.array(est), theta_true


@pytest.mark.parametrize("case", ["plate", "solar boat"])
def test_multi_hanging_plan_uncertainty_matches_a_monte_carlo_of_the_planned_experiment(case):
    from bifilar.studies.hangings import plan_hangings

    if case == "plate":
        # the thesis plate on parallel wires attached 0.3 m above its CoM (away from the edge of stability,
        # so that every perturbed experiment still hangs): Ixx needs another hanging
        cfg, params = trapezoid(b=5.0, bp=5.0, h=0.3).config, {}
    else:  # the plan of docs/solar_boat.md section 5 (rig rounded): one hanging, four modes
        cfg, params = read_yaml(SOLAR), {"spacing": 2.094, "length": 4.059}
    st = sw.resolve_settings(cfg, tensions=False)
    hp = plan_hangings(cfg, "t", params, st, ["Ixx", "Iyy", "Izz"], 0.05)
    assert hp.missing == [] and len(hp.hangings) >= (2 if case == "plate" else 1)
    acc = hp.accuracy()
    n = 120
    est, truth = monte_carlo_of_plan(hp, n, np.random.default_rng(3), offset=0.01)
    sd = est.std(axis=0, ddof=1)
    for i, c in enumerate(hp.components):
        # 120 draws: the sample std is within ~20 % (3 sigma) of the true one; the mean within 3 sd / sqrt(n)
        assert sd[i] == pytest.approx(acc[c]["sigma"], rel=0.2), c
        assert abs(est[:, i].mean() - truth[i]) < 3 * acc[c]["sigma"] / math.sqrt(n) + 1e-4 * truth[i], c


def test_reference_column_is_the_derivative_of_a_turned_hangings_periods():
    # dT/dI_ref of a hanging turned by R, against central differences of the exact linear periods of the
    # turned body with the reference tensor changed (I_h = R (I + d E_c) R^T)
    from dataclasses import replace

    from bifilar.estimation.sensitivity import periods_of
    from bifilar.studies.remedy import hanging_config, hanging_sensitivity, reference_column, rotation

    base = trapezoid(b=5.0, bp=5.0, h=0.3)
    I0 = base.inertia
    for rv in ((45.0, 0.0, 0.0), (0.0, 30.0, 60.0)):
        R = rotation(rv)
        sc, sens, _ = hanging_sensitivity(hanging_config(base, R, "turned"))
        for comp, (i, j) in (("Ixx", (0, 0)), ("Ixy", (0, 1)), ("Iyz", (1, 2))):
            E = np.zeros((3, 3))
            E[i, j] = E[j, i] = 1.0
            h = 1e-4 * float(np.max(np.linalg.eigvalsh(I0)))
            Tp, Tm = (periods_of(replace(sc, inertia=R @ (I0 + s * h * E) @ R.T), sens.modes, sens.rest)
                      for s in (1, -1))
            np.testing.assert_allclose(reference_column(sens, R, comp), (Tp - Tm) / (2 * h), rtol=1e-4,
                                       atol=1e-9 * float(np.max(sens.periods)) / h, err_msg=f"{rv} {comp}")


def test_plan_for_a_target_no_point_can_measure_names_its_remedy():
    code, out, err = run(["plan", str(PLATE), "--param", "spacing=1:4", "--no-tensions", "--target", "Iyy"])
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert err.startswith("error: --target: Iyy is not identifiable") and "remedy" in err and "pitch" in err, err
