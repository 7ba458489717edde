"""One sweep point: every figure of a configuration (see :mod:`bifilar.studies.sweep`
for the list), computed from the base config, the point's parameters and the
settings only.  A bad point is returned with ``valid: false`` and a
one-line reason, never raised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import BifilarError, ConvergenceError, InputError, SlackWireError, UnstableRestError
from ..errors import one_line as _one_line
from ..jsonable import to_jsonable
from .settings import _IDX, PRINCIPAL, SweepSettings
from .shorthands import apply_params
from .limits import component_scale, physical_limits
from .point_amplitude import _budgeted, _law_runs, _runs_at, _stated_amplitude
from .point_estimators import _Ladder, linear_estimate  # noqa: F401  (sweep's, tests' and scripts' names)


#: below this |d ln T / d ln I| for every mode a component counts as not identifiable
IDENTIFIABLE_MIN = 1e-6

# one point


_plain = to_jsonable  # point dicts read back from a journal equal the computed ones


def _fd_step(scene, name: str, rel_step: float = 1e-6) -> float:
    """Finite-difference step of :func:`~bifilar.estimation.sensitivity.period_sensitivity`."""
    if name in _IDX:
        return rel_step * float(np.max(np.linalg.eigvalsh(scene.inertia)))
    if name in ("mass", "gravity"):
        return rel_step * float(getattr(scene, name))
    if name == "stiffness":
        from ..estimation.sensitivity import stiffness_step

        return stiffness_step(rel_step)
    return rel_step * float(np.max(scene.lengths))


#: rad: a neighbour (1e-6 relative input step) whose rest pose turned more than this jumped branch
TURN_MAX = 1e-3
#: at a knife edge (CoM exactly on the attachment line), an input whose push along the neutral
#: direction (:func:`bifilar.analysis.derivatives.analytic_period_jacobian`, ``push``: relative
#: residual of the pose derivative, 0 to rounding for the inputs with a derivative, 0.3-0.6 for
#: a sideways shift of the plate's CoM or attachments) is at least this has no neighbour within
#: :data:`TURN_MAX` either way: the circle of equilibria is exactly neutral, so any such change
#: turns the body until the CoM offset it makes hangs straight down, a finite angle (about 90
#: degrees for a sideways offset).  Its differences (two Newton runs that end turned over, ~1 ms
#: each) are not tried; a weaker push (between the derivative's 1e-8 and this) still is
NO_BRANCH_PUSH = 1e-2


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


def point_sensitivity(scene, names: list[str], rest=None, at=None):
    """:func:`~bifilar.estimation.sensitivity.period_sensitivity`, robust at
    the edge of stability.

    A scene with a neutral mode (e.g. a thin plate whose CoM lies on the
    attachment line) has neighbours that cannot hang near its rest pose:
    a micrometre's change turns the body over (Newton from the rest pose
    lands on a pose turned by ~1 rad).  A derivative must follow the local
    branch, so each side's rest pose must stay within :data:`TURN_MAX` of the
    base pose; otherwise that side is dropped (one-sided difference, first
    order: relative error ~1e-6), and an input with no side left has no
    derivative (its column NaN, listed in ``undefined``, with a note): the
    point's sigmas are then null, as ``invert`` gives no std there (within
    that input's uncertainty the hanging changes qualitatively; a sigma
    leaving it out was confidently wrong, docs/design.md "Closed-loop check
    of the planner").  The inputs
    with an analytic derivative at the neutral scene (the branch's
    derivative, :mod:`bifilar.analysis.derivatives`) take it instead: only
    those pushing along the neutral direction are differenced, except at an
    exact knife edge those pushing hard (:data:`NO_BRANCH_PUSH`), which are
    left out at once as having no side.  Regular
    scenes take :func:`~bifilar.estimation.sensitivity.period_sensitivity`
    (analytic).  ``at``: :func:`~bifilar.analysis.modes.modes_of_inertia`
    of ``scene`` about ``rest`` if built (its modes at the scene's inertia
    are the linear modes).  Returns (Sensitivity, notes).
    """
    from ..analysis.derivatives import NotDifferentiable, analytic_period_jacobian
    from ..analysis.equilibrium import knife_edge_axes, rest_pose
    from ..analysis.modes import linear_modes
    from ..estimation.sensitivity import Sensitivity, perturb, period_sensitivity, periods_of

    rest = rest if rest is not None else rest_pose(scene)
    ms = at(scene.inertia) if at is not None else linear_modes(scene, rest)
    T0 = np.array([m.period if m.period else np.nan for m in ms.modes])
    neutral = not np.all(np.isfinite(T0))
    if not neutral:
        try:
            return period_sensitivity(scene, names, rest=rest, modes=ms), []
        except (UnstableRestError, SlackWireError, ConvergenceError):
            pass
    jac = np.zeros((len(T0), len(names)))
    notes = []
    todo = list(range(len(names)))
    no_branch: set = set()
    undefined: list[str] = []
    if neutral:
        # the analytic derivative where it exists (the branch's derivative, exact: what a
        # one-sided difference approximates to O(h)); the branch-following differences
        # below only for the inputs that push along the neutral direction
        try:
            an, push = analytic_period_jacobian(scene, rest, ms, names, push=True)
        except NotDifferentiable:
            an = None
        if an is not None:
            live = np.isfinite(T0)
            todo = [j for j in todo if np.all(np.isnan(an[live, j]))]
            keep = [j for j in range(len(names)) if j not in todo]
            jac[:, keep] = an[:, keep]
            if np.all(np.isfinite(knife_edge_axes(scene.attachments))):
                no_branch = {j for j in todo if push[j] >= NO_BRANCH_PUSH}
    for j in todo:
        name = names[j]
        h = _fd_step(scene, name)
        side = {}
        for sgn in (() if j in no_branch else (1.0, -1.0)):
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
            # no derivative: within the input's uncertainty the hanging changes qualitatively, so no std
            # can be given (NaN: the budget's sigma is null, as invert's std is, not a sigma without it)
            jac[:, j] = np.nan
            undefined.append(name)
            notes.append(f"{name}: no derivative (no nearby stable rest for a {h:.1e} change either way: "
                         "the point is at the edge of stability): the uncertainty cannot be given")
    return Sensitivity(list(names), T0, jac, ms, rest, undefined=tuple(undefined)), notes


def _nonlinear_runs(scene, rest, ms, labels: list[str], amplitude: float, st: SweepSettings, starts=None) -> list:
    """One nonlinear run per mode label from ``amplitude`` x its shape, all
    in one call of the batched engine (:func:`bifilar.analysis.batch.simulate_batch`;
    :func:`bifilar.analysis.simulate.simulate` one by one if it is absent).
    Each result has .period, .tension_min/.tension_max (n,) N, .slack,
    .depth_max m, .mode, .warnings.  ``starts``: their start poses if already
    solved and checked (``simulate_batch(..., starts=)``)."""
    if not labels:
        return []
    try:
        from ..analysis.batch import simulate_batch
    except ImportError:
        from ..analysis.simulate import simulate

        return [simulate(scene, lab, amplitude, st.periods, rest=rest, modes=ms, rtol=st.rtol) for lab in labels]
    n = len(labels)
    return simulate_batch([scene] * n, mode=labels, amplitude=amplitude, periods=st.periods, rtol=st.rtol,
                          rests=[rest] * n, modes=[ms] * n, starts=starts)


def point_uncertainty(st: SweepSettings, params: dict) -> dict:
    """Input uncertainties of a point: the settings' (defaults < config
    ``uncertainty:`` block < ``--sigma``), with any swept ``uncertainty.KEY``
    parameter of the point taking its value (units as
    :data:`~bifilar.estimation.sensitivity.DEFAULT_UNCERTAINTY`)."""
    unc = st.unc
    for name, v in params.items():
        if name.startswith("uncertainty."):
            unc[name.split(".", 1)[1]] = float(v)
    return unc


def predicted_budget(sens, scene, comp: str, k: int, unc: dict, column=None):
    """The predicted uncertainty of ``comp`` estimated from mode ``k``: the
    one place the sweep, the plan and the remedies compute it (a
    :class:`~bifilar.estimation.sensitivity.Budget`; ``value_sigma`` kg m^2).

    Propagation of the period's timing sigma ``unc["timing"]`` (s) and of
    every measured input's sigma: linear, or the second-order std of
    :func:`bifilar.estimation.budget.component_std` where the linear one is
    wrong (shares and contributions stay the linear ones).  ``column``: dT/dI (s per kg m^2)
    of every mode, replacing ``sens``'s column of ``comp`` (a component of
    the reference body frame seen from another hanging, see
    :mod:`bifilar.studies.remedy`).  Several components of one point at
    once: :func:`predicted_budgets`.
    """
    from dataclasses import replace

    from ..estimation.sensitivity import inertia_budget

    if column is not None:  # the same budget with comp's column replaced (the hanging's other inputs unchanged)
        jac = np.array(sens.jacobian, float, copy=True)
        jac[:, sens.names.index(comp)] = np.asarray(column, float)
        sens = replace(sens, jacobian=jac)
        return inertia_budget(sens, scene, comp, k, unc["timing"], unc)
    return predicted_budgets(sens, scene, [(comp, k)], unc)[0]


def predicted_budgets(sens, scene, requests, unc: dict, honest: bool = True, at=None) -> list:
    """:func:`predicted_budget` of each ``(component, mode index k)`` of
    ``requests`` (0-based k), the honest stds of all of them computed
    together at the scene's truth (:func:`bifilar.estimation.honest.honest_stds`:
    one sensitivity, one set of sigma points for every component).
    ``honest=False``: the linear budgets only (a planner's screen).  ``at``:
    :func:`~bifilar.analysis.modes.modes_of_inertia` of ``scene`` about
    ``sens.rest`` if built (shared with the honest pass)."""
    from dataclasses import replace

    from ..estimation.honest import honest_stds
    from ..estimation.sensitivity import inertia_budget

    out = [inertia_budget(sens, scene, comp, k, unc["timing"], unc) for comp, k in requests]
    # an input with no derivative (a knife edge, dependent wires): invert
    # gives no std there, and the honest figure would fall back to the
    # linear one after a costly inversion (the known limit).  A scene with a
    # neutral mode (a knife edge) gets no second-order terms either
    # (budget.second_order: its sigma points are not treated yet), so its
    # honest std is a linear budget, which the point's branch-following
    # sensitivity already gives (the budget's own forward differences at a
    # knife edge either fail, giving this fallback, or agree within
    # LINEAR_ENOUGH, or jump to another branch)
    neutral = not np.all(np.isfinite(np.asarray(sens.periods, float)))
    todo = [i for i, (_, k) in enumerate(requests)
            if honest and not neutral and np.all(np.isfinite(np.asarray(sens.jacobian, float)[k]))]
    if todo:
        # the std invert prints: second order where the linear one is wrong (a
        # shallow CoM), so a planner can penalise such a rig (issue 10)
        sds = honest_stds(scene, [(requests[i][0], requests[i][1] + 1) for i in todo], unc, unc["timing"],
                          fallbacks=[out[i].value_sigma for i in todo], rest=sens.rest, sens=sens, at=at)
        for i, sd in zip(todo, sds):
            out[i] = replace(out[i], value_sigma=sd)
    return out


def timed_separation(periods, timed) -> float:
    """The mode-separation guard: the smallest relative gap
    ``|T_k - T_j| / T_k`` between any timed mode ``k`` (indices ``timed``)
    and any other mode ``j`` (periods in s; neutral modes, NaN, ignored).
    Close periods beat and spoil the timing.  ``inf`` when nothing is
    timed or there is no other mode."""
    periods = np.asarray(periods, float)
    gaps = [abs(periods[k] - periods[j]) / periods[k] for k in timed for j in range(len(periods))
            if j != k and np.isfinite(periods[j]) and np.isfinite(periods[k])]
    return float(min(gaps)) if gaps else math.inf


def rig_of(scene, rest) -> dict:
    """The rig to build (SI): anchors (world, m), attachments (body frame, CoM
    origin, m), wire lengths (m), each wire's angle from the vertical at rest
    (deg) and the attachment points' world positions at rest (m)."""
    d = np.asarray(rest.wire_vectors, float)  # anchor -> attachment
    ang = np.degrees(np.arccos(np.clip(-d[:, 2] / np.linalg.norm(d, axis=1), -1.0, 1.0)))
    return {"anchors": scene.anchors, "attachments": scene.attachments, "lengths": scene.lengths,
            "wire_angles_deg": ang, "attachments_world": rest.com + scene.attachments @ rest.R.T}


def evaluate_point(base_cfg: dict, source: str, params: dict, settings: SweepSettings, *,
                   screen: bool = False) -> dict:
    """All figures of one sweep point (see the module docstring); never raises
    for a bad point: ``valid: false`` and a one-line ``error`` instead.

    ``screen``: the cheap figures a planner's search needs, marked
    ``"screen": true``: each component's sigma is the linear one (no
    second-order check, :func:`predicted_budgets` with ``honest=False``)
    and the estimator biases are left out (``bias`` None); everything
    else (validity, tensions, depth, separation, identifiability) is the
    full point's."""
    out: dict = {"params": dict(params), "valid": False, "error": None}
    if screen:
        out["screen"] = True
    try:
        out.update(_evaluate(base_cfg, source, params, settings, screen))
        out["valid"] = True
    except (KeyboardInterrupt, SystemExit):
        raise
    except Exception as exc:  # noqa: BLE001 - a sweep point must never crash the sweep
        out["error"] = _error_text(exc)
    return _plain(out)


def _error_text(exc: Exception) -> str:
    """A bad point's one-line ``error``."""
    if isinstance(exc, BifilarError):
        return _one_line(exc)
    return f"internal error ({type(exc).__name__}: {_one_line(exc)})"


def evaluate_points(base_cfg: dict, source: str, grid: list[dict], settings: SweepSettings, *,
                    screen: bool = False) -> list[dict]:
    """:func:`evaluate_point` of every point of ``grid``, the nonlinear runs
    of all of them in one call of the batched engine
    (:func:`bifilar.analysis.batch.simulate_batch`: from
    :data:`~bifilar.analysis.batch.SMALL_BATCH` runs on, one stacked LSODA
    integration with each run's own error bound).  The figures agree with
    :func:`evaluate_point`'s to the integrator tolerance (``settings.rtol``)
    but depend on the batch's other runs at that level, so a point computed
    here is not bit-for-bit the one computed alone: for a planner's
    screens, not for a journaled sweep.  A point whose run fails is
    evaluated alone (its own error message)."""
    out: list = [None] * len(grid)
    prepared = []
    for i, params in enumerate(grid):
        out[i] = {"params": dict(params), "valid": False, "error": None}
        if screen:
            out[i]["screen"] = True
        try:
            prepared.append((i, *_prepare(base_cfg, source, params, settings, screen)))
        except (KeyboardInterrupt, SystemExit):
            raise
        except Exception as exc:  # noqa: BLE001 - the error evaluate_point gives (its _prepare raises the same),
            out[i]["error"] = _error_text(exc)  # not evaluated again: a refused amplitude costs 0.1-0.3 s
            out[i] = _plain(out[i])
    jobs = [(i, k, pre) for i, _, pre in prepared for k in pre.runs]
    runs: list = []
    if jobs:
        from ..analysis.batch import simulate_batch
        from ..analysis.start_pose import StartPoses

        st = settings
        runs = simulate_batch([pre.scene for _, _, pre in jobs], mode=[pre.labels[k] for _, k, pre in jobs],
                              amplitude=[pre.amplitude for _, _, pre in jobs], periods=st.periods, rtol=st.rtol,
                              rests=[pre.rest for _, _, pre in jobs], modes=[pre.ms for _, _, pre in jobs],
                              errors="return", starts=StartPoses.concat([pre.starts for _, _, pre in prepared if pre.runs]))
    sims: dict = {i: {} for i, _, _ in prepared}
    for (i, k, _), r in zip(jobs, runs):
        sims[i][k] = r
    for i, res, pre in prepared:
        if any(r.error for r in sims[i].values()):
            out[i] = evaluate_point(base_cfg, source, grid[i], settings, screen=screen)
            continue
        try:
            out[i].update(_finish(res, pre, {k: sims[i][k] for k in pre.runs}, settings, screen))
            out[i]["valid"] = True
            out[i] = _plain(out[i])
        except (KeyboardInterrupt, SystemExit):
            raise
        except Exception:  # noqa: BLE001
            out[i] = evaluate_point(base_cfg, source, grid[i], settings, screen=screen)
    return out


def _slack_cause(err: SlackWireError, scene, cfg: dict, st: SweepSettings, params: dict) -> SlackWireError:
    """A point's slack-wire refusal ``err`` with the words ``invert`` gives
    when the slack lies within what the measured inputs' uncertainties give
    it (:func:`~bifilar.estimation.slack_cause.within_uncertainty`, with the
    point's uncertainties: the config's block, ``--sigma`` and
    ``uncertainty.KEY`` parameters), where the point's config (``cfg``)
    states a geometry uncertainty; ``err`` itself otherwise (a rig as
    designed: its slack is its own).  Only invalid points pay for it (one
    rest pose per measured input, ~30 for four wires)."""
    from ..estimation.slack_cause import states_geometry, within_uncertainty

    if not states_geometry(cfg.get("uncertainty")):
        return err
    return within_uncertainty(err, scene, point_uncertainty(st, params),
                              "the point's uncertainties: the config's block and any --sigma")


def _prepare(base_cfg: dict, source: str, params: dict, st: SweepSettings, screen: bool = False):
    """(the point's figures up to its nonlinear runs, :class:`_Prepared`); raises for a bad point."""
    from ..analysis.equilibrium import rest_pose
    from ..config import scene_from_dict
    from ..estimation.sensitivity import best_mode_for, grouped_shares, input_sigma, measured_inputs, stiff_inputs

    cfg, amp_override = apply_params(base_cfg, params, source)
    amplitude = st.amplitude if amp_override is None else amp_override
    if not amplitude > 0:
        raise InputError("amplitude", f"must be positive, got {amplitude:g}")
    scene = scene_from_dict(cfg, source, warn=False)  # the base config's warnings were shown once
    try:
        rest0 = rest_pose(scene)  # invalid points (slack, unstable) fail here with their reason
    except SlackWireError as e:
        raise _slack_cause(e, scene, cfg, st, params) from None
    unc = point_uncertainty(st, params)
    if scene.stiffness is not None:  # EA's default, listed in the point's uncertainty only where EA is stated
        from ..estimation.sensitivity import DEFAULT_STIFFNESS_REL

        unc.setdefault("stiffness", DEFAULT_STIFFNESS_REL)
    names = list(st.components) + measured_inputs(scene)
    if input_sigma(scene, "gravity", unc) > 0:  # a stated uncertainty of g (default 0: known), as invert's budget
        names.append("gravity")
    names += stiff_inputs(scene, unc)  # EA's factor where rig.stiffness is stated, as invert's budget
    at = _stiffness(scene, rest0)
    sens, notes = point_sensitivity(scene, names, rest0, at=at)
    ms, rest = sens.modes, sens.rest
    labels = [m.label for m in ms.modes]
    periods = sens.periods
    res: dict = {
        "amplitude": amplitude,
        "mass": scene.mass,
        "lengths": scene.lengths,
        "periods": {m.label: m.period for m in ms.modes},
        "components": {},
        "uncertainty": unc,
        "rig": rig_of(scene, rest),
        "notes": notes,
        "warnings": [],
    }
    _clearance(res, scene, rest)
    chosen: dict[str, int] = {}
    for comp in st.components:
        I = float(scene.inertia[_IDX[comp]])
        scale = component_scale(scene.inertia, comp)
        col = sens.column(comp)
        rel = np.abs(col) * scale / np.where(np.isfinite(periods), periods, np.inf)
        rel = np.where(np.isfinite(rel), rel, 0.0)
        entry: dict = {"value": I, "identifiable": bool(rel.max() >= IDENTIFIABLE_MIN),
                       "from_modes": {labels[i]: float(rel[i]) for i in np.argsort(-rel) if rel[i] >= IDENTIFIABLE_MIN}}
        if not entry["identifiable"]:
            entry.update(mode=None, sigma=math.inf, rel_sigma=math.inf,
                         reason=f"no mode's period depends on {comp} (max |d ln T / d ln {comp}| = {rel.max():.1e})")
            res["components"][comp] = entry
            continue
        chosen[comp] = best_mode_for(sens, comp)
        res["components"][comp] = entry
    from ..estimation.elastic_split import component_refusals, point_risks

    risks, refusal = point_risks(res, scene, rest, unc)  # four or five elastic wires: what drawn configs do
    # a refused sigma needs no second-order pass (its linear budget keeps the shares)
    budgets = dict(zip(chosen, predicted_budgets(sens, scene, list(chosen.items()), unc,
                                                 honest=not screen and refusal is None, at=at)))
    # near the held-direction rule only: each component by its mode's bias from the rigid hold (twin26)
    refused = {c: refusal for c in budgets} if refusal is not None else component_refusals(
        risks, scene, rest, ms, chosen, budgets)
    if refused:
        from dataclasses import replace

        budgets = {comp: replace(b, value_sigma=math.inf) if comp in refused else b for comp, b in budgets.items()}
    for comp, k in chosen.items():
        entry = res["components"][comp]
        scale = component_scale(scene.inertia, comp)
        col = sens.column(comp)
        b = budgets[comp]
        j_all = [j for j, n in enumerate(sens.names) if n not in _IDX]
        dI_dx = {sens.names[j]: -float(sens.jacobian[k, j] / col[k]) for j in j_all}
        sep = timed_separation(periods, {k})
        axis = _IDX[comp][0] if comp in PRINCIPAL else None
        entry.update(
            mode=labels[k], period=float(periods[k]),
            sigma=b.value_sigma, rel_sigma=b.value_sigma / scale if scale else math.inf,
            rel_sensitivity_period=b.rel_sensitivity,
            dlnI_dx={n: v / scale for n, v in dI_dx.items()} if scale else dI_dx,
            shares=grouped_shares(b, b.value_sigma), separation=sep,
            axis_vertical=bool(axis is not None and abs(rest.R[2, axis]) > 0.99),
        )
        entry.update(physical_limits(scene.inertia, comp, b))
        if comp in refused:  # four or five elastic wires whose drawn configs the model cannot answer for
            entry["sigma_unavailable"] = refused[comp]
        elif not math.isfinite(b.value_sigma):  # an input without a derivative (a knife edge, dependent wires)
            from ..estimation.inversion_result import rigid_dependent, std_unavailable_text

            bad = [n for j, n in enumerate(sens.names) if n not in _IDX and not np.isfinite(sens.jacobian[k, j])]
            entry["sigma_unavailable"] = std_unavailable_text(bad, "--sigma KEY=VALUE", rigid_dependent([(scene, rest)]))
        elif risks is not None:  # the drawn configs left slack (or, never here, held otherwise) are refused too
            from ..estimation.elastic_split import combined_refusal

            entry["p_refused"] = combined_refusal(entry["p_refused"], risks.p_model)
        res["components"][comp] = entry
    res["separation"] = timed_separation(periods, set(chosen.values()))
    pre = _Prepared(scene, rest, ms, labels, periods, sens, chosen, amplitude, [], at=at, budgets=budgets)
    if st.tensions:
        pre.runs = sorted(set(chosen.values()))
        _stretching(res, scene, rest, [ms.modes[k] for k in pre.runs])
        from ..analysis.simulate import checked_start_poses

        # the refusal `simulate` gives (InputError) rather than a run from an unreachable start; the start poses
        # go on to the runs (solved once)
        if pre.runs:
            # the amplitude laws' runs' start poses in the same call (one solve: tests/test_point_cost.py); only
            # the laws a sigma reads (a component without a finite small-amplitude sigma has no stated one)
            pre.law = _law_runs(scene, rest, ms, labels, _budgeted(chosen, budgets), amplitude, at)
            law = pre.law
            sp = checked_start_poses(scene, rest, [ms.modes[k] for k in pre.runs], amplitude,
                                     more=(law.scenes, law.rests, [m.get(lab) for m, lab in zip(law.mode_sets, law.labels)],
                                           law.amplitudes))
            n = len(pre.runs)
            pre.starts, law.starts = sp.take(np.arange(n)), sp.take(np.arange(n, len(sp.feasible)))
    return res, pre


def _clearance(res: dict, scene, rest) -> None:
    """Mark the point ``res`` whose body at rest reaches above the ceiling
    (``ceiling_clash``) or whose wires cross at rest (``wires_cross``),
    with the warnings `modes` gives (:mod:`bifilar.analysis.clearance`;
    geometry of the rest pose, ~0.1 ms): the model sees neither, so its
    figures hold for a rig that cannot be built as described; the ranking
    puts such points after every clean one (:func:`~bifilar.studies.ranking.rank_order`).
    Then a body hanging far turned (:func:`~bifilar.analysis.rest_warnings.turn_warning`),
    unflagged: a rig may be meant so; the recommended point repeats it."""
    from ..analysis.clearance import ceiling_warning, crossing_warning
    from ..analysis.rest_warnings import turn_warning

    for flag, check in (("ceiling_clash", ceiling_warning), ("wires_cross", crossing_warning)):
        w = check(scene, rest)
        res[flag] = w is not None
        if w is not None:
            res["warnings"].append(w)
    res["warnings"] += [w for w in [turn_warning(scene, rest)] if w is not None]


def _stiffness(scene, rest):
    """The point's reduced stiffness about its rest pose, built once
    (:func:`~bifilar.analysis.modes.modes_of_inertia`): its linear modes,
    the honest pass's and the thesis rung's hanging models and the linear
    estimates' eigenproblems all use it (each built its own before, the
    same numbers)."""
    from ..analysis.modes import modes_of_inertia

    return modes_of_inertia(scene, rest)


@dataclass
class _Prepared:
    """A point evaluated up to its nonlinear runs: what :func:`_finish` needs."""

    scene: Any
    rest: Any
    ms: Any
    labels: list
    periods: np.ndarray
    sens: Any
    chosen: dict
    amplitude: float
    runs: list  # mode indices to run nonlinearly (empty: none)
    starts: Any = None  # their start poses (StartPoses, in the order of runs), checked
    at: Any = None  # modes_of_inertia of scene about rest (_stiffness), or None
    budgets: dict = None  # {component: its Budget at a small amplitude (predicted_budgets)}
    law: Any = None  # the runs of its amplitude laws (_LawRuns), planned with its own runs


def _evaluate(base_cfg: dict, source: str, params: dict, st: SweepSettings, screen: bool = False) -> dict:
    res, pre = _prepare(base_cfg, source, params, st, screen)
    sims: dict[int, Any] = {}
    if pre.runs:
        labels = [pre.labels[k] for k in pre.runs]
        runs = None
        if pre.law is not None and pre.law.starts is not None:
            # the point's runs (with their health) and its amplitude laws' (without), each run as alone: the
            # same figures
            runs = _runs_at(pre.law, st, own=(pre.scene, pre.rest, pre.ms, labels, pre.amplitude, pre.starts))
            if any(r.error for r in runs[:len(labels)]):
                runs = None  # the point's own runs again, alone: the error they raise
            else:
                runs, pre.law.runs = runs[:len(labels)], runs[len(labels):]
        if runs is None:
            runs = _nonlinear_runs(pre.scene, pre.rest, pre.ms, labels, pre.amplitude, st, pre.starts)
        from .point_symmetry import symmetric_run_warnings

        symmetric_run_warnings(pre.scene, pre.rest, pre.ms, labels, pre.amplitude, st.periods, st.rtol, runs)
        sims = dict(zip(pre.runs, runs))
    return _finish(res, pre, sims, st, screen)


def run_health(run) -> dict:
    """A point's nonlinear run's health, as ``simulate --json`` gives it (SI):
    its period (s), constraint violation (m), energy drift and the
    health keys of :func:`~bifilar.analysis.simulate.health_json`
    (``period_error``, ``energy_drift_resolution``, ...); JSON null where undefined."""
    from ..analysis.simulate import health_json

    def f(x):
        return float(x) if x is not None and np.isfinite(x) else None

    return {"period": f(run.period), "max_constraint_violation": f(run.max_constraint_violation),
            "energy_drift": f(run.energy_drift), **health_json(run)}


def _stretching(res: dict, scene, rest, modes) -> None:
    """Mark the point ``res`` whose dependent wires cannot follow the modes
    its nonlinear runs excite (:func:`~bifilar.analysis.wire_statics.stretching_modes`):
    ``stretching_modes`` (their labels) and the warning `modes` gives; the
    runs' tensions, slack and amplitude terms are then not physical."""
    from ..analysis.wire_statics import stretching_modes, stretching_text

    hits = [lb for lb, _ in stretching_modes(scene, rest, modes)]
    if hits:
        res["stretching_modes"] = hits
        res["warnings"].append(stretching_text(scene, hits))


def statics_range(scene, rest, tmax) -> dict:
    """What statics leaves open of a point's wire tensions (N) where its
    wires are dependent at rest (4 or 5 wires, :func:`~bifilar.analysis.equilibrium.tensions_determined`
    false), whose reported tensions are only the model's split:
    ``range`` (n, 2) the least and greatest tension each wire can carry at
    rest (:func:`~bifilar.analysis.wire_statics.tension_range`), and
    ``range_peak`` the greatest a wire can reach in the runs, at wire
    ``range_peak_wire`` (1-based): the greatest share of one wire in a
    split, at the rest geometry, of the wrench the wires exert with each
    wire at its peak in the runs (``tmax``, the model's split; at least its
    rest tension, the body hanging before release), one linear programme
    per wire (:func:`~bifilar.analysis.wire_statics.split_bounds`).

    Why it bounds the runs: at fixed geometry a wire's greatest share of
    the wrench of tensions ``T`` grows with every ``T_j`` (a larger ``T``
    only widens the splits ``T + N s >= 0`` along the self-stresses ``N``),
    so no sample's tensions, each at most ``tmax``, give more; what the
    geometry's change in the runs adds is small: against a linear
    programme over the splits of every sample of a run (its own geometry)
    this lies 0-2.1e-4 above on vertical 4- and 5-wire rigs, CoM centred
    or 5-10 cm off, torsion 0.1-0.3 rad and both swings 0.1-0.3 m, and
    2-20 % above on a 4-wire rig whose wires splay out 30 % (its swings
    tilt the wires' lines apart; torsion exact).  Session 12's rule, each
    wire's top at rest times its own peak-to-rest ratio, lay up to 5.0e-4
    below on those off-centre rigs (a torsion loads the wires unevenly) and
    up to 40 % above on the splayed one (docs/design.md, "rankfix,
    session 13"; tests/test_tension_range_limit.py).  All None for
    determined tensions."""
    from ..analysis.equilibrium import tensions_determined
    from ..analysis.wire_statics import tension_range
    from ..analysis.wire_statics import reduced_statics, split_bounds

    if tensions_determined(scene, rest):
        return {"range": None, "range_peak": None, "range_peak_wire": None}
    rng = tension_range(scene, rest)
    A, P = reduced_statics(scene, rest)
    peak = np.maximum(np.asarray(tmax, float), np.asarray(rest.tensions, float))
    top = np.maximum(split_bounds(A, P, A @ peak, peak, lower=False)[:, 1], rng[:, 1])
    i = int(np.argmax(top))
    return {"range": rng, "range_peak": float(top[i]), "range_peak_wire": i + 1}


def _finish(res: dict, pre: _Prepared, sims: dict, st: SweepSettings, screen: bool) -> dict:
    """The point's figures from its nonlinear runs ``sims`` {mode index: run} on."""
    scene, rest, ms, labels, periods, sens, chosen = (pre.scene, pre.rest, pre.ms, pre.labels, pre.periods,
                                                      pre.sens, pre.chosen)
    if st.tensions:
        tmax = np.max([s.tension_max for s in sims.values()], axis=0) if sims else rest.tensions
        tmin = np.min([s.tension_min for s in sims.values()], axis=0) if sims else rest.tensions
        slack = sorted({w for s in sims.values() for w, _ in s.slack})
        res["tension"] = {"rest": rest.tensions, "max": tmax, "min": tmin, "peak": float(np.max(tmax)),
                          "slack": bool(slack), "slack_wires": slack, "by_mode": {
                              labels[k]: {"max": s.tension_max, "min": s.tension_min,  # ranking.guarded_limits
                                          "slack_wires": sorted({w for w, _ in s.slack})} for k, s in sims.items()},
                          **statics_range(scene, rest, tmax)}
        res["depth"] = {"rest": rest.depth, "max": max([rest.depth] + [s.depth_max for s in sims.values()]),
                        "by_mode": {labels[k]: s.depth_max for k, s in sims.items()}}
        res["runs"] = {labels[k]: run_health(s) for k, s in sims.items()}
        for s in sims.values():
            res["warnings"] += [f"{s.mode}: {w}" for w in s.warnings]
    else:
        res["tension"] = {"rest": rest.tensions, "max": None, "min": None, "peak": None, "slack": None,
                          "slack_wires": [], "by_mode": {}, "range": None, "range_peak": None, "range_peak_wire": None}
        res["depth"] = {"rest": rest.depth, "max": None}
        res["runs"] = {}
    _stated_amplitude(res, pre, sims, st, screen)
    if screen:
        return res
    # biases at the prescribed amplitude
    at = pre.at  # the linear estimates' eigenproblems: the point's one stiffness
    if at is None and chosen:
        from ..analysis.modes import modes_of_inertia

        at = modes_of_inertia(scene, rest)
    from ..estimation.sensitivity import period_matcher

    ladder = _Ladder(scene, rest, pre.at)
    matched = period_matcher(ms) if chosen else None  # (one for every component's linear estimate)
    for comp, k in chosen.items():
        e = res["components"][comp]
        T_lin = float(periods[k])
        T_nl = sims[k].period if k in sims else None
        T_ref = T_nl if T_nl is not None else T_lin
        bias, bnotes = ladder.biases(comp, labels[k], T_ref, e["axis_vertical"])
        I_lin = linear_estimate(scene, comp, k, T_ref, ms, rest, sens.column(comp)[k], float(periods[k]), at=at,
                                matched=matched)
        bias["linear"] = (I_lin - e["value"]) / e["value"] if I_lin is not None and e["value"] else None
        e.update(nonlinear_period=T_nl, bias=bias, bias_reference="nonlinear" if T_nl else "linear",
                 bias_notes=bnotes)
        if st.tensions and T_nl is None:
            bnotes["linear"] = "no period measured in the nonlinear run; biases against the linear period"
    return res
