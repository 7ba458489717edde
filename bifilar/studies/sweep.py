"""Compare suspension configurations: the sweep engine behind ``bifilar sweep``.

Every point of a sweep is a full scene: the base config is copied, edited by
dotted path or shorthand (:mod:`bifilar.studies.shorthands`) and validated by
:func:`bifilar.config.scene_from_dict` like any config.  An invalid point
(bad config, slack wire, unstable rest, solver failure) is kept with its
one-line reason and skipped, never a crash.

Figures per valid point (SI units; world frame z up; inertia components in
the body axes of the point's scene):

* ``periods``: linear period of every mode, s (``None`` for a neutral mode);
* per inertia component (default ``Ixx Iyy Izz``), estimated from its
  best-suited mode (:func:`~bifilar.estimation.sensitivity.best_mode_for`):
  the relative sensitivity of the estimate to the period
  ``(dI/I)/(dT/T)`` and to every measured input ``d ln I / d x`` (1/unit of
  x), the predicted standard uncertainty ``sigma`` (kg m^2) and
  ``rel_sigma`` for the stated measurement errors
  (:func:`~bifilar.estimation.sensitivity.inertia_budget`), the variance
  shares by kind, the mode separation (relative distance from the chosen
  mode's period to the nearest other period: close periods beat and ruin
  the timing), and the relative bias of simple estimators against the full
  model at the prescribed amplitude: the small-angle formula (thesis
  5.2.18), the thesis's linearisation (§7.1), and the exact linear model
  (the amplitude error of linear theory);
* ``tension``: rest tension per wire, and peak and minimum tension per wire
  during the prescribed excitation of each chosen mode (nonlinear model,
  the chosen modes of a point in one call of the batched engine
  :func:`~bifilar.analysis.batch.simulate_batch`, a few periods at
  rtol 1e-8), with slack detection; ``depth``: depth of the lowest body
  point below the ceiling at rest and the largest during the excitation, m.

The biases: each estimator is fed the period the full model shows at the
amplitude (or, without the nonlinear runs, the linear period) and its
estimate compared with the config's value.  The small-angle formula and the
thesis's linearisation come from :mod:`bifilar.estimation.invert` (the
small-angle formula: two wires D = the attachment spacing, h = the mean
vertical drop of the wires at rest; n >= 3 wires its multifilar analogue;
torsion about the vertical only); the exact linear model is inverted here
(:func:`linear_estimate`).

A component that no mode's period depends on (``|d ln T / d ln I| < 1e-6``
for every mode, e.g. the pitch inertia of a body on two vertical wires: its
in-plane swing is a pure translation) is reported with ``identifiable:
false`` and an infinite (``null``) uncertainty.

Each point's figures depend only on the base config, the point's parameters
and the evaluation settings (every rest pose is found afresh by the
deterministic search rather than continued from a neighbour, which would
make a point depend on the order of evaluation: it costs ~2 ms of the
~130 ms a point takes), so results are identical for any ``workers`` count
and for a resumed sweep.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..jsonable import to_jsonable
from ..errors import BifilarError, ConvergenceError, InputError, SlackWireError, UnstableRestError
from ..estimation.sensitivity import DEFAULT_UNCERTAINTY, INERTIA_COMPONENTS
from .shorthands import ParamSpec, apply_params

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
PRINCIPAL = ("Ixx", "Iyy", "Izz")
#: below this |d ln T / d ln I| for every mode a component counts as not identifiable
IDENTIFIABLE_MIN = 1e-6
PLAN_KEYS = {"target", "max_tension", "max_depth", "lengths_available", "min_separation", "amplitude", "components"}
JOURNAL_VERSION = 1


# --------------------------------------------------------------------------
# settings


@dataclass(frozen=True)
class Constraints:
    """Feasibility limits (any may be None = no limit).

    max_tension : N, the largest wire tension during the excitations.
    max_depth : m, the lowest body point below the ceiling, swing included.
    lengths_available : m, the wire lengths one can cut/buy; every wire of a
        feasible point has one of them (to 1e-6 m).
    min_separation : relative distance between a chosen mode's period and
        the nearest other period (e.g. 0.05 = 5 %).
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


def resolve_uncertainty(cfg: dict, overrides: dict | None = None) -> dict:
    """Input uncertainties: defaults < the config's ``uncertainty:`` block < ``overrides`` (flags)."""
    out = dict(DEFAULT_UNCERTAINTY)
    block = cfg.get("uncertainty") if isinstance(cfg, dict) else None
    if block is not None and not isinstance(block, dict):
        raise InputError("uncertainty", "must be a mapping like {timing: 0.001, length: 0.001}")
    for src, d in (("uncertainty", block or {}), ("--sigma", overrides or {})):
        for k, v in d.items():
            if k not in DEFAULT_UNCERTAINTY:
                raise InputError(f"{src}.{k}" if src == "uncertainty" else src,
                                 f"unknown uncertainty key {k!r}; keys: {', '.join(DEFAULT_UNCERTAINTY)}")
            out[k] = _number(v, f"{src}.{k}" if src == "uncertainty" else src, nonneg=True)
    return out


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
    """Constraints from the ``plan:`` block, overridden by the given values (flags)."""
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
        min_separation=pick("min_separation", min_separation, nonneg=True),
    )


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


# --------------------------------------------------------------------------
# one point


_plain = to_jsonable  # point dicts read back from a journal equal the computed ones


def _one_line(exc: BaseException) -> str:
    errs = getattr(exc, "errors", None)
    if errs:
        more = f" (+{len(errs) - 1} more)" if len(errs) > 1 else ""
        return str(errs[0]).splitlines()[0] + more
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _fd_step(scene, name: str, rel_step: float = 1e-6) -> float:
    """Finite-difference step of :func:`~bifilar.estimation.sensitivity.period_sensitivity`."""
    if name in _IDX:
        return rel_step * float(np.max(np.linalg.eigvalsh(scene.inertia)))
    if name in ("mass", "gravity"):
        return rel_step * float(getattr(scene, name))
    return rel_step * float(np.max(scene.lengths))


#: rad: a neighbour (1e-6 relative input step) whose rest pose turned more than this jumped branch
TURN_MAX = 1e-3


def _neighbour_rest(scene, base, global_search: bool):
    """Rest pose of a finite-difference neighbour on the branch through
    ``base`` (Newton from it; the global search only if that fails and
    ``global_search``), or None when there is none near ``base``."""
    from ..analysis import equilibrium as eq
    from ..rotations import matrix_to_rotvec

    local = getattr(eq, "_from_guess", None)  # TODO(lead): a public rest_pose(..., local_only=True)
    r = local(scene, base) if local is not None else None
    if r is None and global_search:
        try:
            r = eq.rest_pose(scene, guess=base)
        except (UnstableRestError, SlackWireError, ConvergenceError):
            r = None
    if r is None or float(np.linalg.norm(matrix_to_rotvec(r.R @ base.R.T))) > TURN_MAX:
        return None
    return r


def point_sensitivity(scene, names: list[str], rest=None):
    """:func:`~bifilar.estimation.sensitivity.period_sensitivity`, robust at
    the edge of stability.

    A scene with a neutral mode (e.g. a thin plate whose CoM lies on the
    attachment line) has neighbours that cannot hang near its rest pose:
    a micrometre's change turns the body over (Newton from the rest pose
    lands on a pose turned by ~1 rad).  A derivative must follow the local
    branch, so each side's rest pose must stay within :data:`TURN_MAX` of the
    base pose; otherwise that side is dropped (one-sided difference, first
    order: relative error ~1e-6), and an input with no side left is left out
    of the uncertainty budget (its column set to 0) with a note.  Regular
    scenes take the shared central differences.  Returns (Sensitivity, notes).
    """
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes
    from ..estimation.sensitivity import Sensitivity, perturb, period_sensitivity, periods_of

    rest = rest if rest is not None else rest_pose(scene)
    ms = linear_modes(scene, rest)
    T0 = np.array([m.period if m.period else np.nan for m in ms.modes])
    neutral = not np.all(np.isfinite(T0))
    if not neutral:
        try:
            return period_sensitivity(scene, names), []
        except (UnstableRestError, SlackWireError, ConvergenceError):
            pass
    jac = np.zeros((len(T0), len(names)))
    notes = []
    for j, name in enumerate(names):
        h = _fd_step(scene, name)
        side = {}
        for sgn in (1.0, -1.0):
            sc = perturb(scene, name, sgn * h)
            r = _neighbour_rest(sc, rest, global_search=not neutral)
            if r is not None:
                side[sgn] = periods_of(sc, ms, r)
        if len(side) == 2:
            jac[:, j] = (side[1.0] - side[-1.0]) / (2 * h)
        elif side:
            sgn, T1 = next(iter(side.items()))
            jac[:, j] = (T1 - T0) / (sgn * h)
            notes.append(f"{name}: one-sided derivative (no nearby stable rest for a {'-+'[sgn < 0]}{h:.1e} change)")
        else:
            notes.append(f"{name}: left out of the budget (no nearby stable rest for a {h:.1e} change either way: "
                         "the point is at the edge of stability)")
    return Sensitivity(list(names), T0, jac, ms, rest), notes


def linear_estimate(scene, comp: str, k: int, T_target: float, modes, rest, slope: float,
                    T0: float | None = None) -> float | None:
    """The exact linear model's estimate of ``comp`` (kg m^2): the value for
    which the linear period of mode ``k`` of ``modes`` (tracked by MAC, rest
    poses warm-started from ``rest``) equals ``T_target`` (s), the other
    inputs as in ``scene``.  Secant iteration from ``slope`` = dT/dI (s per
    kg m^2) to 1e-13 in the period; ``T0`` the period at the scene's value
    (computed if None).  None if a step leaves the stable region."""
    from ..estimation.sensitivity import perturb, periods_of

    I0 = float(scene.inertia[_IDX[comp]])
    try:
        if T0 is None:
            T0 = float(periods_of(scene, modes, rest)[k])
        x0, f0 = 0.0, float(T0 - T_target)
        if f0 == 0.0:
            return I0
        x1 = -f0 / float(slope)
        for _ in range(12):
            f1 = float(periods_of(perturb(scene, comp, x1), modes, rest)[k] - T_target)
            if abs(f1) <= 1e-13 * T_target or f1 == f0:
                return I0 + x1
            x0, f0, x1 = x1, f1, x1 - f1 * (x1 - x0) / (f1 - f0)
    except (UnstableRestError, SlackWireError, ConvergenceError):
        return None
    return None


class _Ladder:
    """The simple estimators of :mod:`bifilar.estimation.invert` applied to
    one point: the small-angle formula (thesis 5.2.18; two wires: D = the
    attachment spacing, h = the mean vertical drop of the wires at rest;
    n >= 3: the multifilar analogue with R = the mean horizontal distance of
    the attachments from the CoM's vertical) and the thesis's section 7.1
    linearisation of its Kane model (two wires, anchors at one height,
    inclined wires).  Falls back to :func:`bifilar.models.reduced.small_angle_inertia`
    (and marks the thesis's method pending) when that module is absent.
    """

    def __init__(self, scene, rest):
        self.scene, self.rest = scene, rest
        try:
            from ..estimation import invert as inv
            from ..estimation.measurements import Hanging
        except ImportError:
            inv = Hanging = None
        self.inv = inv if inv is not None and hasattr(inv, "ThesisModel") else None
        self._Hanging = Hanging
        self._hm = None

    def small_angle(self, comp: str, T: float) -> float:
        """Estimate of ``comp`` (kg m^2): the formula gives the moment about the
        vertical; the other components keep their prior."""
        sc, rest = self.scene, self.rest
        if self.inv is not None:
            I_v, _ = self.inv.small_angle_vertical_inertia(sc, rest, T)
        else:
            from ..models.reduced import small_angle_inertia

            P = rest.com + sc.attachments @ rest.R.T
            h = float(np.mean(sc.anchors[:, 2] - P[:, 2]))
            if sc.n_wires == 2:
                D = float(np.linalg.norm(P[0] - P[1]))
            else:
                D = 2.0 * float(np.mean(np.linalg.norm(P[:, :2] - rest.com[:2], axis=1)))
            I_v = float(small_angle_inertia(sc.mass, sc.gravity, D, h, T))
        n = rest.R.T @ np.array([0.0, 0.0, 1.0])  # the vertical in body axes
        a = _IDX[comp][0]
        return float(sc.inertia[a, a] + (I_v - n @ sc.inertia @ n) / n[a] ** 2)

    def thesis(self, comp: str, mode_label: str, T: float) -> tuple[float | None, str]:
        """(estimate in kg m^2 or None, note)."""
        inv = self.inv
        if inv is None:
            return None, "pending: bifilar.estimation.invert (the thesis's linearisation) not available"
        try:
            if self._hm is None:
                self._hm = inv.HangingModel(self._Hanging("sweep point", self.scene, np.eye(3)), self.scene.inertia)
            hm = self._hm
            tm = inv.ThesisModel(hm, hm.mode_index(mode_label, "mode"), comp)
            lo, hi = inv.physical_interval(self.scene.inertia, comp)
            scale = float(np.max(np.linalg.eigvalsh(self.scene.inertia)))
            x = inv.solve_scalar(tm.period, T, float(self.scene.inertia[_IDX[comp]]), lo, hi, scale, "mode", comp)
            return float(x), f"linearisation {tm.which} of thesis section 7.1"
        except inv.NotApplicable as exc:
            return None, str(exc)
        except (BifilarError, ValueError, ArithmeticError) as exc:
            return None, _one_line(exc)

    def biases(self, comp: str, mode_label: str, T_ref: float, axis_vertical: bool) -> tuple[dict, dict]:
        """Relative bias of each estimator fed the reference period ``T_ref`` (s)."""
        I_true = float(self.scene.inertia[_IDX[comp]])
        bias: dict = {"small_angle": None, "thesis": None}
        notes: dict = {}
        if mode_label.startswith("torsion") and axis_vertical:
            bias["small_angle"] = self.small_angle(comp, T_ref) / I_true - 1
        else:
            notes["small_angle"] = "applies only to the torsion about the vertical axis"
        x, notes["thesis"] = self.thesis(comp, mode_label, T_ref)
        if x is not None:
            bias["thesis"] = x / I_true - 1
        return bias, notes


def _nonlinear_runs(scene, rest, ms, labels: list[str], amplitude: float, st: SweepSettings) -> list:
    """One nonlinear run per mode label from ``amplitude`` x its shape, all
    in one call of the batched engine (:func:`bifilar.analysis.batch.simulate_batch`;
    :func:`bifilar.analysis.simulate.simulate` one by one if it is absent).
    Each result has .period, .tension_min/.tension_max (n,) N, .slack,
    .depth_max m, .mode, .warnings."""
    if not labels:
        return []
    try:
        from ..analysis.batch import simulate_batch
    except ImportError:
        from ..analysis.simulate import simulate

        return [simulate(scene, lab, amplitude, st.periods, rest=rest, modes=ms, rtol=st.rtol) for lab in labels]
    n = len(labels)
    return simulate_batch([scene] * n, mode=labels, amplitude=amplitude, periods=st.periods, rtol=st.rtol,
                          rests=[rest] * n, modes=[ms] * n)


def evaluate_point(base_cfg: dict, source: str, params: dict, settings: SweepSettings) -> dict:
    """All figures of one sweep point (see the module docstring); never raises
    for a bad point: ``valid: false`` and a one-line ``error`` instead."""
    out: dict = {"params": dict(params), "valid": False, "error": None}
    try:
        out.update(_evaluate(base_cfg, source, params, settings))
        out["valid"] = True
    except (KeyboardInterrupt, SystemExit):
        raise
    except BifilarError as exc:
        out["error"] = _one_line(exc)
    except Exception as exc:  # noqa: BLE001 - a sweep point must never crash the sweep
        out["error"] = f"internal error ({type(exc).__name__}: {_one_line(exc)})"
    return _plain(out)


def _evaluate(base_cfg: dict, source: str, params: dict, st: SweepSettings) -> dict:
    from ..analysis.equilibrium import rest_pose
    from ..config import scene_from_dict
    from ..estimation.budget import component_std  # issue 10 (budget)
    from ..estimation.sensitivity import best_mode_for, grouped_shares, inertia_budget, measured_inputs

    cfg, amp_override = apply_params(base_cfg, params, source)
    amplitude = st.amplitude if amp_override is None else amp_override
    if not amplitude > 0:
        raise InputError("amplitude", f"must be positive, got {amplitude:g}")
    scene = scene_from_dict(cfg, source, warn=False)  # the base config's warnings were shown once
    rest0 = rest_pose(scene)  # invalid points (slack, unstable) fail here with their reason
    unc = st.unc
    names = list(st.components) + measured_inputs(scene)
    sens, notes = point_sensitivity(scene, names, rest0)
    ms, rest = sens.modes, sens.rest
    labels = [m.label for m in ms.modes]
    periods = sens.periods
    res: dict = {
        "amplitude": amplitude,
        "mass": scene.mass,
        "lengths": scene.lengths,
        "periods": {m.label: m.period for m in ms.modes},
        "components": {},
        "notes": notes,
        "warnings": [],
    }
    chosen: dict[str, int] = {}
    for comp in st.components:
        I = float(scene.inertia[_IDX[comp]])
        col = sens.column(comp)
        rel = np.abs(col) * abs(I) / np.where(np.isfinite(periods), periods, np.inf) if I != 0 else np.abs(col)
        rel = np.where(np.isfinite(rel), rel, 0.0)
        entry: dict = {"value": I, "identifiable": bool(rel.max() >= IDENTIFIABLE_MIN)}
        if not entry["identifiable"]:
            entry.update(mode=None, sigma=math.inf, rel_sigma=math.inf,
                         reason=f"no mode's period depends on {comp} (max |d ln T / d ln {comp}| = {rel.max():.1e})")
            res["components"][comp] = entry
            continue
        k = best_mode_for(sens, comp)
        chosen[comp] = k
        b = inertia_budget(sens, scene, comp, k, unc["timing"], unc)
        # issue 10 (budget): the std invert prints, second order where the linear one is wrong
        sigma = component_std(scene, comp, labels[k], unc, unc["timing"], fallback=b.value_sigma)
        j_all = [j for j, n in enumerate(sens.names) if n not in _IDX]
        dI_dx = {sens.names[j]: -float(sens.jacobian[k, j] / col[k]) for j in j_all}
        others = [periods[i] for i in range(len(periods)) if i != k and np.isfinite(periods[i])]
        sep = float(min(abs(periods[k] - p) for p in others) / periods[k]) if others else math.inf
        axis = _IDX[comp][0] if comp in PRINCIPAL else None
        entry.update(
            mode=labels[k], period=float(periods[k]),
            sigma=sigma, rel_sigma=sigma / abs(I) if I else math.inf,
            rel_sensitivity_period=b.rel_sensitivity,
            dlnI_dx={n: v / I for n, v in dI_dx.items()} if I else dI_dx,
            shares=grouped_shares(b), separation=sep,
            axis_vertical=bool(axis is not None and abs(rest.R[2, axis]) > 0.99),
        )
        res["components"][comp] = entry
    # nonlinear runs: one per chosen mode
    sims: dict[int, Any] = {}
    if st.tensions:
        ks = sorted(set(chosen.values()))
        from ..analysis.simulate import initial_state

        for k in ks:  # the refusal `simulate` gives (InputError) rather than a run from an unreachable start
            initial_state(scene, rest, ms.modes[k], amplitude)
        sims = dict(zip(ks, _nonlinear_runs(scene, rest, ms, [labels[k] for k in ks], amplitude, st)))
        tmax = np.max([s.tension_max for s in sims.values()], axis=0) if sims else rest.tensions
        tmin = np.min([s.tension_min for s in sims.values()], axis=0) if sims else rest.tensions
        slack = sorted({w for s in sims.values() for w, _ in s.slack})
        res["tension"] = {"rest": rest.tensions, "max": tmax, "min": tmin, "peak": float(np.max(tmax)),
                          "slack": bool(slack), "slack_wires": slack, "by_mode": {
                              labels[k]: {"max": s.tension_max, "min": s.tension_min} for k, s in sims.items()}}
        depth_max = max([rest.depth] + [s.depth_max for s in sims.values()])
        res["depth"] = {"rest": rest.depth, "max": depth_max}
        for s in sims.values():
            res["warnings"] += [f"{s.mode}: {w}" for w in s.warnings]
    else:
        res["tension"] = {"rest": rest.tensions, "max": None, "min": None, "peak": None, "slack": None,
                          "slack_wires": [], "by_mode": {}}
        res["depth"] = {"rest": rest.depth, "max": None}
    # biases at the prescribed amplitude
    ladder = _Ladder(scene, rest)
    for comp, k in chosen.items():
        e = res["components"][comp]
        T_lin = float(periods[k])
        T_nl = sims[k].period if k in sims else None
        T_ref = T_nl if T_nl is not None else T_lin
        bias, bnotes = ladder.biases(comp, labels[k], T_ref, e["axis_vertical"])
        I_lin = linear_estimate(scene, comp, k, T_ref, ms, rest, sens.column(comp)[k], float(periods[k]))
        bias["linear"] = (I_lin - e["value"]) / e["value"] if I_lin is not None and e["value"] else None
        e.update(nonlinear_period=T_nl, bias=bias, bias_reference="nonlinear" if T_nl else "linear",
                 bias_notes=bnotes)
        if st.tensions and T_nl is None:
            bnotes["linear"] = "no period measured in the nonlinear run; biases against the linear period"
    return res


# --------------------------------------------------------------------------
# many points: workers, journal, resume


class SweepInterrupted(KeyboardInterrupt):
    """The sweep stopped early (Ctrl-C or a point budget); finished points are
    in the journal.  ``done``: number of points finished."""

    def __init__(self, done: int, total: int):
        super().__init__(f"sweep interrupted after {done} of {total} points")
        self.done = done
        self.total = total


def point_key(params: dict) -> str:
    """Canonical text of a point's parameters (exact floats)."""
    return json.dumps({k: float(v) for k, v in params.items()}, sort_keys=True)


def fingerprint(base_cfg: dict, settings: SweepSettings) -> str:
    """Hash of everything that determines a point's figures besides its parameters."""
    doc = json.dumps({"config": base_cfg, "settings": settings.describe(), "version": JOURNAL_VERSION},
                     sort_keys=True, default=str)
    return hashlib.sha256(doc.encode()).hexdigest()[:16]


def journal_path(out: str | os.PathLike) -> Path:
    return Path(str(out) + ".partial.jsonl")


def read_journal(path: Path, fp: str) -> dict[str, dict]:
    """Finished points of an interrupted sweep, by :func:`point_key`.

    A torn last line (interrupted while writing) is cut off the file.  A
    journal written for another config or other settings, or holding lines
    that are not sweep records, is refused (:class:`~bifilar.errors.InputError`
    naming ``--resume``).
    """
    from ..output import read_journal as read_jsonl

    def check_header(head) -> None:
        if not isinstance(head, dict) or head.get("journal") != "bifilar-sweep":
            raise InputError("--resume", f"{path} is not a sweep journal")
        if head.get("fingerprint") != fp:
            raise InputError("--resume", f"{path} was written for another config or other settings "
                                         "(components, amplitude, uncertainties, tensions); rerun with --force to start over")

    def is_record(rec) -> bool:
        return isinstance(rec, dict) and isinstance(rec.get("key"), str) and isinstance(rec.get("point"), dict)

    _, records = read_jsonl(path, check_header, is_record)
    return {rec["key"]: rec["point"] for rec in records}


def _journal_writer(path: Path | None, fp: str, append: bool):
    from ..output import JournalWriter

    return JournalWriter(path, {"journal": "bifilar-sweep", "version": JOURNAL_VERSION, "fingerprint": fp},
                         append=append)


def effective_workers(workers: int, points: int) -> int:
    """Processes a sweep of ``points`` points actually starts for ``--workers
    workers``: never more than the points, nor than the CPUs (``os.cpu_count``)."""
    return max(1, min(int(workers), int(points), os.cpu_count() or 1))


def _ignore_sigint() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and keeps finished points


def run_sweep(base_cfg: dict, source: str, grid: list[dict], settings: SweepSettings, *, workers: int = 1,
              journal: Path | None = None, resume: bool = False, progress: Callable[[int, int], None] | None = None,
              stop_after: int | None = None) -> list[dict]:
    """Evaluate every point of ``grid`` (list of {param: value}); returns the
    point dicts in grid order.

    workers : processes (``concurrent.futures.ProcessPoolExecutor``) when > 1.
    journal : append each finished point to this JSON-lines file; with
        ``resume`` the points already in it are reused (same params -> same
        result) instead of recomputed.
    stop_after : stop (raising :class:`SweepInterrupted`) after this many
        newly computed points: a reproducible stand-in for Ctrl-C.
    Raises :class:`SweepInterrupted` on Ctrl-C too; finished points are in the journal.
    """
    fp = fingerprint(base_cfg, settings)
    done: dict[str, dict] = {}
    if resume and journal is not None and journal.exists():
        done = read_journal(journal, fp)
    keys = [point_key(p) for p in grid]
    results: list[dict | None] = [done.get(k) for k in keys]
    todo = [i for i, r in enumerate(results) if r is None]
    total = len(grid)
    finished = total - len(todo)
    jr = _journal_writer(journal, fp, append=resume)
    new = 0
    if progress:
        progress(finished, total)

    def record(i: int, point: dict) -> None:
        nonlocal finished, new
        results[i] = point
        jr.add({"key": keys[i], "point": point})
        finished += 1
        new += 1
        if progress:
            progress(finished, total)

    try:
        if workers <= 1 or len(todo) <= 1:
            for i in todo:
                if stop_after is not None and new >= stop_after:
                    raise SweepInterrupted(finished, total)
                record(i, evaluate_point(base_cfg, source, grid[i], settings))
        else:
            from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

            ex = ProcessPoolExecutor(max_workers=effective_workers(workers, len(todo)), initializer=_ignore_sigint)
            try:
                pending = {ex.submit(evaluate_point, base_cfg, source, grid[i], settings): i for i in todo}
                while pending:
                    ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for f in ready:
                        i = pending.pop(f)
                        if stop_after is not None and new >= stop_after:
                            raise SweepInterrupted(finished, total)
                        record(i, f.result())
            finally:
                ex.shutdown(wait=True, cancel_futures=True)
    except SweepInterrupted:
        raise
    except KeyboardInterrupt:
        raise SweepInterrupted(finished, total) from None
    finally:
        jr.close()
    return results  # type: ignore[return-value]


# --------------------------------------------------------------------------
# feasibility, ranking, recommendation


def objective(point: dict, target: str | None) -> float:
    """Relative standard uncertainty the ranking minimises: of ``target``, or
    the worst of the point's components (inf when not identifiable)."""
    if not point.get("valid"):
        return math.inf
    comps = point["components"]
    vals = [comps[target]["rel_sigma"]] if target else [c["rel_sigma"] for c in comps.values()]
    vals = [math.inf if v is None else v for v in vals]
    return float(max(vals)) if vals else math.inf


def _target_modes(point: dict, target: str | None) -> list[dict]:
    comps = point["components"]
    sel = [comps[target]] if target else list(comps.values())
    return [c for c in sel if c.get("identifiable")]


def violations(point: dict, c: Constraints, target: str | None = None) -> list[tuple[str, str]]:
    """(constraint, message) for every limit the point breaks."""
    out: list[tuple[str, str]] = []
    if not point.get("valid"):
        return [("valid", point.get("error") or "invalid")]
    t = point["tension"]
    if t.get("slack"):
        out.append(("slack", f"wire(s) {', '.join(map(str, t['slack_wires']))} go slack during the excitation"))
    if c.max_tension is not None:
        if t.get("peak") is None:
            out.append(("max_tension", "no nonlinear run (tensions off)"))
        elif t["peak"] > c.max_tension:
            out.append(("max_tension", f"peak tension {t['peak']:.4g} N > {c.max_tension:g} N"))
    if c.max_depth is not None:
        d = point["depth"].get("max")
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
        seps = [e["separation"] for e in _target_modes(point, target) if e.get("separation") is not None]
        if seps and min(seps) < c.min_separation:
            out.append(("min_separation", f"mode separation {100 * min(seps):.3g} % < {100 * c.min_separation:g} %"))
    return out


CONSTRAINT_FLAGS = {"max_tension": "--max-tension", "max_depth": "--max-depth",
                    "lengths_available": "--lengths-available", "min_separation": "--min-separation",
                    "slack": "--amplitude", "valid": "--param"}


def binding_constraint(points: list[dict], c: Constraints, target: str | None) -> tuple[str, str]:
    """Which limit leaves no point feasible: (flag name, message)."""
    valid = [p for p in points if p.get("valid")]
    if not valid:
        reasons = sorted({p.get("error") or "?" for p in points})
        return "--param", "no valid configuration in the range: " + "; ".join(reasons[:3])
    finite = [p for p in valid if math.isfinite(objective(p, target))]
    if not finite:
        what = target or "every component"
        return "--target", f"{what} is not identifiable from any mode anywhere in the range"
    viol = [dict(violations(p, c, target)) for p in finite]
    names = [n for n in ("slack", "max_tension", "max_depth", "lengths_available", "min_separation")
             if any(n in v for v in viol)]
    # the constraint that no point satisfies, else the one whose removal frees the most points
    never = [n for n in names if all(n in v for v in viol)]
    best = never[0] if never else max(names, key=lambda n: sum(set(v) == {n} for v in viol))
    flag = CONSTRAINT_FLAGS[best]
    if best == "max_tension":
        lo = min(p["tension"]["peak"] for p in finite if p["tension"].get("peak") is not None)
        msg = f"no configuration meets --max-tension {c.max_tension:g} N: the lowest peak tension found is {lo:.4g} N"
    elif best == "max_depth":
        lo = min(p["depth"]["max"] for p in finite if p["depth"].get("max") is not None)
        msg = f"no configuration meets --max-depth {c.max_depth:g} m: the smallest depth found is {lo:.4g} m"
    elif best == "min_separation":
        hi = max(min(e["separation"] for e in _target_modes(p, target)) for p in finite)
        msg = (f"no configuration meets --min-separation {c.min_separation:g}: the best mode separation "
               f"found is {hi:.3g}")
    elif best == "slack":
        msg = "every configuration lets a wire go slack during the excitation; reduce --amplitude"
    else:
        msg = "no configuration uses only the available wire lengths " + ", ".join(f"{a:g}" for a in c.lengths_available)
    others = [CONSTRAINT_FLAGS[n] for n in names if n != best]
    if others:
        msg += f" (also limiting: {', '.join(others)})"
    return flag, msg


def pareto_front(points: list[dict], target: str | None) -> list[int]:
    """Indices of the valid points not dominated in (peak tension, objective),
    sorted by increasing peak tension."""
    cand = [(p["tension"]["peak"], objective(p, target), i) for i, p in enumerate(points)
            if p.get("valid") and p["tension"].get("peak") is not None and math.isfinite(objective(p, target))]
    cand.sort()
    front, best = [], math.inf
    for tp, ob, i in cand:
        if ob < best:
            front.append(i)
            best = ob
    return front


def assess(points: list[dict], constraints: Constraints, target: str | None) -> dict:
    """Mark each point ``feasible`` / ``violations`` / ``objective`` / ``rank``
    (in place) and return the recommendation document."""
    for p in points:
        v = violations(p, constraints, target)
        p["objective"] = _plain(objective(p, target))
        p["violations"] = [m for _, m in v]
        p["feasible"] = not v
        p["rank"] = None
    ranked = sorted((i for i, p in enumerate(points) if p["feasible"] and p["objective"] is not None),
                    key=lambda i: points[i]["objective"])
    for r, i in enumerate(ranked):
        points[i]["rank"] = r + 1
    front = pareto_front(points, target)
    doc: dict = {"target": target or "worst relative of " + ", ".join(_components(points)),
                 "constraints": constraints.describe(), "pareto_front": front,
                 "n_valid": sum(bool(p.get("valid")) for p in points),
                 "n_feasible": sum(bool(p["feasible"]) for p in points)}
    if not ranked:
        flag, msg = binding_constraint(points, constraints, target)
        doc.update(best=None, binding=flag, reason=msg)
        return doc
    i = ranked[0]
    doc.update(best=i, params=points[i]["params"], objective=points[i]["objective"], why=explain(points[i], constraints, target),
               ranking=ranked[:10])
    return doc


def _components(points: list[dict]) -> list[str]:
    for p in points:
        if p.get("valid"):
            return list(p["components"])
    return []


def explain(p: dict, c: Constraints, target: str | None) -> list[str]:
    """Plain-language reasons a point was recommended."""
    lines = []
    comps = p["components"]
    sel = [target] if target else [k for k, e in comps.items()]
    worst = max(sel, key=lambda k: math.inf if comps[k]["rel_sigma"] is None else comps[k]["rel_sigma"])
    e = comps[worst]
    lines.append(f"lowest predicted uncertainty of {'the target ' + target if target else 'the worst component'}: "
                 f"{worst} +- {100 * e['rel_sigma']:.3g} % (from the {e['mode']} mode)")
    if e.get("shares"):
        top = max(e["shares"], key=e["shares"].get)
        lines.append(f"its variance is {100 * e['shares'][top]:.0f} % {top}")
    if e.get("separation") is not None:
        lines.append(f"mode separation {100 * e['separation']:.3g} %"
                     + (f" (>= {100 * c.min_separation:g} % required)" if c.min_separation is not None else ""))
    t = p["tension"]
    if t.get("peak") is not None:
        lines.append(f"peak wire tension {t['peak']:.4g} N" + (f" (<= {c.max_tension:g} N)" if c.max_tension else ""))
    if p["depth"].get("max") is not None:
        lines.append(f"needs {p['depth']['max']:.4g} m below the ceiling" + (f" (<= {c.max_depth:g} m)" if c.max_depth else ""))
    return lines


# --------------------------------------------------------------------------
# tables: CSV rows and lengths


def csv_rows(points: list[dict], param_names: list[str], components: list[str]) -> tuple[list[str], list[list]]:
    """Flat table: one row per point (header, rows); strings for labels and reasons."""
    n_w = max((len(p["tension"]["rest"]) for p in points if p.get("valid")), default=0)
    header = list(param_names) + ["valid", "feasible", "rank", "objective"]
    for c in components:
        header += [f"{c}_mode", f"{c}_period_s", f"{c}_sigma", f"{c}_rel_sigma", f"{c}_rel_sens_period",
                   f"{c}_separation", f"{c}_bias_small_angle", f"{c}_bias_thesis", f"{c}_bias_linear",
                   f"{c}_nonlinear_period_s"]
    header += [f"tension_rest_{i + 1}" for i in range(n_w)] + [f"tension_max_{i + 1}" for i in range(n_w)]
    header += [f"tension_min_{i + 1}" for i in range(n_w)] + ["slack", "depth_rest_m", "depth_max_m", "periods", "error"]
    rows = []
    for p in points:
        row = [p["params"].get(n) for n in param_names] + [p.get("valid"), p.get("feasible"), p.get("rank"), p.get("objective")]
        if not p.get("valid"):
            row += [None] * (len(header) - len(row) - 1) + [p.get("error") or "; ".join(p.get("violations", []))]
            rows.append(row)
            continue
        for c in components:
            e = p["components"].get(c, {})
            b = e.get("bias") or {}
            row += [e.get("mode"), e.get("period"), e.get("sigma"), e.get("rel_sigma"), e.get("rel_sensitivity_period"),
                    e.get("separation"), b.get("small_angle"), b.get("thesis"), b.get("linear"), e.get("nonlinear_period")]
        t = p["tension"]
        for key in ("rest", "max", "min"):
            vals = t.get(key) or [None] * n_w
            row += list(vals) + [None] * (n_w - len(vals))
        row += [t.get("slack"), p["depth"]["rest"], p["depth"]["max"],
                ";".join(f"{k}={v:.10g}" if v is not None else f"{k}=" for k, v in p["periods"].items()),
                "; ".join(p.get("violations", []))]
        rows.append(row)
    return header, rows


def write_points_csv(path: Path, points: list[dict], param_names: list[str], components: list[str]) -> None:
    """CSV (header row) of :func:`csv_rows`, written atomically; empty cells for missing values."""
    from ..output import write_table_csv

    write_table_csv(path, *csv_rows(points, param_names, components))


# --------------------------------------------------------------------------
# figures


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _series(points, fn):
    out = []
    for p in points:
        try:
            v = fn(p) if p.get("valid") else None
        except (KeyError, TypeError):
            v = None
        out.append(np.nan if v is None else float(v))
    return np.asarray(out, float)


def plot_sweep(path: Path, points: list[dict], params: list[ParamSpec], zip_: bool, components: list[str],
               constraints: Constraints, rec: dict, title: str = "") -> None:
    """Figures of a sweep in one image: each figure against the swept
    parameter (1-D sweeps and ``--zip``), heatmaps with the feasible region
    outlined (2-D grids), the uncertainty-vs-peak-tension front (always)."""
    plt = _pyplot()
    from .shorthands import param_unit

    target = None if rec.get("target", "").startswith("worst") else rec.get("target")
    obj = _series(points, lambda p: p["objective"])
    peak = _series(points, lambda p: p["tension"]["peak"])
    dmax = _series(points, lambda p: p["depth"]["max"] if p["depth"]["max"] is not None else p["depth"]["rest"])
    feas = np.array([bool(p.get("feasible")) for p in points])
    two_d = len(params) == 2 and not zip_
    one_d = len(params) == 1 or zip_
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    ax = axes.ravel()
    if one_d:
        x = np.array([p["params"][params[0].name] for p in points], float)
        xl = f"{params[0].name} [{param_unit(params[0].name)}]"
        for c in components:
            ax[0].semilogy(x, 100 * _series(points, lambda p, c=c: p["components"][c]["rel_sigma"]), "o-", ms=3, label=c)
            for m, ls in (("small_angle", "--"), ("thesis", ":"), ("linear", "-")):
                y = 100 * _series(points, lambda p, c=c, m=m: p["components"][c]["bias"][m])
                if np.any(np.isfinite(y)):
                    ax[1].plot(x, y, ls, marker=".", label=f"{c} {m.replace('_', '-')}")
            ax[2].semilogy(x, 100 * _series(points, lambda p, c=c: p["components"][c]["separation"]), "o-", ms=3, label=c)
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[1].set_ylabel("estimator bias vs full model [%]")
        ax[1].axhline(0, color="k", lw=0.5)
        ax[2].set_ylabel("mode separation [%]")
        if constraints.min_separation is not None:
            ax[2].axhline(100 * constraints.min_separation, color="r", lw=1, ls="--", label="minimum")
        rest_t = _series(points, lambda p: max(p["tension"]["rest"]))
        tmin = _series(points, lambda p: min(p["tension"]["min"]) if p["tension"]["min"] else None)
        ax[3].plot(x, rest_t, "k-", label="rest (largest wire)")
        ax[3].plot(x, peak, "r^-", ms=4, label="peak during excitation")
        ax[3].plot(x, tmin, "bv-", ms=4, label="minimum during excitation")
        if constraints.max_tension is not None:
            ax[3].axhline(constraints.max_tension, color="r", ls="--", lw=1, label="limit")
        ax[3].set_ylabel("wire tension [N]")
        ax[4].plot(x, _series(points, lambda p: p["depth"]["rest"]), "k-", label="at rest")
        ax[4].plot(x, dmax, "o-", ms=3, label="with swing")
        if constraints.max_depth is not None:
            ax[4].axhline(constraints.max_depth, color="r", ls="--", lw=1, label="limit")
        ax[4].set_ylabel("depth below ceiling [m]")
        for a in ax[:5]:
            a.set_xlabel(xl)
            if np.any(~feas):
                for xi, f in zip(x, feas):
                    if not f:
                        a.axvspan(xi - 1e-12, xi + 1e-12, color="0.85", lw=3, zorder=-1)
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
        if rec.get("best") is not None:
            for a in ax[:5]:
                a.axvline(x[rec["best"]], color="g", lw=1, alpha=0.6)
    elif two_d:
        p0, p1 = params
        nx, ny = len(p0.values), len(p1.values)
        X, Y = np.meshgrid(np.asarray(p1.values), np.asarray(p0.values))
        panels = [(np.log10(100 * obj), "log10 rel. uncertainty [%]" + (f" of {target}" if target else " (worst)")),
                  (peak, "peak wire tension [N]"), (dmax, "depth with swing [m]"),
                  (100 * _series(points, lambda p: min(e["separation"] for e in p["components"].values()
                                                       if e.get("separation") is not None)), "min mode separation [%]"),
                  (np.log10(100 * _series(points, lambda p: (p["components"].get(components[0]) or {}).get("rel_sigma"))),
                   f"log10 rel. uncertainty of {components[0]} [%]")]
        F = feas.reshape(nx, ny).astype(float)
        for a, (Z, lab) in zip(ax[:5], panels):
            Z = np.asarray(Z, float).reshape(nx, ny)
            if np.all(~np.isfinite(Z)):
                a.text(0.5, 0.5, "n/a", ha="center", transform=a.transAxes)
            else:
                m = a.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading="nearest", cmap="viridis")
                fig.colorbar(m, ax=a, label=lab)
            if 0 < F.sum() < F.size and nx > 1 and ny > 1:
                a.contour(X, Y, F, levels=[0.5], colors="r", linewidths=1.5)
                a.contourf(X, Y, F, levels=[-0.5, 0.5], colors="none", hatches=["xx"])
            a.set_xlabel(f"{p1.name} [{param_unit(p1.name)}]")
            a.set_ylabel(f"{p0.name} [{param_unit(p0.name)}]")
            if rec.get("best") is not None:
                b = points[rec["best"]]["params"]
                a.plot(b[p1.name], b[p0.name], "r*", ms=14, mec="w")
        ax[0].set_title("red line: edge of the feasible region (hatched: infeasible)", fontsize=9)
    else:
        idx = np.arange(len(points))
        for c in components:
            ax[0].semilogy(idx, 100 * _series(points, lambda p, c=c: p["components"][c]["rel_sigma"]), "o", label=c)
        ax[0].set_xlabel("point")
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[0].legend()
        ax[1].plot(idx, peak, "r^")
        ax[1].set_ylabel("peak tension [N]")
        ax[2].plot(idx, dmax, "o")
        ax[2].set_ylabel("depth with swing [m]")
        for a in ax[3:5]:
            a.axis("off")
    # the trade-off front
    a = ax[5]
    ok = np.isfinite(obj) & np.isfinite(peak)
    a.semilogy(peak[ok & ~feas], 100 * obj[ok & ~feas], "x", color="0.6", label="infeasible")
    a.semilogy(peak[ok & feas], 100 * obj[ok & feas], "o", color="C0", ms=4, label="feasible")
    front = rec.get("pareto_front") or []
    if front:
        a.semilogy(peak[front], 100 * obj[front], "k-", lw=1, label="Pareto front")
    if rec.get("best") is not None and np.isfinite(peak[rec["best"]]):
        a.semilogy(peak[rec["best"]], 100 * obj[rec["best"]], "g*", ms=14, label="recommended")
    if constraints.max_tension is not None:
        a.axvline(constraints.max_tension, color="r", ls="--", lw=1)
    a.set_xlabel("peak wire tension [N]")
    a.set_ylabel("predicted rel. uncertainty [%]")
    a.set_title("uncertainty vs peak tension", fontsize=10)
    a.grid(alpha=0.3, which="both")
    if ok.any():
        a.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    from ..output import atomic_write

    fmt_ = Path(path).suffix.lstrip(".").lower() or "png"
    atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=110, format=fmt_))
    plt.close(fig)
