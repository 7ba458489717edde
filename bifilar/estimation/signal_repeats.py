"""Repeated frames in a record without its time column.

A camera (or its software) that writes the same frame twice leaves a sample
duplicated and every later sample one frame later than the nominal time
base ``t_j = j dt`` of a record read at ``--sample-rate`` says: the time base
runs long by the repeats' share and the fitted period with it (mut16: six
repeats in 30 cycles, a period long beyond its std and no warning; the
phase steps BACK by one frame's phase at each).  Unlike a dropped frame, a
repeat leaves its mark in the samples themselves: two consecutive samples
equal (the same frame measured twice) where the oscillation moves by many
times the noise and the record's resolution between frames.

:func:`repeated_samples` finds them by the chance that two consecutive
samples of a regular record come that close, given the local motion per
frame and the noise (design.md "dropfix2, session 18"); :func:`remove_repeats`
removes them, refits the record on the nominal time base of the samples
left and says so.  SI units: time s, frequency Hz; ``y`` in any unit.
"""

from __future__ import annotations

import math

import numpy as np

#: the chance, over the whole record, that a regular record shows one pair
#: this close somewhere (each pair is tested at this share of the samples'
#: count: a Bonferroni bound, so a record without repeats is touched with
#: probability below it)
FALSE_RATE = 1e-3
#: a repeat's two samples differ by at most this many stds of a difference
#: (the same frame measured twice: 0 exactly, or the noise alone)
NEAR_ZERO = 3.0


def repeated_samples(y) -> tuple[np.ndarray, float]:
    """``(idx, blind)``: the indices ``j`` of the samples that repeat sample
    ``j - 1`` in a uniformly sampled record ``y``, and ``blind``, the share
    of the samples where even an exact repeat could not be told from
    chance (slow motion against the noise and the resolution).

    A pair counts where the chance that a regular record's consecutive
    samples lie as close as ``w = |y_j - y_(j-1)|`` (at least half the
    record's resolution ``q``, :func:`resolution`), given the local motion
    a frame ``v``, the smaller of the single-frame steps either side where
    they move the same way (a repeat leaves them whole; a drop beside it
    only makes one longer; 0 at a turning point), and
    the difference's noise ``s = sqrt(2 sigma^2 + q^2 / 6)`` (``sigma`` the
    white noise from the third differences), ``2 w / (sqrt(2 pi) s) exp(-(v
    - w)^2 / (5 s^2))``, is below ``FALSE_RATE / n``, and ``w`` is within
    ``NEAR_ZERO s`` of 0 (a frame measured twice; a middle step merely
    shorter than two drops beside it is not).  The exponent's 5 (not 2)
    allows for the noise in ``v`` itself: the three differences share four
    samples, and the cheapest noise that opens the gap ``v - w`` (the two
    second differences at ``j - 1`` and ``j`` both ``>= v - w``) has
    ``sum e^2 = (v - w)^2 / 5``, i.e. ``exp(-(v - w)^2 / (10 sigma^2))``.
    """
    from .signal_timebase import white_noise

    y = np.asarray(y, float)
    n = y.size
    if n < 8 or not np.all(np.isfinite(y)):
        return np.zeros(0, int), 1.0
    d = np.diff(y)
    ad = np.abs(d)
    q = resolution(y, ad)
    s = math.sqrt(2.0 * white_noise(y) ** 2 + q * q / 6.0)
    if not s > 0:
        return np.zeros(0, int), 1.0
    j = np.arange(2, n - 1)
    # the single-frame steps either side (a repeat leaves them whole), moving the same way (at a turning
    # point the middle step is small by nature)
    v = np.where(np.sign(d[j - 2]) == np.sign(d[j]), np.minimum(ad[j - 2], ad[j]), 0.0)
    limit = math.log(FALSE_RATE / n)

    def log_chance(w):
        return np.minimum(0.0, np.log(2.0 * w / (math.sqrt(2.0 * math.pi) * s))) \
            - np.maximum(v - w, 0.0) ** 2 / (5.0 * s * s)

    w = np.maximum(ad[j - 1], 0.5 * q)
    idx = j[(log_chance(w) < limit) & (w <= NEAR_ZERO * s)]
    blind = float(np.mean(log_chance(np.full(j.size, 0.5 * q)) >= limit))
    return idx, blind


def _decimal_step(v: float) -> float:
    """The last decimal place of ``v``'s shortest representation (a value
    read from text as ``0.01234`` gives 1e-5; a full double ~1e-17 of it)."""
    mant, _, exp = repr(float(v)).partition("e")
    frac = mant.partition(".")[2].rstrip("0")
    return 10.0 ** ((int(exp) if exp else 0) - len(frac))


def resolution(y, ad=None) -> float:
    """The record's resolution ([y]): the step of the lattice its values lie
    on (a quantised record's, e.g. whole pixels or 3 mrad) where the
    smallest nonzero difference divides 99 % of the others, else the
    decimal places the values were written with (their median), at least
    4 machine epsilons of the largest value.  Two samples equal by chance
    are as likely as the resolution is coarse."""
    y = np.asarray(y, float)
    if ad is None:
        ad = np.abs(np.diff(y))
    scale = float(np.max(np.abs(y))) if y.size else 1.0
    floor = 4.0 * np.finfo(float).eps * (scale or 1.0)
    sub = y[y != 0][:: max(1, y.size // 200)]  # ~200 values: the median of their last decimal places
    q = max(float(np.median([_decimal_step(v) for v in sub])) if sub.size else 0.0, floor)
    pos = ad[ad > 0]
    if pos.size:
        qm = float(pos.min())
        r = pos / qm
        if qm >= q and np.mean(np.abs(r - np.round(r)) < 1e-6 * np.maximum(r, 1.0)) >= 0.99:
            q = qm
    return q


def remove_repeats(t, y, fit, refit, field: str = "SIGNAL") -> dict | None:
    """The record ``(t`` s on the nominal time base, ``y)`` with the
    repeated frames (:func:`repeated_samples`) in ``fit``'s window
    removed, or None where the window shows none.

    ``refit(t_new, y_new)`` fits other samples on another time base with the
    caller's options (a PeriodFit).  Returns a dict: ``t`` (s, the nominal
    time base of the samples left, from ``t[0]``), ``y``, ``fit`` (the refit;
    its std holds ``std_added`` as ``uncertainty["time_base"]`` where a
    repeat could hide), ``repeated`` (how many removed), ``std_added`` (s:
    the repeats expected where the test is blind, each lengthening the
    period by ``1 / n`` of itself on average), ``nominal_period`` (s, the
    fit before), ``warning`` (one line).
    """
    from .signal_timebase import fit_window, widen_std

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    win = fit_window(t, fit)  # repeats outside the fit's window do not touch its period
    idx, blind = repeated_samples(y[win])
    if idx.size == 0:
        return None
    idx = idx + win.start
    keep = np.ones(y.size, bool)
    keep[idx] = False
    dt = float(np.median(np.diff(t)))
    yc = y[keep]
    tc = t[0] + np.arange(yc.size) * dt
    fit2 = refit(tc, yc)
    n = win.stop - win.start - idx.size  # the window's samples left
    # repeats where the pair test is blind: the rate seen where it can see, over the blind share
    missed = idx.size / max(n * (1.0 - blind), 1.0) * blind * n
    extra = float(fit2.period) * missed / n
    if extra > 0:
        widen_std(fit2, extra)
    long = float(fit.period) / float(fit2.period) - 1.0
    msg = (f"{field}: {idx.size} repeated frames found and removed (two consecutive samples equal where the "
           f"oscillation moves by far more than the noise between frames: a frame written twice, which delays "
           f"every later sample by one frame in a record without a time column and lengthens the period by the "
           f"repeats' share, here {long:.2%}): the period {float(fit2.period):.6g} s is fitted on the samples left "
           f"(with the repeats {float(fit.period):.6g} s)"
           + (f" and its std holds {extra:.2g} s for repeats where the motion is too slow to show them"
              if extra > 0 else "") + "; give the time column to be sure")
    return {"t": tc, "y": yc, "fit": fit2, "repeated": int(idx.size), "std_added": extra,
            "nominal_period": float(fit.period), "warning": msg}
