"""The shortcuts that make a sweep point cheaper (issue 14, docs/performance.md
"Sweep points and plan") give what the paths they replace give:

* :func:`bifilar.analysis.modes.modes_of_inertia` (the reduced stiffness
  once, only the eigenproblem per inertia) against :func:`linear_modes` of
  the scene with that inertia, and against scipy's generalized eigensolver;
* :func:`bifilar.studies.point.linear_estimate` sharing one stiffness over a
  point's components (``at``) against its own Newton + stiffness, and its
  root against the linear period it must reproduce;
* :func:`bifilar.estimation.honest.honest_stds` fed the point's analytic
  sensitivity (``sens``) against the budget's own Jacobian.
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


@pytest.mark.parametrize("case", ["Solar Boat", "pitch rig"])
def test_honest_stds_with_the_points_sensitivity(case, monkeypatch):
    from bifilar.estimation import budget
    from bifilar.estimation.honest import honest_stds

    scene = _scene(*SCENES[case])
    unc = default_uncertainty()
    sens = period_sensitivity(scene, COMPS + measured_inputs(scene))
    assert sens.method == "analytic"
    req = [(c, best_mode_for(sens, c) + 1) for c in COMPS]
    ref = honest_stds(scene, req, unc, unc["timing"], rest=sens.rest)  # no fallback: the budget's own std

    def no_call(*a, **k):
        raise AssertionError("the budget recomputed the sensitivity it was given")

    monkeypatch.setattr(budget, "robust_sensitivity", no_call)
    got = honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens)
    # analytic both ways (the same derivative, columns picked by name): equal to rounding
    assert got == pytest.approx(ref, rel=1e-12)


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


def test_sigma_points_settled_in_one_step_all_at_once(monkeypatch):
    # budget._one_step takes the first Gauss-Newton step of every sigma point (and pair corner) at once;
    # against _resolve point by point (the path before): the same re-solved unknowns, bit for bit, over
    # the honest cases (second order and pair terms: the wheel, the drone) and an inversion of three
    # modes for three components (K = P = 3, the example measurements file)
    from bifilar.estimation import budget, honest
    from bifilar.estimation.invert import invert
    from bifilar.estimation.measurements import load_measurements

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
        out = []
        for case, (cfg, comps) in _honest_cases().items():
            scene = scene_from_dict(cfg, case, warn=False)
            unc = default_uncertainty()
            sens = period_sensitivity(scene, list(dict.fromkeys(COMPS + comps)) + measured_inputs(scene))
            req = [(c, best_mode_for(sens, c) + 1) for c in comps
                   if np.nanmax(np.abs(sens.column(c)) * component_scale(scene.inertia, c) / sens.periods) >= 1e-6]
            out.append(honest.honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens))
        res = invert(load_measurements(CONFIGS / "measurements_example.yaml"), ladder=False)
        out.append((res.values.tolist(), res.std.tolist()))
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


def _mode_set_fields(ms):
    return ([(m.label, m.period, m.omega2, m.shape.tobytes(), m.energy_share.tobytes(), m.dominant) for m in ms.modes],
            np.asarray(ms.mass_matrix).tobytes(), np.asarray(ms.basis).tobytes(), ms.basis.strides)


def test_batched_mode_sets_equal_mode_set_scene_by_scene(monkeypatch):
    # modes_batch labels its scenes with mode_sets (the elementwise arithmetic on the whole batch); against
    # mode_set scene by scene (the path before): the same mode sets bit for bit, over batches of sigma-point
    # scenes of the Solar Boat, the drone, the trifilar (degenerate swings: mode_set itself) and the
    # knife-edge plate (a neutral mode)
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
    n_modes = neutral = 0
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
    assert n_modes > 200 and neutral > 0
    assert 0 < len(alone) < n_modes / 8  # the trifilar's degenerate swings went through mode_set, few else


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
