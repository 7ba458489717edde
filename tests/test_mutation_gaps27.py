"""Mutation round 27 (docs/mutation.md, "Round 27"): tests that kill the
surviving mutants of session 26's new code (elastic26's stretch rule and
elastic_split's drawn-config checks, rank26/plan26's guards, camera26's
floors).  Every expected value is worked out by hand or by an independent
formulation, never taken from the code under test; each test's docstring
names the mutants it kills (ids of ``scripts/mutate.py``'s mutants of the
module at 9bd2205)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from test_plan26 import _hand
from test_twin26 import twin  # noqa: F401  (the 4-wire twin's fixture: scene, rest, modes, risks)


# ---------------------------------------------------------------------------
# studies/ranking.py (rank26, plan26), studies/point_hangings.py (rank26)
# ---------------------------------------------------------------------------

def test_a_ranked_component_exactly_on_the_bands_upper_end_is_marginal():
    """``marginal``'s band is 40-60 % of the 50 % line, "both ends
    included": a ranked component at exactly 0.6 (the double (1 + 0.2) x 0.5,
    the same as 0.6) is marginal, one at 0.6000001 is not (rank26's test
    has the lower end and the set-aside upper end, not the ranked upper
    end).  Kills ranking 67 (``v <= hi -> v < hi``)."""
    from bifilar.studies.ranking import marginal

    assert (1 + 0.2) * 0.5 == 0.6  # the band's end is this double
    best = {"params": {"spacing": 1.0}, "components": {"Ixx": {"rel_sigma": 0.6}, "Iyy": {"rel_sigma": 0.6000001}}}
    assert [e["component"] for e in marginal(best, ["Ixx", "Iyy"], [])] == ["Ixx"]


def test_the_separation_guard_skips_components_without_a_mode_counted_or_not():
    """A component with no mode at the point has ``separation`` None: it
    neither sets the guard nor breaks the minimum, whether the ranking
    counts it (``among``) or the point is read without a ranking (a point
    without its own top-level ``separation``, as a journal from before the
    field).  By hand: 0.05 (Izz's); counted alone, Ixy gives inf (no counted
    component has a mode).  Kills ranking 86 (``isinstance(e, dict) and ...
    -> or``: None enters min, a TypeError), 88 (``point.get("components") or
    {} -> and``: the components never read, None) and 89 (as 86 on the old
    point's path)."""
    from bifilar.studies.ranking import point_separation

    comps = {"Izz": {"separation": 0.05, "mode": "torsion"}, "Ixy": {"separation": None, "mode": None}}
    assert point_separation({"components": comps, "separation": 0.05}, ["Izz", "Ixy"]) == 0.05
    assert point_separation({"components": comps, "separation": 0.05}, ["Ixy"]) == math.inf
    assert point_separation({"components": comps}) == 0.05  # no ranking, no top-level figure: the components'


def test_a_point_whose_runs_lack_slack_wires_keeps_its_own_limits():
    """``guarded_limits``: a point from before the per-run slack figure
    (``tension.by_mode`` without ``slack_wires``, a resumed journal) keeps
    its own figures over every run, even where a run would be left out (the
    swing's peak 3 N and depth 1.3 m, wire 2 slack).  Kills ranking 97
    (``or -> and``: the left-out branch read ``by_t[m]["slack_wires"]``, a
    KeyError)."""
    from bifilar.studies.ranking import guarded_limits

    p = _hand({"swing-x": (3.0, 1.3, [2]), "torsion": (2.0, 1.1, [])}, {"Iyy": "swing-x", "Izz": "torsion"})
    for run in p["tension"]["by_mode"].values():
        del run["slack_wires"]
    assert guarded_limits(p, ["Izz"]) == {"peak": 3.0, "depth": 1.3, "slack_wires": [2], "left_out": []}


def test_a_reason_is_cut_to_exactly_note_chars_with_an_ellipsis():
    """``no_sigma_reason``: cut at ``NOTE_CHARS`` (160) characters with
    "...": a reason of exactly 160 characters (": " and 158 more) is
    kept whole; one of 161 becomes its first 157 characters and "..." (160
    in all).  Kills ranking 151 (``<= NOTE_CHARS -> <``) and 153 (``NOTE_CHARS
    - 3 -> - 4``: 159 characters)."""
    from bifilar.studies.ranking import NOTE_CHARS, no_sigma_reason

    assert NOTE_CHARS == 160
    exact = ": " + "x" * 158
    assert no_sigma_reason({"sigma_unavailable": exact}) == exact
    longer = ": " + "y" * 159
    assert no_sigma_reason({"sigma_unavailable": longer}) == ": " + "y" * 155 + "..."


def test_the_linear_caution_names_the_largest_factor_among_the_plans_components():
    """``point_hangings.linear_caution``: Izz's variance at the point is 90 %
    second order (its own sigma 1 / sqrt(0.1) = 3.16x its linear one), Ixx's
    50 % (1.41x, above LINEAR_CAUTION 1.1); Iyy, in the plan, has no sigma
    at the point and Ixy no shares (a point from before them): both passed
    over.  Without Izz in the plan the caution names Ixx at 1.41x; with it,
    Izz (the largest factor, listed first); a component wholly second order
    (linear sigma 0) is named (an infinite factor), not a ZeroDivisionError.
    Kills point_hangings 5 (``not s or rel is None -> and``: Ixy's missing
    share read, a TypeError), 6 (``rel is None or not isfinite -> and``:
    ``isfinite(None)``), 18 (the factor compared with the worst one's
    relative sigma: the last above 1.1 named) and 12 (``lin > 0 ->
    >=``)."""
    from bifilar.studies.point_hangings import linear_caution

    point = {"components": {"Izz": {"rel_sigma": 0.25, "shares": {"second_order": 0.9}},
                            "Ixx": {"rel_sigma": 0.1, "shares": {"second_order": 0.5}},
                            "Iyy": {"rel_sigma": None, "shares": {"second_order": 0.5}},
                            "Ixy": {"rel_sigma": 0.2}}}
    plan = {"accuracy": {"Ixx": 0.07, "Iyy": 0.1, "Ixy": 0.1}}
    line = linear_caution(point, plan, "the recommended point")
    assert "of Ixx's variance" in line and f"({1 / math.sqrt(0.5):.3g}x)" in line and "Izz" not in line
    line = linear_caution(point, {"accuracy": {**plan["accuracy"], "Izz": 0.03}}, "the recommended point")
    assert "of Izz's variance" in line and f"({1 / math.sqrt(0.1):.3g}x)" in line
    point["components"]["Ixx"]["shares"]["second_order"] = 1.0
    line = linear_caution(point, plan, "the recommended point")
    assert "of Ixx's variance" in line
    # no linear sigma to compare with: said in words, not as "(infx)" (session 27, mut27's finding)
    assert "inf" not in line and "where the linear terms give none" in line


# ---------------------------------------------------------------------------
# estimation/elastic_split.py (elastic26, twin26): the drawn configs' stiffnesses
# ---------------------------------------------------------------------------

def _c07(ea: float = 2000.0, lengths=None):
    from bifilar.config import scene_from_dict

    anchors = [[0.2, 0.2, 1.2], [-0.2, 0.2, 1.2], [-0.2, -0.2, 1.2], [0.2, -0.2, 1.2]]
    attach = [[0.2, 0.2, 0.01], [-0.2, 0.2, 0.01], [-0.2, -0.2, 0.01], [0.2, -0.2, 0.01]]
    cfg = {"name": "c07", "body": {"mass": 2.0, "inertia": {"principal": [0.03, 0.045, 0.06]}},
           "rig": {"anchors": anchors, "attachments": attach, "lengths": lengths or [1.2] * 4, "stiffness": ea}}
    return scene_from_dict(cfg, "test", warn=False)


def _hand_stretch(R, d, w, G, k, lam):
    """The independent formulation of the stretch directions: the stretch
    stiffness ``sum_i k_i g_i g_i^T`` (``g_i = G_i / |d_i|``, a wire's length
    change per unit of the pose) against the mass matrix ``diag(m, m, m, R I
    R^T)`` of c07's body by scipy's generalised ``eigh``, and ``kappa`` the
    Rayleigh quotient of equilibrium.constraint_hessians (its own loop)
    weighted by the multipliers ``lam`` (N/m), for the directions of the
    wires with a spring (``k > 0``), the stiffest first."""
    from scipy.linalg import eigh

    from bifilar.analysis.equilibrium import constraint_hessians

    g = G / np.linalg.norm(d, axis=1)[:, None]
    M = np.zeros((6, 6))
    M[:3, :3] = 2.0 * np.eye(3)
    M[3:, 3:] = R @ np.diag([0.03, 0.045, 0.06]) @ R.T
    ev, V = eigh(np.einsum("i,ij,ik->jk", k, g, g), M)  # ascending, V^T M V = 1
    n = int(np.sum(k > 0))
    top = V[:, ::-1][:, :n]
    return ev[::-1][:n], np.einsum("ij,ik,kj->j", top, np.einsum("i,ijk->jk", lam, constraint_hessians(d, w)), top)


#: two poses far from rest (rotation vector rad, CoM m): turned 0.8 and 0.4 rad, so R I R^T is not R I R
POSES = (([0.6, -0.4, 0.5], [0.01, -0.02, -1.19]), ([-0.3, 0.2, 0.1], [0.0, 0.01, -1.2]))


def test_drawn_stretch_stiffnesses_are_the_generalised_eigenproblem_at_a_turned_pose():
    """``elastic_split._stretch`` at two turned poses (:data:`POSES`, an
    anisotropic body), wire tensions 5, 0 (exactly: no spring, "at or below
    0 N"), -1 (slack) and 7 N, against :func:`_hand_stretch` with springs
    ``EA / L`` and multipliers ``T / |d|`` on the two taut wires only.  Kills
    elastic_split 14 (``tensions > 0 -> >= 0``: a spring on the 0 N wire), 29
    and 30 (the inertia turned as R I R), 33 (a slack wire's multiplier 1 /
    |d|), 34 (``T / |d| -> T |d|``) and stretch_held 56 (M^-1/2 doubled: mu
    and kappa 4x, their ratio and so every held count unchanged, but mu is
    documented in rad^2/s^2)."""
    from bifilar.analysis.equilibrium import constraint_jacobian
    from bifilar.estimation.elastic_split import _stretch
    from bifilar.rotations import rotvec_to_matrix

    sc = _c07()
    T = np.array([5.0, 0.0, -1.0, 7.0])
    Rs, Gs, ws, want_mu, want_kappa = [], [], [], [], []
    for rv, com in POSES:
        R = rotvec_to_matrix(np.array(rv))
        d, w, G = constraint_jacobian(sc, np.array(com), R)
        k = np.where(T > 0, 2000.0 / 1.2, 0.0)
        mu, kappa = _hand_stretch(R, d, w, G, k, np.where(T > 0, T / np.linalg.norm(d, axis=1), 0.0))
        want_mu.append(mu), want_kappa.append(kappa), Rs.append(R), Gs.append(G), ws.append(w)
    mu, kappa = _stretch(sc, np.array(Rs), np.array(Gs), np.array(ws), np.array([T, T]))
    assert mu[:, :2] == pytest.approx(np.array(want_mu), rel=1e-9)
    assert np.all(np.abs(mu[:, 2:]) < 1e-9 * mu[:, :1])  # the 0 N and the slack wire: no stretch
    assert kappa[:, :2] == pytest.approx(np.array(want_kappa), rel=1e-7, abs=1e-9)


def test_a_scenes_stretch_split_springs_only_the_stretched_wires():
    """``stretch_directions`` of an elastic scene at a pose
    (``stretch_split``): c07 turned (:data:`POSES`' first) with its lengths
    set so that wire 1 is stretched 1 mm, wire 2 is exactly its length
    (``|d|`` itself: not stretched, no spring), wire 3 1 mm slack and wire 4
    stretched 2 mm: the springs ``EA / L`` and the tensions ``EA / L (|d| -
    L)`` of wires 1 and 4 alone, against :func:`_hand_stretch`.  Kills
    stretch_held 77 (``* (ln > L) -> /``: a slack wire's spring infinite) and
    78 (``ln > L -> >=``: a spring on the unstretched wire)."""
    from bifilar.analysis.equilibrium import constraint_jacobian
    from bifilar.analysis.stretch_held import stretch_split
    from bifilar.rotations import rotvec_to_matrix

    rv, com = POSES[0]
    R = rotvec_to_matrix(np.array(rv))
    d, w, G = constraint_jacobian(_c07(), np.array(com), R)
    ln = np.linalg.norm(G[:, :3], axis=1)  # as stretch_split takes it
    L = ln + np.array([-1e-3, 0.0, 1e-3, -2e-3])
    sc = _c07(lengths=L.tolist())
    assert np.asarray(sc.lengths)[1] == ln[1]
    k = np.where(ln > L, 2000.0 / L, 0.0)
    want_mu, want_kappa = _hand_stretch(R, d, w, G, k, k * np.maximum(ln - L, 0.0) / ln)
    mu, kappa, _, _ = stretch_split(sc, R, G)
    assert mu[:2] == pytest.approx(want_mu, rel=1e-9) and np.all(np.abs(mu[2:]) < 1e-9 * mu[0])
    assert kappa[:2] == pytest.approx(want_kappa, rel=1e-7, abs=1e-9)


def test_the_held_count_is_the_stretch_rule_at_its_factor_ten_both_ends_included():
    """The rule (stretch_held's docstring): a direction is held where its
    stretch stiffness is *at least* 10x its geometric one's magnitude, above
    rounding.  By hand, mu 150, 10, 5 and 0 against |kappa| 1: held, held
    (10 >= 10), not, not (0 is rounding); ``elastic_split._held``, the count
    the drawn configs are compared by, is the same at its own factor: 2, and
    at margin 0.1 three, at 10 one.  Kills stretch_held 66 and elastic_split
    38 (the default margin 1 -> 2: held at 20x) and stretch_held 67 (``>=
    -> >``)."""
    from bifilar.analysis.stretch_held import held_mask, soft_mask
    from bifilar.estimation.elastic_split import _held

    mu, kappa = np.array([150.0, 10.0, 5.0, 0.0]), np.array([1.0, -1.0, 1.0, 1.0])
    assert held_mask(mu, kappa).tolist() == [True, True, False, False]
    assert soft_mask(mu, kappa).tolist() == [False, False, True, False]
    assert (_held(mu, kappa), _held(mu, kappa, 0.1), _held(mu, kappa, 10.0)) == (2, 3, 1)


def test_rounding_is_relative_to_the_stiffest_direction_and_no_stretch_holds_nothing():
    """"Stretch stiffness below 1e-12 of the largest is rounding": mu 100
    and 1e-11 (1e-13 of it) with kappa 1 and 0: the second is neither held
    nor soft (kills stretch_held 71, ``1e-12 * mu_max -> / mu_max``: 1e-14,
    the rounding held); every wire slack (mu all 0, kappa 0: no direction
    resists anything): nothing held or soft (kills stretch_held 70, ``mu >
    ... -> >=``: 0 >= 0 held every direction)."""
    from bifilar.analysis.stretch_held import held_mask, soft_mask

    assert held_mask(np.array([100.0, 1e-11]), np.array([1.0, 0.0])).tolist() == [True, False]
    assert not soft_mask(np.array([100.0, 1e-11]), np.array([1.0, 0.0]))[1]
    zero = np.zeros(4)
    assert not held_mask(zero, zero).any() and not soft_mask(zero, zero).any()


@pytest.fixture(scope="module")
def c07_rest():
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.estimation import elastic_split as es
    from bifilar.estimation.uncertainty import default_uncertainty

    sc = _c07()
    names, sd = es._inputs(sc, default_uncertainty())
    return sc, rest_pose(sc), names, sd


#: one input of each kind (c07's 33 inputs all: 3.4 s at load 13, the same verdicts)
SAMPLE = ["mass", "length.1", "anchor.1.x", "anchor.2.y", "attachment.3.z", "com.x", "com.y", "stiffness"]


def test_the_rests_gradients_are_central_differences_per_std(c07_rest):
    """``elastic_split._gradients`` (com, rotation vector and tensions per
    std of c07's inputs, one of each kind, forward differences at 1e-6 std) against
    central differences of the checked rest pose at 1e-3 std (truncation
    ~1e-6 of the curvature): they agree to 1.2e-6 of each array's largest
    entry; asserted 2e-5.  Kills elastic_split 45 (the step ``1e-6 / s``: a
    1 mm step on the lengths, 1.6e-4 .. 9.4e-4 off), 49 and 51 (com and
    rotation ``/ h -> * h``)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.estimation import elastic_split as es
    from bifilar.estimation.sensitivity import perturb
    from bifilar.rotations import matrix_to_rotvec

    sc, rest, names, sd = c07_rest
    pick = [names.index(n) for n in SAMPLE]
    names, sd = [names[j] for j in pick], sd[pick]
    got = es._gradients(sc, rest, names, sd)
    want = [np.zeros_like(x) for x in got]
    for j, (name, s) in enumerate(zip(names, sd)):
        h = 1e-3 * s
        a, b = rest_pose(perturb(sc, name, h)), rest_pose(perturb(sc, name, -h))
        want[0][j] = (a.com - b.com) / (2 * h) * s
        want[1][j] = matrix_to_rotvec(a.R @ b.R.T) / (2 * h) * s
        want[2][j] = (a.tensions - b.tensions) / (2 * h) * s
    for x, y in zip(got, want):
        assert np.max(np.abs(x - y)) < 2e-5 * np.max(np.abs(y))


def test_a_wire_re_planed_only_from_a_linear_slack_probability_of_one_in_a_million(c07_rest):
    """``_slack_planes``' skip: a wire whose linear slack probability
    ``Phi(-mean / |grad|)`` is below ``PLANE_SKIP`` (1e-6) keeps its linear
    plane; above it, the plane is re-taken at ``DESIGN_SHARE`` (0.9) of the
    way to the linear slack point.  Hand-made: c07's rest with tensions 1 N
    on wires 1 and 2 and gradients along the mass's deviate alone, so that
    ``Phi`` is 7e-7 (kept exactly) and 2e-6 (re-planed); wires 3 and 4 have
    none (gg 0, kept).  The re-planed plane is checked independently: at the
    design point (0.9 x 1 N / grad deviates of the mass, moving no wire near
    slack) it equals the exact elastic rest's tension of wire 2 there, its
    slope that tension's central difference in the mass (1e-3 std).  Kills
    elastic_split 58 (``or -> and``: wire 1 re-planed, or 1 / 0), 59 (``0.5
    -> 1.0``: Phi doubled, 1.4e-6) and 60 (``0.5 * erfc -> /``)."""
    from types import SimpleNamespace

    from scipy.special import ndtri

    from bifilar.analysis.elastic_rest import elastic_rest
    from bifilar.estimation import elastic_split as es
    from bifilar.estimation.sensitivity import perturb

    sc, rest, names, sd = c07_rest
    j = names.index("mass")
    T = np.array([1.0, 1.0, *rest.tensions[2:]])
    dT = np.zeros((1, 4))
    dT[0, :2] = -1.0 / ndtri(7e-7), -1.0 / ndtri(2e-6)  # N per std: mean / |grad| = 4.83, 4.61
    mean, grad = es._slack_planes(sc, SimpleNamespace(com=rest.com, R=rest.R, tensions=T), ["mass"], sd[[j]], dT)
    assert mean[0] == 1.0 and grad[0, 0] == dT[0, 0]  # kept
    assert mean[2:].tolist() == T[2:].tolist() and not grad[:, 2:].any()
    zp = -0.9 * 1.0 / dT[0, 1]  # the design point, in stds of the mass

    def tension(z):
        moved = perturb(sc, "mass", z * sd[j])
        return elastic_rest(moved, moved.stiffness, rest.com, rest.R)[2][1]

    slope = (tension(zp + 1e-3) - tension(zp - 1e-3)) / 2e-3
    assert grad[0, 1] == pytest.approx(slope, rel=1e-5)
    assert mean[1] + zp * grad[0, 1] == pytest.approx(tension(zp), abs=1e-9)
    assert abs(mean[1] - 1.0) > 1.0  # re-planed: the real tension (4.9 N) there, not the hand-made 1 N


@pytest.mark.parametrize("ratio, near", [(150.0, False), (99.0, True), (1.01, True)])
def test_the_drawn_configs_are_near_the_rule_within_a_factor_ten_either_way(c07_rest, monkeypatch, ratio, near):
    """``drawn_rig_risks``: a drawn config is near the rule where a direction's
    stretch over geometric stiffness lies within a factor 1 / HELD_MARGIN (10)
    of the rule's 10 either way, i.e. between 1x and 100x, and it holds another
    number where it crosses 10x.  The stiffnesses are hand-set (``_stretch``
    wrapped: two directions at 1e4x, the third at ``ratio`` in every drawn
    config, 150x at the config: held 3), c07's lengths and EA the only inputs
    (``position``, ``mass``, ``com`` stds 0), 200 draws: p_near is the share of
    the taut draws (by hand from the drawn tensions) at 99x and 1.01x, 0 at
    150x; p_held that share at 1.01x (below 10x), 0 else.  The drawn tensions the
    wrapper sees are checked too: ``rest + z . dT`` with ``z`` the seed's
    normal draws and ``dT`` central differences of the checked rest pose per
    std (1e-3 std).  Kills elastic_split 109 (``1.0 / HELD_MARGIN -> 2.0 /``:
    the band to 200x, 150 near) and 106 (the drawn tensions ``rest - z . dT``)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.estimation import elastic_split as es
    from bifilar.estimation.sensitivity import perturb
    from bifilar.estimation.uncertainty import default_uncertainty

    sc, rest, _, _ = c07_rest
    unc = dict(default_uncertainty(), position=0.0, mass=0.0, com=0.0)
    names, sd = es._inputs(sc, unc)
    assert [n for n in names if not n.startswith("length.")] == ["stiffness"] and len(names) == 5
    seen = []

    def fake(scene, R, G, w, tensions):
        seen.append(np.array(tensions, float))
        r = 150.0 if np.ndim(tensions) == 1 else ratio
        mu = np.broadcast_to(np.array([1e4, 1e4, r, 0.0]), np.shape(tensions)).copy()
        return mu, np.ones_like(mu)

    monkeypatch.setattr(es, "_stretch", fake)
    risks = es.drawn_rig_risks(sc, rest, unc, draws=200, seed=5)
    dT = np.zeros((len(names), 4))
    for j, (name, s) in enumerate(zip(names, sd)):
        a, b = rest_pose(perturb(sc, name, 1e-3 * s)), rest_pose(perturb(sc, name, -1e-3 * s))
        dT[j] = (a.tensions - b.tensions) / 2e-3
    z = np.random.default_rng(5).standard_normal((200, len(names)))
    drawn = rest.tensions + z @ dT
    assert seen[-1] == pytest.approx(drawn, abs=1e-5 * np.max(np.abs(z @ dT)))
    taut = float(np.mean(np.all(drawn >= 0, axis=1)))
    assert taut > 0.9 and risks.held == 3
    assert risks.p_near == pytest.approx(taut if near else 0.0, abs=1e-12)
    assert risks.p_held == pytest.approx(taut if ratio < 10 else 0.0, abs=1e-12)


def _risks(p_slack=0.0, p_held=0.0, p_near=0.0, failed=None):
    from bifilar.estimation.elastic_split import DrawnRigRisks

    return DrawnRigRisks(p_slack, p_held, p_near, max(p_slack, p_held), np.array([1.0, 1.5, 1.0, 1.5]),
                         np.array([4.9, 4.9, 4.9, 4.9]), 3, failed)


def test_per_mode_is_near_only_with_no_other_reason_to_refuse():
    """``per_mode`` by its docstring: some drawn configs come near the rule
    (p_near > 0), none crosses it (p_held 0), and ``sigma_refusal`` refuses
    for no other reason (not failed, p_slack < 5 %); hand-made risks.  Kills
    elastic_split 150, 151 and 154 (an ``and -> or`` each: per-mode checks
    on a rig refused for a crossing, a failure or slack)."""
    from bifilar.estimation.elastic_split import per_mode

    assert per_mode(_risks(p_near=0.5, p_slack=0.01))
    for r in (None, _risks(p_near=0.5, p_held=0.2), _risks(p_near=0.5, p_slack=0.05), _risks(p_slack=0.01),
              _risks(p_near=0.5, failed="no rest")):
        assert not per_mode(r), r


def test_a_near_hold_bias_of_at_most_a_tenth_of_the_sigma_keeps_it():
    """``near_hold_refusal``: the sigma is kept where the bias is *at most*
    ``COUPLING_SHARE`` (0.1) of it, either sign: 0.05 against 0.5 (the same
    double as 0.1 x 0.5) and -0.05 kept, 0.0500001 refused with its ratio.
    Kills elastic_split 162 (``<= -> <``)."""
    from bifilar.estimation.elastic_split import near_hold_refusal

    assert 0.1 * 0.5 == 0.05
    r = _risks(p_near=1.0)
    assert near_hold_refusal(r, "Izz", 0.05, 0.5) is None and near_hold_refusal(r, "Izz", -0.05, 0.5) is None
    text = near_hold_refusal(r, "Izz", 0.0500001, 0.5)
    assert "moves Izz by 0.05 against the wires' springs, 0.1 of its sigma (more than 0.1)" in text


def test_a_components_near_hold_bias_is_its_periods_bias_times_its_derivative(twin):
    """``component_refusals`` on test_twin26's 4-wire twin (p_near 1): the
    swing-x period's bias ``b`` (test_stretch's hand-differenced springs less
    the model's period, 7.6e-5 of it) through a derivative dI/dT of 4 kg
    m^2/s (twin26's tests use 1, where a product and a quotient agree) is
    ``4 b``: refused just below ``4 |b| / 0.1`` of sigma, kept just above (5 %),
    the text quoting ``4 |b|`` (to 1 %: the model's elastic periods and the
    hand-differenced springs' are 0.4 % apart in this bias).  Where
    ``per_mode`` does not apply nothing is refused here ("{} where per_mode
    does not apply").  Kills elastic_split 165 (``bias * dI_dT -> /``) and
    164 (``not per_mode or not chosen -> and``)."""
    from types import SimpleNamespace

    from bifilar.estimation.elastic_split import component_refusals
    from test_stretch import _spring_periods

    sc, rest, ms, risks = twin
    k = [m.label for m in ms.modes].index("swing-x")
    T = ms.modes[k].period
    springs = _spring_periods(sc, rest.com, rest.R)
    b = springs[np.argmin(abs(springs - T))] - T
    for factor, refused in ((0.95, True), (1.05, False)):
        budget = SimpleNamespace(dI_dT=4.0, value_sigma=factor * 4.0 * abs(b) / 0.1)
        got = component_refusals(risks, sc, rest, ms, {"Iyy": k}, {"Iyy": budget})
        assert ("Iyy" in got) == refused, (factor, got)
    tiny = {"Iyy": SimpleNamespace(dI_dT=4.0, value_sigma=abs(b))}  # the bias 4 sigma
    # where per_mode does not apply (no draw near the rule, or a crossing: the rig's own refusal) none is refused here
    assert component_refusals(_risks(), sc, rest, ms, {"Iyy": k}, tiny) == {}
    assert component_refusals(_risks(p_held=0.2, p_near=0.3), sc, rest, ms, {"Iyy": k}, tiny) == {}
    text = component_refusals(risks, sc, rest, ms, {"Iyy": k}, tiny)
    quoted = float(text["Iyy"].split("moves Iyy by ")[1].split(" ")[0])
    assert quoted == pytest.approx(4.0 * abs(b), rel=1e-2)  # the model's springs vs the hand ones: 0.4 % apart


def test_stiffer_wires_are_advised_for_the_held_directions_not_for_slack():
    """``sigma_refusal``: stiffer wires help where the drawn configs come near
    or across the held-direction rule (the stretch's share grows with EA),
    and make slack worse (c07: 0.13 % slack at EA 2 kN, 73.8 % at 20 kN), so
    a refusal for slack alone (p_near 0) does not advise them; one for a
    crossing does.  Kills elastic_split 129 (``p_near > 0 -> >= 0``) and 130
    (``> 0 -> > 1``)."""
    from bifilar.estimation.elastic_split import sigma_refusal

    slack = sigma_refusal(_risks(p_slack=0.7))
    held = sigma_refusal(_risks(p_held=0.2, p_near=0.3))
    assert "70 % of the configs leave a wire slack" in slack and "stiffer" not in slack
    assert "in 20 % of the configs" in held and "stiffer wires (the stretch's share grows with EA)" in held


# ---------------------------------------------------------------------------
# models/native_call.py (perfcall26): the load-time check
# ---------------------------------------------------------------------------

def test_the_call_extensions_check_wants_the_same_bits_in_the_same_output_array(monkeypatch):
    """``_call_agrees`` (documented: the callable and the ctypes ``f`` give
    the same bits at two states, into and as the same output array), with a
    hand-made ``f`` (no compiler needed): a callable writing ``f``'s values
    into ``out`` and returning it passes; one returning a new array with the
    same values fails, as does one 1 ulp off in one element.  Kills
    native_call 8 (``return False -> True`` where the result is not ``out``;
    the line no test reached)."""
    from bifilar.models import native_call as nc
    from bifilar.models import native_kernel as nk

    pv, out = np.array([2.0, 3.0]), np.empty(13)

    def f(y, t):
        out[:] = np.sin(pv[0] * y) + pv[1] * y ** 2
        return out

    monkeypatch.setattr(nk, "_ctypes_f", lambda func, values, ticks: (f, f, pv, out))
    monkeypatch.setattr(nk, "_address", lambda func: 0)

    def call(kind):
        def make(addr, p, o, n, plain):
            assert (addr, n) == (0, 13) and p is pv and o is out and plain is f

            def k(y, t):
                v = np.sin(2.0 * y) + 3.0 * y ** 2
                if kind == "ulp":
                    v[5] = np.nextafter(v[5], np.inf)
                if kind == "new":
                    return v
                o[:] = v
                return o
            return k
        return make

    assert nc._call_agrees(call("same"), None, [2.0, 3.0])
    assert not nc._call_agrees(call("new"), None, [2.0, 3.0])
    assert not nc._call_agrees(call("ulp"), None, [2.0, 3.0])


# ---------------------------------------------------------------------------
# estimation/signal_harmonic2.py (camera26, camera26b): the record's length, the note's floor
# ---------------------------------------------------------------------------

def test_the_harmonics_floor_does_not_depend_on_when_the_record_starts():
    """camera26b's seed-148 record (a three_mode fit whose third oscillation
    stands in for the swing's 2nd harmonic: the floor is the whole noise g,
    the premise checked by hand in test_camera26b) started at t = 100 s in
    place of 0: the same decision and the same term, since the record's
    length is t[-1] - t[0], 10 s; its note says the floor (the whole noise)
    set the term and that the third oscillation stands in for the harmonic.
    Kills signal_harmonic2 20 (``t[-1] - t[0] -> +``: 210 s, the harmonic
    never within 0.75 / T_record: floor 0.3), 110 (the stand-in clause on
    the other floors only) and 112 (``0 < best -> 1 <``: the floor never
    said)."""
    from bifilar.estimation import signal_harmonic2
    from bifilar.estimation.signal import fit_period

    from test_readers20 import _camera_like

    t, x, T = _camera_like(148, dur=10.0)
    fit = fit_period(t + 100.0, x, "auto")
    h = fit.uncertainty["second_harmonic_fit"]
    f1, f2, f3 = (m["frequency"] for m in fit.modes)
    assert fit.model == "three_mode" and abs(2 * f2 - f1) * 10.0 < 0.75 <= abs(f3 - f1) * 10.0
    assert h["floor"] == signal_harmonic2.STAND_IN_FLOOR
    assert fit.uncertainty["second_harmonic"] == pytest.approx(h["shift_noise"], rel=1e-12)
    # the note says the floor set the term, and why (the shift within its noise: camera26b's premise)
    assert abs(h["period_shift"]) < h["shift_noise"]
    note = next(n for n in fit.notes if n.startswith("residuals may hold the 2nd harmonic"))
    assert "(the floor, 1 of that noise" in note and "stands in for this unresolved harmonic)" in note


def test_a_term_above_its_floor_is_the_unbiased_estimate_and_its_note_names_no_floor():
    """Round 24's seed-15 record (two_mode, from t = 100 s; its shift and
    noise checked there against an independent Frisch-Waugh-Lovell
    projection): the shift is over 3x its noise, so the term is
    ``sqrt(shift^2 - g^2)`` by hand from those two, above ``NOISE_FLOOR g``,
    and the note says nothing of a floor.  Kills signal_harmonic2 115
    (``floor * g -> floor / g``: the floor named on every term)."""
    from bifilar.estimation.signal import fit_period
    from bifilar.estimation.signal_harmonic2 import NOISE_FLOOR, second_harmonic_term

    from test_mutation_gaps24 import _refit_copy
    from test_readers20 import _camera_like

    t, x, _ = _camera_like(15, dur=10.0)
    case = _refit_copy(fit_period(t + 100.0, x, "auto"))
    term = second_harmonic_term(case)
    h = case.uncertainty["second_harmonic_fit"]
    assert h["floor"] == NOISE_FLOOR and abs(h["period_shift"]) > 3 * h["shift_noise"]
    assert term == pytest.approx(math.sqrt(h["period_shift"] ** 2 - h["shift_noise"] ** 2), rel=1e-12)
    assert len(case.notes) == 1 and "floor" not in case.notes[0]


def test_a_zero_term_from_a_fitted_harmonic_names_no_floor():
    """The real KTH 20s/0.35 record (skipped without ../shared/data): its
    three_mode fit's third oscillation is the swing's 2nd harmonic (camera26:
    floor 0), the shift within its noise, so the term is 0 and the note names
    no floor (a floor of 0 set nothing).  Kills signal_harmonic2 113 (``0 <
    best -> <=``: "the floor, 0 of that noise")."""
    from test_camera26 import _kth

    fit = _kth("20s", 0.35)
    h = fit.uncertainty["second_harmonic_fit"]
    assert h["floor"] == 0.0 and fit.uncertainty["second_harmonic"] == 0.0
    note = next(n for n in fit.notes if n.startswith("residuals may hold the 2nd harmonic"))
    assert "floor" not in note


# ---------------------------------------------------------------------------
# studies/point_estimators.py (moved from point.py in session 26, never mutated)
# ---------------------------------------------------------------------------

def test_the_linear_estimate_is_the_inertia_whose_linear_period_is_the_target():
    """``linear_estimate`` (test_perf26c compares it only with itself under
    another MAC): the KTH trifilar's Izz moved +3 %, its torsion's linear
    period from that scene's own rest pose and ``linear_modes`` (not the
    fixed-rest ``modes_of_inertia`` the secant uses) as the target: the
    estimate is the moved Izz to 1e-12 of it (the secant stops at 1e-13 of
    the period; found 6e-16); the unmoved period gives Izz itself.  Kills
    point_estimators 5 (``f0 == 0.0 -> !=``: Izz returned for any target)."""
    from pathlib import Path

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.sensitivity import perturb
    from bifilar.studies.point_estimators import linear_estimate

    sc = scene_from_dict(read_yaml(Path(__file__).resolve().parents[1] / "configs" / "trifilar_kth.yaml"), warn=False)
    rest = rest_pose(sc)
    ms = linear_modes(sc, rest)
    k = [m.label for m in ms.modes].index("torsion")
    I0 = float(sc.inertia[2, 2])
    moved = perturb(sc, "Izz", 0.03 * I0)
    target = linear_modes(moved, rest_pose(moved)).modes[k].period
    slope = 0.5 * ms.modes[k].period / I0  # T ~ sqrt(I): a start, not the answer
    assert linear_estimate(sc, "Izz", k, target, ms, rest, slope) == pytest.approx(1.03 * I0, rel=1e-12)
    assert linear_estimate(sc, "Izz", k, ms.modes[k].period, ms, rest, slope) == I0


def test_the_ladders_small_angle_rung_is_for_the_torsion_about_the_vertical_only():
    """``_Ladder.biases`` (moved with point_estimators): the small-angle
    formula (thesis 5.2.18) is a torsion about the vertical; a swing, or a
    torsion about a non-vertical axis, gets no figure and the note saying
    so (the KTH trifilar: swing-x for Izz, the torsion with the axis not
    vertical).  Kills point_estimators 48 (``and -> or``)."""
    from pathlib import Path

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.studies.point_estimators import _Ladder

    sc = scene_from_dict(read_yaml(Path(__file__).resolve().parents[1] / "configs" / "trifilar_kth.yaml"), warn=False)
    ladder = _Ladder(sc, rest_pose(sc))
    for mode, vertical in (("swing-x", True), ("torsion", False)):
        bias, notes = ladder.biases("Izz", mode, 1.4, vertical)
        assert bias["small_angle"] is None and notes["small_angle"].startswith("applies only to the torsion"), mode
