"""`bifilar invert` and `bifilar period` on the command line: the JSON of
interface.md, exit status 2 with one line naming the argument for bad input,
plots, the measurements file, and the start-up-excluded run time of the
exact linear method."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.cli import main
from bifilar.config import load_scene

from conftest import CONFIGS

LIN1 = CONFIGS / "thesis_lin1_torsion.yaml"
LIN2 = CONFIGS / "thesis_lin2_pitch.yaml"
PLATE = CONFIGS / "thesis_plate_rest.yaml"
I_B1 = 100 * (25 + 6.25) / 12


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def lines(text):
    return [ln for ln in text.splitlines() if ln.strip()]


def linear_period(cfg, mode):
    s = load_scene(cfg, warn=False)
    return linear_modes(s, rest_pose(s)).get(mode).period


def test_invert_json_per_interface():
    T = linear_period(LIN2, "torsion")
    r = run("invert", LIN2, "--period", f"torsion={T!r}+-0.001", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)  # exactly one JSON document on stdout
    assert set(doc["inertia"]) == {"Izz"}  # picked: the component torsion is most sensitive to
    # noise-free linear period -> the config's inertia (1e-9: root finder stops at 1e-12 in T)
    assert doc["inertia"]["Izz"]["value"] == pytest.approx(I_B1, rel=1e-9)
    assert doc["inertia"]["Izz"]["std"] > 0
    assert doc["method"] == "linear"
    assert [row["method"] for row in doc["ladder"]] == ["small-angle", "thesis", "linear"]
    shares = doc["budget"]["Izz"]["groups"]
    assert sum(g["share"] for g in shares.values()) == pytest.approx(1.0, rel=1e-12)
    assert doc["assumed_uncertainty"]["length"]["value"] == 1e-3


def test_solve_for_repeats_and_several_periods():
    s = load_scene(LIN2, warn=False)
    ms = linear_modes(s, rest_pose(s))
    args = []
    for m in ("torsion", "pitch", "swing-y"):
        args += ["--period", f"{m}={ms.get(m).period!r}+-0.0005"]
    r = run("invert", LIN2, *args, "--solve-for", "Izz", "--solve-for", "Iyy", "--solve-for", "Ixx", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    want = {"Ixx": 100 * 25 / 12, "Iyy": 100 * 6.25 / 12, "Izz": I_B1}
    for n, v in want.items():  # noise-free periods: Gauss-Newton to 1e-9
        assert doc["inertia"][n]["value"] == pytest.approx(v, rel=1e-9)
    C = np.array(doc["correlation"]["matrix"])
    assert doc["correlation"]["names"] == ["Ixx", "Iyy", "Izz"] and C.shape == (3, 3)


def test_timed_trials_and_uncertainty_override():
    r = run("invert", LIN2, "--timed", "torsion=10:19.05,19.06,19.04", "--uncertainty", "mass=0.01",
            "--uncertainty", "trial_time=0.005", "--amplitude", "0", "--json")  # floor below the 0.01 s scatter
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    m = doc["measurements"][0]
    assert m["source"] == "timed" and m["period"] == pytest.approx(1.905, rel=1e-12)
    assert m["std"] == pytest.approx(0.01 / math.sqrt(3) / 10, rel=1e-12)
    assert doc["assumed_uncertainty"]["mass"]["value"] == 0.01
    # a 1 % mass uncertainty dominates the torsion estimate (I ~ m T^2)
    assert doc["budget"]["Izz"]["groups"]["mass"]["share"] > 0.5


@pytest.mark.parametrize("args,field", [
    (["--period", "wobble=2.0"], "--period"),
    (["--period", "torsion"], "--period"),
    (["--period", "torsion=fast"], "--period"),
    (["--period", "torsion=-2"], "--period"),
    (["--period", "torsion=2+-"], "--period"),
    (["--period", "swing-x=10"], "--period"),  # no inertia makes the swing last 10 s
    (["--period", "torsion=1.9", "--solve-for", "Iww"], "--solve-for"),
    (["--period", "torsion=1.9", "--method", "best"], "--method"),
    (["--period", "torsion=1.9", "--amplitude", "pitch=0.1"], "--amplitude"),
    (["--period", "torsion=1.9", "--monte-carlo", "many"], "--monte-carlo"),
    (["--period", "torsion=1.9", "--uncertainty", "colour=1"], "--uncertainty"),
    (["--period", "pitch=1.9", "--method", "small-angle"], "--method"),  # not torsion
    ([], "--period"),
])
def test_bad_input_exit_2_one_line(args, field):
    r = run("invert", LIN2, *args)
    assert r.exit_code == 2, (r.stdout, r.stderr)
    ls = lines(r.stderr)
    assert len(ls) == 1 and ls[0].startswith(f"error: {field}"), ls
    assert r.stdout == ""


def test_unreachable_period_says_the_achievable_range():
    r = run("invert", LIN2, "--period", "swing-x=10", "--solve-for", "Iyy")
    assert r.exit_code == 2
    assert "range over" in r.stderr and " s .. " in r.stderr


def test_method_forced_and_nonlinear_needs_amplitude():
    T = linear_period(PLATE, "torsion")
    r = run("invert", PLATE, "--period", f"torsion={T!r}", "--method", "small-angle", "--amplitude", "0", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    # inclined wires: the formula gives b'/b = 1/2 of the truth, and the
    # budget carries the difference from the best rung as model bias
    assert doc["method"] == "small-angle"
    assert doc["inertia"]["Izz"]["value"] == pytest.approx(I_B1 / 2, rel=1e-9)
    assert doc["budget"]["Izz"]["groups"]["model bias"]["share"] > 0.99
    r = run("invert", PLATE, "--period", f"torsion={T!r}", "--method", "nonlinear")
    assert r.exit_code == 2 and "--method" in r.stderr and "amplitude" in r.stderr


def test_plot_files_and_force(tmp_path):
    T = linear_period(LIN2, "torsion")
    out = tmp_path / "curve.png"
    r = run("invert", LIN2, "--period", f"torsion={T!r}", "--plot", out)
    assert r.exit_code == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    r = run("invert", LIN2, "--period", f"torsion={T!r}", "--plot", out)
    assert r.exit_code == 2 and "--force" in r.stderr
    r = run("invert", LIN2, "--period", f"torsion={T!r}", "--plot", LIN2, "--force")
    assert r.exit_code == 2 and "input" in r.stderr


def test_measurements_file_and_signal(tmp_path):
    # a recorded torsion of the thesis plate (CoM 0.5 m below CD): a damped
    # cosine whose undamped period is the model's linear period at the truth
    T = linear_period(LIN2, "torsion")
    zeta, fs = 0.01, 50.0
    wn = 2 * math.pi / T
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.arange(0, 60, 1 / fs)
    y = 0.01 * np.exp(-zeta * wn * t) * np.cos(wd * t) + np.random.default_rng(1).normal(0, 1e-5, t.size)
    rec = tmp_path / "torsion.csv"
    np.savetxt(rec, np.column_stack([t, y]), delimiter=",", header="time,angle", comments="")
    mfile = tmp_path / "m.yaml"
    mfile.write_text(f"config: {LIN2}\nmeasurements:\n  - mode: torsion\n    signal: torsion.csv\n"
                     "    quantity: angle\n    model: viscous\n")
    r = run("invert", "--measurements", mfile, "--json", "--plot", tmp_path / "p.png")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    m = doc["measurements"][0]
    assert m["source"] == "signal" and m["damping_ratio"] == pytest.approx(zeta, rel=0.05)
    # the damping is removed before inverting: the truth within 3 std
    Izz = doc["inertia"]["Izz"]
    assert abs(Izz["value"] - I_B1) < 3 * Izz["std"]
    assert doc["method"] == "nonlinear"  # the fit gave the amplitude (quantity: angle)
    assert len(doc["plots"]) == 2 and all(Path(p).exists() for p in doc["plots"])
    # CLI --signal gives the same period as the file
    r2 = run("invert", LIN2, "--signal", f"torsion={rec}", "--signal-model", "viscous", "--json")
    assert r2.exit_code == 0, r2.stderr
    assert json.loads(r2.stdout)["measurements"][0]["period"] == pytest.approx(m["period"], rel=1e-12)


def test_measurements_file_errors_name_fields(tmp_path):
    f = tmp_path / "m.yaml"
    f.write_text(f"config: {LIN2}\nmeasurements:\n  - mode: torsion\n    period: soon\n")
    r = run("invert", "--measurements", f)
    assert r.exit_code == 2
    assert lines(r.stderr) == ["error: measurements.0.period: expected SECONDS[+-SIGMA] with numbers, got 'soon'"]


def test_example_measurements_file_cli():
    r = run("invert", "--measurements", CONFIGS / "measurements_example.yaml", "--no-ladder")
    assert r.exit_code == 0, r.stderr
    for word in ("Ixx", "Iyy", "Izz", "Correlation", "budget", "assumed standard uncertainties"):
        assert word in r.stdout


def test_linear_inversion_needs_no_global_rest_pose_search(monkeypatch):
    """The linear method's speed (< 100 ms after start-up, benchmarked in
    scripts/, not asserted here) rests on every rest pose after the first
    being found by Newton from a neighbour: a fall-back to the global SLSQP
    search per sensitivity or scan point costs ~2 s.  Counted, not timed
    (a timed assertion fails on a loaded machine and proves nothing)."""
    from bifilar.analysis import equilibrium

    calls = []
    real = equilibrium._slsqp
    monkeypatch.setattr(equilibrium, "_slsqp", lambda *a, **k: calls.append(1) or real(*a, **k))
    T = linear_period(LIN1, "torsion")
    r = CliRunner().invoke(main, ["invert", str(LIN1), "--period", f"torsion={T!r}+-0.001", "--json"])
    assert r.exit_code == 0, r.stderr
    assert len(calls) == 0, f"{len(calls)} global rest-pose searches"


# --------------------------------------------------------------------------- bifilar period


def test_period_json_per_interface(tmp_path):
    T_d, zeta = 1.4811, 0.001
    wd = 2 * math.pi / T_d
    wn = wd / math.sqrt(1 - zeta**2)
    t = np.arange(0, 30, 0.01)
    y = np.exp(-zeta * wn * t) * np.sin(wd * t) + np.random.default_rng(2).normal(0, 1e-3, t.size)
    f = tmp_path / "sig.csv"
    np.savetxt(f, np.column_stack([t, y]), delimiter=",", header="t,gyro", comments="")
    r = run("period", f, "--json", "--model", "viscous", "--plot", tmp_path / "fit.png")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    assert list(doc)[:3] == ["period", "std", "damping_ratio"]
    assert abs(doc["period"] - T_d) < 5 * doc["std"]  # the fit's own std is the yardstick
    assert doc["damping_ratio"] == pytest.approx(zeta, abs=5e-4)
    assert (tmp_path / "fit.png").exists()
    # --sample-rate instead of the time column gives the same fit
    r2 = run("period", f, "--json", "--model", "viscous", "--sample-rate", "100", "--column", "gyro")
    assert json.loads(r2.stdout)["period"] == pytest.approx(doc["period"], rel=1e-9)


@pytest.mark.parametrize("args,field", [
    (["--model", "magic"], "--model"),
    (["--sample-rate", "fast"], "--sample-rate"),
    (["--column", "nope"], "--column"),
])
def test_period_bad_input(tmp_path, args, field):
    f = tmp_path / "sig.csv"
    t = np.arange(0, 10, 0.01)
    np.savetxt(f, np.column_stack([t, np.sin(t)]), delimiter=",", header="t,y", comments="")
    r = run("period", f, *args)
    assert r.exit_code == 2
    ls = lines(r.stderr)
    assert len(ls) == 1 and ls[0].startswith(f"error: {field}"), ls


# `period --json` on the real gyro record: tests/test_period_real.py


# --------------------------------------------------------------------------- roots, refusals, guesses (issue 10)

R1_YAML = ("body: {mass: 100.0, inertia: {tensor: [[215.0,0,0],[0,52.0833333333,3.0],[0,3.0,260.4166666667]]}}\n"
           "rig: {anchors: [[0,-5,0],[0,5,0]], attachments: [[0,-2.5,0.5],[0,2.5,0.5]], lengths: [5.0,5.0]}\n")


def test_ambiguous_roots_in_json(tmp_path):
    cfg = tmp_path / "r1.yaml"
    cfg.write_text(R1_YAML)
    s = load_scene(cfg)
    I = s.inertia.copy()
    I[1, 2] = I[2, 1] = 20.0
    from dataclasses import replace
    s2 = replace(s, inertia=I)
    T = linear_modes(s2, rest_pose(s2)).get("torsion").period
    r = run("invert", cfg, "--period", f"torsion={T!r}+-0.0001", "--solve-for", "Iyz", "--json", "--no-ladder")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    vals = sorted(x["inertia"]["Iyz"]["value"] for x in doc["roots"])
    # the mirror-symmetric rig: -20 and +20 give the same torsion period
    assert doc["ambiguous"] is True and vals == pytest.approx([-20.0, 20.0], rel=1e-6)
    assert doc["inertia"]["Iyz"]["value"] == doc["roots"][0]["inertia"]["Iyz"]["value"]
    assert all(x["inertia"]["Iyz"]["std"] > 0 for x in doc["roots"])
    assert "warning:" in r.stderr and "cannot tell them apart" in r.stderr
    t = run("invert", cfg, "--period", f"torsion={T!r}+-0.0001", "--solve-for", "Iyz", "--no-ladder")
    assert t.exit_code == 0 and "AMBIGUOUS" in t.stdout


@pytest.mark.parametrize("period", ["1e300", "1e-300"])
def test_unreachable_extreme_period_is_exit_2(tmp_path, period):
    cfg = tmp_path / "r1.yaml"
    cfg.write_text(R1_YAML)
    r = run("invert", cfg, "--period", f"torsion={period}", "--solve-for", "Izz", "--json")
    assert r.exit_code == 2 and r.stdout == ""
    ls = lines(r.stderr)
    assert len(ls) == 1 and ls[0].startswith("error: --period: no physical Izz"), ls


def test_guessed_and_null_priors_on_the_command_line(tmp_path):
    T = linear_period(LIN1, "torsion")
    text = LIN1.read_text()
    assert "principal: [208.3333333333, 52.0833333333, 260.4166666667]" in text
    # the thin plate with a prior Izz above Ixx + Iyy: only a starting guess
    hi = tmp_path / "hi.yaml"
    hi.write_text(text.replace("260.4166666667", "300.0"))
    r = run("invert", hi, "--period", f"torsion={T!r}+-0.001", "--solve-for", "Izz", "--json", "--no-ladder")
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["inertia"]["Izz"]["value"] == pytest.approx(I_B1, rel=1e-6)
    # not solved for, it is a known value and checked as such on load
    bad = run("invert", hi, "--period", f"torsion={T!r}")
    assert bad.exit_code == 2 and "body.inertia.principal" in bad.stderr and "triangle" in bad.stderr
    # solving for Ixx instead, Izz = 300 is given: the torsion period does not depend on Ixx (less than
    # 1e-6 over its physical range), a refusal naming the component and the mode that would measure it
    bad = run("invert", hi, "--period", f"torsion={T!r}", "--solve-for", "Ixx")
    assert bad.exit_code == 2 and bad.stderr.startswith("error: --solve-for: Ixx cannot be solved for")
    # Izz unknown (null): solved for without --solve-for, the start said in a note
    nul = tmp_path / "null.yaml"
    nul.write_text(text.replace("260.4166666667", "null"))
    r = run("invert", nul, "--period", f"torsion={T!r}+-0.001", "--json", "--no-ladder")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    assert list(doc["inertia"]) == ["Izz"] and doc["inertia"]["Izz"]["value"] == pytest.approx(I_B1, rel=1e-6)
    assert any("null" in n for n in doc["notes"])
    other = run("invert", nul, "--period", f"torsion={T!r}", "--solve-for", "Ixx")
    assert other.exit_code == 2 and "--solve-for" in other.stderr
    assert run("modes", nul).exit_code == 2
