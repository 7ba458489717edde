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


def _record(seed, T=1.45, cyc=40, noise=2.9e-3, drop_part=(0.0, 0.0), drop=0.03, rep_at=()):
    """A 0.1 rad cosine of period ``T`` (s) decaying at 0.01/s, ``cyc``
    cycles at 30 fps with white noise (rad); a share ``drop`` of the frames
    between the shares ``drop_part`` of the record dropped; the samples at
    ``rep_at`` (indices) written twice.  Returns (T, the nominal time base
    s, y rad)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, cyc * T, 1 / 30.0)
    y = 0.1 * np.exp(-0.01 * t) * np.cos(2 * np.pi / T * t + 0.3) + noise * rng.standard_normal(t.size)
    a, b = drop_part
    y = y[~((t >= a * t[-1]) & (t < b * t[-1]) & (rng.uniform(size=t.size) < drop))]
    for j in sorted(rep_at, reverse=True):
        y = np.insert(y, j, y[j - 1])
    return T, np.arange(y.size) / 30.0, y


def test_repeats_outside_the_fit_window_leave_its_period_alone():
    """Three frames written twice in the first 8 s of a 58 s record whose
    fit starts at 12 s (--t-start): the window's samples are regular, the
    fit's period and std stand (no check).  The old code read the whole
    file, removed them, refitted and warned (the std x1.01, the samples
    shifted by three frames).  The same repeats inside the window are
    still found and removed."""
    T, t, y = _record(1, rep_at=(60, 150, 230))
    fit, res = _check(t, y, t_start=12.0)
    assert res is None, res and res["time_base"]
    _, res = _check(t, y)
    assert res is not None and res["time_base"]["method"] == "repeats_removed"
    assert res["time_base"]["repeated_frames"] == 3


def test_drops_outside_the_fit_window_leave_its_period_alone():
    """3 % of the frames dropped in the first 40 % of a record (noise 2.9
    mrad on 0.1 rad, 1.45 s) whose fit starts after them: the window's
    period is right within its std (|z| 1.24) and now stands.  The old code
    read the phase steps of the whole file and widened the std 7x (z
    0.17: an interval far wider than the window's samples allow) with a
    dropped-frames warning.  The drops inside the window are still put
    back (z -4.5 before, within 1 after)."""
    T, t, y = _record(0, drop_part=(0.0, 0.4))
    fit, res = _check(t, y, t_start=0.42 * t[-1])
    assert res is None, res and res["time_base"]
    assert abs(fit.period - T) <= 2.5 * fit.std
    fit, res = _check(t, y)
    assert res is not None and res["time_base"]["method"] == "recovered"
    assert abs(fit.period - T) > 3 * fit.std and abs(res["fit"].period - T) <= 2.5 * res["fit"].std


def test_hidden_drops_inside_a_window_are_still_refused():
    """Dense drops the noise hides (dropfix's draw 2003, refused on the
    whole record) fitted from 10 s on: the window's samples carry them, so
    the answer is still refused."""
    T, t, y = _draw(2003, drop=0.03)
    with pytest.raises(InputError):
        _check(t, y, t_start=10.0)


def test_repeats_whose_amplitude_strays_widen_when_the_phase_leans_back():
    """Draws 7000 and 7020 of dropfix3's quantised records with 0.3 %
    repeated: their phase walks back with the repeats (advances' skew -1.7,
    -2.5, beyond 2.5 sds of chance) but their amplitude strays too, so the
    phase's chi^2 is only 2.1 and 1.7 x the amplitude's, under the 3 a walk
    needs when it leans neither way: answered 0.2-0.5 % long at z +25.8 and
    +8.4 with no word.  Leaning back, 1.5 x suffices: the std holds the
    walk and the interval reaches the truth (|z| <= 1.96).  Fails on the
    old code (no check)."""
    for seed in (7000, 7020):
        T, t, y = _draw(seed, "drift+quant", rep=0.003)
        fit, res = _check(t, y)
        assert res is not None and res["time_base"]["method"] == "phase_walk", (seed, res and res["time_base"])
        f = res["fit"]
        assert abs(f.period - T) <= 1.96 * f.std, (seed, (f.period - T) / f.std)
        tb = res["time_base"]
        assert 1.5 < tb["phase_chi2"] / max(tb["amplitude_chi2"], 1.0) < 3.0


def test_a_regular_record_does_not_lean_back_by_chance():
    """The relaxed rule rests on the lean being beyond chance: over 200
    clean draws of the sweep (no frame fault, 15-50 cycles) ``leans_back``
    at the true frequency must be rare.  Its bound, 2.5 sds of white
    noise's skew, is passed with probability ~0.6 % if the skew were
    normal (measured: 0 of 300); allowed 4 of 200 (at a rate of 0.6 %,
    P(5 or more) < 1 %)."""
    from bifilar.estimation.signal_phasewander import _window_cycles, leans_back

    n = 0
    for s in range(20000, 20200):
        T, t, y = _draw(s)
        w = _window(T, t)
        n += leans_back(phase_lean(t, y, w), _window_cycles(t, y, w)[5])
    assert n <= 4, n
