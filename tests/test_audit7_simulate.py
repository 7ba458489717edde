"""Audit, session 7: `simulate` on cases nobody here wrote (docs/design.md,
"Audit, session 7: modes, simulate and the command line").

Expected values are analytic (the parallel-wire bifilar's torsion period,
thesis eq. 5.2.17) or physical facts (a body released at rest has nothing to
time), never the output of the code under test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.errors import InputError

from bifilar.config import load_scene
from conftest import CONFIGS, trapezoid

MIN_TIMED_ANGLE = 1e-6  # rad: bifilar.analysis.simulate.MIN_TIMED_ANGLE, the documented limit
# parallel vertical wires: anchors and attachments both 1 m apart, 2 m wires, a 10 kg body
D, L, M, IZZ = 1.0, 2.0, 10.0, 0.8
T_TORSION = 2 * math.pi * math.sqrt(4 * IZZ * L / (M * 9.81 * D**2))  # thesis (5.2.17), exact for small angles


@pytest.fixture(scope="module")
def parallel():
    sc = trapezoid(b=D, bp=D, l1=L, inertia=[0.5, 0.4, IZZ], mass=M, h=0.1)
    rest = rest_pose(sc)
    return sc, rest, linear_modes(sc, rest)


@pytest.mark.parametrize("config", ["thesis_cylinder_6_4.yaml", "thesis_plate_rest.yaml"])
@pytest.mark.parametrize("method", ["auto", "DOP853"])
def test_amplitude_zero_has_no_period(config, method):
    """Released at rest the body stays at rest: the sign changes of its
    coordinate are rounding.  They were timed as a period (the thesis
    cylinder's torsion: 3.59 s against 6.43 s, 7 'cycles', exit 0)."""
    sc = load_scene(CONFIGS / config, warn=False)
    r = simulate(sc, "torsion", 0.0, 10, method=method)
    assert r.period is None and r.period_std is None
    assert len(r.crossings) == 0
    assert any(w.startswith("amplitude 0:") for w in r.warnings)
    assert r.to_json()["cycles"] == 0
    # the drift is relative to the oscillation's energy, which is zero: undefined, not a reassuring 0
    assert np.isnan(r.energy_drift) and r.to_json()["energy_drift"] is None


@pytest.mark.parametrize("method", ["auto", "DOP853"])
@pytest.mark.parametrize("amplitude", [1e-9, -1e-12, 1e-300])
def test_amplitude_too_small_to_time_gives_the_linear_period(parallel, amplitude, method):
    """Below 1e-6 rad the integrator's tolerances stop shrinking with the
    amplitude: the 'period' followed the tolerance and the rounding (1e-7 off
    at 1e-9 rad, 1e-4 at 1e-12, tens of % at 1e-300), printed with exit 0.
    Such a motion has the small-angle period to ~A^2: that is given, with a
    warning saying so, and the run (record, tensions) as before."""
    sc, rest, ms = parallel
    r = simulate(sc, "torsion", amplitude, 10, rest=rest, modes=ms, method=method)
    assert abs(r.period / T_TORSION - 1) < 1e-9 and len(r.crossings) == 0
    assert any("too small to time" in w and "linear" in w for w in r.warnings)
    assert len(r.t) > 100 and np.all(r.tensions > 0)
    assert np.isnan(r.energy_drift)  # relative to an oscillation energy at rounding: undefined


def test_translation_amplitude_limit_is_an_angle(parallel):
    """A swing's amplitude is in metres: the limit is the wire angle 1e-6 rad
    times the wire length.  Along the attachment line the parallel wires
    swing the body without turning it: a simple pendulum of length L."""
    sc, rest, ms = parallel
    T_pendulum = 2 * math.pi * math.sqrt(L / 9.81)
    for amplitude, timed in ((0.5 * MIN_TIMED_ANGLE * L, False), (2 * MIN_TIMED_ANGLE * L, True)):
        r = simulate(sc, "swing-y", amplitude, 4, rest=rest, modes=ms)
        assert abs(r.period / T_pendulum - 1) < 1e-9
        assert (len(r.crossings) > 0) == timed


@pytest.mark.parametrize("method", ["auto", "DOP853"])
def test_period_at_the_smallest_amplitude(parallel, method):
    """At the limit the period is still the small-angle one to the printed
    digits (the nonlinear shift is ~A^2 = 1e-12)."""
    sc, rest, ms = parallel
    r = simulate(sc, "torsion", MIN_TIMED_ANGLE, 10, rest=rest, modes=ms, method=method)
    assert abs(r.period / T_TORSION - 1) < 1e-9
    assert np.isfinite(r.energy_drift)


def test_rtol_below_what_the_integrators_keep_is_refused(parallel):
    """LSODA (the default method) refuses rtol below 100 x the double
    precision (exit 1 after NaN warnings at --rtol 1e-14, which the option
    accepted), and solve_ivp silently loosens it to that while the report
    stated the tighter one."""
    sc, rest, ms = parallel
    eps100 = 100 * np.finfo(float).eps
    for method in ("auto", "DOP853", "LSODA"):
        with pytest.raises(InputError) as ei:
            simulate(sc, "torsion", 0.05, 2, rest=rest, modes=ms, method=method, rtol=0.45 * eps100)
        assert ei.value.field == "--rtol"
    r = simulate(sc, "torsion", 0.05, 2, rest=rest, modes=ms, method="auto", rtol=1.01 * eps100)
    assert r.period is not None and r.rtol == pytest.approx(1.01 * eps100)


def test_cli_rtol_1e14_exits_2_naming_it(tmp_path):
    from click.testing import CliRunner

    from bifilar.cli import main

    res = CliRunner().invoke(main, ["simulate", str(CONFIGS / "thesis_plate_rest.yaml"), "--rtol", "1e-14",
                                    "--periods", "2", "--json"])
    assert res.exit_code == 2, res.output
    err = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("error: --rtol: ") and "Traceback" not in res.stderr
    assert res.stdout == ""


@pytest.fixture(scope="module")
def leaning_plate():
    sc = trapezoid()  # the thesis plate: wires leaning in 30 degrees (the kane chart is regular there)
    rest = rest_pose(sc)
    return sc, rest, linear_modes(sc, rest)


def test_kane_model_takes_the_same_amplitude_and_mode_checks(leaning_plate):
    """`--model kane`: 1e-14 rad was timed 4e-4 off the linear period (exit
    0); the neutral pitch 'ran' with the advice to integrate longer."""
    from bifilar.analysis.kane_run import simulate_kane

    sc, rest, ms = leaning_plate
    r = simulate_kane(sc, rest, ms, mode="torsion", amplitude=1e-14, periods=2)
    assert r.period == pytest.approx(ms.get("torsion").period, rel=1e-12)
    assert any("too small to time" in w for w in r.warnings)
    with pytest.raises(InputError) as ei:
        simulate_kane(sc, rest, ms, mode="pitch", amplitude=0.05, periods=2)
    assert ei.value.field == "--mode"
    with pytest.raises(InputError) as ei:
        simulate_kane(sc, rest, ms, mode="torsion", amplitude=0.05, periods=2, rtol=1e-14)
    assert ei.value.field == "--rtol"


def test_on_slack_stop_names_the_wire_with_every_method():
    """With DOP853 the slack event stops the run where the tension reaches
    zero, which the samples show as a rounding above it: the JSON said
    "slack": [] beside 'run stopped ... because a wire went slack', naming
    no wire.  The wire must be the one the LSODA run (sampled tensions) and a
    tension of its own at the stop state name."""
    import yaml

    from bifilar.config import scene_from_dict
    from conftest import TRIFILAR

    sc = scene_from_dict(yaml.safe_load(TRIFILAR), warn=False)
    rest = rest_pose(sc)
    ms = linear_modes(sc, rest)
    runs = {meth: simulate(sc, "torsion", 1.03, 3, rest=rest, modes=ms, method=meth, on_slack="stop")
            for meth in ("auto", "DOP853")}
    for meth, r in runs.items():
        assert any(w.startswith("run stopped at t = ") for w in r.warnings), meth
        assert len(r.slack) == 1, (meth, r.slack)
        assert any(w.startswith(f"WIRE {r.slack[0][0]} GOES SLACK") for w in r.warnings)
        assert r.slack[0][1] == pytest.approx(r.t[-1], abs=r.linear_period / 32)
    assert runs["auto"].slack[0][0] == runs["DOP853"].slack[0][0]
    # at the stop the named wire carries (about) nothing, the others clearly more
    last = runs["DOP853"].tensions[-1]
    k = runs["DOP853"].slack[0][0] - 1
    assert abs(last[k]) < 1e-6 * sc.mass * sc.gravity and np.all(np.delete(last, k) > 1e-3 * sc.mass * sc.gravity)
