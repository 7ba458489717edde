"""Tests written to kill surviving mutants of the alias check of recordings
(``bifilar/estimation/signal_alias.py``; see docs/mutation.md).

The check is called here on a problem reduced to what it reads (the
measurement's fitted period and sample rate, the hanging's predicted
periods), so that the frequencies can be chosen by hand.  The truths: the
documented rule (module docstring, docs/invert.md) worked out by hand on
each case -- the distances are written in the comments -- and dimensional
analysis: the rule is stated in relative distances and a ratio of
frequencies, so the decision must not change when every frequency and the
sample rate are multiplied by the same factor (seconds -> deciseconds).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from bifilar.errors import InputError
from bifilar.estimation.signal_alias import check_signal_aliases

#: three predicted modes (Hz): the measured one M, a faster F and a very slow S
MODES = (("M", 0.5), ("F", 0.9), ("S", 0.04))


def _problem(f_fit, fs, *, scale=1.0, f_natural=None, modes=MODES):
    """A problem holding one recording of mode 'M' whose fit shows ``f_fit``
    Hz (damped; ``f_natural`` Hz after the damping correction, default the
    same) sampled at ``fs`` Hz, every frequency multiplied by ``scale``."""
    model = SimpleNamespace(modes0=SimpleNamespace(
        modes=[SimpleNamespace(label=lab, period=1.0 / (scale * f)) for lab, f in modes]))
    m = SimpleNamespace(source="signal", details={"signal": {"sample_rate": scale * fs}},
                        observed_period=1.0 / (scale * f_fit),
                        period=1.0 / (scale * (f_natural if f_natural is not None else f_fit)),
                        hanging=0, field="--signal", label="M")
    return SimpleNamespace(measurements=[m], models=[model], mode_index=[0])


def _outcome(pb):
    """'refused' (with the message), or the number of warnings."""
    try:
        return len(check_signal_aliases(pb)), ""
    except InputError as e:
        assert e.field == "--signal"
        return "refused", e.message


# (f_fit, fs, expected outcome), the distances relative to each mode's predicted frequency worked by hand:
CASES = {
    # M recorded at 0.8 Hz (1.6 samples per cycle), running 5 % fast (0.525 Hz): the samples show
    # 0.8 - 0.525 = 0.275 Hz.  Direct: M |0.275 - 0.5| / 0.5 = 0.45, F 0.69, S 5.9.  Aliases (k >= 1):
    # M at |0.5 - 0.8| = 0.3 Hz, |0.275 - 0.3| / 0.5 = 0.05; F at 0.1 Hz, 0.175 / 0.9 = 0.19: only by alias.
    "alias": (0.275, 0.8, "refused"),
    # M 10 % fast (0.55 Hz) at 1.2 Hz, 2.2 samples per cycle.  Direct: M 0.05 / 0.5 = 0.1, F 0.35 / 0.9
    # = 0.39, S 12.75.  Aliases: F only (k = 1, at 0.3 Hz): 0.25 / 0.9 = 0.28 > 0.1: warned, not refused.
    "near_nyquist": (0.55, 1.2, 1),
    # the fitted 0.52 Hz is faster than predicted and decides: 1.27 Hz is 2.54 x the prediction but
    # 2.44 x the fit (below 2.5).  Direct M 0.04; alias F (k = 1, 0.37 Hz) 0.15 / 0.9 = 0.17: warned.
    "fit_faster": (0.52, 1.27, 1),
    # 1.3 Hz is 2.6 samples per cycle of M at 0.5 Hz (fitted 0.45 Hz): resolved, nothing said although
    # F's alias 1.3 - 0.9 = 0.4 Hz lies nearer (0.05 / 0.9 = 0.056) than M (0.1): a coincidence.
    "resolved": (0.45, 1.3, 0),
}


@pytest.mark.parametrize("scale", [0.1, 1.0, 10.0])
@pytest.mark.parametrize("case", sorted(CASES))
def test_alias_decisions_are_the_documented_rule_in_any_unit_of_time(case, scale):
    """Each case's decision worked out by hand (CASES), the same with every
    frequency x 0.1 and x 10 (periods from 0.1 s to 250 s): the rule has no
    scale of its own.  The refusal names the alias |f - k fs| of M."""
    f_fit, fs, expected = CASES[case]
    got, msg = _outcome(_problem(f_fit, fs, scale=scale))
    assert got == expected, (case, scale, msg)
    if expected == "refused":
        assert "alias of mode 'M'" in msg and f"= {0.3 * scale:.4g} Hz" in msg, msg
        assert f"nearest: 'M' at {0.5 * scale:.4g} Hz" in msg, msg


def test_the_nearest_mode_is_nearest_relative_to_its_own_frequency():
    """'near_nyquist' (warned) again, read through the message: the nearest
    mode is M (relative distance 0.1), not the fastest F (0.39) nor the slow
    S, which is the nearest in |df| x f (0.51 x 0.04 = 0.02 < 0.05 x 0.5).
    Had the check taken either, the distance 0.39 or 12.75 exceeds F's
    alias's 0.28 and the recording would have been refused."""
    got, msg = _outcome(_problem(0.55, 1.2))
    assert got == 1, msg
    # the same fit with S absent and F absent: still one warning (nothing else decides)
    for keep in (("M", "F"), ("M", "S")):
        modes = tuple(x for x in MODES if x[0] in keep)
        assert _outcome(_problem(0.55, 1.2, modes=modes))[0] == 1


def test_the_check_reads_the_damped_frequency_the_samples_show():
    """A heavily damped recording (zeta = 0.2): the samples oscillate at the
    damped frequency, the fit's observed period (0.5 Hz here), not at the
    natural frequency of its damping-corrected period (0.5 / sqrt(1 - 0.04)
    = 0.510 Hz).  At 1.26 Hz, 2.52 samples per damped cycle of a mode also
    predicted at 0.5 Hz: resolved, nothing to say (by the natural frequency
    it would be 2.47, below 2.5, and warned); at 1.2 Hz the warning quotes
    the damped frequency as the fitted one."""
    f_nat = 0.5 / math.sqrt(1 - 0.2 ** 2)
    modes = (("M", 0.5), ("S", 0.04))
    assert _outcome(_problem(0.5, 1.26, f_natural=f_nat, modes=modes))[0] == 0
    w = check_signal_aliases(_problem(0.5, 1.2, f_natural=f_nat, modes=modes))
    assert len(w) == 1 and "0.5 Hz fitted" in w[0] and f"only {1.2 / 0.5:.2f} x" in w[0], w
