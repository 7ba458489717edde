"""A one-scene LSODA run's progress ticks come from inside the compiled
kernel (``compiled_kernel(..., ticks=)``, session 12), not from a wrapper
around it: the wrapper's extra Python call per right-hand side cost 3.6 %
of ``bifilar simulate``'s run (the CLI always passes a progress callback:
a bar on a terminal, the stop check elsewhere).  The ticks and the numbers
are those the wrapper gave."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bifilar import integrators as itg
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.models import maximal as mx

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def plate():
    return load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")


def test_one_scene_run_ticks_without_a_wrapper(plate, monkeypatch):
    """``simulate`` (the CLI's engine) with a progress callback integrates
    the ticking kernel: no ``with_progress`` wrapper (the old code wrapped
    the kernel: this test fails there), a tick per 1 % of the run as
    before, and the same run as without a callback, bit for bit."""
    plain = simulate(plate, "torsion", 0.05, 20, rtol=1e-9, method="auto")

    def no_wrapper(*a, **k):
        raise AssertionError("the one-scene run wrapped its kernel for progress")

    monkeypatch.setattr(itg, "with_progress", no_wrapper)
    calls = []
    res = simulate(plate, "torsion", 0.05, 20, rtol=1e-9, method="auto",
                   progress=lambda done, total: calls.append(done / total))
    assert res.period == plain.period and np.array_equal(res.y, plain.y) and res.nfev == plain.nfev
    fr = np.array(calls)
    # ticks at t >= 0, 1 %, 2 %, ... of the run (the integrator's own times, so each a little past its mark:
    # the last may pass the end, LSODA steps beyond it), then the window's final 1.0: ~101 calls
    assert 95 <= len(fr) <= 110 and fr[-1] == 1.0 and np.all(np.diff(fr[:-1]) > 0)
    assert np.max(np.abs(np.diff(fr))) < 0.05


def test_ticking_kernel_same_bits_and_schedule(plate):
    """The ticking kernel returns what the plain one does and calls ``tick``
    exactly when the wrapper would (``t >= at[0]``, then ``at[0]`` moves
    on by the step)."""
    P = mx.params_from_scenes(plate)
    plain = mx.compiled_kernel(P, signature="odeint")
    seen_new, seen_old = [], []
    ticking = mx.compiled_kernel(P, signature="odeint", ticks=itg.ticker(10.0, lambda t, te: seen_new.append(t), 0.1))
    wrapped = itg.with_progress(plain, 10.0, lambda t, te: seen_old.append(t), 0.1, time_first=False)
    rng = np.random.default_rng(3)
    ts = np.sort(rng.uniform(0, 10, 60))
    for t in ts:
        y = rng.normal(size=13)
        y[3] += 1.0
        a = np.array(ticking(y, float(t)))
        b = np.array(wrapped(y, float(t)))
        assert a.tobytes() == b.tobytes()
    assert seen_new == seen_old and 5 <= len(seen_new) <= 11
    with pytest.raises(ValueError):
        mx.compiled_kernel(P, ticks=itg.ticker(1.0, print))
