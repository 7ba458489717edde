"""Signal audit, session 6: cases of `bifilar period` / `invert --signal`
nobody had written (docs/invert.md, "Signal audit, session 6").

* Aliasing: a recording sampled below twice its frequency shows a slower
  alias.  `period` alone cannot tell (it notes a frequency near the Nyquist
  limit); `invert --signal` compares the fitted frequency with the config's
  predicted modes and their aliases |f - k fs| (analytic here) and refuses a
  match that is only by alias, and warns below 2.5 samples per cycle.
"""

from __future__ import annotations

import json
import math

import numpy as np
from click.testing import CliRunner

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.cli import main
from bifilar.config import load_scene
from bifilar.estimation.signal import fit_period
from bifilar.estimation.signal_alias import fold

from conftest import CONFIGS

LIN1 = CONFIGS / "thesis_lin1_torsion.yaml"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _torsion_period():
    s = load_scene(LIN1, warn=False)
    return linear_modes(s, rest_pose(s)).get("torsion").period


def _record(path, T, fs, dur=120.0, seed=0):
    """A lightly damped oscillation of period ``T`` (s), 0.05 rad, sampled at
    ``fs`` (Hz) with 0.5 mrad noise, as a CSV with a time column."""
    t = np.arange(0.0, dur, 1.0 / fs)
    rng = np.random.default_rng(seed)
    y = 0.05 * np.exp(-0.002 * t) * np.cos(2 * np.pi / T * t + 0.3) + 5e-4 * rng.standard_normal(t.size)
    np.savetxt(path, np.c_[t, y], delimiter=",", header="t,angle", comments="")
    return path


def test_fold_is_the_sampled_frequency():
    """The fold of f at fs is the frequency a sampled cosine shows: the
    samples of cos(2 pi f t) and cos(2 pi fold t) coincide."""
    rng = np.random.default_rng(1)
    for _ in range(50):
        fs = rng.uniform(0.5, 5.0)
        f = rng.uniform(0.0, 3.0) * fs
        fa, k = fold(f, fs)
        assert 0.0 <= fa <= fs / 2 + 1e-12
        n = np.arange(40)
        assert np.allclose(np.cos(2 * np.pi * f * n / fs), np.cos(2 * np.pi * fa * n / fs), atol=1e-8)
        assert (k == 0) == (f <= fs / 2)


def test_invert_refuses_a_recording_that_matches_its_mode_only_by_alias(tmp_path):
    """The torsion (predicted 2.68 s, 0.373 Hz) recorded at 0.6 Hz shows at
    0.6 - 0.373 = 0.227 Hz: refused naming the alias, not read as a slip."""
    T = _torsion_period()
    fs = 0.6
    p = _record(tmp_path / "slow.csv", T, fs)
    r = run("invert", LIN1, "--signal", f"torsion={p}", "--json")
    assert r.exit_code == 2, (r.stdout, r.stderr)
    ls = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(ls) == 1 and ls[0].startswith("error: --signal")
    assert "alias" in ls[0] and f"{fs - 1 / T:.3g}" in ls[0]
    assert r.stdout == ""


def test_invert_warns_when_the_sample_rate_is_close_to_nyquist(tmp_path):
    """A torsion at 2.2 s (inside its physical range) recorded at 0.85 Hz
    shows at 0.85 - 1/2.2 = 0.395 Hz, also inside the range: the record
    cannot tell, so the answer comes with a plain warning."""
    fs = 0.85
    p = _record(tmp_path / "near.csv", 2.2, fs)
    r = run("invert", LIN1, "--signal", f"torsion={p}", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    fitted = doc["measurements"][0]["observed_period"]
    assert math.isclose(1 / fitted, fs - 1 / 2.2, rel_tol=1e-3)  # the alias is what was fitted
    w = [x for x in doc["warnings"] if "sample rate" in x]
    assert len(w) == 1 and "alias" in w[0] and "2.5" in w[0]
    assert "sample rate" in r.stderr


def test_invert_well_sampled_recording_has_no_alias_warning(tmp_path):
    T = _torsion_period()
    p = _record(tmp_path / "fine.csv", T, 10.0, dur=60.0)
    r = run("invert", LIN1, "--signal", f"torsion={p}", "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    assert not [x for x in doc["warnings"] if "sample rate" in x]
    assert math.isclose(doc["measurements"][0]["observed_period"], T, rel_tol=1e-4)


def test_period_notes_a_frequency_near_nyquist():
    """Sampled at 2.2 x its frequency a record is fitted right, with a note
    that fs - f gives the same samples; at 10 x there is no such note."""
    T = 1.3
    for ratio, noted in ((2.2, True), (10.0, False)):
        fs = ratio / T
        t = np.arange(0.0, 60.0, 1.0 / fs)
        y = np.cos(2 * np.pi / T * t + 0.4) + 0.01 * np.random.default_rng(2).standard_normal(t.size)
        fit = fit_period(t, y, model="viscous")
        assert abs(fit.period - T) < 5 * fit.std
        notes = [n for n in fit.notes if "Nyquist" in n]
        assert bool(notes) == noted
        if noted:
            assert f"{fs - 1 / T:.4g} Hz" in notes[0]


# ---------------------------------------------------------------------------
# quantisation: a camera's pixel step without noise to dither it
# ---------------------------------------------------------------------------

def _quantised_draws(n, fs=60.0, dur=20.0, T=1.2345, steps=20, seed=11):
    """(t, y) of a decaying oscillation of amplitude ``steps`` pixel steps,
    no noise, quantised to whole pixels about a level (an encoder zeroed at
    rest): the quantisation error is a function of the phase, not noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, dur, 1.0 / fs)
    wd = 2 * np.pi / T
    wn = wd / math.sqrt(1 - 0.005 ** 2)
    for _ in range(n):
        y = steps * np.exp(-0.005 * wn * t) * np.cos(wd * t + rng.uniform(0, 2 * np.pi))
        yield t, np.round(y)


def test_lattice_step_finds_the_pixel_step():
    from bifilar.estimation.signal_checks import lattice_step

    t, y = next(_quantised_draws(1))
    q, origin = lattice_step(0.25 * y + 3.0)
    assert math.isclose(q, 0.25, rel_tol=1e-9) and math.isclose((origin - 3.0) / 0.25, round((origin - 3.0) / 0.25))
    assert lattice_step(y + 1e-3 * np.random.default_rng(0).standard_normal(y.size)) is None


def test_quantised_record_std_covers_its_error():
    """Undithered quantisation (20 steps of amplitude, 60 fps, no noise):
    the least-squares std alone left sd(z) ~ 1.7 and 95 % coverage near
    0.75; with the re-quantised copies the std covers the error.

    Test economy, session 23: 30 draws (was 65; each full fit fits 40
    re-quantised copies, ~0.2 s of CPU) and the bounds of
    tests/test_signal_quantisation.py's ``_assert_covers`` (at least 28 of
    the 30 within 1.96 of their std, sd(z) below 1.2), whose power was
    measured on 240 further draws of the pixel case, this generator's
    records through atan(k / 500) (< 2e-5 relative from these): the right
    std fails them with P 2.5e-4; the std without its quantisation term
    (sd(z) 1.78 there) passes them with P 1.0e-4, a std 0.62 of the right
    one with 1.3e-2.  The old bounds on 65 draws (coverage >= 0.865, sd(z)
    < 1.3) passed the least-squares std with P 4.0e-3 and the std without
    its quantisation term as this tree computes the rest (coverage 0.77,
    sd(z) 1.47) with 0.035.  These 30 draws (the first 30 of the old 65,
    the same records as the pixel test's): coverage 1.00, sd(z) 0.88; with
    the serial-correlation std alone 0.70, 1.70 (``_compose_std`` taking
    the serial-correlation std, beside the split-half term: coverage 0.77,
    sd(z) 1.54, fails, checked session 23)."""
    from test_signal_quantisation import COVER_DRAWS, _assert_covers

    T = 1.2345
    z = []
    for t, y in _quantised_draws(COVER_DRAWS):
        fit = fit_period(t, y, model="viscous", crossing_check=False)
        assert fit.std_quantisation > 0 and fit.uncertainty["quantisation_test"]["step"] == 1.0
        z.append((fit.period - T) / fit.std)
    _assert_covers(np.array(z))


# ---------------------------------------------------------------------------
# heteroscedastic errors: a camera's timestamp jitter
# ---------------------------------------------------------------------------

def test_timestamp_jitter_std_covers_its_error():
    """Frames taken on a uniform clock but stamped with a jitter of 0.15
    frame: each sample errs by y'(t) dt, most at the zero crossings, where
    the frequency is measured.  The plain least-squares std assumed equal
    errors everywhere (sd of z 1.2-1.3, coverage ~0.88); the sandwich std
    covers.  300 draws of the viscous fit (~2 s)."""
    fs, T, zeta = 60.0, 1.2345, 0.005
    n = int(20 * fs)
    tn = np.arange(n) / fs
    wd = 2 * np.pi / T
    wn = wd / math.sqrt(1 - zeta ** 2)
    rng = np.random.default_rng(2)
    z = []
    for _ in range(300):
        y = np.exp(-zeta * wn * tn) * np.cos(wd * tn + rng.uniform(0, 2 * np.pi)) + 0.002 * rng.standard_normal(n)
        ts = tn + 0.15 / fs * rng.standard_normal(n)
        o = np.argsort(ts)
        fit = fit_period(ts[o], y[o], model="viscous", crossing_check=False, split_check=False)
        z.append((fit.period - T) / fit.std)
    z = np.array(z)
    cover = float(np.mean(np.abs(z) < 1.96))
    assert cover >= 0.95 - 3 * math.sqrt(0.95 * 0.05 / z.size), (cover, z.std())
    assert z.std() < 1.13, z.std()


def test_a_faster_modes_alias_near_a_resolved_mode_is_no_refusal(tmp_path):
    """drone_parallel: torsion 1.88 s (0.53 Hz) predicted, pitch 0.985 s.
    A torsion recorded at 2.3 s (0.435 Hz) at 1.4 Hz (3.2 samples per
    cycle, resolved) lies nearer the pitch's alias 1.4 - 1.015 = 0.385 Hz
    (relative to the pitch) than to any mode: a coincidence, not a refusal
    by alias."""
    cfg = CONFIGS / "drone_parallel.yaml"
    s = load_scene(cfg, warn=False)
    pitch = linear_modes(s, rest_pose(s)).get("pitch").period
    fa, k = fold(1 / pitch, 1.4)
    assert k == 1 and abs(1 / 2.3 - fa) * pitch < 0.08  # the premise: the alias is close
    p = _record(tmp_path / "drone.csv", 2.3, 1.4)
    r = run("invert", cfg, "--signal", f"torsion={p}", "--json")
    assert "alias of mode" not in r.stderr, r.stderr


# ---------------------------------------------------------------------------
# a slow swell larger than the oscillation
# ---------------------------------------------------------------------------

def test_a_slow_swell_larger_than_the_oscillation_is_not_its_period():
    """A baseline swelling through half a cycle of 60-77 s with 2-3 times
    the amplitude of a 1.3 s oscillation: the record holds 23 clear cycles,
    but the swell was the strongest periodogram bin (refused: "fewer than 2
    cycles") or the larger mode of the two-mode fit (its 77 s "period"
    refused).  Now the period is the oscillation's, within its std."""
    t = np.arange(0.0, 30.0, 0.02)
    rng = np.random.default_rng(0)
    for amp, Tw in ((2.0, 77.0), (3.0, 60.0), (2.0, 60.0)):
        y = (amp * np.cos(2 * np.pi * t / Tw + 0.5) + np.exp(-0.048 * t) * np.cos(2 * np.pi * t / 1.3 + 1)
             + 0.02 * rng.standard_normal(t.size))
        fit = fit_period(t, y, model="auto")
        assert abs(fit.period - 1.3) < 4 * fit.std, (amp, Tw, fit.period, fit.std)
