"""Tests written to kill surviving mutants of the period from the
experimenter's words (``bifilar/estimation/period_specs.py``; see
docs/mutation.md).  Truths: the documented spellings and their values
worked by hand (``0.5ms`` is 5e-4 s, ``1e-3`` is relative), and a
synthetic damped recording ``A0 exp(-zeta wn t) cos(wd t + phi)`` whose
natural and damped periods, envelope and number of cycles are known in
closed form -- never output of the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.errors import InputError
from bifilar.estimation import period_specs as ps


@pytest.mark.parametrize("text,value", [
    ("0.1%", 1e-3 * 2.5), ("0.1 %", 1e-3 * 2.5), ("1e-3", 1e-3 * 2.5), ("0.002", 0.002 * 2.5),
    ("0.5ms", 5e-4), ("0.5 MS", 5e-4), ("0.0005s", 5e-4), ("2e-3 s", 2e-3)])
def test_target_spellings_are_the_documented_values(text, value):
    """``--target`` for a 2.5 s period: a percentage and a bare number are
    relative to the period, ``ms`` and ``s`` absolute."""
    assert ps.parse_target(text, 2.5) == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("text", ["0%", "-1ms", "0", "nan", "inf s", "fast"])
def test_target_must_be_a_positive_number(text):
    with pytest.raises(InputError) as e:
        ps.parse_target(text, 2.5)
    assert e.value.field == "--target"


# ---------------------------------------------------------------------------
# a recorded signal: the damping correction, the amplitude, the cycles
# ---------------------------------------------------------------------------

TN, ZETA, A0, FS, DUR = 1.5, 0.02, 0.08, 50.0, 40.0
WN = 2 * math.pi / TN
WD = WN * math.sqrt(1 - ZETA ** 2)


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    t = np.arange(0.0, DUR, 1 / FS)
    y = A0 * np.exp(-ZETA * WN * t) * np.cos(WD * t + 0.4) + 2e-4 * np.random.default_rng(3).standard_normal(t.size)
    path = tmp_path_factory.mktemp("rec") / "rec.csv"
    np.savetxt(path, np.c_[t, y], delimiter=",", header="t,angle", comments="")
    return path


def _true_effective_amplitude(t_used):
    """The amplitude the fitted period refers to, from the true envelope
    over the samples used: squared amplitudes weighted as the phase's
    least-squares slope weighs them (weights A^2 times the lever arm from
    their weighted mean time; tests/test_end_to_end_audit.py checks the
    rule against a chirp's own law)."""
    t = np.asarray(t_used)
    env = A0 * np.exp(-ZETA * WN * t)
    w = env ** 2
    tc = t - np.sum(w * t) / np.sum(w)
    K = np.cumsum((w * tc)[::-1])[::-1]
    return math.sqrt(np.sum(K * w) / np.sum(K))


def test_a_damped_recordings_period_is_the_natural_one_and_its_observed_the_damped_one(record):
    """``period``: the natural period 2 pi / wn (the damping correction
    ``Td sqrt(1 - zeta^2)``), within 3 of its std; ``observed_period`` the
    damped 2 pi / wd; the damping ratio; ``cycles`` the fit window in damped
    periods."""
    r = ps.period_from_signal(record, quantity="other")
    assert abs(r["period"] - TN) < 3 * r["std"], (r["period"], r["std"])
    assert r["observed_period"] == pytest.approx(2 * math.pi / WD, rel=1e-4)
    assert r["damping_ratio"] == pytest.approx(ZETA, rel=0.02)
    assert r["amplitude"] is None  # "other": no amplitude in a unit of the mode
    r = ps.period_from_signal(record, quantity="other", t_start=5.0, t_stop=35.0)
    f = r["fit"]
    assert f.t0 >= 5.0 and f.t1 <= 35.0
    assert r["cycles"] == pytest.approx((f.t1 - f.t0) * WD / (2 * math.pi), rel=1e-4)  # ~20 cycles in 30 s


def test_the_amplitude_is_the_one_the_period_refers_to_in_the_modes_unit(record):
    """``angle``: the envelope as the fitted period weighs it over the fit
    window (:func:`signal_result.period_amplitude`), times ``scale``; ``rate``: an angular
    rate's envelope divided by the angular frequency (the angle's
    amplitude).  The envelope here is the true one, A0 exp(-zeta wn t)."""
    r = ps.period_from_signal(record, quantity="angle")
    a = _true_effective_amplitude(r["fit"].t_used)
    assert r["amplitude"] == pytest.approx(a, rel=5e-3)
    assert ps.period_from_signal(record, quantity="angle", scale=2.5)["amplitude"] == pytest.approx(2.5 * a, rel=5e-3)
    assert ps.period_from_signal(record, quantity="rate")["amplitude"] == pytest.approx(a / WD, rel=5e-3)


def test_the_trial_std_source_names_one_trial_or_the_scatter_below_the_floor():
    """Two trials agreeing to 0.01 s (scatter 0.00707 s, below the 0.1 s
    floor): the floor, with their scatter named; one trial: the floor, "one
    trial"; three scattering by 0.4 s: the scatter (Type A)."""
    _, _, d = ps.period_from_trials(10, [15.20, 15.21])
    assert d["trial_std"] == 0.1 and "scatter 0.00707 s is below it" in d["trial_std_source"], d
    assert d["dof"] == 1
    _, _, d = ps.period_from_trials(10, [15.20])
    assert d["trial_std"] == 0.1 and "(one trial)" in d["trial_std_source"] and d["dof"] is None, d
    _, _, d = ps.period_from_trials(10, [15.0, 15.4, 15.8])
    assert d["trial_std"] == pytest.approx(0.4) and d["trial_std_source"] == "scatter of the 3 trials (Type A)"


def test_sample_intervals_under_a_nanosecond_and_spans_over_three_years_are_refused():
    """The documented limits: samples less than 1 / MAX_SAMPLE_RATE = 1 ns
    apart (is the time in seconds?) are refused, 1.5 ns apart is not the
    scale check's business; likewise a span over 1e8 s."""
    assert ps.MAX_SAMPLE_RATE == 1e9
    y = np.cos(np.arange(50) / 3)
    ps.check_signal_scale(1.5e-9 * np.arange(50), y)
    with pytest.raises(InputError, match="apart"):
        ps.check_signal_scale(0.5e-9 * np.arange(50), y)
    # a recording spanning more than MAX_DURATION = 1e8 s (three years) is refused too
    assert ps.MAX_DURATION == 1e8
    ps.check_signal_scale(0.9e8 / 49 * np.arange(50), y)
    with pytest.raises(InputError, match="spans"):
        ps.check_signal_scale(2e8 / 49 * np.arange(50), y)
