"""Tests of bifilar.estimation.signal: readers, period fits, uncertainty.

Every tolerance is justified next to it.  Random draws use fixed seeds, so
the statistical tests are deterministic; their bands are nevertheless set
at >= 3 sigma of the sampling distribution of the checked statistic, so a
correct implementation would pass for (almost) any seed and a wrong one
(e.g. an uninflated std for correlated noise, a factor 3 off) fails.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from scipy.integrate import solve_ivp
from scipy.signal import lfilter

from bifilar.errors import InputError
from bifilar.estimation.signal import (
    MIN_SAMPLES,
    SignalError,
    fit_period,
    period_from_crossings,
    read_signal,
)


def damped(t, T=1.3, zeta=0.01, A=1.0, phi=0.3, c0=0.5, c1=0.01, tm=10.0):
    """Viscous damped cosine with damped period T (s) plus offset and drift."""
    wd = 2 * np.pi / T
    wn = wd / math.sqrt(1 - zeta ** 2)
    return c0 + c1 * (t - tm) + A * np.exp(-zeta * wn * t) * np.cos(wd * t + phi)


# ---------------------------------------------------------------------------
# fits on synthetic signals
# ---------------------------------------------------------------------------

def test_noise_free_viscous_recovered_exactly():
    t = np.arange(0, 20, 0.01)
    T, zeta = 1.3, 0.01
    y = damped(t, T, zeta, c0=0.5, c1=0.01, tm=t[0] + (t[-1] - t[0]) / 2)
    fit = fit_period(t, y)
    # exact model, no noise: only float rounding and the 1e-13 solver
    # tolerances remain, many orders below 1e-9
    assert abs(fit.period - T) / T < 1e-9
    assert abs(fit.damping_ratio - zeta) < 1e-9
    assert abs(fit.offset - 0.5) < 1e-9 and abs(fit.drift - 0.01) < 1e-9
    assert fit.r_squared > 1 - 1e-15
    # residuals at rounding level must not trigger the autocorrelation inflation
    assert fit.std_inflation == 1.0
    # the amplitude the period refers to: RMS of A exp(-sigma t) over the
    # 20 s window, A sqrt((1 - exp(-2 sigma T_rec)) / (2 sigma T_rec))
    sg = zeta * 2 * math.pi / T / math.sqrt(1 - zeta ** 2)
    x = 2 * sg * (t[-1] - t[0])
    assert abs(fit.amplitude_rms - math.sqrt(-math.expm1(-x) / x)) < 1e-3  # sampling: 2000 points


def test_noise_free_quadratic_envelope_recovered():
    # exact quadratic-damping model: A(t) = A0 / (1 + k A0 t)
    t = np.arange(0, 30, 0.01)
    w, k, A0 = 2 * np.pi / 1.7, 0.15, 0.8
    y = 0.2 + A0 / (1 + k * A0 * t) * np.cos(w * t + 1.0)
    fit = fit_period(t, y, model="quadratic")
    # noise-free exact model: rounding-level agreement (1e-9 is generous)
    assert abs(fit.period - 1.7) / 1.7 < 1e-9
    assert abs(fit.damping["k"] - k) / k < 1e-8
    assert abs(fit.amplitude - A0) < 1e-9


def test_white_noise_coverage_and_std_calibration():
    """200 noisy draws: bias, scatter and the reported std agree."""
    rng = np.random.default_rng(20240611)
    t = np.arange(0, 20, 0.01)
    T, sigma_noise = 1.3, 0.05
    clean = damped(t, T)
    est, std = [], []
    for _ in range(200):
        fit = fit_period(t, clean + sigma_noise * rng.standard_normal(t.size),
                         crossing_check=False, split_check=False)
        est.append(fit.period)
        std.append(fit.std)
    est, std = np.array(est), np.array(std)
    emp = est.std(ddof=1)
    z = (est - T) / std
    # unbiased: mean error within 3 standard errors of the mean (3 emp/sqrt(200))
    assert abs(est.mean() - T) < 3 * emp / math.sqrt(200)
    # reported std vs empirical scatter: the sample std of 200 draws has a
    # relative sampling error of 1/sqrt(2*199) = 5 %, so 20 % is a 4-sigma band
    assert abs(np.median(std) / emp - 1) < 0.20
    # coverage of the 95 % interval: binomial sd of a 200-draw fraction at
    # p = 0.95 is 1.5 %, [0.905, 0.99] is a 3-sigma band
    cover95 = np.mean(np.abs(z) < 1.96)
    assert 0.905 <= cover95 <= 0.99
    # "within 3 sigma of the truth": expected 99.7 %, allow 2 misses of 200
    assert np.mean(np.abs(z) < 3) >= 0.99


def test_autocorrelated_noise_inflates_std_honestly():
    """AR(1) noise (rho = 0.8): the white-noise std is ~3x too small; the
    AR spectral density at the oscillation frequency (for AR(1) at low
    frequency sqrt((1+rho)/(1-rho))) must restore it."""
    rng = np.random.default_rng(7)
    t = np.arange(0, 20, 0.01)
    T, rho, s = 1.3, 0.8, 0.03
    clean = damped(t, T)
    est, std, infl = [], [], []
    for _ in range(120):
        e = rng.standard_normal(t.size) * s
        e[0] /= math.sqrt(1 - rho ** 2)  # start in the stationary distribution
        noise = lfilter([1.0], [1.0, -rho], e)  # x[i] = rho x[i-1] + e[i]
        fit = fit_period(t, clean + noise, crossing_check=False, split_check=False)
        est.append(fit.period)
        std.append(fit.std)
        infl.append(fit.std_inflation)
    emp = np.std(est, ddof=1)
    # expected factor sqrt(1.8/0.2) = 3; the estimated rho scatters by ~0.01
    assert 2.6 < np.median(infl) < 3.4
    # sample std of 120 draws: 6.5 % relative error; 25 % is a ~4-sigma band
    # (an uninflated std would be off by a factor 3 and fail)
    assert abs(np.median(std) / emp - 1) < 0.25
    assert any("not white" in n for n in fit.notes)


def _quadratic_pendulum(c=0.2, T0=1.5, th0=0.2, t_end=30.0, fs=100.0):
    w = 2 * np.pi / T0
    sol = solve_ivp(lambda _t, x: [x[1], -c * abs(x[1]) * x[1] - w ** 2 * x[0]],
                    (0, t_end), [th0, 0.0], rtol=1e-11, atol=1e-13, dense_output=True)
    t = np.arange(0, t_end, 1 / fs)
    return t, sol.sol(t)[0], w


def test_quadratic_damping_preferred_by_auto():
    t, th, w = _quadratic_pendulum()
    rng = np.random.default_rng(11)
    y = th + 1e-3 * rng.standard_normal(t.size)
    fit = fit_period(t, y, model="auto", candidates=("viscous", "quadratic", "quadratic+viscous"))
    assert fit.model == "quadratic"
    # every candidate is fitted, and the winner once more without its drift term
    assert fit.chosen_by == "BIC" and set(fit.alternatives) == {
        "viscous", "quadratic", "quadratic+viscous", "quadratic without drift"}
    # the viscous model is far worse (envelope 1/(1+x) vs exp(-x) differs by
    # ~10 % of A0 mid-record, 20x the noise): a decisive BIC margin
    sel = fit.selection["candidates"]
    assert sel["viscous"]["bic"] - sel["quadratic"]["bic"] > 100
    # period agrees with the crossing period within 3 combined sigma
    cr = period_from_crossings(t, y)
    assert abs(fit.period - cr.period) < 3 * math.hypot(fit.std, cr.std)
    # small amplitude: frequency ~ w; drag shifts it at second order in
    # c*theta0 (~1e-5 here), so 1e-4 relative
    assert abs(fit.period - 2 * np.pi / w) / (2 * np.pi / w) < 1e-4
    # harmonic balance of c|v|v gives dA/dt = -(4 c w / 3 pi) A^2; the
    # first-order averaging is good to O(c theta0) ~ 4 %, observed 0.05 %;
    # 2 % tolerance
    k_theory = 4 * 0.2 * w / (3 * np.pi)
    assert abs(fit.damping["k"] - k_theory) / k_theory < 0.02


def test_viscous_data_not_mistaken_for_quadratic():
    rng = np.random.default_rng(5)
    t = np.arange(0, 30, 0.01)
    y = damped(t, 1.5, 0.02) + 0.01 * rng.standard_normal(t.size)
    fit = fit_period(t, y, model="auto")
    assert fit.model == "viscous"


def test_two_beating_modes_recovered():
    rng = np.random.default_rng(3)
    t = np.arange(0, 60, 0.02)
    T1, T2 = 1.00, 1.05  # 0.048 Hz apart = 2.9 frequency bins of a 60 s record
    y = (np.exp(-0.01 * t) * np.cos(2 * np.pi / T1 * t)
         + 0.6 * np.exp(-0.02 * t) * np.cos(2 * np.pi / T2 * t + 1.0)
         + 0.02 * rng.standard_normal(t.size))
    fit = fit_period(t, y, model="two_mode")
    (m1, m2) = fit.modes
    assert fit.period == m1["period"]
    # each period within 4 of its own sigmas and, as a sanity bound, 1e-3
    assert abs(m1["period"] - T1) < 4 * m1["std"] and abs(m1["period"] - T1) / T1 < 1e-3
    assert abs(m2["period"] - T2) < 4 * m2["std"] and abs(m2["period"] - T2) / T2 < 1e-3
    # the dominant (larger amplitude) mode is listed first
    assert m1["amplitude"] > m2["amplitude"]
    # a single-mode fit cannot represent the beating
    assert fit.r_squared > fit_period(t, y).r_squared + 0.1


def test_crossings_agree_with_fit_on_clean_data():
    rng = np.random.default_rng(2)
    t = np.arange(0, 30, 0.005)
    y = damped(t, 1.59, 0.005, c1=0.0) + 1e-3 * rng.standard_normal(t.size)
    fit = fit_period(t, y)
    cr = fit.crossing
    assert cr is not None and cr.n_periods >= 30
    # both unbiased here: agree within 3 combined sigma; and the crossing
    # std must be honest too: within 3 sigma of the truth
    assert abs(fit.period - cr.period) < 3 * math.hypot(fit.std, cr.std)
    assert abs(cr.period - 1.59) < 3 * cr.std
    # the experimenter's mean interval is the same estimate to ~1e-4
    assert abs(cr.mean_period - 1.59) / 1.59 < 1e-4


def test_crossings_robust_to_spikes_at_the_level():
    t = np.arange(0, 20, 0.001)
    y = np.sin(2 * np.pi * t / 1.25)
    rng = np.random.default_rng(0)
    y = y + 1e-3 * rng.standard_normal(t.size)
    # spikes much larger than the 3-sigma hysteresis exactly at crossings
    for tc in (2.5, 5.625, 10.0):
        i = int(round(tc / 0.001))
        y[i + 1] += 0.05
        y[i + 3] -= 0.05
    cr = period_from_crossings(t, y)
    assert abs(cr.period - 1.25) < 1e-4  # no spurious crossings counted
    # ups at 1.25 ... 18.75 (t = 0 starts on the level: not a crossing), downs
    # at 0.625 ... 19.375: 15 + 16 crossings -> 14 + 15 intervals
    assert cr.n_periods == 29


def test_trim_auto_drops_the_settled_tail():
    rng = np.random.default_rng(9)
    t = np.arange(0, 40, 0.01)
    T, zeta, noise = 1.0, 0.05, 0.01
    y = damped(t, T, zeta, c1=0.0) + noise * rng.standard_normal(t.size)
    fit = fit_period(t, y, trim="auto")
    # envelope exp(-zeta w t) reaches 5 sigma_noise at t = ln(20)/(zeta w) = 9.5 s;
    # moving-RMS envelope and half-period padding: allow +-2.5 s
    t_expect = math.log(1 / (5 * noise)) / (zeta * 2 * np.pi / T)
    assert abs(fit.t1 - t_expect) < 2.5
    assert any("trim=auto" in n for n in fit.notes)
    assert abs(fit.period - T) < 3 * fit.std


def test_explicit_window():
    t = np.arange(0, 20, 0.01)
    y = damped(t)
    fit = fit_period(t, y, t_start=2.0, t_stop=12.0)
    assert fit.t0 >= 2.0 and fit.t1 <= 12.0
    assert abs(fit.period - 1.3) / 1.3 < 1e-9  # noise-free: rounding level
    with pytest.raises(SignalError) as e:
        fit_period(t, y, t_start=5.0, t_stop=5.05)
    assert e.value.field == "--t-start"


def test_fallback_to_crossings(monkeypatch):
    import bifilar.estimation.signal_models as M

    def boom(*a, **k):
        raise np.linalg.LinAlgError("forced failure")

    monkeypatch.setattr(M, "_solve", boom)
    t = np.arange(0, 20, 0.01)
    fit = fit_period(t, damped(t))
    assert fit.model == "crossings" and abs(fit.period - 1.3) < 1e-3
    with pytest.raises(SignalError):
        fit_period(t, damped(t), fallback=False)


def test_unknown_model_is_a_signal_error():
    t = np.arange(0, 20, 0.01)
    with pytest.raises(SignalError) as e:
        fit_period(t, damped(t), model="cubic")
    assert e.value.field == "--model"


# ---------------------------------------------------------------------------
# readers
# ---------------------------------------------------------------------------

def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def test_read_csv_with_time_column(tmp_path):
    t = np.arange(100) / 50.0
    y = np.sin(t)
    rows = "\n".join(f"{a:.6f},{b:.9f},{2 * b:.9f}" for a, b in zip(t, y))
    p = _write(tmp_path / "s.csv", "Time,angle,other\n" + rows + "\n")
    tt, yy, meta = read_signal(p)
    assert np.allclose(tt, t) and np.allclose(yy, y, atol=1e-9)
    assert meta["column"] == "angle" and meta["columns"] == ["Time", "angle", "other"]
    assert meta["time_source"] == "column 'Time'" and meta["sample_rate"] == pytest.approx(50.0)
    _, y2, _ = read_signal(p, column="other")
    assert np.allclose(y2, 2 * y, atol=1e-8)


def test_read_tab_separated_samples_with_sample_rate(tmp_path):
    # the KTH recordings' layout: a tab-separated header "x<TAB>y", no time
    rows = "\n".join(f"{i}.5\t{-i}" for i in range(60))
    p = _write(tmp_path / "0.30.csv", "x\ty\n" + rows + "\n")
    t, y, meta = read_signal(p, sample_rate=240)
    assert np.allclose(t, np.arange(60) / 240) and y[1] == 1.5
    assert meta["column"] == "x" and meta["sample_rate_source"] == "argument"
    _, y2, _ = read_signal(p, column="y", sample_rate=240)
    assert y2[2] == -2


def test_read_headerless_single_column_with_sample_rate(tmp_path):
    p = _write(tmp_path / "raw.txt", "\n".join(str(0.1 * i) for i in range(30)) + "\n")
    t, y, meta = read_signal(p, sample_rate=10)
    assert t[-1] == pytest.approx(2.9) and y.size == 30
    assert meta["warnings"]  # says it invented the column name


def test_read_mat_with_rate_variable(tmp_path):
    p = tmp_path / "trial.mat"
    data = np.sin(np.arange(500) / 100.0)[:, None]  # column vector, as MATLAB saves
    scipy.io.savemat(p, {"bicycle": "X", "ActualRate": np.array([[1000]], dtype=np.uint16),
                         "data": data, "other": np.arange(3.0)})
    t, y, meta = read_signal(p)
    assert meta["column"] == "data" and y.shape == (500,)
    assert meta["sample_rate"] == 1000 and meta["sample_rate_source"] == "variable 'ActualRate'"
    assert t[1] == pytest.approx(1e-3) and meta["fields"]["bicycle"] == "X"
    # an explicit rate wins and is reported
    t2, _, meta2 = read_signal(p, sample_rate=500)
    assert t2[1] == pytest.approx(2e-3) and meta2["sample_rate_source"] == "argument"
    assert any("overrides" in w for w in meta2["warnings"])


def test_read_mat_with_time_vector(tmp_path):
    p = tmp_path / "tv.mat"
    tv = np.linspace(0, 1, 50)
    scipy.io.savemat(p, {"time": tv, "theta": np.cos(tv)})
    t, y, meta = read_signal(p)
    assert meta["column"] == "theta" and np.allclose(t, tv)


def test_nan_handling(tmp_path):
    n = 300
    y = [str(float(i)) for i in range(n)]
    y[10] = "NaN"
    y[20] = ""
    p = _write(tmp_path / "few.csv", "v\n" + "\n".join(y) + "\n")
    t, yy, meta = read_signal(p, sample_rate=100)
    # 2 of 300 (< 1 %) dropped; times keep their original instants
    assert yy.size == n - 2 and meta["n_dropped"] == 2 and meta["warnings"]
    assert t[10] == pytest.approx(0.11)
    y[30:40] = ["nan"] * 10
    p2 = _write(tmp_path / "many.csv", "v\n" + "\n".join(y) + "\n")
    with pytest.raises(SignalError) as e:
        read_signal(p2, sample_rate=100)
    assert e.value.field == "signal" and "NaN" in str(e.value)


@pytest.mark.parametrize("case,field,fragment", [
    ("missing", "path", "no such file"),
    ("column", "--column", "available: t, a, b"),
    ("text", "signal", "non-numeric"),
    ("short", "signal", f"at least {MIN_SAMPLES}"),
    ("nonmono", "time", "not strictly increasing"),
    ("notime", "--sample-rate", "no time column"),
    ("badrate", "--sample-rate", "positive"),
    ("matcolumn", "--column", "not a numeric 1-D array"),
    ("matmissing", "--column", "available: data"),
    ("matnorate", "--sample-rate", "no sample-rate variable"),
])
def test_reader_errors_name_the_field(tmp_path, case, field, fragment):
    good = "\n".join(f"{i / 100},{i},{-i}" for i in range(50))
    kw = {}
    if case == "missing":
        p = tmp_path / "nope.csv"
    elif case == "column":
        p = _write(tmp_path / "c.csv", "t,a,b\n" + good + "\n")
        kw = {"column": "z"}
    elif case == "text":
        p = _write(tmp_path / "x.csv", "t,a\n0,1\n0.1,2\n0.2,oops\n" + "\n".join(f"{i},{i}" for i in range(3, 40)))
    elif case == "short":
        p = _write(tmp_path / "s.csv", "t,a\n" + "\n".join(f"{i},{i}" for i in range(10)))
    elif case == "nonmono":
        p = _write(tmp_path / "m.csv", "t,a\n" + "\n".join(f"{i if i != 30 else 5},{i}" for i in range(50)))
    elif case == "notime":
        p = _write(tmp_path / "n.csv", "a,b\n" + "\n".join(f"{i},{i}" for i in range(50)))
    elif case == "badrate":
        p = _write(tmp_path / "r.csv", "a\n" + "\n".join(str(i) for i in range(50)))
        kw = {"sample_rate": -3}
    elif case == "matcolumn":
        p = tmp_path / "a.mat"
        scipy.io.savemat(p, {"data": np.arange(50.0), "fs": 100.0, "name": "fork"})
        kw = {"column": "name"}
    elif case == "matmissing":
        p = tmp_path / "b.mat"
        scipy.io.savemat(p, {"data": np.arange(50.0), "fs": 100.0})
        kw = {"column": "gyro"}
    elif case == "matnorate":
        p = tmp_path / "c.mat"
        scipy.io.savemat(p, {"data": np.arange(50.0)})
    with pytest.raises(SignalError) as e:
        read_signal(p, **kw)
    assert e.value.field == field
    assert fragment in str(e.value)
    assert str(e.value).startswith(field + ": ")
    assert isinstance(e.value, InputError)  # the CLI maps it to exit status 2


# ---------------------------------------------------------------------------
# real recordings (skipped when ../shared/data is absent)
# ---------------------------------------------------------------------------

# the KTH series' period against the radius, and the gyro trial's read and
# fit: tests/test_period_real.py (one fit per record for all its checks)
