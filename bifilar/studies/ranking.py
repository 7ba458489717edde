"""Feasibility and ranking of a sweep's points (the recommendation
document built on them: :mod:`bifilar.studies.recommend`).

Operates on the point dicts of :func:`bifilar.studies.point.evaluate_point`;
the objective is the predicted relative standard uncertainty (of the target
component, or the worst of the *measurable* components: those identifiable
at some valid point of the range; the others get a remedy, see
:mod:`bifilar.studies.remedy`, instead of blocking every recommendation;
those identifiable but whose best relative sigma over the range exceeds
:data:`USEFUL_REL` are set aside with their best figure and point,
:func:`set_aside`, instead of deciding it).

The mode-separation guard is one figure per point, :func:`point_separation`:
the smallest relative gap between any timed mode (the mode each measurable
component is estimated from, a set-aside component's mode not counted) and
any other mode (:func:`bifilar.studies.point.timed_separation`); it is what
the table, the text and the plot show and what ``min_separation`` limits.
"""

from __future__ import annotations

import math
import re
from functools import cmp_to_key

from ..estimation.budget import LINEAR_ENOUGH
from .settings import Constraints



def rel_sigma(entry: dict, small_amplitude: bool = False):
    """A component entry's relative sigma (None: none can be given);
    ``small_amplitude``: the figure for a small amplitude (``invert
    --amplitude 0``) instead of the stated one's, i.e. without the stated
    amplitude's own uncertainty (``amplitude_budget``)."""
    rs = entry.get("rel_sigma")
    ab = entry.get("amplitude_budget")
    if small_amplitude and ab and ab.get("budgeted"):
        return ab["rel_sigma_small_amplitude"]
    return rs


def objective(point: dict, target: str | None, among=None, small_amplitude: bool = False) -> float:
    """Relative standard uncertainty the ranking minimises: of ``target``, or
    the worst of the components ``among`` (default: all of the point's);
    inf when one of them is not identifiable or has no sigma
    (``sigma_unavailable``), or the point is invalid.  ``small_amplitude``:
    of the sigmas for a small amplitude (:func:`rel_sigma`; a planner's
    search, whose screens may have no nonlinear run)."""
    if not point.get("valid"):
        return math.inf
    comps = point["components"]
    sel = [target] if target else (list(among) if among is not None else list(comps))
    vals = [rel_sigma(comps[k], small_amplitude) for k in sel if k in comps]
    vals = [math.inf if v is None else v for v in vals]
    return float(max(vals)) if vals else math.inf


#: objectives within this relative difference rank as equal: mirror-image points (``length_offset =
#: -0.1`` and ``0.1`` of a symmetric rig) have the same figures up to rounding (6e-14 relative measured),
#: far below anything the figures resolve, so which of them is recommended must not be left to the last bits
TIE_REL = 1e-9


#: objectives within this relative difference are not told apart by the sweep's own figures: a point's
#: sigma is its linear budget wherever the second-order std (the one invert prints) lies within
#: :data:`~bifilar.estimation.budget.LINEAR_ENOUGH` (2 %) of it, so two points that close in the objective may
#: swap under invert's figure (the audits' invert std / sigma: 1.0006-1.017, docs/design.md, sessions 10 and
#: 11).  Within it a point without a caution (:func:`tension_range_caution`) ranks before one with
EQUAL_REL = LINEAR_ENOUGH


def clashes(point: dict) -> bool:
    """The point's body reaches above the ceiling at rest or its wires cross
    there (``ceiling_clash``, ``wires_cross``: :func:`bifilar.studies.point.evaluate_point`)."""
    return bool(point.get("ceiling_clash") or point.get("wires_cross"))


def rank_order(points: list[dict], idx, key, caution=None, last=None) -> list[int]:
    """The indices ``idx`` of ``points`` by increasing ``key(point)``
    (finite), ties broken by the other components, then the parameters,
    not by the grid order or rounding: the points whose key is within
    :data:`TIE_REL` of the smallest remaining one form a group, ordered by
    their components' relative sigmas, largest first, each compared within
    :data:`TIE_REL` (:func:`_tie_order`), then by their parameter values
    (as given, in the sweep's parameter order); then the next group.

    ``caution(point)`` (optional, true for a point carrying a caution: its
    dependent wires may carry more than ``--max-tension``) puts a point
    without one first where the figures cannot tell them apart: when the
    smallest remaining key is a cautioned point's, the best point without a
    caution whose key lies within :data:`EQUAL_REL` of it (and its tie
    group) comes next instead; within a tie group those without a caution
    come first.  ``last(point)`` (optional, e.g. :func:`clashes`): those
    points after all the others, each part ranked as above.

    The components come first because the worst one alone can tie where
    the others differ: a thin rod's Ixx (its roll, 10.9 %, set by the CoM's
    2 mm whatever the spacing) tied at spacing 0.7 and 0.9, and the smaller
    spacing was recommended with its Izz at 0.30 % against 0.27 %."""
    if last is not None:
        idx = list(idx)
        return (rank_order(points, [i for i in idx if not last(points[i])], key, caution)
                + rank_order(points, [i for i in idx if last(points[i])], key, caution))
    flagged = (lambda i: bool(caution(points[i]))) if caution is not None else (lambda i: False)  # noqa: E731
    order = sorted(idx, key=lambda i: key(points[i]))
    out: list[int] = []
    while order:
        head = key(points[order[0]])
        if flagged(order[0]):
            near = [i for i in order if key(points[i]) <= head + EQUAL_REL * abs(head) and not flagged(i)]
            if near:
                head = key(points[near[0]])
                order = near + [i for i in order if i not in near]
        group = [i for i in order if key(points[i]) <= head + TIE_REL * abs(head)]
        group.sort(key=cmp_to_key(lambda i, j: (flagged(i) - flagged(j)) or _tie_order(points[i], points[j])))
        out += group
        order = [i for i in order if i not in group]
    return out


#: why a point was passed over (:func:`preferences`): its flag and the end of the line saying so
PASSED_OVER = {
    "ceiling_clash": "but whose body reaches above the ceiling at rest (ceiling_clash; clean points rank first)",
    "wires_cross": "but whose wires cross at rest (wires_cross; clean points rank first)",
    "tension_range_caution": (f"(within the {100 * EQUAL_REL:g} % the sweep's sigma resolves) but whose dependent "
                              "wires may carry more than --max-tension (its tension_range_caution)"),
}


def preferences(points: list[dict], ranked: list[int], key, caution) -> tuple[list[dict], list[str]]:
    """The points :func:`rank_order` (with ``caution`` and ``last`` =
    :func:`clashes`) put after the first of ``ranked`` although their
    ``key`` is lower: ([{index, params, objective, reason}], one line per
    reason naming the best of them), ``reason`` a key of :data:`PASSED_OVER`."""
    if not ranked:
        return [], []
    k0 = key(points[ranked[0]])
    over: list[dict] = []
    for i in ranked[1:]:
        p = points[i]
        why = [r for r in ("ceiling_clash", "wires_cross") if p.get(r)] or (["tension_range_caution"] if caution(p) else [])
        if key(p) < k0 and why:
            over.append({"index": i, "params": p.get("params", {}), "objective": key(p), "reason": why[0]})
    lines = []
    for reason, end in PASSED_OVER.items():
        hit = [o for o in over if o["reason"] == reason]
        if hit:
            gap = 1.0 - hit[0]["objective"] / k0 if k0 else 0.0
            who = ", ".join(f"{k} = {v:.6g}" for k, v in hit[0]["params"].items()) or f"point {hit[0]['index']}"
            more = f" (and {len(hit) - 1} other(s))" if len(hit) > 1 else ""
            lines.append(f"preferred to {who}{more}, whose predicted uncertainty is {100 * gap:.2g} % lower {end}")
    return over, lines


def _tie_order(a: dict, b: dict) -> int:
    """-1, 0 or 1: ``a`` before ``b`` among points whose objective ties: the
    lower sorted-descending vector of component relative sigmas (an entry
    within :data:`TIE_REL` of the other's counts as equal; a missing one as
    inf), then the smaller parameters."""
    def sig(p):
        v = [rel_sigma(e) for e in (p.get("components") or {}).values() if isinstance(e, dict)]
        return sorted((math.inf if x is None else float(x) for x in v), reverse=True)

    for x, y in zip(sig(a), sig(b)):
        if x == y or abs(x - y) <= TIE_REL * max(abs(x), abs(y)):
            continue
        return -1 if x < y else 1
    pa = tuple(float(v) for v in a.get("params", {}).values())
    pb = tuple(float(v) for v in b.get("params", {}).values())
    return (pa > pb) - (pa < pb)


#: a component whose *smallest* relative standard uncertainty over the range (of all its valid points) exceeds
#: this is not measurable in the range (:func:`set_aside`): at 50 % its 95 % interval (+- 98 %) reaches from
#: about zero to twice the value, no better than a guess.  Left out of the objective, it can no longer decide
#: the recommendation: a bifilar with wires 0.8 / 1.2 m was recommended at a point measuring Iyy at +- 195 %
#: (86 % of experiments unphysical) and Ixx 11 %, Izz 3.1 %, over the point giving Ixx 7.3 %, Izz 0.54 % without
#: Iyy; a 30 g part got no recommendation for an Iyy at best +- 944 % (docs/design.md, "audit24, session 24",
#: item 6, and "rank25, session 25")
USEFUL_REL = 0.5


def identifiable_components(points: list[dict]) -> list[str]:
    """Components identifiable at one valid point at least (config order)."""
    return [c for c in point_components(points)
            if any(p.get("valid") and p["components"][c].get("identifiable") for p in points)]


#: a ranked component whose relative sigma at the recommended point, or a set-aside one whose best, lies within
#: this fraction of :data:`USEFUL_REL` of it (40-60 %) is reported as ``marginal`` (:func:`marginal`): c11's plan
#: over length_offset -0.5:0.5 ranks Iyy at 49.3 % there (its best 35 %; the answer's Ixx 11.5 % where leaving
#: Iyy out gives 4.7 %, docs/design.md "rank25, session 25", left item 2)
MARGINAL_BAND = 0.2


def marginal(best: dict | None, among, aside: list[dict], target: str | None = None, max_rel: float = USEFUL_REL,
             band: float = MARGINAL_BAND) -> list[dict]:
    """The components ranked or set aside by a line they are close to (with
    the defaults, 40-60 %, both ends included; nothing changes which are
    ranked): a component ranked (``among``, not ``target``, which the user
    asked for) whose relative sigma (:func:`rel_sigma`) at the recommended
    point ``best`` lies within ``band`` x ``max_rel`` of ``max_rel``, and
    one set aside (``aside``: :func:`set_aside` entries) whose best does.
    One dict each (the ranked first, config order): ``component``,
    ``rel_sigma`` (1: at ``best``, or the set-aside one's best), ``params``
    (that point's), ``ranked`` (bool), ``reason`` (one line)."""
    lo, hi = (1 - band) * max_rel, (1 + band) * max_rel
    near = []
    comps = (best or {}).get("components") or {}
    for c in among or ():
        v = rel_sigma(comps[c]) if c != target and c in comps else None
        if v is not None and lo <= v <= hi:
            near.append((c, float(v), best.get("params", {}), True))
    near += [(a["component"], a["best_rel_sigma"], a["params"], False) for a in aside if a["best_rel_sigma"] <= hi]
    out = []
    for c, v, params, ranked in near:
        at = ", ".join(f"{k} = {x:.6g}" for k, x in params.items())
        out.append({"component": c, "rel_sigma": v, "params": params, "ranked": ranked, "reason": (
            f"{c} is marginal: its " + ("uncertainty at the recommended point" if ranked else "smallest uncertainty")
            + f", +- {100 * v:.3g} %" + (f" (at {at})" if at and not ranked else "") + f", is within {100 * band:g} % "
            f"of the {100 * max_rel:g} % line above which a component is set aside (its best over the range); "
            + (f"it is ranked at a figure little better than a guess: leave {c} out of --component to rank by the "
               "others" if ranked else f"it is set aside: rank by it with --target {c} if it is wanted"))})
    return out


def set_aside(points: list[dict], target: str | None = None, max_rel: float = USEFUL_REL) -> list[dict]:
    """The components not measurable in the range although identifiable:
    those some valid point gives a sigma, the smallest of whose relative
    sigmas (:func:`rel_sigma`, the stated amplitude's) exceeds ``max_rel``
    (:data:`USEFUL_REL`; strictly: a best of exactly ``max_rel`` is kept).
    ``target`` (ranked by itself, as the user asked) is never set aside.
    One dict each, config order: ``component``, ``best_rel_sigma`` (1),
    ``params`` (the point giving it), ``reason`` (one line with the remedy:
    leave it out of --component, add --hangings, or rank by it with --target)."""
    out = []
    for c in identifiable_components(points):
        if c == target:
            continue
        figs = [(rel_sigma(p["components"][c]), i) for i, p in enumerate(points)
                if p.get("valid") and p["components"][c].get("identifiable")]
        figs = [(float(v), i) for v, i in figs if v is not None and math.isfinite(v)]
        if not figs:
            continue  # no sigma anywhere: binding_constraint says why (as invert does)
        best, i = min(figs)
        if best > max_rel:
            at = ", ".join(f"{k} = {v:.6g}" for k, v in points[i].get("params", {}).items())
            out.append({"component": c, "best_rel_sigma": best, "params": points[i].get("params", {}),
                        "reason": (f"{c} is not measurable in this range: its smallest uncertainty is "
                                   f"+- {100 * best:.3g} %" + (f" (at {at})" if at else "") + ", above the "
                                   f"{100 * max_rel:g} % a measurement must beat to say more than a guess; it is "
                                   f"left out of the ranking: leave {c} out of --component, add --hangings, or "
                                   f"rank by it with --target {c}")})
    return out


def aside_under_hangings(aside: list[dict]) -> list[dict]:
    """:func:`set_aside`'s entries (new dicts) where the points are ranked by
    their multi-hanging plan (``--hangings``): that plan's joint sigma, the
    ranking figure, covers a set-aside component too, so its reason says so
    instead of naming --hangings as the way out."""
    return [{**a, "reason": a["reason"].split("; it is left out of the ranking")[0]
             + "; it is left out of the point's own figure, but --hangings ranks by the multi-hanging plan's "
             "joint sigma, which includes it"} for a in aside]


def measurable_components(points: list[dict], target: str | None = None, max_rel: float = USEFUL_REL) -> list[str]:
    """Components the objective ranks by (config order): identifiable at one
    valid point at least (:func:`identifiable_components`) and not set aside
    (:func:`set_aside`: a best relative sigma over the range above
    ``max_rel``; ``target`` never is)."""
    aside = {a["component"] for a in set_aside(points, target, max_rel)}
    return [c for c in identifiable_components(points) if c not in aside]


def counted_components(point: dict, among=None) -> dict | None:
    """The one rule of which of the point's modes the guards count: {name:
    entry} of the components ``among`` (the components the ranking counts,
    :func:`measurable_components`) that have a mode and their ``separation``
    at the point; None (every mode counts) where ``among`` is None or no
    component of the point has that figure (a hand-made point).  A component
    set aside (:func:`set_aside`) is not timed, so its mode counts only where
    a counted component is estimated from it too.  Used by
    :func:`point_separation` and :func:`guarded_limits`."""
    comps = point.get("components") or {}
    own = {k: e for k, e in comps.items() if isinstance(e, dict) and e.get("separation") is not None}
    if among is None or not own:
        return None
    return {k: own[k] for k in among if k in own}


def point_separation(point: dict, among=None) -> float | None:
    """The point's mode-separation guard (see the module docstring), relative:
    the smallest gap between the mode of a component ``among`` (the
    components the ranking counts, :func:`measurable_components`; default:
    every component of the point) and any other mode.  A component set aside
    (:func:`set_aside`) is not timed, so its mode alone is not guarded: c04's
    Iyy swing 1.18 % from another mode ruled out spacing 0.04 where Izz's
    torsion was 5.4 % and Ixx's roll 235 % from any (docs/design.md,
    "rank26, session 26"); a mode
    a counted component is estimated from stays guarded, and so does every
    gap between a counted mode and the set-aside one (the modes still beat).
    Each component's own figure is its entry's ``separation``
    (:func:`bifilar.studies.point.timed_separation` of its mode); inf where
    no counted component has a mode at the point; a point without the
    components' figures (a hand-made one) gives its ``separation``."""
    counted = counted_components(point, among)
    if counted is not None:
        return min(e["separation"] for e in counted.values()) if counted else math.inf
    sep = point.get("separation")
    if sep is None:  # a point from before the guard had its own field
        own = [e["separation"] for e in (point.get("components") or {}).values()
               if isinstance(e, dict) and e.get("separation") is not None]
        sep = min(own) if own else None
    return sep


def guarded_limits(point: dict, among=None) -> dict:
    """The point's figures the physical limits are applied to, over the
    nonlinear runs of the modes the guards count (:func:`counted_components`):
    ``peak`` (N, the largest wire tension in those runs; the greatest at rest
    where none is counted), ``depth`` (m below the ceiling, at rest or in
    those runs), ``slack_wires`` (1-based) and ``left_out``, the runs not
    counted (their labels).  A set-aside component is not timed, so its
    mode's run is not excited: c04 at spacing 0.04 (docs/design.md, "plan26,
    session 26").  The point's own ``tension`` / ``depth`` figures (every
    run) where every run counts, ``among`` is None, tensions are off or the
    point has no per-run figures (``tension.by_mode``'s ``slack_wires``,
    ``depth.by_mode``: a point from before them)."""
    t, d = point.get("tension") or {}, point.get("depth") or {}
    out = {"peak": t.get("peak"), "depth": d.get("max"), "slack_wires": list(t.get("slack_wires") or []),
           "left_out": []}
    counted, by_t, by_d = counted_components(point, among), t.get("by_mode") or {}, d.get("by_mode")
    if counted is None or t.get("peak") is None or by_d is None:
        return out
    modes = {e.get("mode") for e in counted.values()}
    runs = [m for m in by_t if m in modes]
    if len(runs) == len(by_t) or any("slack_wires" not in by_t[m] for m in by_t):
        return out
    return {"peak": float(max(max(by_t[m]["max"]) for m in runs) if runs else max(t["rest"])),
            "depth": max([d["rest"]] + [by_d[m] for m in runs]),
            "slack_wires": sorted({w for m in runs for w in by_t[m]["slack_wires"]}),
            "left_out": [m for m in by_t if m not in modes]}


def guard_limits(point: dict, among) -> dict:
    """{"guard_limits": :func:`guarded_limits`} where a run is left out of the
    point's limits (a set-aside component's mode), else {}: the JSON's
    additive field, absent (the document as before) where every run counts."""
    g = guarded_limits(point, among)
    return {"guard_limits": g} if g["left_out"] else {}


def violations(point: dict, c: Constraints, target: str | None = None, among=None) -> list[tuple[str, str]]:
    """(constraint, message) for every limit the point breaks; ``among``:
    the components the ranking counts (the mode-separation guard's modes,
    :func:`point_separation`; default every component's)."""
    out: list[tuple[str, str]] = []
    if not point.get("valid"):
        return [("valid", point.get("error") or "invalid")]
    g = guarded_limits(point, among)  # a set-aside component's run left out
    if g["slack_wires"]:
        out.append(("slack", f"wire(s) {', '.join(map(str, g['slack_wires']))} go slack during the excitation"))
    if c.max_tension is not None:
        if g["peak"] is None:
            out.append(("max_tension", "no nonlinear run (tensions off)"))
        elif g["peak"] > c.max_tension:
            out.append(("max_tension", f"peak tension {g['peak']:.4g} N > {c.max_tension:g} N"))
    if c.max_depth is not None:
        d = g["depth"]
        if d is None:
            out.append(("max_depth", "no nonlinear run (tensions off)"))
        elif d > c.max_depth:
            out.append(("max_depth", f"depth {d:.4g} m > {c.max_depth:g} m"))
    if c.lengths_available is not None:
        L = point.get("lengths")
        if L is not None and not all(min(abs(x - a) for a in c.lengths_available) <= 1e-6 for x in L):
            out.append(("lengths_available", f"wire lengths {', '.join(f'{x:g}' for x in L)} m not all in "
                                             f"{', '.join(f'{a:g}' for a in c.lengths_available)}"))
    if c.min_separation is not None:
        sep = point_separation(point, among)
        if sep is not None and sep < c.min_separation:
            out.append(("min_separation", f"mode separation {100 * sep:.3g} % < {100 * c.min_separation:g} %"))
    return out


def tension_range_caution(point: dict, c: Constraints) -> str | None:
    """The caution of a point that meets ``--max-tension`` on the model's
    split of dependent wires (4 or 5 wires at rest whose tensions statics
    cannot fix) while statics lets a wire of a real rig reach more
    (``tension.range_peak``, :func:`~bifilar.studies.point.statics_range`):
    the point stays feasible (the model's split is one admissible split,
    the symmetric one on a symmetric rig), and the line says what a wire
    may carry; None where the limit is not set, the point breaks it
    anyway, or every split stays within it."""
    t = point.get("tension") or {}
    top, peak = t.get("range_peak"), t.get("peak")
    if c.max_tension is None or top is None or peak is None or peak > c.max_tension or top <= c.max_tension:
        return None
    lo, hi = t["range"][t["range_peak_wire"] - 1]
    return (f"--max-tension {c.max_tension:g} N holds for the model's split of the dependent wires (peak "
            f"{peak:.4g} N), but statics does not fix that split: wire {t['range_peak_wire']} may carry "
            f"{lo:.4g} .. {hi:.4g} N at rest and up to {top:.4g} N in the runs, above the limit; the real split "
            "is set by the wires' stretch and their lengths' tolerances: measure the tensions or match the wires")


CONSTRAINT_FLAGS = {"max_tension": "--max-tension", "max_depth": "--max-depth",
                    "lengths_available": "--lengths-available", "min_separation": "--min-separation",
                    "slack": "--amplitude", "valid": "--param"}


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def why_invalid(points: list[dict]) -> str:
    """The most common reason of the invalid points, in one line: the
    reasons grouped by their wording with the numbers left out (``wires 1
    and 2 cannot reach ... 0.5 + 0.5 m`` and ``... 1 + 1 m`` are one
    reason), the largest group's first point quoted with its parameters and
    the count (and how many other reasons there are); a tie goes to the
    group met first in grid order."""
    bad = [(i, p) for i, p in enumerate(points) if not p.get("valid")]
    if not bad:
        return "every point is valid"
    groups: dict[str, list] = {}
    for i, p in bad:
        groups.setdefault(_NUMBER.sub("#", p.get("error") or "?"), []).append(i)
    first = max(groups.values(), key=len)  # max keeps the first of equal counts: grid order
    i = first[0]
    at = ", ".join(f"{k} = {v:.6g}" for k, v in points[i].get("params", {}).items())
    more = f" ({len(groups) - 1} other reason(s) for the rest)" if len(groups) > 1 else ""
    return (f"the most common reason ({len(first)} of {len(points)} points" + (f", e.g. at {at}" if at else "")
            + f"): {points[i].get('error') or '?'}{more}")


def binding_constraint(points: list[dict], c: Constraints, target: str | None, among=None) -> tuple[str, str]:
    """Which limit leaves no point feasible: (flag name, message)."""
    valid = [p for p in points if p.get("valid")]
    if not valid:
        return "--param", "no valid configuration in the range: " + why_invalid(points)
    finite = [p for p in valid if math.isfinite(objective(p, target, among))]
    if not finite and not target and among is not None and not among and (aside := set_aside(points)):
        return "--component", "no component is measurable in this range: " + "; ".join(a["reason"] for a in aside)
    if not finite:
        # identifiable, but no std anywhere (a knife edge, dependent wires): say why, as invert does
        sel = [target] if target else list(among if among is not None else point_components(points))
        why = [(c, p["components"][c]["sigma_unavailable"]) for p in valid for c in sel
               if p["components"].get(c, {}).get("sigma_unavailable")]
        if why:
            return "--param", (f"no point of the range has an uncertainty for {why[0][0]} "
                               f"({len(valid)} valid point(s)): {why[0][1]}")
        what = target or "no component"
        verb = "is not" if target else "is"
        return "--target", f"{what} {verb} identifiable from any mode anywhere in the range"
    viol = [dict(violations(p, c, target, among)) for p in finite]
    names = [n for n in ("slack", "max_tension", "max_depth", "lengths_available", "min_separation")
             if any(n in v for v in viol)]
    # the constraint that no point satisfies, else the one whose removal frees the most points
    never = [n for n in names if all(n in v for v in viol)]
    best = never[0] if never else max(names, key=lambda n: sum(set(v) == {n} for v in viol))
    flag = CONSTRAINT_FLAGS[best]
    if best == "max_tension":
        lo = min(g for p in finite if (g := guarded_limits(p, among)["peak"]) is not None)
        msg = f"no configuration meets --max-tension {c.max_tension:g} N: the lowest peak tension found is {lo:.4g} N"
    elif best == "max_depth":
        lo = min(g for p in finite if (g := guarded_limits(p, among)["depth"]) is not None)
        msg = f"no configuration meets --max-depth {c.max_depth:g} m: the smallest depth found is {lo:.4g} m"
    elif best == "min_separation":
        hi = max(point_separation(p, among) for p in finite)
        msg = (f"no configuration meets --min-separation {c.min_separation:g}: the best mode separation "
               f"found is {hi:.3g}")
    elif best == "slack":
        msg = "every configuration lets a wire go slack during the excitation; reduce --amplitude"
    else:
        msg = "no configuration uses only the available wire lengths " + ", ".join(f"{a:g}" for a in c.lengths_available)
    others = [CONSTRAINT_FLAGS[n] for n in names if n != best]
    if others:
        msg += f" (also limiting: {', '.join(others)})"
    return flag, _unmeasured_feasible(msg, valid, c, target, among)


def _unmeasured_feasible(msg: str, valid: list[dict], c: Constraints, target: str | None, among) -> str:
    """The clause a binding-limit message needs where some valid point meets
    every limit but has no sigma (None, or inf: ``sigma_unavailable``) for a
    component the objective asks for (a
    vertical bifilar's Iyy, measurable only where the wires lean: a light
    part's Iyy from a swing at +- 944 %, every such point 0.3-1.2 % from
    another mode, docs/design.md "audit24, session 24"): the
    limit alone does not leave "no configuration" then.  ``msg`` (the binding
    limit's line) is returned with "configuration" narrowed to those that
    measure the components, and which points meet every limit without them
    and what to do; unchanged where no point does."""
    sel = [target] if target else list(among if among is not None else point_components(valid))
    meet = [p for p in valid if not violations(p, c, target, among)]
    miss: list[str] = []
    first = None  # the first such point and the first component it gives no sigma for
    for p in meet:  # no sigma: None, or inf (a stated amplitude whose range reaches the half turn, json25)
        lack = [k for k in sel if k in p["components"] and not math.isfinite(objective(p, k))]
        first = first or ((p, lack[0]) if lack else None)
        miss += [k for k in lack if k not in miss]
    if not meet or not miss:
        return msg
    p, k = first
    at = ", ".join(f"{n} = {v:.6g}" for n, v in p.get("params", {}).items())
    why = no_sigma_reason(p["components"][k])
    eg = "; ".join(x for x in (f"at {at}" if at else "", f"{k}{why}" if why else "") if x)
    return (msg.replace("configuration", f"configuration that measures {', '.join(sel)}", 1)
            + f"; {len(meet)} point(s) meet every limit but give no uncertainty for {', '.join(miss)}"
            + (f" (e.g. {eg})" if eg else "") + f": leave {', '.join(miss)} out of --component, or add --hangings")


#: a point's reason quoted in a one-line note or message is cut to this many characters (whole in the JSON)
NOTE_CHARS = 160


def no_sigma_reason(entry: dict) -> str:
    """Why a point's component ``entry`` has no sigma, in its own words,
    for one line after the component's name: its ``sigma_unavailable``
    (a knife edge, dependent or elastic wires, a stated amplitude whose
    range reaches the half turn) or, not identifiable there, its
    ``reason``; without the leading "the uncertainty cannot be given",
    starting with ": " unless it goes on with a phrase (" on these four
    or five elastic wires: ..."), cut at :data:`NOTE_CHARS` characters
    with "..." (the sweep table's note and the binding message); "" where
    the entry holds no reason."""
    why = entry.get("sigma_unavailable") or entry.get("reason") or ""
    why = why.removeprefix("the uncertainty cannot be given")
    if why and not why.startswith((":", " ")):
        why = ": " + why
    return why if len(why) <= NOTE_CHARS else why[:NOTE_CHARS - 3].rstrip() + "..."


def pareto_front(points: list[dict], target: str | None, among=None) -> list[int]:
    """Indices of the valid points not dominated in (peak tension, objective),
    sorted by increasing peak tension (empty without the nonlinear runs)."""
    cand = [(guarded_limits(p, among)["peak"], objective(p, target, among), i) for i, p in enumerate(points)
            if p.get("valid") and p["tension"].get("peak") is not None and math.isfinite(objective(p, target, among))]
    cand.sort()
    front, best = [], math.inf
    for tp, ob, i in cand:
        if ob < best:
            front.append(i)
            best = ob
    return front


def point_components(points: list[dict]) -> list[str]:
    """The inertia components (names such as "Izz") the first valid point estimates; [] when none is valid."""
    for p in points:
        if p.get("valid"):
            return list(p["components"])
    return []
