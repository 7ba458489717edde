"""Fits of a recording's windows and the record's stationarity: one model
fitted to a stretch of samples (:func:`_fit_window`, with the models'
names and kinds), the same model refitted to each half or window of the
record (:func:`_window_fit`), and the split check whose disagreement beyond
noise widens the period's std (:func:`_stationarity`: Cochran's Q over the
windows).  SI units (time s, frequency Hz); samples in the recording's own
unit.  Split from :mod:`bifilar.estimation.signal` (its orchestration).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .signal_checks import residual_peaks
from .signal_io import SignalError
from .signal_models import (
    _fit_chirp,
    _fit_quadratic,
    _fit_three_mode,
    _fit_two_mode,
    _fit_viscous,
    _linear_amplitudes,
    _solve,
)
from .signal_result import PeriodFit, _build


#: cycles each half of the record needs for the non-stationarity check
MIN_WINDOW_CYCLES = 2.0


#: the windows disagree beyond noise when Cochran's Q exceeds this quantile
WINDOW_Q_LEVEL = 0.99


#: the viscous model whose frequency follows the envelope's square, tried
#: when a viscous fit's halves disagree (:func:`_amplitude_law`)
AMPLITUDE_LAW_MODEL = "viscous+chirp"


_KIND = {"viscous": ("viscous", False), "quadratic": ("quadratic", False),
         "quadratic+viscous": ("quadratic", True), "two_mode": ("two_mode", False),
         "three_mode": ("three_mode", False), AMPLITUDE_LAW_MODEL: ("chirp", False)}


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


def _residual_peaks(fit: PeriodFit):
    try:
        peaks = residual_peaks(fit.t_used, fit.residuals, fit.frequency)
    except (ValueError, np.linalg.LinAlgError):
        return
    known = [m["frequency"] for m in fit.modes]
    band = 1.5 / (fit.t1 - fit.t0)
    for pk in peaks:
        if pk["harmonic"] is None and any(abs(pk["frequency"] - f) <= band for f in known):
            pk["harmonic"] = 1
    fit.residual_check["peaks"] = peaks
    other = [pk for pk in peaks if pk["harmonic"] is None]
    harm = sorted({pk["harmonic"] for pk in peaks if pk["harmonic"] is not None and pk["harmonic"] >= 2})
    if harm:
        fit.notes.append("residuals keep harmonics " + ", ".join(f"{h}f" for h in harm)
                         + " of the oscillation (a sensor or motion not linear in the angle); orthogonal "
                           "to the fundamental, they hardly bias the period")
    for pk in (pk for pk in peaks if pk["harmonic"] == 1):
        # within 1.5/T_record of a fitted mode: unresolved from it over the record, so NOT
        # orthogonal to it (e.g. another mode's 2nd harmonic beside the torsion, camera23)
        near = min(known + [fit.frequency], key=lambda f: abs(pk["frequency"] - f))
        fit.notes.append(f"residuals keep an oscillation at {pk['frequency']:.4g} Hz "
                         f"({pk['ratio']:.0f} x the noise level) within 1.5/T_record = {band:.3g} Hz of the "
                         f"fitted mode at {near:.4g} Hz: unresolved from it over the record and not orthogonal "
                         f"to it, it can bias that mode's period beyond the stated std")
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
