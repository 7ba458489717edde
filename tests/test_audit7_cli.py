"""Audit, session 7: the command line on inputs nobody here wrote (docs/design.md,
"Audit, session 7: modes, simulate and the command line")."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from bifilar.cli import main
from conftest import CONFIGS, one_error_line

PLATE = str(CONFIGS / "thesis_plate_rest.yaml")


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("sigma", ["1e-15", "1e-17"])
def test_period_sigma_below_the_models_resolution_is_input_error(sigma):
    """A period stated to 1e-15 s cannot be reproduced to 0.1 of that by any
    model period (~1e-14 relative): it ended in exit 1, 'ConvergenceError: the
    linear estimate does not reproduce the measurements'."""
    one_error_line(run("invert", PLATE, "--period", f"torsion=1.9+-{sigma}", "--json"), "--period")


def test_period_sigma_of_a_picosecond_still_inverts():
    res = run("invert", PLATE, "--period", "torsion=1.9+-1e-10", "--json", "--no-ladder")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["inertia"]["Izz"]["value"] > 0


def test_measurements_file_sigma_below_resolution(tmp_path):
    f = tmp_path / "m.yaml"
    f.write_text(f"config: {PLATE}\nmeasurements:\n  - {{mode: torsion, period: 1.9, std: 1.0e-16}}\n")
    res = run("invert", PLATE, "--measurements", f, "--json")
    assert res.exit_code == 2 and "below 1e-12 of the period" in res.stderr, res.stderr


def test_noise_free_recording_inverts(tmp_path):
    """A synthetic record without noise fits with a std of ~4e-16 s, below
    what the model's period resolves: `invert --signal` ended in exit 1.  The
    std is raised to 1e-12 of the period (and the details say so)."""
    import numpy as np

    t = np.linspace(0.0, 20.0, 2001)
    f = tmp_path / "sine.csv"
    np.savetxt(f, np.c_[t, np.sin(2 * np.pi * t / 1.9)], delimiter=",", header="t,x", comments="")
    res = run("invert", PLATE, "--signal", f"torsion={f}", "--json", "--no-ladder")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    assert doc["inertia"]["Izz"]["value"] > 0
    assert "std_floor" in json.dumps(doc["measurements"])


@pytest.mark.parametrize("option", ["--t-start", "--t-stop", "--sample-rate"])
def test_period_window_nan_is_named_as_such(tmp_path, option):
    """`--t-start nan` was refused as 'only 0 samples between nan s and inf s'."""
    import numpy as np

    t = np.linspace(0.0, 20.0, 2001)
    f = tmp_path / "s.csv"
    np.savetxt(f, np.c_[t, np.sin(2 * np.pi * t / 1.9)], delimiter=",", header="t,x", comments="")
    res = run("period", f, option, "nan", "--json")
    one_error_line(res, option)
    assert "must be a number, got nan" in res.stderr

