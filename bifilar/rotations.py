"""Rotation utilities, vectorised over leading axes.

Quaternions are scalar-first ``[w, x, y, z]`` unit quaternions mapping
body components to world components.  Rotation vectors are in radians.
"""

from __future__ import annotations

import math

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix: ``skew(a) @ b == cross(a, b)``; ``v`` shape (..., 3)."""
    return skew_of(np.asarray(v, dtype=float))


def skew_of(v: np.ndarray) -> np.ndarray:
    """:func:`skew` of ``v`` (..., 3) in its own dtype (complex-safe), written
    entry by entry (the values of nested stacks: +0.0 on the diagonal)."""
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    out = np.zeros(v.shape + (3,), np.result_type(v, 0.0))
    out[..., 0, 1] = -w
    out[..., 0, 2] = y
    out[..., 1, 0] = w
    out[..., 1, 2] = -x
    out[..., 2, 0] = -y
    out[..., 2, 1] = x
    return out


def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cross product ``u x v`` over the last axis (..., 3): ``np.cross``'s
    products and differences in its order (the same values, complex-safe),
    written into one array without its axis handling (several times faster
    on small batches)."""
    ux, uy, uz = u[..., 0], u[..., 1], u[..., 2]
    vx, vy, vz = v[..., 0], v[..., 1], v[..., 2]
    out = np.empty(np.broadcast_shapes(u.shape, v.shape), np.result_type(u, v))
    out[..., 0] = uy * vz - uz * vy
    out[..., 1] = uz * vx - ux * vz
    out[..., 2] = ux * vy - uy * vx
    return out


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (..., 3, 3) of quaternion(s) ``q`` (..., 4); q need not be unit."""
    q = np.asarray(q, dtype=float)
    if q.size <= 4 * _FEW:
        m = _quat_to_matrix_few(q)
        if m is not None:
            return m
    if q.size <= 4 * _STACKED:
        return _quat_to_matrix_stacked(q)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(q.shape[:-1] + (3, 3))  # filled entry by entry: the numpy calls of nested stacks cost more
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)  # than the arithmetic on the few rotations of a start-pose solve
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


#: up to this many quaternions :func:`quat_to_matrix` works on Python floats (a start-pose solve's 2-3)
_FEW = 8


#: up to this many quaternions (above :data:`_FEW`) :func:`quat_to_matrix` takes the entries' products from one
#: outer product (:func:`_quat_to_matrix_stacked`); beyond it the entry-by-entry path is faster
_STACKED = 256

# the nine entries as 1 - 2 (a + b) (diagonal) or 2 (a + s b), a and b products q_i q_j (flat index 4 i + j of
# the outer product, in the operand order of the entry-by-entry path), s = -1 where that path subtracts
_ENTRY_A = np.array([10, 6, 7, 6, 5, 11, 7, 11, 5])
_ENTRY_B = np.array([15, 3, 2, 3, 15, 1, 2, 1, 10])
_ENTRY_SIGN = np.array([1.0, -1.0, 1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0])
_ENTRY_DIAGONAL = np.array([True, False, False, False, True, False, False, False, True])


def _quat_to_matrix_stacked(q: np.ndarray) -> np.ndarray:
    """:func:`quat_to_matrix` of ``q`` (..., 4) in ~10 numpy calls instead of
    ~50: the products q_i q_j from one outer product (x y and y x are the
    same double), each entry's sum as ``a + s b`` (``a + (-b)`` is ``a -
    b`` in IEEE arithmetic, signed zeros, inf and NaN included), then ``2
    S`` or ``1 - 2 S``: the entry-by-entry path's operations on the same
    doubles, so the same bits (tests/test_perf26a.py).  Faster from ~9
    quaternions (a start-pose solve's 9-row batches: 23 -> 12 us) up to
    ~300 (docs/performance.md, "Session 26, perf26a")."""
    q = q / np.sqrt(np.add.reduce(q * q, axis=-1, keepdims=True))  # np.linalg.norm's operations
    P = (q[..., :, None] * q[..., None, :]).reshape(q.shape[:-1] + (16,))
    S2 = 2 * (P[..., _ENTRY_A] + _ENTRY_SIGN * P[..., _ENTRY_B])
    return np.where(_ENTRY_DIAGONAL, 1 - S2, S2).reshape(q.shape[:-1] + (3, 3))


def _quat_to_matrix_few(q: np.ndarray):
    """:func:`quat_to_matrix` of a few quaternions on Python floats: the same
    IEEE operations in the same order as the numpy path (the norm's sum of
    squares left to right, as ``add.reduce`` sums four terms; then the
    entries' expressions), without a numpy call per entry; None (the numpy
    path) where a norm is zero or not finite, for numpy's NaN and inf."""
    rows = []
    for w, x, y, z in q.reshape(-1, 4).tolist():
        n = math.sqrt(w * w + x * x + y * y + z * z)
        if not 0.0 < n < math.inf:
            return None
        w, x, y, z = w / n, x / n, y / n, z / n
        rows.append([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return np.array(rows, float).reshape(q.shape[:-1] + (3, 3))


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (..., 4), w >= 0, of rotation matrix/matrices ``R`` (..., 3, 3)."""
    R = np.asarray(R, dtype=float)
    flat = R.reshape(-1, 3, 3)
    out = np.empty((flat.shape[0], 4))
    for k, rows in enumerate(flat.tolist()):
        out[k] = _shepperd(rows)
    out /= np.linalg.norm(out, axis=-1, keepdims=True)
    return out.reshape(R.shape[:-2] + (4,))


def _shepperd(rows: list):
    """Shepperd's method for one matrix (nested lists): its quaternion before
    the final normalisation, w >= 0.  On Python floats, with the IEEE
    operations the numpy scalars made (``np.trace``'s order, ``np.argmax``'s
    first largest, sqrt correctly rounded either way) but without a numpy
    call per entry; a matrix that is no rotation (a NaN, a negative root, a
    zero divisor) goes through numpy scalars as before, for their NaN and inf."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = rows
    tr = m00 + m11 + m22
    d = (tr, m00, m11, m22)
    i = max(range(4), key=lambda j: (d[j], -j))
    r = (1.0 + tr, 1.0 + m00 - m11 - m22, 1.0 + m11 - m00 - m22, 1.0 + m22 - m00 - m11)[i]
    if not r > 0 or any(v != v for v in d):
        return _shepperd_numpy(np.array(rows, float))
    s = 2.0 * math.sqrt(r)
    if i == 0:
        q = [0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s]
    elif i == 1:
        q = [(m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s]
    elif i == 2:
        q = [(m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s]
    else:
        q = [(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s]
    return q if q[0] >= 0 or q[0] != q[0] else [-c for c in q]  # q * np.sign(q[0]) where q[0] < 0


def _shepperd_numpy(m: np.ndarray) -> np.ndarray:
    """:func:`_shepperd` on numpy scalars (the path before, for any matrix)."""
    tr = np.trace(m)
    i = int(np.argmax([tr, m[0, 0], m[1, 1], m[2, 2]]))
    if i == 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif i == 1:
        s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif i == 2:
        s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    return q * np.sign(q[0]) if q[0] != 0 else q


def quat_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p * q`` (..., 4)."""
    pw, px, py, pz = np.moveaxis(np.asarray(p, float), -1, 0)
    qw, qx, qy, qz = np.moveaxis(np.asarray(q, float), -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def rotvec_to_quat(v: np.ndarray) -> np.ndarray:
    """Unit quaternion of rotation vector(s) ``v`` (..., 3), radians."""
    v = np.asarray(v, dtype=float)
    ang = np.sqrt(np.add.reduce(v * v, axis=-1, keepdims=True))  # np.linalg.norm(v, axis=-1, ...)'s operations
    half = 0.5 * ang
    # sin(half)/ang with a series for tiny angles (the series' branch only where one is tiny: the same values)
    small = ang < 1e-8
    if small.any():
        k = np.where(small, 0.5 - ang**2 / 48.0, np.sin(half) / np.where(small, 1.0, ang))
    else:
        k = np.sin(half) / ang
    return np.concatenate([np.cos(half), k * v], axis=-1)


def rotvec_to_matrix(v: np.ndarray) -> np.ndarray:
    """Rotation matrix exp(skew(v)) (..., 3, 3) of rotation vector(s) ``v`` (radians)."""
    return quat_to_matrix(rotvec_to_quat(v))


def quat_to_rotvec(q: np.ndarray) -> np.ndarray:
    """Rotation vector (..., 3), radians, |v| <= pi, of quaternion(s) ``q``."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    q = q * np.where(q[..., :1] < 0, -1.0, 1.0)
    w = q[..., :1]
    xyz = q[..., 1:]
    s = np.linalg.norm(xyz, axis=-1, keepdims=True)
    ang = 2.0 * np.arctan2(s, w)
    small = s < 1e-12
    k = np.where(small, 2.0 / np.where(small, w, 1.0), ang / np.where(small, 1.0, s))
    return k * xyz


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Rotation vector (..., 3), radians, of rotation matrix/matrices ``R``."""
    return quat_to_rotvec(matrix_to_quat(R))
