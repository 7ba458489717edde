"""The period std on the real recordings of ../shared/data (skipped when the
folder is absent): the KTH trifilar 5 s / 10 s / 20 s series and the
compound-pendulum gyro trial.  See docs/real_data.md for the full tables."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from bifilar.estimation.signal import fit_period, read_signal

from conftest import SHARED

KTH = SHARED / "data" / "trifilar-kth-2014"
GYRO = SHARED / "data" / "compound-gyro-bicycleparameters" / "BrowserInsForkCompoundFirst1.mat"
RADII = (0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75)
SERIES = ("5s", "10s", "20s")
#: issue 11: the std must be below these fractions of the period
LIMITS = {"5s": 0.002, "10s": 0.001, "20s": 0.0002}
#: the halves disagree beyond noise above this Cochran Q (chi^2_1, 99 %)
Q99 = stats.chi2.ppf(0.99, 1)


def _load(series, r):
    return read_signal(KTH / series / f"{r:.2f}.csv", column="x", sample_rate=240)[:2]


@pytest.fixture(scope="module")
def kth():
    if not KTH.exists():
        pytest.skip(f"real data not found at {KTH}")
    out = {}
    for s in SERIES:
        for r in RADII:
            t, y = _load(s, r)
            # auto picks two_mode or three_mode on these files (the single-mode
            # models lose by thousands in BIC, checked on a sample below);
            # comparing only those two keeps the test at seconds
            fit = fit_period(t, y, model="auto", candidates=("two_mode", "three_mode"),
                             crossing_check=False)
            amp = float(np.sqrt(np.mean(fit.envelope(fit.t_used) ** 2)))
            out[s, r] = (fit, amp)
    return out


@pytest.mark.parametrize("series,r", [("10s", 0.30)])
def test_auto_chooses_two_modes_on_the_laser_dot(series, r):
    if not KTH.exists():
        pytest.skip(f"real data not found at {KTH}")
    t, y = _load(series, r)
    fit = fit_period(t, y, model="auto", crossing_check=False, split_check=False)
    # the ~2 s swing mode leaks into x: one mode leaves it in the residuals
    assert fit.model == "two_mode", fit.choice_reason
    assert 1.8 < fit.modes[1]["period"] < 2.2
    assert fit.selection["candidates"]["viscous"]["bic"] - fit.bic > 1000
    assert "lowest BIC" in fit.choice_reason


def test_std_below_the_limits_unless_the_record_shows_a_drift(kth):
    """Every std is below its limit (0.2 %, 0.1 %, 0.02 % of T for 5, 10,
    20 s), or the excess is the record's own split-half disagreement: the
    halves differ beyond noise and that term dominates the std."""
    within = 0
    for (s, r), (fit, _) in kth.items():
        if fit.std / fit.period < LIMITS[s]:
            within += 1
            continue
        (T1, s1), (T2, s2) = fit.half_periods
        assert (T1 - T2) ** 2 / (s1 ** 2 + s2 ** 2) > Q99, (s, r)
        assert fit.uncertainty["dominant"] == "nonstationarity", (s, r)
        # tau ~ |T1 - T2| / sqrt(2): the std reflects the spread, no more
        assert fit.std < 1.5 * abs(T1 - T2), (s, r)
    # most recordings meet the limits (docs/real_data.md: 31 of 33 since
    # three_mode models the beat in the 20 s files; 28 with two_mode alone)
    assert within >= 29


def test_period_increases_with_radius(kth):
    """I = I_platform + m r^2 grows with the test mass's radius r, so the
    torsion period must increase monotonically along each series; every fit
    explains over 99 % of the variance and carries the ~2 s swing the laser
    dot also sees among its other modes.  (Moved from test_signal.py, which
    fitted all 33 records a second time; the files hold only the x, y
    pixels, x read by default.)"""
    meta = read_signal(KTH / "10s" / "0.50.csv", sample_rate=240)[2]
    assert meta["columns"] == ["x", "y"] and meta["column"] == "x"
    for s in SERIES:
        periods = [kth[s, r][0].period for r in RADII]
        assert np.all(np.diff(periods) > 0), (s, np.round(periods, 5))
        for r in RADII:
            fit = kth[s, r][0]
            assert fit.r_squared > 0.99, (s, r)
            assert any(1.8 < m["period"] < 2.2 for m in fit.modes[1:]), (s, r)


def test_series_differences_follow_the_amplitude(kth):
    """The 10 s and 20 s periods of a position differ (beyond their stds at
    some positions) because the recordings have different amplitudes: a
    finite-amplitude pendulum's period grows as T^2 = T0^2 + c A^2.  The
    differences regress on (A10^2 - A20^2) / 2T with c > 0 at > 3 sigma,
    and removing that term leaves differences consistent with the stds
    (chi^2/dof below the 99 % point for 10 dof, 2.32)."""
    d, x, sd = [], [], []
    for r in RADII:
        (fa, aa), (fb, ab) = kth["10s", r], kth["20s", r]
        d.append(fa.period - fb.period)
        x.append((aa ** 2 - ab ** 2) / (2 * fa.period))
        sd.append(math.hypot(fa.std, fb.std))
    d, x, sd = map(np.asarray, (d, x, sd))
    w = 1 / sd ** 2
    c = float(np.sum(w * x * d) / np.sum(w * x * x))
    sc = float(1 / math.sqrt(np.sum(w * x * x)))
    chi2 = float(np.sum(w * (d - c * x) ** 2)) / (d.size - 1)
    assert c > 3 * sc, (c, sc)
    assert chi2 < stats.chi2.ppf(0.99, d.size - 1) / (d.size - 1), chi2
    # the same c (s^2/px^2) as the pooled T^2 fit of docs/real_data.md
    # (1.2e-7 +- 3e-8): within a factor 2
    assert 0.5 * 1.2e-7 < c < 2 * 1.2e-7, c


def test_gyro_std_reflects_its_split_half_drift():
    """The compound-pendulum gyro trial (BicycleParameters fork), read once
    as ``bifilar period REC --json`` reads it: the checks of three tests that
    each fitted this 30 000-sample record (~5 s a fit; session 15 merged
    them here: test_signal's read and fit, test_invert_cli's CLI contract,
    this file's split-half drift)."""
    import json

    from click.testing import CliRunner

    from bifilar.cli import main

    if not GYRO.exists():
        pytest.skip(f"real data not found at {GYRO}")
    r = CliRunner().invoke(main, ["period", str(GYRO), "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    # the read: the .mat's one variable and its sampling rate
    sig = d["signal"]
    assert sig["column"] == "data" and sig["sample_rate"] == 1000.0 and sig["n_samples"] == 30000
    assert sig["sample_rate_source"] == "variable 'ActualRate'"
    # the fit, against the crossing count of the same record (an independent method): 1e-3 relative (they
    # differ by 3e-4 because the period shortens as the amplitude decays and the two weight the record
    # differently); r^2 and a light damping
    assert d["r_squared"] > 0.99 and 1.55 < d["period"] < 1.63 and 0 < d["damping_ratio"] < 0.05
    assert abs(d["period"] - d["crossing_period"]) / d["period"] < 1e-3
    (T1, s1), (T2, s2) = d["half_periods"]
    # the halves differ by ~3 ms, at tens of their stds, and the notes say so
    assert 2e-3 < T1 - T2 < 4e-3 and (T1 - T2) > 10 * math.hypot(s1, s2)
    assert any("period changes" in n for n in d["notes"])
    # the headline std carries it (not the 7e-5 s of noise and correlation)
    assert d["uncertainty"]["dominant"] == "nonstationarity"
    assert 0.5 * (T1 - T2) < d["std"] < (T1 - T2)
    # its drift is no amplitude law (session 9): the law's shift over the
    # envelope is not resolved, the viscous fit and its split term stay
    assert d["amplitude_law"] is not None and d["amplitude_law"]["used"] is False
    # a growing "second mode" is no reason to prefer two modes
    assert d["model"] == "viscous"
    assert not d["selection"]["candidates"]["two_mode"]["admissible"]
