"""A decaying recording whose frequency follows its envelope's square:
the ``viscous+chirp`` amplitude law (``omega = w + beta u + beta2 u^2``,
``u = (A / A0)^2``), tried when a viscous fit's halves disagree and used
only when it explains them (:func:`_amplitude_law`), fitted jointly with
the other oscillations its residuals keep (:func:`_with_other_oscillations`).
SI units (time s, frequency rad/s); samples in the recording's own unit.
Split from :mod:`bifilar.estimation.signal`.
"""

from __future__ import annotations

import math

import numpy as np

from .signal_checks import residual_peaks
from .signal_io import SignalError
from .signal_models import _fit_chirp, _linear_amplitudes, _solve
from .signal_result import PeriodFit, _build
from .signal_windows import _KIND, AMPLITUDE_LAW_MODEL, _inadmissible, _residual_peaks, _stationarity


#: a law ``T = T0 (1 + c A^2 + d A^4)`` is a pendulum's when ``d / c^2`` lies
#: in this range (a simple pendulum 0.92; a period linear in ``A^2`` 0; a
#: frequency linear in it 1): the fit's ``beta2 w / beta^2 = 1 - d / c^2``
#: must lie in ``1 - range`` within 3 of its std.  A drift in time fitted
#: as a law of the decaying amplitude needs ``|d / c^2|`` of tens
AMPLITUDE_LAW_D_RANGE = (-1.0, 2.0)


#: an oscillation left in the amplitude law's residuals is fitted with the
#: law when it lies at least this many periodogram bins (1 / record length)
#: from the fundamental and from zero
OTHER_BINS = 3.0


#: ... and below this many times the fundamental frequency
OTHER_MAX_RATIO = 4.0


#: at most this many of them (the strongest), one solve each
OTHER_MAX = 3


def _with_other_oscillations(law: PeriodFit, t, y, drift: bool, key: str) -> PeriodFit:
    """The amplitude law's fit with the other oscillations its residuals
    keep (significant periodogram peaks that are neither the fundamental
    nor its harmonics: a coupled swing the release excites) fitted with it
    as damped cosines, when that lowers the criterion ``key`` (``bic`` /
    ``aic``).  Left in the residuals such a swing leaks into the law's
    frequency: on the damped trifilar of tests/test_chirp_coupled_swing.py
    it put the period at ``amplitude_period`` one std above the truth in
    every noise draw (docs/invert.md, "Signal audit, session 9")."""
    try:
        peaks = residual_peaks(t, law.residuals, law.frequency)
    except (ValueError, np.linalg.LinAlgError):
        return law
    T_rec = float(t[-1] - t[0])
    # separate oscillations of the rig only: a peak within OTHER_BINS
    # periodogram bins of the fundamental (or of zero) is the law's own
    # misfit, which a cosine there would absorb into the fundamental's
    # place; one above OTHER_MAX_RATIO times the fundamental (a sensor's
    # hum) leaks too little into it to matter
    sep, f0 = OTHER_BINS / T_rec, law.frequency
    fr = [pk["frequency"] for pk in peaks if pk["harmonic"] is None and sep < pk["frequency"] < OTHER_MAX_RATIO * f0
          and abs(pk["frequency"] - f0) > sep]
    t0, tm = law.t0, law.t_ref
    sg = float(law.params[5])
    best = law
    for f in fr[:OTHER_MAX]:  # strongest first, each kept when it lowers the criterion
        w = 2 * math.pi * f
        try:
            coef, _ = _linear_amplitudes(t, best.residuals, t0, tm, [w], [sg])
            p0 = np.r_[best.params, coef[2], coef[3], w, sg]
            free = np.ones(p0.size, bool)
            free[1] = drift
            joint = _build(_solve("chirp", t, y, t0, tm, p0, free, max_nfev_per_param=50), t, y,
                           AMPLITUDE_LAW_MODEL, [])
        except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError,
                ZeroDivisionError):
            continue
        if not (joint.converged and np.isfinite(joint.period) and getattr(joint, key) < getattr(best, key)):
            continue
        # each cosine stays the oscillation it was started at (within a bin)
        if any(abs(wj - w0) > 2 * math.pi / T_rec for wj, w0 in zip(joint.params[10::4], np.r_[best.params[10::4], w])):
            continue
        best = joint
    return best


def _shift_resolved(law: PeriodFit, t) -> tuple[bool, float, float]:
    """(resolved, shift, its std): the law's frequency shift over the record,
    ``omega(u = 1) - omega(u_end) = beta (1 - u_end) + beta2 (1 - u_end^2)``
    (rad/s; ``u_end = e^{-2 sigma T_rec}``, the envelope's square at the
    record's end), with its std from the covariance of ``beta`` and
    ``beta2`` (inflated as the law's stds are), resolved at 3 std.  Not
    ``beta`` alone: ``u`` and ``u^2`` over a record decaying to ``u_end ~
    0.4`` are nearly collinear, so ``beta``'s own std is many times the
    shift's (a quadcopter's torsion at 0.1 rad, Q 200, 30 cycles, a gyro
    at 200 Hz with noise 1 % of its amplitude: beta -0.0020 +- 0.0015
    rad/s, the shift -0.0012 +- 0.0001), and a law the record resolves
    was set aside for the halves' std, 35 times the period's error."""
    md = law.modes[0]
    sg, T_rec = float(law.params[5]), float(t[-1] - t[0])
    u_end = math.exp(-2.0 * sg * T_rec)
    g = np.array([1.0 - u_end, 1.0 - u_end ** 2 if md["beta2_std"] > 0 else 0.0])  # beta2 held: 0
    cov = np.asarray(law.covariance, float)[6:8, 6:8]
    raw_b = math.sqrt(max(float(cov[0, 0]), 0.0))
    infl = md["beta_std"] / raw_b if raw_b > 0 else 1.0
    shift = float(g[0] * md["beta"] + g[1] * md["beta2"])
    sd = float(math.sqrt(max(float(g @ cov @ g), 0.0)) * infl)
    return bool(abs(shift) >= 3 * sd), shift, sd


def _amplitude_law(fit: PeriodFit, t, y, criterion, n_general: int = 0) -> PeriodFit:
    """A viscous fit whose halves disagree (``std_nonstationary > 0``) is
    refitted with the frequency following the envelope's square
    (:data:`AMPLITUDE_LAW_MODEL`, :func:`.signal_models._fit_chirp`: a
    pendulum's ``T = T0 (1 + c A^2)`` as it decays).  The law replaces the
    fit only when it explains the halves' difference: its ``criterion``
    (BIC/AIC) is lower, and the split check on its own fit (each half
    fitted with the law held at the whole record's ``beta``, its period
    referred to the same amplitude) finds no disagreement beyond noise.
    The period is then the one at the amplitude the least-squares phase
    weights (``amplitude_period``, :func:`.signal_result.period_amplitude`)
    with the fit's own std.  A drift the law cannot explain (a period that
    changes with time, not with the amplitude) keeps the viscous fit and
    its between-half std.  ``fit.amplitude_law`` says which (``used``,
    ``reason``) and holds the law's numbers.  The law's fit keeps the
    first ``n_general`` notes of ``fit`` (the window's: trimming, a leading
    rest) and its runner-ups; the viscous fit's notes on itself are
    replaced by one line."""
    if fit.std_nonstationary <= 0 or _KIND.get(fit.model, ("",))[0] != "viscous":
        return fit
    drift = fit.selection.get("drift", True)
    t0, tm = float(t[0]), float(0.5 * (t[0] + t[-1]))
    key = criterion.lower()
    info: dict = {"used": False, "model": AMPLITUDE_LAW_MODEL, "criterion": criterion,
                  "without_law": {"model": fit.model, "period": fit.period,
                                  "std": math.hypot(fit.std, fit.std_nonstationary),  # before quantisation
                                  "std_nonstationary": fit.std_nonstationary,
                                  "half_periods": [list(h) for h in fit.half_periods or ()]}}
    fit.amplitude_law = info
    # the decay's white-noise std (the chirp's residuals inflate the serial factor)
    sg, sg_std = float(fit.params[5]), math.sqrt(max(float(fit.covariance[5, 5]), 0.0))
    if not sg > 3 * sg_std:
        info["reason"] = (f"the amplitude law was not tried: the envelope does not decay measurably (sigma = "
                          f"{sg:.3g} +- {sg_std:.2g} 1/s), so an amplitude law cannot be told from a drift")
        fit.notes.append(f"period changes along the record; {info['reason']}")
        return fit
    try:
        law = _build(_fit_chirp(t, y, t0, tm, fit.params, drift), t, y, AMPLITUDE_LAW_MODEL, [])
        # other oscillations only for a law that may be used (their solves cost)
        if getattr(law, key) < getattr(fit, key) and _shift_resolved(law, t)[0]:
            law = _with_other_oscillations(law, t, y, drift, key)
        law.selection["drift"] = bool(drift)
    except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError,
            ZeroDivisionError) as exc:
        info["reason"] = f"the amplitude law could not be fitted: {exc}"
        fit.notes.append(f"period changes along the record; {info['reason']}")
        return fit
    delta = float(getattr(law, key) - getattr(fit, key))
    md = law.modes[0]
    info.update(criterion_delta=delta, beta=md["beta"], beta_std=md["beta_std"], beta2=md["beta2"],
                beta2_std=md["beta2_std"],
                reference_amplitude=md["reference_amplitude"], period_zero_amplitude=md["period_zero_amplitude"],
                period_start=md["period_start"],
                other_oscillations=[{k: o[k] for k in ("frequency", "period", "amplitude", "damping_ratio")}
                                    for o in law.modes[1:]])
    why = _inadmissible(law)
    if why is None and not delta < 0:
        why = f"it does not lower {criterion} ({delta:+.1f})"
    resolved, shift, shift_std = _shift_resolved(law, t)
    info.update(shift=shift, shift_std=shift_std)
    if why is None and not resolved:
        why = (f"its frequency shift over the envelope ({shift:.3g} +- {shift_std:.2g} rad/s) is not "
               "resolved: too little decay to tell an amplitude law from a drift")
    if why is None:
        b, b2, s2 = md["beta"], md["beta2"], md["beta2_std"]
        unit = b * b / float(law.params[4])  # beta2 of a period linear in A^2
        lo, hi = (1.0 - AMPLITUDE_LAW_D_RANGE[1]) * unit, (1.0 - AMPLITUDE_LAW_D_RANGE[0]) * unit
        info["curvature_ratio"] = b2 / unit if unit > 0 else float("nan")
        if not (lo - 3 * s2 <= b2 <= hi + 3 * s2):
            why = (f"its A^4 term is {info['curvature_ratio']:.3g} x the square of its A^2 term's (1 - d/c^2 "
                   f"for T = T0 (1 + c A^2 + d A^4), a pendulum's within {1 - AMPLITUDE_LAW_D_RANGE[1]:g}.."
                   f"{1 - AMPLITUDE_LAW_D_RANGE[0]:g}): the period drifts along the record, not with the amplitude")
    if why is None:
        law.notes = []
        _stationarity(law, t, y)
        q = law.uncertainty.get("windows_test")
        if q is None:
            why = "its own split check could not be made"
        else:
            info.update(halves=[list(h) for h in law.half_periods], Q=q["Q"], critical_Q=q["critical_Q"])
            if law.std_nonstationary > 0:
                why = (f"its halves still disagree (Q = {q['Q']:.1f} > {q['critical_Q']:.1f}): the period "
                       "changes along the record by more than the amplitude explains")
    if why is not None:
        info["reason"] = f"the amplitude law was not used: {why}"
        fit.notes.append(f"period changes along the record; {info['reason']}; the between-half std stays")
        return fit
    info["used"] = True
    info["reason"] = (f"the halves' difference follows the envelope's square: {criterion} {delta:+.1f}, halves "
                      f"agree once referred to one amplitude (Q = {info['Q']:.1f} <= {info['critical_Q']:.1f})")
    own = law.selection  # the law's own free parameters (before the viscous fit's selection replaces it)
    for k in ("selection", "alternatives", "chosen_by", "crossing"):
        setattr(law, k, getattr(fit, k))
    law.selection = dict(fit.selection, **{k: v for k, v in own.items() if k == "free_parameters"})
    law.choice_reason = ((fit.choice_reason + "; ") if fit.choice_reason else "") + \
        f"then {AMPLITUDE_LAW_MODEL}: {info['reason']}"
    law.oscillation = fit.oscillation
    law.amplitude_law = info
    keep = fit.notes[:n_general] + [n for n in fit.notes[n_general:] if n.startswith("runner-up ")]
    law.notes = keep + [
        f"period changes along the record with the amplitude: fitted with the frequency following the "
        f"envelope's square ({AMPLITUDE_LAW_MODEL}; {fit.model} alone: T = {fit.period:.6f} +- "
        f"{info['without_law']['std']:.2g} s, "
        f"halves {', '.join(f'{h[0]:.6f}' for h in (fit.half_periods or ()))} s, between-half std "
        f"{fit.std_nonstationary:.2g} s); the period is the one at "
        f"amplitude {md['reference_amplitude']:.4g} (amplitude_period), from {md['period_start']:.6f} s at the "
        f"window's start to {md['period_zero_amplitude']:.6f} s at zero amplitude"] + [
        f"fitted with the law: another oscillation at {o['frequency']:.4g} Hz (amplitude {o['amplitude']:.3g}; "
        "left in the residuals it would leak into the law's frequency)" for o in info["other_oscillations"]] \
        + law.notes
    _residual_peaks(law)
    return law
