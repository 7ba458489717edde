"""The wires' axial stiffness EA as an uncertain input (docs/design.md "eaunc, session 18").

With ``rig.stiffness`` stated the model hangs the body on the loaded wires
``L (1 + T / EA)``; before session 18 EA was taken as exact (no budget term,
sweep/plan could not state its uncertainty, ``tensions`` compared a recorded
length with the unloaded one).  The truths here are independent of the
model's elastic code: the audit16 rigs (vertical 2 m wires on a 0.4 m
circle, attachments 5 cm above the CoM) hang level with each wire carrying
``m g / n`` exactly, so the loaded rig is the rigid one built by hand at the
lengths ``L (1 + m g / (n EA))`` (Hooke's law), and a period's derivative in
EA is a central difference of that hand-built rig's period.
"""

from __future__ import annotations

import numpy as np
import pytest

from test_estimation_audit16 import _heavy
from conftest import in_tmpdir

EA = 1.0e5


def _scene(n: int, mass: float, stiffness=EA, lengths=None):
    from bifilar.config import scene_from_dict

    cfg = _heavy(n, mass, stiffness)
    if lengths is not None:
        cfg["rig"]["lengths"] = list(lengths)
    return scene_from_dict(cfg, "h", warn=False)


def _hand_period(n: int, mass: float, ea: float, dI: float = 0.0) -> float:
    """The torsion period (s) of the rigid rig at the loaded lengths by Hooke's law (EA ``ea``, N), Izz + dI."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.estimation.sensitivity import perturb

    s = perturb(_scene(n, mass, None, [2.0 * (1 + mass * 9.81 / n / ea)] * n), "Izz", dI)
    return linear_modes(s, rest_pose(s)).get("torsion").period


def _invert(scene, T: float, unc: dict):
    from bifilar.estimation.invert import invert
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet

    meas = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                          [Measurement("torsion", T, unc.get("timing", 1e-3), "period", "--period", amplitude=0.0)])
    return invert(meas, method="linear", solve_for=["Izz"], unc=unc, ladder=False)


@pytest.mark.parametrize("n, mass, s_ea", [(3, 200.0, 0.15), (2, 100.0, 0.02)])
def test_the_budget_holds_ea_by_the_hand_built_loaded_rigs_derivative(n, mass, s_ea):
    """invert's ``stiffness`` term is ``s_EA |dT/ds| / |dT/dIzz|`` with both
    derivatives central differences of the rigid rig built by hand at its
    Hooke's-law lengths (s: EA's relative change, 1e-3 steps: their error
    ~1e-6 relative).  The budget differences the elastic chain forward by
    1e-4 (its truncation ~1e-4 of the derivative): 3e-3 allowed.  The term
    is ~0.7 of the timing term on the trifilar (strain 6.5e-3).  The
    bifilar's budget is second order (its CoM 5 cm below the attachments):
    its term is the sigma points' secant over +-sqrt(3) s_EA of the loaded
    lengths' ``1 / (1 + s)``, ``1 + 3 s_EA^2`` times the derivative (1.07
    at 0.15), so it is checked at 0.02 (1.0012).  The std
    is the root sum of squares with the term (the other groups unchanged
    with ``stiffness=0``, as before session 18, when no term existed: this
    test fails on the old code, which has no ``stiffness`` group and no
    ``stiffness`` uncertainty key)."""
    h = 1e-3
    dT_ds = (_hand_period(n, mass, EA * (1 + h)) - _hand_period(n, mass, EA * (1 - h))) / (2 * h)
    dI = 1e-3 * 20.0
    dT_dI = (_hand_period(n, mass, EA, dI) - _hand_period(n, mass, EA, -dI)) / (2 * dI)
    T = _hand_period(n, mass, EA)
    unc = {"stiffness": s_ea}
    res = _invert(_scene(n, mass), T, unc)
    assert res.values[0] == pytest.approx(20.0, rel=1e-7)  # the loaded rig's period gives the truth back
    groups = res.budget.grouped(0)
    want = s_ea * abs(dT_ds / dT_dI)
    assert groups["stiffness"][1] == pytest.approx(want, rel=3e-3), (groups["stiffness"], want)
    exact = _invert(_scene(n, mass), T, {"stiffness": 0.0})
    assert "stiffness" not in exact.budget.grouped(0)
    assert res.budget.std[0] ** 2 == pytest.approx(exact.budget.std[0] ** 2 + want ** 2, rel=1e-3)


def test_ea_is_budgeted_only_where_it_is_stated():
    """The default (0.1 relative) applies only to a scene that states EA:
    a rigid rig's budget, its assumed uncertainties and a sweep point's
    shares gain nothing (bit-identity of every shipped config's outputs:
    docs/design.md "eaunc, session 18"); a stated one lists
    ``stiffness 0.1`` among the assumed uncertainties."""
    from bifilar.estimation.sensitivity import input_sigma, stiff_inputs

    rigid, stiff = _scene(3, 200.0, None), _scene(3, 200.0)
    assert input_sigma(rigid, "stiffness", {"stiffness": 0.3}) == 0.0 and stiff_inputs(rigid, {}) == []
    assert input_sigma(stiff, "stiffness", {}) == 0.1 and stiff_inputs(stiff, {"stiffness": 0.0}) == []
    T = _hand_period(3, 200.0, EA)
    r = _invert(stiff, T, {}).to_json()
    assert r["assumed_uncertainty"]["stiffness"]["value"] == 0.1
    r0 = _invert(rigid, T, {}).to_json()
    assert "stiffness" not in r0["assumed_uncertainty"]
    assert all("stiffness" not in e["groups"] for e in r0["budget"].values())
    # a stiffness uncertainty stated for a rig without EA is said to be left out (lead, session 18: it was
    # dropped without a word), and only there
    said = "uncertainty stiffness is EA's"
    assert sum(said in w for w in _invert(rigid, T, {"stiffness": 0.1}).to_json()["warnings"]) == 1
    assert not any(said in w for w in _invert(stiff, T, {"stiffness": 0.1}).to_json()["warnings"])


def test_sweep_states_ea_and_its_point_sigma_carries_the_term():
    """``--param stiffness=`` sets every wire's EA (N) (a config without
    ``rig.stiffness`` gains it), and the point's sigma carries EA's term:
    its square minus the same point's with ``uncertainty.stiffness = 0``
    is the term ``s_EA |dT/ds| / |dT/dIzz|`` of the hand-built loaded rig
    (2e-2 allowed: the sigma is the honest pass's, whose other terms move
    by their own finite-difference noise at the 1e-4 level, and the
    difference of two squares amplifies it ~3x).  On the old code the
    shorthand is unknown (the point is refused)."""
    from bifilar.studies import sweep as sw

    cfg = _heavy(3, 200.0, None)
    st = sw.resolve_settings(cfg, components=["Izz"], tensions=False)
    with_ea = sw.evaluate_point(cfg, "h", {"stiffness": EA}, st)
    exact = sw.evaluate_point(cfg, "h", {"stiffness": EA, "uncertainty.stiffness": 0.0}, st)
    assert with_ea["valid"] and exact["valid"], (with_ea["error"], exact["error"])
    h = 1e-3
    dT_ds = (_hand_period(3, 200.0, EA * (1 + h)) - _hand_period(3, 200.0, EA * (1 - h))) / (2 * h)
    dT_dI = (_hand_period(3, 200.0, EA, 0.02) - _hand_period(3, 200.0, EA, -0.02)) / 0.04
    want = 0.1 * abs(dT_ds / dT_dI)
    s1, s0 = with_ea["components"]["Izz"]["sigma"], exact["components"]["Izz"]["sigma"]
    assert np.sqrt(s1 ** 2 - s0 ** 2) == pytest.approx(want, rel=2e-2), (s1, s0, want)
    assert with_ea["components"]["Izz"]["shares"]["stiffness"] > 0.05
    assert "stiffness" not in exact["components"]["Izz"]["shares"]


def test_tensions_compares_the_motion_with_the_loaded_wires():
    """``tensions`` checks that the motion's poses keep each wire at its
    length (1 %).  With ``rig.stiffness`` the run hangs on the loaded wires,
    so against the unloaded ``rig.lengths`` the check saw the stretch: a
    200 kg trifilar on EA 4e4 N (strain 1.6 %) warned that its own
    simulated record 'does not fit this config's rig' and reported a
    mismatch of 0.0327 m, Hooke's law's ``L m g / (3 EA)`` (the old code
    fails here).  Now the mismatch is the run's constraint drift (< 1e-9 m)
    and no warning."""
    import json

    from click.testing import CliRunner

    from bifilar.cli import main

    cfg = _heavy(3, 200.0, 4.0e4)
    import yaml

    runner = CliRunner()
    with in_tmpdir():
        with open("soft.yaml", "w") as f:
            yaml.safe_dump(cfg, f)
        r = runner.invoke(main, ["tensions", "soft.yaml", "--periods", "1", "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["max_wire_length_mismatch"] < 1e-9, doc["max_wire_length_mismatch"]
    assert "does not fit" not in r.stderr
    assert doc["inertia_from_tensions"]["Izz"]["value"] == pytest.approx(20.0, rel=1e-8)


def test_the_amplitude_factor_moves_with_g_as_with_ea():
    """The amplitude factor ``r = T(A) / T_lin`` of a stiff rig depends on
    ``g`` and EA through the strain ``m g / EA`` of its loaded wires (and
    ``g`` otherwise only scales time): raising ``g`` by 5 % and lowering
    every EA to ``1 / 1.05`` of itself move ``r`` alike (two independent
    runs, the trifilar's torsion at 0.1 rad, rtol 1e-10: the runs agree to
    ~1e-10 of ``r`` while each moves it by 5.4e-8).  So the exact route that
    gave ``dr/dg = 0`` (right on rigid wires) is wrong here; the routes
    derive it as ``-dr/ds / g`` from EA's factor ``s`` (and run it where
    EA's is not measured).  The old code has no ``stiff`` routes (fails)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.estimation.factor_inputs import (SteppedFactors, derive_factor_routes, factor_routes,
                                                  stepped_factor_runs)
    from bifilar.estimation.sensitivity import perturb

    s = _scene(3, 200.0)
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    k = [m.label for m in ms.modes].index("torsion")
    h = 0.05
    dg, ds = h * s.gravity, 1 / (1 + h) - 1
    g = SteppedFactors(s, rest, ms, [k], 0.1, 3.0, [("gravity", dg, perturb(s, "gravity", dg)),
                                                    ("stiffness", ds, perturb(s, "stiffness", ds))])
    stepped_factor_runs([g], 1e-10)
    moved_g, moved_ea = g.dr_dx[k]["gravity"] * dg, g.dr_dx[k]["stiffness"] * ds
    assert abs(moved_g) > 2e-8, moved_g  # not 0: g moves the factor through the strain
    assert moved_g == pytest.approx(moved_ea, rel=1e-2), (moved_g, moved_ea)
    assert factor_routes(3, ["gravity"], stiff=True) == (["gravity"], {})  # EA's not measured: run
    run, derived = factor_routes(3, ["gravity", "stiffness"], stiff=True)
    dx = {"stiffness": 2.0e-6}
    derive_factor_routes(dx, derived, s, np.eye(3))
    assert run == ["stiffness"] and dx["gravity"] == pytest.approx(-2.0e-6 / s.gravity, rel=1e-12)
