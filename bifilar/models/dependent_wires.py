"""The multipliers of dependent or nearly dependent wires.

A rig of 4 or 5 wires whose wire directions are dependent (parallel
vertical wires at rest) or nearly so (the same table twisted) makes the
multiplier system ``J M^-1 J^T lam = rb`` of the maximal-coordinate model
(:mod:`bifilar.models.maximal`) singular or nearly so: its minimum-norm
solution with a smooth cut-off (:func:`_min_norm`, which the generated
kernel calls), the rank rule that cut-off implies (:func:`held_directions`,
shared by the run, the rest pose and the held length error) and the rest
pose's multipliers by the same rule (:func:`min_norm_multipliers`).
Multipliers in N / m (tension over wire length), ``J`` per unit of the
body's coordinates, ``M`` kg and kg m^2.
"""

from __future__ import annotations

import numpy as np

MIN_NORM_RCOND = 1e-6
"""Eigenvalues of J M^-1 J^T near or below this fraction of the largest are
treated as zero by :func:`_min_norm` (dependent or nearly dependent wires;
a smooth cut-off, see there).  The ratio is ~ s^2 / 4, s the wire
directions' smallest singular value relative to their largest (per unit
displacement of the body, the wires' lengths change by s): a direction with
s ~ 1e-3 is held by the wires' stretch with a stiffness EA s^2 / L, below the
pendulum's m g / (n L) for any wire whose strain at its load exceeds ~4e-6
(lab wires: 1e-5 .. 1e-3), so a real rig moves along it as along a dependent
one (docs/design.md, "offcentre, session 14").  It was 1e-10: a table on four
vertical wires twisted 0.15 rad (ratio 3e-10) then took the rigid
multipliers of that direction, +-3e4 .. 2e5 N where elastic wires carry
17-32 N."""


_TRIU = {n: np.triu_indices(n) for n in range(1, 6)}


def _min_norm(upper: tuple, rb: tuple) -> tuple:
    """Minimum-norm solution ``lam = A^+ rb`` of the multiplier system.

    ``upper``: the n (n + 1) / 2 entries of the symmetric positive
    semi-definite ``A = J M^-1 J^T`` row by row (i <= j), ``rb``: the n
    right-hand sides; floats (one state) or arrays of one broadcast shape (a
    batch).  Each eigen-direction's share ``b_k / w_k`` is weighted by
    ``w_k^4 / (w_k^4 + e^4)``, ``e`` :data:`MIN_NORM_RCOND` times the largest
    eigenvalue: 1 to within 1e-8 for ``w_k > 100 e`` (the solution exact),
    1e-8 below ``e / 100`` (dropped, the pseudo-inverse), and smooth between,
    so a run whose wires pass through near-dependence (a twisted table on
    vertical wires) meets no jump of the right-hand side.  When the wires
    are dependent the accelerations ``M^-1 J^T lam`` are the same for every
    solution (the null space of A is that of J^T); the minimum-norm
    multipliers are also the tensions the rest pose reports (``lstsq`` of
    the equilibrium equations).  Returns n floats or arrays.
    """
    n = len(rb)
    if all(isinstance(x, float) for x in upper + rb):  # one state: the cheapest numpy calls
        A = np.empty((n, n))
        A[_TRIU[n]] = upper
        w, V = np.linalg.eigh(A, UPLO="U")
        e = MIN_NORM_RCOND * float(w[-1])  # _filtered_inverse written out (the cheapest numpy calls)
        w3 = np.maximum(w, 0.0) ** 3
        return tuple((V @ ((V.T @ rb) * w3 / (w3 * w + e * e * e * e))).tolist())
    shape = np.broadcast_shapes(*(np.shape(x) for x in upper + rb))
    A = np.empty(shape + (n, n))
    b = np.stack([np.broadcast_to(x, shape) for x in rb], axis=-1)
    k = 0
    for i in range(n):
        for j in range(i, n):
            A[..., i, j] = upper[k]
            A[..., j, i] = upper[k]
            k += 1
    w, V = np.linalg.eigh(A)
    c = np.einsum("...ji,...j->...i", V, b) * _filtered_inverse(w, w[..., -1:])
    lam = np.einsum("...ij,...j->...i", V, c)
    return tuple(np.moveaxis(lam, -1, 0))


def _filtered_inverse(w: np.ndarray, top) -> np.ndarray:
    """``w^3 / (w^4 + e^4)`` (``1 / w`` weighted by :func:`_min_norm`'s cut-off),
    ``e = MIN_NORM_RCOND * top``; eigenvalues ``w`` (..., n) of the multiplier
    matrix, ``top`` its largest (broadcast).  Rounding's negative eigenvalues
    of a singular matrix come out as ~0, as the dropped ones."""
    w = np.maximum(w, 0.0)
    e4 = (MIN_NORM_RCOND * np.asarray(top)) ** 4
    return w ** 3 / (w ** 4 + e4)


def held_directions(w: np.ndarray, margin: float = 1.0) -> np.ndarray:
    """Which eigen-directions of the multiplier matrix ``J M^-1 J^T`` (its
    eigenvalues ``w`` (..., n), ascending) :func:`_min_norm` holds: those at
    or above :data:`MIN_NORM_RCOND` of the largest (the cut-off's weight
    1/2 and more); the others are the dependent or nearly dependent wires'
    self-stresses, left free.  The one rank rule of rigs of more than
    :data:`~bifilar.models.maximal.MAX_ELIMINATION_WIRES` wires: the run's, the rest pose's
    (:mod:`bifilar.analysis.equilibrium`) and the held length error's.
    ``margin``: at or above ``margin`` times that (1e3: where the cut-off's
    weight is 1 to within 1e-12, the multipliers the exact solution's)."""
    w = np.asarray(w, float)
    return w >= margin * MIN_NORM_RCOND * w[..., -1:]


def min_norm_multipliers(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_min_norm`'s solution of ``A lam = b`` for one symmetric
    positive semi-definite ``A`` (n, n) (``J M^-1 J^T``) and ``b`` (n,),
    as an array, the same cut-off (for the rest pose's multipliers)."""
    w, V = np.linalg.eigh(np.asarray(A, float))
    return V @ ((V.T @ np.asarray(b, float)) * _filtered_inverse(w, w[-1]))
