"""The limits of what a body can be and what a study can give: the triangle
inequality's one allowance for rounded moments (config loader = invert's
admissible set), 95 % intervals cut at the physical limit, and a sweep
with no valid point.  Expected values come from forward computations
(``linear_modes`` of the stated tensor) and closed-form limits, never from
the code under test."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import scene_from_dict
from bifilar.errors import ConfigErrors
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.problem import admissible, admissible_interval

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}

#: the README's plate, moments rounded to 2 decimals: 208.33 + 52.08 = 260.41
#: < 260.42 by rounding only (3.8e-5 of I3), hung with its CoM 0.5 m below
#: the attachment line (so that every input has a derivative)
README_PLATE = [208.33, 52.08, 260.42]


def plate(principal=README_PLATE, h=0.5):
    return scene_from_dict({
        "gravity": 9.81,
        "body": {"mass": 100.0, "inertia": {"principal": list(principal)}},
        "rig": {"anchors": [[0, -5, 0], [0, 5, 0]], "attachments": [[0, -2.5, h], [0, 2.5, h]],
                "lengths": [5.0, 5.0]},
    }, warn=False)


def with_component(scene, comp, x):
    I = scene.inertia.copy()
    i, j = _IDX[comp]
    I[i, j] = I[j, i] = x
    return replace(scene, inertia=I)


def period_of(scene, label):
    return linear_modes(scene, rest_pose(scene)).get(label).period


def one(scene, label, T, std, amplitude=0.0):
    return MeasurementSet([Hanging("h", scene, np.eye(3))],
                          [Measurement(label, float(T), std, "period", "--period", amplitude=amplitude)])


# --------------------------------------------------------------------------- 2. one triangle rule


def _loader_accepts(principal) -> bool:
    try:
        plate(principal)
    except ConfigErrors:
        return False
    return True


@pytest.mark.parametrize("excess", [0.0, 3e-5, 9e-5, 1.1e-4, 3e-4, 1e-2])
def test_loader_and_invert_share_one_triangle_rule(excess):
    """A tensor the config loader accepts is admissible to invert, and one
    it refuses is not (both sides of the allowance, for rounding of
    5-digit moments: I1 + I2 may fall short of I3 by up to ~1e-4 of I3)."""
    I3 = 260.0
    principal = [200.0, 60.0 - excess * I3, I3]  # I1 + I2 = (1 - excess) I3
    assert _loader_accepts(principal) == admissible(np.diag(principal))
    assert _loader_accepts(principal) == (excess <= 1e-4)


def test_admissible_interval_ends_where_admissible_does():
    """The closed form of the admissible interval (a 3x3 pencil) ends
    exactly where the eigenvalue test changes its mind (the positive-definite
    end of a product, Ixy here, is open: a singular tensor is no body)."""
    I = np.diag(README_PLATE)
    for comp in ("Ixx", "Iyy", "Izz", "Ixy"):
        lo, hi = admissible_interval(I, comp)
        i, j = _IDX[comp]
        w = hi - lo
        for x, inside in ((lo + 1e-9 * w, True), (hi - 1e-9 * w, True), (lo - 1e-6 * w, False), (hi + 1e-6 * w, False)):
            J = I.copy()
            J[i, j] = J[j, i] = x
            assert admissible(J) == inside, (comp, x)


@pytest.mark.parametrize("label,comp", [("pitch", "Iyy"), ("torsion", "Izz")])
def test_config_at_the_loaders_allowance_inverts_without_being_inadmissible(label, comp):
    """The README plate's own period gives back the README plate's moment:
    it was refused for Iyy ('no physical Iyy gives a period of 1.91239 s':
    invert's set ended 1e-6 from the limit, at Iyy = 52.0895) and answered
    at an 'edge of the physical set' for Izz (260.4105 instead of 260.42)."""
    s = plate()
    x_true = float(s.inertia[_IDX[comp]])
    T = period_of(s, label)
    res = invert(one(s, label, T, std=1e-5), solve_for=[comp], ladder=False)
    assert res.value(comp) == pytest.approx(x_true, rel=1e-7)
    assert not res.roots[0]["edge"]
    assert not any("triangle" in w or "edge of the physical set" in w for w in res.warnings), res.warnings
