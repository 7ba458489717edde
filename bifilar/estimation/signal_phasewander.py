"""Frame faults the noise hides: the phase of each cycle against the fit's.

A record read at ``--sample-rate`` whose camera dropped (or repeated)
frames that neither :mod:`.signal_frames` (the frames' lattice),
:func:`.signal_timebase.phase_steps` (each frame's step) nor
:mod:`.signal_repeats` (two equal samples) can see, because the noise or a
coarse quantisation hides a single frame, still has its phase walk as the
frames' count does: one frame's phase ``h = 2 pi f dt`` forward at each
drop, back at each repeat.  The fit follows the mean rate (a two- or
three-mode fit some of the walk as well), so the period is off by the
frames' share and its std does not say so (design.md "dropfix3, session
19": a 1 % dropped record z -7.4, one drop z -6.0, 0.3 % repeated in a
3 mrad quantised record z up to +47).

:func:`cycle_phase` demodulates the residual of the fit cycle by cycle
against the fit's own curve: its component along the curve is the
amplitude's misfit, the one across it the phase's, each with the same
white-noise variance.  A time base that walks moves only the phase; a beat
or a chirp the model does not follow, or noise that is not white (the KTH
laser records), moves both alike or the amplitude more.  Where the phase's
chi^2 is far above its noise AND above the amplitude's
(:func:`phase_walk_check`), the period's std gains the shift the frames
such a walk implies would make.  SI units: time s, frequency Hz, phase
rad.
"""

from __future__ import annotations

import math

import numpy as np

#: a random walk of ``D`` unit steps over the record, less its least-squares
#: line, keeps ``D / 15`` of mean square (a Brownian motion's: 1/15; measured
#: 0.067 over 2000 simulated walks)
WALK_SHARE = 1.0 / 15.0
#: the phase's chi^2 per cycle above which the fit does not follow the
#: record's phase (clean, quantised, beating and chirping records the model
#: follows: 0.3-1.4; the hidden faults 4.4-800)
PHASE_CHI2 = 3.0
#: ... and this many times the amplitude's (or the cycles', where that is
#: less): a time base's walk moves the phase only (hidden drops and repeats
#: 4.1-271 with two of 40 at 1.7-2.1; the KTH laser records, whose noise is
#: not white, 0.14-2.2; chirps fitted two-mode 0.1-0.2)
PHASE_OVER_AMPLITUDE = 3.0
#: records longer than this are not checked (the camera records the frame
#: checks are for: :data:`.signal_frames.MAX_SAMPLES`)
MAX_SAMPLES = 12_000
#: at least this many whole cycles
MIN_CYCLES = 6
#: at least this many samples a cycle
MIN_SAMPLES_PER_CYCLE = 8
#: ... or this many times where the phase's advances lean back
#: (:func:`leans_back`): repeats in a quantised record whose amplitude
#: strays too (dropfix3's misses 7000 and 7020: 2.1 and 1.7, leaning -1.7
#: and -2.5); the KTH laser records up to 2.2 lean at most 0.3 sds of
#: chance back (design.md "dropfix4, session 20")
PHASE_OVER_AMPLITUDE_BACK = 1.5
#: a lean counts only beyond this many sds of white noise's skew
LEAN_SIGNIFICANCE = 2.5
#: the phase advances' skew (:func:`phase_lean`) above which frame faults are
#: named dropped (forward): 44 of 48 records with 1 % dropped lean above it
#: (median +0.98), 1 of 40 quantised records with repeats
LEAN_FORWARD = 0.1
#: ... and below which they are named repeated (back): 39 of those 40
#: (median -1.67), 1 of the 48 with drops (design.md "dropfix4, session 20")
LEAN_BACK = -0.3


def cycle_phase(t, y, fit) -> dict | None:
    """The record ``(t`` s, ``y)``'s misfit to ``fit`` (a PeriodFit with a
    model curve) cycle by cycle, across and along the fit's curve.

    The samples in the fit's window are cut into ``K`` whole cycles of ``W``
    samples at the fitted frequency ``f``; in each, the residual ``r = y -
    fit.predict(t)`` and the prediction ``p`` (its cycle mean removed) are
    demodulated, ``z_r = sum r exp(-2 pi i f t)``, ``z_p`` alike.  The
    phase misfit ``phi_k = Im(z_r conj(z_p)) / |z_p|^2`` (rad) and the
    amplitude's ``alpha_k = Re(...) / |z_p|^2`` (a share) both have the
    variance ``W sigma^2 / (2 |z_p|^2)`` under white noise ``sigma``
    (:func:`.signal_timebase.white_noise`).  Returns None for a record
    without a model curve, over ``MAX_SAMPLES``, under ``MIN_CYCLES`` cycles
    or ``MIN_SAMPLES_PER_CYCLE`` samples a cycle; else a dict: ``chi2``
    (sum ``phi_k^2 / var_k``), ``chi2_amplitude`` (the same of
    ``alpha_k``), ``cycles`` (``K``), ``samples`` (``K W``), ``step`` (``h
    = 2 pi f dt``, rad), ``walk`` (frames: the random walk of one-frame
    steps whose mean square about its least-squares line, ``WALK_SHARE``
    of its steps, would leave the record's own per-cycle phase (``arg z``
    of ``y``, its cycle mean removed, unwrapped) as far from a straight line
    as it lies beyond the white noise; at least 0).
    """
    from .signal_timebase import white_noise

    if getattr(fit, "model", "") == "crossings" or not getattr(fit, "_kind", ""):
        return None
    cyc = _window_cycles(t, y, fit)
    if cyc is None:
        return None
    t, y, f, dt, W, K = cyc
    p = np.asarray(fit.predict(t), float).reshape(K, W)
    e = np.exp(-2j * np.pi * f * t).reshape(K, W)
    zr = np.sum((y.reshape(K, W) - p) * e, axis=1)
    zp = np.sum((p - p.mean(axis=1, keepdims=True)) * e, axis=1)
    sig = white_noise(y)
    ap = np.abs(zp) ** 2
    if not (sig > 0 and np.all(ap > 0)):
        return None
    var = W * sig * sig / (2.0 * ap)
    cross = zr * np.conj(zp) / ap
    h = 2.0 * np.pi * f * dt
    # the record's own phase per cycle against a weighted straight line: the walk the frames leave,
    # whatever the fit has followed of it
    zy = _record_cycles(y, e, K, W)
    lean = _advance_skew(zy)
    sw = np.sqrt(np.abs(zy) ** 2 / (W * sig * sig / 2.0))  # 1 / the phase noise's std per cycle
    X = np.column_stack([np.ones(K), np.arange(K) / K]) * sw[:, None]
    b = np.unwrap(np.angle(zy)) * sw
    res = b - X @ np.linalg.lstsq(X, b, rcond=None)[0]
    walk = (float(res @ res) - (K - 2)) / (h * h * WALK_SHARE * float(sw @ sw))
    return {"chi2": float(np.sum(cross.imag ** 2 / var)), "chi2_amplitude": float(np.sum(cross.real ** 2 / var)),
            "cycles": int(K), "samples": int(K * W), "step": float(h), "walk": max(walk, 0.0), "lean": lean}


def _window_cycles(t, y, fit):
    """``(t, y, f, dt, W, K)``: the samples in ``fit``'s window (s, [y]) cut
    to ``K`` whole cycles of ``W`` samples at its frequency ``f`` (Hz),
    ``dt`` (s) the median sample step; None for a record over
    ``MAX_SAMPLES``, under ``MIN_CYCLES`` cycles or
    ``MIN_SAMPLES_PER_CYCLE`` samples a cycle."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if t.size > MAX_SAMPLES:
        return None
    from .signal_timebase import fit_window

    win = fit_window(t, fit)
    t, y = t[win], y[win]
    f = float(fit.frequency)
    if t.size < MIN_CYCLES * MIN_SAMPLES_PER_CYCLE or not (np.isfinite(f) and f > 0):
        return None
    dt = float(np.median(np.diff(t)))
    W = int(round(1.0 / (f * dt)))
    K = t.size // max(W, 1)
    if W < MIN_SAMPLES_PER_CYCLE or K < MIN_CYCLES:
        return None
    return t[:K * W], y[:K * W], f, dt, W, K


def _record_cycles(y, e, K: int, W: int):
    """The record's own complex amplitude per cycle: ``sum (y - its cycle
    mean) e`` over each of the ``K`` rows of ``W`` samples (``e`` the
    demodulating ``exp(-2 pi i f t)`` in the same shape)."""
    yc = np.asarray(y, float).reshape(K, W)
    return np.sum((yc - yc.mean(axis=1, keepdims=True)) * e, axis=1)


def phase_lean(t, y, fit) -> float | None:
    """The skew (unit-free) of the record's phase advance from one cycle to
    the next in ``fit``'s window (``t`` s, ``y``; the cycles of
    :func:`cycle_phase`, each one's phase ``arg`` of its demodulated sum,
    unwrapped): the frame-interval residuals' lean.  A dropped frame adds
    one frame's phase to one cycle's advance (a few large advances: skew
    > 0), a repeated frame takes it away (skew < 0); white noise, a beat or
    a steady chirp leave it near 0 (its scatter ``sqrt(6 / K)``).  None
    where :func:`cycle_phase` would not read the cycles."""
    cyc = _window_cycles(t, y, fit)
    if cyc is None:
        return None
    t, y, f, _, W, K = cyc
    return _advance_skew(_record_cycles(y, np.exp(-2j * np.pi * f * t).reshape(K, W), K, W))


def _advance_skew(zy) -> float | None:
    """The skew of the unwrapped phase of ``zy`` (one complex amplitude a
    cycle) from one cycle to the next; None where it does not vary."""
    d = np.diff(np.unwrap(np.angle(zy)))
    d = d - d.mean()
    m2 = float(np.mean(d * d))
    return float(np.mean(d ** 3)) / m2 ** 1.5 if m2 > 0 else None


def leans_back(lean: float | None, cycles: int) -> bool:
    """Whether the cycles' phase advances lean back beyond chance: skew
    (:func:`phase_lean`) below ``LEAN_BACK`` and below ``-LEAN_SIGNIFICANCE``
    times white noise's scatter of the skew of ``cycles - 1`` advances,
    ``sqrt(6 / (cycles - 1))``."""
    return lean is not None and cycles > 2 and lean < min(LEAN_BACK, -LEAN_SIGNIFICANCE * math.sqrt(6.0 / (cycles - 1)))


def lean_direction(lean: float | None) -> str | None:
    """``"forward"`` (dropped frames) where :func:`phase_lean` is above
    ``LEAN_FORWARD``, ``"back"`` (repeated frames) below ``LEAN_BACK``,
    else None (no direction named)."""
    if lean is None:
        return None
    return "forward" if lean > LEAN_FORWARD else "back" if lean < LEAN_BACK else None


def phase_walk_check(t, y, fit, field: str = "SIGNAL") -> dict | None:
    """The std of a record without its time column widened for frame
    faults the other checks cannot see, or None where its phase shows none.

    Acts where :func:`cycle_phase`'s phase chi^2 is above ``PHASE_CHI2``
    per cycle and ``PHASE_OVER_AMPLITUDE`` times the amplitude's (or the
    cycles', where that is more); ``PHASE_OVER_AMPLITUDE_BACK`` times where
    the cycles' phase advances lean back beyond chance (:func:`leans_back`:
    repeated frames, whose mark no beat, chirp or coloured noise leaves).  The walk's ``D`` frames (``walk``) give
    ``D + 2 sqrt(D) + 1`` (a one-sided bound for a count whose estimate
    from a few steps scatters by ~65 %, at least one frame), and the
    period's std gains ``T`` times that over the samples in quadrature
    (:func:`.signal_timebase.widen_std`; ``fit`` is changed in place).  The
    fit stays the answer (its sign unknown: drops shorten, repeats
    lengthen).  Returns the dict :func:`.signal_timebase.check_time_base`
    returns: ``t``, ``fit``, ``warning`` (one line), ``time_base``
    (``method`` ``"phase_walk"``, ``dropped_frames`` None,
    ``nominal_period``, ``std_added`` s, ``phase_chi2`` and
    ``amplitude_chi2`` per cycle, ``frames_implied``, ``lean``: the
    advances' skew)."""
    from .signal_timebase import widen_std

    try:
        c = cycle_phase(t, y, fit)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError):
        return None
    if c is None:
        return None
    K = c["cycles"]
    ratio = c["chi2"] / max(c["chi2_amplitude"], K)
    back = leans_back(c["lean"], K)  # repeated frames' walk: the ratio needed is lower
    if not (c["chi2"] > PHASE_CHI2 * K and ratio > (PHASE_OVER_AMPLITUDE_BACK if back else PHASE_OVER_AMPLITUDE)):
        return None
    D = c["walk"]
    frames = D + 2.0 * math.sqrt(D) + 1.0
    T = float(fit.period)
    extra = T * frames / c["samples"]
    widen_std(fit, extra)
    msg = (f"{field}: the oscillation's phase, cycle by cycle, strays from the fit's by {math.sqrt(c['chi2'] / K):.2g} "
           f"x its noise while its amplitude keeps to it ({math.sqrt(c['chi2_amplitude'] / K):.2g} x): in a record "
           f"without a time column the mark of dropped or repeated frames too faint to find one by one, which "
           f"shift the period by their share; the period's std holds the {extra:.2g} s that about {frames:.0f} "
           f"frames would shift it; give the time column to be sure")
    return {"t": np.asarray(t, float), "fit": fit, "warning": msg,
            "time_base": {"method": "phase_walk", "dropped_frames": None, "nominal_period": T, "std_added": extra,
                          "phase_chi2": c["chi2"] / K, "amplitude_chi2": c["chi2_amplitude"] / K,
                          "frames_implied": frames, "lean": c["lean"]}}
