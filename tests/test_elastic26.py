"""Four elastic wires near parallel: the model's modes against the body on springs (elastic26, session 26).

The independent formulation (scripts/elastic_spring_check.py's ``spring_periods``) has no constraint at
all: the rigid body hangs on four springs (``T = EA / L max(|d| - L, 0)``), its rest by Newton on the
potential's hand-written gradient with a central-difference Hessian, its modes the eigenproblem of that
Hessian (differenced again) against the body's mass (kinetic-energy metric, world rotation vector).  The rig is audit24's c07 (2 kg plate on four
vertical 1.2 m wires on a 0.4 m square, CoM 1 cm below the attachments) with anchors 1 and 3 splayed
outwards along x by ``eps``.  The model held a fourth wire direction rigidly where the multiplier matrix's
eigenvalue reached 1e-6 of the largest (eps ~ 3.5 mm here; a 1 mm draw of every input reaches it in 17 %
of configs): the torsion was lost, and below it the torsion lacked the wires' stretch stiffness (1.8e-4 of
its period at 1 mm, EA 20 kN).  Now a direction is held only where its stretch stiffness is at least 10x
its geometric one (bounce and tilts: 300 .. 4000x; the splay's: 3.5e-5 .. 1e-2x); the others carry their
springs.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from bifilar.analysis.equilibrium import constraint_jacobian, rest_pose, stretch_split
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.stretch_held import STRETCH_HOLD, geometric_stiffness, held_mask
from bifilar.config import scene_from_dict
from conftest import ROOT

sys.path.insert(0, str(ROOT / "scripts"))
from elastic_spring_check import spring_periods  # noqa: E402  (the independent formulation, also a script)

INERTIA = [0.03, 0.045, 0.06]
P = [[0.2, 0.2, 0.01], [-0.2, 0.2, 0.01], [-0.2, -0.2, 0.01], [0.2, -0.2, 0.01]]


def _c07(eps: float, ea: float):
    anchors = [[0.2 + eps, 0.2, 1.2], [-0.2, 0.2, 1.2], [-0.2 - eps, -0.2, 1.2], [0.2, -0.2, 1.2]]
    cfg = {"name": "c07", "body": {"mass": 2.0, "inertia": {"principal": INERTIA}},
           "rig": {"anchors": anchors, "attachments": P, "lengths": [1.2] * 4, "stiffness": ea}}
    return scene_from_dict(cfg, "test", warn=False)


# eps 1 mm: below the old eigenvalue cut-off (ratio 8.6e-8), 5 mm: above it (2.1e-6; the old model had no
# torsion there).  Tolerance 1e-6 of the period: the springs' differenced Hessian is good to ~1e-8 (the
# torsion agreed to 4e-9 at eps 0, where both are the rigid model's), the old rule was 1.8e-5 (EA 2 kN) and
# 1.8e-4 (20 kN) off at 1 mm.  The swings differ by the held directions' own stretch, the tilt's coupling
# (session 17's convention: rigid wires at their loaded lengths), 3.2e-7 at EA 20 kN at every eps, 3.1e-6
# at 2 kN: compared at 20 kN only, within the same 1e-6.
@pytest.mark.parametrize("eps, ea", [(1e-3, 2000.0), (5e-3, 2000.0), (1e-3, 20000.0), (5e-3, 20000.0)])
def test_model_periods_follow_the_body_on_springs_across_the_old_cut_off(eps, ea):
    sc = _c07(eps, ea)
    rest = rest_pose(sc)
    # the directions the wires resist are >= 300x stiffer by stretch than by their geometry (held) or <= 1e-2x
    # (carried as springs): the count does not turn on a millimetre (the old eigenvalue rule held 3 or 4)
    mu, kappa, _, _ = stretch_split(sc, rest.R, constraint_jacobian(sc, rest.com, rest.R)[2])
    ratio = mu / np.abs(kappa)
    assert np.sum(held_mask(mu, kappa)) == 3
    assert np.all((ratio[:3] > 30 * STRETCH_HOLD) & (ratio[3:] < 1e-3 * STRETCH_HOLD))
    modes = {m.label: m.period for m in linear_modes(sc, rest).modes}
    springs = spring_periods(sc, rest.com, rest.R)
    assert sorted(modes) == ["swing-x", "swing-y", "torsion"]  # the old rule at 5 mm: no torsion
    assert springs[3] < 0.2 * springs[2]  # three pendulum modes, the other three the wires' stretch
    assert modes["torsion"] == pytest.approx(springs[2], rel=1e-6)
    if ea == 20000.0:
        assert sorted([modes["swing-x"], modes["swing-y"]]) == pytest.approx(sorted(springs[:2]), rel=1e-6)


def test_geometric_stiffness_is_the_sum_of_the_constraint_hessians():
    from bifilar.analysis.equilibrium import constraint_hessians

    rng = np.random.default_rng(3)
    d, w, lam = rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), rng.normal(size=5)
    want = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    assert geometric_stiffness(lam, d, w) == pytest.approx(want, abs=1e-13)
    batch = geometric_stiffness(np.stack([lam, 2 * lam]), np.stack([d, d]), np.stack([w, w]))
    assert batch[1] == pytest.approx(2 * want, abs=1e-12)


def test_configs_drawn_one_millimetre_off_hold_the_same_directions_and_keep_the_sigma():
    # c07 at EA 2 kN with the 1 mm default stds: under the eigenvalue rule 17 % of drawn configs held a fourth
    # direction (91 % within its factor 10; none of 1000 held by chance: 0.83^1000) and the sigma was refused (the answered scattered 26x it);
    # now none changes the count or comes within a factor 10 of the rule, 0.08 % leave a wire slack (< 5 %),
    # and the sigma is given (closed loops, 200 draws, seeds 1 and 2: realised sd 1.072x and 0.994x it,
    # inside chi^2's 0.902..1.098; docs/design.md "elastic26, session 26")
    from bifilar.estimation.elastic_split import drawn_rig_risks, sigma_refusal
    from bifilar.estimation.uncertainty import default_uncertainty

    sc = _c07(0.0, 2000.0)
    risks = drawn_rig_risks(sc, rest_pose(sc), default_uncertainty(), draws=1000)  # old rule: 17 % of them
    assert (risks.held, risks.p_held, risks.p_near) == (3, 0.0, 0.0)
    assert 0 < risks.p_slack < 0.01 and sigma_refusal(risks) is None
