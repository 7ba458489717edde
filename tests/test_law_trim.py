"""A sweep point's amplitude laws' runs stop 10/64 of a period past the
point's own runs' last timed crossing (perf15, session 22;
``studies.point_amplitude._law_length``): each law run's crossings, so its
period, must be the bits of the same run integrated for the point's full
``periods`` -- the path it replaces -- on the Solar Boat at 0.05 and 0.3,
the thesis plate's pitch hanging, the thesis cylinder and the KTH
trifilar; a run whose shortened record cannot show that is run again in
full (``_trimmed_complete``).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.analysis.batch import simulate_batch
from bifilar.config import read_yaml
from bifilar.studies import point as pt
from bifilar.studies import point_amplitude as pa
from bifilar.studies import sweep as sw

from conftest import CONFIGS

CASES = [("solar_boat", {"spacing": 3.0}),
         ("solar_boat", {"spacing": 1.0, "length": 2.0, "amplitude": 0.3}),
         ("thesis_lin2_pitch", {}),  # a thesis plate hanging with finite sigmas (the shipped plate is a knife edge)
         ("thesis_cylinder_6_4", {}),
         ("trifilar_kth", {})]


def _law_runs_both_ways(name, params):
    """(the point's own runs, its law runs as the point makes them, the same
    runs integrated for the full ``periods``, the trimmed length)."""
    path = CONFIGS / f"{name}.yaml"
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    _, pre = pt._prepare(cfg, str(path), params, st)
    assert pre.law is not None and pre.law.starts is not None
    labels = [pre.labels[k] for k in pre.runs]
    runs = pa._runs_at(pre.law, st, own=(pre.scene, pre.rest, pre.ms, labels, pre.amplitude, pre.starts))
    own, law = runs[:len(labels)], runs[len(labels):]
    lw = pre.law
    full = simulate_batch(lw.scenes, mode=lw.labels, amplitude=lw.amplitudes, periods=st.periods, rtol=st.rtol,
                          rests=lw.rests, modes=lw.mode_sets, errors="return", starts=lw.starts, health=False)
    return own, law, full, pa._law_length(own, st.periods), st.periods


@pytest.mark.parametrize("name, params", CASES)
def test_trimmed_law_runs_time_the_crossings_of_the_full_runs(name, params):
    own, law, full, end, periods = _law_runs_both_ways(name, params)
    assert end < periods and law  # the shortcut is taken on these points (else the test compares a path with itself)
    for a, b in zip(law, full):
        assert not b.error
        assert a.period == b.period  # bit for bit
        assert np.array_equal(a.crossings, b.crossings)
        assert a.linear_period == b.linear_period


def test_law_length_past_the_last_crossing_and_on_the_sample_grid():
    r = SimpleNamespace(error=None, crossings=np.array([0.75, 1.75, 2.75]) * 2.0, period=2.0 * 1.001,
                        linear_period=2.0)
    end = pa._law_length([r], 3.0)
    assert end * pa.LAW_SAMPLES == round(end * pa.LAW_SAMPLES)  # a sample of the full grid
    assert 2.75 + pa.LAW_TAIL <= end < 2.75 + pa.LAW_TAIL + 1 / pa.LAW_SAMPLES
    soft = SimpleNamespace(error=None, crossings=r.crossings, period=2.0 * 0.98, linear_period=2.0)
    assert pa._law_length([soft], 3.0) >= 2.75 / 0.98 + pa.LAW_TAIL  # a softening factor: law runs cross later
    assert pa._law_length([r, SimpleNamespace(error="x", crossings=[], period=None, linear_period=2.0)], 3.0) == 3.0
    assert pa._law_length([r], 2.9) == 2.9  # no end before the point's own


def _run(tau, T=2.0):
    return SimpleNamespace(error=None, crossings=np.asarray(tau) * T, period=1.0, linear_period=T)


def test_trimmed_complete_refuses_what_could_hide_a_crossing():
    end = 2.75 + 10 / 64
    assert pa._trimmed_complete(_run([0.75, 1.75, 2.75]), end, 3.0)
    assert not pa._trimmed_complete(_run([0.75, 1.75, end - 3 / 64]), end, 3.0)  # stencil cut at the record's end
    assert not pa._trimmed_complete(_run([0.75]), end, 3.0)  # no period
    assert not pa._trimmed_complete(_run([0.75, 1.75, 2.1]), end, 3.0)  # irregular cycles
    assert not pa._trimmed_complete(_run([0.2, 1.2, 2.2]), end, 3.0)  # the next crossing may come by 3 periods


def test_a_law_run_cut_before_its_last_crossing_is_run_again_in_full(monkeypatch):
    monkeypatch.setattr(pa, "LAW_TAIL", -0.3)  # ends before the last crossing: every law run must be redone
    calls = []
    real = pa._trimmed_complete

    def spy(run, end, periods):
        ok = real(run, end, periods)
        calls.append(ok)
        return ok

    monkeypatch.setattr(pa, "_trimmed_complete", spy)
    own, law, full, end, periods = _law_runs_both_ways("solar_boat", {"spacing": 3.0})
    assert calls and not any(calls)
    for a, b in zip(law, full):
        assert a.period == b.period and np.array_equal(a.crossings, b.crossings)
