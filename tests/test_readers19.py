"""readers19 (docs/design.md "readers19, session 19"): a recording's faults
named, not guessed.  A saturating sensor's flat tops are left out of the
fit, an offset's single step is taken out, and the reader's minor messages
of audit18 say what they meet.  Each check compares the faulty record with
the same record without the fault (same noise draw): the independent
answer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.io
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.estimation.signal import fit_period, read_signal
from bifilar.estimation.signal_clip import find_clipping
from bifilar.estimation.signal_io import SignalError
from bifilar.estimation.signal_offset import find_offset_step

T0 = 1.5539  # s, audit18's trifilar plate's torsion


def _record(seed: int, cycles: int = 20, fs: float = 50.0, noise: float = 0.01):
    """A gyro-like record: 0.4 [y] amplitude, Q ~ 2000, white noise ``noise`` of it."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, cycles * T0, 1.0 / fs)
    w = 2 * math.pi / T0
    y = 0.4 * np.exp(-w * t / 4000) * np.cos(w * t + 0.7) + noise * 0.4 * rng.standard_normal(t.size)
    return t, y


def test_a_saturating_gyro_is_fitted_on_its_unclipped_samples():
    """Audit18 S1: clipped at 80 % of its peak, the record was fitted with its flat tops (auto: two_mode,
    std ~3x the clean one's; a viscous fit reads the harmonics as noise).  Now the clipped samples are
    left out: the period is the clean record's within its std, the std within 30 % of the clean one's
    (41 % of the samples gone: sqrt(1/0.59) = 1.3 at most), and the note names the level.  Old code:
    no ``clipped`` (KeyError) and a std ~10x."""
    t, y = _record(19)
    clipped = np.clip(y, -0.32, 0.32)
    clean = fit_period(t, y, "viscous", crossing_check=False)
    fit = fit_period(t, clipped, "viscous", crossing_check=False)
    c = fit.oscillation["clipped"]
    assert c["levels"] == {"max": 0.32, "min": -0.32}
    assert c["samples_left_out"] == int(np.sum(np.abs(clipped) >= 0.32))
    assert "saturates" in c["line"] and "0.32" in c["line"] and "\n" not in c["line"]
    assert fit.std < 1.3 * clean.std
    assert abs(fit.period - clean.period) < 2 * math.hypot(fit.std, clean.std)
    # one side only (a gyro's range offset): the other side's samples stay
    one = np.minimum(y, 0.3)
    f1 = fit_period(t, one, "viscous", crossing_check=False)
    assert f1.oscillation["clipped"]["levels"] == {"max": 0.3}
    assert abs(f1.period - clean.period) < 2 * math.hypot(f1.std, clean.std)


def test_the_cli_warns_of_clipping_once(tmp_path):
    t, y = _record(3)
    p = tmp_path / "gyro.csv"
    np.savetxt(p, np.c_[t, np.clip(y, -0.3, 0.3)], delimiter=",", header="t,rate", comments="", fmt="%.10g")
    r = CliRunner().invoke(main, ["period", str(p), "--json", "--model", "viscous"])
    assert r.exit_code == 0, r.stderr
    w = [x for x in json.loads(r.stdout)["warnings"] if "saturates" in x]
    assert len(w) == 1 and "max 0.3 and min -0.3" in w[0], w


def test_equal_samples_that_are_not_clipping_are_left_alone():
    """A quantised record (3 mrad on 0.1 rad, undamped: the same top level at every turning point,
    several samples each), a noisy one and a record read at 4 decimals are never clipped."""
    t = np.arange(0.0, 30 * T0, 1 / 120.0)
    for phase in np.linspace(0, 3, 7):
        y = 0.1 * np.cos(2 * math.pi * t / T0 + phase)
        assert find_clipping(np.round(y / 0.003) * 0.003) is None
    t, y = _record(5)
    assert find_clipping(y) is None and find_clipping(np.round(y, 4)) is None


def test_an_offset_step_is_found_and_taken_out():
    """Audit18 S6: an offset stepping once by 10-50 % of the amplitude was answered with a std 5-20x the
    clean one's and no word.  Now the step is found at its sample, its size to a few %, and taken out:
    the clean record's period and std.  Old code: no ``offset_step`` (KeyError), std ~10x."""
    t, y = _record(7, cycles=30, noise=0.005)
    k = int(0.45 * t.size)
    stepped = y + 0.12 * (np.arange(t.size) >= k)
    clean = fit_period(t, y, "viscous", crossing_check=False)
    fit = fit_period(t, stepped, "viscous", crossing_check=False)
    st = fit.oscillation["offset_step"]
    assert abs(st["time"] - t[k]) <= 0.02 + 1e-9  # to a sample
    assert st["size"] == pytest.approx(0.12, rel=0.05)  # 5 %: the local fit's noise is ~1 %
    assert "steps by +0.12" in st["line"] and f"t = {t[k]:.4g} s" in st["line"]
    assert fit.std < 1.3 * clean.std
    assert abs(fit.period - clean.period) < 2 * math.hypot(fit.std, clean.std)


def test_no_step_in_clean_beating_or_drifting_records():
    t, y = _record(11, cycles=30)
    w = 2 * math.pi / T0
    for yy in (y, y + 0.1 * np.cos(0.6 * w * t), y * (1 + 0.2 * t / t[-1]), y + 0.3 * np.sin(2 * math.pi * t / 40)):
        assert find_offset_step(t, yy, T0) is None


def _csv(tmp_path, name, text, encoding="utf-8"):
    p = tmp_path / name
    p.write_text(text, encoding=encoding)
    return p


def _rows(fmt="{t:.4f},{y:.6f}", n=200, last=""):
    t = np.arange(n) * 0.02
    y = 0.1 * np.cos(2 * math.pi * t / T0)
    return "".join(fmt.format(t=a, y=b) + last + "\n" for a, b in zip(t, y))


def test_audit18_minor_reader_cases(tmp_path):
    """Audit18's F list: each was refused with the wrong cause (old code: 'non-numeric value 'rad'',
    'its first row is not a header', 'not a text table', 'NaN/missing', the rate before the signal)."""
    ref = read_signal(_csv(tmp_path, "ref.csv", "t,y\n" + _rows()))
    t, y, m = read_signal(_csv(tmp_path, "units.csv", "t,y\ns,rad\n" + _rows()))
    assert np.array_equal(y, ref[1]) and any("units and skipped" in w for w in m["warnings"])
    t, y, m = read_signal(_csv(tmp_path, "ms.csv", "t,y\n[ms],[rad]\n" + _rows("{t:.1f},{y:.6f}".replace("{t:.1f}", "{t:.4f}"))))
    assert np.allclose(t, ref[0] * 1e-3)
    t, y, m = read_signal(_csv(tmp_path, "trail.csv", "t,y,\n" + _rows(last=",")))
    assert np.array_equal(y, ref[1]) and m["columns"] == ["t", "y"]
    t, y, m = read_signal(_csv(tmp_path, "u16.csv", "t,y\n" + _rows(), encoding="utf-16"))
    assert np.array_equal(y, ref[1])
    for enc in ("utf-16-le", "utf-16-be"):  # no byte-order mark: the NULs decode as UTF-8 and were refused as
        t, y, m = read_signal(_csv(tmp_path, f"{enc}.csv", "t,y\n" + _rows(), encoding=enc))  # "not a header"
        assert np.array_equal(y, ref[1])
    t, y, m = read_signal(_csv(tmp_path, "inf.csv", "t,y\n" + _rows().replace("0.100000", "inf", 1)))
    assert any("1 infinite (inf)" in w for w in m["warnings"]) and not any("NaN" in w for w in m["warnings"])
    p = tmp_path / "wrong.mat"
    scipy.io.savemat(p, {"foo": "bar", "data_x": np.arange(5.0).reshape(-1, 1), "meta": np.eye(2)})
    with pytest.raises(SignalError) as e:
        read_signal(p)
    assert e.value.field == "signal" and "'data_x'" in e.value.message and "only 5 samples" in e.value.message
    p = _csv(tmp_path, "min.csv", "t,y\nmin,rad\n" + _rows())
    with pytest.raises(SignalError) as e:
        read_signal(p)
    assert e.value.field == "time" and "'min'" in e.value.message
