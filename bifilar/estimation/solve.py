"""Solving the inversion: scalar root finding, Gauss-Newton least squares,
and the nonlinear model's amplitude-factor fixed point (where it does not
settle, :mod:`bifilar.estimation.nonlinear_roots`, whose names this module
re-exports).

Periods in s, inertia components in kg m^2, CoM shifts in m (see
:mod:`bifilar.estimation.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import BifilarError, ConvergenceError, InputError
from .problem import _IDX, HangingModel, Problem, admissible, physical_interval
# the amplitude runs (moved to their own module, re-exported here)
from .amplitude_runs import (IRREGULAR_REFUSE_SHARE, RUN_EVALUATIONS_PER_CYCLE, _stiff_message,  # noqa: F401
                             _unchecked_factor, amplitude_factor, irregular_difference, measured_factor,
                             measurement_run)
# the roots where the fixed point does not settle (moved to their own module, re-exported here)
from .nonlinear_roots import (FULL_MAP_ERRORS, FULL_MAP_SHARE, GAIN_RANGE, _contracted,  # noqa: F401
                              _model_tol, _refuse_unsettled, _settle_by_secant, _solve_full_scalar,
                              _unsettled_message, factor_gains)


def solve_scalar(T_of_x, target: float, x0: float, lo: float, hi: float, scale: float, fld: str, what: str,
                 rtol: float = 1e-12, xtol: float = 1e-15) -> float:
    """Solve ``T(x) = target`` (s) for ``x`` in ``(lo, hi)`` starting at ``x0``.

    Newton/secant on ``T^2 - target^2`` (close to linear in an inertia),
    kept inside the interval, until ``|T - target| <= rtol target``; once a
    sign change is bracketed, Brent's method to ``xtol`` times ``scale`` in
    ``x``.  Raises :class:`InputError` naming ``fld`` with the achievable
    range when no ``x`` gives ``target``.
    """
    from scipy.optimize import brentq

    memo: dict[float, float] = {}
    margin = 1e-9 * scale

    def f(x: float) -> float:
        if x not in memo:
            T = float(T_of_x(x))
            memo[x] = T * T - target * target if math.isfinite(T) else math.nan
        return memo[x]

    lo_m = lo + margin if math.isfinite(lo) else -math.inf
    hi_m = hi - margin if math.isfinite(hi) else math.inf
    x = min(max(x0, lo_m + margin), hi_m - margin) if math.isfinite(lo_m) or math.isfinite(hi_m) else x0
    fx = f(x)
    tol = 2 * rtol * target * target
    if not math.isfinite(fx):
        raise ConvergenceError(f"the model has no period for this mode at {what} = {x:.6g}")
    if abs(fx) <= tol:
        return x
    h = 1e-6 * scale
    xh = x - h if x + h >= hi_m else x + h
    d = (f(xh) - fx) / (xh - x)
    for _ in range(80):
        if d != 0 and math.isfinite(d):
            xn = x - fx / d
        else:
            xn = x + (10 * scale if fx < 0 else -10 * scale)
        # stay inside the interval; never jump more than 100 scales
        xn = min(max(xn, x - 100 * scale), x + 100 * scale)
        if xn <= lo_m:
            xn = x - 0.9 * (x - lo_m)
        if xn >= hi_m:
            xn = x + 0.9 * (hi_m - x)
        fn = f(xn)
        if not math.isfinite(fn):
            xn = 0.5 * (x + xn)
            fn = f(xn)
            if not math.isfinite(fn):
                break
        if abs(fn) <= tol:
            return xn
        if fn * fx < 0:
            a, b = (x, xn) if x < xn else (xn, x)
            return brentq(f, a, b, xtol=max(xtol * scale, 1e-300), rtol=4 * np.finfo(float).eps, maxiter=200)
        if xn == x:
            break
        d = (fn - fx) / (xn - x)
        x, fx = xn, fn
    raise InputError(fld, _range_message(T_of_x, target, x0, lo_m, hi_m, scale, what))


def _range_message(T_of_x, target, x0, lo, hi, scale, what) -> str:
    xs = []
    a = lo if math.isfinite(lo) else x0 - 1e3 * scale
    b = hi if math.isfinite(hi) else x0 + 1e4 * scale
    for x in np.concatenate([np.linspace(a, b, 41), [x0]]):
        try:
            T = float(T_of_x(float(x)))
        except BifilarError:
            continue
        if math.isfinite(T):
            xs.append((x, T))
    if not xs:
        return f"no {what} gives a period of {target:.6g} s for this mode"
    Ts = [t for _, t in xs]
    tmin, tmax = min(Ts), max(Ts)
    # a local search (the thesis rung, Monte Carlo re-estimates): the range
    # sampled, not a claim about values beyond it (roots.py scans the whole
    # physical interval for the answer itself)
    return (f"no {what} found that gives a period of {target:.9g} s: sampled with {what} from {a:.4g} to {b:.4g} "
            f"(the rest of the tensor at its prior), this mode's period ranges over {tmin:.9g} s .. {tmax:.9g} s")


@dataclass
class Estimate:
    p: np.ndarray
    method: str
    r: np.ndarray  # amplitude factors (1 when linear)
    iterations: int = 0
    sims: list = field(default_factory=list)
    laws: list = field(default_factory=list)  # AmplitudeLaw per measurement with an amplitude, else None
    #: further values of the one unknown the full nonlinear model reproduces the period at (found where the
    #: fixed point did not settle and the model was scanned: :func:`_solve_full_scalar`)
    other_roots: list = field(default_factory=list)


def _targets(pb: Problem, r: np.ndarray) -> np.ndarray:
    return np.array([m.period for m in pb.measurements]) / r


def solve_linear(pb: Problem, targets: np.ndarray | None = None, p0=None, physical: bool = False) -> np.ndarray:
    """Unknowns for which the linear periods equal ``targets`` (default: the
    measured periods): scalar root finding for one unknown and one period,
    else Gauss-Newton least squares (``physical``: among physical tensors
    only, continued along the edge of that set where it stops there, as
    :func:`~bifilar.estimation.roots.find_roots` finds an edge root)."""
    targets = np.array([m.period for m in pb.measurements]) if targets is None else targets
    p0 = pb.prior if p0 is None else np.asarray(p0, float)
    sc = pb.scales()
    if len(pb.unknowns) == 1 and len(pb.measurements) == 1:
        name = pb.unknowns[0]
        m = pb.measurements[0]
        if name in _IDX:
            lo, hi = physical_interval(pb.I_ref0, name)
        else:
            lo, hi = -math.inf, math.inf
        x = solve_scalar(lambda x: pb.linear_periods([x])[0], float(targets[0]), float(p0[0]), lo, hi,
                         float(sc[0]), m.field, name)
        return np.array([x])
    return gauss_newton(pb, targets, p0, admissible_only=physical)


def gauss_newton(pb: Problem, targets: np.ndarray, p0: np.ndarray, max_iter: int = 40, *,
                 admissible_only: bool = False, relabel: bool = False, known: list | None = None,
                 edge_refine: bool = True):
    """Weighted least squares ``min sum ((T_k(p) - target_k) / sigma_k)^2``.

    ``admissible_only``: keep every iterate physical (positive definite and
    the triangle inequality; default: positive definite only).  ``relabel``:
    re-decide the measured modes by label at every iterate
    (:func:`bifilar.estimation.roots.relabel`).  ``known``: solutions found
    already; returns None as soon as an iterate comes within 1e-6 scales of
    one (the same root again).  ``edge_refine``: where the iterates stop at
    the edge of the physical set, continue to the least-squares point along
    it (:func:`_edge_minimum`), and from there inside when the misfit falls
    that way."""
    from .roots import relabel as _relabel

    sig = np.array([m.std for m in pb.measurements])
    sc = pb.scales()
    p = np.asarray(p0, float).copy()
    ok_p = _admissible if admissible_only else _physical

    def cost(p):
        try:
            with np.errstate(over="ignore"):  # an absurd period overflows r @ r: inf, refused by the caller
                r = (pb.linear_periods(p) - targets) / sig
                return (float(r @ r) if np.all(np.isfinite(r)) else math.inf), r
        except BifilarError:
            return math.inf, None

    if relabel and not _relabel(pb, p):
        raise ConvergenceError("a measured mode's label is missing at the start point")
    c, res = cost(p)
    if not math.isfinite(c):
        raise ConvergenceError("the model has no period for a measured mode at the prior")
    for it in range(max_iter):
        if known and any(np.max(np.abs(p - q) / sc) < 1e-6 for q in known):
            return None
        J = pb.jacobian(p) / sig[:, None] * sc[None, :]
        _check_identifiable(pb, J)
        step = -np.linalg.lstsq(J, res, rcond=None)[0] * sc
        t = 1.0
        for _ in range(30):
            pn = p + t * step
            if ok_p(pb, pn):
                cn, rn = cost(pn)
                if cn <= c * (1 + 1e-12) or cn < 1e-24:
                    break
            t *= 0.5
        else:
            # the Gauss-Newton direction descends unless the misfit is at the
            # rounding floor of the periods (~1e-13 relative): converged; at
            # the edge of the admissible set no step inside lowers it
            if np.max(np.abs(step) / sc) < 1e-6 or admissible_only:
                break
            raise ConvergenceError("Gauss-Newton found no step that lowers the misfit")
        small = np.max(np.abs(t * step) / sc) < 1e-12
        p, c, res = pn, cn, rn
        if relabel and _relabel(pb, p):
            c, res = cost(p)
        if small:
            break
    if admissible_only and edge_refine and admissible_margin(pb, p) < EDGE_MARGIN:
        # stopped by the edge of the physical set, maybe not at its minimum
        # there: the least squares along the edge (one point, not wherever
        # each start first met the edge, each once reported as a root)
        pe = _edge_minimum(pb, cost, p, c, sc)
        if pe is not None:
            p = pe
            if relabel:
                _relabel(pb, p)
            n = _edge_normal(pb, p, sc)
            J = pb.jacobian(p) / sig[:, None] * sc[None, :]
            step = -np.linalg.lstsq(J, cost(p)[1], rcond=None)[0]
            if n is not None and n @ step > 0:
                # the misfit falls into the set: not a minimum of the physical
                # set but a way to one inside (found from there)
                return gauss_newton(pb, targets, p, max_iter, admissible_only=True, relabel=relabel, known=known,
                                    edge_refine=False)
    return p


#: an iterate this close to the edge of the physical set (relative margin) is on it
EDGE_MARGIN = 1e-6


def admissible_margin(pb: Problem, p) -> float:
    """How far the tensor at unknowns ``p`` is inside the physical set,
    relative to the largest prior moment: the smaller of its least
    eigenvalue and ``tr I / (2 - s) - I_max`` (the triangle inequality with
    the config loader's slack ``s``); negative outside.  Both are concave in
    ``p`` (the set is convex)."""
    from ..scene import TRIANGLE_SLACK

    ev = np.linalg.eigvalsh(pb.models[0].inertia_ref(pb.values(p)))
    scale = float(np.max(np.linalg.eigvalsh(pb.I_ref0)))
    return float(min(ev[0], ev.sum() / (2.0 - TRIANGLE_SLACK) - ev[-1]) / scale)


def _edge_minimum(pb: Problem, cost, p, c, sc, iters: int = 30, W=None):
    """The least-squares point of ``cost`` (misfit, residuals) along the edge
    of the physical set from ``p``, where Gauss-Newton stopped at it:
    Gauss-Newton steps in the edge's tangent plane (the normal ``n`` the
    gradient of :func:`admissible_margin`, in units of the scales ``sc``),
    each pulled back into the (convex) set along ``n`` and halved until the
    misfit drops.  None when no lower physical point is found.  ``W``:
    (K, K) the whitening matrix (1/s) of ``cost``'s residuals, ``W (T(p) -
    target)``; default ``diag(1 / sigma_timing)``."""
    W = np.diag(1.0 / np.array([m.std for m in pb.measurements])) if W is None else np.asarray(W, float)
    p = np.asarray(p, float)
    best = None
    for _ in range(iters):
        n = _edge_normal(pb, p, sc)
        if n is None:
            break
        N = np.linalg.svd(n[None, :])[2][1:].T  # (P, P - 1) tangent basis
        J = W @ pb.jacobian(p) * sc[None, :]
        res = cost(p)[1]
        if res is None or N.shape[1] == 0:
            break
        step = N @ -np.linalg.lstsq(J @ N, res, rcond=None)[0]
        t, moved = 1.0, False
        for _ in range(30):
            q = _pull_inside(pb, p + t * step * sc, n, sc)
            if q is not None:
                cq = cost(q)[0]
                if cq < c:
                    moved = True
                    break
            t *= 0.5
        if not moved:
            break
        small = np.max(np.abs(q - p) / sc) < 1e-12
        p, c, best = q, cq, q
        if small:
            break
    return best


def _edge_normal(pb: Problem, p, sc, h: float = 1e-7):
    """Unit inward normal of the physical set's edge at ``p`` (the gradient
    of :func:`admissible_margin` in units of the scales ``sc``, forward
    differences), or None where it vanishes."""
    m0 = admissible_margin(pb, p)
    n = np.array([(admissible_margin(pb, p + h * e * sc) - m0) / h for e in np.eye(len(p))])
    if not np.all(np.isfinite(n)) or not np.any(n):
        return None
    return n / np.linalg.norm(n)


def _pull_inside(pb: Problem, q, n, sc):
    """``q`` moved along the inward normal ``n`` (scaled units) by the least
    amount (bisection to 1e-12 of the scales) that makes it physical; None
    when 0.1 scales are not enough."""
    if _admissible(pb, q):
        return q
    lo, hi = 0.0, 1e-3
    while not _admissible(pb, q + hi * n * sc):
        hi *= 10
        if hi > 0.1:
            return None
    while hi - lo > 1e-12:
        mid = 0.5 * (lo + hi)
        if _admissible(pb, q + mid * n * sc):
            hi = mid
        else:
            lo = mid
    return q + hi * n * sc


def _admissible(pb: Problem, p) -> bool:
    return admissible(pb.models[0].inertia_ref(pb.values(p)))


def _physical(pb: Problem, p) -> bool:
    I = pb.models[0].inertia_ref(pb.values(p))
    return bool(np.linalg.eigvalsh(I)[0] > 0)


def _check_identifiable(pb: Problem, Js: np.ndarray) -> None:
    s = np.linalg.svd(Js, compute_uv=False)
    if s.size and (s[-1] <= 1e-9 * s[0] or not np.all(np.isfinite(s))):
        _, _, Vt = np.linalg.svd(Js)
        v = Vt[-1]
        worst = [pb.unknowns[i] for i in np.argsort(-np.abs(v))[:2]]
        raise InputError("--solve-for", f"the measured periods cannot separate {' and '.join(worst)} "
                                        "(their effects on the periods are (nearly) the same or zero): add "
                                        "modes or hangings that tell them apart, or solve for fewer components")


#: the stated amplitude's law is fitted through ``A`` and this fraction of it
#: (the draws about ``A`` with its 10 %: the slope at ``A`` is what matters)
STATED_LAW_RATIO = 0.9
#: an unstated release's law through ``A_max`` and this fraction of it (the
#: whole range 0 .. A_max matters)
RELEASE_LAW_RATIO = 0.5
#: relative step (of the unknown's scale) of the amplitude factor's derivative in the unknowns
FACTOR_STEP = 1e-4
#: the largest noise the runs' period error may put into the full model period's derivative ``r dT_lin/dp +
#: T_lin dr/dp``, as a share of ``|dT_lin/dp|`` (:func:`factor_step_rtol`): 1 % of the factor gain
FACTOR_GAIN_NOISE = 1e-2
#: the tightest rtol :func:`factor_step_rtol` asks for (below it the runs' periods stop converging: the
#: 6.4 cylinder's swing-y at 1e-12 still differs from its converged factor by ~1e-12)
FACTOR_RTOL_FLOOR = 1e-12


def factor_step_rtol(rtol: float, T_lin: float, dT_dp: float, h: float) -> float | None:
    """The rtol at which the forward difference ``dr/dp = (r(p + h) - r(p))
    / h`` of two amplitude runs is good enough for the factor gain, or None
    where ``rtol`` already is.  ``T_lin`` the mode's linear period (s),
    ``dT_dp`` its derivative in the unknown (s per unit of ``p``, the
    largest over the measurements that share the unknown), ``h`` the step
    (unit of ``p``).

    A run's relative period error is taken as at most its ``rtol``
    (measured 0.02-0.13 x rtol for LSODA at 1e-8, docs/design.md "drdi,
    session 13"), so the difference carries up to ``T_lin rtol / h`` of
    noise into ``T_lin dr/dp``; where that exceeds
    :data:`FACTOR_GAIN_NOISE` of ``|dT_dp|`` the two runs are made again at
    the rtol that brings it there (not below :data:`FACTOR_RTOL_FLOOR`).
    The 6.4 cylinder's Ixx (swing-y, ``Ixx`` barely moves the period): the
    sweep's runs (3 periods, rtol 1e-8) gave ``dr/dIxx`` = -1.7e-7, the
    converged value is 2.6e-10, and the factor gain 0.713 instead of
    1.0004 (sigma 313.7 kg m^2 against 223.7)."""
    if not dT_dp or not h:
        return None
    noise = T_lin * rtol / (h * abs(dT_dp))
    if not math.isfinite(noise) or noise <= FACTOR_GAIN_NOISE:
        return None
    return max(rtol * FACTOR_GAIN_NOISE / noise, FACTOR_RTOL_FLOOR)


#: the largest step (of the unknown's scale) :func:`factor_step` widens ``dr/dp``'s difference to, 100 x
#: :data:`FACTOR_STEP` (the 6.4 cylinder's ``dr/dIxx`` is the same, 2.6e-10, over 1e-3 and 1e-2 of the
#: largest moment: docs/design.md "gainnoise, session 13")
FACTOR_STEP_MAX = 1e-2
#: a widened step brings the bound at :data:`FACTOR_RTOL_FLOOR` this many times under
#: :data:`FACTOR_GAIN_NOISE`: at the floor a run's relative period error is up to ~rtol itself, not the
#: 0.02-0.13 x rtol of 1e-8 (a cylinder's Ixx at bound 1e-2 erred by 1.8e-2 in the gain; at 1e-3 by 6e-4)
FACTOR_FLOOR_MARGIN = 10.0


def factor_step(rtol: float, T_lin: float, dT_dp: float, h: float) -> tuple[float, float] | None:
    """(rtol, step) of the rerun pair whose forward difference gives
    ``dr/dp`` to :data:`FACTOR_GAIN_NOISE` of the factor gain, or None where
    the first runs (``rtol``, step ``h``) already do
    (:func:`factor_step_rtol`; ``T_lin`` s, ``dT_dp`` s per unit of ``p``,
    ``h`` and the step in the unit of ``p``).  Where even
    :data:`FACTOR_RTOL_FLOOR` leaves the bound ``T_lin rtol / (h |dT_dp|)``
    above it (a period that hardly moves with the unknown: invert accepts
    an unknown whose periods change by 1e-6 over its physical range, up to
    1.8 of its scale from the estimate, so the bound at the floor reaches
    ~2e-2 for a moment and 4e-2 for a CoM shift), the step is widened to
    bring it :data:`FACTOR_FLOOR_MARGIN` times under it, at most
    ``FACTOR_STEP_MAX / FACTOR_STEP`` times ``h``
    (beyond that, a raw bound above 1 at the floor, the gain keeps up to
    that noise: docs/design.md "gainnoise, session 13")."""
    tight = factor_step_rtol(rtol, T_lin, dT_dp, h)
    if tight is None:
        return None
    if tight > FACTOR_RTOL_FLOOR:
        return tight, h
    wide = FACTOR_FLOOR_MARGIN * T_lin * tight / (FACTOR_GAIN_NOISE * abs(dT_dp))
    return tight, min(max(h, wide), h * FACTOR_STEP_MAX / FACTOR_STEP)



@dataclass
class AmplitudeLaw:
    """The amplitude law of one mode, ``r(A) = T(A) / T_lin = 1 + a A^2 + b
    A^4`` (``A`` in the unit of ``--amplitude``: the mode's normalised
    shape, rad or m), fitted exactly through ``r`` simulated at ``A0`` and
    at ``lam A0`` (:func:`amplitude_law`), and (for a stated amplitude) the
    factor's derivative in the unknowns at ``A0``.

    Why even powers: the period of a conservative oscillation depends on
    the square of its amplitude (the Lindstedt series).  Why two simulated
    amplitudes and not the quadratic rule ``dT/dA = 2 T_lin (r - 1) / A``
    (the law with ``b = 0``): the lengthening grows faster than ``A^2``
    where a large amplitude or a nearby mode makes higher terms count (the
    Solar Boat at spacing 1, length 2, torsion at 0.3 rad: the quadratic
    slope is 0.91 of the one finite differences give).  Why ``lam``: with
    ``r(0) = 1`` the two points fix the even quartic; for a stated amplitude
    ``lam`` = :data:`STATED_LAW_RATIO` (0.9: the slope at ``A0``, where the
    draws about it lie, within 1.3 % of finite differences in that worst
    case against 4.5 % for 0.5), for the unstated release's range 0 .. A0
    :data:`RELEASE_LAW_RATIO` (0.5: the law over the whole range).  Tested
    against directly simulated amplitudes (tests/test_amplitude_law.py)."""

    amplitude: float  # A0, where r was simulated
    a: float  # 1 / unit^2
    b: float  # 1 / unit^4
    #: d r(A0) / d p (P,) per unit of each unknown (a stated amplitude's law; None otherwise)
    dr_dp: np.ndarray | None = None
    #: s: the largest difference a check run found where the measurement's amplitude runs at the estimate (the
    #: factor's, the law's, the derivative's) are not a regular motion (:func:`irregular_difference`); 0 otherwise
    irregular: float = 0.0
    #: {input key: d r(A0) / d x per SI unit} of the budgeted inputs (a stated amplitude's law, once the
    #: budget has measured it: :func:`~bifilar.estimation.factor_inputs.factor_input_derivatives`; None before)
    dr_dx: dict | None = None
    #: input keys whose ``dr/dx`` could not be measured (their stepped run failed: left at 0)
    dr_dx_failed: list = field(default_factory=list)
    #: {input key: the exact route that gave its ``dr/dx`` without a run} (``gravity``, ``translation``,
    #: ``com``, ``scaling``: :func:`~bifilar.estimation.factor_inputs._factor_routes`)
    dr_dx_derived: dict = field(default_factory=dict)
    #: s: the model period's std from the uncertainty of the second mode a recording's release started
    #: (:attr:`Measurement.secondary`: the shift it makes, which goes as its amplitude squared); 0 without one
    secondary_std: float = 0.0
    #: s: the model period's std from the modes a recording's release may have started unseen
    #: (:attr:`Measurement.hidden`, :func:`~bifilar.estimation.signal_swing.hidden_shift_std`); 0 without them
    hidden_std: float = 0.0
    #: s: the model period's std from the other reading of a recording's tone (several modes within the release
    #: bound, :attr:`~bifilar.estimation.signal_swing.Secondary.joint`,
    #: :func:`~bifilar.estimation.signal_swing.joint_reading_std`); 0 without one
    reading_std: float = 0.0

    def factor(self, A) -> np.ndarray | float:
        """r(A) (dimensionless; array in, array out)."""
        A2 = np.square(A)
        return 1.0 + self.a * A2 + self.b * A2 * A2

    def slope(self, A: float | None = None) -> float:
        """dr/dA at ``A`` (default A0), 1 / unit; ``dT/dA = T_lin dr/dA``."""
        A = self.amplitude if A is None else A
        return float(2.0 * self.a * A + 4.0 * self.b * A ** 3)

    @property
    def quartic_share(self) -> float:
        """``x = b A0^4 / (a A0^2)``: the quartic term's size against the
        quadratic one at A0 (0 for a quadratic law; inf when ``a`` = 0); the
        slope is the quadratic rule's times ``(1 + 2 x) / (1 + x)``."""
        q = self.a * self.amplitude ** 2
        return float(self.b * self.amplitude ** 4 / q) if q else math.inf

    def _quartic_fraction(self) -> float:
        q = self.b * self.amplitude ** 4
        tot = self.a * self.amplitude ** 2 + q
        return q / tot if tot else 0.0

    def release_weight(self, u) -> np.ndarray | float:
        """``w = (r(A) - 1) / (r(A0) - 1)`` as a function of ``u = (A /
        A0)^2`` (``u`` itself for a quadratic law)."""
        c = self._quartic_fraction()
        return (1.0 - c) * u + c * np.square(u)

    def release_moments(self) -> tuple[float, float]:
        """(mean, std) of :meth:`release_weight` for a release amplitude
        uniform in 0 .. A0 (``u = (A/A0)^2``: ``E[u^k] = 1 / (2k + 1)``;
        quadratic law: 1/3 and 2/sqrt(45))."""
        c = self._quartic_fraction()
        m = (1.0 - c) / 3.0 + c / 5.0
        m2 = (1.0 - c) ** 2 / 5.0 + 2.0 * c * (1.0 - c) / 7.0 + c * c / 9.0
        return m, math.sqrt(max(m2 - m * m, 0.0))


def amplitude_law(A: float, r_A: float, lam: float, r_lam: float, dr_dp=None) -> AmplitudeLaw:
    """The :class:`AmplitudeLaw` through ``r(A) = r_A`` and ``r(lam A) =
    r_lam`` (amplitude factors simulated at those release amplitudes, ``A``
    rad or m, nonzero; ``0 < lam``, ``lam != 1``)."""
    A2, l2 = A * A, lam * lam
    d1, d2 = r_A - 1.0, r_lam - 1.0
    # d1 = a A^2 + b A^4, d2 = a l2 A^2 + b l2^2 A^4
    b = (d2 - l2 * d1) / (l2 * (l2 - 1.0) * A2 * A2)
    a = (d1 - b * A2 * A2) / A2
    return AmplitudeLaw(float(A), float(a), float(b), None if dr_dp is None else np.asarray(dr_dp, float))


def amplitude_law_at(hm: HangingModel, values: dict, mode_index: int, amplitude: float, cycles: float,
                     rtol: float = 1e-10, r_A: float | None = None, lam: float = RELEASE_LAW_RATIO,
                     fundamental: bool = False) -> AmplitudeLaw:
    """The :class:`AmplitudeLaw` of base mode ``mode_index`` at ``values``
    from runs at ``amplitude`` (skipped when its factor ``r_A`` is given)
    and at ``lam`` times it, each for ``cycles`` linear periods at ``rtol``
    (:func:`amplitude_factor`, with ``fundamental``)."""
    if r_A is None:
        r_A, _ = amplitude_factor(hm, values, mode_index, amplitude, cycles, rtol, fundamental=fundamental)
    r_lam, _ = amplitude_factor(hm, values, mode_index, lam * amplitude, cycles, rtol, fundamental=fundamental)
    return amplitude_law(amplitude, r_A, lam, r_lam)


def stated_amplitude_law(pb: Problem, p, k: int, r_A: float, rtol: float = 1e-10,
                         irregular: float = 0.0) -> AmplitudeLaw:
    """The law of measurement ``k`` (a stated amplitude) at the unknowns
    ``p`` for the budget: the slope from a run at :data:`STATED_LAW_RATIO`
    of the amplitude, and ``dr/dp`` by forward differences (one run per
    unknown, step :data:`FACTOR_STEP` of its scale).  The nonlinear rung's
    model period is ``T_lin(p) r(A; p)``: its derivative in the unknowns is
    ``r dT_lin/dp + T_lin dr/dp``, and the second term is not small where
    the amplitude factor depends on the body (the Solar Boat's torsion at
    spacing 2.5, 0.6 rad: 0.29 of the first, opposite sign).  ``r_A``: the
    factor at ``p`` (simulated already; ``irregular`` its run's
    :func:`irregular_difference`, s).  Each run ``m.cycles`` periods at
    ``rtol``, checked as :func:`measured_factor` does (``law.irregular``:
    the largest difference)."""
    m = pb.measurements[k]
    r_lam, _, d = measured_factor(pb, k, p, rtol, STATED_LAW_RATIO * m.amplitude)
    law = amplitude_law(m.amplitude, r_A, STATED_LAW_RATIO, r_lam)
    irregular = max(irregular, d)
    sc = pb.scales()
    dr = np.zeros(len(p))
    T_lin, dT = pb.linear_periods(p)[k], np.max(np.abs(pb.jacobian(p)), axis=0)
    for j in range(len(p)):
        q = np.array(p, float)
        h = FACTOR_STEP * sc[j]
        q[j] += h
        r_q, _, d = measured_factor(pb, k, q, rtol)
        dr[j] = (r_q - r_A) / h
        irregular = max(irregular, d)
        redo = factor_step(rtol, T_lin, dT[j], h)
        if redo is not None:  # the runs' period error would show in the gain: both again at a tighter rtol
            tight, wide = redo  # (and over a wider step where the floor's rtol alone cannot bound it)
            q[j] = p[j] + wide
            dr[j] = (_unchecked_factor(pb, k, q, tight) - _unchecked_factor(pb, k, p, tight)) / wide
    law.dr_dp = dr
    law.irregular = irregular
    sec = getattr(m, "secondary", None)
    if sec is not None:
        # the second mode's part of the model period, and its std from the amplitude's (the shift ~ a^2)
        r_alone, _ = measurement_run(pb, k, p, rtol, second=None)
        sec.shift = float(pb.linear_periods(p)[k] * (r_A - r_alone))
        sec.shift_std = 2.0 * abs(sec.shift) * sec.amplitude_std / abs(sec.amplitude)
        law.secondary_std = sec.shift_std
    else:
        r_alone = r_A
    if getattr(m, "hidden", None):
        law.hidden_std = _hidden_shifts(pb, p, k, r_alone, rtol)
    if sec is not None and sec.joint is not None:
        from .signal_swing import joint_reading_std

        law.reading_std = joint_reading_std(m)
    return law


def _hidden_shifts(pb: Problem, p, k: int, r_alone: float, rtol: float) -> float:
    """Set the period shift (s) of each mode measurement ``k``'s recording
    may hide (:attr:`Measurement.hidden`) at the unknowns ``p``: one run of
    the timed mode released with it at its bound (:func:`amplitude_factor`,
    as the measurement's own runs, ``rtol``), less the timed mode's release
    alone (factor ``r_alone``); a run that fails leaves that shift None.
    Returns the shifts' budgeted std, s
    (:func:`~bifilar.estimation.signal_swing.hidden_shift_std`).  The second
    mode the record showed, if any, is left out of these runs: each hidden
    mode's shift adds to its at fourth order in the amplitudes."""
    from .signal_swing import hidden_shift_std

    m = pb.measurements[k]
    T_lin = float(pb.linear_periods(p)[k])
    for h in m.hidden:
        try:
            r_h, _ = measurement_run(pb, k, p, rtol, second=(h.index, h.amplitude))
            h.shift = float(T_lin * (r_h - r_alone))
        except BifilarError:
            h.shift = None
    return hidden_shift_std(m.hidden)


def solve_nonlinear(pb: Problem, p_lin: np.ndarray, rtol: float = 1e-10, tol: float = 1e-9,
                    max_sims: int = 6, progress=None, physical: bool = False) -> Estimate:
    """Fixed point ``p = solve_linear(T_meas / r(p))`` with the amplitude
    factors ``r`` simulated at each iterate (measurements without an
    amplitude keep r = 1); then the amplitude law of each measurement with
    an amplitude (:func:`stated_amplitude_law` at the last iterate: 1 + P
    more runs), whose slope and ``dr/dp`` the budget uses.  Every run is
    checked against the measured period's std (:func:`measured_factor`): a
    motion that is not regular is refused above a tenth of it, below it its
    difference is the law's ``irregular``, a budget term; a fixed point that
    does not settle where its runs were not regular is refused
    (:func:`_refuse_unsettled`).  Where the runs were regular, one unknown
    from one period is then solved on the full model
    (:func:`_solve_full_scalar`), several are refused the same way.
    ``physical``: the linear solves keep to physical tensors (the linear
    root ``p_lin`` lies on the edge of the physical set: no physical tensor
    reproduces the periods, and an unconstrained step from the edge may find
    no lower misfit where the tensor stays positive definite)."""
    K = len(pb.measurements)
    r = np.ones(K)
    p = np.asarray(p_lin, float)
    sc = pb.scales()
    sims = [None] * K
    irregular = np.zeros(K)  # s, per measurement (irregular_difference of the latest iterate's run)
    seen = np.zeros(K)  # s, the largest over the iterates
    it = 0
    p_at = p
    done = False
    scalar = K == 1 and len(p) == 1 and bool(pb.measurements[0].amplitude)
    runs: dict = {}  # one unknown: {x: measured_factor's (r, run, difference)} of every iterate
    other: list = []  # further roots of the full model (one unknown, where the fixed point did not settle)
    steps: list = []  # one unknown: (p, its fixed-point image) of every iterate
    for it in range(1, max_sims + 1):
        p_at = p  # where r is simulated
        for k, m in enumerate(pb.measurements):
            if m.amplitude:
                r[k], sims[k], irregular[k] = measured_factor(pb, k, p, rtol)
                seen[k] = max(seen[k], irregular[k])
                if scalar:
                    runs[float(p[0])] = (r[k], sims[k], irregular[k])
            if progress:
                progress(it - 1 + (k + 1) / K, 3)
        try:
            pn = solve_linear(pb, _targets(pb, r), p0=p, physical=physical)
        except BifilarError as exc:
            if not np.any(seen > 0):
                if scalar:
                    break  # a factor from far off took the target out of the linear model's reach: the full model
                raise
            # the factor of a motion that is not regular took the targets out of reach (the Solar Boat's
            # swing-y at 1.7 m, rtol 1e-11: r = 1.25 at Ixx = 129, "no Ixx gives 2.998 s", a period never measured)
            k = int(np.argmax(seen))
            raise InputError(pb.measurements[k].field, _unsettled_message(
                pb.measurements[k], seen[k], f"the fixed point T = T_lin r left the periods the model reaches ({exc})"
            )) from None
        done = np.max(np.abs(pn - p) / sc) < tol
        steps.append((p, pn))
        p = pn
        if done:
            break
    if not done and not np.any(seen > 0) and _contracted(pb, steps, r):
        done = True  # as before session 11: the last iterate, within a tenth of the std of the fixed point
    if not done and not scalar and len(p) == 1 and not np.any(seen > 0) and len(steps) >= 2:
        settled = _settle_by_secant(pb, steps, rtol)
        if settled is not None:
            p_at, p, r, sims, irregular = settled
            seen = np.maximum(seen, irregular)
            done = True
    if not done and np.any(seen > 0):
        _refuse_unsettled(pb, p, p_at, r, seen, max_sims)
    if not done and scalar:
        found = _solve_full_scalar(pb, p_at, rtol, runs)
    if not done and scalar and found is not None:
        # the root nearest the linear model's (where the fixed point started); the others are named
        i = int(np.argmin([abs(float(q[0][0]) - float(p_lin[0])) for q in found]))
        p_at, r[0], sims[0], irregular[0] = found[i]
        other = [float(q[0][0]) for j, q in enumerate(found) if j != i]
        seen[0] = max(seen[0], irregular[0])
        # the linear solve with the root's factor, as the fixed point ends (within the run's noise of the root)
        p = solve_linear(pb, _targets(pb, r), p0=p_at, physical=physical)
    elif not done and not scalar:
        _refuse_unsettled(pb, p, p_at, r, seen, max_sims)
    laws = [stated_amplitude_law(pb, p_at, k, r[k], rtol, irregular[k]) if m.amplitude else None
            for k, m in enumerate(pb.measurements)]
    return Estimate(p, "nonlinear", r.copy(), it, sims, laws, other)
