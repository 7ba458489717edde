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
singular.  With four or five taut wires the constraints can be dependent (a
symmetric rig: J has rank 3); the multipliers are then the minimum-norm ones
(:func:`_min_norm`), which give the same accelerations as any other
solution (docs/design.md).

Every function is vectorised: ``y`` may have any leading shape ``(..., 13)``
that broadcasts against the leading shape of the :class:`RigParams` arrays
(one set of parameters per scene of a batch).

Speed: :func:`rhs`, :func:`solve_dynamics`, :func:`tensions` and
:func:`make_flat_rhs` run a *compiled kernel* (:func:`compiled_kernel`): the
equations above written out component by component as straight-line Python,
generated once per wire count and pattern of zero parameters, which runs on
Python floats for one state (~2.5 us a call for two wires against ~260 us
for the array code it replaced; ``signature="odeint"`` is odeint's own
``f(y, t)``, no wrapper) and on arrays for a batch (one numpy operation per
term).
:func:`kinematics`, :func:`energy` and :func:`constraint_violation` stay
array code (not in the hot loop).
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..rotations import quat_to_matrix
from ..scene import Scene
from .dependent_wires import (MIN_NORM_RCOND, _filtered_inverse, _min_norm,  # noqa: F401 (the kernel's and callers' names)
                              held_directions, min_norm_multipliers)
from .kernel_values import param_values as _param_values  # the name tests count and monkeypatch

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


def _components(y: np.ndarray):
    """State components for the compiled kernel: Python floats for one state
    (13,), else arrays of the leading shape."""
    y = np.asarray(y, dtype=float)
    if y.ndim == 1:
        return y.tolist()
    # contiguous rows: the kernel's elementwise operations on strided columns of a
    # (k, 13) record cost ~40 % more than the copy
    return list(np.ascontiguousarray(np.moveaxis(y, -1, 0)))


def _stack(parts, lead_shape) -> np.ndarray:
    """Stack kernel outputs (floats or arrays) along a new last axis."""
    if not lead_shape and all(isinstance(p, float) for p in parts):
        return np.array(parts)
    return np.stack(np.broadcast_arrays(*parts), axis=-1)


def solve_dynamics(y: np.ndarray, P: RigParams, stabilise: bool = True):
    """Accelerations and multipliers at state(s) ``y``.

    Returns
    -------
    vdot : (..., 3) CoM acceleration, m/s^2, world.
    wdot : (..., 3) angular acceleration, rad/s^2, body axes.
    lam : (..., n) multipliers (N/m); tensions are ``-lam * |d|``.
    kin : dict from :func:`kinematics`.
    """
    y = np.asarray(y, dtype=float)
    out = compiled_kernel(P, stabilise, extras=True)(*_components(y))
    n = int(P.lengths.shape[-1])
    lead = np.broadcast_shapes(y.shape[:-1], P.batch_shape)
    vdot = _stack(out[7:10], lead)
    wdot = _stack(out[10:13], lead)
    lam = _stack(out[13:13 + n], lead)
    return vdot, wdot, lam, kinematics(y, P)


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
    """Time derivative (..., 13) of the state(s) ``y`` (..., 13) (SI units,
    layout of the state); ``t`` (s) is unused (autonomous system)."""
    y = np.asarray(y, dtype=float)
    out = compiled_kernel(P, stabilise)(*_components(y))
    return _stack(out, np.broadcast_shapes(y.shape[:-1], P.batch_shape))


def make_flat_rhs(P: RigParams, stabilise: bool = True):
    """``f(t, yflat)`` for :func:`scipy.integrate.solve_ivp` over a whole batch.

    The batch of B scenes is one ODE of size 13 B; every scene shares the
    step sequence (fine for sweeps of similar scenes, and the cheapest way
    to vectorise in numpy).  For a single scene (batch shape ``()``) the
    compiled kernel runs on Python floats.
    """
    k = compiled_kernel(P, stabilise)
    if P.batch_shape == ():
        array = np.array

        def f1(t: float, yflat: np.ndarray) -> np.ndarray:
            return array(k(*yflat.tolist()))

        return f1
    shape = P.batch_shape + (NSTATE,)

    def f(t: float, yflat: np.ndarray) -> np.ndarray:
        Y = yflat.reshape(shape)
        out = k(*np.moveaxis(Y, -1, 0))
        return np.stack(np.broadcast_arrays(*out), axis=-1).reshape(-1)

    return f


CACHE_CHUNK = 4096
"""States a kernel call takes at once from a long record of one scene
(:func:`chunked`): the kernel's ~300 temporaries then stay in the
processor's cache (a 13 000-sample record in one call costs ~2x more)."""


def chunked(kernel, size: int = CACHE_CHUNK, first: int = 0):
    """``kernel`` (a :func:`compiled_kernel` of one scene's parameters) applied
    to 1-D arrays of states (a record) ``size`` states at a time, its outputs
    gathered into arrays of the record's length: the same values, faster for
    long records.  Outputs before ``first`` are not gathered (None: e.g.
    ``first=13`` keeps only the extras, what the tensions and health read).
    Other arguments (floats, batches of shape (k, B)) and records of at most
    ``size`` states go through unchanged (every output)."""

    def f(*comps):
        if np.ndim(comps[0]) != 1 or len(comps[0]) <= size:
            return kernel(*comps)
        K = len(comps[0])
        res: list = []
        for k in range(0, K, size):
            part = kernel(*(c[k:k + size] for c in comps))
            if not res:
                res = [None] * first + [np.empty(K) for _ in range(len(part) - first)]
            for i in range(first, len(part)):
                res[i][k:k + size] = part[i]  # (a constant output fills its rows)
        return tuple(res)

    return f


def tensions(y: np.ndarray, P: RigParams) -> np.ndarray:
    """Wire tensions (..., n), N; positive = pulling.  Uses the unstabilised
    multipliers so that the value is the physical one on the manifold."""
    y = np.asarray(y, dtype=float)
    n = int(P.lengths.shape[-1])
    k = compiled_kernel(P, False, extras=True)
    out = (chunked(k, first=13) if P.batch_shape == () else k)(*_components(y))  # chunks of one scene's states only
    lead = np.broadcast_shapes(y.shape[:-1], P.batch_shape)
    lam = _stack(out[13:13 + n], lead)
    phi = _stack(out[13 + n:13 + 2 * n], lead)
    return -lam * np.sqrt(P.lengths**2 + 2.0 * phi)


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


# --------------------------------------------------------------------------
# Compiled right-hand side
# --------------------------------------------------------------------------
# The equations above, written out component by component as straight-line
# Python (one source per wire count and pattern of identically zero
# parameters, generated once and cached).  Every operation is elementwise, so
# the same function runs on Python floats (one scene: no numpy call overhead,
# ~10x faster than array code on 3-vectors) and on numpy arrays of any
# broadcastable shape (a batch: one vectorised operation per term).  The n x n
# multiplier system is solved by unpivoted symmetric elimination, which is
# exact for its symmetric positive definite matrix J M^-1 J^T, for up to three
# wires; four or five wires may be dependent (J M^-1 J^T singular) and go
# through the pseudo-inverse of _min_norm (an evaluation costs ~5-10x more).

_STATE_NAMES = ("rx", "ry", "rz", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")
_AX = "xyz"
_FACTORY_CACHE: dict = {}


class _Code:
    """Straight-line code builder that drops products with a factor known to be zero."""

    def __init__(self, zero: set[str]):
        self.zero = set(zero)
        self.lines: list[str] = []

    def expr(self, terms) -> str | None:
        """``terms``: iterable of (sign, factor, ...); None when every term vanishes.
        The first surviving positive term leads (a leading minus would cost a
        negation)."""
        live = [(sign, fac) for sign, *fac in terms if not any(f in self.zero for f in fac)]
        live.sort(key=lambda sf: sf[0] < 0)  # stable: positive terms first, each group in its order
        out = ""
        for sign, fac in live:
            p = "*".join(fac)
            out += ("-" if sign < 0 else "") + p if not out else (" - " if sign < 0 else " + ") + p
        return out or None

    def ops(self, terms) -> int:
        """Arithmetic operations of the expression of ``terms``."""
        live = [fac for sign, *fac in terms if not any(f in self.zero for f in fac)]
        return sum(len(fac) - 1 for fac in live) + max(len(live) - 1, 0)

    def let(self, name: str, terms) -> str:
        e = self.expr(terms)
        if e is None:
            self.zero.add(name)
        else:
            self.lines.append(f"{name} = {e}")
        return name

    def v(self, name: str) -> str:
        return "0.0" if name in self.zero else name


def _param_names(n: int) -> list[str]:
    names = ["mass", "g", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "Nxx", "Nyy", "Nzz", "Nxy", "Nxz", "Nyz",
             "Mxx", "Myy", "Mzz", "Mxy", "Mxz", "Myz", "Ex", "Ey", "Ez", "bga", "hb"]
    for i in range(n):
        names += [f"ax{i}", f"ay{i}", f"az{i}", f"px{i}", f"py{i}", f"pz{i}", f"L2{i}", f"hbL{i}"]
        if i > 0:
            names += [f"Da{a}{i}" for a in _AX] + [f"Dp{a}{i}" for a in _AX]
    return names


_NEVER_ZERO = ("mass", "bga", "hb")
"""Parameters the kernel never drops as zero (a zero would be a degenerate
scene anyway), besides the per-wire ``L2``/``hbL`` (the Baumgarte terms are
written only when ``stabilise``)."""




SIGNATURES = ("args", "odeint")
"""Call signatures of a compiled kernel: ``"args"`` ``f(rx, ..., wz)`` (13
floats or arrays) returning a tuple; ``"odeint"`` ``f(y, t)`` for
:func:`scipy.integrate.odeint` on one scene (``y`` an array (13,), unpacked
with one ``tolist``) returning an array (13,) (+ extras) that the kernel
owns and overwrites on its next call: copy it to keep it (odeint copies it
at once; :func:`scipy.integrate.solve_ivp` keeps references, so it takes
the ``"args"`` form)."""


def _kernel_source(n: int, zero: frozenset, stabilise: bool, extras: bool,
                   signature: str = "args", physical: bool = False,
                   derivatives: bool = True, ticks: bool = False) -> tuple[str, list[str]]:
    """Source of a factory ``make(<params>) -> f(<13 state components>)``.

    ``f`` returns the 13 derivative components, followed (``extras``) by the
    n multipliers ``lam`` (N/m) and the n constraint values ``phi`` (m^2),
    and (``physical``, with ``stabilise`` and ``extras``) by the n
    unstabilised multipliers: what the kernel without ``stabilise`` gives
    as its ``lam``, the same expressions (its right-hand sides, and the
    elimination's factors, which do not depend on the stabilisation), so
    one pass over a record gives the health's multipliers and the
    physical tensions.  ``derivatives=False`` (with ``extras``): the 13
    derivative components are None, not computed (the extras the same).
    ``ticks`` (``signature="odeint"``): the factory takes two more
    arguments ``_at, _tick`` and ``f`` calls ``_tick(t)`` first whenever
    ``t >= _at[0]`` (:func:`~bifilar.integrators.ticker`).

    The multiplier system is solved for ``mu = lam / m`` (m/s^2 per m of
    wire): ``(m J M^-1 J^T) mu = rb`` has the rows ``d_i . d_j + J_i . (m
    I^-1) J_j``, the CoM acceleration is ``sum mu_i d_i - g e_z`` and the
    angular one ``I^-1 tau + sum mu_i (m I^-1) J_i``, which spares the
    divisions by the mass.  The attachment velocity is taken in body axes
    (``R^T v + w x p``: a sparse ``p`` costs fewer terms than ``(R w) x (R
    p)``).
    """
    if ticks and signature != "odeint":
        raise ValueError("ticks are for the 'odeint' signature")
    if signature not in SIGNATURES:
        raise ValueError(f"signature must be one of {SIGNATURES}, got {signature!r}")
    lines, out, params = kernel_statements(n, zero, stabilise, extras, physical, derivatives)
    if signature == "odeint":
        # the derivatives packed into one buffer viewed by one array: odeint copies the array it is
        # handed at once, and turning a 13-tuple into an array costs ~20 % of a kernel call; the
        # parameters are default arguments, i.e. locals of f (odeint passes only y and t), read
        # without the closure's cell indirection (~1-2 % of a call)
        local = [f"{p}={p}" for p in _read(params, lines + out) + ["_pack", "_buf", "_out"]
                 + (["_at", "_tick"] if ticks else [])]
        head = (f"    _buf = bytearray({8 * len(out)})\n    _out = _np.frombuffer(_buf)\n"
                f"    _pack = _struct.Struct('{len(out)}d').pack_into\n"
                f"    def f(y, t, {', '.join(local)}):\n"
                + ("        if t >= _at[0]:\n            _tick(t)\n" if ticks else "")
                + f"        {', '.join(_STATE_NAMES)} = y.tolist()\n")
        tail = f"        _pack(_buf, 0, {', '.join(out)})\n        return _out\n"
    else:
        head = f"    def f({', '.join(_STATE_NAMES)}):\n"
        tail = f"        return ({', '.join(out)},)\n"
    body = "\n".join("        " + ln for ln in lines)
    src = f"def make({', '.join(params + (['_at', '_tick'] if ticks else []))}):\n{head}{body}\n{tail}    return f\n"
    return src, params


def kernel_statements(n: int, zero: frozenset, stabilise: bool, extras: bool, physical: bool = False,
                      derivatives: bool = True) -> tuple[list, list, list]:
    """The kernel's straight-line statements, rendered by :func:`_kernel_source`
    as Python and by :mod:`bifilar.models.native_kernel` as C.

    Returns ``(lines, out, params)``: ``lines`` the statements ``"name =
    expr"`` (a name may be assigned again: the elimination's updates; four
    or more wires add a tuple assignment from ``_min_norm``), ``out`` the
    output expressions (13 derivative components in the state's layout,
    SI units, then the extras of :func:`_kernel_source`), ``params`` the
    parameter names (:func:`_param_names` less the zero set ``zero``) the
    statements read by name.  Every expression is names, float literals
    and ``+ - * /`` with parentheses, evaluated left to right as written
    (Python's and C's precedence and associativity are the same)."""
    C = _Code(zero)
    L = C.lines
    # rotation body -> world from the (not necessarily unit) quaternion
    L += ["s = qw*qw + qx*qx + qy*qy + qz*qz", "k = 2.0/s", "tx = k*qx", "ty = k*qy", "tz = k*qz",
          "xx = tx*qx", "yy = ty*qy", "zz = tz*qz", "xy = tx*qy", "xz = tx*qz", "yz = ty*qz",
          "wx_ = tx*qw", "wy_ = ty*qw", "wz_ = tz*qw",
          "R00 = 1.0 - (yy + zz)", "R01 = xy - wz_", "R02 = xz + wy_",
          "R10 = xy + wz_", "R11 = 1.0 - (xx + zz)", "R12 = yz - wx_",
          "R20 = xz - wy_", "R21 = yz + wx_", "R22 = 1.0 - (xx + yy)"]
    R = [["R00", "R01", "R02"], ["R10", "R11", "R12"], ["R20", "R21", "R22"]]
    w = ["wx", "wy", "wz"]
    # CoM velocity in body axes, gyroscopic torque -w x I w and I^-1 of it (body axes)
    for a in range(3):
        C.let(f"vb{_AX[a]}", [(1, R[b][a], "v" + _AX[b]) for b in range(3)])
    Iname = {(0, 0): "xx", (1, 1): "yy", (2, 2): "zz", (0, 1): "xy", (1, 0): "xy", (0, 2): "xz", (2, 0): "xz",
             (1, 2): "yz", (2, 1): "yz"}
    L.append("w2 = wx*wx + wy*wy + wz*wz")
    if {"Ixy", "Ixz", "Iyz"} <= C.zero:  # principal body axes: Euler's equations, I^-1 (-w x I w)_x = Ex wy wz, ...
        C.let("Ntx", [(1, "Ex", "wy", "wz")])
        C.let("Nty", [(1, "Ey", "wz", "wx")])
        C.let("Ntz", [(1, "Ez", "wx", "wy")])
    else:
        for a in range(3):
            C.let(f"Iw{_AX[a]}", [(1, "I" + Iname[a, b], w[b]) for b in range(3)])
        C.let("taux", [(-1, "wy", "Iwz"), (1, "wz", "Iwy")])
        C.let("tauy", [(-1, "wz", "Iwx"), (1, "wx", "Iwz")])
        C.let("tauz", [(-1, "wx", "Iwy"), (1, "wy", "Iwx")])
        for a in range(3):
            C.let(f"Nt{_AX[a]}", [(1, "N" + Iname[a, b], "tau" + _AX[b]) for b in range(3)])
    for i in range(n):
        p = [f"px{i}", f"py{i}", f"pz{i}"]
        # attachment offset (world), wire vector anchor -> attachment, and in body axes
        for a in range(3):
            C.let(f"Rp{_AX[a]}{i}", [(1, R[a][b], p[b]) for b in range(3)])
        for a in range(3):
            C.let(f"d{_AX[a]}{i}", [(1, "r" + _AX[a]), (1, f"Rp{_AX[a]}{i}"), (-1, f"a{_AX[a]}{i}")])
        e_terms = [[(1, R[b][a], f"d{_AX[b]}{i}") for b in range(3)] for a in range(3)]  # R^T d
        if i > 0:  # e_i = e_0 + R^T (a_0 - a_i) + (p_i - p_0): fewer terms when anchors differ along few axes
            via0 = [[(1, f"e{_AX[a]}0")] + [(1, R[b][a], f"Da{_AX[b]}{i}") for b in range(3)] + [(1, f"Dp{_AX[a]}{i}")]
                    for a in range(3)]
            if sum(map(C.ops, via0)) < sum(map(C.ops, e_terms)):
                e_terms = via0
        for a in range(3):
            C.let(f"e{_AX[a]}{i}", e_terms[a])
        # attachment velocity in body axes: R^T v + w x p
        C.let(f"sx{i}", [(1, "vbx"), (1, "wy", p[2]), (-1, "wz", p[1])])
        C.let(f"sy{i}", [(1, "vby"), (1, "wz", p[0]), (-1, "wx", p[2])])
        C.let(f"sz{i}", [(1, "vbz"), (1, "wx", p[1]), (-1, "wy", p[0])])
        C.let(f"dd{i}", [(1, f"d{a}{i}", f"d{a}{i}") for a in _AX])
        if extras:
            C.lines.append(f"phi{i} = 0.5*(dd{i} - L2{i})")
        if stabilise:
            C.let(f"phd{i}", [(1, f"e{a}{i}", f"s{a}{i}") for a in _AX])
        # rotational Jacobian row p x (R^T d) and (m I^-1) of it
        C.let(f"Jx{i}", [(1, p[1], f"ez{i}"), (-1, p[2], f"ey{i}")])
        C.let(f"Jy{i}", [(1, p[2], f"ex{i}"), (-1, p[0], f"ez{i}")])
        C.let(f"Jz{i}", [(1, p[0], f"ey{i}"), (-1, p[1], f"ex{i}")])
        for a in range(3):
            C.let(f"MJ{_AX[a]}{i}", [(1, "M" + Iname[a, b], f"J{_AX[b]}{i}") for b in range(3)])
        # centripetal term (R^T d) . (w x (w x p)) = (e.w)(w.p) - |w|^2 (e.p)
        C.let(f"ew{i}", [(1, f"e{a}{i}", "w" + a) for a in _AX])
        C.let(f"wp{i}", [(1, "w" + _AX[a], p[a]) for a in range(3)])
        C.let(f"ep{i}", [(1, f"e{_AX[a]}{i}", p[a]) for a in range(3)])
        terms = [(-1, f"s{a}{i}", f"s{a}{i}") for a in _AX]
        terms += [(-1, f"ew{i}", f"wp{i}"), (1, "w2", f"ep{i}")]
        terms += [(1, "g", f"dz{i}")]
        terms += [(-1, f"J{a}{i}", f"Nt{a}") for a in _AX]
        if physical:
            C.let(f"rbu{i}", terms)
        if stabilise:  # - 2 alpha phidot - beta^2 phi, phi = (|d|^2 - L^2) / 2
            terms += [(-1, "bga", f"phd{i}"), (-1, "hb", f"dd{i}"), (1, f"hbL{i}")]
        C.let(f"rb{i}", terms)
    # multiplier matrix m J M^-1 J^T (symmetric, upper triangle)
    for i in range(n):
        for j in range(i, n):
            dd = [(1, f"dd{i}")] if i == j else [(1, f"d{a}{i}", f"d{a}{j}") for a in _AX]
            C.let(f"A{i}{j}", dd + [(1, f"J{a}{i}", f"MJ{a}{j}") for a in _AX])
    if n > MAX_ELIMINATION_WIRES:
        # four or more wires: the constraints can be dependent (every wire taut on a symmetric rig),
        # J M^-1 J^T is then singular and the minimum-norm multipliers are taken (see _min_norm)
        upper = ", ".join(C.v(f"A{i}{j}") for i in range(n) for j in range(i, n))
        rbs = ", ".join(C.v(f"rb{i}") for i in range(n))
        C.lines.append(f"{', '.join(f'mu{i}' for i in range(n))}, = _min_norm(({upper},), ({rbs},))")
        if physical:
            rbus = ", ".join(C.v(f"rbu{i}") for i in range(n))
            C.lines.append(f"{', '.join(f'muu{i}' for i in range(n))}, = _min_norm(({upper},), ({rbus},))")
    # unpivoted symmetric elimination, then back substitution
    for k in range(n if n <= MAX_ELIMINATION_WIRES else 0):
        C.lines.append(f"iA{k} = 1.0/A{k}{k}")
        for i in range(k + 1, n):
            C.lines.append(f"f = A{k}{i}*iA{k}")
            for j in range(i, n):
                C.lines.append(f"A{i}{j} = A{i}{j} - f*A{k}{j}")
            C.lines.append(f"rb{i} = {C.v(f'rb{i}')} - f*{C.v(f'rb{k}')}")
            C.zero.discard(f"rb{i}")
            if physical:
                C.lines.append(f"rbu{i} = {C.v(f'rbu{i}')} - f*{C.v(f'rbu{k}')}")
                C.zero.discard(f"rbu{i}")
    for i in reversed(range(n if n <= MAX_ELIMINATION_WIRES else 0)):
        rest = "".join(f" - A{i}{j}*mu{j}" for j in range(i + 1, n))
        C.lines.append(f"mu{i} = ({C.v(f'rb{i}')}{rest})*iA{i}")
        if physical:
            rest = "".join(f" - A{i}{j}*muu{j}" for j in range(i + 1, n))
            C.lines.append(f"muu{i} = ({C.v(f'rbu{i}')}{rest})*iA{i}")
    if derivatives:
        C.let("ax_", [(1, f"mu{i}", f"dx{i}") for i in range(n)])
        C.let("ay_", [(1, f"mu{i}", f"dy{i}") for i in range(n)])
        C.let("az_", [(1, f"mu{i}", f"dz{i}") for i in range(n)] + [(-1, "g")])
        for a in range(3):
            C.let(f"al{_AX[a]}", [(1, f"Nt{_AX[a]}")] + [(1, f"mu{i}", f"MJ{_AX[a]}{i}") for i in range(n)])
        # quaternion rate q * (0, w) / 2 with a pull back to |q| = 1 at rate 1/s
        L += ["u = 1.0 - s", "hx = 0.5*wx", "hy = 0.5*wy", "hz = 0.5*wz",
              "dqw = u*qw - qx*hx - qy*hy - qz*hz",
              "dqx = u*qx + qw*hx + qy*hz - qz*hy",
              "dqy = u*qy + qw*hy - qx*hz + qz*hx",
              "dqz = u*qz + qw*hz + qx*hy - qy*hx"]
        out = ["vx", "vy", "vz", "dqw", "dqx", "dqy", "dqz", C.v("ax_"), C.v("ay_"), C.v("az_"),
               C.v("alx"), C.v("aly"), C.v("alz")]
    else:  # only the extras are read (a record's tensions and health): the derivatives are not computed
        out = ["None"] * 13
    if extras:
        out += [f"mass*mu{i}" for i in range(n)] + [C.v(f"phi{i}") for i in range(n)]
        if physical:
            out += [f"mass*muu{i}" for i in range(n)]
    params = [p for p in _param_names(n) if p not in zero]
    lines, out = _inline_single_use(C.lines, out)
    return lines, out, params


_TOKEN = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
_ASSIGN = re.compile(r"^([A-Za-z_][A-Za-z_0-9]*) = (.+)$")


def _read(names: list, code: list) -> list:
    """The names of ``names`` that the statements ``code`` read."""
    seen = {t for ln in code for t in _TOKEN.findall(ln)}
    return [p for p in names if p in seen]


def _inline_single_use(lines: list, out: list) -> tuple[list, list]:
    """The kernel's statements ``lines`` and output expressions ``out``
    with every temporary that is assigned once and read once written into
    the expression that reads it (in parentheses), and every alias ``a =
    b`` replaced by ``b``: the same floating-point operations in the same
    order (bit-identical results), minus a store and a load of a local
    per temporary (~6 % of a two-wire call on Python floats,
    docs/performance.md, session 12).  A temporary is left alone where a
    name it reads is assigned again between its statement and its use
    (the elimination's updates)."""
    stmts = []  # [target or None, expression]
    for ln in lines:
        m = _ASSIGN.match(ln)
        stmts.append([m.group(1), m.group(2)] if m else [None, ln])
    stmts += [[None, e] for e in out]
    defs: dict = {}
    for i, (tgt, expr) in enumerate(stmts):
        for name in ([tgt] if tgt else [t for t in _TOKEN.findall(expr.split(" = ")[0]) if " = " in expr]):
            defs.setdefault(name, []).append(i)
    uses: dict = {}
    for j, (_, expr) in enumerate(stmts):
        rhs = expr.split(" = ", 1)[1] if stmts[j][0] is None and " = " in expr else expr
        for t in _TOKEN.findall(rhs):
            uses.setdefault(t, []).append(j)

    def untouched(names, i, j) -> bool:  # no name of ``names`` assigned in statements i+1 .. j-1
        return not any(i < k < j for nm in names for k in defs.get(nm, ()))

    for i, (tgt, expr) in enumerate(stmts):
        if tgt is None or len(defs[tgt]) != 1:
            continue
        at = uses.get(tgt, [])
        alias = _TOKEN.fullmatch(expr) is not None
        if not at or min(at) <= i or not (alias or len(at) == 1) or not untouched(_TOKEN.findall(expr), i,
                                                                                 max(at) + 1):
            continue
        sub = expr if alias else "(" + expr + ")"
        pat = re.compile(r"\b" + tgt + r"\b")
        for j in sorted(set(at)):
            t2, e2 = stmts[j]
            if t2 is None and " = " in e2:  # a tuple assignment: replace on its right-hand side only
                left, right = e2.split(" = ", 1)
                stmts[j][1] = left + " = " + pat.sub(sub, right)
            else:
                stmts[j][1] = pat.sub(sub, e2)
        toks = _TOKEN.findall(expr)
        for t in toks:  # the expression's names are now read where it went, not at i
            uses[t].remove(i)
            uses[t] += at
        stmts[i] = None
    kept = [s for s in stmts if s is not None]
    body = [f"{t} = {e}" if t else e for t, e in kept[:len(kept) - len(out)]]
    return body, [e for _, e in kept[len(kept) - len(out):]]


MAX_ELIMINATION_WIRES = 3
"""Wire counts up to this solve the multiplier system by straight-line
elimination in the kernel; more wires go through :func:`_min_norm`."""
def _zero_set(vals: dict) -> frozenset:
    out = set()
    for k, v in vals.items():
        # (a single scene's floats: no numpy call; the value first, so that a nonzero one -- most -- costs no name test)
        if ((v == 0) if type(v) is float else np.all(np.asarray(v) == 0)) and not (
                k in _NEVER_ZERO or k.startswith(("L2", "hbL"))):  # never drop these (a zero: a degenerate scene)
            out.add(k)
    return frozenset(out)


def compiled_kernel(P: "RigParams", stabilise: bool = True, extras: bool = False, signature: str = "args",
                    physical: bool = False, derivatives: bool = True, ticks: tuple | None = None,
                    native: bool = True):
    """The model's right-hand side compiled for the parameters ``P``.

    Returns ``f(rx, ry, rz, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz) -> tuple``
    of the 13 state-derivative components (the layout of :func:`rhs`),
    followed when ``extras`` by the n multipliers ``lam`` (N/m; tension
    ``-lam |d|``) and the n constraint values ``phi = (|d|^2 - L^2)/2``
    (m^2).  The arguments are floats for a single scene (fastest) or arrays
    broadcasting against ``P.batch_shape``; with ``signature="odeint"``
    (one scene) the function is ``f(y, t)`` on an array ``y`` (13,), the
    right-hand side :func:`scipy.integrate.odeint` calls, without a wrapper,
    returning an array it reuses (see :data:`SIGNATURES`).  ``physical``
    (with ``stabilise`` and ``extras``): the n unstabilised multipliers
    (N/m) follow, what ``compiled_kernel(P, False, True)`` gives as its
    ``lam`` (the physical tension ``-lam |d|`` of :func:`tensions`) for a
    few operations more than the stabilised kernel alone.
    ``derivatives=False`` (with ``extras``, ``signature="args"``): the 13
    derivative components are returned as None, not computed (~20 % fewer
    operations; the extras are the same bits).  Cached on ``P``.
    ``ticks`` (``signature="odeint"``): ``(at, tick)`` of
    :func:`~bifilar.integrators.ticker`, called from inside the kernel
    (a progress bar's ticks without a wrapper's extra Python call per
    right-hand side: +3.6 % of a run's time with the wrapper, ~+0.5 %
    this way); the same numbers; a new function each call, not cached.
    ``native`` (``signature="odeint"``, stabilised, no extras, up to
    :data:`MAX_ELIMINATION_WIRES` wires): the same statements compiled as
    C when :mod:`.native_kernel` has the library (the same numbers bit for
    bit; ``BIFILAR_NATIVE=0`` or ``native=False``: the Python kernel).
    """
    if ticks is not None and signature != "odeint":
        raise ValueError("ticks are for the 'odeint' signature")
    if signature == "odeint" and P.batch_shape != ():
        raise ValueError("signature='odeint' is for one scene (parameters of batch shape ())")
    if physical and not (stabilise and extras):
        raise ValueError("physical=True adds the unstabilised multipliers to a stabilised kernel with extras")
    if not derivatives and not (extras and signature == "args"):
        raise ValueError("derivatives=False is for a kernel with extras and the 'args' signature")
    cache = P.__dict__.get("_kernels")
    if cache is None:
        cache = {}
        object.__setattr__(P, "_kernels", cache)
    key = (bool(stabilise), bool(extras), signature) + (("physical",) if physical else ()) + \
        (() if derivatives else ("no derivatives",)) + (() if ticks is None else ("ticks",))
    native = native and signature == "odeint" and stabilise and not extras and not physical
    if native:
        f = (cache.get(key + ("native",)) if ticks is None else None) or _native_odeint(P, cache, key, ticks)
        if f is not None:
            return f
    if key not in cache or ticks is not None:
        if "values" not in cache:  # the parameters' values and zero set, once for every kernel of P
            vals = _param_values(P)
            cache["values"] = (vals, _zero_set(vals))
        vals, zero = cache["values"]
        n = int(P.lengths.shape[-1])
        fkey = (n, zero) + key
        if fkey not in _FACTORY_CACHE:
            src, params = _kernel_source(n, zero, stabilise, extras, signature, physical, derivatives,
                                         ticks is not None)
            ns: dict = {"_min_norm": _min_norm, "_np": np, "_struct": struct}
            exec(compile(src, f"<bifilar.maximal kernel n={n}>", "exec"), ns)  # noqa: S102 - generated here
            _FACTORY_CACHE[fkey] = (ns["make"], params)
        make, params = _FACTORY_CACHE[fkey]
        if ticks is not None:  # the tick schedule is the caller's run's: a kernel of its own
            return make(*[vals[p] for p in params], *ticks)
        cache[key] = make(*[vals[p] for p in params])
    return cache[key]


_KEPT_NAMES: dict = {}
"""(wire count, zero set) -> the C kernel's parameter names in order (those of
:func:`_param_names` not in the zero set), once a pattern and process."""


def _native_odeint(P: "RigParams", cache: dict, key: tuple, ticks):
    """odeint's kernel of ``P`` compiled as C (:mod:`.native_kernel`), or None
    (not built yet, disabled, unavailable, more than MAX_ELIMINATION_WIRES
    wires): the Python kernel's numbers bit for bit.  Cached on ``P`` as
    the Python kernel is, the ``ticks`` one excepted."""
    if "values" not in cache:
        vals = _param_values(P)
        cache["values"] = (vals, _zero_set(vals))
    vals, zero = cache["values"]
    n = int(P.lengths.shape[-1])
    if n > MAX_ELIMINATION_WIRES:
        return None
    from . import native_kernel

    names = _KEPT_NAMES.get((n, zero))
    if names is None:
        names = _KEPT_NAMES[(n, zero)] = [p for p in _param_names(n) if p not in zero]
    f = native_kernel.odeint_kernel((n, zero), lambda: kernel_statements(n, zero, True, False),
                                    lambda: [vals[p] for p in names], ticks,
                                    reference=lambda: compiled_kernel(P, signature="odeint", native=False))
    if f is not None and ticks is None:
        cache[key + ("native",)] = f
    return f


def kernel_source(P: "RigParams", stabilise: bool = True, extras: bool = False, signature: str = "args",
                  physical: bool = False) -> str:
    """The generated source behind :func:`compiled_kernel` (for inspection)."""
    vals = _param_values(P)
    return _kernel_source(int(P.lengths.shape[-1]), _zero_set(vals), stabilise, extras, signature, physical)[0]
