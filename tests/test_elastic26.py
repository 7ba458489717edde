"""Four elastic wires near parallel: the model's modes against the body on springs (elastic26, session 26).

The independent formulation here has no constraint at all: the rigid body hangs on four springs
(``T = EA / L max(|d| - L, 0)``), its rest by Newton on the potential's hand-written gradient with a
central-difference Hessian, its modes the eigenproblem of that Hessian (differenced again) against the
body's mass (kinetic-energy metric, world rotation vector).  The rig is audit24's c07 (2 kg plate on four
vertical 1.2 m wires on a 0.4 m square, CoM 1 cm below the attachments) with anchors 1 and 3 splayed
outwards along x by ``eps``.  The model held a fourth wire direction rigidly where the multiplier matrix's
eigenvalue reached 1e-6 of the largest (eps ~ 3.5 mm here; a 1 mm draw of every input reaches it in 17 %
of configs): the torsion was lost, and below it the torsion lacked the wires' stretch stiffness (1.8e-4 of
its period at 1 mm, EA 20 kN).  Now a direction is held only where its stretch stiffness is at least 10x
its geometric one (bounce and tilts: 300 .. 4000x; the splay's: 3.5e-5 .. 1e-2x); the others carry their
springs.
"""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis.equilibrium import constraint_jacobian, rest_pose, stretch_split
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.stretch_held import STRETCH_HOLD, geometric_stiffness, held_mask
from bifilar.config import scene_from_dict
from bifilar.rotations import rotvec_to_matrix

INERTIA = [0.03, 0.045, 0.06]
P = [[0.2, 0.2, 0.01], [-0.2, 0.2, 0.01], [-0.2, -0.2, 0.01], [0.2, -0.2, 0.01]]


def _c07(eps: float, ea: float):
    anchors = [[0.2 + eps, 0.2, 1.2], [-0.2, 0.2, 1.2], [-0.2 - eps, -0.2, 1.2], [0.2, -0.2, 1.2]]
    cfg = {"name": "c07", "body": {"mass": 2.0, "inertia": {"principal": INERTIA}},
           "rig": {"anchors": anchors, "attachments": P, "lengths": [1.2] * 4, "stiffness": ea}}
    return scene_from_dict(cfg, "test", warn=False)


def _spring_periods(sc, com0, R0) -> np.ndarray:
    """The six periods (s, slowest first) of the body on springs EA / L (no constraint), from its rest."""
    a, p, L = np.asarray(sc.anchors), np.asarray(sc.attachments), np.asarray(sc.lengths)
    k = np.asarray(sc.stiffness, float) / L
    m, g = sc.mass, sc.gravity

    def grad(c, R):
        w = p @ R.T
        d = c + w - a
        ln = np.linalg.norm(d, axis=1)
        u = d / ln[:, None]
        T = k * np.maximum(ln - L, 0.0)
        return np.concatenate([[0.0, 0.0, m * g] + T @ u, np.cross(w, u).T @ T])

    def move(c, R, x):
        return c + x[:3], rotvec_to_matrix(x[3:]) @ R

    def hess(c, R, h=1e-7):
        H = np.empty((6, 6))
        for j in range(6):
            e = np.zeros(6)
            e[j] = h
            H[:, j] = (grad(*move(c, R, e)) - grad(*move(c, R, -e))) / (2 * h)
        return 0.5 * (H + H.T)

    c, R = np.asarray(com0, float) - [0.0, 0.0, 1e-3], np.asarray(R0, float)  # 1 mm below: every wire taut
    for _ in range(30):
        x = -np.linalg.solve(hess(c, R), grad(c, R))
        c, R = move(c, R, x)
        if np.max(np.abs(x)) < 1e-14:
            break
    assert np.max(np.abs(grad(c, R))) < 1e-9 * m * g  # the springs' equilibrium reached
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[3:, 3:] = R @ sc.inertia @ R.T
    w2 = np.linalg.eigvals(np.linalg.solve(M, hess(c, R))).real
    return np.sort(2 * np.pi / np.sqrt(w2))[::-1]


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
    modes = {m.label: m.period for m in linear_modes(sc, rest).modes}
    springs = _spring_periods(sc, rest.com, rest.R)
    assert sorted(modes) == ["swing-x", "swing-y", "torsion"]  # the old rule at 5 mm: no torsion
    assert springs[3] < 0.2 * springs[2]  # three pendulum modes, the other three the wires' stretch
    assert modes["torsion"] == pytest.approx(springs[2], rel=1e-6)
    if ea == 20000.0:
        assert sorted([modes["swing-x"], modes["swing-y"]]) == pytest.approx(sorted(springs[:2]), rel=1e-6)


def test_the_held_directions_are_the_stiff_stretches_with_a_wide_gap():
    # every direction the wires resist is either >= 300x stiffer by stretch than by its geometry (held) or
    # <= 1e-2x (carried as a spring) on the c07 rigs up to 5 mm of splay and EA 2 .. 20 kN: the count does
    # not turn on a millimetre (the old eigenvalue rule held 3 or 4 within it)
    for ea in (2000.0, 20000.0):
        for eps in (0.0, 1e-3, 5e-3):
            sc = _c07(eps, ea)
            rest = rest_pose(sc)
            G = constraint_jacobian(sc, rest.com, rest.R)[2]
            mu, kappa, _, _ = stretch_split(sc, rest.R, G)
            ratio = mu / np.abs(kappa)
            assert np.sum(held_mask(mu, kappa)) == 3
            assert np.all((ratio[:3] > 30 * STRETCH_HOLD) & (ratio[3:] < 1e-3 * STRETCH_HOLD))


def test_geometric_stiffness_is_the_sum_of_the_constraint_hessians():
    from bifilar.analysis.equilibrium import constraint_hessians

    rng = np.random.default_rng(3)
    d, w, lam = rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), rng.normal(size=5)
    want = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    assert geometric_stiffness(lam, d, w) == pytest.approx(want, abs=1e-13)
    batch = geometric_stiffness(np.stack([lam, 2 * lam]), np.stack([d, d]), np.stack([w, w]))
    assert batch[1] == pytest.approx(2 * want, abs=1e-12)


def test_configs_drawn_one_millimetre_off_hold_the_same_directions_and_keep_the_sigma():
    # c07 at EA 2 kN with the 1 mm default stds: under the eigenvalue rule 17 % of 4000 drawn configs held a
    # fourth direction (91 % within its factor 10) and the sigma was refused (the answered scattered 26x it);
    # now none changes the count or comes within a factor 10 of the rule, 0.08 % leave a wire slack (< 5 %),
    # and the sigma is given (closed loops, 200 draws, seeds 1 and 2: realised sd 1.072x and 0.994x it,
    # inside chi^2's 0.902..1.098; docs/design.md "elastic26, session 26")
    from bifilar.estimation.elastic_split import drawn_rig_risks, sigma_refusal
    from bifilar.estimation.uncertainty import default_uncertainty

    sc = _c07(0.0, 2000.0)
    risks = drawn_rig_risks(sc, rest_pose(sc), default_uncertainty())
    assert (risks.held, risks.p_held, risks.p_near) == (3, 0.0, 0.0)
    assert 0 < risks.p_slack < 0.01 and sigma_refusal(risks) is None
