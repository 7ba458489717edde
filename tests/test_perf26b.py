"""perf26b: the shortcuts of session 26's sweep-point work, each against the path it replaces, bit for bit
(docs/design.md, "perf26b, session 26")."""

from __future__ import annotations

import numpy as np


def _clustered_problems(rng, n, k, spec):
    """``n`` solved eigenproblems (N (n, 6, k), Y, w2, K) of ``k`` degrees of freedom whose eigenvalues
    repeat as ``spec`` says: a list of (start, stop) index ranges made equal (exactly, or within a few ulps
    every other problem), each problem with its own random basis, so that the eigensolver's vectors inside
    a cluster are an arbitrary rotation, as on a symmetric rig."""
    from bifilar.analysis.modes import eigh_generalized

    Ns, Ys, ws, Ks = [], [], [], []
    for q in range(n):
        N = np.linalg.qr(rng.normal(size=(6, 6)))[0][:, :k]
        w = np.sort(rng.uniform(0.5, 40.0, k))
        for a, b in spec:
            w[a:b] = w[a] * (1 + (4e-16 * np.arange(b - a) if q % 2 else 0.0))
        Q = np.linalg.qr(rng.normal(size=(k, k)))[0]
        d = rng.uniform(1.0, 5.0, k)
        K = np.sqrt(d)[:, None] * (Q @ np.diag(w) @ Q.T) * np.sqrt(d)[None, :]  # K y = w diag(d) y
        K = 0.5 * (K + K.T)
        w2, Y = eigh_generalized(K, np.diag(d))
        Ns.append(N), Ys.append(Y), ws.append(w2), Ks.append(K)
    return np.array(Ns), np.array(Ys), np.array(ws), np.array(Ks)


def test_batched_alignment_equals_the_single_scene_one():
    # mode_sets aligns the degenerate clusters of every scene of one cluster structure in one stacked pass
    # (_align_degenerate_batch; the trifilar's sigma points: 0.55 ms of its 1.9 ms of modes); against
    # _align_degenerate scene by scene (the path before, still mode_set's for one scene): the same Y bit for
    # bit, on clusters of 2 and 3 and two clusters in one scene
    from bifilar.analysis import modes as md

    rng = np.random.default_rng(26)
    checked = 0
    for k, spec in [(3, [(0, 2)]), (4, [(1, 3)]), (4, [(0, 3)]), (5, [(0, 2), (2, 4)]), (6, [(3, 6)])]:
        N, Y, w2, K = _clustered_problems(rng, 12, k, spec)
        for b in range(len(w2)):  # the structure asked for is the one mode_set finds
            assert md.clusters(w2[b], md._noise(w2[b], Y[b], K[b])) == [(a, c) for a, c in _ranges(k, spec)]
        groups = _ranges(k, spec)
        got = md._align_degenerate_batch(N, Y, groups)
        ref = np.array([md._align_degenerate(N[b], Y[b], w2[b], md._noise(w2[b], Y[b], K[b])) for b in range(len(w2))])
        assert got.tobytes() == ref.tobytes()
        assert not np.array_equal(got, Y)  # (the alignment did something)
        # a scene's numbers do not depend on the others in its batch
        assert md._align_degenerate_batch(N[3:4], Y[3:4], groups).tobytes() == ref[3:4].tobytes()
        checked += len(w2)
    assert checked == 60


def test_mode_sets_with_mixed_structures_equal_mode_set():
    # mode_sets groups a batch's scenes by cluster structure (plain scenes, one cluster, another cluster) and
    # sets each cluster's eigenvalues to their mean for the group at once; against mode_set of each scene: the
    # same mode sets (labels, periods, omega^2, shapes, energy shares, unit components) bit for bit
    from bifilar.analysis import modes as md

    rng = np.random.default_rng(7)
    parts = [_clustered_problems(rng, 5, 4, spec) for spec in ([], [(0, 2)], [(1, 3)], [(0, 2), (2, 4)])]
    N, Y, w2, K = (np.concatenate([p[i] for p in parts]) for i in range(4))
    order = rng.permutation(len(w2))  # the structures interleaved in the batch
    N, Y, w2, K = N[order], Y[order], w2[order], K[order]
    mass = rng.uniform(1, 100, len(w2))
    A = rng.normal(size=(len(w2), 3, 3))
    M = np.zeros((len(w2), 6, 6))
    M[:, :3, :3] = mass[:, None, None] * np.eye(3)
    M[:, 3:, 3:] = A @ np.swapaxes(A, 1, 2) + np.eye(3)
    which = [b for b in range(len(w2)) if b != 4]
    got = md.mode_sets(N, Y, w2, mass, M, K, which=which)
    assert got[4] is None
    for b in which:
        ref = md.mode_set(N[b], Y[b], w2[b], mass[b], M[b], K=K[b])
        assert [(m.label, m.period, m.omega2, m.shape.tobytes(), m.energy_share.tobytes(), m.dominant)
                for m in got[b].modes] == [(m.label, m.period, m.omega2, m.shape.tobytes(), m.energy_share.tobytes(),
                                            m.dominant) for m in ref.modes]
    repeated = sum(len({m.period for m in got[b].modes}) < len(got[b].modes) for b in which)
    assert repeated >= 14  # (the clustered scenes kept their equal periods)


def _ranges(k, spec):
    """:func:`~bifilar.analysis.modes.clusters`' ranges of ``k`` eigenvalues whose ``spec`` ranges repeat."""
    out, i = [], 0
    for a, b in sorted(spec):
        out += [(j, j + 1) for j in range(i, a)] + [(a, b)]
        i = b
    return out + [(j, j + 1) for j in range(i, k)]


def _old_propagate(names, Jp, period_sigma, Jx, input_names, input_sigmas, extra=None):
    """uncertainty.propagate's contributions and covariance before session 26 (an input's column by its own
    G @ Jx[:, j], the covariance by np.outer in the dicts' order)."""
    from bifilar.estimation.uncertainty import gain_matrix

    Jp = np.atleast_2d(np.asarray(Jp, float))
    sig = np.asarray(period_sigma, float)
    G = gain_matrix(Jp, sig)
    contrib = {f"timing[{k}]": G[:, k] * sig[k] for k in range(Jp.shape[0])}
    for j, n in enumerate(input_names):
        s = float(input_sigmas[j])
        if s > 0:
            contrib[n] = -(G @ Jx[:, j]) * s
    for n, c in (extra or {}).items():
        contrib[n] = np.asarray(c, float).reshape(len(names))
    cov = np.zeros((len(names), len(names)))
    for c in contrib.values():
        cov += np.outer(c, c)
    return contrib, cov


def test_one_period_budget_equals_the_column_by_column_one():
    # propagate takes every input's column in one product where one period is measured (K = 1: the honest
    # sigma of a sweep point, invert --period) and sums a one-unknown covariance on Python floats
    # (covariance_of; 90 -> 33 us a call, three a Solar Boat point); against the code before, bit for bit,
    # over inputs whose contributions span 12 decades, zero sigmas, extra terms and 1-3 unknowns (K = 2, 3
    # take the old per-column path: the same numbers too)
    from bifilar.estimation.uncertainty import covariance_of, propagate

    rng = np.random.default_rng(2026)
    for trial in range(60):
        K, P = [(1, 1), (1, 1), (1, 2), (2, 1), (3, 3), (1, 3)][trial % 6]
        J = int(rng.integers(1, 30))
        names = [f"I{p}" for p in range(P)]
        Jp = rng.normal(size=(K, P)) * 10.0 ** rng.uniform(-3, 3)
        if K < P:  # (an underdetermined fit has no gain matrix: as many periods as unknowns)
            Jp = rng.normal(size=(P, P))
            K = P
        sig = 10.0 ** rng.uniform(-5, -2, K)
        Jx = rng.normal(size=(K, J)) * 10.0 ** rng.uniform(-6, 6, J)
        s_in = np.where(rng.random(J) < 0.2, 0.0, 10.0 ** rng.uniform(-4, -1, J))
        inames = [f"x{j}" for j in range(J)]
        extra = {"amplitude[t]": rng.normal(size=P) * 1e-3} if trial % 2 else None
        got = propagate(names, Jp, sig, Jx, inames, s_in, extra=extra)
        ref_c, ref_cov = _old_propagate(names, Jp, sig, Jx, inames, s_in, extra=extra)
        assert list(got.contributions) == list(ref_c)
        assert all(got.contributions[n].tobytes() == ref_c[n].tobytes() for n in ref_c)
        assert got.covariance.tobytes() == ref_cov.tobytes()
        assert covariance_of(ref_c, P).tobytes() == ref_cov.tobytes()


def test_one_unknown_covariance_sums_in_the_dicts_order():
    # covariance_of on one unknown adds the squares in the dict's order, as the np.outer loop it replaces
    # (budget, second_order, prior_inertia, birge): the same bits where the order matters (terms of very
    # different sizes, in an order whose reversal rounds differently), NaN and inf as numpy gives them
    from bifilar.estimation.uncertainty import covariance_of

    rng = np.random.default_rng(1)
    differs = 0
    for _ in range(200):
        c = {f"t{i}": np.array([v]) for i, v in enumerate(rng.normal(size=25) * 10.0 ** rng.uniform(-8, 0, 25))}
        ref = np.zeros((1, 1))
        for v in c.values():
            ref += np.outer(v, v)
        assert covariance_of(c, 1).tobytes() == ref.tobytes()
        back = np.zeros((1, 1))
        for v in reversed(list(c.values())):
            back += np.outer(v, v)
        differs += back.tobytes() != ref.tobytes()
    assert differs > 20  # (the order is visible in the last bits: the test can see a reordering)
    for bad in (np.nan, np.inf):
        with np.errstate(invalid="ignore", over="ignore"):
            assert covariance_of({"a": np.array([1.0]), "b": np.array([bad])}, 1).tobytes() == \
                np.array([[1.0 + bad * bad]]).tobytes()
