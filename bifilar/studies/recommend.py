"""The recommendation document of a study: which feasible point ``sweep``
recommends (:func:`assess`) and ``plan`` answers (:func:`choose`), why
(:func:`explain`, :func:`preference`), per component whether and from which
modes it is measurable (:func:`identifiability`), and the remedies of
those it is not (:func:`add_point_remedies`).  One rule for both
commands: the points are ranked by :func:`~bifilar.studies.ranking.rank_order`
on their objective, a point whose dependent wires may carry more than
``--max-tension`` (:func:`cautioned`) after one without that the figures
cannot tell apart, and a point whose body reaches the ceiling or whose
wires cross at rest after every clean one.

Operates on the point dicts of :func:`bifilar.studies.point.evaluate_point`
(objectives relative, tensions N, depths m)."""

from __future__ import annotations

import math
from dataclasses import replace

from ..jsonable import to_jsonable as _plain
from .ranking import (CONSTRAINT_FLAGS, USEFUL_REL, aside_under_hangings, binding_constraint, clashes, guard_limits,
                      guarded_limits, marginal, measurable_components, objective, pareto_front, point_components,
                      point_separation, preferences, rank_order, set_aside, tension_range_caution, violations)
from .settings import Constraints


def cautioned(constraints: Constraints):
    """A point's test for :func:`~bifilar.studies.ranking.rank_order`: its dependent wires may carry more
    than ``--max-tension`` (:func:`~bifilar.studies.ranking.tension_range_caution`)."""
    return lambda p: tension_range_caution(p, constraints) is not None


def choose(full: list[dict], constraints: Constraints, target: str | None, among) -> tuple[dict, list, str | None]:
    """The optimum of the fully evaluated feasible points ``full``, ranked as
    the sweep ranks them (:func:`~bifilar.studies.ranking.rank_order`: a
    point whose dependent wires may carry more than ``--max-tension`` after
    one without that the figures cannot tell apart, a point whose body
    reaches the ceiling or whose wires cross at rest after every clean
    one), with its
    ``objective``, and (``preferred_over``, ``preference``)."""
    key = lambda p: objective(p, target, among)  # noqa: E731
    ranked = rank_order(full, range(len(full)), key, cautioned(constraints), clashes)
    best = dict(full[ranked[0]])
    best["objective"] = key(best)
    return (best, *preference(full, ranked, key, constraints))


def preference(points: list[dict], ranked: list[int], key, constraints: Constraints) -> tuple[list, str | None]:
    """(``preferred_over``, ``preference``) of :class:`~bifilar.studies.plan.PlanResult` for the optimum
    ``points[ranked[0]]``: the points ranked after it although their objective is lower, without their
    index, and the lines saying why joined by "; " (None: none)."""
    over, lines = preferences(points, ranked, key, cautioned(constraints))
    return [{k: v for k, v in o.items() if k != "index"} for o in over], "; ".join(lines) or None


def assess(points: list[dict], constraints: Constraints, target: str | None, hangings=None) -> dict:
    """Mark each point ``feasible`` / ``violations`` / ``objective`` / ``rank``
    (in place) and return the recommendation document.

    ``hangings``: the experiment times the multi-hanging plan, which applies
    ``min_separation`` to each mode it times; ``hangings(points)`` is that
    plan's objective at each of a list of points
    (:func:`bifilar.studies.hangings.hangings_objectives`).
    The feasible points are ranked by it (each one's ``hangings_objective``;
    by their own figures only where no multi-hanging plan gives a sigma): the
    point whose own hanging is best can be far from the best for the
    hangings (a trifilar's Ixx from a swing, 35 %, at the point whose
    hangings give 2.3 % where another's give 0.45 %; docs/design.md,
    "Closed-loop audit of the planner, session 11").
    The guard is then the multi-hanging plan's, applied to each mode it
    times, and the points are assessed without it on their own hanging
    (``separation_guard`` ``"multi_hanging"`` where the recommended point's
    own hanging does not meet ``min_separation``, ``"planned_hanging"``
    where it does); the hangings plan at the recommended point must time
    only separated modes (:func:`bifilar.studies.hangings.check_separated`).
    """
    doc = _assess(points, constraints, target)
    doc["separation_guard"] = "planned_hanging"
    if hangings is None:
        return doc
    own = doc
    doc = _assess(points, replace(constraints, min_separation=None), target, hangings)
    doc["constraints"] = constraints.describe()
    if doc.get("best") is not None:
        separated = not violations(points[doc["best"]], constraints, target, doc["measurable"])
        doc["separation_guard"] = "planned_hanging" if separated else "multi_hanging"
        why = ("--hangings" if separated else
               f"--hangings; its own hanging does not meet --min-separation {constraints.min_separation:g}")
        doc["why"].insert(0, f"ranked by the multi-hanging plan ({why}): its "
                             f"{'target' if target else 'worst component'} +- "
                             f"{100 * doc['hangings_objective']:.3g} %; the point's own figures follow")
    elif own.get("binding") == CONSTRAINT_FLAGS["min_separation"]:
        doc["separation_guard"] = "multi_hanging"
        if doc["n_feasible"]:
            doc.update(binding=CONSTRAINT_FLAGS["min_separation"], reason=(
                f"no configuration meets --min-separation {constraints.min_separation:g} with the hangings either: "
                "no point's multi-hanging plan identifies every component from modes that far from the other "
                "modes of their hanging"))
    else:  # no multi-hanging plan gives a sigma: the points' own ranking
        doc = _assess(points, constraints, target)
        doc["separation_guard"] = "planned_hanging"
    return doc


def _assess(points: list[dict], constraints: Constraints, target: str | None, hangings=None) -> dict:
    """:func:`assess` under ``constraints`` as given; ``hangings``: rank by
    it (each feasible point's ``hangings_objective``), the points whose
    multi-hanging plan gives no sigma left out.

    Without a target the objective is the worst of the measurable components
    (:func:`measurable_components`); ``set_aside`` lists those identifiable
    but not measurable in the range, each with its best relative sigma, the
    point and why (:func:`~bifilar.studies.ranking.set_aside`); ``marginal``
    those ranked or set aside by a line they are close to (within 20 %,
    :func:`~bifilar.studies.ranking.marginal`; nothing else changes);
    ``identifiability`` says per component whether it is measurable and from
    which modes at the recommended point (``remedy`` entries are added by
    :func:`add_point_remedies`).
    """
    among = measurable_components(points, target)
    aside = set_aside(points, target)
    if hangings is not None:
        aside = aside_under_hangings(aside)
    for p in points:
        v = violations(p, constraints, target, among)
        p["objective"] = _plain(objective(p, target, among))
        p["guard_separation"] = _plain(point_separation(p, among)) if p.get("valid") else None
        p.update(guard_limits(p, among) if p.get("valid") else {})
        p["violations"] = [m for _, m in v]
        p["feasible"] = not v
        p["rank"] = None
        p["tension_range_caution"] = tension_range_caution(p, constraints)
    ok = [i for i, p in enumerate(points) if p["feasible"] and p["objective"] is not None]
    key = lambda p: p["objective"]  # noqa: E731
    if hangings is not None:
        for i, v in zip(ok, hangings([points[i] for i in ok])):
            points[i]["hangings_objective"] = _plain(v)
        ok = [i for i in ok if points[i]["hangings_objective"] is not None]
        key = lambda p: p["hangings_objective"]  # noqa: E731
    ranked = rank_order(points, ok, key, cautioned(constraints), clashes)
    for r, i in enumerate(ranked):
        points[i]["rank"] = r + 1
    front = pareto_front(points, target, among)
    comps = point_components(points)
    doc: dict = {"target": target_label(target, among or comps, comps, hangings is not None),
                 "measurable": among, "set_aside": aside,
                 "not_measurable": [c for c in comps if c not in among and c not in _names(aside)],
                 "constraints": constraints.describe(), "pareto_front": front,
                 "n_valid": sum(bool(p.get("valid")) for p in points),
                 "n_feasible": sum(bool(p["feasible"]) for p in points)}
    if not ranked and hangings is not None and doc["n_feasible"]:
        doc.update(best=None)  # no multi-hanging plan gives a sigma: assess says why
    elif not ranked:
        flag, msg = binding_constraint(points, constraints, target, among)
        doc.update(best=None, binding=flag, reason=msg)
    else:
        i = ranked[0]
        if hangings is not None:
            doc["hangings_objective"] = points[i]["hangings_objective"]
        over, lines = preferences(points, ranked, key, cautioned(constraints))
        doc.update(best=i, params=points[i]["params"], objective=points[i]["objective"],
                   why=explain(points[i], constraints, target, among), ranking=ranked[:10],
                   rig=points[i].get("rig"), separation=point_separation(points[i], among), preferred_over=over)
        doc["why"][1:1] = lines
    ref = points[doc["best"]] if doc.get("best") is not None else None
    doc["marginal"] = marginal(ref, among, aside, target)
    doc["identifiability"] = identifiabilities(comps, ref, among, aside, doc["marginal"])
    return doc


def target_label(target: str | None, among, comps, hangings: bool = False) -> str:
    """A study document's ``target``: the ``target`` asked for, else "worst
    relative of" the components the ranking figure covers: the measurable
    ones ``among``, or, where the points are ranked by their multi-hanging
    plan (``hangings``), every component ``comps`` (that plan's sigma,
    :func:`~bifilar.studies.hangings.hangings_objective`, is the worst of
    them all, a set-aside one included: rank25's left item 4)."""
    if target:
        return target
    return ("worst relative of " + ", ".join(comps) + " by the multi-hanging plan" if hangings
            else "worst relative of " + ", ".join(among))


def _names(aside: list[dict]) -> list[str]:
    return [a["component"] for a in aside]


def identifiabilities(comps, point: dict | None, among: list[str], aside: list[dict], near=()) -> dict:
    """:func:`identifiability` of each of ``comps`` at ``point``: measurable
    where in ``among``, identifiable but set aside where in ``aside``
    (:func:`~bifilar.studies.ranking.set_aside` entries), marginal where in
    ``near`` (:func:`~bifilar.studies.ranking.marginal` entries)."""
    why = {a["component"]: a for a in aside}
    close = {m["component"]: m for m in near}
    return {c: identifiability(c, point, c in among or c in why, why.get(c), close.get(c)) for c in comps}


def identifiability(comp: str, point: dict | None, measurable: bool, aside: dict | None = None,
                    near: dict | None = None) -> dict:
    """Per component: identifiable in the range, and at ``point`` (the
    recommended one) the modes whose period depends on it (``|d ln T / d ln I|``)
    and the mode it is estimated from; ``set_aside``: None, or the
    :func:`~bifilar.studies.ranking.set_aside` entry of a component
    identifiable but not measurable in the range (left out of the ranking);
    ``marginal``: None, or the :func:`~bifilar.studies.ranking.marginal`
    entry of one ranked (by its figure at ``point``) or set aside (by its
    best) close to that line."""
    d: dict = {"identifiable": measurable, "from_modes": {}, "mode": None, "remedy": None, "set_aside": aside,
               "marginal": near}
    if point is not None and point.get("valid"):
        e = point["components"].get(comp, {})
        d.update(from_modes=e.get("from_modes", {}), mode=e.get("mode"), rel_sigma=e.get("rel_sigma"))
    return d


def explain(p: dict, c: Constraints, target: str | None, among=None) -> list[str]:
    """Plain-language reasons a point was recommended."""
    lines = []
    comps = p["components"]
    sel = [target] if target else list(among if among is not None else comps)
    worst = max(sel, key=lambda k: math.inf if comps[k]["rel_sigma"] is None else comps[k]["rel_sigma"])
    e = comps[worst]
    lines.append(f"lowest predicted uncertainty of {'the target ' + target if target else 'the worst measurable component'}: "
                 f"{worst} +- {100 * e['rel_sigma']:.3g} % (from the {e['mode']} mode)")
    if e.get("shares"):
        top = max(e["shares"], key=e["shares"].get)
        what = ("second-order terms (inputs whose effect is not linear over their uncertainty)"
                if top == "second_order" else top)
        lines.append(f"its variance is {100 * e['shares'][top]:.0f} % {what}")
    sep = point_separation(p, among)
    if sep is not None:
        lines.append(f"mode separation {100 * sep:.3g} % (smallest gap between a timed mode and any other)"
                     + (f", >= {100 * c.min_separation:g} % required" if c.min_separation is not None else ""))
    t, g = p["tension"], guarded_limits(p, among)
    out = (f" (the {', '.join(g['left_out'])} run left out: only a set-aside component's mode, not timed)"
           if g["left_out"] else "")
    if g["peak"] is not None:
        lines.append(f"peak wire tension {g['peak']:.4g} N" + out
                     + (f" (<= {c.max_tension:g} N)" if c.max_tension else "")
                     + (f"; the model's split of dependent wires: statics lets a wire reach {t['range_peak']:.4g} N"
                        if t.get("range_peak") is not None and t["range_peak"] > g["peak"] else ""))
    if g["depth"] is not None:
        lines.append(f"needs {g['depth']:.4g} m below the ceiling" + out
                     + (f" (<= {c.max_depth:g} m)" if c.max_depth else ""))
    return lines


def reference_point(rec: dict, points: list[dict]) -> dict | None:
    """The point a sweep's remedies are evaluated at: the recommended one
    ``points[rec["best"]]``, else the first valid one, else None."""
    if rec.get("best") is not None:
        return points[rec["best"]]
    return next((p for p in points if p.get("valid")), None)


def point_advice(point: dict, cfg: dict, source: str, settings, reaction: float, sensor,
                 min_separation: float | None = None, among=None) -> dict:
    """What a recommended (``sweep``) or planned (``plan``) ``point`` says
    about the experiment: ``how_to_time`` (:func:`~bifilar.studies.point_advice.timing_advice`;
    ``reaction`` s, a stopwatch trial's std; ``sensor`` (noise relative to
    the amplitude, rate Hz) or None; ``min_separation`` relative, only the
    modes that far from the others, where the guard was left to the
    multi-hanging plan) and ``amplitude_advice``
    (:func:`~bifilar.studies.amplitude.amplitude_advice`), each of the
    components the ranking counts, ``among`` (the document's ``measurable``;
    None: every one): a set-aside component is not timed, so its mode is
    advised only where a counted component is estimated from it too
    (:func:`~bifilar.studies.ranking.counted_components`; c04 at spacing 0.04
    had "swing-x ... for Iyy, 50 cycles per trial" for an Iyy at +- 944 %)."""
    from .amplitude import amplitude_advice
    from .point_advice import timing_advice
    from .ranking import counted_components

    if (counted := counted_components(point, among)) is not None:
        point = {**point, "components": {k: e for k, e in point["components"].items() if k in counted}}

    return {"how_to_time": timing_advice(point, reaction, sensor, min_separation),
            "amplitude_advice": amplitude_advice(cfg, source, point, settings)}


def unmeasured(doc: dict) -> list[str]:
    """The components a study's recommended (``sweep``) or planned (``plan``)
    point cannot measure in its own hanging, from ``doc["identifiability"]``
    (:func:`identifiabilities`): those no mode anywhere in the range depends
    on and those set aside (:func:`~bifilar.studies.ranking.set_aside`: best
    relative sigma above :data:`~bifilar.studies.ranking.USEFUL_REL`).  Both
    get the same advice: their remedies (:func:`add_point_remedies`) and the
    multi-hanging plan at the point, which says what the other hangings
    measure them to."""
    return [c for c, e in doc["identifiability"].items() if not e["identifiable"] or e.get("set_aside")]


def remedy_clause(entry: dict) -> str:
    """The end of a component's identifiability line (``entry``: an
    :func:`identifiability` dict with its remedies added): "; remedy: ..."
    (:func:`bifilar.studies.remedy.describe`), or for a component set aside
    whose best remedy still leaves it above
    :data:`~bifilar.studies.ranking.USEFUL_REL` that no change tried
    measures it to that (the best quoted), or that none was found; "" for
    a component set aside whose remedies were not looked for."""
    r = entry.get("remedy")
    if r is None and entry.get("set_aside") and "alternatives" not in entry and "remedy_error" not in entry:
        return ""
    if r is None:
        return "; the model found no remedy among the changes tried"
    if entry.get("set_aside") and not r["rel_sigma"] <= USEFUL_REL:
        return (f"; none of the changes tried measures it to {100 * USEFUL_REL:g} % (the best: {r['text']})")
    return f"; remedy: {r['text']}"


def add_point_remedies(doc: dict, need: list, ref: dict | None, cfg: dict, source: str, settings) -> None:
    """Add the remedies of the components ``need`` (those no point can
    measure, and a target that is not) to ``doc["identifiability"]``
    (:func:`bifilar.studies.remedy.add_remedies`), evaluated at the point
    ``ref`` (a sweep's recommended one, else its first valid one; a plan's
    optimum); nothing where ``need`` is empty or ``ref`` None."""
    from .remedy import add_remedies

    if need and ref is not None:
        add_remedies(doc, cfg, source, ref["params"], settings, list(need))
