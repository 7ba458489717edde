"""Closed-loop audit of the planner, session 11 (docs/design.md): the
experiment `sweep` and `plan` describe, done on rigs unlike the shipped
configs, against what they predict."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis.batch import simulate_batch
from bifilar.cli import main
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.uncertainty import DEFAULT_AMPLITUDE_REL

from conftest import measured_scene

# a 6 kg body on three wires of 0.74, 0.99 and 1.24 m from anchors at three heights (hangs level)
TRIFILAR_UNEQUAL = """\
name: trifilar, unequal wires (audit session 11)
body:
  mass: 6.0
  inertia: {principal: [0.085, 0.11, 0.16]}
  bounding_box: {min: [-0.3, -0.3, -0.08], max: [0.3, 0.3, 0.02]}
rig:
  anchors:     [[0.32, 0.0, 0.80], [-0.16, 0.277128, 1.05], [-0.16, -0.277128, 1.30]]
  attachments: [[0.25, 0.0, 0.06], [-0.125, 0.216506, 0.06], [-0.125, -0.216506, 0.06]]
  lengths:     [0.74, 0.99, 1.24]
uncertainty: {timing: 0.001, length: 0.001, position: 0.001, com: 0.002, mass: 0.001}
"""


def _cli(*args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.stderr
    return json.loads(r.stdout)


def test_advice_on_an_unstated_amplitude_beyond_its_range_says_the_estimate_is_off(tmp_path):
    # sweep --amplitude 0.3 (rad, 17 degrees) recommends timing the torsion there and stating it; its advice
    # also gave the std invert prints without --amplitude (a 0-10 degree release budgeted) as 0.92 times the
    # sigma, as if leaving the amplitude out cost nothing.  Done: 40 experiments released at 0.3 with its
    # 10 %, inputs drawn from their stds, 10 cycles timed with 1 ms, inverted without --amplitude: their
    # estimates sit ~1.6 % (3 stds) above the truth and the 95 % interval misses it in nearly every one.
    # The advice now says so: the error it states is the realised mean error within 3 standard errors of
    # that mean (and within 5 % of it: the release's spread moves the mean by ~1 %), the interval flagged
    # Test economy, session 23: 20 experiments (was 40; the inverts 4.3 -> 2.1 s of CPU).  Here: mean error
    # 2.63e-3, 20 of its standard errors above the truth (40: 2.40e-3, 20), none of the intervals holds it
    # (40: 12.5 %); the advice's error (2.49e-3) sits 1.4e-4 from the mean against a band of 5.2e-4, 20 % of
    # the mean (40: 0.9e-4 against 4.7e-4, 20 %).  The advice's error scaled by 1.3
    # (studies/amplitude.unstated_beyond_range) fails the band (checked, session 23); an advice silent about
    # it or stating no error (the old one) fails as before
    cfg = tmp_path / "tri.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    point = tmp_path / "point.yaml"
    A = 0.3
    doc = _cli("sweep", cfg, "--param", "spacing=0.4", "--param", "length=1.2", "--component", "Izz",
               "--amplitude", A, "--write-config", point, "--json")
    adv = doc["recommendation"]["amplitude_advice"]
    row = adv["components"]["Izz"]
    truth = doc["points"][0]["components"]["Izz"]["value"]
    scene = scene_from_dict(read_yaml(point), warn=False)
    unc = doc["points"][0]["uncertainty"]
    rng = np.random.default_rng(11)
    n = 20
    amps = A * (1 + DEFAULT_AMPLITUDE_REL * rng.standard_normal(n))
    periods = [r.period for r in simulate_batch([scene] * n, mode="torsion", amplitude=list(amps), periods=10,
                                                rtol=1e-10)]
    err, held = [], []
    for T in periods:
        ms = MeasurementSet([Hanging("reference", measured_scene(scene, rng, unc), np.eye(3))],
                            [Measurement("torsion", T + rng.normal(0, unc["timing"]), unc["timing"], "period",
                                         "--period")])
        ms.uncertainty = dict(unc)
        res = invert(ms, solve_for=["Izz"], ladder=False)
        err.append(res.value("Izz") - truth)
        lo, hi = res.interval[0]
        held.append(lo <= truth <= hi)
    err = np.array(err)
    se = err.std(ddof=1) / np.sqrt(n)
    assert err.mean() > 6 * se and np.mean(held) < 0.5  # the experiment: off, and not covered
    b = row.get("unstated_beyond_range")
    assert b is not None, "the advice does not say that an unstated 0.3 rad release is outside invert's range"
    assert b["interval_holds_truth"] is False
    assert abs(b["error"] - err.mean()) < 3 * se + 0.05 * abs(err.mean())
    assert b["error_in_std"] > 2 and "state the amplitude" in adv["text"]


def test_advice_within_the_unstated_range_is_unchanged(tmp_path):
    # at 0.1 rad (below 10 degrees) the unstated budget covers the release: no such entry, no extra work
    cfg = tmp_path / "tri.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    doc = _cli("sweep", cfg, "--param", "spacing=0.4", "--param", "length=1.2", "--component", "Izz",
               "--amplitude", 0.1, "--json")
    adv = doc["recommendation"]["amplitude_advice"]
    assert adv["components"]["Izz"]["unstated_beyond_range"] is None
    assert "beyond that range" not in adv["text"]


HANGINGS_LENGTHS = (0.6, 1.0)
HANGINGS_ARGS = ("--component", "Izz", "--component", "Ixx", "--component", "Iyy", "--amplitude", 0.2, "--hangings",
                 "--json")


@pytest.fixture(scope="module")
def hangings_at_points(tmp_path_factory):
    """The multi-hanging plan's worst relative sigma (Izz, Ixx, Iyy at 0.2 rad) at each wire length of
    HANGINGS_LENGTHS, each point swept alone with --hangings (its plan is the one at the recommended point).
    The first point's sweep also writes its measurements file (``--write-measurements``), which
    test_a_written_measurements_file_inverted_unchanged_returns_the_configs_inertia inverts: (config,
    {length: worst}, the first point's JSON, its measurements file)."""
    d = tmp_path_factory.mktemp("hangings")
    cfg, mfile = d / "tri.yaml", d / "M.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    worst, first = {}, None
    for L in HANGINGS_LENGTHS:
        write = ("--write-measurements", mfile) if first is None else ()
        doc = _cli("sweep", cfg, "--param", f"length={L}", *write, *HANGINGS_ARGS)
        first = first or doc
        worst[L] = max(a["rel_sigma"] for a in doc["recommendation"]["multi_hanging"]["accuracy"].values())
    return cfg, worst, first, mfile


def test_sweep_with_hangings_recommends_the_point_whose_hangings_are_best(hangings_at_points):
    # `sweep --hangings` ranked the points by their own hanging's sigmas (Ixx from a swing, best at the
    # shorter wires) and planned the hangings at the winner: on this trifilar's 4 x 4 grid (spacing
    # 0.3-0.6, length 0.6-1.2) the corner spacing 0.3, length 0.6, whose hangings give 2.3 % worst where
    # those at spacing 0.4, length 1.0 give 0.48 %.  With --hangings the experiment is the hangings': the
    # recommendation must be the point whose multi-hanging plan is the most accurate (each point's plan
    # computed on its own, above; 1e-9 for ties)
    cfg, worst = hangings_at_points[:2]
    assert worst[1.0] < 0.9 * worst[0.6]  # the case: the own hanging's best (0.6) is not the hangings' best
    doc = _cli("sweep", cfg, "--param", "length=" + ",".join(map(str, HANGINGS_LENGTHS)), *HANGINGS_ARGS)
    rec = doc["recommendation"]
    got = max(a["rel_sigma"] for a in rec["multi_hanging"]["accuracy"].values())
    assert got <= min(worst.values()) * (1 + 1e-9), (rec["params"], got, worst)
    assert rec["hangings_objective"] == pytest.approx(got, rel=1e-9)


def test_plan_with_hangings_is_as_good_as_the_grid_points_hangings(hangings_at_points):
    # `plan --hangings` over the same range searched the planned hanging's own sigmas and ended at length
    # 0.6 (2.2 % by its hangings); it now takes, of the points its search evaluated, the one whose hangings
    # plan is best (length 0.9, 1.6 %): at least as good as the range's ends' (band 2 %)
    cfg, worst = hangings_at_points[:2]
    doc = _cli("plan", cfg, "--param", f"length={HANGINGS_LENGTHS[0]}:{HANGINGS_LENGTHS[-1]}", *HANGINGS_ARGS)
    got = max(a["rel_sigma"] for a in doc["multi_hanging"]["accuracy"].values())
    assert got <= 1.02 * min(worst.values()), (doc["optimum"]["params"], got, worst)
    # it says what that figure is the best of: the points the search evaluated, not a search of it (session 12)
    opt = doc["optimum"]
    assert 1 < opt["hangings_ranked"] <= doc["evaluations"]
    assert f"of the {opt['hangings_ranked']} feasible points the search evaluated" in opt["hangings_note"]


def test_a_written_measurements_file_inverted_unchanged_returns_the_configs_inertia(hangings_at_points):
    """The measurements file a plan writes holds the periods the config's
    body shows at the planned amplitude, and ``invert --measurements`` of
    that file unchanged must return the config's inertia: the same inputs,
    the same model, no noise, so every component within a small fraction
    of its std (the runs' own period error is ~1e-9 s against a 1 ms
    timing std).  The file took its periods from the plan's 3-period runs
    while invert models 10 cycles; for the unequal trifilar's hangings at
    0.2 (modes that beat) they differed by up to 0.98 ms, and Ixx came back
    0.22 std from the truth (docs/design.md, closed-loop audit of the
    planner, session 11: found, then fixed).

    Test economy, session 26: the file is the one the fixture's sweep at
    length 0.6 (the config's spacing, 0.5) writes.  Its plan's 3-period
    periods differ from the 10-cycle ones the file holds by up to 9.98 ms
    (swing-y; swing-x -0.33, the 45-degree-about-x torsion +0.25 ms), and
    with the 10-cycle runs taken out (``hangings._periods_over_cycles``
    returning the planned periods) this test fails: z Izz +0.325, Ixx
    -0.102, Iyy -0.068 against the band 0.02 (with them: |z| <= 1.5e-7).
    The session-11 point (spacing 0.3, length 0.6) fails it too (Ixx
    -0.223, 0.98 ms).  teeth26b, session 26: suite26's "|z| <= 1.5e-7 with
    them taken out" is not what this code gives (how that break was made is
    not recorded); the last assertion keeps the case in reach: should the
    plan's periods ever equal the 10-cycle ones (checked: the plan's
    ``period_at_amplitude`` set to them fails it, 4e-9 s apart), it says
    so instead of passing without teeth.  Also caught: the file's amplitude
    written as 0 (invert refuses it: swing-x +29.6 sigma)."""
    _, _, doc, mfile = hangings_at_points
    truth = {c: doc["points"][0]["components"][c]["value"] for c in ("Izz", "Ixx", "Iyy")}
    out = _cli("invert", "--measurements", mfile, "--json")
    z = {c: (out["inertia"][c]["value"] - truth[c]) / out["inertia"][c]["std"] for c in truth}
    assert all(abs(v) < 0.02 for v in z.values()), z
    # the case: a written period over invert's cycles more than a timing std (1 ms) from the plan's 3-period
    # one (9.98 ms here), the difference the test's band is to catch
    written = {(h["name"], m["mode"]): float(str(m["period"]).split("+-")[0])
               for h in read_yaml(mfile)["hangings"] for m in h["measurements"]}
    planned = {(m["hanging"], m["mode"]): m["period_at_amplitude"]
               for m in doc["recommendation"]["multi_hanging"]["measurements"]}
    assert written.keys() == planned.keys() and max(abs(written[k] - planned[k]) for k in written) > 1e-3, planned


def test_with_hangings_the_physical_limit_warning_uses_the_joint_sigma(tmp_path):
    """With ``--hangings`` the experiment is the multi-hanging plan, so the
    fraction of experiments whose periods no physical inertia explains
    (``p_unphysical``) is that of the plan's joint sigma.  The unequal
    trifilar's point at spacing 0.48, length 1.2 at 0.2: its own hanging
    gets Ixx from a swing (sigma 0.24 kg m^2, 280 %), 0.15 of it from the
    limit 0.05 (positive definite with the other components), and warned
    of 66 % of experiments (found in the session-11 audit, not fixed);
    the plan's three torsions give Ixx to 0.38e-3 kg m^2, the limit 93 of
    them away (p below any float).  Checked against the normal tail from the
    JSON's own interval and sigma, not the code's number."""
    import math

    cfg = tmp_path / "tri.yaml"
    cfg.write_text(TRIFILAR_UNEQUAL)
    doc = _cli("sweep", cfg, "--param", "spacing=0.48", "--param", "length=1.2", *HANGINGS_ARGS)
    own = doc["points"][0]["components"]["Ixx"]
    assert own["p_unphysical"] > 0.5  # the case: the own hanging's sigma would warn
    assert not any("Ixx" in w and "physical limit" in w for w in doc["warnings"]), doc["warnings"]
    for c, a in doc["recommendation"]["multi_hanging"]["accuracy"].items():
        lo, hi = a["physical_interval"]
        z = min(a["value"] - lo, hi - a["value"]) / a["sigma"]
        assert z > 20 and a["p_unphysical"] <= math.erfc(z / math.sqrt(2)), (c, z)
    # where the joint sigma does reach the limit it still warns: the same body made flat (Izz = Ixx + Iyy)
    flat = tmp_path / "flat.yaml"
    flat.write_text(TRIFILAR_UNEQUAL.replace("[0.085, 0.11, 0.16]", "[0.085, 0.11, 0.195]"))
    doc = _cli("sweep", flat, "--param", "spacing=0.48", "--param", "length=1.2", *HANGINGS_ARGS)
    acc = doc["recommendation"]["multi_hanging"]["accuracy"]
    assert acc["Izz"]["p_unphysical"] > 0.3
    assert any(w.startswith("the recommended point: Izz by the multi-hanging plan:") for w in doc["warnings"])
