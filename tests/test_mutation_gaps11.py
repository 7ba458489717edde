"""Mutation round 11 (docs/mutation.md, "Round 11"): tests that fail on a
mutant of session 10's code, or of round 10's three gaps, that the suite
let through.  Each states the truth it checks (an analytic result, an
independent formulation or the documented rule on a record built for it);
none reads its expected value off the code under test.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

# ---------------------------------------------------------------------------
# signal_law.py: the law's own split check
# ---------------------------------------------------------------------------

ST_T0, ST_C, ST_A0, ST_Q, ST_CYCLES, ST_FS = 1.3, 1 / 16, 0.5, 40.0, 40, 30.0


def _chirp_with_step(step: float, noise: float = 1e-5, seed: int = 1):
    """A decaying record (rad) of ``T = T0 (1 + c A^2)`` to A^4 (the frequency ``w0 (1 - c A^2 + c^2 A^4)``,
    A = A0 exp(-sigma t), Q = 40, 40 cycles at 30 Hz, phase integrated in closed form) whose frequency
    also steps up by ``step`` w0 at mid-record, phase continuous (a rig that changes once, in time: no
    amplitude explains it); white noise of ``noise`` A0."""
    rng = np.random.default_rng(seed)
    w0 = 2 * math.pi / ST_T0
    sg = w0 / (2 * ST_Q)
    t = np.arange(0.0, ST_CYCLES * ST_T0, 1 / ST_FS)
    L = t[-1]

    def E(k):
        return (1 - np.exp(-k * t)) / k

    ph = w0 * t - w0 * ST_C * ST_A0**2 * E(2 * sg) + w0 * ST_C**2 * ST_A0**4 * E(4 * sg) + 0.3
    ph = ph + step * w0 * np.maximum(t - L / 2, 0.0)
    return t, ST_A0 * np.exp(-sg * t) * np.cos(ph) + noise * ST_A0 * rng.standard_normal(t.size)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_law_whose_own_halves_still_disagree_is_not_used(seed):
    # _amplitude_law's rule: the law replaces the viscous fit only when its own split check (each half
    # with the law held at the whole record's beta, referred to one amplitude) finds no disagreement
    # beyond noise; "a drift the law cannot explain (a period that changes with time, not with the
    # amplitude) keeps the viscous fit and its between-half std".  The record: a pendulum's law (d/c^2 =
    # 0, inside the A^4 band) plus a frequency step of 3e-6 at mid-record, ~50x the halves' std (4e-8 of
    # the period each at 1e-5 noise).  The whole record's law absorbs most of a step (at Q = 100 all but
    # ~3 %, so the halves agreed), at Q = 40 not: it still passes every earlier check (BIC lower, beta
    # resolved, the A^4 ratio ~1), and its halves disagree, so the law is refused for that reason alone.
    # Without the step the same record's law is used (the refusal is the step's)
    from bifilar.estimation.signal import AMPLITUDE_LAW_MODEL, fit_period

    t, y = _chirp_with_step(0.0, seed=seed)
    clean = fit_period(t, y, model="auto")
    assert clean.amplitude_law["used"] and clean.model == AMPLITUDE_LAW_MODEL, clean.amplitude_law["reason"]

    t, y = _chirp_with_step(3e-6, seed=seed)
    fit = fit_period(t, y, model="auto")
    law = fit.amplitude_law
    # the earlier checks pass
    assert law["criterion_delta"] < 0 and abs(law["beta"]) >= 3 * law["beta_std"]
    assert law["curvature_ratio"] == pytest.approx(1.0, abs=0.2)
    # its halves, referred to one amplitude, differ by more than their noise: chi^2 with one dof
    (T1, s1), (T2, s2) = law["halves"]
    assert abs(T1 - T2) > 5 * math.hypot(s1, s2)
    assert law["Q"] > law["critical_Q"]
    assert not law["used"] and "halves still disagree" in law["reason"]
    assert fit.model != AMPLITUDE_LAW_MODEL and fit.std_nonstationary > 0


# ---------------------------------------------------------------------------
# point_amplitude.py: a failed law run, a point without a sigma
# ---------------------------------------------------------------------------

def _law_point(monkeypatch, law_runs=None, budget=None):
    """The Solar Boat at spacing 2.5, length 2, Izz from torsion at 0.3 rad (tests/test_planner_amplitude.py),
    its amplitude law's runs (the half-amplitude run, then the stepped scene's) passed through
    ``law_runs`` and its small-amplitude budgets through ``budget``."""
    import bifilar.studies.point as point
    import bifilar.studies.point_amplitude as pa
    from test_planner_amplitude import SOLAR, _point

    real_runs, real_stated = point._runs_at, point._stated_amplitude

    def runs_at(law, st, own=None):
        runs = real_runs(law, st, own)
        n = len(runs) - len(law.scenes)
        return runs[:n] + (law_runs(runs[n:]) if law_runs else runs[n:])

    def stated(res, pre, sims, st):
        if budget:
            pre.budgets = {c: budget(b) for c, b in pre.budgets.items()}
        return real_stated(res, pre, sims, st)

    monkeypatch.setattr(point, "_runs_at", runs_at)
    monkeypatch.setattr(pa, "_runs_at", runs_at)
    monkeypatch.setattr(point, "_stated_amplitude", stated)
    return _point(SOLAR, {"spacing": 2.5, "length": 2.0}, components=["Izz"], amplitude=0.3)


def _broken(which: int, error: bool):
    """The law run ``which`` (0 the half-amplitude run, 1 the stepped scene's) failed: with an error
    (its period kept: a run that errs is failed whatever it timed) or without a period (no error)."""
    def f(runs):
        assert len(runs) == 2
        runs = list(runs)
        runs[which] = replace(runs[which], error="broken on purpose") if error else replace(runs[which], period=None)
        return runs
    return f


@pytest.mark.parametrize("which, error", [(0, True), (1, True), (0, False), (1, False)])
def test_a_failed_law_run_leaves_the_small_amplitude_sigma_and_says_so(monkeypatch, which, error):
    # _amplitude_laws: "a component whose runs fail is left out (its sigma then says so)": a run with an
    # error, or without a period, is failed (each of the guard's four terms on its own).  The sigma is then
    # invert's at --amplitude 0 (an independent call), amplitude_budget says budgeted false and why
    from test_planner_amplitude import _invert

    st, scene, p = _law_point(monkeypatch, law_runs=_broken(which, error))
    e = p["components"]["Izz"]
    ab = e["amplitude_budget"]
    assert ab["budgeted"] is False and ab["contribution"] is None
    assert "amplitude law's runs failed" in ab["note"] and "--amplitude 0" in ab["note"]
    assert ab["period_factor"] > 1.01  # the point's own run did run: only the law's failed
    small = _invert(scene, e["mode"], e["period"], "Izz", st.unc, 0.0)
    assert e["sigma"] == pytest.approx(small.sigma("Izz"), rel=1e-6)
    assert ab["sigma_small_amplitude"] == e["sigma"]


def test_a_point_with_a_law_but_no_sigma_says_no_sigma(monkeypatch):
    # _stated_amplitude: a component whose small-amplitude std is undefined gets no amplitude budget even
    # when its law ran (the budget of an undefined std is undefined): note "no sigma", budgeted false
    st, scene, p = _law_point(monkeypatch, budget=lambda b: replace(b, value_sigma=float("nan")))
    ab = p["components"]["Izz"]["amplitude_budget"]
    assert ab["period_factor"] > 1.01
    assert ab["budgeted"] is False and ab["note"] == "no sigma" and ab["sigma_small_amplitude"] is None
    # the same point with its sigma is budgeted: the law did run
    monkeypatch.undo()
    st, scene, p = _law_point(monkeypatch)
    assert p["components"]["Izz"]["amplitude_budget"]["budgeted"] is True
