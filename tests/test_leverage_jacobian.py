"""The fit check's leverages (estimation/fit_check.leverages) read the
uncertainty budget's Jacobian (BudgetContext.jacobian) instead of stepping
every unknown again.  References: the leverages of the old, independent
formulation (central differences of the labelled linear periods, steps
1e-6 of each unknown, written out here) on the drone's four modes solving
Izz and Iyy, and closed forms: two timings of one mode have ``h_k = w_k /
sum w`` (``w = 1 / s^2``); a swing that the solved moment does not move has
leverage 0 and the torsion that alone moves it 1."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.config import load_scene, scene_from_dict
from bifilar.estimation.budget import _budget
from bifilar.estimation.fit_check import labelled_periods, leverages
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from conftest import CONFIGS

DRONE = {"torsion": 1.8800643384877211, "pitch": 0.9853502980039075, "swing-x": 2.4873718137340903,
         "swing-y": 2.456919878869915}  # the drone's linear periods, s (`bifilar modes`)


def _ms(scene, periods):
    return MeasurementSet([Hanging("ref", scene, np.eye(3))],
                          [Measurement(lab.split("#")[0], float(T), s, "period", "--period", amplitude=0.0)
                           for lab, (T, s) in periods.items()])


def _budget_jacobian(res):
    pb, p = res.problem, np.asarray(res.values, float)
    ctx = _budget(pb, p, np.ones(len(pb.measurements)), "linear", {}, "linear", pb.unc)[3]
    return pb, p, ctx.jacobian


def _stepped_leverages(pb, p):
    """The old formulation: J by central differences of the labelled periods, then the hat matrix's diagonal."""
    J = np.empty((len(pb.measurements), len(p)))
    for i in range(len(p)):
        h = 1e-6 * abs(p[i]) if p[i] else 1e-8
        up, dn = p.copy(), p.copy()
        up[i] += h
        dn[i] -= h
        J[:, i] = (labelled_periods(pb, up) - labelled_periods(pb, dn)) / (2.0 * h)
    A = J / np.array([m.std for m in pb.measurements])[:, None]
    U, sv, _ = np.linalg.svd(A, full_matrices=False)
    U = U[:, sv > 1e-9 * sv[0]]
    return np.sum(U * U, axis=1)


def test_budget_jacobian_leverages_match_the_stepped_ones():
    res = invert(_ms(load_scene(CONFIGS / "drone_parallel.yaml"), {m: (T, 1e-3) for m, T in DRONE.items()}),
                 solve_for=["Izz", "Iyy"], ladder=False, method="linear")
    pb, p, J = _budget_jacobian(res)
    assert J.shape == (4, 2)
    h = leverages(J, [m.std for m in pb.measurements])
    assert np.max(np.abs(h - _stepped_leverages(pb, p))) < 1e-10  # measured 1.3e-11
    assert h.sum() == pytest.approx(2.0, abs=1e-9)  # the fit's rank
    assert h[0] > 0.99 and h[1] > 0.99  # torsion alone moves Izz, pitch alone Iyy (the swings neither)


def test_leverage_closed_forms():
    """A 5 kg plate on two vertical 1.5 m wires 0.3 m apart: T_torsion = 2 pi sqrt(Izz L / (m g R^2)),
    the swing-x a simple pendulum that Izz does not move."""
    M, G, L, R, IZZ = 5.0, 9.81, 1.5, 0.15, 0.075
    plate = scene_from_dict({"gravity": G, "body": {"mass": M, "inertia": {"principal": [0.05, 0.03, IZZ]}},
                             "rig": {"anchors": [[-R, 0, 0], [R, 0, 0]], "attachments": [[-R, 0, 0.05], [R, 0, 0.05]],
                                     "lengths": [L, L]}})
    T_t = 2 * math.pi * math.sqrt(IZZ * L / (M * G * R * R))
    res = invert(_ms(plate, {"torsion": (T_t, 1e-3), "torsion#2": (T_t, 1e-4)}), solve_for=["Izz"], ladder=False,
                 method="linear")
    pb, p, J = _budget_jacobian(res)
    h = leverages(J, [m.std for m in pb.measurements])
    assert h == pytest.approx([1 / 101, 100 / 101], abs=1e-12)
    assert np.max(np.abs(h - _stepped_leverages(pb, p))) < 1e-10
    T_s = 2 * math.pi * math.sqrt(L / G)
    res = invert(_ms(plate, {"torsion": (T_t, 1e-3), "swing-x": (T_s, 1e-3)}), solve_for=["Izz"], ladder=False,
                 method="linear")
    pb, p, J = _budget_jacobian(res)
    assert leverages(J, [1e-3, 1e-3]) == pytest.approx([1.0, 0.0], abs=1e-9)
    assert leverages(np.array([[np.nan], [1.0]]), [1e-3, 1e-3]) is None  # a period without a derivative
