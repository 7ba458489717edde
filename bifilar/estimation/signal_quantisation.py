"""An undithered quantised recording (a camera's pixels, an encoder's
steps): re-quantised copies of the fit give the period's spread the steps
cause (:func:`_quantisation`), copies about the level a record rests on
when it does (:func:`_rest_on_level`).  SI units (time s); samples in the
recording's own unit.  Split from :mod:`bifilar.estimation.signal`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .signal_checks import quantisation_levels
from .signal_io import SignalError
from .signal_models import _model, further_modes
from .signal_result import PeriodFit
from .signal_windows import _KIND, _fit_window


#: a quantised record is simulated when its noise before quantisation is
#: below this many steps (above it the noise dithers the steps away)
DITHER_STEPS = 0.5


#: simulated records of the quantisation check
QUANT_DRAWS = 40


def _turned(p, kind: str, dphi: float) -> np.ndarray:
    """Parameters ``p`` of a ``kind`` model with every oscillation's phase
    advanced by ``dphi`` (rad): each ``(a, b)`` pair turned."""
    pb = np.array(p, dtype=float)
    for i in [2, *further_modes(kind, pb.size)]:
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
