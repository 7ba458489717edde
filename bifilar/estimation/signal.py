"""Period of a recorded oscillation, with an honest uncertainty.

Pure functions and result dataclasses; SI units throughout (time in s,
frequency in Hz, angular rates in rad/s).  The signal itself may be in any
unit (volts of a rate gyro, pixels of a camera, radians): amplitudes, offsets,
residuals and noise are reported in that same unit, written ``[y]`` below.

The implementation is split by concern; this module is the public API:

* :mod:`.signal_io` -- reading CSV/MAT recordings, checking the time column;
* :mod:`.signal_models` -- the damped-oscillation models and their solver;
* :mod:`.signal_checks` -- is it an oscillation, whiteness, residual peaks,
  the serial-correlation factor;
* :mod:`.signal_result` -- :class:`PeriodFit`, covariance and std factors;
* :mod:`.signal_crossings` -- the crossing method.

The figure of a fit is :func:`bifilar.figures.plot_fit`.

Public API
----------
``read_signal(path, column=None, sample_rate=None) -> (t, y, meta)``
    CSV/TSV text or MATLAB ``.mat`` -> time (s), samples ([y]), metadata.
``fit_period(t, y, model="viscous", ...) -> PeriodFit``
    Nonlinear least-squares fit of a damped-oscillation model
    (``viscous``, ``quadratic``, ``quadratic+viscous``, ``two_mode``,
    ``three_mode`` or ``auto``, which compares them all).
``period_from_crossings(t, y, ...) -> CrossingPeriod``
    The experimenter's method: interpolated crossings of the mean level.

Uncertainty (the headline ``std``)
----------------------------------
``std = sqrt(max(f_serial * std_noise, std_quantisation)^2 + std_nonstationary^2)``:

* ``std_noise``: least squares, ``s^2 (J^T J)^-1`` with ``s^2 = RSS/(n-p)``
  (exact for white residuals);
* ``f_serial`` (``std_inflation``, >= 1): serial correlation of the
  residuals, applied when the Ljung-Box test rejects whiteness (see
  :mod:`.signal_checks`);
* ``std_nonstationary``: the same model is fitted to each half of the
  record (``MIN_WINDOW_CYCLES`` cycles or more each; for ``two_mode`` and
  ``three_mode`` the other modes' frequencies and dampings stay at the
  whole-record values);
  when the halves disagree beyond their own stds (Cochran's ``Q =
  (T1 - T2)^2 / (s1^2 + s2^2)`` above its ``WINDOW_Q_LEVEL`` chi^2_1
  quantile, 6.63) the between-half std ``tau = sqrt((Q - 1) / w)`` (the
  DerSimonian-Laird estimate; for equal stds ``sqrt(((T1 - T2)^2 - s1^2 -
  s2^2) / 2)``) is added in quadrature: the period changes along the
  record by that much, so "the" period of the record is not known better;
  unless the difference is the record's amplitude law: a viscous fit whose
  halves disagree is refitted with the frequency following the envelope's
  square (``viscous+chirp``, :func:`_amplitude_law`), which replaces it
  when it explains the halves (lower criterion, a resolved shift, an
  ``A^4`` term a pendulum can have, and its own halves agreeing); its
  period is the one at ``amplitude_period`` and its std the fit's own
  (``amplitude_law`` says which path was taken);
* ``std_quantisation``: a quantised record (few distinct values: a
  camera's pixel, an ADC's bit, or pixels converted to an angle, whose
  levels are unevenly spaced) with too little noise to dither the steps is
  re-quantised onto its own levels and refitted (:func:`_quantisation`;
  about the level it rests on when it is found resting on one); the
  spread of those periods replaces the noise term when larger, or alone
  is the std (with as many dof as copies: ``uncertainty["dof"]``) when
  the copies' noise terms reach the record's.

``uncertainty`` lists the terms and which one dominates.

Refusals (``SignalError`` on ``signal`` or ``time``, exit 2 in the CLI):
a time column that is not strictly increasing or has gaps
(:func:`.signal_io.check_time`), no significant spectral peak, fewer than
two cycles (:func:`.signal_checks.require_oscillation`), and a fit that
explains less than ``R2_MIN`` of the variance.  Records longer than
``MAX_FIT_SAMPLES`` are averaged in blocks of consecutive samples first (a
note says so), so memory and time stay bounded.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from scipy import stats

from .signal_checks import (
    MIN_CYCLES,
    R2_MIN,
    quantisation_levels,
    require_oscillation,
    residual_peaks,
)
from .signal_alias import ALIAS_MARGIN  # a fit above 1/ALIAS_MARGIN of the sample rate gets a note
from .signal_crossings import CrossingPeriod, period_from_crossings
from .signal_io import (
    MAX_GAP_FRACTION,
    MAX_NAN_FRACTION,
    MIN_COVERAGE,
    MIN_SAMPLES,
    SignalError,
    _validate,
    _window,
    check_time,
    read_signal,
)
from .signal_models import (
    _auto_trim,
    _fit_chirp,
    _fit_quadratic,
    _fit_three_mode,
    _fit_two_mode,
    _fit_viscous,
    _leading_rest,
    _linear_amplitudes,
    _model,
    _solve,
)
from .signal_result import PeriodFit, _build

__all__ = [
    "SignalError",
    "CrossingPeriod",
    "PeriodFit",
    "read_signal",
    "fit_period",
    "period_from_crossings",
    "check_time",
    "MIN_SAMPLES",
    "MAX_NAN_FRACTION",
    "MAX_GAP_FRACTION",
    "MIN_COVERAGE",
    "MAX_FIT_SAMPLES",
    "MODELS",
]

#: records longer than this are averaged in blocks of consecutive samples
MAX_FIT_SAMPLES = 200_000
#: every model ``auto`` compares (each with a linear drift term; the winner
#: is also tried without it)
MODELS = ("viscous", "quadratic", "quadratic+viscous", "two_mode", "three_mode")
#: cycles each half of the record needs for the non-stationarity check
MIN_WINDOW_CYCLES = 2.0
#: the windows disagree beyond noise when Cochran's Q exceeds this quantile
WINDOW_Q_LEVEL = 0.99
#: the viscous model whose frequency follows the envelope's square, tried
#: when a viscous fit's halves disagree (:func:`_amplitude_law`)
AMPLITUDE_LAW_MODEL = "viscous+chirp"
#: a law ``T = T0 (1 + c A^2 + d A^4)`` is a pendulum's when ``d / c^2`` lies
#: in this range (a simple pendulum 0.92; a period linear in ``A^2`` 0; a
#: frequency linear in it 1): the fit's ``beta2 w / beta^2 = 1 - d / c^2``
#: must lie in ``1 - range`` within 3 of its std.  A drift in time fitted
#: as a law of the decaying amplitude needs ``|d / c^2|`` of tens
AMPLITUDE_LAW_D_RANGE = (-1.0, 2.0)

_KIND = {"viscous": ("viscous", False), "quadratic": ("quadratic", False),
         "quadratic+viscous": ("quadratic", True), "two_mode": ("two_mode", False),
         "three_mode": ("three_mode", False), AMPLITUDE_LAW_MODEL: ("chirp", False)}
_MODEL_CHOICES = MODELS + ("auto",)


def fit_period(t, y, model: str = "viscous", *, trim: str | None = None, trim_k: float = 5.0,
               t_start: float | None = None, t_stop: float | None = None, drift: bool = True,
               viscous_term: bool = False, freq_guess: float | None = None,
               candidates: Sequence[str] = MODELS, criterion: str = "BIC",
               crossing_check: bool = True, split_check: bool = True,
               fallback: bool = True) -> PeriodFit:
    """Fit a damped-oscillation model and return its period with a 1-sigma std.

    Models (``tau = t - t0``, ``t0`` the window start, ``tm`` its middle):

    ``viscous``
        ``y = c0 + c1 (t - tm) + A exp(-sigma tau) cos(omega_d tau + phi)``,
        ``sigma = zeta omega_n``, ``omega_d = omega_n sqrt(1 - zeta^2)``.
    ``quadratic``
        ``y = c0 + c1 (t - tm) + A(tau) cos(omega tau + phi)`` with the
        envelope of ``dA/dt = -k A^2`` (drag ~ velocity^2; Jardin & Mueller
        2009, J. Aircraft 46(3)): ``A = A0 / (1 + k A0 tau)``; with
        ``viscous_term=True`` also ``- sigma A``:
        ``A = A0 exp(-sigma tau) / (1 + k A0 (1 - exp(-sigma tau)) / sigma)``.
    ``two_mode``
        Two viscous damped cosines (beating modes); ``period`` is the mode
        with the larger amplitude, ``modes`` lists both.
    ``three_mode``
        ``two_mode`` plus a third viscous damped cosine, started at the
        strongest peaks of the two-mode residuals that are resolved from
        both modes and are not harmonics ``k f1`` (k >= 2) of the dominant
        one (a nonlinear sensor's harmonics are orthogonal to the
        fundamental and do not bias it; an oscillation close to it does,
        and beats with it).
    ``quadratic+viscous``
        ``quadratic`` with ``viscous_term=True`` (combined damping).
    ``auto``
        Fits every model in ``candidates`` (default all of :data:`MODELS`,
        each with the linear drift ``c1``) on the same samples, drops the
        inadmissible ones (not converged, undefined covariance, a multi-mode
        fit with a growing mode or two modes closer than the frequency
        resolution), returns the one with the lowest ``criterion``
        (``"BIC"`` or ``"AIC"``), tries it once more without the drift term
        (kept if the criterion prefers it), and reports the ranking and why
        in ``selection`` / ``choice_reason`` (``alternatives`` keeps the
        fits).

    Start values come from the zero-padded FFT peak (Hann window,
    parabolic interpolation of the log magnitude) and linear least squares
    for the amplitudes; then :func:`scipy.optimize.least_squares` (analytic
    Jacobian).  See the module docstring for the covariance and the
    inflation of the std by serial correlation and non-stationarity.

    Parameters
    ----------
    t : array_like
        Sample times, s, strictly increasing (need not be uniform).
    y : array_like
        Samples, [y].
    model : str
        ``viscous`` (default), ``quadratic``, ``quadratic+viscous``,
        ``two_mode``, ``three_mode`` or ``auto``.
    trim : {None, "auto"}
        ``"auto"`` drops the settled tail where the envelope has fallen
        below ``trim_k`` x the white-noise level (estimated from second
        differences of the residuals of a first fit), then refits.
    trim_k : float
        Threshold of ``trim="auto"`` in units of the noise std.
    t_start, t_stop : float, optional
        Explicit fit window, s.  Without ``t_start``, a leading stretch at
        rest (at least one period, envelope below ``REST_FRACTION`` of its
        largest) is left out: the fit starts a quarter period after the
        onset found from the one-period envelope
        (:func:`.signal_models._leading_rest`), said in ``notes`` and in
        ``oscillation["leading_rest"]`` (``onset``, ``t_start`` = the first
        sample fitted, s; ``samples_left_out``).
    drift : bool
        Fit the linear drift ``c1`` (else fixed at 0).
    viscous_term : bool
        Add a viscous term to the quadratic model.
    freq_guess : float, optional
        Start frequency, Hz, instead of the FFT peak.
    candidates, criterion :
        For ``model="auto"``.
    crossing_check : bool
        Also run :func:`period_from_crossings` on the window (``crossing``).
    split_check : bool
        Also fit the two halves of the window (``half_periods``,
        ``windows``) and add their disagreement beyond noise to ``std``
        (``std_nonstationary``); when a viscous fit's halves disagree, try
        the amplitude law (:func:`_amplitude_law`, ``amplitude_law``).
    fallback : bool
        If the nonlinear fit fails, return the crossing period
        (``model="crossings"``) instead of raising.

    Returns
    -------
    PeriodFit

    Raises
    ------
    SignalError
        Bad input (``signal``, ``time``, ``--t-start``/``--t-stop``,
        ``--model``); not an oscillation (``signal``: no significant
        spectral peak, fewer than two cycles, r^2 below ``R2_MIN``); or,
        with ``fallback=False``, a failed fit.
    """
    if model not in _MODEL_CHOICES:
        raise SignalError("--model", f"unknown model {model!r}; choose one of {', '.join(_MODEL_CHOICES)}")
    if criterion.upper() not in ("AIC", "BIC"):
        raise SignalError("--criterion", f"unknown criterion {criterion!r}; use AIC or BIC")
    for c in candidates:
        if c not in MODELS:
            raise SignalError("--model", f"unknown candidate {c!r}; choose among {', '.join(MODELS)}")
    if model == "quadratic" and viscous_term:
        model = "quadratic+viscous"
    t, y = _validate(t, y)
    t, y = _window(t, y, t_start, t_stop)
    notes: list[str] = []
    t, y = _block_average(t, y, notes)
    osc = require_oscillation(t, y)
    if t_start is None:
        rest = _leading_rest(t, y, 1.0 / osc["frequency"])
        if rest is not None and int(np.sum(t >= rest[1])) >= MIN_SAMPLES \
                and (t[-1] - rest[1]) * osc["frequency"] >= 3:
            keep = t >= rest[1]
            t_on, t_fit = rest[0], float(t[keep][0])  # the first sample fitted
            notes.append(f"leading rest: the record is at rest until the oscillation starts at t = {t_on:.4g} s "
                         f"(envelope); the fit starts at t = {t_fit:.4g} s, leaving out {int((~keep).sum())} "
                         "samples (give --t-start to choose)")
            osc = dict(osc, leading_rest={"onset": t_on, "t_start": t_fit, "samples_left_out": int((~keep).sum())})
            t, y = t[keep], y[keep]
    try:
        fit = _fit_period(t, y, model, trim, trim_k, drift, freq_guess, tuple(candidates),
                          criterion.upper(), crossing_check, split_check, notes)
    except SignalError:
        raise
    except (ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError) as exc:
        if not fallback:
            raise SignalError("signal", f"nonlinear fit failed: {exc}") from exc
        cr = period_from_crossings(t, y)
        fit = _from_crossings(cr, t, y, notes + [f"nonlinear fit failed ({exc}); period from crossings"])
    fit.oscillation = osc
    _require_fit(fit)
    _alias_note(fit, t)
    return fit




def _alias_note(fit: PeriodFit, t):
    """Note that an oscillation near the Nyquist frequency may be an alias:
    sampled at ``fs``, a frequency ``f`` and ``fs - f`` give the same samples
    (``invert --signal`` compares them with the config's modes,
    :mod:`.signal_alias`)."""
    fs = 1.0 / float(np.median(np.diff(t)))
    f = fit.frequency
    if np.isfinite(f) and f > 0 and fs < ALIAS_MARGIN * f:
        fit.notes.append(f"the sample rate {fs:.4g} Hz is only {fs / f:.2f} x the fitted frequency {f:.4g} Hz: an "
                         f"oscillation at {fs - f:.4g} Hz (period {1 / (fs - f):.4g} s), above the Nyquist "
                         f"frequency {fs / 2:.4g} Hz, gives the same samples; a record alone cannot tell them apart")


def _block_average(t, y, notes):
    """Average records longer than ``MAX_FIT_SAMPLES`` in blocks of ``k``
    consecutive samples (times averaged too, so an oscillation much slower
    than a block keeps its phase; its amplitude is scaled by
    ``sinc(f k dt)``).  Memory stays O(n)."""
    n = t.size
    if n <= MAX_FIT_SAMPLES:
        return t, y
    k = -(-n // MAX_FIT_SAMPLES)
    m = n // k
    tb = t[:m * k].reshape(m, k).mean(axis=1)
    yb = y[:m * k].reshape(m, k).mean(axis=1)
    notes.append(f"{n} samples averaged in blocks of {k} ({k * float(t[1] - t[0]):.3g} s) to {m} "
                 f"for the fit (limit {MAX_FIT_SAMPLES}); the last {n - m * k} dropped")
    return tb, yb


def _require_fit(fit: PeriodFit):
    """Refuse a fit that does not describe an oscillation."""
    cycles = (fit.t1 - fit.t0) / fit.period if fit.period > 0 else 0.0
    if not (cycles >= MIN_CYCLES):
        raise SignalError("signal", f"fewer than {MIN_CYCLES:g} cycles: the fitted period {fit.period:.4g} s "
                                    f"spans {cycles:.2f} of the {fit.t1 - fit.t0:.4g} s record")
    if np.isfinite(fit.r_squared) and fit.r_squared < R2_MIN:
        raise SignalError("signal", f"the {fit.model} fit explains only {fit.r_squared:.1%} of the variance "
                                    f"(less than {R2_MIN:.0%}): not a usable oscillation")


def _from_crossings(cr: CrossingPeriod, t, y, notes) -> PeriodFit:
    nan = float("nan")
    return PeriodFit(model="crossings", period=cr.period, std=cr.std, frequency=1 / cr.period,
                     damping_ratio=nan, damping={}, amplitude=nan, phase=nan, offset=cr.level, drift=nan,
                     residual_rms=nan, r_squared=nan, n_samples=int(t.size), covariance=np.empty((0, 0)),
                     params=np.empty(0), param_names=(), t0=float(t[0]), t1=float(t[-1]),
                     t_ref=float(0.5 * (t[0] + t[-1])), std_raw=cr.std, crossing=cr,
                     t_used=t.copy(), residuals=None, notes=list(notes), converged=False,
                     uncertainty={"noise": cr.std, "serial_correlation": 0.0, "nonstationarity": 0.0,
                                  "total": cr.std, "dominant": "noise"})


def _fit_one(name, t, y, t0, tm, visc, env, drift, two: PeriodFit | None = None) -> PeriodFit:
    """One model on ``(t, y)``; ``three_mode`` extends the two-mode fit
    ``two`` (fitted here if not given)."""
    kind, vt = _KIND[name]
    if kind == "viscous":
        raw = visc if drift or not visc.free[1] else _fit_viscous(t, y, t0, tm, visc.p[4] / (2 * math.pi), False)[0]
    elif kind == "quadratic":
        raw = _fit_quadratic(t, y, t0, tm, visc, env, drift, vt)
    elif kind == "two_mode":
        raw = _fit_two_mode(t, y, t0, tm, visc, drift)
    elif kind == "chirp":
        raw = _fit_chirp(t, y, t0, tm, visc.p, drift)
    else:
        if two is None:
            raw2 = _fit_two_mode(t, y, t0, tm, visc, drift)
            p2, r2 = raw2.p, raw2.resid
        else:
            p2, r2 = two.params, two.residuals
        raw = _fit_three_mode(t, y, t0, tm, p2, r2, drift)
    f = _build(raw, t, y, name, [])
    f.selection["drift"] = bool(drift)
    return f


def _inadmissible(f: PeriodFit) -> str | None:
    """Why a candidate cannot be "the" model of a free decay (None if it can)."""
    if not f.converged:
        return "least squares did not converge"
    if not (np.isfinite(f.std) and f.std > 0):
        return "covariance undefined (parameters not identifiable)"
    if f.model in ("two_mode", "three_mode"):
        T_rec = f.t1 - f.t0
        for m in f.modes:
            if m["sigma"] < 0 and m["sigma"] < -3 * m["sigma_std"]:
                return (f"its mode at {m['period']:.4g} s grows (sigma = {m['sigma']:.3g} 1/s): it mimics a "
                        f"changing frequency, not a mode of a free decay")
        fr = sorted(m["frequency"] for m in f.modes)
        if min(b - a for a, b in zip(fr[:-1], fr[1:])) < 1.0 / T_rec:
            return "two of its modes are closer than the frequency resolution 1/T_record"
    return None


def _fit_window(t, y, model, drift, freq_guess, candidates, criterion, start=None):
    """``model`` (or ``auto``) on ``(t, y)``; returns the fit and the
    viscous solution (None when ``start``, the amplitude law's parameters
    for these ``t0``, ``tm``, was enough: a copy of a fitted record)."""
    t0 = float(t[0])
    tm = float(0.5 * (t[0] + t[-1]))
    if start is not None and model == AMPLITUDE_LAW_MODEL:
        free = np.ones(start.size, bool)
        free[1] = drift
        raw = _solve("chirp", t, y, t0, tm, start, free)
        if raw.converged:
            f = _build(raw, t, y, model, [])
            f.selection["drift"] = bool(drift)
            return f, None
    visc, env = _fit_viscous(t, y, t0, tm, freq_guess, drift)
    if model != "auto":
        return _fit_one(model, t, y, t0, tm, visc, env, drift), visc
    key = criterion.lower()
    fits: dict[str, PeriodFit] = {}
    failed: dict[str, str] = {}
    for c in sorted(candidates, key=lambda c: c == "three_mode"):
        if c == "three_mode" and "two_mode" in fits and _inadmissible(fits["two_mode"]):
            # the third oscillation extends an admissible two-mode fit
            failed[c] = "not tried: two_mode is inadmissible"
            continue
        try:
            fits[c] = _fit_one(c, t, y, t0, tm, visc, env, drift, fits.get("two_mode"))
        except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError,
                ZeroDivisionError) as exc:
            failed[c] = str(exc)
    if not fits:
        raise ValueError("no candidate model could be fitted: " + "; ".join(f"{c}: {m}" for c, m in failed.items()))
    why = {c: _inadmissible(f) for c, f in fits.items()}
    ranking = sorted((c for c in fits if why[c] is None), key=lambda c: getattr(fits[c], key))
    if not ranking:
        raise ValueError("no admissible model: " + "; ".join(f"{c}: {m}" for c, m in why.items()))
    chosen = ranking[0]
    if drift:
        try:
            nd = _fit_one(chosen, t, y, t0, tm, visc, env, False)
            label = f"{chosen} without drift"
            fits[label] = nd
            why[label] = _inadmissible(nd)
            if why[label] is None and getattr(nd, key) < getattr(fits[chosen], key):
                ranking.insert(0, label)
            elif why[label] is None:
                ranking.insert(1, label)
        except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
            failed[f"{chosen} without drift"] = str(exc)
    pick = ranking[0]
    best = fits[pick]
    best_v = getattr(best, key)
    sel = {c: {"rss": float(f.residual_rms ** 2 * f.n_samples), "n_params": len(f.selection["free_parameters"]),
               "aic": f.aic, "bic": f.bic, "delta": getattr(f, key) - best_v, "period": f.period,
               "std": f.std, "r_squared": f.r_squared, "admissible": why[c] is None,
               "rejected_because": why[c]}
           for c, f in fits.items()}
    best.selection = dict(best.selection, candidates=sel, ranking=ranking, failed=failed, criterion=criterion)
    best.alternatives = fits
    best.chosen_by = criterion
    reason = f"lowest {criterion} of the {len(ranking)} admissible fits on the same {best.n_samples} samples"
    if len(ranking) > 1:
        ru = ranking[1]
        reason += f"; runner-up {ru} ({criterion} +{getattr(fits[ru], key) - best_v:.1f})"
    rej = [f"{c} ({why[c]})" for c in fits if why[c] is not None]
    if rej:
        reason += "; rejected: " + "; ".join(rej)
    skipped = [c for c, m in failed.items() if m.startswith("not tried")]
    if skipped:
        reason += "; " + "; ".join(f"{c} {failed[c]}" for c in skipped)
    if len(failed) > len(skipped):
        reason += "; failed: " + ", ".join(c for c in failed if c not in skipped)
    best.choice_reason = reason
    for c in ranking[1:4]:
        f = fits[c]
        best.notes.append(f"runner-up {c}: T = {f.period:.6f} +- {f.std:.2g} s, "
                          f"{criterion} {getattr(f, key) - best_v:+.1f}")
    if pick.endswith(" without drift"):
        best.model = pick[: -len(" without drift")]
    return best, visc


def _fit_period(t, y, model, trim, trim_k, drift, freq_guess, candidates, criterion,
                crossing_check, split_check, notes):
    fit, visc = _fit_window(t, y, model, drift, freq_guess, candidates, criterion)
    if trim is not None:
        if trim != "auto":
            raise SignalError("--trim", f"unknown trim {trim!r}; use 'auto' or None")
        t_cut, noise = _auto_trim(t, y, visc, trim_k)
        if t_cut is not None and t_cut < t[-1]:
            keep = t <= t_cut
            if keep.sum() >= MIN_SAMPLES and (t_cut - t[0]) >= 3 * fit.period:
                notes.append(f"trim=auto: dropped the tail after t = {t_cut:.3f} s where the envelope "
                             f"< {trim_k:g} x noise ({noise:.3g}); {int((~keep).sum())} samples")
                t, y = t[keep], y[keep]
                fit, _ = _fit_window(t, y, model, drift, freq_guess, candidates, criterion)
            else:
                notes.append(f"trim=auto: envelope < {trim_k:g} x noise after t = {t_cut:.3f} s, "
                             f"but fewer than 3 periods would remain; not trimmed")
        else:
            notes.append("trim=auto: envelope above threshold to the end; nothing trimmed")
    fit.notes = notes + fit.notes
    if not np.isfinite(fit.period) or not np.isfinite(fit.std):
        raise ValueError("non-finite period or std")
    if crossing_check:
        try:
            fit.crossing = period_from_crossings(t, y)
            cr = fit.crossing
            comb = math.hypot(cr.std, fit.std)
            if np.isfinite(comb) and abs(cr.period - fit.period) > 4 * comb:
                fit.notes.append(f"crossing period {cr.period:.6f} +- {cr.std:.2g} s differs from the fit "
                                 f"by {abs(cr.period - fit.period) / comb:.1f} sigma")
        except SignalError as exc:
            fit.notes.append(f"crossing check impossible: {exc.message}")
    _residual_peaks(fit)
    if split_check:
        _stationarity(fit, t, y)
        fit = _amplitude_law(fit, t, y, criterion, len(notes))
    _quantisation(fit, t, y, criterion)
    _compose_std(fit)
    return fit


#: a quantised record is simulated when its noise before quantisation is
#: below this many steps (above it the noise dithers the steps away)
DITHER_STEPS = 0.5
#: simulated records of the quantisation check
QUANT_DRAWS = 40


def _turned(p, kind: str, dphi: float) -> np.ndarray:
    """Parameters ``p`` of a ``kind`` model with every oscillation's phase
    advanced by ``dphi`` (rad): each ``(a, b)`` pair turned."""
    pb = np.array(p, dtype=float)
    pairs = range(2, pb.size, 4) if kind in ("viscous", "two_mode", "three_mode") else \
        [2] + list(range(8, pb.size, 4)) if kind == "chirp" else [2]
    for i in pairs:
        a, b = pb[i], pb[i + 1]
        pb[i], pb[i + 1] = a * math.cos(dphi) - b * math.sin(dphi), a * math.sin(dphi) + b * math.cos(dphi)
    return pb


def _requantised_copies(fit: PeriodFit, t, lev, p, s_steps, drift, rng, criterion, ref=None,
                        in_index=False):
    """``QUANT_DRAWS`` copies of the curve of parameters ``p`` (the fit's
    model; times ``ref = (t0, t_ref)``, default the fit's), each shifted by
    a random phase, given ``s_steps`` (local steps) of noise, put onto the
    levels ``lev`` and refitted: their periods (s), noise terms (s) and
    offsets at the record's two ends minus the curve's ((m, 2), [y]).  The
    curve is in [y], or in level indices when ``in_index``.  Copies whose
    fit fails are left out."""
    kind = fit._kind
    t0, t_ref = ref if ref is not None else (fit.t0, fit.t_ref)
    t_end = np.array([t[0], t[-1]])
    periods, noise_terms, ends = [], [], []
    for _ in range(QUANT_DRAWS):
        dphi = rng.uniform(0.0, 2 * math.pi)
        pb = _turned(p, kind, dphi)
        kb = _model(kind, pb, t, t0, t_ref)
        kb = (kb if in_index else lev.index(kb)) + s_steps * rng.standard_normal(t.size)
        yb = lev.level(np.round(kb))
        # the law's fit starts from the record's own, turned alike (one solve)
        start = _turned(fit.params, kind, dphi) if kind == "chirp" else None
        try:
            fb, _ = _fit_window(t, yb, fit.model, drift, fit.frequency, (), criterion, start)
        except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError,
                ZeroDivisionError):
            continue
        if fb.converged and np.isfinite(fb.period):
            periods.append(fb.period)
            noise_terms.append(fb.std)  # the copy's own noise term (with its serial factor)
            if not in_index:
                ends.append(fb.params[0] + fb.params[1] * (t_end - fb.t_ref) - (p[0] + p[1] * (t_end - t_ref)))
    return periods, noise_terms, np.reshape(ends, (-1, 2))


#: the record rests on a level when its offsets at both ends lie within
#: this chi^2_2 quantile (99 %) of the level, on the copies' covariance
REST_LEVEL_CHI2 = 0.99


def _rest_on_level(fit: PeriodFit, t, y, lev, ends, drift, criterion):
    """The record's fit in level indices with its offset on the nearest
    level and no drift (parameters, ``(t0, t_ref)``), or None.

    A record centred on a level (an encoder zeroed at rest) has the least
    period error of any offset: its quantisation error is odd about the
    level.  Its fitted offset and drift miss the level by their own
    quantisation error, and copies about them overstate the error (x1.4
    for 15 steps at 30 fps).  The record (its level indices, where a
    camera's pixels lie on a lattice whatever map took them to [y]) is
    fitted with the chosen model; it rests on the nearest level when its
    offsets at both ends, minus that level, lie within the
    ``REST_LEVEL_CHI2`` quantile of chi^2_2 on the covariance of the
    copies' own offset errors (``ends``, in local steps; chi^2_1 on the
    offset alone for a fit without drift)."""
    if ends.shape[0] < 10:
        return None
    k = lev.index(y)
    try:
        fk, _ = _fit_window(t, k, fit.model, drift, fit.frequency, (), criterion)
    except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError,
            ZeroDivisionError):
        return None
    p = fk.params.copy()
    t_end = np.array([t[0], t[-1]]) - fk.t_ref
    level = float(np.round(p[0]))
    d = p[0] + p[1] * t_end - level
    e = ends / lev.step(np.array([lev.level(np.array([level]))[0]]))[0]
    if not drift:  # one offset: both ends alike
        d, e = d[:1], e[:, :1]
    C = e.T @ e / e.shape[0]
    try:
        chi2 = float(d @ np.linalg.solve(C, d))
    except np.linalg.LinAlgError:
        return None
    if not np.isfinite(chi2) or chi2 > stats.chi2.ppf(REST_LEVEL_CHI2, d.size):
        return None
    p[0], p[1] = level, 0.0
    return p, (fk.t0, fk.t_ref)


def _quantisation(fit: PeriodFit, t, y, criterion):
    """Std of the period a quantised record (a camera's pixel, an ADC's
    bit, or pixels converted to an angle; :func:`.signal_checks.quantisation_levels`)
    can have when its noise is too weak to dither the steps (below
    ``DITHER_STEPS`` of the local step).

    Undithered, the quantisation error is a deterministic function of the
    signal: it repeats from cycle to cycle (correlated at lags of a period,
    beyond the lags the whiteness test looks at) and part of it lies in the
    band the fit absorbs, so neither the least-squares std nor the
    serial-correlation factor sees it (a period off by up to 3.5 of its std).
    The fitted curve, shifted by a random phase, plus the noise left before
    quantisation (in steps, ``sigma0^2 = mean(r^2 / w^2) - 1/12`` with ``w``
    the width of each sample's level: ``RSS/n - q^2/12`` over ``q^2`` on a
    uniform lattice), is therefore put onto the record's own levels (the
    nearest level; on a uniform lattice, rounding) ``QUANT_DRAWS`` times and
    refitted with the chosen model; the rms spread of those periods about
    the fitted one, ``std_quantisation``, is the std when it exceeds the
    noise term (a lattice shifted at random instead under-covers a signal
    centred on a level, as an encoder zeroed at rest is).  A record found
    resting on a level (:func:`_rest_on_level`) is re-quantised again about
    that level, without drift, and those copies give the spread.  The
    draws are seeded by the record, so a result is reproducible."""
    lev = quantisation_levels(y)
    if lev is None or fit.model not in _KIND or fit.residuals is None:
        return
    q = lev.typical_step
    w = lev.step(y)
    s_steps = math.sqrt(max(float(np.mean((fit.residuals / w) ** 2)) - 1.0 / 12.0, 0.0))
    sigma0 = s_steps * q
    fit.uncertainty["quantisation_step"] = q
    if s_steps >= DITHER_STEPS:
        return
    p = fit.params.copy()
    drift = fit.selection.get("drift", True)
    k_rec = np.round(lev.index(y))
    rng = np.random.default_rng([t.size, int(np.sum(k_rec) % (1 << 31))])
    periods, noise_terms, ends = _requantised_copies(fit, t, lev, p, s_steps, drift, rng, criterion)
    if len(periods) < QUANT_DRAWS // 2:
        fit.notes.append(f"quantisation check failed: only {len(periods)} of {QUANT_DRAWS} simulated records fitted")
        return
    rest = _rest_on_level(fit, t, y, lev, ends, drift, criterion)
    if rest is not None:
        again = _requantised_copies(fit, t, lev, rest[0], s_steps, drift, rng, criterion, ref=rest[1],
                                    in_index=True)
        if len(again[0]) >= QUANT_DRAWS // 2:
            periods, noise_terms, _ = again
        else:
            rest = None
    dev = np.asarray(periods) - fit.period
    sq = float(np.sqrt(np.mean(dev ** 2)))  # about the fitted period: the copies' shift counts too
    fit.std_quantisation = sq
    uniform = lev.uniform is not None
    # the record's noise term within those of its copies: its residuals are
    # what quantisation and sigma0 make, and the spread of the copies (which
    # holds both) is the std; a larger one means errors the copies lack
    noise = float(fit.std)  # still the noise term (with its serial factor), like the copies' fb.std
    replaces = bool(noise <= max(noise_terms))
    fit.uncertainty["quantisation_test"] = {"step": q, "uniform": uniform, "levels": int(lev.values.size),
                                            "noise_before_quantisation": sigma0, "noise_steps": s_steps,
                                            "draws": len(periods), "std": sq,
                                            "noise_term": noise, "copies_noise_term_max": max(noise_terms),
                                            "replaces_noise": replaces, "rest_on_level": rest is not None,
                                            "mean_shift": float(np.mean(periods)) - fit.period}
    where = (f"in steps of {q:.3g}" if uniform else
             f"on {lev.values.size} unevenly spaced levels (median step {q:.3g}; a map of a lattice, e.g. "
             f"pixels converted to an angle)")
    fit.notes.append(f"the record is quantised {where} with little noise ({s_steps:.2g} step, below "
                     f"{DITHER_STEPS:g} step): the period of {len(periods)} re-quantised copies of the fit "
                     f"spreads by {sq:.2g} s"
                     + (" (copies centred on the level the record rests on, within its offset's "
                        "quantisation error, without drift)" if rest is not None else ""))


def _residual_peaks(fit: PeriodFit):
    try:
        peaks = residual_peaks(fit.t_used, fit.residuals, fit.frequency)
    except (ValueError, np.linalg.LinAlgError):
        return
    known = [m["frequency"] for m in fit.modes]
    for pk in peaks:
        if pk["harmonic"] is None and any(abs(pk["frequency"] - f) <= 1.5 / (fit.t1 - fit.t0) for f in known):
            pk["harmonic"] = 1
    fit.residual_check["peaks"] = peaks
    other = [pk for pk in peaks if pk["harmonic"] is None]
    harm = sorted({pk["harmonic"] for pk in peaks if pk["harmonic"] is not None})
    if harm:
        fit.notes.append("residuals keep harmonics " + ", ".join(f"{h}f" for h in harm)
                         + " of the oscillation (a sensor or motion not linear in the angle); orthogonal "
                           "to the fundamental, they hardly bias the period")
    for pk in other:
        fit.notes.append(f"residuals keep an unmodelled oscillation at {pk['frequency']:.4g} Hz "
                         f"(period {1 / pk['frequency']:.4g} s, {pk['ratio']:.0f} x the noise level)")


def _window_fit(fit: PeriodFit, th, yh) -> PeriodFit:
    """The chosen model fitted to a window, started from the whole-record
    frequencies; for ``two_mode`` / ``three_mode`` the other modes'
    frequencies and dampings stay fixed (a short window cannot resolve
    them), the rest is free."""
    kind, vt = _KIND[fit.model]
    drift = fit.selection.get("drift", True)
    t0 = float(th[0])
    tm = float(0.5 * (th[0] + th[-1]))
    if kind == "chirp":  # the whole record's amplitude law, carried to the window's start
        visc, _ = _fit_viscous(th, yh, t0, tm, fit.frequency, drift)
        sg = float(fit.params[5])
        u0 = math.exp(-2.0 * sg * (t0 - fit.t0))
        beta, beta2 = float(fit.params[6]) * u0, float(fit.params[7]) * u0 * u0
        um = math.exp(-2.0 * sg * (tm - t0))
        w = float(visc.p[4]) - beta * um - beta2 * um * um
        # other oscillations the fit carries: frequencies and dampings fixed (as for two_mode)
        ws, ss = [w] + list(fit.params[10::4]), [sg] + list(fit.params[11::4])
        coef, _ = _linear_amplitudes(th, yh, t0, tm, ws, ss)
        p0 = [coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w, sg, beta, beta2]
        for k in range(1, len(ws)):
            p0 += [coef[2 + 2 * k], coef[3 + 2 * k], ws[k], ss[k]]
        free = np.zeros(len(p0), bool)
        free[[0, 2, 3, 4, 5]] = True
        free[1] = drift
        free[8::4] = free[9::4] = True
        return _build(_solve(kind, th, yh, t0, tm, np.array(p0), free), th, yh, fit.model, [])
    if kind not in ("two_mode", "three_mode"):
        visc, env = _fit_viscous(th, yh, t0, tm, fit.frequency, drift)
        return _fit_one(fit.model, th, yh, t0, tm, visc, env, drift)
    p = fit.params
    ws, ss = list(p[4::4]), list(p[5::4])
    coef, _ = _linear_amplitudes(th, yh, t0, tm, ws, ss)
    p0 = [coef[0], coef[1] if drift else 0.0]
    for k in range(len(ws)):
        p0 += [coef[2 + 2 * k], coef[3 + 2 * k], ws[k], ss[k]]
    free = np.ones(len(p0), bool)
    free[1] = drift
    free[8::4] = False
    free[9::4] = False
    raw = _solve(kind, th, yh, t0, tm, np.array(p0), free)
    return _build(raw, th, yh, kind, [])


def _window_periods(fit: PeriodFit, t, y, K: int) -> list[dict]:
    edges = np.linspace(t[0], t[-1], K + 1)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        m = (t >= a) & (t <= b)
        f = _window_fit(fit, t[m], y[m])
        md = next((d for d in f.modes if d["omega"] == f.params[4]), f.modes[0])
        T, s = md["period"], md["std"]
        if f._kind == "chirp":  # each window's frequency at the whole record's reference amplitude
            T = 2 * math.pi / (f.params[4] + 2 * math.pi / fit.period - fit.params[4])
        out.append({"t0": float(a), "t1": float(b), "period": float(T), "std": float(s)})
    return out


def _stationarity(fit: PeriodFit, t, y):
    """Periods of the two halves, and the between-window std
    ``std_nonstationary`` when they disagree beyond their noise."""
    if fit.model not in _KIND:
        return
    cycles = (t[-1] - t[0]) / fit.period
    if cycles < 2 * MIN_WINDOW_CYCLES:
        fit.notes.append(f"non-stationarity not checked: {cycles:.1f} cycles "
                         f"(halves need >= {MIN_WINDOW_CYCLES:g} each)")
        return
    try:
        halves = _window_periods(fit, t, y, 2)
        wins = halves
    except (SignalError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        fit.notes.append(f"split check failed: {exc}")
        return
    fit.half_periods = tuple((w["period"], w["std"]) for w in halves)
    (T1, s1), (T2, s2) = fit.half_periods
    comb = math.hypot(s1, s2)
    if np.isfinite(comb) and abs(T1 - T2) > 3 * comb:
        fit.notes.append(f"period changes along the record: {T1:.6f} +- {s1:.2g} s (first half) vs "
                         f"{T2:.6f} +- {s2:.2g} s (second half), {abs(T1 - T2) / comb:.1f} sigma")
    T = np.array([w["period"] for w in wins])
    s = np.array([w["std"] for w in wins])
    if not np.all(np.isfinite(s) & (s > 0)):
        fit.notes.append("non-stationarity not assessed: a window's std is undefined")
        return
    K = T.size
    wt = 1.0 / s ** 2
    Tbar = float(np.sum(wt * T) / np.sum(wt))
    Q = float(np.sum(wt * (T - Tbar) ** 2))
    crit = float(stats.chi2.ppf(WINDOW_Q_LEVEL, K - 1))
    tau = 0.0
    if Q > crit:
        tau = math.sqrt(max(Q - (K - 1), 0.0) / (np.sum(wt) - np.sum(wt ** 2) / np.sum(wt)))
        fit.notes.append(f"the {K} window periods ({', '.join(f'{x:.6f}' for x in T)} s) disagree beyond "
                         f"their noise (Q = {Q:.1f} > {crit:.1f}): between-window std {tau:.2g} s added")
    fit.windows = wins
    fit.std_nonstationary = tau
    fit.uncertainty["windows_test"] = {"windows": K, "Q": Q, "critical_Q": crit,
                                       "p": float(stats.chi2.sf(Q, K - 1))}


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
        m0 = law.modes[0]  # other oscillations only for a law that may be used (their solves cost)
        if getattr(law, key) < getattr(fit, key) and abs(m0["beta"]) >= 3 * m0["beta_std"]:
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
    if why is None and not abs(md["beta"]) >= 3 * md["beta_std"]:
        why = (f"its frequency shift over the envelope ({md['beta']:.3g} +- {md['beta_std']:.2g} rad/s) is not "
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
    for k in ("selection", "alternatives", "chosen_by", "crossing"):
        setattr(law, k, getattr(fit, k))
    law.selection = dict(fit.selection, **{k: v for k, v in law.selection.items() if k == "free_parameters"})
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


def _compose_std(fit: PeriodFit):
    """Headline std from the three terms; which one dominates.  When the
    quantisation check found the record's noise term among its copies'
    (``quantisation_test.replaces_noise``), the copies' spread, which holds
    the noise as well, stands for noise, serial correlation and
    quantisation together: the least-squares and serial-correlation stds
    read the quantisation error as noise spread over all frequencies, and
    overstate it when the signal dwells on each level for several samples
    (x2.4 for 10 steps at 120 fps).  ``uncertainty["dof"]``: the degrees
    of freedom of the std (None: infinite, normal); finite, the number of
    copies, when their spread is the std (a Student interval, as for a
    period from timed trials)."""
    noise = float(fit.std_raw)
    serial = noise * float(fit.std_inflation)
    ns = float(fit.std_nonstationary)
    replaced = bool((fit.uncertainty.get("quantisation_test") or {}).get("replaces_noise"))
    if replaced:
        quant = float(fit.std_quantisation)
    else:
        quant = max(float(fit.std_quantisation), serial)  # the simulated spread includes the noise
    total = math.hypot(quant, ns)
    terms = {"noise": noise, "serial_correlation": math.sqrt(max(serial ** 2 - noise ** 2, 0.0)),
             "quantisation": quant if replaced else math.sqrt(max(quant ** 2 - serial ** 2, 0.0)),
             "nonstationarity": ns}
    if replaced:
        fit.uncertainty["noise_replaced_by_quantisation"] = True
    dom = max(("quantisation", "nonstationarity") if replaced else terms, key=terms.get)
    # the copies' rms spread about the fitted period, from m copies, has m
    # dof (m sq^2 / sigma^2 ~ chi^2_m); the other terms count as normal
    dof = math.inf
    if replaced:
        from .uncertainty import combined_dof

        dof = combined_dof([(quant, float(fit.uncertainty["quantisation_test"]["draws"])), (ns, math.inf)])
    fit.uncertainty = dict(terms, total=total, dominant=dom, serial_factor=float(fit.std_inflation),
                           dof=dof if math.isfinite(dof) else None, **fit.uncertainty)
    fit.std = total
    if fit.modes:
        fit.modes[0]["std_total"] = total
    if replaced and serial > quant:
        fit.notes.append(f"std {total:.2g} s from the re-quantised copies, whose spread holds the noise too; "
                         f"the noise term {serial:.2g} s, which reads the quantisation error as white noise, is "
                         f"no larger than the copies' own (up to {fit.uncertainty['quantisation_test']['copies_noise_term_max']:.2g} s) "
                         "and overstates it")
    elif dom != "noise":
        fit.notes.append(f"std {total:.2g} s is dominated by {dom.replace('_', ' ')} "
                         f"(noise alone {noise:.2g} s)")
