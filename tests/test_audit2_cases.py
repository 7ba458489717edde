"""Second audit of cases nobody here wrote (docs/errors.md): several
hangings of one body, unit slips in periods and timed totals, recordings
from other tools and rigs, and the plausibility of a recommended point.
Each case is checked against an independent calculation or the project's
rules (exit 2 with one line naming the field, warnings on stderr and in
the JSON document)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main
from conftest import CONFIGS

TRIFILAR_RIG = {"anchors": [[0.0, 0.3, 0.0], [-0.259808, -0.15, 0.0], [0.259808, -0.15, 0.0]],
                "attachments": [[0.0, 0.3, 0.02], [-0.259808, -0.15, 0.02], [0.259808, -0.15, 0.02]],
                "lengths": [1.0, 1.0, 1.0]}


def run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def _two_hangings(tmp_path, mass2=4.0, gravity2=9.81):
    body = {"mass": 4.0, "inertia": {"principal": [0.25, 0.25, 0.35]}}
    doc = {"solve_for": ["Ixx", "Izz"], "hangings": [
        {"name": "z-up", "config": {"body": body, "rig": TRIFILAR_RIG},
         "measurements": [{"mode": "torsion", "cycles": 10, "times": [21.14, 21.15, 21.16]}]},
        {"name": "x-up", "config": {"gravity": gravity2, "body": {**body, "mass": mass2}, "rig": TRIFILAR_RIG},
         "rotation": {"axis": [0, 1, 0], "angle_deg": -90},
         "measurements": [{"mode": "torsion", "cycles": 10, "times": [18.30, 18.32, 18.31]}]}]}
    p = tmp_path / "hangings.yaml"
    p.write_text(yaml.safe_dump(doc))
    return p


# -- 1. hangings of one body agree on its mass and on gravity ----------------

def test_hangings_with_different_mass_are_refused_naming_both_values(tmp_path):
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, mass2=4.4), "--json"])
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith("error: hangings.1.config.body.mass:")
    assert "4.4 kg" in lines[0] and "4 kg" in lines[0]


def test_hangings_with_different_gravity_are_refused(tmp_path):
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, gravity2=9.70), "--json"])
    assert code == 2 and out == ""
    assert err.strip().startswith("error: hangings.1.config.gravity:") and "9.7 " in err and "9.81 " in err


def test_hangings_equal_to_rounding_are_accepted(tmp_path):
    """A mass equal to 1e-12 relative (e.g. summed from parts) is the same mass."""
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, mass2=4.0 * (1 + 1e-12)),
                          "--amplitude", "0", "--json"])
    assert code == 0, err
    assert set(json.loads(out)["inertia"]) == {"Ixx", "Izz"}


# -- 2. an implausible period warns about a unit slip ------------------------

SLOW = {"name": "wide disc on close vertical wires",  # torsion T = 2 pi (k/r) sqrt(h/g) ~ 127 s
        "body": {"mass": 10.0, "inertia": {"principal": [45.0, 45.0, 90.0]}},
        "rig": {"anchors": [[0.0, -0.15, 0.0], [0.0, 0.15, 0.0]],
                "attachments": [[0.0, -0.15, 0.05], [0.0, 0.15, 0.05]], "lengths": [10.0, 10.0]}}


def _slow(tmp_path):
    p = tmp_path / "slow.yaml"
    p.write_text(yaml.safe_dump(SLOW))
    return p


def test_implausibly_long_period_warns_about_a_unit_slip_but_runs(tmp_path):
    """110 s is reachable on this rig (the vertical bifilar's torsion
    2 pi sqrt(Izz h / (m g r^2)) gives 110 s for Izz = 67.6), so it is
    estimated, with a warning in the JSON and on stderr."""
    code, out, err = run(["invert", _slow(tmp_path), "--period", "torsion=110+-0.1", "--amplitude", "0", "--json"])
    assert code == 0, err
    doc = json.loads(out)
    slip = [w for w in doc["warnings"] if "unit slip" in w]
    assert len(slip) == 1 and slip[0].startswith("--period:") and "ms" in slip[0] and "0.11 s" in slip[0]
    assert "unit slip" in err
    m, g, r, h = 10.0, 9.81, 0.15, 10.0
    assert doc["inertia"]["Izz"]["value"] == pytest.approx(110**2 * m * g * r**2 / (4 * np.pi**2 * h), rel=2e-3)


def test_plausible_period_does_not_warn_about_units():
    code, out, err = run(["invert", CONFIGS / "thesis_plate_rest.yaml", "--period", "torsion=1.8+-0.001",
                          "--amplitude", "0", "--json"])
    assert code == 0, err
    assert not [w for w in json.loads(out)["warnings"] if "unit slip" in w] and "unit slip" not in err


def test_plausibility_rule_bounds():
    from bifilar.estimation.measurements import PLAUSIBLE_PERIOD, implausible_period

    lo, hi = PLAUSIBLE_PERIOD
    assert implausible_period(lo, "torsion", "--period") is None
    assert implausible_period(hi, "torsion", "--period") is None
    assert "minutes" in implausible_period(lo / 2, "torsion", "--period")
    assert "ms" in implausible_period(hi * 2, "torsion", "--period")


# -- 9. timed totals typed in ms warn ------------------------------------------

def test_period_timed_totals_in_ms_warn():
    code, out, err = run(["period", "--timed", "torsion=10:15200,15210", "--json"])
    assert code == 0, err
    doc = json.loads(out)
    assert doc["period"] == pytest.approx(1520.5)
    (w,) = doc["warnings"]
    assert w.startswith("--timed:") and "ms" in w and "1.5205 s" in w
    assert err.strip() == f"warning: {w}"


def test_period_timed_plausible_totals_do_not_warn():
    code, out, err = run(["period", "--timed", "torsion=10:15.20,15.21", "--json"])
    assert code == 0 and json.loads(out)["warnings"] == [] and err == ""


def test_invert_timed_totals_in_ms_warn_when_reachable(tmp_path):
    """The same rule as --period (one function): totals of 10 cycles
    typed as 1100 'seconds' give 110 s, which the slow rig reaches."""
    code, out, err = run(["invert", _slow(tmp_path), "--timed", "torsion=10:1100,1101", "--amplitude", "0", "--json"])
    assert code == 0, err
    slip = [w for w in json.loads(out)["warnings"] if "unit slip" in w]
    assert len(slip) == 1 and slip[0].startswith("--timed:") and "look like ms" in slip[0]
