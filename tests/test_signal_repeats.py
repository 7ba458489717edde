"""Repeated frames in a record without its time column (design.md
"dropfix2, session 18"; mut16's finding: six repeats in 30 cycles left the
period long beyond its std and no warning).

A camera writing a frame twice leaves a sample duplicated and every later
sample one frame late on the nominal time base of ``--sample-rate``: the
period comes out long by the repeats' share.  The records here are
synthetic damped cosines at 30 fps (no simulation): the truth is the
cosine's own period, the repeats' places are known.  All seeded.
"""

from __future__ import annotations

import json

import numpy as np
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.estimation.signal_repeats import repeated_samples, resolution

FS = 30.0
T = 1.7


def _record(seed=0, cycles=30, repeats=6, period=T):
    """(y as written, the indices of the repeated samples in it): a 0.05
    rad cosine of ``period`` (s) decaying slowly, 0.5 mrad noise, at 30 fps,
    ``repeats`` frames (drawn at random) written twice."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, cycles * period, 1.0 / FS)
    y = 0.05 * np.exp(-0.003 * t) * np.cos(2 * np.pi / period * t + 0.4) + 5e-4 * rng.standard_normal(t.size)
    frames = np.sort(rng.choice(np.arange(10, t.size - 10), repeats, replace=False))
    cnt = np.zeros(t.size, int)
    cnt[frames] = 1
    # frame k written twice: its copy sits right after it, at k + (repeats before it) + 1
    return np.repeat(y, 1 + cnt), frames + np.arange(repeats) + 1


def test_each_repeat_is_found_where_it_was_put_and_none_elsewhere():
    """The six duplicated samples are found at their places (a float
    record's exact equality cannot be chance); the same record without
    them, and a quantised record with its many chance equalities (3 mrad
    steps, 2.3 mrad noise: the slow stretches repeat values by nature, and
    a pair counts only where the motion a frame is far beyond both), show
    none.  Independent of any fit."""
    y, where = _record(seed=4)
    idx, blind = repeated_samples(y)
    assert idx.tolist() == where.tolist() and blind == 0.0
    y0 = np.delete(y, where)
    assert repeated_samples(y0)[0].size == 0
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 49 * 2.885, 1.0 / FS)
    yq = 0.1 * np.exp(-0.006 * t) * np.cos(2 * np.pi / 2.885 * t + 0.3) + 0.0023 * rng.standard_normal(t.size)
    yq = np.round((yq + 0.05 * t / t[-1]) / 0.003) * 0.003
    assert abs(resolution(yq) - 0.003) < 1e-9
    assert int(np.sum(np.diff(yq) == 0)) > 100  # chance equalities aplenty
    assert repeated_samples(yq)[0].size == 0


def test_period_removes_repeated_frames_without_a_time_column(tmp_path):
    """mut16's case: six frames written twice in 30 cycles, read at
    --sample-rate 30.  On the nominal time base the period is long by about
    6 frames over the record (0.4 %), far beyond its std (the old answer,
    exit 0, no warning); now the repeats are removed and the answer is the
    fit of the samples left: within 2.5 of its std of the cosine's period
    (the 96 repeated-frame draws of design.md's table: |z| <= 2.2), the
    JSON saying so.  Fails on the old code (the period 1.70820 s, 0.48 % long, z +25, no
    ``time_base``)."""
    y, where = _record(seed=4)
    p = tmp_path / "rep.csv"
    np.savetxt(p, y[:, None], header="angle", comments="")
    r = CliRunner().invoke(main, ["period", str(p), "--sample-rate", "30", "--json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    tb = doc["signal"]["time_base"]
    assert tb is not None and tb["method"] == "repeats_removed" and tb["repeated_frames"] == 6, tb
    assert abs(doc["period"] - T) < 2.5 * doc["std"], (doc["period"], doc["std"])
    # the nominal fit: long by the repeats' share (6 frames of ~1530), the harm removed
    assert 0.002 * T < tb["nominal_period"] - T < 0.006 * T
    w = [x for x in doc["warnings"] if "repeated frames" in x]
    assert len(w) == 1 and "removed" in w[0] and "time column" in w[0] and "\n" not in w[0]


def test_invert_signal_removes_repeated_frames(tmp_path):
    """``invert --signal``'s period of a record with repeats is the one
    fitted on the samples left (old code: the nominal one, 0.4 % long)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import load_scene

    from conftest import CONFIGS

    lin1 = CONFIGS / "thesis_lin1_torsion.yaml"
    s = load_scene(lin1, warn=False)
    Tm = linear_modes(s, rest_pose(s)).get("torsion").period
    y, _ = _record(seed=9, cycles=25, period=Tm)
    p = tmp_path / "tors.csv"
    np.savetxt(p, y[:, None], header="angle", comments="")
    r = CliRunner().invoke(main, ["invert", str(lin1), "--signal", f"torsion={p}", "--sample-rate", "30", "--json"])
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    m = doc["measurements"][0]
    assert m["signal"]["time_base"]["method"] == "repeats_removed"
    assert abs(m["period"] - Tm) < 2.5 * m["std"], (m["period"], m["std"], Tm)
    assert [x for x in doc["warnings"] if x.startswith("mode 'torsion'") and "repeated frames" in x]


def test_a_strongly_growing_fitted_mode_ranks_without_overflow():
    """A multi-mode fit's mode ranking (``signal_models._mode_rank``) of a
    mode growing by hundreds of e-folds over the record (met by a two-mode
    refit on a recovered time base: OverflowError, a traceback) ranks it
    by the capped growth, larger than a steady mode of the same amplitude.
    Fails on the old code (math range error)."""
    from bifilar.estimation.signal_models import _mode_rank

    grow = _mode_rank(6.0, 1.0, 10.0, -100.0)  # 2 sigma T = -2000
    steady = _mode_rank(6.0, 1.0, 10.0, 0.0)
    assert grow[1] < steady[1] < 0


def test_drops_left_after_the_repeats_are_removed_are_still_refused(tmp_path):
    """Frames dropped (1 %, 16) and repeated (0.3 %, 6) in one record of
    2.68 s: the repeats are removed, and the drops left hide
    their steps in the noise (no lattice; the phase steps forward 3 times,
    never back) with the fit leaving 1.15-1.2 x the record's noise, so the
    answer is refused, asking for the time column (the harness's draw
    17002; old code: exit 0, the period 1.2 % short, z -16, no word; two
    repeats in draw 17004 had lowered its excess from 1.215 to 1.176 below
    the old 1.2, hence ``MIN_RESIDUAL_EXCESS`` 1.15, which changed none of
    the 196 drop, beat and chirp records of design.md's table)."""
    rng = np.random.default_rng(17002)
    Tt = rng.uniform(0.8, 3.0)
    t = np.arange(0, int(rng.uniform(15, 50)) * Tt, 1 / FS)
    y = 0.1 * np.exp(-rng.uniform(0, 0.02) * t) * np.cos(2 * np.pi / Tt * t + rng.uniform(0, 6.28))
    y = y + rng.uniform(2e-4, 3e-3) * rng.standard_normal(t.size)
    y = y[rng.uniform(size=t.size) >= 0.01]
    y = np.repeat(y, 1 + (rng.uniform(size=y.size) < 0.003))
    assert repeated_samples(y)[0].size == 6
    p = tmp_path / "both.csv"
    np.savetxt(p, y[:, None], header="angle", comments="")
    r = CliRunner().invoke(main, ["period", str(p), "--sample-rate", "30", "--json"])
    assert r.exit_code == 2 and r.stdout == "", (r.exit_code, r.stdout[:300])
    line = r.stderr.strip()
    assert "\n" not in line and "dropped frames" in line and "--sample-rate" in line and "time column" in line
