"""A refusal names the unknowns the periods barely determine.  Izz, com.x
and com.y of a trifilar solved from its torsion and two swings: the swings'
periods move by 0.003-0.04 s per metre of CoM, so 1 ms of timing is
centimetres of CoM, and a draw of the inputs at their stated stds leaves no
physical tensor that reproduces the periods.  The refusal advised 'check the
periods, their modes and the config' first, where the unknowns are the cause
(end-to-end audit, session 9); it now names them with their timing-only std
at the config's values (a linear least-squares std, checked here against
its closed form from the period Jacobian)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import scene_from_dict
from bifilar.errors import InputError
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.estimation.problem import build_problem
from bifilar.estimation.roots import LOOSE_UNKNOWN, _loose_hint, loosely_determined

UNC = {"length": 1e-3, "position": 1e-3, "mass": 1e-3, "com": 2e-3, "gravity": 0.0, "timing": 1e-3}


def _ring(r, z, n=3):
    return [[r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n), z] for k in range(n)]


@pytest.fixture(scope="module")
def trifilar():
    att = [[x - 0.04, y + 0.03, 0.05] for x, y, _ in _ring(0.25, 0)]
    truth = scene_from_dict({"body": {"mass": 3.0, "inertia": {"tensor": [[0.06, 0.004, 0], [0.004, 0.05, 0],
                                                                          [0, 0, 0.1]]}},
                             "rig": {"anchors": _ring(0.35, 1.0), "attachments": att, "lengths": [1.0] * 3}},
                            "trifilar", warn=False)
    ms = linear_modes(truth, rest_pose(truth))
    labels = [m.label for m in ms.modes if m.period][:3]
    return truth, labels, [ms.get(lb).period for lb in labels]


def _measured(truth, labels, T, seed):
    rng = np.random.default_rng(seed)
    fm, dcom = 1 + rng.normal(0, UNC["mass"]), rng.normal(0, UNC["com"], 3)
    sc = replace(truth, mass=truth.mass * fm, lengths=truth.lengths + rng.normal(0, 1e-3, 3),
                 anchors=truth.anchors + rng.normal(0, 1e-3, (3, 3)),
                 attachments=truth.attachments + rng.normal(0, 1e-3, (3, 3)) - dcom[None, :])
    Tm = [float(t + rng.normal(0, 1e-3)) for t in T]
    return MeasurementSet([Hanging("ref", sc, np.eye(3))],
                          [Measurement(lb, t, 1e-3, "period", "--period", amplitude=0.0) for lb, t in zip(labels, Tm)])


def test_a_refusal_names_the_barely_determined_com_first(trifilar, monkeypatch):
    # the multi-start search (~12 s here, with this draw ending refused, see the module docstring) is
    # stubbed with its failure: the best admissible fit it found and its residuals
    from bifilar.estimation import roots

    truth, labels, T = trifilar
    pb = build_problem(_measured(truth, labels, T, 1), ["Izz", "com.x", "com.y"], UNC)
    best = {"z": np.array([0.853, -0.69, 0.137]), "p": np.array([0.0912, 0.045, 0.0518]), "test": "|residual| <= 0.1"}
    monkeypatch.setattr(roots, "multi_roots", lambda pb_, targets=None, extra_var=None: ([], best))
    with pytest.raises(InputError) as exc:
        roots.find_roots(pb)
    msg = exc.value.message
    assert "no physical tensor reproduces" in msg
    assert "barely determine com.x and com.y" in msg or "barely determine com.y and com.x" in msg
    assert "Izz +-" not in msg  # the torsion fixes Izz
    assert msg.index("barely determine") < msg.index("check the periods")


def test_the_loose_std_is_the_timing_only_least_squares_std(trifilar):
    truth, labels, T = trifilar
    pb = build_problem(_measured(truth, labels, T, 1), ["Izz", "com.x", "com.y"], UNC)
    loose = dict(loosely_determined(pb, pb.prior))
    J = pb.jacobian(pb.prior) / 1e-3
    std = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    sc = pb.scales()
    for i, n in enumerate(pb.unknowns):
        assert (n in loose) == (std[i] > LOOSE_UNKNOWN * sc[i])
        if n in loose:
            assert loose[n] == pytest.approx(std[i], rel=1e-6)
    assert {"com.x", "com.y"} <= set(loose) and loose["com.x"] > 0.01  # centimetres of CoM from 1 ms


def test_well_determined_unknowns_keep_the_old_advice(trifilar):
    truth, labels, T = trifilar
    pb = build_problem(_measured(truth, labels, T, 1), ["Izz"], UNC)
    assert loosely_determined(pb, pb.prior) == []
    assert _loose_hint(pb).startswith("check the periods")
