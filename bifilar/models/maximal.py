"""The default dynamics model: maximal coordinates, wire tensions as multipliers.

State of one body, 13 numbers (SI units, world frame z up)::

    y = [r (3), q (4), v (3), w (3)]

``r`` CoM position (m), ``q`` scalar-first unit quaternion body -> world,
``v`` CoM velocity (m/s), ``w`` angular velocity in BODY axes (rad/s).

Each wire i joins the ceiling anchor ``a_i`` to the body point ``p_i`` and
imposes the holonomic constraint ``phi_i = (|d_i|^2 - L_i^2) / 2 = 0`` with
``d_i = r + R p_i - a_i``.  Newton-Euler with multipliers ``lam``::

    m dv/dt       = -m g e_z + sum_i lam_i d_i
    I dw/dt       = -w x I w + sum_i lam_i (p_i x R^T d_i)
    J(du/dt)      = -|ds_i/dt|^2 - (R^T d_i).(w x (w x p_i)) - 2 a dphi/dt - b^2 phi

(index-1 form with Baumgarte stabilisation ``a``, ``b``, which vanishes on the
constraint manifold).  The wire tension is ``T_i = -lam_i |d_i|`` (N, positive
when the wire pulls).  No angle is used anywhere, so no pose a rig reaches is
singular: the constraint Jacobian loses rank only if wires become parallel
*and* attach at the same point, which the config checks reject.

Every function is vectorised: ``y`` may have any leading shape ``(..., 13)``
that broadcasts against the leading shape of the :class:`RigParams` arrays
(one set of parameters per scene of a batch).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..rotations import quat_to_matrix
from ..scene import Scene

NSTATE = 13


@dataclass(frozen=True)
class RigParams:
    """Arrays of scene parameters with a leading batch shape ``S`` (SI units).

    mass (S), gravity (S), inertia (S, 3, 3) and inertia_inv (S, 3, 3) in body
    axes, anchors (S, n, 3) world, attachments (S, n, 3) body, lengths (S, n),
    baumgarte (S, 2) = (alpha, beta) in 1/s.
    """

    mass: np.ndarray
    gravity: np.ndarray
    inertia: np.ndarray
    inertia_inv: np.ndarray
    anchors: np.ndarray
    attachments: np.ndarray
    lengths: np.ndarray
    baumgarte: np.ndarray

    @property
    def batch_shape(self) -> tuple:
        return self.mass.shape

    def take(self, idx) -> "RigParams":
        return RigParams(**{k: getattr(self, k)[idx] for k in self.__dataclass_fields__})


def params_from_scenes(scenes: Scene | Sequence[Scene], baumgarte: float | None = None) -> RigParams:
    """Stack scenes (all with the same number of wires) into :class:`RigParams`.

    A single scene gives a batch shape ``()``.  ``baumgarte`` is the
    stabilisation rate in 1/s; default ``sqrt(g / L_min)``, the pendulum
    frequency scale, so the constraint error decays within about one swing
    without making the equations stiff.
    """
    single = isinstance(scenes, Scene)
    sc = [scenes] if single else list(scenes)
    nw = {s.n_wires for s in sc}
    if len(nw) != 1:
        raise ValueError("a batch needs scenes with the same number of wires")
    I = np.array([s.inertia for s in sc])
    g = np.array([s.gravity for s in sc])
    L = np.array([s.lengths for s in sc])
    rate = np.sqrt(g / L.min(axis=1)) if baumgarte is None else np.full(len(sc), float(baumgarte))
    P = RigParams(
        mass=np.array([s.mass for s in sc]),
        gravity=g,
        inertia=I,
        inertia_inv=np.linalg.inv(I),
        anchors=np.array([s.anchors for s in sc]),
        attachments=np.array([s.attachments for s in sc]),
        lengths=L,
        baumgarte=np.stack([rate, rate], axis=-1),
    )
    return P.take(0) if single else P


def unpack(y: np.ndarray):
    y = np.asarray(y, dtype=float)
    return y[..., 0:3], y[..., 3:7], y[..., 7:10], y[..., 10:13]


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix-vector product (..., i, j) @ (..., j) -> (..., i)."""
    return np.matmul(A, x[..., None])[..., 0]


def kinematics(y: np.ndarray, P: RigParams) -> dict:
    """Pose-derived quantities (world frame unless named ``_b``), vectorised.

    Returns a dict with R (...,3,3), Rp (...,n,3) attachment offsets in world
    axes, d (...,n,3) wire vectors anchor->attachment, d_b (...,n,3) the same
    in body axes, sdot (...,n,3) attachment velocities, phi (...,n),
    phidot (...,n).
    """
    r, q, v, w = unpack(y)
    R = quat_to_matrix(q)
    p = P.attachments
    Rp = np.matmul(R[..., None, :, :], p[..., :, :, None])[..., 0]
    d = r[..., None, :] + Rp - P.anchors
    d_b = np.matmul(np.swapaxes(R, -1, -2)[..., None, :, :], d[..., :, :, None])[..., 0]
    w_w = _mv(R, w)
    sdot = v[..., None, :] + np.cross(w_w[..., None, :], Rp)
    phi = 0.5 * (np.einsum("...k,...k->...", d, d) - P.lengths**2)
    phidot = np.einsum("...k,...k->...", d, sdot)
    return {"R": R, "Rp": Rp, "d": d, "d_b": d_b, "w_w": w_w, "sdot": sdot, "phi": phi, "phidot": phidot}


def solve_dynamics(y: np.ndarray, P: RigParams, stabilise: bool = True):
    """Accelerations and multipliers at state(s) ``y``.

    Returns
    -------
    vdot : (..., 3) CoM acceleration, m/s^2, world.
    wdot : (..., 3) angular acceleration, rad/s^2, body axes.
    lam : (..., n) multipliers (N/m); tensions are ``-lam * |d|``.
    kin : dict from :func:`kinematics`.
    """
    r, q, v, w = unpack(y)
    kin = kinematics(y, P)
    d, d_b = kin["d"], kin["d_b"]
    p = P.attachments
    m = P.mass[..., None]
    Iw = _mv(P.inertia, w)
    tau = -np.cross(w, Iw)  # gyroscopic torque, body axes
    Jw = np.cross(p, d_b)  # (..., n, 3) rotational part of the constraint Jacobian
    IinvJw = np.matmul(P.inertia_inv[..., None, :, :], Jw[..., :, :, None])[..., 0]
    A = np.matmul(d, np.swapaxes(d, -1, -2)) / P.mass[..., None, None] + np.matmul(Jw, np.swapaxes(IinvJw, -1, -2))
    Iinv_tau = _mv(P.inertia_inv, tau)
    wxp = np.cross(w[..., None, :], p)
    centripetal = np.einsum("...k,...k->...", d_b, np.cross(w[..., None, :], wxp))
    rhs = (
        -np.einsum("...k,...k->...", kin["sdot"], kin["sdot"])
        - centripetal
        + P.gravity[..., None] * d[..., 2]
        - np.einsum("...nk,...k->...n", Jw, Iinv_tau)
    )
    if stabilise:
        a = P.baumgarte[..., 0:1]
        b = P.baumgarte[..., 1:2]
        rhs = rhs - 2.0 * a * kin["phidot"] - b * b * kin["phi"]
    lam = np.linalg.solve(A, rhs[..., None])[..., 0]
    vdot = np.einsum("...n,...nk->...k", lam, d) / m
    vdot = vdot - np.stack([np.zeros_like(P.gravity), np.zeros_like(P.gravity), P.gravity], axis=-1)
    wdot = Iinv_tau + np.einsum("...n,...nk->...k", lam, IinvJw)
    return vdot, wdot, lam, kin


def quat_rate(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """dq/dt = q * (0, w) / 2 for body-axes angular velocity ``w``, with a
    gentle pull back to |q| = 1 (rate 1/s) that vanishes on unit quaternions."""
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    wx, wy, wz = np.moveaxis(w, -1, 0)
    dq = 0.5 * np.stack(
        [
            -qx * wx - qy * wy - qz * wz,
            qw * wx + qy * wz - qz * wy,
            qw * wy - qx * wz + qz * wx,
            qw * wz + qx * wy - qy * wx,
        ],
        axis=-1,
    )
    return dq + (1.0 - np.einsum("...k,...k->...", q, q))[..., None] * q


def rhs(t: float, y: np.ndarray, P: RigParams, stabilise: bool = True) -> np.ndarray:
    """Time derivative of the state(s) ``y`` (..., 13)."""
    r, q, v, w = unpack(y)
    vdot, wdot, _, _ = solve_dynamics(y, P, stabilise)
    return np.concatenate([v, quat_rate(q, w), vdot, wdot], axis=-1)


def make_flat_rhs(P: RigParams, stabilise: bool = True):
    """``f(t, yflat)`` for :func:`scipy.integrate.solve_ivp` over a whole batch.

    The batch of B scenes is one ODE of size 13 B; every scene shares the
    step sequence (fine for sweeps of similar scenes, and the cheapest way
    to vectorise in numpy).
    """
    shape = P.batch_shape + (NSTATE,)

    def f(t: float, yflat: np.ndarray) -> np.ndarray:
        return rhs(t, yflat.reshape(shape), P, stabilise).reshape(-1)

    return f


def tensions(y: np.ndarray, P: RigParams) -> np.ndarray:
    """Wire tensions (..., n), N; positive = pulling.  Uses the unstabilised
    multipliers so that the value is the physical one on the manifold."""
    _, _, lam, kin = solve_dynamics(y, P, stabilise=False)
    return -lam * np.linalg.norm(kin["d"], axis=-1)


def energy(y: np.ndarray, P: RigParams) -> np.ndarray:
    """Total mechanical energy (...), J: kinetic + m g z_com."""
    r, q, v, w = unpack(y)
    ke = 0.5 * P.mass * np.einsum("...k,...k->...", v, v) + 0.5 * np.einsum("...k,...k->...", w, _mv(P.inertia, w))
    return ke + P.mass * P.gravity * r[..., 2]


def constraint_violation(y: np.ndarray, P: RigParams) -> np.ndarray:
    """| |d_i| - L_i | per wire (..., n), m."""
    kin = kinematics(y, P)
    return np.abs(np.linalg.norm(kin["d"], axis=-1) - P.lengths)


def pack(r, q, v=None, w=None) -> np.ndarray:
    r = np.asarray(r, float)
    q = np.asarray(q, float)
    v = np.zeros_like(r) if v is None else np.asarray(v, float)
    w = np.zeros_like(r) if w is None else np.asarray(w, float)
    return np.concatenate([r, q, v, w], axis=-1)
