"""Plan the experiment: the configuration that minimises the predicted
inertia uncertainty subject to the constraints (``bifilar plan``).

The search is over continuous parameters (dotted config paths or shorthands
of :mod:`bifilar.studies.shorthands`, each within ``[lo, hi]``):

1. a coarse grid (9 points for one parameter, 6 x 6 for two, 4^3, then 3^d)
   evaluated by the sweep engine (:func:`bifilar.studies.sweep.run_sweep`,
   so ``workers`` apply);
2. bounded local minimisation of the objective with an exterior penalty
   (continuous at the edge of the feasible set, so the optimum may sit on a
   constraint: it usually does, the uncertainty falls as the wires tilt
   while the tension rises): Nelder-Mead in the unit box from the three
   best grid points (several parameters: mode crossings cut the feasible
   set into islands), then Brent's method along each parameter within its
   bracketing grid cells.  Without a target the worst of the components is
   smoothed (a 16-norm) for the search.

The answer is the best feasible point evaluated, so it is never worse than
the grid.

Screens and confirmation (issue 14).  Both steps evaluate *screens*
(:func:`~bifilar.studies.point.evaluate_point` with ``screen=True``: each
component's linear sigma, no estimator biases; the grid's nonlinear runs in
one batch; the local search's without nonlinear runs when there is no
tension or depth limit and every grid point's wires keep half their rest
tension, :func:`_far_from_limits`, and the stated amplitude's own
uncertainty changes no grid point's objective by 2 % or more,
:func:`_amplitude_negligible`; the search then ranks every point by its
small-amplitude sigma, ``invert --amplitude 0``'s, since a screen without a
run has no amplitude factor).  The best :data:`CONFIRM` feasible
screens are then evaluated in full (the honest second-order sigma, the
nonlinear runs, the biases); when a full figure equals its screen's (the
small-amplitude sigmas compared: the linear budget holds, as it does
wherever the CoM is not shallow; the amplitude's term depends on the run,
batched or not, in the last bits) the
search path was the full one's, and the answer is the same.  Otherwise
(second order matters, or the confirmed point goes slack) the whole search
is run again on full points, as before.  The answer is ranked by the full
sigma, the stated amplitude's uncertainty included.

The objective is the relative standard uncertainty of ``target`` (or the
worst of the *measurable* components: those identifiable at some point of
the coarse grid and not set aside, :func:`~bifilar.studies.ranking.set_aside`:
a component whose best relative sigma exceeds
:data:`~bifilar.studies.ranking.USEFUL_REL` on the grid first gets a search
of its own sigma, and is set aside only where that too stays above) at a
point, exactly as the sweep ranks points; a target
no point can measure is refused with its remedy
(:mod:`bifilar.studies.remedy`).  With ``zip_`` the parameters move
together, each the same fraction of its range (one search variable).
When ``lengths_available`` is given and a wire length is a search
parameter, that parameter is searched over the available lengths within its
bounds (discrete) and the others continuously for each of them.

With ``hangings`` (``plan --hangings``: the multi-hanging plan is what is
timed) and no point whose own hanging meets ``min_separation`` (the
degenerate swings of a symmetric trifilar), the search is run again without
that guard and the points it evaluated are ranked by their multi-hanging
plan (:func:`~bifilar.studies.hangings.hangings_objective`), which applies the guard to every mode it
times (``separation_guard`` ``"multi_hanging"``).

Deterministic: no random numbers, so the same inputs give the same plan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from ..errors import InputError
from .ranking import (aside_under_hangings, clashes, guard_limits, guarded_limits, identifiable_components, marginal,
                      measurable_components, point_separation, rank_order, rel_sigma, set_aside, tension_range_caution)
from .recommend import cautioned, choose, identifiabilities, preference, target_label
from .sweep import (Constraints, SweepSettings, binding_constraint, evaluate_point, objective, run_sweep,
                    violations)

_GRID = {1: 9, 2: 6, 3: 4}
STARTS = 3  # local searches from the best grid points (d > 1)
CONFIRM = 2  # the best feasible screens re-evaluated in full (their figures must not change)
#: a screen of the local search runs no nonlinear motion when every grid point's
#: wires keep this fraction of their rest tension during the excitation
SLACK_MARGIN = 0.5


@dataclass
class PlanResult:
    """Outcome of :func:`plan`.

    best : the point dict of the optimum (see :mod:`bifilar.studies.sweep`).
    evaluated : every point evaluated (grid first, then the local search).
    active : constraints within 1 % of their limit at the optimum.
    among : the measurable components (identifiable somewhere in the range);
        without a target the worst of them is minimised.
    zip : the parameters moved together (one search variable).
    separation_guard : where ``constraints.min_separation`` applies:
        ``"planned_hanging"`` (the timed modes of the planned point's own
        hanging) or ``"multi_hanging"`` (left to the multi-hanging plan's
        timed modes, :func:`plan` with ``hangings``).
    hangings_objective : with ``hangings`` (:func:`plan`), the
        objective of the optimum's multi-hanging plan (its joint sigma), by
        which the points were ranked (``best["objective"]`` stays the
        planned hanging's own).
    hangings_ranked : with ``hangings``, how many feasible points were
        ranked by their multi-hanging plan (the points the search
        evaluated; :meth:`hangings_note`).
    preferred_over : evaluated points ranked after the optimum although
        their objective is lower: [{params, objective, reason}], ``reason``
        ``tension_range_caution`` (their dependent wires may carry more than
        ``--max-tension``; within :data:`~bifilar.studies.ranking.EQUAL_REL`),
        ``ceiling_clash`` or ``wires_cross`` (their body reaches above the
        ceiling or their wires cross at rest: after every clean point;
        :func:`~bifilar.studies.ranking.rank_order`); ``preference`` the
        lines saying so, joined by "; " (None: none).
    """

    best: dict
    evaluated: list[dict]
    target: str | None
    constraints: Constraints
    bounds: list[tuple[str, float, float]]
    active: list[str] = field(default_factory=list)
    among: list[str] = field(default_factory=list)
    zip: bool = False
    set_aside: list[dict] = field(default_factory=list)
    separation_guard: str = "planned_hanging"
    hangings_objective: float | None = None
    hangings_ranked: int | None = None
    preferred_over: list[dict] = field(default_factory=list)
    preference: str | None = None

    def hangings_note(self) -> str | None:
        """With ``hangings``: what the answer's multi-hanging figure is the
        best of.  The search is steered by each point's own hanging, and
        the multi-hanging objective is rugged (the chosen hangings and modes
        change between neighbouring points: 0.45 % beside 1.6 % on the
        session-11 audit's trifilar), so a point it never evaluated can do
        better: a direct search of that objective there found 0.4420 %
        against the plan's 0.4424 % (docs/design.md, "Joint sigma, session
        12"; it would cost about 20 more hangings plans)."""
        if self.hangings_objective is None:
            return None
        return (f"the best multi-hanging plan of the {self.hangings_ranked} feasible points the search evaluated "
                "(steered by each point's own hanging); the multi-hanging figure itself was not searched, so a "
                "point between them may do slightly better")

    def accuracy(self) -> dict:
        """Predicted accuracy per component at the optimum (kg m^2, relative, mode, period s)."""
        out = {}
        for c, e in self.best["components"].items():
            out[c] = {"value": e["value"], "sigma": e.get("sigma"), "rel_sigma": e.get("rel_sigma"),
                      "mode": e.get("mode"), "period": e.get("period"), "identifiable": e["identifiable"],
                      "bias": e.get("bias")}
        return out

    def to_json(self) -> dict:
        b = self.best
        return {
            "optimum": {"params": b["params"], "objective": b["objective"], "accuracy": self.accuracy(),
                        "tension": b["tension"], "depth": b["depth"], "periods": b["periods"],
                        "rig": b.get("rig"), "separation": point_separation(b, self.among),
                        "tension_range_caution": tension_range_caution(b, self.constraints),
                        "active_constraints": self.active, "hangings_objective": self.hangings_objective,
                        "hangings_ranked": self.hangings_ranked, "hangings_note": self.hangings_note(),
                        "preferred_over": self.preferred_over, "preference": self.preference,
                        **guard_limits(b, self.among)},
            "target": target_label(self.target, self.among, list(b["components"]), self.hangings_objective is not None),
            "identifiability": self.identifiability(),
            "set_aside": self.set_aside,
            "marginal": self.marginal(),
            "constraints": self.constraints.describe(),
            "bounds": {n: [lo, hi] for n, lo, hi in self.bounds},
            "zip": self.zip,
            "separation_guard": self.separation_guard,
            "evaluations": len(self.evaluated),
        }

    def identifiability(self) -> dict:
        """Per component: measurable in the range, modes at the optimum."""
        return identifiabilities(list(self.best["components"]), self.best, self.among, self.set_aside, self.marginal())

    def marginal(self) -> list[dict]:
        """The components ranked or set aside by a line they are close to
        (:func:`~bifilar.studies.ranking.marginal`, at the optimum)."""
        return marginal(self.best, self.among, self.set_aside, self.target)


def _is_length(name: str) -> bool:
    return name == "length" or (name.startswith("rig.lengths.") and name.count(".") == 2)


def _penalty(p: dict, c: Constraints, target: str | None, among=None, small_amplitude: bool = False) -> float:
    """Exterior penalty, continuous at the edge of the feasible set:
    feasible -> the relative uncertainty; infeasible -> that times
    (1 + 100 x the relative excess over each limit); invalid or not
    identifiable -> 1e6 (the optimum itself is always a feasible point);
    a point whose body reaches the ceiling or whose wires cross at rest
    (:func:`~bifilar.studies.ranking.clashes`) as one that breaks a limit by 100 %.
    ``small_amplitude``: of the small-amplitude sigmas (:func:`~bifilar.studies.ranking.rel_sigma`)."""
    if not p.get("valid"):
        return 1e6
    ob = objective(p, target, among, small_amplitude)
    if not math.isfinite(ob):
        return 1e6
    if target is None:  # the worst component, smoothed (a 16-norm) so that the simplex slides along the ridge
        sel = among if among is not None else list(p["components"])
        rel = np.array([rel_sigma(p["components"][k], small_amplitude) for k in sel], float)
        ob = float(np.sum(rel**16) ** (1 / 16))
    v = dict(violations(p, c, target, among))
    clash = clashes(p)  # ranked after every clean point (ranking.rank_order): the search is steered off it too
    if not v and not clash:
        return ob
    excess = 0.0
    g = guarded_limits(p, among)  # the runs of the counted modes (violations' figures)
    if "max_tension" in v and g["peak"] is not None:
        excess += g["peak"] / c.max_tension - 1
    if "max_depth" in v and g["depth"] is not None:
        excess += g["depth"] / c.max_depth - 1
    if "min_separation" in v and c.min_separation:
        excess += 1 - point_separation(p, among) / c.min_separation
    excess += 1.0 * ("slack" in v) + 1.0 * ("lengths_available" in v) + 1.0 * clash
    return ob * (1 + 100 * max(excess, 1e-6))


def plan(base_cfg: dict, source: str, bounds: list[tuple[str, float, float]], settings: SweepSettings,
         constraints: Constraints, target: str | None = None, *, workers: int = 1,
         progress: Callable[[int, int], None] | None = None, max_local: int | None = None,
         zip_: bool = False, hangings: bool = False) -> PlanResult:
    """Search ``bounds`` [(name, lo, hi)] for the feasible configuration with
    the smallest predicted relative uncertainty (see the module docstring).

    ``zip_``: move every parameter together, each the same fraction of its
    range (one search variable), e.g. ``spacing`` and ``ceiling_spacing``
    over the same range keep the wires parallel.

    ``hangings``: the experiment times the multi-hanging plan
    (:func:`bifilar.studies.hangings.plan_hangings`, which applies
    ``min_separation`` to each mode it times).  When no point's own hanging
    meets ``min_separation`` (e.g. the degenerate swings of a symmetric
    trifilar), the search is run again without that guard
    (``separation_guard`` ``"multi_hanging"``): the hangings plan at the
    optimum must then time only separated modes
    (:func:`bifilar.studies.hangings.check_separated`).  Where points meet
    it, the search is steered by the points' own figures, and the point it
    evaluated whose multi-hanging plan is the most accurate is the answer
    (``hangings_objective``; the guard left to that plan, as above, where
    the point's own hanging does not meet it), as a sweep with
    ``--hangings`` ranks them (:func:`bifilar.studies.recommend.assess`).

    Raises :class:`InputError` naming the binding constraint's flag (e.g.
    ``--max-tension``) when no evaluated configuration is feasible.
    """
    kw = dict(workers=workers, progress=progress, max_local=max_local, zip_=zip_)
    try:
        res = _plan(base_cfg, source, bounds, settings, constraints, target, **kw)
    except InputError as exc:
        if not (hangings and exc.field == "--min-separation"):
            raise
    else:
        if not hangings:
            return res
        relaxed = replace(constraints, min_separation=None)
        best, hob, n = _best_for_hangings(base_cfg, source, res, settings, relaxed, constraints.min_separation)
        if best is None:
            return res
        guard = "multi_hanging" if violations(best, constraints, res.target, res.among) else "planned_hanging"
        return replace(res, best=best, separation_guard=guard, active=_active(best, relaxed, bounds, res.among),
                       hangings_objective=hob, hangings_ranked=n, set_aside=aside_under_hangings(res.set_aside))
    relaxed = replace(constraints, min_separation=None)
    res = _plan(base_cfg, source, bounds, settings, relaxed, target, **kw)
    best, hob, n = _best_for_hangings(base_cfg, source, res, settings, relaxed, constraints.min_separation)
    best = best or res.best
    return replace(res, best=best, constraints=constraints, separation_guard="multi_hanging",
                   active=_active(best, relaxed, bounds, res.among), hangings_objective=hob, hangings_ranked=n,
                   set_aside=aside_under_hangings(res.set_aside) if hob is not None else res.set_aside)


def _best_for_hangings(base_cfg: dict, source: str, res: PlanResult, settings: SweepSettings,
                       relaxed: Constraints, min_separation: float | None) -> tuple[dict | None, float | None, int]:
    """Of the points the search without the separation guard evaluated
    (``relaxed``: feasible otherwise), the one whose multi-hanging plan
    (:func:`~bifilar.studies.hangings.hangings_objective`, ``min_separation`` applied to its timed
    modes) is the most accurate, evaluated in full (its ``objective`` the
    planned hanging's own, as without hangings), and that plan's
    objective, and how many points were ranked; (None, None, n) when no
    plan identifies every component
    (:func:`bifilar.studies.hangings.check_separated` then says why at
    ``res.best``)."""
    target, among = res.target, res.among
    cands = [p for p in res.evaluated if p.get("valid") and not violations(p, relaxed, target, among)
             and math.isfinite(objective(p, target, among))]
    from .hangings import hangings_objectives

    score = dict(zip([id(p) for p in cands], hangings_objectives(base_cfg, source, [p["params"] for p in cands],
                                                                 settings, min_separation, target)))
    keep = [i for i, p in enumerate(cands) if math.isfinite(score[id(p)])]
    ranked = rank_order(cands, keep, lambda p: score[id(p)], cautioned(res.constraints), clashes)
    for r, i in enumerate(ranked):
        p = cands[i] if not cands[i].get("screen") else evaluate_point(base_cfg, source, cands[i]["params"], settings)
        if p.get("valid") and not violations(p, relaxed, target, among) and math.isfinite(objective(p, target, among)):
            res.preferred_over, res.preference = preference(cands, ranked[r:], lambda q: score[id(q)],
                                                             res.constraints)
            return {**p, "objective": objective(p, target, among)}, score[id(cands[i])], len(cands)
    return None, None, len(cands)


def _plan(base_cfg: dict, source: str, bounds: list[tuple[str, float, float]], settings: SweepSettings,
          constraints: Constraints, target: str | None = None, *, workers: int = 1,
          progress: Callable[[int, int], None] | None = None, max_local: int | None = None,
          zip_: bool = False) -> PlanResult:
    """:func:`plan` under ``constraints`` as given."""
    if not bounds:
        raise InputError("--param", "give at least one --param NAME=LO:HI")
    names = [b[0] for b in bounds]
    if len(set(names)) != len(names):
        raise InputError("--param", "a parameter is given twice")
    discrete: dict[str, list[float]] = {}
    if constraints.lengths_available is not None:
        for n, lo, hi in bounds:
            if _is_length(n):
                vals = [a for a in constraints.lengths_available if lo - 1e-12 <= a <= hi + 1e-12]
                if not vals:
                    raise InputError("--lengths-available",
                                     f"none of the available lengths lies in {n} = {lo:g}..{hi:g} m")
                discrete[n] = vals
    if zip_ and discrete:
        raise InputError("--zip", "cannot move the parameters together when a wire length takes only the "
                                  "--lengths-available values; drop one of them")
    cont = [(n, lo, hi) for n, lo, hi in bounds if n not in discrete]
    if zip_:
        cont = [("zip", 0.0, 1.0)]

    def expand(vals: dict) -> dict:
        """Search variables -> the parameters of a point."""
        if not zip_:
            return vals
        t = vals["zip"]
        return {n: float(lo + t * (hi - lo)) for n, lo, hi in bounds}

    def unit(params: dict) -> np.ndarray:
        """A point's parameters -> the search variables scaled to [0, 1]."""
        if zip_:
            n, lo, hi = bounds[0]
            return np.array([(params[n] - lo) / (hi - lo)])
        return np.array([(params[n] - lo) / (hi - lo) for n, lo, hi in cont])

    d = len(cont)
    ng = _GRID.get(d, 3)
    axes = [np.linspace(lo, hi, ng) for _, lo, hi in cont]
    combos = [dict(zip(discrete, vals)) for vals in _product(list(discrete.values()))]
    grid = []
    for fixed in combos:
        for vals in _product(axes):
            grid.append({**expand({n: float(v) for (n, _, _), v in zip(cont, vals)}), **fixed})
    grid = [{n: g[n] for n in names} for g in grid]  # keep the user's order
    local_budget = max_local if max_local is not None else (12 if d == 1 else 30 * d) * max(len(combos), 1)
    total = len(grid) + (local_budget if d else 0)
    done = [0]

    def tick():
        done[0] += 1
        if progress:
            progress(min(done[0], total), total)

    def key_of(params: dict) -> tuple:
        return tuple(float(params[n]) for n in names)

    def search(screen: bool) -> tuple[dict, list, bool, list]:
        """Grid, then the local search (module docstring), every point
        evaluated as a screen (:func:`evaluate_point` ``screen=True``) or
        in full; returns ({params key: point}, the measurable components,
        whether the search ranked the small-amplitude sigmas, the
        components set aside: :func:`~bifilar.studies.ranking.set_aside`
        of the grid and of each one's own search)."""
        cache: dict[tuple, dict] = {}
        done[0] = 0
        pts = run_sweep(base_cfg, source, grid, settings, workers=workers, screen=screen,
                        progress=(lambda k, n: progress(k, total)) if progress else None)
        done[0] = len(grid)
        for g, p in zip(grid, pts):
            cache[key_of(g)] = p
        if target is not None and target not in identifiable_components(pts):
            raise InputError("--target", f"{target} is not identifiable from any mode anywhere in the range"
                             + _remedy_text(base_cfg, source, pts, settings, target))

        def evaluator(st: SweepSettings, into: dict):
            def evaluate(params: dict) -> dict:
                key = key_of(params)
                if key not in into:
                    into[key] = evaluate_point(base_cfg, source, {n: float(params[n]) for n in names}, st,
                                               screen=screen)
                    tick()
                return into[key]
            return evaluate

        # a component the grid would set aside (its best sigma above USEFUL_REL) may reach it between the
        # grid points: its own sigma searched first (no limits: the sweep's rule takes every valid point;
        # without the nonlinear runs), the best point found evaluated as the grid is, and the rule applied
        # to the grid and those points (kept out of the answer's candidates: not searched for the
        # objective, and each would cost a hangings plan with --hangings)
        seen, full = list(pts), dict(cache)
        for a in set_aside(pts, target) if d else []:
            def own(p, c=a["component"]):
                return _penalty(p, Constraints(), c)

            side = dict(cache)
            _local_search(cont, combos, expand, unit, ng, local_budget, side,
                          evaluator(replace(settings, tensions=False), side), own)
            seen.append(evaluator(settings, full)(min(side.values(), key=own)["params"]))
        among, aside = measurable_components(seen, target), set_aside(seen, target)

        local = settings
        if (screen and settings.tensions and _far_from_limits(pts, constraints)
                and _amplitude_negligible(pts, target, among)):
            local = replace(settings, tensions=False)  # the confirmation runs the best point's motion
        # without runs no screen has the stated amplitude's term: the whole search then ranks the
        # small-amplitude figures (within AMPLITUDE_ENOUGH of the full ones on the grid)
        small = not local.tensions

        def score(p):
            return _penalty(p, constraints, target, among, small)

        if d:
            _local_search(cont, combos, expand, unit, ng, local_budget, cache, evaluator(local, cache), score)
        return cache, among, small, aside

    # the search on screens (linear sigmas, no biases), then the best feasible
    # screen confirmed in full; where the full figure differs (second order
    # matters in this range: a shallow CoM) the whole search again in full
    cache, among, small, aside = search(screen=True)
    feasible = sorted((p for p in cache.values() if p.get("valid") and not violations(p, constraints, target, among)
                       and math.isfinite(objective(p, target, among))),
                      key=lambda p: objective(p, target, among, small))
    # ranked as the answer will be (a cautioned point after an uncautioned one within EQUAL_REL, points whose
    # body reaches the ceiling or whose wires cross after every clean one), so that those confirmed include the
    # answer's candidates
    confirm = [feasible[i] for i in rank_order(feasible, range(len(feasible)),
                                               lambda p: objective(p, target, among, small),
                                               cautioned(constraints), clashes)[:CONFIRM]]
    for p in confirm:
        full = evaluate_point(base_cfg, source, p["params"], settings)
        cache[key_of(p["params"])] = full
        if not (full.get("valid") and objective(full, target, among, small_amplitude=True)
                == objective(p, target, among, small_amplitude=True)
                and not violations(full, constraints, target, among)):
            cache, among, _, aside = search(screen=False)
            break
    evaluated = list(cache.values())
    feasible = [p for p in evaluated if p.get("valid") and not violations(p, constraints, target, among)
                and math.isfinite(objective(p, target, among))]
    if not feasible:
        flag, msg = binding_constraint(evaluated, constraints, target, among)
        raise InputError(flag, msg)
    best, over, why = choose([p for p in feasible if not p.get("screen")], constraints, target, among)
    return PlanResult(best, evaluated, target, constraints, list(bounds), _active(best, constraints, bounds, among),
                      among, zip_, preferred_over=over, preference=why, set_aside=aside)


#: the local search may run without nonlinear runs (and so rank the small-amplitude sigmas) only when on
#: every valid grid point the stated amplitude's term changes the objective by less than this (relative)
AMPLITUDE_ENOUGH = 0.02


def _amplitude_negligible(points: list[dict], target: str | None, among) -> bool:
    """Whether the stated amplitude's own uncertainty (``amplitude_budget``)
    changes the objective of every valid grid point by less than
    :data:`AMPLITUDE_ENOUGH`: then the local search may leave the nonlinear
    runs out (its screens rank the small-amplitude figures; the optimum is
    confirmed in full).  At a large amplitude it may not: the amplitude's
    term moves the optimum (the Solar Boat at 0.3: spacing 1 instead of
    2.5)."""
    for p in points:
        if not p.get("valid"):
            continue
        full, small = objective(p, target, among), objective(p, target, among, small_amplitude=True)
        if math.isfinite(full) and math.isfinite(small) and full > (1 + AMPLITUDE_ENOUGH) * small:
            return False
    return True


def _far_from_limits(points: list[dict], c: Constraints) -> bool:
    """Whether the nonlinear runs can be left out of a screen of the local
    search: no limit on the tension or depth, and every valid grid point's
    wires keep at least :data:`SLACK_MARGIN` of their rest tension
    throughout the excitation (so no point between them goes slack)."""
    if c.max_tension is not None or c.max_depth is not None:
        return False
    valid = [p for p in points if p.get("valid")]
    if not valid:
        return False
    for p in valid:
        t = p["tension"]
        if t.get("min") is None or t.get("slack"):
            return False
        if not np.all(np.asarray(t["min"], float) >= SLACK_MARGIN * np.asarray(t["rest"], float)):
            return False
    return True


def _local_search(cont, combos, expand, unit, ng: int, local_budget: int, cache: dict, evaluate, score) -> None:
    """The local part of :func:`plan` (module docstring, step 2) over the
    continuous search variables ``cont`` [(name, lo, hi)], for each
    combination ``combos`` of the discrete ones, from the best points of
    ``cache`` (filled by ``evaluate``, ranked by ``score``)."""
    from scipy.optimize import minimize, minimize_scalar

    d = len(cont)
    lo_v = np.array([lo for _, lo, _ in cont])
    span = np.array([hi - lo for _, lo, hi in cont])
    h = 1.0 / (ng - 1)
    for fixed in combos:
        budget = local_budget // max(len(combos), 1)

        def f(x, fixed=fixed):
            x = np.clip(np.atleast_1d(x), 0.0, 1.0)
            params = {**expand({n: float(lo_v[i] + x[i] * span[i]) for i, (n, _, _) in enumerate(cont)}), **fixed}
            return score(evaluate(params))

        def best_x(fixed=fixed, rank=0):
            sub = sorted((p for p in cache.values() if all(p["params"][n] == v for n, v in fixed.items())),
                         key=score)
            p0 = sub[min(rank, len(sub) - 1)]
            return unit(p0["params"])

        if d > 1:
            # Nelder-Mead in the unit box from the best STARTS grid points (the feasible set is often
            # cut into islands by mode-crossing bands), simplex one half-cell wide
            starts = [best_x(rank=r) for r in range(STARTS)]
            for x0 in starts:
                simplex = np.vstack([x0] + [np.clip(x0 + (0.5 * h if x0[i] + 0.5 * h <= 1 else -0.5 * h) * e, 0, 1)
                                            for i, e in enumerate(np.eye(d))])
                minimize(f, x0, method="Nelder-Mead", bounds=[(0, 1)] * d,
                         options={"initial_simplex": simplex, "maxfev": (budget - 10 * d) // STARTS,
                                  "xatol": 1e-3, "fatol": 1e-6})
        x0 = best_x()
        for i in range(d):  # polish each parameter by Brent's method in its bracketing cells
            def g(t, i=i, x0=x0):
                x = x0.copy()
                x[i] = t
                return f(x)

            minimize_scalar(g, bounds=(max(0.0, x0[i] - h), min(1.0, x0[i] + h)), method="bounded",
                            options={"xatol": 1e-3, "maxiter": 10 if d > 1 else budget})
            x0 = best_x()


def _remedy_text(base_cfg, source, pts, settings, comp) -> str:
    """``"; remedy: ..."`` for a component no point measures (empty if none found)."""
    from dataclasses import replace

    from .remedy import candidates, cheapest, describe

    ref = next((p for p in pts if p.get("valid")), None)
    if ref is None:
        return ""
    r = cheapest(candidates(base_cfg, source, ref["params"], replace(settings, tensions=False), [comp]), comp)
    return f"; remedy at {', '.join(f'{k} = {v:.4g}' for k, v in ref['params'].items())}: {describe(r)}" if r else ""


def _product(lists):
    import itertools

    return itertools.product(*lists) if lists else [()]


def _active(p: dict, c: Constraints, bounds, among=None) -> list[str]:
    """Constraints (and parameter bounds) the optimum sits on (within 1 %);
    ``among``: the components ranked (the separation guard's modes,
    :func:`~bifilar.studies.ranking.point_separation`)."""
    out = []
    t, dpt = (g := guarded_limits(p, among))["peak"], g["depth"]
    if c.max_tension is not None and t is not None and t >= 0.99 * c.max_tension:
        out.append(f"max tension ({t:.4g} of {c.max_tension:g} N)")
    if c.max_depth is not None and dpt is not None and dpt >= 0.99 * c.max_depth:
        out.append(f"max depth ({dpt:.4g} of {c.max_depth:g} m)")
    sep = point_separation(p, among)
    if c.min_separation is not None and sep is not None and sep <= 1.01 * c.min_separation:
        out.append(f"min separation ({sep:.3g} vs {c.min_separation:g})")
    for n, lo, hi in bounds:
        v = p["params"][n]
        if abs(v - lo) <= 0.01 * (hi - lo):
            out.append(f"lower bound of {n} ({lo:g})")
        elif abs(v - hi) <= 0.01 * (hi - lo):
            out.append(f"upper bound of {n} ({hi:g})")
    return out
