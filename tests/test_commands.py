"""End-to-end CLI checks of modes, simulate and tensions on the example configs
(interface.md shapes; numbers checked against closed forms where one exists)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.cli import main

from conftest import CONFIGS


def run(*args):
    r = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    return r


@pytest.mark.parametrize("cfg", sorted(p for p in CONFIGS.glob("*.yaml") if not p.stem.startswith("measurements")),
                         ids=lambda p: p.stem)
def test_modes_json_on_every_example(cfg):
    r = run("modes", cfg, "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    eq = doc["equilibrium"]
    R = np.array(eq["rotation"])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert all(T > 0 for T in eq["tensions"])
    assert len(doc["modes"]) == 6 - len(eq["tensions"])
    for m in doc["modes"]:
        assert max(abs(v) for v in m["shape"]) == pytest.approx(1.0)
        assert m["period"] is None or m["period"] > 0


@pytest.mark.parametrize("cfg", sorted(p for p in CONFIGS.glob("*.yaml") if not p.stem.startswith("measurements")),
                         ids=lambda p: p.stem)
def test_simulate_json_on_every_example(cfg):
    r = run("simulate", cfg, "--periods", "2", "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    # default run (rtol 1e-10, amplitude 0.05): the constraint holds to ~1e-11 of the wire length and the
    # energy of the oscillation to ~1e-8; the measured period is within a few per mille of the linear one
    assert doc["max_constraint_violation"] < 1e-9 and doc["energy_drift"] < 1e-6
    assert doc["period"] == pytest.approx(doc["linear_period"], rel=5e-3)
    assert min(doc["tension"]["min"]) > 0 and not doc["slack"]


def test_modes_thesis_plate_numbers():
    doc = json.loads(run("modes", CONFIGS / "thesis_plate_rest.yaml", "--json").stdout)
    # thesis Fig 7.2.1: 566 N per wire; 6.1: side sway 2 pi sqrt(5 cos 30 / g)
    np.testing.assert_allclose(doc["equilibrium"]["tensions"], 981 / (2 * np.cos(np.pi / 6)), rtol=1e-12)
    sway = next(m for m in doc["modes"] if m["label"] == "swing-x")
    assert sway["period"] == pytest.approx(2 * np.pi * np.sqrt(5 * np.cos(np.pi / 6) / 9.81), rel=1e-12)


def test_simulate_json_interface_and_health():
    r = run("simulate", CONFIGS / "thesis_plate_rest.yaml", "--mode", "torsion", "--amplitude", "0.05",
            "--periods", "4", "--json")
    assert r.exit_code == 0
    doc = json.loads(r.stdout)
    for key in ("period", "linear_period", "max_constraint_violation", "energy_drift", "tension"):
        assert key in doc
    assert doc["max_constraint_violation"] < 1e-9
    assert doc["energy_drift"] < 1e-6
    assert doc["period"] > doc["linear_period"]  # hardening: period grows with amplitude for this rig
    assert len(doc["tension"]["min"]) == 2


# slack wires during the motion: tests/test_cli.py (trifilar twisted to nearly horizontal wires)


def test_simulate_out_and_plot_files(tmp_path):
    out, png = tmp_path / "run.csv", tmp_path / "run.png"
    r = run("simulate", CONFIGS / "drone_parallel.yaml", "--periods", "2", "--out", out, "--plot", png)
    assert r.exit_code == 0, r.output
    data = np.genfromtxt(out, delimiter=",", names=True)
    assert {"t", "com_z", "tension_1", "tension_2"} <= set(data.dtype.names)
    assert png.stat().st_size > 1000
    # a second run must not overwrite without --force
    r2 = run("simulate", CONFIGS / "drone_parallel.yaml", "--periods", "2", "--out", out)
    assert r2.exit_code == 2 and "--force" in r2.stderr


def test_tensions_command_thesis_methods_agree():
    r = run("tensions", CONFIGS / "thesis_lin2_pitch.yaml", "--amplitude", "0.2", "--periods", "2", "--json")
    assert r.exit_code == 0
    doc = json.loads(r.stdout)
    assert max(doc["general"]["max_abs_difference_to_model"]) < 1e-6
    assert doc["inertia_from_tensions"]["Izz"]["value"] == pytest.approx(260.4166666667, rel=1e-6)
    assert "Ixx" in doc["inertia_from_tensions_poorly_excited"]


def test_tensions_prints_no_value_for_a_component_the_motion_does_not_excite(tmp_path):
    """A vertical bifilar's torsion hardly turns the body about x or y: the fit
    holds Ixx, Iyy at the config's values, so their first-pass numbers (Iyy
    20.3 for a true 30 in an audit) are not determined and must not be
    printed; the excited Izz still holds the config's value in its interval."""
    import yaml

    cfg = tmp_path / "vertical.yaml"
    cfg.write_text(yaml.safe_dump({
        "body": {"mass": 50.0, "inertia": {"principal": [20.0, 30.0, 40.0]}},
        "rig": {"anchors": [[-0.5, 0.0, 2.1], [0.5, 0.0, 2.1]], "attachments": [[-0.5, 0.0, 0.1], [0.5, 0.0, 0.1]],
                "lengths": [2.0, 2.0]}}))
    r = run("tensions", cfg, "--periods", "2", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    est, poor = doc["inertia_from_tensions"], doc["inertia_from_tensions_poorly_excited"]
    assert {"Ixx", "Iyy"} <= set(poor) and "Izz" not in poor
    for c in ("Ixx", "Iyy"):
        assert est[c]["value"] is None and est[c]["std"] is None and est[c]["interval_95"] == [None, None]
        assert "not determined" in est[c]["reason"] and est[c]["config"] == pytest.approx(10.0 * (2 + "xy".index(c[1])))
    lo, hi = est["Izz"]["interval_95"]
    assert lo <= 40.0 <= hi and est["Izz"]["value"] == pytest.approx(40.0, rel=1e-6)
    table = run("tensions", cfg, "--periods", "2")
    assert table.exit_code == 0 and table.stdout.count("not determined") == 2, table.stdout
