"""simulate's period error on a motion that is not regular (docs/design.md,
"A motion that is not regular").

The thesis plate's swing-y at 1.5 m (0.3 x the wires) passes energy between
modes: its mean period over a run depends on the start, and the error
model's bound (a constant x rtol x the period) did not hold (6.7e-9 s printed,
5e-7 s off over 40 periods).  The references are independent runs (DOP853 at
rtol 1e-12 with the check switched off), never the output of the code under
test."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis import simulate as sim
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.cli import main
from bifilar.config import load_scene
from bifilar.errors import InputError
from conftest import CONFIGS, plate3_scene

PLATE = CONFIGS / "thesis_plate_rest.yaml"
PERIODS = 40  # the fewest (of 30, 35, 40) over which the plate's swing-y at 1.5 m leaves its bound


def setup(name):
    sc = load_scene(CONFIGS / name)
    rest = rest_pose(sc)
    return sc, rest, linear_modes(sc, rest)


def reference(sc, rest, ms, mode, amplitude):
    """The same start integrated by the other engine at rtol 1e-12, unchecked."""
    return simulate(sc, mode, amplitude, PERIODS, rest=rest, modes=ms, method="DOP853", rtol=1e-12, check=False)


def test_the_plates_irregular_swing_warns_and_widens_its_error():
    """Before: period_error 6.7e-9 s (15 x rtol x T plus the drift's part),
    no warning, while the period was 5e-7 s from an independent run."""
    sc, rest, ms = setup("thesis_plate_rest.yaml")
    r = simulate(sc, "swing-y", 1.5, PERIODS, rest=rest, modes=ms, method="auto")  # the CLI's default
    ref = reference(sc, rest, ms, "swing-y", 1.5)
    true = abs(r.period - ref.period)
    model = 15 * 1e-10 * r.period + sim.drift_period_error(r.period, r.linear_period, r.energy_drift)
    assert true > 20 * model  # the error model does not hold here (the reason for the check)
    assert r.period_error >= 0.9 * true  # the check's difference is the error's size, not a bound (design.md)
    # the bound is the model's plus the crossings' interpolation part, which the run keeps below
    # CROSSING_SHARE of it; that part depends on where the last crossing falls between the samples,
    # which moves with the BLAS kernel on this irregular motion (0 here, 2.4 % of the model on Haswell)
    assert r.period_check is not None
    assert model * (1 - 1e-9) <= r.period_check["model_bound"] <= (1 + sim.CROSSING_SHARE) * model
    assert r.period_check["rtol"] == pytest.approx(1e-12)
    w = [w for w in r.warnings if "not regular" in w]
    assert len(w) == 1 and "differs by" in w[0]


def test_the_cli_says_so_in_json_and_table():
    args = ["simulate", str(PLATE), "--mode", "swing-y", "--amplitude", "1.5", "--periods", str(PERIODS)]
    r = CliRunner().invoke(main, [*args, "--json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    chk = doc["period_check"]
    # (and at least the part an unstable symmetric orbit sets: test_symcheck.py)
    assert doc["period_error"] == pytest.approx(max(chk["difference"], chk["model_bound"],
                                                    doc["period_error_symmetry"]), rel=1e-12)
    assert chk["difference"] == pytest.approx(abs(doc["period"] - chk["period"]), rel=1e-9)
    assert any("not regular" in w for w in doc["warnings"])
    assert "not regular" in r.stderr
    table = CliRunner().invoke(main, args)
    row = next(ln for ln in table.stdout.splitlines() if "measured period" in ln)
    value = row.split("│")[2].split("+-")[0].strip()
    assert len(value.split(".")[1]) <= 7  # ~5e-7 s: 3.2403761, not the 9 decimals of a 7e-9 bound


@pytest.mark.parametrize("name, mode", [("solar_boat.yaml", "roll"), ("thesis_cylinder_6_4.yaml", "pitch")])
def test_regular_beating_is_checked_and_does_not_warn(name, mode):
    """Beating with a nearby mode spreads the single-cycle periods (1e-3 of
    the period at 0.3 rad) as much as the irregular motion's early cycles, but
    the mean period is still what the error model bounds: the check runs and agrees."""
    sc, rest, ms = setup(name)
    r = simulate(sc, mode, 0.3, PERIODS, rest=rest, modes=ms, method="auto")
    assert r.period_std > 1e-4 * r.period  # a spread far above a clean mode's
    assert r.period_check is not None and r.period_check["difference"] < r.period_check["model_bound"]
    assert r.period_error == r.period_check["model_bound"]
    assert not any("regular" in w for w in r.warnings)
    assert abs(r.period - reference(sc, rest, ms, mode, 0.3).period) <= r.period_error


def test_a_clean_default_run_is_not_checked():
    """The default run of a clean mode pays nothing: no second run."""
    sc, rest, ms = setup("thesis_plate_rest.yaml")
    r = simulate(sc, "torsion", 0.05, 10, rest=rest, modes=ms)
    bare = simulate(sc, "torsion", 0.05, 10, rest=rest, modes=ms, check=False)
    assert r.period_check is None and r.to_json()["period_check"] is None
    assert r.nfev == bare.nfev and r.period_error == bare.period_error


# --------------------------------------------------------------------------- check_period's choices (fake runs)


class Run:
    """The fields check_period reads and writes."""

    def __init__(self, period=2.0, std=1e-3, rtol=1e-10, method="DOP853", err=1e-9):
        self.period, self.period_std, self.rtol, self.method = period, std, rtol, method
        self.period_error, self.period_check, self.warnings = err, None, []


def test_the_check_takes_the_other_engine_where_rtol_cannot_tighten():
    asked = []

    def again(method, rtol, atol):
        asked.append((method, rtol, atol))
        return Run(period=2.0 + 1e-13, method=method, rtol=rtol)

    r = Run(rtol=1e-13, err=1e-12)
    sim.check_period(r, again, "DOP853", None)
    assert asked == [("LSODA", 1e-13, None)]
    assert r.period_error == 1e-12 and not r.warnings  # agreement: the model's bound stays
    asked.clear()
    sim.check_period(Run(), again, "auto", np.array([1e-12, 2e-12]))
    assert asked[0][0] == "auto" and asked[0][1] == pytest.approx(1e-12)
    assert np.allclose(asked[0][2], [1e-14, 2e-14])  # an explicit atol tightens with rtol


def test_a_failed_check_says_the_bound_is_unchecked():
    def again(method, rtol, atol):
        raise InputError("--periods", "stiff body: budget")

    r = Run()
    sim.check_period(r, again, "DOP853", None)
    assert r.period_error == 1e-9 and r.period_check is None
    assert len(r.warnings) == 1 and "may not hold" in r.warnings[0]


def test_a_difference_over_the_users_timing_warns_even_near_the_bound():
    """1.5x the bound is within what a regular run may show, but over a tenth
    of the stated timing the user must be told."""
    def again(method, rtol, atol):
        return Run(period=2.0 + 1.5e-9)

    quiet, loud = Run(), Run()
    sim.check_period(quiet, again, "DOP853", None, timing=1e-6)
    sim.check_period(loud, again, "DOP853", None, timing=1e-9)
    assert quiet.period_error == pytest.approx(1.5e-9) and not quiet.warnings
    assert loud.period_error == pytest.approx(1.5e-9) and "not regular" in loud.warnings[0]


def test_invert_does_not_pay_for_the_check(monkeypatch):
    """invert checks an amplitude run only where the span of its single-cycle
    periods exceeds a tenth of the measured period's std (run_accuracy.check_matters):
    the example's beating pitch runs span 4e-5 s against 0.5 ms, so none is
    run twice (checking every beating run cost it 19 % more CPU for nothing
    shown; tests/test_invert_irregular.py for the runs that are checked).
    Counted, not timed."""
    calls = []
    monkeypatch.setattr(sim, "check_period", lambda *a, **k: calls.append(a))
    r = CliRunner().invoke(main, ["invert", "--measurements", str(CONFIGS / "measurements_example.yaml"),
                                  "--no-ladder", "--json"])
    assert r.exit_code == 0, r.stderr
    assert calls == []


def test_a_difference_of_several_bounds_warns_below_the_users_timing():
    """Below the timing threshold (a stated 1 ms: 1e-4 s) only the ratio to
    the model's bound decides: 1.5x is what a regular run may show (survey:
    at most 0.31x), 3x is over IRREGULAR_FACTOR = 2 and warns; the reported
    error is the difference either way (pins the factor: a mutation to 200
    passed every other test, the plate case also crossing the 1e-8 default)."""
    for ratio, warns in ((1.5, False), (3.0, True)):
        def again(method, rtol, atol, ratio=ratio):
            return Run(period=2.0 + ratio * 1e-9)

        r = Run()
        sim.check_period(r, again, "DOP853", None, timing=1e-3)
        assert r.period_error == pytest.approx(ratio * 1e-9, rel=1e-6)
        assert bool(r.warnings) is warns and (not warns or "not regular" in r.warnings[0])


@pytest.mark.parametrize("amplitude", [3.0, 3.1])
def test_a_torsion_near_the_wires_turn_states_an_error_that_holds(amplitude):
    """Audit18's row H2: a trifilar plate's torsion at 3.0 / 3.1 rad (the
    wires' turn at pi is an unstable equilibrium: T / T_lin 2.5 / 3.2),
    whose single cycles agree, so no irregular-motion check ran; the drift
    term of the error model (the period's distance from the linear one
    growing as the energy) fails there, and LSODA at the default rtol 1e-10
    missed the converged period by 6.0e-7 / 7.0e-6 s against a stated
    4.8e-8 / 6.9e-8 (12.5 / 101 x).  Truth: DOP853 at rtol 1e-13 from the
    same start (audit18: an independent DOP853 run matched it to 1.6e-10 s).
    Now a period more than 20 % from the linear one is checked by a second
    run: the stated error holds the truth, and one warning says why it grew."""
    sc = plate3_scene()
    rest = rest_pose(sc)
    ms = linear_modes(sc, rest)
    r = simulate(sc, "torsion", amplitude, 10, rest=rest, modes=ms, method="auto", rtol=1e-10)
    ref = simulate(sc, "torsion", amplitude, 10, rest=rest, modes=ms, method="DOP853", rtol=1e-13, check=False)
    err = abs(r.period - ref.period)
    assert err > 5e-7  # the case: the default run really is this far off (old bound 4.8e-8 / 6.9e-8)
    assert err <= r.period_error < 2.0 * err
    assert sum("from the linear one, beyond" in w for w in r.warnings) == 1
    assert not any("not regular" in w for w in r.warnings)  # its cycles agree: no verdict on regularity
