"""A sensor that saturates: the clipped samples found and left out of the fit.

A rate gyro (or an ADC, or a camera at the edge of its frame) whose range the
oscillation exceeds records every sample beyond it at the same extreme value:
flat tops at the record's maximum (or minimum, or both).  Fitted as they are,
the flat tops are a fundamental with a smaller amplitude plus its odd
harmonics: audit18 (row S1, a gyro clipped at 80 % of its peak rate) had
`period` answer with a two-mode fit and a std ~3x the clean record's,
`invert` warn of "an oscillation at T/3 ... no other mode makes" (the
clip's third harmonic), and Izz biased by the clipped fit's smaller
amplitude.  The samples between the flat tops are the oscillation's own, so
the fit leaves the clipped ones out (the fit takes any sample times:
:func:`.signal.fit_period`).  Part of :mod:`bifilar.estimation.signal`.

SI units: time in s; the samples in the file's own unit ``[y]``.
"""

from __future__ import annotations

import numpy as np

#: a clipped level holds at least this many runs of two or more samples
#: (a flat top at each of several turning points)
MIN_RUNS = 3
#: ... and, leaving out its longest run (a hold at the release angle is one),
#: at least this many times the samples of the most populated other value.
#: A quantised record's top level holds at most ~2.4x its neighbour's (a
#: sine's dwell in the top band of width q against the next, ``1 : sqrt(2)
#: - 1``), a noisy record's values are all but unique; a clip holds ~0.4 of
#: the samples at 80 % of the peak
MIN_RATIO = 5.0
#: the clipped samples left must still define the fit: at least this share
MIN_KEPT_SHARE = 0.25


def _runs(mask: np.ndarray) -> np.ndarray:
    """Lengths of the runs of True in ``mask``."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return np.nonzero(d == -1)[0] - np.nonzero(d == 1)[0]


#: at most this many of the most populated values are examined as clipped
#: levels (an offset stepping under a clip moves one side's level: two per
#: side; each further step adds one)
MAX_LEVELS = 8
#: a clipped level is a turning point: both neighbours of at least this
#: share of its runs of two or more lie on one side of it
MIN_TURNING_SHARE = 0.8


def _clip_side(y: np.ndarray, at: np.ndarray, level: float) -> tuple[str | None, int]:
    """Whether the runs of ``at`` (samples of ``y`` equal to ``level``) are
    flat tops (``"max"``: both neighbours below), flat bottoms (``"min"``)
    or neither (None), and how many runs of two or more it holds."""
    m = np.concatenate([[False], at, [False]]).astype(np.int8)
    d = np.diff(m)
    start, stop = np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]  # run [start, stop)
    multi = (stop - start) >= 2
    start, stop = start[multi], stop[multi]
    if start.size < MIN_RUNS:
        return None, int(start.size)
    before = np.where(start > 0, y[np.maximum(start - 1, 0)], np.nan)
    after = np.where(stop < y.size, y[np.minimum(stop, y.size - 1)], np.nan)
    nb = np.c_[before, after]
    below = np.all((nb < level) | np.isnan(nb), axis=1)
    above = np.all((nb > level) | np.isnan(nb), axis=1)
    for side, ok in (("max", below), ("min", above)):
        if ok.mean() >= MIN_TURNING_SHARE:
            return side, int(start.size)
    return None, int(start.size)


def find_clipping(y) -> dict | None:
    """The samples of ``y`` ([y], finite) at a clipped level, or None.

    A value is a clipped level where the samples exactly equal to it form
    at least :data:`MIN_RUNS` runs of two or more, both neighbours of most
    of them (:data:`MIN_TURNING_SHARE`) on one side (flat tops, or flat
    bottoms), and hold, without their longest run, at least
    :data:`MIN_RATIO` times the samples of any value that is not such a
    level.  The record's maximum and minimum are the usual ones; an offset
    stepping under a sensor's range moves one side's level (flat tops at
    two values: both found).  Returns ``mask`` (bool, the clipped samples),
    ``levels`` (``{"max": level, "min": level}`` for the clipped sides, the
    outermost level of each, [y]), ``all_levels`` (``[[side, level], ...]``
    every clipped level), ``runs`` (the number of flat tops) and
    ``samples`` (the number clipped)."""
    y = np.asarray(y, float)
    if y.size < 8:
        return None
    vals, counts = np.unique(y, return_counts=True)
    if vals.size < 3:
        return None
    order = np.argsort(-counts, kind="stable")[:MAX_LEVELS]
    cand = []  # (value, side, runs, samples less the longest run)
    for i in order:
        if counts[i] < 2 * MIN_RUNS:
            break
        at = y == vals[i]
        side, nruns = _clip_side(y, at, float(vals[i]))
        if side is not None:
            cand.append((float(vals[i]), side, nruns, int(at.sum()) - int(_runs(at).max()), at))
    while cand:
        taken = {c[0] for c in cand}
        other = int(max((c for v, c in zip(vals, counts) if float(v) not in taken), default=0))
        keep = [c for c in cand if c[3] >= MIN_RATIO * other]
        if len(keep) == len(cand):
            break
        cand = keep
    if not cand:
        return None
    mask = np.zeros(y.size, bool)
    for c in cand:
        mask |= c[4]
    if (~mask).sum() < MIN_KEPT_SHARE * y.size:
        return None
    levels: dict[str, float] = {}
    for v, side, *_ in cand:
        if side not in levels or (v > levels[side] if side == "max" else v < levels[side]):
            levels[side] = v
    return {"mask": mask, "levels": {s: levels[s] for s in ("max", "min") if s in levels},
            "all_levels": sorted([[c[1], c[0]] for c in cand], key=lambda x: (x[0], -x[1])),
            "runs": int(sum(c[2] for c in cand)), "samples": int(mask.sum())}


def drop_clipped(t, y, osc: dict, notes: list, min_samples: int):
    """Leave the clipped samples (:func:`find_clipping`) out before the fit:
    ``(t, y, osc)`` with ``osc["clipped"]`` (``levels`` [y], ``runs``,
    ``samples_left_out``, ``line``) and the line in ``notes``; unchanged
    where nothing is clipped or fewer than ``min_samples`` would be left."""
    c = find_clipping(y)
    if c is None:
        return t, y, osc
    keep = ~c["mask"]
    if int(keep.sum()) < min_samples:
        return t, y, osc
    if len(c["all_levels"]) == len(c["levels"]):
        lv = "the record's " + " and ".join(f"{s} {v:.6g}" for s, v in c["levels"].items())
    else:  # an offset step under the clip: one side flat at two levels
        lv = "the levels " + ", ".join(f"{v:.6g} ({'top' if s == 'max' else 'bottom'})" for s, v in c["all_levels"])
    line = (f"the sensor saturates: {c['samples']} of {y.size} samples sit exactly at {lv} "
            f"(flat tops at {c['runs']} turning points: clipped); "
            "they are left out of the fit (the samples between them are the oscillation's own); "
            "record with a range that holds the motion")
    notes.append(line)
    info = {"levels": c["levels"], "all_levels": c["all_levels"], "runs": c["runs"], "samples_left_out": c["samples"],
            "line": line}
    return t[keep], y[keep], dict(osc, clipped=info)


#: soft clipping: the central samples of a period (within this share of its
#: amplitude of its level) define its sinusoid, and are the ones kept
SOFT_CENTRAL = 0.5
#: the samples kept where it fires: within this share of each period's
#: amplitude of its level (a ``tanh`` law compressing the peak to 70 % of
#: the true one compresses these by at most ~1.5 %, against ~7 % at 0.5)
SOFT_KEPT = 0.3
#: the peaks' samples (the central sinusoid beyond this share of its
#: amplitude) are compared with it: ``r = sum((y - c) s) / sum(s^2)`` per side
SOFT_OUTER = 0.8
#: fires where the peaks' mean ratio ``(r_max + r_min) / 2`` (a quadratic
#: sensor law, e.g. a laser dot's position, stretches one side as much as it
#: compresses the other and cancels) falls short of 1 by this much ...
SOFT_MIN_COMPRESSION = 0.045
#: ... and by this many of its standard errors over the periods (median and
#: robust std)
SOFT_MIN_SIGMAS = 6.0
#: at least this many one-period windows with peaks on both sides
SOFT_MIN_PERIODS = 6


def _soft_windows(t, y, T: float):
    """One-period windows of ``t`` (s) from ``t[0]`` (the last one holds the
    remainder): for each, its sample slice, the sinusoid ``c + p cos + q
    sin`` at period ``T`` fitted to its central samples (iterated twice) and
    the peaks' ratios ``(r_max, r_min)`` (None where a side has no peak
    sample)."""
    w = 2 * np.pi / T
    n_win = int((t[-1] - t[0]) // T)
    bounds = np.searchsorted(t, t[0] + T * np.arange(n_win + 1))
    if n_win >= 1:
        bounds[-1] = t.size
    out = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        ts, ys = t[a:b] - t[a], y[a:b]
        if ts.size < 8:
            continue
        B = np.c_[np.ones(ts.size), np.cos(w * ts), np.sin(w * ts)]
        x = np.linalg.lstsq(B, ys, rcond=None)[0]
        for _ in range(2):
            m = np.abs(ys - x[0]) < SOFT_CENTRAL * np.hypot(x[1], x[2])
            if m.sum() < 5:
                break
            x = np.linalg.lstsq(B[m], ys[m], rcond=None)[0]
        A = float(np.hypot(x[1], x[2]))
        s = B[:, 1:] @ x[1:]
        r = []
        for side in (s > SOFT_OUTER * A, s < -SOFT_OUTER * A):
            r.append(float(np.sum((ys[side] - x[0]) * s[side]) / np.sum(s[side] ** 2)) if side.any() else None)
        out.append((a, b, s, A, r))
    return out


def find_soft_clipping(t, y, T: float) -> dict | None:
    """A sensor that saturates gradually (its output compressed near full
    scale, ``tanh``-like: a gyro or an amplifier near its range), or None.

    ``t`` (s, increasing), ``y`` ([y]), ``T`` the period (s).  In each
    one-period window a sinusoid is fitted to the central samples (within
    :data:`SOFT_CENTRAL` of its amplitude of its level, where a saturating
    sensor is nearly linear) and its peaks (beyond :data:`SOFT_OUTER`)
    compared with the samples there: ``r`` per side, 1 for a linear sensor,
    below 1 where the peaks are compressed.  Fires where the windows' median
    of ``(r_max + r_min) / 2`` lies :data:`SOFT_MIN_COMPRESSION` and
    :data:`SOFT_MIN_SIGMAS` standard errors below 1 (a quadratic law
    stretches one side as it compresses the other: the mean cancels it).
    Returns ``mask`` (bool, the samples beyond the central band: the
    compressed ones, left out), ``compression`` (1 - the median mean ratio),
    ``ratios`` (the median ``r`` of the max and the min side) and
    ``periods`` (windows used)."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    if not (np.isfinite(T) and T > 0) or t.size < 16:
        return None
    win = _soft_windows(t, y, T)
    r = np.array([w[4] for w in win if None not in w[4]], float).reshape(-1, 2)
    if r.shape[0] < SOFT_MIN_PERIODS:
        return None
    mean = r.mean(axis=1)
    med = float(np.median(mean))
    se = 1.2533 * 1.4826 * float(np.median(np.abs(mean - med))) / np.sqrt(mean.size)  # of a median
    comp = 1.0 - med
    if comp < SOFT_MIN_COMPRESSION or comp < SOFT_MIN_SIGMAS * se:
        return None
    mask = np.zeros(t.size, bool)
    for a, b, s, A, _ in win:
        mask[a:b] = np.abs(s) > SOFT_KEPT * A
    return {"mask": mask, "compression": comp, "ratios": [float(np.median(r[:, 0])), float(np.median(r[:, 1]))],
            "periods": int(r.shape[0]), "samples": int(mask.sum())}


def drop_soft_clipped(t, y, osc: dict, notes: list, min_samples: int):
    """Leave the peaks of a gradually saturating sensor
    (:func:`find_soft_clipping`) out before the fit: ``(t, y, osc)`` with
    ``osc["soft_clipped"]`` (``compression``, ``ratios``, ``samples_left_out``,
    ``line``) and the line in ``notes``; unchanged where nothing is found,
    where the record is hard-clipped (``osc["clipped"]``) or fewer than
    ``min_samples`` would be left."""
    if osc.get("clipped"):
        return t, y, osc
    c = find_soft_clipping(t, y, 1.0 / float(osc["frequency"]))
    if c is None:
        return t, y, osc
    keep = ~c["mask"]
    if int(keep.sum()) < min_samples:
        return t, y, osc
    line = (f"the sensor saturates gradually: its peaks come out {c['compression']:.0%} short of the sinusoid "
            f"through the samples near the level (max side x{c['ratios'][0]:.3f}, min side x{c['ratios'][1]:.3f}, "
            f"median of {c['periods']} periods: compressed near full scale); the {c['samples']} of {t.size} samples "
            f"beyond {SOFT_KEPT:.0%} of each period's amplitude are left out of the fit; record with a range "
            "that holds the motion")
    notes.append(line)
    info = {"compression": c["compression"], "ratios": c["ratios"], "samples_left_out": c["samples"], "line": line}
    return t[keep], y[keep], dict(osc, soft_clipped=info)


#: the fit of the samples kept must find the whole record's spectral peak
#: within this share of it (those samples lie in bands about the crossings,
#: every half period: a fit of them alone can take 3f, or a multi-mode fit
#: put its dominant mode there)
SOFT_MAX_SHIFT = 0.25


def soft_fit_holds(fit, osc: dict) -> bool:
    """Whether ``fit`` (a :class:`.signal_result.PeriodFit` of the samples
    :func:`drop_soft_clipped` kept) finds the oscillation of ``osc`` (its
    ``frequency``, Hz, the whole record's spectral peak) within
    :data:`SOFT_MAX_SHIFT`."""
    f, f0 = float(fit.frequency), float(osc["frequency"])
    return bool(np.isfinite(f) and abs(f / f0 - 1.0) <= SOFT_MAX_SHIFT)


def keep_soft_clipped(whole: tuple, osc: dict):
    """The record as it was before :func:`drop_soft_clipped` (``whole`` =
    ``(t, y, osc, notes)``), its soft clipping still named (``osc_kept =
    osc["soft_clipped"]`` with ``kept`` True and the line saying the peaks
    stay in the fit and the amplitude reads low): where the samples near
    the level alone do not fix the period (:func:`soft_fit_holds`).
    Returns ``(t, y, osc, notes)``."""
    t, y, osc0, notes = whole
    sc = osc["soft_clipped"]
    line = sc["line"].split("; the ")[0] + (
        "; the samples near the level alone do not fix the period (another oscillation with it?), so the peaks "
        f"are kept in the fit: its amplitude reads up to {sc['compression']:.0%} low; record with a range that "
        "holds the motion")
    notes = list(notes) + [line]
    return t, y, dict(osc0, soft_clipped=dict(sc, kept=True, samples_left_out=0, line=line)), notes


def take_fault_warnings(fit) -> list[str]:
    """The lines of a sensor's faults the fit dealt with (the clipped samples
    left out, :func:`drop_clipped`; an offset's step taken out,
    :func:`.signal_offset.remove_offset_step`), moved from the fit's notes
    to be returned: the caller lists them as warnings."""
    lines = []
    for key in ("clipped", "soft_clipped", "offset_step"):
        c = (fit.oscillation or {}).get(key)
        if c:
            if c["line"] in fit.notes:
                fit.notes.remove(c["line"])
            lines.append(c["line"])
    return lines
