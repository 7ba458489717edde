"""perf26c: the MAC's base-side products computed once per base mode set (``sensitivity.period_matcher``,
``_mac_base``), against the per-call formula they replace, bit for bit (docs/design.md, "perf26c, session 26")."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from scipy.optimize import linear_sum_assignment


def _reference_periods(base, other):
    """matched_periods as it was before perf26c: the MAC matrix from the base's shapes A, its mass matrix M
    and the other's shapes B in one expression per call, the best one-to-one matching, NaN elsewhere."""
    M = base.mass_matrix
    A = np.array([m.shape for m in base.modes])
    B = np.array(getattr(other, "shapes", None) if getattr(other, "shapes", None) is not None
                 else [m.shape for m in other.modes])
    num = (A @ M @ B.T) ** 2
    den = np.outer(np.einsum("ij,jk,ik->i", A, M, A), np.einsum("ij,jk,ik->i", B, M, B))
    rows, cols = linear_sum_assignment(-(num / np.maximum(den, 1e-300)))
    out = np.full(len(base.modes), np.nan)
    P = getattr(other, "periods", None)
    for r, i in zip(rows, cols):
        out[r] = P[i] if P is not None else (other.modes[i].period or np.nan)
    return out, cols


def _mode_set(rng, M, shapes, lazy):
    """A mode set as the MAC reads it (modes' shapes and periods, the mass matrix; a lazy one's arrays)."""
    periods = rng.uniform(0.5, 5.0, len(shapes))
    modes = [SimpleNamespace(shape=s, period=float(p)) for s, p in zip(shapes, periods)]
    if lazy:
        return SimpleNamespace(modes=modes, mass_matrix=M, shapes=np.array(shapes), periods=periods)
    return SimpleNamespace(modes=modes, mass_matrix=M)


def _problems(rng, n):
    """``n`` (base, other) pairs: a random SPD mass matrix, k = 2-6 base shapes, the other's shapes those
    shuffled, mixed with each other (so that the MAC's normalisation decides the matching), rescaled by
    1e-3..1e3 and sign-flipped; the other has k or k - 1 modes, lazy or not."""
    for q in range(n):
        k = int(rng.integers(2, 7))
        G = rng.normal(size=(6, 6))
        M = G @ G.T + 6 * np.eye(6)
        A = rng.normal(size=(k, 6))
        perm = rng.permutation(k)
        B = A[perm] + 0.45 * rng.normal(size=(k, 6)) * np.linalg.norm(A[perm], axis=1)[:, None] / np.sqrt(6)
        B *= (10.0 ** rng.uniform(-3, 3, k) * rng.choice([-1, 1], k))[:, None]
        if q % 3 == 2:
            B = B[: k - 1]
        yield _mode_set(rng, M, list(A), False), _mode_set(rng, M, list(B), q % 2 == 0)


def test_period_matcher_equals_the_per_call_mac():
    # linear_estimate's secant reads 8 matched periods a boat point against one base mode set: the base's
    # products (A @ M, diag A M A^T) computed once must give the per-call formula's periods bit for bit,
    # whether or not the other set is lazy or has a mode fewer; the matchings must not be trivial (a break of
    # the normalisation or the square must move some), so count the problems whose matching is not the
    # identity
    from bifilar.estimation.sensitivity import matched_periods, period_matcher

    rng = np.random.default_rng(2603)
    moved = 0
    for base, other in _problems(rng, 150):
        ref, cols = _reference_periods(base, other)
        moved += not np.array_equal(cols, np.arange(len(cols)))
        assert np.array_equal(period_matcher(base)(other), ref, equal_nan=True)
        assert np.array_equal(matched_periods(base, other), ref, equal_nan=True)
    assert moved >= 100


def test_one_matcher_serves_many_others():
    # the matcher's base side is computed once and read by every call: 20 others against one base
    from bifilar.estimation.sensitivity import period_matcher

    rng = np.random.default_rng(26)
    pairs = list(_problems(rng, 60))
    for base, _ in pairs[:3]:
        f = period_matcher(base)
        k = len(base.modes)
        for _, other in (p for p in pairs if len(p[0].modes) == k):
            other = _mode_set(rng, base.mass_matrix, list(np.array([m.shape for m in other.modes])), False)
            assert np.array_equal(f(other), _reference_periods(base, other)[0], equal_nan=True)


def test_mac_matches_equal_the_per_call_mac():
    # mac_matches (the honest sigma's sigma points, stacked) takes its base side from the same _mac_base
    from bifilar.estimation.sensitivity import mac_matches

    rng = np.random.default_rng(7)
    for base, _ in list(_problems(rng, 20)):
        k = len(base.modes)
        others = [next(iter(_problems(rng, 1)))[1] for _ in range(4)]
        others = [o for o in others if len(o.modes) <= k]
        A = np.array([m.shape for m in base.modes])
        for j in range(5):  # others of base's own size, stacked: shapes of the base mixed as _problems does
            B = A[rng.permutation(k)] + 0.45 * rng.normal(size=(k, 6)) * np.linalg.norm(A, axis=1).mean() / 2.5
            B *= (10.0 ** rng.uniform(-3, 3, k) * rng.choice([-1, 1], k))[:, None]
            others.append(_mode_set(rng, base.mass_matrix, list(B), j % 2 == 0))
        got = mac_matches(base, others)
        for o, g in zip(others, got):
            assert np.array_equal(g, _reference_periods(base, o)[1])


def test_linear_estimate_unchanged_on_the_boat():
    # the caller: linear_estimate's secant with the matcher against the per-call MAC, the Solar Boat at
    # spacing 3 (the three components of its sweep point, targets 1 % off their periods)
    from pathlib import Path

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes, modes_of_inertia
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation import sensitivity
    from bifilar.studies import point

    cfg = read_yaml(Path(__file__).resolve().parents[1] / "configs" / "solar_boat.yaml")
    scene = scene_from_dict(cfg, warn=False)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    at = modes_of_inertia(scene, rest)
    cases = []
    for comp in ("Ixx", "Iyy", "Izz"):
        a = "xyz".index(comp[1])
        k = int(np.argmax([m.energy_share[3 + a] for m in ms.modes]))
        T = ms.modes[k].period
        cases.append((comp, k, 1.01 * T, 0.5 * T / scene.inertia[a, a]))  # slope: T ~ sqrt(I)

    def estimates():
        return [point.linear_estimate(scene, c, k, T, ms, rest, slope, at=at) for c, k, T, slope in cases]

    got = estimates()
    real = sensitivity.period_matcher
    try:
        sensitivity.period_matcher = lambda base: (lambda other: _reference_periods(base, other)[0])
        ref = estimates()
    finally:
        sensitivity.period_matcher = real
    assert all(g is not None for g in got)
    assert got == ref
