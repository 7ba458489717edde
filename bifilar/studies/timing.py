"""How to time a planned experiment: cycles per trial and trials per mode.

The predicted uncertainties of ``sweep`` and ``plan`` assume each timed
period is known to ``uncertainty.timing`` (s, one standard deviation).  This
module says how to get there with a given timing instrument:

* **stopwatch**: one trial times ``N`` whole cycles by hand; the total time
  has a standard uncertainty ``reaction`` (s, start and stop together; 0.1 s
  by default, the value ``bifilar invert`` assumes for a hand-timed trial),
  so ``n`` trials give ``sigma_T = reaction / (N sqrt(n))``;
* **sensor**: a recording of ``N`` cycles sampled at ``rate`` (Hz) with
  white noise of standard deviation ``noise`` relative to the oscillation's
  amplitude; the Cramer-Rao bound of a sinusoid's angular frequency (unknown
  amplitude, phase and offset; S. Kay, Fundamentals of Statistical Signal
  Processing I, 1993, example 3.14: ``var(w) = 12 / (eta M^3)`` per sample
  squared, ``eta = A^2 / (2 sigma^2)``) over a record of duration ``D = N T``
  with ``M = rate D`` samples is ``sigma_w = sqrt(24) noise / (sqrt(M) D)``, so one record gives
  ``sigma_T = T^2 sigma_w / (2 pi)`` and ``n`` records ``sigma_T / sqrt(n)``.

``N`` cycles per trial: at least :data:`MIN_CYCLES` (the usual ten), at
least ``1 / s`` with ``s`` the relative gap to the nearest other mode (the
window then spans a whole beat of the two, so that a record resolves them
and a small admixture of the neighbour averages out of a count instead of
biasing it), at most :data:`MAX_CYCLES` (damping, patience).  Then ``n`` is
the smallest number of trials reaching the target ``sigma_T``.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError

MIN_CYCLES = 10
MAX_CYCLES = 50
DEFAULT_REACTION = 0.1  # s, one hand-timed start and stop (bifilar.estimation.uncertainty.DEFAULT_TRIAL_TIME_SIGMA)


def parse_sensor(text: str | None) -> tuple[float, float] | None:
    """``NOISE,RATE`` (noise relative to the amplitude, sample rate Hz) -> tuple; None passes."""
    if text is None:
        return None
    try:
        noise, rate = (float(x) for x in text.split(","))
    except ValueError:
        raise InputError("--sensor", f"{text!r} must be NOISE,RATE, e.g. 0.01,100 (noise relative to the "
                                     "amplitude, sample rate in Hz)") from None
    if not (noise > 0 and rate > 0 and math.isfinite(noise) and math.isfinite(rate)):
        raise InputError("--sensor", f"noise and rate must be positive, got {noise:g} and {rate:g}")
    return noise, rate


def check_reaction(reaction: float) -> float:
    if not (reaction > 0 and math.isfinite(reaction)):
        raise InputError("--stopwatch", f"the reaction-time sigma per trial must be positive, got {reaction:g} s")
    return float(reaction)


def cycles_per_trial(separation: float | None) -> int:
    """Cycles per trial for a mode ``separation`` (relative) from its nearest
    neighbour (see the module docstring)."""
    if separation is None or math.isinf(separation):
        return MIN_CYCLES
    if not separation > 0:
        return MAX_CYCLES
    return int(min(MAX_CYCLES, max(MIN_CYCLES, math.ceil(1.0 / separation - 1e-9))))


def stopwatch_sigma(reaction: float, cycles: int, trials: int) -> float:
    """sigma of the period, s, from ``trials`` hand-timed trials of ``cycles`` cycles."""
    return reaction / (cycles * math.sqrt(trials))


def sensor_sigma(period: float, noise: float, rate: float, cycles: int, trials: int) -> float:
    """sigma of the period, s, from ``trials`` records of ``cycles`` cycles (Cramer-Rao bound)."""
    D = cycles * period
    M = rate * D
    sw = math.sqrt(24.0) * noise / (math.sqrt(M) * D)
    return period**2 * sw / (2 * math.pi) / math.sqrt(trials)


def _trials(sigma_one: float, target: float) -> int:
    if target <= 0:
        return 0  # an exact timing cannot be reached; reported as such
    return int(max(1, math.ceil((sigma_one / target) ** 2 - 1e-9)))


def how_to_time(point: dict, target_sigma: float, reaction: float = DEFAULT_REACTION,
                sensor: tuple[float, float] | None = None) -> list[dict]:
    """Per timed mode of a point (the mode of each measurable component):
    period s, the components it serves, its separation, the cycles per trial
    and the trials that reach ``target_sigma`` (s) with a stopwatch (and with
    the sensor when given), and the sigma and total timing that gives."""
    periods = point["periods"]
    labels = list(periods)
    T_all = np.array([np.nan if periods[k] is None else periods[k] for k in labels], float)
    modes: dict[str, list[str]] = {}
    for c, e in point["components"].items():
        if e.get("identifiable") and e.get("mode"):
            modes.setdefault(e["mode"], []).append(c)
    out = []
    for label, comps in modes.items():
        k = labels.index(label)
        T = float(T_all[k])
        others = [abs(T - t) / T for j, t in enumerate(T_all) if j != k and np.isfinite(t)]
        sep = min(others) if others else None
        out.append({"mode": label, "components": comps, **advice(T, sep, target_sigma, reaction, sensor)})
    return out


def advice(T: float, sep: float | None, target_sigma: float, reaction: float = DEFAULT_REACTION,
           sensor: tuple[float, float] | None = None) -> dict:
    """Cycles per trial and trials for one mode of period ``T`` (s) and
    relative separation ``sep`` to reach ``target_sigma`` (s)."""
    N = cycles_per_trial(sep)
    row = {"period": T, "separation": sep, "cycles_per_trial": N, "target_sigma": target_sigma}
    n = _trials(stopwatch_sigma(reaction, N, 1), target_sigma)
    row["stopwatch"] = {"reaction_sigma": reaction, "trials": n,
                        "sigma": stopwatch_sigma(reaction, N, n) if n else None, "time_s": n * N * T}
    if sensor is not None:
        noise, rate = sensor
        n2 = _trials(sensor_sigma(T, noise, rate, N, 1), target_sigma)
        row["sensor"] = {"noise": noise, "rate": rate, "records": n2,
                         "sigma": sensor_sigma(T, noise, rate, N, n2) if n2 else None, "time_s": n2 * N * T}
    return row


def describe(row: dict) -> str:
    """One line per timed mode."""
    sw = row["stopwatch"]
    if not sw["trials"]:
        return f"{row['mode']} (T = {row['period']:.4g} s): the plan assumes exact timing (timing = 0)"
    txt = (f"{row['mode']} (T = {row['period']:.4g} s, for {', '.join(row['components'])}): time "
           f"{row['cycles_per_trial']} cycles per trial; stopwatch (+-{sw['reaction_sigma']:g} s a trial): "
           f"{sw['trials']} trials (~{sw['time_s'] / 60:.3g} min) for +-{1e3 * sw['sigma']:.3g} ms a period")
    if "sensor" in row:
        se = row["sensor"]
        txt += f"; sensor: {se['records']} record(s) of {row['cycles_per_trial']} cycles (+-{1e3 * se['sigma']:.3g} ms)"
    return txt
