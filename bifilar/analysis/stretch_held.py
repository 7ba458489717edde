"""Which wire directions of four or five elastic wires the model holds rigidly.

With ``rig.stiffness`` (EA, N) every direction of the body's small motion
that changes the wires' lengths is resisted by two stiffnesses: the wires'
stretch ``mu`` (springs ``EA_i / L_i`` along the wires) and the geometric
one ``kappa`` (the tensions turning with the wires, which the rigid model
also has).  A direction whose stretch is much the stiffer moves at a
frequency far above the pendulum's (a bounce, a tilt of a plate on vertical
wires: ``mu / kappa`` 300 .. 4000 on a 2 kg plate on four 1.2 m wires of EA
2 .. 20 kN); the model holds it rigidly, as the rigid wires at their loaded
lengths.  A direction along which nearly parallel wires stretch only at
second order (a millimetre's splay: ``mu / kappa`` 3.5e-5 .. 3.5e-4) is a
pendulum direction whose stretch stiffens it a little: the model carries
that stiffness elastically (:func:`~bifilar.analysis.equilibrium.reduced_stiffness`)
instead of dropping it, or of holding the direction rigidly where the
multiplier matrix's eigenvalue crossed ``MIN_NORM_RCOND`` (before session
26: a mode lost or mixed within a length's uncertainty, docs/design.md
"elastic26, session 26").

Directions are the generalised eigenvectors of the stretch stiffness against
the body's mass matrix (kinetic-energy metric); ``mu`` and ``kappa`` are
their Rayleigh quotients (rad^2 / s^2).  SI units, world frame, the
(dr, dtheta world) chart of :func:`~bifilar.analysis.equilibrium.constraint_jacobian`.
Vectorised over leading axes (a batch of drawn configs).
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene

#: a direction is held rigidly where its stretch stiffness is at least this many times its geometric one
#: (|kappa|): its own frequency then at least sqrt(10) of the pendulum's and the rigid hold's error on the
#: others of order kappa / mu; the measured gap on near-parallel rigs is 0.1 (a strongly leaning 4-wire rig
#: at EA 2 kN) .. 160 (the softest held direction seen), so the rule does not turn on a length's millimetre
STRETCH_HOLD = 10.0
#: stretch stiffness below this fraction of the largest is rounding (exactly dependent wires): not a direction
STRETCH_ROUNDING = 1e-12


def geometric_stiffness(lam: np.ndarray, d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``sum_i lam_i H_i`` (..., 6, 6), ``H_i`` the Hessian of ``phi_i =
    (|d_i|^2 - L_i^2) / 2`` in the (dr, dtheta world) chart
    (:func:`~bifilar.analysis.equilibrium.constraint_hessians`, summed):
    multipliers ``lam`` (..., n) N/m, wire vectors ``d`` and world lever arms
    ``w`` (..., n, 3) m.  Units N/m, N, N m."""
    lam, d, w = (np.asarray(x, float) for x in (lam, d, w))
    eye = np.eye(3)
    K = np.zeros(lam.shape[:-1] + (6, 6))
    lw = np.einsum("...i,...ij->...j", lam, w)
    skew = np.zeros(lw.shape[:-1] + (3, 3))
    skew[..., 0, 1], skew[..., 0, 2], skew[..., 1, 2] = -lw[..., 2], lw[..., 1], -lw[..., 0]
    skew = skew - np.swapaxes(skew, -1, -2)
    K[..., :3, :3] = lam.sum(-1)[..., None, None] * eye
    K[..., :3, 3:] = -skew
    K[..., 3:, :3] = skew
    dw = np.einsum("...i,...ij,...ik->...jk", lam, d, w)
    ww = np.einsum("...i,...ij,...ik->...jk", lam, w, w)
    trace = np.einsum("...i,...ij,...ij->...", lam, w, w) - np.einsum("...i,...ij,...ij->...", lam, d, w)
    K[..., 3:, 3:] = trace[..., None, None] * eye - ww + 0.5 * (dw + np.swapaxes(dw, -1, -2))
    return K


def stretch_directions(k: np.ndarray, lam: np.ndarray, d: np.ndarray, w: np.ndarray, G: np.ndarray,
                       M: np.ndarray):
    """The wires' stretch directions at a pose: wire stiffnesses ``k``
    (..., n) N/m (``EA_i / L_i``, 0 for a slack wire), multipliers ``lam``
    (..., n) N/m (tension over wire length), wire vectors ``d``, lever arms
    ``w`` (..., n, 3) m, the constraint Jacobian ``G`` (..., n, 6) and the
    mass matrix ``M`` (..., 6, 6) (kg, kg m^2, world frame).  Returns
    ``mu`` (..., n) (the stretch stiffness over the mass, rad^2/s^2, the
    largest first), ``kappa`` (..., n) (the geometric stiffness along the
    same direction, rad^2/s^2), ``U`` (..., n, n) (the directions as
    combinations of the wires' scaled stretches) and ``Gs`` (..., n, 6) (the
    stretches ``sqrt(k_i)`` times each wire's length change per unit of the
    pose): ``U[:, j] . Gs x = 0`` holds direction ``j``."""
    k, d, G, M = (np.asarray(x, float) for x in (k, d, G, M))
    Gs = np.sqrt(k)[..., None] * G / np.linalg.norm(d, axis=-1)[..., None]
    ev, E = np.linalg.eigh(M)
    Mih = np.einsum("...ij,...j,...kj->...ik", E, 1.0 / np.sqrt(ev), E)  # M^-1/2
    U, sv, Wt = np.linalg.svd(Gs @ Mih)
    n = Gs.shape[-2]
    V = Mih @ np.swapaxes(Wt, -1, -2)[..., :n]  # (..., 6, n): the directions, unit kinetic energy
    kappa = np.einsum("...ij,...ik,...kj->...j", V, geometric_stiffness(lam, d, w), V)
    return sv ** 2, kappa, U, Gs


def held_mask(mu: np.ndarray, kappa: np.ndarray, margin: float = 1.0) -> np.ndarray:
    """Which of :func:`stretch_directions`' directions the model holds:
    stretch stiffness at least ``margin`` x :data:`STRETCH_HOLD` x the
    geometric one's magnitude, and above rounding."""
    mu = np.asarray(mu, float)
    return (mu >= margin * STRETCH_HOLD * np.abs(kappa)) & (mu > STRETCH_ROUNDING * mu[..., :1])


def soft_mask(mu: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """The directions the wires' stretch resists but the model does not
    hold (:func:`held_mask` false, above rounding): their stretch stiffness
    is carried elastically."""
    mu = np.asarray(mu, float)
    return ~held_mask(mu, kappa) & (mu > STRETCH_ROUNDING * mu[..., :1])


def _wire_stiffness(scene: Scene, ln: np.ndarray) -> np.ndarray:
    """Each wire's spring ``EA_i / L_i`` (N/m; 0 where it is not stretched,
    ``ln`` (n,) m its length at the pose) of an elastic scene."""
    L = np.asarray(scene.lengths, float)
    return np.broadcast_to(np.asarray(scene.stiffness, float), L.shape) / L * (ln > L)


def _mass_matrix(scene: Scene, R: np.ndarray) -> np.ndarray:
    M = np.zeros((6, 6))
    M[:3, :3] = scene.mass * np.eye(3)
    M[3:, 3:] = R @ scene.inertia @ R.T
    return M


def stretch_split(scene: Scene, R: np.ndarray, G: np.ndarray):
    """:func:`stretch_directions` of an elastic ``scene`` at a pose
    (attitude ``R`` body -> world, Jacobian ``G`` (n, 6) of
    :func:`~bifilar.analysis.equilibrium.constraint_jacobian`), its
    tensions the springs' at that pose (``EA_i / L_i`` beyond ``L_i``)."""
    d = G[:, :3]
    ln = np.linalg.norm(d, axis=1)
    k = _wire_stiffness(scene, ln)
    lam = k * np.maximum(ln - np.asarray(scene.lengths, float), 0.0) / ln
    return stretch_directions(k, lam, d, scene.attachments @ R.T, G, _mass_matrix(scene, R))


def soft_reduction(scene: Scene, R: np.ndarray, G: np.ndarray, lam: np.ndarray, K: np.ndarray):
    """Where an elastic ``scene`` has a direction its wires' stretch resists
    but the model does not hold (:func:`soft_mask`): (N (6, 6 - r), the
    stiffness (6, 6) with the springs, r), N the motions that keep the held
    stretches (:func:`held_mask`) at zero, r their number, the stiffness
    ``K`` (the tensions' geometric stiffness, multipliers ``lam`` (n,) N/m)
    plus each wire's spring less its tension along the wire (the elastic
    wires' Hessian, :func:`~bifilar.analysis.elastic_rest.elastic_hessian`);
    else None (the rigid model's null space of ``G`` is the one).  Pose as
    :func:`stretch_split`; N/m, N, N m."""
    mu, kappa, U, Gs = stretch_split(scene, R, G)
    if not np.any(soft_mask(mu, kappa)):
        return None
    held = held_mask(mu, kappa)
    rank = int(np.sum(held))
    N = np.linalg.svd(U[:, held].T @ Gs)[2][rank:].T
    ln = np.linalg.norm(G[:, :3], axis=1)
    Gn = G / ln[:, None]
    return N, K + np.einsum("i,ij,ik->jk", _wire_stiffness(scene, ln) - lam, Gn, Gn), rank
