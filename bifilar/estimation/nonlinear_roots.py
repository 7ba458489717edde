"""The nonlinear model's roots where the amplitude-factor fixed point of
:func:`~bifilar.estimation.solve.solve_nonlinear` does not settle: the
fixed point's contraction test (:func:`_contracted`), secant steps on its
map for one unknown from several periods (:func:`_settle_by_secant`), the
full model's roots for one unknown from one period
(:func:`_solve_full_scalar`), the refusals where none of that settles
(:func:`_refuse_unsettled`), and the gain of the factor at an estimate
(:func:`factor_gains`).

Periods in s, inertia components in kg m^2, CoM shifts in m (see
:mod:`bifilar.estimation.problem`).  Moved unchanged out of
:mod:`bifilar.estimation.solve` (which re-exports every name); the solver's
own functions (:func:`~bifilar.estimation.solve.measured_factor`,
:func:`~bifilar.estimation.solve.solve_scalar`,
:func:`~bifilar.estimation.solve.solve_linear`) are imported where called,
as solve.py imports this module.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..errors import BifilarError, InputError
from .problem import _IDX, Problem, admissible_interval, physical_interval

if TYPE_CHECKING:
    from .solve import Estimate


#: the gain ``g = d(T_lin r)/dp / (r dT_lin/dp)`` of one unknown outside this range warns (:func:`factor_gains`):
#: at or below 0 the nonlinear model's period turns back (other values reproduce it), near 0 it barely follows
#: the unknown, from 2 on the factor moves the period faster than the linear model (the fixed point no longer
#: contracts); the shipped configs' realistic releases give 0.2 (the thesis plate's torsion at 1.2 rad, its
#: reach) to 1.7 (the Solar Boat's swing-y at 1.0 m, Ixx 20 % above its own)
GAIN_RANGE = (0.1, 2.0)


def factor_gains(pb: Problem, est: Estimate) -> list:
    """Per measurement, ``g = 1 + T_lin dr/dp / (r dT_lin/dp)`` at the
    nonlinear estimate ``est`` of one unknown (None for several unknowns or
    a measurement without a stated amplitude's law): the slope of the full
    model's period ``T_lin r`` in the unknown over the linear one's, from
    the law's ``dr/dp`` (no run added)."""
    if len(pb.unknowns) != 1:
        return [None] * len(pb.measurements)
    p = np.asarray(est.p, float)
    T_lin = pb.linear_periods(p)
    dT = pb.jacobian(p)[:, 0]
    out = []
    for k, law in enumerate(est.laws):
        if law is None or law.dr_dp is None or not dT[k]:
            out.append(None)
        else:
            out.append(float(1.0 + T_lin[k] * law.dr_dp[0] / (est.r[k] * dT[k])))
    return out


def _refuse_unsettled(pb: Problem, p, p_at, r, seen, max_sims: int) -> None:
    """Raise :class:`InputError` where the fixed point of :func:`~bifilar.estimation.solve.solve_nonlinear`
    stopped after ``max_sims`` simulations at ``p`` (the factors ``r`` simulated
    at ``p_at``) with a measurement's model period still moving by more than
    :data:`~bifilar.estimation.solve.IRREGULAR_REFUSE_SHARE` of its std.  Where its runs were not a
    regular motion (``seen``: the largest check difference of each
    measurement, s) the factor is no smooth function of the body (the Solar
    Boat's swing-y at 1.7 m over 10 cycles: r 0.997, 0.993, 1.008, 1.026 at
    Ixx 83.14, 83.11, 86.2, 72.7), and the last iterate (there 50.6 against a
    truth of 83.1, 7 std off, every check passed) is no solution.  Where they
    were regular, the factor changes with the unknowns too fast for the fixed
    point (several unknowns; one unknown is solved on the full model instead,
    :func:`_solve_full_scalar`); its last iterate is no solution either: the
    fit check, made with the factors of ``p_at``, cannot see it."""
    from .solve import IRREGULAR_REFUSE_SHARE
    dT = np.abs(pb.linear_periods(p) - pb.linear_periods(p_at)) * r
    for k, m in enumerate(pb.measurements):
        if dT[k] <= IRREGULAR_REFUSE_SHARE * m.std:
            continue
        why = (f"the fixed point T = T_lin r did not settle in {max_sims} simulations (its last step moved the model "
               f"period by {dT[k]:.1g} s, more than {IRREGULAR_REFUSE_SHARE:g} of the period's std {m.std:.1g} s)")
        if seen[k] > 0:
            raise InputError(m.field, _unsettled_message(m, seen[k], why))
        if m.amplitude:
            raise InputError(m.field, (
                f"mode '{m.label}' released at {m.amplitude:g}: {why}: its amplitude factor changes with the unknowns "
                "about as fast as the linear period or faster (near an internal resonance: the mode beats with "
                "another), so the estimate cannot be given; release at a smaller amplitude"))


def _unsettled_message(m, seen: float, why: str) -> str:
    """The refusal of :func:`_refuse_unsettled` for measurement ``m``: ``seen``
    its largest check difference (s), ``why`` what the fixed point did."""
    return (f"mode '{m.label}' released at {m.amplitude:g} over {m.cycles:g} cycles is not a regular motion near the "
            f"estimate: the nonlinear model's period is no smooth function of the body there (a second run from the "
            f"same start differed by up to {seen:.1g} s) and {why}, so the estimate cannot be given; time fewer "
            "cycles or release at a smaller amplitude")


#: the full model's equation ``T_lin(x) r(x) = T_meas`` of one unknown is solved to
#: this share of the period's std (the fixed point's own ~1e-9 of the scale is
#: not needed: each evaluation is a simulation), or to :data:`FULL_MAP_ERRORS` times
#: the run's own period error where that is larger (:func:`_model_tol`)
FULL_MAP_SHARE = 1e-3
FULL_MAP_ERRORS = 10.0


def _model_tol(m, sims) -> float:
    """The tolerance (s) on the full model's period of measurement ``m``
    (:data:`FULL_MAP_SHARE` of its std), at least :data:`FULL_MAP_ERRORS`
    times the largest ``period_error`` of the runs ``sims`` (a period timed
    to 1e-9 s is reproduced to the integration's ~1e-10 s, not 1e-12)."""
    errs = [float(getattr(sim, "period_error", math.nan)) for sim in sims if sim is not None]
    errs = [e for e in errs if math.isfinite(e)]
    return max(FULL_MAP_SHARE * m.std, FULL_MAP_ERRORS * max(errs, default=0.0))


def _solve_full_scalar(pb: Problem, p, rtol: float, runs: dict):
    """One unknown, one period with an amplitude, where the fixed point of
    :func:`~bifilar.estimation.solve.solve_nonlinear` did not settle: the roots of ``F(x) = T_lin(x)
    r(A; x) - T_meas`` on the full model, each evaluation one run of
    :func:`~bifilar.estimation.solve.measured_factor`: every sign change of ``F`` between the runs
    already made (``runs``: {x: (r, run, difference)}, the fixed point's
    iterates inside the unknown's admissible interval; it gains every
    evaluation) refined by Brent's method, kept where ``|F|`` ends within
    :data:`FULL_MAP_SHARE` of the period's std (else a jump of the factor:
    the timed coordinate of a beating mode passing from one to another);
    where none is, secant steps from ``p`` then Brent once bracketed
    (:func:`~bifilar.estimation.solve.solve_scalar`).  The fixed point ``x = T_lin^-1(T_meas /
    r(x))`` contracts only while the gain ``g = d(T_lin r)/dx / (r
    dT_lin/dx)`` lies in (0, 2): its error is multiplied by ``1 - g`` per
    simulation.  Near an internal resonance the factor moves faster (the
    Solar Boat's swing-y at 1.0 m with Ixx = 100: g = 1.7, six runs left
    Ixx 0.38 off, 4 timing std in the period; at 1.3 m with Ixx = 95: g =
    5.8, the iterates ran off to 117.8, 360 std).  Returns the roots
    ascending, each (x, r, run, irregular difference); None where none
    is found inside the physical set and the iterates left it (the root
    lies beyond its edge: the caller keeps the last iterate, which invert
    moves back to the edge and checks there); raises :class:`InputError`
    where none is found otherwise."""
    from scipy.optimize import brentq

    from .solve import measured_factor, solve_scalar

    m = pb.measurements[0]
    name = pb.unknowns[0]
    lo, hi = admissible_interval(pb.I_ref0, name) if name in _IDX else physical_interval(pb.I_ref0, name)
    sc = float(pb.scales()[0])

    def F(x: float) -> float:
        if x not in runs:
            runs[x] = measured_factor(pb, 0, np.array([x]), rtol)
        return float(pb.linear_periods([x])[0]) * runs[x][0] - m.period

    xs = sorted(x for x in runs if lo <= x <= hi)
    Fs = [F(x) for x in xs]

    def tol() -> float:
        return _model_tol(m, [v[1] for v in runs.values()])

    roots, jumps = [], []
    for i in range(len(xs) - 1):
        if Fs[i] * Fs[i + 1] < 0:
            x = brentq(F, xs[i], xs[i + 1], xtol=1e-9 * sc, rtol=4 * np.finfo(float).eps, maxiter=100)
            (roots if abs(F(x)) <= tol() else jumps).append(x)
    if not roots:
        what = f"{name} (the nonlinear model at amplitude {m.amplitude:g})"
        try:
            x = solve_scalar(lambda x: F(x) + m.period, m.period, float(p[0]), lo, hi, sc, m.field, what,
                             rtol=tol() / m.period, xtol=1e-9)
        except BifilarError:
            x = None
        if (x is None or abs(F(x)) > tol()) and any(not lo <= y <= hi for y in runs):
            # the iterates left the physical set (a thin plate's period lengthened beyond the edge): the last
            # iterate, which invert moves back to the edge and checks there
            return None
        if x is None or abs(F(x)) > tol():
            at = sorted(jumps + ([x] if x is not None else []))
            at = [a for i, a in enumerate(at) if i == 0 or abs(a - at[i - 1]) > 1e-6 * sc]  # the search re-finds one
            jumped = f" (its period jumps across the measured one at {name} = {', '.join(f'{j:.6g}' for j in at)})" if at else ""
            raise InputError(m.field, (
                f"mode '{m.label}' released at {m.amplitude:g}: the fixed point T = T_lin r did not settle and "
                f"the search on the full nonlinear model found no {name} that reproduces the period "
                f"{m.period:.9g} s{jumped}: near an internal resonance (the mode beats with another) that period "
                f"is no monotonic, continuous function of {name}, so the estimate cannot be given; release at a "
                "smaller amplitude"))
        roots = [x]
    return [(np.array([x]), *runs[x]) for x in sorted(roots)]


def _contracted(pb: Problem, steps: list, r) -> bool:
    """Whether the fixed point's iterates ``steps`` ((p, image) pairs; one
    unknown, the factors ``r`` of the last) have settled within
    :data:`~bifilar.estimation.solve.IRREGULAR_REFUSE_SHARE` of every period's std: the last step's
    move of the model periods times ``c / (1 - c)``, the error left by a
    contraction ``c`` (the last step over the one before) that stays below
    1.  A gain near 1 (``c`` ~ 0) settles in a few runs; the Solar Boat's
    torsion at spacing 2.5, 0.6 rad (g = 0.7, c = 0.3) left ~6e-4 of the
    first step after six, taken before session 11 and still."""
    from .solve import IRREGULAR_REFUSE_SHARE
    if len(steps) < 2 or len(pb.unknowns) != 1:
        return False
    (a0, b0), (a1, b1) = steps[-2:]
    d0, d1 = float(b0[0] - a0[0]), float(b1[0] - a1[0])
    if not d0 or abs(d1) >= abs(d0):
        return False
    c = abs(d1 / d0)
    left = np.abs(pb.linear_periods(b1) - pb.linear_periods(a1)) * r * c / (1.0 - c)
    return bool(np.all(left <= IRREGULAR_REFUSE_SHARE * np.array([m.std for m in pb.measurements])))


def _settle_by_secant(pb: Problem, steps: list, rtol: float, max_more: int = 8):
    """One unknown from several periods, where the fixed point ``x ->
    Phi(x)`` of :func:`~bifilar.estimation.solve.solve_nonlinear` (``Phi``: the linear model's fit to
    ``T_meas / r(x)``) did not settle: secant steps on ``Phi(x) - x`` from
    its last two iterates (``steps``: (x, Phi(x)) pairs), which converge
    where the fixed point's gain lies outside (0, 2), at most ``max_more``
    more evaluations (each one run per measurement with an amplitude),
    until ``Phi`` moves the model periods by under :data:`FULL_MAP_SHARE`
    of their std.  Returns (x, Phi(x), r, runs, irregular differences), or
    None (then refused by :func:`_refuse_unsettled`)."""
    from .solve import _targets, measured_factor, solve_linear
    K = len(pb.measurements)
    lo, hi = admissible_interval(pb.I_ref0, pb.unknowns[0]) if pb.unknowns[0] in _IDX else (-math.inf, math.inf)
    (x0, f0), (x1, f1) = [(float(a[0]), float(b[0]) - float(a[0])) for a, b in steps[-2:]]
    for _ in range(max_more):
        if f1 == f0 or not math.isfinite(f1 - f0):
            return None
        x = x1 - f1 * (x1 - x0) / (f1 - f0)
        x = min(max(x, lo + 1e-9 * (hi - lo)), hi - 1e-9 * (hi - lo)) if math.isfinite(hi - lo) else x
        r = np.ones(K)
        sims, irr = [None] * K, np.zeros(K)
        for k, m in enumerate(pb.measurements):
            if m.amplitude:
                r[k], sims[k], irr[k] = measured_factor(pb, k, np.array([x]), rtol)
        if np.any(irr > 0):
            return None
        try:
            px = solve_linear(pb, _targets(pb, r), p0=np.array([x]))
        except BifilarError:
            return None
        dT = np.abs(pb.linear_periods(px) - pb.linear_periods([x])) * r
        if all(dT[k] <= _model_tol(m, sims) for k, m in enumerate(pb.measurements)):
            return np.array([x]), px, r, sims, irr
        (x0, f0), (x1, f1) = (x1, f1), (x, float(px[0]) - x)
    return None
