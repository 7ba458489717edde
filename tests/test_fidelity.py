"""The fidelity ladder (bifilar.analysis.fidelity): every cheap answer is checked
against the full nonlinear model, and every error estimate against the error
it estimates."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis import batch as bt
from bifilar.analysis import fidelity as fd
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.errors import InputError
from bifilar.models import reduced

from conftest import PLATE_I, trapezoid

G = 9.81
REF_RTOL = 1e-12
# the full-model reference at rtol 1e-12 has a period error ~1e-12 (work-precision table):
# errors below this floor cannot be resolved
FLOOR = 5e-12


def _full(scene, mode, A, periods=10):
    rest = rest_pose(scene)
    md = linear_modes(scene, rest).get(mode)
    return bt.run_one(scene, rest, md, A, periods, REF_RTOL, health=False, lowest_point=False).period


def test_closed_form_is_thesis_5_2_17_and_the_linear_mode():
    # parallel wires D = b = b' of length h: T = 2 pi / sqrt(m g D^2 / (4 h I)) (thesis 5.2.17)
    s = trapezoid(b=5.0, bp=5.0, l1=4.0)
    tp = fd.symmetric_torsion_params(s)
    T0 = fd.torsion_linear_period(tp)
    assert T0 == pytest.approx(2 * np.pi / np.sqrt(100 * G * 25 / (4 * 4.0 * PLATE_I[2])), rel=1e-14)
    assert T0 == pytest.approx(reduced.small_angle_period(100, G, 5.0, 4.0, PLATE_I[2]), rel=1e-14)
    # trapezoid: equals the linear torsion mode of the full model (independent linearisation)
    for b, bp, h in ((10, 5, 0.0), (10, 5, 0.5), (6, 9, 0.2)):
        s = trapezoid(b=b, bp=bp, h=h)
        ms = linear_modes(s, rest_pose(s))
        assert fd.torsion_linear_period(fd.symmetric_torsion_params(s)) == pytest.approx(ms.get("torsion").period,
                                                                                        rel=1e-11)


@pytest.mark.parametrize("b,bp,l", [(10, 5, 5), (5, 5, 5), (1, 1, 50), (10, 9, 3), (2, 6, 4)])
def test_kappa_is_the_leading_amplitude_term_of_the_exact_model(b, bp, l):
    tp = reduced.TorsionParams(100.0, 260.4, l, b, bp)
    T0 = fd.torsion_linear_period(tp)
    A = 0.003
    # (T/T0 - 1)/A^2 = kappa + O(A^2): at A = 3e-3 the O(A^2) remainder is < 1e-4 relative for these
    # rigs; the quadrature (epsrel 1e-13) leaves 1e-13 / A^2 ~ 1e-8 of noise
    assert (reduced.torsion_period(tp, A) / T0 - 1) / A**2 == pytest.approx(fd.torsion_kappa(tp), rel=2e-4)


def test_closed_form_error_estimate_bounds_the_true_error():
    # random rigs (wires up to ~80 degrees from vertical, Izz over 8 decades) and amplitudes
    rng = np.random.default_rng(11)
    worst, n = 0.0, 0
    while n < 300:
        l = rng.uniform(0.3, 5)
        b = rng.uniform(0.05, 3) * l
        bp = b * rng.uniform(0.2, 2)
        if abs(b - bp) / 2 >= 0.98 * l:
            continue
        tp = reduced.TorsionParams(1.0, 10 ** rng.uniform(-4, 4), l, b, bp)
        A = rng.choice([0.01, 0.05, 0.15, 0.3, 0.5])
        est = fd.closed_form_error(tp, A)
        if not np.isfinite(est):
            continue
        err = abs(reduced.torsion_period(tp, A) / fd.torsion_linear_period(tp) - 1)
        worst = max(worst, err / est)
        n += 1
    assert worst <= 1.0


def test_backbone_is_exact_for_symmetric_torsion():
    # along the symmetric trapezoid's torsion path the backbone IS the exact 1-DOF model
    s = trapezoid(h=0.5)
    rest = rest_pose(s)
    md = linear_modes(s, rest).get("torsion")
    tp = fd.symmetric_torsion_params(s)
    for A in (0.05, 0.3):
        # 20-point Gauss-Legendre on a smooth integrand: ~1e-10
        assert fd.backbone_period(s, rest, md, A) == pytest.approx(reduced.torsion_period(tp, A), rel=1e-9)


@pytest.mark.parametrize("scene,mode", [
    (trapezoid(l1=5.0, l2=4.8, h=0.5), "torsion"),  # unequal wires: coupled torsion
    (trapezoid(l1=5.0, l2=4.8, h=0.5), "pitch"),
    (trapezoid(h=0.5), "swing-y"),
    (trapezoid(b=2.0, bp=1.0, l1=1.0, l2=1.1, h=0.2, mass=5.0, inertia=[0.5, 0.3, 0.7]), "swing-x"),
])
def test_linear_rung_estimate_covers_the_full_model(scene, mode):
    rest = rest_pose(scene)
    md = linear_modes(scene, rest).get(mode)
    for A in (0.02, 0.1):
        Tbb = fd.backbone_period(scene, rest, md, A)
        est = fd.BACKBONE_SAFETY * abs(Tbb - md.period) / md.period
        err = abs(md.period - _full(scene, mode, A)) / md.period
        assert err <= est + FLOOR
        assert est <= 3 * err + FLOOR  # and the estimate is not vacuous


@pytest.mark.parametrize("scene,mode,A,tol,expected", [
    (trapezoid(h=0.5), "torsion", 1e-4, 1e-6, "closed-form"),
    (trapezoid(h=0.5), "torsion", 0.1, 1e-6, "reduced-1dof"),
    (trapezoid(h=0.5), "torsion", 0.1, 1e-13, "full"),
    (trapezoid(l1=5.0, l2=4.8, h=0.5), "torsion", 1e-4, 1e-6, "linear"),
    (trapezoid(l1=5.0, l2=4.8, h=0.5), "torsion", 0.05, 1e-6, "full"),
    (trapezoid(h=0.5), "swing-y", 1e-3, 1e-6, "linear"),
])
def test_ladder_picks_the_cheap_model_only_within_tolerance(scene, mode, A, tol, expected):
    ans = fd.period(scene, mode, A, tol)
    T, model, est = ans  # unpacks as the brief's triple
    assert model == expected
    assert est <= tol or model == "full"
    err = abs(T - _full(scene, mode, A)) / T
    assert err <= max(tol, FLOOR)
    assert err <= est + FLOOR  # the estimate is an upper bound
    # the rungs tried before were rejected for their estimates
    for rung, e in ans.tried.items():
        if rung != model:
            assert e > tol


def test_full_rung_meets_its_tolerance():
    s = trapezoid(l1=5.0, l2=4.9, h=0.3)
    for tol in (1e-5, 1e-9):
        T, model, est = fd.period(s, "pitch", 0.05, tol)
        assert model == "full"
        assert abs(T - _full(s, "pitch", 0.05)) / T <= max(tol, FLOOR)


def test_bad_tolerance():
    with pytest.raises(InputError):
        fd.period(trapezoid(), "torsion", 0.1, 0.0)
    with pytest.raises(InputError):
        fd.period(trapezoid(), "torsion", float("nan"), 1e-6)


def test_non_symmetric_rigs_are_not_given_the_one_dof_model():
    assert fd.symmetric_torsion_params(trapezoid(l1=5.0, l2=5.0 + 1e-9)) is None
    assert fd.symmetric_torsion_params(trapezoid(h=-0.1)) is None
    assert fd.symmetric_torsion_params(trapezoid(inertia=[200, 60, 240])) is not None
    s = trapezoid()
    tilted = s.with_changes(inertia=np.array([[200.0, 0, 5.0], [0, 60.0, 0], [5.0, 0, 240.0]]))
    assert fd.symmetric_torsion_params(tilted) is None
