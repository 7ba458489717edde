"""A body that passes validation but makes the equations stiff: a thin rod
(principal moments [1e-9, 1, 1]) whose roll mode is ~1e4-1e5 times faster than
its swings.  Its linear modes are checked against closed forms, and a run
too long for its cost is refused after a short probe (bounded number of
right-hand-side evaluations, not wall time)."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.batch import rest_and_modes
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import scene_from_dict
from bifilar.models import maximal as mx

G = 9.81


def rod(mass=1.0, L=1.5, h=0.1, d=0.5, I_roll=1e-9):
    """Rod along x (roll inertia ``I_roll``, 1 kg m^2 about y and z) on two
    vertical wires ``L`` long, attached ``d`` either side of the CoM and ``h`` above it."""
    return scene_from_dict({
        "gravity": G,
        "body": {"mass": mass, "inertia": {"principal": [I_roll, 1.0, 1.0]}},
        "rig": {"anchors": [[-d, 0, 0], [d, 0, 0]], "attachments": [[-d, 0, h], [d, 0, h]], "lengths": [L, L]},
    }, warn=False)


@pytest.mark.parametrize("I_roll", [1e-9, 1e-11])
def test_modes_of_a_thin_rod_match_closed_forms(I_roll):
    """Slow modes next to a 5-50 kHz roll: each period must go with its own
    shape (a degeneracy tolerance relative to the fastest mode merged them:
    swapped torsion and swing-x, one mean period for all three, or called
    them neutral).  The generalised eigenproblem with a 1e11 spread of
    inertias loses ~1e-6 of the slow periods: tolerance 1e-5."""
    m, L, h, d = 1.0, 1.5, 0.1, 0.5
    s = rod(m, L, h, d, I_roll=I_roll)
    expect = {
        "torsion": 2 * np.pi * np.sqrt(1.0 * L / (m * G * d**2)),  # bifilar torsion, vertical wires
        "swing-x": 2 * np.pi * np.sqrt(L / G),  # along the rod: the wires stay parallel
        "swing-y": 2 * np.pi * np.sqrt((L + h) / G),  # across: a pendulum to the CoM (roll inertia ~0)
    }
    ms_single = linear_modes(s, rest_pose(s))
    _, (ms_batch,) = rest_and_modes([s])
    for ms in (ms_single, ms_batch):
        for label, T in expect.items():
            assert ms.get(label).period == pytest.approx(T, rel=1e-5), label
        roll = ms.get("roll").period
        assert roll < 1e-3 * min(expect.values())


def counted(monkeypatch):
    """Count the model's right-hand-side evaluations in ``simulate``."""
    import bifilar.analysis.simulate as sim

    calls = [0]
    real = mx.make_flat_rhs

    def counting(*a, **k):
        f = real(*a, **k)

        def g(t, y):
            calls[0] += 1
            return f(t, y)
        return g

    monkeypatch.setattr(sim.mx, "make_flat_rhs", counting)
    return calls


def test_stiff_body_is_refused_after_a_short_probe_with_an_estimate(monkeypatch):
    """A 10 kg thin rod: its roll mode is ~5e4 times faster than its torsion.
    The cost is estimated from a probe of 1 % of the run and a run beyond the
    budget is refused before it starts, after a bounded number of
    evaluations (not minutes of them)."""
    from bifilar.errors import InputError

    scene = rod(mass=10.0, L=2.0)
    calls = counted(monkeypatch)
    with pytest.raises(InputError) as e:
        simulate(scene, mode="torsion", periods=10, max_evaluations=1e5)
    assert e.value.field == "--periods" and "stiff body" in str(e.value)
    est = float(str(e.value).split("needs about ")[1].split(" evaluations")[0])
    assert est > 1e5
    # the probe is 1 % of the run: its evaluations are est / 100, est as printed with 2 significant
    # figures (so up to 5 % below the exact count: 1730 evaluations print as 1.7e+05)
    assert calls[0] <= 1.05 * est / 100 + 1 and calls[0] < 2e4


def test_stiff_run_is_right_and_bounded_when_the_probe_underestimates(monkeypatch):
    """The 1 kg rod: the probe's rate underestimates the run (the fast roll
    gets excited as it goes), so the run itself stops at the budget; within
    the budget the measured torsion period is the closed-form one."""
    from bifilar.errors import InputError

    scene = rod()
    T = 2 * np.pi * np.sqrt(1.0 * 1.5 / (1.0 * G * 0.5**2))
    calls = counted(monkeypatch)
    # the probe's estimate (2.7e4 .. 3.1e4) and the run's need (9.5e4 .. 1.0e5) move with the rounding-level
    # roll of the start (rx ~ 2e-14 rad excites a 1.9e-4 s roll): a budget well between the two
    with pytest.raises(InputError) as e:
        simulate(scene, mode="torsion", periods=2, max_evaluations=5e4)
    assert e.value.field == "--periods" and "reached t = " in str(e.value)
    assert calls[0] <= 5e4 + 4e2 + 1  # the budget, the probe (~300) and the refused call
    res = simulate(scene, mode="torsion", amplitude=0.05, periods=2)
    assert any(w.startswith("stiff body:") for w in res.warnings)
    # amplitude 0.05 rad: the period grows by ~theta^2/16 = 1.6e-4
    assert res.period == pytest.approx(T, rel=3e-4)
    assert res.energy_drift < 1e-7 and res.max_constraint_violation < 1e-9
