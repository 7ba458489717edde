"""Parameter values of the compiled right-hand side (:mod:`bifilar.models.maximal`).

The kernel's named parameters (mass, gravity, Baumgarte gains, inertia,
its inverse and mass x inverse, Euler coefficients, anchors and
attachments, squared lengths and their differences), all SI (kg, m/s^2,
kg m^2, m, m^2), anchors in world axes and attachments in body axes, for
one scene (Python floats) or a batch (arrays with the batch shape), with
rounding-level products of inertia and wire coordinates taken as exact
zeros so that the kernel drops their terms.  Split from ``maximal.py``
(session 21) when it passed 800 lines.
"""
from __future__ import annotations

import numpy as np

_AX = "xyz"


def param_values(P: "RigParams") -> dict:
    """Parameter name -> value (float for a single scene, else array of the batch shape).

    ``I..``/``N..`` the inertia and its inverse (body axes), ``M..`` = mass x
    the inverse inertia (the kernel solves for the multipliers divided by the
    mass, see :func:`_kernel_source`), ``E.`` Euler's coefficients
    ``(I_yy - I_zz) / I_xx``, ... (principal body axes), ``bga`` = 2 alpha, ``hb`` = beta^2 / 2
    and ``hbL<i>`` = beta^2 L_i^2 / 2 (the Baumgarte terms folded into
    ``bga phidot + hb |d|^2 - hbL``), ``L2<i>`` = L_i^2, ``Da.<i>`` = a_0 -
    a_i (world) and ``Dp.<i>`` = p_i - p_0 (body), for wire i's vector in
    body axes from wire 0's.
    Products of inertia and wire coordinates at rounding level
    (:func:`_denoised`) are taken as exact zeros, so the kernel drops their
    terms (the KTH trifilar's inertia summed from rotated beams carries
    products of ~1e-17 of its moments: with them its kernel took the
    general-axes path, ~25 % more operations a call).
    """
    if P.mass.ndim == 0:
        return _one_scene_values(P)
    mats, pos = _denoised(P)
    n = P.lengths.shape[-1]
    bgb = P.baumgarte[..., 1] ** 2
    L2 = P.lengths ** 2
    d = mats[..., 0, _DIAG, _DIAG]  # the inertia's diagonal
    anchors, attachments = pos[..., :n, :], pos[..., n:, :]
    # blocks of (names, values along the last axis): a few array operations, each value the same
    # elementwise expression as written out per name (one numpy call per value cost ~90 us a scene)
    blocks = [(("mass", "g", "bga", "hb"), np.stack([P.mass, P.gravity, 2.0 * P.baumgarte[..., 0], 0.5 * bgb], axis=-1)),
              ([pre + k for pre in "INM" for k in _SYM_NAMES],
               (0.5 * (mats[..., _SYM_I, _SYM_J] + mats[..., _SYM_J, _SYM_I])).reshape(mats.shape[:-3] + (18,))),
              (["E" + a for a in _AX], (d[..., [1, 2, 0]] - d[..., [2, 0, 1]]) / d),  # (I_yy - I_zz) / I_xx, ...
              ([f"{c}{a}{i}" for i in range(n) for c in "ap" for a in _AX],
               np.stack([anchors, attachments], axis=-2).reshape(P.lengths.shape[:-1] + (6 * n,))),
              ([f"{c}{i}" for i in range(n) for c in ("L2", "hbL")],
               np.stack([L2, (0.5 * bgb)[..., None] * L2], axis=-1).reshape(L2.shape[:-1] + (2 * n,)))]
    if n > 1:
        blocks.append(([f"D{c}{a}{i}" for i in range(1, n) for c in "ap" for a in _AX],
                       np.stack([anchors[..., :1, :] - anchors[..., 1:, :], attachments[..., 1:, :] - attachments[..., :1, :]],
                                axis=-2).reshape(P.lengths.shape[:-1] + (6 * (n - 1),))))
    vals: dict = {}
    for names, arr in blocks:
        vals.update((nm, np.ascontiguousarray(arr[..., k])) for k, nm in enumerate(names))
    return vals


def _one_scene_values(P: "RigParams") -> dict:
    """:func:`_param_values` of one scene (batch shape ()), on Python
    floats: the same IEEE operations on the same doubles as the batch code
    (``x ** 2`` of an array is ``x * x``), so the same values, for ~0.2 us
    of ``tolist`` instead of a numpy call (~5 us) per operation."""
    alpha, beta = P.baumgarte.tolist()
    bgb = beta * beta
    m = float(P.mass)
    mats = [_clean_matrix(A) for A in (P.inertia.tolist(), P.inertia_inv.tolist(),
                                       (np.asarray(P.mass)[..., None, None] * P.inertia_inv).tolist())]
    anc, att, L = P.anchors.tolist(), P.attachments.tolist(), P.lengths.tolist()
    tol = ROUNDING_NOISE * max(max(abs(x) for row in anc + att for x in row), max(L))
    anc, att = ([[0.0 if abs(x) <= tol else x for x in row] for row in rows] for rows in (anc, att))
    vals = {"mass": m, "g": float(P.gravity), "bga": 2.0 * alpha, "hb": 0.5 * bgb}
    for pre, A in zip("INM", mats):
        for k, i, j in zip(_SYM_NAMES, _SYM_I, _SYM_J):
            vals[pre + k] = 0.5 * (A[i][j] + A[j][i])
    d = [mats[0][k][k] for k in range(3)]
    for k in range(3):
        vals["E" + _AX[k]] = (d[(k + 1) % 3] - d[(k + 2) % 3]) / d[k]
    for i, Li in enumerate(L):
        for k, a in enumerate(_AX):
            vals[f"a{a}{i}"] = anc[i][k]
            vals[f"p{a}{i}"] = att[i][k]
        vals[f"L2{i}"] = Li * Li
        vals[f"hbL{i}"] = (0.5 * bgb) * (Li * Li)
        if i > 0:
            for k, a in enumerate(_AX):
                vals[f"Da{a}{i}"] = anc[0][k] - anc[i][k]
                vals[f"Dp{a}{i}"] = att[i][k] - att[0][k]
    return vals


def _clean_matrix(A: list) -> list:
    """A 3 x 3 matrix (nested lists) with the off-diagonal entries at
    rounding level of its largest diagonal entry set to zero (:func:`_denoised`
    on one scene)."""
    tol = ROUNDING_NOISE * max(abs(A[k][k]) for k in range(3))
    return [[x if i == j or not abs(x) <= tol else 0.0 for j, x in enumerate(row)] for i, row in enumerate(A)]


_DIAG = [0, 1, 2]
_SYM_NAMES = ("xx", "yy", "zz", "xy", "xz", "yz")
_SYM_I = [0, 1, 2, 0, 0, 1]
_SYM_J = [0, 1, 2, 1, 2, 2]


ROUNDING_NOISE = 16 * np.finfo(float).eps
"""Relative size below which :func:`_denoised` takes a product of inertia
(of its matrix's largest diagonal entry) or a wire coordinate (of the rig's
largest anchor, attachment or length) for rounding noise: 3.6e-15, ~100x
above the noise the shipped configs carry (the KTH trifilar's 1e-19 ..
3e-17) and far below any stated figure (a product of inertia known to
1e-15 of the moments)."""


def _denoised(P: "RigParams"):
    """(mats, pos) of ``P`` (SI, the batch shape kept): ``mats`` (..., 3,
    3, 3) the inertia, its inverse and mass x the inverse, ``pos`` (...,
    2n, 3) the anchors then the attachments, with rounding-level entries set to
    exact zeros (:data:`ROUNDING_NOISE`): the off-diagonal entries of each
    matrix relative to its largest diagonal entry, the wire coordinates
    relative to the rig's largest coordinate or length.  Dropping them moves
    the right-hand side by ~1e-16 of its terms; each scene of a batch is
    cleaned alone (the same values as in a kernel of its own)."""
    mats = np.stack([P.inertia, P.inertia_inv, np.asarray(P.mass)[..., None, None] * P.inertia_inv], axis=-3)
    A = np.abs(mats)
    diag = np.max(np.diagonal(A, axis1=-2, axis2=-1), axis=-1)[..., None, None]
    mats = np.where((A <= ROUNDING_NOISE * diag) & _OFF_DIAGONAL, 0.0, mats)
    pos = np.concatenate([P.anchors, P.attachments], axis=-2)
    A = np.abs(pos)
    span = np.maximum(np.max(A, axis=(-2, -1)), np.max(P.lengths, axis=-1))[..., None, None]
    pos = np.where(A <= ROUNDING_NOISE * span, 0.0, pos)
    return mats, pos


_OFF_DIAGONAL = ~np.eye(3, dtype=bool)
