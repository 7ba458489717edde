"""Rest poses and linear modes of many scenes at once (the first stages of
:mod:`bifilar.analysis.batch`, which re-exports :func:`rest_poses`,
:func:`modes_batch` and :func:`rest_and_modes`).

* :func:`rest_poses`: Newton's method on the KKT equations, all scenes at
  once, from the start pose :func:`~bifilar.analysis.equilibrium.rest_pose`
  uses (never from a neighbour's pose: a rig with two stable equilibria
  would end at the one nearer it); a scene whose Newton run does not end
  where ``rest_pose``'s Newton start would be accepted (a taut, stable
  equilibrium turned by at most its 0.5 rad from the start orientation, a
  two-wire rig's CoM straight below its attachment line) falls back to
  ``rest_pose`` (global search and its one-line errors), or, where the
  caller gives the pose of the scene they are all small changes of
  (``near``: the sigma points' base), first to Newton from that pose; a knife edge's
  pose is turned to the canonical member of its neutral circle, as
  ``rest_pose`` does.  So the batch order, its first scene and a guess
  change no scene's pose or verdict (``near`` changes a fallback scene's
  pose by rounding, ~1e-15, where it lies on ``near``'s branch; a Newton
  end it does not accept goes to ``rest_pose``, and on the 1009 fallback
  scenes of tests/test_invert_roots.py no verdict differed).
* :func:`modes_batch`: null space of the constraint Jacobian, reduced
  stiffness and mass, and the generalised eigenproblem by batched Cholesky
  and ``eigh``; labels as :func:`~bifilar.analysis.modes.linear_modes`.

Vectorised over scenes (numpy arrays with a leading scene axis); units SI,
world frame z up.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import BifilarError
from ..models.maximal import MAX_ELIMINATION_WIRES, held_directions
from ..rotations import cross, matrix_to_quat, rotvec_to_matrix, skew_of
from ..scene import Scene, lowest_point_z
from .equilibrium import (LINE_TURN_TOL, MIN_WIRE_SLOPE, NEWTON_START_MAX_TURN, START_BOX, RestPose, canonical_attitude, knife_edge_axes,
                          line_turns, multiplier_matrix, near_dependent, rest_pose, start_coms)
from . import newton_kernel
from .modes import LazyModeSet, ModeSet, mode_sets, plain_order, unit_shapes

__all__ = ["rest_poses", "modes_batch", "rest_and_modes", "BatchGeometry", "Deferred"]


# --------------------------------------------------------------------------
# geometry helpers, vectorised over scenes
# --------------------------------------------------------------------------
def _stack(scenes: Sequence[Scene]):
    a = np.array([s.anchors for s in scenes])
    p = np.array([s.attachments for s in scenes])
    L = np.array([s.lengths for s in scenes])
    m = np.array([s.mass for s in scenes])
    g = np.array([s.gravity for s in scenes])
    I = np.array([s.inertia for s in scenes])
    return a, p, L, m, g, I


def _groups(scenes: Sequence[Scene]) -> list[list[int]]:
    """Indices of the scenes grouped by wire count (arrays need one count)."""
    out: dict[int, list[int]] = {}
    for k, s in enumerate(scenes):
        out.setdefault(s.n_wires, []).append(k)
    return [out[n] for n in sorted(out)]


def _mixed(scenes: Sequence[Scene]) -> bool:
    """Whether ``scenes`` have more than one wire count (:func:`_groups`
    would give several groups), without grouping them."""
    return len({s.lengths.shape[0] for s in scenes}) > 1


def _per_group(fn, scenes, *lists, **kw) -> list:
    """Apply ``fn(sub_scenes, *sub_lists, **kw) -> list`` per wire-count group
    and reassemble the results in input order (lists may be None)."""
    out: list = [None] * len(scenes)
    for ii in _groups(scenes):
        subs = [None if x is None else [x[k] for k in ii] for x in lists]
        for k, r in zip(ii, fn([scenes[k] for k in ii], *subs, **kw)):
            out[k] = r
    return out


_cross = cross  # cross products over the last axis: np.cross's values, without its axis handling


def _jacobian(a, p, com, R):
    """Wire vectors d, lever arms w = R p (B, n, 3) and G = [d, w x d] (B, n, 6)
    of the stacked anchors a, attachments p, CoMs com and attitudes R (SI,
    world frame): :mod:`.newton_kernel`'s compiled loop where it is there,
    else :func:`_jacobian_numpy` (the same bits)."""
    got = newton_kernel.jacobians(a, p, com, R)
    return _jacobian_numpy(a, p, com, R) if got is None else got


def _jacobian_numpy(a, p, com, R):
    """:func:`_jacobian` in numpy (the reference; the Newton pass's own)."""
    w = np.einsum("bij,bnj->bni", R, p)
    d = com[:, None, :] + w - a
    return d, w, np.concatenate([d, _cross(w, d)], axis=-1)


def _constraints(a, p, L, com, R, ii):
    """d, w, G (as :func:`_jacobian`) and phi = (|d|^2 - L^2)/2 (k, n) for the scenes ``ii`` (numpy's)."""
    d, w, G = _jacobian_numpy(a[ii], p[ii], com[ii], R[ii])
    return d, w, G, 0.5 * (np.einsum("bni,bni->bn", d, d) - L[ii] ** 2)


_skew = skew_of  # cross-product matrices (..., 3, 3) in v's dtype, written entry by entry


def _hessian(d, w, lam):
    """sum_i lam_i H_i (B, 6, 6): the constraint Hessians of
    :func:`~bifilar.analysis.equilibrium.constraint_hessians`, weighted
    (wire vectors d, lever arms w (B, n, 3), multipliers lam (B, n); SI):
    :mod:`.newton_kernel`'s compiled loop where it is there, else
    :func:`_hessian_numpy` (the same bits)."""
    got = newton_kernel.hessians(d, w, lam)
    return _hessian_numpy(d, w, lam) if got is None else got


def _hessian_numpy(d, w, lam):
    """:func:`_hessian` in numpy (the reference; the Newton pass's own)."""
    W = _skew(w)  # (B, n, 3, 3)
    eye = np.eye(3)
    dw = np.einsum("bni,bni->bn", d, w)
    Hrr = -np.einsum("bnij,bnjk->bnik", W, W) + 0.5 * (d[..., :, None] * w[..., None, :] + w[..., :, None] * d[..., None, :]) \
        - dw[..., None, None] * eye
    H = np.empty(d.shape[:1] + (6, 6))
    ls = lam.sum(axis=1)
    H[:, :3, :3] = ls[:, None, None] * eye
    H[:, :3, 3:] = -np.einsum("bn,bnij->bij", lam, W)
    H[:, 3:, :3] = np.einsum("bn,bnij->bij", lam, W)
    H[:, 3:, 3:] = np.einsum("bn,bnij->bij", lam, Hrr)
    return H


# --------------------------------------------------------------------------
# rest poses
# --------------------------------------------------------------------------
def _newton_batch(a, p, L, m, g, com, R, lam, iters: int = 40, native=True):
    """Newton on grad V + G^T lam = 0, phi = 0 for every scene (damped like
    the single-scene solver).  Returns com, R, lam, kkt residual (B,).
    ``native``: each pass but the attitude update by the compiled pass of
    :mod:`.newton_kernel` where it is there (the same bits; a pass it
    declines is numpy's), False: numpy only, or a function standing for
    the compiled ``nstep`` (its load check)."""
    Bn, n = L.shape
    gradV = np.zeros((Bn, 6))
    gradV[:, 2] = m * g
    fscale = m * g
    Lmax = L.max(axis=1)
    active = np.ones(Bn, bool)
    res = np.full(Bn, np.inf)
    run = None
    if native is not False:
        com, R, lam = (np.ascontiguousarray(x, float) for x in (com, R, lam))
        args = (active, *(np.ascontiguousarray(x, float) for x in (a, p, L, fscale, Lmax)), com, R, lam, res)
        run = newton_kernel.pass_for(*args) if native is True else newton_kernel._runner(native, *args)
    for _ in range(iters):
        if run is not None:
            k, rv, jj = run()
            if k == 0:
                break
            if k > 0:
                R[jj] = rotvec_to_matrix(rv) @ R[jj]
                continue
        ii = np.nonzero(active)[0]
        if not len(ii):
            break
        d, w, G, phi = _constraints(a, p, L, com, R, ii)
        r1 = gradV[ii] + np.einsum("bni,bn->bi", G, lam[ii])
        res[ii] = np.maximum(np.abs(r1).max(axis=1) / fscale[ii], np.abs(phi).max(axis=1) / Lmax[ii] ** 2)
        conv = res[ii] < 1e-15
        active[ii[conv]] = False
        if np.all(conv):
            break
        keep = ~conv
        ii, d, w, G, phi, r1 = ii[keep], d[keep], w[keep], G[keep], phi[keep], r1[keep]
        K = np.zeros((len(ii), 6 + n, 6 + n))
        K[:, :6, :6] = _hessian_numpy(d, w, lam[ii])
        K[:, :6, 6:] = np.swapaxes(G, 1, 2)
        K[:, 6:, :6] = G
        rhs = -np.concatenate([r1, phi], axis=1)
        try:
            step = np.linalg.solve(K, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            step = np.stack([np.linalg.lstsq(Kb, rb, rcond=None)[0] for Kb, rb in zip(K, rhs)])
        dx = step[:, :6]
        lim = 0.2 * Lmax[ii]
        s = np.minimum(1.0, np.minimum(lim / np.maximum(np.abs(dx[:, :3]).max(axis=1), 1e-300),
                                       0.5 / np.maximum(np.abs(dx[:, 3:]).max(axis=1), 1e-300)))
        com[ii] = com[ii] + s[:, None] * dx[:, :3]
        R[ii] = rotvec_to_matrix(s[:, None] * dx[:, 3:]) @ R[ii]
        lam[ii] = lam[ii] + s[:, None] * step[:, 6:]
    # the final residual of the scenes that moved after their last one (a converged scene stopped where its
    # residual was taken: the same expressions on the same rows, so the same bits; every scene of a sigma-point
    # batch converges in 3 steps, and this pass was the fifth of its 5 constraint passes)
    if run is not None and run(final=True)[0] == 0:
        return com, R, lam, res
    ii = np.nonzero(active)[0]
    if len(ii):
        d, w, G, phi = _constraints(a, p, L, com, R, ii)
        r1 = gradV[ii] + np.einsum("bni,bn->bi", G, lam[ii])
        res[ii] = np.maximum(np.abs(r1).max(axis=1) / fscale[ii], np.abs(phi).max(axis=1) / Lmax[ii] ** 2)
    return com, R, lam, res


def newton_start(a, p, L, m, g):
    """(com (B, 3), R (B, 3, 3), multipliers (B, n)): where :func:`rest_poses`
    starts Newton for scenes with the stacked anchors a, attachments p
    (B, n, 3), lengths L (B, n), masses m and gravities g (B,) (SI, world
    frame z up): :func:`rest_pose`'s start pose, the identity attitude and
    the least-squares multipliers there (as ``_newton_kkt``)."""
    com = start_coms(a, p, L)
    R = np.broadcast_to(np.eye(3), (len(m), 3, 3)).copy()
    _, _, G0 = _jacobian(a, p, com, R)
    gradV = np.zeros((len(m), 6))
    gradV[:, 2] = m * g
    return com, R, -np.einsum("bij,bj->bi", np.linalg.pinv(np.swapaxes(G0, 1, 2)), gradV)


def _null_space(G: np.ndarray, m: np.ndarray, I: np.ndarray, R: np.ndarray):
    """Orthonormal null-space bases (B, 6, 6-n) of full-rank G (B, n, 6) and
    whether each G has full rank (the rule of :func:`~bifilar.analysis.
    equilibrium.constraint_rank`; masses m (B,), body inertias I and
    attitudes R (B, 3, 3) for its multiplier matrix on 4 and 5 wires)."""
    _, s, vt = np.linalg.svd(G)
    n = G.shape[1]
    full = s[:, -1] > 1e-12 * s[:, 0]
    if n > MAX_ELIMINATION_WIRES:
        near = near_dependent(s)
        full = np.where(near, np.all(held_directions(np.linalg.eigvalsh(multiplier_matrix(m, I, R, G))), axis=1), full)
    return np.swapaxes(vt[:, n:, :], 1, 2), full


def _mass_matrix(m, I, R):
    M = np.zeros((len(m), 6, 6))
    M[:, 0, 0] = M[:, 1, 1] = M[:, 2, 2] = m
    M[:, 3:, 3:] = R @ I @ np.swapaxes(R, 1, 2)
    return M


def _accepted(a, p, L, m, g, I, com, R, lam, kkt):
    """What :func:`_newton_batch`'s ends (com, R, lam, kkt of scenes with the
    stacked arrays a, p, L, m, g, I; SI, world frame) give a rest pose, and
    which pass the checks :func:`~bifilar.analysis.equilibrium.rest_pose`
    applies to its Newton start's end (converged, every wire taut, full
    rank, stable, a two-wire rig's CoM below its attachment line, not every
    wire straight across), without the turn rule, which depends on where
    Newton started.  A knife edge (CoM on the attachment line) rests
    anywhere on a neutral circle, Newton's end there depends on rounding:
    its canonical member is taken, as ``rest_pose`` does.  Returns R (turned
    in place), d, w, G, |d|, tensions T, null space N, full rank, ok (B,)."""
    axis = knife_edge_axes(p)
    edge = np.all(np.isfinite(axis), axis=1)
    if edge.any():
        R[edge] = canonical_attitude(R[edge], axis[edge])
    d, w, G = _jacobian(a, p, com, R)
    dn = np.linalg.norm(d, axis=2)
    T = lam * dn
    ok = (kkt < 1e-9) & np.all(T > 1e-9 * (m * g)[:, None], axis=1)
    # stability: reduced stiffness positive semi-definite (as rest_pose checks)
    N, full = _null_space(G, m, I, R)
    ok &= full
    if G.shape[1] > MAX_ELIMINATION_WIRES:
        # Newton's multipliers are the run's (rest_multipliers) only where its cut-off weighs every direction
        # 1 to within 1e-12 (eigenvalue ratios above 1e3 x MIN_NORM_RCOND): the blend below goes to rest_pose
        ok &= ~near_dependent(np.linalg.svd(G, compute_uv=False)) | np.all(
            held_directions(np.linalg.eigvalsh(multiplier_matrix(m, I, R, G)), margin=1e3), axis=1)
    if N.shape[2]:
        Kr = np.swapaxes(N, 1, 2) @ _hessian(d, w, lam) @ N
        ev = np.linalg.eigvalsh(0.5 * (Kr + np.swapaxes(Kr, 1, 2)))
        ok &= ~(ev[:, 0] < -1e-9 * np.maximum(np.abs(ev[:, -1]), 1e-300))
    ok &= ~(np.abs(line_turns(p, R, edge_axes=axis)[0]) > LINE_TURN_TOL)
    ok &= np.max(np.abs(d[..., 2]) / dn, axis=1) >= MIN_WIRE_SLOPE
    return R, d, w, G, dn, T, N, full, ok


#: largest turn (rad) of a scene's Newton end from the ``near`` pose of :func:`rest_poses` at which that end
#: is taken (rest_pose's local start from a neighbour's pose allows the same: equilibrium._from_guess)
NEAR_MAX_TURN = 0.05


def _from_near(near: RestPose, which: np.ndarray, stacked, com, kkt, arrays) -> None:
    """Newton from ``near``'s pose and multipliers for the scenes ``which``
    (B,) bool of a batch (``stacked``: its a, p, L, m, g, I; ``com``, ``kkt``
    and ``arrays`` = (R, d, w, G, |d|, T, N, full, ok) of
    :func:`rest_poses`' first pass, overwritten in place for each scene
    whose end passes :func:`_accepted`, turned from ``near`` by at most
    :data:`NEAR_MAX_TURN` and from the start orientation by at most the
    start box (``rest_pose``'s refusal beyond it is left to ``rest_pose``)."""
    ii = np.nonzero(which)[0]
    a, p, L, m, g, I = (x[ii] for x in stacked)
    n = len(ii)
    c0 = np.broadcast_to(np.asarray(near.com, float), (n, 3)).copy()
    R0 = np.broadcast_to(np.asarray(near.R, float), (n, 3, 3)).copy()
    lam0 = np.asarray(near.tensions, float) / np.linalg.norm(np.asarray(near.wire_vectors, float), axis=1)
    if lam0.shape[0] != L.shape[1]:
        return
    c, R, lam, res = _newton_batch(a, p, L, m, g, c0, R0, np.broadcast_to(lam0, (n, len(lam0))).copy())
    got = _accepted(a, p, L, m, g, I, c, R, lam, res)
    acc = got[-1] & _within_turn(got[0] @ np.asarray(near.R, float).T, np.cos(NEAR_MAX_TURN / 2))
    acc &= (got[0][:, 0, 0] + got[0][:, 1, 1] + got[0][:, 2, 2] - 1) / 2 >= np.cos(START_BOX)
    if not acc.any():
        return
    jj = ii[acc]
    com[jj], kkt[jj] = c[acc], res[acc]
    for full_arr, part in zip(arrays[:-1], got[:-1]):
        full_arr[jj] = part[acc]
    arrays[-1][jj] = True


def rest_poses(scenes: Sequence[Scene], guess: RestPose | Sequence[RestPose] | None = None, *,
               errors: str = "raise", geometry: list | None = None,
               near: RestPose | None = None, defer: bool = False) -> list:
    """Rest poses of many scenes (same number of wires), vectorised.

    Parameters
    ----------
    guess : ignored (kept for callers that pass a neighbour's pose): every
        scene starts where :func:`rest_pose` starts, since a rig with two
        stable equilibria would end at the one nearer a warm start, and a
        sweep's answer would depend on its order and its first scene.
    errors : ``"raise"``: the first scene that cannot hang raises its
        error (:class:`SlackWireError`, ...); ``"return"``: its entry in
        the list is the exception instead.

    Returns a list of :class:`RestPose` (or exceptions), in input order,
    equal to :func:`rest_pose` of each scene to its convergence tolerance
    (KKT residual < 1e-9 relative; ~1e-15 in practice).  Each pose's
    ``lowest_z`` and ``depth`` are computed when first read (most batched
    callers never read them).

    ``geometry``: a list to which the batch's :class:`BatchGeometry` is
    appended (scenes of one wire count only), for :func:`modes_batch` of
    the same scenes and poses.

    ``near``: the rest pose of a scene every scene is a small change of (a
    sigma point's base, :mod:`bifilar.estimation.second_order`): a scene
    whose Newton run from the start pose is not accepted (it ends turned by
    more than 0.5 rad, or at a slack or unstable equilibrium: ~45 % of the
    sigma points of tests/test_invert_roots.py's random rigs) gets a second
    batched Newton run from ``near`` (:func:`_from_near`), its end taken
    where it passes the same checks and is turned from ``near`` by at most
    :data:`NEAR_MAX_TURN`; only the others go to :func:`rest_pose` (its
    global search, ~5 ms a scene).  Where ``rest_pose`` reaches the
    equilibrium on ``near``'s branch, the two ends agree to the KKT
    tolerance (measured on the 444 such scenes of tests/test_invert_roots.py:
    CoM <= 4.3e-16 m, each entry of R <= 1.6e-15, tensions <= 5e-16
    relative; tests/test_sigma_rest.py).

    ``defer``: a scene left to :func:`rest_pose` (or the elastic statics)
    gets a :class:`Deferred` entry instead, whose :meth:`~Deferred.settle`
    runs it: for a caller that may not need every such verdict (the
    sigma points of a key whose other sigma point cannot hang).
    """
    scenes = list(scenes)
    if not scenes:
        return []
    if _mixed(scenes):
        return _per_group(lambda sc: rest_poses(sc, errors=errors), scenes)
    out = [None] * len(scenes)
    a, p, L, m, g, I = _stack(scenes)
    # Newton from rest_pose's start pose (not from a guess: a rig with two stable equilibria would end at
    # the one nearer the guess, so a sweep's answer would depend on its order; tests/test_multi_equilibria.py)
    com, R, lam = newton_start(a, p, L, m, g)
    com, R, lam, kkt = _newton_batch(a, p, L, m, g, com, R, lam)
    R, d, w, G, dn, T, N, full, ok = _accepted(a, p, L, m, g, I, com, R, lam, kkt)
    # the single path's acceptance rule for its Newton start (rest_pose's stage 2) beside _accepted's: a turn of
    # at most NEWTON_START_MAX_TURN from the start orientation (inside the 90-degree box; farther, another
    # stable equilibrium may be the one its global search finds); a scene failing goes to rest_pose, which
    # turns it about the line, searches or refuses it
    ok &= _within_turn(R, np.cos(NEWTON_START_MAX_TURN / 2))
    # elastic wires (rig.stiffness): rest_pose's elastic statics; on 2-3 wires from this rigid pose where it is
    # rest_pose's (what rest_pose starts them from, without its search: session 18, ~2 ms a sigma point)
    stiff = np.array([s.stiffness is not None for s in scenes])
    from_rigid = ok & stiff & (G.shape[1] <= MAX_ELIMINATION_WIRES)
    ok &= ~stiff
    if near is not None and not ok.all():
        _from_near(near, ~ok & ~stiff, (a, p, L, m, g, I), com, kkt, (R, d, w, G, dn, T, N, full, ok))
    for k, s in enumerate(scenes):
        if out[k] is not None:
            continue
        if ok[k]:
            out[k] = _LazyDepthRest(s, com=com[k].copy(), R=R[k].copy(), tensions=T[k].copy(),
                                    wire_vectors=d[k].copy(), kkt_residual=float(kkt[k]))
        else:
            dk = Deferred(s, (com[k].copy(), R[k].copy()) if from_rigid[k] else None)
            out[k] = dk if defer else dk.settle(errors)
    if geometry is not None:
        geometry.append(BatchGeometry(scenes, out, ok, (a, p, L, m, g, I), R, d, w, G, dn, N, full, T))
    return out


class BatchGeometry:
    """What :func:`rest_poses` computed at the final poses of one batch
    (stacked scene arrays, attitudes, wire vectors d, lever arms w,
    constraint Jacobian G, |d| and G's null space) and :func:`modes_batch`
    computes again from the same scenes and poses with the same
    expressions: handed over, the same numbers without the second pass
    (~0.15 ms of a Solar Boat point's 36 sigma-point scenes).  Valid only
    for exactly the scenes and rest poses of that batch, in its order, each
    taken from the batch's own Newton run (not a ``rest_pose`` fallback):
    :meth:`matches`."""

    def __init__(self, scenes, rests, ok, stacked, R, d, w, G, dn, N, full, T=None):
        self.scenes, self.rests, self.ok = list(scenes), list(rests), ok
        self.stacked, self.R, self.d, self.w, self.G, self.dn = stacked, R, d, w, G, dn
        self.N, self.full = N, full
        self.T = T  # the wire tensions (B, n) whose rows each pose's ``tensions`` copies

    def matches(self, scenes: Sequence[Scene], rests: Sequence[RestPose]) -> bool:
        """Whether ``scenes`` and ``rests`` are this batch's, all of them, in
        its order, every pose from its Newton run (identity, not equality)."""
        return (len(scenes) == len(self.scenes) == len(rests) and bool(np.all(self.ok))
                and all(s is s0 for s, s0 in zip(scenes, self.scenes))
                and all(r is r0 for r, r0 in zip(rests, self.rests)))


def _within_turn(R: np.ndarray, c: float) -> np.ndarray:
    """(B,) |q_w| >= ``c`` of the quaternions :func:`~bifilar.rotations.matrix_to_quat`
    gives rotation matrices ``R`` (B, 3, 3): decided from the trace
    (|q_w| = sqrt(1 + tr) / 2 for a rotation, to ~1e-15) where it is more
    than 1e-9 from ``c``, else (and for a matrix with a NaN) by
    ``matrix_to_quat`` itself, so the same verdicts without its per-matrix
    Python work for every scene."""
    with np.errstate(invalid="ignore"):
        w = 0.5 * np.sqrt(np.maximum(1.0 + (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]), 0.0))
    inside, outside = w >= c + 1e-9, w < c - 1e-9
    out = inside.copy()
    unsure = ~(inside | outside)
    if unsure.any():
        out[unsure] = np.abs(matrix_to_quat(R[unsure])[:, 0]) >= c
    return out


_LAZY = ("lowest_z", "depth", "q")


class _LazyDepthRest(RestPose):
    """A :class:`RestPose` whose ``lowest_z``, ``depth`` and ``q`` are
    computed on first read (then kept), with the same expressions as
    before: the body's lowest point (:func:`~bifilar.scene.lowest_point_z`,
    one support-function call a scene) was ~45 % of a batch's cost, the
    quaternion (:func:`~bifilar.rotations.matrix_to_quat` of ``R``: the same
    bits alone as in a batch) ~10 %, and most batched rest poses (the sigma
    points of the honest budget) read neither.  Pickled and copied as the
    plain :class:`RestPose` with those values.  ``scene`` None
    (``dataclasses.replace``): every field must be given."""

    def __init__(self, scene: Scene | None = None, **fields):  # noqa: D107 - RestPose's fields, or all but the lazy two
        d = self.__dict__  # (what object.__setattr__ field by field wrote, in one call)
        d.update(fields)
        d["_scene"] = scene

    def __getattr__(self, name):  # only called for attributes not yet set: the lazy ones
        if name not in _LAZY or "_scene" not in self.__dict__:
            raise AttributeError(name)
        if name == "q":
            object.__setattr__(self, "q", matrix_to_quat(self.R))
            return self.q
        s = self.__dict__["_scene"]
        lz = float(lowest_point_z(s, self.com, self.R))
        object.__setattr__(self, "lowest_z", lz)
        object.__setattr__(self, "depth", s.ceiling_z - lz)
        return self.__dict__[name]

    def __reduce__(self):
        return (_plain_rest, ({f: getattr(self, f) for f in RestPose.__dataclass_fields__},))


class Deferred:
    """A scene :func:`rest_poses` (``defer=True``) left to :func:`rest_pose`:
    :meth:`settle` gives what its entry would have been."""

    def __init__(self, scene: Scene, rigid=None):  # noqa: D107 - rigid: _rest_or_error's
        self.scene, self.rigid = scene, rigid

    def settle(self, errors: str = "raise"):
        """The scene's :func:`rest_pose` (its elastic rest from the rigid pose
        on 2-3 stiff wires), or its error with ``errors="return"``."""
        return _rest_or_error(self.scene, errors, self.rigid)


def _plain_rest(fields: dict) -> RestPose:
    return RestPose(**fields)


def _rest_or_error(scene: Scene, errors: str, rigid=None):
    """:func:`rest_pose` of ``scene``, or its error with ``errors="return"``; ``rigid`` (com, R): the rigid
    rest pose of a scene with ``rig.stiffness`` on 2-3 wires, from which its elastic rest starts."""
    try:
        if rigid is not None:
            from types import SimpleNamespace

            from .elastic_rest import elastic_rest_pose

            return elastic_rest_pose(scene, SimpleNamespace(com=rigid[0], R=rigid[1]))
        return rest_pose(scene)
    except BifilarError as exc:
        if errors != "return":
            raise
        return exc


# --------------------------------------------------------------------------
# linear modes
# --------------------------------------------------------------------------
def modes_batch(scenes: Sequence[Scene], rests: Sequence[RestPose], lazy: bool = False, *,
                geometry: BatchGeometry | None = None) -> list[ModeSet]:
    """:func:`~bifilar.analysis.modes.linear_modes` of many scenes at once
    (same number of wires).  Periods agree with the single-scene function to
    ~1e-12 relative, shapes to ~1e-10 (both solve the same symmetric
    generalised eigenproblem; here by Cholesky and ``numpy.linalg.eigh``).
    ``lazy``: a scene whose eigenvalues are all distinct and positive
    (:func:`~bifilar.analysis.modes.plain_order`) gets a
    :class:`~bifilar.analysis.modes.LazyModeSet`, its periods and shapes
    computed for the batch at once and its :class:`Mode` objects only when
    read (the same mode set, bit for bit); the others as without.
    ``geometry``: the :class:`BatchGeometry` of the :func:`rest_poses` call
    that gave ``rests`` (used where it :meth:`~BatchGeometry.matches`
    them; the same numbers either way)."""
    scenes = list(scenes)
    if not scenes:
        return []
    if _mixed(scenes):
        return _per_group(lambda sc, rs: modes_batch(sc, rs, lazy), scenes, list(rests))
    T = None
    if geometry is not None and geometry.matches(scenes, rests):
        (a, p, L, m, g, I), R, d, w, G, dn = geometry.stacked, geometry.R, geometry.d, geometry.w, geometry.G, geometry.dn
        N, full, T = geometry.N, geometry.full, geometry.T
    else:
        a, p, L, m, g, I = _stack(scenes)
        com = np.array([r.com for r in rests])
        R = np.array([r.R for r in rests])
        d, w, G = _jacobian(a, p, com, R)
        dn = np.linalg.norm(d, axis=2)
        N, full = _null_space(G, m, I, R)
    if G.shape[1] > MAX_ELIMINATION_WIRES:  # elastic wires: linear_modes, whose rank rule knows the stiffness
        full = full & np.array([s.stiffness is None for s in scenes])
    lam = (np.array([r.tensions for r in rests]) if T is None else T) / dn
    M = _mass_matrix(m, I, R)
    Nt = np.swapaxes(N, 1, 2)
    Kr = Nt @ _hessian(d, w, lam) @ N
    Mr = Nt @ M @ N
    Kr = 0.5 * (Kr + np.swapaxes(Kr, 1, 2))
    Mr = 0.5 * (Mr + np.swapaxes(Mr, 1, 2))
    k = N.shape[2]
    if k == 0:
        return [ModeSet([], M[b], N[b]) for b in range(len(scenes))]
    Lc = np.linalg.cholesky(Mr)
    Li = np.linalg.inv(Lc)
    w2, Z = np.linalg.eigh(Li @ Kr @ np.swapaxes(Li, 1, 2))
    Y = np.swapaxes(Li, 1, 2) @ Z
    plain = plain_order(w2, Y, Kr) & full if lazy else np.zeros(len(scenes), bool)
    # mode_set of each full-rank scene, its arithmetic batched where exact (mode_sets: the same mode sets)
    out = mode_sets(N, Y, w2, m, M, Kr, which=np.nonzero(full & ~plain)[0])
    if plain.any():
        out = _lazy_mode_sets(out, np.nonzero(plain)[0], N, Y, w2, m, M, Kr)
    for b in np.nonzero(~full)[0]:
        from .modes import linear_modes

        out[b] = linear_modes(scenes[b], rests[b])
    return out


def _lazy_mode_sets(out: list, bs, N, Y, w2, m, M, Kr) -> list:
    """``out`` with a :class:`LazyModeSet` for each scene ``bs`` (indices) of
    a solved batch (arrays of :func:`modes_batch`): periods (the expression
    of :func:`~bifilar.analysis.modes.mode_sets` on the same eigenvalues)
    and unit shapes (the same scaling) of all of them at once; each one's
    :class:`Mode` objects from :func:`mode_sets` of that scene alone."""
    S, _ = unit_shapes(N[bs] @ Y[bs])  # (the stacked product: each scene's N @ Y, the same bits)
    periods = 2 * np.pi / np.sqrt(w2[bs])
    for q, b in enumerate(bs.tolist()):
        sl = slice(b, b + 1)
        out[b] = LazyModeSet(lambda sl=sl: mode_sets(N[sl], Y[sl], w2[sl], m[sl], M[sl], Kr[sl])[0],
                             periods[q], S[q].T, M[b], N[b])
    return out


def rest_and_modes(scenes: Sequence[Scene], guess=None, *, errors: str = "raise"):
    """(rests, modesets) of many scenes; failed scenes (``errors="return"``)
    have the exception as rest and None as modes."""
    geo: list = []
    rests = rest_poses(scenes, guess, errors=errors, geometry=geo)
    good = [k for k, r in enumerate(rests) if isinstance(r, RestPose)]
    ms: list = [None] * len(rests)
    for k, x in zip(good, modes_batch([scenes[k] for k in good], [rests[k] for k in good],
                                      geometry=geo[0] if geo else None)):
        ms[k] = x
    return rests, ms
