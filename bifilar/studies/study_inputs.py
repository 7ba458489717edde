"""The inputs of a ``sweep`` or ``plan`` study from its config and options:
the evaluation settings, the constraints and the component to rank by,
each bad value refused naming its option (exit 2) before any work.

Units as the options give them: ``--sigma`` timing s, length, position,
com m, mass, gravity, stiffness relative; tensions N, depths and lengths m.
"""

from __future__ import annotations

from ..errors import InputError

MAX_SWEEP_PERIODS = 1_000
"""Most periods a ``sweep`` or ``plan`` point simulates per mode."""


def parse_sigmas(sigmas) -> dict:
    """``["timing=0.002", ...]`` (``--sigma KEY=VALUE``) -> {KEY: float};
    a later KEY replaces an earlier one.  The values' units are the keys'
    (the module's docstring); which keys exist, and their range, is
    :func:`~bifilar.studies.settings.resolve_settings`'s to check."""
    out = {}
    for s in sigmas:
        if "=" not in s:
            raise InputError("--sigma", f"{s!r} must be KEY=VALUE, e.g. timing=0.002")
        k, v = (x.strip() for x in s.split("=", 1))
        try:
            out[k] = float(v)
        except ValueError:
            raise InputError("--sigma", f"{s!r}: {v!r} is not a number") from None
    return out


def resolve_study(cfg: dict, components, target, amplitude, sigmas, max_tension, max_depth, lengths_available,
                  min_separation, no_tensions, sim_periods, names=(), source="config", rig="shared"):
    """(settings, constraints, target) of a study of config ``cfg`` (the
    YAML mapping read from ``source``) from the options: ``components``
    (names; empty: the config's ``plan.components`` or the principal
    moments), ``target`` (component or None), ``amplitude`` (rad or m, or
    None), ``sigmas`` (``KEY=VALUE`` strings, :func:`parse_sigmas`),
    ``max_tension`` (N), ``max_depth`` (m), ``lengths_available`` (the
    ``L1,L2,...`` string, m, or None), ``min_separation`` (relative),
    ``no_tensions`` (skip the nonlinear runs), ``sim_periods`` (periods a
    point's runs simulate per mode, at most :data:`MAX_SWEEP_PERIODS`),
    ``rig`` (``shared`` or ``separate``, the multi-hanging plan's rig).
    Raises :class:`~bifilar.errors.InputError` naming the option on bad
    input, or at once when no point of a search over the parameters
    ``names`` (dotted config paths or shorthands) can meet a constraint
    (:func:`~bifilar.studies.settings.unreachable`)."""
    from dataclasses import replace

    from ..estimation.rig import RIG_MODELS
    from .settings import resolve_constraints, resolve_settings, resolve_target, unreachable
    from .shorthands import parse_values

    if sim_periods is not None and sim_periods > MAX_SWEEP_PERIODS:
        raise InputError("--periods", f"must be at most {MAX_SWEEP_PERIODS} periods per mode, got {sim_periods:g}")
    if rig not in RIG_MODELS:
        raise InputError("--rig", f"must be one of {', '.join(RIG_MODELS)}, got {rig!r}")
    la = None
    if lengths_available is not None:
        la = [float(v) for v in parse_values(lengths_available, "--lengths-available")]
    cons = resolve_constraints(cfg, max_tension, max_depth, la, min_separation)
    settings = resolve_settings(cfg, components=list(components) or None, amplitude=amplitude,
                                sigma=parse_sigmas(sigmas), tensions=not no_tensions, periods=sim_periods)
    settings = replace(settings, rig=rig)
    if no_tensions and cons.needs_nonlinear:
        which = "--max-tension" if cons.max_tension is not None else "--max-depth"
        raise InputError("--no-tensions", f"{which} needs the nonlinear run; drop one of them")
    both = sorted(set(parse_sigmas(sigmas)) & {n.split(".", 1)[1] for n in names if n.startswith("uncertainty.")})
    if both:
        raise InputError("--sigma", f"{both[0]} is both set by --sigma and swept as uncertainty.{both[0]}; drop one")
    unreachable(cfg, source, list(names), cons)
    return settings, cons, resolve_target(cfg, target, settings.components)
