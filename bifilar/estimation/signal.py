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
* :mod:`.signal_crossings` -- the crossing method;
* :mod:`.signal_windows` -- one model fitted to a stretch of the record, the
  halves' and windows' refits and the stationarity (split) check;
* :mod:`.signal_quantisation` -- re-quantised copies of an undithered record;
* :mod:`.signal_law` -- the amplitude law of a decaying nonlinear record.

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

from .signal_checks import MIN_CYCLES, R2_MIN, require_oscillation
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
from .signal_models import _auto_trim, _leading_rest
from .signal_law import _amplitude_law
from .signal_quantisation import _quantisation
from .signal_harmonic2 import second_harmonic_term
from .signal_result import PeriodFit
from .signal_clip import drop_clipped, drop_soft_clipped, keep_soft_clipped, soft_fit_holds
from .signal_offset import remove_offset_step
from .signal_start import trim_held_end, trim_held_start
from .signal_windows import AMPLITUDE_LAW_MODEL, _fit_window, _residual_peaks, _stationarity  # noqa: F401 (the model's name)

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
        sample fitted, s; ``samples_left_out``).  Else a start held by hand
        (the level off the rest's, :mod:`.signal_start`) is left out:
        ``oscillation["held_start"]``; without ``t_stop``, a held or
        stopped end likewise: ``oscillation["held_end"]``.
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
        else:  # the body held at the release angle before it was let go
            t, y, osc = trim_held_start(t, y, osc, notes)
    if t_stop is None:  # the body caught and held, or stopped, before the record ends
        t, y, osc = trim_held_end(t, y, osc, notes)
    t, y, osc = drop_clipped(t, y, osc, notes, MIN_SAMPLES)  # a saturated sensor's flat tops: left out
    whole = (t, y, osc, list(notes))  # before the compressed peaks are left out
    t, y, osc = drop_soft_clipped(t, y, osc, notes, MIN_SAMPLES)  # ... or its compressed peaks
    t, y, osc = remove_offset_step(t, y, osc, notes)  # the sensor's offset stepping: taken out
    try:
        fit = _fit_period(t, y, model, trim, trim_k, drift, freq_guess, tuple(candidates),
                          criterion.upper(), crossing_check, split_check, notes)
        if osc.get("soft_clipped") and not soft_fit_holds(fit, osc):
            t, y, osc, notes = keep_soft_clipped(whole, osc)
            t, y, osc = remove_offset_step(t, y, osc, notes)
            fit = _fit_period(t, y, model, trim, trim_k, drift, freq_guess, tuple(candidates),
                              criterion.upper(), crossing_check, split_check, notes)
    except SignalError:
        raise
    except (ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError) as exc:
        if not fallback:
            raise SignalError("signal", f"nonlinear fit failed: {exc}") from exc
        try:
            cr = period_from_crossings(t, y)
        except SignalError as exc2:  # one line saying both
            raise SignalError("signal", f"nonlinear fit failed ({exc}); crossing fallback refused: "
                                        f"{exc2.message}") from exc
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
            fit.crossing = period_from_crossings(t, y, frequency=fit.frequency)  # the fit counts the cycles
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
    _compose_std(fit, second_harmonic_term(fit))
    return fit


def _compose_std(fit: PeriodFit, harmonic2: float = 0.0):
    """Headline std from the terms; which one dominates.  ``harmonic2`` (s):
    :func:`second_harmonic_term`, a further mode's 2nd harmonic beside the
    dominant frequency, added in quadrature (``uncertainty["second_harmonic"]``).  When the
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
    total = math.hypot(quant, ns, harmonic2)
    terms = {"noise": noise, "serial_correlation": math.sqrt(max(serial ** 2 - noise ** 2, 0.0)),
             "quantisation": quant if replaced else math.sqrt(max(quant ** 2 - serial ** 2, 0.0)),
             "nonstationarity": ns, "second_harmonic": harmonic2}
    if replaced:
        fit.uncertainty["noise_replaced_by_quantisation"] = True
    dom = max(("quantisation", "nonstationarity", "second_harmonic") if replaced else terms, key=terms.get)
    # the copies' rms spread about the fitted period, from m copies, has m
    # dof (m sq^2 / sigma^2 ~ chi^2_m); the other terms count as normal
    dof = math.inf
    if replaced:
        from .uncertainty import combined_dof

        dof = combined_dof([(quant, float(fit.uncertainty["quantisation_test"]["draws"])), (ns, math.inf),
                            (harmonic2, math.inf)])
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
