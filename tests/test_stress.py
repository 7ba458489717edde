"""Numerical stability under stress: geometries and amplitudes at the edges of
what the default model is asked to do, each checked against an exact result
(the exact 1-DOF torsion period, dimensional scaling, conservation laws),
not against the code's own numbers.  1000-period runs are benchmark rows
(docs/performance.md), not tests; here 100 periods."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis import batch as bt
from bifilar.analysis import fidelity as fd
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import scene_from_dict
from bifilar.errors import InputError
from bifilar.models import reduced

from conftest import PLATE_I, trapezoid

G = 9.81


def _exact_torsion(s, A):
    return reduced.torsion_period(fd.symmetric_torsion_params(s), A)


def _healthy(r, L, drift=1e-7):
    assert r.error is None and not r.slack
    # rtol 1e-10 keeps the wires to ~1e-12 of their length (work-precision table); 1e-9 L is a margin
    assert r.max_constraint_violation < 1e-9 * L
    assert r.energy_drift < drift


# --------------------------------------------------------------------------
# vertical and nearly vertical wires
# --------------------------------------------------------------------------
def test_vertical_wires_default_model_is_regular_and_kane_refuses():
    kane = pytest.importorskip("bifilar.models.kane")
    par = trapezoid(b=5.0, bp=5.0, l1=4.0, h=0.5)  # parallel vertical wires
    near = trapezoid(b=5.0, bp=5.0 * (1 - 1e-7), l1=4.0, h=0.5)  # 1e-7 rad off vertical
    runs = bt.simulate_batch([par, near], "torsion", 0.2, 4, rtol=1e-11)
    for s, r in zip((par, near), runs):
        # exact energy-integral period; rtol 1e-11 gives ~1e-11 (work-precision table)
        assert r.period == pytest.approx(_exact_torsion(s, 0.2), rel=1e-9)
        _healthy(r, 4.0)
    # continuity across the vertical configuration (the thesis's angles are singular exactly there)
    assert runs[1].period == pytest.approx(runs[0].period, rel=1e-6)
    p = kane.KaneParams(b=5.0, b_prime=5.0, l=4.0, l_prime=4.0, mass=100.0, inertia=np.diag([260.4, 208.3, 52.1]),
                        r=np.hypot(2.5, 0.5), lam=np.arccos(2.5 / np.hypot(2.5, 0.5)))
    with pytest.raises(kane.KaneSingularityError):
        kane.rhs(0.0, np.array([0, 0.0, np.pi / 2, 0, 0, 0, 0, 0, 0, 0]), p)


# --------------------------------------------------------------------------
# scales: wires 0.05 m .. 500 m, masses 1 g .. 10 t
# --------------------------------------------------------------------------
@pytest.mark.parametrize("scale", [0.01, 100.0])
def test_wire_lengths_from_5_cm_to_500_m(scale):
    # the thesis trapezoid scaled by 1/100 (wires 5 cm) and by 100 (wires 500 m)
    s = trapezoid(b=10 * scale, bp=5 * scale, l1=5 * scale, h=0.5 * scale, inertia=[x * scale**2 for x in PLATE_I])
    r = bt.simulate_batch([s], "torsion", 0.1, 4, rtol=1e-10)[0]
    assert r.period == pytest.approx(_exact_torsion(s, 0.1), rel=1e-9)
    _healthy(r, 5 * scale)
    # periods scale with sqrt(length) (dimensional analysis, independent of the solver)
    ref = _exact_torsion(trapezoid(h=0.5), 0.1)
    assert r.period == pytest.approx(ref * np.sqrt(scale), rel=1e-9)


def test_masses_from_1_g_to_10_t_scale_exactly():
    # mass and inertia scaled together: periods unchanged, tensions proportional to the mass
    ks = [1e-5, 1.0, 100.0]  # 1 g, 100 kg, 10 t
    scenes = [trapezoid(l1=5.0, l2=4.8, h=0.5, mass=100 * k, inertia=[208.3 * k, 52.1 * k, 260.4 * k]) for k in ks]
    runs = bt.simulate_batch(scenes, "torsion", 0.1, 4, rtol=1e-11)
    for k, r in zip(ks, runs):
        assert r.period == pytest.approx(runs[1].period, rel=1e-10)  # same equations up to rounding
        np.testing.assert_allclose(r.tension_max / k, runs[1].tension_max, rtol=1e-8)
        _healthy(r, 5.0)


# --------------------------------------------------------------------------
# inertia ratios and CoM height
# --------------------------------------------------------------------------
def test_inertia_ratio_1e4():
    # a slender rod along the attachment line: I_rod_axis / I_across = 1e-4; the fast roll about the
    # rod (100x the torsion frequency) is not excited and must not destabilise the torsion run
    s = trapezoid(b=2.0, bp=1.0, l1=1.0, h=0.05, mass=1.0, inertia=[1.0, 1e-4, 1.0])
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    periods = [m.period for m in ms.modes if m.period]
    assert max(periods) / min(periods) > 10
    r = bt.simulate_batch([s], "torsion", 0.1, 5, rtol=1e-10)[0]
    assert r.period == pytest.approx(_exact_torsion(s, 0.1), rel=1e-9)
    _healthy(r, 1.0)


@pytest.mark.parametrize("h", [1e-6, 50.0])
def test_com_close_to_and_far_below_the_attachment_line(h):
    # torsion of the symmetric trapezoid does not depend on h (reduced.py): exact reference for both;
    # h = 1e-6 m leaves the roll about CD with a 1e-6 relative stiffness (period ~ 1/sqrt(h))
    s = trapezoid(h=h)
    ms = linear_modes(s, rest_pose(s))
    roll = [m for m in ms.modes if m.label in ("roll", "pitch")]
    assert roll and all(m.period is not None for m in roll)
    r = bt.simulate_batch([s], "torsion", 0.1, 3, rtol=1e-10)[0]
    assert r.period == pytest.approx(_exact_torsion(s, 0.1), rel=1e-9)
    _healthy(r, 5.0)


# --------------------------------------------------------------------------
# unequal wires: the chaotic side sway of thesis 6.3 / 6.4
# --------------------------------------------------------------------------
def test_kane_tseng_cylinder_unequal_wires_large_torsion_stays_healthy():
    # thesis 6.4 (Kane & Tseng 1967): solid cylinder, height = diameter = b, wires l = 2b and l' = 1.8b
    # attached b apart at the top rim; raised by turning it pi/4 about its axis. b = g makes time
    # dimensionless.  The motion is chaotic: trajectories are not compared, only conserved quantities.
    b, m = G, 1.0
    s = scene_from_dict({"gravity": G, "body": {"mass": m, "inertia": {"principal": [7 * m * b**2 / 48,
                                                                                     7 * m * b**2 / 48,
                                                                                     m * b**2 / 8]}},
                         "rig": {"anchors": [[0, -b / 2, 0], [0, b / 2, 0]],
                                 "attachments": [[0, -b / 2, b / 2], [0, b / 2, b / 2]],
                                 "lengths": [2 * b, 1.8 * b]}})
    runs = [bt.run_one(s, rest_pose(s), linear_modes(s, rest_pose(s)).get("torsion"), np.pi / 4, 15, 1e-11,
                       method=meth) for meth in ("dop853", "lsoda")]
    for r in runs:
        assert r.max_constraint_violation < 1e-9 * b
        # energy is conserved to ~1e-9 of the oscillation energy at rtol 1e-11 even in chaos
        assert r.energy_drift < 1e-7
        assert min(r.tension_min) > 0
    # both integrators agree while the separation of nearby trajectories is still small (first cycles)
    np.testing.assert_allclose(runs[0].crossings[:2], runs[1].crossings[:2], rtol=1e-7)


def test_double_pendulum_side_sway_with_com_below_cd():
    # thesis 6.3: CoM 0.5 m below CD, side sway (swing-x) couples to the roll about CD like a double
    # pendulum; linear periods must equal the double pendulum's normal modes (independent model)
    s = trapezoid(h=0.5)
    ms = linear_modes(s, rest_pose(s))
    p = reduced.side_sway_double_pendulum_params(100.0, PLATE_I[1], 5.0, 10.0, 5.0, 0.5)  # I about CD (y)
    w, _ = reduced.double_pendulum_normal_modes(p)
    T_dp = np.sort(2 * np.pi / np.asarray(w))  # angular frequencies, rad/s
    T_model = np.sort([ms.get(k).period for k in ("swing-x", "pitch")])  # pitch: rotation about CD (y)
    np.testing.assert_allclose(T_model, T_dp, rtol=1e-9)
    r = bt.simulate_batch([s], "swing-x", 0.2, 10, rtol=1e-10)[0]
    _healthy(r, 5.0)


# --------------------------------------------------------------------------
# amplitudes up to slack, long runs, near-degenerate modes
# --------------------------------------------------------------------------
def _lopsided_trifilar():
    """Trifilar whose CoM sits 0.23 m towards the edge of wires 2-3 (edge at 0.25 m):
    wire 1 carries only 2.7 % of the weight at rest, so a modest swing unloads it."""
    ang = np.radians([0, 120, 240])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    att = pts + [0.23, 0, 0.1]
    return scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                            "rig": {"anchors": pts.tolist(), "attachments": att.tolist(), "lengths": [2.0] * 3}})


def test_amplitude_ladder_up_to_slack():
    s = _lopsided_trifilar()
    rest = rest_pose(s)
    # statics: wire 1 carries m g (0.25 - 0.23) / 0.75 = 0.7848 N (lever rule across the triangle)
    assert rest.tensions[0] == pytest.approx(3.0 * G * 0.02 / 0.75, rel=1e-9)
    amps = np.array([0.1, 0.2, 0.3, 0.45, 0.6])
    for method in ("dop853", "lsoda"):
        runs = bt.simulate_batch([s] * len(amps), "swing-x", amps, 2, rtol=1e-10, method=method)
        tmin = np.array([r.tension_min[0] for r in runs])
        assert np.all(np.diff(tmin) < 0)  # larger swings unload wire 1 more
        slack = np.array([bool(r.slack) for r in runs])
        np.testing.assert_array_equal(slack, tmin <= 0)  # reported exactly when a tension reaches zero
        assert slack[-1] and not slack[0]
        assert all(w == 1 for r in runs for w, _ in r.slack)
        assert any("SLACK" in w for w in runs[-1].warnings)
        for r in runs:  # the bilateral model (wires may push) stays on its constraints
            assert r.max_constraint_violation < 1e-9 * 2.0
    # a start pose the wires cannot reach is refused, naming the amplitude
    with pytest.raises(InputError, match="too large"):
        bt.simulate_batch([trapezoid(h=0.5)], "swing-y", 2.5, 2)
    bad = bt.simulate_batch([trapezoid(h=0.5)] * 2, "swing-y", [0.5, 2.5], 2, errors="return")
    assert bad[0].error is None and "too large" in bad[1].error


def test_hundred_periods_bounded_drift():
    s = trapezoid(l1=5.0, l2=4.7, h=0.5)
    r = bt.simulate_batch([s], "torsion", np.pi / 12, 100, rtol=1e-11)[0]
    assert len(r.crossings) >= 95  # coupled torsion: the timed coordinate beats a little
    assert r.max_constraint_violation < 1e-10  # thesis reached 3.9e-5 over a few periods
    assert r.energy_drift < 1e-7
    # the single-cycle periods scatter only through the (quasi-periodic) coupling, not a drift:
    # first and last ten cycles agree to the scatter
    per = np.diff(r.crossings)
    assert abs(per[:10].mean() - per[-10:].mean()) < 3 * per.std() + 1e-12


def test_nearly_degenerate_swings_beating():
    # trifilar, one wire 1e-4 longer: swing-x and swing-y periods split by ~1e-5
    ang = np.radians([90, 210, 330])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    s = scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                         "rig": {"anchors": pts.tolist(), "attachments": (pts + [0, 0, 0.2]).tolist(),
                                 "lengths": [2.0, 2.0, 2.0002]}})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    sw = sorted([m for m in ms.modes if m.label.startswith("swing")], key=lambda m: m.period)
    assert len(sw) == 2 and 0 < sw[1].period / sw[0].period - 1 < 1e-3
    # the batched modes resolve the near-degenerate pair the same way
    mb = bt.modes_batch([s], [rest])[0]
    assert mb.labels == ms.labels
    for md in sw:
        # a pure mode stays pure in the linear regime: its measured period is its backbone period
        r = bt.run_one(s, rest, md, 0.01, 10, 1e-11)
        T_bb = fd.backbone_period(s, rest, md, 0.01)
        assert abs(r.period - T_bb) / T_bb <= fd.BACKBONE_SAFETY * abs(T_bb - md.period) / md.period + 1e-10
        _healthy(r, 2.0)
