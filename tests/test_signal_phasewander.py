"""Frame faults the noise or the quantisation hides (design.md "dropfix3,
session 19"): the per-cycle phase of a record without its time column
against the fit's.

dropfix2's sweep left two classes answering outside their interval with no
word: drops whose single steps the noise hides (draw 1041: 1 % dropped,
2.8 s, noise 2 % of the amplitude, z -7.4) and repeats in a 3 mrad
quantised record (draw 7038, 0.3 % repeated, z +11.6).  The records here
are the sweep's draws, synthetic damped cosines at 30 fps (no simulation):
the truth is the cosine's own period.  All seeded.
"""

from __future__ import annotations

import types

import numpy as np

from bifilar.estimation.signal import fit_period
from bifilar.estimation.signal_phasewander import cycle_phase
from bifilar.estimation.signal_timebase import check_time_base

FS = 30.0


def _draw(seed, kind="clean", drop=0.0, rep=0.0):
    """dropfix's sweep (design.md "dropfix, session 17"): T 0.8-3 s, 15-50
    cycles at 30 fps, 0.1 rad decaying at up to 0.02/s, noise 0.2-3 % of
    it; ``drift+quant`` adds a drift of 0.05 and rounds to 3 mrad; a share
    ``drop`` of the frames dropped, ``rep`` written twice.  Returns
    (T s, the nominal time base s, y rad)."""
    rng = np.random.default_rng(seed)
    T = rng.uniform(0.8, 3.0)
    cyc = int(rng.uniform(15, 50))
    t = np.arange(0, cyc * T, 1 / FS)
    y = 0.1 * np.exp(-rng.uniform(0, 0.02) * t) * np.cos(2 * np.pi / T * t + rng.uniform(0, 6.28))
    y = y + rng.uniform(2e-4, 3e-3) * rng.standard_normal(t.size)
    if kind == "drift+quant":
        y = np.round((y + 0.05 * t / t[-1]) / 0.003) * 0.003
    yk = y[rng.uniform(size=t.size) >= drop]
    if rep > 0:
        yk = np.repeat(yk, 1 + (rng.uniform(size=yk.size) < rep).astype(int))
    return T, np.arange(yk.size) / FS, yk


def _answer(T, t, y):
    """(z before, the time base's check or None, z after) as `period
    --sample-rate 30` answers."""
    fit = fit_period(t, y, model="auto")
    z0 = (fit.period - T) / fit.std
    res = check_time_base(t, y, fit, "sample_rate", lambda tn, yn=y: fit_period(tn, yn, model="auto"))
    f = res["fit"] if res else fit
    return z0, res, (f.period - T) / f.std


def test_drops_the_noise_hides_widen_the_std_to_the_truth():
    """Draw 1041 (20 frames dropped in 2420, none seen one by one: 0-1 steps,
    no lattice) was answered 0.8 % short at z -7.4; its phase strays from
    the three-mode fit's by ~5 x its noise per cycle while the amplitude
    keeps to it, and the walk implies ~22 frames: the std now holds them and
    the interval reaches the truth (95 %: |z| <= 1.96).  Fails on the old
    code (no check: z -7.4)."""
    T, t, y = _draw(1041, drop=0.01)
    z0, res, z = _answer(T, t, y)
    assert z0 < -5  # the case: the nominal fit far outside its interval
    assert res is not None and res["time_base"]["method"] == "phase_walk", res and res["time_base"]
    assert abs(z) <= 1.96, z
    assert res["time_base"]["phase_chi2"] > 3 * max(res["time_base"]["amplitude_chi2"], 1)
    assert "give the time column" in res["warning"] and "\n" not in res["warning"]


def test_repeats_the_quantisation_hides_widen_the_std_to_the_truth():
    """Draw 7038: a 3 mrad quantised record (0.9 mrad noise, a drift) with
    two frames written twice, which the pair test cannot tell from the
    chance equalities of a quantised record: 0.23 % long, z +11.6.  The
    phase strays back (58 x its noise's chi^2 per cycle, the amplitude's
    ~1.3): the std widened, the interval reaches the truth.  Fails on the
    old code (no check)."""
    T, t, y = _draw(7038, "drift+quant", rep=0.003)
    z0, res, z = _answer(T, t, y)
    assert z0 > 5
    assert res is not None and res["time_base"]["method"] == "phase_walk", res and res["time_base"]
    assert abs(z) <= 1.96, z


def test_records_without_faults_are_left_alone():
    """A clean record and a quantised one of the same sweep (4000, 7001
    without repeats: phase chi^2 per cycle ~1) get no time-base check."""
    for seed, kind in ((4000, "clean"), (7001, "drift+quant")):
        T, t, y = _draw(seed, kind)
        _, res, _ = _answer(T, t, y)
        assert res is None, (seed, res and res["time_base"])


def _stub_fit(A, w, t):
    """A PeriodFit stand-in whose model curve is ``A cos(w t)`` (rad) over
    ``t``: what cycle_phase reads of a fit."""
    return types.SimpleNamespace(model="viscous", _kind="stub", t0=float(t[0]), t1=float(t[-1]),
                                 frequency=w / (2 * np.pi), predict=lambda tt: A * np.cos(w * np.asarray(tt)))


def test_cycle_phase_splits_phase_from_amplitude_as_predicted():
    """Against a known curve ``A cos(w t)``: a record whose phase is
    modulated by ``eps sin(2 pi t / Tm)`` (Tm = 10 cycles) and one whose
    amplitude is by the same share.  Per cycle the misfit is ``eps sin``
    across (PM) or along (AM) the curve, so its chi^2 is the noise's ``K``
    plus ``sum (eps sin)^2 / var`` with ``var = 2 sigma^2 / (A^2 W)``
    (``W`` samples a cycle); the other component keeps ``K``.  Tolerance
    20 %: chi^2's own scatter (``sqrt(2 K)`` plus the cross term, ~8 % of
    the signal's share here) and the white noise read from third
    differences (~2 %)."""
    rng = np.random.default_rng(7)
    A, T, sig, eps = 0.1, 1.5, 2e-3, 0.03
    W = int(T * FS)
    K = 40
    t = np.arange(K * W) / FS
    w = 2 * np.pi / T
    mod = eps * np.sin(2 * np.pi * t / (10 * T))
    fit = _stub_fit(A, w, t)
    # the expected signal chi^2: eps sin at each cycle's centre, over var
    tc = (np.arange(K) + 0.5) * T
    sig_share = float(np.sum((eps * np.sin(2 * np.pi * tc / (10 * T))) ** 2)) * A * A * W / (2 * sig * sig)
    pm = cycle_phase(t, A * np.cos(w * t + mod) + sig * rng.standard_normal(t.size), fit)
    am = cycle_phase(t, A * (1 + mod) * np.cos(w * t) + sig * rng.standard_normal(t.size), fit)
    assert pm["cycles"] == am["cycles"] == K
    assert abs(pm["chi2"] - (K + sig_share)) < 0.2 * sig_share
    assert abs(am["chi2_amplitude"] - (K + sig_share)) < 0.2 * sig_share
    # the other component: the noise's chi^2 alone, K within 4 sqrt(2 K)
    assert abs(pm["chi2_amplitude"] - K) < 4 * np.sqrt(2 * K)
    assert abs(am["chi2"] - K) < 4 * np.sqrt(2 * K)
