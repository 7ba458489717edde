"""The rest-pose search's two shortcuts (issue 14): the Newton start that
skips SLSQP, and the exact constraint Jacobian handed to SLSQP.

Both must find the same poses as the slow paths: the Newton start the same
pose (or the same error) as the global SLSQP search, and SLSQP with the
analytic Jacobian the same pose as SLSQP differencing the constraints itself.
The final Newton polish makes each pose exact to ~1e-15 (KKT residual), so two
routes to the same equilibrium agree to ~1e-14 relative; 1e-12 is the bar.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from bifilar.analysis import equilibrium as eq
from bifilar.config import load_scene, scene_from_dict
from bifilar.errors import BifilarError, ConfigErrors
from bifilar.rotations import rotvec_to_matrix
from conftest import CONFIGS
from test_fuzz import valid_configs

EXAMPLES = ["thesis_plate_rest", "solar_boat", "trifilar_kth", "drone_parallel", "thesis_cylinder_6_4",
            "thesis_lin2_pitch"]


def _same_pose(a: eq.RestPose, b: eq.RestPose, L: float) -> None:
    assert np.max(np.abs(a.com - b.com)) <= 1e-12 * L
    assert np.max(np.abs(a.R - b.R)) <= 1e-12
    assert np.max(np.abs(a.tensions - b.tensions)) <= 1e-12 * np.max(b.tensions)


def test_left_jacobian_against_finite_differences():
    """exp(x + h e_k) exp(x)^T ~ exp(h J e_k): central differences, error O(h^2) ~ 1e-10."""
    rng = np.random.default_rng(3)
    for x in (rng.uniform(-1, 1, 3), np.array([1e-8, 0, 0]), np.array([0.0, 1.5, -0.2])):
        J = eq._left_jacobian(x)
        h = 1e-5
        for k in range(3):
            e = np.zeros(3)
            e[k] = h
            D = (rotvec_to_matrix(x + e) - rotvec_to_matrix(x - e)) @ rotvec_to_matrix(x).T / (2 * h)
            w = np.array([D[2, 1], D[0, 2], D[1, 0]])  # D ~ skew(J e_k)
            assert np.allclose(w, J[:, k], atol=1e-9)


@pytest.mark.parametrize("name", EXAMPLES)
def test_slsqp_with_and_without_jacobian_same_pose(name):
    scene = load_scene(CONFIGS / f"{name}.yaml")
    com0, R0 = eq._initial_pose(scene)
    poses = []
    for jac in (True, False):
        c, R, res, at_bound = eq._slsqp(scene, com0, R0, jacobian=jac)
        assert not at_bound
        poses.append(eq._finish(scene, *eq._newton_kkt(scene, c, R)))
    _same_pose(*poses, float(np.max(scene.lengths)))


@pytest.mark.parametrize("name", EXAMPLES)
def test_newton_start_finds_the_global_search_pose(name):
    scene = load_scene(CONFIGS / f"{name}.yaml")
    _same_pose(eq.rest_pose(scene), eq.rest_pose(scene, global_search=True), float(np.max(scene.lengths)))


def test_leaning_rig_newton_start():
    """An asymmetric bifilar (unequal wires, CoM off the midline) hangs tilted;
    both routes find the same tilted pose."""
    cfg = {
        "gravity": 9.81, "body": {"mass": 3.0, "inertia": {"principal": [0.05, 0.08, 0.11]}},
        "rig": {"anchors": [[0, -0.4, 0], [0.05, 0.45, 0.02]], "attachments": [[0.02, -0.2, 0.1], [0, 0.25, 0.12]],
                "lengths": [1.0, 1.3]},
    }
    scene = scene_from_dict(cfg)
    a, b = eq.rest_pose(scene), eq.rest_pose(scene, global_search=True)
    assert np.degrees(np.arccos(np.clip(a.R[2, 2], -1, 1))) > 1  # it does lean
    _same_pose(a, b, 1.3)


def test_slack_wire_still_named_through_the_fallback():
    """Newton start refuses a pose with a slack wire (negative multiplier); SLSQP names it.
    A square quadrifilar table with wire 3 50 mm too long (as in test_core)."""
    pts = np.array([[1, 1, 0], [-1, 1, 0], [-1, -1, 0], [1, -1, 0]], float)
    cfg = {"body": {"mass": 1.0, "inertia": {"principal": [0.25, 0.25, 0.5]}},
           "rig": {"anchors": pts.tolist(), "attachments": (pts - [0.1, 0.1, 0]).tolist(),
                   "lengths": [1.0, 1.0, 1.05, 1.0]}}
    scene = scene_from_dict(cfg)
    assert eq._newton_start(scene, *eq._initial_pose(scene)) is None
    with pytest.raises(BifilarError) as e1:
        eq.rest_pose(scene)
    with pytest.raises(BifilarError) as e2:
        eq.rest_pose(scene, global_search=True)
    assert type(e1.value) is type(e2.value) and str(e1.value) == str(e2.value)


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck))
@given(valid_configs())
def test_newton_start_agrees_with_global_search_on_random_rigs(cfg):
    """Random 2-5 wire rigs (many that cannot hang): the same pose, or the same error."""
    try:
        scene = scene_from_dict(cfg, warn=False)
    except ConfigErrors:
        return

    def outcome(global_search):
        try:
            return eq.rest_pose(scene, global_search=global_search)
        except BifilarError as exc:
            return type(exc).__name__

    a, b = outcome(False), outcome(True)
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
    else:
        _same_pose(a, b, float(np.max(scene.lengths)))
