"""Four elastic wires: the slack tail of drawn configs (elastic26b, session 26).

A drawn config's tensions are not linear in the inputs: a tension's gradient moves with the points, so
the exact rests' tensions minus the linear ones scatter in proportion to the deviation (audit24's c07,
2 kg plate on four vertical 1.2 m wires, EA 2 kN, 1 mm stds: 0.06 N within one std of the tension,
0.3 N at three, against a std of 1.45 N).  The linear spread put the slack tail at 0.083 % of drawn
configs where their exact rests (elastic_rest of each drawn scene, 50,000 draws) leave 0.130 % slack;
six closed loops had refused 4 of 1200 for slack against 1.0 expected.  ``p_slack`` now takes each
wire's tension as a plane tangent near that wire's most probable slack config (the first-order
reliability method's design point), where the differences are taken again.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.analysis.elastic_rest import elastic_rest
from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation import elastic_split as es
from bifilar.estimation.sensitivity import perturb
from bifilar.estimation.uncertainty import default_uncertainty
from conftest import ROOT

QUAD = ROOT / "tests" / "data" / "audit24" / "c07_quad.yaml"


def _c07(ea: float = 2000.0):
    cfg = read_yaml(QUAD)
    cfg["body"]["inertia"]["principal"] = [0.03, 0.045, 0.06]
    cfg["rig"]["stiffness"] = ea
    return scene_from_dict(cfg, warn=False)


def _moved(scene, names, sd, z):
    for name, zj, s in zip(names, z, sd):
        scene = perturb(scene, name, zj * s)
    return scene


def test_the_tension_planes_follow_the_exact_rests_in_the_slack_tail():
    # configs drawn about wire 1's linear slack point (0.7 of the way, so that most stay taut), their
    # deviations across its gradient one std in every other input: the exact rests' tension of wire 1
    # against the linear tensions and against the plane.  The linear tension is off there by the
    # gradient's turn (rms 0.37 N over these 40); the plane, tangent at 0.9 of the way, by the curvature
    # left (0.05 N); a 3x bound leaves room for the draws and fails where the plane is the linear one
    # (DESIGN_SHARE 0) or its offset has the wrong sign
    sc = _c07()
    rest = rest_pose(sc)
    names, sd = es._inputs(sc, default_uncertainty())
    _, _, dT = es._gradients(sc, (rest.com, rest.R, rest.tensions), names, sd, checked=False)
    mean, grad = es._slack_planes(sc, rest, names, sd, dT)
    g = dT[:, 0]
    zs = -rest.tensions[0] * g / (g @ g)
    u = np.random.default_rng(7).standard_normal((40, len(names)))
    u -= np.outer(u @ g, g) / (g @ g)
    exact, lin, plane = [], [], []
    for z in 0.7 * zs + u:
        moved = _moved(sc, names, sd, z)
        T = elastic_rest(moved, moved.stiffness, rest.com, rest.R)[2]
        if np.all(T > 0):
            exact.append(T[0])
            lin.append(rest.tensions[0] + z @ g)
            plane.append(mean[0] + z @ grad[:, 0])
    assert len(exact) >= 30
    rms = [float(np.sqrt(np.mean((np.array(exact) - np.array(x)) ** 2))) for x in (lin, plane)]
    assert rms[0] > 0.2 and rms[1] < rms[0] / 3, rms
