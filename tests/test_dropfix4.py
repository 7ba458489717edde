"""Time-base faults of a record without its time column, session 20
(design.md "dropfix4, session 20"): which way the refusal says the time
base is off, the check kept to the fit's window, and a phase walk that
leans back.

The records are the synthetic draws of dropfix's sweep (damped cosines at
30 fps, :func:`test_signal_phasewander._draw`: the truth is the cosine's own
period); all seeded.
"""

from __future__ import annotations

import types

import numpy as np
import pytest

from bifilar.errors import InputError
from bifilar.estimation.signal import fit_period
from bifilar.estimation.signal_phasewander import lean_direction, phase_lean
from bifilar.estimation.signal_timebase import check_time_base

from test_signal_phasewander import _draw


def _window(T, t):
    """What phase_lean reads of a fit: its window and frequency (here the
    truth's, so that no fit's error enters the count)."""
    return types.SimpleNamespace(t0=float(t[0]), t1=float(t[-1]), frequency=1.0 / T)


def _check(t, y, **kw):
    fit = fit_period(t, y, model="auto", **kw)
    return fit, check_time_base(t, y, fit, "sample_rate", lambda tn, yn=y: fit_period(tn, yn, model="auto", **kw))


def test_the_lean_tells_drops_from_repeats():
    """A dropped frame adds one frame's phase to one cycle's advance, a
    repeated one takes it away: the advances' skew leans forward or back.
    dropfix's 48 records with 1 % dropped and its 40 quantised (3 mrad)
    records with 0.3 % repeated (measured: 48 of 48 forward, 40 of 40 back
    at the true frequency).  Allowed: 6 of 48 / 5 of 40 the other way or
    unnamed, ~3 binomial sds below a rate of 0.95 (a rate as low as 0.8
    passes with probability < 0.01), and never the wrong direction named
    more than twice."""
    fwd = [lean_direction(phase_lean(t, y, _window(T, t))) for T, t, y in (_draw(s, drop=0.01) for s in range(1000, 1048))]
    back = [lean_direction(phase_lean(t, y, _window(T, t)))
            for T, t, y in (_draw(s, "drift+quant", rep=0.003) for s in range(7000, 7040))]
    assert fwd.count("forward") >= 42 and fwd.count("back") <= 2, fwd
    assert back.count("back") >= 35 and back.count("forward") <= 2, back


def test_hidden_repeats_are_refused_as_repeated_frames():
    """Draw 7001: a 3 mrad quantised record with frames written twice (0.3
    %), whose quantisation's own steps phase_steps counts as two steps
    forward: refused (no std holds the shift), and the refusal used to say
    "dropped frames ... shorten the period" of a record whose period is
    long.  Its cycles' phase advances lean back (skew about -1.5): the
    refusal now names repeated frames that lengthen it.  Fails on the old
    code (its line says dropped frames)."""
    T, t, y = _draw(7001, "drift+quant", rep=0.003)
    with pytest.raises(InputError) as e:
        _check(t, y)
    msg = str(e.value)
    assert "repeated frames" in msg and "lengthen the period" in msg and "leans back" in msg, msg
    assert "dropped" not in msg and "shorten" not in msg and "\n" not in msg
    assert "time column" in msg and "--sample-rate" in msg


def test_hidden_drops_are_still_refused_as_dropped_frames():
    """Draw 2002 (3 % dropped, their steps hidden by the noise, z -12.6):
    refused as before, its advances leaning forward (skew about +0.8):
    dropped frames that shorten the period."""
    T, t, y = _draw(2002, drop=0.03)
    with pytest.raises(InputError) as e:
        _check(t, y)
    msg = str(e.value)
    assert "dropped frames" in msg and "shorten the period" in msg and "leans forward" in msg, msg
    assert "repeated" not in msg
