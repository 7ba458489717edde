"""Audit session 6 (docs/invert.md, "Audit, session 6"): cases nobody had
tried, each a synthetic experiment with a known truth whose measured inputs
are off by normal errors of the size written HERE (1 mm lengths and
positions, 2 mm CoM, 0.1 % mass, 1 ms timing), re-estimated by ``invert``
itself, draw by draw.

A thin disc on a trifilar lies on the triangle limit (``Izz = Ixx + Iyy``):
in about half of all experiments the measured torsion period lies beyond
the longest period a physical ``Izz`` gives.  The inputs' errors (1 mm of
the attachments' 0.15 m radius moves the period by ~0.7 %, ~10 ms) put it
many timing sigma beyond, and the edge of the physical set was accepted
within 2 *timing* sigma only: 35 % of these honest experiments were refused
("no physical Izz gives a period of ...", exit 2; 70 of 200).  The edge is
now accepted within 2 sigma of the period's uncertainty with the inputs'
counted (as the fit check of several periods counts them), an input error
that explains the difference checked with the full model.
"""

from __future__ import annotations

import math

import numpy as np
from conftest import measured_scene

from bifilar.config import scene_from_dict
from bifilar.errors import InputError
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
from bifilar.analysis.batch import modes_batch, rest_poses

UNC = {"length": 1e-3, "position": 1e-3, "mass": 1e-3, "com": 2e-3, "gravity": 0.0, "timing": 1e-3}


def _ring(r, z):
    return [[r * math.cos(2 * math.pi * k / 3), r * math.sin(2 * math.pi * k / 3), z] for k in range(3)]


def thin_disc():
    # 1 kg, radius 0.2 m: Ixx = Iyy = m r^2 / 4, Izz = m r^2 / 2 (on the limit); three 0.8 m
    # vertical wires at 0.15 m, attached 5 mm above the CoM
    return scene_from_dict({"body": {"mass": 1.0, "inertia": {"principal": [0.01, 0.01, 0.02]}},
                            "rig": {"anchors": _ring(0.15, 0.805), "attachments": _ring(0.15, 0.005),
                                    "lengths": [0.8, 0.8, 0.8]}}, "disc", warn=False)


def _experiments(truth, n, seed):
    rng = np.random.default_rng(seed)
    T = modes_batch([truth], rest_poses([truth]))[0].get("torsion").period
    for _ in range(n):
        sc = measured_scene(truth, rng, UNC)
        yield MeasurementSet([Hanging("ref", sc, np.eye(3))],
                             [Measurement("torsion", float(T + rng.normal(0, UNC["timing"])), UNC["timing"],
                                          "period", "--period", amplitude=0.0)])


def test_thin_disc_on_the_triangle_limit_is_answered_and_covered():
    truth = thin_disc()
    n, refused, covered, edge = 40, [], 0, 0
    for ms in _experiments(truth, n, 3):
        try:
            res = invert(ms, solve_for=["Izz"], unc=UNC, ladder=False)
        except InputError as exc:  # before: 'no physical Izz gives a period of ...' in ~35 %
            refused.append(str(exc))
            continue
        lo, hi = res.interval[0]
        covered += lo <= 0.02 <= hi
        edge += bool(res.roots[0]["edge"])
        # an edge answer is within the period's uncertainty with the inputs' counted, never beyond
        assert res.fit["passed"]
        assert res.value("Izz") <= 0.02 / (1 - 1e-4) * (1 + 1e-12)  # the loader's triangle slack
    # the edge is accepted within 2 sigma with the inputs counted: of all experiments ~2.3 % are refused
    # (40 draws: 0.9 expected, <= 4 with P = 0.998); before, ~35 % (14 expected)
    assert len(refused) <= 4, refused[:2]
    # about half lie beyond the limit (binomial 40 x 0.5: 20 +- 3.2; > 8 at 3.8 sigma)
    assert edge > 8, edge
    # the interval covers the truth (on the limit: the edge answers' intervals reach it); 95 % of 40: >= 34 at 2.3 sigma
    assert covered >= 34, covered


def test_sigma_point_step_past_definiteness_is_not_a_crash():
    # a 10 g body (Izz 4.5e-6 kg m^2 of at most 5.0005e-6: near the triangle limit) on 0.5 m wires 6 cm
    # apart, CoM 5 mm below: in one experiment of 200 a sigma point's Gauss-Newton step left the tensor
    # not positive definite and the mass matrix's Cholesky raised LinAlgError, an internal error (exit 1)
    truth = scene_from_dict({"body": {"mass": 0.01, "inertia": {"principal": [2e-6, 3e-6, 4.5e-6]}},
                             "rig": {"anchors": [[-0.03, 0, 0.505], [0.03, 0, 0.505]],
                                     "attachments": [[-0.03, 0, 0.005], [0.03, 0, 0.005]], "lengths": [0.5, 0.5]}},
                            "light", warn=False)
    for k, ms in enumerate(_experiments(truth, 99, 1)):
        if k == 98:  # the audit's draw (seed 1, draw 98)
            res = invert(ms, solve_for=["Izz"], unc=UNC, ladder=False)
            assert res.fit["passed"]
            # the point that cannot be re-solved makes its input degenerate: no std rather than a wrong one
            assert res.std_unavailable or np.isfinite(res.sigma("Izz"))
