"""Work a sweep point no longer does (docs/performance.md, "Sweep points and
plan"), and that leaving it out changes no number:

* batched rest poses (:func:`bifilar.analysis.batch_rest.rest_poses`) compute
  the body's lowest point only when ``lowest_z`` / ``depth`` is read (the
  honest budget's sigma points never read it), and then the value
  :func:`bifilar.scene.lowest_point_z` and :func:`rest_pose` give;
* a point's start poses are solved once (its refusal check,
  :func:`bifilar.analysis.simulate.checked_start_poses`, hands them to
  ``simulate_batch(..., starts=)``), where they were solved three times (the
  check by ``initial_state``, ``feasible_amplitudes`` and ``initial_states``),
  with the same runs as without ``starts``.
"""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

import bifilar.analysis.batch_rest as br
import bifilar.analysis.start_pose as spm
from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.equilibrium import RestPose, rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import checked_start_poses, initial_state
from bifilar.config import read_yaml, scene_from_dict
from bifilar.errors import InputError
from bifilar.scene import lowest_point_z
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS


def _scene(name, params):
    cfg, _ = apply_params(read_yaml(CONFIGS / f"{name}.yaml"), params, name)
    return scene_from_dict(cfg, name, warn=False)


def _counting(monkeypatch, module, name):
    calls = []
    real = getattr(module, name)

    def counted(*a, **kw):
        calls.append(1)
        return real(*a, **kw)

    monkeypatch.setattr(module, name, counted)
    return calls


# the thesis plate hangs on a knife edge (a neutral pitch): the batch's warm start may leave it pitched, so
# its depth is compared with the eager expression at that pose only
@pytest.mark.parametrize("name, neutral", [("solar_boat", False), ("thesis_plate_rest", True), ("drone_parallel", False)])
def test_lazy_depth_equals_rest_pose_and_is_computed_only_when_read(name, neutral, monkeypatch):
    base = _scene(name, {})
    scenes = [_scene(name, {"length": L}) for L in (3.0, 4.0, 5.0)] if name != "drone_parallel" else [base]
    calls = _counting(monkeypatch, br, "lowest_point_z")
    rests = br.rest_poses(scenes)
    assert calls == []  # no scene's lowest point before it is read
    for s, r in zip(scenes, rests):
        ref = rest_pose(s) if not neutral else r
        assert r.depth == pytest.approx(ref.depth, rel=1e-12, abs=1e-12)
        assert r.lowest_z == pytest.approx(ref.lowest_z, rel=1e-12, abs=1e-12)
        # exactly the expression of the eager code it replaces
        lz = float(lowest_point_z(s, r.com, r.R))
        assert (r.lowest_z, r.depth) == (lz, s.ceiling_z - lz)
    assert len(calls) == len(scenes)  # once a scene, kept after the first read
    rests[0].depth
    assert len(calls) == len(scenes)


def test_lazy_rest_pose_pickles_copies_and_replaces_as_a_rest_pose():
    s = _scene("solar_boat", {})
    r = br.rest_poses([s, s])[1]
    for other in (pickle.loads(pickle.dumps(r)), copy.deepcopy(r), dataclasses.replace(r, kkt_residual=0.0)):
        assert isinstance(other, RestPose)
        assert other.depth == r.depth and other.lowest_z == r.lowest_z
        assert np.array_equal(other.com, r.com) and np.array_equal(other.R, r.R)
    assert type(pickle.loads(pickle.dumps(r))) is RestPose  # the scene (its support callable) is not pickled
    with pytest.raises(AttributeError):
        r.no_such_field


def test_a_point_solves_its_start_poses_once(monkeypatch):
    cfg = read_yaml(CONFIGS / "solar_boat.yaml")
    st = sw.resolve_settings(cfg)
    runs = []
    real = simulate_batch

    def batch(*a, **kw):
        runs.append(len(a[0]))
        return real(*a, **kw)

    import bifilar.analysis.batch as bt

    monkeypatch.setattr(bt, "simulate_batch", batch)
    solves = _counting(monkeypatch, spm, "solve_start_poses")
    p = sw.evaluate_point(cfg, "solar_boat", {"spacing": 3.0}, st)
    assert p["valid"] and runs and runs[0] >= 2  # a point with several runs ...
    # ... solves their start poses once (was 1 + 2 + one a run), those of its amplitude laws' runs (the stated
    # amplitude's slope and dr/dI: other amplitudes and other scenes, docs/design.md "The stated amplitude") in
    # the same call (was a second one); its own runs go in one call of the batched engine (one scene: shared
    # kernels and sample passes, with their health), all the laws' runs (without health: the 0.9 amplitude ones
    # and the stepped scenes', crossings in one pass) in a second (session 9; the 0.9 ones were in the first)
    n_comps = sum(e.get("mode") is not None for e in p["components"].values())
    n_modes = len({e["mode"] for e in p["components"].values() if e.get("mode") is not None})
    assert len(solves) == 1 and runs == [n_modes, n_modes + n_comps]


@pytest.mark.parametrize("name, amplitude", [("solar_boat", 0.05), ("thesis_plate_rest", 0.6)])
def test_runs_from_checked_starts_equal_runs_solving_their_own(name, amplitude):
    s = _scene(name, {"spacing": 3.0})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    modes = [m for m in ms.modes if m.period][:3]
    sp = checked_start_poses(s, rest, modes, amplitude)
    for j, m in enumerate(modes):  # the one-scene check's states, to the solver's convergence
        assert np.allclose(sp.states()[j], initial_state(s, rest, m, amplitude), rtol=0, atol=1e-12)
    kw = dict(mode=[m.label for m in modes], amplitude=amplitude, periods=1.0, rtol=1e-8, rests=[rest] * len(modes),
              modes=[ms] * len(modes))
    own = simulate_batch([s] * len(modes), **kw)
    given = simulate_batch([s] * len(modes), starts=sp, **kw)
    for a, b in zip(own, given):  # the same start states, so the same runs bit for bit
        assert (a.period, a.depth_max) == (b.period, b.depth_max)
        assert np.array_equal(a.tension_max, b.tension_max) and np.array_equal(a.crossings, b.crossings)


def test_checked_start_poses_refuses_as_initial_state_in_turn():
    s = _scene("thesis_plate_rest", {"spacing": 3.0})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    swing = next(m for m in ms.modes if m.dominant < 3)
    twist = next(m for m in ms.modes if m.dominant >= 3)
    for modes, amp in [([twist, swing], 1.2), ([swing, twist], 1.2), ([twist, swing], 4.0), ([swing], np.nan)]:
        first = None
        for m in modes:  # initial_state one mode at a time: the first refusal
            try:
                initial_state(s, rest, m, amp)
            except InputError as exc:
                first = str(exc)
                break
        if first is None:
            checked_start_poses(s, rest, modes, amp)
            continue
        with pytest.raises(InputError) as exc:
            checked_start_poses(s, rest, modes, amp)
        assert str(exc.value) == first


def test_quat_to_matrix_filled_entry_by_entry_is_the_rotation():
    from scipy.linalg import expm

    from bifilar.rotations import quat_to_matrix, rotvec_to_quat, skew

    v = np.random.default_rng(3).normal(size=(2, 5, 3))
    R = quat_to_matrix(2.5 * rotvec_to_quat(v))  # any scale of q
    assert R.shape == (2, 5, 3, 3)
    for i in range(2):
        for j in range(5):
            assert np.allclose(R[i, j], expm(skew(v[i, j])), rtol=0, atol=1e-13)
    assert np.allclose(quat_to_matrix(np.array([1.0, 0, 0, 0])), np.eye(3), rtol=0, atol=0)


def test_evaluate_points_hands_each_points_starts_to_the_batch(monkeypatch):
    """A planner's screens (``evaluate_points``): each point's start poses are
    solved once, by its check, and the batch of all points' runs uses them;
    the figures are those of the batch solving its own starts."""
    import json

    from bifilar.studies import point as pt
    from bifilar.studies.shorthands import parse_param

    cfg = read_yaml(CONFIGS / "thesis_plate_rest.yaml")
    st = sw.resolve_settings(cfg)
    grid = sw.build_grid([parse_param(p) for p in ["spacing=2:4:3", "amplitude=0.05,1.2"]])
    solves = _counting(monkeypatch, spm, "solve_start_poses")
    got = pt.evaluate_points(cfg, "thesis_plate_rest", grid, st, screen=True)
    assert sum(p["valid"] for p in got) >= 4 and not all(p["valid"] for p in got)  # refusals among them
    # one a point (its check, its amplitude laws' runs' start poses in the same call), none in the batch, a refused
    # point's not repeated
    assert len(solves) == len(grid)
    for p, params in zip(got, grid):
        if not p["valid"]:  # the error a point alone gives
            assert p == sw.evaluate_point(cfg, "thesis_plate_rest", params, st, screen=True)
    monkeypatch.setattr(spm.StartPoses, "concat", staticmethod(lambda parts: None))  # the batch solves its own
    ref = pt.evaluate_points(cfg, "thesis_plate_rest", grid, st, screen=True)
    assert json.dumps(got, sort_keys=True, default=str) == json.dumps(ref, sort_keys=True, default=str)


def _figures(r):
    """Every figure of a run, as bits."""
    return (r.period, r.period_std, r.crossings.tobytes(), r.tension_min.tobytes(), r.tension_max.tobytes(),
            r.slack, r.depth_max, r.lowest_z_min, r.max_constraint_violation, r.energy_drift, r.nfev, r.warnings,
            r.t_final, r.y_final.tobytes())


@pytest.mark.parametrize("name", ["solar_boat", "trifilar_kth"])
def test_runs_of_one_scene_build_its_parameters_and_kernels_once(name, monkeypatch):
    """A point's runs (one scene, one rest pose, its modes) share the scene's
    parameters and so the compiled kernels cached on them: built once for
    all runs (were built for each run, twice: the right-hand side's and
    the health's); every figure the same as a run building its own
    (``run_one``), bit for bit."""
    import bifilar.models.maximal as mx
    from bifilar.analysis.batch import run_one

    s = _scene(name, {})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    modes = [m for m in ms.modes if m.period][:3]
    builds = _counting(monkeypatch, mx, "_param_values")
    runs = simulate_batch([s] * 3, mode=[m.label for m in modes], amplitude=0.05, periods=3.0, rtol=1e-8,
                          rests=[rest] * 3, modes=[ms] * 3)
    # the right-hand side's kernel and the health's (extras), once for the 3 runs; their parameter values
    # once for both (session 7: compiled_kernel keeps them on the parameters; was once per kernel)
    assert len(builds) == 1
    for m, r in zip(modes, runs):
        own = run_one(s, rest, m, 0.05, 3.0, rtol=1e-8)
        assert _figures(r) == _figures(own)
        assert r.period is not None and abs(r.period / m.period - 1) < 1e-2


def test_stage_sums_of_all_rows_at_once_equal_row_by_row():
    """``integrators._combine`` of a coefficient matrix (the crossings'
    interpolation, the dense output) takes all rows at once: each entry the
    1-D sum's bits (term by term in stage order), and the product."""
    from bifilar.integrators import _combine

    rng = np.random.default_rng(7)
    for r, s_, N in [(8, 8, 3), (4, 16, 26), (1, 5, 1)]:
        c = rng.normal(size=(r, s_))
        Kf = rng.normal(size=(s_, N)) * 10.0 ** rng.integers(-8, 8, size=(s_, N))
        got = _combine(c, Kf)
        assert got.shape == (r, N)
        assert np.array_equal(got, np.stack([_combine(row, Kf) for row in c]))
        assert np.allclose(got, c @ Kf, rtol=1e-12, atol=1e-12 * np.abs(c) @ np.abs(Kf))


def test_few_crossing_roots_on_floats_equal_the_vectorised_iteration():
    """Up to ``SCALAR_ROOTS`` roots ``poly_root_unit`` iterates on Python
    floats: the same bits as the vectorised iteration (the same roots among
    many), each a root of its polynomial inside [0, 1]; edge cases
    included (a root at 0 or 1, a flat derivative, an exact zero)."""
    from bifilar import integrators as itg

    rng = np.random.default_rng(11)
    cols = []
    while len(cols) < 40:
        p = rng.normal(size=8) * 10.0 ** rng.integers(-3, 3, size=8)
        v0, v1 = p[0], p.sum()
        if v0 < 0 <= v1:
            cols.append(p)
    cols += [np.array([-1.0, 0, 0, 3.0, 0, 0, 0, 0]),  # p'(0) = 0: Newton's first step has no slope
             np.array([-1e-300, 1.0, 0, 0, 0, 0, 0, 0]),  # root at ~0
             np.array([-1.0, 1.0, 0, 0, 0, 0, 0, 0]),  # p(1) = 0: root at 1
             np.array([-0.5, 1.0, 0, 0, 0, 0, 0, 0])]  # p(0.5) = 0 exactly, the secant's first guess
    P = np.array(cols).T
    v0 = P[0].copy()
    v1 = np.array([np.polynomial.polynomial.polyval(1.0, P[:, j]) for j in range(P.shape[1])])
    assert P.shape[1] > itg.SCALAR_ROOTS
    many = itg.poly_root_unit(P, v0, v1)  # the vectorised iteration
    for j0 in range(0, P.shape[1], 3):
        sl = slice(j0, j0 + 3)
        few = itg.poly_root_unit(P[:, sl], v0[sl], v1[sl])
        assert np.array_equal(few, many[sl])
    assert np.all((many >= 0) & (many <= 1))
    for j, x in enumerate(many):
        p = np.polynomial.Polynomial(P[:, j])
        scale = np.polynomial.Polynomial(np.abs(P[:, j]))(1.0)
        assert abs(p(x)) <= 1e-12 * scale
    assert many[-1] == 0.5 and many[-2] == 1.0


@pytest.mark.parametrize("name", ["solar_boat", "thesis_plate_rest", "drone_parallel"])
def test_runs_of_a_group_fold_their_lowest_points_once(name, monkeypatch):
    """The runs of a small group (a point's modes; other scenes beside them)
    put their states into one shared running minimum, folded once at the
    end (were folded run by run: a support-function call each); each run's
    lowest point and depth those of the run alone, bit for bit."""
    import bifilar.analysis.batch_health as bh
    from bifilar.analysis.batch import run_one

    s, other = _scene(name, {}), _scene(name, {"length": 4.0})
    rests = [rest_pose(s), rest_pose(other)]
    mss = [linear_modes(x, r) for x, r in zip((s, other), rests)]
    modes = [m for m in mss[0].modes if m.period][:2]
    folds = []
    real = bh.LowestPoint.fold

    def fold(self):
        if self._buf:
            folds.append(len(self.scenes))
        return real(self)

    monkeypatch.setattr(bh.LowestPoint, "fold", fold)
    labels = [modes[0].label, modes[1].label, mss[1].modes[0].label]
    runs = simulate_batch([s, s, other], mode=labels, amplitude=0.05, periods=2.0, rtol=1e-8,
                          rests=[rests[0], rests[0], rests[1]], modes=[mss[0], mss[0], mss[1]])
    assert folds == [3]  # one fold of the three runs' states
    monkeypatch.setattr(bh.LowestPoint, "fold", real)
    for r, x, rest, m in zip(runs, (s, s, other), (rests[0], rests[0], rests[1]),
                             (modes[0], modes[1], mss[1].modes[0])):
        own = run_one(x, rest, m, 0.05, 2.0, rtol=1e-8)
        assert _figures(r) == _figures(own)
        assert np.isfinite(r.depth_max) and r.depth_max >= rest.depth - 1e-9 * x.lengths.max()


@pytest.mark.parametrize("name", ["solar_boat", "trifilar_kth"])
def test_start_pose_hessian_in_one_evaluation_equals_one_displacement_at_a_time(name, monkeypatch):
    """The closest-pose Newton step's constraint Hessian
    (``start_pose._mu_hessian``) evaluates the 12 displaced poses of its
    central differences at once: bit for bit the Hessian of one
    displacement at a time (the loop it replaces), and the second
    derivative it stands for (differences of a 100x larger step agree)."""
    s = _scene(name, {"spacing": 3.0} if name == "solar_boat" else {})
    rest = rest_pose(s)
    rig = spm._Rig([s, s, s], [rest] * 3)
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.normal(scale=0.02 * rig.Lmax[0], size=(3, 3)), rng.normal(scale=0.1, size=(3, 3))], 1)
    mu = rng.normal(size=(3, s.n_wires))
    scale = spm._scale(rig)
    got = spm._mu_hessian(rig, x, mu, scale)

    def one_at_a_time(step):
        H = np.zeros((3, 6, 6))
        for j in range(6):
            h = step * scale[:, j]
            e = np.zeros((3, 6))
            e[:, j] = h
            dp, wp, _ = rig.wires(x + e)
            dm, wm, _ = rig.wires(x - e)
            dG = (rig.jacobian(x + e, dp, wp) - rig.jacobian(x - e, dm, wm)) / (2.0 * h[:, None, None])
            H[:, :, j] = np.einsum("bn,bni->bi", mu, dG)
        return H

    assert np.array_equal(got, one_at_a_time(1e-6))
    # in blocks (what bounds a large batch's memory): the same bits
    monkeypatch.setattr(spm, "HESSIAN_BLOCK", 2)
    assert np.array_equal(spm._mu_hessian(rig, x, mu, scale), got)
    coarse = one_at_a_time(1e-4)
    assert np.allclose(got, coarse, rtol=0, atol=1e-5 * np.abs(coarse).max())
    assert np.allclose(got, np.swapaxes(got, 1, 2), rtol=0, atol=1e-5 * np.abs(got).max())  # a Hessian


def _health_window(monkeypatch, name):
    """The arguments of one LSODA window's ``sample_health`` call in a point-like run."""
    import bifilar.analysis.batch_lsoda as bl

    cap = []
    real = bl.sample_health
    monkeypatch.setattr(bl, "sample_health", lambda *a, **k: (cap.append(a), real(*a, **k))[1])
    s = _scene(name, {})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    simulate_batch(s, mode=next(m for m in ms.modes if m.period).label, amplitude=0.05, periods=3.0, rtol=1e-8,
                   rests=[rest], modes=[ms])
    monkeypatch.setattr(bl, "sample_health", real)
    return s, cap[-1]


@pytest.mark.parametrize("name", ["solar_boat", "trifilar_kth"])
def test_sample_health_ignores_masked_samples_and_reads_the_tensions(name, monkeypatch):
    """``sample_health`` (NaN-ignoring fmin / fmax reductions, masks only
    where a run stopped): a window whose run stopped after k samples gives
    the figures of the first k samples alone, bit for bit; and its
    tension extremes are those of the model's tensions at the samples."""
    import copy

    import bifilar.analysis.batch_health as bh
    import bifilar.models.maximal as mx

    s, (Ys, tt, obs, kx, n, com0, T_ref, stop_tau, on_slack, first) = _health_window(monkeypatch, name)

    def health(Y, t, stop):
        o = copy.copy(obs)
        o.lowest = None
        for f in ("Tmin", "Tmax", "viol", "dE", "slack_t"):
            setattr(o, f, np.full_like(getattr(obs, f), np.inf if f == "Tmin" else -np.inf if f == "Tmax" else
                                       np.nan if f == "slack_t" else 0.0))
        bh.sample_health(Y, t, o, kx, n, com0, T_ref, np.array([stop], float), on_slack, first)
        return tuple(getattr(o, f).tobytes() for f in ("Tmin", "Tmax", "viol", "dE", "E0"))

    k = len(tt) // 5  # 0.6 of a period: not every extreme reached
    assert health(Ys, tt, tt[k - 1]) == health(Ys[:k], tt[:k], tt[-1])  # masked = left out
    assert health(Ys, tt, tt[k - 1]) != health(Ys, tt, tt[-1])  # and the rest of the window counts
    P = mx.params_from_scenes(s)
    y = Ys[:, 0, :].copy()
    y[:, :3] += com0[0]
    T = mx.tensions(y, P)  # (k, n), an independent evaluation
    o = copy.copy(obs)
    assert np.allclose(o.Tmax, T.max(axis=0), rtol=1e-6) and np.allclose(o.Tmin, T.min(axis=0), rtol=1e-6)
    assert np.all(o.Tmax >= T.max(axis=0) * (1 - 1e-9)) and np.all(o.Tmin <= T.min(axis=0) * (1 + 1e-9))


@pytest.mark.parametrize("name", ["solar_boat", "thesis_plate_rest", "trifilar_kth"])
def test_runs_of_one_scene_take_their_samples_through_crossings_and_health_together(name, monkeypatch):
    """A point's LSODA runs (one scene, one rest pose, one length) are each
    integrated as alone and their samples go through the crossings and the
    health in one pass (``batch_lsoda._lsoda_joint``): every figure the run
    alone gives, bit for bit; runs of different lengths (or that fail) are
    taken one by one, with the same figures."""
    import bifilar.analysis.batch_lsoda as bl
    from bifilar.analysis.batch import run_one

    s = _scene(name, {"spacing": 3.0} if name != "trifilar_kth" else {})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    modes = [m for m in ms.modes if m.period][:3]
    for periods in ([3.0, 3.0, 3.0], [3.0, 2.0, 3.0]):
        passes = _counting(monkeypatch, bl, "sample_health")
        runs = simulate_batch([s] * 3, mode=[m.label for m in modes], amplitude=0.05, periods=periods, rtol=1e-8,
                              rests=[rest] * 3, modes=[ms] * 3)
        assert len(passes) == (1 if periods[0] == periods[1] else 3)
        for m, p, r in zip(modes, periods, runs):
            assert _figures(r) == _figures(run_one(s, rest, m, 0.05, p, rtol=1e-8))
        monkeypatch.undo()


@pytest.mark.parametrize("name", ["solar_boat", "thesis_plate_rest", "trifilar_kth"])
def test_runs_of_several_scenes_without_health_take_their_crossings_together(name, monkeypatch):
    """Runs of several scenes of one wire count whose periods only are read
    (``health=False``: a point's amplitude laws' stepped scenes, the inertia
    changed) are each integrated as alone with their own scene's kernel and
    their crossings taken in one pass (``batch_lsoda._lsoda_joint`` with one
    float parameter set a run; was one pass a scene): every figure of each
    run alone (``run_one``), bit for bit; with health, or runs of different
    lengths, they are taken scene by scene, with the same figures."""
    import bifilar.analysis.batch_lsoda as bl
    from bifilar.analysis.batch import run_one

    s = _scene(name, {"spacing": 3.0} if name != "trifilar_kth" else {})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    modes = [m for m in ms.modes if m.period][:3]
    Imax = float(np.max(np.linalg.eigvalsh(s.inertia)))
    scenes, mss = [], []
    for i, j in [(0, 0), (2, 2), (0, 1)]:  # moments and a product stepped, as the law steps them
        inertia = np.array(s.inertia, float)
        inertia[i, j] += 1e-3 * Imax
        inertia[j, i] = inertia[i, j]
        sc = dataclasses.replace(s, inertia=inertia)
        scenes.append(sc)
        mss.append(linear_modes(sc, rest))
    labels = [m.label for m in modes] + [modes[0].label] * (3 - len(modes))
    for health, periods in ((False, [3.0] * 3), (False, [3.0, 2.0, 3.0]), (True, [3.0] * 3)):
        windows = _counting(monkeypatch, bl, "_window")
        runs = simulate_batch(scenes, mode=labels, amplitude=0.05, periods=periods, rtol=1e-8, rests=[rest] * 3,
                              modes=mss, health=health)
        assert len(windows) == (1 if not health and periods[0] == periods[1] else 3)
        for sc, m, lab, p, r in zip(scenes, mss, labels, periods, runs):
            alone = run_one(sc, rest, m.get(lab), 0.05, p, rtol=1e-8, health=health)
            assert repr(_figures(r)) == repr(_figures(alone))  # (repr: exact floats, and NaN health figures equal)
            assert r.period is not None and abs(r.period / m.get(lab).period - 1) < 1e-2
        monkeypatch.undo()


@pytest.mark.parametrize("on_slack", ["continue", "stop"])
def test_joint_runs_with_a_slack_wire_equal_the_runs_alone(on_slack, monkeypatch):
    """Runs taken through the health together where a wire goes slack (the
    trifilar of tests/test_batch.py, wire 1 unloaded by a 0.6 m swing):
    slack times, a run stopped there (``on_slack="stop"``) and the figures
    of each run alone, bit for bit."""
    import bifilar.analysis.batch_lsoda as bl
    from bifilar.analysis.batch import run_one

    ang = np.radians([0, 120, 240])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    s = scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                         "rig": {"anchors": pts.tolist(), "attachments": (pts + [0.23, 0, 0.1]).tolist(),
                                 "lengths": [2.0] * 3}})
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    passes = _counting(monkeypatch, bl, "sample_health")
    runs = simulate_batch([s, s], mode=["swing-x", "swing-y"], amplitude=0.6, periods=3.0, rtol=1e-9,
                          rests=[rest] * 2, modes=[ms] * 2, on_slack=on_slack)
    assert len(passes) == 1 and runs[0].slack
    if on_slack == "stop":
        assert runs[0].t_final < 3 * runs[0].linear_period
    for lab, r in zip(["swing-x", "swing-y"], runs):
        assert _figures(r) == _figures(run_one(s, rest, ms.get(lab), 0.6, 3.0, rtol=1e-9, on_slack=on_slack))


def test_start_pose_jacobian_cross_product_is_numpys():
    """The start pose's constraint Jacobian takes w x d by the explicit
    components (``batch_rest._cross``) in place of ``np.cross``: the same
    products and differences, so the same bits, on any magnitudes and
    leading axes."""
    from bifilar.analysis.batch_rest import _cross

    rng = np.random.default_rng(13)
    for shape in [(3,), (3, 2, 3), (36, 4, 3)]:
        u = rng.normal(size=shape) * 10.0 ** rng.integers(-6, 6, size=shape)
        v = rng.normal(size=shape) * 10.0 ** rng.integers(-6, 6, size=shape)
        assert np.array_equal(_cross(u, v), np.cross(u, v))
