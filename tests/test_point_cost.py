"""The shortcuts that make a sweep point cheaper (issue 14, docs/performance.md
"Sweep points and plan") give what the paths they replace give:

* :func:`bifilar.analysis.modes.modes_of_inertia` (the reduced stiffness
  once, only the eigenproblem per inertia) against :func:`linear_modes` of
  the scene with that inertia, and against scipy's generalized eigensolver;
* :func:`bifilar.studies.point.linear_estimate` sharing one stiffness over a
  point's components (``at``) against its own Newton + stiffness, and its
  root against the linear period it must reproduce;
* :func:`bifilar.estimation.honest.honest_stds` fed the point's analytic
  sensitivity (``sens``) against the budget's own Jacobian;
* (session 6) the batched ``mode_sets`` with repeated eigenvalues, the
  trimmed ``mode_set`` / ``modes_of_inertia``, ``matrix_to_quat`` on Python
  floats, ``batch_rest._cross`` / ``_skew`` and the body-from-parts cache,
  each against the path before (kept verbatim here where it was replaced);
* (session 8) ``modes_batch`` taking the ``rest_poses`` batch's arrays
  (``BatchGeometry``), ``line_turns`` with the caller's knife-edge axes and
  ``rotations.cross``, and the start poses' ``left_jacobian`` without masks
  and ``_Rig.take`` without copies.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bifilar.analysis.equilibrium import reduced_stiffness, rest_pose
from bifilar.analysis.modes import linear_modes, modes_of_inertia
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation.sensitivity import best_mode_for, matched_periods, measured_inputs, perturb, period_sensitivity
from bifilar.estimation.uncertainty import default_uncertainty
from bifilar.studies.point import component_scale, linear_estimate
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS, trapezoid

COMPS = ["Ixx", "Iyy", "Izz"]


def _scene(name, params):
    cfg, _ = apply_params(read_yaml(CONFIGS / f"{name}.yaml"), params, name)
    return scene_from_dict(cfg, name, warn=False)


SCENES = {"Solar Boat": ("solar_boat", {"spacing": 3.0}), "pitch rig": ("thesis_lin2_pitch", {}),
          "trifilar": ("trifilar_kth", {})}


@pytest.mark.parametrize("case", list(SCENES))
def test_modes_of_inertia_equal_linear_modes(case):
    scene = _scene(*SCENES[case])
    rest = rest_pose(scene)
    at = modes_of_inertia(scene, rest)
    I2 = perturb(perturb(scene, "Izz", 0.3 * scene.inertia[2, 2]), "Ixy", 0.05 * scene.inertia[0, 0]).inertia
    for inertia in (scene.inertia, I2):
        ref = linear_modes(replace(scene, inertia=inertia), rest)
        got = at(inertia)
        assert [m.label for m in got.modes] == [m.label for m in ref.modes]
        for a, b in zip(got.modes, ref.modes):
            assert a.period == b.period  # the same operations: bit for bit
            assert np.array_equal(a.shape, b.shape)
    # and an independent solver of the same eigenproblem
    from scipy.linalg import eigh

    lam = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
    N, Kr, Mr, _ = reduced_stiffness(replace(scene, inertia=I2), rest.com, rest.R, lam)
    w2 = eigh(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T), eigvals_only=True)
    T_ref = np.sort(2 * np.pi / np.sqrt(w2[w2 > 0]))
    T_got = np.sort([m.period for m in at(I2).modes if m.period])
    assert T_got == pytest.approx(T_ref, rel=1e-10)


@pytest.mark.parametrize("comp", COMPS)
def test_linear_estimate_shared_stiffness(comp):
    scene = _scene("solar_boat", {"spacing": 3.0})
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    k = best_mode_for(sens, comp)
    T_target = sens.periods[k] * (1 + 3e-4)  # a nonlinear period a little longer
    slope = sens.column(comp)[k]
    own = linear_estimate(scene, comp, k, T_target, sens.modes, sens.rest, slope)
    shared = linear_estimate(scene, comp, k, T_target, sens.modes, sens.rest, slope,
                             at=modes_of_inertia(scene, sens.rest))
    assert shared == pytest.approx(own, rel=1e-13, abs=1e-13 * abs(own))
    # the root reproduces the target period in the plain linear model
    i = COMPS.index(comp)
    moved = perturb(scene, comp, shared - float(scene.inertia[i, i]))
    T = matched_periods(sens.modes, linear_modes(moved, rest_pose(moved, guess=sens.rest)))[k]
    assert T == pytest.approx(T_target, rel=1e-12)


def test_linear_estimate_other_scene_still_solves_its_rest():
    # a measured scene (inputs off the truth) with the truth's rest as a start: the estimate must use the
    # measured scene's own rest pose, not the start
    truth = trapezoid(h=0.5)
    sens = period_sensitivity(truth, COMPS)
    k = best_mode_for(sens, "Izz")
    measured = perturb(perturb(truth, "length.1", 2e-3), "attachment.2.y", -1e-3)
    x = linear_estimate(measured, "Izz", k, sens.periods[k], sens.modes, sens.rest, sens.column("Izz")[k])
    moved = perturb(measured, "Izz", x - float(measured.inertia[2, 2]))
    T = matched_periods(sens.modes, linear_modes(moved, rest_pose(moved)))[k]
    assert T == pytest.approx(sens.periods[k], rel=1e-12)


from bifilar.estimation.problem import Problem  # noqa: E402

_CENTRAL = Problem.jacobian  # the differences, kept before any test patches them


def _richardson_jacobian(pb, p, rel_step=5e-4):
    """Problem.jacobian's central differences at steps 2h and h, Richardson-extrapolated
    (truncation O(h^4): <= 1.2e-11 relative at 5e-4 on these rigs, 1.9e-10 at 1e-3), with a
    step large enough for the periods' rounding (~1e-14 over 5e-4: ~2e-11 relative): a
    converged reference for d T / d I."""
    return (4 * _CENTRAL(pb, p, rel_step) - _CENTRAL(pb, p, 2 * rel_step)) / 3


@pytest.mark.parametrize("case", ["Solar Boat", "pitch rig"])
def test_honest_stds_with_the_points_sensitivity(case, monkeypatch):
    # fed the point's analytic sensitivity, the honest pass takes its input columns and the unknown's
    # column d T / d I (budget._unknowns_jacobian) from it instead of differencing: the input columns
    # are the same derivative (equal to rounding), the unknown's column moves each std by the central
    # differences' error (~1e-9 relative) towards a converged reference (Richardson-extrapolated
    # differences), which the analytic value meets to ~1e-11
    from bifilar.estimation import budget, problem
    from bifilar.estimation.honest import honest_stds

    scene = _scene(*SCENES[case])
    unc = default_uncertainty()
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    assert sens.method == "analytic"
    req = [(c, best_mode_for(sens, c) + 1) for c in COMPS]
    ref = np.array(honest_stds(scene, req, unc, unc["timing"], rest=sens.rest))  # no fallback: the budget's own
    monkeypatch.setattr(problem.Problem, "jacobian", _richardson_jacobian)
    conv = np.array(honest_stds(scene, req, unc, unc["timing"], rest=sens.rest))

    def no_call(*a, **k):
        raise AssertionError("the budget recomputed a derivative it was given")

    monkeypatch.setattr(budget, "robust_sensitivity", no_call)
    monkeypatch.setattr(problem.Problem, "jacobian", no_call)
    got = np.array(honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens))
    assert got == pytest.approx(ref, rel=1e-7)  # the differences' error: measured <= 9.3e-9
    err_new, err_old = np.max(np.abs(got / conv - 1)), np.max(np.abs(ref / conv - 1))
    assert err_new <= 1e-10 and err_new <= 0.1 * err_old


def test_honest_unknowns_jacobian_is_the_analytic_column():
    # the seeded column of each component is the sensitivity's, by mode label; a cache without it
    # (another scene, a component not seeded) falls back to the differences
    from bifilar.estimation import budget
    from bifilar.estimation.honest import _seed_sensitivity
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.problem import build_problem

    scene = _scene(*SCENES["Solar Boat"])
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    cache: dict = {}
    _seed_sensitivity(cache, scene, sens)
    unc = default_uncertainty()
    for comp in COMPS:
        k = best_mode_for(sens, comp)
        md = sens.modes.modes[k]
        meas = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                              [Measurement(md.label, float(md.period), 1e-3, "period", "--period", amplitude=0.0)])
        pb = build_problem(meas, [comp], unc, rests=[sens.rest])
        J = budget._unknowns_jacobian(pb, pb.prior, cache)
        assert J.shape == (1, 1) and J[0, 0] == sens.column(comp)[k]
        fd = budget._unknowns_jacobian(pb, pb.prior, {})
        assert fd[0, 0] == pytest.approx(J[0, 0], rel=1e-7) and fd[0, 0] != J[0, 0]
    other = perturb(scene, "length.1", 1e-3)
    pb = build_problem(MeasurementSet([Hanging("ref", other, np.eye(3))],
                                      [Measurement(md.label, float(md.period), 1e-3, "period", "--period")]),
                       ["Izz"], unc)
    assert np.array_equal(budget._unknowns_jacobian(pb, pb.prior, cache), pb.jacobian(pb.prior))
    # the same scene hung turned by 90 degrees about z (its reference Ixx is the scene's Iyy): the seeded
    # columns are the scene's body-axis ones, so they must not serve
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    md = sens.modes.modes[best_mode_for(sens, "Iyy")]
    pb = build_problem(MeasurementSet([Hanging("ref", scene, turn)],
                                      [Measurement(md.label, float(md.period), 1e-3, "period", "--period")]),
                       ["Ixx"], unc, rests=[sens.rest])
    assert np.array_equal(budget._unknowns_jacobian(pb, pb.prior, cache), pb.jacobian(pb.prior))


def test_honest_stds_ignore_a_finite_difference_sensitivity():
    # the knife-edge plate: the point's sensitivity has differenced columns, which the budget must not take
    from bifilar.estimation.honest import _seed_sensitivity

    scene = trapezoid()
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    cache: dict = {}
    _seed_sensitivity(cache, scene, sens)
    assert cache == {}


def test_hanging_model_locate_reuses_the_stiffness_only_at_its_geometry():
    # inertia-only changes reuse the stiffness; a geometry change (and back) re-solves it: every answer
    # equals linear_modes at locate's rest pose
    from bifilar.estimation.measurements import Hanging
    from bifilar.estimation.problem import HangingModel

    scene = _scene("solar_boat", {"spacing": 3.0})
    hm = HangingModel(Hanging("h", scene, np.eye(3)), scene.inertia)
    other = perturb(scene, "length.1", 0.01)
    for sc in (perturb(scene, "Izz", 5.0), other, perturb(other, "Ixx", -3.0), perturb(scene, "Iyy", 2.0)):
        rest, ms, _ = hm.locate(sc)
        ref = linear_modes(sc, rest_pose(sc, guess=rest, local_only=True))
        assert [m.period for m in ms.modes] == pytest.approx([m.period for m in ref.modes], rel=1e-12)


def test_clusters_by_hand_and_by_their_defining_properties():
    # hand-worked cases: equal within tol (the larger of a pair's tolerances), chained from each
    # cluster's FIRST member (0, 0.6, 1.2 at tol 1: 1.2 is 1.2 from 0, so it starts a new cluster
    # although it is within 1 of 0.6)
    from bifilar.analysis.modes import clusters

    w = [1.0, 1.0 + 1e-12, 2.0, 2.0 + 3e-11, 5.0]
    assert clusters(w, 1e-10) == [(0, 2), (2, 4), (4, 5)]
    assert clusters(w, 1e-11) == [(0, 2), (2, 3), (3, 4), (4, 5)]
    assert clusters([0.0, 0.6, 1.2], 1.0) == [(0, 2), (2, 3)]
    assert clusters([1.0, 1.0 + 5e-11], [1e-11, 1e-10]) == [(0, 2)]
    assert clusters([1.0, 1.0 + 5e-11], [1e-11, 1e-11]) == [(0, 1), (1, 2)]
    assert clusters([3.0], 1e-10) == [(0, 1)]
    # random cases against the properties that define the grouping (not a copy of the loop): the
    # ranges tile 0..n; every member is within the pair tolerance of its cluster's first member; the
    # member after a cluster is not
    rng = np.random.default_rng(7)
    for _ in range(200):
        w2 = np.sort(rng.choice([1.0, 1.0 + 1e-12, 2.0, 2.0 + 3e-11, 5.0], size=rng.integers(1, 6)))
        tol = rng.choice([1e-11, 1e-10, 1e-13], size=len(w2))
        out = clusters(w2, tol)
        assert [k for k, _ in out] == [0] + [j for _, j in out[:-1]] and out[-1][1] == len(w2)
        for k, j in out:
            assert all(abs(w2[i] - w2[k]) <= max(tol[k], tol[i]) for i in range(k, j))
            if j < len(w2):
                assert abs(w2[j] - w2[k]) > max(tol[k], tol[j])
        assert clusters(w2, 1e-10) == clusters(w2, np.full(len(w2), 1e-10))


def test_thesis_models_of_one_hanging_share_the_kane_forcing():
    # a model built on a hanging that already served another mode and component equals one built afresh
    from bifilar.estimation.ladder import ThesisModel
    from bifilar.estimation.measurements import Hanging
    from bifilar.estimation.problem import HangingModel

    scene = trapezoid(h=0.5)

    def fresh():
        return HangingModel(Hanging("h", scene, np.eye(3)), scene.inertia)

    shared = fresh()
    ThesisModel(shared, shared.mode_index("pitch", "m"), "Ixx")
    for label, comp in (("torsion", "Izz"), ("pitch", "Iyy")):
        a = ThesisModel(shared, shared.mode_index(label, "m"), comp)
        h = fresh()
        b = ThesisModel(h, h.mode_index(label, "m"), comp)
        assert a.which == b.which
        for x in (0.9 * a.x0, a.x0, 1.2 * a.x0):
            assert a.period(x) == b.period(x)
        assert a.period(1.1 * a.x0) != a.period(a.x0)  # it does depend on the component
    # another hanging's models use its own forcing, not the first one's
    other = trapezoid(h=0.3)
    h2 = HangingModel(Hanging("h2", other, np.eye(3)), other.inertia)
    a = ThesisModel(h2, h2.mode_index("pitch", "m"), "Ixx")
    ref = ThesisModel(shared, shared.mode_index("pitch", "m"), "Ixx")
    assert a.period(a.x0) != pytest.approx(ref.period(ref.x0), rel=1e-6)
    assert a.period(a.x0) == pytest.approx(h2.modes0.get("pitch").period, rel=0.05)


def _thesis_period_before(tm, x):
    """ThesisModel.period as it was before its index arrays and the reference norm were kept (verbatim)."""
    import math

    M = tm.M_a + (x - tm.x0) * tm.dM
    L = np.linalg.solve(M, tm.dN)
    sub = L[np.ix_(tm.idx, tm.idx)]
    ev, V = np.linalg.eig(sub)
    cos = [abs(np.vdot(V[:, k], tm.v_ref)) / (np.linalg.norm(V[:, k]) * np.linalg.norm(tm.v_ref))
           for k in range(2)]
    k = int(np.argmax(cos))
    return 2 * math.pi / math.sqrt(-ev[k].real) if ev[k].real < 0 else math.nan


def _thesis_models(name, params, comps):
    """(component, ThesisModel, HangingModel) of each of ``comps`` whose thesis rung applies to the
    config ``name`` changed by ``params`` (a product is timed on the torsion, Izz's mode)."""
    from bifilar.estimation.ladder import ThesisModel
    from bifilar.estimation.measurements import Hanging
    from bifilar.estimation.problem import HangingModel

    scene = _scene(name, params)
    hm = HangingModel(Hanging("h", scene, np.eye(3)), scene.inertia)
    sens = period_sensitivity(scene, COMPS)
    for comp in comps:
        try:
            tm = ThesisModel(hm, best_mode_for(sens, comp if comp in COMPS else "Izz"), comp)
        except Exception:  # noqa: BLE001 - a rung that does not apply
            continue
        yield comp, tm, hm


@pytest.mark.parametrize("name,params", [("solar_boat", {"spacing": 3.0}), ("thesis_lin2_pitch", {}),
                                         ("thesis_lin3_roll", {}), ("thesis_cylinder_6_4", {})])
def test_thesis_period_with_kept_indices_equals_the_one_before(name, params):
    # (session 7: at the prior x0, where the root search starts, period returns the period __init__ solved:
    # the shortcut is taken, and f = 1.0 below checks it against the computation)
    n = 0
    for _, tm, _ in _thesis_models(name, params, COMPS):
        assert tm._at_x0 is not None
        for f in (0.5, 0.9, 1.0, 1.1, 2.0):
            x = f * tm.x0
            got, ref = tm.period(x), _thesis_period_before(tm, x)
            assert got == ref or (np.isnan(got) and np.isnan(ref))
            n += 1
    assert n >= 5


@pytest.mark.parametrize("name,params", [("solar_boat", {"spacing": 3.0}), ("thesis_lin2_pitch", {}),
                                         ("thesis_lin3_roll", {}), ("thesis_cylinder_6_4", {})])
def test_thesis_mass_matrix_with_another_inertia_equals_a_kane_evaluation(name, params):
    # each component's mass matrix (the hanging's Kane quantities at rest, only the inertia term redone)
    # against a whole Kane evaluation with the params whose inertia is changed (the path before)
    from bifilar.estimation.ladder import _thesis_cache
    from bifilar.estimation.problem import basis
    from bifilar.models import kane
    from bifilar.models.kane_mapping import replace_params

    n = 0
    for comp, tm, hm in _thesis_models(name, params, COMPS + ["Ixy", "Ixz", "Iyz"]):
        mp = tm.mapping
        p1 = replace_params(mp.params, inertia=mp.params.inertia + mp.C.T @ (hm.R @ basis(comp) @ hm.R.T) @ mp.C)
        M_b, _ = kane.mass_matrix_and_forcing(mp.theta0, np.zeros(5), p1)
        assert np.array_equal(tm.dM, M_b - tm.M_a)
        assert np.array_equal(kane.mass_matrix_with_inertia(_thesis_cache(hm)["state"], p1.inertia), M_b)
        assert np.any(tm.dM != 0)
        n += 1
    assert n >= 3


@pytest.mark.parametrize("params", [{"spacing": 3.0}, {"spacing": 6.0, "length": 5.0}])
def test_knife_edge_point_takes_its_linear_budget_without_the_honest_pass(params, monkeypatch):
    # CoM on the attachment line: a neutral mode, so the honest std has no second-order part and equals
    # what the honest pass gives with the point's linear figure as fallback, without running it
    from bifilar.estimation import honest
    from bifilar.studies import point as pt

    scene = _scene("thesis_plate_rest", params)
    # the inputs without a derivative at the knife edge (attachment x, com x) stated exact: else no sigma
    unc = {**default_uncertainty(), "position": 0.0, "com": 0.0}
    sens, _ = pt.point_sensitivity(scene, COMPS + measured_inputs(scene))
    assert not np.all(np.isfinite(sens.periods))
    # the components the point itself calls identifiable (relative sensitivity >= IDENTIFIABLE_MIN): a
    # test of "!= 0" took Iyy in on a BLAS kernel where its finite differences left 1e-17 of rounding
    fin = np.where(np.isfinite(sens.periods), sens.periods, np.inf)

    def rel(c):  # as evaluate_point: a neutral mode (nan period) measures nothing
        r = np.abs(sens.column(c)) * component_scale(scene.inertia, c) / fin
        return np.where(np.isfinite(r), r, 0.0)
    req = [(c, best_mode_for(sens, c)) for c in COMPS if rel(c).max() >= pt.IDENTIFIABLE_MIN]
    assert [c for c, _ in req] == ["Ixx", "Izz"]  # Iyy: no mode of the plate on parallel wires measures it
    lin = pt.predicted_budgets(sens, scene, req, unc, honest=False)
    ref = honest.honest_stds(scene, [(c, k + 1) for c, k in req], unc, unc["timing"],
                             fallbacks=[b.value_sigma for b in lin], rest=sens.rest)

    def no_call(*a, **k):
        raise AssertionError("the honest pass ran at a knife edge")

    monkeypatch.setattr(honest, "honest_stds", no_call)
    got = pt.predicted_budgets(sens, scene, req, unc)
    assert [b.value_sigma for b in got] == pytest.approx(ref, rel=1e-12)


def test_constraint_hessians_equal_the_skew_formula():
    # built without np.stack; the same numbers as the cross-product-matrix formula, bit for bit
    from bifilar.analysis.equilibrium import constraint_hessians
    from bifilar.rotations import skew

    rng = np.random.default_rng(3)
    for n in (2, 3, 4):
        d = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
        w = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
        H = constraint_hessians(d, w)
        for i in range(n):
            W = skew(w[i])
            assert np.array_equal(H[i, :3, 3:], -W) and np.array_equal(H[i, 3:, :3], W)
            ref = -W @ W + 0.5 * (np.outer(d[i], w[i]) + np.outer(w[i], d[i])) - np.dot(d[i], w[i]) * np.eye(3)
            assert np.array_equal(H[i, 3:, 3:], ref)


def _count_calls(monkeypatch, owner, name, real) -> list:
    """Replace ``owner.name`` by ``real`` counting its calls: the list gets a 1 per call."""
    calls: list = []

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(owner, name, counted)
    return calls


def _knife_edges():
    """Knife edges (CoM exactly on the attachment line): the thesis plate over a grid of spacings and
    lengths, thesis_lin1, and random rigs (line direction with a tilt, unequal arms, anchors at
    different heights and offsets, a full inertia tensor)."""
    out = [_scene("thesis_plate_rest", {"spacing": s, "length": L}) for s in (1.0, 3.0, 4.5) for L in (5.0, 7.0)]
    out.append(_scene("thesis_lin1_torsion", {}))
    rng = np.random.default_rng(11)
    while len(out) < 16:
        u = rng.normal(size=3) * [1.0, 1.0, 0.2]
        u /= np.linalg.norm(u)
        att = np.array([-rng.uniform(0.3, 2.0) * u, rng.uniform(0.3, 2.0) * u])
        anc = att + [0.0, 0.0, 0.0] + rng.normal(scale=0.3, size=(2, 3)) * [1, 1, 0] + [[0, 0, 3.0], [0, 0, 3.5]]
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        I = Q @ np.diag(rng.uniform(1.0, 1.8, 3)) @ Q.T
        scene = scene_from_dict({"body": {"mass": float(rng.uniform(5, 50)), "inertia": {"tensor": I.tolist()}},
                                 "rig": {"anchors": anc.tolist(), "attachments": att.tolist(),
                                         "lengths": (np.linalg.norm(anc - att, axis=1) + rng.uniform(0, 0.2, 2)).tolist()}},
                                warn=False)
        try:
            r = rest_pose(scene)
        except Exception:  # noqa: BLE001 - a rig that cannot hang: draw another
            continue
        if not all(m.period for m in linear_modes(scene, r).modes):
            out.append(scene)
    return out


def test_knife_edge_inputs_pushing_hard_are_left_out_without_their_differences(monkeypatch):
    # at a knife edge an input pushing along the neutral direction (NO_BRANCH_PUSH) is left out at once;
    # the differences it skips (NO_BRANCH_PUSH = inf: the path before) find no side either: the same
    # Jacobian bit for bit and the same notes, over 16 knife edges
    from bifilar.analysis import equilibrium as eq
    from bifilar.studies import point as pt

    newton = _count_calls(monkeypatch, eq, "_from_guess", eq._from_guess)
    skipped = 0
    for scene in _knife_edges():
        names = COMPS + measured_inputs(scene)
        rest = rest_pose(scene)
        newton.clear()
        got, notes = pt.point_sensitivity(scene, names, rest)
        n_got = len(newton)
        with monkeypatch.context() as m:
            m.setattr(pt, "NO_BRANCH_PUSH", np.inf)
            newton.clear()
            ref, ref_notes = pt.point_sensitivity(scene, names, rest)
        assert notes == ref_notes
        assert np.array_equal(got.jacobian, ref.jacobian, equal_nan=True)
        assert np.array_equal(got.periods, ref.periods, equal_nan=True)
        skipped += len(newton) - n_got
    assert skipped >= 16 * 2  # the shortcut was taken (two sides of at least one input a scene)


def _honest_cases():
    from test_honest_budget import _cases

    out = {k: v for k, v in _cases().items() if k != "Solar Boat"}
    drone = read_yaml(CONFIGS / "drone_parallel.yaml")
    out["drone"] = (drone, COMPS)  # Izz: the quadratic term in com.x (docs/performance.md)
    out["Solar Boat"] = (apply_params(read_yaml(CONFIGS / "solar_boat.yaml"), {"spacing": 3.0}, "boat")[0], COMPS)
    return out


@pytest.mark.parametrize("case", list(_honest_cases()))
def test_honest_stds_share_one_hanging_model(case, monkeypatch):
    # every component's problem shares one HangingModel (its stiffness and the mode sets it solved);
    # against a model built afresh for each component (the path before): the same stds, bit for bit,
    # second-order terms included (the wheel, the drone), with and without the linear fallback
    from bifilar.estimation import honest, problem

    cfg, comps = _honest_cases()[case]
    scene = scene_from_dict(cfg, case, warn=False)
    unc = default_uncertainty()
    sens = period_sensitivity(scene, list(dict.fromkeys(COMPS + comps)) + measured_inputs(scene))
    req = [(c, best_mode_for(sens, c) + 1) for c in comps
           if np.nanmax(np.abs(sens.column(c)) * component_scale(scene.inertia, c) / sens.periods) >= 1e-6]
    lin = [b.value_sigma for b in (inertia_budget_of(sens, scene, c, k - 1, unc) for c, k in req)]
    built = []
    real = problem.build_problem

    def counted(*a, **k):
        pb = real(*a, **k)
        built.append(id(pb.models[0]))
        return pb

    monkeypatch.setattr(problem, "build_problem", counted)
    got = [honest.honest_stds(scene, req, unc, unc["timing"], fallbacks=fb, rest=sens.rest, sens=sens)
           for fb in (None, lin)]
    assert len(set(built)) == 2  # one model per call, shared by its components

    def fresh(*a, models=None, **k):  # the path before: a model per component
        return real(*a, **k)

    monkeypatch.setattr(problem, "build_problem", fresh)
    ref = [honest.honest_stds(scene, req, unc, unc["timing"], fallbacks=fb, rest=sens.rest, sens=sens)
           for fb in (None, lin)]
    assert got == ref


def inertia_budget_of(sens, scene, comp, k, unc):
    from bifilar.estimation.sensitivity import inertia_budget

    return inertia_budget(sens, scene, comp, k, unc["timing"], unc)


def test_hanging_model_locate_returns_the_mode_set_it_solved_at_an_inertia():
    # a second locate at an inertia (the prior and another) gives what a fresh model's stiffness gives,
    # bit for bit; when modes0 is replaced (roots.relabel) the match is against the new base modes
    from bifilar.estimation.measurements import Hanging
    from bifilar.estimation.problem import HangingModel

    scene = _scene("solar_boat", {"spacing": 3.0})
    hm = HangingModel(Hanging("h", scene, np.eye(3)), scene.inertia)
    other = perturb(scene, "Izz", 40.0)
    for sc in (scene, other, scene, other):
        rest, ms, match = hm.locate(sc)
        ref = modes_of_inertia(sc, rest_pose(sc))(sc.inertia)
        assert [m.period for m in ms.modes] == [m.period for m in ref.modes]
        assert all(np.array_equal(a.shape, b.shape) for a, b in zip(ms.modes, ref.modes))
    assert hm.locate(scene)[1] is hm.modes0
    first = hm.locate(scene)[2]
    assert hm.locate(scene)[2] is first  # the match too, while modes0 stands
    hm.modes0 = hm.locate(other)[1]
    _, _, match = hm.locate(scene)
    from bifilar.estimation.sensitivity import mac_match

    assert list(match) == list(mac_match(hm.modes0, hm.locate(scene)[1]))


def _honest_case_stds(measurements: str) -> list:
    """The honest stds of every :func:`_honest_cases` case (fed the analytic sensitivity), and the
    values and stds of an inversion of the configs' ``measurements`` file (no ladder)."""
    from bifilar.estimation import honest
    from bifilar.estimation.invert import invert
    from bifilar.estimation.measurements import load_measurements

    out = []
    for case, (cfg, comps) in _honest_cases().items():
        scene = scene_from_dict(cfg, case, warn=False)
        unc = default_uncertainty()
        sens = period_sensitivity(scene, list(dict.fromkeys(COMPS + comps)) + measured_inputs(scene))
        req = [(c, best_mode_for(sens, c) + 1) for c in comps
               if np.nanmax(np.abs(sens.column(c)) * component_scale(scene.inertia, c) / sens.periods) >= 1e-6]
        out.append(honest.honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens))
    res = invert(load_measurements(CONFIGS / measurements), ladder=False)
    out.append((res.values.tolist(), res.std.tolist()))
    return out


def test_sigma_points_settled_in_one_step_all_at_once(monkeypatch):
    # budget._one_step takes the first Gauss-Newton step of every sigma point (and pair corner) at once;
    # against _resolve point by point (the path before): the same re-solved unknowns, bit for bit, over
    # the honest cases (second order and pair terms: the wheel, the drone) and an inversion of three
    # modes for three components (K = P = 3, the example measurements file)
    from bifilar.estimation import second_order as budget  # where the sigma points are solved (session 16 split)

    seen: list = []
    real_solve, real_one = budget._solve_points, budget._one_step

    def record(*a, **k):
        out = real_solve(*a, **k)
        seen.append(out)
        return out

    def counted(*a, **k):
        out = real_one(*a, **k)
        settled.append(len(out))
        return out

    def run():
        seen.clear()
        out = _honest_case_stds("measurements_example.yaml")
        return out, [{k: None if v is None else v.tolist() for k, v in d.items()} for d in seen]

    settled: list = []
    monkeypatch.setattr(budget, "_solve_points", record)
    monkeypatch.setattr(budget, "_one_step", counted)
    got, got_points = run()
    assert sum(settled) >= 100  # the one-step path did the work
    monkeypatch.setattr(budget, "_one_step", lambda *a, **k: {})
    ref, ref_points = run()
    assert got_points == ref_points
    assert got == ref


def _solve_points_before(pb, ctx, p_hat, r_hat, points: dict) -> dict:
    """budget._solve_points before its per-key hangings were kept (verbatim, names qualified)."""
    from bifilar.estimation.budget import (_hanging_periods, _key_hanging, _one_step, _perturbed_scene, _resolve,
                                           scene_key)

    jobs: dict[int, list] = {h: [] for h in range(len(pb.models))}
    res: dict = {pid: {} for pid in points}
    cache = ctx.cache
    skeys = [scene_key(s) for s in ctx.scenes] if cache is not None else None
    for pid, moves in points.items():
        for h in sorted({h for key, _ in moves for h in _key_hanging(pb, key)}):
            if any(m.hanging == h for m in pb.measurements):
                ck = ("sigma point", skeys[h], tuple(moves)) if cache is not None else None
                if ck is not None and ck in cache:
                    res[pid][h] = cache[ck]
                else:
                    jobs[h].append((pid, _perturbed_scene(pb, h, ctx.scenes[h], moves), ck))
    for h, jl in jobs.items():
        if jl:
            for (pid, _, ck), o in zip(jl, _hanging_periods([j[1] for j in jl], ctx.rests[h], ctx.modes[h])):
                res[pid][h] = o
                if ck is not None:
                    cache[ck] = o
    whole = {pid: hits for pid, hits in res.items() if all(v is not None for v in hits.values())}
    done = _one_step(pb, ctx, p_hat, r_hat, whole)
    return {pid: (done[pid] if pid in done else _resolve(pb, ctx, p_hat, r_hat, points[pid], hits))
            if pid in whole else None for pid, hits in res.items()}


def test_solve_points_with_kept_hangings_equals_the_one_before(monkeypatch):
    # the hangings each input key affects are found once per key, not once per point; against the loop
    # before: the same re-solved points, bit for bit, over the honest cases (one hanging, sigma points and
    # pair corners) and an inversion of six hangings (inputs of one hanging, shared CoM, mass, gravity)
    from bifilar.estimation import second_order as budget  # where the sigma points are solved

    seen: list = []

    def recording(fn):
        def run(*a, **k):
            out = fn(*a, **k)
            seen.append({key: None if v is None else v.tolist() for key, v in out.items()})
            return out
        return run

    def run_all():
        seen.clear()
        out = _honest_case_stds("measurements_hangings_example.yaml")
        return out, list(seen)

    real = budget._solve_points
    monkeypatch.setattr(budget, "_solve_points", recording(real))
    got, got_points = run_all()
    monkeypatch.setattr(budget, "_solve_points", recording(_solve_points_before))
    ref, ref_points = run_all()
    assert len(got_points) >= 10 and got_points == ref_points
    assert got == ref


def _mode_set_fields(ms):
    return ([(m.label, m.period, m.omega2, m.shape.tobytes(), m.energy_share.tobytes(), m.dominant) for m in ms.modes],
            np.asarray(ms.mass_matrix).tobytes(), np.asarray(ms.basis).tobytes(), ms.basis.strides)


def test_batched_mode_sets_equal_mode_set_scene_by_scene(monkeypatch):
    # modes_batch labels its scenes with mode_sets (the elementwise arithmetic on the whole batch); against
    # mode_set scene by scene (the path before): the same mode sets bit for bit, over batches of sigma-point
    # scenes of the Solar Boat, the drone, the trifilar (degenerate swings: each cluster aligned scene by
    # scene, the rest batched) and the knife-edge plate (a neutral mode)
    from bifilar.analysis import batch_rest
    from bifilar.analysis import modes as md
    from bifilar.analysis.batch import modes_batch, rest_poses

    def scene_by_scene(N, Y, w2, m, M, K, which=None):
        out = [None] * len(w2)
        for b in (range(len(w2)) if which is None else which):
            out[b] = md.mode_set(N[b], Y[b], w2[b], m[b], M[b], K=K[b])
        return out

    rng = np.random.default_rng(5)
    cases = [_scene("solar_boat", {"spacing": 3.0}), _scene("drone_parallel", {}), _scene("trifilar_kth", {}),
             _scene("thesis_plate_rest", {})]
    n_modes = neutral = repeated = 0
    alone: list = []
    for base in cases:
        names = measured_inputs(base)
        scenes = [perturb(base, n, float(rng.normal()) * 2e-3) for n in names] + [base]
        rests = rest_poses(scenes, rest_pose(base), errors="return")
        scenes = [s for s, r in zip(scenes, rests) if not isinstance(r, Exception)]
        rests = [r for r in rests if not isinstance(r, Exception)]
        real = md.mode_set
        with monkeypatch.context() as m:
            m.setattr(md, "mode_set", lambda *a, **k: alone.append(1) or real(*a, **k))
            got = modes_batch(scenes, rests)
        with monkeypatch.context() as m:
            m.setattr(batch_rest, "mode_sets", scene_by_scene)
            ref = modes_batch(scenes, rests)
        assert [_mode_set_fields(a) for a in got] == [_mode_set_fields(b) for b in ref]
        n_modes += sum(len(a.modes) for a in got)
        neutral += sum(m.period is None for a in got for m in a.modes)
        repeated += sum(len({m.period for m in a.modes if m.period}) < sum(1 for m in a.modes if m.period)
                        for a in ref)
    assert n_modes > 200 and neutral > 0
    # the trifilar's degenerate swings (a cluster aligned, its periods equal): batched too, nothing went through
    # mode_set alone
    assert repeated >= 5
    assert not alone


def test_rest_poses_from_one_guess_equal_those_from_copies_of_it():
    # the multipliers of a guess shared by every scene are computed once; against a copy per scene (each
    # its own computation, the path before): the same poses bit for bit
    import copy

    from bifilar.analysis.batch import rest_poses

    base = _scene("solar_boat", {"spacing": 3.0})
    guess = rest_pose(base)
    scenes = [perturb(base, n, 1e-3) for n in measured_inputs(base)]
    one = rest_poses(scenes, guess)
    each = rest_poses(scenes, [copy.deepcopy(guess) for _ in scenes])
    for a, b in zip(one, each):
        for f in ("com", "R", "q", "tensions", "wire_vectors", "kkt_residual"):
            assert np.array_equal(getattr(a, f), getattr(b, f))


@pytest.mark.parametrize("name,params", [("solar_boat", {"spacing": 3.0}), ("thesis_plate_rest", {"spacing": 2.0}),
                                         ("drone_parallel", {}), ("trifilar_kth", {"spacing": 0.6})])
def test_point_builds_its_reduced_stiffness_once(name, params, monkeypatch):
    # one modes_of_inertia a point serves its modes, the honest pass's and the thesis rung's hanging models
    # and the linear estimates; against each building its own (the path before): the same point, bit for bit
    from bifilar.analysis import equilibrium as eq
    from bifilar.analysis import modes as md
    from bifilar.studies import point as pt
    from bifilar.studies.settings import resolve_settings

    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = resolve_settings(cfg)
    built = _count_calls(monkeypatch, md, "reduced_stiffness", eq.reduced_stiffness)
    got = pt.evaluate_point(cfg, name, params, st)
    n_shared = len(built)  # 1, plus the neighbours' of finite differences (the trifilar's repeated swings)
    monkeypatch.setattr(pt, "_stiffness", lambda scene, rest: None)
    built.clear()
    ref = pt.evaluate_point(cfg, name, params, st)
    assert got["valid"] and len(built) >= n_shared + 2
    assert got == ref


def test_stacked_mac_matches_equal_mac_match_one_by_one():
    # mac_matches (the MAC matrices of a batch in one stacked product) against mac_match scene by scene
    # (the path before): the same assignments over sigma-point batches of asymmetric and symmetric rigs
    # (the trifilar's repeated swings, the knife-edge plate's neutral mode), and MAC matrices equal to
    # rounding
    from bifilar.analysis.batch import modes_batch, rest_poses
    from bifilar.estimation.sensitivity import _mac_assignment, mac_match, mac_matches

    rng = np.random.default_rng(9)
    n = 0
    for name, params in (("solar_boat", {"spacing": 3.0}), ("drone_parallel", {}), ("trifilar_kth", {}),
                         ("thesis_plate_rest", {}), ("thesis_cylinder_6_4", {})):
        base = _scene(name, params)
        rest = rest_pose(base)
        ms0 = linear_modes(base, rest)
        scenes = [perturb(base, nm, float(rng.normal()) * 3e-3) for nm in measured_inputs(base)]
        rests = rest_poses(scenes, rest, errors="return")
        mss = modes_batch([s for s, r in zip(scenes, rests) if not isinstance(r, Exception)],
                          [r for r in rests if not isinstance(r, Exception)])
        got = mac_matches(ms0, mss)
        for ms, g in zip(mss, got):
            assert list(g) == list(mac_match(ms0, ms))
        n += len(mss)
    assert n > 60


def test_modes_of_inertia_returns_the_mode_set_it_solved_and_input_sigma_without_the_merge():
    # modes_of_inertia hands an inertia asked for again the mode set it solved (the same object), equal to a
    # fresh function's; input_sigma looks keys up without merging the defaults in: the same sigmas
    from bifilar.estimation.sensitivity import DEFAULT_UNCERTAINTY, input_sigma

    scene = _scene("solar_boat", {"spacing": 3.0})
    rest = rest_pose(scene)
    at = modes_of_inertia(scene, rest)
    I2 = perturb(scene, "Izz", 7.0).inertia
    first = at(scene.inertia)
    at(I2)
    assert at(scene.inertia) is first
    for inertia in (scene.inertia, I2):
        ref = modes_of_inertia(scene, rest)(inertia)
        assert [(m.period, m.shape.tobytes()) for m in at(inertia).modes] == [(m.period, m.shape.tobytes())
                                                                               for m in ref.modes]
    for unc in (None, {}, {"mass": 0.02, "length": 0.003}, {"position": 1e-4, "com": 2e-3, "gravity": 1e-4}):
        merged = {**DEFAULT_UNCERTAINTY, **(unc or {})}
        for name in ["mass", "gravity", "Ixx"] + measured_inputs(scene):
            head = name.split(".")[0]
            want = {"mass": merged["mass"] * scene.mass, "gravity": merged["gravity"] * scene.gravity,
                    "length": merged["length"], "anchor": merged["position"], "attachment": merged["position"],
                    "com": merged["com"]}.get(head, 0.0)
            assert input_sigma(scene, name, unc) == want


def test_constraint_jacobian_equals_the_np_cross_formula():
    # [d, w x d] written out with np.cross's operations: the same numbers as np.hstack([d, np.cross(w, d)]),
    # bit for bit
    from bifilar.analysis.equilibrium import constraint_jacobian
    from bifilar.rotations import rotvec_to_matrix

    rng = np.random.default_rng(4)
    for name in ("solar_boat", "trifilar_kth", "drone_parallel", "thesis_plate_rest"):
        scene = _scene(name, {})
        for _ in range(20):
            com = rng.normal(size=3) * 10.0 ** rng.uniform(-2, 1)
            R = rotvec_to_matrix(rng.normal(size=3))
            d, w, G = constraint_jacobian(scene, com, R)
            assert np.array_equal(G, np.hstack([d, np.cross(w, d)]))


# equilibrium._newton_kkt as it was before its loop invariants (scales, L^2, the damping limit) were hoisted
# out of the loop, kept verbatim as the reference the hoisted one must equal bit for bit
from bifilar.analysis import equilibrium as eq  # noqa: E402


def _newton_kkt_before(scene, com, R, lam=None, iters=60):
    """Newton on grad V + G^T lam = 0, phi = 0.  Returns com, R, lam, residual."""
    m, g = scene.mass, scene.gravity
    n = scene.n_wires
    gradV = np.array([0, 0, m * g, 0, 0, 0], float)
    L = scene.lengths
    d, w, G = eq.constraint_jacobian(scene, com, R)
    if lam is None:
        lam = -np.linalg.lstsq(G.T, gradV, rcond=None)[0]
    force_scale = m * g
    prev = np.inf
    for _ in range(iters):
        d, w, G = eq.constraint_jacobian(scene, com, R)
        phi = 0.5 * (np.einsum("ij,ij->i", d, d) - L**2)
        r1 = gradV + G.T @ lam
        res = max(np.max(np.abs(r1)) / force_scale, np.max(np.abs(phi)) / np.max(L) ** 2)
        # converged, or at the rounding floor (a singular system: dependent
        # wires or a neutral direction stall at ~1e-14 instead of 1e-15)
        if res < 1e-15 or (res < 1e-12 and res > 0.5 * prev):
            break
        prev = res
        H = np.einsum("i,ijk->jk", lam, eq.constraint_hessians(d, w))
        K = np.zeros((6 + n, 6 + n))
        K[:6, :6] = H
        K[:6, 6:] = G.T
        K[6:, :6] = G
        # solved dimensionless (unknowns dr / L, dtheta, dlam L^2 / (m g); rows force / (m g), moment / (m g L),
        # phi / L^2), by least squares: the Newton step when K is regular, the minimum-norm step when a
        # neutral direction (CoM on the attachment line) or dependent wires make it singular
        Ls = float(np.max(L))
        cs = np.concatenate([np.full(3, Ls), np.ones(3), np.full(n, force_scale / Ls**2)])
        rs = np.concatenate([np.full(3, 1 / force_scale), np.full(3, 1 / (force_scale * Ls)), np.full(n, 1 / Ls**2)])
        step = cs * np.linalg.lstsq(rs[:, None] * K * cs[None, :], -rs * np.concatenate([r1, phi]), rcond=None)[0]
        # damp huge steps (far from the solution)
        dx = step[:6]
        lim = 0.2 * np.max(L)
        s = min(1.0, lim / max(np.max(np.abs(dx[:3])), 1e-300), 0.5 / max(np.max(np.abs(dx[3:])), 1e-300))
        com = com + s * dx[:3]
        R = eq.rotvec_to_matrix(s * dx[3:]) @ R
        lam = lam + s * step[6:]
    d, w, G = eq.constraint_jacobian(scene, com, R)
    phi = 0.5 * (np.einsum("ij,ij->i", d, d) - L**2)
    res = max(np.max(np.abs(gradV + G.T @ lam)) / force_scale, np.max(np.abs(phi)) / np.max(L) ** 2)
    return com, R, lam, res


def test_newton_with_hoisted_scales_equals_the_loop_before():
    # rest poses from cold starts, from a neighbour's pose (finite differences, sigma points) and at a knife
    # edge (the least-squares step): the same com, R, multipliers and residual, bit for bit
    rng = np.random.default_rng(6)
    for name, params in (("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {}), ("drone_parallel", {}),
                         ("thesis_plate_rest", {})):
        scene = _scene(name, params)
        rest = rest_pose(scene)
        lam0 = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
        starts = [(*eq._initial_pose(scene), None, 40)]
        for nm in measured_inputs(scene)[:8]:
            sc = perturb(scene, nm, float(rng.normal()) * 1e-3)
            starts.append((rest.com, rest.R, lam0, 30, sc))
        for com, R, lam, iters, *sc in starts:
            s = sc[0] if sc else scene
            got = eq._newton_kkt(s, com.copy(), R.copy(), None if lam is None else lam.copy(), iters=iters)
            ref = _newton_kkt_before(s, com.copy(), R.copy(), None if lam is None else lam.copy(), iters=iters)
            assert all(np.array_equal(a, b) for a, b in zip(got, ref))


def test_body_from_parts_cached_equals_built_anew():
    # a sweep point rebuilds its scene from the config; a body from parts whose list holds the same values is
    # taken from the cache (build._body_cache): the same mass, inertia, CoM and support as a build from scratch,
    # and any change of a value (or of its type, or -0.0 for 0.0) builds anew
    import copy

    from bifilar.config import build

    cfg = read_yaml(CONFIGS / "solar_boat.yaml")
    dirs = np.random.default_rng(3).normal(size=(7, 3))

    def fields(sc):
        return (sc.mass, sc.inertia.tobytes(), np.asarray(sc.parts_com).tobytes(), sc.support(dirs).tobytes())

    built: list = []
    real = build._build_body_from_parts
    build._body_cache.clear()
    try:
        build._build_body_from_parts = lambda *a: built.append(1) or real(*a)
        first = scene_from_dict(copy.deepcopy(cfg), warn=False)
        again = scene_from_dict(copy.deepcopy(cfg), warn=False)  # a fresh copy, as apply_params gives
        assert len(built) == 1 and fields(again) == fields(first)
        assert again.inertia is not first.inertia  # copies: a caller editing one scene's arrays edits no other
        build._body_cache.clear()
        assert fields(scene_from_dict(copy.deepcopy(cfg), warn=False)) == fields(first)
        assert len(built) == 2
        for edit in (lambda p: p[1].update(mass=p[1]["mass"] * (1 + 1e-15)),
                     lambda p: p[0].update(position=[-0.0, 0.0, -0.01]),
                     lambda p: p[0].update(mass=int(p[0]["mass"]) if p[0]["mass"] == int(p[0]["mass"]) else 52)):
            c = copy.deepcopy(cfg)
            edit(c["body"]["parts"])
            n = len(built)
            sc = scene_from_dict(c, warn=False)
            assert len(built) == n + 1  # built anew
            build._body_cache.clear()
            assert fields(scene_from_dict(c, warn=False)) == fields(sc)
        # an invalid parts list is never taken from the cache: its errors every time
        bad = copy.deepcopy(cfg)
        bad["body"]["parts"][0]["mass"] = -1.0
        for _ in range(2):
            with pytest.raises(Exception, match="parts.0"):
                scene_from_dict(bad, warn=False)
    finally:
        build._build_body_from_parts = real
        build._body_cache.clear()


# mode_set as it was before its overhead was trimmed (main at 7b5ff9a), verbatim but for the names: the
# reference the trimmed one must equal bit for bit
def _old_clusters(w2, tol):
    t = np.broadcast_to(np.asarray(tol, float), np.shape(w2)).tolist()
    w = np.asarray(w2, float).tolist()
    out = []
    k = 0
    while k < len(w):
        j = k + 1
        while j < len(w) and abs(w[j] - w[k]) <= max(t[k], t[j]):
            j += 1
        out.append((k, j))
        k = j
    return out


def _old_align_degenerate(N, Y, w2, tol, groups=None):
    Y = Y.copy()
    for k, j in (groups if groups is not None else _old_clusters(w2, tol)):
        if j - k < 2:
            continue
        S = N @ Y[:, k:j]  # (6, c)
        T = S.copy()
        rows: list[int] = []
        for _ in range(j - k):
            norms = np.linalg.norm(T, axis=1)
            norms[rows] = -1.0
            r = int(np.argmax(norms >= (1 - 1e-6) * norms.max()))
            rows.append(r)
            v = T[r] / np.linalg.norm(T[r])
            T = T - np.outer(T @ v, v)
        Y[:, k:j] = Y[:, k:j] @ np.linalg.inv(S[rows, :])
    return Y


def _old_assemble(S, share, w2, zero, periods, i, M, N):
    from bifilar.analysis.modes import _BASE_LABEL, COMPONENTS, Mode, ModeSet

    dom_e = np.argmax(share, axis=0)
    order = sorted(range(len(w2)), key=lambda j: (-(periods[j] if not zero[j] else -1.0), int(dom_e[j])))
    seen: dict[str, int] = {}
    modes = []
    for j in order:
        base = _BASE_LABEL[COMPONENTS[dom_e[j]]]
        c = seen.get(base, 0) + 1
        seen[base] = c
        modes.append(Mode(base if c == 1 else f"{base}-{c}", None if zero[j] else float(periods[j]), float(w2[j]),
                          S[:, j].copy(), share[:, j].copy(), int(i[j])))
    return ModeSet(modes, M, N)


def _old_mode_set(N, Y, w2, mass, M, K=None):
    from bifilar.analysis.modes import NEUTRAL_RTOL, _noise

    w2 = np.array(w2, float)
    tol = _noise(w2, np.array(Y, float), K)
    groups = _old_clusters(w2, tol)
    Y = _old_align_degenerate(N, np.array(Y, float), w2, tol, groups)
    for a, b in groups:
        if b - a > 1:  # (the mean of one number is that number)
            w2[a:b] = np.mean(w2[a:b])
    S = N @ Y
    absS = np.abs(S)
    i = np.argmax(absS >= (1 - 1e-9) * absS.max(axis=0), axis=0)
    S = S / S[i, np.arange(S.shape[1])]
    diagM = np.diag(M)[3:]
    share = np.concatenate([mass * S[:3] ** 2, diagM[:, None] * S[3:] ** 2], axis=0)
    share = share / share.sum(axis=0)
    scale = max(float(np.max(np.abs(w2))) if len(w2) else 0.0, 1e-300)
    zero = (np.abs(w2) <= np.maximum(tol, NEUTRAL_RTOL * scale)) | (w2 <= 0)
    periods = np.where(zero, np.nan, 2 * np.pi / np.sqrt(np.where(zero, 1.0, w2)))
    return _old_assemble(S, share, w2, zero, periods, i, M, N)


def _eigenproblems(rng, n):
    """Random solved eigenproblems (N, Y, w2, mass, M, K) of 6 - k degrees of freedom, with clusters of 2 and 3
    equal eigenvalues, eigenvalues equal but for a few ulps, neutral and negative ones."""
    from bifilar.analysis.modes import eigh_generalized

    out = []
    for q in range(n):
        k = int(rng.integers(2, 6))
        N = np.linalg.qr(rng.normal(size=(6, 6)))[0][:, :k]
        w = np.sort(rng.uniform(0.5, 40.0, k))
        kind = q % 5
        if kind == 1:
            w[1] = w[0]
        elif kind == 2 and k >= 3:
            w[1] = w[2] = w[0]
        elif kind == 3:
            w[1] = w[0] * (1 + 4e-16)
        elif kind == 4:
            w[0] = 1e-17 * w[-1] * (1 if q % 2 else -1)
        Q = np.linalg.qr(rng.normal(size=(k, k)))[0]
        d = rng.uniform(1.0, 5.0, k)
        Mr = np.diag(d)
        K = np.sqrt(d)[:, None] * (Q @ np.diag(w) @ Q.T) * np.sqrt(d)[None, :]  # K y = w Mr y
        K = 0.5 * (K + K.T)
        w2, Y = eigh_generalized(K, Mr)
        M = np.zeros((6, 6))
        m = float(rng.uniform(1, 100))
        M[:3, :3] = m * np.eye(3)
        A = rng.normal(size=(3, 3))
        M[3:, 3:] = A @ A.T + np.eye(3)
        out.append((N, Y, w2, m, M, K))
    return out


def test_trimmed_mode_set_equals_the_one_before():
    # mode_set, modes_of_inertia and the batched mode_sets lost numpy overhead (a cluster's alignment without
    # np.linalg.norm's and np.outer's wrappers and without the last pick's unused projection; the labels from
    # Python numbers; the mass matrix's translational block once): the same mode sets bit for bit as the
    # functions before, kept above, on random eigenproblems with repeated, nearly repeated and neutral
    # eigenvalues and on the sigma-point scenes of four rigs
    from bifilar.analysis import modes as md
    from bifilar.analysis.batch import modes_batch, rest_poses

    rng = np.random.default_rng(11)
    probs = _eigenproblems(rng, 200)
    clustered = 0
    for N, Y, w2, m, M, K in probs:
        for k in (K, None):
            got, ref = md.mode_set(N, Y, w2, m, M, K=k), _old_mode_set(N, Y, w2, m, M, K=k)
            assert _mode_set_fields(got) == _mode_set_fields(ref)
        clustered += len(md.clusters(w2, md._noise(w2, Y, K))) < len(w2)
    assert clustered >= 60
    # the batched mode_sets of the same problems (those of one size together)
    for k in range(2, 6):
        sub = [p for p in probs if p[0].shape[1] == k]
        got = md.mode_sets(*(np.array([p[i] for p in sub]) for i in range(6)))
        # (the batch's bases are views of one stacked array: their strides differ, not their numbers)
        assert [_mode_set_fields(a)[:3] for a in got] == [_mode_set_fields(_old_mode_set(*p))[:3] for p in sub]
    # real scenes: single (modes_of_inertia) and batched
    for name, params in [("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {}), ("drone_parallel", {}),
                         ("thesis_plate_rest", {})]:
        base = _scene(name, params)
        scenes = [perturb(base, n, float(rng.normal()) * 1e-3) for n in measured_inputs(base)] + [base]
        rests = rest_poses(scenes, errors="return")
        pairs = [(s, r) for s, r in zip(scenes, rests) if not isinstance(r, Exception)]
        for (s, r), b in zip(pairs, modes_batch([s for s, _ in pairs], [r for _, r in pairs])):
            lam = r.tensions / np.linalg.norm(r.wire_vectors, axis=1)
            Nn, Kr, _, _ = reduced_stiffness(s, r.com, r.R, lam)
            Ks = 0.5 * (Kr + Kr.T)
            M = np.zeros((6, 6))
            M[:3, :3] = s.mass * np.eye(3)
            M[3:, 3:] = r.R @ np.asarray(s.inertia, float) @ r.R.T
            Mr = Nn.T @ M @ Nn
            w2, Y = md.eigh_generalized(Ks, 0.5 * (Mr + Mr.T))
            ref = _old_mode_set(Nn, Y, w2, s.mass, M, K=Ks)
            assert _mode_set_fields(md.linear_modes(s, r))[:2] == _mode_set_fields(ref)[:2]
            # the batch's own eigenproblem (stacked Cholesky): its arrays, the old mode_set
            assert [m.label for m in b.modes] == [m.label for m in ref.modes]


def _old_matrix_to_quat(R):
    # rotations.matrix_to_quat before (main at 7b5ff9a): its loop body, Shepperd's method on numpy scalars, is
    # kept as rotations._shepperd_numpy (the fallback for matrices that are no rotation); the reference of the
    # Python-float path
    from bifilar.rotations import _shepperd_numpy

    R = np.asarray(R, dtype=float)
    flat = R.reshape(-1, 3, 3)
    out = np.empty((flat.shape[0], 4))
    for k, m in enumerate(flat):
        out[k] = _shepperd_numpy(m)
    out /= np.linalg.norm(out, axis=-1, keepdims=True)
    return out.reshape(R.shape[:-2] + (4,))


def test_matrix_to_quat_on_python_floats_equals_the_one_before():
    # the batched rest poses take every scene's quaternion (36-50 sigma-point scenes a point): Shepperd's
    # method on Python floats against the numpy-scalar loop before, bit for bit, on random rotations, the
    # four branches (turns by ~pi about each axis), exact ties of the trace and a diagonal entry, a -0.0, and
    # matrices that are no rotation (NaN, a negative root)
    from bifilar.rotations import matrix_to_quat, rotvec_to_matrix

    rng = np.random.default_rng(7)
    v = rng.normal(size=(300, 3))
    v *= rng.uniform(0, np.pi, (300, 1)) / np.linalg.norm(v, axis=1, keepdims=True)
    Rs = list(rotvec_to_matrix(v))
    for ax in np.eye(3):
        Rs += list(rotvec_to_matrix(np.array([ax * (np.pi - e) for e in (0.0, 1e-9, 1e-3, 0.3)])))
    Rs += [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0]),
           np.array([[0.0, -1.0, 0.0], [1.0, 0.0, -0.0], [-0.0, 0.0, 1.0]])]
    weird = [np.full((3, 3), np.nan), np.diag([-2.0, -3.0, -4.0]), np.zeros((3, 3)), rng.normal(size=(3, 3))]
    Rs = np.array(Rs)
    got, ref = matrix_to_quat(Rs), _old_matrix_to_quat(Rs)
    assert got.tobytes() == ref.tobytes()
    assert matrix_to_quat(Rs[:6].reshape(2, 3, 3, 3)).tobytes() == ref[:6].tobytes()
    with np.errstate(all="ignore"):
        for m in weird:
            assert np.array_equal(matrix_to_quat(m), _old_matrix_to_quat(m), equal_nan=True)


def test_batched_cross_and_skew_written_in_place_equal_the_stacked_ones():
    # batch_rest._cross and _skew (every batched Newton step and stiffness) fill one array instead of stacking:
    # the same numbers as np.cross and the nested stacks, bit for bit, signed zeros included
    from bifilar.analysis.batch_rest import _cross, _skew

    rng = np.random.default_rng(8)
    u, v = rng.normal(size=(2, 5, 4, 3))
    u[0, 0] = [0.0, -0.0, 1.0]
    assert _cross(u, v).tobytes() == np.cross(u, v).tobytes()
    assert _cross(u[0], v[0, 0]).tobytes() == np.cross(u[0], v[0, 0]).tobytes()  # broadcast
    z = np.zeros(u.shape[:-1])
    x, y, w = u[..., 0], u[..., 1], u[..., 2]
    stacked = np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2)
    assert _skew(u).tobytes() == stacked.tobytes()


def test_scene_with_equals_dataclasses_replace():
    # perturb, HangingModel.scene and the budget's CoM shift (~60 scenes a point) set a Scene's fields directly
    # (scene.scene_with) instead of through dataclasses.replace: the same fields, the same objects in them, a
    # new Scene; a name that is no field raises replace's error
    from dataclasses import fields, replace

    from bifilar.scene import Scene, scene_with

    base = _scene("solar_boat", {"spacing": 3.0})
    for changes in ({"mass": 2.5}, {"inertia": np.eye(3)}, {"inertia": np.eye(3), "attachments": base.anchors},
                    {"lengths": base.lengths * 2, "gravity": 9.0}, {}):
        got, ref = scene_with(base, **changes), replace(base, **changes)
        assert type(got) is Scene and got is not base
        for f in fields(Scene):
            assert getattr(got, f.name) is getattr(ref, f.name)
        assert set(vars(got)) == set(vars(ref))  # no attribute besides the fields
    with pytest.raises(TypeError):
        scene_with(base, mas=1.0)
    with pytest.raises(Exception):
        scene_with(base, mass=1.0).mass = 2.0  # still frozen
    # perturb through it: the same scene as through replace
    from bifilar.estimation import sensitivity

    names = ("mass", "gravity", "Izz", "Ixy", "length.2", "anchor.1.y", "attachment.2.z", "com.x")
    got = [sensitivity.perturb(base, n, 1e-3) for n in names]
    real = sensitivity.scene_with
    sensitivity.scene_with = replace
    try:
        ref = [sensitivity.perturb(base, n, 1e-3) for n in names]
    finally:
        sensitivity.scene_with = real
    for g, r in zip(got, ref):
        for f in ("mass", "gravity", "inertia", "anchors", "attachments", "lengths"):
            assert np.asarray(getattr(g, f)).tobytes() == np.asarray(getattr(r, f)).tobytes()


# --------------------------------------------------------------------------
# session 7 (issue 14, the Solar Boat point towards 15 ms)
# --------------------------------------------------------------------------
def _sigma_batches():
    """Batches of sigma-point-like scenes (each measured input moved by +-3e-3 x a normal draw) with their
    rest poses and base mode sets: the Solar Boat, the drone, the trifilar (repeated swings), the knife-edge
    plate (a neutral mode), the thesis cylinder."""
    from bifilar.analysis.batch import rest_poses

    rng = np.random.default_rng(11)
    for name, params in (("solar_boat", {"spacing": 3.0}), ("solar_boat", {"spacing": 1.5, "length": 3.5}),
                         ("drone_parallel", {}), ("trifilar_kth", {}), ("thesis_plate_rest", {}),
                         ("thesis_cylinder_6_4", {})):
        base = _scene(name, params)
        rest = rest_pose(base)
        scenes = [perturb(base, nm, sgn * float(rng.normal()) * 3e-3) for nm in measured_inputs(base) for sgn in (1, -1)]
        rests = rest_poses(scenes, rest, errors="return")
        keep = [q for q, r in enumerate(rests) if not isinstance(r, Exception)]
        yield name, base, rest, [scenes[q] for q in keep], [rests[q] for q in keep]


def test_lazy_mode_sets_equal_the_eager_ones():
    # modes_batch(lazy=True) gives a scene with distinct, positive eigenvalues a LazyModeSet (periods and unit
    # shapes for the batch at once, the Mode objects when read); against modes_batch without it (the path
    # before): the same periods and shapes before the modes are built, the same mode sets bit for bit once
    # built, pickled as the plain ModeSet; scenes with a cluster (the trifilar's swings) or a neutral mode (the
    # knife-edge plate) stay eager
    import pickle

    from bifilar.analysis.batch import modes_batch
    from bifilar.analysis.modes import LazyModeSet, ModeSet

    lazy_n = eager_n = 0
    for name, _, _, scenes, rests in _sigma_batches():
        ref = modes_batch(scenes, rests)
        got = modes_batch(scenes, rests, lazy=True)
        for a, b in zip(got, ref):
            if isinstance(a, LazyModeSet):
                lazy_n += 1
                assert "modes" not in a.__dict__
                assert np.array_equal(a.periods, [m.period for m in b.modes])
                assert np.array_equal(a.shapes, [m.shape for m in b.modes])
                assert np.array_equal(a.mass_matrix, b.mass_matrix) and np.array_equal(a.basis, b.basis)
                plain = pickle.loads(pickle.dumps(a))
                assert type(plain) is ModeSet and _mode_set_fields(plain)[0] == _mode_set_fields(b)[0]
            else:
                eager_n += 1
                assert name in ("trifilar_kth", "thesis_plate_rest") or len({m.period for m in b.modes}) < len(b.modes)
                assert len({m.period for m in b.modes}) < len(b.modes) or any(m.period is None for m in b.modes)
            assert _mode_set_fields(a)[:3] == _mode_set_fields(b)[:3]
    assert lazy_n > 80 and eager_n > 20


def test_plain_order_refuses_clusters_and_neutral_modes_whatever_their_last_bits():
    # plain_order admits a scene only when mode_set would neither merge nor call neutral any of its eigenvalues,
    # with a margin of 2 over the resolution: built by hand, a gap of 3 resolutions passes, of 1.5 does not
    # (mode_set would not merge it, but the margin is for the batch's rounding), of 0.5 does not (a cluster)
    from bifilar.analysis.modes import DEGENERATE_RTOL, _noise, clusters, plain_order

    K = np.diag([1.0, 2.0, 5.0])
    Y = np.eye(3)
    for gap, want in ((3.0, True), (1.5, False), (0.5, False)):
        w2 = np.array([1.0, 2.0, 2.0 + gap * DEGENERATE_RTOL * 2.0 * (1 + 1e-12)])
        Kg = np.diag(w2)
        assert bool(plain_order(w2[None], Y[None], Kg[None])[0]) is want
        if want:
            assert len(clusters(w2, _noise(w2, Y, Kg))) == 3
        if gap < 1:
            assert len(clusters(w2, _noise(w2, Y, Kg))) == 2
    assert not plain_order(np.array([[0.0, 1.0, 2.0]]), Y[None], K[None])[0]  # neutral
    assert not plain_order(np.array([[-1.0, 1.0, 2.0]]), Y[None], K[None])[0]  # unstable


def _hanging_periods_before(scenes, rest, base_modes) -> list:
    """budget._hanging_periods before session 7 (eager mode sets), verbatim."""
    from bifilar.analysis.batch import modes_batch, rest_poses
    from bifilar.errors import BifilarError  # noqa: F401 - as the module had it
    from bifilar.estimation.montecarlo import _modes_or_none
    from bifilar.estimation.sensitivity import mac_matches

    rests = rest_poses(scenes, rest, errors="return")
    good = [q for q, r in enumerate(rests) if not isinstance(r, BaseException)]
    out: list = [None] * len(scenes)
    if not good:
        return out
    mss = _modes_or_none(modes_batch, [scenes[q] for q in good], [rests[q] for q in good])
    kept = [(q, ms) for q, ms in zip(good, mss) if ms is not None and len(ms.modes) == len(base_modes.modes)]
    for (q, ms), col in zip(kept, mac_matches(base_modes, [ms for _, ms in kept])):
        T = np.array([ms.modes[c].period or np.nan for c in col])
        out[q] = (T, scenes[q], rests[q], ms, col)
    return out


def test_hanging_periods_with_lazy_mode_sets_equal_the_ones_before():
    # the sigma points' periods and MAC columns from the lazy mode sets against the eager path: bit for bit
    from bifilar.estimation.budget import _hanging_periods

    for _, base, rest, scenes, _ in _sigma_batches():
        ms0 = linear_modes(base, rest)
        got = _hanging_periods(scenes, rest, ms0)
        ref = _hanging_periods_before(scenes, rest, ms0)
        assert len(got) == len(ref)
        for a, b in zip(got, ref):
            assert (a is None) == (b is None)
            if a is not None:
                assert a[0].tobytes() == b[0].tobytes() and list(a[4]) == list(b[4])
                assert _mode_set_fields(a[3])[:3] == _mode_set_fields(b[3])[:3]


def _old_zero_set(vals: dict) -> frozenset:
    """maximal._zero_set before session 7, verbatim."""
    from bifilar.models.maximal import _NEVER_ZERO

    out = set()
    for k, v in vals.items():
        if k in _NEVER_ZERO or k.startswith(("L2", "hbL")):
            continue  # never drop these (a zero would be a degenerate scene anyway)
        if np.all(np.asarray(v) == 0):
            out.add(k)
    return frozenset(out)


def test_kernel_parameters_once_per_rig_and_zero_set_on_floats():
    # compiled_kernel computes a rig's parameter values and zero set once for all its kernels (was once per
    # kernel), and _zero_set tests a single scene's floats without numpy: the same zero sets (signed zeros,
    # NaN, batch arrays) and the same kernels' outputs as kernels of a fresh RigParams each
    from bifilar.models import maximal as mx

    vals = {"mass": 0.0, "Ixy": 0.0, "Ixz": -0.0, "Iyz": 1e-300, "Ex": float("nan"), "px0": 2.0, "L20": 0.0,
            "ax0": np.zeros(3), "ay0": np.array([0.0, 1.0]), "az0": np.array([-0.0, 0.0])}
    assert mx._zero_set(vals) == _old_zero_set(vals) == frozenset({"Ixy", "Ixz", "ax0", "az0"})
    for name, params in (("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {}), ("thesis_plate_rest", {})):
        scene = _scene(name, params)
        P = mx.params_from_scenes([scene]).take(0)
        assert mx._zero_set(mx._param_values(P)) == _old_zero_set(mx._param_values(P))
        y = np.array([0.01, -0.02, 0.03, 0.999, 0.02, -0.01, 0.03, 0.1, -0.2, 0.05, 0.3, -0.1, 0.2])
        y[3:7] /= np.linalg.norm(y[3:7])
        for kw in ({}, {"extras": True}, {"signature": "odeint"}):
            fresh = mx.compiled_kernel(mx.params_from_scenes([scene]).take(0), **kw)
            got = mx.compiled_kernel(P, **kw)
            a = got(y, 0.0) if kw.get("signature") else got(*y)
            b = fresh(y, 0.0) if kw.get("signature") else fresh(*y)
            assert np.array_equal(np.asarray(a, float), np.asarray(b, float))
        assert "values" in P.__dict__["_kernels"]


@pytest.mark.parametrize("name,params", [("solar_boat", {"spacing": 3.0}), ("thesis_lin2_pitch", {}),
                                         ("trifilar_kth", {}), ("thesis_plate_rest", {}), ("drone_parallel", {})])
def test_modes_of_inertia_lazy_equals_eager(name, params):
    # modes_of_inertia(...)(inertia, lazy=True): a LazyModeSet where mode_set keeps the eigensolver's order (no
    # cluster, no neutral mode: the trifilar's swings and the knife-edge plate stay eager); against the eager
    # mode set (the path before): the same periods and shapes before its modes are built, the same mode set
    # after; and matched_periods (what linear_estimate reads) the same bits
    from bifilar.analysis.modes import LazyModeSet

    scene = _scene(name, params)
    rest = rest_pose(scene)
    base = linear_modes(scene, rest)
    n_lazy = 0
    for comp, f in (("Ixx", 1.0), ("Izz", 1.0 + 3e-4), ("Iyy", 1.0 - 2e-3), ("Ixy", 0.01)):
        inertia = perturb(scene, comp, (f - 1.0 if comp != "Ixy" else f) * scene.inertia[0, 0]).inertia
        eager = modes_of_inertia(scene, rest)(inertia)
        lazy = modes_of_inertia(scene, rest)(inertia, lazy=True)
        assert np.array_equal(matched_periods(base, lazy), matched_periods(base, eager), equal_nan=True)
        if isinstance(lazy, LazyModeSet):
            n_lazy += 1
            assert "modes" not in lazy.__dict__
            assert np.array_equal(lazy.periods, [m.period for m in eager.modes])
            assert np.array_equal(lazy.shapes, [m.shape for m in eager.modes])
        assert _mode_set_fields(lazy)[:3] == _mode_set_fields(eager)[:3]
    assert (n_lazy == 4) == (name not in ("trifilar_kth", "thesis_plate_rest"))


@pytest.mark.parametrize("comp", COMPS)
def test_linear_estimate_with_lazy_mode_sets_equals_the_eager_one(comp):
    # linear_estimate's secant steps read periods and shapes only (lazy mode sets); against the same steps
    # with eager mode sets (an `at` that ignores lazy: the path before): the same estimate, bit for bit
    scene = _scene("solar_boat", {"spacing": 3.0})
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    k = best_mode_for(sens, comp)
    at = modes_of_inertia(scene, sens.rest)
    eager = modes_of_inertia(scene, sens.rest)
    for rel in (3e-4, -1e-3, 2e-2):
        T_target = sens.periods[k] * (1 + rel)
        got = linear_estimate(scene, comp, k, T_target, sens.modes, sens.rest, sens.column(comp)[k], at=at)
        ref = linear_estimate(scene, comp, k, T_target, sens.modes, sens.rest, sens.column(comp)[k],
                              at=lambda inertia, lazy=False: eager(inertia))
        assert got is not None and got == ref


def test_admissible_interval_remembered_equals_computed(monkeypatch):
    # admissible_interval remembers its answers (a sweep over geometry asks the same tensors at every point);
    # against the computation (the path before, _admissible_interval): the same ends, the component's own value
    # ignored as before, and the memory bounded
    from bifilar.estimation import problem as pr

    rng = np.random.default_rng(3)
    monkeypatch.setattr(pr, "_admissible_seen", {})
    calls = []
    real = pr._admissible_interval
    monkeypatch.setattr(pr, "_admissible_interval", lambda I0, name: calls.append(name) or real(I0, name))
    for _ in range(40):
        A = rng.normal(size=(3, 3))
        I = A @ A.T + 0.3 * np.eye(3)
        for name in ("Ixx", "Izz", "Ixy", "Iyz"):
            i, j = pr._IDX[name]
            I0 = I.copy()
            I0[i, j] = I0[j, i] = 0.0
            first = pr.admissible_interval(I, name)
            assert first == real(I0, name)
            I2 = I.copy()
            I2[i, j] = I2[j, i] = I[i, j] + 1.0  # its own value is ignored
            n = len(calls)
            assert pr.admissible_interval(I2, name) == first and len(calls) == n
    assert len(calls) == 160 and len(pr._admissible_seen) <= pr._ADMISSIBLE_KEEP


def test_rest_poses_quaternion_when_read_and_the_turn_check_from_the_trace():
    # batch rest poses compute q when it is read (matrix_to_quat of R alone: the same bits as in the batch),
    # and the Newton start's turn check decides from the trace away from its threshold (matrix_to_quat near
    # it); against matrix_to_quat of the whole batch (the path before): the same quaternions and verdicts,
    # on random rotations, rotations within 1e-12 of the threshold either way, and a NaN
    from bifilar.analysis.batch import rest_poses
    from bifilar.analysis.batch_rest import _within_turn
    from bifilar.analysis.equilibrium import NEWTON_START_MAX_TURN
    from bifilar.rotations import matrix_to_quat, rotvec_to_matrix

    rng = np.random.default_rng(8)
    c = np.cos(NEWTON_START_MAX_TURN / 2)
    axes = rng.normal(size=(400, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    ang = np.concatenate([rng.uniform(0, np.pi, 200), NEWTON_START_MAX_TURN + rng.uniform(-1e-12, 1e-12, 200)])
    R = rotvec_to_matrix(axes * ang[:, None])
    R[7, 1, 2] = np.nan
    with np.errstate(invalid="ignore"):
        want = np.abs(matrix_to_quat(R)[:, 0]) >= c
    assert np.array_equal(_within_turn(R, c), want) and want[200:].any() and not want[200:].all()
    base = _scene("solar_boat", {"spacing": 3.0})
    scenes = [perturb(base, n, 1e-3) for n in measured_inputs(base)]
    got = rest_poses(scenes, rest_pose(base))
    assert all("q" not in r.__dict__ for r in got)
    Q = matrix_to_quat(np.array([r.R for r in got]))
    for r, q in zip(got, Q):
        assert np.array_equal(r.q, q)


def _old_derivatives_skew(v):
    """derivatives._skew before session 7, verbatim."""
    z = np.zeros(v.shape[:-1], dtype=v.dtype)
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2)


@pytest.mark.parametrize("name,params", [("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {}),
                                         ("thesis_plate_rest", {"spacing": 2.0}), ("drone_parallel", {})])
def test_analytic_jacobian_with_in_place_cross_and_skew_equals_np_cross_and_stacks(name, params, monkeypatch):
    # the analytic period derivatives (complex steps through _parts, _stepped, _pose_derivative) take
    # batch_rest's _cross and _skew (written in place); against np.cross and the stacked skew (the path
    # before): the same Jacobian bit for bit
    from bifilar.analysis import derivatives as dv

    scene = _scene(name, params)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    names = COMPS + measured_inputs(scene)
    got = dv.analytic_period_jacobian(scene, rest, ms, names)
    monkeypatch.setattr(dv, "_skew", _old_derivatives_skew)
    monkeypatch.setattr(dv, "_cross", np.cross)
    ref = dv.analytic_period_jacobian(scene, rest, ms, names)
    assert np.asarray(got, float).tobytes() == np.asarray(ref, float).tobytes()
    v = np.random.default_rng(4).normal(size=(5, 2, 3)) * (1 + 1j)
    assert np.array_equal(dv._skew(v), _old_derivatives_skew(v)) and dv._skew(v).dtype == complex
    assert np.array_equal(dv._cross(v, v[::-1]), np.cross(v, v[::-1]))


def _old_skew(v):
    """rotations.skew before session 7, verbatim."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], axis=-1), np.stack([v[..., 2], z, -v[..., 0]], axis=-1),
                     np.stack([-v[..., 1], v[..., 0], z], axis=-1)], axis=-2)


def _old_rotvec_to_quat(v):
    """rotations.rotvec_to_quat before session 7, verbatim."""
    v = np.asarray(v, dtype=float)
    ang = np.linalg.norm(v, axis=-1, keepdims=True)
    half = 0.5 * ang
    small = ang < 1e-8
    k = np.where(small, 0.5 - ang**2 / 48.0, np.sin(half) / np.where(small, 1.0, ang))
    return np.concatenate([np.cos(half), k * v], axis=-1)


def test_rotvec_to_quat_and_skew_with_fewer_calls_equal_the_ones_before():
    # rotvec_to_quat (the start poses' and Newton steps' rotations: ~15 calls a point) sums squares as
    # np.linalg.norm does and takes the series' branch only where an angle is tiny; skew writes its entries in
    # place; against the verbatim functions before: the same bits, tiny, zero, -0.0 and NaN vectors included
    from bifilar.rotations import rotvec_to_matrix, rotvec_to_quat, skew

    rng = np.random.default_rng(12)
    for shape in ((3,), (7, 3), (4, 2, 3)):
        v = rng.normal(size=shape) * rng.choice([1e-12, 1e-9, 1e-3, 1.0, 3.0], size=shape[:-1] + (1,))
        for w in (v, np.zeros(shape), -np.zeros(shape), np.where(rng.uniform(size=shape) < 0.2, np.nan, v)):
            assert np.array_equal(rotvec_to_quat(w), _old_rotvec_to_quat(w), equal_nan=True)
            assert np.array_equal(skew(w), _old_skew(w), equal_nan=True)
            assert np.array_equal(np.signbit(skew(w)), np.signbit(_old_skew(w)))
    assert rotvec_to_matrix(np.zeros(3)).tolist() == np.eye(3).tolist()


def test_thesis_model_validates_only_a_products_unit_step():
    # ThesisModel builds a moment's unit-step inertia without KaneParams' checks (adding C^T r r^T C keeps it
    # positive semi-definite: they cannot fail) and a product's through them, as before: a body whose moments
    # are small against the unit step of Ixy is refused (InputError), its Ixx is not
    from bifilar.errors import InputError
    from bifilar.estimation.ladder import ThesisModel
    from bifilar.estimation.measurements import Hanging
    from bifilar.estimation.problem import HangingModel

    scene = _scene("thesis_lin2_pitch", {})
    small = replace(scene, inertia=scene.inertia * (0.3 / float(np.max(scene.inertia))))
    hm = HangingModel(Hanging("h", small, np.eye(3)), small.inertia)
    sens = period_sensitivity(small, COMPS)
    k = best_mode_for(sens, "Iyy")
    ThesisModel(hm, k, "Iyy")
    with pytest.raises(InputError, match="positive semi-definite"):
        ThesisModel(hm, k, "Ixz")



def test_quat_to_matrix_of_a_few_on_python_floats_equals_the_numpy_path(monkeypatch):
    # quat_to_matrix of up to 8 quaternions (a start-pose solve's, ~11 calls a point) on Python floats; against
    # the numpy path (all it was before; _FEW = 0 takes it for every size): the same bits over random, tiny,
    # huge and nearly identity quaternions in every shape it takes, and numpy's own NaN / inf for a zero or
    # non-finite one
    from bifilar import rotations
    from bifilar.rotations import quat_to_matrix

    def _numpy_quat_to_matrix(q):
        with monkeypatch.context() as m:
            m.setattr(rotations, "_FEW", 0)
            m.setattr(rotations, "_STACKED", 0)  # (session 26: 9-256 quaternions take one outer product)
            return quat_to_matrix(q)

    rng = np.random.default_rng(21)
    n = 0
    for shape in ((4,), (1, 4), (3, 4), (8, 4), (2, 3, 4), (9, 4)):
        for scale in (1e-150, 1e-3, 1.0, 1e3, 1e150):
            for _ in range(60):
                q = rng.normal(size=shape) * scale
                if rng.uniform() < 0.3:
                    q[..., 1:] *= 1e-9
                assert np.array_equal(quat_to_matrix(q), _numpy_quat_to_matrix(q))
                n += 1
    with np.errstate(all="ignore"):
        for bad in (np.zeros(4), np.array([[1.0, 0, 0, 0], [np.nan, 0, 0, 1]]), np.array([np.inf, 1.0, 0, 0])):
            assert np.array_equal(quat_to_matrix(bad), _numpy_quat_to_matrix(bad), equal_nan=True)
    assert n == 1800


def test_modes_batch_with_the_rest_poses_geometry_equals_computing_it_again():
    # (session 8) modes_batch takes the stacked arrays, wire vectors, |d|, constraint Jacobian and null space of
    # the rest_poses call that gave its rests (BatchGeometry) instead of computing them again from the same
    # scenes and poses; against modes_batch without it (the path before): the same mode sets bit for bit, lazy
    # and eager, over sigma-point-like batches of six rigs (knife edge, repeated swings, a neutral mode), and
    # the geometry refused (computed again) for a subset, another order, other rest objects and a batch with a
    # rest_pose fallback (a rig turned 0.8 rad: the batch's Newton end is not taken)
    from bifilar.analysis.batch import modes_batch, rest_poses
    from bifilar.estimation.budget import _hanging_periods

    rng = np.random.default_rng(21)
    used = 0
    for name, params in (("solar_boat", {"spacing": 3.0}), ("solar_boat", {"spacing": 1.5, "length": 3.5}),
                         ("drone_parallel", {}), ("trifilar_kth", {}), ("thesis_plate_rest", {}),
                         ("thesis_cylinder_6_4", {})):
        base = _scene(name, params)
        scenes = [perturb(base, nm, sgn * float(rng.normal()) * 3e-3) for nm in measured_inputs(base) for sgn in (1, -1)]
        geo: list = []
        rests = rest_poses(scenes, errors="return", geometry=geo)
        ref_rests = rest_poses(scenes, errors="return")
        for a, b in zip(rests, ref_rests):  # (rest_poses itself unchanged by handing its arrays over)
            assert type(a) is type(b)
            if not isinstance(a, Exception):
                assert a.com.tobytes() == b.com.tobytes() and a.R.tobytes() == b.R.tobytes()
                assert a.tensions.tobytes() == b.tensions.tobytes()
        good = [q for q, r in enumerate(rests) if not isinstance(r, Exception)]
        sc, rs = [scenes[q] for q in good], [rests[q] for q in good]
        assert geo[0].matches(sc, rs) is (len(good) == len(scenes))
        used += geo[0].matches(sc, rs)
        for lazy in (False, True):
            got = modes_batch(sc, rs, lazy, geometry=geo[0])
            ref = modes_batch(sc, rs, lazy)
            assert [_mode_set_fields(a)[:3] for a in got] == [_mode_set_fields(b)[:3] for b in ref]
        assert not geo[0].matches(sc[1:], rs[1:]) and not geo[0].matches(sc[::-1], rs[::-1])
        assert not geo[0].matches(sc, [replace(r) for r in rs])
        ms0 = linear_modes(base, rest_pose(base))
        got = _hanging_periods(scenes, rest_pose(base), ms0)
        ref = _hanging_periods_before(scenes, rest_pose(base), ms0)
        for a, b in zip(got, ref):
            assert (a is None) == (b is None)
            if a is not None:
                assert a[0].tobytes() == b[0].tobytes() and list(a[4]) == list(b[4])
    assert used >= 5
    turned = _scene("solar_boat", {"spacing": 3.0, "rotate_z": 0.8})
    pair = [turned, _scene("solar_boat", {"spacing": 3.0})]
    geo = []
    rs = rest_poses(pair, geometry=geo)
    assert not geo[0].matches(pair, rs)  # the turned rig's pose is rest_pose's, not the batch Newton's end
    assert [_mode_set_fields(a)[:3] for a in modes_batch(pair, rs, geometry=geo[0])] == \
        [_mode_set_fields(b)[:3] for b in modes_batch(pair, rs)]


def test_line_turns_with_the_callers_knife_edge_axes_and_in_place_cross():
    # (session 8) rest_poses hands line_turns the knife-edge axes it computed (was computed twice) and the line
    # frame's side vector is rotations.cross (np.cross's operations): the same psi and n, NaN cases included,
    # as line_turns with np.cross and its own knife_edge_axes (the path before), on random two-wire rigs,
    # knife edges and a vertical attachment line
    from bifilar.analysis import equilibrium as eq
    from bifilar.rotations import cross, rotvec_to_matrix

    rng = np.random.default_rng(3)
    p = rng.normal(size=(60, 2, 3))
    p[5] = [[1.0, 0.0, 0.0], [-2.0, 0.0, 0.0]]  # knife edge: the CoM on the line
    p[6] = [[0.1, 0.0, 0.5], [0.1, 0.0, -0.5]]  # the line vertical at R = identity
    R = rotvec_to_matrix(rng.normal(size=(60, 3)))
    R[6] = np.eye(3)
    axes = eq.knife_edge_axes(p)
    psi, n = eq.line_turns(p, R, edge_axes=axes)

    def frame_with_np_cross(pp, RR):
        nn, down, _, v, nz = _old_line_frame(pp, RR)
        return nn, down, np.cross(nn, down), v, nz

    with pytest.MonkeyPatch.context() as m:
        m.setattr(eq, "_line_frame", frame_with_np_cross)
        psi0, n0 = eq.line_turns(p, R)
    assert psi.tobytes() == psi0.tobytes() and n.tobytes() == n0.tobytes()
    assert np.isnan(psi[5]) and np.isnan(psi[6]) and np.isfinite(psi[:5]).all()
    u, v = rng.normal(size=(2, 7, 3)) + 1j * rng.normal(size=(2, 7, 3))
    assert cross(u, v).tobytes() == np.cross(u, v).tobytes()  # complex (the analytic derivatives' steps)


def _old_line_frame(p, R):
    """equilibrium._line_frame before session 8 without its cross product (verbatim otherwise)."""
    p = np.asarray(p, float)
    u = p[..., 1, :] - p[..., 0, :]
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    foot = p[..., 0, :] - np.einsum("...i,...i->...", p[..., 0, :], u)[..., None] * u
    n = np.einsum("...ij,...j->...i", R, u)
    v = -np.einsum("...ij,...j->...i", R, foot)
    zp = np.array([0.0, 0.0, 1.0]) - n[..., 2:3] * n
    nz = np.linalg.norm(zp, axis=-1, keepdims=True)
    down = -zp / np.where(nz > 0, nz, 1.0)
    return n, down, None, v, nz[..., 0]


def _old_left_jacobian(theta):
    """start_pose.left_jacobian before session 8, verbatim."""
    from bifilar.rotations import skew

    theta = np.asarray(theta, float)
    a2 = np.einsum("...i,...i->...", theta, theta)
    a = np.sqrt(a2)
    small = a < 1e-4
    safe = np.where(small, 1.0, a)
    b = np.where(small, 0.5 - a2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    c = np.where(small, 1.0 / 6.0 - a2 / 120.0, (safe - np.sin(safe)) / safe**3)
    K = skew(theta)
    return np.eye(3) + b[..., None, None] * K + c[..., None, None] * (K @ K)


def _old_rig_take(self, ii):
    """start_pose._Rig.take before session 8, verbatim."""
    from bifilar.analysis.start_pose import _Rig

    out = object.__new__(_Rig)
    for k, v in self.__dict__.items():
        out.__dict__[k] = v[ii]
    return out


def test_start_poses_without_masks_or_copies_equal_the_ones_before():
    # (session 8) left_jacobian skips the series' masks where no angle is tiny, and _Rig.take of every scene in
    # order is the rig itself (no copies); against the verbatim functions before: the same left Jacobians (tiny,
    # small, large and mixed angles, a NaN) and the same start poses bit for bit (chart pose, CoM, attitude,
    # quaternion, residual, gap) of a sweep point's runs and a mixed batch (amplitudes 1e-7..0.3, the series
    # branch included, an unreachable start going through the continuation and least squares)
    from bifilar.analysis import start_pose as spm

    rng = np.random.default_rng(4)
    th = rng.normal(size=(40, 3)) * np.logspace(-9, 0.5, 40)[:, None]
    th[7] = np.nan
    for t in (th, th[20:], th[:3], th[5]):
        with np.errstate(invalid="ignore"):
            assert spm.left_jacobian(t).tobytes() == _old_left_jacobian(t).tobytes()
    cases = []
    for name, params in (("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {}), ("drone_parallel", {}),
                         ("thesis_plate_rest", {})):
        s = _scene(name, params)
        rest = rest_pose(s)
        modes = [m for m in linear_modes(s, rest).modes if m.period]
        for amp in (1e-7, 0.05, 0.3):
            cases.append(([s] * len(modes), [rest] * len(modes), modes, amp))
        cases.append(([s] * len(modes), [rest] * len(modes), modes, np.geomspace(1e-6, 2.0, len(modes))))
    for scenes, rests, modes, amp in cases:
        got = spm.start_poses(scenes, rests, modes, amp)
        with pytest.MonkeyPatch.context() as m:
            m.setattr(spm, "left_jacobian", _old_left_jacobian)
            m.setattr(spm._Rig, "take", _old_rig_take)
            ref = spm.start_poses(scenes, rests, modes, amp)
        for f in spm.StartPoses.__dataclass_fields__:
            assert getattr(got, f).tobytes() == getattr(ref, f).tobytes(), f
    assert any(not np.all(spm.start_poses(*c).feasible) for c in cases)  # (the fallbacks were exercised)
    rig = spm._Rig(cases[0][0], cases[0][1])
    assert rig.take(np.arange(len(cases[0][0]))) is rig  # the shortcut is taken ...
    for ii in (np.arange(len(cases[0][0]))[::-1], np.array([0, 0, 1]), np.arange(2)):  # ... only for all, in order
        sub = rig.take(ii)
        assert sub is not rig and all(np.array_equal(v[ii], sub.__dict__[k]) for k, v in rig.__dict__.items())


def test_start_poses_with_more_rows_equal_the_calls_of_their_own():
    """(session 8, the amplitude law's runs) ``checked_start_poses(...,
    more=)``: the law's runs' start poses (another amplitude, stepped
    scenes) solved in the point's call are, row by row, the bits of the two
    calls they replace; a refusal of the point's own rows is the same."""
    from bifilar.analysis.simulate import checked_start_poses
    from bifilar.analysis.start_pose import start_poses
    from bifilar.errors import InputError
    from bifilar.studies.point import _law_runs

    for name, params, amp in [("solar_boat", {"spacing": 3.0}, 0.3), ("trifilar_kth", {}, 0.05)]:
        scene = _scene(name, params)
        rest = rest_pose(scene)
        ms = linear_modes(scene, rest)
        idx = [k for k, m in enumerate(ms.modes) if m.period][:3]
        timed = [ms.modes[k] for k in idx]
        chosen = dict(zip(COMPS, idx))
        law = _law_runs(scene, rest, ms, [m.label for m in ms.modes], chosen, amp)
        more_modes = [m.get(lab) for m, lab in zip(law.mode_sets, law.labels)]
        got = checked_start_poses(scene, rest, timed, amp, more=(law.scenes, law.rests, more_modes, law.amplitudes))
        own = checked_start_poses(scene, rest, timed, amp)
        other = start_poses(law.scenes, law.rests, more_modes, law.amplitudes)
        ref = own.concat([own, other])
        assert len(got.feasible) == len(timed) + len(law.labels) == 2 * len(timed) + len(set(chosen.values()))
        for f in ("com", "R", "q", "x", "residual", "feasible", "gap", "amplitude"):
            assert np.array_equal(getattr(got, f), getattr(ref, f)), f
    scene = _scene("thesis_plate_rest", {"spacing": 3.0})  # a refused start: the error of the call alone
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    swing = ms.get("swing-y")
    with pytest.raises(InputError) as alone:
        checked_start_poses(scene, rest, [swing], 1.2)
    with pytest.raises(InputError) as more:
        checked_start_poses(scene, rest, [swing], 1.2, more=([scene], [rest], [swing], [0.01]))
    assert str(more.value) == str(alone.value)


@pytest.mark.parametrize("name, params, amp", [("solar_boat", {"spacing": 3.0}, None),
                                               ("thesis_lin2_pitch", {}, None),
                                               ("trifilar_kth", {}, 0.3)])
def test_point_with_its_laws_runs_in_its_call_equals_the_separate_calls(name, params, amp, monkeypatch):
    """(session 8) A point's amplitude laws' runs, their start poses solved
    and the runs run in the point's own calls, give every figure of the
    point bit for bit as the path before: the point's runs first, then the
    laws' runs in a call of their own solving their own start poses."""
    import json

    from bifilar.analysis import simulate as simm
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = sw.resolve_settings(cfg, **({"amplitude": amp} if amp else {}))
    got = sw.evaluate_point(cfg, name, params, st)
    assert got["valid"] and all(e["amplitude_budget"]["budgeted"] for e in got["components"].values()
                                if e.get("mode"))
    real = simm.checked_start_poses
    monkeypatch.setattr(simm, "checked_start_poses", lambda s, r, m, a, more=None: real(s, r, m, a))

    def before(base_cfg, source, params, st, screen=False):  # the path before: two solves, two calls
        res, pre = pt._prepare(base_cfg, source, params, st, screen)
        pre.law = None
        sims = dict(zip(pre.runs, pt._nonlinear_runs(pre.scene, pre.rest, pre.ms, [pre.labels[k] for k in pre.runs],
                                                     pre.amplitude, st, pre.starts)))
        return pt._finish(res, pre, sims, st, screen)

    monkeypatch.setattr(pt, "_evaluate", before)
    ref = sw.evaluate_point(cfg, name, params, st)
    assert json.dumps(got, sort_keys=True, default=str) == json.dumps(ref, sort_keys=True, default=str)


@pytest.mark.parametrize("name, params", [("solar_boat", {"spacing": 3.0}), ("thesis_lin2_pitch", {})])
def test_law_runs_stepped_modes_from_the_points_stiffness_equal_their_linear_modes(name, params):
    """(session 8) The amplitude laws' stepped scenes take their modes from
    the point's stiffness (``modes_of_inertia``): every label, period and
    shape those of each stepped scene's own ``linear_modes``, bit for bit;
    the stepped inertia is the one invert steps (``FACTOR_STEP`` of the
    largest moment, on the component and its transpose)."""
    from bifilar.estimation.solve import FACTOR_STEP
    from bifilar.studies.point import _IDX, _law_runs

    scene = _scene(name, params)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    idx = [k for k, m in enumerate(ms.modes) if m.period][:3]
    chosen = dict(zip(COMPS + ["Ixy"], idx + idx[:1]))
    labels = [m.label for m in ms.modes]
    got = _law_runs(scene, rest, ms, labels, chosen, 0.05, modes_of_inertia(scene, rest))
    ref = _law_runs(scene, rest, ms, labels, chosen, 0.05)
    h = FACTOR_STEP * np.max(np.linalg.eigvalsh(scene.inertia))
    n = len(got.modes)
    for (c, _), sc, a, b in zip(got.comps, got.scenes[n:], got.mode_sets[n:], ref.mode_sets[n:]):
        i, j = _IDX[c]
        dI = np.zeros((3, 3))
        dI[i, j] = dI[j, i] = h
        assert np.allclose(sc.inertia - scene.inertia, dI, rtol=0, atol=1e-9 * h)
        assert [m.label for m in a.modes] == [m.label for m in b.modes]
        for x, y in zip(a.modes, b.modes):
            assert x.period == y.period and np.array_equal(x.shape, y.shape) and x.dominant == y.dominant


@pytest.mark.parametrize("name, params", [("solar_boat", {"spacing": 3.0}), ("trifilar_kth", {})])
def test_law_runs_without_health_have_the_periods_of_the_runs_with_it(name, params):
    """(session 8) The amplitude laws' runs skip the health figures (only
    their periods are read): every run's period and crossings those of the
    same run with its health, bit for bit; and a planner's screen of the
    point (``evaluate_points``: all its laws' runs in one call without
    health) gives what the point alone gives."""
    import json

    from bifilar.analysis.batch import simulate_batch
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = sw.resolve_settings(cfg)
    res, pre = pt._prepare(cfg, name, params, st)
    law = pre.law
    assert law is not None and len(law.labels) >= 2
    kw = dict(mode=law.labels, amplitude=law.amplitudes, periods=st.periods, rtol=st.rtol, rests=law.rests,
              modes=law.mode_sets, errors="return")
    with_health = simulate_batch(law.scenes, **kw)
    got = pt._runs_at(law, st)
    assert np.all(np.isnan([r.max_constraint_violation for r in got]))  # the health was skipped
    for a, b in zip(got, with_health):
        assert a.period is not None and a.period == b.period and np.array_equal(a.crossings, b.crossings)
    for screen in (False, True):
        alone = sw.evaluate_point(cfg, name, params, st, screen=screen)
        batch = pt.evaluate_points(cfg, name, [params], st, screen=screen)[0]
        assert alone["valid"] and json.dumps(alone, sort_keys=True, default=str) == json.dumps(batch, sort_keys=True,
                                                                                                default=str)


@pytest.mark.parametrize("name, params", [("solar_boat", {"spacing": 3.0}), ("thesis_plate_rest", {"spacing": 3.0})])
def test_point_computes_the_health_of_its_own_runs_only_and_takes_its_laws_crossings_in_one_pass(name, params,
                                                                                                   monkeypatch):
    """(session 9) A point's runs with their health are its own runs only
    (the laws' runs at 0.9 of the amplitude shared that call, their health
    computed and never read), and all its laws' runs -- the 0.9 ones and
    the stepped scenes' -- have their crossings taken in one pass (was one
    a scene); every figure of the point is the one of the path before
    (its own runs alone, then each of the laws' runs as ``simulate_batch``
    runs it alone with its health), bit for bit."""
    import json

    import bifilar.analysis.batch_lsoda as bl
    from bifilar.analysis.batch import run_one
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = sw.resolve_settings(cfg)
    rows, windows = [], []
    real_health, real_window = bl.sample_health, bl._window
    monkeypatch.setattr(bl, "sample_health", lambda Ys, *a, **kw: rows.append(Ys.shape[1]) or real_health(Ys, *a, **kw))
    monkeypatch.setattr(bl, "_window", lambda Ys, *a, **kw: windows.append(Ys.shape[1]) or real_window(Ys, *a, **kw))
    got = sw.evaluate_point(cfg, name, params, st)
    res, pre = pt._prepare(cfg, name, params, st)
    assert got["valid"] and rows == [len(pre.runs)]
    # (session 15: a point whose components have no finite sigma, the plate's knife edge, runs no law)
    assert windows == [len(pre.runs)] + ([len(pre.law.labels)] if pre.law.labels else [])
    monkeypatch.undo()

    def before(base_cfg, source, params, st, screen=False):  # each run alone, the laws' with their health
        res, pre = pt._prepare(base_cfg, source, params, st, screen)
        sims = {k: run_one(pre.scene, pre.rest, pre.ms.modes[k], pre.amplitude, st.periods, rtol=st.rtol)
                for k in pre.runs}
        law = pre.law
        law.runs = [run_one(s_, r_, m_.get(lab), a_, st.periods, rtol=st.rtol)
                    for s_, r_, m_, lab, a_ in zip(law.scenes, law.rests, law.mode_sets, law.labels, law.amplitudes)]
        return pt._finish(res, pre, sims, st, screen)

    monkeypatch.setattr(pt, "_evaluate", before)
    ref = sw.evaluate_point(cfg, name, params, st)
    assert json.dumps(got, sort_keys=True, default=str) == json.dumps(ref, sort_keys=True, default=str)


def test_point_runs_only_the_amplitude_laws_a_sigma_reads(monkeypatch):
    """(session 15, perf17) The thesis plate's point (knife edge: the CoM on
    the attachment line, an input without a derivative) has no finite
    small-amplitude sigma for either component, so no stated-amplitude
    sigma reads an amplitude law there; its 4 law runs (0.9 A and stepped)
    were made anyway, 4 of the point's 6 runs (~40 % of its CPU).  Now only
    the point's own runs are made, and every figure is the path before's
    (all laws run), bit for bit, the sweep's and the planner's
    (``evaluate_points``) alike."""
    import json

    from bifilar.analysis import batch as bt
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    name, params = "thesis_plate_rest", {"spacing": 3.0}
    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = sw.resolve_settings(cfg)
    scenes: list = []
    real = bt.simulate_batch
    monkeypatch.setattr(bt, "simulate_batch", lambda sc, **kw: scenes.append(len(sc)) or real(sc, **kw))
    got = sw.evaluate_point(cfg, name, params, st)
    comps = [e for e in got["components"].values() if e.get("mode")]
    assert got["valid"] and len(comps) == 2
    assert all(e["sigma"] is None and e["amplitude_budget"]["note"] == "no sigma" for e in comps)
    assert sum(scenes) == len({e["mode"] for e in comps}) == 2  # the point's own runs only (was 6: 2 + 4 laws')
    many = pt.evaluate_points(cfg, name, [params], st)[0]
    monkeypatch.setattr(pt, "_budgeted", lambda chosen, budgets: dict(chosen))  # the path before: every law run
    scenes.clear()
    ref = sw.evaluate_point(cfg, name, params, st)
    assert sum(scenes) == 6
    ref_many = pt.evaluate_points(cfg, name, [params], st)[0]
    for a, b in ((got, ref), (many, ref_many)):
        assert json.dumps(a, sort_keys=True, default=str) == json.dumps(b, sort_keys=True, default=str)


# (session 16, perf18) the batched rest poses' Newton without a second final residual; the start poses' mean
# moments once a distinct scene


def _sigma_like(name, params, rel=1e-3):
    """A scene and its neighbours with each measured input moved +-``rel`` of its scale (a sigma-point batch)."""
    base = _scene(name, params)
    Lmax = float(np.max(base.lengths))
    out = [base]
    for n in measured_inputs(base):
        h = rel * (float(getattr(base, n)) if n in ("mass", "gravity") else Lmax)
        out += [perturb(base, n, h), perturb(base, n, -h)]
    return base, out


@pytest.mark.parametrize("case", ["Solar Boat", "trifilar"])
def test_newton_batch_takes_the_final_residual_only_where_a_scene_moved(case, monkeypatch):
    # Newton's kkt residual of a scene that converged is the one it was stopped on (the same expressions on
    # the same rows): the pass after the loop is taken only for scenes that moved after their last residual
    # (a batch cut short).  Main took it for every scene: one _constraints call more than the loop's
    # evaluations (the calls without a step are the last ones), ~0.1 ms of a sigma-point batch's ~1.8 ms.
    from bifilar.analysis import batch_rest as br
    from bifilar.analysis.equilibrium import start_coms

    _, scenes = _sigma_like(*SCENES[case])
    a, p, L, m, g, I = br._stack(scenes)
    B = len(scenes)

    def start():
        com = start_coms(a, p, L)
        R = np.broadcast_to(np.eye(3), (B, 3, 3)).copy()
        _, _, G0 = br._jacobian(a, p, com, R)
        gradV = np.zeros((B, 6))
        gradV[:, 2] = m * g
        return com, R, -np.einsum("bij,bj->bi", np.linalg.pinv(np.swapaxes(G0, 1, 2)), gradV)

    def full_residual(com, R, lam):  # main's pass after the loop, on every scene
        d, w, G, phi = br._constraints(a, p, L, com, R, slice(None))
        r1 = np.zeros((B, 6))
        r1[:, 2] = m * g
        r1 = r1 + np.einsum("bni,bn->bi", G, lam)
        return np.maximum(np.abs(r1).max(axis=1) / (m * g), np.abs(phi).max(axis=1) / L.max(axis=1) ** 2)

    start()  # (the compiled library's load check, once a process, runs the numpy pass itself: not counted)
    calls = {"constraints": 0, "hessian": 0}
    # the numpy pass's calls (native=False; the compiled pass of newton29, session 29, has the same rule:
    # its final pass runs only for the scenes still active, and its residuals are these bits, below)
    real_c, real_h = br._constraints, br._hessian_numpy

    def counted(key, fn):
        def wrapped(*args):
            calls[key] += 1
            return fn(*args)
        return wrapped

    monkeypatch.setattr(br, "_constraints", counted("constraints", real_c))
    monkeypatch.setattr(br, "_hessian_numpy", counted("hessian", real_h))
    com, R, lam, res = br._newton_batch(a, p, L, m, g, *start(), native=False)
    assert np.all(res < 1e-15)  # every scene converged
    # one residual a step and the one that found the batch converged; none after
    assert calls["constraints"] == calls["hessian"] + 1
    monkeypatch.setattr(br, "_constraints", real_c)
    assert np.array_equal(res, full_residual(com, R, lam))  # the same bits as main's pass
    # cut short (two steps): every scene moved after its last residual, which is taken again (some have
    # converged by then, some not)
    com2, R2, lam2, res2 = br._newton_batch(a, p, L, m, g, *start(), iters=2, native=False)
    assert np.any(res2 > 1e-15) and np.any(res2 < 1e-15)
    assert np.array_equal(res2, full_residual(com2, R2, lam2))
    # the default (the compiled pass where it is built): the same residuals, whole and cut short
    assert np.array_equal(br._newton_batch(a, p, L, m, g, *start())[3], res)
    assert np.array_equal(br._newton_batch(a, p, L, m, g, *start(), iters=2)[3], res2)


def test_start_poses_take_the_mean_moment_once_a_scene(monkeypatch):
    # a point's start poses (its 3 runs and its laws' 6: 4 distinct scenes) solved each scene's mean principal
    # moment once a row (9 eigvalsh on the Solar Boat); then once a distinct scene; since start27 (session 27)
    # the distinct scenes' in one stacked call, the same numbers (bit for bit: tests/test_start27.py)
    from bifilar.analysis import start_pose as sp

    base, scenes = _sigma_like("solar_boat", {"spacing": 3.0})
    rows = [base, base, base] + scenes[1:4] + [base, scenes[1]]
    rests = [rest_pose(s) for s in rows]
    n = {"eigvalsh": 0}
    real = np.linalg.eigvalsh

    def counted(x):
        n["eigvalsh"] += 1
        return real(x)

    monkeypatch.setattr(np.linalg, "eigvalsh", counted)
    rig = sp._Rig(rows, rests)
    monkeypatch.setattr(np.linalg, "eigvalsh", real)
    assert n["eigvalsh"] == 1  # one a row: 8; one a distinct scene: 4
    assert np.array_equal(rig.W[:, 3], np.array([real(s.inertia).mean() for s in rows]))


def test_thesis_forcing_jacobian_from_the_rest_forcing(monkeypatch):
    # the thesis rung's forcing Jacobian (ladder._thesis_forcing: complex step in the five angles, at rest
    # rates) took the whole of mass_matrix_and_forcing's _core on complex numbers per column; at zero rates
    # its N5 is the gravity term alone (kane.rest_forcing, the same expressions): the same numbers on random
    # angles about a rest pose, real and complex, and the same Jacobian with no full _core call (main: 5)
    from bifilar.analysis.equilibrium import rest_pose as rp
    from bifilar.estimation import ladder
    from bifilar.estimation.invert import HangingModel
    from bifilar.estimation.measurements import Hanging
    from bifilar.models import kane, kane_equations
    from bifilar.models.kane_mapping import kane_mapping

    scene = _scene("solar_boat", {"spacing": 3.0})
    rest = rp(scene)
    mp = kane_mapping(scene, rest)
    p, th0, z5 = mp.params, mp.theta0, np.zeros(5)
    rng = np.random.default_rng(5)
    for q in range(20):
        th = th0 + (0.05 * rng.normal(size=5) if q else 0.0)
        assert np.array_equal(kane.rest_forcing(th, p), kane.mass_matrix_and_forcing(th, z5, p)[1])
        for j in range(5):
            e = np.zeros(5, complex)
            e[j] = 1e-30j
            assert np.array_equal(kane.rest_forcing(th + e, p), kane.mass_matrix_and_forcing(th + e, z5 + 0j, p)[1])
    dN_ref = np.column_stack([kane.mass_matrix_and_forcing(th0 + 1e-30j * np.eye(5)[j], z5 + 0j, p)[1].imag / 1e-30
                              for j in range(5)])
    n = {"core": 0}
    real = kane_equations._core

    def counted(*a, **k):
        n["core"] += 1
        return real(*a, **k)

    monkeypatch.setattr(kane_equations, "_core", counted)
    hm = HangingModel(Hanging("h", scene, np.eye(3)), scene.inertia, rest=rest)
    M_a, N0, dN = ladder._thesis_forcing(hm)
    assert n["core"] == 1  # the real state's quantities (M5, N0) only
    assert np.array_equal(dN, dN_ref)


def test_honest_stds_build_the_rig_links_once(monkeypatch):
    # the honest pass's problems (one a component) share one set of hanging models, so one rig_links (the
    # configs' geometry, not the unknown): main built it again for each component (3 on the Solar Boat,
    # ~0.03 ms each); the stds are the same bits
    from bifilar.estimation import rig
    from bifilar.estimation.honest import honest_stds

    scene = _scene(*SCENES["Solar Boat"])
    unc = default_uncertainty()
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    req = [(c, best_mode_for(sens, c) + 1) for c in COMPS]
    n = {"links": 0}
    real = rig.rig_links

    def counted(*a, **k):
        n["links"] += 1
        return real(*a, **k)

    ref = honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens)
    ref_each = [honest_stds(scene, [r], unc, unc["timing"], rest=sens.rest, sens=sens)[0] for r in req]
    monkeypatch.setattr(rig, "rig_links", counted)
    got = honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens)
    assert n["links"] == 1  # main: 3
    assert got == ref == ref_each
