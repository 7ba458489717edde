"""Multi-hanging plans: which orientations of the body to hang and which
modes to time so that every requested inertia component is identified, and
the uncertainty of each from the joint fit.

Candidates: the point's own hanging and the hangings of
:data:`bifilar.studies.remedy.HANGINGS` (the body turned 90 or 45 degrees
about a reference body axis on the same rig, convention of
:mod:`bifilar.studies.remedy` and of ``bifilar invert --measurements``:
``I_h = R I_ref R^T``).  A candidate measurement is one mode of one hanging
whose period is separated from every other mode of that hanging by at least
``min_separation``.

The joint fit: the unknowns ``theta`` are the requested components (kg m^2,
reference body axes); each timed period ``T_m`` (s) depends on them through
``J[m, c] = dT_m / dI_c`` (chain rule through ``R``).  The periods'
covariance ``S`` holds the timing variance ``sigma_T^2`` of each period,
within a hanging the errors of the inputs measured for it alone propagated
to its periods (``Jx Sx Jx^T``), and across hangings those of the inputs
measured once for several: the body's own (mass, CoM in reference body
axes) and, with the rig model ``shared`` (the default; ``--rig``,
:mod:`bifilar.estimation.rig`), the rig's wire lengths and anchors, which
every candidate hangs on, and an attachment at a body point another
candidate uses too (``separate``: those measured again for each hanging).
The estimate is the one ``bifilar invert --measurements``
makes, least squares weighted by the timing variances, with the covariance
``C = (J^T J)^-1 J^T S J (J^T J)^-1``; the plan reports ``sqrt(C_cc)`` per
component and the correlations.  The selection below ranks measurements by
the fit weighted by ``S^-1`` (``C = (J^T S^-1 J)^-1``, the best one), which
does better where the inputs dominate (2x on the KTH trifilar's Ixx), but
the plan reports what invert delivers: it reported the weighted fit and was
2x optimistic.

Selection (greedy, cheapest first): add the measurement that most increases
the rank of ``J`` (relative sensitivities, tolerance
:data:`~bifilar.studies.point.IDENTIFIABLE_MIN`), then lowers the worst
relative uncertainty, a new hanging counting only when it beats a mode of a
hanging already used by :data:`NEW_HANGING_GAIN`; once every component is
identified, further measurements are added while each lowers the worst
relative uncertainty by more than :data:`MIN_GAIN` (a mode of a hanging in
use) or halves it (a new hanging).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import BifilarError, InputError
from ..estimation.inversion_result import rigid_dependent, std_unavailable_text
from ..estimation.sensitivity import input_sigma
from .limits import component_scale, physical_limits
from .point import IDENTIFIABLE_MIN, point_uncertainty
from .remedy import HANGINGS, hanging_config, hanging_sensitivity, reference_column, rotation
from .settings import _IDX, SweepSettings
from .shorthands import apply_params

NEW_HANGING_GAIN = 0.5  # a new hanging must at least halve the worst uncertainty to beat a mode of a used one
MIN_GAIN = 0.10


@dataclass
class Hanging:
    """One candidate hanging: name, rotation (reference -> hanging body
    frame), config, scene, Sensitivity and per-mode separation."""

    name: str
    rotvec_deg: tuple
    R: np.ndarray
    config: dict
    scene: object
    sens: object
    separation: np.ndarray
    notes: list = field(default_factory=list)


@dataclass
class HangingPlan:
    """The chosen measurements and the joint-fit prediction (SI)."""

    components: list
    hangings: list            # of Hanging, those used
    measurements: list        # of dicts: hanging, mode, period, separation
    covariance: np.ndarray    # (C, C) kg^2 m^4
    values: dict              # prior value of each component, kg m^2
    scales: dict
    unc: dict
    missing: list = field(default_factory=list)
    #: inputs with no derivative for a timed period and a nonzero sigma: no sigma can be given (NaN covariance)
    undefined: list = field(default_factory=list)
    #: the guard applied to every timed mode (relative gap to its hanging's other modes; None: none)
    min_separation: float | None = None
    #: of ``missing``, the components some mode of a hanging tried depends on, left out for the guard
    separation_blocked: list = field(default_factory=list)
    #: the rig model the covariance assumes (:mod:`bifilar.estimation.rig`)
    rig: str = "shared"
    #: the amplitude factor's dr/dx in the inputs' terms (:mod:`bifilar.studies.hangings_inputs`):
    #: ``input_factor_terms`` (measured and in the covariance), ``input_factor_bound`` {component: the
    #: bound on what they change its sigma, relative; 0 where measured, None where none holds: a swing
    #: timed} or None (no stated amplitude),
    #: optionally ``input_factor_note``
    factor: dict = field(default_factory=lambda: {"input_factor_terms": False, "input_factor_bound": None})
    #: a plan made without the dr/dx runs its bound says matter (``factor_runs`` False): the plan with them
    refine: object = field(default=None, repr=False, compare=False)
    #: with ``refine``: each component's sigma without any input term, relative (the least it can be)
    floor: dict | None = None
    #: the body's inertia tensor in reference body axes (kg m^2), for the components' physical limits
    inertia: np.ndarray | None = None

    def accuracy(self) -> dict:
        """Per component: value, sigma (kg m^2), rel_sigma, and where the
        estimate may leave what a real body can have with this joint sigma
        (:func:`~bifilar.studies.limits.physical_limits`: ``physical_interval``,
        ``p_unphysical``, ``p_refused``, ``physical_limit`` when warned)."""
        from types import SimpleNamespace

        sd = np.sqrt(np.clip(np.diag(self.covariance), 0, None)) if len(self.covariance) else []
        out = {}
        for c, s in zip(self.components, sd):
            out[c] = {"value": self.values[c], "sigma": float(s), "rel_sigma": float(s) / self.scales[c]}
            if self.inertia is not None:
                out[c].update(physical_limits(self.inertia, c, SimpleNamespace(value_sigma=float(s))))
        return out

    def correlation(self) -> list:
        sd = np.sqrt(np.diag(self.covariance))
        return (self.covariance / np.outer(sd, sd)).tolist()

    def to_json(self) -> dict:
        return {"components": self.components, "accuracy": self.accuracy(), "correlation": self.correlation(),
                "hangings": [{"name": h.name, "rotation_deg": list(h.rotvec_deg), "notes": h.notes}
                             for h in self.hangings],
                "measurements": self.measurements, "uncertainty": self.unc, "not_identified": self.missing,
                "min_separation": self.min_separation, "rig": self.rig, **self.factor,
                "sigma_unavailable": (std_unavailable_text(self.undefined, "--sigma KEY=VALUE", rigid_dependent(
                    (h.scene, h.sens.rest) for h in self.hangings)) if self.undefined else None)}


def _separations(T: np.ndarray) -> np.ndarray:
    out = np.full(len(T), math.inf)
    for k in range(len(T)):
        gaps = [abs(T[k] - T[j]) / T[k] for j in range(len(T)) if j != k and np.isfinite(T[j])]
        if gaps and np.isfinite(T[k]):
            out[k] = min(gaps)
    return out


def candidate_hangings(base_cfg: dict, source: str, params: dict) -> list[Hanging]:
    """The point's own hanging first, then every turned hanging that can hang."""
    from ..config import scene_from_dict

    cfg, _ = apply_params(base_cfg, params, source)
    scene = scene_from_dict(cfg, source, warn=False)
    out = []
    for name, rv in (("as planned", (0.0, 0.0, 0.0)),) + tuple(HANGINGS):
        R = rotation(rv)
        c = cfg if name == "as planned" else hanging_config(scene, R, f"{cfg.get('name', 'body')}, {name}")
        try:
            sc, sens, notes = hanging_sensitivity(c, source)
        except BifilarError:
            continue
        out.append(Hanging(name, tuple(rv), R, c, sc, sens, _separations(sens.periods), notes))
    return out


SHARED_INPUTS = ("mass", "com.x", "com.y", "com.z")
"""Inputs of the body itself, the same error in every hanging (one weighing,
one CoM: reference body axes), as ``bifilar invert --measurements`` has them."""


def _rows(h: Hanging, comps: list[str], unc: dict, rig: tuple | None = None):
    """Per mode of a hanging: dT/dtheta (K, C), the part of the periods'
    covariance (K, K, s^2) from the inputs measured for this hanging alone
    (wire lengths, anchors, attachments), and dT/dx times sigma_x (K, 4 + S
    [+ 1], s) for the inputs every hanging shares: the body's own
    (:data:`SHARED_INPUTS`; the CoM in reference body axes, ``d_h = R
    d_ref``), then the ``S`` rig inputs and body points measured once for
    several hangings, then g where its uncertainty is stated
    (:func:`gravity_column`).  ``rig``: (:class:`~bifilar.estimation.rig.RigLinks`
    of the candidate hangings, this hanging's index in them, the shared
    keys in column order); None: every rig input measured for this hanging
    (``separate``).  The input columns are :func:`_input_map`'s."""
    J = np.column_stack([reference_column(h.sens, h.R, c) for c in comps])
    raw, M_own, M_sh = _input_map(h, unc, rig)
    jac = np.nan_to_num(np.column_stack([h.sens.column(n) for n in raw]), nan=0.0) if raw else np.zeros((len(J), 0))
    Jx, Js = jac @ M_own, np.hstack([jac @ M_sh, gravity_column(h, unc)])
    # per mode: the inputs without a derivative (a knife edge) and a nonzero sigma: no std can be given
    # from that period (as invert gives none)
    stated = [(n, h.sens.column(n)) for n in raw if input_sigma(h.scene, n, unc) > 0]
    undefined = [[n for n, c in stated if not np.isfinite(c[k])] for k in range(len(J))]
    return J, Jx @ Jx.T, Js, undefined


def gravity_column(h: Hanging, unc: dict) -> np.ndarray:
    """(K, 1) dT_k/dg times g's standard uncertainty (s) for each mode of
    hanging ``h`` when ``unc`` states one (relative, ``--sigma gravity``),
    else (K, 0): one shared column, the same g in every hanging, as
    ``invert --measurements`` budgets it.  Exact, no run: with the body and
    the rig fixed, ``t' = sqrt(g) t`` takes g out of the equations of motion
    (kinetic energy free of g, potential linear in it), so every period,
    linear or at any amplitude, scales as ``g^-1/2``: ``dT/dg = -T / (2 g)``,
    and the amplitude factor ``r`` (a ratio of periods) does not depend on g."""
    T = np.asarray(h.sens.periods, float)
    s = input_sigma(h.scene, "gravity", unc)  # m/s^2 (the stated relative std times g)
    if s <= 0:
        return np.zeros((len(T), 0))
    return (-0.5 * T / float(h.scene.gravity) * s)[:, None]


def _input_map(h: Hanging, unc: dict, rig: tuple | None = None) -> tuple[list, np.ndarray, np.ndarray]:
    """How the inputs of hanging ``h`` enter the joint fit: (``raw``, the
    names of ``h.sens`` it measures: its rig inputs and attachments, then
    those of :data:`SHARED_INPUTS` it has; ``M_own`` (R, O) and ``M_sh`` (R,
    4 + S), each input's standard uncertainty times its share in a column:
    the ``O`` inputs measured for this hanging alone, and the shared ones of
    :func:`_rows`).  A derivative of the periods (or of anything else,
    e.g. the amplitude factor) in the raw inputs, (K, R) per SI unit, times
    ``M_own`` / ``M_sh`` gives its columns in seconds per standard
    uncertainty; an input stated exact (sigma 0) has a zero row (its
    derivative, even a missing one, contributes nothing)."""
    names = h.sens.names
    xs = [n for n in names if n not in _IDX and n not in SHARED_INPUTS]
    sx = np.array([input_sigma(h.scene, n, unc) for n in xs])
    if rig is None:
        M_own, M_rig = np.diag(sx), np.zeros((len(xs), 0))
    else:  # each input's effect carried to its key: one of this hanging's, or a shared column
        links, hi, shared = rig
        own: dict = {}
        A_own, M_rig = [], np.zeros((len(xs), len(shared)))
        for q, n in enumerate(xs):
            for key, c in links.of(hi, n):
                if key in shared:
                    M_rig[q, shared.index(key)] += c * sx[q]
                else:
                    if key not in own:
                        own[key] = len(own)
                        A_own.append(np.zeros(len(xs)))
                    A_own[own[key]][q] += c * sx[q]
        M_own = np.array(A_own).reshape(-1, len(xs)).T
    body = [n for n in SHARED_INPUTS if n in names]
    M_body = np.zeros((len(body), 4))
    for q, n in enumerate(body):
        s = input_sigma(h.scene, n, unc)
        if n == "mass":
            M_body[q, 0] = s
        else:  # the CoM in reference body axes: d_h = R d_ref, column a gets R[ax, a]
            M_body[q, 1:] = s * h.R["xyz".index(n[-1])]
    M_own = np.vstack([M_own, np.zeros((len(body), M_own.shape[1]))])
    M_sh = np.vstack([np.hstack([np.zeros((len(xs), 4)), M_rig]), np.hstack([M_body, np.zeros((len(body), M_rig.shape[1]))])])
    return xs + body, M_own, M_sh


def rig_split(hs: list, model: str) -> list:
    """Per candidate hanging of ``hs`` the ``rig`` argument of :func:`_rows`
    under the rig model ``model`` (:mod:`bifilar.estimation.rig`; the
    candidates hang on one rig, so ``shared`` makes the wire lengths and
    anchors one input for all of them, and a body point several use one)."""
    from ..estimation.rig import rig_links

    links = rig_links([h.name for h in hs], [h.scene for h in hs], [h.R for h in hs], model)
    shared = [k for k in links.keys if len(links.hangings(k)) > 1]
    return [(links, hi, shared) for hi in range(len(hs))]


def joint_covariance(blocks: list[tuple], timing: float, as_invert: bool = True, inputs: np.ndarray | None = None):
    """(C, rank, unresolved) of the joint fit over hangings; S = timing^2 I
    + the input covariance of each hanging's chosen modes (block diagonal)
    + the shared inputs' ``Js Js^T`` across hangings (the body's, and the
    rig's measured once: :func:`_rows`); ``blocks``: per
    hanging (J rows, input covariance, shared-input rows ``Js``, and with
    a stated amplitude the rows of the model's full derivative ``r dT_lin/dI
    + T_lin dr/dI`` and the amplitude's variance per period (s^2): the
    timing and the amplitude then go through the full rows' gain, the
    inputs through ``J``'s, as invert's ``budget._with_factor_gain``).
    ``as_invert``: the fit ``bifilar invert`` makes (least squares weighted
    by the timing variance, equal for every period), C = (J^T J)^-1 J^T S J
    (J^T J)^-1; else the best one, weighted by S^-1, C = (J^T S^-1 J)^-1
    (the selection's criterion).  C is inf when J^T J is singular,
    ``unresolved`` then a boolean per unknown: it has weight in the null
    space.  ``inputs`` (with a stated amplitude and ``as_invert``): the
    inputs' columns over the periods with the amplitude factor's measured
    ``dr/dx``, ``r dT_lin/dx s_x + T_lin dr/dx s_x`` (s;
    :func:`~bifilar.studies.hangings_inputs.joint_factor_inputs`): the
    inputs then go through the full rows' gain as well, as invert puts
    them (their ``Js Js^T`` and blocks are then not used for C)."""
    n = blocks[0][0].shape[1] if blocks else 0
    F = np.zeros((n, n))
    full = bool(blocks) and all(len(b) > 3 for b in blocks)
    if blocks:
        Jall = np.vstack([b[0] for b in blocks])
        Js = np.vstack([b[2] for b in blocks])
        S = Js @ Js.T
        k = 0
        for b in blocks:
            S[k:k + len(b[0]), k:k + len(b[0])] += b[1]
            k += len(b[0])
        # the periods' own variance: timing, and a stated amplitude's (with the model's gain, below)
        St = timing**2 * np.eye(len(Jall)) + (np.diag(np.concatenate([b[4] for b in blocks])) if full else 0.0)
        if not (as_invert and full):
            S, St = S + St, np.zeros_like(S)
        F = Jall.T @ Jall if as_invert else Jall.T @ np.linalg.solve(S, Jall)
    w, V = np.linalg.eigh(F)
    ok = w > max(float(w.max()) if w.size else 0.0, 0.0) * 1e-12
    rank = int(np.sum(ok)) if w.size else 0
    if rank < n:
        null = V[:, ~ok]
        return np.full((n, n), np.inf), rank, np.max(np.abs(null), axis=1) > 1e-6
    Finv = V @ np.diag(1 / w) @ V.T
    if not as_invert:
        return Finv, rank, np.zeros(n, bool)
    C = Finv @ Jall.T @ S @ Jall @ Finv
    if full:  # the timing and amplitude terms through the model's full derivative (budget._with_factor_gain)
        Jf = np.vstack([b[3] for b in blocks])
        Gf = np.linalg.solve(Jf.T @ Jf, Jf.T)
        if inputs is not None:  # and the inputs with their factor terms
            C, St = np.zeros_like(C), St + inputs @ inputs.T
        C = C + Gf @ St @ Gf.T
    return C, rank, np.zeros(n, bool)


def plan_hangings(base_cfg: dict, source: str, params: dict, settings: SweepSettings, components: list[str],
                  min_separation: float | None = None, reaction: float | None = None, sensor=None,
                  factor_runs: bool = True) -> HangingPlan:
    """Choose hangings and modes that identify ``components`` (see the
    module docstring) at the point ``params``; each measurement carries how
    to time it (:func:`bifilar.studies.timing.advice`, stopwatch sigma
    ``reaction`` s per trial, optional ``sensor``).  With a stated
    amplitude the inputs' terms take the amplitude factor's ``dr/dx``
    where its bound says they can change a sigma
    (:mod:`bifilar.studies.hangings_inputs`); ``factor_runs`` False: never
    measured (a ranking's screen, :func:`hangings_objectives`), the bound
    stated."""
    from .timing import DEFAULT_REACTION, advice

    unc = point_uncertainty(settings, params)
    timing = unc["timing"]
    hs = candidate_hangings(base_cfg, source, params)
    if not hs:
        raise InputError("--param", "the body cannot hang in any orientation tried at the planned point")
    ref = hs[0].scene
    scales = {c: component_scale(ref.inertia, c) for c in components}
    values = {c: float(ref.inertia[_IDX[c]]) for c in components}
    split = rig_split(hs, settings.rig)
    data = [_rows(h, components, unc, r) for h, r in zip(hs, split)]
    cands = []
    close = np.zeros(len(components), bool)  # some mode too close to another depends on the component
    for hi, h in enumerate(hs):
        T = h.sens.periods
        for k in range(len(T)):
            if not np.isfinite(T[k]):
                continue
            rel = np.abs(data[hi][0][k]) * np.array([scales[c] for c in components]) / T[k]
            if min_separation and h.separation[k] < min_separation:
                close |= rel >= IDENTIFIABLE_MIN
            elif rel.max() >= IDENTIFIABLE_MIN:
                cands.append((hi, k))
    chosen: list[tuple[int, int]] = []

    def evaluate(sel, as_invert=False, amp=None, inputs=None):
        blocks = []
        for hi in sorted({a for a, _ in sel}):
            ks = [k for a, k in sel if a == hi]
            J, Sx, Js, _ = data[hi]
            scale = np.array([scales[c] for c in components])
            # the stated amplitude (amp {(hanging, mode): (r, s^2)}): invert's nonlinear rung fits T_lin r, so
            # each period's row, its inputs' rows and the body's scale by r, and the amplitude's own
            # uncertainty adds its variance to the period's (stated_amplitude_budget, per period)
            r = np.array([amp[(hi, k)][0] for k in ks]) if amp else np.ones(len(ks))
            va = np.array([amp[(hi, k)][1] for k in ks]) if amp else np.zeros(len(ks))
            block = (J[ks] * scale * r[:, None], Sx[np.ix_(ks, ks)] * np.outer(r, r), Js[ks] * r[:, None])
            if amp:  # the amplitude factor's dependence on the components: the gain of the timing and amplitude terms
                T_lin = np.array([hs[hi].sens.periods[k] for k in ks], float)
                dr = np.array([amp[(hi, k)][2] for k in ks])
                block += ((J[ks] * r[:, None] + T_lin[:, None] * dr) * scale, va)
            blocks.append(block)  # in units of each component's scale
        C, rank, unresolved = joint_covariance(blocks, timing, as_invert, inputs)
        worst = float(np.sqrt(np.max(np.diag(C)))) if rank == len(components) else math.inf
        return rank, worst, C, unresolved, blocks

    rank, worst = 0, math.inf
    while cands:
        used = {a for a, _ in chosen}
        best = None
        for m in cands:
            if m in chosen:
                continue
            r, w, _, _, _ = evaluate(chosen + [m])
            eff = w / NEW_HANGING_GAIN if (m[0] not in used and used) else w
            key = (-r, eff)
            if best is None or key < best[0]:
                best = (key, m, r, w)
        if best is None:
            break
        _, m, r, w = best
        if rank == len(components):  # phase 2: only worthwhile additions
            if w > (NEW_HANGING_GAIN if m[0] not in used else 1 - MIN_GAIN) * worst:
                break
        elif r <= rank and w >= worst:
            break
        chosen.append(m)
        rank, worst = r, w
    # chosen for the best fit (small amplitude); reported for the fit invert makes of them, the
    # planned amplitude stated for each period
    amp = _amplitude_terms(hs, chosen, settings, components) if chosen else None
    rank, worst, C0, unresolved, blocks = evaluate(chosen, as_invert=True, amp=amp) if chosen else (
        0, math.inf, np.full((len(components),) * 2, np.inf), np.ones(len(components), bool), [])
    sc = np.array([scales[c] for c in components])
    used_idx = sorted({a for a, _ in chosen})
    meas = [{"hanging": hs[a].name, "mode": hs[a].sens.modes.modes[k].label, "period_sigma": timing,
             **advice(float(hs[a].sens.periods[k]), float(hs[a].separation[k]), timing,
                      DEFAULT_REACTION if reaction is None else reaction, sensor),
             "amplitude": settings.amplitude if amp else 0.0,
             "period_at_amplitude": float(hs[a].sens.periods[k]) * (amp[(a, k)][0] if amp else 1.0)}
            for a in used_idx for (b, k) in sorted(chosen) if b == a]
    missing = [c for c, u in zip(components, unresolved) if u]
    undefined = sorted({n for a, k in chosen for n in data[a][3][k]})

    def finish(X, rel, note) -> HangingPlan:
        """The plan with the inputs' columns ``X`` (None: without dr/dx) and the bound ``rel`` (relative)."""
        C = C0 if X is None else evaluate(chosen, as_invert=True, amp=amp, inputs=X)[2]
        C = C * np.outer(sc, sc)
        if undefined:  # the selection left them out; the prediction cannot (invert gives no std either)
            C = np.full_like(C, np.nan)
        factor = {"input_factor_terms": X is not None,  # a bound of None: none holds (a swing timed)
                  "input_factor_bound": None if rel is None else {
                      c: (float(v) if math.isfinite(v) else None) for c, v in zip(components, rel)}}
        if note:
            factor["input_factor_note"] = note
        return HangingPlan(list(components), [hs[a] for a in used_idx], meas, C, values, scales, unc, missing,
                           undefined, min_separation, [c for c, b in zip(components, close) if b and c in missing],
                           settings.rig, factor, inertia=np.array(ref.inertia, float))

    if not (amp and rank == len(components)):
        return finish(None, None, None)
    # the inputs' dr/dx where they can change a sigma (hangings_inputs)
    from .hangings_inputs import joint_factor_inputs
    from .point_inputs import FACTOR_INPUT_ENOUGH

    maps = [_input_map(h, unc, r) for h, r in zip(hs, split)]

    def factor_terms(runs):
        return joint_factor_inputs(hs, maps, chosen, amp, unc, settings, np.vstack([b[0] for b in blocks]),
                                   np.vstack([b[3] for b in blocks]), np.sqrt(np.diag(C0)), runs)

    X, rel, note = factor_terms(factor_runs)
    plan = finish(X, rel, note)
    if not factor_runs and not all(v <= FACTOR_INPUT_ENOUGH for v in rel):  # the runs can change it
        plan.refine = lambda: finish(*factor_terms(True))
        # whatever the inputs' terms, each sigma is at least its timing's and amplitude's part
        none = np.zeros((sum(len(b[0]) for b in blocks), 0))
        floor = np.sqrt(np.clip(np.diag(evaluate(chosen, as_invert=True, amp=amp, inputs=none)[2]), 0, None))
        plan.floor = {c: float(f) for c, f in zip(components, floor)}
    return plan


def hangings_objective(base_cfg: dict, source: str, params: dict, settings: SweepSettings,
                       min_separation: float | None, target: str | None) -> float:
    """The relative standard uncertainty of ``target`` (or the worst of the
    components) by the multi-hanging plan at ``params``
    (:func:`bifilar.studies.hangings.plan_hangings`: the hangings and modes
    chosen at a small amplitude, their joint sigma with the planned
    amplitude stated, as the plan at the recommended point reports it; a
    small-amplitude ranking put a trifilar's 0.43 % point first whose plan
    at 0.2 rad gives 0.69 %), each timed mode at least ``min_separation``
    from the other modes of its hanging; inf when that plan leaves a
    component unidentified or without a sigma."""
    return _objective(plan_hangings(base_cfg, source, params, settings, list(settings.components), min_separation),
                      settings, target)[0]


def _objective(hp: HangingPlan, settings: SweepSettings, target: str | None) -> tuple[float, float]:
    """(:func:`hangings_objective` of the plan ``hp``, the least it can be
    once the inputs' ``dr/dx`` terms its bound leaves out are measured:
    each component's relative sigma less its ``input_factor_bound``, and
    at least its timing's and amplitude's part, ``hp.floor``)."""
    if hp.missing:
        return math.inf, math.inf
    comps = [target] if target else list(settings.components)
    bound = hp.factor.get("input_factor_bound") or {}
    sd = dict(zip(hp.components, np.sqrt(np.clip(np.diag(hp.covariance), 0, None))))
    vals = [float(sd[c]) / hp.scales[c] for c in comps]
    if not all(math.isfinite(v) for v in vals):
        return math.inf, math.inf
    left = [0.0 if c not in bound else 1.0 if bound[c] is None else bound[c] for c in comps]  # None: no bound
    floor = [(hp.floor or {}).get(c, 0.0) for c in comps]
    return float(max(vals)), float(max(max(v * (1.0 - b), f) for v, b, f in zip(vals, left, floor)))


def hangings_objectives(base_cfg: dict, source: str, points: list, settings: SweepSettings,
                        min_separation: float | None, target: str | None) -> list:
    """:func:`hangings_objective` of each of ``points`` (parameter dicts),
    the dr/dx runs only where they can decide the best: every plan first
    without them (``factor_runs`` False: each sigma with the bound on what
    they change), then, by the least each can be, in order, each plan whose
    bound says they matter again with them while that least is below the
    best figure so far (a branch and bound: the best is the best with
    them, as the plan at the recommended point reports it).  A point left
    out keeps the figure without them (the bound shows it cannot be the
    best).  The runs cost about what the rest of a plan does (the KTH
    trifilar at 0.3 rad: 0.15 s of 0.29 s, docs/design.md, "Joint sigma,
    session 12")."""
    comps = list(settings.components)
    plans = [plan_hangings(base_cfg, source, p, settings, comps, min_separation, factor_runs=False) for p in points]
    first = [_objective(hp, settings, target) for hp in plans]
    out = [v for v, _ in first]
    best = math.inf
    for i in sorted(range(len(points)), key=lambda i: first[i][1]):
        if not first[i][1] <= best:
            break
        if plans[i].refine is not None:
            out[i] = _objective(plans[i].refine(), settings, target)[0]
        best = min(best, out[i])
    return out


def check_separated(plan: HangingPlan) -> None:
    """Refuse (:class:`InputError` on ``--min-separation``) a plan that
    leaves a component unidentified because every mode of the hangings
    tried that depends on it is within ``min_separation`` of another mode
    of its hanging: the planner left that guard to this plan
    (:func:`bifilar.studies.plan.plan` with ``hangings``), so it cannot be
    made at the planned point."""
    if plan.separation_blocked:
        raise InputError("--min-separation", f"no configuration meets --min-separation {plan.min_separation:g} "
                         f"with the hangings either: every mode of the hangings tried that depends on "
                         f"{', '.join(plan.separation_blocked)} is within {100 * plan.min_separation:g} % of "
                         "another mode of its hanging at the planned point; lower --min-separation or change "
                         "the --param ranges")


def _amplitude_terms(hs: list, chosen: list, settings: SweepSettings, components: list) -> dict | None:
    """{(hanging index, mode index): (r, s^2, dr/dI, A dr/dA)} of the chosen measurements at
    the planned amplitude ``A``: the amplitude factor ``r = T(A) / T_lin`` by
    the nonlinear model (``settings.periods`` periods at ``settings.rtol``,
    as a sweep point's run) and the variance its stated uncertainty
    (invert's default 10 %) adds to the period, ``(T_lin A dr/dA rel)^2``
    with the slope of the mode's amplitude law (a second run at
    :data:`~bifilar.estimation.solve.STATED_LAW_RATIO` of ``A``, as invert's;
    :func:`bifilar.studies.point_amplitude.stated_amplitude_budget`), and the
    factor's derivative in each of ``components`` (reference body axes, 1 /
    kg m^2; a run with the component stepped by
    :data:`~bifilar.estimation.solve.FACTOR_STEP` of the largest moment, as
    invert's :func:`~bifilar.estimation.solve.stated_amplitude_law`), and
    ``A dr/dA`` of the law (the mass's exact route to ``dr/dx``,
    :func:`~bifilar.estimation.factor_inputs.factor_routes`); None
    without the nonlinear runs (``--no-tensions``: the plan is then for a
    small amplitude, ``amplitude: 0``) or when a run gives no period."""
    from dataclasses import replace

    from ..analysis.batch import simulate_batch
    from ..analysis.modes import linear_modes
    from ..estimation.solve import FACTOR_STEP, STATED_LAW_RATIO, amplitude_law
    from ..estimation.uncertainty import DEFAULT_AMPLITUDE_REL

    if not settings.tensions:
        return None
    A = settings.amplitude
    n = len(chosen)
    h = FACTOR_STEP * float(np.max(np.linalg.eigvalsh(hs[0].scene.inertia)))
    stepped = []  # per chosen measurement and component: (scene, modes) with the component stepped by h
    for a, _ in chosen:
        for c in components:
            E = np.zeros((3, 3))
            i, j = _IDX[c]
            E[i, j] = E[j, i] = h
            sc = replace(hs[a].scene, inertia=hs[a].scene.inertia + hs[a].R @ E @ hs[a].R.T)
            stepped.append((sc, linear_modes(sc, hs[a].sens.rest)))
    try:  # the chosen measurements' runs, their laws' and their steps' in one call of the batched engine
        runs = simulate_batch([hs[a].scene for a, _ in chosen] * 2 + [sc for sc, _ in stepped],
                              mode=[k + 1 for _, k in chosen] * 2 + [k + 1 for _, k in chosen for _ in components],
                              amplitude=[A] * n + [STATED_LAW_RATIO * A] * n + [A] * len(stepped),
                              periods=settings.periods, rtol=settings.rtol,
                              rests=[hs[a].sens.rest for a, _ in chosen] * 2 + [hs[a].sens.rest for a, _ in chosen
                                                                                for _ in components],
                              modes=[hs[a].sens.modes for a, _ in chosen] * 2 + [ms for _, ms in stepped])
    except BifilarError:
        return None
    out = {}
    for q, ((a, k), run, low) in enumerate(zip(chosen, runs, runs[n:2 * n])):
        T_lin = float(hs[a].sens.periods[k])
        steps = runs[2 * n + q * len(components):2 * n + (q + 1) * len(components)]
        if not run.period or not low.period or not all(s.period for s in steps):
            return None
        r = run.period / T_lin
        law = amplitude_law(A, r, STATED_LAW_RATIO, low.period / T_lin)
        dr = np.array([(s.period / s.linear_period - r) / h for s in steps])
        out[(a, k)] = (r, (T_lin * A * law.slope() * DEFAULT_AMPLITUDE_REL) ** 2, dr, A * law.slope())
    _refine_steps(out, hs, chosen, settings, components, stepped, h)
    return out


def _refine_steps(out: dict, hs: list, chosen: list, settings: SweepSettings, components: list, stepped: list,
                  h: float) -> None:
    """Replace in ``out`` (:func:`_amplitude_terms`) each ``dr/dI`` whose
    runs' period error could move the factor gain by more than
    :data:`~bifilar.estimation.solve.FACTOR_GAIN_NOISE`, as invert of the
    written file does (:func:`~bifilar.estimation.solve.factor_step_rtol`
    with the largest ``|dT/dI|`` of the chosen measurements): the chosen
    mode's run and the stepped scene's again at the rtol it asks for (one
    batched call at the tightest); a failed pair keeps its first value."""
    from ..analysis.batch import simulate_batch
    from ..estimation.solve import factor_step_rtol

    cols = {c: np.max([abs(reference_column(hs[a].sens, hs[a].R, c)[k]) for a, k in chosen]) for c in components}
    redo = []
    for q, (a, k) in enumerate(chosen):
        for i, c in enumerate(components):
            tight = factor_step_rtol(settings.rtol, float(hs[a].sens.periods[k]), float(cols[c]), h)
            if tight is not None:
                redo.append((q, a, k, i, tight))
    if not redo:
        return
    try:
        runs = simulate_batch([x for q, a, _, i, _ in redo for x in (hs[a].scene, stepped[q * len(components) + i][0])],
                              mode=[k + 1 for _, _, k, _, _ in redo for _ in (0, 1)], amplitude=settings.amplitude,
                              periods=settings.periods, rtol=min(t for *_, t in redo),
                              rests=[hs[a].sens.rest for _, a, _, _, _ in redo for _ in (0, 1)],
                              modes=[x for q, a, _, i, _ in redo
                                     for x in (hs[a].sens.modes, stepped[q * len(components) + i][1])],
                              errors="return", health=False)
    except BifilarError:
        return
    for n, (_, a, k, i, _) in enumerate(redo):
        own, step = runs[2 * n], runs[2 * n + 1]
        if not own.error and not step.error and own.period and step.period:
            out[(a, k)][2][i] = (step.period / step.linear_period - own.period / own.linear_period) / h


def _periods_over_cycles(plan: HangingPlan, notes: list | None = None) -> list:
    """The period (s) of each of ``plan.measurements`` as ``invert`` models
    a period stated with an amplitude: the mean period of a nonlinear run
    over :data:`~bifilar.estimation.measurements.DEFAULT_CYCLES` cycles at
    invert's default rtol 1e-10 (the planned ``period_at_amplitude`` is the
    plan's 3-period run, ``settings.periods``, which for a mode that beats
    at a large amplitude differs by up to a timing std: the audit's
    trifilar at 0.2 wrote a torsion 0.98 ms off, and its own file, inverted
    unchanged, gave Ixx 0.22 std from the truth).  One batched call, each
    scene's failure its own (``errors="return"``); a small-amplitude plan
    (``amplitude`` 0) keeps the planned period.  A failed run keeps the
    planned period too, and says so: one line per measurement appended to
    ``notes`` (:func:`_fallback_note`), naming the hanging, the mode and why."""
    from ..analysis.batch import simulate_batch
    from ..estimation.measurements import DEFAULT_CYCLES

    out = [float(m["period_at_amplitude"]) for m in plan.measurements]
    by_name = {h.name: h for h in plan.hangings}
    todo = []
    for q, m in enumerate(plan.measurements):
        h = by_name.get(m["hanging"])
        if not m.get("amplitude") or h is None:
            continue
        labels = [md.label for md in h.sens.modes.modes]
        if m["mode"] in labels:
            todo.append((q, h, labels.index(m["mode"])))
    if not todo:
        return out
    try:
        runs = simulate_batch([h.scene for _, h, _ in todo], mode=[k + 1 for _, _, k in todo],
                              amplitude=[float(plan.measurements[q]["amplitude"]) for q, _, _ in todo],
                              periods=DEFAULT_CYCLES, rtol=1e-10, rests=[h.sens.rest for _, h, _ in todo],
                              modes=[h.sens.modes for _, h, _ in todo], errors="return")
        whys = [None if run.period else (run.error or "fewer than two upward crossings") for run in runs]
    except BifilarError as exc:  # the batch as a whole (an integration that failed): every row keeps its own
        runs, whys = [None] * len(todo), [str(exc)] * len(todo)
    for (q, _, _), run, why in zip(todo, runs, whys):
        if why is None:
            out[q] = float(run.period)
        elif notes is not None:
            notes.append(_fallback_note(plan.measurements[q], DEFAULT_CYCLES, why))
    return out


def _fallback_note(m: dict, cycles: float, why: str) -> str:
    """The warning of measurement ``m`` (a dict of ``plan.measurements``)
    whose run over ``cycles`` cycles failed for the reason ``why``: the
    measurements file's period for it is the plan's own shorter run's."""
    why = " ".join(str(why).split())  # one line (a file comment too)
    return (f"--write-measurements: hanging '{m['hanging']}', mode '{m['mode']}' at amplitude {m['amplitude']:g}: the "
            f"run over {cycles:g} cycles that invert models for a stated amplitude failed ({why}), so the file's "
            "period for it is the plan's own shorter run's (--periods), which where the mode beats can differ from "
            "invert's model by up to a timing std; invert may refuse it for the same reason")


def measurements_document(plan: HangingPlan, reaction: float | None = None, notes: list | None = None) -> dict:
    """The plan as a ``bifilar invert --measurements`` file (docs/invert.md):
    one hanging per entry with its inline config and rotation, one
    measurement per timed mode.  The periods are the *planned* ones (the
    config's inertia, at the planned amplitude) with the timing sigma and
    the planned ``amplitude`` (0 when the plan ran no nonlinear model,
    ``--no-tensions``), as the plan's sigmas assume: replace the periods
    with the measured values (or ``cycles``/``times``) and the amplitude
    with the one released after the experiment; without an amplitude,
    invert budgets an assumed 0-10 degree release range, which the plan
    leaves out.  ``notes``: a list the warnings of periods that could not
    be run over invert's cycles are appended to (:func:`_periods_over_cycles`)."""
    from ..jsonable import to_jsonable

    periods = _periods_over_cycles(plan, notes)
    hangs = []
    for h in plan.hangings:
        # the plan's sigma assumes the amplitude is stated (its 10 % budgeted); the periods are the
        # ones the body shows at it over the cycles invert models (invert then corrects for it)
        ms = [{"mode": m["mode"], "period": f"{periods[q]:.9g} +- {m['period_sigma']:.3g}",
               "amplitude": m["amplitude"]} for q, m in enumerate(plan.measurements) if m["hanging"] == h.name]
        entry = {"name": h.name, "config": to_jsonable(h.config),
                 "rotation": "identity" if not any(h.rotvec_deg) else {"rotvec_deg": list(h.rotvec_deg)},
                 "measurements": ms}
        hangs.append(entry)
    unc = {k: v for k, v in plan.unc.items() if k != "timing"}
    return {"solve_for": list(plan.components), "uncertainty": unc, "rig": plan.rig, "hangings": hangs}


def describe(plan: HangingPlan) -> list[str]:
    """Plain lines: hangings, modes, predicted uncertainty per component."""
    return describe_json(plan.to_json())


def describe_json(doc: dict) -> list[str]:
    """:func:`describe` of a :meth:`HangingPlan.to_json` document."""
    lines = []
    for h in doc["hangings"]:
        modes = [m for m in doc["measurements"] if m["hanging"] == h["name"]]
        lines.append(f"hang {h['name']}" + (f" (rotation vector {h['rotation_deg']} deg)" if any(h["rotation_deg"]) else "")
                     + ": time " + ", ".join(f"{m['mode']} (T = {m['period']:.5g} s, sep {100 * m['separation']:.3g} %; "
                                             f"{m['cycles_per_trial']} cycles x {m['stopwatch']['trials']} stopwatch trials)"
                                             for m in modes))
    if len(doc["hangings"]) > 1 and doc.get("rig"):
        lines.append("the hangings' wire lengths and anchors are budgeted as measured once for all of them (one "
                     "rig, --rig shared)" if doc["rig"] == "shared" else
                     "each hanging's wire lengths, anchors and attachments are budgeted as measured again for it "
                     "(--rig separate)")
    if doc.get("min_separation"):
        lines.append(f"each timed mode is at least {100 * doc['min_separation']:g} % (--min-separation) from "
                     "every other mode of its hanging")
    for c, a in doc["accuracy"].items():
        ok = a["sigma"] is not None and math.isfinite(a["sigma"])
        lines.append(f"{c} = {a['value']:.6g} +- {a['sigma']:.3g} kg m^2 ({100 * a['rel_sigma']:.3g} %)" if ok
                     else f"{c}: uncertainty not given (below)" if doc.get("sigma_unavailable")
                     else f"{c}: not identified by the hangings tried")
    if doc.get("sigma_unavailable"):
        lines.append(doc["sigma_unavailable"])
    return lines


def close_modes_warning(point: dict, min_separation: float, what: str = "the point") -> str:
    """The warning of a planned point whose own hanging's timed modes the
    search did not hold to ``min_separation`` (left to the multi-hanging
    plan): which of them are too close to another mode, not to be timed."""
    close = {}
    for c, e in point["components"].items():
        if e.get("identifiable") and e.get("separation") is not None and e["separation"] < min_separation:
            close.setdefault(e["mode"], []).append(f"{c}, separation {100 * e['separation']:.2g} %")
    modes = "; ".join(f"{m} ({', '.join(v)})" for m, v in close.items()) or "none"
    return (f"{what}: its own hanging does not meet --min-separation {min_separation:g}, so time the modes of the "
            f"multi-hanging plan (each at least {100 * min_separation:g} % from the other modes of its hanging), "
            f"not the point's own modes closer than that: {modes}")


__all__ = ["HangingPlan", "candidate_hangings", "check_separated", "close_modes_warning", "describe", "hangings_objective", "joint_covariance", "measurements_document",
           "plan_hangings"]
