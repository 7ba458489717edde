"""Statics of dependent wires: the linear programmes over the splits of a
wrench that 4 or 5 wires statics cannot split (rank below n) leave open.

:func:`~bifilar.analysis.equilibrium.tension_range` (each wire's least and
greatest tension at rest) and :func:`~bifilar.studies.point.statics_range`
(the greatest a wire can reach in the runs) use them; scipy's ``linprog``
is imported only here.  SI units (N), world frame.
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from .equilibrium import RestPose, constraint_jacobian


def reduced_statics(scene: Scene, rest: RestPose) -> tuple[np.ndarray, np.ndarray]:
    """(A, P) at the rest pose: A (6, n) the wrench of unit wire tensions
    (rows force, moment about the CoM; ``A T = -grad V`` at rest, world
    frame) and P (rank, 6) the projection on its range, so that ``P A T =
    P f`` are the equilibrium equations without their dependent rows
    (rounding apart)."""
    d, _, G = constraint_jacobian(scene, rest.com, rest.R)
    A = (G / np.linalg.norm(d, axis=1)[:, None]).T
    U, sv, _ = np.linalg.svd(A)
    return A, U[:, :int(np.sum(sv > 1e-12 * sv[0]))].T


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
