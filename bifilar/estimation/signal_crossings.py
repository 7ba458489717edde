"""Period from interpolated crossings of the mean level (the
experimenter's method).  Part of :mod:`bifilar.estimation.signal`; times in s,
samples in the signal's unit ``[y]``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .signal_io import SignalError, _validate, _window
from .signal_models import _noise_sigma, _spectral_peaks, _spectrum

#: the crossings may count at most this many cycles fewer, over their span,
#: than the record's strongest spectral peak: more are cycles lost inside
#: the hysteresis band (:func:`_require_cycles_counted`)
MAX_LOST_CYCLES = 1.0

@dataclass
class CrossingPeriod:
    """Period from interpolated crossings of the mean level.

    Attributes
    ----------
    period : float
        s.  Least-squares slope of crossing time against cycle number, both
        directions pooled with separate intercepts (so a level slightly off
        the true centre cancels).
    std : float
        s, 1-sigma standard error of ``period`` from the regression residuals.
    mean_period : float
        s, mean of the successive same-direction crossing intervals (what an
        experimenter with a stopwatch computes).
    scatter : float
        s, sample standard deviation of the individual periods (the
        cycle-to-cycle spread; the mean's error is much smaller because the
        intervals telescope).
    n_periods : int
        Number of same-direction intervals.
    level, hysteresis : float
        Crossing level and half-width of the hysteresis band, in [y].
    up_times, down_times : ndarray
        Crossing times (s), upward and downward.
    periods : ndarray
        Individual same-direction intervals (s).
    """

    period: float
    std: float
    mean_period: float
    scatter: float
    n_periods: int
    level: float
    hysteresis: float
    up_times: np.ndarray = field(repr=False)
    down_times: np.ndarray = field(repr=False)
    periods: np.ndarray = field(repr=False)

    @property
    def frequency(self) -> float:
        """Hz."""
        return 1.0 / self.period


def _crossing_time(t, d, i0, i1):
    """Time where ``d`` crosses zero between samples i0 and i1 (inclusive):
    zero of a straight line fitted through them (linear interpolation when
    they are two)."""
    ts, ds = t[i0:i1 + 1], d[i0:i1 + 1]
    if ts.size > 2:
        tm = ts.mean()
        A = np.vstack([np.ones_like(ts), ts - tm]).T
        (c, s), *_ = np.linalg.lstsq(A, ds, rcond=None)
        if s != 0 and np.sign(s) == np.sign(ds[-1] - ds[0]):
            tc = tm - c / s
            if ts[0] <= tc <= ts[-1]:
                return float(tc)
    # fall back on the sign change nearest the middle
    sc = np.nonzero(np.sign(ds[:-1]) != np.sign(ds[1:]))[0]
    k = sc[np.argmin(np.abs(sc - (ts.size - 1) / 2))] if sc.size else 0
    t0, t1, d0, d1 = ts[k], ts[k + 1], ds[k], ds[k + 1]
    return float(t0 - d0 * (t1 - t0) / (d1 - d0)) if d1 != d0 else float(0.5 * (t0 + t1))


def _merge_glitches(t, spans):
    """Noise spikes larger than the hysteresis band make bursts of crossings
    within a small fraction of a half-period.  Group crossings closer than
    0.2 x the median spacing: an odd group is one real crossing (refitted
    over the whole group), an even group is a glitch and is dropped."""
    if len(spans) < 3:
        return spans
    mids = np.array([0.5 * (t[a] + t[b]) for a, b, _ in spans])
    gaps = np.diff(mids)
    thr = 0.2 * float(np.median(gaps))
    out, group = [], [spans[0]]
    for k in range(1, len(spans)):
        if gaps[k - 1] < thr:
            group.append(spans[k])
            continue
        if len(group) % 2:
            out.append((group[0][0], group[-1][1], group[0][2]))
        group = [spans[k]]
    if len(group) % 2:
        out.append((group[0][0], group[-1][1], group[0][2]))
    return out


def _require_cycles_counted(t, y, period: float, t_cross, h: float, frequency: float | None = None):
    """Refuse (``SignalError`` on ``signal``) crossings that time a multiple
    of the period: cycles whose swing stays inside the hysteresis band (half-
    width ``h``, [y]) make no crossings, and when they are half the
    same-direction intervals or more, the median interval that numbers the
    cycles is two or three periods, so two or three cycles count as one
    (a 1 s sine losing two-thirds of its cycles: 3.16 +- 0.18 s).  An
    independent frequency (Hz) counts the cycles: ``frequency`` where given
    (the fit's, when the crossings cross-check it), else the strongest
    spectral peak of the window (``t`` s, ``y`` [y];
    :func:`.signal_models._spectral_peaks`, which sees a cycle under the
    band).  Over the crossings' span (``t_cross``, s) the crossings'
    ``period`` (s) may give at most ``MAX_LOST_CYCLES`` fewer cycles than
    it.  Only fewer: crossings counting more cycles time a faster
    oscillation beside it (a second mode of comparable amplitude), which the
    fit's cross-check notes."""
    what = "the fit's frequency"
    if frequency is None:
        peaks = _spectral_peaks(*_spectrum(t, y), k=1)
        frequency = peaks[0] if peaks else math.nan
        what = "the record's spectral peak"
    if not period > 0 or not frequency > 0:
        return
    span = float(np.max(t_cross) - np.min(t_cross))
    lost = (frequency - 1.0 / period) * span
    if lost > MAX_LOST_CYCLES:
        raise SignalError("signal", f"the crossings count {span / period:.1f} cycles in {span:.4g} s (period "
                                    f"{period:.4g} s) where {what} at {frequency:.4g} Hz has "
                                    f"{span * frequency:.1f}: cycles lost inside the hysteresis band +-{h:.3g} "
                                    "about the level; no period from crossings")


def period_from_crossings(t, y, level: float | None = None, hysteresis: float | None = None,
                          t_start: float | None = None, t_stop: float | None = None,
                          frequency: float | None = None) -> CrossingPeriod:
    """Period from successive same-direction crossings of the mean level.

    Parameters
    ----------
    t : array_like
        Sample times, s, strictly increasing.
    y : array_like
        Samples, [y].
    level : float, optional
        Crossing level in [y]; default the mean of ``y`` in the window.
    hysteresis : float, optional
        Half-width in [y] of the band the signal must traverse for a crossing
        to count; default 3 x the white-noise level (from second differences),
        so noise near the level does not create spurious crossings.
    t_start, t_stop : float, optional
        Analysis window, s.
    frequency : float, optional
        Hz, an independent estimate of the oscillation's frequency that
        counts its cycles (the fit's); default the window's strongest
        spectral peak.

    Returns
    -------
    CrossingPeriod
        Period (s) with its standard error, the mean interval and scatter.

    Raises
    ------
    SignalError
        ``signal`` if fewer than two full periods are found, or if the
        crossings count more than ``MAX_LOST_CYCLES`` cycles fewer than
        ``frequency`` (or the spectral peak) over their span (cycles lost inside the
        hysteresis band: :func:`_require_cycles_counted`).
    """
    t, y = _validate(t, y)
    t, y = _window(t, y, t_start, t_stop)
    lvl = float(np.mean(y)) if level is None else float(level)
    h = 3.0 * _noise_sigma(y) if hysteresis is None else float(hysteresis)
    d = y - lvl
    state = np.where(d > h, 1, np.where(d < -h, -1, 0))
    idx = np.nonzero(state)[0]
    st = state[idx]
    ch = np.nonzero(st[1:] != st[:-1])[0]
    # (first, last) sample bracketing each crossing, and its direction
    spans = [(int(idx[c]), int(idx[c + 1]), int(st[c + 1])) for c in ch]
    spans = _merge_glitches(t, spans)
    times = [_crossing_time(t, d, i0, i1) for i0, i1, _ in spans]
    dirs = [dr for _, _, dr in spans]
    times = np.asarray(times)
    dirs = np.asarray(dirs)
    up, down = times[dirs > 0], times[dirs < 0]
    if times.size < 5 or up.size < 2 or down.size < 2:
        raise SignalError("signal", f"only {times.size} crossings of level {lvl:g} found; "
                                    f"need at least two full periods")
    # cycle numbers by rounding on a rough period, so that a crossing lost
    # to noise does not shift the count; t = a + T n + delta [downward]
    T_rough = float(np.median(np.concatenate([np.diff(up), np.diff(down)])))
    n_up = np.round((up - up[0]) / T_rough)
    n_dn = np.round((down - up[0]) / T_rough - 0.5) + 0.5
    periods = np.concatenate([np.diff(up)[np.diff(n_up) == 1], np.diff(down)[np.diff(n_dn) == 1]])
    if periods.size < 2:
        raise SignalError("signal", "fewer than two complete same-direction periods between crossings")
    n_all = np.concatenate([n_up, n_dn])
    t_all = np.concatenate([up, down])
    X = np.vstack([np.ones(t_all.size), n_all, np.r_[np.zeros(up.size), np.ones(down.size)]]).T
    coef, *_ = np.linalg.lstsq(X, t_all, rcond=None)
    res = t_all - X @ coef
    dof = t_all.size - 3
    if dof > 0:
        s2 = float(res @ res) / dof
        cov = s2 * np.linalg.inv(X.T @ X)
        std = float(math.sqrt(cov[1, 1]))
    else:
        std = float("nan")
    _require_cycles_counted(t, y, float(coef[1]), t_all, h, frequency)
    return CrossingPeriod(
        period=float(coef[1]), std=std, mean_period=float(periods.mean()),
        scatter=float(periods.std(ddof=1)), n_periods=int(periods.size), level=lvl,
        hysteresis=h, up_times=up, down_times=down, periods=periods)


