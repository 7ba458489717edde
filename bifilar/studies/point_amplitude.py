"""A sweep point's stated amplitude: the sigma ``invert --period MODE=T
--amplitude A`` prints, from the small-amplitude budget, the point's
nonlinear run (the amplitude factor) and the mode's amplitude law (its
slope, from a run at :data:`~bifilar.estimation.solve.STATED_LAW_RATIO` of
the amplitude, and the factor's derivative in the component, from a run of
the scene with the component stepped), run as ``invert`` runs them.  SI
units.  Split from :mod:`bifilar.studies.point`, which calls
:func:`_law_runs` (with its own runs) and :func:`_stated_amplitude`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import BifilarError
from .limits import component_scale, physical_limits
from .settings import _IDX, SweepSettings

if TYPE_CHECKING:
    from .point import _Prepared


def stated_amplitude_budget(budget, T_lin: float, r: float, rel: float, slope: float | None = None,
                            dr_dI: float = 0.0, inputs: dict | None = None):
    """The budget ``invert --period MODE=T --amplitude A`` prints (one
    period, one unknown, the nonlinear rung) from the small-amplitude one
    (``--amplitude 0``) of the same component and mode: ``budget`` (a
    :class:`~bifilar.estimation.sensitivity.Budget`, its ``value_sigma``
    the honest std, kg m^2), ``T_lin`` the mode's linear period (s), ``r =
    T(A) / T_lin`` the amplitude factor at the stated amplitude ``A``,
    ``rel`` the amplitude's relative standard uncertainty (invert's default
    :data:`~bifilar.estimation.uncertainty.DEFAULT_AMPLITUDE_REL` for an
    ``--amplitude`` without ``+-``), ``slope`` = ``A dr/dA`` from the
    mode's amplitude law (:class:`~bifilar.estimation.solve.AmplitudeLaw`;
    None: the quadratic rule's ``2 (r - 1)``, only for a caller without the
    law's run) and ``dr_dI`` the factor's derivative in the component
    (1 / kg m^2; invert's forward difference, see
    :func:`~bifilar.estimation.solve.stated_amplitude_law`).

    The nonlinear rung fits ``T_lin(I) r(A; I) = T``
    (:mod:`bifilar.estimation.budget`, ``_budget``): the period's derivative
    in ``I`` is ``g dT_lin/dI`` with ``g = r + T_lin dr_dI dI/dT``, so the
    timing's contribution ``s_T / (g dT/dI)`` is the small-amplitude one
    divided by ``g``, the stated amplitude's own uncertainty ``s_A = rel A``
    adds ``T_lin (dr/dA) s_A / (g dT/dI)`` = ``|slope rel T_lin dI/dT /
    g|``, and an input's contribution is unchanged (the factor taken to
    depend on the inputs as on the unknown) except those of ``inputs``
    {input: its contribution, kg m^2}, which replace theirs: ``invert``
    measures ``dr/dx`` by one run per input and puts each input through
    the full gain (``budget._with_factor_gain``; the sweep's
    :func:`~bifilar.studies.point_inputs.input_factor_terms`, the Solar
    Boat's Izz at spacing 1, length 2, 0.3 rad: without them invert's std
    is 1.12 of this one, docs/design.md, "The stated amplitude").
    The second-order terms (re-solved sigma points) are those of the
    small-amplitude budget (the factor cancels in them), so the same change
    applies to the honest std.  Returns (std, timing contribution, amplitude
    contribution, variance shares by kind), kg m^2."""
    c_t = float(budget.contributions["timing"])
    g = r + T_lin * dr_dI * float(budget.dI_dT)
    slope = 2.0 * (r - 1.0) if slope is None else slope
    c_a = abs(slope * rel * T_lin * float(budget.dI_dT) / g)
    sd = float(budget.value_sigma)
    var = sd * sd - c_t * c_t * (1.0 - 1.0 / (g * g)) + c_a * c_a
    lin = {k: float(c) for k, c in budget.contributions.items()}
    for key, c in (inputs or {}).items():
        var += c * c - lin[key] * lin[key]
        lin[key] = abs(float(c))
    lin["timing"] = c_t / g
    lin["amplitude"] = c_a
    tot = sum(c * c for c in lin.values())
    shares = {k: (c * c / tot if tot > 0 else 0.0) for k, c in lin.items()}
    return math.sqrt(max(var, 0.0)), c_t / g, c_a, shares


@dataclass
class _LawRuns:
    """The runs of a point's amplitude laws (:func:`_amplitude_laws`), SI:
    per timed mode one at :data:`~bifilar.estimation.solve.STATED_LAW_RATIO`
    of the amplitude (``modes``, mode indices), then per component one of
    the scene with it stepped by ``h`` (kg m^2) at the amplitude
    (``comps``: (component, mode index)); ``scenes`` .. ``mode_sets`` the
    :func:`~bifilar.analysis.batch.simulate_batch` arguments in that order,
    ``starts`` their start poses once solved (with the point's own, one
    call: :func:`~bifilar.analysis.simulate.checked_start_poses`'s
    ``more``), ``runs`` the runs once run (beside the point's own:
    :func:`_evaluate`, :func:`_runs_at`)."""

    comps: list
    modes: list
    h: float
    scenes: list
    labels: list
    amplitudes: list
    rests: list
    mode_sets: list
    starts: Any = None
    runs: Any = None


def _budgeted(chosen: dict, budgets: dict | None) -> dict:
    """The components of ``chosen`` {component: mode index} whose
    small-amplitude sigma (``budgets``' ``value_sigma``, kg m^2) is finite:
    the only ones whose stated-amplitude sigma reads their amplitude law
    (:func:`_stated_amplitude` gives the others no sigma), so the only ones
    whose law is run.  A knife-edge point (the thesis plate: an input
    without a derivative) has none: its law's runs, 4 of its 6, were made
    and never read (docs/design.md, "Session 15, perf17")."""
    if budgets is None:
        return dict(chosen)
    return {c: k for c, k in chosen.items() if math.isfinite(float(budgets[c].value_sigma))}


def _law_runs(scene, rest, ms, labels, chosen: dict, amplitude: float, at=None) -> _LawRuns:
    """What :func:`_amplitude_laws` runs for the components ``chosen``
    {component: mode index} (each stepped as invert's
    :func:`~bifilar.estimation.solve.stated_amplitude_law` steps it:
    :data:`~bifilar.estimation.solve.FACTOR_STEP` of the largest moment).
    ``at``: the point's :func:`_stiffness` (the stepped scenes' modes from
    its eigenproblem, the same bits as their own ``linear_modes``), else
    each stepped scene's ``linear_modes``."""
    from dataclasses import replace

    from ..analysis.modes import linear_modes
    from ..estimation.solve import FACTOR_STEP, STATED_LAW_RATIO

    comps = list(chosen.items())
    modes = sorted({k for _, k in comps})
    h = FACTOR_STEP * float(np.max(np.linalg.eigvalsh(scene.inertia)))
    stepped = []
    for c, _ in comps:
        I = np.array(scene.inertia, float)
        i, j = _IDX[c]
        I[i, j] += h
        if i != j:
            I[j, i] += h
        sc = replace(scene, inertia=I)
        stepped.append((sc, at(I) if at is not None else linear_modes(sc, rest)))
    n = len(modes) + len(comps)
    return _LawRuns(comps, modes, h, [scene] * len(modes) + [sc for sc, _ in stepped],
                    [labels[k] for k in modes] + [labels[k] for _, k in comps],
                    [STATED_LAW_RATIO * amplitude] * len(modes) + [amplitude] * len(comps), [rest] * n,
                    [ms] * len(modes) + [m for _, m in stepped])


def _amplitude_laws(pre: "_Prepared", sims: dict, st: SweepSettings) -> dict:
    """{component: (A dr/dA, dr/dI)} of every component whose mode has a
    run at the point's amplitude: the law's second run at
    :data:`~bifilar.estimation.solve.STATED_LAW_RATIO` of the amplitude
    per mode, and one run per component with it stepped by
    :data:`~bifilar.estimation.solve.FACTOR_STEP` of the largest moment (as
    invert's :func:`~bifilar.estimation.solve.stated_amplitude_law`;
    :func:`_law_runs`), as the point's own runs (periods, rtol): run with
    them if :func:`_evaluate` did (``pre.law.runs``), else in one call of
    the batched engine from the start poses solved with the point's
    (``pre.law.starts``); a component whose runs fail is left out (its
    sigma then says so)."""
    from ..estimation.solve import STATED_LAW_RATIO, amplitude_law

    law = pre.law
    if law is None:
        law = _law_runs(pre.scene, pre.rest, pre.ms, pre.labels, _budgeted(pre.chosen, pre.budgets), pre.amplitude,
                        pre.at)
    comps = [(n, c, k) for n, (c, k) in enumerate(law.comps) if sims.get(k) is not None and sims[k].period]
    if not comps:
        return {}
    runs = law.runs
    if runs is None:
        try:
            runs = _runs_at(law, st, own_runs=list(sims.values()))
        except BifilarError:
            return {}
    out = {}
    for n, c, k in comps:
        half, step = runs[law.modes.index(k)], runs[len(law.modes) + n]
        if half.error or step.error or not half.period or not step.period:
            continue
        r = sims[k].period / float(pre.periods[k])
        fit = amplitude_law(pre.amplitude, r, STATED_LAW_RATIO, half.period / float(pre.periods[k]))
        out[c] = (pre.amplitude * fit.slope(), (step.period / step.linear_period - r) / law.h)
    _refine_dr_dI(out, pre, law, comps, st)
    return out


def _refine_dr_dI(out: dict, pre: "_Prepared", law: _LawRuns, comps: list, st: SweepSettings) -> None:
    """Replace in ``out`` {component: (A dr/dA, dr/dI)} the ``dr/dI`` whose
    runs' period error could move the factor gain by more than
    :data:`~bifilar.estimation.solve.FACTOR_GAIN_NOISE`
    (:func:`~bifilar.estimation.solve.factor_step_rtol`, as invert's
    :func:`~bifilar.estimation.solve.stated_amplitude_law`) by the same
    forward difference of the mode's run and the stepped scene's, both run
    again at the rtol it asks for (one batched call at the tightest of
    them); a component whose runs fail keeps its first ``dr/dI``."""
    from ..analysis.batch import simulate_batch
    from ..estimation.solve import factor_step_rtol

    redo = []
    for n, c, k in comps:
        dI_dT = float(pre.budgets[c].dI_dT) if c in out else 0.0
        tight = factor_step_rtol(st.rtol, float(pre.periods[k]), 1.0 / dI_dT if dI_dT else 0.0, law.h)
        if tight is not None:
            redo.append((n, c, k, tight))
    if not redo:
        return
    scenes, labels, mss, rows = [], [], [], []
    for n, _, k, _ in redo:
        scenes += [pre.scene, law.scenes[len(law.modes) + n]]
        labels += [pre.labels[k]] * 2
        mss += [pre.ms, law.mode_sets[len(law.modes) + n]]
        rows.append((k, len(law.modes) + n))
    try:
        runs = simulate_batch(scenes, mode=labels, amplitude=pre.amplitude, periods=st.periods,
                              rtol=min(t for *_, t in redo), rests=[pre.rest] * len(scenes), modes=mss,
                              errors="return", health=False, starts=_known_starts(pre, law, rows))
    except BifilarError:
        return
    for i, (_, c, _, _) in enumerate(redo):
        own, step = runs[2 * i], runs[2 * i + 1]
        if own.error or step.error or not own.period or not step.period:
            continue
        dr = (step.period / step.linear_period - own.period / own.linear_period) / law.h
        out[c] = (out[c][0], dr)


def _known_starts(pre: "_Prepared", law: _LawRuns, rows: list):
    """The start poses of :func:`_refine_dr_dI`'s runs, in its order, where the
    point solved them already (``StartPoses``, SI, world frame), else None
    (``simulate_batch`` then solves them).  ``rows``: per component (the
    mode index k of the point's own run, the row j of its stepped run in
    ``law``).  The own run again at a tighter rtol starts where the point's
    run of mode k started (row ``pre.runs.index(k)`` of ``pre.starts``:
    the same scene, rest pose, mode and amplitude), the stepped one where
    the law's run of that scene did (row j of ``law.starts``); both were
    solved in the point's one call, whose rows are solved independently, so
    each is what a call of its own gives (tests/test_point_cost.py): the
    same bits as the 2-row solve they replace (~1.3 ms; docs/design.md,
    "runs28, session 28").  None where the law was planned without the
    point's runs (no ``law.starts``)."""
    if pre.starts is None or law.starts is None or any(k not in pre.runs for k, _ in rows):
        return None
    from ..analysis.start_pose import StartPoses

    return StartPoses.concat([part for k, j in rows
                              for part in (pre.starts.take([pre.runs.index(k)]), law.starts.take([j]))])


LAW_SAMPLES = 64
"""Samples a period on which the one-scene LSODA engine evaluates a run
(:mod:`bifilar.analysis.batch_lsoda`: ``max(64, spp)``, 64 for a point's
runs, which keep no samples): a run's upward crossings are located on the
8 samples about each, 3 before its left sample and 4 after
(:func:`~bifilar.integrators.sampled_crossings`)."""

LAW_TAIL = 10 / LAW_SAMPLES
"""How far past the point's own runs' last timed crossing (in linear
periods, scaled to the slower side of the amplitude factor) its amplitude
laws' runs are integrated (:func:`_law_length`): the crossing stencil's 4
samples after its left sample, one for the rounding of the crossing's
sample index, and ~0.08 of a period for the law runs' crossings to fall
later than the point's (a law run's amplitude factor lies between 1 and the
point's, the stepped scenes' by ~1e-6 of it)."""


def _law_length(own_runs, periods: float) -> float:
    """Periods (in each run's linear period) to integrate a point's amplitude
    laws' runs for, of ``periods`` (the point's own, :class:`SweepSettings`):
    a multiple of 1 / :data:`LAW_SAMPLES`, :data:`LAW_TAIL` past the last
    upward crossing of the point's own runs ``own_runs`` (SceneRuns of the
    same scene and amplitude), divided by their amplitude factor where it
    is below 1; ``periods`` where a run has no crossings or the end would
    not come before it.  The laws' runs read only their periods, i.e.
    their crossings up to ``periods``: integrating past the last one (the
    last ~quarter period of three, after the release from the mode's
    extreme) changes none of them (LSODA's steps do not depend on where its
    output stops; :func:`_runs_at` checks each run and runs it in full
    otherwise)."""
    last = 0.0
    for r in own_runs:
        if r is None or r.error or len(r.crossings) < 2 or not r.period or not r.linear_period:
            return periods
        last = max(last, float(r.crossings[-1]) / r.linear_period / min(1.0, r.period / r.linear_period))
    end = math.ceil((last + LAW_TAIL) * LAW_SAMPLES) / LAW_SAMPLES
    return end if end < periods else periods


def _trimmed_complete(run, end: float, periods: float) -> bool:
    """Whether a law run integrated to ``end`` (< ``periods``, linear
    periods) has every crossing the run to ``periods`` has, located on the
    same samples: at least two (a period), the last one's 8-sample stencil
    inside the shortened record with a sample to spare, cycles regular
    within 10 %, and the next upward crossing, three quarters of the
    shortest cycle after the last at the earliest, past ``periods``."""
    if run.error or not run.period or not run.linear_period or len(run.crossings) < 2:
        return False
    # on Python floats (a run's ~3 crossings: the same divisions, differences and extremes as numpy's, without
    # its calls; tests/test_runs27.py)
    T = float(run.linear_period)
    tau = [t / T for t in np.asarray(run.crossings, float).tolist()]
    cyc = [b - a for a, b in zip(tau, tau[1:])]
    if any(c != c for c in cyc):  # a NaN cycle: numpy's extremes are NaN and every test below fails
        return False
    lo, hi = min(cyc), max(cyc)
    if not (tau[-1] <= end - 6 / LAW_SAMPLES and lo > 0 and hi <= 1.1 * lo):
        return False
    return tau[-1] + 0.75 * lo > periods


def _runs_at(law: _LawRuns, st: SweepSettings, own=None, own_runs=None) -> list:
    """The runs of ``law`` (errors returned per run, from ``law.starts`` if
    solved), then only their periods read: run without the health figures
    (``simulate_batch(..., health=False)``: the same steps and samples, so
    the same periods, tests/test_point_cost.py), all in one call (its runs
    of the point's scene share that scene's parameters and kernels, and
    every run's crossings are taken in one pass,
    :func:`~bifilar.analysis.batch.simulate_batch`).  ``own``: (scene, rest,
    mode set, labels, amplitude, their start poses) of the point's own
    runs, run first in a call of their own with their health (which the
    law's runs no longer share: their health was computed and not read);
    returns the point's runs, then the law's."""
    from ..analysis.batch import simulate_batch

    def call(scenes, labels, amps, rests, mss, starts, health, periods=st.periods):
        if not scenes:
            return []
        return simulate_batch(scenes, mode=labels, amplitude=amps, periods=periods, rtol=st.rtol, rests=rests,
                              modes=mss, errors="return", starts=starts, health=health)

    first = []
    if own is not None:
        scene, rest, ms, own_labels, amplitude, own_starts = own
        n = len(own_labels)
        first = call([scene] * n, list(own_labels), [amplitude] * n, [rest] * n, [ms] * n, own_starts, True)
        own_runs = first
    args = (law.scenes, law.labels, law.amplitudes, law.rests, law.mode_sets)
    end = _law_length(own_runs, st.periods) if own_runs else st.periods
    runs = call(*args, law.starts, False, end)
    if end < st.periods:
        redo = [i for i, r in enumerate(runs) if not _trimmed_complete(r, end, st.periods)]
        if redo:  # in full, as they were run before (each run's figures are its own, whatever its batch)
            starts = None if law.starts is None else law.starts.take(redo)
            full = call(*[[a[i] for i in redo] for a in args], starts, False)
            for i, r in zip(redo, full):
                runs[i] = r
    return first + runs


def _stated_amplitude(res: dict, pre: "_Prepared", sims: dict, st: SweepSettings, screen: bool = False) -> None:
    """Each component's sigma for the amplitude stated to ``invert`` (the
    point's nonlinear run gives the amplitude factor, :func:`_amplitude_laws`
    its slope and its derivative in the component;
    :func:`stated_amplitude_budget`), the small-amplitude figure kept in
    ``amplitude_budget``; without a run (``--no-tensions``, a planner's
    screen without runs) the sigma stays the small-amplitude one and
    ``amplitude_budget.budgeted`` is false.  The inputs' terms take the
    factor's measured ``dr/dx`` (:mod:`bifilar.studies.point_inputs`: the
    runs of every timed mode that needs them in one call;
    ``input_factor_terms`` true) where they could change a sigma by more
    than :data:`~bifilar.studies.point_inputs.FACTOR_INPUT_ENOUGH` of it
    (``input_factor_bound``, relative, bounds what is left out); a screen
    (``screen``) does not run them."""
    from ..estimation.sensitivity import Budget, grouped_shares
    from ..estimation.uncertainty import DEFAULT_AMPLITUDE_REL
    from .point_far_amplitude import far_amplitude
    from .point_inputs import FACTOR_INPUT_ENOUGH, input_factor_bound, input_factor_terms, measure_factor_inputs

    laws = _amplitude_laws(pre, sims, st)
    unc = res["uncertainty"]
    todo = {}
    fars = {}  # mode index: its FarAmplitude (None within FAR_FROM_LINEAR), one pair of runs a mode
    for comp, k in pre.chosen.items():
        e = res["components"][comp]
        b = pre.budgets[comp]
        sd0 = float(b.value_sigma)
        run = sims.get(k)
        T_lin = float(pre.periods[k])
        r = run.period / T_lin if run is not None and run.period else None
        info = {"amplitude": pre.amplitude, "relative_std": DEFAULT_AMPLITUDE_REL, "budgeted": False,
                "period_factor": r, "contribution": None,
                "sigma_small_amplitude": sd0 if math.isfinite(sd0) else None,
                "rel_sigma_small_amplitude": e["rel_sigma"] if math.isfinite(sd0) else None}
        e["amplitude_budget"] = info
        if r is None or not math.isfinite(sd0) or comp not in laws:
            info["note"] = ("no nonlinear run at this point: the sigma is for a small amplitude stated as such "
                            "(invert --amplitude 0)" if r is None else "no sigma" if not math.isfinite(sd0) else
                            "the amplitude law's runs failed: the sigma is for a small amplitude stated as such "
                            "(invert --amplitude 0)")
            continue
        slope, dr_dI = laws[comp]
        if k not in fars:
            fars[k] = far_amplitude(pre, k, r, T_lin, DEFAULT_AMPLITUDE_REL, st)
        far = fars[k]
        if far is not None and far.slope is None:  # the range reaches the half turn, or its runs failed: as invert
            e.update(sigma=math.inf, rel_sigma=math.inf, sigma_unavailable=far.note)
            info["note"] = far.note
            continue
        if far is not None:  # far from linear: the secant over the amplitude's 95 % range, where larger
            slope = math.copysign(max(abs(slope), far.slope), slope)
            info["amplitude_secant"] = far.secant
        g = r + T_lin * dr_dI * float(b.dI_dT)
        sd = stated_amplitude_budget(b, T_lin, r, DEFAULT_AMPLITUDE_REL, slope, dr_dI)[0]
        bound = input_factor_bound(pre, comp, k, unc, T_lin, g)
        todo[comp] = (k, T_lin, r, g, slope, dr_dI, bound, bound > FACTOR_INPUT_ENOUGH * sd)
    need = {k: slope for k, _, _, _, slope, _, _, more in todo.values() if more}
    try:
        measured = measure_factor_inputs(pre, need, unc, st) if need and not screen else {}
    except BifilarError:  # the stepped runs could not be made: the terms stay out, their bound says how much
        measured = {}
    for comp, (k, T_lin, r, g, slope, dr_dI, bound, _) in todo.items():
        e = res["components"][comp]
        b = pre.budgets[comp]
        info = e["amplitude_budget"]
        terms = None
        if k in measured:
            dx, failed = measured[k]
            terms = input_factor_terms(pre, comp, k, unc, T_lin, r, g, dx, failed)
        sd, c_t, c_a, shares = stated_amplitude_budget(b, T_lin, r, DEFAULT_AMPLITUDE_REL, slope, dr_dI, terms)
        info.update(budgeted=True, contribution=c_a, slope=slope, quadratic_slope=2.0 * (r - 1.0), factor_gain=g,
                    input_factor_terms=terms is not None,
                    input_factor_bound=0.0 if terms is not None and not measured[k][1] else bound / sd)
        if terms is not None and measured[k][1]:
            info["note"] = ("no dr/dx measured for " + ", ".join(measured[k][1]) + ": their terms take the factor "
                            "to depend on them as on the unknown")
        scale = component_scale(pre.scene.inertia, comp)
        # the linear terms' variance: the small-amplitude budget's second-order excess is carried unchanged
        lin_var = sd * sd - (b.value_sigma ** 2 - sum(float(c) ** 2 for c in b.contributions.values()))
        e.update(sigma=sd, rel_sigma=sd / scale if scale else math.inf,
                 shares=grouped_shares(Budget(comp, b.mode, sd, {}, shares, b.dI_dT, b.rel_sensitivity), sd, lin_var))
        e.pop("physical_limit", None)
        e.update(physical_limits(pre.scene.inertia, comp, Budget(comp, b.mode, sd, {"timing": c_t}, shares,
                                                                 b.dI_dT, b.rel_sensitivity),
                                 interval=e["physical_interval"]))
