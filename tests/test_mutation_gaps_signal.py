"""Tests written to kill surviving mutants of the period fit of recordings
(``bifilar/estimation/signal_models.py``, ``signal_checks.py``; see
docs/mutation.md).  Every expected value comes from an independent truth:
a closed form, a direct (slow) computation of the same definition, a finite
difference, or a synthetic signal with known parameters and noise -- never
from output of the code under test.
"""

import decimal
import math

import numpy as np
import pytest

from bifilar.estimation import signal_checks as sc
from bifilar.estimation import signal_models as sm


# ---------------------------------------------------------------------------
# signal_models: closed forms and derivatives
# ---------------------------------------------------------------------------

def _E_exact(sg, tau):
    """E = (1 - exp(-sg tau)) / sg and dE/dsg = (sg tau exp(-sg tau) - (1 - exp(-sg tau))) / sg^2
    in 50-digit decimal arithmetic (the cancellations of both closed forms are exact at that precision)."""
    with decimal.localcontext() as ctx:
        ctx.prec = 50
        s, t = decimal.Decimal(float(sg)), decimal.Decimal(float(tau))
        ex = (-s * t).exp()
        E = (1 - ex) / s
        dE = (s * t * ex - (1 - ex)) / (s * s)
        return float(E), float(dE)


@pytest.mark.parametrize("sg", [3e-7, 2e-5, 0.05, 0.7])
def test_E_and_its_derivative_match_high_precision_both_branches(sg):
    # tau up to 100 s: sg tau spans the series branch (< 1e-4) and the
    # closed form; both must give E and dE/dsg to near machine precision
    tau = np.array([1e-3, 0.1, 1.0, 4.0, 30.0, 100.0])
    E, dE = sm._E(sg, tau)
    for k, tk in enumerate(tau):
        Ee, dEe = _E_exact(sg, tk)
        assert E[k] == pytest.approx(Ee, rel=1e-11)
        assert dE[k] == pytest.approx(dEe, rel=1e-11)


def _central_jacobian(f, p, floor):
    """Central differences of ``f(p)`` (an array) in each parameter, step
    ``1e-6 max(|p_j|, floor)``."""
    cols = []
    for j in range(p.size):
        h = 1e-6 * max(abs(p[j]), floor)
        pp, pm = p.copy(), p.copy()
        pp[j] += h
        pm[j] -= h
        cols.append((f(pp) - f(pm)) / (2 * h))
    return np.column_stack(cols)


def _fd_jacobian(kind, p, t, t0, tm):
    return _central_jacobian(lambda q: sm._model(kind, q, t, t0, tm), p, 1e-3)


@pytest.mark.parametrize("kind,p", [
    ("viscous", [0.3, -0.02, 1.1, -0.4, 4.2, 0.03]),
    ("quadratic", [0.3, -0.02, 1.1, -0.4, 4.2, 0.08, 0.03]),
    ("two_mode", [0.3, -0.02, 1.1, -0.4, 4.2, 0.03, 0.2, 0.1, 6.0, 0.05]),
    ("three_mode", [0.3, -0.02, 1.1, -0.4, 4.2, 0.03, 0.2, 0.1, 6.0, 0.05, 0.05, -0.07, 4.6, 0.01]),
])
def test_model_value_and_jacobian(kind, p):
    """The model is the documented formula (written out here) and its
    Jacobian is its derivative (central differences)."""
    p = np.array(p, float)
    t = np.linspace(2.0, 22.0, 400)
    t0, tm = 2.0, 12.0
    y, J = sm._model(kind, p, t, t0, tm, want_jac=True)
    tau, s = t - t0, t - tm
    want = p[0] + p[1] * s
    if kind == "quadratic":
        a, b, w, kap, sg = p[2:7]
        E = -np.expm1(-sg * tau) / sg
        want = want + np.exp(-sg * tau) / (1 + kap * E) * (a * np.cos(w * tau) + b * np.sin(w * tau))
    else:
        for c in range(2, p.size, 4):
            a, b, w, sg = p[c:c + 4]
            want = want + np.exp(-sg * tau) * (a * np.cos(w * tau) + b * np.sin(w * tau))
    assert np.allclose(y, want, rtol=1e-12, atol=1e-12)
    assert np.allclose(J, _fd_jacobian(kind, p, t, t0, tm), rtol=1e-6, atol=1e-7)
    # the plain call returns the same values
    assert np.allclose(sm._model(kind, p, t, t0, tm), y, rtol=0, atol=1e-14)


def test_envelope_is_the_amplitude_of_the_first_oscillation():
    t = np.linspace(1.0, 11.0, 50)
    tau = t - 1.0
    pv = np.array([0.0, 0.0, 3.0, 4.0, 5.0, 0.1])
    assert np.allclose(sm._envelope("viscous", pv, t, 1.0), 5.0 * np.exp(-0.1 * tau), rtol=1e-13)
    p2 = np.r_[pv, 1.0, 1.0, 7.0, 0.5]
    assert np.allclose(sm._envelope("two_mode", p2, t, 1.0), 5.0 * np.exp(-0.1 * tau), rtol=1e-13)
    pq = np.array([0.0, 0.0, 3.0, 4.0, 5.0, 0.2, 0.1])
    E = (1 - np.exp(-0.1 * tau)) / 0.1
    assert np.allclose(sm._envelope("quadratic", pq, t, 1.0), 5.0 * np.exp(-0.1 * tau) / (1 + 0.2 * E),
                       rtol=1e-12)


@pytest.mark.parametrize("kap", [0.0, 0.3])
def test_linear_amplitudes_is_the_least_squares_solution(kap):
    rng = np.random.default_rng(1)
    t = np.linspace(0.5, 20.5, 700)
    t0, tm = 0.5, 10.5
    ws, ss = [3.0, 4.4], [0.05, 0.02]
    y = rng.normal(0, 1, t.size) + 2 * np.cos(3.0 * t)
    tau = t - t0
    cols = [np.ones_like(t), t - tm]
    for w, sg in zip(ws, ss):
        g = np.exp(-sg * tau)
        if kap:
            g = g / (1 + kap * (1 - np.exp(-sg * tau)) / sg)
        cols += [g * np.cos(w * tau), g * np.sin(w * tau)]
    A = np.vstack(cols).T
    want, *_ = np.linalg.lstsq(A, y, rcond=None)
    coef, rss = sm._linear_amplitudes(t, y, t0, tm, ws, ss, kap)
    assert np.allclose(coef, want, rtol=1e-9, atol=1e-10)
    r = y - A @ want
    assert rss == pytest.approx(float(r @ r), rel=1e-10)


def test_robust_std_and_noise_sigma_recover_a_known_white_noise():
    rng = np.random.default_rng(2)
    x = rng.normal(0.0, 0.3, 200_000)
    # 1.4826 MAD estimates sigma of a normal variable (std of the estimate
    # ~ 1.17 sigma / sqrt(n) ~ 0.0008 here)
    assert sm._robust_std(x + 5.0) == pytest.approx(0.3, rel=0.01)
    # a quantised record whose MAD is zero falls back to the plain std
    q = np.zeros(100)
    q[::10] = 1.0
    assert sm._robust_std(q) == pytest.approx(float(np.std(q)), rel=1e-12)
    # second differences of white noise have variance 6 sigma^2; a slow
    # smooth oscillation adds nothing measurable
    t = np.arange(x.size) * 1e-3
    assert sm._noise_sigma(x + 2.0 * np.sin(2 * np.pi * 0.5 * t)) == pytest.approx(0.3, rel=0.01)
    assert sm._noise_sigma(np.ones(3)) == 0.0


def test_lag1_is_the_sample_autocorrelation_at_lag_one():
    rng = np.random.default_rng(3)
    e = rng.normal(size=20_000)
    x = np.empty_like(e)
    x[0] = e[0]
    for i in range(1, e.size):
        x[i] = 0.6 * x[i - 1] + e[i]
    x += 7.0
    d = x - x.mean()
    assert sm._lag1(x) == pytest.approx(float(np.sum(d[:-1] * d[1:]) / np.sum(d * d)), rel=1e-12)
    assert sm._lag1(x) == pytest.approx(0.6, abs=0.03)
    assert sm._lag1(np.full(10, 2.0)) == 0.0


def test_spectral_peaks_find_a_pure_tone_within_a_small_fraction_of_a_bin():
    dt = 0.01
    t = np.arange(0, 20.0, dt)
    f1 = 3.21
    # tones at several offsets from the padded bins (bin = 1 / (8.192 T)):
    # the parabola through the log magnitudes of a Hann peak finds each
    # within 1e-3 / T (its own error is ~ 3e-5 / T)
    for f0 in (1.2345, 1.2377, 1.24, 1.2412):
        y = 2.0 * np.cos(2 * np.pi * f0 * t + 0.3) + 0.5 * np.cos(2 * np.pi * f1 * t) + 0.1 * t
        f, S, T = sm._spectrum(t, y)
        assert T == pytest.approx(t.size * dt, rel=1e-12)
        pk = sm._spectral_peaks(f, S, T, 2)
        # strongest first
        assert pk[0] == pytest.approx(f0, abs=1e-3 / T)
        assert pk[1] == pytest.approx(f1, abs=1e-3 / T)
        assert sm._spectral_peaks(f, S, T) == pk[:1]
    # a tone below 1.5 cycles per record is no peak
    slow = np.cos(2 * np.pi * (1.0 / T) * t)
    f, S, T = sm._spectrum(t, slow)
    assert all(p >= 1.5 / T for p in sm._spectral_peaks(f, S, T, 3))


def test_uniform_resamples_an_irregular_grid_at_the_median_step():
    t = np.array([0.0, 1.0, 2.0, 3.5, 4.0, 5.0, 6.0])
    y = 2.0 * t + 1.0
    yu, dt = sm._uniform(t, y)
    assert dt == pytest.approx(1.0)
    assert np.allclose(yu, 2.0 * np.arange(0.0, 6.0, 1.0) + 1.0)
    # an even grid (within 1e-3 dt) is returned as is
    te = np.arange(10) * 0.1 + 1e-6 * np.sin(np.arange(10))
    yu, dt = sm._uniform(te, te)
    assert yu is te


def test_near_dominant_is_the_documented_band():
    f1, T = 1.0, 10.0
    band = sm.THIRD_MODE_BAND
    assert not sm._near_dominant(f1 + 0.5 / T, f1, T)
    assert sm._near_dominant(f1 + 1.5 / T, f1, T)
    assert sm._near_dominant(f1 - 1.5 / T, f1, T)
    assert sm._near_dominant(f1 + 0.99 * band * f1, f1, T)
    assert not sm._near_dominant(f1 + 1.01 * band * f1, f1, T)
    assert not sm._near_dominant(f1 - 1.01 * band * f1, f1, T)


def test_canonical_puts_the_larger_mode_first_and_keeps_the_model():
    t = np.linspace(0.0, 10.0, 300)
    p = np.array([0.1, 0.0, 0.3, 0.4, 6.0, 0.02, 3.0, -4.0, 4.0, 0.05])
    free = np.ones(10, bool)
    free[1] = False
    y, J = sm._model("two_mode", p, t, 0.0, 5.0, want_jac=True)
    raw = sm._Raw("two_mode", p.copy(), free, 0.0, 5.0, np.zeros_like(t), J[:, free], 0.0, True, "")
    out = sm._canonical(raw, t)
    assert np.allclose(out.p, [0.1, 0.0, 3.0, -4.0, 4.0, 0.05, 0.3, 0.4, 6.0, 0.02])
    # the same curve, and the Jacobian of the permuted parameters
    assert np.allclose(sm._model("two_mode", out.p, t, 0.0, 5.0), y, atol=1e-13)
    assert np.allclose(out.J, _fd_jacobian("two_mode", out.p, t, 0.0, 5.0)[:, free], rtol=1e-6, atol=1e-7)


def test_moving_envelope_of_a_constant_tone_is_its_amplitude():
    dt, T = 0.01, 0.5
    t = np.arange(0, 10.0, dt)
    A, noise = 2.0, 0.3
    rng = np.random.default_rng(4)
    y = A * np.sin(2 * np.pi * t / T) + rng.normal(0, noise, t.size)
    # a window of exactly one period of a noiseless tone: sqrt(2 A^2 / 2) = A
    env, m = sm._moving_envelope(t, A * np.sin(2 * np.pi * t / T), T, 0.0)
    assert m == 50
    assert np.allclose(env[m:-m], A, rtol=1e-9)
    # the noise power is removed: mean env^2 = 2 (A^2/2 + s^2 - s^2) = A^2
    env, m = sm._moving_envelope(t, y, T, noise)
    # (spread of the signal x noise cross term: 1.4 % here; a mutant that
    # adds the noise power instead is 9 % off)
    assert np.mean(env[m:-m] ** 2) == pytest.approx(A ** 2, rel=0.05)
    assert sm._moving_envelope(t[:40], y[:40], T, noise)[0] is None


def test_leading_rest_finds_the_release_of_a_body_at_rest():
    dt, T = 0.01, 1.0
    t = np.arange(0.0, 30.0, dt)
    t_on = 6.3
    tau = np.clip(t - t_on, 0.0, None)
    rng = np.random.default_rng(5)
    y = 0.5 + np.where(t >= t_on, np.sin(2 * np.pi * tau / T) * np.exp(-0.02 * tau), 0.0)
    y = y + rng.normal(0, 0.005, t.size)
    onset, start = sm._leading_rest(t, y, T)
    assert onset == pytest.approx(t_on, abs=0.1 * T)
    assert start - onset == pytest.approx(0.25 * T, rel=1e-9)
    # a record that starts oscillating has no rest
    y2 = np.sin(2 * np.pi * t / T) + rng.normal(0, 0.005, t.size)
    assert sm._leading_rest(t, y2, T) is None
    # a "rest" shorter than one period is none either
    t_on = 0.6
    tau = np.clip(t - t_on, 0.0, None)
    y3 = np.where(t >= t_on, np.sin(2 * np.pi * tau / T), 0.0) + rng.normal(0, 0.005, t.size)
    assert sm._leading_rest(t, y3, T) is None


# ---------------------------------------------------------------------------
# signal_checks: the textbook definitions computed directly
# ---------------------------------------------------------------------------

def test_periodogram_is_the_direct_dft_of_the_detrended_record():
    rng = np.random.default_rng(6)
    n, dt = 64, 0.05
    t = np.arange(n) * dt
    y = rng.normal(size=n) + 3.0 + 0.7 * t
    f, I, T = sc.periodogram(t, y)
    # detrend by an explicit least-squares line, DFT by the sum
    A = np.vstack([np.ones(n), np.arange(n)]).T
    yd = y - A @ np.linalg.lstsq(A, y, rcond=None)[0]
    k = np.arange(1, n // 2 + 1)
    F = np.array([np.sum(yd * np.exp(-2j * np.pi * kk * np.arange(n) / n)) for kk in k])
    assert np.allclose(f, k / (n * dt), rtol=1e-12)
    assert np.allclose(I, np.abs(F) ** 2 / n, rtol=1e-9, atol=1e-12)
    assert T == pytest.approx(n * dt, rel=1e-12)


def test_ljung_box_is_the_textbook_statistic():
    rng = np.random.default_rng(7)
    e = rng.normal(size=300)
    x = e.copy()
    x[1:] += 0.3 * e[:-1]
    x += 4.0
    n, h = x.size, 12
    d = x - x.mean()
    rho = np.array([np.sum(d[:-k] * d[k:]) for k in range(1, h + 1)]) / np.sum(d * d)
    Q = n * (n + 2) * sum(rho[k - 1] ** 2 / (n - k) for k in range(1, h + 1))
    from scipy import stats

    got_Q, got_p = sc.ljung_box(x, h)
    assert got_Q == pytest.approx(Q, rel=1e-9)
    assert got_p == pytest.approx(stats.chi2.sf(Q, h), rel=1e-9)
    # the lag count is capped at n // 4; nothing to test on a constant
    x8 = x[:40]
    d8 = x8 - x8.mean()
    r8 = np.array([np.sum(d8[:-k] * d8[k:]) for k in range(1, 11)]) / np.sum(d8 * d8)
    Q8 = 40 * 42 * sum(r8[k - 1] ** 2 / (40 - k) for k in range(1, 11))
    assert sc.ljung_box(x8, 20)[0] == pytest.approx(Q8, rel=1e-9)
    # scale-free: the same record in units 1e3 times smaller
    assert sc.ljung_box(1e-3 * x, h)[0] == pytest.approx(Q, rel=1e-9)
    assert sc.ljung_box(np.full(50, 2.0)) == (0.0, 1.0)
    assert sc.ljung_box(np.arange(3.0)) == (0.0, 1.0)


def test_autocov_is_the_lagged_sum():
    rng = np.random.default_rng(8)
    x = rng.normal(size=37)
    want = [np.sum(x[:x.size - l] * x[l:]) for l in range(6)]
    assert np.allclose(sc._autocov(x, 5), want, rtol=1e-10, atol=1e-12)


def test_peak_threshold_is_the_bonferroni_exponential_quantile():
    # docs/real_data.md: ln(m / 10^-3)
    assert sc.peak_threshold(1000) == pytest.approx(math.log(1000 / 1e-3), rel=1e-12)
    # P(I/S > c) = exp(-c) per bin; m bins at family level alpha: c = ln(m / alpha)
    for m in (1, 10, 4096):
        assert math.exp(-sc.peak_threshold(m)) * m == pytest.approx(sc.PEAK_ALPHA, rel=1e-12)


def test_local_level_is_the_mean_of_an_exponential_from_its_median():
    rng = np.random.default_rng(9)
    I = rng.exponential(2.5, 4001)
    I[1997:2004] = 1e6  # the peak's own +-3 bins do not count
    # median of an exponential of mean mu is mu ln 2; +-1000 bins around
    # k = 2000 (std of the estimate ~ 2.5 / sqrt(2000) ~ 2 %)
    assert sc._local_level(I, 2000) == pytest.approx(2.5, rel=0.08)
    # near the edge: at least 50 bins each side where they exist
    assert sc._local_level(I, 10) == pytest.approx(2.5, rel=0.35)
    # the level is local: a coloured spectrum (mean 1 below bin 1000, 100
    # above) gives each region its own level (window k/2 .. 3k/2)
    J = rng.exponential(1.0, 6000) * np.where(np.arange(6000) < 1000, 1.0, 100.0)
    assert sc._local_level(J, 500) == pytest.approx(1.0, rel=0.15)
    assert sc._local_level(J, 3000) == pytest.approx(100.0, rel=0.1)


def test_residual_peaks_finds_a_tone_and_names_a_harmonic():
    rng = np.random.default_rng(10)
    dt = 0.01
    t = np.arange(0, 40.0, dt)
    f0 = 0.8
    r = rng.normal(0, 0.1, t.size) + 0.2 * np.cos(2 * np.pi * 3 * f0 * t) + 0.15 * np.cos(2 * np.pi * 1.37 * t)
    pk = sc.residual_peaks(t, r, f0)
    assert len(pk) == 2
    assert pk[0]["frequency"] == pytest.approx(3 * f0, abs=1 / 40)
    assert pk[0]["harmonic"] == 3
    assert pk[1]["frequency"] == pytest.approx(1.37, abs=1 / 40)
    assert pk[1]["harmonic"] is None
    # the test is scale-free: the same record in units 1e4 times smaller
    small = sc.residual_peaks(t, 1e-4 * r, f0)
    assert [p["frequency"] for p in small] == pytest.approx([p["frequency"] for p in pk])
    # white noise alone: a false alarm at most at rate PEAK_ALPHA
    assert sc.residual_peaks(t, rng.normal(0, 0.1, t.size), f0) == []


def test_require_oscillation_accepts_a_tone_and_refuses_noise_and_too_few_cycles():
    from bifilar.estimation.signal_io import SignalError

    rng = np.random.default_rng(11)
    dt = 0.01
    t = np.arange(0, 20.0, dt)
    y = np.cos(2 * np.pi * 0.75 * t) + rng.normal(0, 0.2, t.size)
    got = sc.require_oscillation(t, y)
    assert got["frequency"] == pytest.approx(0.75, abs=1 / 20)
    assert got["cycles"] == pytest.approx(15, abs=1)
    assert got["threshold"] == pytest.approx(math.log(t.size // 2 / sc.PEAK_ALPHA), rel=1e-12)
    with pytest.raises(SignalError, match="no significant"):
        sc.require_oscillation(t, rng.normal(0, 1, t.size))
    # two cycles exactly are enough (the strongest bin sits at k = 2)
    assert sc.require_oscillation(t, np.cos(2 * np.pi * (2.0 / 20) * t))["cycles"] == pytest.approx(2.0)
    with pytest.raises(SignalError, match="fewer than"):
        sc.require_oscillation(t, np.cos(2 * np.pi * (1.0 / 20) * t) + rng.normal(0, 1e-3, t.size))
    # constant or straight records, whose detrending leaves only rounding
    # (not exact zeros), are called so -- not "fewer than 2 cycles"
    for flat in (np.zeros(t.size), np.full(t.size, 2.0), 0.4 * t + 1.0):
        with pytest.raises(SignalError, match="constant"):
            sc.require_oscillation(t, flat)
    # a tiny but real oscillation on an offset is still one
    assert sc.require_oscillation(t, 5.0 + 1e-8 * np.cos(2 * np.pi * 0.75 * t))["frequency"] == \
        pytest.approx(0.75, abs=1 / 20)
    with pytest.raises(SignalError, match="constant"):
        sc.require_oscillation(t[:7], np.cos(t[:7]))


def test_serial_factor_of_ar1_noise_is_its_spectral_ratio():
    """AR(1) x_t = rho x_{t-1} + e_t: S(f) / gamma(0) = (1 - rho^2) /
    |1 - rho exp(-2 pi i f dt)|^2 (-> (1 + rho) / (1 - rho) at f = 0)."""
    rng = np.random.default_rng(12)
    rho, n, dt = 0.7, 40_000, 0.01
    e = rng.normal(size=n)
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1 - rho ** 2)
    for i in range(1, n):
        x[i] = rho * x[i - 1] + e[i]
    for f0 in (0.5, 20.0):
        z = np.exp(-2j * np.pi * f0 * dt)
        want = math.sqrt(max((1 - rho ** 2) / abs(1 - rho * z) ** 2, 1.0))
        fac, p = sc.serial_factor(x, f0, dt)
        assert p >= 1
        assert fac == pytest.approx(want, rel=0.05)
    # scale-free: the same noise in units 1e3 times smaller
    assert sc.serial_factor(1e-3 * x, 0.5, dt)[0] == pytest.approx(sc.serial_factor(x, 0.5, dt)[0], rel=1e-9)
    # white noise: no inflation (the factor is at least 1 and near it)
    fac, _ = sc.serial_factor(e, 0.5, dt)
    assert 1.0 <= fac < 1.05
    assert sc.serial_factor(np.zeros(100), 0.5, dt) == (1.0, 0)


# ---------------------------------------------------------------------------
# fit_period on synthetic records: known truth, known noise
# ---------------------------------------------------------------------------

def _crlb_period_std(f, theta, t, noise):
    """Cramer-Rao std of the period 2 pi / theta[4] for white noise of std
    ``noise``: the Fisher matrix from a central-difference Jacobian of the
    model ``f(theta, t)`` written in the test."""
    J = _central_jacobian(lambda q: f(q, t), theta, 1e-2)
    cov = noise ** 2 * np.linalg.inv(J.T @ J)
    w = theta[4]
    return 2 * math.pi / w ** 2 * math.sqrt(cov[4, 4]), np.sqrt(np.diag(cov))


def _fit_synthetic(truth, th, T_rec, noise, seed, model, dt=0.02):
    """Fit ``model`` to ``truth(th, t) + white noise`` and return the fit,
    the Cramer-Rao std of the period and of every parameter."""
    from bifilar.estimation.signal import fit_period

    t = np.arange(0.0, T_rec + dt / 2, dt)
    y = truth(th, t) + np.random.default_rng(seed).normal(0, noise, t.size)
    fit = fit_period(t, y, model, crossing_check=False, split_check=False)
    return (fit, *_crlb_period_std(truth, th, t, noise))


def _viscous_truth(th, t):
    c0, c1, A, ph, w, sg = th
    return c0 + c1 * (t - 10.0) + A * np.exp(-sg * t) * np.cos(w * t + ph)


def test_viscous_fit_recovers_period_damping_and_its_own_std():
    noise = 0.05
    th = np.array([0.4, 0.01, 1.5, 0.7, 2 * math.pi / 1.3, 0.04])
    fit, sT, sd = _fit_synthetic(_viscous_truth, th, 20.0, noise, 13, "viscous")
    # the printed white-noise std is the Cramer-Rao std (s estimated from
    # n - p residuals: ~2 % spread)
    assert fit.std_raw == pytest.approx(sT, rel=0.08)
    assert fit.period == pytest.approx(1.3, abs=4 * sT)
    assert fit.damping["sigma"] == pytest.approx(0.04, abs=4 * sd[5])
    assert fit.damping["sigma_std"] == pytest.approx(sd[5], rel=0.08)
    assert fit.noise_std == pytest.approx(noise, rel=0.08)
    assert fit.amplitude == pytest.approx(1.5, abs=4 * sd[2])
    assert fit.period_undamped == pytest.approx(2 * math.pi / math.hypot(th[4], 0.04), abs=4 * sT)


def _two_mode_truth(th, t):
    c0, c1, A, ph, w, sg, A2, ph2, w2, sg2 = th
    return (c0 + c1 * (t - 15.0) + A * np.exp(-sg * t) * np.cos(w * t + ph)
            + A2 * np.exp(-sg2 * t) * np.cos(w2 * t + ph2))


def test_two_mode_fit_recovers_both_modes():
    th = np.array([0.1, 0.0, 1.0, 0.3, 2 * math.pi / 1.1, 0.02, 0.35, -1.0, 2 * math.pi / 0.83, 0.05])
    fit, sT, sd = _fit_synthetic(_two_mode_truth, th, 30.0, 0.03, 14, "two_mode")
    assert fit.std_raw == pytest.approx(sT, rel=0.08)
    assert fit.period == pytest.approx(1.1, abs=4 * sT)
    p2 = [m["period"] for m in fit.modes]
    assert len(p2) == 2
    s2 = 2 * math.pi / th[8] ** 2 * sd[8]
    assert p2[1] == pytest.approx(0.83, abs=4 * s2)


def _quadratic_truth(th, t):
    c0, c1, A, ph, w, kap = th
    return c0 + c1 * (t - 12.0) + A / (1 + kap * t) * np.cos(w * t + ph)


def test_quadratic_fit_recovers_the_drag_envelope():
    th = np.array([0.0, 0.0, 2.0, 0.2, 2 * math.pi / 1.7, 0.15])
    fit, sT, sd = _fit_synthetic(_quadratic_truth, th, 24.0, 0.02, 15, "quadratic")
    assert fit.std_raw == pytest.approx(sT, rel=0.08)
    assert fit.period == pytest.approx(1.7, abs=4 * sT)
    assert fit.damping["kappa"] == pytest.approx(0.15, abs=4 * sd[5])


def _three_mode_truth(th, t):
    return _two_mode_truth(th[:10], t) + th[10] * np.exp(-th[13] * t) * np.cos(th[12] * t + th[11])


def test_three_mode_fit_recovers_a_close_third_oscillation():
    # dominant 1.1 s, a swing mode at 0.6 s (outside THIRD_MODE_BAND) and a
    # third oscillation 12 % above the dominant frequency, beating with it
    w1 = 2 * math.pi / 1.1
    th = np.array([0.1, 0.0, 1.0, 0.3, w1, 0.01, 0.4, -1.0, 2 * math.pi / 0.6, 0.02,
                   0.3, 0.5, 1.12 * w1, 0.015])
    fit, sT, sd = _fit_synthetic(_three_mode_truth, th, 40.0, 0.03, 16, "three_mode")
    assert fit.model == "three_mode"
    assert fit.period == pytest.approx(1.1, abs=4 * sT)
    periods = sorted(m["period"] for m in fit.modes)
    s3 = 2 * math.pi / th[12] ** 2 * sd[12]
    assert periods[0] == pytest.approx(0.6, abs=0.01)
    assert periods[1] == pytest.approx(2 * math.pi / th[12], abs=4 * s3)


def test_solve_reports_an_unfinished_fit_as_not_converged():
    """MINPACK status 0 (the evaluation budget ran out) is no convergence."""
    t = np.linspace(0.0, 20.0, 1000)
    p = np.array([0.0, 0.0, 1.0, 0.0, 5.0, 0.05])
    y = sm._model("viscous", p, t, 0.0, 10.0)
    raw = sm._solve("viscous", t, y, 0.0, 10.0, [0.3, 0.0, 0.2, 0.2, 5.3, 0.2], max_nfev_per_param=1)
    assert not raw.converged
    raw = sm._solve("viscous", t, y, 0.0, 10.0, [0.0, 0.0, 0.9, 0.1, 5.01, 0.04])
    assert raw.converged
    assert np.allclose(raw.p, p, atol=1e-8)


def test_auto_trim_stops_where_the_envelope_meets_k_noise():
    """A decay A exp(-sigma t) with a large drift: the envelope meets k x
    noise at t* = ln(A / (k noise)) / sigma (within a period or so: the
    moving RMS spans one period and the trim keeps half a window more)."""
    dt, T, A, sg, noise, k = 0.01, 1.0, 2.0, 0.1, 0.02, 5.0
    t = np.arange(0.0, 60.0, dt)
    tm = 30.0
    p = np.array([0.5, 0.8, A, 0.0, 2 * math.pi / T, sg])
    e = np.random.default_rng(17).normal(0, noise, t.size)
    y = sm._model("viscous", p, t, 0.0, tm) + e
    raw = sm._Raw("viscous", p, np.ones(6, bool), 0.0, tm, e, np.zeros((t.size, 6)), float(e @ e), True, "")
    t_cut, got_noise = sm._auto_trim(t, y, raw, k)
    assert got_noise == pytest.approx(noise, rel=0.05)
    t_star = math.log(A / (k * noise)) / sg
    assert t_star - 0.5 * T <= t_cut <= t_star + 1.5 * T
    # nothing above a huge threshold: no trim time, no failure
    assert sm._auto_trim(t, y, raw, 1e6)[0] is None
