"""Session 28 (fixed28): the fixed cost of a batch of sigma points and of
each component's pass over them, cut without changing a bit.

* ``second_order``'s per-input quadratics, offsets and sum of squares on
  stacked rows (``_surrogates``, ``_sum_of_squares``, ``_sequential_sum``)
  against the per-input loop before: the same budgets, contributions,
  surrogates, flagged inputs and pair terms, bit for bit;
* ``_sequential_sum`` adds in order (``rows.sum(axis=0)`` may add pairwise:
  other bits);
* ``modes_batch`` takes the tensions from the batch geometry (not from
  each pose) and ``propagate`` the budget's gain matrix (not its own):
  against the paths before, the same mode sets and budgets, bit for bit;
* ``_settle`` returns at once when nothing was deferred (its verdicts:
  tests/test_sigma_rest.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bifilar.estimation import second_order as so
from bifilar.estimation.uncertainty import LinearBudget, covariance_of

from conftest import CONFIGS


def _second_order_before(pb, p_hat, r_hat, ctx, lin):
    """second_order.second_order before session 28 (verbatim, names qualified)."""
    keys = [k for k in ctx.inputs if ctx.sigmas.get(k, 0) > 0]
    if any(any(m.period is None for m in ms.modes) for ms in ctx.modes):
        keys = []
    h_ = so.SIGMA_POINT
    sol = so._solve_points(pb, ctx, p_hat, r_hat, {(key, sgn): [(key, sgn * h_ * ctx.sigmas[key])]
                                                   for key in keys for sgn in (1, -1)})
    p0 = np.asarray(p_hat, float)
    failed, surrogate = [], {}
    for key in keys:
        pp, pm = sol[(key, 1)], sol[(key, -1)]
        if pp is None or pm is None:
            failed.append(key)
            continue
        surrogate[key] = ((pp - pm) / (2 * h_) + ctx.factor_shift.get(key, 0.0), (pp + pm - 2 * p0) / 6)
    std1 = lin.std
    contrib = {k: v for k, v in lin.contributions.items() if k not in surrogate}
    offset = np.zeros(len(pb.unknowns))
    for key, (a, b) in surrogate.items():
        contrib[key] = a
        contrib[f"{key} (2nd order)"] = math.sqrt(2) * b
        offset = offset + b
    var2 = sum((np.asarray(c) ** 2 for c in contrib.values()), np.zeros(len(offset))) + offset ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        change = np.abs(np.sqrt(var2) / std1 - 1)
        off_rel = np.abs(offset) / std1
    ctx.cross = {}
    if np.all(change < so.LINEAR_ENOUGH) and np.all(off_rel < so.OFFSET_ENOUGH):
        contrib, offset = dict(lin.contributions), np.zeros(len(offset))
        ctx.surrogate = {}
    else:
        ctx.surrogate = surrogate
        ctx.nonlinear = [k for k, (a, b) in surrogate.items()
                         if np.any(math.sqrt(2) * np.abs(b) > 0.05 * std1)
                         or np.any(np.abs(a - lin.contributions.get(k, a)) > 0.05 * std1)]
        offset = offset + so._pair_terms(pb, ctx, p_hat, r_hat, sol, contrib, std1)
    if not ctx.surrogate and not ctx.amplitude:
        return lin, failed
    for lab, D in ctx.amplitude.items():
        mean_w, std_w = so._release_moments(ctx, lab)
        contrib[f"amplitude[{lab}]"] = D * std_w
        offset = offset + D * mean_w
    if np.any(offset):
        contrib["offset"] = offset
    cov = covariance_of(contrib, len(lin.names))
    return LinearBudget(list(lin.names), cov, contrib, dict(lin.sigmas), dict(lin.dof)), failed


def _bits(x) -> bytes:
    return np.asarray(x, float).tobytes()


def _boat_two_modes():
    """The Solar Boat's Izz and Ixx from torsion timed at 0.2 rad and roll (K = P = 2; the nonlinear
    method: every input's amplitude-factor shift)."""
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
    from bifilar.estimation.uncertainty import default_uncertainty

    u = default_uncertainty()
    ms = MeasurementSet([Hanging("reference", scene_from_dict(read_yaml(CONFIGS / "solar_boat.yaml"), warn=False),
                                 np.eye(3))],
                        [Measurement("torsion", 1.8901, u["timing"], "period", "--period", amplitude=0.2),
                         Measurement("roll", 2.7250, u["timing"], "period", "--period")])
    ms.uncertainty = dict(u)
    return ms, u


def _drawn_a03():
    """audit27's drawn a03 timed at 1.87 s (com.y to second order, with a pair term)."""
    from bifilar.config import read_yaml, scene_from_dict
    from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet, config_uncertainty
    from bifilar.estimation.uncertainty import default_uncertainty

    drawn = CONFIGS.parent / "tests" / "data" / "audit27" / "a03_drawn.yaml"
    u = default_uncertainty(config_uncertainty(drawn))
    ms = MeasurementSet([Hanging("reference", scene_from_dict(read_yaml(drawn), warn=False), np.eye(3))],
                        [Measurement("torsion", 1.87, u["timing"], "period", "--period")])
    ms.uncertainty = dict(u)
    return ms, u


def _second_order_runs(monkeypatch, fn, forced: bool, settled: list | None = None) -> list:
    """What ``fn`` as second_order returns and leaves in the context, and
    every re-solved sigma point, over the honest stds of the drone (second
    order in com.x) and of the shallow wheel (pair terms), and inversions
    of :func:`_drawn_a03` (a pair term) and :func:`_boat_two_modes` (linear
    kept).  ``forced``: with LINEAR_ENOUGH = OFFSET_ENOUGH = 0 (every
    budget to second order, so every input's quadratic reaches it; the
    drone and the boat only).  ``settled``: a list to which each
    ``_one_step`` call's (K, points given, points settled) is appended."""
    from bifilar.config import scene_from_dict
    from bifilar.estimation import honest, invert
    from bifilar.estimation.sensitivity import best_mode_for, period_sensitivity
    from bifilar.estimation.uncertainty import default_uncertainty

    from test_point_cost import _honest_cases

    seen: list = []
    real_points, real_one = so._solve_points, so._one_step

    def one(pb, ctx, p_hat, r_hat, hits_of):
        out = real_one(pb, ctx, p_hat, r_hat, hits_of)
        if settled is not None:
            settled.append((len(pb.measurements), len(hits_of), len(out)))
        return out

    def points(*a, **k):
        out = real_points(*a, **k)
        seen.append([(pid, None if v is None else _bits(v)) for pid, v in out.items()])
        return out

    def recording(pb, p_hat, r_hat, ctx, lin):
        budget, failed = fn(pb, p_hat, r_hat, ctx, lin)
        seen.append((_bits(budget.covariance), [(k, _bits(v)) for k, v in budget.contributions.items()],
                     list(failed), [(k, _bits(a), _bits(b)) for k, (a, b) in ctx.surrogate.items()],
                     list(ctx.nonlinear), [(k, [_bits(c) for c in v]) for k, v in ctx.cross.items()]))
        return budget, failed

    monkeypatch.setattr(so, "_solve_points", points)
    monkeypatch.setattr(so, "_one_step", one)
    monkeypatch.setattr(so, "second_order", recording)
    monkeypatch.setattr(invert, "second_order", recording)
    thresholds = so.LINEAR_ENOUGH, so.OFFSET_ENOUGH
    if forced:
        monkeypatch.setattr(so, "LINEAR_ENOUGH", 0.0)
        monkeypatch.setattr(so, "OFFSET_ENOUGH", 0.0)
    cases = _honest_cases()
    unc = default_uncertainty()
    for case in ("drone",) if forced else ("drone", "shallow wheel"):
        cfg, comps = cases[case]
        scene = scene_from_dict(cfg, case, warn=False)
        sens = period_sensitivity(scene)
        req = [(c, best_mode_for(sens, c) + 1) for c in comps[:2]]
        seen.append(honest.honest_stds(scene, req, unc, unc["timing"], rest=sens.rest, sens=sens))
    for ms, u in ((_boat_two_modes(),) if forced else (_drawn_a03(), _boat_two_modes())):
        res = invert.invert(ms, ladder=False, unc=dict(u))
        seen.append((_bits(res.values), _bits(res.std), res.method, list(res.budget.contributions)))
    monkeypatch.setattr(so, "_solve_points", real_points)
    monkeypatch.setattr(so, "_one_step", real_one)
    monkeypatch.setattr(so, "LINEAR_ENOUGH", thresholds[0])
    monkeypatch.setattr(so, "OFFSET_ENOUGH", thresholds[1])
    return seen


def test_second_order_on_stacked_rows_equals_the_loop_before(monkeypatch):
    # and, on the path before, propagate's own gain matrix (not _budget's) and modes_batch's tensions read
    # from the poses (not the batch geometry's)
    from bifilar.estimation import budget, uncertainty

    new = so.second_order  # (the runs leave their recording wrapper in its place)
    settled: list = []
    got = [_second_order_runs(monkeypatch, new, forced, settled) for forced in (False, True)]
    # the boat's two periods (its stacked columns): every sigma point settled in _one_step's first step, as
    # _resolve would (a wrong column there leaves them all to _resolve: the same numbers, slower)
    two = [s for s in settled if s[0] == 2]
    assert two and all(n == given for _, given, n in two) and sum(n for _, _, n in two) >= 36
    monkeypatch.setattr(budget, "propagate", lambda *a, gain=None, **k: uncertainty.propagate(*a, **k))
    _no_tensions_geometry(monkeypatch)
    ref = [_second_order_runs(monkeypatch, _second_order_before, forced) for forced in (False, True)]
    assert got == ref
    budgets = [s for run in ref for s in run if isinstance(s, tuple) and len(s) == 6]
    # the runs took both branches: a budget kept linear, and second-order terms with pair terms; the boat's
    # inversion used the nonlinear method (the amplitude-factor shifts) and, forced, went to second order
    assert any(s[3] == [] for s in budgets) and any(s[5] for s in budgets)
    assert any("com.y (2nd order)" in s[3] for s in ref[0] if isinstance(s, tuple) and len(s) == 4)
    assert ref[0][-1][2] == "nonlinear" and "(2nd order)" not in str(ref[0][-1][3])
    assert any("com.z (2nd order)" in s[3] for s in ref[1][-1:])


def test_sequential_sum_adds_in_order():
    rng = np.random.default_rng(28)
    for n, P in ((0, 1), (1, 1), (7, 2), (40, 1), (1000, 1), (300, 3)):
        X = rng.standard_normal((n, P)) * 10.0 ** rng.uniform(-8, 8, (n, P))
        acc = np.zeros(P)
        for row in X:
            acc = acc + row
        assert so._sequential_sum(X).tobytes() == acc.tobytes()
        assert so._sum_of_squares(list(X), P).tobytes() == sum((r ** 2 for r in X), np.zeros(P)).tobytes()
    # the reason for the accumulate: numpy's own sum adds 1000 rows pairwise, other bits
    assert X.sum(axis=0).tobytes() != acc.tobytes() or True
    Y = rng.standard_normal((1000, 1)) * 10.0 ** rng.uniform(-8, 8, (1000, 1))
    acc = np.zeros(1)
    for row in Y:
        acc = acc + row
    assert Y.sum(axis=0).tobytes() != acc.tobytes() and so._sequential_sum(Y).tobytes() == acc.tobytes()
    # terms of another shape (a scalar among arrays): the loop
    assert so._sum_of_squares([np.array([1.0, 2.0]), 3.0], 2).tolist() == [10.0, 13.0]


def _sigma_batches():
    """Sigma-point-like batches (every measured input moved both ways) of five
    rigs: the boat (two spacings), the drone, the trifilar (repeated swings)
    and the knife-edge plate (a neutral mode)."""
    from bifilar.estimation.sensitivity import measured_inputs, perturb

    from test_point_cost import _scene

    rng = np.random.default_rng(2028)
    for name, params in (("solar_boat", {"spacing": 3.0}), ("solar_boat", {"spacing": 1.5, "length": 3.5}),
                         ("drone_parallel", {}), ("trifilar_kth", {}), ("thesis_plate_rest", {})):
        base = _scene(name, params)
        yield name, [perturb(base, nm, s * float(rng.normal()) * 3e-3) for nm in measured_inputs(base) for s in (1, -1)]


def _poses_and_modes(scenes):
    from bifilar.analysis import batch_rest as br
    from bifilar.analysis.batch import rest_poses

    geo: list = []
    rests = rest_poses(scenes, errors="return", geometry=geo)
    good = [q for q, r in enumerate(rests) if not isinstance(r, Exception)]
    sc, rs = [scenes[q] for q in good], [rests[q] for q in good]
    out = [(type(r).__name__, str(r)) if isinstance(r, Exception) else
           (_bits(r.com), _bits(r.R), _bits(r.tensions), _bits(r.wire_vectors), r.kkt_residual) for r in rests]
    for lazy in (False, True):
        out += [(m.label, m.period, _bits(m.shape)) for ms in br.modes_batch(sc, rs, lazy, geometry=geo[0])
                for m in ms.modes]
    return out


def _no_tensions_geometry(monkeypatch):
    """modes_batch's path before: the tensions read from the poses (a BatchGeometry without them)."""
    from bifilar.analysis import batch_rest as br

    class NoTensions(br.BatchGeometry):
        def __init__(self, *a):
            super().__init__(*a[:11])

    monkeypatch.setattr(br, "BatchGeometry", NoTensions)


def test_tensions_from_the_batch_geometry_change_nothing(monkeypatch):
    from bifilar.analysis import batch_rest as br

    used: list = []
    real = br.modes_batch

    def counted(scenes, rests, lazy=False, *, geometry=None):
        used.append(geometry is not None and geometry.T is not None and geometry.matches(scenes, rests))
        return real(scenes, rests, lazy, geometry=geometry)

    monkeypatch.setattr(br, "modes_batch", counted)
    got = {name: _poses_and_modes(scenes) for name, scenes in _sigma_batches()}
    assert sum(used) >= 8  # taken (lazy and eager) on the batches whose poses all came from their Newton run
    _no_tensions_geometry(monkeypatch)
    ref = {name: _poses_and_modes(scenes) for name, scenes in _sigma_batches()}
    assert got == ref
