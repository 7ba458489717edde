"""Each period model recovers its own synthetic truth within its stated std.

Many noisy synthetic signals per model (viscous, quadratic, two beating
modes, three modes with a weak third one close to the dominant one, a
strong linear drift, coloured AR(1) noise); the headline ``std``
(serial correlation and split-half non-stationarity included) must give a
calibrated two-sided coverage.  Seeds are fixed, so the test is
deterministic; the bands are nevertheless binomial / order-statistic bands
of >= 3 sigma, so a correct std passes for (almost) any seed and a std off
by a factor 1.5 either way fails.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from bifilar.estimation.signal import fit_period

FS = 50.0          # Hz
T_REC = 24.0       # s: 1200 samples, ~20 cycles
N_DRAWS = 30       # per scenario; 6 scenarios -> 180 pooled


def _t():
    return np.arange(0, T_REC, 1 / FS)


def viscous(t, T=1.2, zeta=0.01, A=1.0, phi=0.4, c0=0.3, c1=0.0):
    wd = 2 * np.pi / T
    wn = wd / math.sqrt(1 - zeta ** 2)
    return c0 + c1 * (t - t.mean()) + A * np.exp(-zeta * wn * t) * np.cos(wd * t + phi)


def quadratic(t, T=1.2, k=0.08, A0=1.0, phi=0.4):
    return 0.1 + A0 / (1 + k * A0 * t) * np.cos(2 * np.pi / T * t + phi)


def beats(t, T1=1.2, T2=1.32):
    return (np.exp(-0.01 * t) * np.cos(2 * np.pi / T1 * t + 0.3)
            + 0.6 * np.exp(-0.02 * t) * np.cos(2 * np.pi / T2 * t + 1.1))


def three(t, T1=1.2, T2=2.3, df=2.0 / T_REC):
    """A dominant mode, a slow second one and a weak third oscillation
    ``df`` (two frequency bins) above the dominant one, beating with it."""
    f3 = 1 / T1 + df
    return (np.exp(-0.01 * t) * np.cos(2 * np.pi / T1 * t + 0.3)
            + 0.4 * np.exp(-0.01 * t) * np.cos(2 * np.pi / T2 * t + 1.1)
            + 0.12 * np.exp(-0.02 * t) * np.cos(2 * np.pi * f3 * t + 2.0))


def ar1(rng, n, rho, s):
    e = rng.standard_normal(n) * s
    e[0] /= math.sqrt(1 - rho ** 2)  # stationary start
    return lfilter([1.0], [1.0, -rho], e)


# (name, model fitted, clean signal, true period, noise generator)
SCENARIOS = [
    ("viscous", "viscous", lambda t: viscous(t), 1.2, lambda r, n: 0.05 * r.standard_normal(n)),
    ("quadratic", "quadratic", lambda t: quadratic(t), 1.2, lambda r, n: 0.03 * r.standard_normal(n)),
    ("two-mode beats", "two_mode", lambda t: beats(t), 1.2, lambda r, n: 0.05 * r.standard_normal(n)),
    ("three modes, close third", "three_mode", lambda t: three(t), 1.2,
     lambda r, n: 0.05 * r.standard_normal(n)),
    ("strong drift", "viscous", lambda t: viscous(t, c1=0.2), 1.2, lambda r, n: 0.05 * r.standard_normal(n)),
    ("AR(1) noise", "viscous", lambda t: viscous(t), 1.2, lambda r, n: ar1(r, n, 0.85, 0.03)),
]


@pytest.fixture(scope="module")
def z_scores():
    t = _t()
    rng = np.random.default_rng(20261123)
    out = {}
    for name, model, clean, T, noise in SCENARIOS:
        y0 = clean(t)
        z = []
        for _ in range(N_DRAWS):
            fit = fit_period(t, y0 + noise(rng, t.size), model=model, crossing_check=False)
            z.append((fit.period - T) / fit.std)
        out[name] = np.array(z)
    return out


def test_pooled_two_sided_coverage(z_scores):
    z = np.concatenate(list(z_scores.values()))
    n = z.size  # 180
    # 95 % interval: binomial sd of the covered fraction at p = 0.95 and
    # n = 180 is 1.6 %; 3 sd below is 0.901.  (Above: a too-large std would
    # cover everything; the median test below catches that.)
    assert np.mean(np.abs(z) < 1.96) >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / n)
    # the median of |z| is 0.674 for a calibrated std; its sampling sd is
    # 1 / (2 f(0.674) sqrt(n)) = 0.059 (f = 2 phi(0.674) = 0.636, the density
    # of |z|), so [0.50, 0.85] is a 3-sigma band; a std 1.5x too large gives
    # 0.45, 1.5x too small 1.01
    med = float(np.median(np.abs(z)))
    sd_med = 1 / (2 * 0.636 * math.sqrt(n))
    assert 0.674 - 3 * sd_med < med < 0.674 + 3 * sd_med, med
    # two-sided: no bias, errors on both sides (sign test: 3 sigma of a
    # fair-coin count of 180 is 20)
    assert abs(int(np.sum(z > 0)) - n / 2) < 3 * math.sqrt(n) / 2


@pytest.mark.parametrize("name", [s[0] for s in SCENARIOS])
def test_each_model_covers_its_truth(z_scores, name):
    z = z_scores[name]
    # 30 draws: covered fraction sd 4 %; 0.80 is 3.8 sd below 0.95
    assert np.mean(np.abs(z) < 1.96) >= 0.80, np.round(z, 2)
    # and the std is not grossly inflated: median |z| above 0.674 / 2.5
    assert np.median(np.abs(z)) > 0.27, np.round(z, 2)


def test_auto_picks_the_generating_model():
    t = _t()
    rng = np.random.default_rng(5)
    for clean, want in ((viscous(t), "viscous"), (quadratic(t), "quadratic"), (beats(t), "two_mode")):
        picks = []
        for _ in range(4):
            fit = fit_period(t, clean + 0.02 * rng.standard_normal(t.size), model="auto",
                             crossing_check=False, split_check=False)
            picks.append(fit.model)
            assert fit.choice_reason and fit.selection["ranking"][0].startswith(fit.model)
            # every model offered was fitted on the same samples
            cands = fit.selection["candidates"]
            assert {"viscous", "quadratic", "quadratic+viscous", "two_mode"} <= set(cands)
            assert all(c["rss"] > 0 for c in cands.values())
        # BIC takes a nested model with one more parameter by chance when its
        # chi^2_1 gain exceeds ln n = 7.1 (p ~ 1 %; a boundary parameter as k
        # half that): 3 of 4 leaves room for one such draw
        assert picks.count(want) >= 3, picks


def test_auto_fits_a_close_third_oscillation_instead_of_calling_it_drift():
    """A weak oscillation two frequency bins from the dominant mode beats
    with it: auto picks three_mode (its BIC gain is hundreds here), whose
    std stays at its noise and correlation terms, while the two-mode fit
    of the same record leaves the beat in its residuals (correlated, halves
    disagreeing) and states a std several times larger."""
    t = _t()
    rng = np.random.default_rng(11)
    for _ in range(2):
        y = three(t) + 0.05 * rng.standard_normal(t.size)
        fit = fit_period(t, y, model="auto", crossing_check=False)
        assert fit.model == "three_mode", fit.choice_reason
        assert fit.selection["candidates"]["two_mode"]["bic"] - fit.bic > 50
        # the third oscillation found where it was put (two bins above f1)
        f3 = sorted(m["frequency"] for m in fit.modes)[-1]
        assert abs(f3 - (1 / 1.2 + 2.0 / T_REC)) < 0.5 / T_REC, fit.modes
        assert fit.std_nonstationary == 0.0
        assert abs(fit.period - 1.2) < 3 * fit.std
        two = fit_period(t, y, model="two_mode", crossing_check=False)
        assert two.std > 3 * fit.std, (two.std, fit.std)


def test_drift_along_the_record_inflates_the_std():
    """A period that changes by 1 % along the record (a chirped sinusoid):
    the halves disagree and the headline std covers the spread."""
    t = _t()
    rng = np.random.default_rng(8)
    T0, frac = 1.2, 0.01
    # instantaneous frequency f(t) = f0 (1 - frac t / T_REC)
    f0 = 1 / T0
    phase = 2 * np.pi * f0 * (t - frac * t ** 2 / (2 * T_REC))
    y = np.cos(phase) + 0.02 * rng.standard_normal(t.size)
    fit = fit_period(t, y, model="viscous", crossing_check=False)
    assert fit.std_nonstationary > 0 and fit.uncertainty["dominant"] == "nonstationarity"
    # the local period goes from T0 to T0 / (1 - frac): spread ~ T0 frac; the
    # halves' means differ by T0 frac / 2, tau = that / sqrt(2) = 0.35 T0 frac
    assert 0.2 * T0 * frac < fit.std < 0.6 * T0 * frac
