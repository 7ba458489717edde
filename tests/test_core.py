"""The core: rest pose, modes and nonlinear simulation of the default model,
each against an independent result (closed form, a different formulation,
or a conservation law)."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import scene_from_dict
from bifilar.errors import SlackWireError, UnstableRestError
from bifilar.models import maximal as mx

from conftest import trapezoid

G = 9.81


def test_rest_tension_thesis_7_2(thesis_plate):
    # thesis Fig 7.2.1: 100 kg at 30 degrees -> m g / (2 cos 30) = 566.38 N per wire
    rest = rest_pose(thesis_plate)
    expected = 100 * G / (2 * np.cos(np.pi / 6))
    assert abs(expected - 566.3806) < 1e-4
    # Newton polishes the KKT equations to ~1e-15: 1e-12 leaves room for rounding
    np.testing.assert_allclose(rest.tensions, expected, rtol=1e-12)
    np.testing.assert_allclose(rest.com, [0, 0, -5 * np.cos(np.pi / 6)], atol=1e-12)
    np.testing.assert_allclose(rest.R, np.eye(3), atol=1e-12)


def test_parallel_wire_torsion_matches_small_angle_formula():
    # thesis (5.2.17): T = 2 pi / sqrt(m g D^2 / (4 h I)) -- exact for the linear mode of parallel wires
    D, h, I, m = 5.0, 5.0, 260.4167, 100.0
    s = trapezoid(b=D, bp=D, l1=h, inertia=[208.4, 52.1, I])
    ms = linear_modes(s, rest_pose(s))
    T = 2 * np.pi / np.sqrt(m * G * D**2 / (4 * h * I))
    assert ms.get("torsion").period == pytest.approx(T, rel=1e-12)


def test_side_sway_is_the_planar_pendulum_of_thesis_6_1(thesis_plate):
    # thesis 6.1: with the CoM on CD the side sway is a pendulum of length 5 cos(pi/6): 4.1744 s
    ms = linear_modes(thesis_plate, rest_pose(thesis_plate))
    T = 2 * np.pi * np.sqrt(5 * np.cos(np.pi / 6) / G)
    assert round(T, 4) == 4.1744
    assert ms.get("swing-x").period == pytest.approx(T, rel=1e-12)
    # rotation about the attachment line has no stiffness when the CoM is on it
    assert any(m.period is None for m in ms.modes)


def test_modes_agree_with_eigenvalues_of_the_nonlinear_rhs():
    """Independent check of the linearisation: eigenvalues of a finite-difference
    Jacobian of the full 13-state right-hand side at rest contain +-i omega_k."""
    s = trapezoid(l1=5.0, l2=4.6, h=0.5, inertia=[200.0, 60.0, 240.0])  # tilted, coupled rest pose
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    P = mx.params_from_scenes(s)
    y0 = mx.pack(rest.com, rest.q)
    J = np.zeros((13, 13))
    h = 1e-6
    for k in range(13):
        e = np.zeros(13)
        e[k] = h
        J[:, k] = (mx.rhs(0, y0 + e, P) - mx.rhs(0, y0 - e, P)) / (2 * h)
    ev = np.linalg.eigvals(J)
    osc = np.sort(np.abs(ev[(np.abs(ev.real) < 1e-5) & (ev.imag > 1e-3)].imag))
    lin = np.sort([2 * np.pi / m.period for m in ms.modes])
    # central differences with h = 1e-6: truncation ~h^2 and rounding ~eps/h ~ 1e-10 relative;
    # eigenvalue sensitivity adds a few orders: 1e-6 is a safe bound
    np.testing.assert_allclose(osc, lin, rtol=1e-6)


def test_small_amplitude_simulation_reproduces_linear_periods():
    s = trapezoid(h=0.5)
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    for label in ("torsion", "swing-y"):
        r = simulate(s, label, 1e-4, 6, rest=rest, modes=ms, rtol=1e-12)
        # amplitude effect ~ A^2 = 1e-8; integrator and crossing error ~1e-11
        assert r.period == pytest.approx(ms.get(label).period, rel=5e-8)
        assert r.max_constraint_violation < 1e-10


def test_constraint_and_energy_over_100_periods():
    s = trapezoid(l1=5.0, l2=4.7, h=0.5)
    r = simulate(s, "torsion", np.pi / 12, 100, rtol=1e-11, samples_per_period=16)
    assert r.max_constraint_violation < 1e-10  # thesis reached 3.9e-5
    assert r.energy_drift < 1e-8
    assert len(r.crossings) >= 95


def test_tensions_satisfy_newtons_second_law():
    # Independent check of the multiplier tensions: sum of wire forces + gravity must equal
    # m a, with a differentiated numerically from the integrated CoM velocity.
    s = trapezoid(l1=5.0, l2=4.8, h=0.5)
    r = simulate(s, "torsion", np.pi / 12, 2, rtol=1e-12, samples_per_period=2000)
    P = mx.params_from_scenes(s)
    kin = mx.kinematics(r.y, P)
    unit = kin["d"] / np.linalg.norm(kin["d"], axis=-1, keepdims=True)
    F = -(r.tensions[..., None] * unit).sum(axis=1) - np.array([0, 0, 100 * G])
    a = np.gradient(r.y[:, 7:10], r.t, axis=0, edge_order=2)
    # second-order differences with 2000 samples per period: error ~ (omega dt)^2 / 6 ~ 2e-6 of the
    # acceleration amplitude (itself below g): 1e-4 m g is a comfortable bound
    np.testing.assert_allclose(F[2:-2], 100 * a[2:-2], atol=1e-4 * 100 * G)


def test_slack_wire_at_rest_is_named():
    # square quadrifilar table, CoM nearer corner 1, wire 3 (opposite corner) 50 mm too long:
    # the table hangs level on wires 1, 2, 4 and wire 3 is slack by 50 mm
    pts = np.array([[1, 1, 0], [-1, 1, 0], [-1, -1, 0], [1, -1, 0]], float)
    att = pts - [0.1, 0.1, 0]
    cfg = {"body": {"mass": 1.0, "inertia": {"principal": [0.25, 0.25, 0.5]}},
           "rig": {"anchors": pts.tolist(), "attachments": att.tolist(), "lengths": [1.0, 1.0, 1.05, 1.0]}}
    with pytest.raises(SlackWireError) as e:
        rest_pose(scene_from_dict(cfg))
    assert e.value.wires == [3]
    assert "wire 3" in str(e.value) and "50 mm" in str(e.value)


def test_trifilar_with_unequal_wires_tilts_but_hangs():
    # three points always share a plane: any three lengths hang taut when the CoM is inside
    ang = np.radians([90, 210, 330])
    pts = np.c_[np.cos(ang), np.sin(ang), np.zeros(3)]
    cfg = {"body": {"mass": 1.0, "inertia": {"principal": [0.25, 0.25, 0.5]}},
           "rig": {"anchors": pts.tolist(), "attachments": pts.tolist(), "lengths": [1.0, 1.0, 1.05]}}
    rest = rest_pose(scene_from_dict(cfg))
    assert np.all(rest.tensions > 0)
    assert abs(rest.tensions.sum() * 1.0 - 9.81) < 0.1  # nearly vertical wires carry ~ m g


def test_unstable_rest_is_reported():
    s = trapezoid(h=-0.5)  # attachments below the CoM
    with pytest.raises(UnstableRestError):
        rest_pose(s)


def test_trifilar_torsion_formula():
    # trifilar with vertical wires: T = 2 pi sqrt(I L / (m g R^2)) (linear, exact for the linear mode)
    R, L, m, I = 0.5, 2.0, 3.0, 0.4
    ang = np.radians([0, 120, 240])
    pts = np.c_[R * np.cos(ang), R * np.sin(ang), np.zeros(3)]
    cfg = {"body": {"mass": m, "inertia": {"principal": [0.3, 0.3, I]}},
           "rig": {"anchors": pts.tolist(), "attachments": pts.tolist(), "lengths": [L] * 3}}
    s = scene_from_dict(cfg)
    ms = linear_modes(s, rest_pose(s))
    assert len(ms.modes) == 3
    assert ms.get("torsion").period == pytest.approx(2 * np.pi * np.sqrt(I * L / (m * G * R**2)), rel=1e-12)
