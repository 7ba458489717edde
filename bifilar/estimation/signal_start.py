"""A record whose start is not a free oscillation (the hand ramping the body
to its release angle and holding it there before letting go), or whose end
is not (the body caught and held, or stopped).

SI units: times in s, frequencies in Hz; the signal in its own unit ``[y]``.

A fit of the whole record reads the hold as part of the motion (``auto``
took it for a second mode, at a std 8-50x the free part's: audit17 row C3;
a caught end widened a viscous fit's std 20-1000x through its halves).
The free part is found from one-period windows slid along the record
(:func:`local_sinusoids`): in each, the linear least-squares fit of ``c +
p cos(w t) + q sin(w t)`` at the record's frequency ``w`` gives the
window's level ``c`` and amplitude ``A = hypot(p, q)``.  Over a free
oscillation ``c`` follows a straight line (the record's level and drift)
within a small share of ``A``: one period of a damped cosine averages to
``~ A zeta``, a second close mode beats without moving ``c``.  A window
over the hold has its level at the release angle, about one amplitude off
that line, and little oscillation at ``w``.  :func:`held_start` finds the
leading run of such windows (the rules at :func:`held_start`); the fit
starts half a period after the first free window (:data:`MARGIN_PERIODS`).
:func:`held_end` is the mirror, on the record reversed in time, with the
leading-rest rule reversed for a body stopped at its rest level.
``fit_period`` calls :func:`trim_held_start` unless ``t_start`` is given
and :func:`trim_held_end` unless ``t_stop`` is: an explicit window wins.
"""

from __future__ import annotations

import numpy as np

#: a leading window is held when its level lies this share of the record's
#: largest amplitude off the record's level line (the hold: ~1)
FIRE_SHARE = 0.15
#: ... and a window is free again below this share (a window holding a
#: fifth of a period of hold reads ~0.05)
FREE_SHARE = 0.06
#: ... and this many times further off than any window a period past the
#: held run (a second mode far from the first moves the level
#: everywhere: no start stands out)
REST_RATIO = 5.0
#: a held run longer than LONG_RUN periods holds a window whose amplitude at
#: the record's frequency is below HELD_AMPLITUDE of the first free
#: period's (a hold does not oscillate: its wobble, <= 5 %, and what the
#: ramp adds; a shorter run has no window wholly held)
HELD_AMPLITUDE = 0.25
LONG_RUN = 1.5
#: the free part starts with this many periods of windows below FREE_SHARE
FREE_RUN = 2
#: ... and it falls from FIRE_SHARE to FREE_SHARE within this many periods
#: (a release is sudden: ~0.1 period; a swell of the baseline is gradual)
SHARP_PERIODS = 1.0
#: the fit starts this many periods after the start of the first free window
MARGIN_PERIODS = 0.5
#: windows per period
STEPS = 8


def local_sinusoids(t, y, T: float):
    """Level and amplitude of ``y`` in one-period windows.

    ``t`` in s (increasing), ``y`` in [y], ``T`` the period (s).  Windows of
    ``m`` samples (``T`` at the median step), started every ``m / STEPS``
    samples.  Returns ``(t_start, t_mid, c, A)``: each window's first and
    middle time (s), level and amplitude ([y]) of the least-squares ``c + p
    cos(2 pi t / T) + q sin(2 pi t / T)``; None when the record is shorter
    than two periods.  O(n) by cumulative sums."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n = t.size
    dt = float(np.median(np.diff(t)))
    m = int(round(T / dt))
    if m < 4 or 2 * m > n:
        return None
    w = 2 * np.pi / T
    tc = t - t[0]
    co, si = np.cos(w * tc), np.sin(w * tc)
    cols = (np.ones(n), co, si, co * co, si * si, co * si, y, y * co, y * si)
    S = np.vstack([np.concatenate(([0.0], np.cumsum(v))) for v in cols])
    i0 = np.arange(0, n - m + 1, max(m // STEPS, 1))
    W = S[:, i0 + m] - S[:, i0]  # window sums
    one, sc, ss, scc, sss, scs, sy, syc, sys_ = W
    M = np.empty((i0.size, 3, 3))
    M[:, 0] = np.stack([one, sc, ss], 1)
    M[:, 1] = np.stack([sc, scc, scs], 1)
    M[:, 2] = np.stack([ss, scs, sss], 1)
    b = np.stack([sy, syc, sys_], 1)
    try:
        x = np.linalg.solve(M, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return None
    return t[i0], t[np.minimum(i0 + m // 2, n - 1)], x[:, 0], np.hypot(x[:, 1], x[:, 2])


def held_start(t, y, T: float):
    """Where a record that starts held (not oscillating freely) becomes free.

    ``t`` (s), ``y`` ([y]), ``T`` the record's period (s, e.g. its spectral
    peak's).  Returns None for a record whose first windows lie on the
    level line of the rest (a free oscillation from its first sample, from
    rest or mid-swing), else a dict: ``t_free`` (s, the start of the first
    window free of the hold), ``t_start`` (s, the first time to fit,
    ``t_free + MARGIN_PERIODS T``), ``deviation`` (the first window's level
    off the line, in units of the largest amplitude), ``rest_deviation``
    (the largest of the other windows', same unit).

    The rules, with ``u`` a window's level off a straight line in units of
    the largest window amplitude: the line is fitted first to the levels
    of the record's second half; the free part starts at the first window
    ``j`` followed by ``FREE_RUN`` periods of windows with ``u <
    FREE_SHARE``, within the record's first half.  It fires when ``u`` falls
    from ``FIRE_SHARE`` to ``FREE_SHARE`` within ``SHARP_PERIODS`` periods
    (a release is sudden; a swelling baseline is gradual), a run longer
    than ``LONG_RUN`` periods holds a window with ``A`` below
    ``HELD_AMPLITUDE`` of the first free period's (a hold does not
    oscillate), and, against the line refitted to the windows a period
    past ``j``, the first window lies ``FIRE_SHARE`` off and ``REST_RATIO``
    times further than any of those."""
    loc = local_sinusoids(t, y, T)
    if loc is None:
        return None
    ts, tm, c, A = loc
    t = np.asarray(t, float)
    half = tm >= 0.5 * (t[0] + t[-1])
    if half.sum() < 3 or not np.any(~half):
        return None
    k, b = np.polyfit(tm[half], c[half], 1)
    dev = np.abs(c - (k * tm + b))
    Amax = float(np.max(A))
    if not Amax > 0:
        return None
    u = dev / Amax
    if not u[0] >= FIRE_SHARE:
        return None
    below = (u < FREE_SHARE).astype(int)
    run = np.convolve(below, np.ones(FREE_RUN * STEPS, int), mode="valid") == FREE_RUN * STEPS
    free = np.nonzero(run)[0]
    if free.size == 0:
        return None
    j = int(free[0])  # the first window of FREE_RUN periods of windows on the line
    if j == 0 or ts[j] > 0.5 * (t[0] + t[-1]):
        return None
    if ts[j] - ts[np.nonzero(u[:j] >= FIRE_SHARE)[0][-1]] > SHARP_PERIODS * T:
        return None  # the level comes back gradually: a slow swell of the baseline, not a release
    later = ts >= ts[j] + T  # surely free: a period past the last window touching the hold
    if not np.any(later):
        return None
    if ts[j] - ts[0] > LONG_RUN * T and not \
            np.min(A[:j]) < HELD_AMPLITUDE * float(np.median(A[j:j + STEPS])):
        return None  # a long run whose windows all oscillate as the free part does: nothing was held
    q = np.polyfit(tm[later], c[later], 1)  # the free part's own level line, carried back over the held run
    u = np.abs(c - np.polyval(q, tm)) / Amax
    rest = float(np.max(u[later]))
    if not (u[0] >= FIRE_SHARE and u[0] >= REST_RATIO * rest):
        return None
    t_free = float(ts[j])
    return {"t_free": t_free, "t_start": t_free + MARGIN_PERIODS * T, "deviation": float(u[0]),
            "rest_deviation": rest}


def trim_held_start(t, y, osc: dict, notes: list):
    """Leave out a held start (:func:`held_start`) before the fit.

    ``t`` (s), ``y`` ([y]) the record, ``osc`` the oscillation check's dict
    (its ``frequency``, Hz), ``notes`` the fit's notes.  Returns ``(t, y,
    osc)``: unchanged when the record starts free or too little would
    remain (fewer than ``MIN_SAMPLES`` samples or 3 periods); else from
    ``t_start`` on, with a note and ``osc["held_start"]``: ``t_free``,
    ``t_start`` (the first sample fitted, s), ``samples_left_out``,
    ``deviation``, ``rest_deviation`` (see :func:`held_start`), ``line``
    (the note, :func:`start_warning`)."""
    from .signal_io import MIN_SAMPLES

    T = 1.0 / float(osc["frequency"])
    h = held_start(t, y, T)
    if h is None:
        return t, y, osc
    keep = t >= h["t_start"]
    if int(keep.sum()) < MIN_SAMPLES or (t[-1] - h["t_start"]) < 3 * T:
        return t, y, osc
    t_fit = float(t[keep][0])
    h = dict(h, t_start=t_fit, samples_left_out=int((~keep).sum()))
    h["line"] = start_warning(h, float(t[0]))
    notes.append(h["line"])
    return t[keep], y[keep], dict(osc, held_start=h)


def start_warning(h: dict, t0: float) -> str:
    """The one line saying a held start was left out (``h`` from
    :func:`trim_held_start`, ``t0`` the record's first time, s)."""
    return (f"the record is not a free oscillation before about t = {h['t_free']:.4g} s (its level there lies "
            f"{h['deviation']:.2g} of the amplitude off the rest's: the body held or moved by hand before the "
            f"release); the fit starts at t = {h['t_start']:.4g} s, leaving out the first {h['t_start'] - t0:.3g} s "
            f"({h['samples_left_out']} samples; give --t-start to choose the start)")


def take_start_warning(fit) -> str | None:
    """The held-start and held-end lines of a
    :class:`~.signal_result.PeriodFit` (None when its record starts and ends
    free; both joined by "; "), taken out of ``fit.notes`` so that the
    CLI shows it once, as a warning."""
    lines = [h["line"] for h in ((fit.oscillation or {}).get(k) for k in ("held_start", "held_end")) if h]
    for line in lines:
        if line in fit.notes:
            fit.notes.remove(line)
    return "; ".join(lines) or None


def held_end(t, y, T: float):
    """Where a record that ends held (the body caught by hand and held, or
    stopped at rest) stops being free: :func:`held_start` on the record
    reversed in time, or a trailing stretch at rest
    (:func:`.signal_models._leading_rest` reversed).  ``t`` (s), ``y``
    ([y]), ``T`` (s).  Returns None, or a dict with ``t_stop`` (s, the last
    time to fit, ``MARGIN_PERIODS T`` before the first window touching the
    hold), ``t_held`` (s, the end of the last free window) and ``how``
    (``"held"`` or ``"rest"``)."""
    from .signal_models import _leading_rest

    t = np.asarray(t, float)
    tr, yr = -t[::-1], np.asarray(y, float)[::-1]
    h = held_start(tr, yr, T)
    if h is not None:
        return {"t_held": -h["t_free"], "t_stop": -h["t_start"], "how": "held", "deviation": h["deviation"],
                "rest_deviation": h["rest_deviation"]}
    rest = _leading_rest(tr, yr, T)
    if rest is None:
        return None
    return {"t_held": -rest[0], "t_stop": -rest[1], "how": "rest"}


def trim_held_end(t, y, osc: dict, notes: list):
    """Leave out a held end (:func:`held_end`) before the fit, as
    :func:`trim_held_start` leaves out a held start: ``osc["held_end"]``
    (``t_stop`` the last sample fitted, s; ``samples_left_out``, ``how``,
    ``line``) and a note."""
    from .signal_io import MIN_SAMPLES

    T = 1.0 / float(osc["frequency"])
    h = held_end(t, y, T)
    if h is None:
        return t, y, osc
    keep = t <= h["t_stop"]
    if int(keep.sum()) < MIN_SAMPLES or (h["t_stop"] - t[0]) < 3 * T:
        return t, y, osc
    h = dict(h, t_stop=float(t[keep][-1]), samples_left_out=int((~keep).sum()))
    what = "held by hand" if h["how"] == "held" else "stopped at rest"
    h["line"] = (f"the record is not a free oscillation after about t = {h['t_held']:.4g} s (the body {what}: "
                 f"caught?); the fit ends at t = {h['t_stop']:.4g} s, leaving out the last "
                 f"{float(t[-1]) - h['t_stop']:.3g} s ({h['samples_left_out']} samples; give --t-stop to choose "
                 "the end)")
    notes.append(h["line"])
    return t[keep], y[keep], dict(osc, held_end=h)
