"""Period of a recorded oscillation, with an honest uncertainty.

Pure functions and result dataclasses; SI units throughout (time in s,
frequency in Hz, angular rates in rad/s).  The signal itself may be in any
unit (volts of a rate gyro, pixels of a camera, radians): amplitudes, offsets,
residuals and noise are reported in that same unit, written ``[y]`` below.

Public API
----------
``read_signal(path, column=None, sample_rate=None) -> (t, y, meta)``
    CSV/TSV text or MATLAB ``.mat`` -> time (s), samples ([y]), metadata.
``fit_period(t, y, model="viscous", ...) -> PeriodFit``
    Nonlinear least-squares fit of a damped-oscillation model
    (``viscous``, ``quadratic``, ``two_mode`` or ``auto``).
``period_from_crossings(t, y, ...) -> CrossingPeriod``
    The experimenter's method: interpolated crossings of the mean level.
``plot_fit(fit, t, y, path)``
    PNG of the signal, the fitted model and the residuals.

Uncertainty
-----------
The covariance of the fitted parameters is ``s^2 (J^T J)^-1`` with ``s^2``
the residual variance (``RSS / (n - p)``).  That is exact for white noise.
When the residuals are autocorrelated (lag-1 autocorrelation ``rho`` above
the white-noise 95 % bound ``2/sqrt(n)``) the effective number of independent
samples is ``n (1 - rho) / (1 + rho)`` and the standard deviations are
multiplied by ``sqrt((1 + rho) / (1 - rho))``; the factor is reported as
``PeriodFit.std_inflation`` and the uninflated value as ``std_raw``.  For an
AR(1) residual this factor equals the ratio of the noise spectral density at
a low frequency to its white-noise value, i.e. it is the correct correction
for a signal much slower than the sampling rate.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from scipy import optimize

from bifilar.errors import InputError

__all__ = [
    "SignalError",
    "CrossingPeriod",
    "PeriodFit",
    "read_signal",
    "fit_period",
    "period_from_crossings",
    "plot_fit",
    "MIN_SAMPLES",
    "MAX_NAN_FRACTION",
]

#: fewer samples than this cannot define a period with an uncertainty
MIN_SAMPLES = 20
#: NaN / missing samples up to this fraction are dropped with a warning
MAX_NAN_FRACTION = 0.01

_TIME_RE = re.compile(
    r"^(t|time)([\s_]*[\(\[]\s*(s|sec|seconds)\s*[\)\]]|[\s_]+(s|sec|seconds))?$"
)
_RATE_NAMES = {
    "actualrate", "samplerate", "sample_rate", "samplingrate", "sampling_rate",
    "fs", "srate", "rate", "samplefrequency", "sample_frequency", "fsample",
}
_MISSING = {"", "nan", "na", "n/a", "null", "none", "-nan"}


class SignalError(InputError):
    """A recorded signal cannot be read or analysed.

    ``str(err)`` is ``"field: message"``; ``field`` names the offending
    input: ``"path"`` (the file), ``"--column"``, ``"--sample-rate"``,
    ``"time"`` (the time vector) or ``"signal"`` (the samples themselves).
    """

    def __init__(self, field: str, message: str):
        super().__init__(field, message)


# ---------------------------------------------------------------------------
# readers
# ---------------------------------------------------------------------------

def _is_time_name(name: str) -> bool:
    return bool(_TIME_RE.match(str(name).strip().lower()))


def _check_rate(sample_rate) -> float | None:
    if sample_rate is None:
        return None
    try:
        fs = float(sample_rate)
    except (TypeError, ValueError):
        raise SignalError("--sample-rate", f"not a number: {sample_rate!r}") from None
    if not math.isfinite(fs) or fs <= 0:
        raise SignalError("--sample-rate", f"must be a positive number of Hz, got {sample_rate!r}")
    return fs


def read_signal(path, column: str | None = None, sample_rate: float | None = None):
    """Read one recorded signal.

    Parameters
    ----------
    path : str or Path
        A text table (``.csv``, ``.tsv``, ``.txt``, ...; comma, tab,
        semicolon or whitespace separated, one header row, ``#`` comments
        skipped) or a MATLAB ``.mat`` file (v5/v7, read by
        :func:`scipy.io.loadmat`).
    column : str, optional
        Text: the signal column (default: the first column that is not the
        time column).  MAT: the variable (default: the first numeric 1-D
        array that is not time-like).
    sample_rate : float, optional
        Sample rate in Hz.  When given, ``t = arange(n) / sample_rate`` and a
        time column, if any, is ignored.  Otherwise text files need a time
        column named ``t`` or ``time`` (case-insensitive, seconds; ``time_s``
        and ``time (s)`` also accepted) and MAT files a scalar variable named
        like ``ActualRate``, ``SampleRate`` or ``fs`` (Hz) or a time vector.

    Returns
    -------
    t : ndarray
        Sample times in s, strictly increasing.
    y : ndarray
        Samples, in the unit of the file.
    meta : dict
        ``path``, ``format``, ``column``, ``columns`` (all available),
        ``time_source``, ``sample_rate`` (Hz, nominal or median),
        ``sample_rate_source``, ``n_samples``, ``n_dropped``, ``duration``
        (s), ``warnings`` (list of str) and, for MAT files, ``fields``
        (the scalar and string variables, e.g. the trial description).

    Raises
    ------
    SignalError
        Missing or unreadable file (``path``), unknown column (``--column``,
        listing the available ones), no way to know the time
        (``--sample-rate``), non-numeric data, more than 1 % NaN or fewer than
        ``MIN_SAMPLES`` samples (``signal``), non-increasing time (``time``).
    """
    fs = _check_rate(sample_rate)
    p = Path(path)
    if not p.exists():
        raise SignalError("path", f"no such file: {p}")
    if not p.is_file():
        raise SignalError("path", f"not a file: {p}")
    if p.suffix.lower() == ".mat":
        t, y, meta = _read_mat(p, column, fs)
    else:
        t, y, meta = _read_text(p, column, fs)
    return _finish(t, y, meta)


def _sniff_delimiter(line: str) -> str | None:
    for d in ("\t", ",", ";"):
        if d in line:
            return d
    return None  # whitespace


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return s.strip().lower() in _MISSING - {""}


def _parse_column(rows, linenos, idx: int, name: str, fname: str) -> np.ndarray:
    out = np.empty(len(rows))
    for k, row in enumerate(rows):
        cell = row[idx] if idx < len(row) else ""
        try:
            out[k] = float(cell)
        except ValueError:
            if cell.strip().lower() in _MISSING:
                out[k] = np.nan
            else:
                raise SignalError(
                    "signal",
                    f"non-numeric value {cell!r} in column {name!r} at line "
                    f"{linenos[k]} of {fname}") from None
    return out


def _read_text(p: Path, column, fs):
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise SignalError("path", f"{p.name} is not a text table (and not a .mat file)") from None
    # comment lines are skipped; a blank line between data rows is a missing
    # sample (NaN), so that times derived from a sample rate stay right
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines()) if not ln.lstrip().startswith("#")]
    while lines and not lines[0][1].strip():
        lines.pop(0)
    while lines and not lines[-1][1].strip():
        lines.pop()
    if not lines:
        raise SignalError("signal", f"{p.name} is empty")
    delim = _sniff_delimiter(lines[0][1])

    def split(s: str) -> list[str]:
        cells = s.split(delim) if delim else s.split()
        return [c.strip().strip('"').strip("'").strip() for c in cells]

    warnings_: list[str] = []
    header = split(lines[0][1])
    if all(_is_number(c) for c in header):
        names = [f"col{i + 1}" for i in range(len(header))]
        data = lines
        warnings_.append(f"no header row; columns named {', '.join(names)}")
    else:
        names = header
        data = lines[1:]
    time_idx = next((i for i, n in enumerate(names) if _is_time_name(n)), None)

    if column is None:
        cand = [i for i in range(len(names)) if i != time_idx]
        if not cand:
            raise SignalError("--column", f"{p.name} has only a time column ({names[time_idx]!r})")
        col_idx = cand[0]
    else:
        col = str(column)
        col_idx = next((i for i, n in enumerate(names) if n == col), None)
        if col_idx is None:
            col_idx = next((i for i, n in enumerate(names) if n.lower() == col.lower()), None)
        if col_idx is None:
            raise SignalError("--column", f"no column {col!r} in {p.name}; available: {', '.join(names)}")
        if col_idx == time_idx and fs is None:
            raise SignalError("--column", f"{col!r} is the time column of {p.name}; "
                                          f"choose one of {', '.join(n for n in names if n != col)}")
    rows = [split(ln) for _, ln in data]
    linenos = [i for i, _ in data]
    y = _parse_column(rows, linenos, col_idx, names[col_idx], p.name)
    meta: dict[str, Any] = {
        "path": str(p), "format": "text", "delimiter": delim or "whitespace",
        "column": names[col_idx], "columns": list(names), "warnings": warnings_,
    }
    if fs is not None:
        t = np.arange(len(y)) / fs
        meta.update(time_source="sample_rate", sample_rate=fs, sample_rate_source="argument")
        if time_idx is not None:
            warnings_.append(f"time column {names[time_idx]!r} ignored: sample_rate given")
    elif time_idx is not None:
        t = _parse_column(rows, linenos, time_idx, names[time_idx], p.name)
        meta.update(time_source=f"column {names[time_idx]!r}", sample_rate=None,
                    sample_rate_source=f"median step of column {names[time_idx]!r}")
    else:
        raise SignalError(
            "--sample-rate",
            f"{p.name} has no time column (named 't' or 'time'; columns: "
            f"{', '.join(names)}); give the sample rate in Hz")
    return t, y, meta


def _as_1d_numeric(v) -> np.ndarray | None:
    if isinstance(v, np.ndarray) and v.dtype.kind in "iuf" and v.size >= 2:
        s = np.squeeze(v)
        if s.ndim == 1:
            return s.astype(float)
    return None


def _read_mat(p: Path, column, fs):
    from scipy.io import loadmat

    try:
        m = loadmat(str(p))
    except NotImplementedError:
        raise SignalError("path", f"{p.name} is a MATLAB v7.3 (HDF5) file; save it with -v7") from None
    except Exception as exc:  # scipy raises several types for corrupt files
        raise SignalError("path", f"cannot read {p.name} as a MAT file ({exc})") from None
    vars_ = {k: v for k, v in m.items() if not k.startswith("__")}
    numeric = [k for k, v in vars_.items() if _as_1d_numeric(v) is not None]
    warnings_: list[str] = []
    fields: dict[str, Any] = {}
    for k, v in vars_.items():
        if isinstance(v, np.ndarray):
            if v.dtype.kind in "iuf" and v.size == 1:
                fields[k] = v.item()
            elif v.dtype.kind == "U" and v.size <= 1:
                fields[k] = str(v.item()) if v.size else ""

    if column is None:
        cand = [k for k in numeric if not _is_time_name(k)]
        if not cand:
            raise SignalError("--column", f"no numeric 1-D variable in {p.name}; variables: {', '.join(vars_)}")
        name = cand[0]
    else:
        name = column if column in vars_ else next(
            (k for k in vars_ if k.lower() == str(column).lower()), None)
        if name is None:
            raise SignalError("--column", f"no variable {column!r} in {p.name}; available: "
                                          f"{', '.join(numeric) or '(no numeric 1-D variable)'}"
                                          f" (all: {', '.join(vars_)})")
        if _as_1d_numeric(vars_[name]) is None:
            v = vars_[name]
            raise SignalError("--column", f"variable {name!r} of {p.name} is not a numeric 1-D array "
                                          f"(dtype {getattr(v, 'dtype', type(v))}, shape {getattr(v, 'shape', '?')}); "
                                          f"numeric 1-D variables: {', '.join(numeric) or 'none'}")
    y = _as_1d_numeric(vars_[name])
    meta: dict[str, Any] = {"path": str(p), "format": "mat", "column": name,
                            "columns": list(numeric), "fields": fields, "warnings": warnings_}
    rate_var = next((k for k in vars_ if k.lower() in _RATE_NAMES and isinstance(vars_[k], np.ndarray)
                     and vars_[k].dtype.kind in "iuf" and vars_[k].size == 1), None)
    if fs is not None:
        t = np.arange(len(y)) / fs
        meta.update(time_source="sample_rate", sample_rate=fs, sample_rate_source="argument")
        if rate_var is not None and not np.isclose(float(vars_[rate_var].item()), fs):
            warnings_.append(f"sample_rate {fs:g} Hz given overrides {rate_var} = "
                             f"{float(vars_[rate_var].item()):g} Hz in the file")
        return t, y, meta
    if rate_var is not None:
        fsv = float(vars_[rate_var].item())
        if not math.isfinite(fsv) or fsv <= 0:
            raise SignalError("--sample-rate", f"{rate_var} = {fsv!r} in {p.name} is not a sample rate; give one")
        t = np.arange(len(y)) / fsv
        meta.update(time_source="sample_rate", sample_rate=fsv, sample_rate_source=f"variable {rate_var!r}")
        return t, y, meta
    tvar = next((k for k in numeric if _is_time_name(k) and _as_1d_numeric(vars_[k]).size == y.size), None)
    if tvar is not None:
        meta.update(time_source=f"variable {tvar!r}", sample_rate=None,
                    sample_rate_source=f"median step of variable {tvar!r}")
        return _as_1d_numeric(vars_[tvar]), y, meta
    raise SignalError("--sample-rate", f"{p.name} has no sample-rate variable (ActualRate, SampleRate, fs) "
                                       f"and no time vector; give the sample rate in Hz")


def _finish(t: np.ndarray, y: np.ndarray, meta: dict):
    n = len(y)
    bad = ~np.isfinite(y) | ~np.isfinite(t)
    nb = int(bad.sum())
    meta["n_dropped"] = nb
    if nb:
        if nb > max(1, int(MAX_NAN_FRACTION * n)):
            raise SignalError("signal", f"{nb} of {n} samples of {meta['column']!r} are NaN or missing "
                                        f"(more than {MAX_NAN_FRACTION:.0%}); clean the recording")
        t, y = t[~bad], y[~bad]
        meta["warnings"].append(f"dropped {nb} NaN/missing sample(s) of {n}")
    if len(y) < MIN_SAMPLES:
        raise SignalError("signal", f"only {len(y)} usable samples in {meta['column']!r}; "
                                    f"need at least {MIN_SAMPLES}")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise SignalError("time", f"time is not strictly increasing at sample {i + 2} "
                                  f"(t = {t[i]:g} s then {t[i + 1]:g} s)")
    if meta.get("sample_rate") is None:
        meta["sample_rate"] = float(1.0 / np.median(dt))
    meta["n_samples"] = int(len(y))
    meta["duration"] = float(t[-1] - t[0])
    return t, y, meta


# ---------------------------------------------------------------------------
# helpers: validation, spectra, noise
# ---------------------------------------------------------------------------

def _validate(t, y) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if t.shape != y.shape:
        raise SignalError("signal", f"t and y differ in length ({t.size} vs {y.size})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise SignalError("signal", "t and y must be finite (read_signal drops NaNs)")
    if t.size < MIN_SAMPLES:
        raise SignalError("signal", f"only {t.size} samples; need at least {MIN_SAMPLES}")
    if np.any(np.diff(t) <= 0):
        raise SignalError("time", "time is not strictly increasing")
    return t, y


def _window(t, y, t_start, t_stop):
    lo = -np.inf if t_start is None else float(t_start)
    hi = np.inf if t_stop is None else float(t_stop)
    if lo >= hi:
        raise SignalError("--t-start", f"t_start = {lo:g} s is not before t_stop = {hi:g} s")
    m = (t >= lo) & (t <= hi)
    if m.sum() < MIN_SAMPLES:
        raise SignalError("--t-start" if t_start is not None else "--t-stop",
                          f"only {int(m.sum())} samples between {lo:g} s and {hi:g} s; "
                          f"need at least {MIN_SAMPLES}")
    return t[m], y[m]


def _uniform(t, y):
    d = np.diff(t)
    dt = float(np.median(d))
    if np.all(np.abs(d - dt) <= 1e-3 * dt):
        return y, dt
    tu = np.arange(t[0], t[-1], dt)
    return np.interp(tu, t, y), dt


def _spectrum(t, y, window=True, pad=8):
    """|FFT| of the linearly detrended signal, zero-padded ``pad`` times."""
    yu, dt = _uniform(t, y)
    n = yu.size
    x = np.arange(n)
    yd = yu - np.polyval(np.polyfit(x, yu, 1), x)
    w = np.hanning(n) if window else np.ones(n)
    nfft = 1 << int(math.ceil(math.log2(pad * n)))
    S = np.abs(np.fft.rfft(yd * w, nfft))
    f = np.fft.rfftfreq(nfft, dt)
    return f, S, n * dt


def _spectral_peaks(f, S, T_rec, k=1):
    """Frequencies (Hz) of the ``k`` largest local maxima above 1.5 cycles
    per record, refined by a parabola through the log magnitudes."""
    fmin = 1.5 / T_rec
    i = np.arange(1, S.size - 1)
    lm = i[(S[i] >= S[i - 1]) & (S[i] > S[i + 1]) & (f[i] >= fmin)]
    if lm.size == 0:
        return []
    lm = lm[np.argsort(S[lm])[::-1][:k]]
    df = f[1] - f[0]
    out = []
    for j in lm:
        l0, l1, l2 = np.log(S[j - 1:j + 2] + 1e-300)
        den = l0 - 2 * l1 + l2
        d = 0.5 * (l0 - l2) / den if den < 0 else 0.0
        out.append(float(f[j] + np.clip(d, -0.5, 0.5) * df))
    return out


def _robust_std(x) -> float:
    x = np.asarray(x, float)
    mad = np.median(np.abs(x - np.median(x)))
    return float(1.4826 * mad) if mad > 0 else float(np.std(x))


def _noise_sigma(y) -> float:
    """White-noise level of ``y`` from its second differences (a smooth
    oscillation contributes ``A w^2 dt^2`` there, negligible when sampled
    finely); robust (MAD) unless the signal is so quantised that the MAD is
    zero."""
    if len(y) < 4:
        return 0.0
    return _robust_std(np.diff(y, 2)) / math.sqrt(6.0)


def _lag1(r) -> float:
    r = np.asarray(r, float) - np.mean(r)
    den = float(r @ r)
    return float(r[:-1] @ r[1:] / den) if den > 0 else 0.0


# ---------------------------------------------------------------------------
# crossings
# ---------------------------------------------------------------------------

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


def period_from_crossings(t, y, level: float | None = None, hysteresis: float | None = None,
                          t_start: float | None = None, t_stop: float | None = None) -> CrossingPeriod:
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

    Returns
    -------
    CrossingPeriod
        Period (s) with its standard error, the mean interval and scatter.

    Raises
    ------
    SignalError
        ``signal`` if fewer than two full periods are found.
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
    return CrossingPeriod(
        period=float(coef[1]), std=std, mean_period=float(periods.mean()),
        scatter=float(periods.std(ddof=1)), n_periods=int(periods.size), level=lvl,
        hysteresis=h, up_times=up, down_times=down, periods=periods)


# ---------------------------------------------------------------------------
# models
# ---------------------------------------------------------------------------
# every model: y = c0 + c1 (t - tm) + oscillation(t - t0); linear amplitudes
# (a, b) with A cos(w tau + phi) = a cos(w tau) + b sin(w tau), i.e.
# A = hypot(a, b), phi = atan2(-b, a).

_NAMES = {
    "viscous": ("c0", "c1", "a", "b", "omega_d", "sigma"),
    "quadratic": ("c0", "c1", "a", "b", "omega", "kappa", "sigma"),
    "two_mode": ("c0", "c1", "a1", "b1", "omega1", "sigma1", "a2", "b2", "omega2", "sigma2"),
}


def _E(sg: float, tau: np.ndarray):
    """E = (1 - exp(-sg tau)) / sg and dE/dsg, with the series for small
    sg tau (E -> tau as sg -> 0)."""
    x = sg * tau
    small = np.abs(x) < 1e-4
    E = np.empty_like(tau)
    dE = np.empty_like(tau)
    if np.any(~small):
        xs, ts = x[~small], tau[~small]
        E[~small] = -np.expm1(-xs) / sg
        dE[~small] = (ts * np.exp(-xs) - E[~small]) / sg
    xs, ts = x[small], tau[small]
    E[small] = ts * (1 - xs / 2 + xs ** 2 / 6 - xs ** 3 / 24)
    dE[small] = ts ** 2 * (-0.5 + xs / 3 - xs ** 2 / 8 + xs ** 3 / 30)
    return E, dE


def _damped(a, b, w, sg, tau, J=None, col=0):
    e = np.exp(-sg * tau)
    c, s = np.cos(w * tau), np.sin(w * tau)
    osc = a * c + b * s
    if J is not None:
        J[:, col] = e * c
        J[:, col + 1] = e * s
        J[:, col + 2] = e * tau * (b * c - a * s)
        J[:, col + 3] = -tau * e * osc
    return e * osc


def _model(kind: str, p, t, t0, tm, want_jac=False):
    tau = t - t0
    s = t - tm
    J = np.empty((t.size, len(p))) if want_jac else None
    if J is not None:
        J[:, 0] = 1.0
        J[:, 1] = s
    y = p[0] + p[1] * s
    if kind == "viscous":
        y = y + _damped(p[2], p[3], p[4], p[5], tau, J, 2)
    elif kind == "two_mode":
        y = y + _damped(p[2], p[3], p[4], p[5], tau, J, 2) + _damped(p[6], p[7], p[8], p[9], tau, J, 6)
    elif kind == "quadratic":
        a, b, w, kap, sg = p[2:7]
        E, dE = _E(sg, tau)
        D = 1.0 + kap * E
        g = np.exp(-sg * tau) / D
        c, sn = np.cos(w * tau), np.sin(w * tau)
        osc = a * c + b * sn
        y = y + g * osc
        if J is not None:
            J[:, 2] = g * c
            J[:, 3] = g * sn
            J[:, 4] = g * tau * (b * c - a * sn)
            J[:, 5] = -g * E / D * osc
            J[:, 6] = (-tau * g - g * kap * dE / D) * osc
    else:  # pragma: no cover - guarded by fit_period
        raise ValueError(kind)
    return (y, J) if want_jac else y


def _envelope(kind: str, p, t, t0):
    """Amplitude envelope ([y]) of the (first) oscillation."""
    tau = t - t0
    if kind == "viscous" or kind == "two_mode":
        return math.hypot(p[2], p[3]) * np.exp(-p[5] * tau)
    E, _ = _E(p[6], tau)
    return math.hypot(p[2], p[3]) * np.exp(-p[6] * tau) / (1.0 + p[5] * E)


def _linear_amplitudes(t, y, t0, tm, omegas, sigmas, kap=0.0):
    """Least-squares offset, drift and (a, b) per mode for fixed nonlinear
    parameters (variable projection start)."""
    tau = t - t0
    cols = [np.ones_like(t), t - tm]
    for w, sg in zip(omegas, sigmas):
        g = np.exp(-sg * tau)
        if kap:
            g = g / (1.0 + kap * _E(sg, tau)[0])
        cols += [g * np.cos(w * tau), g * np.sin(w * tau)]
    A = np.vstack(cols).T
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    return coef, float(r @ r)


@dataclass
class _Raw:
    kind: str
    p: np.ndarray
    free: np.ndarray
    t0: float
    tm: float
    resid: np.ndarray
    J: np.ndarray
    cost: float
    converged: bool
    message: str


def _solve(kind, t, y, t0, tm, p0, free=None, squared=()) -> _Raw:
    """Levenberg-Marquardt (MINPACK) on the free parameters; parameters in
    ``squared`` must stay >= 0 and are solved for as ``q`` with ``p = q^2``
    (no bounded solver needed: the bounded 'trf' costs ten times more per
    iteration on long records).  The returned Jacobian is in the natural
    parameters."""
    p0 = np.asarray(p0, float).copy()
    free = np.ones(p0.size, bool) if free is None else np.asarray(free, bool)
    sq = np.zeros(p0.size, bool)
    sq[list(squared)] = True
    sq &= free
    p0[sq] = np.maximum(p0[sq], 0.0)
    q0 = p0.copy()
    q0[sq] = np.sqrt(p0[sq])

    def full(q):
        p = p0.copy()
        p[free] = q
        p[sq] = p[sq] ** 2
        return p

    def fun(q):
        with np.errstate(all="ignore"):
            r = _model(kind, full(q), t, t0, tm) - y
        return np.nan_to_num(r, nan=1e150, posinf=1e150, neginf=-1e150)

    def jac(q):
        with np.errstate(all="ignore"):
            J = _model(kind, full(q), t, t0, tm, want_jac=True)[1]
        qq = p0.copy()
        qq[free] = q
        J[:, sq] *= 2.0 * qq[sq]
        return np.nan_to_num(J[:, free])

    res = optimize.least_squares(fun, q0[free], jac=jac, method="lm", x_scale="jac",
                                 ftol=1e-13, xtol=1e-13, gtol=1e-13, max_nfev=200 * int(free.sum()))
    p = full(res.x)
    yhat, J = _model(kind, p, t, t0, tm, want_jac=True)
    r = y - yhat
    ok = bool(res.status > 0) and bool(np.all(np.isfinite(r)))
    return _Raw(kind, p, free, t0, tm, r, J[:, free], float(r @ r), ok, res.message)


# ---------------------------------------------------------------------------
# result
# ---------------------------------------------------------------------------

@dataclass
class PeriodFit:
    """Result of :func:`fit_period`.  Times in s, frequencies in Hz,
    angular rates in rad/s, signal quantities in the signal's unit [y].

    Attributes
    ----------
    model : str
        ``viscous``, ``quadratic``, ``quadratic+viscous``, ``two_mode`` or
        ``crossings`` (fallback).
    period : float
        s, the observed (damped) period ``2 pi / omega`` of the oscillation;
        for ``two_mode`` the mode with the larger amplitude at ``t0``.
    std : float
        s, 1-sigma uncertainty of ``period`` = ``std_raw * std_inflation``.
    frequency : float
        Hz, ``1 / period``.
    period_undamped : float or None
        s, ``2 pi / omega_n`` with ``omega_n = hypot(omega_d, sigma)``
        (viscous models; the period an undamped pendulum formula wants).
    damping_ratio : float
        Viscous: ``zeta = sigma / omega_n``.  Quadratic: the equivalent
        viscous ratio at the amplitude of ``t0``, ``(sigma + kappa) / omega``.
    damping : dict
        Model parameters of the damping (with ``*_std`` entries):
        viscous ``sigma`` (1/s, envelope exp(-sigma (t - t0))) and ``zeta``;
        quadratic ``k`` (1/([y] s), dA/dt = -k A^2 - sigma A), ``kappa``
        (= k A0, 1/s) and ``sigma`` (1/s, 0 unless a viscous term is fitted).
    amplitude, phase : float
        [y] and rad, of the oscillation at ``t0``:
        ``A cos(omega (t - t0) + phase)``.
    offset, drift : float
        [y] at ``t_ref`` and [y]/s: ``c0 + c1 (t - t_ref)``.
    residual_rms, r_squared : float
        [y] and dimensionless, over the fit window.
    n_samples : int
        Samples in the fit window.
    params, param_names, covariance :
        Fitted parameter vector, names and covariance ``s^2 (J^T J)^-1``
        (not inflated; fixed parameters have zero rows).
    t0, t1, t_ref : float
        s, fit window and the drift's reference time (window middle).
    std_raw, std_inflation, lag1_autocorr :
        White-noise period std (s), the factor ``sqrt((1+rho)/(1-rho))``
        applied because residuals were autocorrelated (1.0 if not), rho.
    noise_std : float
        [y], white-noise level of the residuals from their second differences.
    aic, bic : float
        Gaussian information criteria ``n ln(RSS/n) + 2p`` / ``+ p ln n``.
    modes : list of dict
        Per mode: ``period``, ``std``, ``frequency``, ``damping_ratio``,
        ``amplitude`` (s, s, Hz, -, [y]).
    crossing : CrossingPeriod or None
        Cross-check by :func:`period_from_crossings` on the same window.
    half_periods : tuple or None
        ``((T1, std1), (T2, std2))``, s: the same model fitted to the first
        and the second half of the window.  A difference beyond 3 combined
        sigma (noted) means the period changes along the record, e.g. with
        amplitude, so ``std`` understates the uncertainty of "the" period.
    alternatives, selection, chosen_by :
        For ``model="auto"``: every candidate fit, their RSS/AIC/BIC, and
        the criterion used.
    t_used, residuals : ndarray
        Times (s) and residuals ([y]) of the window, for plotting.
    notes : list of str
        Trimming, inflation, bounds hit, fallbacks, disagreements.
    """

    model: str
    period: float
    std: float
    frequency: float
    damping_ratio: float
    damping: dict
    amplitude: float
    phase: float
    offset: float
    drift: float
    residual_rms: float
    r_squared: float
    n_samples: int
    covariance: np.ndarray = field(repr=False)
    params: np.ndarray = field(repr=False)
    param_names: tuple = field(repr=False)
    t0: float = 0.0
    t1: float = 0.0
    t_ref: float = 0.0
    std_raw: float = float("nan")
    std_inflation: float = 1.0
    lag1_autocorr: float = 0.0
    noise_std: float = float("nan")
    period_undamped: float | None = None
    aic: float = float("nan")
    bic: float = float("nan")
    converged: bool = True
    modes: list = field(default_factory=list)
    crossing: CrossingPeriod | None = field(default=None, repr=False)
    half_periods: tuple | None = None
    alternatives: dict = field(default_factory=dict, repr=False)
    selection: dict = field(default_factory=dict)
    chosen_by: str | None = None
    t_used: np.ndarray = field(default=None, repr=False)
    residuals: np.ndarray = field(default=None, repr=False)
    notes: list = field(default_factory=list)
    _kind: str = field(default="", repr=False)

    @property
    def window(self) -> tuple[float, float]:
        """Fit window (t0, t1), s."""
        return (self.t0, self.t1)

    def predict(self, t) -> np.ndarray:
        """Fitted model at times ``t`` (s), in [y]."""
        t = np.asarray(t, dtype=float)
        if not self._kind:
            raise ValueError("no model curve for a crossing-only result")
        return _model(self._kind, self.params, t.ravel(), self.t0, self.t_ref).reshape(t.shape)

    def envelope(self, t) -> np.ndarray:
        """Amplitude envelope ([y]) of the (dominant) oscillation at ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        return _envelope(self._kind, self.params, t.ravel(), self.t0).reshape(t.shape)

    def summary(self) -> str:
        s = (f"{self.model}: T = {self.period:.6f} +- {self.std:.2g} s"
             f" (zeta = {self.damping_ratio:.4g}, r^2 = {self.r_squared:.5f}, n = {self.n_samples},"
             f" window {self.t0:.3f}-{self.t1:.3f} s")
        if self.std_inflation > 1.0:
            s += f", std x{self.std_inflation:.2f} for rho = {self.lag1_autocorr:.3f}"
        return s + ")"

    def to_dict(self) -> dict:
        """JSON-friendly scalars (no arrays)."""
        keys = ("model", "period", "std", "frequency", "period_undamped", "damping_ratio", "damping",
                "amplitude", "phase", "offset", "drift", "residual_rms", "r_squared", "n_samples",
                "t0", "t1", "std_raw", "std_inflation", "lag1_autocorr", "noise_std", "aic", "bic",
                "converged", "modes", "selection", "chosen_by", "notes")
        d = {k: getattr(self, k) for k in keys}
        if self.crossing is not None:
            d["crossing_period"] = self.crossing.period
            d["crossing_std"] = self.crossing.std
        return d


def _std(cov, i):
    v = cov[i, i]
    return float(math.sqrt(v)) if np.isfinite(v) and v >= 0 else float("nan")


def _grad_std(cov, idx, grad):
    g = np.asarray(grad, float)
    sub = cov[np.ix_(idx, idx)]
    v = float(g @ sub @ g)
    return math.sqrt(v) if np.isfinite(v) and v >= 0 else float("nan")


def _build(raw: _Raw, t, y, model_name: str, notes: list[str]) -> PeriodFit:
    n = t.size
    npar = int(raw.free.sum())
    dof = max(n - npar, 1)
    s2 = raw.cost / dof
    # covariance s^2 (J^T J)^-1 via the SVD of J (free parameters only)
    U, S, Vt = np.linalg.svd(raw.J, full_matrices=False)
    tol = S[0] * max(raw.J.shape) * np.finfo(float).eps if S.size else 0.0
    with np.errstate(divide="ignore"):
        inv2 = np.where(S > tol, 1.0 / S ** 2, np.inf)
    covf = (Vt.T * inv2) @ Vt * s2 if np.all(np.isfinite(inv2)) else np.full((npar, npar), np.nan)
    if not np.all(np.isfinite(inv2)):
        notes.append("Jacobian is rank deficient: covariance undefined")
    cov = np.zeros((raw.p.size, raw.p.size))
    fi = np.nonzero(raw.free)[0]
    cov[np.ix_(fi, fi)] = covf

    r = raw.resid
    rho = _lag1(r)
    infl = 1.0
    roundoff = math.sqrt(raw.cost / n) <= 1e-9 * max(float(np.std(y)), np.finfo(float).tiny)
    if rho > 2.0 / math.sqrt(n) and not roundoff:
        rho_c = min(rho, 1.0 - 1.0 / n)
        infl = math.sqrt((1.0 + rho_c) / (1.0 - rho_c))
        notes.append(f"residuals autocorrelated (lag-1 rho = {rho:.3f} > 2/sqrt(n) = "
                     f"{2 / math.sqrt(n):.3f}): std inflated x{infl:.2f} "
                     f"(effective samples {n / infl ** 2:.0f} of {n})")
    tss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - raw.cost / tss if tss > 0 else float("nan")
    rss_n = max(raw.cost / n, np.finfo(float).tiny)
    aic = n * math.log(rss_n) + 2 * npar
    bic = n * math.log(rss_n) + npar * math.log(n)
    p = raw.p
    names = _NAMES[raw.kind]

    def mode(ia, ib, iw, isg):
        a, b, w, sg = (float(p[i]) for i in (ia, ib, iw, isg))
        T = 2 * math.pi / w
        sdT_raw = 2 * math.pi / w ** 2 * _std(cov, iw)
        wn = math.hypot(w, sg)
        zeta = sg / wn
        zstd = _grad_std(cov, [iw, isg], [-sg * w / wn ** 3, w ** 2 / wn ** 3])
        return {"period": T, "std": sdT_raw * infl, "std_raw": sdT_raw, "frequency": 1 / T,
                "omega": w, "omega_n": wn, "period_undamped": 2 * math.pi / wn,
                "damping_ratio": zeta, "damping_ratio_std": zstd * infl,
                "sigma": sg, "sigma_std": _std(cov, isg) * infl,
                "amplitude": math.hypot(a, b), "phase": math.atan2(-b, a)}

    if raw.kind == "viscous":
        modes = [mode(2, 3, 4, 5)]
        m = modes[0]
        damping = {"sigma": m["sigma"], "sigma_std": m["sigma_std"],
                   "zeta": m["damping_ratio"], "zeta_std": m["damping_ratio_std"]}
        T_und = m["period_undamped"]
    elif raw.kind == "two_mode":
        modes = [mode(2, 3, 4, 5), mode(6, 7, 8, 9)]
        modes.sort(key=lambda d: -d["amplitude"])
        m = modes[0]
        damping = {"sigma": m["sigma"], "sigma_std": m["sigma_std"], "zeta": m["damping_ratio"],
                   "zeta_std": m["damping_ratio_std"], "second_sigma": modes[1]["sigma"],
                   "second_zeta": modes[1]["damping_ratio"]}
        T_und = m["period_undamped"]
    else:  # quadratic
        a, b, w, kap, sg = (float(v) for v in p[2:7])
        A0 = math.hypot(a, b)
        T = 2 * math.pi / w
        sdT_raw = 2 * math.pi / w ** 2 * _std(cov, 4)
        k = kap / A0 if A0 > 0 else float("nan")
        kstd = _grad_std(cov, [2, 3, 5], [-kap * a / A0 ** 3, -kap * b / A0 ** 3, 1 / A0]) if A0 > 0 else float("nan")
        zeta = (sg + kap) / w
        zstd = _grad_std(cov, [4, 5, 6], [-(sg + kap) / w ** 2, 1 / w, 1 / w])
        damping = {"k": k, "k_std": kstd * infl, "kappa": kap, "kappa_std": _std(cov, 5) * infl,
                   "sigma": sg, "sigma_std": _std(cov, 6) * infl if raw.free[6] else 0.0}
        modes = [{"period": T, "std": sdT_raw * infl, "std_raw": sdT_raw, "frequency": 1 / T, "omega": w,
                  "damping_ratio": zeta, "damping_ratio_std": zstd * infl, "amplitude": A0,
                  "phase": math.atan2(-b, a)}]
        m = modes[0]
        T_und = None
        T_rec = float(t[-1] - t[0])
        if kap * T_rec < 1e-6:
            notes.append("quadratic damping coefficient at its bound k = 0 (the data want none)")
        if raw.free[6] and sg * T_rec < 1e-6:
            notes.append("viscous term of the quadratic model at its bound sigma = 0")
    free_n = [nm for nm, f in zip(names, raw.free) if f]
    if not raw.converged:
        notes.append(f"least squares did not converge: {raw.message}")
    return PeriodFit(
        model=model_name, period=m["period"], std=m["std"], frequency=m["frequency"],
        damping_ratio=m["damping_ratio"], damping=damping, amplitude=m["amplitude"], phase=m["phase"],
        offset=float(p[0]), drift=float(p[1]), residual_rms=float(math.sqrt(raw.cost / n)),
        r_squared=float(r2), n_samples=int(n), covariance=cov, params=p.copy(), param_names=names,
        t0=float(t[0]), t1=float(t[-1]), t_ref=float(raw.tm), std_raw=m["std_raw"], std_inflation=infl,
        lag1_autocorr=rho, noise_std=_noise_sigma(r), period_undamped=T_und, aic=aic, bic=bic,
        converged=raw.converged, modes=modes, t_used=t.copy(), residuals=r.copy(), notes=notes,
        selection={"free_parameters": free_n}, _kind=raw.kind)


# ---------------------------------------------------------------------------
# fitting
# ---------------------------------------------------------------------------

def _envelope_thirds(t, yd):
    """RMS-based amplitudes (sqrt 2 RMS) of the first and last thirds and
    their centre times."""
    T_rec = t[-1] - t[0]
    m1 = t <= t[0] + T_rec / 3
    m3 = t >= t[-1] - T_rec / 3
    A1 = math.sqrt(2 * np.mean(yd[m1] ** 2))
    A3 = math.sqrt(2 * np.mean(yd[m3] ** 2))
    return A1, A3, float(np.mean(t[m1])), float(np.mean(t[m3]))


def _start_viscous(t, y, t0, tm, f_guess, drift):
    T_rec = t[-1] - t[0]
    if f_guess is None:
        f, S, _ = _spectrum(t, y)
        pk = _spectral_peaks(f, S, T_rec, 1)
        if not pk:
            raise SignalError("signal", "no spectral peak above 1.5 cycles per record: "
                                        "the window holds too few oscillations")
        f_guess = pk[0]
    w0 = 2 * math.pi * f_guess
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w0], [0.0])
    yd = y - coef[0] - coef[1] * (t - tm)
    A1, A3, tc1, tc3 = _envelope_thirds(t, yd)
    sg0 = math.log(A1 / A3) / (tc3 - tc1) if A1 > 0 and A3 > 0 else 0.0
    sg0 = float(np.clip(sg0, -10.0 / T_rec, 10.0 / T_rec))
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w0], [sg0])
    p0 = [coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w0, sg0]
    return np.array(p0), (A1, A3, tc1 - t0, tc3 - t0)


def _fit_viscous(t, y, t0, tm, f_guess, drift):
    p0, env = _start_viscous(t, y, t0, tm, f_guess, drift)
    free = np.ones(6, bool)
    free[1] = drift
    return _solve("viscous", t, y, t0, tm, p0, free), env


def _fit_quadratic(t, y, t0, tm, visc: _Raw, env, drift, viscous_term):
    A1, A3, tau1, tau3 = env
    # 1/A(tau) = (1 + kappa tau)/A0 through the two thirds
    den = A3 * tau3 - A1 * tau1
    kap0 = (A1 - A3) / den if den > 0 and A1 > A3 else 0.0
    kap0 = float(np.clip(kap0, 1e-3 / (t[-1] - t[0]), 100.0 / (t[-1] - t[0])))
    w = visc.p[4]
    free = np.ones(7, bool)
    free[1] = drift
    free[6] = viscous_term
    starts = []
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w], [0.0], kap0)
    starts.append([coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w, kap0, 0.0])
    if viscous_term:
        sg = max(visc.p[5], 0.0)
        tiny = 1e-3 / (t[-1] - t[0])
        starts.append([visc.p[0], visc.p[1], visc.p[2], visc.p[3], w, tiny, max(sg, tiny)])
        coef, _ = _linear_amplitudes(t, y, t0, tm, [w], [0.5 * sg], 0.5 * kap0)
        starts.append([coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w, 0.5 * kap0, 0.5 * sg])
    best = None
    for p0 in starts:
        raw = _solve("quadratic", t, y, t0, tm, np.array(p0), free, squared=(5, 6))
        if best is None or raw.cost < best.cost:
            best = raw
    return best


def _fit_two_mode(t, y, t0, tm, visc: _Raw, drift):
    T_rec = t[-1] - t[0]
    cands = []
    for win in (False, True):
        f, S, _ = _spectrum(t, y, window=win)
        cands += _spectral_peaks(f, S, T_rec, 6)
    f, S, _ = _spectrum(t, visc.resid)
    cands += _spectral_peaks(f, S, T_rec, 3)
    cands.append(visc.p[4] / (2 * math.pi))
    uniq: list[float] = []
    for c in cands:  # candidates closer than a third of a bin are one
        if all(abs(c - u) >= 0.3 / T_rec for u in uniq):
            uniq.append(c)
    cands = uniq
    sg = visc.p[5]
    best_pair, best_rss = None, np.inf
    for i, fa in enumerate(cands):
        for fb in cands[i + 1:]:
            if abs(fa - fb) < 0.3 / T_rec:
                continue
            _, rss = _linear_amplitudes(t, y, t0, tm, [2 * math.pi * fa, 2 * math.pi * fb], [sg, sg])
            if rss < best_rss:
                best_pair, best_rss = (fa, fb), rss
    if best_pair is None:
        raise SignalError("signal", "cannot find two distinct spectral peaks for a two-mode fit")
    w1, w2 = (2 * math.pi * best_pair[0], 2 * math.pi * best_pair[1])
    coef, _ = _linear_amplitudes(t, y, t0, tm, [w1, w2], [sg, sg])
    p0 = [coef[0], coef[1] if drift else 0.0, coef[2], coef[3], w1, sg, coef[4], coef[5], w2, sg]
    free = np.ones(10, bool)
    free[1] = drift
    raw = _solve("two_mode", t, y, t0, tm, np.array(p0), free)
    if math.hypot(raw.p[6], raw.p[7]) > math.hypot(raw.p[2], raw.p[3]):
        # canonical order: the dominant mode (amplitude at t0) first
        perm = np.r_[0, 1, 6, 7, 8, 9, 2, 3, 4, 5]
        raw.p = raw.p[perm]
        raw.free = raw.free[perm]
        raw.J = _model("two_mode", raw.p, t, t0, tm, want_jac=True)[1][:, raw.free]
    return raw


def _auto_trim(t, y, raw: _Raw, k: float):
    """Last time at which the envelope (sqrt 2 x moving RMS over one period
    of the offset- and drift-free signal, noise power removed) is still at
    least ``k`` x the white-noise level of the residuals."""
    noise = _noise_sigma(raw.resid)
    if noise <= 0:
        return None, noise
    T = 2 * math.pi / raw.p[4]
    dt = float(np.median(np.diff(t)))
    m = max(int(round(T / dt)), 1)
    yd = y - raw.p[0] - raw.p[1] * (t - raw.tm)
    if m >= yd.size:
        return None, noise
    ms = np.convolve(yd ** 2, np.ones(m) / m, mode="same")
    env = np.sqrt(2 * np.clip(ms - noise ** 2, 0, None))
    above = np.nonzero(env >= k * noise)[0]
    if above.size == 0:
        return None, noise
    return float(t[min(above[-1] + m // 2, t.size - 1)]), noise


_MODELS = ("viscous", "quadratic", "two_mode", "auto")


def fit_period(t, y, model: str = "viscous", *, trim: str | None = None, trim_k: float = 5.0,
               t_start: float | None = None, t_stop: float | None = None, drift: bool = True,
               viscous_term: bool = False, freq_guess: float | None = None,
               candidates: Sequence[str] = ("viscous", "quadratic"), criterion: str = "BIC",
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
    ``auto``
        Fits every model in ``candidates`` (default viscous and quadratic;
        add ``"quadratic+viscous"`` or ``"two_mode"``), returns the one with
        the lowest ``criterion`` (``"BIC"`` or ``"AIC"``) and keeps all in
        ``alternatives`` / ``selection``.

    Start values come from the zero-padded FFT peak (Hann window,
    parabolic interpolation of the log magnitude) and linear least squares
    for the amplitudes; then :func:`scipy.optimize.least_squares` (analytic
    Jacobian).  See the module docstring for the covariance and the
    autocorrelation inflation of the std.

    Parameters
    ----------
    t : array_like
        Sample times, s, strictly increasing (need not be uniform).
    y : array_like
        Samples, [y].
    model : str
        ``viscous`` (default), ``quadratic``, ``two_mode`` or ``auto``.
    trim : {None, "auto"}
        ``"auto"`` drops the settled tail where the envelope has fallen
        below ``trim_k`` x the white-noise level (estimated from second
        differences of the residuals of a first fit), then refits.
    trim_k : float
        Threshold of ``trim="auto"`` in units of the noise std.
    t_start, t_stop : float, optional
        Explicit fit window, s.
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
        Also fit each half of the window (``half_periods``).
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
        ``--model``) or, with ``fallback=False``, a failed fit.
    """
    if model not in _MODELS:
        raise SignalError("--model", f"unknown model {model!r}; choose one of {', '.join(_MODELS)}")
    if criterion.upper() not in ("AIC", "BIC"):
        raise SignalError("--criterion", f"unknown criterion {criterion!r}; use AIC or BIC")
    t, y = _validate(t, y)
    t, y = _window(t, y, t_start, t_stop)
    notes: list[str] = []
    try:
        return _fit_period(t, y, model, trim, trim_k, drift, viscous_term, freq_guess,
                           candidates, criterion.upper(), crossing_check, split_check, notes)
    except SignalError:
        raise
    except (ValueError, RuntimeError, np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError) as exc:
        if not fallback:
            raise SignalError("signal", f"nonlinear fit failed: {exc}") from exc
        cr = period_from_crossings(t, y)
        return _from_crossings(cr, t, y, [f"nonlinear fit failed ({exc}); period from crossings"])


def _from_crossings(cr: CrossingPeriod, t, y, notes) -> PeriodFit:
    nan = float("nan")
    return PeriodFit(model="crossings", period=cr.period, std=cr.std, frequency=1 / cr.period,
                     damping_ratio=nan, damping={}, amplitude=nan, phase=nan, offset=cr.level, drift=nan,
                     residual_rms=nan, r_squared=nan, n_samples=int(t.size), covariance=np.empty((0, 0)),
                     params=np.empty(0), param_names=(), t0=float(t[0]), t1=float(t[-1]),
                     t_ref=float(0.5 * (t[0] + t[-1])), std_raw=cr.std, crossing=cr,
                     t_used=t.copy(), residuals=None, notes=list(notes), converged=False)


def _fit_window(t, y, model, drift, viscous_term, freq_guess, candidates, criterion):
    t0 = float(t[0])
    tm = float(0.5 * (t[0] + t[-1]))
    visc, env = _fit_viscous(t, y, t0, tm, freq_guess, drift)
    if model == "viscous":
        return _build(visc, t, y, "viscous", []), visc
    if model == "quadratic":
        raw = _fit_quadratic(t, y, t0, tm, visc, env, drift, viscous_term)
        return _build(raw, t, y, "quadratic+viscous" if viscous_term else "quadratic", []), visc
    if model == "two_mode":
        raw = _fit_two_mode(t, y, t0, tm, visc, drift)
        return _build(raw, t, y, "two_mode", []), visc
    # auto
    fits: dict[str, PeriodFit] = {}
    for c in candidates:
        if c == "viscous":
            fits[c] = _build(visc, t, y, "viscous", [])
        elif c in ("quadratic", "quadratic+viscous"):
            raw = _fit_quadratic(t, y, t0, tm, visc, env, drift, c == "quadratic+viscous")
            fits[c] = _build(raw, t, y, c, [])
        elif c == "two_mode":
            fits[c] = _build(_fit_two_mode(t, y, t0, tm, visc, drift), t, y, c, [])
        else:
            raise SignalError("--model", f"unknown candidate {c!r}")
    if not fits:
        raise SignalError("--model", "auto needs at least one candidate model")
    key = criterion.lower()
    chosen = min(fits, key=lambda c: getattr(fits[c], key))
    other = "aic" if key == "bic" else "bic"
    best = fits[chosen]
    sel = {c: {"rss": float(f.residual_rms ** 2 * f.n_samples), "n_params": len(f.selection["free_parameters"]),
               "aic": f.aic, "bic": f.bic, "period": f.period, "std": f.std, "r_squared": f.r_squared}
           for c, f in fits.items()}
    best.selection = dict(best.selection, candidates=sel)
    best.alternatives = fits
    best.chosen_by = criterion
    alt = min(fits, key=lambda c: getattr(fits[c], other))
    if alt != chosen:
        best.notes.append(f"{other.upper()} would prefer {alt!r} over {chosen!r}")
    for c, f in fits.items():
        if c != chosen:
            best.notes.append(f"{c}: T = {f.period:.6f} +- {f.std:.2g} s, "
                              f"{criterion} {getattr(f, key) - getattr(best, key):+.1f}")
    return best, visc


def _fit_period(t, y, model, trim, trim_k, drift, viscous_term, freq_guess, candidates, criterion,
                crossing_check, split_check, notes):
    fit, visc = _fit_window(t, y, model, drift, viscous_term, freq_guess, candidates, criterion)
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
                fit, _ = _fit_window(t, y, model, drift, viscous_term, freq_guess, candidates, criterion)
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
    if split_check:
        _split_check(fit, t, y, drift)
    return fit


def _split_check(fit: PeriodFit, t, y, drift):
    """Fit the chosen model to each half of the window (``half_periods``)."""
    kind = {"viscous": ("viscous", False), "quadratic": ("quadratic", False),
            "quadratic+viscous": ("quadratic", True), "two_mode": ("two_mode", False)}[fit.model]
    tmid = 0.5 * (t[0] + t[-1])
    halves = []
    for m in (t <= tmid, t > tmid):
        th, yh = t[m], y[m]
        if th.size < MIN_SAMPLES or th[-1] - th[0] < 3 * fit.period:
            fit.notes.append("split check skipped: fewer than 3 periods per half")
            return
        try:
            f, _ = _fit_window(th, yh, kind[0], drift, kind[1], fit.frequency, (), "BIC")
        except (SignalError, ValueError, np.linalg.LinAlgError) as exc:
            fit.notes.append(f"split check failed: {exc}")
            return
        halves.append((f.period, f.std))
    fit.half_periods = tuple(halves)
    (T1, s1), (T2, s2) = halves
    comb = math.hypot(s1, s2)
    if np.isfinite(comb) and abs(T1 - T2) > 3 * comb:
        fit.notes.append(f"period changes along the record: {T1:.6f} +- {s1:.2g} s (first half) vs "
                         f"{T2:.6f} +- {s2:.2g} s (second half), {abs(T1 - T2) / comb:.1f} sigma; "
                         f"std covers noise only, not this drift (amplitude-dependent period?)")


# ---------------------------------------------------------------------------
# plot
# ---------------------------------------------------------------------------

def plot_fit(fit: PeriodFit, t, y, path, title: str | None = None):
    """Write a PNG: the signal with the fitted model (and envelope) on top,
    the residuals below.  ``t`` in s, ``y`` in [y]; matplotlib (Agg canvas)
    is imported here so the library does not need it otherwise.

    Returns the path written.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = np.asarray(t, float).ravel()
    y = np.asarray(y, float).ravel()
    fig = Figure(figsize=(10, 6.5), constrained_layout=True)
    FigureCanvasAgg(fig)
    ax, axr = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    lw = 0.6 if t.size > 3000 else 0.9
    ax.plot(t, y, color="0.55", lw=lw, label="signal")
    if fit.model != "crossings":
        tt = fit.t_used
        ax.plot(tt, fit.predict(tt), color="C3", lw=lw, label=f"{fit.model} fit")
        base = fit.offset + fit.drift * (tt - fit.t_ref)
        env = fit.envelope(tt)
        ax.plot(tt, base + env, color="C0", lw=0.8, ls="--", label="envelope")
        ax.plot(tt, base - env, color="C0", lw=0.8, ls="--")
        axr.plot(tt, fit.residuals, color="C3", lw=lw)
        axr.axhline(0, color="k", lw=0.5)
    for lo, hi in ((t[0], fit.t0), (fit.t1, t[-1])):
        if hi > lo:
            ax.axvspan(lo, hi, color="0.9", zorder=0)
            axr.axvspan(lo, hi, color="0.9", zorder=0)
    if fit.crossing is not None:
        ax.plot(fit.crossing.up_times, np.full(fit.crossing.up_times.size, fit.crossing.level), "|",
                color="k", ms=8, label="upward crossings")
    txt = f"T = {fit.period:.6f} ± {fit.std:.2g} s"
    if np.isfinite(fit.damping_ratio):
        txt += f"\nζ = {fit.damping_ratio:.4g}"
    if np.isfinite(fit.r_squared):
        txt += f",  r² = {fit.r_squared:.5f}"
    if fit.std_inflation > 1:
        txt += f"\nstd ×{fit.std_inflation:.2f} (ρ₁ = {fit.lag1_autocorr:.3f})"
    ax.text(0.99, 0.97, txt, transform=ax.transAxes, ha="right", va="top", fontsize=9,
            bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
    ax.set_ylabel("signal")
    axr.set_ylabel("residual")
    axr.set_xlabel("t [s]")
    ax.legend(loc="upper left", fontsize=8)
    if title:
        ax.set_title(title)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(str(path), dpi=110)
    return Path(path)
