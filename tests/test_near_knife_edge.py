"""Rest pose and pitch mode of a near knife edge: the thesis plate with its CoM
a tiny distance h below the attachment line (1e-11 m to 1e-3 m; an exact knife
edge is tests/test_knife_edge_rest.py).

The equilibrium is unique (the CoM straight below the line) but the pitch
stiffness about the line is only m g h, so the turn about the line is fixed by
the equations to a resolution of about eps r / h rad (eps the double epsilon,
r = 2.5 m the farthest attachment from the CoM: a moment residual of one
rounding unit of m g r, divided by the stiffness m g h).  Newton's stopping
test (residual < 1e-15 of m g, or stalled) may therefore stop at different
turns from different starts.  These tests check that every start (the default
one, guesses turned about the line by up to 1 rad, warm-started batches in two
orders) gives the true pose within that resolution, and the pitch period the
analytic one of the two-degree-of-freedom pendulum (exact for this symmetric
rig) within the same relative resolution eps L / h.

Expected values come from geometry (the CoM straight below the line, the
world direction computed here) and the analytic 2 x 2 eigenproblem, not from
the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.batch import modes_batch, rest_poses
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import load_scene
from bifilar.rotations import rotvec_to_matrix
from conftest import CONFIGS

EPS = np.finfo(float).eps
PLATE = load_scene(CONFIGS / "thesis_plate_rest.yaml")  # attachments (0, +-2.5, 0): CoM on the line
# the same plate on an aslant line: anchors at different heights and offsets, wires 4 and 5 m
TILTED = PLATE.with_changes(anchors=np.array([[0.3, -5.0, 0.0], [-0.2, 5.0, -1.0]]), lengths=np.array([4.0, 5.0]))
HS = [1e-11, 1e-9, 1e-7, 1e-5, 1e-3]
R_ATT = 2.5  # m, farthest attachment from the CoM
HALF_X = 1.25  # m, half the plate's width across the line (bounding box): depth change per radian of turn


def near(scene, h, sideways=0.0):
    """``scene`` with its CoM h (m) below the attachment line and ``sideways`` (m) off it along body x."""
    return scene.with_changes(attachments=scene.attachments + np.array([sideways, 0.0, h]))


def turned(scene, rest, angle):
    """``rest`` turned by ``angle`` (rad) about the attachment line (body y through attachment 1)."""
    n = rest.R @ np.array([0.0, 1.0, 0.0])
    Q = rotvec_to_matrix(angle * n)
    a0 = rest.com + rest.R @ scene.attachments[0]
    return rest.__class__(com=a0 + Q @ (rest.com - a0), R=Q @ rest.R, q=rest.q, tensions=rest.tensions,
                          wire_vectors=rest.wire_vectors, lowest_z=rest.lowest_z, depth=rest.depth,
                          kkt_residual=rest.kkt_residual)


def all_starts(scene, h, sideways):
    """Rest poses of ``scene`` from every start: default, guesses turned about the line,
    batches warm-started from turned poses with a neighbour scene before and after it."""
    r0 = rest_pose(scene)
    out = [r0]
    for a in (0.03, -0.03, 0.3, -0.3, 1.0, -1.0):
        out.append(rest_pose(scene, guess=turned(scene, r0, a)))
    base = TILTED if scene.anchors[1, 2] != 0 else PLATE
    neighbour = near(base, 2 * h, 2 * sideways)
    for a in np.linspace(-1.0, 1.0, 9):
        g = turned(scene, r0, a)
        out.append(rest_poses([scene, neighbour], g)[0])
        out.append(rest_poses([neighbour, scene], g)[1])
    return out


def miss_angle(scene, rest):
    """Turn (rad) about the attachment line that would put the CoM straight below it:
    zero at the true equilibrium.  Geometry only."""
    n = rest.R @ np.array([0.0, 1.0, 0.0])  # line direction, world
    e = -(rest.R @ scene.attachments[0])  # CoM minus a point of the line, world
    e = e - (e @ n) * n  # its part across the line
    v = np.cross(n, [0.0, 0.0, 1.0])
    v /= np.linalg.norm(v)  # horizontal, across the line
    return float(np.arctan2(e @ v, -e[2]))


@pytest.mark.parametrize("h", HS)
@pytest.mark.parametrize("rig,sideways", [("level", 0.0), ("level", 0.3), ("tilted", 0.0), ("tilted", 0.3)])
def test_every_start_gives_the_true_pose_within_the_resolution(rig, h, sideways):
    """Attitude within eps r / h of the CoM-below-the-line pose (with a sideways offset 0.3 h the
    true pose is turned by atan(0.3) about the line: not the start orientation), the CoM within
    1e-12 m and the depth within the plate's half width times that turn, for every start."""
    scene = near(PLATE if rig == "level" else TILTED, h, sideways * h)
    rests = all_starts(scene, h, sideways * h)
    tol = EPS * R_ATT / h + 1e-13  # rad
    miss = np.array([miss_angle(scene, r) for r in rests])
    assert np.max(np.abs(miss)) <= tol, (np.abs(miss).max(), tol)
    coms = np.array([r.com for r in rests])
    assert np.max(np.ptp(coms, axis=0)) <= 1e-12
    depths = np.array([r.depth for r in rests])
    assert np.ptp(depths) <= 2 * HALF_X * tol + 1e-12


def pendulum_periods(scene, h):
    """Periods (s) of the x-pitch pair of the level plate: a double pendulum (the wire trapezoid
    swinging about the anchor line, drop l to the attachment line; the plate turning about the
    attachment line, CoM h below it), M = [[m l^2, m l h], [m l h, Iyy + m h^2]], K = diag(m g l, m g h).
    Exact for this rig (mirror symmetry y -> -y decouples x and pitch from the rest).  Slowest first."""
    m, g, Iyy = scene.mass, scene.gravity, scene.inertia[1, 1]
    ends = np.linalg.norm(scene.attachments[1] - scene.attachments[0])
    a = np.linalg.norm(scene.anchors[1] - scene.anchors[0])
    l = np.sqrt(scene.lengths[0] ** 2 - ((a - ends) / 2) ** 2)
    M = np.array([[m * l * l, m * l * h], [m * l * h, Iyy + m * h * h]])
    K = np.diag([m * g * l, m * g * h])
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    return 2 * np.pi / np.sqrt(w2)


@pytest.mark.parametrize("h", HS)
def test_pitch_period_follows_the_pendulum_law_from_every_start(h):
    """The pitch period from every start (single-scene and batched modes) is the analytic one
    within eps L / h relative (the stiffness m g h resolved against terms of m g L), and the small-h law 2 pi sqrt(Iyy / (m g h))
    within its own O(m h^2 / Iyy) error."""
    scene = near(PLATE, h)
    T_pitch, T_swing = pendulum_periods(scene, h)
    tol = EPS * float(np.max(scene.lengths)) / h + 1e-12
    rests = all_starts(scene, h, 0.0)
    modesets = [linear_modes(scene, r) for r in rests] + modes_batch([scene] * len(rests), rests)
    for ms in modesets:
        periods = {md.label: md.period for md in ms.modes}
        assert periods["pitch"] is not None
        assert abs(periods["pitch"] / T_pitch - 1) <= tol, (periods["pitch"], T_pitch)
        assert abs(periods["swing-x"] / T_swing - 1) <= 1e-12
    law = 2 * np.pi * np.sqrt(scene.inertia[1, 1] / (scene.mass * scene.gravity * h))
    assert abs(T_pitch / law - 1) <= 2 * scene.mass * h**2 / scene.inertia[1, 1] + 1e-14
