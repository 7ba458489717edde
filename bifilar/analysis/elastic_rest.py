"""Rigs of 4 or 5 nearly dependent wires at rest: how far the rigid model's
split can be trusted, and the split of elastic wires (session 15, elastic).

A level table on four vertical wires whose anchors are off by 0.1 .. 3 mm on
1 m wires has wires that are independent, but only just: the rigid model's
split of its weight then hangs on length differences smaller than the wires'
stretch under load (docs/design.md "elastic, session 15").  Two tools:

* :func:`length_strain_scale`: the relative length change (a strain) of one
  wire that moves the rigid split by a mean wire's load; where that is below
  :data:`PLAUSIBLE_STRAIN` (what lab wires stretch at their load), the rigid
  split is set by the wires' stretch, which the rigid model does not know;
* :func:`elastic_rest`: the static equilibrium of the body on elastic,
  tension-only wires of axial stiffness ``EA`` (``rig.stiffness``, N), each
  a spring of stiffness ``EA_i / L_i`` beyond its length ``L_i``: Newton on
  the potential ``m g z + sum EA_i / (2 L_i) max(|d_i| - L_i, 0)^2`` over the
  pose, from the rigid rest pose.

SI units (N, m), world frame; poses as (com (3,), R (3, 3) body -> world).
"""

from __future__ import annotations

import numpy as np

from ..errors import ConvergenceError
from ..rotations import rotvec_to_matrix
from ..scene import Scene
from .equilibrium import constraint_hessians, constraint_jacobian

#: the largest strain a lab wire plausibly has at its load (steel or nylon wire, thread: 1e-5 .. 1e-3,
#: docs/design.md "offcentre, session 14"): a rig whose rigid split a length change of this size moves by
#: a mean wire's load is nearly dependent (:func:`length_strain_scale`)
PLAUSIBLE_STRAIN = 1e-3


def length_strain_scale(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray) -> float:
    """The strain ``e*`` (relative length change of one wire, ``dL_i / L_i``)
    that moves the rigid model's split by the mean load ``W / n`` of a wire
    (``W`` the weight), at a pose (com m, R body -> world) where every wire
    is at its length and ``lam`` (n,) N/m are the multipliers balancing the
    weight (negative ones allowed: the all-taut pose of a refused rig).

    First order: the KKT system ``[K G^T; G 0] [dx; dlam] = [0; L_i dL_i e_i]``
    (``K = sum lam_i H_i``) gives each wire's tension change
    ``dT = |d| dlam + lam dL`` for a length change of wire ``i``.  0 where
    the system is singular (dependent wires: the split is not set by the
    geometry at all).  Well-conditioned rigs give ~0.1 .. 1; a wire whose
    strain at load is above ``e*`` is stretched more than the length change
    that sets the split, so the rigid split is not the real one."""
    d, w, G = constraint_jacobian(scene, com, R)
    n = scene.n_wires
    ln = np.linalg.norm(d, axis=1)
    K = np.zeros((6 + n, 6 + n))
    K[:6, :6] = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    K[:6, 6:] = G.T
    K[6:, :6] = G
    L = np.asarray(scene.lengths, float)
    # dimensionless, as _newton_kkt: unknowns dr / L, dtheta, dlam L^2 / W; rows force / W, moment / (W L), phi / L^2
    W, Ls = scene.mass * scene.gravity, float(np.max(L))
    cs = np.concatenate([np.full(3, Ls), np.ones(3), np.full(n, W / Ls ** 2)])
    rs = np.concatenate([np.full(3, 1 / W), np.full(3, 1 / (W * Ls)), np.full(n, 1 / Ls ** 2)])
    A = rs[:, None] * K * cs[None, :]
    if np.linalg.cond(A) > 1e14:
        return 0.0
    rhs = np.zeros((6 + n, n))
    rhs[6:, :] = np.diag(L * L)  # d phi_i = -L_i dL_i, moved to the right: a unit strain dL_i = L_i per column
    sol = cs[:, None] * np.linalg.solve(A, rs[:, None] * rhs)
    dT = ln[:, None] * sol[6:, :] + np.diag(lam * L)  # (wire, strained wire): dT per unit strain
    worst = float(np.max(np.abs(dT)))
    return (W / n) / worst if worst > 0 else np.inf


def nearly_dependent(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray) -> bool:
    """Whether the wires (4 or 5) are so nearly dependent that a length
    change smaller than a plausible stretch sets their rigid split
    (:func:`length_strain_scale` below :data:`PLAUSIBLE_STRAIN`)."""
    from ..models.maximal import MAX_ELIMINATION_WIRES

    return scene.n_wires > MAX_ELIMINATION_WIRES and length_strain_scale(scene, com, R, lam) < PLAUSIBLE_STRAIN


def elastic_rest(scene: Scene, ea, com0: np.ndarray, R0: np.ndarray, iters: int = 60):
    """The static equilibrium of ``scene`` on elastic, tension-only wires of
    axial stiffness ``ea`` (N, scalar or (n,)): each wire a spring
    ``T_i = EA_i / L_i max(|d_i| - L_i, 0)``.  Newton on the potential's
    gradient in (dr, dtheta world) with the exact Hessian (the springs'
    ``k_i g_i g_i^T`` and their tensions' geometric term), each step halved
    until the potential falls, from the rigid pose (``com0`` m, ``R0``) moved
    down by the stretch the mean load gives the softest wire (every wire
    taut at the start).  Returns (com (3,), R (3, 3), tensions (n,) N,
    residual: the largest force or moment / length left, per unit weight);
    :class:`~bifilar.errors.ConvergenceError` when Newton does not reach
    1e-10 of the weight (its rounding floor ~1e-12)."""
    L = np.asarray(scene.lengths, float)
    k = np.broadcast_to(np.asarray(ea, float), L.shape) / L  # N/m
    W = scene.mass * scene.gravity
    Ls = float(np.max(L))
    gradV = np.array([0.0, 0.0, W, 0.0, 0.0, 0.0])

    def state(c, R):
        d, w, G = constraint_jacobian(scene, c, R)
        ln = np.linalg.norm(d, axis=1)
        s = np.maximum(ln - L, 0.0)
        T = k * s
        energy = W * c[2] + 0.5 * float(np.sum(k * s * s))
        return d, w, G, ln, T, gradV + G.T @ (T / ln), energy

    scale = np.concatenate([np.full(3, 1.0 / W), np.full(3, 1.0 / (W * Ls))])
    c = np.asarray(com0, float) - np.array([0.0, 0.0, (W / scene.n_wires) / float(np.min(k))])
    R = np.asarray(R0, float)
    d, w, G, ln, T, g, E = state(c, R)
    for _ in range(iters):
        if np.max(np.abs(g * scale)) < 1e-14:
            break
        taut = (ln > L).astype(float)
        lam = T / ln
        Gn = G / ln[:, None]
        # Hessian of the springs' energy: k (taut) g g^T / |d|^2 plus the tension's  lam (H_i - g g^T / |d|^2)
        H = np.einsum("i,ij,ik->jk", k * taut, Gn, Gn) + np.einsum("i,ijk->jk", lam, constraint_hessians(d, w)) \
            - np.einsum("i,ij,ik->jk", lam, Gn, Gn)
        H = 0.5 * (H + H.T)
        ev = np.linalg.eigvalsh(H)
        if ev[0] <= 1e-12 * ev[-1]:  # not convex here (a wire slack, a neutral turn): shift to a descent step
            H = H + (1e-12 * ev[-1] - ev[0]) * np.eye(6)
        x = -np.linalg.solve(H, g)
        for _half in range(40):
            c1, R1 = c + x[:3], rotvec_to_matrix(x[3:]) @ R
            st = state(c1, R1)
            if st[-1] <= E + 1e-15 * W * Ls:
                break
            x = 0.5 * x
        else:  # no step lowers the potential: at the rounding floor
            break
        c, R = c1, R1
        d, w, G, ln, T, g, E = st
    res = float(np.max(np.abs(g * scale)))
    if not res < 1e-10:
        raise ConvergenceError(f"elastic rest pose did not converge (residual {res:.2e} of the weight)")
    return c, R, T, res
