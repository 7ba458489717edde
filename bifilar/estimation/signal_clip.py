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


def find_clipping(y) -> dict | None:
    """The samples of ``y`` ([y], finite) at a clipped extreme, or None.

    A side (the record's maximum, its minimum) is clipped where the samples
    exactly equal to it form at least :data:`MIN_RUNS` runs of two or more,
    and hold, without their longest run, at least :data:`MIN_RATIO` times
    the samples of any other value of the record.  Returns ``mask`` (bool,
    the clipped samples), ``levels`` (``{"max": level, "min": level}`` for
    the clipped sides, [y]), ``runs`` (the number of flat tops) and
    ``samples`` (the number clipped)."""
    y = np.asarray(y, float)
    if y.size < 8:
        return None
    vals, counts = np.unique(y, return_counts=True)
    if vals.size < 3:
        return None
    other = int(np.max(counts[1:-1]))  # the most populated value that is neither extreme
    mask = np.zeros(y.size, bool)
    levels: dict[str, float] = {}
    nruns = 0
    for side, level in (("max", vals[-1]), ("min", vals[0])):
        at = y == level
        runs = _runs(at)
        multi = runs[runs >= 2]
        if multi.size < MIN_RUNS:
            continue
        if int(at.sum()) - int(runs.max()) < MIN_RATIO * other:
            continue
        mask |= at
        levels[side] = float(level)
        nruns += int(multi.size)
    if not levels or (~mask).sum() < MIN_KEPT_SHARE * y.size:
        return None
    return {"mask": mask, "levels": levels, "runs": nruns, "samples": int(mask.sum())}


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
    lv = " and ".join(f"{s} {v:.6g}" for s, v in c["levels"].items())
    line = (f"the sensor saturates: {c['samples']} of {y.size} samples sit exactly at the record's {lv} "
            f"(flat tops at {c['runs']} turning points: clipped); "
            "they are left out of the fit (the samples between them are the oscillation's own); "
            "record with a range that holds the motion")
    notes.append(line)
    info = {"levels": c["levels"], "runs": c["runs"], "samples_left_out": c["samples"], "line": line}
    return t[keep], y[keep], dict(osc, clipped=info)


def take_fault_warnings(fit) -> list[str]:
    """The lines of a sensor's faults the fit dealt with (the clipped samples
    left out, :func:`drop_clipped`; an offset's step taken out,
    :func:`.signal_offset.remove_offset_step`), moved from the fit's notes
    to be returned: the caller lists them as warnings."""
    lines = []
    for key in ("clipped", "offset_step"):
        c = (fit.oscillation or {}).get(key)
        if c:
            if c["line"] in fit.notes:
                fit.notes.remove(c["line"])
            lines.append(c["line"])
    return lines
