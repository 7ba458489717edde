"""The per-call memo of invert's amplitude runs (docs/design.md "invfast,
session 23") gives what the runs it replaces give.

:func:`bifilar.estimation.invert.invert` is wrapped by
:func:`bifilar.estimation.amplitude_runs.per_call_runs`: within one call an
amplitude run (:func:`amplitude_factor`) whose inputs are the same, bit for
bit, is made once.  Checked here against the path it replaces
(``invert.__wrapped__``, every run made): the same result, field for field,
on a thin plate timed just beyond the physical set's edge at an unstated
amplitude (the budget, the fit check and the edge roots each ask for the
unstated release's law at the estimate: 14 runs of 4 distinct inputs at its roots); the memoised call makes each of the full path's
distinct runs exactly once and no other.  And the memo's own
rules: a copy per caller, a key that tells one ulp of the amplitude apart,
a checked run (``timing``) told from an unchecked one, nothing outside a
call.
"""

from __future__ import annotations

import pickle
from collections import Counter
from dataclasses import replace

import numpy as np
import bifilar.analysis.simulate as simulate_module
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.estimation import amplitude_runs
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.problem import HangingModel
from bifilar.scene import TRIANGLE_SLACK

from conftest import PLATE_I, trapezoid


def _plate_beyond_edge():
    """The thin plate (Izz = Ixx + Iyy) with its torsion timed 3e-4 s (3
    stds) longer than at the physical set's edge, amplitude unstated: answered
    at the edge within the default input uncertainties (test_invert_roots)."""
    truth = trapezoid(h=0.5)
    I = truth.inertia.copy()
    I[2, 2] = (PLATE_I[0] + PLATE_I[1]) / (1 - TRIANGLE_SLACK)
    at_edge = replace(truth, inertia=I)
    T = linear_modes(at_edge, rest_pose(at_edge)).get("torsion").period
    return MeasurementSet([Hanging("h", truth, np.eye(3))],
                          [Measurement("torsion", float(T + 3e-4), 1e-4, "period", "--period")])


def _counted(monkeypatch):
    """Counter of the runs made ({pickled inputs: times}), filled by a wrapper of simulate's one run."""
    runs: Counter = Counter()
    once = simulate_module._simulate_once

    def counting(scene, mode, amplitude, periods, **kw):
        inputs = {k: v for k, v in kw.items() if k != "progress"}
        runs[pickle.dumps((scene, mode, amplitude, periods, inputs))] += 1
        return once(scene, mode, amplitude, periods, **kw)

    monkeypatch.setattr(simulate_module, "_simulate_once", counting)
    return runs


def _answer(res) -> dict:
    d = res.to_json()
    d.pop("runtime_s", None)
    return d


def test_memoised_invert_returns_the_full_paths_answer_with_each_run_made_once(monkeypatch):
    ms = _plate_beyond_edge()
    runs = _counted(monkeypatch)
    full = _answer(invert.__wrapped__(ms, solve_for=["Izz"], ladder=False))
    full_runs = Counter(runs)
    runs.clear()
    fast = _answer(invert(ms, solve_for=["Izz"], ladder=False))
    assert fast == full  # every field, floats compared exactly
    assert full["roots"][0]["edge"]  # the case: answered at the edge, where the fit check and the roots ask
    # the full path repeats runs (the case the memo is for), the memo makes each of them once, none other
    assert max(full_runs.values()) > 1, full_runs.values()
    assert set(runs) == set(full_runs) and max(runs.values()) == 1, runs.values()


def test_the_memo_hands_out_copies_tells_one_ulp_apart_and_ends_with_the_call():
    hm = HangingModel(Hanging("h", trapezoid(h=0.5), np.eye(3)), np.diag(PLATE_I))
    k = hm.modes0.modes.index(hm.modes0.get("torsion"))
    A = 0.1

    def factor(a=A):
        return amplitude_runs.amplitude_factor(hm, {}, k, a, 3.0)

    calls = []

    @amplitude_runs.per_call_runs
    def one_call():
        r1, s1 = factor()
        s1.warnings.append("edited by the first caller")
        r2, s2 = factor()
        r3, _ = factor(np.nextafter(A, 1.0))
        calls.append(len(amplitude_runs._RUNS.get()))
        amplitude_runs.amplitude_factor(hm, {}, k, A, 3.0, timing=1e-3)  # a checked run is another input
        calls.append(len(amplitude_runs._RUNS.get()))
        return (r1, s1), (r2, s2), r3

    (r1, s1), (r2, s2), r3 = one_call()
    assert r2 == r1 and s2 is not s1 and "edited by the first caller" not in s2.warnings
    assert np.array_equal(s2.y, s1.y) and s2.period == s1.period
    assert calls == [2, 3]  # A and its next float: two runs kept, the repeat served; the checked one a third
    assert amplitude_runs._RUNS.get() is None  # the memo ended with the call
    r4, _ = factor()  # outside a call: run again, the same number
    assert r4 == r1


def test_a_function_in_the_inputs_is_told_by_its_identity_and_the_unpicklable_run_every_time():
    # a scene's support is a closure pickle cannot write: the same function is the same input, another
    # function (even one that computes the same) is another; inputs pickle cannot write (a lock) run every time
    import threading

    n = []

    def support_a(d):
        return d

    def support_b(d):
        return d

    @amplitude_runs.per_call_runs
    def one_call():
        for f in (support_a, support_a, support_b, support_a):
            amplitude_runs._remembered((f, 1.0), lambda: n.append(1) or len(n))
        lock = threading.Lock()
        for _ in range(2):
            amplitude_runs._remembered((lock,), lambda: n.append(1) or len(n))

    one_call()
    assert len(n) == 2 + 2
