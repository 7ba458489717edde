"""The fidelity ladder: the cheapest model whose error is below the tolerance.

:func:`period` answers "what period will this mode have at this amplitude?"
with the first rung of the ladder whose *estimated* relative error is at
most ``tol``, and says which rung it used and its error estimate:

1. ``closed-form`` (microseconds): the small-angle torsion period of a
   symmetric two-wire trapezoid, T0 = 2 pi sqrt(4 H0 Izz / (m g b b')),
   H0 = sqrt(l^2 - ((b - b')/2)^2) (thesis 5.2.17 when b = b' = D, H0 = h).
   Its model error is the amplitude effect T/T0 - 1 = kappa A^2 + O(A^4)
   with, from the exact 1-DOF Lagrangian (:func:`torsion_kappa`),
   kappa = 1/16 - 3 c / (32 H0^2) + m c^2 / (16 H0^2 Izz),  c = b b'/2;
   the estimate is 1.25 |kappa| A^2 + 4 S^2 A^4, S the sum of the three
   terms' magnitudes (used while S A^2 <= 0.1; over 9500 random rigs and
   amplitudes the true error stays below 0.8 of this estimate).
2. ``reduced-1dof`` (milliseconds): the exact one-degree-of-freedom torsion
   model :func:`bifilar.models.reduced.torsion_period` (energy integral by
   quadrature).  Exact for those rigs (the symmetric yaw-and-rise motion is
   an invariant motion of the full model), so its error is the quadrature's
   (estimate 1e-12).
3. ``linear`` (a few milliseconds, any rig and mode): the linear-mode
   period.  Its model error is the amplitude effect, estimated by the
   *backbone* period -- the exact period of the conservative one-degree-of-
   freedom motion along the curve of projected displaced poses that
   :func:`~bifilar.analysis.simulate.initial_state` starts from (potential
   m g z and kinetic metric of the full model along that curve, energy
   integral by Gauss-Legendre quadrature) -- as 2 |T_backbone - T_lin| /
   T_lin: the backbone holds the mode's own nonlinearity exactly; the factor
   2 covers the coupling to the other modes, which the backbone leaves out
   (checked against the full model in tests/test_fidelity.py).
4. ``full`` (tens of milliseconds): the nonlinear maximal-coordinate model
   (:func:`bifilar.analysis.batch.run_one`, the period measured as
   ``bifilar simulate`` measures it), at rtol = tol / 10 and again at
   rtol / 10 (and tighter while the two differ by more than tol, down to
   1e-13); the estimate is the difference of the last two plus
   :data:`FULL_RTOL_ERROR` times the tighter one's rtol, the answer the
   tighter one (its model error is zero by definition: it is the reference
   model).

Only the period is computed: no tensions, energy or dense output (ask
:func:`bifilar.analysis.batch.simulate_batch` for those).

Errors are relative (|T - T_full| / T_full, dimensionless); periods in s,
amplitudes as in ``simulate`` (rad for rotation-dominated modes, m for
translation-dominated ones).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..models import reduced
from ..rotations import rotvec_to_matrix
from ..scene import Scene
from . import batch as bt
from .equilibrium import RestPose, rest_pose
from .modes import Mode, ModeSet, linear_modes
from .start_pose import start_poses

RUNGS = ("closed-form", "reduced-1dof", "linear", "full")
#: The full model's period error at rtol r, over r: measured up to 3.7 (rtol 1e-8..1e-11 on the ladder
#: tests' trapezoids, torsion, pitch and swing at 0.05-0.1 rad, the default and Sandybridge kernels
#: alike), so 10: the floor of the full rung's error estimate where two runs' difference understates it.
FULL_RTOL_ERROR = 10.0
KAPPA_SAFETY = 1.25
"""Factor on the leading amplitude term of the closed-form estimate."""
QUARTIC_SAFETY = 4.0
"""Factor on S^2 A^4, the bound on the next term of the closed-form estimate."""
CLOSED_FORM_MAX_SA2 = 0.1
"""The closed form is offered while S A^2 <= this (the series is then accurate)."""
BACKBONE_SAFETY = 2.0
"""Allowance for the coupling of the timed mode to the others in the linear
rung's estimate (the backbone's own error is of the same order as the
amplitude effect it estimates; measured ratios in the tests are <= 1.2)."""
QUADRATURE_ERROR = 1e-12


@dataclass(frozen=True)
class PeriodAnswer:
    """period (s), model (one of :data:`RUNGS`), est_error (relative), and the
    estimates of the rungs tried before (model -> relative error estimate)."""

    period: float
    model: str
    est_error: float
    tried: dict

    def __iter__(self):  # unpack as (period, model_used, est_error)
        return iter((self.period, self.model, self.est_error))


# --------------------------------------------------------------------------
# rung 1 and 2: the symmetric trapezoid in torsion
# --------------------------------------------------------------------------
def symmetric_torsion_params(scene: Scene, rel: float = 1e-12) -> reduced.TorsionParams | None:
    """:class:`~bifilar.models.reduced.TorsionParams` if the scene is a
    symmetric two-wire trapezoid in the sense of the exact 1-DOF torsion
    model (equal wires; anchors at one height and attachments at one body
    height, each pair symmetric about a vertical axis; the attachment line
    parallel to the anchor line; body z a principal axis), else None.
    ``rel``: relative tolerance of every test (rounding only)."""
    if scene.n_wires != 2:
        return None
    a, p, L, I = scene.anchors, scene.attachments, scene.lengths, scene.inertia
    scale = float(max(np.max(np.abs(a)), np.max(np.abs(p)), np.max(L)))
    tol = rel * scale
    if abs(L[0] - L[1]) > tol or abs(a[0, 2] - a[1, 2]) > tol or abs(p[0, 2] - p[1, 2]) > tol:
        return None
    if np.max(np.abs(p[0, :2] + p[1, :2])) > tol:  # attachments symmetric about the body z axis through the CoM
        return None
    da = (a[1] - a[0])[:2]
    dp = (p[1] - p[0])[:2]
    if abs(da[0] * dp[1] - da[1] * dp[0]) > tol * scale or np.dot(da, dp) <= 0:
        return None
    trace = float(np.trace(I))
    if abs(I[0, 2]) > rel * trace or abs(I[1, 2]) > rel * trace:
        return None
    if p[0, 2] < -tol:  # attachments below the CoM: the rig cannot hang stably
        return None
    b, bp = float(np.linalg.norm(da)), float(np.linalg.norm(dp))
    if b <= 0 or bp <= 0 or abs(b - bp) / 2 >= L[0]:
        return None
    return reduced.TorsionParams(m=float(scene.mass), Izz=float(I[2, 2]), l=float(L[0]), b=b, bp=bp,
                                 g=float(scene.gravity))


def torsion_linear_period(tp: reduced.TorsionParams) -> float:
    """Closed form T0 = 2 pi sqrt(4 H0 Izz / (m g b b')), s (thesis 5.2.17 for b = b')."""
    return float(2 * np.pi * np.sqrt(4 * tp.H0 * tp.Izz / (tp.m * tp.g * tp.b * tp.bp)))


def torsion_kappa(tp: reduced.TorsionParams) -> float:
    """kappa in T(A) = T0 (1 + kappa A^2 + O(A^4)), 1/rad^2, of the exact
    1-DOF torsion model.

    With V = m g z(theta), z = c theta^2 / (4 H0) + (c^2 / (32 H0^3) - c / (48 H0)) theta^4,
    and M = Izz (1 + mu theta^2), mu = m c^2 / (4 H0^2 Izz): the quartic
    potential term shifts the frequency by 3 beta A^2 / (2 K) (Duffing,
    K = m g c / (2 H0), beta the theta^4 coefficient) and the growing
    inertia by -mu A^2 / 4; the period by minus their sum.
    """
    c, H0 = tp.c, tp.H0
    return float(1.0 / 16.0 - 3.0 * c / (32.0 * H0**2) + tp.m * c**2 / (16.0 * H0**2 * tp.Izz))


def torsion_kappa_scale(tp: reduced.TorsionParams) -> float:
    """S = 1/16 + 3 c / (32 H0^2) + m c^2 / (16 H0^2 Izz), 1/rad^2: the sum of
    the magnitudes of kappa's terms, the scale of the higher-order terms."""
    c, H0 = tp.c, tp.H0
    return float(1.0 / 16.0 + 3.0 * c / (32.0 * H0**2) + tp.m * c**2 / (16.0 * H0**2 * tp.Izz))


def closed_form_error(tp: reduced.TorsionParams, amplitude: float) -> float:
    """Estimated relative error of :func:`torsion_linear_period` at
    ``amplitude`` (rad): 1.25 |kappa| A^2 + 4 S^2 A^4; inf where S A^2 > 0.1."""
    A = abs(float(amplitude))
    S = torsion_kappa_scale(tp)
    if S * A**2 > CLOSED_FORM_MAX_SA2:
        return float("inf")
    return KAPPA_SAFETY * abs(torsion_kappa(tp)) * A**2 + QUARTIC_SAFETY * S**2 * A**4 + 1e-15


# --------------------------------------------------------------------------
# rung 3: linear period and its backbone estimate
# --------------------------------------------------------------------------
_GL_X, _GL_W = np.polynomial.legendre.leggauss(20)
_PHI = 0.25 * np.pi * (_GL_X + 1.0)  # nodes on [0, pi/2]
_PHI_W = 0.25 * np.pi * _GL_W


def _path(scene: Scene, rest: RestPose, md: Mode, s: np.ndarray):
    """Projected displaced poses (com (k,3), R (k,3,3)) at mode coordinates s (k,):
    what :func:`~bifilar.analysis.simulate.initial_state` builds for amplitude s."""
    sp = start_poses([scene] * len(s), [rest] * len(s), [md] * len(s), s)
    return sp.com, sp.R


def _potential(scene: Scene, rest: RestPose, com: np.ndarray) -> np.ndarray:
    return scene.mass * scene.gravity * (com[..., 2] - rest.com[2])


def backbone_period(scene: Scene, rest: RestPose, md: Mode, amplitude: float) -> float:
    """Period (s) of the 1-DOF conservative motion along the curve of
    projected displaced poses s -> initial_state(s), from s = amplitude to the
    turning point on the other side (where m g z is the same) and back:
    T = 2 int sqrt(mu(s) / (2 (V(A) - V(s)))) ds, mu the kinetic metric of the
    full model along the curve (mass and world inertia, tangent by central
    differences), V = m g z_com; s = A sin(phi) on each side removes the
    endpoint singularities (20-point Gauss-Legendre per side).

    For small amplitudes, where the potential differences approach rounding,
    the shift T - T_lin is computed at a reference amplitude (0.02 rad, or
    0.02 L_max for a translation) and scaled by (A / A_ref)^2, its leading
    order."""
    A = float(amplitude)
    scale = 1.0 if md.dominant >= 3 else float(np.max(scene.lengths))
    A_ref = 0.02 * scale
    if abs(A) < A_ref:
        T_ref = backbone_period(scene, rest, md, np.copysign(A_ref, A if A != 0 else 1.0))
        return float(md.period + (T_ref - md.period) * (A / A_ref) ** 2)
    com, _ = _path(scene, rest, md, np.array([A, -A]))
    V = _potential(scene, rest, com)
    E = V[0]
    Ap = -A  # turning point on the other side: V(Ap) = E (secant from the symmetric guess)
    if abs(V[1] - E) > 1e-13 * abs(E):
        x0, f0 = -A, V[1] - E
        x1 = -A * (1 + 1e-3)
        f1 = _potential(scene, rest, _path(scene, rest, md, np.array([x1]))[0])[0] - E
        for _ in range(30):
            if f1 == f0:
                break
            x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
            x0, f0, x1 = x1, f1, x2
            f1 = _potential(scene, rest, _path(scene, rest, md, np.array([x1]))[0])[0] - E
            if abs(x1 - x0) < 1e-14 * abs(A):
                break
        Ap = x1
    delta = 1e-4 * abs(A)
    s = np.concatenate([A * np.sin(_PHI), Ap * np.sin(_PHI)])
    k = len(s)
    com, R = _path(scene, rest, md, np.concatenate([s, s + delta, s - delta]))
    V = _potential(scene, rest, com[:k])
    dr = (com[k:2 * k] - com[2 * k:]) / (2 * delta)
    Rr = R[k:2 * k] @ np.swapaxes(R[2 * k:], 1, 2)  # small rotation: vee of its skew part (error O(theta^3))
    dth = 0.5 * np.stack([Rr[:, 2, 1] - Rr[:, 1, 2], Rr[:, 0, 2] - Rr[:, 2, 0], Rr[:, 1, 0] - Rr[:, 0, 1]], 1) \
        / (2 * delta)
    Iw = R[:k] @ scene.inertia @ np.swapaxes(R[:k], 1, 2)
    mu = scene.mass * np.sum(dr * dr, 1) + np.einsum("ki,kij,kj->k", dth, Iw, dth)
    gap = E - V
    if np.any(gap <= 0) or np.any(mu <= 0):
        raise ArithmeticError("backbone: the potential is not a well along the mode path")
    f = np.sqrt(mu / (2 * gap)) * np.cos(np.concatenate([_PHI, _PHI]))
    w = np.concatenate([_PHI_W * abs(A), _PHI_W * abs(Ap)])
    return float(2.0 * np.sum(w * f))


# --------------------------------------------------------------------------
# the ladder
# --------------------------------------------------------------------------
def period(scene: Scene, mode: str | int = "torsion", amplitude: float = 0.05, tol: float = 1e-6, *,
           rest: RestPose | None = None, modes: ModeSet | None = None, periods: float = 10.0) -> PeriodAnswer:
    """Period (s) of ``mode`` at ``amplitude`` from the cheapest adequate model.

    Returns a :class:`PeriodAnswer`, which unpacks as ``(period,
    model_used, est_error)``: ``est_error`` is the estimated relative error
    |T - T_full| / T_full against the full nonlinear model's measured period
    over ``periods`` periods; ``model_used`` one of :data:`RUNGS`.  ``tol``
    is the largest acceptable relative error (> 0).
    """
    if not (tol > 0 and np.isfinite(tol)):
        raise InputError("tol", f"must be a positive number, got {tol!r}")
    if not np.isfinite(amplitude):
        raise InputError("--amplitude", f"must be finite, got {amplitude!r}")
    A = abs(float(amplitude))
    tried: dict = {}
    tp = symmetric_torsion_params(scene) if mode in ("torsion",) else None
    if tp is not None:
        T0 = torsion_linear_period(tp)
        est = closed_form_error(tp, A)
        tried["closed-form"] = est
        if est <= tol:
            return PeriodAnswer(T0, "closed-form", est, tried)
        if QUADRATURE_ERROR <= tol and A < np.pi:
            try:
                T = reduced.torsion_period(tp, A, "exact")
            except InputError:
                T = None
            if T is not None:
                tried["reduced-1dof"] = QUADRATURE_ERROR
                return PeriodAnswer(float(T), "reduced-1dof", QUADRATURE_ERROR, tried)
    rest = rest or rest_pose(scene)
    modes = modes or linear_modes(scene, rest)
    md = bt._mode_of(modes, mode)
    if A == 0.0:
        return PeriodAnswer(float(md.period), "linear", 1e-13, tried)
    try:
        Tbb = backbone_period(scene, rest, md, A)
        est = BACKBONE_SAFETY * abs(Tbb - md.period) / md.period + 1e-13
    except (ArithmeticError, ValueError, np.linalg.LinAlgError, InputError):
        est = np.inf  # no estimate (e.g. the wires cannot follow the path that far): go on up the ladder
    if not np.isfinite(est):
        est = np.inf
    tried["linear"] = est
    if est <= tol:
        return PeriodAnswer(float(md.period), "linear", float(est), tried)
    rtol = float(np.clip(tol / 10.0, 1e-12, 1e-6))
    amp = A * (1.0 if amplitude >= 0 else -1.0)

    def run(rt):
        r = bt.run_one(scene, rest, md, amp, periods, rt, health=False, lowest_point=False)
        if r.period is None:
            raise InputError("--periods", "too few periods to measure a period; integrate longer")
        return r.period

    T1 = run(rtol)
    while True:
        rtol = max(rtol / 10.0, 1e-13)
        T2 = run(rtol)
        # The difference bounds T2's error only where the error falls tenfold a decade of rtol; it
        # need not (the l1 5 / l2 4.8 trapezoid's torsion at 0.05 rad: errors 6.5e-9 and 3.4e-9 at
        # rtol 1e-7 and 1e-8 under OpenBLAS's Sandybridge kernel, the difference 3.1e-9 below the
        # finer run's own error), so FULL_RTOL_ERROR times the finer run's rtol is added as the floor
        # of its error.
        est = abs(T1 - T2) / T2 + FULL_RTOL_ERROR * rtol + 1e-14
        if est <= tol or rtol <= 1e-13:
            break
        T1 = T2
    tried["full"] = est
    return PeriodAnswer(float(T2), "full", float(est), tried)
