"""Coverage of the 95 % intervals of ``invert``: synthetic experiments with a
known truth, every measured input off by a normal error of the size written
HERE (not read from DEFAULT_UNCERTAINTY, so a changed default is caught), the
"measured" period from the batched engine (:mod:`bifilar.analysis.batch`,
the truth's exact linear period, or its nonlinear run at a random release
amplitude), each experiment re-estimated with the batched solver
(:func:`bifilar.estimation.montecarlo.solve_draws_batched`), and the interval
``invert`` states for the nominal experiment (its half-widths) checked for
covering the truth.  The half-widths vary by far less than the spread
between experiments, except for the wheel, whose truth sits at the extremum
of the response: there the measured inputs spread about the truth and the
error's skew is the reverse of the nominal model's, which the second-order
interval is symmetrised against (docs/invert.md, "The 95 % interval").

Two-sided: with N = 400 experiments the binomial std of a true 95 % coverage
is 1.09 %, so 95 +- 2.2 % is a 2-sigma band (a correct budget passes it for
95 % of seeds; the seeds are fixed).  A std 15 % too small gives 91.2 %, 15 %
too large 97.6 %: both fail.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from conftest import measured_scene, trapezoid

from bifilar.analysis.batch import modes_batch, rest_poses, simulate_batch
from bifilar.config import scene_from_dict
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.montecarlo import solve_draws_batched

#: the stated standard uncertainties of the experiments (docs/invert.md's table)
UNC = {"length": 1e-3, "position": 1e-3, "mass": 1e-3, "com": 2e-3, "gravity": 0.0, "timing": 1e-3}
N = 400
LOW, HIGH = 0.928, 0.972


def _one(scene, T, std, amplitude):
    return MeasurementSet([Hanging("ref", scene, np.eye(3))],
                          [Measurement("torsion", float(T), std, "period", "--period", amplitude=amplitude)])


#: ten times finer inputs, so that an unstated amplitude dominates the budget
UNC_FINE = {k: v / 10 for k, v in UNC.items()}


def _truth_period(truth, amplitudes=None):
    """The truth's linear torsion period (batched engine), or its nonlinear
    periods at ``amplitudes`` (rad; batched nonlinear runs, 4 cycles)."""
    r = rest_poses([truth])[0]
    ms = modes_batch([truth], [r])[0]
    T0 = ms.get("torsion").period
    if amplitudes is None:
        return T0
    runs = simulate_batch([truth] * len(amplitudes), "torsion", list(amplitudes), 4.0, rtol=1e-9)
    return np.array([run.period for run in runs])


def _coverage(truth, comp, seed, amplitude=0.0, amp_range=None, unc=UNC):
    rng = np.random.default_rng(seed)
    if amp_range is None:
        T_true = np.full(N, _truth_period(truth))
    else:
        # release amplitudes uniform in the range invert assumes when none is given
        T_true = _truth_period(truth, rng.uniform(0.0, amp_range, N))
    i, j = {"Izz": (2, 2)}[comp]
    I_true = truth.inertia[i, j]
    # the nominal experiment: what invert states for it
    res = invert(_one(truth, T_true.mean() if amp_range else T_true[0], unc["timing"], amplitude),
                 solve_for=[comp], unc=unc, ladder=False)
    # uncut: the cut at the physical limit does not carry over between experiments and never
    # changes whether the truth is covered (tests/test_limits_cases.py)
    lo, hi = res.interval_unclipped[0] - res.value(comp)
    draws = [_one(measured_scene(truth, rng, unc), T + rng.normal(0, unc["timing"]), unc["timing"], amplitude)
             for T in T_true]
    est = solve_draws_batched(res, draws)[:, 0]
    ok = np.isfinite(est)
    assert ok.mean() > 0.99
    err = I_true - est[ok]
    return float(np.mean((err >= lo) & (err <= hi))), res


def lab_plate(drop=0.05):
    # a 5 kg plate on 1.5 m vertical wires attached 0.3 m apart, CoM `drop` below
    return trapezoid(b=0.30, bp=0.30, l1=1.5, h=drop, inertia=(0.070, 0.040, 0.105), mass=5.0)


def wheel(depth=0.02):
    # the 3 kg wheel: CoM `depth` below the attachments
    return scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.11, 0.11, 0.20]}},
                            "rig": {"anchors": [[-0.3, 0, 1.5 + depth], [0.3, 0, 1.5 + depth]],
                                    "attachments": [[-0.3, 0, depth], [0.3, 0, depth]],
                                    "lengths": [1.5, 1.5]}}, "wheel", warn=False)


def full_tensor():
    # a body with products of inertia on a trifilar-like two-wire rig, CoM 60 mm down
    s = lab_plate(drop=0.06)
    I = np.array([[0.070, 0.004, -0.003], [0.004, 0.045, 0.002], [-0.003, 0.002, 0.105]])
    return replace(s, inertia=I)


def test_coverage_symmetric_plate():
    cov, _ = _coverage(lab_plate(), "Izz", 20240601)
    assert LOW <= cov <= HIGH, cov


@pytest.mark.slow
def test_coverage_full_tensor_body():
    cov, _ = _coverage(full_tensor(), "Izz", 7)
    assert LOW <= cov <= HIGH, cov


@pytest.mark.slow
def test_coverage_shallow_com_wheel():
    # CoM 20 mm below the attachments: a sideways CoM error tilts the wheel,
    # a second-order effect (the linear budget covered ~70 %; per-input sigma
    # points alone 90.5-95 % over seeds, short of the interactions: sideways
    # CoM x attachment y, and the depth's own error, ~y^2 dz and y^2 dz^2)
    cov, res = _coverage(wheel(0.02), "Izz", 11)
    assert any("not linear" in w for w in res.warnings)
    assert LOW <= cov <= HIGH, cov


@pytest.mark.slow
def test_coverage_unstated_amplitude():
    # periods timed at release amplitudes uniform in 0-10 degrees, no --amplitude
    # (inputs ten times finer, so the amplitude dominates the budget)
    cov, res = _coverage(lab_plate(), "Izz", 5, amplitude=None, amp_range=math.radians(10.0), unc=UNC_FINE)
    assert any("no amplitude given" in w for w in res.warnings)
    assert LOW <= cov <= HIGH, cov
    # the test can fail: stating a small amplitude (no systematic term) undercovers
    cov0, _ = _coverage(lab_plate(), "Izz", 5, amplitude=0.0, amp_range=math.radians(10.0), unc=UNC_FINE)
    assert cov0 < 0.85, cov0
