"""Settings of a sweep or plan: what is estimated, the measurement
uncertainties, the feasibility limits, and the grid of points.

Everything is resolved from the config (``plan:`` and ``uncertainty:``
blocks) overridden by the command-line flags, and checked: a bad value is an
:class:`~bifilar.errors.InputError` naming the field or flag.  Units SI
(see :class:`SweepSettings` and :class:`Constraints`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass
from typing import Any


from ..errors import InputError
from ..estimation.sensitivity import (DEFAULT_UNCERTAINTY, INERTIA_COMPONENTS, PLANNER_UNCERTAINTY_KEYS,
                                      uncertainty_too_large)
from .shorthands import ParamSpec

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
PRINCIPAL = ("Ixx", "Iyy", "Izz")
#: the default mode-separation guard (relative): over ~12 timed cycles two modes
#: 2 % apart drift a quarter of a cycle apart, so a beating of the two is still
#: visible as a slow change of the amplitude rather than a spoiled count
DEFAULT_MIN_SEPARATION = 0.02
PLAN_KEYS = {"target", "max_tension", "max_depth", "lengths_available", "min_separation", "amplitude", "components"}

# --------------------------------------------------------------------------
# settings


@dataclass(frozen=True)
class Constraints:
    """Feasibility limits (any may be None = no limit).

    max_tension : N, the largest wire tension during the excitations.
    max_depth : m, the lowest body point below the ceiling, swing included.
    lengths_available : m, the wire lengths one can cut/buy; every wire of a
        feasible point has one of them (to 1e-6 m).
    min_separation : the smallest allowed relative gap between any timed
        mode's period and any other mode's (e.g. 0.05 = 5 %; see
        :func:`bifilar.studies.point.timed_separation`).
    """

    max_tension: float | None = None
    max_depth: float | None = None
    lengths_available: tuple[float, ...] | None = None
    min_separation: float | None = None

    @property
    def needs_nonlinear(self) -> bool:
        return self.max_tension is not None or self.max_depth is not None

    def describe(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class SweepSettings:
    """How each point is evaluated (everything here changes the figures).

    components : inertia components to estimate (body axes).
    amplitude : excitation amplitude (times each mode's normalised shape;
        rad for rotational modes, m for swings); a point may override it
        with the ``amplitude`` shorthand.
    uncertainty : standard uncertainties of the measured inputs, keys as
        :data:`~bifilar.estimation.sensitivity.DEFAULT_UNCERTAINTY`
        (``timing`` in s per measured period, ``length``/``position``/``com``
        in m, ``mass``/``gravity`` relative).
    tensions : run the nonlinear model (tensions, depth during the swing,
        amplitude bias); without it the biases are against the linear period.
    periods : number of periods simulated per mode; rtol : integrator tolerance.
    """

    components: tuple[str, ...] = PRINCIPAL
    amplitude: float = 0.05
    uncertainty: tuple[tuple[str, float], ...] = tuple(sorted(DEFAULT_UNCERTAINTY.items()))
    tensions: bool = True
    periods: float = 3.0
    rtol: float = 1e-8
    #: the multi-hanging plan's rig model (:mod:`bifilar.estimation.rig`): ``shared`` (the
    #: candidate hangings' one rig measured once) or ``separate``; a point's figures do not depend on it
    rig: str = "shared"

    @property
    def unc(self) -> dict:
        return dict(self.uncertainty)

    def describe(self) -> dict:
        d = asdict(self)
        d["uncertainty"] = self.unc
        d["components"] = list(self.components)
        return d


def _number(v: Any, field_: str, *, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise InputError(field_, f"must be a finite number, got {v!r}")
    v = float(v)
    if positive and v <= 0:
        raise InputError(field_, f"must be positive, got {v:g}")
    if nonneg and v < 0:
        raise InputError(field_, f"must not be negative, got {v:g}")
    return v


def check_component(name: str, field_: str) -> str:
    if name not in INERTIA_COMPONENTS:
        raise InputError(field_, f"unknown inertia component {name!r}; use one of {', '.join(INERTIA_COMPONENTS)}")
    return name


#: uncertainty keys only invert budgets (sweep's and plan's sigma is invert's without them): what each states
INVERT_ONLY_UNCERTAINTY = {
    "inertia": "the relative uncertainty of the inertia components not solved for, the config's priors",
    "release": "the bound on a second mode a recording's release started unseen",
}


def stated_geometry_uncertainty(cfg: dict) -> dict:
    """The config's ``uncertainty:`` block's ``position`` and ``com`` (m,
    standard uncertainties), the inputs a recorded motion's torque arms and
    wire directions rest on (``tensions --motion``), checked as
    :func:`resolve_uncertainty` checks the block; ``{}`` where it states
    neither (the estimator's defaults, 1 and 2 mm).  Audit18: the block was
    ignored there, so a stated 5 mm printed the 1 mm std."""
    block = cfg.get("uncertainty") if isinstance(cfg, dict) else None
    if not isinstance(block, dict):
        return {}
    keys = [k for k in ("position", "com") if k in block]
    unc = resolve_uncertainty({"uncertainty": {k: block[k] for k in keys}})
    return {k: unc[k] for k in keys}


def resolve_uncertainty(cfg: dict, overrides: dict | None = None) -> dict:
    """Input uncertainties: defaults < the config's ``uncertainty:`` block < ``overrides`` (flags)."""
    out = dict(DEFAULT_UNCERTAINTY)
    block = cfg.get("uncertainty") if isinstance(cfg, dict) else None
    if block is not None and not isinstance(block, dict):
        raise InputError("uncertainty", "must be a mapping like {timing: 0.001, length: 0.001}")
    for src, d in (("uncertainty", block or {}), ("--sigma", overrides or {})):
        for k, v in d.items():
            if k in INVERT_ONLY_UNCERTAINTY:
                raise InputError(f"{src}.{k}" if src == "uncertainty" else src,
                                 f"{k!r} is invert's ({INVERT_ONLY_UNCERTAINTY[k]}); sweep and plan predict invert's "
                                 "sigma without it: give it to invert's --uncertainty instead; keys here: "
                                 f"{', '.join(PLANNER_UNCERTAINTY_KEYS)}")
            if k not in PLANNER_UNCERTAINTY_KEYS:
                raise InputError(f"{src}.{k}" if src == "uncertainty" else src,
                                 f"unknown uncertainty key {k!r}; keys: {', '.join(PLANNER_UNCERTAINTY_KEYS)}")
            out[k] = _number(v, f"{src}.{k}" if src == "uncertainty" else src, nonneg=True)
            too_large = uncertainty_too_large(k, out[k])
            if too_large:
                raise InputError(f"{src}.{k}" if src == "uncertainty" else src, too_large)
    return out


def stated_timing(cfg: dict) -> float | None:
    """The config's ``uncertainty.timing`` (s, the standard uncertainty of one
    measured period), None where the config does not state it; the whole
    ``uncertainty:`` block is checked as :func:`resolve_uncertainty` checks it."""
    unc = resolve_uncertainty(cfg)
    block = cfg.get("uncertainty") if isinstance(cfg, dict) else None
    return unc["timing"] if block and "timing" in block else None


def plan_block(cfg: dict) -> dict:
    """The config's ``plan:`` block, checked (keys: :data:`PLAN_KEYS`)."""
    block = cfg.get("plan") if isinstance(cfg, dict) else None
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise InputError("plan", "must be a mapping like {max_tension: 1500, max_depth: 6}")
    for k in block:
        if k not in PLAN_KEYS:
            raise InputError(f"plan.{k}", f"unknown key; allowed: {', '.join(sorted(PLAN_KEYS))}")
    return block


def resolve_constraints(cfg: dict, max_tension=None, max_depth=None, lengths_available=None,
                        min_separation=None) -> Constraints:
    """Constraints from the ``plan:`` block, overridden by the given values
    (flags); the mode-separation guard defaults to
    :data:`DEFAULT_MIN_SEPARATION` (``0`` switches it off)."""
    block = plan_block(cfg)

    def pick(key, flag, **kw):
        if flag is not None:
            return _number(flag, "--" + key.replace("_", "-"), **kw)
        if key in block and block[key] is not None:
            return _number(block[key], f"plan.{key}", **kw)
        return None

    la = lengths_available if lengths_available is not None else block.get("lengths_available")
    if la is not None:
        src = "--lengths-available" if lengths_available is not None else "plan.lengths_available"
        if not isinstance(la, (list, tuple)) or not la:
            raise InputError(src, "must be a non-empty list of wire lengths in m")
        la = tuple(sorted(_number(v, src, positive=True) for v in la))
    return Constraints(
        max_tension=pick("max_tension", max_tension, positive=True),
        max_depth=pick("max_depth", max_depth, positive=True),
        lengths_available=la,
        min_separation=_default(pick("min_separation", min_separation, nonneg=True), DEFAULT_MIN_SEPARATION),
    )


def _default(v, d):
    return d if v is None else v


def resolve_settings(cfg: dict, components=None, amplitude=None, sigma=None, tensions=True,
                     periods=3.0, rtol=1e-8) -> SweepSettings:
    """Evaluation settings from the config (``plan:``, ``uncertainty:``) and flags."""
    block = plan_block(cfg)
    comps = components or block.get("components") or PRINCIPAL
    if isinstance(comps, str):
        comps = [comps]
    comps = tuple(dict.fromkeys(check_component(c, "--component") for c in comps))
    if amplitude is None:
        amplitude = block.get("amplitude", 0.05)
        amplitude = _number(amplitude, "plan.amplitude", positive=True)
    else:
        amplitude = _number(amplitude, "--amplitude", positive=True)
    _number(periods, "--periods", positive=True)
    if periods < 2:
        raise InputError("--periods", f"need at least 2 periods to time a cycle, got {periods:g}")
    if not 0 < rtol < 1e-3:
        raise InputError("--rtol", f"must be in (0, 1e-3), got {rtol:g}")
    unc = resolve_uncertainty(cfg, sigma)
    return SweepSettings(comps, float(amplitude), tuple(sorted(unc.items())), bool(tensions), float(periods), float(rtol))


def resolve_target(cfg: dict, target: str | None, components: tuple[str, ...]) -> str | None:
    """The component to rank by (None: the worst relative uncertainty of ``components``)."""
    src = "--target"
    if target is None:
        target = plan_block(cfg).get("target")
        src = "plan.target"
    if target is None:
        return None
    check_component(target, src)
    if target not in components:
        raise InputError(src, f"{target} is not among the estimated components {', '.join(components)}; "
                              f"add --component {target}")
    return target


# --------------------------------------------------------------------------
# grid


def build_grid(params: list[ParamSpec], zip_: bool = False) -> list[dict]:
    """Points of a sweep: the Cartesian grid of the parameters' values (first
    parameter slowest), or with ``zip_`` the values taken together."""
    if not params:
        raise InputError("--param", "give at least one --param NAME=VALUES")
    names = [p.name for p in params]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise InputError("--param", f"{dup} is given twice")
    if zip_:
        n = {len(p.values) for p in params}
        if len(n) != 1:
            raise InputError("--zip", "the parameters must have the same number of values: "
                                      + ", ".join(f"{p.name} has {len(p.values)}" for p in params))
        return [dict(zip(names, vals)) for vals in zip(*[p.values for p in params])]
    total = math.prod(len(p.values) for p in params)  # Python ints: np.prod wraps to 0 at 2**64
    if total > 100_000:
        raise InputError("--param", f"the grid has {total} points; keep it below 100000")
    return [dict(zip(names, vals)) for vals in itertools.product(*[p.values for p in params])]


def _touches(names, prefixes) -> bool:
    return any(n == p or n.startswith(p + ".") or n.startswith(p) for n in names for p in prefixes)


def unreachable(cfg: dict, source: str, names: list[str], c: Constraints) -> None:
    """Refuse, before any work, a constraint no point of the search can meet
    (:class:`InputError` naming the flag).

    * ``max_tension`` below the static load ``m g / n`` (N): the vertical
      components of the n tensions carry the weight at rest and, on
      average, during the swing, so some wire carries at least that much at
      every point; checked unless a parameter changes the mass or gravity;
    * ``lengths_available`` that the config's wires do not use, when no
      parameter changes a length.
    """
    from ..config import scene_from_dict

    if c.max_tension is not None and not _touches(names, ("body", "gravity")):
        sc = scene_from_dict(cfg, source, warn=False)
        load = sc.mass * sc.gravity / sc.n_wires
        if c.max_tension < load:
            raise InputError("--max-tension", f"{c.max_tension:g} N is below the static load m g / n = "
                                              f"{sc.mass:.6g} kg x {sc.gravity:g} m/s^2 / {sc.n_wires} wires = "
                                              f"{load:.4g} N that some wire carries at every point")
    if c.lengths_available is not None and not _touches(names, ("length", "rig.lengths")):
        sc = scene_from_dict(cfg, source, warn=False)
        off = [x for x in sc.lengths if min(abs(x - a) for a in c.lengths_available) > 1e-6]
        if off:
            raise InputError("--lengths-available", f"the wires are {', '.join(f'{x:g}' for x in sc.lengths)} m at "
                                                    "every point (no length parameter) and not all available; sweep "
                                                    "length or rig.lengths.I")
