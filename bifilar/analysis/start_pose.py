"""Start poses of nonlinear runs: rest displaced along a mode, put back on the wires.

One solver for one scene (:func:`~bifilar.analysis.simulate.initial_state`)
and for many (:func:`~bifilar.analysis.batch.initial_states`,
:func:`~bifilar.analysis.batch.feasible_amplitudes`, the backbone curve of
:mod:`~bifilar.analysis.fidelity`).  The problem it solves is defined
without reference to any solver path, so its answer (and whether there is
one) does not depend on iteration counts or on the machine's rounding:

* The pose is written in the chart of
  :func:`~bifilar.analysis.simulate.relative_pose`: x = (dr, theta), CoM =
  rest CoM + dr (m, world frame), R = exp([theta]x) R_rest (theta a world
  rotation vector, rad).
* The experimenter displaces the mode's dominant coordinate to
  ``amplitude x shape[dominant]`` and holds it there: that coordinate of x is
  set to exactly this value and never changed.
* The other five coordinates are the point of the wire manifold
  (every |d_i| = L_i) closest to the displaced pose x0 = amplitude x shape
  in the metric W = diag(m, m, m, I, I, I) (I the mean principal moment):
  min (x - x0)^T W (x - x0) subject to phi_i(x) = (|d_i|^2 - L_i^2) / 2 = 0.
  Its first-order conditions, W (x - x0) = G^T mu and phi = 0, are what the
  solver drives to zero; G is the Jacobian of phi in the chart,
  G_i = [d_i, (w_i x d_i)^T J_l(theta)] (dR = [J_l(theta) dtheta]x R).

Solver: Gauss-Newton on those conditions (each step the minimum-W-norm pose
from x0 that satisfies the constraints linearised at the current pose,
x+ = x0 + W^-1 G^T mu), with a backtracking line search on the wire
residual, vectorised over scenes.  A scene not converged after
:data:`ITERATIONS` steps goes to a fallback: ``scipy.optimize.least_squares``
minimises the wire residual over the five free coordinates from x0; if its
minimum is at most :data:`FEASIBLE_TOL` the Gauss-Newton iteration restarts
from that pose (on the wires).  A start is refused (infeasible) only when
the least-squares minimum of max_i | |d_i| - L_i | exceeds
:data:`FEASIBLE_TOL` x L_max: no pose with the held coordinate at its value
puts every wire within 1e-9 of its length.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..models.maximal import MAX_ELIMINATION_WIRES, held_directions
from ..rotations import quat_multiply, rotvec_to_matrix, rotvec_to_quat, skew
from ..scene import Scene
from .batch_rest import _cross
from .elastic_rest import loaded_scenes
from .equilibrium import RestPose, multiplier_matrix
from .wire_statics import held_violation
from .modes import COMPONENTS

ITERATIONS = 200
"""Gauss-Newton steps before a scene goes to the fallback."""
CONTINUATION_STEPS = 8
"""Fallback: the amplitude is raised from 0 in this many steps ..."""
CONTINUATION_HALVINGS = 6
"""... each halved at most this many times where it fails."""
_NEAR = 0.05
"""The least-squares estimate of how far off the wires an unreachable start
is counts only within this of the branch's end (0.05 L_max, 0.05 rad)."""
_THETA_MAX = np.pi - 1e-6
"""Poses with |theta| beyond this are outside the chart of ``relative_pose``
(its rotation vectors have |theta| <= pi)."""
FEASIBLE_TOL = 1e-9
"""A start is on the wires when max_i | |d_i| - L_i | <= FEASIBLE_TOL x L_max;
it is refused when the fallback's minimum of that residual is above it."""
_RES_DONE = 1e-15
"""On the wires: max |phi_i| / L_max^2 below this."""
_STEP_DONE = 1e-9
"""The closest pose is found when a Newton step (back on the wires) moves it
less than this (|dr| / L_max and |dtheta|, rad): Newton's next step would be
~1e-18 where the constraints are regular; where dependent wires make them
singular, putting a pose back on them is only good to ~1e-8 (a double root)."""


@dataclass
class StartPoses:
    """Start poses of B scenes (SI units, world frame).

    com (B, 3) m; R (B, 3, 3); q (B, 4) unit quaternions (w >= 0);
    x (B, 6) the pose in the chart of ``relative_pose`` (dr m, theta rad);
    residual (B,) max_i | |d_i| - L_i | / L_max at the pose; feasible (B,)
    residual <= :data:`FEASIBLE_TOL`; gap (B,) m: max_i | |d_i| - L_i | of
    the closest start found (0 where feasible); amplitude (B,).
    """

    com: np.ndarray
    R: np.ndarray
    q: np.ndarray
    x: np.ndarray
    residual: np.ndarray
    feasible: np.ndarray
    gap: np.ndarray
    amplitude: np.ndarray
    edge: np.ndarray
    """(B,) :func:`edge_ratio` of each start (1 at rest; below :data:`EDGE_TOL` the
    start is at the end of its reach and infeasible, with gap 0)."""
    held: np.ndarray
    """(B,) m: the start's length error in the directions the run holds
    (:func:`~bifilar.analysis.wire_statics.held_violation`), on rigs of more
    than three wires where the solver left the start off the wires; NaN
    elsewhere (where it is not needed: the whole error decides)."""

    def off_wires(self, j: int) -> dict:
        """:func:`refusal`'s ``held`` and ``residual`` of start ``j``."""
        return {"held": float(self.held[j]), "residual": float(self.residual[j])}

    def take(self, ii) -> "StartPoses":
        """The start poses of scenes ``ii`` (indices), in that order."""
        ii = np.asarray(ii, int)
        return StartPoses(**{f: getattr(self, f)[ii] for f in StartPoses.__dataclass_fields__})

    @staticmethod
    def concat(parts: Sequence["StartPoses"]) -> "StartPoses":
        """The start poses of ``parts`` one after the other."""
        return StartPoses(**{f: np.concatenate([getattr(sp, f) for sp in parts]) for f in StartPoses.__dataclass_fields__})

    def states(self) -> np.ndarray:
        """(B, 13) states of :mod:`bifilar.models.maximal`: CoM, quaternion, zero velocity."""
        return np.concatenate([self.com, self.q, np.zeros((len(self.com), 6))], axis=1)


def left_jacobian(theta: np.ndarray) -> np.ndarray:
    """J_l(theta) (..., 3, 3) of SO(3): d exp([theta]x) = [J_l dtheta]x exp([theta]x)
    (theta rad, any leading axes); series below 1e-4 rad."""
    theta = np.asarray(theta, float)
    a2 = np.einsum("...i,...i->...", theta, theta)
    a = np.sqrt(a2)
    small = a < 1e-4
    if small.any():
        safe = np.where(small, 1.0, a)
        b = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
        c = np.where(small, 1.0 / 6.0 - a2 / 120.0, (safe - np.sin(safe)) / safe**3)
    else:  # (no series: the same values without the masks, as a start pose's turns of ~0.1 rad take it)
        b = (1.0 - np.cos(a)) / a**2
        c = (a - np.sin(a)) / a**3
    K = skew(theta)
    return np.eye(3) + b[..., None, None] * K + c[..., None, None] * (K @ K)


class _Rig:
    """The arrays of B scenes (same wire count) and their rest poses."""

    def __init__(self, scenes: Sequence[Scene], rests: Sequence[RestPose]):
        self.a = np.array([s.anchors for s in scenes], float)
        self.p = np.array([s.attachments for s in scenes], float)
        self.L = np.array([s.lengths for s in scenes], float)
        self.Lmax = self.L.max(axis=1)
        m = np.array([s.mass for s in scenes], float)
        # the distinct scenes' eigenvalues in one eigvalsh call (a point's rows repeat its scene: 4 distinct of its
        # 9; LAPACK solves each matrix of a stack alone, and a row's mean is the 3-term sum of one scene's: the
        # same numbers as a call a scene, tests/test_start27.py)
        first: dict = {}
        for s in scenes:
            first.setdefault(id(s), s)
        stack = np.array([s.inertia for s in first.values()], float).reshape(-1, 3, 3)
        ibar = dict(zip(first, np.linalg.eigvalsh(stack).mean(axis=1)))
        Ibar = np.array([ibar[id(s)] for s in scenes], float)
        self.W = np.concatenate([np.repeat(m[:, None], 3, 1), np.repeat(Ibar[:, None], 3, 1)], axis=1)
        self.com0 = np.array([r.com for r in rests], float)
        self.R0 = np.array([r.R for r in rests], float)
        self.q0 = np.array([r.q for r in rests], float)

    def take(self, ii) -> "_Rig":
        if len(ii) == len(self.L) and isinstance(ii, np.ndarray) and ii.dtype.kind == "i" \
                and bool(np.all(ii == np.arange(len(ii)))):
            return self  # every scene, in order: the same arrays (the solvers' loops while all are active)
        out = object.__new__(_Rig)
        for k, v in self.__dict__.items():
            out.__dict__[k] = v[ii]
        return out

    def pose(self, x: np.ndarray):
        """CoM (B, 3) and R (B, 3, 3) of chart poses x (B, 6)."""
        return self.com0 + x[:, :3], rotvec_to_matrix(x[:, 3:]) @ self.R0

    def wires(self, x: np.ndarray):
        """Wire vectors d (B, n, 3), lever arms w (B, n, 3) and phi (B, n), m^2."""
        com, R = self.pose(x)
        w = np.einsum("bij,bnj->bni", R, self.p)
        d = com[:, None, :] + w - self.a
        return d, w, 0.5 * (np.einsum("bni,bni->bn", d, d) - self.L**2)

    def jacobian(self, x: np.ndarray, d: np.ndarray, w: np.ndarray) -> np.ndarray:
        """G (B, n, 6) = d phi / d x in the chart (theta through J_l)."""
        wxd = _cross(w, d)  # np.cross's products and differences, without its axis handling
        return np.concatenate([d, np.einsum("bni,bij->bnj", wxd, left_jacobian(x[:, 3:]))], axis=-1)

    def residual(self, x: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        """max_i | |d_i| - L_i | / L_max (B,); ``d`` the wire vectors at x if
        known (:meth:`wires`' values there: the same residual)."""
        if d is None:
            d, _, _ = self.wires(x)
        return np.abs(np.linalg.norm(d, axis=2) - self.L).max(axis=1) / self.Lmax


def _pinv_solve(S: np.ndarray, rhs: np.ndarray, worst: np.ndarray | None = None) -> np.ndarray:
    """mu (B, n) = S^+ rhs for symmetric positive semi-definite S (B, n, n):
    eigenvalues below 1e-15 of the largest dropped (dependent wires give a
    singular S; the minimum-norm mu is then the one taken).  ``worst`` (B, n),
    if given, is lowered in place to the eigenvalues over the largest,
    ascending (the system's conditioning, read past dependent wires'
    eigenvalues by :func:`solve_start_poses`)."""
    ev, V = np.linalg.eigh(S)
    keep = ev > 1e-15 * np.maximum(ev[:, -1:], 1e-300)
    inv = np.where(keep, 1.0 / np.where(keep, ev, 1.0), 0.0)
    if worst is not None:
        np.minimum(worst, ev / np.maximum(ev[:, -1:], 1e-300), out=worst)
    return np.einsum("bij,bj->bi", V, inv * np.einsum("bji,bj->bi", V, rhs))


def _scale(rig: _Rig) -> np.ndarray:
    """(B, 6) size of each chart coordinate: L_max for dr, 1 rad for theta."""
    return np.concatenate([np.repeat(rig.Lmax[:, None], 3, 1), np.ones((len(rig.Lmax), 3))], axis=1)


def _to_wires(rig: _Rig, x: np.ndarray, Winv: np.ndarray, iters: int,
              worst: np.ndarray | None = None, geometry: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Newton onto the wires from poses x (B, 6): each step the
    minimum-W-norm correction of the linearised constraints (the held
    coordinate has Winv = 0, so it never moves), shortened by backtracking
    until the wire residual |phi| / L_max^2 (2-norm, along which the step is
    a descent direction even where dependent wires make the linearised
    system inconsistent) falls (Armijo) and the pose stays inside the chart.
    Returns (x, on the wires: max |phi| / L_max^2 < 1e-15); ``worst`` (B, n),
    if given, is lowered in place to the worst conditioning of the steps'
    systems (:func:`_pinv_solve`); ``geometry`` (a list), if given, is set
    to ``[d, w, phi]`` of :meth:`_Rig.wires` at the returned poses (kept
    with every accepted step: the same rows' values, which the closest-pose
    Newton then needs not compute again)."""
    x = x.copy()
    L2 = rig.Lmax**2
    d, w, phi = rig.wires(x)
    res = np.abs(phi).max(axis=1) / L2
    merit = np.linalg.norm(phi, axis=1) / L2
    active = res >= _RES_DONE
    weak = np.zeros(len(x), int)  # consecutive steps that lowered the residual by less than 0.05 %
    for _ in range(iters):
        ii = np.nonzero(active)[0]
        if not len(ii):
            break
        sub = rig.take(ii)
        G = sub.jacobian(x[ii], d[ii], w[ii])
        GW = G * Winv[ii][:, None, :]
        wi = None if worst is None else worst[ii]
        dx = -np.einsum("bnj,bn->bj", GW, _pinv_solve(GW @ np.swapaxes(G, 1, 2), phi[ii], wi))
        if worst is not None:
            worst[ii] = wi
        alpha = np.ones(len(ii))
        todo = np.ones(len(ii), bool)
        before = merit[ii].copy()
        for _h in range(20):  # down to a step of 1e-6
            jj = np.nonzero(todo)[0]
            if not len(jj):
                break
            xt = x[ii[jj]] + alpha[jj, None] * dx[jj]
            dt, wt, pt = sub.take(jj).wires(xt)
            mt = np.linalg.norm(pt, axis=1) / L2[ii[jj]]
            ok = np.isfinite(mt) & (mt <= (1.0 - 1e-4 * alpha[jj]) * merit[ii[jj]])
            ok &= np.linalg.norm(xt[:, 3:], axis=1) < _THETA_MAX
            acc, kk = jj[ok], ii[jj[ok]]
            x[kk], d[kk], w[kk], phi[kk], merit[kk] = xt[ok], dt[ok], wt[ok], pt[ok], mt[ok]
            res[kk] = np.abs(pt[ok]).max(axis=1) / L2[kk]
            todo[acc] = False
            alpha[jj[~ok]] *= 0.5
        weak[ii] = np.where(merit[ii] > 0.9995 * before, weak[ii] + 1, 0)
        # done, or stalled: no step lowered the residual, or it creeps toward a nonzero minimum (on a solvable
        # system it falls quadratically, by a factor 4 a step at a fold, and by 0.2-3 % a step while dependent
        # wires make the system nearly singular: a four-wire rectangle's torsion, tests/test_audit_cases.py)
        active[ii[todo | (res[ii] < _RES_DONE) | (weak[ii] >= 8)]] = False
    if geometry is not None:
        geometry[:] = [d, w, phi]
    return x, res < _RES_DONE


def _kkt(rig: _Rig, x0: np.ndarray, x: np.ndarray, mu: np.ndarray, Winv: np.ndarray, at: tuple | None = None):
    """Residuals of the closest-pose conditions at (x, mu): F1 (B, 6) =
    W (x - x0) + G^T mu on the free coordinates (0 on the held one), phi (B, n),
    and G (B, n, 6).  ``at``: (d, w, phi) of :meth:`_Rig.wires` at x, and
    G, if already known (the same values)."""
    d, w, phi = rig.wires(x) if at is None else at[:3]
    G = rig.jacobian(x, d, w) if at is None or len(at) < 4 else at[3]
    free = Winv > 0
    F1 = np.where(free, (x - x0) / np.where(free, Winv, 1.0) + np.einsum("bnj,bn->bj", G, mu), 0.0)
    return F1, phi, G


#: scenes a block in :func:`_mu_hessian` (bounds its 12 displaced copies' memory)
HESSIAN_BLOCK = 512


def _mu_hessian(rig: _Rig, x: np.ndarray, mu: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """sum_i mu_i d^2 phi_i / dx^2 (B, 6, 6) at poses x (B, 6), by central
    differences of the analytic Jacobian with steps 1e-6 ``scale`` (B, 6);
    column j from the displacements +-h_j e_j.  The 12 displaced poses of
    all scenes go through one evaluation: row by row the expressions of
    one displacement at a time, so the same bits (tests/test_run_cost.py).
    Large batches go in blocks of :data:`HESSIAN_BLOCK` scenes (rows are
    independent, so the same bits): the 12 displaced copies of 10 000
    scenes' wire arrays raised a 10 000-scene batch's peak memory by ~75 MB."""
    m = len(x)
    if m > HESSIAN_BLOCK:
        return np.concatenate([_mu_hessian(rig.take(np.arange(i, min(i + HESSIAN_BLOCK, m))), x[i:i + HESSIAN_BLOCK],
                                           mu[i:i + HESSIAN_BLOCK], scale[i:i + HESSIAN_BLOCK])
                               for i in range(0, m, HESSIAN_BLOCK)])
    hs = 1e-6 * scale
    E = np.zeros((6, m, 6))
    E[np.arange(6), :, np.arange(6)] = hs.T
    Xs = np.concatenate([x + E, x - E]).reshape(12 * m, 6)  # +h_0 e_0 .. +h_5 e_5, then -h_0 e_0 .. -h_5 e_5
    big = rig.take(np.tile(np.arange(m), 12))
    ds, ws, _ = big.wires(Xs)
    Gs = big.jacobian(Xs, ds, ws).reshape(12, m, -1, 6)
    H = np.zeros((m, 6, 6))
    for j in range(6):
        dG = (Gs[j] - Gs[6 + j]) / (2.0 * hs[:, j][:, None, None])
        H[:, :, j] = np.einsum("bn,bni->bi", mu, dG)
    return H


def _closest(rig: _Rig, x0: np.ndarray, x: np.ndarray, Winv: np.ndarray, iters: int,
             at: tuple | None = None, geometry: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Newton's method on the first-order conditions of the closest pose
    (module doc) from poses x on the wires; constraint Hessians by central
    differences of the analytic Jacobian (their error, ~1e-10, slows the
    convergence a little and does not move the solution, whose residuals are
    analytic).  ``at``: (d, w, phi) of :meth:`_Rig.wires` at x if known
    (:func:`_to_wires`' ``geometry``).  Each row's wires at its pose are
    kept from where they were computed (the start, :func:`_to_wires` after
    each step), not computed again for the next step's conditions: row by
    row the same values (tests/test_perf26a.py).  ``geometry`` (a list), if
    given, is set to ``[d, w, phi]`` at the returned poses (each row's as
    kept).  Returns (x, converged)."""
    B = len(x)
    x = x.copy()
    scale = _scale(rig)
    free = Winv > 0
    Wd = np.where(free, 1.0 / np.where(free, Winv, 1.0), 0.0)
    # multipliers from the stationarity condition in the least-squares sense
    d, w, phi = rig.wires(x) if at is None else (a.copy() for a in at)
    G = rig.jacobian(x, d, w)
    first = (d, w, phi, G)  # the first step's conditions are at these poses
    GW = G * Winv[:, None, :]
    mu = -_pinv_solve(GW @ np.swapaxes(G, 1, 2), np.einsum("bnj,bj->bn", G * free[:, None, :], x - x0))
    n = mu.shape[1]
    conv = np.zeros(B, bool)
    active = np.ones(B, bool)
    for _ in range(iters):
        ii = np.nonzero(active)[0]
        if not len(ii):
            break
        sub = rig.take(ii)
        F1, phi_i, G = _kkt(sub, x0[ii], x[ii], mu[ii], Winv[ii],
                            first if first is not None else (d[ii], w[ii], phi[ii]))
        first = None
        H = _mu_hessian(sub, x[ii], mu[ii], scale[ii])
        H = 0.5 * (H + np.swapaxes(H, 1, 2)) + Wd[ii][:, :, None] * np.eye(6)
        fr = free[ii]
        H = np.where(fr[:, :, None] & fr[:, None, :], H, np.eye(6))
        Gf = G * fr[:, None, :]
        K = np.zeros((len(ii), 6 + n, 6 + n))
        K[:, :6, :6] = H
        K[:, :6, 6:] = np.swapaxes(Gf, 1, 2)
        K[:, 6:, :6] = Gf
        rhs = -np.concatenate([F1, phi_i], axis=1)
        step = np.einsum("bij,bj->bi", np.linalg.pinv(K, rcond=1e-13), rhs)
        # back onto the wires after each step (dependent wires curve the constraints at second order where
        # the linearised ones cannot follow: a four-wire rectangle's torsion)
        geo: list = []
        xt, on = _to_wires(sub, x[ii] + step[:, :6], Winv[ii], ITERATIONS, geometry=geo)
        on &= np.all(np.isfinite(xt), axis=1)
        small = on & (np.max(np.abs(xt - x[ii]) / scale[ii], axis=1) < _STEP_DONE)
        x[ii[on]] = xt[on]
        d[ii[on]], w[ii[on]], phi[ii[on]] = (a[on] for a in geo)
        mu[ii[on]] = mu[ii[on]] + step[on, 6:]
        conv[ii[small]] = True
        active[ii[small | ~on]] = False
    if geometry is not None:
        geometry[:] = [d, w, phi]
    return x, conv


def _solve(rig: _Rig, x0: np.ndarray, x: np.ndarray, Winv: np.ndarray, worst: np.ndarray | None = None,
           at: list | None = None):
    """Closest poses to x0 on the wires, from x: onto the wires, then Newton.
    Returns (x, converged, on the wires within :data:`FEASIBLE_TOL`: where
    dependent wires make the constraints singular, Gauss-Newton can stop a
    hair off them, e.g. 2e-11 of the length for a four-wire rectangle
    twisted by 0.01 rad); ``worst`` as in :func:`_to_wires` (the path onto
    the wires from x); ``at`` (a list), if given, is set to ``[residual
    (B,) of :meth:`_Rig.residual`, d, w]`` at the returned poses.  The
    residual is taken from the wires each row's pose was last put on (its
    :func:`_to_wires` or :func:`_closest` geometry), not computed again:
    row by row the same values (tests/test_start27.py)."""
    geo: list = []
    x, on = _to_wires(rig, x, Winv, ITERATIONS, worst, geo)
    out = x.copy()
    d, w = geo[0], geo[1]
    conv = np.zeros(len(x), bool)
    ii = np.nonzero(on)[0]
    if len(ii):
        got: list = []
        xc, cc = _closest(rig.take(ii), x0[ii], x[ii], Winv[ii], ITERATIONS, tuple(a[ii] for a in geo),
                          geometry=got)
        out[ii], conv[ii] = xc, cc
        d, w = d.copy(), w.copy()
        d[ii], w[ii] = got[0], got[1]
    res = rig.residual(out, d)
    if at is not None:
        at[:] = [res, d, w]
    return out, conv, res <= FEASIBLE_TOL


_JUMP = 0.25
"""A continuation step is refused (and halved) when its pose's free coordinates
end further than this from the step's prediction (|dr| / L_max, |dtheta| rad).
Along a branch the deviation falls with the step: as ds^2 where the branch is
regular and as sqrt(ds) at a fold (the thesis plate's last step to its reach
0.39 of L_max from 7/8 of it, 0.28 from 15/16, 0.14 from 63/64: steps are
halved until it passes); a pose on another branch stays O(1) away however
small the step (the plate's pitched branch: 1 rad of tilt at the reach)."""
_ILL = 1e-6
"""A direct start is checked against the branch from rest when a Gauss-Newton
system on its path had a conditioning (smallest eigenvalue over largest) below
this: ordinary starts 0.015-0.35 (the thesis plate's modes up to 1.3 rad or 2 m),
~edge ratio^2 near the end of the reach (9e-9 at 1e-8 rad short of the plate's)."""
_SAME = 1e-6
"""A direct start and the branch's end are the same pose when their free
coordinates agree to this (|dr| / L_max, rad): each converged to _STEP_DONE."""


def _deviation(rig: _Rig, x: np.ndarray, ref: np.ndarray, Winv: np.ndarray) -> np.ndarray:
    """(B,) max over the free coordinates of |x - ref| / scale (|dr| / L_max, |dtheta| rad)."""
    return np.max(np.where(Winv > 0, np.abs(x - ref), 0.0) / _scale(rig), axis=1)


def _least_squares(rig: _Rig, x0: np.ndarray, hold: int) -> tuple[np.ndarray, float]:
    """Fallback for one scene (rig of one): least_squares on (|d_i| - L_i) / L_max
    over the five free coordinates from x0.  Returns (x (6,), its residual)."""
    from scipy.optimize import least_squares

    free = np.array([j for j in range(6) if j != hold])
    Lmax = float(rig.Lmax[0])

    def full(z):
        x = x0.copy()
        x[free] = z
        return x[None, :]

    def fun(z):
        d, _, _ = rig.wires(full(z))
        return (np.linalg.norm(d[0], axis=1) - rig.L[0]) / Lmax

    def jac(z):
        x = full(z)
        d, w, _ = rig.wires(x)
        G = rig.jacobian(x, d, w)[0]
        return G[:, free] / (np.linalg.norm(d[0], axis=1)[:, None] * Lmax)

    xs = np.where(free < 3, Lmax, 1.0)
    sol = least_squares(fun, x0[free], jac=jac, method="trf", x_scale=xs, ftol=1e-10, xtol=1e-10, gtol=1e-10,
                        max_nfev=200)
    x = full(sol.x)
    return x[0], float(rig.residual(x)[0])


def _continuation(rig: _Rig, x0: np.ndarray, Winv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Scenes whose direct solve did not converge: follow each branch of start
    poses from rest (amplitude 0) to the displaced pose x0 (B, 6) in steps of
    the amplitude (:data:`CONTINUATION_STEPS`, halved where a step fails, at
    most :data:`CONTINUATION_HALVINGS` times), each solved from the previous
    pose, all scenes in step.  Returns (x (B, 6): the pose at x0 or the last
    pose reached with the held coordinate then moved to its value, whether x0
    was reached (B,))."""
    B = len(x0)
    s = np.zeros(B)
    ds = np.full(B, 1.0 / CONTINUATION_STEPS)
    x = np.zeros((B, 6))
    reached = np.zeros(B, bool)
    failed = np.zeros(B, bool)
    while True:
        ii = np.nonzero(~reached & ~failed)[0]
        if not len(ii):
            break
        t = np.minimum(1.0, s[ii] + ds[ii])
        guess = x[ii] + (t - s[ii])[:, None] * x0[ii]
        sub = rig.take(ii)
        xt, ct, _ = _solve(sub, t[:, None] * x0[ii], guess, Winv[ii])
        # a step that moves the free coordinates further than _JUMP from its prediction left the branch (or
        # took too long a step across a fold): halved like a step that failed
        ct = ct & (_deviation(sub, xt, guess, Winv[ii]) <= _JUMP)
        ok, kk = ct, ii[ct]
        s[kk], x[kk] = t[ok], xt[ok]
        ds[kk] = np.minimum(2.0 * ds[kk], 1.0 / CONTINUATION_STEPS)
        reached[kk[t[ok] >= 1.0]] = True
        kb = ii[~ct]
        ds[kb] = 0.5 * (t[~ct] - s[kb])  # half the step taken (shorter than ds where it ended at the amplitude)
        failed[kb[ds[kb] < 0.5**CONTINUATION_HALVINGS / CONTINUATION_STEPS]] = True
    held = Winv == 0.0
    x = np.where(held & ~reached[:, None], x + (1.0 - s)[:, None] * x0, x)
    return x, reached


def solve_start_poses(rig: _Rig, x0: np.ndarray, hold: np.ndarray,
                      at_rest: list | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Chart poses x (B, 6) of the start problem for displaced poses x0 (B, 6)
    with coordinate ``hold`` (B,) fixed; returns (x, residual (B,) relative,
    gap (B,) m: where no start is on the wires, the least-squares minimum of
    max_i | |d_i| - L_i | near the end of the branch, else 0).  ``at_rest``
    (a list), if given, is set to ``[d, w, G, at_x]``: d, w and G at rest
    (x = 0), what :func:`edge_ratio` needs too, and ``at_x`` (d, w) at the
    returned poses where the direct solve gave every one of them (else
    None)."""
    B = len(x0)
    Winv = 1.0 / rig.W
    Winv[np.arange(B), hold] = 0.0
    worst = np.ones(rig.L.shape)
    got: list = []
    x, conv, on = _solve(rig, x0, x0, Winv, worst, got)
    res, at_x = got[0], (got[1], got[2])
    # read past the eigenvalues of wires dependent at rest (four vertical ones: one at rounding there, ~1e-10 a
    # little way off; RANK_TOL as in edge_ratio)
    d, w, _ = rig.wires(np.zeros_like(x0))
    G = rig.jacobian(np.zeros_like(x0), d, w)
    ev = np.linalg.eigvalsh((G * Winv[:, None, :]) @ np.swapaxes(G, 1, 2))
    worst = worst[np.arange(B), np.sum(ev <= RANK_TOL * ev[:, -1:], axis=1)]
    gap = np.zeros(B)
    # branch guard: a direct solve whose path onto the wires passed near a singular point (the end of the
    # reach) amplifies rounding there and may have left for another branch of poses; it is checked against
    # the branch followed from rest, and kept only where that branch ends at it
    beyond = conv & (worst < _ILL)
    ii = np.nonzero(~conv | beyond)[0]
    if len(ii):
        xc, reached = _continuation(rig.take(ii), x0[ii], Winv[ii])
        same = beyond[ii] & reached & (_deviation(rig.take(ii), xc, x[ii], Winv[ii]) <= _SAME)
        # a start on the wires whose closest pose was not pinned down (neither directly nor along the branch)
        # is kept as it is: the held coordinate is exact and every wire at its length; a direct start the
        # branch confirms is kept bit for bit
        keep = (on[ii] & ~reached & ~beyond[ii]) | same
        x[ii[~keep]] = xc[~keep]
        far = ii[~reached & ~keep]
        if len(far):
            # how far off the wires the closest start is: Gauss-Newton from the branch's end with the held
            # coordinate at its value, then least squares from there, kept only while it stays near (a pose
            # it finds far away lies on another branch: not a start of this mode)
            sub = rig.take(far)
            xe, _ = _to_wires(sub, x[far], Winv[far], ITERATIONS)
            x[far] = xe
            for j, b in enumerate(far):
                one = sub.take([j])
                xl, res = _least_squares(one, xe[j], int(hold[b]))
                near = np.max(np.abs(xl - xe[j]) / _scale(one)[0]) <= _NEAR
                gap[b] = (res if near else float(one.residual(xe[j][None, :])[0])) * float(rig.Lmax[b])
                gap[b] = max(gap[b], 2.0 * FEASIBLE_TOL * float(rig.Lmax[b]))
        res = rig.residual(x)  # (else x is _solve's: its residual as it gave it)
        at_x = None
    if at_rest is not None:
        at_rest[:] = [d, w, G, at_x]
    feasible = (gap == 0.0) & (res <= FEASIBLE_TOL)
    return x, res, np.where(feasible, 0.0, np.where(gap > 0.0, gap, res * rig.Lmax))


def start_poses(scenes: Sequence[Scene], rests: Sequence[RestPose], modes, amplitude) -> StartPoses:
    """Start poses of scenes (same number of wires) displaced by ``amplitude``
    (scalar or (B,), rad or m) x each mode's shape, the dominant coordinate
    held (see the module doc).  Never raises for an unreachable start: see
    ``feasible`` and ``gap``."""
    scenes = loaded_scenes(scenes, rests)  # stated stiffness: the wires the run holds, loaded
    B = len(scenes)
    amp = np.broadcast_to(np.asarray(amplitude, float), (B,)).copy()
    rig = _Rig(scenes, rests)
    S = np.array([md.shape for md in modes], float)
    hold = np.array([md.dominant for md in modes], int)
    x0 = amp[:, None] * S
    x0[np.arange(B), hold] = amp * S[np.arange(B), hold]  # the held value, exactly amplitude x shape
    rest_geometry: list = []
    x, res, gap = solve_start_poses(rig, x0, hold, rest_geometry)
    held = np.full(B, np.nan)
    if B and scenes[0].n_wires > MAX_ELIMINATION_WIRES:
        # nearly dependent wires: a start the solver left off the wires is put on the lengths the run holds; it
        # is the run's start where the rest of its error, along the self-stresses the run leaves free, is at
        # most FREE_TOL (docs/design.md, "nearfix, session 15")
        for b in np.nonzero(gap > 0.0)[0]:
            one = rig.take(np.array([b]))
            x[b], held[b] = _onto_held(scenes[b], one, x[b], int(hold[b]))
            res[b] = float(one.residual(x[b][None])[0])
            rest_geometry[3] = None  # (a pose moved: the starts' wires computed again)
        gap = np.where((held <= FEASIBLE_TOL * rig.Lmax) & (res <= FREE_TOL), 0.0, gap)
    edge = edge_ratio(rig, x, hold, rest_geometry)
    com, R = rig.pose(x)
    q = _quaternion(rig, x)
    return StartPoses(com=com, R=R, q=q, x=x, residual=res, feasible=(gap == 0.0) & ~(edge < EDGE_TOL), gap=gap,
                      amplitude=amp, edge=edge, held=held)


FREE_TOL = 1e-6
"""On rigs of more than three wires, a start whose length error lies along
the self-stresses of wires nearly dependent there (which the run's
multipliers leave free, :func:`~bifilar.models.maximal._min_norm`; the
error in the other directions within :data:`FEASIBLE_TOL`) is a start when
that error is at most this share of the longest wire: what the run's own
length error may reach before simulate warns of it, and 10x below the
strain of lab wires at their load (1e-5 .. 1e-3), whose stretch takes it up
(a tension change along the self-stress of at most ~10 % of the load).  A
twisted table whose anchors are splayed by 1e-6 m is 1.3e-9 .. 4.5e-8 m
off at 0.01 .. 0.3 rad (docs/design.md, "nearfix, session 15")."""


def _quaternion(rig: _Rig, x: np.ndarray) -> np.ndarray:
    """(B, 4) unit quaternions (w >= 0) of chart poses x (B, 6)."""
    q = quat_multiply(rotvec_to_quat(x[:, 3:]), rig.q0)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q * np.where(q[:, :1] < 0, -1.0, 1.0)


def _onto_held(scene: Scene, rig: _Rig, x: np.ndarray, hold: int) -> tuple[np.ndarray, float]:
    """Chart pose (6,) of one scene (``rig`` of one) put onto the wires'
    lengths in the directions the run holds there (the eigen-directions of
    its multiplier matrix ``G M^-1 G^T`` that :func:`~bifilar.models.maximal.
    held_directions` keeps at ``x``, as many all along): Gauss-Newton from
    ``x``, each step the minimum-W-norm correction of those constraints
    linearised (coordinate ``hold`` fixed), backtracking on their residual;
    the self-stresses of nearly dependent wires, which the run leaves free,
    are left as they are.  Where the solver could not put every wire at its
    length (the rigid constraints' near-null direction makes its steps long
    and its Armijo test stall) this ends at the held part's rounding.
    Returns the pose and its :func:`~bifilar.analysis.wire_statics.
    held_violation` (m), ``x`` itself where that is lower there."""
    Winv = 1.0 / rig.W[0]
    Winv[hold] = 0.0
    L2 = float(rig.Lmax[0]) ** 2

    def held_part(xx, k):
        d, w, phi = rig.wires(xx[None])
        R = rig.pose(xx[None])[1]
        ev, V = np.linalg.eigh(multiplier_matrix(scene.mass, scene.inertia, R, np.concatenate([d, _cross(w, d)], -1)))
        k = int(np.sum(held_directions(ev[0]))) if k is None else k
        Vh = V[0][:, len(ev[0]) - k:]  # the k largest
        return Vh.T @ phi[0], Vh, d, w, k

    def violation(xx):
        state = np.concatenate([rig.pose(xx[None])[0][0], _quaternion(rig, xx[None])[0], np.zeros(6)])
        return held_violation(scene, state[None])

    x_in = x
    r, Vh, d, w, k = held_part(x, None)
    for _ in range(ITERATIONS):
        if np.max(np.abs(r)) / L2 < _RES_DONE:
            break
        Gh = Vh.T @ rig.jacobian(x[None], d, w)[0]
        GW = Gh * Winv
        dx = -GW.T @ np.linalg.lstsq(GW @ Gh.T, r, rcond=1e-15)[0]
        before, alpha = np.linalg.norm(r), 1.0
        for _h in range(20):
            xt = x + alpha * dx
            rt, Vt, dt, wt, _k = held_part(xt, k)
            if np.linalg.norm(rt) <= (1.0 - 1e-4 * alpha) * before and np.linalg.norm(xt[3:]) < _THETA_MAX:
                x, r, Vh, d, w = xt, rt, Vt, dt, wt
                break
            alpha *= 0.5
        else:
            break
    held_in, held_out = violation(x_in), violation(x)
    return (x, held_out) if held_out < held_in else (x_in, held_in)


EDGE_TOL = float(np.sqrt(2.0 * FEASIBLE_TOL))
"""Smallest :func:`edge_ratio` of a start that is not at the end of its reach
(4.5e-5).  At the end the wires that stop the mode are horizontal (their
vertical drop z = 0); with lengths met to FEASIBLE_TOL x L, a drop below
sqrt(2 FEASIBLE_TOL) L cannot be told from none (z^2 = L^2 - h^2 moves by
2 L dL), and the ratio is about that drop over L: 2e-8 for 5 cm wires swung
by exactly 5 cm (the multipliers then singular: +-1.6e7 N for a 1 kg body),
5e-6 for the thesis plate twisted to its analytic reach arccos(1/4), 8e-5
at 1e-8 rad short of it, 1.6e-4 at 1e-9 m short of the 5 cm swing's."""


def edge_ratio(rig: "_Rig", x: np.ndarray, hold: np.ndarray, at_rest: list | None = None) -> np.ndarray:
    """(B,) how far starts x (B, 6, chart) are from the end of their reach: the
    r-th singular value of the wires' unit constraint gradients together
    with the held coordinate's (rows [d_i / |d_i|, (w_i x d_i) / (|d_i| l)],
    l the farthest attachment from the CoM, and e_hold) at the start over the
    same at rest, r the matrix's rank at rest (:data:`RANK_TOL`; n + 1 but
    for dependent wires).  The held coordinate cannot move further where that matrix
    is singular: the wires are horizontal (a swing on parallel wires) or the
    held direction lies in the wires' span, and the start's tensions are not
    determined (the multipliers' matrix is singular).  ``at_rest``: [d, w,
    G] at rest (x = 0) if known (:func:`solve_start_poses`' ``at_rest``);
    the rest's and the starts' matrices then go through one SVD call (each
    matrix's singular values its own: the same values); a fourth item, if
    not None, is (d, w) at x (the wires where the solver left the starts:
    the same values as computed again, tests/test_start27.py)."""
    B = len(x)
    lever = np.maximum(np.max(np.linalg.norm(rig.p, axis=2), axis=1), 1e-300)  # (B,)

    def singular(xx, geo=None):
        d, w, _ = rig.wires(xx) if geo is None or len(geo) < 4 or geo[3] is None else (*geo[3], None)
        G = rig.jacobian(xx, d, w)
        k = 1
        if geo is not None:  # rest rows first
            d, G, k = np.concatenate([geo[0], d]), np.concatenate([geo[2], G]), 2
        G = G / np.linalg.norm(d, axis=2)[:, :, None]
        G[:, :, 3:] /= np.tile(lever, k)[:, None, None]
        e = np.zeros((k * B, 1, 6))
        e[np.arange(k * B), 0, np.tile(hold, k)] = 1.0
        return np.linalg.svd(np.concatenate([G, e], axis=1), compute_uv=False)

    if at_rest:
        both = singular(x, at_rest)
        at_rest, at_x = both[:B], both[B:]
    else:
        at_rest, at_x = singular(np.zeros_like(x)), None
    # the rank at rest: dependent wires (four parallel ones) leave one singular value at rounding there
    r = np.sum(at_rest > RANK_TOL * at_rest[:, :1], axis=1)
    k = np.arange(B), r - 1
    return (singular(x) if at_x is None else at_x)[k] / at_rest[k]


RANK_TOL = 1e-8
"""Singular values of the rest matrix of :func:`edge_ratio` below this share of
its largest are rounding: a rig of four or five dependent wires (parallel
vertical wires of a rectangle: 1e-17) has that rank and no more."""


def refusal(scene: Scene, mode, amplitude: float, gap: float, which: str = "", held: float = float("nan"),
            residual: float = float("nan")) -> InputError:
    """The :class:`InputError` (``--amplitude``) for a start no pose reaches;
    ``gap`` (m) how far the closest start found is off the wires; ``which``
    names the scene in a batch (e.g. "scene 3 ('name')"); ``held`` (m) and
    ``residual`` (relative, :meth:`StartPoses.off_wires`): where the start
    found is off the wires only along the lengths the run leaves free (its
    held part within :data:`FEASIBLE_TOL`), the refusal says so and that
    the rest exceeds :data:`FREE_TOL`."""
    unit = "rad" if mode.dominant >= 3 else "m"
    where = f" for {which}" if which else ""
    err = residual * max(scene.lengths)
    if held <= FEASIBLE_TOL * max(scene.lengths) and err > FREE_TOL * max(scene.lengths):  # (NaN: not judged)
        return InputError("--amplitude", f"{amplitude:g} {unit} of the {mode.label} mode is too large{where}: "
                                         f"the closest start found is {err:.3g} m off the wires, all but {held:.1e} m "
                                         "of it along the self-stress of wires nearly dependent there (lengths the "
                                         f"run leaves free, but only up to {FREE_TOL:g} of the longest wire, its own "
                                         "length error); use a smaller amplitude")
    if gap == 0.0:  # on the wires, at the end of the reach (EDGE_TOL)
        return InputError("--amplitude", f"{amplitude:g} {unit} of the {mode.label} mode is at the end of its reach"
                                         f"{where}: the wires that stop it are horizontal there (within the start "
                                         f"solver's {FEASIBLE_TOL:g} of the longest wire) and their tensions are not "
                                         f"determined; the reachable starts end at |amplitude| = {abs(amplitude):.6g} "
                                         f"{unit}: use a smaller amplitude")
    return InputError("--amplitude", f"{amplitude:g} {unit} of the {mode.label} mode is too large{where}: no pose with "
                                     f"the {COMPONENTS[mode.dominant]} coordinate held there keeps every wire at its "
                                     f"length (the closest start is {gap:.3g} m off the wires, more than "
                                     f"{FEASIBLE_TOL:g} of the longest wire); use a smaller amplitude")
