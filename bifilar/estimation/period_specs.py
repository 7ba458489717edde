"""A measured period from the experimenter's words: command-line specs
(``torsion=2.681+-0.001``, ``torsion=10:26.81,26.79``, ``--amplitude``,
``--uncertainty``), stopwatch trials (period and std from N cycles timed in
each trial, cycles needed for a target std) and a recorded signal's fitted
period (``bifilar period``'s fit, with the checks of its scale and rate).

Used by ``bifilar invert`` and ``bifilar period`` and by the measurements
file reader (:mod:`bifilar.estimation.measurements`), which shares these
parsers.  SI units: periods and times in s, sample rates in Hz, amplitudes
in the unit of the mode's dominant coordinate (rad or m).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ..errors import InputError
from .sensitivity import uncertainty_too_large
from .uncertainty import UNCERTAINTY_KEYS, default_uncertainty

_PM = re.compile(r"\s*(?:\+-|\+/-|±)\s*")


def parse_value_sigma(text: Any, fld: str, what: str = "value") -> tuple[float, float | None]:
    """``"2.68"``, ``"2.68+-0.001"``, ``"2.68 ± 0.001"`` or a number -> (value, sigma or None)."""
    if isinstance(text, bool):
        raise InputError(fld, f"expected a number, got {text!r}")
    if isinstance(text, (int, float)):
        if not math.isfinite(float(text)):  # YAML's .nan / .inf reach here as floats
            raise InputError(fld, f"must be finite, got {text!r}")
        return float(text), None
    s = str(text).strip()
    parts = _PM.split(s)
    if len(parts) > 2 or not parts[0]:
        raise InputError(fld, f"expected {what}[+-SIGMA], got {s!r}")
    try:
        v = float(parts[0])
        sg = float(parts[1]) if len(parts) == 2 else None
    except ValueError:
        raise InputError(fld, f"expected {what}[+-SIGMA] with numbers, got {s!r}") from None
    if not math.isfinite(v) or (sg is not None and not math.isfinite(sg)):
        raise InputError(fld, f"must be finite, got {s!r}")
    if sg is not None and sg < 0:
        raise InputError(fld, f"the uncertainty after +- must not be negative, got {s!r}")
    return v, sg


def split_label(text: str, fld: str, example: str) -> tuple[str, str]:
    """``LABEL=REST`` -> (label, rest)."""
    if "=" not in str(text):
        raise InputError(fld, f"expected LABEL=..., e.g. {example}; got {text!r}")
    label, rest = str(text).split("=", 1)
    label, rest = label.strip(), rest.strip()
    if not label or not rest:
        raise InputError(fld, f"expected LABEL=..., e.g. {example}; got {text!r}")
    return label, rest


def parse_period_spec(text: str, fld: str = "--period") -> tuple[str, float, float | None]:
    """``LABEL=SECONDS[+-SIGMA]`` -> (label, period s, sigma s or None)."""
    label, rest = split_label(text, fld, "torsion=2.681+-0.001")
    T, s = parse_value_sigma(rest, fld, "SECONDS")
    if T <= 0:
        raise InputError(fld, f"the period must be positive, got {T:g} s in {text!r}")
    if s is not None and s == 0:
        raise InputError(fld, f"a zero uncertainty cannot be weighted; give a positive SIGMA or none in {text!r}")
    check_period_sigma(T, s, fld)
    return label, T, s


def check_period_sigma(T: float, s: float | None, fld: str) -> None:
    """Refuse a period's standard uncertainty ``s`` (s) at least as large as
    the period ``T`` (s): such a measurement says nothing about the period
    (and a 1e300 s sigma makes the weighted normal equations singular)."""
    if s is not None and s >= T:
        raise InputError(fld, f"the uncertainty {s:g} s is not smaller than the period {T:g} s: such a "
                         "measurement says nothing about the period; give the period's standard uncertainty")
    if s is not None and s < MIN_RELATIVE_SIGMA * T:
        raise InputError(fld, f"the uncertainty {s:g} s is below {MIN_RELATIVE_SIGMA:g} of the period {T:g} s: "
                         "no timing is that precise, and the model computes a period only to about 1e-14 of it, "
                         "so no answer could be checked against it; give the period's standard uncertainty")


def check_assumed_sigma(T: float, s: float, fld: str, source: str) -> None:
    """Check a period's standard uncertainty ``s`` (s) that the user did not
    give with the period but that comes from an assumed uncertainty
    (``source``: the field that set it, e.g. ``uncertainty.timing`` or
    ``--uncertainty``, or the reaction-time floor ``trial_time`` of timed
    trials), as :func:`check_period_sigma` checks a stated one, naming
    ``source`` as the field: zero cannot be weighted (the fit divided by it:
    exit 1, 'normalised residuals +inf'), and one not smaller than the
    period ``T`` says nothing (``timing: 1e300`` made the weighted normal
    equations singular: exit 1, an internal error)."""
    if s <= 0:
        raise InputError(source, f"the period {T:g} s of {fld} gets an uncertainty of 0 s from it, which cannot "
                                 "be weighted; give a positive one (or the period's own as +-SIGMA)")
    if s >= T:
        raise InputError(source, f"the period {T:g} s of {fld} gets an uncertainty of {s:g} s from it, not smaller "
                                 "than the period: such a measurement says nothing about the period; give the "
                                 "period's standard uncertainty")
    if s < MIN_RELATIVE_SIGMA * T:
        raise InputError(source, f"the period {T:g} s of {fld} gets an uncertainty of {s:g} s from it, below "
                                 f"{MIN_RELATIVE_SIGMA:g} of the period: no timing is that precise; give the "
                                 "period's standard uncertainty")


MIN_RELATIVE_SIGMA = 1e-12
"""Smallest stated period uncertainty, relative to the period: below it the
fit check (an answer within 0.1 sigma of the period) asks for more than the
model's period resolves (~1e-14 relative: ``invert --period torsion=1.9+-1e-15``
ended in exit 1, 'the linear estimate does not reproduce the measurements');
1e-12 of a 1 s period is a picosecond."""


PLAUSIBLE_PERIOD = (0.05, 100.0)
"""Periods (s) a pendulum rig plausibly shows: a torsion period of 100 s
needs a radius of gyration 30x the attachments' on 10 m wires, one of
0.05 s wires of a few mm.  Outside, a unit slip (ms, the total time of
several cycles) is likelier than the rig: :func:`implausible_period` warns."""


def implausible_period(T: float, label: str | None, fld: str, cycles: float | None = None) -> str | None:
    """A warning (text, no ``warning:`` prefix) when the period ``T`` (s) of
    mode ``label`` (None: a recording's, no mode named) lies outside
    :data:`PLAUSIBLE_PERIOD`, naming the likely
    unit slip; None when it is plausible.  ``cycles``: the period comes from
    timed trials of that many cycles each (their totals / cycles), whose
    totals may have been typed in ms.  Only a warning: whether a period is
    reachable at all is for the inversion to decide (it refuses one that no
    physical inertia gives, naming the slip)."""
    lo, hi = PLAUSIBLE_PERIOD
    if lo <= T <= hi:
        return None
    of = f" for mode '{label}'" if label is not None else ""
    head = (f"{fld}: a period of {T:.6g} s{of} is outside the {lo:g} .. {hi:g} s a pendulum rig "
            "plausibly shows; a unit slip?")
    if cycles is not None:
        tot = T * cycles
        if T > hi:
            return head + (f" the trials' totals ({tot:.6g} on average for {cycles:g} cycles) look like ms "
                           f"(they would give {T / 1000:.6g} s)")
        return head + (f" the trials' totals ({tot:.6g} on average for {cycles:g} cycles) look like minutes "
                       f"(they would give {T * 60:.6g} s), or the cycles and the totals are swapped")
    if T > hi:
        cyc = "" if label is None else "; or the total time of N cycles entered as a period (divide by N)"
        return head + f" in ms it would be {T / 1000:.6g} s{cyc}"
    return head + (f" in minutes it would be {T * 60:.6g} s; a frequency in Hz would be a period of "
                   f"{1 / T:.6g} s")


_TIMED = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(?:cycles?|periods?|x)?\s*(?::|@|in)\s*(.+)$", re.I)


def parse_times(text: Any, fld: str) -> list[float]:
    """``"26.81 s, 26.79 s, 26.84"`` or a list -> [s, ...]."""
    items = text if isinstance(text, (list, tuple)) else re.split(r"[,;\s]+", str(text).strip())
    out = []
    for it in items:
        if isinstance(it, str):
            it = it.strip()
            if it in ("", "s"):
                continue
            it = re.sub(r"\s*s$", "", it)
        try:
            v = float(it)
        except (TypeError, ValueError):
            raise InputError(fld, f"not a time in seconds: {it!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise InputError(fld, f"times must be positive and finite, got {it!r}")
        out.append(v)
    if not out:
        raise InputError(fld, "no times given")
    return out


def parse_timed_spec(text: str, fld: str = "--timed") -> tuple[str, float, list[float]]:
    """``LABEL=N:T1,T2,...`` (or ``LABEL=10 cycles in 26.81 s, 26.79 s``) ->
    (label, cycles, [total time of each trial, s])."""
    label, rest = split_label(text, fld, "torsion=10:26.81,26.79,26.84")
    m = _TIMED.match(rest)
    if not m:
        raise InputError(fld, f"expected LABEL=CYCLES:T1,T2,... (e.g. torsion=10:26.81,26.79), got {text!r}")
    n = float(m.group(1))
    if n <= 0:
        raise InputError(fld, f"the number of cycles must be positive, got {m.group(1)}")
    return label, n, parse_times(m.group(2), fld)


def parse_amplitudes(specs: list[str] | tuple, fld: str = "--amplitude") -> dict:
    """``["0.05"]`` (every mode) or ``["torsion=0.05+-0.005", ...]`` -> {label or None: (A, sigma or None)}."""
    out: dict = {}
    for s in specs or ():
        if "=" in s:
            label, rest = split_label(s, fld, "torsion=0.05")
        else:
            label, rest = None, s
        A, sg = parse_value_sigma(rest, fld, "AMPLITUDE")
        if A < 0:
            raise InputError(fld, f"the amplitude must not be negative, got {s!r}")
        if label in out:
            raise InputError(fld, f"amplitude for {'every mode' if label is None else label} given twice")
        out[label] = (A, sg)
    return out


def parse_uncertainty_overrides(specs, fld: str = "--uncertainty") -> dict:
    """``["length=0.0005", "mass=0.002"]`` or a mapping -> {key: value}."""
    items = specs.items() if isinstance(specs, dict) else [split_label(s, fld, "length=0.0005") for s in specs or ()]
    out = {}
    for k, v in items:
        sub = f"{fld}.{k}" if isinstance(specs, dict) else fld
        if k not in UNCERTAINTY_KEYS:
            raise InputError(sub, f"unknown uncertainty {k!r}; known: {', '.join(UNCERTAINTY_KEYS)}")
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise InputError(sub, f"{k} must be a number ({UNCERTAINTY_KEYS[k]}), got {v!r}") from None
        if not (math.isfinite(x) and x >= 0):
            raise InputError(sub, f"{k} must be a non-negative number ({UNCERTAINTY_KEYS[k]}), got {v!r}")
        too_large = uncertainty_too_large(k, x)
        if too_large:
            raise InputError(sub, too_large)
        out[k] = x
    return out


def period_from_trials(cycles: float, times: list[float], time_std: float | None = None,
                       unc: dict | None = None) -> tuple[float, float, dict]:
    """Period and its standard uncertainty from hand-timed trials.

    Timing model: trial ``i`` times ``cycles`` cycles in ``times[i]`` (s);
    ``T = mean(times) / cycles``.  Each trial's total time has the standard
    uncertainty

    * ``time_std`` (s) if given (Type B, trusted as is);
    * else ``max(scatter, floor)``: the sample std of the trials (Type A,
      ``n - 1`` degrees of freedom, ``n >= 2``) but never below the
      reaction-time floor ``floor = trial_time`` of the assumed
      uncertainties (s; default 0.1 s for a hand-timed start and stop,
      override with ``--uncertainty trial_time=...`` or the measurements
      file's ``uncertainty:``).  A scatter below the floor says only that
      the trials happened to agree (or were rounded), not that the timing
      is better than a human's reaction, so identical or near-identical
      trials both get the floor and are never more uncertain than
      trials that scatter less.

    ``sigma_T = sigma_trial / (sqrt(n) cycles)``.  The 95 % interval uses
    Student's t with ``n - 1`` degrees of freedom whenever the std is not
    given and ``n >= 2`` -- also when the floor sets ``sigma_trial``: the
    floor is a lower bound of a human's timing std, not its value, so a
    true std above the floor whose trials happened to agree would otherwise
    get the normal 1.96 (two trials with a true std of 2 floors covered 88 %
    instead of 95 %).  ``max(scatter, floor) t`` is never shorter than the
    exact Student interval ``scatter t``, so the coverage is at least 95 %
    for Gaussian errors of any std, exact far above the floor and
    conservative near or below it (tests/test_coverage_trials.py).  A given
    ``time_std`` (or one trial) uses the normal 1.96.

    Returns ``(T [s], sigma_T [s], details)``; details has ``cycles``,
    ``times``, ``trial_std`` (s), ``trial_std_source``, ``scatter`` (s or
    None), ``floor`` (s), ``dof`` (None = infinite), ``coverage_factor``,
    ``interval95`` ([lo, hi], s) and ``trial_periods`` (s).
    """
    from scipy import stats

    u = default_uncertainty(unc)
    t = np.asarray(times, float)
    n = t.size
    T = float(t.mean() / cycles)
    floor = float(u["trial_time"])
    scatter = float(t.std(ddof=1)) if n >= 2 else None
    dof = None
    if time_std is not None:
        s, how = float(time_std), "given"
    elif scatter is not None and scatter > floor:
        s, how, dof = scatter, f"scatter of the {n} trials (Type A)", n - 1
    else:
        s, dof = floor, (n - 1 if n >= 2 else None)
        how = ("reaction-time floor trial_time (one trial)" if n < 2 else
               f"reaction-time floor trial_time (the trials' scatter {scatter:.3g} s is below it)")
    if s <= 0:
        s, how = 1e-3 * float(t.mean()), "floor 1e-3 x the trial time (trial_time = 0)"
    sigma = s / math.sqrt(n) / cycles
    k = float(stats.t.ppf(0.975, dof)) if dof is not None else 1.959963984540054
    det = {"cycles": cycles, "times": [float(x) for x in t], "trial_std": s, "trial_std_source": how,
           "scatter": scatter, "floor": floor, "dof": dof, "coverage_factor": k,
           "interval95": [T - k * sigma, T + k * sigma],
           "trial_periods": [float(x / cycles) for x in t]}
    return T, sigma, det


MAX_SAMPLE_RATE = 1e9
"""Largest sample rate of a recording, Hz (a sample interval below 1 ns; a
pendulum's recording is sampled at 10 Hz .. 100 kHz)."""
SIGNAL_MAGNITUDE = (1e-100, 1e100)
"""Range of the largest |sample| of a recording: beyond it the fit's squares
overflow or underflow double precision (rescale the signal)."""
MAX_DURATION = 1e8
"""Longest recording, s (three years)."""


def check_signal_scale(t, y, fld: str = "--signal") -> None:
    """Refuse (:class:`~bifilar.errors.InputError`) a recording whose numbers
    no fit can handle in double precision: sample intervals under
    1 / :data:`MAX_SAMPLE_RATE` s, a duration over :data:`MAX_DURATION` s,
    or a largest |sample| outside :data:`SIGNAL_MAGNITUDE`.  ``t`` in s."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t.size >= 2:
        dt = float(np.min(np.diff(t)))
        if np.isfinite(dt) and 0 < dt < 1.0 / MAX_SAMPLE_RATE:
            raise InputError(fld, f"samples {dt:.3g} s apart (over {MAX_SAMPLE_RATE:g} Hz): is the time in seconds?")
        span = float(t[-1] - t[0])
        if not np.isfinite(span) or span > MAX_DURATION:
            raise InputError(fld, f"the recording spans {span:.3g} s (at most {MAX_DURATION:g} s): is the time in seconds?")
    finite = y[np.isfinite(y)]
    peak = float(np.max(np.abs(finite))) if finite.size else 0.0
    lo, hi = SIGNAL_MAGNITUDE
    if peak > hi or 0 < peak < lo:
        # the samples' own field, as the reader's refusals name it (`period`'s argument is SIGNAL)
        raise InputError("signal" if fld == "SIGNAL" else fld, f"samples as large as {peak:.3g}: outside {lo:g} .. {hi:g}; rescale the signal "
                              "(the period does not depend on its unit)")


def trials_for_target(period: float, trial_std: float, target: float,
                      trials: tuple = (1, 2, 3, 5, 10, 20)) -> list[dict]:
    """Cycles per trial needed for a target standard uncertainty of the
    period, for several numbers of trials.

    ``period`` (s) and ``trial_std`` (s, one trial's total-time std, e.g.
    the reaction floor) as from :func:`period_from_trials`; ``target`` the
    wanted ``sigma_T`` in s.  With the timing error of a trial independent
    of its length, ``sigma_T = trial_std / (sqrt(n) N)``, so
    ``N = ceil(trial_std / (sqrt(n) target))``.  Returns one dict per ``n``:
    ``trials``, ``cycles``, ``seconds_per_trial`` (N T) and ``std`` (s).
    """
    out = []
    for n in trials:
        N = max(1, math.ceil(trial_std / (math.sqrt(n) * target) - 1e-12))
        out.append({"trials": int(n), "cycles": int(N), "seconds_per_trial": N * period,
                    "std": trial_std / (math.sqrt(n) * N)})
    return out


def parse_target(text: str, period: float, fld: str = "--target") -> float:
    """``"0.1%"`` (relative), ``"1e-3"`` (relative), ``"0.5ms"`` or
    ``"0.0005s"`` (absolute) -> target standard uncertainty of the period, s."""
    s = str(text).strip().lower().replace(" ", "")
    try:
        if s.endswith("%"):
            v = float(s[:-1]) / 100 * period
        elif s.endswith("ms"):
            v = float(s[:-2]) * 1e-3
        elif s.endswith("s"):
            v = float(s[:-1])
        else:
            v = float(s) * period
    except ValueError:
        raise InputError(fld, f"expected e.g. 0.1% , 1e-3 (relative) or 0.5ms, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(fld, f"the target must be positive, got {text!r}")
    return v


def fit_record(path, fld: str = "SIGNAL", *, column=None, sample_rate=None, model: str = "auto", t_start=None,
               t_stop=None, trim=None) -> tuple:
    """Read and fit a recorded oscillation as `period` and `invert --signal`
    both do: ``(t, y, fit, meta, time_base_warning, start_warning)``.

    :func:`~bifilar.estimation.signal.read_signal` (``t`` s, ``y`` in the
    file's unit), the scale check, :func:`~bifilar.estimation.signal.fit_period`
    (``t_start``/``t_stop`` s, ``trim``), then the time base of a record
    without its time column (dropped or repeated frames put back, or the
    std widened: :func:`~bifilar.estimation.signal_timebase.check_time_base`,
    which may return another ``t``, ``y`` and fit; its line, or None) and a
    start or end held by hand left out of the fit
    (:func:`~bifilar.estimation.signal_start.take_start_warning`: its line,
    or None).  Both lines are also appended to ``meta["warnings"]``, and the
    time base's summary is ``meta["time_base"]``.  ``fld`` names the input
    in refusals.  Raises :class:`~bifilar.estimation.signal.SignalError`
    (exit 2) for a record that cannot be read or fitted."""
    from .signal import fit_period, read_signal
    from .signal_clip import take_fault_warnings
    from .signal_start import take_start_warning
    from .signal_timebase import check_time_base

    t, y, meta = read_signal(path, column=column, sample_rate=sample_rate)
    check_signal_scale(t, y, fld)
    fit = fit_period(t, y, model=model, t_start=t_start, t_stop=t_stop, trim=trim)

    def refit(tn, yn=y):
        return fit_period(tn, yn, model=model, t_start=t_start, t_stop=t_stop, trim=trim)

    tbc = check_time_base(t, y, fit, meta.get("time_source"), refit, fld)
    tbw = None
    if tbc:  # frames dropped or repeated in a record without its time column: put back, or the std widened
        t, y, fit, tbw = tbc["t"], tbc.get("y", y), tbc["fit"], tbc["warning"]
        meta["warnings"] = list(meta.get("warnings") or []) + [tbw]
        meta["time_base"] = tbc["time_base"]
    held = take_start_warning(fit)  # the body held before the release: left out of the fit
    faults = take_fault_warnings(fit)  # a saturated sensor's flat tops left out, an offset's step taken out
    for line in [held] + faults:
        if line:
            meta["warnings"] = list(meta.get("warnings") or []) + [line]
    return t, y, fit, meta, tbw, held


def period_from_signal(path, *, column=None, sample_rate=None, model: str = "auto", quantity: str = "other",
                       scale: float | None = None, t_start=None, t_stop=None, trim=None, fld: str = "--signal"):
    """Fit a recorded oscillation (:mod:`bifilar.estimation.signal`).

    Returns a dict: ``period`` (s, undamped: the fitted damped period times
    ``sqrt(1 - zeta^2)``), ``std`` (s, including the damping ratio's
    uncertainty), ``dof`` (of ``std``: finite when the fit's std is the
    spread of re-quantised copies, None otherwise: normal),
    ``observed_period``, ``damping_ratio``, ``amplitude``
    (rad or m, None unless ``quantity`` is ``angle`` or ``rate``),
    ``decay`` (the amplitude the period refers to over the envelope at the
    fit window's start, unit-free, <= 1 for a decaying record; None for a
    crossings-only fit), ``cycles``, ``fit``, ``t``, ``y``, ``meta``,
    ``time_base_warning`` (one line, or None: a record without its time
    column whose phase steps as dropped frames step it,
    :mod:`.signal_timebase`; also in ``meta["warnings"]``),
    ``start_warning`` (one line, or None: the record's start held by hand
    and left out of the fit, :mod:`.signal_start`; also in
    ``meta["warnings"]``).

    The amplitude of a decaying recording is the one its fitted period
    refers to, :attr:`~bifilar.estimation.signal_result.PeriodFit.amplitude_period`
    (the envelope weighted as a least-squares slope weighs it), times
    ``scale``; for ``rate`` it is further divided by omega.
    """
    from .signal import SignalError

    if quantity not in ("angle", "rate", "other"):
        raise InputError(fld, f"quantity must be angle, rate or other, got {quantity!r}")
    try:
        t, y, fit, meta, tbw, held = fit_record(path, fld, column=column, sample_rate=sample_rate, model=model,
                                                t_start=t_start, t_stop=t_stop, trim=trim)
    except SignalError as exc:
        raise InputError(f"{fld} ({exc.field})", exc.message) from None
    Td = float(fit.period)
    zeta = float(fit.damping_ratio) if np.isfinite(fit.damping_ratio) else 0.0
    zstd = 0.0
    if fit.modes:
        zstd = float(fit.modes[0].get("damping_ratio_std", 0.0) or 0.0)
        zstd = zstd if np.isfinite(zstd) else 0.0
    zeta = min(max(zeta, 0.0), 0.999)
    c = math.sqrt(1.0 - zeta * zeta)
    Tn = Td * c
    std = math.hypot(c * float(fit.std), Td * zeta / c * zstd)
    nu = fit.uncertainty.get("dof")
    if nu is not None:  # the fit's std from re-quantised copies; the damping term normal
        from .uncertainty import combined_dof

        nu = combined_dof([(c * float(fit.std), float(nu)), (Td * zeta / c * zstd, math.inf)])
        nu = nu if math.isfinite(nu) else None
    amp = decay = None
    if fit.model != "crossings":
        a_start = float(np.abs(fit.envelope(np.array([fit.t0])))[0])
        decay = fit.amplitude_period / a_start if a_start > 0 and np.isfinite(fit.amplitude_period) else None
        if quantity != "other":
            a_eff = fit.amplitude_period if np.isfinite(fit.amplitude_period) else 0.0
            a_eff *= 1.0 if scale is None else float(scale)
            if quantity == "rate":
                a_eff /= 2 * math.pi / Td
            amp = a_eff
    cycles = max((fit.t1 - fit.t0) / Td, 1.0)
    return {"period": Tn, "std": std, "dof": nu, "observed_period": Td, "damping_ratio": zeta, "amplitude": amp,
            "decay": decay, "cycles": cycles, "fit": fit, "t": t, "y": y, "meta": meta, "time_base_warning": tbw,
            "start_warning": held}
