"""Moments of inertia from measured periods: a ladder of estimators, joint
least squares over several modes and hangings, and the uncertainty budget.

Frames and units: SI (kg, m, s, kg m^2).  The unknowns are components of the
inertia tensor about the CoM in the *reference* body axes (``Ixx Iyy Izz Ixy
Ixz Iyz``; for one hanging, the config's body axes) and optionally the CoM
position ``com.x com.y com.z`` (m, reference body axes, a shift of the CoM
relative to the attachment points, as in
:mod:`bifilar.estimation.sensitivity`).  Everything not solved for keeps the
config's value (the prior).

The ladder (``method``), simplest first
--------------------------------------
``small-angle``
    Thesis (5.2.18) for two wires, ``I = m g D^2 T^2 / (16 pi^2 h)`` with
    ``D`` the distance between the attachment points and ``h`` the mean
    vertical drop of the wires at rest; for ``n >= 3`` wires the multifilar
    analogue ``I = m g R^2 T^2 / (4 pi^2 h)`` with ``R`` the mean horizontal
    distance of the attachment points from the vertical through the CoM
    (equal to ``D/2`` for two wires, so both agree).  It gives the moment
    about the vertical through the CoM; torsion modes only.
``thesis``
    Section 7.1: linearise the thesis's five-angle Kane model about the rest
    pose, ``L = M5^-1 dN5/dtheta``, keep only the two angles the thesis
    keeps ((theta3, theta4) for rotation about b1, (theta2, theta5) about
    b2, (theta1, theta3) about b3; chosen by the axis the mode rotates
    about) and root-find the inertia for which the 2x2 block's eigenvalue
    gives the measured period.  Two wires with anchors at one height only;
    singular for vertical wires (theta2 = 0).
``linear``
    The exact linearised model (:func:`bifilar.analysis.modes.linear_modes`,
    every degree of freedom): the inertia for which the measured mode's
    linear period equals the measured one; modes are tracked by
    :func:`~bifilar.estimation.sensitivity.mac_match`.
``nonlinear``
    The full nonlinear model: the period the simulated motion shows at the
    measured amplitude (:func:`bifilar.analysis.simulate.simulate`, crossings
    as an experimenter times them) equals the measured one.  Solved as
    ``T_lin(I) = T_meas / r(I)`` with the amplitude factor ``r = T_sim /
    T_lin`` re-simulated at each iterate (it depends on ``I`` only weakly, so
    two or three simulations suffice).  A recorded signal's damped period is
    first converted to the undamped one (``T_d = T_n / sqrt(1 - zeta^2)``).

``auto`` picks ``nonlinear`` when an amplitude is known, else ``linear``.

Several periods and unknowns
----------------------------
With more than one period or unknown the estimate is the weighted least
squares solution (Gauss-Newton, Jacobian by central differences) of
``T_k(p) = T_k^meas`` over every measured mode of every hanging; each hanging
is a scene of the same body with ``I_h = R_h I_ref R_h^T``.

Uncertainty
-----------
Linear propagation through the period sensitivities
(:mod:`bifilar.estimation.uncertainty`), with the amplitude's effect on the
nonlinear correction and, when a lower rung is forced, the rung's difference
from the best one as a "model bias" term; optionally checked by Monte Carlo
re-estimation with the full model (:func:`monte_carlo_check`).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import BifilarError, ConvergenceError, InputError, NotApplicable, SlackWireError
from .budget import (DEFAULT_AMPLITUDE_RANGE_DEG, _budget, amplitude_systematic, clip_interval, interval_95,
                     second_order, stated_amplitude_period_std)
from .ladder import METHOD_TITLES, THESIS_COORDS, THESIS_TABLE_7_1_1, ThesisModel, _scalar_rung  # noqa: F401
from .ladder import small_angle_geometry, small_angle_vertical_inertia, thesis_linearisation_for  # noqa: F401
from .measurements import METHODS, MeasurementSet
from .period_specs import implausible_period
from .montecarlo import (  # noqa: F401
    batched_applies,
    draw_monte_carlo,
    monte_carlo_check,
    monte_carlo_journaled,
    solve_draws_batched,
    solve_draws_loop,
)
from .problem import _IDX, HangingModel, Problem, basis, build_problem, physical_interval  # noqa: F401
from .problem import (admissible, admissible_interval, problem_at, refuse_stretching_amplitudes, refuse_unmeasured,
                      start_guesses)
from .birge import birge_factor, birge_note, widen_std, widen_timing
from .parts_prior import described_moments, parts_prior_warnings
from .fit_check import (EDGE_Z, fit_statistics, input_fit_check, labelled_periods, marginal_fit_warning,
                        prior_fit_hint, unchecked_notes)
from .prior_inertia import (past_limit_warning, past_prior_edge, prior_terms, prior_warning, with_prior,
                            with_prior_curvature)
from .inversion_curves import inversion_curves  # noqa: F401  (re-exported: the CLI's --plot)
from .crossing_partner import across_gap, partner_reading
from .roots import Root, find_roots
from .roots import separating_measurement
from .signal_alias import check_signal_aliases
from .solve import (GAIN_RANGE, amplitude_factor, factor_gains, gauss_newton,  # noqa: F401
                    solve_linear, solve_nonlinear, solve_scalar)
from .solve import measured_factor
from .amplitude_runs import per_call_runs
from .answer_checks import (AMPLITUDE_CONTRADICTION_RATIO, AMPLITUDE_CONTRADICTION_Z,  # noqa: F401
                            irregular_warnings, monotonic_warnings, refuse_amplitude_the_record_contradicts,
                            refuse_unreachable_record_amplitudes, unmeasured_warning)
from .sensitivity import DEFAULT_STIFFNESS_REL
from .uncertainty import default_uncertainty
from ..models.kane_mapping import KaneMapping, kane_mapping  # noqa: F401
from .inversion_result import InversionResult, _assumed, std_unavailable_text  # noqa: F401 (callers import them here)


@per_call_runs
def invert(ms: MeasurementSet, *, method: str | None = None, solve_for: list | None = None,
           unc: dict | None = None, monte_carlo: int | None = None, seed: int | None = None,
           ladder: bool = True, rtol: float = 1e-10, progress=None, journal=None,
           resume: bool = False, physical_only: bool = True) -> InversionResult:
    """Estimate the unknowns from the measurements (module docstring).

    Parameters
    ----------
    ms : MeasurementSet (hangings with scenes, measurements).
    method : ``auto`` (default), ``small-angle``, ``thesis``, ``linear`` or
        ``nonlinear``; overrides ``ms.method``.
    solve_for : unknown names; default ``ms.solve_for`` or, per measurement,
        the most sensitive inertia component.
    unc : overrides of the assumed input uncertainties (see
        :data:`bifilar.estimation.uncertainty.UNCERTAINTY_KEYS`).
    monte_carlo : number of Monte Carlo re-estimates (0: none).
    journal, resume : run the Monte Carlo in chunks journaled to this file
        (:func:`monte_carlo_journaled`); ``resume`` continues an interrupted one.
    ladder : also compute every other applicable rung.
    rtol : integrator tolerance of the nonlinear simulations.
    progress : optional ``progress(done, total)`` for long runs.
    physical_only : search every admissible root (:mod:`.roots`; the
        command line always does).  False: the local solve from the prior
        with the tensor only kept positive definite, for studies that show
        what a rung gives even where it leaves the physical set (a thin
        plate's linear estimate of a period lengthened by the amplitude).

    Raises
    ------
    InputError : unknown mode, a period no inertia can produce (message
        gives the achievable range), unidentifiable unknowns, a rung that
        does not apply when forced.
    ConvergenceError : a solver failed.
    """
    t0 = time.perf_counter()
    given = ms  # as called: a refused period's partner reading re-runs it relabelled (crossing_partner)
    method = method or ms.method or "auto"
    if method not in ("auto",) + METHODS:
        raise InputError("--method", f"unknown method {method!r}; choose auto, {', '.join(METHODS)}")
    unc_all = default_uncertainty({**ms.uncertainty, **(unc or {})})
    if any(h.scene.stiffness is not None for h in ms.hangings):  # EA's default, listed only where it is stated
        unc_all.setdefault("stiffness", DEFAULT_STIFFNESS_REL)
    warnings: list[str] = []
    notes: list[str] = list(ms.notes)
    for m in ms.measurements:  # a unit slip that still gives a reachable period runs, with a warning
        w = implausible_period(m.period, m.label, m.field, m.details.get("cycles") if m.source == "timed" else None)
        if w:
            warnings.append(w)
        # a recording's own warnings (the reader's: NaN rows dropped, an angle unwrapped; the time base's
        # dropped or repeated frames; a start held by hand), as `period` lists them at its top level
        for w in (m.details.get("signal") or {}).get("warnings") or []:
            warnings.append(f"mode '{m.label}': {w}")
    if "stiffness" in {**ms.uncertainty, **(unc or {})} and all(h.scene.stiffness is None for h in ms.hangings):
        warnings.append("uncertainty stiffness is EA's (rig.stiffness), which no hanging's config states: the "
                        "wires are taken as rigid and the stated uncertainty is not in this answer's std")
    if "release" in {**ms.uncertainty, **(unc or {})} and not any(m.source == "signal" for m in ms.measurements):
        warnings.append("uncertainty release is budgeted for recordings (--signal) only: a period's "
                        "second modes are not modelled, so the stated bound is not in this answer's std")
    described = described_moments(ms)  # the config's own moments, before nulls get start guesses (parts_prior)
    try:
        ms, start_notes = _with_start_guesses(ms, solve_for or ms.solve_for)
        pb = build_problem(ms, solve_for or ms.solve_for, unc_all)
    except SlackWireError as e:  # a measured config that does not hang: is it the measurement's doing?
        from .slack_cause import explain_slack, uncertainty_source

        raise explain_slack(e, [h.scene for h in ms.hangings], unc_all,
                            uncertainty_source(unc or {}, ms.uncertainty)) from None
    notes += start_notes
    warnings += check_signal_aliases(pb)  # a recording sampled too slowly for its mode (refused if only an alias fits)
    if solve_for or ms.solve_for:  # chosen by the user, not picked per period: each must be measured
        refuse_unmeasured(pb)
    pb.unc = unc_all
    K, P = len(pb.measurements), len(pb.unknowns)
    scalar = K == 1 and P == 1
    has_amp = any(m.amplitude for m in pb.measurements)
    if has_amp:  # the rigid-wire model's nonlinear run of a mode dependent wires cannot follow says nothing
        refuse_stretching_amplitudes(pb)
    best = "nonlinear" if has_amp else "linear"
    if method == "auto":
        method = best
    if method in ("small-angle", "thesis") and not scalar:
        raise InputError("--method", f"{method} estimates one component from one period; this problem has "
                                     f"{P} unknown(s) and {K} period(s): use linear or nonlinear")
    if method == "small-angle" and scalar:
        m0 = pb.measurements[0]
        lab = pb.models[m0.hanging].modes0.modes[pb.mode_index[0]].label
        if not lab.startswith("torsion"):
            raise InputError("--method", f"small-angle does not apply: the formula describes torsion about the "
                                         f"vertical; mode '{lab}' is not torsion")
    if method == "nonlinear" and not has_amp:
        raise InputError("--method", "the nonlinear method needs the oscillation amplitude (--amplitude)")
    for m in pb.measurements:
        if m.source != "signal":
            notes.append(f"mode '{m.label}': damping unknown (timed period); a damping ratio zeta lengthens "
                         "the period by 1/sqrt(1-zeta^2), ~zeta^2/2 (5e-5 for zeta = 0.01)")
            break

    # -- every admissible solution; the measured modes decided at each ----
    targets0 = amp_var0 = None
    if has_amp:
        # the linear model must reproduce T / r: start from the amplitude
        # factors at the (physical) starting tensor; the fixed point below
        # re-simulates them at the estimate
        refuse_unreachable_record_amplitudes(pb)  # a record in degrees or mm read as rad or m
        r0 = np.ones(K)
        for k, m in enumerate(pb.measurements):
            if m.amplitude:
                r0[k] = measured_factor(pb, k, pb.prior, rtol)[0]  # checked: an irregular one refused
        targets0 = np.array([m.period for m in pb.measurements]) / r0
        amp_var0 = lambda: _target_amplitude_variance(pb, pb.prior, r0, rtol, unc_all)  # noqa: E731
    if physical_only:
        # a period in an avoided crossing's gap (at a stated amplitude, or one of several): the refusal names the
        # partner label's answer, this function's own on the relabelled measurements (docs/design.md,
        # "partner28, session 28"); run only where a refusal asks for it
        partner = partner_reading(given, lambda g: invert(g, method=method, solve_for=list(pb.unknowns), unc=unc,
                                                           monte_carlo=0, ladder=False, rtol=rtol))
        roots = find_roots(pb, targets0, amp_var0, partner)
    else:
        roots = [Root(solve_linear(pb, targets0))]
    past_edge = physical_only and scalar and bool(roots[0].edge)  # a limit set by stated priors: not clamped
    roots, past_edge = past_prior_edge(pb, roots, targets0, unc_all) if past_edge else (roots, False)
    root_pbs = [problem_at(ms, pb, r.p, unc_all) for r in roots]
    pb = root_pbs[0]
    p_start = np.asarray(roots[0].p, float)
    if roots[0].edge and not scalar:
        warnings.append("the estimate lies on the edge of the physical set (triangle inequality I1 + I2 = I3, a thin "
                        "flat body): the least-squares fit among physical tensors; the fit check below still holds")
    elif roots[0].edge:
        warnings.append(f"no physical tensor reproduces the period exactly: the estimate lies on the edge of the "
                        f"physical set (triangle inequality I1 + I2 = I3, a thin flat body), within {EDGE_Z:g} timing "
                        "sigma of the measurement or within its uncertainty with the inputs' counted (fit)")
    # -- the ladder -------------------------------------------------------
    rungs: dict[str, dict] = {}
    if not has_amp:
        rungs["linear"] = {"p": p_start, "r": np.ones(K)}
    else:
        # the linear rung: the same equations without the amplitude factors,
        # solved near the estimate (for comparison; it may leave the physical set)
        try:
            rungs["linear"] = {"p": solve_linear(pb, p0=p_start), "r": np.ones(K)}
        except BifilarError as exc:
            rungs["linear"] = {"na": f"failed: {exc}"}
    if method == "linear" and "na" in rungs["linear"]:
        raise InputError("--method", f"linear does not apply: {rungs['linear']['na']}")
    est_nl = None
    if has_amp and (method == "nonlinear" or ladder or method != best):
        from .signal_swing import attach_second_modes, hidden_warnings  # only a nonlinear answer needs it

        warnings += attach_second_modes(pb, p_start, rtol, notes)
        est_nl = solve_nonlinear(pb, p_start, rtol=rtol, progress=progress, physical=bool(roots[0].edge))
        rungs["nonlinear"] = {"p": est_nl.p, "r": est_nl.r, "iterations": est_nl.iterations}
        for s in est_nl.sims:
            if s is not None:
                warnings.extend(f"nonlinear simulation: {w}" for w in s.warnings)
        warnings += irregular_warnings(pb, est_nl)
        warnings += monotonic_warnings(pb, est_nl) + hidden_warnings(pb)
        refuse_amplitude_the_record_contradicts(pb, est_nl)
    ladder_rows = []
    if scalar and (ladder or method in ("small-angle", "thesis")):
        for name in ("small-angle", "thesis"):
            try:
                rungs[name] = _scalar_rung(pb, name)
            except NotApplicable as exc:
                rungs[name] = {"na": str(exc)}
            except BifilarError as exc:
                rungs[name] = {"na": f"failed: {exc}"}
    if method in ("small-angle", "thesis") and "na" in rungs[method]:
        raise InputError("--method", f"{method} does not apply: {rungs[method]['na']}")
    chosen = rungs[method]
    p_hat = chosen["p"]
    r_hat = chosen.get("r", np.ones(K)) if method in ("linear", "nonlinear") else np.ones(K)
    if method == "nonlinear":
        r_hat = est_nl.r

    edge = bool(roots[0].edge)
    if method == "nonlinear" and P == 1 and pb.unknowns[0] in _IDX and physical_only and not past_edge:
        # the fixed point refines locally and may step past the edge of the
        # physical set (a thin plate): back to the edge, which must then fit
        lo, hi = admissible_interval(pb.I_ref0, pb.unknowns[0])
        if not lo <= p_hat[0] <= hi:
            p_hat = np.array([min(max(float(p_hat[0]), lo), hi)])
            rungs["nonlinear"]["p"] = p_hat
            edge = True
            if not roots[0].edge:
                warnings.append("the nonlinear estimate lies on the edge of the physical set (triangle inequality "
                                "I1 + I2 = I3, a thin flat body)")
    # -- the budget -------------------------------------------------------
    from .elastic_split import hangings_check

    # four or five elastic wires: the sweep point's rule on each hanging's config (drawn configs that leave a
    # wire slack or that the model holds otherwise; docs/design.md "inv25, session 25"); a refused std needs
    # no second-order pass
    near: dict = {}  # hangings near the held-direction rule only: each unknown by its bias, below (twin26)
    elastic_refusal, slack_notes = hangings_check(((m.hanging.name, m.scene0, m.rest0) for m in pb.models), unc_all,
                                                  near)
    laws = est_nl.laws if method == "nonlinear" else None
    stated = "inertia" in {**ms.uncertainty, **(unc or {})}
    budget, std_lin, degenerate, T_lin_hat, bctx, amp_default = full_budget(pb, p_hat, r_hat, method, rungs, best,
                                                                            unc_all, rtol, laws=laws,
                                                                            prior_stated=stated,
                                                                            linear_only=elastic_refusal is not None)
    if laws:  # the local slope against the secant over the estimate's std (a period that wiggles in the unknown)
        from .slope_check import secant_check

        rough, changed = secant_check(pb, p_hat, r_hat, laws, budget.std, rtol, multi=len(pb.models) > 1, ctx=bctx)
        warnings += rough
        if changed:
            budget, std_lin, degenerate, T_lin_hat, bctx, amp_default = full_budget(
                pb, p_hat, r_hat, method, rungs, best, unc_all, rtol, laws=laws, prior_stated=stated,
                linear_only=elastic_refusal is not None)
    # periods scattering beyond their stated timing stds: the timing terms widened (birge.py) before any std
    # is printed or used (the warnings below, the ladder's differences in std, the interval, the Monte Carlo)
    fit = _fit_check(pb, p_hat, r_hat, method, edge=edge, laws=laws)
    fit["birge_factor"] = birge_factor(fit)
    budget, std_lin = widen_timing(budget, fit["birge_factor"]), widen_std(budget, std_lin, fit["birge_factor"])
    if near and elastic_refusal is None:
        elastic_refusal = _near_hold_refusal(pb, near, bctx.G, budget.std)
    for lab, (A_max, r_max) in amp_default.items():
        D = bctx.amplitude[lab]
        # the shift in % of |value| so that its sign is the shift's, as the std's is (a negative product
        # read -8 % beside +0.28 std: the same shift with both signs)
        worst = ", ".join(f"{n} {100 * D[i] / abs(p_hat[i]):+.2g} % ({D[i] / budget.std[i]:+.2g} std)"
                          for i, n in enumerate(pb.unknowns) if p_hat[i] and budget.std[i] > 0)
        warnings.append(f"no amplitude given for mode '{lab}': release amplitudes are assumed uniform in 0 .. "
                        f"{DEFAULT_AMPLITUDE_RANGE_DEG:g} degrees ({A_max:.4g} in the mode's dominant coordinate), "
                        f"which lengthen the period by up to {100 * (r_max - 1):.2g} %: the truth may differ from "
                        f"this small-amplitude estimate by up to {worst}; carried in the budget as a systematic "
                        "term (mean offset and spread); give --amplitude (0 for a small one) to remove it")
    for law in laws or []:
        if law is not None and law.dr_dx_failed:
            warnings.append("the amplitude factor's derivative in " + ", ".join(law.dr_dx_failed) + " could not be "
                            "measured (the stepped scene's run failed): the budget takes the factor to depend on "
                            "them as on the unknowns")
    if bctx.prior.dr_failed:
        warnings.append("the amplitude factor's derivative in the prior " + ", ".join(bctx.prior.dr_failed) + " could "
                        "not be measured (the stepped scene's run failed): left at 0 in prior_inertia")
    # a plausible error of the components not solved for, unstated (no std printed where inputs have no derivative)
    w = prior_warning(bctx.prior, budget.std, partial=bool(degenerate))
    if w:
        warnings.append(w)
    if bctx.nonlinear:
        warnings.append("the estimate is not linear in " + ", ".join(bctx.nonlinear) + " over their uncertainties "
                        "(curvature or a vanishing derivative): those inputs are propagated to second order "
                        "(sigma points at +-sqrt(3) sigma, re-solved), std " + ", ".join(
                            f"{n} {budget.std[i]:.3g} (linear {std_lin[i]:.3g})" for i, n in enumerate(pb.unknowns)))
    warnings += parts_prior_warnings(described, pb.unknowns, p_hat)
    warnings += _close_timed_modes(pb, p_hat) + _turned_hangings(pb)
    # several periods or unknowns: the answer a refusal's partner reading names, given directly (cross29)
    across = across_gap(pb, p_hat, T_lin_hat) if physical_only and not scalar else None
    if across is not None:
        warnings.append(across["warning"])
    w = unmeasured_warning(pb, budget.std)
    if w:
        warnings.append(w)
    if fit["birge_factor"] > 1.0:
        warnings.append(birge_note(fit["birge_factor"], fit))
    # -- ladder rows ------------------------------------------------------
    p_best = rungs[best]["p"]
    std = budget.std
    for name in METHODS:
        if name not in rungs:
            continue
        rg = rungs[name]
        row = {"method": name, "description": METHOD_TITLES[name]}
        if "na" in rg:
            row.update({"applicable": False, "note": rg["na"]})
        else:
            vals = {n: float(v) for n, v in zip(pb.unknowns, rg["p"])}
            diff = {n: float(v - pb_b) for n, v, pb_b in zip(pb.unknowns, rg["p"], p_best)}
            row.update({"applicable": True, "values": vals, "difference_from_best": diff,
                        "relative_difference": {n: (diff[n] / p_best[i] if p_best[i] else None)
                                                for i, n in enumerate(pb.unknowns)},
                        "difference_in_std": {n: (diff[n] / std[i] if std[i] > 0 else None)
                                              for i, n in enumerate(pb.unknowns)}})
            for extra in ("note", "geometry", "linearisation", "theta0", "thesis_table", "iterations"):
                if extra in rg:
                    row[extra] = rg[extra]
        ladder_rows.append(row)
    for g in pb.links.shared:
        notes.append(f"hangings {', '.join(repr(n) for n in g['hangings'])} share {g['inputs']} (the same entries in "
                     "their configs: measured once, one error for all of them in the budget and the Monte Carlo; "
                     "--rig separate if each hanging's were measured again)")
    if (w := marginal_fit_warning(pb, fit, _residuals(pb, p_hat, r_hat)[1])) is not None:
        warnings.append(w)
    notes.extend(unchecked_notes(pb, bctx.jacobian, fit["dof"]))
    if fit.get("chi2_with_inputs") is not None and fit["dof"] == 0:
        notes.append(f"the measured period(s) lie beyond what a physical tensor gives, by up to "
                     f"{fit['max_abs_normalised_residual']:.3g} timing sigma, but within their uncertainty with the "
                     f"input uncertainties counted (distance {fit['distance_from_fit']:.3g}, {fit['test']}): the "
                     "measured inputs (lengths, positions, mass, CoM) are probably off within their stated std; the "
                     "answer is the physical limit and the budget carries the inputs")
    elif fit.get("chi2_with_inputs") is not None:
        notes.append(f"the periods disagree beyond their timing uncertainty alone (chi2 {fit['chi2']:.3g} for "
                     f"{fit['dof']} degrees of freedom) but agree within the input uncertainties (chi2 "
                     f"{fit['chi2_with_inputs']:.3g} with them and the assumed release amplitudes): the measured "
                     "inputs (lengths, positions, mass, CoM) are probably off within their stated std, or a period "
                     "was timed at a large amplitude; the budget carries both")
    for i, n in enumerate(pb.unknowns):
        if n in _IDX:
            I = pb.models[0].inertia_ref(pb.values(p_hat))
            if not admissible(I) and past_edge:
                warnings.append(past_limit_warning(I, n, float(p_hat[i]), float(budget.std[i])))
                break
            if not admissible(I):
                warnings.append(f"with {n} = {p_hat[i]:.6g} and the other components at their prior the tensor "
                                "violates the triangle inequality (no real body has it): check the config's "
                                "inertia or solve for more components")
                break
    res = InversionResult(list(pb.unknowns), np.asarray(p_hat, float), budget, method, best, ladder_rows,
                          list(pb.measurements), list(ms.hangings), T_lin_hat, np.asarray(r_hat, float),
                          _assumed(unc_all), degenerate, warnings, notes, problem=pb,
                          sims=(est_nl.sims if est_nl is not None else []), amplitude_laws=list(laws or []))
    res.input_factor_shift = dict(bctx.factor_shift)
    res.across_crossing = across
    res.prior_inertia = bctx.prior
    res.notes += slack_notes
    if elastic_refusal is not None:
        res.std_unavailable = elastic_refusal
        warnings.append(res.std_unavailable)
    elif degenerate:
        # inputs with no derivative (a knife edge): within their stated
        # uncertainty the scene changes qualitatively, and a budget without
        # them is far too small (50x on the thesis plate with its CoM on the
        # attachment line).  No std is better than a wrong one.
        from .inversion_result import rigid_dependent

        dep = rigid_dependent((m.scene0, m.rest0) for m in pb.models)
        res.std_unavailable = std_unavailable_text(degenerate, "--uncertainty KEY=VALUE", dep) + (
            ", or run --monte-carlo N to see the spread")
        warnings.append(res.std_unavailable)
    res.interval = interval_95(p_hat, res.budget, bctx)
    if res.std_unavailable:
        res.interval = np.full_like(res.interval, np.nan)
    # no inertia outside what a real body can have (the truth is one, so the cut keeps the coverage)
    I_hat = pb.models[0].inertia_ref(pb.values(p_hat))
    res.interval_unclipped = res.interval
    loose = [c for c, sd in zip(bctx.prior.names, bctx.prior.sigmas) if sd > 0]  # priors with a stated error
    res.interval, res.interval_clipped = clip_interval(res.interval, p_hat, pb.unknowns, I_hat, loose)
    for i, why in enumerate(res.interval_clipped):
        if why:
            lo, hi = res.interval_unclipped[i]
            res.notes.append(f"the 95 % interval of {pb.unknowns[i]} is cut where no real body lies (the {why} "
                             f"limit; {lo:.6g} .. {hi:.6g} uncut): the truth is a real body, so the cut interval "
                             "covers it as often; value and std unchanged")
    res.fit = fit
    res.roots = [_root_entry(pb, p_hat, r_hat, budget, roots[0].edge, fit)]
    for r, pb_r in zip(roots[1:], root_pbs[1:]):
        res.roots.append(_other_root(pb_r, r, method, unc_all, rtol))
    if len(roots) > 1:
        res.ambiguous = True
        sig_t = float(min(m.std for m in pb.measurements))
        res.separation = separating_measurement(root_pbs, roots, sig_t)
        vals = "; ".join(", ".join(f"{n} = {e['value']:.6g}" for n, e in {**r["inertia"], **r.get("com", {})}.items())
                         for r in res.roots)
        msg = (f"{len(roots)} physical tensors reproduce the measured period(s) ({vals}); the first is shown above, "
               "but the data cannot tell them apart")
        sep = res.separation
        if sep is not None and sep["separation"] >= 3:
            ps = ", ".join(f"{t:.6g} s" for t in sep["periods"])
            msg += (f": time mode '{sep['mode']}' (hanging '{sep['hanging']}') as well, predicted {ps} at these "
                    f"roots ({sep['separation']:.3g} timing sigma apart)")
        else:
            best_sep = f" (the best, '{sep['mode']}', by {sep['separation']:.2g} timing sigma)" if sep else ""
            msg += f": no mode of the hangings used separates them{best_sep}; hang the body another way and time a mode there"
        warnings.append(msg)
    n_mc = ms.monte_carlo if monte_carlo is None else monte_carlo
    if n_mc:
        if journal is not None:
            res.monte_carlo = monte_carlo_journaled(res, n_mc, journal, seed=seed if seed is not None else ms.seed,
                                                    resume=resume, progress=progress)
        else:
            res.monte_carlo = monte_carlo_check(res, n_mc, np.random.default_rng(seed if seed is not None else ms.seed),
                                                progress=progress)
        mc = res.monte_carlo
        if mc.n_ok > 1:  # its quantiles cut at the same limits (draws re-solved past them are no body either)
            cut, _ = clip_interval(np.column_stack([mc.low, mc.high]), p_hat, pb.unknowns, I_hat, loose)
            mc.low, mc.high = cut[:, 0], cut[:, 1]
        if res.budget.dof:
            # timed trials: their Student draws have heavy tails (no variance
            # for n <= 3), so the check compares the 95 % intervals' widths
            with np.errstate(invalid="ignore", divide="ignore"):
                ratio = (mc.high - mc.low) / (res.interval[:, 1] - res.interval[:, 0])
            what = "95 % interval differs from the budget's"
        else:
            ratio, what = mc.ratio, "spread differs from the linear std"
        if mc.timing_scale > 1.0:
            res.notes.append(f"the Monte Carlo drew each period with its timing std widened by the Birge factor "
                         f"{mc.timing_scale:.3g}, as the budget's timing terms are")
        bad = [n for i, n in enumerate(res.names) if np.isfinite(ratio[i]) and not 0.8 < ratio[i] < 1.25]
        if bad:
            warnings.append(f"Monte Carlo {what} by more than 20 % for {', '.join(bad)}: "
                            "the model is not linear over the input uncertainties; quote the Monte Carlo interval")
    res.runtime = time.perf_counter() - t0
    return res


def _close_timed_modes(pb: Problem, p) -> list[str]:
    """The warnings of :func:`~bifilar.analysis.close_modes.close_mode_warnings`
    for the timed modes of each hanging at the unknowns ``p``."""
    from ..analysis.close_modes import close_mode_warnings

    out = []
    vals = pb.values(p)
    for h, hm in enumerate(pb.models):
        timed = {m.label for m in pb.measurements if m.hanging == h}
        if timed:
            where = f"hanging '{hm.hanging.name}': " if len(pb.models) > 1 else ""
            out += close_mode_warnings(hm.locate(hm.scene(vals))[1].modes, timed, where)
    return out


def _turned_hangings(pb: Problem) -> list[str]:
    """:func:`~bifilar.analysis.rest_warnings.turn_warning` of each hanging's
    rest pose (a body hanging far turned from its configured orientation:
    more often a mistyped wire length or attachment than a rig meant so),
    as ``modes`` and each sweep point say it.  The rest pose's orientation
    depends on the mass and CoM, not on the unknown inertia: the config's
    rest pose is the answer's."""
    from ..analysis.rest_warnings import turn_warning

    out = []
    for hm in pb.models:
        w = turn_warning(hm.scene0, hm.rest0)
        if w is not None:
            out.append((f"hanging '{hm.hanging.name}': " if len(pb.models) > 1 else "") + w)
    return out


def _with_start_guesses(ms: MeasurementSet, solve_for) -> tuple[MeasurementSet, list]:
    """``ms`` with a physical starting tensor (:func:`start_guesses`) when the
    config marks components unknown (null) or a component being solved for
    makes the prior tensor unphysical; the nulls are solved for."""
    from dataclasses import replace

    from ..config import null_components

    h0 = ms.hangings[0]
    nulls = null_components(h0.scene)
    unknowns = list(solve_for or [])
    if nulls:
        missing = [n for n in nulls if unknowns and n not in unknowns]
        if missing:
            raise InputError("--solve-for", f"{', '.join(missing)} is unknown in the config (null): solve for it too "
                                            f"(--solve-for {missing[0]}) or give its value")
        if not unknowns:
            unknowns = list(nulls)
            ms = replace(ms, solve_for=unknowns)
    R0 = np.asarray(h0.rotation)
    I_ref = R0.T @ h0.scene.inertia @ R0
    if not unknowns or (not nulls and admissible(I_ref)):
        return ms, []
    given = {n: (None if n in nulls else float(I_ref[_IDX[n]])) for n in unknowns if n in _IDX}
    I_start, notes = start_guesses(I_ref, unknowns, given)
    if {"Ixx", "Iyy", "Izz"} <= set(nulls):
        I_start, notes = _scaled_start(ms, I_start, nulls)
    hangs = [replace(h, scene=replace(h.scene, inertia=np.asarray(h.rotation) @ I_start @ np.asarray(h.rotation).T))
             for h in ms.hangings]
    return replace(ms, hangings=hangs), notes


def _scaled_start(ms: MeasurementSet, I_start: np.ndarray, nulls: list) -> tuple[np.ndarray, list]:
    """The starting tensor (reference body axes, kg m^2) when no moment of
    inertia is known: its null components scaled by the factor whose linear
    periods of the measured modes best match the measured ones (least
    squares in log period over 8 decades around m r^2, r the RMS distance
    of the attachments from the CoM).  Without it the placeholders
    (1 kg m^2) started the solver orders of magnitude off: the thesis
    plate's own periods found no tensor, or the measured labels did not
    exist at the start."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import modes_of_inertia
    from .fit_check import label_index

    null_at = np.zeros((3, 3), bool)
    for n in nulls:
        null_at[_IDX[n]] = null_at[_IDX[n][::-1]] = True
    h0 = ms.hangings[0]
    r2 = float(np.mean(np.sum(np.asarray(h0.scene.attachments, float) ** 2, axis=1)))
    base = h0.scene.mass * max(r2, 1e-6 * float(np.max(h0.scene.lengths)) ** 2) / float(np.mean(np.diag(I_start)))
    hangs = [(h, np.asarray(h.rotation), modes_of_inertia(h.scene, rest_pose(h.scene))) for h in ms.hangings]
    best = (math.inf, 1.0)
    for f in base * np.logspace(-4.0, 4.0, 33):
        I = np.where(null_at, f * I_start, I_start)
        if not admissible(I):
            continue
        err = 0.0
        for m in ms.measurements:
            h, R, modes_at = hangs[m.hanging]
            md = modes_at(R @ I @ R.T)
            i = label_index(md, m.label)
            T = md.modes[i].period if i is not None else None
            if not T:
                err = math.inf
                break
            err += math.log(T / m.period) ** 2
        if err < best[0]:
            best = (err, f)
    f = best[1]
    I = np.where(null_at, f * I_start, I_start)
    note = ("no moment of inertia is known (null): the solver starts from the tensor whose linear periods best "
            f"match the measured ones, moments {', '.join(f'{x:.4g}' for x in np.diag(I))} kg m^2")
    return I, [note]


def _residuals(pb: Problem, p, r) -> tuple[np.ndarray, np.ndarray]:
    """(model periods, normalised residuals) at ``p`` with amplitude factors
    ``r``; the model period of each measurement is that of the mode carrying
    its label at ``p``."""
    T = labelled_periods(pb, p) * np.asarray(r, float)
    return T, (T - np.array([m.period for m in pb.measurements])) / np.array([m.std for m in pb.measurements])


def _fit_check(pb: Problem, p, r, method: str, edge: bool = False, laws=None) -> dict:
    """The estimate must reproduce every measurement (roots.py: the fit
    check).  Raises ConvergenceError when it does not; a forced lower rung
    (small-angle, thesis) is a different model, so its fit is reported,
    not enforced.  ``edge``: an answer on the edge of the physical set,
    accepted within ``EDGE_Z`` sigma, or within the periods' uncertainty
    with the inputs' counted (no tensor inside reproduces them exactly)."""
    T, z = _residuals(pb, p, r)
    K, P = len(z), len(pb.unknowns)
    ok, chi2, test = fit_statistics(z, P)
    if edge and K <= P:
        ok, test = bool(np.all(np.abs(z) <= EDGE_Z)), f"|residual| <= {EDGE_Z:g} sigma (on the edge of the physical set)"
    chi2_in = chi2_at = None
    hint = ""
    if not ok and (K > P or edge) and np.all(np.isfinite(z)):
        # the inputs' errors shift the periods together: the check counts them (fit_check.input_fit_check)
        amp_var = _amplitude_variance(pb, p, laws, method, pb.unc)
        ok, chi2_in, chi2_at, test = input_fit_check(pb, p, z, r, amp_var)
        hint = prior_fit_hint(pb, p, z, r, amp_var=amp_var).removesuffix("; ") if not ok else ""
    out = {"passed": bool(ok), "chi2": chi2, "dof": max(K - P, 0), "test": test,
           "chi2_with_inputs": chi2_in, "distance_from_fit": chi2_at,
           "max_abs_normalised_residual": float(np.max(np.abs(z)))}
    if not ok and method in ("linear", "nonlinear"):
        zs = ", ".join(f"{m.label} {zk:+.3g}" for m, zk in zip(pb.measurements, z))
        raise ConvergenceError(f"the {method} estimate does not reproduce the measurements (normalised residuals "
                               f"{zs} sigma; required {test}): no answer is given{': ' + hint if hint else ''}")
    return out


def _target_amplitude_variance(pb: Problem, p, r, rtol: float, unc: dict) -> np.ndarray:
    """(K,) variance (s^2) of each root-finding target ``T / r`` from its
    stated amplitude's uncertainty, at the unknowns ``p`` whose amplitude
    factors are ``r``: the budget's amplitude term
    (:func:`~bifilar.estimation.budget.stated_amplitude_period_std`, the
    law's slope from one more run at :data:`~bifilar.estimation.solve.STATED_LAW_RATIO`
    of the amplitude) over ``r``.  Used only where a target is out of the
    physical range by timing alone (:func:`~bifilar.estimation.roots.find_roots`)."""
    from .solve import STATED_LAW_RATIO, amplitude_law

    laws = []
    for k, m in enumerate(pb.measurements):
        if not m.amplitude:
            laws.append(None)
            continue
        r_lam = measured_factor(pb, k, p, rtol, STATED_LAW_RATIO * m.amplitude)[0]
        laws.append(amplitude_law(m.amplitude, float(r[k]), STATED_LAW_RATIO, r_lam))
    return (stated_amplitude_period_std(pb, pb.linear_periods(p), laws, unc) / np.asarray(r, float)) ** 2


def _amplitude_variance(pb: Problem, p, laws, method: str, unc: dict) -> np.ndarray | None:
    """(K,) variance (s^2) of each model period from its stated amplitude's
    uncertainty under the nonlinear method (as the budget's amplitude term,
    :func:`~bifilar.estimation.budget.stated_amplitude_period_std`: the
    slope of the mode's amplitude law ``laws[k]``) and from a recording's second mode
    (``law.secondary_std``), from the modes it may hide (``law.hidden_std``) and from its tone's other reading
    (``law.reading_std``), or None for the other methods."""
    if method != "nonlinear":
        return None
    second = np.array([math.hypot(law.secondary_std, law.hidden_std, law.reading_std) if law is not None else 0.0
                       for law in laws or [None] * len(pb.measurements)])
    return stated_amplitude_period_std(pb, pb.linear_periods(p), laws, unc) ** 2 + second ** 2


def full_budget(pb: Problem, p, r, method: str, rungs: dict, best: str, unc: dict, rtol: float,
                cache: dict | None = None, laws=None, prior_stated: bool | None = None, linear_only: bool = False):
    """The budget every answer (the chosen root and any further one) gets:
    the linear budget (:func:`~bifilar.estimation.budget._budget`), the
    systematic term of an unstated amplitude, and second-order propagation
    where the linear one is wrong (:func:`~bifilar.estimation.budget.second_order`).
    Returns (budget, linear std, degenerate inputs, T_lin at ``p`` (s),
    budget context, {mode: (assumed max amplitude, its period factor)}).
    ``cache``: shared by budgets at the same scenes (``BudgetContext.cache``).
    ``laws``: the amplitude laws of the nonlinear method (``Estimate.laws``).
    ``prior_stated``: not None, the components not solved for are budgeted
    (``bctx.prior``, :mod:`~bifilar.estimation.prior_inertia`; whether the
    user stated ``inertia``); None (a planner's std): left out.
    ``linear_only``: no second-order pass (no std is given: a drawn-rig refusal, elastic_split)."""
    budget, degenerate, T_lin, bctx = _budget(pb, p, r, method, rungs, best, unc, cache, laws, rtol)
    if prior_stated is not None:
        bctx.prior = prior_terms(pb, p, r, T_lin, bctx, unc, prior_stated, laws, rtol)
        budget = with_prior(budget, bctx.prior)
    std_lin = budget.std
    amp_default = amplitude_systematic(pb, p, r, bctx, rtol)
    if linear_only or any(bctx.sigmas.get(d, 0) > 0 for d in degenerate):
        # no std can be given anyway (InversionResult.std_unavailable): skip
        # the sigma points, each a global rest-pose search on such a scene
        return budget, std_lin, [d for d in degenerate if bctx.sigmas.get(d, 0) > 0], T_lin, bctx, amp_default
    budget, failed = second_order(pb, p, r, bctx, budget)
    if bctx.prior is not None:  # a stated prior whose first-order term vanishes (a product on a level rig)
        budget = with_prior_curvature(budget, bctx.prior)
    degenerate = [d for d in dict.fromkeys(degenerate + failed) if bctx.sigmas.get(d, 0) > 0]
    return budget, std_lin, degenerate, T_lin, bctx, amp_default


def _root_entry(pb: Problem, p, r, budget, edge: bool, fit: dict) -> dict:
    T, z = _residuals(pb, p, r)
    inertia, com = {}, {}
    for i, n in enumerate(pb.unknowns):
        d = {"value": float(p[i]), "std": float(budget.std[i])}
        if n in _IDX:
            inertia[n] = {**d, "unit": "kg m^2"}
        else:
            com[n.split(".")[1]] = {**d, "unit": "m"}
    out = {"inertia": inertia, "residuals": [{"mode": m.label, "hanging": pb.models[m.hanging].hanging.name,
                                              "measured": m.period, "model": float(t),
                                              "normalised_residual": float(zk)}
                                             for m, t, zk in zip(pb.measurements, T, z)],
           "chi2": fit["chi2"], "birge_factor": float(fit.get("birge_factor", 1.0)), "edge": bool(edge)}
    if com:
        out["com"] = com
    return out


def _other_root(pb: Problem, root, method: str, unc: dict, rtol: float) -> dict:
    """Value, linear-budget std and fit of a further root (the chosen
    method when it is linear or nonlinear, else the linear one)."""
    K = len(pb.measurements)
    p, r = np.asarray(root.p, float), np.ones(K)
    if method == "nonlinear":
        est = solve_nonlinear(pb, p, rtol=rtol, physical=bool(root.edge))
        p, r = est.p, est.r
    m = method if method in ("linear", "nonlinear") else "linear"
    budget = full_budget(pb, p, r, m, {m: {"p": p, "r": r}}, m, unc, rtol,
                         laws=est.laws if method == "nonlinear" else None, prior_stated=True)[0]
    T, z = _residuals(pb, p, r)
    ok, chi2, test = fit_statistics(z, len(pb.unknowns))
    # its own periods' scatter widens its timing terms as the answer's do (birge.py)
    fit = {"passed": ok, "chi2": chi2, "dof": max(K - len(pb.unknowns), 0), "chi2_with_inputs": None}
    fit["birge_factor"] = birge_factor(fit)
    return _root_entry(pb, p, r, widen_timing(budget, fit["birge_factor"]), root.edge, fit)


def _near_hold_refusal(pb, near: dict, gain: np.ndarray, std: np.ndarray) -> str | None:
    """The first unknown's :func:`~bifilar.estimation.elastic_split.near_hold_refusal`
    (hangings ``near`` {index: risks}): each measured period of those hangings
    biased by its mode's :func:`~bifilar.estimation.elastic_split.near_hold_biases`
    (s), carried into the unknowns by the gain ``gain`` (P, K; dp = G dT) and
    set against their stds ``std`` (SI); None where none exceeds its share.
    Several hangings: every one near the rule is named (their biases act
    together), the drawn-config figures quoted being the nearest one's
    (largest ``p_near``)."""
    from .elastic_split import near_hold_biases, near_hold_refusal

    dT = np.zeros(len(pb.measurements))
    for h, hm in enumerate(pb.models):
        if h in near:
            b = near_hold_biases(hm.scene0, hm.rest0, hm.modes0)
            for k, m in enumerate(pb.measurements):
                if m.hanging == h:
                    dT[k] = b[pb.mode_index[k]]
    bias = gain @ dT
    # the figures quoted (share of the drawn configs near the rule, directions held) are the nearest
    # hanging's; every hanging near the rule is named, since the bias is theirs together
    risks = max(near.values(), key=lambda r: r.p_near)
    names = [f"'{pb.models[h].hanging.name}'" for h in near]
    if len(pb.models) == 1:
        where = ""
    elif len(names) == 1:
        where = f"hanging {names[0]}: "
    else:
        nearest = next(n for h, n in zip(near, names) if near[h] is risks)
        where = f"hangings {', '.join(names[:-1])} and {names[-1]} (figures of {nearest}, the nearest): "
    for i, name in enumerate(pb.unknowns):
        text = near_hold_refusal(risks, name, float(bias[i]), float(std[i]))
        if text is not None:
            return where + text
    return None
