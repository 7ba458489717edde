"""The uncertainty budget's second order: sigma points of each measured
input, their re-solved estimates, the quadratic (and, for pairs, biquadratic)
surrogate of the estimate's error, and :class:`BudgetContext`, what the step
needs from the linear budget (:mod:`bifilar.estimation.budget`).  SI units.

Second order (docs/invert.md, "Where the linear budget is wrong")
-----------------------------------------------------------------
Each measured input ``x_j`` (standard uncertainty ``s_j``) is moved to the
two sigma points ``x_j +- sqrt(3) s_j`` (the three-point Gauss-Hermite rule
of the unscented transform with ``kappa = 3 - n``), the rest pose found
again (global search allowed, so a body that tilts is followed), the
measured modes tracked by MAC, and the unknowns re-solved so that the
periods are unchanged (Gauss-Newton steps on ``T^2``, nearly linear in an
inertia).  With ``p_+-`` the two re-solved estimates, the error of the
estimate due to input ``j`` is modelled by the quadratic through the three
points, ``q_j(z) = a_j z + b_j z^2`` with ``z ~ N(0, 1)``,

    a_j = (p_+ - p_-) / (2 sqrt 3),   b_j = (p_+ + p_- - 2 p) / 6,

whose mean is ``b_j`` and whose variance is ``a_j^2 + 2 b_j^2`` (exact for a
quadratic response).  When every input is linear enough (the second-order
std differs from the linear one by < 2 % and the offsets are < 10 % of the
std) the linear budget is kept unchanged; otherwise each input's
contribution becomes ``(a_j, sqrt(2) b_j)`` and the mean offset ``sum b_j``
is carried as a term of its own, so the printed std is the RMS distance of
the truth from the estimate.  Each input so flagged is then paired with
every other input: four more re-solved corners ``(+-h, +-h)`` make a 3 x 3
grid through which the biquadratic in ``(z_i, z_j)`` is exact, and its
interactions (``z_i z_j``, ``z_i^2 z_j``, ``z_i z_j^2``, ``z_i^2 z_j^2``:
the wheel's sideways CoM times the attachments' y errors and times the
CoM depth's) enter the budget in orthonormal Hermite terms
(:func:`_pair_terms`).  The 95 % interval holds both the symmetrised
model (a truth at the response's extremum reverses the skew) and the
model's own equal tails (a skewed monotone response; :func:`interval_95`).
Inputs whose sigma points cannot hang at all
(a knife-edge: the CoM exactly on the attachment line) are *degenerate*
and returned to the caller, which lists them; a scene with a neutral mode
gets no sigma points at all (each would need the slow global rest-pose
search; docs/invert.md, "Degenerate scenes", for what is still open).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import BifilarError
from ..scene import scene_with
from .measurements import COM_UNKNOWNS
from .problem import Problem
from .sensitivity import mac_match, mac_matches, n_modes, perturb
from .uncertainty import LinearBudget, covariance_of


#: sigma points at +- sqrt(3) standard uncertainties (3-point Gauss-Hermite)
SIGMA_POINT = math.sqrt(3.0)
#: keep the linear budget when the second-order std differs by less than this (relative)
LINEAR_ENOUGH = 0.02
#: and every mean offset is below this fraction of the std
OFFSET_ENOUGH = 0.1


@dataclass
class BudgetContext:
    """What the second-order step needs from the linear budget."""

    inputs: list                     # input keys in the budget
    sigmas: dict                     # key -> standard uncertainty (SI)
    G: np.ndarray                    # (P, K) gain matrix
    T_hat: np.ndarray                # (K,) model periods at the estimate (r T_lin)
    degenerate: list                 # keys without a derivative
    scenes: list                     # per hanging, the scene at the estimate
    rests: list
    modes: list
    match: list                      # per hanging, base mode k -> index in modes
    nonlinear: list = field(default_factory=list)   # keys treated to second order
    surrogate: dict = field(default_factory=dict)   # key -> (a, b) of the quadratic
    cross: dict = field(default_factory=dict)       # (key_i, key_j) -> (k11, k21, k12, k22)
    amplitude: dict = field(default_factory=dict)   # label -> D (P,): truth - p at A_max
    #: label -> its AmplitudeLaw over 0 .. A_max: the truth is p + D w(A), w = (r(A) - 1) / (r(A_max) - 1)
    amplitude_law: dict = field(default_factory=dict)
    #: results shared by budgets of the same scenes (several unknowns at one truth):
    #: input sensitivities and sigma points' periods, keyed by the scene's arrays
    cache: dict | None = None
    #: input key -> (P,) what the amplitude factor's dependences (``dr/dx``, ``dr/dp`` in the gain) add to
    #: the input's linear term (nonlinear method; :func:`_with_factor_gain`), added to the sigma points'
    #: linear coefficient (re-solved with the factor held at the estimate's)
    factor_shift: dict = field(default_factory=dict)
    gain: np.ndarray | None = None   # (P, K) the full derivative's gain (nonlinear: with T_lin dr/dp), else G
    prior: object = None             # the components not solved for (prior_inertia.PriorInertia), if computed
    #: (K, P) d T_lin / d p of the measured modes at the estimate (s per SI unit; before the amplitude
    #: factor r): the budget's, reused by the fit check's leverages (fit_check.leverages)
    jacobian: np.ndarray | None = None


def scene_key(scene) -> tuple:
    """A hashable key of every array of ``scene`` (equal keys: the same scene)."""
    key = (float(scene.mass), float(scene.gravity), np.asarray(scene.lengths, float).tobytes(),
           np.asarray(scene.anchors, float).tobytes(), np.asarray(scene.attachments, float).tobytes(),
           np.asarray(scene.inertia, float).tobytes())
    # the wires' EA too where stated: a stiffness sigma point differs from its base only there
    return key if getattr(scene, "stiffness", None) is None else key + (np.asarray(scene.stiffness, float).tobytes(),)


def _key_hanging(pb: Problem, key: str) -> list:
    """Indices of the hangings an input key affects."""
    if key.startswith("com.") or key in ("mass", "gravity", "stiffness"):
        return list(range(len(pb.models)))
    return pb.links.hangings(key)


def _perturbed_scene(pb: Problem, h: int, scene, moves):
    """Hanging ``h``'s ``scene`` with each input ``key`` of ``moves``
    [(key, d), ...] changed by ``d`` (SI; a ``com.*`` key is a shift in the
    reference body frame; a rig or attachment key moves this hanging's
    inputs it stands for, :class:`~bifilar.estimation.rig.RigLinks`, and
    nothing in a hanging it does not act on)."""
    for key, d in moves:
        if key.startswith("com."):
            v = np.zeros(3)
            v["xyz".index(key[-1])] = d
            scene = scene_with(scene, attachments=scene.attachments - (pb.models[h].R @ v)[None, :])
        elif key in ("mass", "gravity", "stiffness"):
            scene = perturb(scene, key, d)
        else:
            for n, c in pb.links.moves(key, h):
                scene = perturb(scene, n, c * d)
    return scene


def _hanging_periods(scenes, rest, base_modes, rests=None, geo=None, mss=None) -> list:
    """(periods, scene, rest, modes, col) of each scene, ``col`` the index of
    each of ``base_modes`` in its modes (MAC); rest poses by the batched
    Newton from the start pose, where that is not accepted from ``rest``
    (the base scene's pose: ``rest_poses``' ``near``), the global search
    where neither is; None where the scene cannot hang.  Batched engine.
    ``rests``, ``geo``: the scenes' rest poses (a pose, an exception, or
    :data:`SKIPPED`: not needed, None here) and batch geometry if already
    computed (:func:`_solve_points`); ``mss``: the mode sets of all the
    scenes if already computed (a batch shared with other sweep points,
    :func:`~bifilar.analysis.shared_batch.shared`: every pose given)."""
    from ..analysis.batch import modes_batch, rest_poses
    from .montecarlo import _modes_or_none

    if rests is None:
        geo = []  # the batch's final-pose arrays, handed to modes_batch (the same numbers, computed once)
        rests = rest_poses(scenes, rest, errors="return", geometry=geo, near=rest)
    good = [q for q, r in enumerate(rests) if r is not SKIPPED and not isinstance(r, BaseException)]
    out: list = [None] * len(scenes)
    if not good:
        return out
    # lazy: most sigma points need only their periods and shapes (the Mode objects when _resolve reads them)
    if mss is None:
        mss = _modes_or_none(lambda s, r: modes_batch(s, r, lazy=True, geometry=geo[0] if geo else None),
                             [scenes[q] for q in good], [rests[q] for q in good])
    kept = [(q, ms) for q, ms in zip(good, mss) if ms is not None and n_modes(ms) == len(base_modes.modes)]
    for (q, ms), col in zip(kept, mac_matches(base_modes, [ms for _, ms in kept])):
        P = getattr(ms, "periods", None)  # a LazyModeSet's (all finite: no neutral mode)
        T = P[col] if P is not None else np.array([ms.modes[c].period or np.nan for c in col])
        out[q] = (T, scenes[q], rests[q], ms, col)
    return out


#: a sigma point's rest pose :func:`_settle` did not decide: its point fails whatever it is
SKIPPED = object()


def _settle(points: dict, jobs: dict, rests: dict, res: dict) -> None:
    """Decide the rest poses ``rest_poses(..., defer=True)`` left to
    ``rest_pose`` (its global search, ~7 ms each), ``rests`` {hanging:
    entries of ``jobs[hanging]``} in place, in the order of ``points``;
    except that of a point already known to fail (a hanging of it cannot
    hang, here or in ``res``, the cached results) or the other sigma point
    of its input, ``(key, -s)`` of ``(key, s)``: :func:`second_order` fails
    the input whichever that verdict is, so it is never read (:data:`SKIPPED`)."""
    from ..analysis.batch_rest import Deferred

    if not any(isinstance(r, Deferred) for rs in rests.values() for r in rs):
        return  # nothing deferred (the common case): no verdict to decide, none to skip
    failed = {pid for pid, hits in res.items() if None in hits.values()}
    pending = []
    order = {pid: n for n, pid in enumerate(points)}
    for h, rs in rests.items():
        for q, ((pid, _, _), r) in enumerate(zip(jobs[h], rs)):
            if isinstance(r, BaseException):
                failed.add(pid)
            elif isinstance(r, Deferred):
                pending.append((order[pid], h, q, pid))
    for _, h, q, pid in sorted(pending):
        sib = (pid[0], -pid[1]) if len(pid) == 2 and pid[1] in (1, -1) and (pid[0], -pid[1]) in points else None
        if pid in failed or sib in failed:
            rests[h][q] = SKIPPED
            continue
        rests[h][q] = rests[h][q].settle("return")
        if isinstance(rests[h][q], BaseException):
            failed.add(pid)


def _resolve(pb: Problem, ctx: BudgetContext, p_hat, r_hat, moves, hits: dict):
    """Unknowns that keep every model period at the estimate's value with
    the inputs of ``moves`` [(key, d), ...] changed: Gauss-Newton steps on ``T^2`` (nearly
    linear in an inertia) with the gain matrix; the rest pose of the
    perturbed geometry is reused while only the inertia changes.  ``hits``:
    {hanging: (T, scene, rest, modes, col)} at the estimate; None if a
    period is lost on the way."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes

    T = ctx.T_hat.copy()
    com_unknown = any(n in COM_UNKNOWNS for n in pb.unknowns)

    def fill(h, ms, col):
        for k, m in enumerate(pb.measurements):
            if m.hanging == h:
                T[k] = r_hat[k] * (ms.modes[col[ctx.match[h][pb.mode_index[k]]]].period or np.nan)

    for h, (_, _, _, ms, col) in hits.items():
        fill(h, ms, col)
    p = np.asarray(p_hat, float).copy()
    sc = None
    for _ in range(8):
        if not np.all(np.isfinite(T)):
            return None
        small = np.max(np.abs(T / ctx.T_hat - 1)) < 1e-2  # one step on T^2: error ~(dT/T)^2 of the step
        step = ctx.G @ ((ctx.T_hat ** 2 - T ** 2) / (2 * ctx.T_hat))
        p = p + step
        if small:
            return p
        sc = pb.scales() if sc is None else sc
        if np.max(np.abs(step) / sc) < 1e-10:
            return p
        vals = pb.values(p)
        for h, (_, _, rest, ms0, col) in hits.items():
            scene = _perturbed_scene(pb, h, pb.models[h].scene(vals), moves)
            try:
                # a moved CoM moves the rest pose: found from rest_pose's start pose (a guess is read only with
                # local_only, which would follow this step's branch instead; none of test_invert.py's 70
                # re-solves nor any sweep point, whose unknowns are inertias, comes here: perf26b)
                r = rest_pose(scene) if com_unknown else rest
                ms = linear_modes(scene, r)
            except (BifilarError, np.linalg.LinAlgError):  # a step past definiteness (a body near its limit)
                return None
            c2 = mac_match(ms0, ms)
            fill(h, ms, c2[col])
    return p if np.all(np.isfinite(T)) else None


def _solve_points(pb: Problem, ctx: BudgetContext, p_hat, r_hat, points: dict) -> dict:
    """Re-solved unknowns (P,) at each point {id: [(key, d), ...]} of moved
    inputs (:func:`_resolve`), None where a hanging cannot hang or a period
    is lost; the perturbed scenes of each hanging in one batch, the rest
    poses it leaves to the global search only where their verdict is read
    (:func:`_settle`)."""
    jobs: dict[int, list] = {h: [] for h in range(len(pb.models))}
    res: dict = {pid: {} for pid in points}
    cache = ctx.cache
    skeys = [scene_key(s) for s in ctx.scenes] if cache is not None else None
    measured = {m.hanging for m in pb.measurements}
    hangs: dict = {}  # input key -> the measured hangings it affects (the same for every point)
    for pid, moves in points.items():
        for key, _ in moves:
            if key not in hangs:
                hangs[key] = [h for h in _key_hanging(pb, key) if h in measured]
        for h in (hangs[moves[0][0]] if len(moves) == 1 else sorted({h for key, _ in moves for h in hangs[key]})):
            ck = ("sigma point", skeys[h], tuple(moves)) if cache is not None else None
            if ck is not None and ck in cache:
                res[pid][h] = cache[ck]
            else:
                jobs[h].append((pid, _perturbed_scene(pb, h, ctx.scenes[h], moves), ck))
    from ..analysis.batch import rest_poses
    from ..analysis.shared_batch import shared

    rests, geos, mss = {}, {}, {}
    busy = [h for h, jl in jobs.items() if jl]
    # one hanging's scenes: solved in a batch shared with other sweep points where there is one (the same numbers)
    both = shared("sigma points", [j[1] for j in jobs[busy[0]]]) if len(busy) == 1 else None
    if both is not None:
        rests[busy[0]], mss[busy[0]] = both
        geos[busy[0]] = None
    for h, jl in jobs.items():
        if jl and h not in rests:
            geos[h] = []
            rests[h] = rest_poses([j[1] for j in jl], ctx.rests[h], errors="return", geometry=geos[h],
                                  near=ctx.rests[h], defer=True)
    _settle(points, jobs, rests, res)
    for h, rs in rests.items():
        jl = jobs[h]
        outs = _hanging_periods([j[1] for j in jl], ctx.rests[h], ctx.modes[h], rs, geos[h], mss.get(h))
        for (pid, _, ck), o, r in zip(jl, outs, rs):
            res[pid][h] = o
            if ck is not None and r is not SKIPPED:
                cache[ck] = o
    whole = {pid: hits for pid, hits in res.items() if None not in hits.values()}  # (hits: tuples or None)
    done = _one_step(pb, ctx, p_hat, r_hat, whole)
    return {pid: (done[pid] if pid in done else _resolve(pb, ctx, p_hat, r_hat, points[pid], hits))
            if pid in whole else None for pid, hits in res.items()}


def _one_step(pb: Problem, ctx: BudgetContext, p_hat, r_hat, hits_of: dict) -> dict:
    """{point id: re-solved unknowns} for the points of ``hits_of`` ({id:
    hits of :func:`_resolve`}) that :func:`_resolve` settles in its first
    Gauss-Newton step (every period finite and within 1e-2 of the
    estimate's: the common case), that step for all of them at once with
    the same arithmetic (elementwise, then ``G @`` per point); the others
    are left out, for :func:`_resolve`."""
    pids = list(hits_of)
    if not pids:
        return {}
    T = np.tile(np.asarray(ctx.T_hat, float), (len(pids), 1))
    r = np.asarray(r_hat, float)
    for h in sorted({h for hits in hits_of.values() for h in hits}):
        ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
        idx = [ctx.match[h][pb.mode_index[k]] for k in ks]
        rows = [q for q, pid in enumerate(pids) if h in hits_of[pid]]
        # each row's periods (every one in the base modes' order, as long) stacked, then the measured columns:
        # the same numbers as each row's own ``T[idx]``
        T[np.ix_(rows, ks)] = r[ks] * np.array([hits_of[pids[q]][h][0] for q in rows])[:, idx]
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(T), axis=1) & (np.max(np.abs(T / ctx.T_hat - 1), axis=1) < 1e-2)
    inc = (ctx.T_hat ** 2 - T ** 2) / (2 * ctx.T_hat)
    p0 = np.asarray(p_hat, float)
    G = np.asarray(ctx.G, float)
    if G.shape[1] == 1:
        # one period: G @ inc[q] is one product per unknown (exactly rounded whatever computes it),
        # so all points' steps at once are the same numbers
        steps = p0 + inc[:, :1] * G[:, 0]
        return {pids[q]: steps[q] for q in np.nonzero(ok)[0].tolist()}
    return {pids[q]: p0 + G @ inc[q] for q in np.nonzero(ok)[0]}


def _coefs3(vm, v0, vp):
    """(constant, linear, quadratic) coefficients in ``z`` of the quadratic
    through values at ``z = -h, 0, +h`` (h = :data:`SIGMA_POINT`)."""
    h = SIGMA_POINT
    return v0, (vp - vm) / (2 * h), (vp + vm - 2 * v0) / (2 * h * h)


def _pair_terms(pb: Problem, ctx: BudgetContext, p_hat, r_hat, sol: dict, contrib: dict, std1) -> np.ndarray:
    """Interactions of each flagged input ``i`` (``ctx.nonlinear``) with
    every other input ``j``: the re-solved unknowns at the four corners
    ``(+-h, +-h)`` complete, with the sigma points ``sol`` and the estimate,
    a 3 x 3 grid in ``(z_i, z_j)``, through which the biquadratic
    ``sum_{p,q<=2} k_pq z_i^p z_j^q`` is exact.  Its interaction part
    ``k11 z_i z_j + k21 z_i^2 z_j + k12 z_i z_j^2 + k22 z_i^2 z_j^2`` is
    stored in ``ctx.cross`` and entered in ``contrib`` in orthonormal
    Hermite terms (``z``, ``(z^2 - 1)/sqrt 2`` and their products are
    uncorrelated, so the variance is the sum of the squared coefficients):
    ``k21`` adds to ``j``'s linear term, ``k12`` to ``i``'s, ``sqrt 2 k22``
    to both quadratic terms, and ``k11``, ``sqrt 2 k21``, ``sqrt 2 k12``,
    ``2 k22`` are terms of their own (listed where > 0.1 % of the std).
    Returns the added mean offset, ``sum k22``.  A pair with a corner that
    cannot hang is left out (the per-input terms stand)."""
    flagged = list(ctx.nonlinear)
    pairs = [(ki, kj) for n, ki in enumerate(flagged) for kj in ctx.surrogate
             if kj != ki and not (kj in flagged and flagged.index(kj) < n)]
    h = SIGMA_POINT
    corners = _solve_points(pb, ctx, p_hat, r_hat,
                            {(ki, kj, si, sj): [(ki, si * h * ctx.sigmas[ki]), (kj, sj * h * ctx.sigmas[kj])]
                             for ki, kj in pairs for si in (1, -1) for sj in (1, -1)})
    p0 = np.asarray(p_hat, float)
    offset = np.zeros(len(p0))
    r2 = math.sqrt(2)
    for ki, kj in pairs:
        F = {(si, sj): corners[(ki, kj, si, sj)] for si in (1, -1) for sj in (1, -1)}
        if any(v is None for v in F.values()):
            continue
        F.update({(1, 0): sol[(ki, 1)], (-1, 0): sol[(ki, -1)], (0, 1): sol[(kj, 1)], (0, -1): sol[(kj, -1)],
                  (0, 0): p0})
        # coefficients in z_i at z_j = -h, 0, +h, then each in z_j
        rows = [_coefs3(F[(-1, sj)], F[(0, sj)], F[(1, sj)]) for sj in (-1, 0, 1)]
        k = [_coefs3(rows[0][pp], rows[1][pp], rows[2][pp]) for pp in range(3)]  # k[p][q]
        k11, k21, k12, k22 = k[1][1], k[2][1], k[1][2], k[2][2]
        ctx.cross[(ki, kj)] = (k11, k21, k12, k22)
        contrib[kj] = contrib[kj] + k21
        contrib[ki] = contrib[ki] + k12
        contrib[f"{ki} (2nd order)"] = contrib[f"{ki} (2nd order)"] + r2 * k22
        contrib[f"{kj} (2nd order)"] = contrib[f"{kj} (2nd order)"] + r2 * k22
        offset = offset + k22
        for name, c in ((f"{ki} x {kj}", k11), (f"{ki}^2 x {kj}", r2 * k21),
                        (f"{ki} x {kj}^2", r2 * k12), (f"{ki}^2 x {kj}^2", 2 * k22)):
            if np.any(np.abs(c) > 1e-3 * std1):
                contrib[f"{name} (2nd order)"] = c
    return offset


def _sequential_sum(rows: np.ndarray) -> np.ndarray:
    """(P,) ``rows`` (n, P) added in order from zeros, ``((0 + r_0) + r_1) + ...``:
    the sums a Python loop ``acc = acc + r`` (or ``sum(rows, zeros)``)
    forms, the same bits (an accumulate is sequential by definition, where
    ``rows.sum(axis=0)`` may add pairwise)."""
    return np.add.accumulate(np.concatenate([np.zeros((1,) + rows.shape[1:]), rows]), axis=0)[-1]


def _surrogates(pp: list, pm: list, p0: np.ndarray, shift: list, P: int):
    """(a (n, P), b (n, P), sum of b in order (P,)) of :func:`second_order`'s
    quadratics of n inputs from their re-solved sigma points ``pp``, ``pm``
    ((P,) each), the estimate ``p0`` and each input's ``factor_shift`` (a
    (P,) array or 0.0): ``a = (p_+ - p_-) / (2 sqrt 3) + shift``, ``b = (p_+ +
    p_- - 2 p) / 6``, each input's row the numbers of that expression on
    its own arrays (elementwise), computed for all rows at once."""
    if not pp:
        return np.zeros((0, P)), np.zeros((0, P)), np.zeros(P)
    PP, PM = np.array(pp, float).reshape(-1, P), np.array(pm, float).reshape(-1, P)
    S = np.zeros(PP.shape)  # (x + 0.0 is x + 0.0 whether the 0.0 is a float or an array's)
    for n, x in enumerate(shift):
        if not (isinstance(x, float) and x == 0.0 and math.copysign(1.0, x) > 0):
            S[n] = x
    a = (PP - PM) / (2 * SIGMA_POINT) + S
    b = (PP + PM - 2 * p0) / 6
    return a, b, _sequential_sum(b)


def _sum_of_squares(values, P: int) -> np.ndarray:
    """(P,) ``sum(c ** 2 for c in values)`` from zeros in order (the same
    bits as that loop), the squares of all (P,) terms at once; a term of
    another shape (a scalar) by the loop."""
    vals = list(values)
    try:
        X = np.array(vals, float)
    except ValueError:  # terms of different shapes
        X = None
    if X is not None and X.shape == (len(vals), P):
        return _sequential_sum(X ** 2)
    return sum((np.asarray(c) ** 2 for c in vals), np.zeros(P))


def second_order(pb: Problem, p_hat, r_hat, ctx: BudgetContext, lin: LinearBudget) -> tuple[LinearBudget, list]:
    """The sigma-point check of the linear budget (module docstring), and
    the unstated-amplitude terms of ``ctx.amplitude``.

    Returns the budget to report (the linear contributions when every input
    is linear enough) and the keys whose sigma points cannot hang (to be
    budgeted by the targeted Monte Carlo).  Fills ``ctx.surrogate`` and
    ``ctx.nonlinear``."""
    keys = [k for k in ctx.inputs if ctx.sigmas.get(k, 0) > 0]
    if any(any(m.period is None for m in ms.modes) for ms in ctx.modes):
        # a neutral mode (knife edge): sigma points would need the slow global
        # rest-pose search; not treated yet (TODO issue 10, docs/invert.md)
        keys = []
    h_ = SIGMA_POINT
    sol = _solve_points(pb, ctx, p_hat, r_hat, {(key, sgn): [(key, sgn * h_ * ctx.sigmas[key])]
                                                for key in keys for sgn in (1, -1)})
    p0 = np.asarray(p_hat, float)
    failed = [key for key in keys if sol[(key, 1)] is None or sol[(key, -1)] is None]
    good = [key for key in keys if key not in set(failed)] if failed else keys
    P = len(pb.unknowns)
    # every input's quadratic at once: the same elementwise arithmetic on stacked rows (:func:`_surrogates`)
    a_all, b_all, offset = _surrogates([sol[(key, 1)] for key in good], [sol[(key, -1)] for key in good], p0,
                                       [ctx.factor_shift.get(key, 0.0) for key in good], P)
    surrogate = {key: (a_all[n], b_all[n]) for n, key in enumerate(good)}
    std1 = lin.std
    contrib = {k: v for k, v in lin.contributions.items() if k not in surrogate}
    sb_all = math.sqrt(2) * b_all
    for n, key in enumerate(good):
        contrib[key] = a_all[n]
        contrib[f"{key} (2nd order)"] = sb_all[n]
    var2 = _sum_of_squares(contrib.values(), P) + offset ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        change = np.abs(np.sqrt(var2) / std1 - 1)
        off_rel = np.abs(offset) / std1
    ctx.cross = {}
    if np.all(change < LINEAR_ENOUGH) and np.all(off_rel < OFFSET_ENOUGH):
        contrib, offset = dict(lin.contributions), np.zeros(len(offset))
        ctx.surrogate = {}
    else:
        ctx.surrogate = surrogate
        ctx.nonlinear = [k for k, (a, b) in surrogate.items()
                         if np.any(math.sqrt(2) * np.abs(b) > 0.05 * std1)
                         or np.any(np.abs(a - lin.contributions.get(k, a)) > 0.05 * std1)]
        offset = offset + _pair_terms(pb, ctx, p_hat, r_hat, sol, contrib, std1)
    if not ctx.surrogate and not ctx.amplitude:
        return lin, failed
    for lab, D in ctx.amplitude.items():
        mean_w, std_w = _release_moments(ctx, lab)
        contrib[f"amplitude[{lab}]"] = D * std_w
        offset = offset + D * mean_w
    if np.any(offset):
        contrib["offset"] = offset
    cov = covariance_of(contrib, len(lin.names))
    return LinearBudget(list(lin.names), cov, contrib, dict(lin.sigmas), dict(lin.dof)), failed


def _release_moments(ctx: BudgetContext, lab: str) -> tuple[float, float]:
    """(mean, std) of the unstated release's weight ``w`` of ``lab``: its
    amplitude law's, or a quadratic law's (1/3, 2/sqrt(45)) for a context
    built without one."""
    law = ctx.amplitude_law.get(lab)
    return law.release_moments() if law is not None else (1.0 / 3.0, math.sqrt(4.0 / 45.0))
