"""The components not solved for, finished (docs/design.md, "priorfit, session 14").

priorunc gave each component ``invert`` does not solve for the standard
uncertainty ``REL |I_c|``, so a product of inertia the config gives as 0 was
exact under any ``--uncertainty inertia=REL`` and left out of the warning,
though on the audit's tilted plate the torsion is ~5x more sensitive to Iyz
than to Iyy; and the fit check (``fit_check.input_fit_check``) ignored the
priors' variance, so a set of hangings whose products the config leaves at 0
was refused when only the moments were solved for.  Now a product's scale is
``sqrt(I_ii I_jj)`` (the Cauchy-Schwarz bound on it) and the fit check counts
the priors' covariance where ``inertia`` is stated, naming it.

Every test here fails on the old code (noted in each)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import scene_from_dict
from bifilar.errors import InputError
from bifilar.estimation import measurements as mm
from bifilar.estimation.invert import invert
from bifilar.scene import scene_with
from tests.test_priorunc import EXACT, _invert, _plate


def test_a_zero_product_has_a_prior_std_and_its_term_is_the_answers_change():
    """The plate (tilted trifilar, Izz from its torsion): the config's Iyz is
    0, its std under ``inertia=0.1`` is 0.1 sqrt(Iyy Izz) (Izz the
    estimate's), and the budget's ``prior_inertia[Iyz]`` term is the
    estimate's change when ``invert`` is re-run with the config's Iyz moved
    by 0.5 % of that scale (an independent finite difference; 2 %: the
    curvature of Izz(Iyz) over the step and the solver's 1e-9 stop).
    Old code: Iyz's std 0, no term."""
    s = _plate()
    res = _invert(s, {"inertia": 0.1})
    doc = res.to_json()
    Iyy, Izz = float(s.inertia[1, 1]), res.value("Izz")
    comp = doc["prior_inertia"]["components"]["Iyz"]
    assert comp["prior"] == 0.0
    assert comp["std"] == pytest.approx(0.1 * np.sqrt(Iyy * Izz), rel=1e-9)
    term = doc["budget"]["Izz"]["inputs"]["prior_inertia[Iyz]"]["std"]
    d = 0.005 * np.sqrt(Iyy * Izz)
    I = s.inertia.copy()
    I[1, 2] = I[2, 1] = d
    slope = (_invert(scene_with(s, inertia=I), {"inertia": 0.1}).value("Izz") - Izz) / d
    assert abs(slope) > 0.5  # the tilted anchors couple Iyz into the torsion (-0.78 kg m^2 per kg m^2)
    assert term == pytest.approx(abs(slope) * comp["std"], rel=0.02)
    # the unstated prior's warning names Iyz first (it moves Izz most), Iyy after it
    w = [x for x in _invert(s, {}).warnings if "not solved for" in x]
    assert len(w) == 1 and "Iyz, Iyy" in w[0], w


# the shipped hangings example's body and rig (configs/measurements_hangings_example.yaml): a level
# trifilar, whose torsion no product moves to first order; re-hung with y+z up it times (Iyy + Izz)/2 - Iyz
TRIFILAR = yaml.safe_load("""
gravity: 9.81
body: {mass: 4.0, inertia: {principal: [0.30, 0.20, 0.40]}}
rig:
  anchors:     [[0.0, 0.3, 0.0], [-0.259808, -0.15, 0.0], [0.259808, -0.15, 0.0]]
  attachments: [[0.0, 0.3, 0.02], [-0.259808, -0.15, 0.02], [0.259808, -0.15, 0.02]]
  lengths:     [1.0, 1.0, 1.0]
""")


def _two_hangings(unc):
    """Izz from the z-up and the y+z-up torsion (periods of the truth, Iyz
    0.015 kg m^2, 3.5 % of sqrt(Iyy Izz); timed to 1e-3 s); the config's
    prior has every product 0 and the right moments."""
    prior = scene_from_dict(TRIFILAR, warn=False)
    c, s_ = np.cos(np.pi / 4), np.sin(np.pi / 4)
    R = np.array([[1, 0, 0], [0, c, -s_], [0, s_, c]])  # rotation [{x: 45}]: body y+z becomes vertical
    truth = prior.inertia.copy()
    truth[1, 2] = truth[2, 1] = 0.015
    hangs, meas = [], []
    for h, (name, Rh) in enumerate([("z-up", np.eye(3)), ("yz-up", R)]):
        sc = scene_with(prior, inertia=Rh @ truth @ Rh.T)
        T = linear_modes(sc, rest_pose(sc)).get("torsion").period
        hangs.append(mm.Hanging(name, scene_with(prior, inertia=Rh @ prior.inertia @ Rh.T), Rh))
        meas.append(mm.Measurement("torsion", T, 1e-3, "period", f"{name}.period", hanging=h, amplitude=0.0,
                                   cycles=10))
    return invert(mm.MeasurementSet(hangs, meas), solve_for=["Izz"], unc={**EXACT, **unc}, ladder=False)


def test_the_fit_check_counts_the_stated_priors():
    """Two hangings, one unknown: with the products taken as exact (0) the
    y+z-up period misses the model by ~Iyz's share (tens of sigma) and the
    answer is refused, with or without ``inertia`` on the old code; stated
    at 10 % (Iyz's std 0.028 kg m^2 covers the truth's 0.015) it passes,
    the check saying which components it counted, and Izz is within its
    std of the truth; stated at 1 % (std 0.0028: the truth 5.3 of it) the
    measurements are still refused."""
    with pytest.raises(InputError, match="no physical tensor reproduces"):
        _two_hangings({})
    res = _two_hangings({"inertia": 0.1})
    fit = res.to_json()["fit"]
    assert fit["passed"] and "inertia=0.1: Ixx, Iyy, Ixy, Ixz, Iyz" in fit["test"], fit
    assert abs(res.value("Izz") - 0.40) < 1.96 * res.sigma("Izz")
    with pytest.raises(InputError, match=r"counting the stated uncertainty .*inertia=0.01"):
        _two_hangings({"inertia": 0.01})


def test_sweep_cautions_where_the_priors_move_the_planned_answer(tmp_path):
    """``sweep``'s recommended point on the tilted plate: its Izz from the
    torsion depends on the config's Iyz and Iyy, which the predicted sigma
    takes as exact; a caution says by how much a 10 % error would move it.
    The planner's shift (the timing gain alone, its own MAC-tracked
    differences) against ``invert``'s ``plausible_shift`` for the period the
    prior gives (the estimate then the prior itself, one period, one
    unknown: the same first-order quantity by another path; 1e-3: the two
    central differences' truncation, ~1e-6 relative, and the solver's stop
    at 1e-9 of the largest moment).  The level bifilar of test_priorunc is
    not cautioned.  Old code: no caution (and no ``planned_prior_shift``)."""
    import json

    from click.testing import CliRunner

    from bifilar.cli import main
    from bifilar.estimation.prior_inertia import planned_prior_shift

    s = _plate()
    rest = rest_pose(s)
    T = linear_modes(s, rest).get("torsion").period
    shift, movers = planned_prior_shift(s, rest, "Izz", "torsion")
    ref = _invert(s, {}, period=T).to_json()["prior_inertia"]["plausible_shift"]["Izz"]["std"]
    assert shift == pytest.approx(ref, rel=1e-3) and movers == ["Iyz", "Iyy"]
    cfg = tmp_path / "plate.yaml"
    from tests.test_priorunc import PLATE

    cfg.write_text(yaml.safe_dump(PLATE))
    r = CliRunner().invoke(main, ["sweep", str(cfg), "--param", "length=1.4:1.4:1", "--component", "Izz",
                                  "--no-tensions", "--json"])
    assert r.exit_code == 0, r.output
    w = [x for x in json.loads(r.stdout)["warnings"] if "not solved for" in x]
    assert len(w) == 1 and "Izz from its torsion" in w[0] and "--uncertainty inertia=REL" in w[0], w
    level = {"gravity": 9.81, "body": {"mass": 2.0, "inertia": {"principal": [0.03, 0.05, 0.07]}},
             "rig": {"anchors": [[-0.2, 0.0, 1.0], [0.2, 0.0, 1.0]], "attachments": [[-0.2, 0.0, 0.05], [0.2, 0.0, 0.05]],
                     "lengths": [0.95, 0.95]}}
    sl = scene_from_dict(level, warn=False)
    # no first-order coupling (the central differences cancel to 5.6e-13 kg m^2), but Ixz moves the torsion
    # as its square (session 15): the planner's second difference over +-10 % of its scale agrees with
    # invert's re-solved pair (prior_curvature, two Gauss-Newton steps) on the same rig, 4.07e-4 kg m^2
    Tl = linear_modes(sl, rest_pose(sl)).get("torsion").period
    ref_l = _invert(sl, {}, period=Tl).to_json()["prior_inertia"]["plausible_shift"]["Izz"]["std"]
    shift_l, movers_l = planned_prior_shift(sl, rest_pose(sl), "Izz", "torsion")
    assert shift_l == pytest.approx(ref_l, rel=0.02) and shift_l > 1e-4 and movers_l == ["Ixz"]
