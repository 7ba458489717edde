"""Session 13, simhealth: the session-12 audit's forward-model health items
(docs/design.md, "simhealth, session 13").  Each test failed on the code
before its fix."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from bifilar.analysis import run_accuracy as ra
from bifilar.analysis import simulate as sm
from bifilar.cli import main
from bifilar.config import scene_from_dict
from conftest import one_error_line, trapezoid


# ---------------------------------------------------------------------------
# 1. the crossings' interpolation error that could not be estimated
# ---------------------------------------------------------------------------

def test_an_unestimated_crossing_error_is_not_counted_as_zero():
    """crossing_period_error gives NaN on a record of fewer than 9 samples
    (here 8 samples of sin(2 pi (t - 0.1)) over 1.75 s: two upward
    crossings, 0.1 and 1.1 s, and no room for two degree-7 stencils);
    period_accuracy counted that NaN as 0 and stated the integrator's
    part alone (3e-10 s) as the bound.  It is now not established: NaN and a
    warning naming --periods."""
    t = np.linspace(0.0, 1.75, 8)
    c = np.sin(2 * np.pi * (t - 0.1))
    assert math.isnan(ra.crossing_period_error(t, c, [0.1, 1.1]))
    err, w = ra.period_accuracy(1.0, "auto", 1e-10, 0.05, 3, 1.0, linear_period=1.0, crossing=float("nan"))
    assert math.isnan(err)
    assert w is not None and "not established" in w and "--periods" in w
    # a finite estimate is still added to the rest (15 x rtol x period for auto, plus the crossings' part)
    err, w = ra.period_accuracy(1.0, "auto", 1e-10, 0.05, 3, 1.0, linear_period=1.0, crossing=2e-12)
    assert err == pytest.approx(15e-10 + 2e-12, rel=1e-12) and w is None


def test_the_auto_engine_reports_an_unestimated_period_error_as_null(monkeypatch):
    """The auto engine's run whose crossing estimate stays NaN: it is taken
    again with more samples up to MAX_SAMPLES_PER_PERIOD (64, 256, 1024),
    then its period_error is null in the JSON with the warning; the old
    code stopped at once and stated the error model's bound alone."""
    calls = []

    def nan_estimate(t, c, tc):
        calls.append(len(t))
        return float("nan")

    monkeypatch.setattr(sm, "crossing_period_error", nan_estimate)
    sc = trapezoid(b=0.4, bp=0.4, l1=1.0, inertia=[0.05, 0.06, 0.08], mass=2.0)
    r = sm.simulate(sc, "torsion", 0.05, 3, method="auto")
    assert r.period is not None and math.isnan(r.period_error)
    doc = r.to_json()
    assert doc["period_error"] is None and doc["period_error_crossings"] is None
    assert sum("not established" in w and "--periods" in w for w in r.warnings) == 1
    assert len(calls) == 3 and calls[-1] > 15 * calls[0]  # 64 -> 256 -> 1024 samples a period
