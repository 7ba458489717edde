"""What a study says about its recommended (``sweep``) or planned
(``plan``) point beside its accuracy: the point's config and the file of
it, the cautions to give with it, the remedies of the components no point
measures and how to time its modes.

A point is a sweep point dict (:func:`bifilar.studies.point.evaluate_point`'s,
``params`` {name: value, SI}, ``periods`` s, ``components`` with sigmas in
kg m^2 or m); the base config ``base_cfg`` is the YAML mapping read from
``source``.
"""

from __future__ import annotations


def point_config(base_cfg: dict, source: str, point: dict) -> dict:
    """The config of ``point``: the base config edited by its parameters
    (:func:`bifilar.studies.shorthands.apply_params`)."""
    from .shorthands import apply_params

    cfg, _ = apply_params(base_cfg, point["params"], source)
    return cfg


def write_point_config(path, base_cfg: dict, source: str, point: dict, what: str) -> None:
    """Write ``point``'s config (YAML, atomically, :func:`bifilar.output.write_yaml`)
    to ``path`` with its parameters and planned linear periods (s) in a
    header comment (``what`` names the point, e.g. ``point 3 recommended by
    bifilar sweep``); ``bifilar modes`` reproduces the periods."""
    from ..output import write_yaml

    write_yaml(path, point_config(base_cfg, source, point),
               [f"{what} of {source}", "parameters: " + ", ".join(f"{k} = {v:.10g}" for k, v in point["params"].items()),
                "planned linear periods (s): " + ", ".join(f"{k} {v:.8g}" for k, v in point["periods"].items() if v),
                "check: bifilar modes THIS_FILE"])


def point_cautions(cfg: dict, source: str, point: dict, what: str, cons=None, joint: dict | None = None) -> list[str]:
    """The cautions of a recommended or planned ``point``, each one line
    ``WHAT: ...`` (``what``: e.g. ``the recommended point``): the config
    plausibility warnings (:func:`bifilar.studies.sweep.point_warnings`),
    the priors a plausible error of which would move an estimate
    (:func:`bifilar.studies.sweep.prior_cautions`), its components'
    ``physical_limit`` (an estimate often outside what a real body can
    have) and, under the constraints ``cons``, its dependent wires' range
    above ``--max-tension`` (:func:`bifilar.studies.ranking.tension_range_caution`)
    and a body hanging far turned at rest
    (:func:`bifilar.analysis.rest_warnings.turn_warning`).
    ``joint``: the multi-hanging plan's ``accuracy`` when that plan is the
    experiment (``--hangings``): its components' limits are those of the
    joint sigma, not of the point's own hanging (whose Ixx from a swing, a
    300 % sigma, warned of 68 % of experiments where the plan's 0.44 % puts
    the limit 94 sigmas away)."""
    from .ranking import tension_range_caution
    from .sweep import point_warnings as check
    from .sweep import prior_cautions

    out = [f"{what}: {w}" for w in check(cfg, source, point["params"])]
    out += [f"{what}: {w}" for w in prior_cautions(cfg, source, point)]
    joint = joint or {}
    out += [f"{what}: {c}: {e['physical_limit']}" for c, e in point.get("components", {}).items()
            if c not in joint and e.get("physical_limit")]
    out += [f"{what}: {c} by the multi-hanging plan: {e['physical_limit']}" for c, e in joint.items()
            if e.get("physical_limit")]
    if cons is not None and (w := tension_range_caution(point, cons)) is not None:
        out.append(f"{what}: {w}")
    from ..analysis.rest_warnings import TURN_WARNING_HEAD

    out += [f"{what}: {w}" for w in point.get("warnings") or () if w.startswith(TURN_WARNING_HEAD)]
    return out


def timing_advice(point: dict, reaction: float, sensor, min_separation: float | None = None) -> list[dict]:
    """How to time ``point``'s modes to reach its assumed timing sigma
    (:func:`bifilar.studies.timing.how_to_time`; ``reaction`` s, a
    stopwatch trial's std; ``sensor`` (noise relative to the amplitude,
    rate Hz) or None).  ``min_separation`` (relative; None or 0: every
    mode): only the modes at least that far from the others (the search
    left the guard to the multi-hanging plan, whose measurements say how to
    time the rest)."""
    from .timing import how_to_time

    rows = how_to_time(point, point["uncertainty"]["timing"], reaction, sensor)
    return [r for r in rows if not min_separation or r["separation"] is None or r["separation"] >= min_separation]
