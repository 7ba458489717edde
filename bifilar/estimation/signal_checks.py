"""Health checks of a recording and of a period fit: is it an oscillation at
all, are the residuals white, what spectral peaks remain, and how much the
serial correlation of the residuals inflates the period's std.  Part of
:mod:`bifilar.estimation.signal`; times in s, frequencies in Hz, samples in
the signal's unit ``[y]``.

Rules (stated in docs/real_data.md, section "Rules")
-----------------------------------------------------
*Significant spectral peak.*  The periodogram ``I_k`` of the linearly
detrended, uniformly sampled record (no taper, no padding; ``m`` Fourier
frequencies) is compared with the local noise level ``S_k`` = median of
``I`` over the neighbouring bins (``k/2 .. 3k/2``, at least 50 bins each
side, the peak's own +-3 bins excluded) divided by ``ln 2`` (the median of
an exponential variable).  Under pure noise ``I_k / S_k`` is exponential
with mean 1, so a peak is significant at false-alarm probability
``PEAK_ALPHA`` (over all ``m`` bins, Bonferroni) when
``I_k / S_k > ln(m / PEAK_ALPHA)``.

*Serial correlation.*  The period's least-squares std assumes white
residuals; the error of a fitted frequency is in fact set by the noise
spectral density *at that frequency*.  When the Ljung-Box test
(``LB_LAGS`` lags) rejects whiteness at ``LB_ALPHA``, an autoregressive
model AR(p) is fitted to the residuals (Yule-Walker, order ``p <=
AR_MAX_ORDER`` by AIC) and the std is multiplied by
``sqrt(S_AR(f0) / gamma(0))`` (at least 1): the ratio of the residual
spectral density at the oscillation frequency to its white-noise value
(for AR(1) noise this is ``sqrt((1 + rho) / (1 - rho))`` at low
frequency).  A parametric spectrum is used because the fit itself has
removed the residual power right at ``f0`` (a notch ~1/T_record wide) that
a non-parametric estimate there would see; a low-order AR model cannot
follow that notch and reports the level around it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats
from scipy.linalg import solve_toeplitz

from .signal_io import SignalError
from .signal_models import _uniform

#: false-alarm probability of the spectral-peak test over all bins
PEAK_ALPHA = 1e-3
#: a fit explaining less than this fraction of the variance is refused
R2_MIN = 0.1
#: a record must hold at least this many cycles of its oscillation
MIN_CYCLES = 2.0
#: Ljung-Box: number of lags and significance level of the whiteness test
LB_LAGS = 20
LB_ALPHA = 0.01
#: highest order of the AR model of the residuals (serial correlation)
AR_MAX_ORDER = 20


def periodogram(t, y):
    """Periodogram of the linearly detrended record on its uniform grid:
    ``(f [Hz], I [y^2], T_rec [s])`` at the Fourier frequencies ``k / T_rec``,
    ``k = 1 .. n/2`` (no taper, no padding)."""
    yu, dt = _uniform(t, y)
    n = yu.size
    x = np.arange(n, dtype=float)
    yd = yu - np.polyval(np.polyfit(x, yu, 1), x)
    F = np.fft.rfft(yd)
    I = (F.real ** 2 + F.imag ** 2) / n
    f = np.fft.rfftfreq(n, dt)
    return f[1:], I[1:], n * dt


def _local_level(I, k):
    """Noise level (mean of an exponential) around bin ``k`` from the median
    of the neighbouring bins, the peak's own +-3 bins excluded."""
    w = max(50, k // 2)
    lo, hi = max(0, k - w), min(I.size, k + w + 1)
    nb = np.r_[I[lo:max(lo, k - 3)], I[min(hi, k + 4):hi]]
    if nb.size < 5:
        nb = np.delete(I, np.arange(max(0, k - 3), min(I.size, k + 4)))
    med = float(np.median(nb)) if nb.size else 0.0
    return med / math.log(2.0)


def peak_threshold(m: int) -> float:
    """Ratio peak / local noise level above which a peak among ``m`` bins is
    significant at ``PEAK_ALPHA``."""
    return math.log(max(m, 1) / PEAK_ALPHA)


def require_oscillation(t, y) -> dict:
    """Refuse (``SignalError`` on ``signal``) a record that holds no
    oscillation: its strongest spectral component must be a significant peak
    (see the module docstring) at two or more cycles per record.

    Returns ``{"frequency": Hz, "ratio": peak / noise level,
    "threshold": ..., "cycles": ...}`` of the strongest peak.
    """
    f, I, T_rec = periodogram(t, y)
    # a constant or straight record leaves only the rounding of its
    # detrending (mean square 2 sum(I) / n by Parseval), not exact zeros
    n = 2 * I.size
    scale = float(np.max(np.abs(y))) if np.size(y) else 0.0
    if I.size < 4 or not 2.0 * float(np.sum(I)) / n > (1e-9 * scale) ** 2:
        raise SignalError("signal", "the record is constant (or a straight line): no oscillation")
    thr = peak_threshold(I.size)
    k = int(np.argmax(I))
    slow = f * T_rec < MIN_CYCLES - 0.5
    if slow[k] and not np.all(slow):
        # a slow swell (a baseline wandering through part of a cycle) may
        # outweigh the oscillation: take the strongest peak (a local maximum,
        # not the swell's falling leakage) with enough cycles when it is
        # significant
        i = np.arange(1, I.size - 1)
        peaks = i[~slow[i] & (I[i] > I[i - 1]) & (I[i] >= I[i + 1])]
        if peaks.size:
            k2 = int(peaks[np.argmax(I[peaks])])
            S2 = _local_level(I, k2)
            if S2 > 0 and I[k2] / S2 >= thr:
                k = k2
    S = _local_level(I, k)
    ratio = float(I[k] / S) if S > 0 else float("inf")
    cycles = float(f[k] * T_rec)
    if ratio < thr:
        raise SignalError("signal", f"no significant spectral peak: the strongest component "
                                    f"({f[k]:.4g} Hz) is {ratio:.1f} x the local noise level, below the "
                                    f"{thr:.1f} x needed (false-alarm probability {PEAK_ALPHA:g}); "
                                    f"noise, a spike or a sweep is not an oscillation")
    if cycles < MIN_CYCLES - 0.5:
        raise SignalError("signal", f"fewer than {MIN_CYCLES:g} cycles: the strongest component is at "
                                    f"{f[k]:.4g} Hz, {cycles:.1f} cycles in the {T_rec:.4g} s record")
    return {"frequency": float(f[k]), "ratio": ratio, "threshold": thr, "cycles": cycles}


def residual_peaks(t, r, f0: float, max_peaks: int = 5) -> list[dict]:
    """Significant peaks left in the residuals ``r`` ([y]) of a fit with
    fundamental ``f0`` (Hz), strongest first: ``frequency`` (Hz), ``ratio``
    (to the local noise level) and ``harmonic`` (k if within 1.5 bins of
    ``k f0``, else None: an unmodelled oscillation)."""
    f, I, T_rec = periodogram(t, r)
    thr = peak_threshold(I.size)
    out = []
    I = I.copy()
    for _ in range(max_peaks):
        k = int(np.argmax(I))
        if I[k] <= 0:
            break
        S = _local_level(I, k)
        ratio = float(I[k] / S) if S > 0 else float("inf")
        if ratio < thr:
            break
        fk = float(f[k])
        h = round(fk / f0) if f0 > 0 else 0
        harm = int(h) if h >= 1 and abs(fk - h * f0) <= 1.5 / T_rec else None
        out.append({"frequency": fk, "ratio": ratio, "harmonic": harm})
        I[max(0, k - 3):k + 4] = 0.0
    return out


def ljung_box(r, lags: int = LB_LAGS) -> tuple[float, float]:
    """Ljung-Box statistic of ``r`` over ``lags`` lags and its p-value
    (chi^2 with ``lags`` degrees of freedom); small p = not white."""
    r = np.asarray(r, float) - np.mean(r)
    n = r.size
    lags = int(min(lags, n // 4))
    if lags < 1:
        return 0.0, 1.0
    ac = _autocov(r, lags)
    if ac[0] <= 0:
        return 0.0, 1.0
    rho = ac[1:] / ac[0]
    Q = float(n * (n + 2) * np.sum(rho ** 2 / (n - np.arange(1, lags + 1))))
    return Q, float(stats.chi2.sf(Q, lags))


def _autocov(x, L: int) -> np.ndarray:
    """Sums ``sum_t x_t x_{t+l}`` for l = 0 .. L, by FFT (O(n log n))."""
    n = x.size
    nfft = 1 << int(math.ceil(math.log2(2 * n)))
    F = np.fft.rfft(x, nfft)
    ac = np.fft.irfft(F.real ** 2 + F.imag ** 2, nfft)[:L + 1]
    return ac


def serial_factor(r, f0: float, dt: float, max_order: int = AR_MAX_ORDER) -> tuple[float, int]:
    """Factor (>= 1) by which serial correlation of the residuals ``r``
    inflates the white-noise std of a frequency fitted at ``f0`` (Hz),
    sampled every ``dt`` (s); and the AR order used.  See the module
    docstring: ``sqrt(S_AR(f0) / gamma(0))``."""
    rc = np.asarray(r, float) - np.mean(r)
    n = rc.size
    pmax = int(max(0, min(max_order, n // 10)))
    g = _autocov(rc, pmax) / n
    if not g[0] > 0:
        return 1.0, 0
    best = (n * math.log(g[0]), 0, np.zeros(0), g[0])
    for p in range(1, pmax + 1):
        try:
            a = solve_toeplitz(g[:p], g[1:p + 1])
        except np.linalg.LinAlgError:
            break
        s2 = float(g[0] - a @ g[1:p + 1])
        if not s2 > 0:
            break
        aic = n * math.log(s2) + 2 * p
        if aic < best[0]:
            best = (aic, p, a, s2)
    _, p, a, s2 = best
    z = np.exp(-2j * math.pi * f0 * dt * np.arange(1, p + 1))
    S = s2 / abs(1.0 - a @ z) ** 2
    return float(math.sqrt(max(S / g[0], 1.0))), int(p)


#: a record is quantised when its samples take at most this fraction of
#: distinct values and all lie on one lattice ``origin + k q``
LATTICE_MAX_LEVELS = 0.25
#: tolerance of the lattice test, in steps
LATTICE_TOL = 1e-3


def lattice_step(y) -> tuple[float, float] | None:
    """``(q, origin)`` ([y]) when every sample lies on the lattice
    ``origin + k q`` (integer k) with fewer distinct levels than
    ``LATTICE_MAX_LEVELS`` of the samples: a camera's pixel step, an ADC's
    least significant bit, or the last printed digit.  None otherwise."""
    y = np.asarray(y, float)
    u = np.unique(y)
    if u.size < 3 or u.size > LATTICE_MAX_LEVELS * y.size:
        return None
    d = np.diff(u)
    q = float(d.min())
    if not q > 0:
        return None
    k = (u - u[0]) / q
    if float(np.max(np.abs(k - np.round(k)))) > LATTICE_TOL:
        return None
    return q, float(u[0])


#: a gap between neighbouring levels within this fraction of a step of a
#: whole multiple m >= 2 of the local step holds m - 1 levels the record
#: never visited
LEVEL_GAP_TOL = 0.1
#: gaps on each side whose median is the local step of a gap
LEVEL_WINDOW = 5


@dataclass(frozen=True)
class Levels:
    """The quantisation levels of a record ([y]), increasing: a uniform
    lattice ``origin + k q`` (``uniform = (q, origin)``) or the record's own
    distinct values with the levels it skipped filled in (a monotone map of
    a lattice: pixels converted to an angle by ``atan``, ``asin`` or a
    calibration polynomial, an encoder printed in rounded radians).  Level
    ``k`` is ``values[k]``; beyond the ends the end steps continue."""

    values: np.ndarray
    uniform: tuple[float, float] | None = None

    def index(self, y) -> np.ndarray:
        """Continuous level index of ``y`` ([y]): integer at a level,
        linear in between (so rounding it picks the nearest level)."""
        y = np.asarray(y, float)
        if self.uniform is not None:
            q, o = self.uniform
            return (y - o) / q
        v = self.values
        k = np.interp(y, v, np.arange(v.size, dtype=float))
        lo, hi = y < v[0], y > v[-1]
        k[lo] = (y[lo] - v[0]) / (v[1] - v[0])
        k[hi] = v.size - 1 + (y[hi] - v[-1]) / (v[-1] - v[-2])
        return k

    def level(self, k) -> np.ndarray:
        """Value ([y]) of the integer level index ``k``."""
        k = np.asarray(k, float)
        if self.uniform is not None:
            q, o = self.uniform
            return q * k + o
        v = self.values
        m = v.size - 1
        y = np.interp(k, np.arange(v.size, dtype=float), v)
        lo, hi = k < 0, k > m
        y[lo] = v[0] + k[lo] * (v[1] - v[0])
        y[hi] = v[-1] + (k[hi] - m) * (v[-1] - v[-2])
        return y

    def step(self, y) -> np.ndarray:
        """Width ([y]) of the quantisation bin around each value of ``y``:
        half the distance between the neighbouring levels."""
        y = np.asarray(y, float)
        if self.uniform is not None:
            return np.full(y.shape, self.uniform[0])
        v = self.values
        w = np.r_[v[1] - v[0], 0.5 * (v[2:] - v[:-2]), v[-1] - v[-2]]
        return w[np.clip(np.round(self.index(y)).astype(int), 0, v.size - 1)]

    @property
    def typical_step(self) -> float:
        """Median width of the bins ([y])."""
        if self.uniform is not None:
            return self.uniform[0]
        return float(np.median(self.step(self.values)))


def quantisation_levels(y) -> Levels | None:
    """The levels of a quantised record: ``Levels`` when the samples take
    at most ``LATTICE_MAX_LEVELS`` as many distinct values as there are
    samples, whatever their spacing (a noisy or sub-pixel record takes as
    many values as samples); None otherwise.  A uniform lattice
    (:func:`lattice_step`) is kept exact; otherwise a gap between
    neighbouring distinct values that is ``m >= 2`` times (within
    ``LEVEL_GAP_TOL``) the median of its ``LEVEL_WINDOW`` neighbouring gaps
    on each side (the local step; robust to a few other skipped levels, and
    centred where the steps change smoothly) holds ``m - 1`` levels the
    record skipped, filled in evenly."""
    y = np.asarray(y, float)
    lat = lattice_step(y)
    if lat is not None:
        return Levels(np.unique(y), uniform=lat)
    u = np.unique(y)
    if u.size < 3 or u.size > LATTICE_MAX_LEVELS * y.size:
        return None
    d = np.diff(u)
    pad = np.r_[np.full(LEVEL_WINDOW, np.nan), d, np.full(LEVEL_WINDOW, np.nan)]
    win = np.lib.stride_tricks.sliding_window_view(pad, 2 * LEVEL_WINDOW + 1)
    win = np.delete(win, LEVEL_WINDOW, axis=1)  # the gap itself
    with np.errstate(all="ignore"):
        s = np.nanmedian(win, axis=1) if win.shape[1] else np.full(d.size, np.nan)
        r = d / s
    m = np.round(r)
    fill = (m >= 2) & (np.abs(r - m) <= LEVEL_GAP_TOL)
    parts = [u[:1]]
    for i in range(d.size):
        if fill[i]:
            parts.append(u[i] + d[i] * np.arange(1, int(m[i])) / m[i])
        parts.append(u[i + 1:i + 2])
    return Levels(np.concatenate(parts))
