"""Statics of dependent wires: the linear programmes over the splits of a
wrench that 4 or 5 wires statics cannot split (rank below n) leave open.

:func:`~bifilar.analysis.equilibrium.tension_range` (each wire's least and
greatest tension at rest) and :func:`~bifilar.studies.point.statics_range`
(the greatest a wire can reach in the runs) use them; scipy's ``linprog``
is imported only here.  :func:`held_violation`: a run's length error in the
directions the model holds (nearly dependent wires' self-stresses left
free).  SI units (N, m), world frame.
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from .equilibrium import RestPose, constraint_jacobian, constraint_rank, multiplier_matrix


def reduced_statics(scene: Scene, rest: RestPose) -> tuple[np.ndarray, np.ndarray]:
    """(A, P) at the rest pose: A (6, n) the wrench of unit wire tensions
    (rows force, moment about the CoM; ``A T = -grad V`` at rest, world
    frame) and P (rank, 6) the projection on its range, so that ``P A T =
    P f`` are the equilibrium equations without their dependent rows
    (rounding apart; nearly dependent ones too, by the run's rule,
    :func:`~bifilar.analysis.equilibrium.constraint_rank`)."""
    d, _, G = constraint_jacobian(scene, rest.com, rest.R)
    A = (G / np.linalg.norm(d, axis=1)[:, None]).T
    U, sv, _ = np.linalg.svd(A)
    return A, U[:, :constraint_rank(scene, rest.R, G, sv)].T


def split_bounds(A: np.ndarray, P: np.ndarray, f: np.ndarray, fallback: np.ndarray, lower: bool = True) -> np.ndarray:
    """The least and greatest tension (n, 2), in the units of ``f``, each
    wire can carry in a split of the wrench ``f`` (6,) over the wires of
    :func:`reduced_statics` ``(A, P)`` with every wire pulling: a linear
    programme per bound (scipy's HiGHS, ~1 ms each); ``fallback`` (n,) a
    feasible split, kept where a programme fails (never met); ``lower``
    False: the greatest only (the first column is ``fallback``)."""
    from scipy.optimize import linprog  # only for dependent wires

    Ar, br = P @ A, P @ f
    n = A.shape[1]
    out = np.column_stack([fallback, fallback]).astype(float)
    for i in range(n):
        for col, sign in ((0, 1.0), (1, -1.0))[(0 if lower else 1):]:
            c = np.zeros(n)
            c[i] = sign
            res = linprog(c, A_eq=Ar, b_eq=br, bounds=(0, None), method="highs")
            if res.status == 0:
                out[i, col] = float(res.x[i])
    return out


def held_violation(scene: Scene, Y: np.ndarray) -> float:
    """The largest error of the wires' lengths (m) over states ``Y`` (k, 13)
    (world frame, the maximal model's layout) in the directions the model
    holds: each state's constraint errors ``phi_i = (|d_i|^2 - L_i^2) / 2``
    with their components along the eigen-directions of ``J M^-1 J^T`` below
    :data:`~bifilar.models.maximal.MIN_NORM_RCOND` of the largest removed
    (the nearly dependent wires' self-stresses, which
    :func:`~bifilar.models.maximal._min_norm` leaves free: a real rig's wires
    stretch there, docs/design.md "offcentre, session 14"), as lengths
    (``phi_i / L_i``).  On rigs with independent wires, the whole error."""
    from ..models.maximal import held_directions
    from ..rotations import quat_to_matrix

    Y = np.asarray(Y, float)
    R = quat_to_matrix(Y[:, 3:7])  # (k, 3, 3)
    w = np.einsum("kij,nj->kni", R, scene.attachments)  # lever arms, world (k, n, 3)
    d = Y[:, None, :3] + w - scene.anchors  # (k, n, 3)
    L = np.asarray(scene.lengths, float)
    phi = 0.5 * (np.einsum("kni,kni->kn", d, d) - L ** 2)
    G = np.concatenate([d, np.cross(w, d)], axis=2)  # d phi / d(dr, dtheta_world) (k, n, 6)
    ev, V = np.linalg.eigh(multiplier_matrix(scene.mass, scene.inertia, R, G))
    held = held_directions(ev)  # (k, n)
    kept = np.einsum("knj,kj->kn", V, np.where(held, np.einsum("knj,kn->kj", V, phi), 0.0))
    return float(np.max(np.abs(kept) / L))
