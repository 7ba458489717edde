"""Aliasing of a recorded oscillation against the config's predicted modes.

A record sampled at ``fs`` (Hz) shows an oscillation of frequency ``f``
above the Nyquist frequency ``fs/2`` at its alias ``|f - k fs|`` (``k =
round(f / fs)``, the fold into ``[0, fs/2]``).  ``bifilar period`` alone
cannot tell the two apart; ``invert --signal`` can, because the config
predicts every mode's frequency: the fitted frequency is compared with each
predicted mode and with each mode's alias at the record's sample rate.

Rules (SI: Hz, s):

* nothing is said when the sample rate is at least ``ALIAS_MARGIN`` times
  the measured mode's frequency (the larger of its prediction at the prior
  and the fitted one): that mode is resolved, and a faster mode's alias
  landing near it is a coincidence, not evidence;
* below that, refused (:class:`InputError`, exit 2) when an alias of a
  predicted mode matches the fitted frequency better than any mode itself
  (distances relative to the mode's predicted frequency, the scale of its
  prediction error): the match is only by alias;
* else warned: a mode a little faster than predicted would alias.
"""

from __future__ import annotations

import math

from ..errors import InputError

#: below this many samples per cycle of the measured mode a recording is
#: warned about (twice the frequency is the Nyquist limit itself)
ALIAS_MARGIN = 2.5


def fold(f: float, fs: float) -> tuple[float, int]:
    """Frequency (Hz) at which an oscillation of ``f`` Hz appears when
    sampled at ``fs`` Hz, and the integer ``k`` of ``|f - k fs|`` (0: no
    alias, ``f <= fs/2``)."""
    k = int(math.floor(f / fs + 0.5))
    return abs(f - k * fs), k


def _predicted(model) -> list[tuple[str, float]]:
    """(label, frequency Hz) of every mode with a period at the prior."""
    out = []
    for md in model.modes0.modes:
        T = md.period
        if T is not None and math.isfinite(T) and T > 0:
            out.append((md.label, 1.0 / T))
    return out


#: a recording's period this many times a predicted mode's, within MS_MATCH, reads its time column in ms
MS_FACTOR, MS_MATCH = 1000.0, 0.1


def _refuse_time_in_ms(m, T_obs: float, modes) -> None:
    """Raise InputError when a recording's period (s) is implausibly long
    (:func:`~bifilar.estimation.period_specs.implausible_period`) and a
    thousandth of it lies within :data:`MS_MATCH` of a predicted mode's
    period: its time column, named plain ``t`` or ``time``, holds ms
    (a column named ``time [ms]`` or ``t_ms`` is converted).  Before, such
    a record was refused as an alias at a sample rate of 0.06 Hz."""
    from .period_specs import implausible_period

    if implausible_period(T_obs, None, m.field) is None:
        return
    T_ms = T_obs / MS_FACTOR
    lab, f = min(modes, key=lambda lf: abs(T_ms * lf[1] - 1.0))
    if abs(T_ms * f - 1.0) <= MS_MATCH:
        col = ((m.details or {}).get("signal") or {}).get("time_source") or "the time column"
        raise InputError(m.field, f"the recording of '{m.label}' has a period of {T_obs:.6g} s, which no pendulum "
                                  f"rig plausibly shows; read in ms ({col}) it is {T_ms:.6g} s, near mode '{lab}' "
                                  f"({1 / f:.4g} s predicted): name the time column 'time [ms]' or 't_ms' (or "
                                  "convert it to s)")


def check_signal_aliases(pb) -> list[str]:
    """Check every recorded measurement of the problem ``pb``
    (:class:`~bifilar.estimation.problem.Problem`) against its hanging's
    predicted modes (module docstring).  Returns the warnings; raises
    :class:`InputError` (on the measurement's field) when the fitted
    frequency matches a mode only by alias."""
    warnings: list[str] = []
    for k, m in enumerate(pb.measurements):
        if m.source != "signal":
            continue
        sig = (m.details or {}).get("signal") or {}
        fs = sig.get("sample_rate")
        T_obs = m.observed_period or m.period
        if not fs or not (T_obs and T_obs > 0):
            continue
        fs = float(fs)
        f_fit = 1.0 / float(T_obs)
        model = pb.models[m.hanging]
        modes = _predicted(model)
        if not modes:
            continue
        md = model.modes0.modes[pb.mode_index[k]]
        f_pred = 1.0 / md.period if md.period and math.isfinite(md.period) and md.period > 0 else 0.0
        _refuse_time_in_ms(m, T_obs, modes)
        f_hi = max(f_pred, f_fit)
        if fs >= ALIAS_MARGIN * f_hi:
            continue  # the measured mode is well resolved; a faster mode's alias nearby is a coincidence
        direct = min(modes, key=lambda lf: abs(f_fit - lf[1]) / lf[1])
        d_direct = abs(f_fit - direct[1]) / direct[1]
        aliases = []
        for lab, f in modes:
            fa, kk = fold(f, fs)
            if kk >= 1:
                aliases.append((abs(f_fit - fa) / f, lab, f, fa, kk))
        if aliases:
            d_alias, lab, f, fa, kk = min(aliases)
            if d_alias < d_direct:
                raise InputError(
                    m.field,
                    f"the recording of '{m.label}' oscillates at {f_fit:.4g} Hz (period {T_obs:.4g} s), which "
                    f"matches the alias of mode '{lab}' (predicted {f:.4g} Hz, period {1 / f:.4g} s) at the "
                    f"sample rate {fs:.4g} Hz (|{f:.4g} - {kk} x {fs:.4g}| = {fa:.4g} Hz) better than any mode "
                    f"itself (nearest: '{direct[0]}' at {direct[1]:.4g} Hz): sampled below twice its frequency, "
                    f"an oscillation shows as a slower alias; record at {ALIAS_MARGIN:g} x {f:.4g} = "
                    f"{ALIAS_MARGIN * f:.3g} Hz or faster")
        warnings.append(
            f"{m.field}: the sample rate {fs:.4g} Hz of the recording of '{m.label}' is only "
            f"{fs / f_hi:.2f} x the mode's frequency ({f_pred:.4g} Hz predicted, {f_fit:.4g} Hz fitted): "
            f"an oscillation between {fs / 2:.4g} and {fs:.4g} Hz would show as its alias below "
            f"{fs / 2:.4g} Hz, which the record cannot tell apart; record at {ALIAS_MARGIN:g} x the "
            f"frequency ({ALIAS_MARGIN * f_hi:.3g} Hz) or faster")
    return warnings
