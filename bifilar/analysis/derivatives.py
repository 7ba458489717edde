"""Analytic first derivatives of the rest pose and of the linear mode
periods with respect to every scene input (issue 14).

One rest pose and one eigen-solve replace the 2 J rest-pose + mode solves of
central finite differences (J inputs).

Inputs are named as in :mod:`bifilar.estimation.sensitivity` (SI units):
``Ixx Iyy Izz Ixy Ixz Iyz`` (body axes, kg m^2; an off-diagonal name moves
both symmetric entries), ``mass`` (kg), ``gravity`` (m/s^2), ``length.i``
(m), ``anchor.i.x|y|z`` (world frame, m), ``attachment.i.x|y|z`` (body
frame, m) and ``com.x|y|z`` (m: the CoM moved by +d, i.e. every attachment
by -d in body axes).

Method
------
Rest pose.  The pose is ``(c, R)`` with the world chart ``(dr, dtheta)``
(``R -> exp(dtheta) R``) and the multipliers ``lam_i = T_i / |d_i|``; the
KKT equations ``F = [grad V + G^T lam; phi] = 0`` (``V = m g z``,
``phi_i = (|d_i|^2 - L_i^2)/2``, ``G`` the Jacobian of ``phi``) define the
pose implicitly, so with ``A = [[K, G^T], [G, 0]]`` (``K = sum lam_i
Hess phi_i``, the Lagrangian's Hessian, which is also the chart derivative
of the Lagrangian gradient at an equilibrium) the derivative along input
``p_j`` is ``A [dx; dlam] = -dF/dp_j``.

Eigenvalues.  A mode ``omega^2`` with shape ``v`` (``v^T M v = 1``) solves
``(K - omega^2 M) v + G^T mu = 0``, ``G v = 0``; differentiating,

    d omega^2 = v^T (dK - omega^2 dM) v + 2 mu^T dG v,

where ``dK, dM, dG`` are total derivatives along the input and the pose and
multiplier derivatives above.  ``dF/dp``, ``dK``, ``dM`` and ``dG`` are taken
by the complex step (``Im f(x + i h e) / h``, exact to rounding: every
matrix is a polynomial in the pose, the rotation perturbed to first order as
``(I + i h [dtheta]x) R``), all inputs at once, at the fixed rest pose: no
new rest pose and no new eigen-solve.  Then ``dT = -T/(2 omega^2) d omega^2``.

Where this does not apply: a neutral mode (no period) gets a NaN row.  A
singular KKT matrix (CoM on the attachment line: a neutral direction) gives
the minimum-norm pose derivative, as the Newton solver's least-squares step
gives a finite-difference neighbour, except for inputs that push along the
neutral direction, whose columns are NaN (the body turns by a finite angle
for any change: the caller differences them one-sidedly, see
:func:`bifilar.estimation.sensitivity.period_sensitivity`).

Repeated eigenvalues (a cluster :func:`bifilar.analysis.modes.linear_modes`
merged, e.g. the two swings of a symmetric trifilar): each input splits the
eigenvalue along its own directions in the eigenspace, the eigenvalues of
``V^T (dK - omega^2 dM) V`` plus the constraint terms over the eigenspace
``V`` (degenerate perturbation theory, :func:`_cluster_derivative`), and
each member takes the split value of the direction it matches by MAC (the
mean of those it matches equally), which is what central differences with
MAC mode tracking converge to (except at an exact tie, where they picked a
branch by rounding).  A nearly repeated pair that ``linear_modes``
kept apart (split between its 1e-10 resolution and 1e-8) has no first-order
row that holds over a useful step: :func:`analytic_period_jacobian` raises
:class:`NotDifferentiable` and the caller falls back to finite differences
with mode tracking for the whole Jacobian.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .batch_rest import _cross, _skew  # complex-safe: np.cross's and the stacked skew's values, written in place
from .equilibrium import RestPose
from .modes import ModeSet, degenerate_clusters

INERTIA_INDEX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
_AX = {"x": 0, "y": 1, "z": 2}
_H = 1e-30  # complex step; any tiny value gives the derivative to rounding


class NotDifferentiable(Exception):
    """The analytic derivative does not exist or is not unique here (the message says why)."""


@dataclass(frozen=True)
class RestDerivative:
    """Derivatives of the rest pose with respect to ``names`` (one row per input).

    dcom : (J, 3) m per unit input (world frame).
    dtheta : (J, 3) rad per unit input: the rotation derivative,
        dR/dp = [dtheta]x R (world-frame rotation vector).
    dtensions : (J, n) N per unit input.
    dlam : (J, n) the multipliers lam_i = T_i / |d_i| (N/m) per unit input.
    """

    names: list
    dcom: np.ndarray
    dtheta: np.ndarray
    dtensions: np.ndarray
    dlam: np.ndarray


def input_directions(scene: Scene, names: list[str]) -> dict:
    """Unit perturbation of every scene array along each input (leading axis J).

    Returns a dict of real arrays: ``anchors`` (J, n, 3), ``attachments``
    (J, n, 3), ``lengths`` (J, n), ``mass`` (J,), ``gravity`` (J,),
    ``inertia`` (J, 3, 3): the derivative of each scene array with respect
    to the input (dimensionless: 1 per unit of the input).
    """
    J, n = len(names), scene.n_wires
    out = {"anchors": np.zeros((J, n, 3)), "attachments": np.zeros((J, n, 3)), "lengths": np.zeros((J, n)),
           "mass": np.zeros(J), "gravity": np.zeros(J), "inertia": np.zeros((J, 3, 3))}
    for j, name in enumerate(names):
        if name in INERTIA_INDEX:
            a, b = INERTIA_INDEX[name]
            out["inertia"][j, a, b] = 1.0
            out["inertia"][j, b, a] = 1.0
            continue
        if name in ("mass", "gravity"):
            out[name][j] = 1.0
            continue
        parts = name.split(".")
        if parts[0] == "length" and len(parts) == 2:
            out["lengths"][j, int(parts[1]) - 1] = 1.0
        elif parts[0] in ("anchor", "attachment") and len(parts) == 3:
            out[parts[0] + "s"][j, int(parts[1]) - 1, _AX[parts[2]]] = 1.0
        elif parts[0] == "com" and len(parts) == 2:
            out["attachments"][j, :, _AX[parts[1]]] = -1.0
        else:
            raise KeyError(f"unknown input {name!r}")
    return out


def _parts(a, p, L, m, g, I, c, R, lam):
    """KKT residual, constraint Jacobian, Lagrangian Hessian and mass matrix,
    batched over a leading axis and complex-safe (no conjugation).

    a, p (B, n, 3); L (B, n); m, g (B,); I (B, 3, 3); c (B, 3); R (B, 3, 3);
    lam (B, n).  Returns F (B, 6 + n), G (B, n, 6), K (B, 6, 6), M (B, 6, 6).
    """
    w = np.einsum("bij,bnj->bni", R, p)
    d = c[:, None, :] + w - a
    G = np.concatenate([d, _cross(w, d)], axis=-1)
    phi = 0.5 * (np.einsum("bni,bni->bn", d, d) - L**2)
    gradV = np.zeros(c.shape[:1] + (6,), dtype=G.dtype)
    gradV[:, 2] = m * g
    F = np.concatenate([gradV + np.einsum("bni,bn->bi", G, lam), phi], axis=-1)
    W = _skew(w)  # (B, n, 3, 3)
    eye = np.eye(3)
    dw = np.einsum("bni,bni->bn", d, w)
    rot = (-W @ W + 0.5 * (np.einsum("bni,bnj->bnij", d, w) + np.einsum("bni,bnj->bnij", w, d))
           - dw[..., None, None] * eye)
    B = c.shape[0]
    K = np.zeros((B, 6, 6), dtype=G.dtype)
    sl = lam.sum(axis=1)
    K[:, :3, :3] = sl[:, None, None] * eye
    K[:, :3, 3:] = -np.einsum("bn,bnij->bij", lam, W)
    K[:, 3:, :3] = np.einsum("bn,bnij->bij", lam, W)
    K[:, 3:, 3:] = np.einsum("bn,bnij->bij", lam, rot)
    M = np.zeros((B, 6, 6), dtype=G.dtype)
    M[:, :3, :3] = m[:, None, None] * eye
    M[:, 3:, 3:] = R @ I @ np.swapaxes(R, -1, -2)
    return F, G, K, M


def _base(scene: Scene, rest: RestPose):
    lam = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
    return (scene.anchors[None], scene.attachments[None], scene.lengths[None], np.array([scene.mass]),
            np.array([scene.gravity]), scene.inertia[None], rest.com[None], rest.R[None], lam[None])


def _stepped(scene, rest, dirs, dx=None, dlam=None):
    """The scene arrays, pose and multipliers moved by i h along every input
    direction (and along the pose/multiplier derivatives ``dx`` (J, 6), ``dlam`` (J, n))."""
    a, p, L, m, g, I, c, R, lam = _base(scene, rest)
    ih = 1j * _H
    J = dirs["mass"].shape[0]
    args = [a + ih * dirs["anchors"], p + ih * dirs["attachments"], L + ih * dirs["lengths"],
            m + ih * dirs["mass"], g + ih * dirs["gravity"], I + ih * dirs["inertia"]]
    if dx is None:
        args += [np.repeat(c, J, 0).astype(complex), np.repeat(R, J, 0).astype(complex),
                 np.repeat(lam, J, 0).astype(complex)]
    else:
        Rj = (np.eye(3) + ih * _skew(dx[:, 3:].astype(complex))) @ R
        args += [c + ih * dx[:, :3], Rj, lam + ih * dlam]
    return args


def _kkt_matrix(scene: Scene, rest: RestPose):
    F, G, K, M = _parts(*_base(scene, rest))
    n = scene.n_wires
    A = np.zeros((6 + n, 6 + n))
    A[:6, :6] = K[0]
    A[:6, 6:] = G[0].T
    A[6:, :6] = G[0]
    return A, G[0], K[0], M[0]


def _scales(scene: Scene):
    """Row and column scales making the KKT matrix dimensionless (as in the Newton solver)."""
    n, Ls, fs = scene.n_wires, float(np.max(scene.lengths)), scene.mass * scene.gravity
    cs = np.concatenate([np.full(3, Ls), np.ones(3), np.full(n, fs / Ls**2)])
    rs = np.concatenate([np.full(3, 1 / fs), np.full(3, 1 / (fs * Ls)), np.full(n, 1 / Ls**2)])
    return rs, cs


def _pose_derivative(scene: Scene, rest: RestPose, dirs: dict, singular: float = 1e-12, consistent: float = 1e-8,
                     push: bool = False):
    """dx (J, 6) = (dcom, dtheta) and dlam (J, n) per unit of each input,
    and a mask (J,) of the inputs whose derivative does not exist; with
    ``push``, also each input's push along the neutral direction (J,): the
    least-squares residual relative to the right-hand side (0 to rounding
    where the derivative exists, O(1) for an input that moves the CoM off a
    knife edge's line sideways).

    The KKT system is solved in the dimensionless scaling of the Newton
    solver.  When the KKT matrix is singular (smallest singular value below
    ``singular`` times the largest: a neutral direction, e.g. the CoM on the
    attachment line) the minimum-norm solution is taken, as the Newton
    solver's least-squares step takes it for a finite-difference neighbour;
    an input that pushes along the neutral direction (least-squares residual
    above ``consistent`` of the right-hand side) has no derivative: the body
    would turn over, or turn by a finite angle, for any change of it."""
    A, G, K, M = _kkt_matrix(scene, rest)
    F = _parts(*_stepped(scene, rest, dirs))[0]
    dF = F.imag / _H  # (J, 6 + n)
    rs, cs = _scales(scene)
    As = rs[:, None] * A * cs[None, :]
    b = -(rs[:, None] * dF.T)  # (6 + n, J)
    U, s, Vt = np.linalg.svd(As)
    keep = s > singular * s[0]
    coef = (U[:, keep].T @ b) / s[keep, None]
    z = Vt[keep].T @ coef
    resid = np.linalg.norm(b - As @ z, axis=0)
    bnorm = np.linalg.norm(b, axis=0)
    bad = resid > consistent * bnorm
    z = cs[:, None] * z
    if push:
        return z[:6].T, z[6:].T, bad, resid / np.where(bnorm > 0, bnorm, 1.0)
    return z[:6].T, z[6:].T, bad


def rest_derivative(scene: Scene, rest: RestPose, names: list[str]) -> RestDerivative:
    """Derivatives of the rest pose ``rest`` of ``scene`` with respect to ``names``
    (implicit function theorem on the KKT equations; see the module docstring).
    Inputs with no derivative (a singular KKT matrix and an input pushing
    along its neutral direction, see :func:`_pose_derivative`) get NaN rows."""
    dirs = input_directions(scene, names)
    dx, dlam, bad = _pose_derivative(scene, rest, dirs)
    dx[bad] = np.nan
    dlam[bad] = np.nan
    d = rest.wire_vectors
    nd = np.linalg.norm(d, axis=1)
    lam = rest.tensions / nd
    # d_i = c + R p_i - a_i: dd_i = dc + [dtheta]x R p_i + R dp_i - da_i
    w = scene.attachments @ rest.R.T
    dd = (dx[:, None, :3] + _cross(dx[:, None, 3:], w[None]) + dirs["attachments"] @ rest.R.T
          - dirs["anchors"])
    dT = dlam * nd + lam * np.einsum("jni,ni->jn", dd, d) / nd
    return RestDerivative(list(names), dx[:, :3], dx[:, 3:], dT, dlam)


def analytic_period_jacobian(scene: Scene, rest: RestPose, ms: ModeSet, names: list[str], push: bool = False):
    """dT_k/dp_j (s per unit input), (K, J), for the modes of ``ms`` (the
    linear modes of ``scene`` about ``rest``), analytic (module docstring).

    A neutral mode (no period) has a NaN row; an input without a derivative
    (singular KKT matrix and the input pushing along its neutral direction)
    a NaN column: the caller differences those columns.  Repeated
    eigenvalues: each member's row along each input's own split
    (:func:`_cluster_derivative`); raises :class:`NotDifferentiable` for a
    nearly repeated pair kept apart (:func:`_repeated`).  ``push``: return
    ``(jacobian, push)``, ``push`` (J,) how hard each input pushes along the
    neutral direction (:func:`_pose_derivative`; dimensionless, 0 to
    rounding where the column is finite).
    """
    if scene.stiffness is not None:
        # elastic wires: the pose is the elastic one and a change of an input moves each wire's stretch too
        # (a length by 1 + T / EA and more), which this rigid KKT derivative does not know: the callers'
        # finite differences of the whole chain carry it (docs/design.md "stretch, session 17")
        raise NotDifferentiable("elastic wires (rig.stiffness): the stretch changes with every input")
    if not ms.modes:
        z = np.zeros((0, len(names)))
        return (z, np.zeros(len(names))) if push else z
    w2 = np.array([m.omega2 for m in ms.modes])
    live = np.array([m.period is not None for m in ms.modes])
    scale = float(np.max(np.abs(w2)))
    groups = _repeated(w2, live, scale)
    dirs = input_directions(scene, names)
    dx, dlam, bad, rel = _pose_derivative(scene, rest, dirs, push=True)
    _, G, K, M = _kkt_matrix(scene, rest)
    _, Gs, Ks, Ms = _parts(*_stepped(scene, rest, dirs, dx, dlam))
    dG, dK, dM = Gs.imag / _H, Ks.imag / _H, Ms.imag / _H
    V = np.array([m.shape for m in ms.modes]).T  # (6, K)
    V = V / np.sqrt(np.einsum("ik,ij,jk->k", V, M, V))  # v^T M v = 1
    Rres = K @ V - M @ V * w2  # (K - w2 M) v = -G^T mu
    mu = -np.linalg.lstsq(G.T, Rres, rcond=None)[0]  # (n, K)
    dw2 = (np.einsum("ik,jil,lk->kj", V, dK, V) - w2[:, None] * np.einsum("ik,jil,lk->kj", V, dM, V)
           + 2 * np.einsum("nk,jnl,lk->kj", mu, dG, V))
    T = np.array([m.period if m.period is not None else np.nan for m in ms.modes])
    for idx in groups:  # a repeated eigenvalue: each member's derivative along each input's own split
        dw2[idx] = _cluster_derivative(V[:, idx], M, w2[idx[0]], mu[:, idx], dK, dM, dG)
    jac = -(T / (2 * np.where(live, w2, 1.0)))[:, None] * dw2
    jac[~live] = np.nan
    jac[:, bad] = np.nan
    return (jac, rel) if push else jac


#: assignments of a cluster's modes to its split directions whose total MAC is within this
#: of the best tie (:func:`_cluster_derivative`): a finite-difference step of 1e-6 of the
#: input's scale moves a MAC by ~1e-6, and a direction computed to rounding moves it by
#: ~1e-16 / (relative split of the d_i)
MAC_TIE = 1e-6

#: members of a cluster that :func:`bifilar.analysis.modes.mode_set` merged carry one eigenvalue
#: (the cluster mean, so equal); a pair it kept apart differs by more than its resolution,
#: ``DEGENERATE_RTOL`` (1e-10) of ``|y|^T |K| |y| >= omega^2``: this separates the two
_MERGED_RTOL = 1e-12


def _repeated(w2: np.ndarray, live: np.ndarray, scale: float) -> list:
    """Index arrays (into the modes) of the clusters of repeated live
    eigenvalues ``w2`` (rad^2/s^2) that :func:`~bifilar.analysis.modes.mode_set`
    merged (one eigenvalue, an aligned basis): their derivatives follow from
    degenerate perturbation theory (:func:`_cluster_derivative`).  Raises
    :class:`NotDifferentiable` for a pair within the wider band of
    :func:`~bifilar.analysis.modes.degenerate_clusters` (1e-8 of ``scale``)
    that was kept apart: its members' derivatives change over inputs
    steps of the size of the split, so no first-order row describes them."""
    idx = np.nonzero(live)[0]
    order = idx[np.argsort(w2[idx], kind="stable")]
    out = []
    for a, b in degenerate_clusters(w2[order], scale):
        members = order[a:b]
        vals = w2[members]
        if float(np.max(vals) - np.min(vals)) > _MERGED_RTOL * float(np.max(np.abs(vals))):
            raise NotDifferentiable("nearly repeated eigenvalues: each mode's derivative depends on the step")
        out.append(np.sort(members))
    return out


def _cluster_derivative(Vc, M, w2, mu, dK, dM, dG) -> np.ndarray:
    """d omega^2 (c, J) of the ``c`` modes of a repeated eigenvalue ``w2``
    (rad^2/s^2) with shapes ``Vc`` (6, c; any basis of the eigenspace, e.g.
    :func:`~bifilar.analysis.modes.mode_set`'s world-aligned one) and
    constraint multipliers ``mu`` (n, c), along each of J inputs (``dK``,
    ``dM`` (J, 6, 6), ``dG`` (J, n, 6): total derivatives).

    Degenerate perturbation theory: along input j the eigenvalue splits into
    the eigenvalues ``d_i`` of the pencil ``(D_j, B)`` on the eigenspace,
    ``D_j[a, b] = v_a^T (dK - w2 dM) v_b + mu_a^T dG v_b + mu_b^T dG v_a``
    (the symmetric form of the single-mode formula, whose diagonal it is),
    ``B = Vc^T M Vc``; the eigenvector ``e_i`` gives the direction
    ``u_i = Vc e_i`` the split modes take.  Each base mode gets the ``d_i``
    of the direction it matches by MAC (one to one, as
    :func:`~bifilar.estimation.sensitivity.mac_match` tracks modes across a
    finite-difference step: a central difference of the tracked period
    converges to exactly this, the eigenvalue branches being analytic in the
    step), so the row is what the finite differences gave, without their
    truncation and rounding error.  Where two ``d_i`` are equal the
    direction is arbitrary but the value is not.  Where two one-to-one
    assignments tie (total MAC within :data:`MAC_TIE`: e.g. swings at 45
    degrees to the split directions, each half of each), a base mode that
    the tied assignments give different directions gets the mean of their
    ``d_i``: no branch is closer, and a choice by rounding would make the
    row depend on the machine.  (Central differences gave the mean where
    the step's own O(h) terms break the tie: they flip branch with its
    sign; where the tie is exact at every step, as for Ixy of a body with
    Ixx = Iyy, whose split directions are the diagonals, they took the
    branch the matching's index order gave, a sign by rounding, where the
    mirror x <-> y makes the swing's period even in Ixy: derivative 0, the
    mean.)  So the members'
    values always add up to ``sum d_i = trace(B^-1 D_j)``, the derivative
    of the cluster's sum, whatever the basis."""
    B = Vc.T @ M @ Vc
    B = 0.5 * (B + B.T)
    t = np.einsum("nk,jnl,lm->jkm", mu, dG, Vc)
    D = np.einsum("ik,jil,lm->jkm", Vc, dK, Vc) - w2 * np.einsum("ik,jil,lm->jkm", Vc, dM, Vc) + t + np.swapaxes(t, 1, 2)
    D = 0.5 * (D + np.swapaxes(D, 1, 2))
    Lc = np.linalg.cholesky(B)
    Li = np.linalg.inv(Lc)
    d, Z = np.linalg.eigh(Li @ D @ Li.T)  # (J, c), (J, c, c)
    E = Li.T @ Z  # (J, c, c): B-orthonormal directions e_i (columns)
    BE = B @ E
    mac = BE**2 / (np.diag(B)[None, :, None] * np.einsum("jki,kl,jli->ji", E, B, E)[:, None, :])
    # every one-to-one assignment of the base modes to the directions (c! of them, c <= 6) and its total MAC
    c = Vc.shape[1]
    perms = np.array(list(itertools.permutations(range(c))))  # (P, c): perms[p, a] = direction of base mode a
    total = mac[:, np.arange(c), perms].sum(axis=2)  # (J, P)
    near = total >= np.max(total, axis=1, keepdims=True) - MAC_TIE
    out = np.empty((c, len(d)))
    for j in range(len(d)):
        for a in range(c):
            cols = np.unique(perms[near[j], a])
            out[a, j] = d[j, cols[0]] if len(cols) == 1 else float(np.mean(d[j, cols]))
    return out
