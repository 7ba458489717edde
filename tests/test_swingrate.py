"""A found swing's own decay rate, read off its tone's envelope
(docs/design.md, "swingrate, session 17").

Session 16 took a damped record's swing to decay at the torsion's rate with
a relative std of 1.0 on that rate (``DECAY_SHARE``): wide enough for a
swing decaying 3x slower, at a 1.5-1.6x wider Izz std on every such
record.  Now a multi-mode fit's tone gives the swing's rate.  Cheap
stand-ins (no simulation): synthetic records whose tone decays as a pitch x
swing tone does, fitted ``two_mode``, and ``infer_secondary`` with the
model's tone runs replaced by a quadratic tone law (tests/test_dampdecay.py's
stand-in problem)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation import signal_swing
from bifilar.estimation.signal import fit_period
from bifilar.estimation.signal_swing import infer_secondary, swing_decay
from bifilar.estimation.signal_swing_rate import _combination, tone_swing_rate

from test_dampdecay import A0, EPS, RATIO, SIGMA, T0, T1, _problem, _tone_law

# the quadcopter's linear modes (tests/test_signal_swing.py's body): swing-y, torsion, pitch, swing-x (s)
T_SWING, T_PITCH, T_SWINGX = 2.1975, 1.1848, 2.2359


def _modes():
    return SimpleNamespace(modes=[SimpleNamespace(label="torsion", period=T0, dominant=5),
                                  SimpleNamespace(label="swing-y", period=T_SWING, dominant=1),
                                  SimpleNamespace(label="pitch", period=T_PITCH, dominant=4)])


def _record(sigma_s: float, swing: float, tone: float, seed: int | None):
    """(t, y): 30 torsion cycles at 60 fps decaying at SIGMA (Q 100) whose
    frequency is lowered by ``swing * EPS * exp(-2 sigma_s t)`` (a swing
    decaying at ``sigma_s``, its shift ~ a^2), with the pitch x swing tone
    at T1 (``f_pitch - f_swing``) of ``tone`` times the torsion at the start,
    decaying at SIGMA + sigma_s (the pitch, a rotation, as the torsion), and
    0.1 % camera noise where ``seed``."""
    t = np.arange(0.0, 30 * T0, 1 / 60.0)
    w0 = 2 * math.pi / T0
    lost = -np.expm1(-2 * sigma_s * t) / (2 * sigma_s)
    y = A0 * np.exp(-SIGMA * t) * np.cos(w0 * t - w0 * EPS * swing * lost) \
        + tone * A0 * np.exp(-(SIGMA + sigma_s) * t) * np.cos(2 * math.pi * t / T1 + 0.7)
    if seed is not None:
        y = y + 1e-3 * A0 * np.random.default_rng(seed).standard_normal(t.size)
    return t, y


def test_a_tone_is_read_as_the_combination_its_frequency_makes():
    """The quadcopter's two tones (docs/design.md, dampdecay): 2.57 s is
    ``f_pitch - f_swing`` (the swing's power 1), 2.40 s ``2 f_swing -
    f_torsion`` (2); a tone at neither within 2 % is not read."""
    f_t, f_s, others = 1 / T0, 1 / T_SWING, [1 / T_PITCH, 1 / T_SWINGX]
    assert _combination(1 / 2.5750, f_t, f_s, others) == 1
    assert _combination(1 / 2.3973, f_t, f_s, others) == 2
    assert _combination(1 / 3.3, f_t, f_s, others) is None


@pytest.mark.parametrize("lam", [1 / 3, 3.0])
def test_a_swing_decaying_at_its_own_rate_is_run_at_its_amplitude_over_the_record(lam, monkeypatch):
    """A swing decaying at 1/3 (3x) the torsion's rate: its tone's rate
    gives it within its std, and the swing is run at the share of its start
    amplitude the record's period averages, measured independently (the
    viscous fits' frequency with the swing less without it, noise-free, as
    tests/test_dampdecay.py measures it).  The old code took the torsion's
    rate: g 0.690 against the truth's 0.876 at 1/3 (21 % off, outside the
    tolerance below) and 0.403 at 3x (71 % off), and had no rate."""
    sigma_s = lam * SIGMA
    w = [2 * math.pi / fit_period(*_record(sigma_s, s, 0.0, None)[:2], "viscous", crossing_check=False,
                                  split_check=False).period for s in (1.0, 0.0)]
    g_true = math.sqrt((w[1] - w[0]) / (2 * math.pi / T0 * EPS))
    monkeypatch.setattr(signal_swing, "_run_tones", _tone_law)
    t, y = _record(sigma_s, 0.0, RATIO, seed=17)
    fit = fit_period(t, y, "two_mode", crossing_check=False, split_check=False)
    decay = fit.amplitude_period / float(np.abs(fit.envelope(np.array([fit.t0])))[0])
    pb = _problem(fit, decay)
    pb.models[0].modes0 = _modes()
    sec = infer_secondary(pb, 0, np.zeros(1))
    assert sec is not None and sec.label == "swing-y"
    # the share the period refers to: the rate's own error here is its fit's (the record is made as the rule reads
    # it), a few % of sigma_s, which moves g by ~1 %; 10 % tells it from the old rule's g (21 % and 71 % off)
    assert sec.decay == pytest.approx(g_true, rel=0.1)
    _, old_rel = swing_decay(pb.measurements[0])
    assert sec.amplitude_std / sec.amplitude < old_rel  # narrower than the stated share gave (0.33 of g alone)
    rate, rate_std = sec.decay_rate
    assert abs(rate - sigma_s) < 2 * rate_std  # the measured rate within 2 of its std of the truth


def test_a_residual_tones_rate_is_read_beside_the_fits_mismatch():
    """A single-mode (viscous) fit of a chirping record (the swing's shift
    decaying, 3x the quadcopter's) leaves the tone in its residuals: its
    rate, refitted beside the fit's mismatch, gives the swing's (1/3 of the
    torsion's) within 2 of its std (measured 1.1), where the tone's own
    damped cosine fit on the residuals reads it 4.5 of its std off (its
    envelope takes part of the mismatch: -0.70 +- 0.23 of the torsion's
    rate for 0.33)."""
    sigma_s = SIGMA / 3
    t, y = _record(sigma_s, 3.0, RATIO, seed=19)
    fit = fit_period(t, y, "viscous", crossing_check=False, split_check=False)
    m = SimpleNamespace(fit=fit, details={"quantity": "angle"})
    tone = signal_swing.record_tones(m)[0]
    assert tone["source"] == "residual" and tone["period"] == pytest.approx(T1, rel=5e-3)  # the chirp pulls it 0.3 %
    assert abs(tone["sigma"] - fit.modes[0]["sigma"] - sigma_s) > 2 * tone["sigma_std"]  # the test tells them apart
    rate, std = tone_swing_rate(m, tone, SimpleNamespace(modes0=_modes()), 1, 0)
    assert abs(rate - sigma_s) < 2 * std
    assert std < 0.5 * sigma_s  # it says something: the old rule's std on it was 1.0 of the torsion's, 3 sigma_s
