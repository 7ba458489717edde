"""Tests written to kill surviving mutants of the analytic period
derivatives (``bifilar/analysis/derivatives.py``; see docs/mutation.md).
Every expected value comes from an independent truth -- dimensional
analysis (a rig described in other units has the same periods and the
same derivatives, converted), the definition of the MAC (it does not
depend on how a shape is normalised), the documented input names --
never from output of the code under test.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis import derivatives
from bifilar.analysis.derivatives import analytic_period_jacobian, input_directions
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import ModeSet, linear_modes
from bifilar.config import load_scene
from bifilar.estimation.sensitivity import INERTIA_COMPONENTS, measured_inputs

from conftest import CONFIGS

#: (length unit, mass unit) in SI: mm and g, km and kg, dm and kg (time stays in s)
UNITS = [(1e-3, 1e-3), (1e3, 1.0), (0.1, 1.0)]


def _in_units(scene, length, mass):
    """The same rig with lengths in units of ``length`` m and masses in units of ``mass`` kg."""
    return scene.with_changes(anchors=scene.anchors / length, attachments=scene.attachments / length,
                              lengths=scene.lengths / length, mass=scene.mass / mass,
                              gravity=scene.gravity / length, inertia=scene.inertia / (mass * length**2))


def _unit(name, length, mass):
    """The SI size of one unit of input ``name`` in those units."""
    if name in INERTIA_COMPONENTS:
        return mass * length**2
    return mass if name == "mass" else length  # gravity (m/s^2, s unchanged), lengths, coordinates


def _jacobian(scene, names):
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    return analytic_period_jacobian(scene, rest, ms, names, push=True)


@pytest.mark.parametrize("length,mass", UNITS)
def test_knife_edge_jacobian_and_push_do_not_depend_on_the_units(length, mass):
    """Kills the KKT scaling mutants of ``_scales`` (``m g -> m / g``, ``m g /
    L^2 -> m g L^2``, ``1 / (m g L) -> m g L`` ...) and of the push (``resid
    / |b| -> resid |b|``, ``|b| > 0 -> >= 0`` (0/0 for an inertia input),
    ``> 1``): the thin plate hangs with its CoM on the attachment line (a
    singular KKT matrix), where the scaling decides which inputs have no
    derivative.  Physics does not depend on the units: in mm and g, km and
    kg, dm and kg the periods are the same, every derivative is the SI one
    times the input's unit, the same inputs are undefined (NaN), and the
    push (documented dimensionless) is the same: 0 to rounding where the
    derivative exists, O(1) where it does not."""
    si = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    names = list(INERTIA_COMPONENTS) + measured_inputs(si) + ["gravity"]
    j0, p0 = _jacobian(si, names)
    undefined = np.all(np.isnan(j0), axis=0)
    assert undefined.any() and not undefined.all()  # the case this is about
    j, p = _jacobian(_in_units(si, length, mass), names)
    j = j / np.array([_unit(n, length, mass) for n in names])[None, :]  # per SI unit
    np.testing.assert_array_equal(np.isnan(j), np.isnan(j0))
    ok = np.isfinite(j0)
    scale = np.max(np.abs(j0[ok]))
    # rounding of the knife edge's rest pose: ~1e-13 of the row; a wrongly scaled threshold: 1e-10 .. 1
    assert np.max(np.abs(j[ok] - j0[ok])) <= 1e-11 * scale
    assert np.all(p[~undefined] <= 1e-10) and np.all(p0[~undefined] <= 1e-10)
    assert np.all(p0[undefined] >= 0.1)
    np.testing.assert_allclose(p[undefined], p0[undefined], rtol=1e-8)


def test_repeated_pair_does_not_depend_on_how_its_shapes_are_normalised():
    """Kills ``BE**2 / (diag(B) ...) -> BE**2 * (diag(B) ...)`` in the MAC of
    ``_cluster_derivative``, whose documented input is *any* basis of the
    eigenspace: a MAC is the squared cosine of two shapes, the same however
    long they are, so stretching one basis shape (and its constraint
    multipliers, linear in it) by 10 must not move any period derivative.
    The basis is the non-orthogonal mix of the raised KTH trifilar's swings
    of test_degenerate_derivatives (both shapes lean towards one split
    direction, so a MAC weighted by a shape's length picks another match)."""
    from test_degenerate_derivatives import raised

    scene = raised()
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    s0, s1 = ms.modes[0].shape, ms.modes[1].shape
    mixed = [replace(ms.modes[0], shape=s0 + 0.3 * s1), replace(ms.modes[1], shape=s1 - 0.6 * s0)]
    mset = ModeSet(mixed + ms.modes[2:], ms.mass_matrix, ms.basis)
    names = measured_inputs(scene)
    base = analytic_period_jacobian(scene, rest, mset, names)
    orig = derivatives._cluster_derivative
    for stretch in ([1.0, 10.0], [10.0, 1.0], [0.1, 1.0]):
        s = np.array(stretch)
        derivatives._cluster_derivative = lambda Vc, M, w2, mu, *rest_: orig(Vc * s, M, w2, mu * s, *rest_)
        try:
            got = analytic_period_jacobian(scene, rest, mset, names)
        finally:
            derivatives._cluster_derivative = orig
        assert np.max(np.abs(got - base)) <= 1e-12 * np.max(np.abs(base[:2])), stretch


@pytest.mark.parametrize("name", ["anchor.1", "attachment.2", "com.x.y", "com", "length.1.x", "mass.1"])
def test_malformed_input_names_are_refused_by_name(name):
    """Kills ``and -> or`` in the name parser of ``input_directions`` (an
    ``anchor.1`` without its axis went on to an IndexError, a ``com.x.y``
    was taken as ``com.x``): the documented names are ``anchor.i.x|y|z``,
    ``attachment.i.x|y|z``, ``com.x|y|z``, ``length.i``; anything else is
    an unknown input."""
    scene = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    with pytest.raises(KeyError, match="unknown input"):
        input_directions(scene, [name])


def test_no_modes_no_rows():
    """Kills ``np.zeros((0, J)) -> np.zeros((1, J))``: without modes the Jacobian has no rows."""
    scene = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    empty = ModeSet([], ms.mass_matrix, ms.basis)
    jac, push = analytic_period_jacobian(scene, rest, empty, ["Izz", "mass"], push=True)
    assert jac.shape == (0, 2) and push.shape == (2,)
    assert analytic_period_jacobian(scene, rest, empty, ["Izz"]).shape == (0, 1)
