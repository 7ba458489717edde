"""An angle recorded wrapped into one turn (``atan2``'s +-pi), put back.

A camera or IMU that reports a heading as ``atan2(...)`` wraps it into
(-pi, pi] (some into [0, 2 pi), or degrees into +-180): an oscillation about
a rest heading near the wrap then jumps by a full turn between samples each
time it crosses it.  Fitted as it is, such a record is a square-wave-like
signal whose "amplitude" is pi: `period` answered it with a two-mode fit
and a std ~30x the clean record's, and `invert --signal-quantity angle`
refused it as a record in degrees (audit, session 18).  Part of
:mod:`bifilar.estimation.signal` (called by
:func:`.signal_io.read_signal`).

SI units: the samples in the file's own unit ``[y]``; the turn tried is
2 pi (radians) and 360 (degrees) of that unit.
"""

from __future__ import annotations

import numpy as np

#: (one turn in the file's unit, how the message names the wrap)
TURNS = ((2.0 * np.pi, "2 pi", "+-pi"), (360.0, "360", "+-180 degrees"))

#: after unwrapping, no step between samples may exceed this fraction of a
#: turn (an eighth: a physical angle sampled at least 8 times a turn of its
#: own motion); a record whose big steps are not all within it of a whole
#: turn is not a wrapped angle and is left as it is
MAX_STEP_TURNS = 0.125


def unwrap_record(y: np.ndarray) -> tuple[np.ndarray, str | None]:
    """``(y, warning)``: the record ``y`` ([y], finite) unwrapped where it is an
    angle wrapped into one turn, with a one-line warning saying so; else
    ``y`` unchanged and None.

    Wrapped means: some step between samples exceeds half a turn, the values
    span at most one turn (as ``atan2`` or a [0, 360) heading gives them), and
    with whole turns added at those steps (:func:`numpy.unwrap`) no step is
    larger than :data:`MAX_STEP_TURNS` of a turn.  A turn of 2 pi is tried
    first, then 360 (degrees)."""
    y = np.asarray(y, dtype=float)
    if y.size < 3:
        return y, None
    d = np.abs(np.diff(y))
    span = float(np.ptp(y))
    for turn, turn_name, wrap_name in TURNS:
        jumps = int(np.count_nonzero(d > 0.5 * turn))
        if not jumps or span > turn * (1.0 + 1e-9):
            continue
        u = np.unwrap(y, period=turn)
        if float(np.max(np.abs(np.diff(u)))) > MAX_STEP_TURNS * turn:
            continue
        return u, (f"the record jumps by a full turn ({turn_name}) between samples {jumps} time(s) and spans at most "
                   f"one turn: an angle wrapped at {wrap_name} (atan2); unwrapped before fitting")
    return y, None
