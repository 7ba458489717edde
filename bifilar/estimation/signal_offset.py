"""A sensor whose offset steps (up to three times): the steps found, named and taken out.

A gyro re-zeroed mid-record, a camera knocked on its mount or a marker
slipping leaves the record's level (its offset) one value before a moment
and another after it.  The fit's offset is one number (and a linear
drift), so a step between them was read as a second mode or as
nonstationarity: audit18 (row S6, a step of 10-50 % of the amplitude at
20-80 % of the record) had `period` answer with a std 5-20x the clean
record's (`two_mode` in 18 of 30) and never name the step.  Here the level
of each period of the record (:func:`.signal_start.local_sinusoids`) is
searched for one jump far beyond the periods' own scatter; where one
stands out, the sample it happens at is found by a local least-squares
fit and the step is subtracted from the samples after it, with one line
naming its time and size.  Part of :mod:`bifilar.estimation.signal`.

SI units: time in s; the samples in the file's own unit ``[y]``.
"""

from __future__ import annotations

import numpy as np

#: the jump between the levels of the periods either side must exceed this
#: many robust stds of the other such jumps (their scatter: noise, a
#: swing's or a beat's wander of the level) ...
MIN_SIGMAS = 10.0
#: ... and this share of the median one-period amplitude (a smaller step
#: barely moves the period; a slow wander of the level must not fire)
MIN_SHARE = 0.05
#: the jump must also stand out among the jumps of this many periods either
#: side of it (their own robust scatter)
LOCAL_PERIODS = 6
#: at least this many periods of record (a step needs levels either side)
MIN_PERIODS = 6
#: the levels either side of the step, fitted with the step and a common
#: drift, scatter by at most 1 / this of the step (a lasting step, not a
#: wander that one jump happens to top)
MIN_CONFIRM = 8.0


def _robust_std(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


#: at most this many steps in one record (each further one is searched
#: among the jumps the others leave)
MAX_STEPS = 3


def find_offset_step(t, y, T: float) -> dict | None:
    """The steps of the level of ``y`` ([y]; ``t`` s; ``T`` the period, s),
    or None.  Returns the largest step's ``index`` (the first sample after
    the step), ``time`` (s, that sample's), ``size`` ([y], after minus
    before) and ``share`` (the size over the median one-period amplitude),
    and ``steps``: every step found (up to :data:`MAX_STEPS`), in time
    order, each with those four keys.

    A step is a jump of the disjoint one-period levels across one period
    beyond :data:`MIN_SIGMAS` robust stds of the record's jumps and of
    those of the :data:`LOCAL_PERIODS` periods either side (the other
    steps' periods left out) and :data:`MIN_SHARE` of the amplitude; the
    jumps are taken largest first.  The levels are then fitted with a line
    and a step at each (the periods holding one left out): every step must
    keep its sign, :data:`MIN_SHARE` of the amplitude and
    :data:`MIN_CONFIRM` times the fit's residual scatter (one failing is
    dropped, the rest refitted)."""
    from .signal_start import STEPS, local_sinusoids

    t = np.asarray(t, float)
    y = np.asarray(y, float)
    ls = local_sinusoids(t, y, T)
    if ls is None:
        return None
    t_start, _, c, A = ls
    c, t_start = c[::STEPS], t_start[::STEPS]  # disjoint one-period windows
    N = c.size
    if N < MIN_PERIODS:
        return None
    amp = float(np.median(A))  # the windows straddling a step read a larger one
    D = c[2:] - c[:-2]  # D[j - 1]: the jump across window j
    dev = D - np.median(D)
    s = _robust_std(D)
    js: list[int] = []
    free = np.ones(D.size, bool)  # the jumps no step found so far touches
    for _ in range(MAX_STEPS):
        cand = np.where(free, np.abs(dev), -np.inf)
        j = int(np.argmax(cand)) + 1
        if not np.isfinite(cand[j - 1]) or not (2 <= j <= N - 3) \
                or abs(dev[j - 1]) <= max(MIN_SIGMAS * s, MIN_SHARE * amp):
            break
        free[max(j - 2, 0):j + 1] = False  # a step moves the jumps across its window and the two beside it
        # beyond the jumps of the periods around it (a fast decay's level wanders early, where the
        # amplitude is large, and the quiet tail sets the record's scatter); other steps' jumps left out
        idx = np.r_[max(j - 1 - LOCAL_PERIODS, 0):max(j - 2, 0), j + 1:min(j + 1 + LOCAL_PERIODS, D.size)]
        idx = idx[free[idx]]
        near = D[idx]
        if near.size >= 4 and abs(D[j - 1] - np.median(near)) <= MIN_SIGMAS * _robust_std(near):
            continue
        js.append(j)
    # confirm: the levels (the windows holding a step left out) as a line with a step after each
    while js:
        k = np.delete(np.arange(N), js)
        X = np.c_[np.ones(k.size), k - 0.5 * N, *[(k > j).astype(float) for j in js]]
        coef, *_ = np.linalg.lstsq(X, c[k], rcond=None)
        r = _robust_std(c[k] - X @ coef)
        h = coef[2:]
        bad = [i for i, j in enumerate(js) if np.sign(h[i]) != np.sign(dev[j - 1]) or abs(h[i]) < MIN_SHARE * amp
               or abs(h[i]) < MIN_CONFIRM * r]
        if not bad:
            break
        js.pop(min(bad, key=lambda i: abs(h[i])))
    steps = []
    for j in sorted(js):
        i = _step_sample(t, y, T, t_start[j - 1], t_start[j + 1] if j + 1 < N else t[-1])
        if i is not None:
            steps.append({"index": i["index"], "time": float(t[i["index"]]), "size": i["size"],
                          "share": abs(i["size"]) / amp})
    if not steps:
        return None
    return dict(max(steps, key=lambda x: abs(x["size"])), steps=steps)


def _step_sample(t, y, T: float, t0: float, t1: float) -> dict | None:
    """The sample, between ``t0`` and ``t1`` + ``T`` (s), after which the
    level steps: the one whose step minimises the residual of ``c + g t + p
    cos + q sin + h [t >= t_i]`` over those samples (linear least squares
    at the period ``T``); ``index`` and ``size`` (``h``, [y])."""
    sel = np.nonzero((t >= t0) & (t <= t1 + T))[0]
    if sel.size < 8:
        return None
    ts, ys = t[sel] - t[sel[0]], y[sel]
    w = 2 * np.pi / T
    B = np.c_[np.ones(ts.size), ts, np.cos(w * ts), np.sin(w * ts)]
    best = None
    for m in range(2, ts.size - 1):
        X = np.c_[B, (np.arange(ts.size) >= m).astype(float)]
        coef, res, *_ = np.linalg.lstsq(X, ys, rcond=None)
        rss = float(res[0]) if res.size else float(np.sum((ys - X @ coef) ** 2))
        if best is None or rss < best[0]:
            best = (rss, m, float(coef[4]))
    return {"index": int(sel[best[1]]), "size": best[2]}


def remove_offset_step(t, y, osc: dict, notes: list):
    """Take the steps of the level (:func:`find_offset_step`) out of ``y``
    before the fit: ``(t, y, osc)``, the samples after each step less its
    size, ``osc["offset_step"]`` (the largest step's ``time`` s, ``size``
    [y], ``share``; ``steps``, every one's; ``line``) and the line in
    ``notes``; unchanged where none is found."""
    st = find_offset_step(t, y, 1.0 / float(osc["frequency"]))
    if st is None:
        return t, y, osc
    y = np.array(y, float)
    for x in st["steps"]:
        y[x["index"]:] -= x["size"]
    each = [f"by {x['size']:+.3g} ({x['share']:.0%} of the amplitude) at t = {x['time']:.4g} s" for x in st["steps"]]
    if len(each) == 1:
        line = (f"the record's level steps {each[0]} (the sensor's offset jumping: re-zeroed, knocked, a marker "
                "slipping?); the step is taken out before the fit")
    else:
        line = (f"the record's level steps {len(each)} times: {', '.join(each)} (the sensor's offset jumping: "
                "re-zeroed, knocked, a marker slipping?); the steps are taken out before the fit")
    notes.append(line)
    steps = [{k: x[k] for k in ("time", "size", "share")} for x in st["steps"]]
    return t, y, dict(osc, offset_step={"time": st["time"], "size": st["size"], "share": st["share"],
                                        "steps": steps, "line": line})
