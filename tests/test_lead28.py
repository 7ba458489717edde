"""Lead, session 28: the unknowns' Jacobian on the physical set's edge.

partner28 found `invert` dying with numpy's LinAlgError ("Matrix is not
positive definite", exit 1 from the CLI) in 5 of 400 drawn two-unknown
experiments at audit27's avoided crossing: Gauss-Newton's edge search stops
on the edge of the physical set (the triangle inequality), and a central
difference beside it steps out far enough that the modes' mass matrix is not
positive definite.  `Problem.jacobian` now takes the one-sided difference
into the side the modes can be solved on for such an unknown (docs/design.md,
"Lead, session 28")."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from bifilar.estimation.problem import Problem

ROOT = Path(__file__).resolve().parents[1]


def _fake(bad):
    """A stand-in with Problem's jacobian: T(p) = (p0^2 + 3 p1, sin p1) (s),
    unit scales, whose 'modes' cannot be solved where ``bad(p)``."""
    def periods(p):
        if bad(p):
            raise np.linalg.LinAlgError("Matrix is not positive definite")
        return np.array([p[0] ** 2 + 3 * p[1], math.sin(p[1])])

    f = SimpleNamespace(measurements=[0, 1], scales=lambda: np.ones(2), linear_periods=periods)
    f._one_sided = lambda p, e, h: Problem._one_sided(f, p, e, h)
    return f


@pytest.mark.parametrize("bad, side", [(lambda p: p[0] < 1.0, "forward"), (lambda p: p[0] > 1.0, "backward")])
def test_jacobian_on_the_edge_is_one_sided_into_the_solvable_side(bad, side):
    """At p0 = 1 with the modes unsolvable on one side: d T / d p0 = 2 p0 = 2
    (one-sided: error h = 1e-6, so 2e-6 relative at most), d T / d p1 = (3,
    cos p1) by the central difference as before (the solvable column).  The
    old central difference raised here."""
    p = np.array([1.0, 0.4])
    J = Problem.jacobian(_fake(bad), p)
    assert J[0, 0] == pytest.approx(2.0, rel=2e-6), side
    assert J[1, 0] == 0.0
    assert J[:, 1] == pytest.approx([3.0, math.cos(0.4)], rel=1e-8)


def test_jacobian_raises_where_neither_side_can_be_solved():
    """No silent number: a point whose neighbours on both sides cannot be solved still raises."""
    with pytest.raises(np.linalg.LinAlgError):
        Problem.jacobian(_fake(lambda p: abs(p[0] - 1.0) > 0.0), np.array([1.0, 0.4]))


def test_partner28s_crashing_draw_is_answered_and_reproduces_its_periods():
    """The draw partner28 found (scripts/crossing_partner_loop.py --modes
    torsion,roll --components Ixx,Izz --seed 4, draw 2: periods given as
    swing-x and roll): answered, and its estimate put back into the drawn
    config and solved by ``linear_modes`` gives both measured periods
    within 2 timing stds (or the answer says it does not).  Whether this
    draw's solve reaches the edge depends on the last bits; the two tests
    above pin the rule itself.  ~3 s CPU."""
    sys.path.insert(0, str(ROOT / "scripts"))
    from closed_loop_invert import INDEX, linear_periods
    from closed_loop_plan import measured_scene
    from crossing_partner_loop import _invert

    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.uncertainty import default_uncertainty

    cfg = read_yaml(ROOT / "tests" / "data" / "audit27" / "a03_neardegen.yaml")
    truth = scene_from_dict(cfg, warn=False)
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    lin = linear_periods(truth)
    rng = np.random.default_rng(4)
    for _ in range(3):
        sc = measured_scene(truth, rng, unc)
        Tm = [lin[m] + rng.normal(0, unc["timing"]) for m in ("torsion", "roll")]
    r = _invert(sc, ["swing-x", "roll"], Tm, unc, 0.0, ["Ixx", "Izz"])
    inertia = sc.inertia.copy()
    for c, v in zip(r.names, r.values):
        a, b = INDEX[c]
        inertia[a, b] = inertia[b, a] = v
    got = linear_periods(sc.with_changes(inertia=inertia))
    resid = max(abs(got[m] - T) for m, T in zip(("swing-x", "roll"), Tm)) / unc["timing"]
    assert resid < 2.0 or any("reproduce" in w for w in r.warnings), (resid, r.warnings)
