"""Period sensitivities of repeated eigenvalues (the swings of a symmetric
trifilar): degenerate perturbation theory in
:func:`bifilar.analysis.derivatives.analytic_period_jacobian` against the
path it replaces, central finite differences with MAC mode tracking
(:func:`~bifilar.estimation.sensitivity.period_sensitivity_fd`), and
against closed forms of a pendulum.

Tolerance against the differences: their step is 1e-6 of the input's scale,
so their truncation error is ~h^2 ~ 1e-12 of a row and their rounding error
~1e-16 T / 1e-6 ~ 1e-10 of T per unit (measured: at most 2.2e-9 of the
row's largest entry on the scenes below); 1e-8 of the row's largest |dT/dx|
separates a right row from a wrong one (a swing given its partner's branch,
or a branch instead of the mean at a MAC tie, is off by 1e-2 .. 1 of the row).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.analysis import derivatives
from bifilar.analysis.modes import degenerate_clusters
from bifilar.config import load_scene, read_yaml
from bifilar.estimation.sensitivity import (INERTIA_COMPONENTS, measured_inputs, period_sensitivity,
                                            period_sensitivity_fd)

from conftest import CONFIGS

ROW_TOL = 1e-8


def kth():
    return load_scene(CONFIGS / "trifilar_kth.yaml")


def raised(dz=0.1):
    """The KTH trifilar with its attachments ``dz`` above the CoM: still two
    equal swings, and inputs (anchor.1.y) that split them along directions at
    45 degrees to the swings' (a MAC tie)."""
    s = kth()
    p = s.attachments.copy()
    p[:, 2] += dz
    return s.with_changes(attachments=p)


def off_centre():
    """The test mass moved to (0.5, 0.3): the CoM off the table's centre, swings still equal."""
    from bifilar.config import scene_from_dict

    cfg = read_yaml(CONFIGS / "trifilar_kth.yaml")
    cfg["body"]["parts"][3]["position"] = [0.5, 0.3, 0.0]
    return scene_from_dict(cfg, warn=False)


def _names(scene):
    return list(INERTIA_COMPONENTS) + measured_inputs(scene) + ["gravity"]


@pytest.mark.parametrize("make", [kth, raised, off_centre])
def test_repeated_swings_analytic_equal_central_differences(make):
    scene = make()
    names = _names(scene)
    an, fd = period_sensitivity(scene, names), period_sensitivity_fd(scene, names)
    w2 = np.array([m.omega2 for m in an.modes.modes])
    assert degenerate_clusters(np.sort(w2), float(np.max(w2)))  # the case this is about
    assert an.method == "analytic" and not an.one_sided and not an.undefined
    scale = np.max(np.abs(fd.jacobian), axis=1, keepdims=True)
    err = np.abs(an.jacobian - fd.jacobian) / scale
    assert np.all(err <= ROW_TOL), float(np.max(err))


def test_mac_tie_takes_the_mean_of_the_split():
    # anchor.1.y of the raised table splits the swings into +-d along the diagonals: each swing is half of
    # each, a central difference flips branch with the step's sign and gives the mean, 0 (not +-d)
    scene = raised()
    sens = period_sensitivity(scene, ["anchor.1.y"])
    T = sens.periods[0]
    assert np.all(np.abs(sens.jacobian[:2, 0]) <= 1e-12 * T)
    # the split itself is not small: one step of the input separates the periods at first order
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.estimation.sensitivity import perturb

    h = 1e-4
    sc = perturb(scene, "anchor.1.y", h)
    Tp = sorted(m.period for m in linear_modes(sc, rest_pose(sc)).modes[:2])
    assert (Tp[1] - Tp[0]) / h > 0.05 * T


def test_pendulum_closed_forms_of_the_swings():
    """Vertical wires at the CoM's height: both swings are a pendulum,
    T = 2 pi sqrt(L / g) whatever the inertia and mass: the sum over the
    wires of dT/dL_i (all lengths moved together keep the pair equal) is
    T / (2 L), dT/dg = -T / (2 g), dT/dm = dT/dI = 0.  Exact to rounding
    (the differences before were off by ~6e-10)."""
    scene = kth()
    L, g = float(scene.lengths[0]), scene.gravity
    names = ["length.1", "length.2", "length.3", "gravity", "mass", "Izz", "Ixx"]
    sens = period_sensitivity(scene, names)
    T = 2 * math.pi * math.sqrt(L / g)
    sw = [k for k, m in enumerate(sens.modes.modes) if m.label.startswith("swing")]
    assert len(sw) == 2
    for k in sw:
        assert sens.periods[k] == pytest.approx(T, rel=1e-13)
        assert sum(sens.jacobian[k, :3]) == pytest.approx(T / (2 * L), rel=1e-12)
        assert sens.jacobian[k, 3] == pytest.approx(-T / (2 * g), rel=1e-12)
        assert abs(sens.jacobian[k, 4]) <= 1e-12 * T / scene.mass
        assert np.all(np.abs(sens.jacobian[k, 5:]) <= 1e-12 * T / float(np.max(scene.inertia)))


def test_nearly_repeated_pair_still_differenced():
    # a split mode_set keeps (1e-9 relative: above its 1e-10 resolution, inside the 1e-8 band): the members'
    # derivatives change over steps of the split's size, so the old finite differences stay
    s = kth()
    p = s.attachments.copy()
    p[0, 0] += 1e-4
    scene = s.with_changes(attachments=p)
    names = ["Izz", "length.1", "anchor.2.x"]
    an, fd = period_sensitivity(scene, names), period_sensitivity_fd(scene, names)
    assert an.method.startswith("finite-difference") and "nearly repeated" in an.method
    np.testing.assert_array_equal(an.jacobian, fd.jacobian)


def _old_repeated(w2, live, scale):
    """The path before: every cluster of repeated eigenvalues raises (finite differences for the whole Jacobian)."""
    if degenerate_clusters(np.sort(w2[live]), scale):
        raise derivatives.NotDifferentiable("repeated eigenvalues")
    return []


def _close(new, old, path=""):
    """Every figure of two point dicts equal, floats within 1e-8 relative (a
    derivative or share: of the largest in its dict), the noise printed in
    an 'is not identifiable' reason (~1e-11 from differences, ~1e-18 now) aside."""
    if isinstance(new, dict):
        assert set(new) == set(old), path
        sib = [abs(v) for v in list(new.values()) + list(old.values()) if isinstance(v, float)]
        for k in new:
            a, b = new[k], old[k]
            if isinstance(a, float) and isinstance(b, float):
                ref = max(sib) if path.endswith(("dlnI_dx", "shares")) else max(abs(a), abs(b))
                assert abs(a - b) <= 1e-8 * ref, f"{path}.{k}: {a} vs {b}"
            elif k == "reason" and isinstance(a, str) and "d ln T" in a:
                assert a.split("=")[0] == b.split("=")[0]
            else:
                _close(a, b, f"{path}.{k}")
    elif isinstance(new, list):
        assert len(new) == len(old), path
        for i, (a, b) in enumerate(zip(new, old)):
            _close(a, b, f"{path}[{i}]")
    elif isinstance(new, float) and isinstance(old, float):
        assert abs(new - old) <= 1e-8 * max(abs(new), abs(old)), path
    else:
        assert new == old, path


@pytest.mark.parametrize("params", [{}, {"height": 0.1}, {"spacing": 2.0, "length": 0.6}])
def test_trifilar_point_equals_the_finite_difference_path(params, monkeypatch):
    # a whole sweep point (sensitivities, honest sigma, biases, runs) with the degenerate swings analytic
    # (its sensitivity seeds the honest budget, which differenced forward before) against the old path
    from bifilar.studies import point as pt
    from bifilar.studies.settings import resolve_settings

    cfg = read_yaml(CONFIGS / "trifilar_kth.yaml")
    st = resolve_settings(cfg)
    new = pt.evaluate_point(cfg, "trifilar", params, st)
    monkeypatch.setattr(derivatives, "_repeated", _old_repeated)
    old = pt.evaluate_point(cfg, "trifilar", params, st)
    assert new["valid"] and old["valid"]
    new.pop("runtime_s", None), old.pop("runtime_s", None)
    _close(new, old)


def test_pair_sum_does_not_depend_on_the_eigenspace_basis():
    # the pair's derivatives come from the pencil (D, B) on its eigenspace: any basis of it (here a
    # non-orthogonal mix of the two swings, B not diagonal) gives the same split values, so the pair's sum
    # (the derivative of the sum of its omega^2, a symmetric function: trace B^-1 D) is the same, while each
    # member's value follows the direction its own shape matches
    from dataclasses import replace

    from bifilar.analysis.derivatives import analytic_period_jacobian
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import ModeSet, linear_modes

    scene = raised()
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    names = measured_inputs(scene)
    base = analytic_period_jacobian(scene, rest, ms, names)
    s0, s1 = ms.modes[0].shape, ms.modes[1].shape
    mixed = [replace(ms.modes[0], shape=s0 + 0.3 * s1), replace(ms.modes[1], shape=s1 - 0.6 * s0)]
    got = analytic_period_jacobian(scene, rest, ModeSet(mixed + ms.modes[2:], ms.mass_matrix, ms.basis), names)
    scale = np.max(np.abs(base[:2]))
    np.testing.assert_allclose(got[:2].sum(axis=0), base[:2].sum(axis=0), rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(got[2:], base[2:], rtol=0, atol=1e-12 * np.max(np.abs(base[2:])))
    # the mixed basis matches other directions than the swings did, so some rows differ
    assert np.max(np.abs(got[:2] - base[:2])) > 1e-3 * scale


def axisymmetric_on_turned_rig():
    """A body with Ixx = Iyy on a three-fold rig turned by 126 degrees, wires leaning
    inwards: the swings are equal, and Ixy splits them along the body's diagonals."""
    from bifilar.config import scene_from_dict

    ang = np.deg2rad([126.0, 246.0, 6.0])
    anchors = [[0.3637 * math.cos(a), 0.3637 * math.sin(a), 1.4014] for a in ang]
    att = [[0.1997 * math.cos(a), 0.1997 * math.sin(a), 0.0] for a in ang]
    L = float(np.linalg.norm(np.subtract(anchors[0], att[0])))
    return scene_from_dict({"gravity": 9.81, "body": {"mass": 3.56, "inertia": {"principal": [0.4298, 0.4298, 0.3654]}},
                            "rig": {"anchors": anchors, "attachments": att, "lengths": [L] * 3}}, warn=False)


def test_exact_tie_by_symmetry_gives_zero():
    # Ixy of an axisymmetric body: the split directions are the diagonals, each swing half of each, and the
    # tie is exact at every step (the mirror x <-> y), so the differences took whichever branch the
    # matching's index order gave (+-0.11 s per kg m^2 here, by rounding); the swing's period is even in
    # Ixy by that mirror: the mean, 0
    scene = axisymmetric_on_turned_rig()
    sens = period_sensitivity(scene, ["Ixy"])
    sw = [k for k, m in enumerate(sens.modes.modes) if m.label.startswith("swing")]
    T = sens.periods[sw[0]]
    assert np.all(np.abs(sens.jacobian[sw, 0]) <= 1e-12 * T / 0.43)
    fd = period_sensitivity_fd(scene, ["Ixy"])
    assert np.all(np.abs(fd.jacobian[sw, 0] + fd.jacobian[sw[::-1], 0]) <= 1e-6 * T / 0.43)  # +-d or the mean
