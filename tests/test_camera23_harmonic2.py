"""A further mode's 2nd harmonic beside the torsion (signal_harmonic2.py).

KTH-like laser-dot records (tests/test_readers20._camera_like, the duration
fixed at 10 s): the swing (1.97-2.0 s) leaks into the torsion's
record with its 2nd harmonic at ~1.0 Hz, unresolved from the torsion's
~0.95 Hz over 10 s.  Without the std term the period's 95 % interval
covered 72 of 100 such records (camera23); these two draws (seeds 15 and
46 of that run) are the ones the term was built for: the period is off by
7.6 and 4.9 of the old stds.  The generated period is the truth.
"""

from __future__ import annotations

import math

import pytest

from bifilar.estimation.signal import fit_period

from test_readers20 import _camera_like


@pytest.mark.parametrize("seed", [15, 46])
def test_interval_covers_with_the_second_harmonic_term(seed):
    t, x, T = _camera_like(seed, dur=10.0)
    fit = fit_period(t, x, "auto")
    term = fit.uncertainty["second_harmonic"]
    without = math.sqrt(fit.std ** 2 - term ** 2)
    # the premise: without the term the period is off by more than 4 stds
    assert abs(fit.period - T) > 4 * without, (fit.period - T, without)
    # with it, within the 95 % interval
    assert abs(fit.period - T) <= 1.96 * fit.std, (fit.period - T, fit.std)
    # and not by widening without measure: the term estimates the bias, which on these draws is the error
    # (the other terms ~1e-4 s): measured 0.79x and 1.35x |error|; a term 3x the error would cover anything
    assert term <= 3.0 * abs(fit.period - T), (term, fit.period - T)
    assert any("2nd harmonic" in n for n in fit.notes)
