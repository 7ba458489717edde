"""The inertia components not solved for (docs/design.md, "priorunc, session 14").

``invert`` solves for some components; the others keep the config's values
(the prior) and were taken as exact, with no budget term and no word, even
where the rig couples them into the measured mode.  The session-13 audit's
plate (40 kg, 0.8 x 0.6 x 0.02 m, on a trifilar whose anchor circle is
tilted 0.3 rad; Izz from its torsion): a prior of Iyy 1.65 % high moved Izz
by -0.27 of its std, and one 10 % high by -1.6 (z mean -1.88, 5 of 8 draws
within 1.96; the harness in /tmp/priorunc).  Now the unknowns' sensitivity
to every prior is computed, ``--uncertainty inertia=REL`` budgets them
(``prior_inertia``), and without it ``invert`` warns where a 10 % prior
error would move an answer by more than a third of its std.

Every test here fails on the old code (the key ``inertia`` was refused as
unknown, the JSON had no ``prior_inertia``, no warning was given, the
interval was cut at the prior's triangle limit, the Monte Carlo held the
priors)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.config import scene_from_dict
from bifilar.scene import scene_with

PLATE = yaml.safe_load("""
name: 40 kg plate, anchor circle tilted 0.3 rad
gravity: 9.81
body: {mass: 40.0, inertia: {principal: [1.201333, 2.134667, 3.333333]}}
rig:
  anchors: [[0.0, 0.334368, 1.603432], [-0.303109, -0.167184, 1.448284], [0.303109, -0.167184, 1.448284]]
  attachments: [[0.0, 0.28, 0.01], [-0.242487, -0.14, 0.01], [0.242487, -0.14, 0.01]]
  lengths: [1.4, 1.4, 1.4]
""")
# a level, symmetric bifilar: no other component moves its torsion to first order
LEVEL = yaml.safe_load("""
gravity: 9.81
body: {mass: 2.0, inertia: {principal: [0.03, 0.05, 0.07]}}
rig:
  anchors: [[-0.2, 0.0, 1.0], [0.2, 0.0, 1.0]]
  attachments: [[-0.2, 0.0, 0.05], [0.2, 0.0, 0.05]]
  lengths: [0.95, 0.95]
""")
T_TORSION = 2.1858  # s, near the plate's torsion at the audit's truth (Ixx 1.22, Iyy 2.10, Izz 3.30)
EXACT = {"length": 0.0, "position": 0.0, "mass": 0.0, "com": 0.0}


def _plate(dIyy: float = 0.0):
    s = scene_from_dict(PLATE, warn=False)
    if dIyy:
        I = s.inertia.copy()
        I[1, 1] += dIyy
        s = scene_with(s, inertia=I)
    return s


def _invert(scene, unc, amplitude=0.0, cycles=10, period=T_TORSION, std=2e-3, **kw):
    from bifilar.estimation import measurements as mm
    from bifilar.estimation.invert import invert

    mset = mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3))],
                             [mm.Measurement("torsion", period, std, "period", "--period", amplitude=amplitude,
                                             cycles=cycles)])
    return invert(mset, solve_for=["Izz"], unc={**EXACT, **unc}, ladder=False, **kw)


@pytest.mark.parametrize("amplitude", [0.0, 0.1])
def test_the_prior_term_is_the_answers_change_with_the_prior_moved(amplitude):
    """The ``prior_inertia[Iyy]`` term against an independent finite
    difference: ``invert`` re-run with the config's Iyy moved by 1 % gives
    the estimate's change, which over the step times the stated 10 % of Iyy
    must be the term (and the JSON's sensitivity its slope).  Linear
    (``--amplitude 0``) and nonlinear (0.1 rad over 3 cycles: the factor's
    ``dr/dIyy`` by one run).  Tolerance 2 %: the difference over 1 % of Iyy
    carries the curvature of Izz(Iyy) over that step (the term itself is
    linear; a 0.5 % step agrees with the 1 % one to 0.3 %), and the
    nonlinear fixed point stops at 1e-9 of the largest moment, 1e-5 of the
    change.  On the old code ``inertia`` is an unknown key (InputError)."""
    s = _plate()
    res = _invert(s, {"inertia": 0.1}, amplitude, cycles=3)
    doc = res.to_json()
    Iyy = float(s.inertia[1, 1])
    term = doc["budget"]["Izz"]["inputs"]["prior_inertia[Iyy]"]
    assert term["input_std"] == pytest.approx(0.1 * Iyy, rel=1e-12)
    # the group: every prior's term in quadrature (since priorfit the products' too: Iyz moves the torsion most)
    terms = {k: v["std"] for k, v in doc["budget"]["Izz"]["inputs"].items() if k.startswith("prior_inertia[")}
    group = doc["budget"]["Izz"]["groups"]["prior_inertia"]["std"]
    assert group == pytest.approx(float(np.sqrt(sum(v ** 2 for v in terms.values()))), rel=1e-9)
    d = 0.01 * Iyy
    moved = _invert(_plate(d), {"inertia": 0.1}, amplitude, cycles=3)
    slope = (moved.value("Izz") - res.value("Izz")) / d
    assert abs(slope) > 0.05  # the tilted rig couples Iyy into the torsion (-0.15 kg m^2 per kg m^2)
    assert term["std"] == pytest.approx(abs(slope) * 0.1 * Iyy, rel=0.02)
    sens = doc["prior_inertia"]["components"]["Iyy"]["sensitivity"]["Izz"]
    assert sens == pytest.approx(slope, rel=0.02)
    # the std is the quadrature of the old budget and the term
    old = _invert(s, {"inertia": 0.0}, amplitude, cycles=3)
    assert res.sigma("Izz") ** 2 == pytest.approx(old.sigma("Izz") ** 2 + group ** 2, rel=1e-6)


def test_an_unstated_prior_that_matters_is_warned_and_a_stated_one_is_not():
    """Without ``--uncertainty inertia=`` the answer is the old one (the
    priors exact) but a warning names the prior that a 10 % error would let
    move Izz by more than a third of its std (here 1.7 stds, Iyy), the
    option and ``--solve-for``; stated (even 0) no warning.  A level
    bifilar, whose torsion no other component moves at first order, is
    warned of Ixz, which moves it at second order (session 15: before, the
    warning was first order only and said nothing here, nor on the Solar
    Boat, whose Izz a 10 % Ixz moves by 28 stds)."""
    res = _invert(_plate(), {})
    w = [x for x in res.warnings if "not solved for" in x]
    assert len(w) == 1 and "\n" not in w[0], res.warnings
    assert "Iyy" in w[0] and "--uncertainty inertia=" in w[0] and "--solve-for" in w[0]
    assert "Ixx" not in w[0]  # the plate's torsion does not depend on Ixx here (sensitivity 0)
    pi = res.to_json()["prior_inertia"]
    assert pi["stated"] is False and pi["relative_std"] == 0.0
    assert pi["plausible_shift"]["Izz"]["in_std"] > 1.0
    assert "prior_inertia" not in res.to_json()["budget"]["Izz"]["groups"]
    assert not [x for x in _invert(_plate(), {"inertia": 0.0}).warnings if "not solved for" in x]
    assert not [x for x in _invert(_plate(), {"inertia": 0.1}).warnings if "not solved for" in x]
    # a level, symmetric bifilar: at first order the torsion depends on Izz alone, at second on Ixz too
    import copy

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes

    s = scene_from_dict(LEVEL, warn=False)
    T = linear_modes(s, rest_pose(s)).get("torsion").period
    res = _invert(s, {}, period=T, std=1e-4)
    w = [x for x in res.warnings if "not solved for" in x]
    assert len(w) == 1 and "Ixz" in w[0] and "Ixx" not in w[0] and "Iyy" not in w[0], res.warnings
    pi = res.to_json()["prior_inertia"]
    assert max(abs(v) for v in pi["components"]["Ixz"]["sensitivity"].values()) < 1e-9  # no first order
    # independent: the truth's Ixz at 10 % of its scale, timed exactly, inverted with the prior's 0: the
    # answer moves by |b| (the even response's second-order term); the warning's RMS distance is sqrt(3)|b|
    moved = copy.deepcopy(LEVEL)
    I0 = moved["body"]["inertia"].pop("principal")
    ixz = 0.1 * (I0[0] * I0[2]) ** 0.5
    moved["body"]["inertia"]["tensor"] = [[I0[0], 0, ixz], [0, I0[1], 0], [ixz, 0, I0[2]]]
    sm = scene_from_dict(moved, warn=False)
    Tm = linear_modes(sm, rest_pose(sm)).get("torsion").period
    b = abs(_invert(s, {}, period=Tm, std=1e-4).value("Izz") - I0[2])
    assert pi["plausible_shift"]["Izz"]["std"] == pytest.approx(3 ** 0.5 * b, rel=0.1)
    assert pi["plausible_shift"]["Izz"]["in_std"] > 1.0 / 3.0  # prior_inertia.WARN_SHIFT


def test_a_limit_set_by_an_uncertain_prior_does_not_cut_the_interval():
    """The interval is cut where no real body lies (Izz <= Ixx + Iyy); with
    Ixx and Iyy known only to 10 % that limit is as uncertain as they are,
    so it must not cut: the old rule cut the plate's interval at 3.336 kg
    m^2 (the priors' sum), 0.026 short of its upper end."""
    res = _invert(_plate(), {"inertia": 0.1})
    s = _plate()
    limit = float(s.inertia[0, 0] + s.inertia[1, 1])
    lo, hi = res.interval[0]
    assert hi > limit and res.interval_clipped == [None]
    # the uncut interval: +-1.96 std (the sigma points' symmetrised quantiles differ from it by 2e-5 of k here)
    v, k = res.value("Izz"), 1.96 * res.sigma("Izz")
    assert lo == pytest.approx(v - k, abs=1e-3 * k) and hi == pytest.approx(v + k, abs=1e-3 * k)


def test_the_monte_carlo_draws_the_stated_priors():
    """The Monte Carlo check draws the components not solved for about their
    priors when their uncertainty is stated: with a period known to 1e-4 s
    and exact inputs the prior term is 99.9 % of the variance, so a Monte
    Carlo that held the priors would spread ~0.05 of the std (and warn).
    40 draws: the sample std's own error is ~11 %, the bounds 0.7-1.3 are
    2.7 of it."""
    res = _invert(_plate(), {"inertia": 0.1}, std=1e-4, monte_carlo=40, seed=7)
    assert res.budget.grouped(0)["prior_inertia"][0] > 0.99
    ratio = float(res.monte_carlo.std[0] / res.sigma("Izz"))
    assert 0.7 < ratio < 1.3, ratio
    assert not [x for x in res.warnings if "Monte Carlo" in x], res.warnings


def test_the_option_on_the_command_line_and_its_refusal(tmp_path):
    """``--uncertainty inertia=REL`` on the command line, in the JSON's
    ``assumed_uncertainty``; above 1 (100 %) exit 2 naming the key."""
    cfg = tmp_path / "plate.yaml"
    cfg.write_text(yaml.safe_dump(PLATE))
    args = ["invert", str(cfg), "--period", f"torsion={T_TORSION}+-0.002", "--amplitude", "0", "--solve-for", "Izz",
            "--json"]
    r = CliRunner().invoke(main, args + ["--uncertainty", "inertia=0.05"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["assumed_uncertainty"]["inertia"]["value"] == 0.05
    assert doc["prior_inertia"]["components"]["Iyy"]["std"] == pytest.approx(0.05 * 2.134667, rel=1e-9)
    assert doc["budget"]["Izz"]["groups"]["prior_inertia"]["std"] > 0
    r = CliRunner().invoke(main, args + ["--uncertainty", "inertia=2"])
    assert r.exit_code == 2 and "inertia" in r.output and "Traceback" not in r.output, r.output


@pytest.mark.parametrize("key", ["inertia", "release"])
def test_sweep_names_invert_only_keys_as_invert_s(key):
    # a config written for invert (its uncertainty block) or a --sigma with invert's keys: sweep and plan
    # predict invert's sigma without them, and say whose key it is (it was "unknown uncertainty key")
    from bifilar.errors import InputError
    from bifilar.studies.settings import resolve_uncertainty

    with pytest.raises(InputError) as e:
        resolve_uncertainty({"uncertainty": {key: 0.01}})
    assert e.value.field == f"uncertainty.{key}" and "invert's" in str(e.value) and "--uncertainty" in str(e.value)
    with pytest.raises(InputError) as e:
        resolve_uncertainty({}, {key: 0.01})
    assert e.value.field == "--sigma" and "invert's" in str(e.value)
    with pytest.raises(InputError, match="unknown uncertainty key"):
        resolve_uncertainty({}, {"inertiaa": 0.01})


def test_where_no_std_is_printed_the_prior_warning_does_not_quote_one():
    """The thesis plate at its knife edge: no std can be given (inputs
    without a derivative: JSON null), yet the priors' warning said "move Izz
    by 12 of its std", a std the user never sees.  It now gives the shift in
    SI units beside the ratio to the budget without those inputs.  The
    shift is Iyz's at second order, the pitch being neutral: Izz - Iyz^2/Iyy
    moves Izz by 1 % (2.6 kg m^2) at 10 % of its scale, so the RMS distance
    sqrt(3)|b| of Iyz alone is ~4.5 and with Ixz ~4.8 kg m^2."""
    import json

    from click.testing import CliRunner

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.cli import main
    from bifilar.config import load_scene
    from conftest import CONFIGS

    cfg = CONFIGS / "thesis_plate_rest.yaml"
    s = load_scene(cfg, warn=False)
    T = linear_modes(s, rest_pose(s)).get("torsion").period
    r = CliRunner().invoke(main, ["invert", str(cfg), "--period", f"torsion={T!r}+-1e-3", "--amplitude", "0",
                                  "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["inertia"]["Izz"]["std"] is None and d["std_unavailable"]
    (w,) = [x for x in d["warnings"] if "not solved for" in x]
    assert "of its std" not in w and "without the inputs that have no derivative" in w and "Iyz" in w
    iyy, izz = s.inertia[1, 1], s.inertia[2, 2]
    b = 0.01 * izz  # Iyz = 0.1 sqrt(Iyy Izz): Iyz^2 / Iyy = 0.01 Izz, the torsion's inertia drop
    shift = float(w.split("move Izz by ")[1].split(" ")[0])
    assert 3 ** 0.5 * b <= shift <= 1.2 * 3 ** 0.5 * b, (shift, b, iyy)
