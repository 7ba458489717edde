"""The amplitude range that invert (estimation/amplitude_secant.far_amplitude_stds)
and a sweep point (studies/point_far_amplitude.far_amplitude) share: one
AmplitudeRange read both ways.  References are hand computations of
``A +- 2 s_A``, the mode's last reachable start (pi rad, twice the longest
wire) and the secant ``max |T(end) - T(A)| / 2`` on a made-up period law
``T(A) = T_lin (1 + c A^2)`` fed to both callers in place of their runs, so
the callers' numbers and messages are checked against arithmetic, not
against the code under test."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.errors import InputError
from bifilar.estimation import amplitude_runs
from bifilar.estimation.amplitude_secant import AmplitudeRange, amplitude_range, far_amplitude_stds
from bifilar.studies.point_far_amplitude import END_RUN_PERIODS, far_amplitude

T_LIN, C = 1.5, 0.15  # s, 1/rad^2: T / T_lin = 1 + C A^2, far from linear (> 20 %) above 1.16 rad
ROT = SimpleNamespace(dominant=5)  # a rotation (rz): the last reachable start is pi rad
SCENE = SimpleNamespace(lengths=np.array([0.9, 1.2, 1.0]))


def law_T(a):
    return T_LIN * (1.0 + C * a * a)


def test_range_by_hand():
    rng = amplitude_range(-2.4, 0.24, SCENE, ROT)
    assert (rng.amplitude, rng.std, rng.unit) == (2.4, 0.24, "rad") and rng.limit == pytest.approx(math.pi, 1e-15)
    assert rng.hi == pytest.approx(2.88, 1e-14) and rng.lo == pytest.approx(1.92, 1e-14)
    assert not rng.reaches_limit and rng.ends() == pytest.approx([2.88, 1.92], 1e-14)
    assert rng.stated() == "2.4 +- 0.24 rad"
    assert rng.secant(2.5, [2.9, 2.3], 1.55) == pytest.approx(0.2, 1e-14)  # max(0.4, 0.2) / 2
    assert amplitude_range(2.8, 0.28, SCENE, ROT).reaches_limit  # 3.36 >= pi
    low = AmplitudeRange(0.1, 0.06, math.pi, "rad")  # lower end -0.02: the linear period stands in for it
    assert low.ends() == pytest.approx([0.22], 1e-14)
    assert low.secant(1.0, [1.01], 0.9) == pytest.approx(0.05, 1e-14)  # max(0.01, 0.1) / 2
    trans = amplitude_range(0.5, 0.1, SCENE, SimpleNamespace(dominant=0))  # a swing: twice the longest wire
    assert (trans.limit, trans.unit) == (pytest.approx(2.4, 1e-15), "m")


def _point(amplitude):
    pre = SimpleNamespace(amplitude=amplitude, labels=["torsion"], scene=SCENE, ms=SimpleNamespace(modes=[ROT]),
                          rest=None)
    return pre, SimpleNamespace(periods=3.0, rtol=1e-10)


def test_sweep_point_secant_by_hand(monkeypatch):
    import bifilar.analysis.batch as batch

    calls = []

    def fake(scenes, mode, amplitude, periods, **kw):
        calls.append((list(amplitude), periods))
        return [SimpleNamespace(error=None, period=law_T(a)) for a in amplitude]

    monkeypatch.setattr(batch, "simulate_batch", fake)
    pre, st = _point(2.0)
    far = far_amplitude(pre, 0, law_T(2.0) / T_LIN, T_LIN, 0.1, st)
    assert calls[0][0] == pytest.approx([2.0, 2.4, 1.6], 1e-14) and calls[0][1] == END_RUN_PERIODS * 3.0
    secant = T_LIN * C * (2.4**2 - 2.0**2) / 2  # the upper end's difference is the larger: 0.198 s
    assert far.secant == pytest.approx(secant, 1e-12) and far.note is None
    assert far.slope == pytest.approx(secant / (0.1 * T_LIN), 1e-12)
    assert far_amplitude(pre, 0, 1.1, T_LIN, 0.1, st) is None and len(calls) == 1  # within 20 %: no run
    pre, st = _point(2.9)
    far = far_amplitude(pre, 0, law_T(2.9) / T_LIN, T_LIN, 0.1, st)
    assert far.slope is None and len(calls) == 1
    assert far.note == ("mode 'torsion' at 2.9 +- 0.29 rad runs 2.26 x its linear period, and its 95 % range "
                        "reaches 3.48 rad, at or past its last reachable start (3.142 rad): invert refuses this "
                        "amplitude (no std holds), so no sigma")


def _problem(amplitude, amplitude_std):
    m = SimpleNamespace(amplitude=amplitude, amplitude_std=amplitude_std, field="--period", label="torsion",
                        hanging=0)
    pb = SimpleNamespace(measurements=[m], models=[SimpleNamespace(scene0=SCENE, modes0=SimpleNamespace(modes=[ROT]))],
                         mode_index=[0])
    law = SimpleNamespace(amplitude=amplitude, factor=lambda a: law_T(a) / T_LIN)
    return pb, [law]


def test_invert_secant_by_hand(monkeypatch):
    monkeypatch.setattr(amplitude_runs, "measured_factor", lambda pb, k, p, rtol, a: (law_T(a) / T_LIN,))
    pb, laws = _problem(0.5, 0.4)  # factor 1.0375: within 20 %, the first-order std kept, no run
    s = np.array([0.01])
    far_amplitude_stds(pb, [0.06], [T_LIN], laws, {"amplitude": 0.1}, s)
    assert s[0] == 0.01
    pb, laws = _problem(2.0, 0.6)  # lower end 0.8; upper 3.2 > pi: refused on --amplitude
    with pytest.raises(InputError) as exc:
        far_amplitude_stds(pb, [0.06], [T_LIN], laws, {"amplitude": 0.1}, np.array([0.01]))
    assert exc.value.field == "--amplitude"
    assert exc.value.message.startswith("mode 'torsion' stated at 2 +- 0.6 rad runs 1.6 x its linear period, and its "
                                        "95 % range reaches 3.2 rad, at or past the mode's last reachable start "
                                        "(3.142 rad), towards which")
    pb, laws = _problem(2.0, None)  # invert's default 10 %: range 1.6 .. 2.4
    s = np.array([0.01])
    far_amplitude_stds(pb, [0.06], [T_LIN], laws, {"amplitude": 0.1}, s)
    assert s[0] == pytest.approx(T_LIN * C * (2.4**2 - 2.0**2) / 2, 1e-12)
    pb, laws = _problem(1.5, 0.8)  # lower end -0.1: the linear period stands in for it
    s = np.array([0.01])
    far_amplitude_stds(pb, [0.06], [T_LIN], laws, {"amplitude": 0.1}, s)
    assert s[0] == pytest.approx(max(T_LIN * C * (3.1**2 - 1.5**2), T_LIN * C * 1.5**2) / 2, 1e-12)


def test_both_callers_give_the_same_secant(monkeypatch):
    """The same law, amplitude and relative std (10 %) through invert's and
    the sweep's code paths give one secant."""
    import bifilar.analysis.batch as batch

    monkeypatch.setattr(amplitude_runs, "measured_factor", lambda pb, k, p, rtol, a: (law_T(a) / T_LIN,))
    monkeypatch.setattr(batch, "simulate_batch", lambda scenes, mode, amplitude, periods, **kw:
                        [SimpleNamespace(error=None, period=law_T(a)) for a in amplitude])
    for A in (1.4, 2.2, 2.6):
        pb, laws = _problem(A, None)
        s = np.array([0.0])
        far_amplitude_stds(pb, [0.06], [T_LIN], laws, {"amplitude": 0.1}, s)
        pre, st = _point(A)
        assert far_amplitude(pre, 0, law_T(A) / T_LIN, T_LIN, 0.1, st).secant == pytest.approx(s[0], 1e-13)
