"""Rigs with two stable rest poses inside the start box: the answer must not
depend on the path.

A trifilar with strongly leaning wires and attachments far off the CoM can hang
in two stable poses, both turned by less than 90 degrees about each axis from
the start orientation (Newton from random starts on ~900 random 3-5 wire rigs
that hang found 9 such, all trifilars; the two here are two of them, rounded).
Newton ends in the one whose basin it starts in, so a warm start from a
neighbour's pose (a sweep, the batch's first scene, a guess) used to return
the other pose, and a sweep's answer depended on its order.  The rest pose is defined as the one reached
from the start pose (body axes along the world axes, below the anchors:
``rest_pose(scene)``); the batch and ``rest_pose(scene, guess=...)`` must
return it from every start.  ``local_only`` (finite differences) keeps the
branch through the guess.

The second pose is found here by Newton from a start near it; that both are
equilibria is checked by force and moment balance recomputed from the wire
vectors, not by the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.batch import rest_poses
from bifilar.analysis.equilibrium import RestPose, rest_pose
from bifilar.config import scene_from_dict
from bifilar.rotations import matrix_to_quat, matrix_to_rotvec, rotvec_to_matrix

BOX = np.pi / 2 - 1e-3  # rad, the start box (documented in equilibrium.py)

# (config, rotation vector near the second stable pose)
RIGS = [
    ({"gravity": 9.81, "body": {"mass": 1.0, "inertia": {"principal": [0.62, 0.51, 0.16]}},
      "rig": {"anchors": [[0.756, -0.454, -0.019], [-0.447, 0.760, -0.047], [-0.271, -0.839, -0.060]],
              "attachments": [[1.813, -0.183, -0.192], [-0.639, 1.443, 0.364], [-1.313, -0.860, 0.508]],
              "lengths": [2.830, 2.012, 1.717]}},
     [-1.26, 1.12, 0.24]),
    ({"gravity": 9.81, "body": {"mass": 1.0, "inertia": {"principal": [0.89, 0.81, 0.43]}},
      "rig": {"anchors": [[-0.988, -0.465, 0.040], [0.907, -0.607, 0.036], [0.850, 0.685, 0.092]],
              "attachments": [[-0.845, 0.233, -0.192], [0.751, -1.678, -0.083], [1.568, 0.484, -0.122]],
              "lengths": [2.302, 1.634, 1.282]}},
     [-1.42, -0.88, -0.01]),
]


def _other(scene, rv) -> RestPose:
    """The equilibrium on the branch through a pose turned by ``rv`` (rotation vector, rad): a
    fake neighbour pose there (wires along the verticals, equal share of the weight), followed
    locally."""
    R = rotvec_to_matrix(np.asarray(rv, float))
    com = np.mean(scene.anchors - scene.attachments @ R.T, axis=0) - [0, 0, 0.8 * np.min(scene.lengths)]
    d = com + scene.attachments @ R.T - scene.anchors
    T = np.full(scene.n_wires, scene.mass * scene.gravity / scene.n_wires)
    fake = RestPose(com=com, R=R, q=matrix_to_quat(R), tensions=T, wire_vectors=d, lowest_z=0.0, depth=0.0,
                    kkt_residual=1.0)
    return rest_pose(scene, guess=fake, local_only=True)


def _balanced(scene, r) -> None:
    """Wires at their lengths, positive tensions, force and moment balance from the wire vectors."""
    d = r.com + scene.attachments @ r.R.T - scene.anchors
    assert np.allclose(np.linalg.norm(d, axis=1), scene.lengths, rtol=1e-12)
    assert np.all(r.tensions > 0)
    f = -(r.tensions[:, None] * d / np.linalg.norm(d, axis=1)[:, None])
    W = scene.mass * scene.gravity
    assert np.allclose(f.sum(axis=0) + [0, 0, -W], 0, atol=1e-10 * W)
    assert np.allclose(np.cross(scene.attachments @ r.R.T, f).sum(axis=0), 0, atol=1e-10 * W * np.max(scene.lengths))


def _same(a, b, scene) -> None:
    """Same pose to the solver's tolerance (KKT residual ~1e-15; 1e-9 allows any rounding)."""
    assert np.max(np.abs(a.R - b.R)) <= 1e-9, (matrix_to_rotvec(a.R), matrix_to_rotvec(b.R))
    assert np.max(np.abs(a.com - b.com)) <= 1e-9 * np.max(scene.lengths)
    assert np.max(np.abs(a.tensions - b.tensions)) <= 1e-9 * np.max(b.tensions)


@pytest.mark.parametrize("k", range(len(RIGS)))
def test_the_rigs_have_two_stable_poses_inside_the_start_box(k):
    cfg, rv = RIGS[k]
    scene = scene_from_dict(cfg)
    one, two = rest_pose(scene), _other(scene, rv)
    for r in (one, two):
        _balanced(scene, r)
        assert np.max(np.abs(matrix_to_rotvec(r.R))) < BOX
    # distinct poses (turned ~1.5 rad apart), CoM heights tens of cm apart
    assert np.max(np.abs(one.R - two.R)) > 0.5 and abs(one.com[2] - two.com[2]) > 0.05


@pytest.mark.parametrize("k", range(len(RIGS)))
def test_every_start_and_order_gives_the_start_pose_equilibrium(k):
    """rest_pose with the other pose as guess, the batch warm-started from it, and a family of
    neighbours (lengths scaled by up to 3 %) in either order, from no guess and from the other
    pose: each scene's pose is rest_pose's.  Before, the warm start returned the other pose."""
    cfg, rv = RIGS[k]
    scene = scene_from_dict(cfg)
    want, two = rest_pose(scene), _other(scene, rv)
    _same(rest_pose(scene, guess=two), want, scene)
    _same(rest_poses([scene], two)[0], want, scene)
    fam = [scene.with_changes(lengths=scene.lengths * (1 + 0.01 * j)) for j in range(-3, 4)]
    singles = [rest_pose(s) for s in fam]
    for guess in (None, two, [two] * len(fam)):
        for order in (1, -1):
            for s, r, w in zip(fam[::order], rest_poses(fam[::order], guess), singles[::order]):
                _same(r, w, s)


@pytest.mark.parametrize("k", range(len(RIGS)))
def test_local_only_keeps_the_guess_branch(k):
    """Finite differences (local_only) follow the branch through the guess: a neighbour 1e-6
    longer keeps the other pose, within ~1e-6 of it."""
    cfg, rv = RIGS[k]
    scene = scene_from_dict(cfg)
    two = _other(scene, rv)
    near = scene.with_changes(lengths=scene.lengths * (1 + 1e-6))
    r = rest_pose(near, guess=two, local_only=True)
    _balanced(near, r)
    assert np.max(np.abs(r.R - two.R)) < 1e-4
