"""The batched engine (bifilar.analysis.batch) and the project's integrator
(bifilar.integrators): each batched result against the single-scene function
(a different code path), an independent integrator (scipy) or an exact
solution."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bifilar import integrators as itg
from bifilar.analysis import batch as bt
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import initial_state, simulate
from bifilar.config import scene_from_dict
from bifilar.errors import InputError, SlackWireError
from bifilar.models import maximal as mx
from bifilar.models import reduced

from conftest import trapezoid

G = 9.81


def _trifilar(R=0.5, L=(2.0, 2.0, 2.0), m=3.0, I=(0.3, 0.3, 0.4), dz=0.0):
    ang = np.radians([90, 210, 330])
    pts = np.c_[R * np.cos(ang), R * np.sin(ang), np.zeros(3)]
    att = pts + [0, 0, dz]
    return scene_from_dict({"body": {"mass": m, "inertia": {"principal": list(I)}},
                            "rig": {"anchors": pts.tolist(), "attachments": att.tolist(), "lengths": list(L)}})


@pytest.fixture(scope="module")
def sweep():
    """A mixed sweep: unequal wires, CoM offsets, masses, spreads."""
    rng = np.random.default_rng(3)
    out = []
    for k in range(30):
        out.append(trapezoid(b=10 + rng.uniform(-1, 1), bp=5 + rng.uniform(-1, 1), l1=5 + rng.uniform(-0.3, 0.3),
                             l2=5 + rng.uniform(-0.3, 0.3), h=rng.uniform(0.1, 0.8), mass=100 * rng.uniform(0.5, 2)))
    return out


# --------------------------------------------------------------------------
# rest poses and modes
# --------------------------------------------------------------------------
def test_rest_poses_match_single_scene_solver(sweep):
    rests = bt.rest_poses(sweep)
    for s, r in zip(sweep, rests):
        ref = rest_pose(s)  # global search + Newton, one scene at a time
        # both polish the same KKT equations to ~1e-15: 1e-11 m / 1e-9 N leave room for the
        # conditioning of the pose (lever arms ~5 m)
        np.testing.assert_allclose(r.com, ref.com, atol=1e-11)
        np.testing.assert_allclose(r.R, ref.R, atol=1e-11)
        np.testing.assert_allclose(r.tensions, ref.tensions, rtol=1e-10)
        assert r.kkt_residual < 1e-12
        assert r.depth == pytest.approx(ref.depth, abs=1e-11)


def test_rest_tension_of_thesis_plate_in_a_batch():
    # thesis Fig 7.2.1: m g / (2 cos 30 deg) = 566.38 N per wire, independently of the batch neighbours
    scenes = [trapezoid(l1=5.0 + 0.1 * k) for k in range(-3, 4)]
    rests = bt.rest_poses(scenes, guess=rest_pose(scenes[0]))
    np.testing.assert_allclose(rests[3].tensions, 100 * G / (2 * np.cos(np.pi / 6)), rtol=1e-12)


def test_slack_scene_in_a_batch_is_named_or_returned():
    pts = np.array([[1, 1, 0], [-1, 1, 0], [-1, -1, 0], [1, -1, 0]], float)
    att = pts - [0.1, 0.1, 0]

    def table(l3):
        return scene_from_dict({"body": {"mass": 1.0, "inertia": {"principal": [0.25, 0.25, 0.5]}},
                                "rig": {"anchors": pts.tolist(), "attachments": att.tolist(),
                                        "lengths": [1.0, 1.0, l3, 1.0]}})

    scenes = [table(1.0), table(1.05), table(1.0)]
    out = bt.rest_poses(scenes, errors="return")
    assert isinstance(out[1], SlackWireError) and out[1].wires == [3]
    assert not isinstance(out[0], Exception) and not isinstance(out[2], Exception)
    with pytest.raises(SlackWireError):
        bt.rest_poses(scenes)


def test_modes_match_single_scene_function(sweep):
    scenes = sweep + [_trifilar(), _trifilar(L=(2.0, 2.0, 2.05), dz=0.1)]
    rests, mss = bt.rest_and_modes(scenes)
    for s, r, ms in zip(scenes, rests, mss):
        ref = linear_modes(s, rest_pose(s))
        assert ms.labels == ref.labels
        for a, b in zip(ms.modes, ref.modes):
            # same symmetric generalised eigenproblem, different factorisation: ~1e-13 in omega^2
            if b.period is None:
                assert a.period is None
                continue
            assert a.period == pytest.approx(b.period, rel=1e-10)
            np.testing.assert_allclose(a.shape, b.shape, atol=1e-8)
            assert a.dominant == b.dominant


def test_degenerate_modes_get_clean_labels_in_a_batch():
    # symmetric trifilar: swing-x and swing-y are exactly degenerate; the batched path must
    # align them with the axes as linear_modes does
    s = _trifilar(dz=0.2)
    ms = bt.modes_batch([s, s], bt.rest_poses([s, s]))[1]
    ref = linear_modes(s, rest_pose(s))
    assert ms.labels == ref.labels
    assert {"swing-x", "swing-y", "torsion"} <= set(ms.labels)


def test_trifilar_torsion_formula_in_a_batch():
    # trifilar with vertical wires: T = 2 pi sqrt(I L / (m g R^2)) exactly for the linear mode
    scenes = [_trifilar(R=R) for R in (0.3, 0.5, 0.7)]
    _, mss = bt.rest_and_modes(scenes)
    for R, ms in zip((0.3, 0.5, 0.7), mss):
        assert ms.get("torsion").period == pytest.approx(2 * np.pi * np.sqrt(0.4 * 2.0 / (3.0 * G * R**2)), rel=1e-12)


def test_initial_states_match_simulate(sweep):
    rests, mss = bt.rest_and_modes(sweep[:8])
    mds = [ms.get("torsion") for ms in mss]
    Y = bt.initial_states(sweep[:8], rests, mds, 0.1)
    for s, r, md, y in zip(sweep, rests, mds, Y):
        np.testing.assert_allclose(y, initial_state(s, r, md, 0.1), atol=1e-13)


# --------------------------------------------------------------------------
# nonlinear runs
# --------------------------------------------------------------------------
def test_single_scene_agrees_with_simulate_for_every_mode():
    s = trapezoid(l1=5.0, l2=4.8, h=0.5)  # coupled: no symmetry to hide behind
    rest = rest_pose(s)
    ms = linear_modes(s, rest)
    for md in ms.modes:
        a = simulate(s, md.label, 0.05, 4, rest=rest, modes=ms, rtol=1e-12)
        for method in ("lsoda", "dop853"):
            b = bt.run_one(s, rest, md, 0.05, 4, 1e-12, method=method)
            # three integrators at rtol 1e-12 give the period to ~1e-12 (work-precision table)
            assert b.period == pytest.approx(a.period, rel=2e-11)
            assert len(b.crossings) == len(a.crossings)
            assert b.max_constraint_violation < 1e-10
            assert b.energy_drift < 1e-8
            # tensions: sampled at different instants; the extremes agree to the sampling
            # resolution of a 2-omega oscillation at >= 20 samples per period (~2 % of its swing)
            swing = a.tension_max - a.tension_min
            np.testing.assert_allclose(b.tension_min, a.tension_min, atol=0.03 * swing.max() + 1e-9)
            np.testing.assert_allclose(b.tension_max, a.tension_max, atol=0.03 * swing.max() + 1e-9)
            # lowest point: the body's height varies by ~A^2 L / 2 ~ 3e-4 m; sampled at >= 20 instants per
            # period instead of 64, its extreme is resolved to ~1-2 % of that
            assert b.depth_max == pytest.approx(a.depth_max, abs=1e-5)


@pytest.mark.parametrize("method", ["dop853", "lsoda"])
def test_symmetric_torsion_period_is_the_exact_one_dof_period(method):
    # reduced.torsion_period is an exact energy-integral period for the symmetric trapezoid,
    # independent of the integrators; a batch above SMALL_BATCH runs the vectorised engines
    hs = np.linspace(0.1, 0.8, bt.SMALL_BATCH)
    scenes = [trapezoid(h=h, bp=4.0 + 2 * h) for h in hs]
    runs = bt.simulate_batch(scenes, "torsion", 0.2, 5, rtol=1e-11, method=method)
    for s, h, r in zip(scenes, hs, runs):
        tp = reduced.TorsionParams(m=100.0, Izz=s.inertia[2, 2], l=5.0, b=10.0, bp=4.0 + 2 * h)
        # rtol 1e-11: period error ~1e-11 in the work-precision table; 1e-9 is a safe bound
        assert r.period == pytest.approx(reduced.torsion_period(tp, 0.2), rel=1e-9)
        assert r.max_constraint_violation < 1e-9 and r.energy_drift < 1e-7


def test_scene_accuracy_does_not_depend_on_its_batch_neighbours():
    # per-scene step control: a scene with 50x shorter wires (7x faster oscillation) and a
    # slack-prone large-amplitude neighbour must not change another scene's result beyond rtol
    base = trapezoid(l1=5.0, l2=4.9, h=0.5)
    others = [trapezoid(b=0.2, bp=0.1, l1=0.1, l2=0.1, h=0.01, mass=1.0, inertia=[0.01, 0.002, 0.011])] * 12 \
        + [trapezoid(l1=5.0, l2=5.2, h=0.3)] * 12
    alone = bt.simulate_batch([base], "torsion", 0.1, 5, rtol=1e-11, method="dop853")[0]
    mixed = bt.simulate_batch([base] + others, "torsion", 0.1, 5, rtol=1e-11, method="dop853")
    # same integrator, same tolerance, its own steps: identical to the step sequence (rounding)
    assert mixed[0].period == pytest.approx(alone.period, rel=1e-12)
    assert mixed[1].period == pytest.approx(bt.simulate_batch([others[0]], "torsion", 0.1, 5, rtol=1e-11,
                                                              method="dop853")[0].period, rel=1e-12)


def test_mixed_wire_counts_and_per_scene_modes_keep_order():
    scenes = [trapezoid(h=0.5), _trifilar(dz=0.1), trapezoid(l1=4.0, h=0.5)]
    runs = bt.simulate_batch(scenes, ["torsion", "torsion", "swing-x"], [0.05, 0.05, 0.02], 3, rtol=1e-10)
    assert [r.mode for r in runs] == ["torsion", "torsion", "swing-x"]
    for s, r in zip(scenes, runs):
        lin = linear_modes(s, rest_pose(s)).get(r.mode).period
        assert r.linear_period == pytest.approx(lin, rel=1e-12)
        assert r.period == pytest.approx(lin, rel=2e-3)  # amplitude shift ~ A^2 / 16 < 1e-3


def test_bad_inputs():
    s = trapezoid(h=0.5)
    with pytest.raises(InputError):
        bt.simulate_batch([s], "nonsense", 0.05, 2)
    out = bt.simulate_batch([s, s], ["torsion", "nonsense"], 0.05, 2, errors="return")
    assert out[0].error is None and out[1].error and np.isnan(out[1].energy_drift)
    with pytest.raises(InputError):
        bt.simulate_batch([s], "torsion", 0.05, -1)
    with pytest.raises(InputError):
        bt.simulate_batch([s], "torsion", 0.05, 2, method="euler")
    # thin plate: rotation about the attachment line has no stiffness
    thin = trapezoid(h=0.0)
    neutral = [m.label for m in linear_modes(thin, rest_pose(thin)).modes if m.period is None][0]
    with pytest.raises(InputError, match="no restoring stiffness"):
        bt.simulate_batch([thin], neutral, 0.05, 2)


def test_slack_wire_is_reported_and_stop_ends_the_run():
    # trifilar with the CoM near the edge of wires 2-3: wire 1 carries 2.7 % of the weight and a
    # 0.6 m swing unloads it
    ang = np.radians([0, 120, 240])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    s = scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                         "rig": {"anchors": pts.tolist(), "attachments": (pts + [0.23, 0, 0.1]).tolist(),
                                 "lengths": [2.0] * 3}})
    big = bt.simulate_batch([s], "swing-x", 0.6, 3, rtol=1e-9)[0]
    assert big.slack and any("SLACK" in w for w in big.warnings)
    assert min(big.tension_min) <= 0
    small = bt.simulate_batch([s], "swing-x", 0.1, 3, rtol=1e-9)[0]
    assert not small.slack and min(small.tension_min) > 0
    rest = rest_pose(s)
    md = linear_modes(s, rest).get("swing-x")
    for method in ("dop853", "lsoda"):
        stopped = bt.run_one(s, rest, md, 0.6, 3, 1e-9, method=method, on_slack="stop")
        # stopped at (dop853: the step; lsoda: the sample) where the tension first reaches zero
        t_slack = min(t for _, t in stopped.slack)
        assert stopped.t_final < 3 * stopped.linear_period
        assert stopped.t_final == pytest.approx(t_slack, abs=0.05 * stopped.linear_period)
        assert all(c <= stopped.t_final for c in stopped.crossings)


def test_dense_samples_match_simulate():
    s = trapezoid(l1=5.0, l2=4.8, h=0.5)
    a = simulate(s, "torsion", 0.05, 2, rtol=1e-12, samples_per_period=32)
    one = bt.simulate_batch([s], "torsion", 0.05, 2, rtol=1e-12, samples_per_period=32, method="dop853")[0]
    many = bt.simulate_batch([s] * bt.SMALL_BATCH, "torsion", 0.05, 2, rtol=1e-12, samples_per_period=32,
                             method="dop853")[3]
    for b in (one, many):  # float path and vectorised path: same sample times as simulate
        np.testing.assert_allclose(b.t, a.t, atol=1e-12)
        # two integrators at rtol 1e-12 over 2 periods, order-7 interpolants: states agree to ~1e-11
        np.testing.assert_allclose(b.y, a.y, atol=1e-9)
    c = bt.simulate_batch([s], "torsion", 0.05, 2, rtol=1e-12, samples_per_period=32, method="lsoda")[0]
    # lsoda samples on its own grid (>= 64 per period in normalised time): compare by interpolation
    # (linear interpolation of a ~0.05 rad oscillation at 64 samples per period: error ~1e-4)
    np.testing.assert_allclose(np.interp(a.t, c.t, c.y[:, 5]), a.y[:, 5], atol=1e-4)
    for j in range(3):  # positions (absolute, world frame): the CoM moves by ~1e-4 m here
        np.testing.assert_allclose(np.interp(a.t, c.t, c.y[:, j]), a.y[:, j], atol=1e-5)


def test_to_json_has_the_interface_keys():
    r = bt.simulate_batch([trapezoid(h=0.5)], "torsion", 0.05, 2)[0]
    doc = r.to_json()
    for key in ("period", "linear_period", "max_constraint_violation", "energy_drift", "tension"):
        assert key in doc
    assert set(doc["tension"]) == {"min", "max"}


# --------------------------------------------------------------------------
# the integrator itself
# --------------------------------------------------------------------------
def _oscillators(omega):
    """Harmonic oscillators y = (x, v), x'' = -omega^2 x, as kernel-style functions."""
    def make_f(idx):
        w2 = omega[idx] ** 2

        def f(x, v):
            return (v, -w2 * x)
        return f
    return make_f


def test_batch_integrator_is_exact_on_oscillators_with_their_own_steps():
    omega = np.array([0.5, 1.0, 7.0, 40.0])
    t_end = 20 * 2 * np.pi / omega  # 20 periods each, very different lengths
    y0 = np.vstack([np.ones(4), np.zeros(4)])

    class Obs(itg.BatchObserver):
        def __init__(self):
            self.cross = {i: [] for i in range(4)}

        def accepted(self, idx, t_old, t_new, y_old, y_new, ext_new, dense):
            up = np.nonzero((y_old[0] < 0) & (y_new[0] >= 0))[0]
            if len(up):
                F = dense(up)
                x = itg.crossing_on_step(F[:, 0, :], y_old[0, up], y_new[0, up])
                for j, xx in zip(up, x):
                    self.cross[int(idx[j])].append(t_old[j] + xx * (t_new[j] - t_old[j]))

    obs = Obs()
    run = itg.integrate_batch(_oscillators(omega), y0, t_end, 1e-10, 1e-12, 0.01 * 2 * np.pi / omega, obs)
    np.testing.assert_allclose(run.t, t_end, rtol=1e-15)
    # exact: x = cos(omega t); global error after 20 periods at rtol 1e-10 ~ 1e-9
    np.testing.assert_allclose(run.y[0], np.cos(omega * t_end), atol=1e-8)
    # each system takes about the same number of steps (its own step size scales with 1/omega)
    assert run.nsteps.max() - run.nsteps.min() <= 2
    for i in range(4):  # upward zero crossings of cos at (k + 3/4) periods
        T = 2 * np.pi / omega[i]
        np.testing.assert_allclose(obs.cross[i], (np.arange(20) + 0.75) * T, atol=1e-9 * T)


def test_single_integrator_takes_scipys_steps():
    s = trapezoid(l1=5.0, l2=4.8, h=0.5)
    rest = rest_pose(s)
    md = linear_modes(s, rest).get("torsion")
    y0 = initial_state(s, rest, md, 0.1)
    P = mx.params_from_scenes(s)
    k = mx.compiled_kernel(P)
    t_end, h0 = 3 * md.period, 0.01
    run = itg.integrate_single(k, y0, t_end, 1e-9, 1e-11, h0)
    sol = solve_ivp(mx.make_flat_rhs(P), (0, t_end), y0, method="DOP853", rtol=1e-9, atol=1e-11, first_step=h0,
                    dense_output=True)
    ref = solve_ivp(mx.make_flat_rhs(P), (0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-15, dense_output=True)
    # same tableau and controller: the same step sequence up to rounding of the error estimate
    # (a few 1e-6 of a step), hence the same number of steps and the same error
    assert abs(len(run.t) - len(sol.t)) <= 1
    np.testing.assert_allclose(run.t[:20], sol.t[:20], rtol=1e-4)
    err_own = np.max(np.abs(run.y[-1] - ref.y[:, -1]))
    err_scipy = np.max(np.abs(sol.y[:, -1] - ref.y[:, -1]))
    assert err_own < 3 * err_scipy + 1e-14
    # order-7 dense output: in the middle of the steps as accurate as scipy's (same interpolant)
    tm = 0.5 * (run.t[:-1] + run.t[1:])
    mid = np.array([itg.dense_eval(run.dense(k, j), run.y[j], 0.5) for j in range(len(tm))])
    ts = 0.5 * (sol.t[:-1] + sol.t[1:])
    err_dense_scipy = np.max(np.abs(sol.sol(ts) - ref.sol(ts)))
    assert np.max(np.abs(mid - ref.sol(tm).T)) < 3 * err_dense_scipy + 1e-13


def test_sampled_crossings_of_a_known_signal():
    t = np.linspace(0, 10, 641)
    c = np.stack([np.sin(2 * np.pi * t / 1.3 + 0.3), np.cos(2 * np.pi * 1.1 * t) - 0.2], axis=1)
    col, tc, _ = itg.sampled_crossings(c, t[1] - t[0])
    exact0 = (np.arange(1, 8) - 0.3 / (2 * np.pi)) * 1.3
    # degree-7 interpolation at ~40-60 samples per period: error ~1e-12 of a period
    np.testing.assert_allclose(tc[col == 0], exact0[exact0 < 10], atol=1e-10)
    k = np.arange(0, 11)
    exact1 = (k + 1 - np.arccos(0.2) / (2 * np.pi)) / 1.1
    np.testing.assert_allclose(tc[col == 1], exact1[exact1 < 10], atol=1e-10)


def test_degenerate_cluster_is_canonical_whatever_the_eigensolver_returns():
    """Another BLAS kernel returns another (equally valid) eigenbasis of a
    repeated eigenvalue, in another order, with last-bit differences in the
    eigenvalues.  Feed mode_set every such variant of the symmetric
    trifilar's swing pair (rotations of the basis, the two eigenvalues
    perturbed by +-1e-15 relative in either order): labels, periods and
    shapes must come out the same every time (independent reference: the
    unperturbed solution; the swing pair of a symmetric trifilar is
    degenerate by symmetry, and its canonical shapes are pure x / pure y
    swings with the coupled roll/pitch, not mixtures)."""
    from scipy.linalg import eigh

    from bifilar.analysis.equilibrium import reduced_stiffness
    from bifilar.analysis.modes import mode_set

    s = _trifilar(dz=0.2)
    r = rest_pose(s)
    lam = r.tensions / np.linalg.norm(r.wire_vectors, axis=1)
    N, Kr, Mr, _ = reduced_stiffness(s, r.com, r.R, lam)
    M = linear_modes(s, r).mass_matrix
    w2, Y = eigh(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T))
    ref = mode_set(N, Y, w2, s.mass, M)
    pair = [k for k in range(len(w2) - 1) if abs(w2[k + 1] - w2[k]) < 1e-8 * abs(w2).max()]
    assert len(pair) == 1, "the symmetric trifilar has one degenerate swing pair"
    k = pair[0]
    assert ref.labels[:2] == ["swing-x", "swing-y"]
    for name in ("swing-x", "swing-y"):
        sh = ref.get(name).shape
        other = 1 if name == "swing-x" else 0
        assert abs(sh[other]) < 1e-9  # a pure swing along its own axis
    rng = np.random.default_rng(0)
    for trial in range(40):
        a = rng.uniform(0, 2 * np.pi)
        Q = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) * rng.choice([-1, 1], 2)
        Y2 = Y.copy()
        Y2[:, k:k + 2] = Y[:, k:k + 2] @ Q
        w2b = w2.copy()
        eps = 1e-15 * abs(w2[k]) * (1 if trial % 2 else -1)
        w2b[k], w2b[k + 1] = w2[k] + eps, w2[k + 1] - eps
        got = mode_set(N, Y2, w2b, s.mass, M)
        assert got.labels == ref.labels
        for g, e in zip(got.modes, ref.modes):
            assert g.period == pytest.approx(e.period, rel=1e-13)
            np.testing.assert_allclose(g.shape, e.shape, atol=1e-9)


def test_a_neutral_mode_stays_neutral_whatever_the_rounding():
    """CoM on the line through the two attachment points of a parallel
    bifilar: rolling about that line has no restoring moment (omega^2 = 0
    exactly, by statics).  Rounding leaves ~1e-16 of the largest omega^2,
    of either sign; it must always read as neutral (period None), never as a
    2e8 s mode that shifts the order of the others (it did, at some inertia
    values, and the inversion's period-vs-inertia scan jumped)."""
    from bifilar.config import scene_from_dict

    for izz in np.linspace(0.1, 0.3, 41):
        s = scene_from_dict({"body": {"mass": 5.0, "inertia": {"principal": [0.2, 0.1, float(izz)]}},
                             "rig": {"anchors": [[0, -0.2, 0], [0, 0.2, 0]],
                                     "attachments": [[0, -0.2, 0], [0, 0.2, 0]], "lengths": [1.5, 1.5]}})
        r = rest_pose(s)
        for ms in (linear_modes(s, r), bt.modes_batch([s], [r])[0]):
            assert [m.period is None for m in ms.modes] == [False, False, False, True]
            # the swings of parallel 1.5 m wires: a simple pendulum's 2 pi sqrt(L / g)
            swings = [m.period for m in ms.modes if m.label.startswith("swing")]
            assert swings == pytest.approx([2 * np.pi * np.sqrt(1.5 / G)] * 2, rel=1e-9)
