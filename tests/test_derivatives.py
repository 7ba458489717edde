"""Analytic period sensitivities (bifilar.analysis.derivatives) against
finite differences and closed forms.

Tolerance against central differences (step 1e-6 of the input's scale, the
reference :func:`period_sensitivity_fd`): the truncation error is
h^2 T'''/6, which on these rigs is at most ~5e-7 of the largest derivative
of the same mode (measured: it falls 100-fold per 10-fold smaller step, e.g.
6.1e-6, 6.1e-8, 2e-10 at steps 1e-5, 1e-6, 1e-7 for the pitch of the thick
plate), and the rounding error ~eps T / h ~ 1e-10 T per unit; so 2e-6 of the
row's largest |dT/dx| (plus 1e-9 s per unit) separates a right derivative
from a wrong one (leaving out the pose derivative or the constraint term
changes entries by 1e-2 .. 1 of the row scale).
"""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.derivatives import rest_derivative
from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import load_scene, scene_from_dict
from bifilar.estimation.sensitivity import (INERTIA_COMPONENTS, measured_inputs, perturb, period_sensitivity,
                                            period_sensitivity_fd)
from bifilar.models.reduced import TorsionParams, torsion_linear_period
from conftest import CONFIGS, trapezoid


def _all_names(scene):
    return list(INERTIA_COMPONENTS) + measured_inputs(scene) + ["gravity"]


def leaning_bifilar():
    """Unequal wires, CoM off the midline, attachments at different heights: hangs tilted."""
    return scene_from_dict({
        "gravity": 9.81, "body": {"mass": 3.0, "inertia": {"tensor": [[0.05, 0.004, -0.002], [0.004, 0.08, 0.001],
                                                                     [-0.002, 0.001, 0.11]]}},
        "rig": {"anchors": [[0, -0.4, 0], [0.05, 0.45, 0.02]], "attachments": [[0.02, -0.2, 0.1], [0, 0.25, 0.12]],
                "lengths": [1.0, 1.3]},
    })


def asymmetric_trifilar():
    """The KTH trifilar with one attachment moved 2 cm: no repeated periods."""
    s = load_scene(CONFIGS / "trifilar_kth.yaml")
    p = s.attachments.copy()
    p[0, 0] += 0.02
    return s.with_changes(attachments=p)


SCENES = {
    "thesis_plate": lambda: load_scene(CONFIGS / "thesis_plate_rest.yaml"),
    "thick_plate": lambda: trapezoid(h=0.5),
    "trifilar": asymmetric_trifilar,
    "solar_boat": lambda: load_scene(CONFIGS / "solar_boat.yaml"),
    "leaning_bifilar": leaning_bifilar,
}


def _check_against_fd(an, fd):
    assert an.method == "analytic"
    assert an.names == fd.names
    np.testing.assert_array_equal(np.isnan(an.periods), np.isnan(fd.periods))
    # FD one-sided columns (a neighbour cannot hang) are first-order accurate only: compared loosely below
    central = [j for j, n in enumerate(fd.names) if n not in fd.one_sided and n not in fd.undefined]
    live = np.isfinite(fd.periods)
    A, F = an.jacobian[live][:, central], fd.jacobian[live][:, central]
    assert np.all(np.isfinite(A))
    scale = np.max(np.abs(F), axis=1, keepdims=True)
    assert np.all(np.abs(A - F) <= 2e-6 * scale + 1e-9), np.max(np.abs(A - F) / scale)
    assert set(an.undefined) == set(fd.undefined)
    for n in fd.undefined:
        assert np.all(np.isnan(an.column(n)))


@pytest.mark.parametrize("key", list(SCENES))
def test_period_jacobian_matches_finite_differences(key):
    scene = SCENES[key]()
    names = _all_names(scene)
    _check_against_fd(period_sensitivity(scene, names), period_sensitivity_fd(scene, names))


def test_neutral_plate_one_sided_columns_are_the_two_sided_derivative():
    """Thin plate, CoM on the attachment line: moving the CoM up makes it unable to
    hang, so finite differences go one way (error O(h) ~ h T''); the analytic
    derivative is the branch's derivative: it agrees with a one-sided difference
    to O(h), and with the one-sided difference extrapolated from two steps to O(h^2)."""
    scene = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    an = period_sensitivity(scene, ["com.z", "attachment.1.z"])
    live = np.isfinite(an.periods)
    for j, name in enumerate(an.names):
        f1 = period_sensitivity_fd(scene, [name], rel_step=2e-6)
        f2 = period_sensitivity_fd(scene, [name], rel_step=1e-6)
        assert name in f1.one_sided
        rich = 2 * f2.jacobian[live, 0] - f1.jacobian[live, 0]  # Richardson: first-order error removed
        scale = np.max(np.abs(f2.jacobian[live, 0]))
        assert np.all(np.abs(an.jacobian[live, j] - rich) <= 1e-6 * scale)


def test_torsion_closed_form():
    """Symmetric bifilar torsion, T = 2 pi sqrt(Izz / (m g z''(0))) (reduced.py):
    dT/dIzz = T/(2 Izz), dT/dm = -T/(2 m), dT/dg = -T/(2 g) exactly, and
    dT/dl from differentiating z''(0) = b b' / (4 sqrt(l^2 - ((b - b')/2)^2))."""
    b, bp, l, m, Izz = 10.0, 5.0, 5.0, 100.0, 100 * (25 + 6.25) / 12
    scene = trapezoid(b=b, bp=bp, l1=l, h=0.5)
    sens = period_sensitivity(scene, ["Izz", "mass", "gravity", "length.1", "length.2"])
    k = sens.modes.labels.index("torsion")
    T = torsion_linear_period(TorsionParams(m=m, Izz=Izz, l=l, b=b, bp=bp))
    assert sens.periods[k] == pytest.approx(T, rel=1e-12)
    assert sens.column("Izz")[k] == pytest.approx(T / (2 * Izz), rel=1e-10)
    assert sens.column("mass")[k] == pytest.approx(-T / (2 * m), rel=1e-10)
    assert sens.column("gravity")[k] == pytest.approx(-T / (2 * 9.81), rel=1e-10)
    H2 = l**2 - ((b - bp) / 2) ** 2
    dT_dl = T / 2 * l / H2  # T ~ H0^(1/2): dT/dl = T/2 * (l / H0^2); both wires together
    assert sens.column("length.1")[k] + sens.column("length.2")[k] == pytest.approx(dT_dl, rel=1e-9)


# repeated periods (the symmetric trifilar's swings): tests/test_degenerate_derivatives.py


@pytest.mark.parametrize("key", ["leaning_bifilar", "solar_boat", "trifilar"])
def test_rest_pose_derivative_matches_finite_differences(key):
    """Pose, attitude and tensions: central differences of rest_pose (step
    1e-6 L or relative; truncation ~1e-12 relative; Newton converges to 1e-15)."""
    scene = SCENES[key]()
    names = measured_inputs(scene) + ["gravity", "Izz"]
    rest = rest_pose(scene)
    der = rest_derivative(scene, rest, names)
    L = float(np.max(scene.lengths))
    for j, name in enumerate(names):
        h = 1e-6 * (scene.mass if name == "mass" else scene.gravity if name == "gravity" else L)
        rp = rest_pose(perturb(scene, name, h), guess=rest, local_only=True)
        rm = rest_pose(perturb(scene, name, -h), guess=rest, local_only=True)
        dcom = (rp.com - rm.com) / (2 * h)
        dR = (rp.R - rm.R) / (2 * h)
        W = dR @ rest.R.T  # = [dtheta]x
        dth = np.array([W[2, 1], W[0, 2], W[1, 0]])
        dT = (rp.tensions - rm.tensions) / (2 * h)
        np.testing.assert_allclose(der.dcom[j], dcom, atol=1e-7 * max(1.0, np.max(np.abs(dcom))))
        np.testing.assert_allclose(der.dtheta[j], dth, atol=1e-7 * max(1.0, np.max(np.abs(dth))) / L)
        np.testing.assert_allclose(der.dtensions[j], dT, atol=1e-6 * max(np.max(np.abs(dT)), scene.mass * scene.gravity / L))
