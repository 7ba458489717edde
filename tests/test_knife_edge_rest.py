"""Rest pose of a knife edge: the CoM on the line through the attachment
points (the thesis plate, CoM on CD).  Turning the body about that line moves
neither a wire nor the CoM, so every turn is an equilibrium (a neutral
circle); the rest pose is its member nearest the start orientation (body axes
along the world axes; ``equilibrium.canonical_attitude``), whichever pose
Newton ended at: the batched path (warm-started from a neighbour scene, in any
batch order) and the single-scene path (from any guess) give the same pose.

Expected values come from geometry (the level plate's depth), brute force
(the trace of every turn on the circle) and statics (force and moment
balance recomputed here), not from the code under test.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bifilar.analysis.batch import modes_batch, rest_poses
from bifilar.analysis.equilibrium import knife_edge_axes, rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import load_scene
from bifilar.rotations import rotvec_to_matrix
from conftest import CONFIGS

PLATE = CONFIGS / "thesis_plate_rest.yaml"


@pytest.fixture(scope="module")
def plates():
    """The thesis plate on wires of 3, 4 and 5 m, and a tilted knife edge:
    anchors at different heights and offsets, so the attachment line hangs
    aslant and the level plate is no member of the neutral circle."""
    s0 = load_scene(PLATE)
    out = [s0.with_changes(lengths=np.array([L, L])) for L in (3.0, 4.0, 5.0)]
    out.append(s0.with_changes(anchors=np.array([[0.3, -5.0, 0.0], [-0.2, 5.0, -1.0]]), lengths=np.array([4.0, 5.0])))
    return out


def _same(a, b, L, tol=1e-9):
    assert np.max(np.abs(a.com - b.com)) <= tol * L
    assert np.max(np.abs(a.R - b.R)) <= tol
    assert np.max(np.abs(a.tensions - b.tensions)) <= tol * np.max(b.tensions)
    assert np.max(np.abs(a.wire_vectors - b.wire_vectors)) <= tol * L
    assert abs(a.depth - b.depth) <= tol * L
    assert abs(a.lowest_z - b.lowest_z) <= tol * L


def _turned(scene, r, angle):
    """``r`` turned by ``angle`` (rad) about the attachment line: another member of the neutral circle."""
    n = r.R @ knife_edge_axes(scene.attachments)
    return dataclasses.replace(r, R=rotvec_to_matrix(angle * n) @ r.R)


def test_knife_edges_are_recognised():
    """The plate (CoM on CD) and thesis_lin1 are knife edges; rigs with the
    CoM off the attachment line, even by a millimetre, are not."""
    for name in ("thesis_plate_rest", "thesis_lin1_torsion"):
        ax = knife_edge_axes(load_scene(CONFIGS / f"{name}.yaml").attachments)
        assert np.allclose(np.abs(ax), [0.0, 1.0, 0.0])
    for name in ("solar_boat", "trifilar_kth", "drone_parallel", "thesis_cylinder_6_4", "thesis_lin2_pitch"):
        assert np.all(np.isnan(knife_edge_axes(load_scene(CONFIGS / f"{name}.yaml").attachments)))
    s = load_scene(PLATE)
    assert np.all(np.isnan(knife_edge_axes(s.attachments + [0.0, 0.0, 1e-3])))


def test_level_plate_is_the_rest_pose(plates):
    """Symmetric plate: the level attitude is on the circle, so it is the rest
    pose; its depth is the wire drop sqrt(L^2 - 2.5^2) plus the half thickness."""
    for s in plates[:3]:
        L = s.lengths[0]
        for r in [rest_pose(s)] + rest_poses(plates[:3][::-1], rest_pose(plates[2])):
            if not np.allclose(np.abs(r.wire_vectors[:, 2]), np.sqrt(L**2 - 2.5**2)):
                continue  # another scene of the batch
            assert np.max(np.abs(r.R - np.eye(3))) <= 1e-12
            assert abs(r.depth - (np.sqrt(L**2 - 2.5**2) + 0.005)) <= 1e-12 * L


def test_rest_pose_is_the_turn_nearest_the_start_and_in_equilibrium(plates):
    """Tilted knife edge: brute force over the circle (every 0.1 degree) finds
    no turn nearer the identity (larger trace) than the rest pose, and the
    pose balances force and moment (recomputed from its wires)."""
    s = plates[3]
    r = rest_pose(s)
    n = r.R @ knife_edge_axes(s.attachments)
    traces = [np.trace(rotvec_to_matrix(phi * n) @ r.R) for phi in np.linspace(-np.pi, np.pi, 3601)]
    assert max(traces) <= np.trace(r.R) + 1e-12
    assert np.trace(r.R) < 3 - 1e-3  # not the level plate: the test has something to find
    d = r.com + s.attachments @ r.R.T - s.anchors
    assert np.allclose(np.linalg.norm(d, axis=1), s.lengths, rtol=1e-12)
    f = -(r.tensions[:, None] * d / np.linalg.norm(d, axis=1)[:, None])  # wire pulls on the body, toward the anchor
    W = s.mass * s.gravity
    assert np.allclose(f.sum(axis=0) + [0, 0, -W], 0, atol=1e-10 * W)
    moment = np.cross(s.attachments @ r.R.T, f).sum(axis=0)
    assert np.allclose(moment, 0, atol=1e-10 * W * np.max(s.lengths))


@pytest.mark.parametrize("angle", [0.3, -1.0, 2.5])
def test_any_warm_start_on_the_circle_gives_the_same_pose(plates, angle):
    """A guess turned about the attachment line (itself an equilibrium):
    rest_pose and rest_poses both return the pose without a guess."""
    for s in plates:
        r = rest_pose(s)
        g = _turned(s, r, angle)
        L = float(np.max(s.lengths))
        _same(rest_pose(s, guess=g), r, L)
        _same(rest_poses([s], g)[0], r, L)


def test_batch_equals_single_in_any_order(plates):
    """Knife-edge scenes warm-started from a neighbour (the first scene, or
    per-scene turned guesses), in three batch orders: each equals its
    single-scene rest pose to 1e-9, and so do its linear periods."""
    singles = [rest_pose(s) for s in plates]
    modes = [linear_modes(s, r) for s, r in zip(plates, singles)]
    orders = [[0, 1, 2, 3], [3, 2, 1, 0], [1, 3, 0, 2]]
    for order in orders:
        sc = [plates[k] for k in order]
        for guess in (None, [_turned(plates[k], singles[k], 0.7 * (j + 1)) for j, k in enumerate(order)]):
            rs = rest_poses(sc, guess)
            ms = modes_batch(sc, rs)
            for k, r, m in zip(order, rs, ms):
                _same(r, singles[k], float(np.max(plates[k].lengths)))
                for a, b in zip(m.modes, modes[k].modes):
                    if b.period is None:
                        assert a.period is None
                    else:
                        assert abs(a.period - b.period) <= 1e-9 * b.period
