"""Does an answer reproduce its measurements?  The periods an answer
predicts for the measured mode labels, and the check that they match the
measured periods within their uncertainty (timing, and where the timing-only
test fails, the measured inputs' and the assumed amplitudes' uncertainty).

Units: periods in s, inertia components in kg m^2 (reference body axes),
CoM shifts in m (see :mod:`bifilar.estimation.problem`).

With ``z_k = (T_model - T_meas) / sigma_k``, an answer fits when ``max |z_k|
<= FIT_Z`` if there are as many periods as unknowns (the equations are solved
exactly; ``FIT_Z`` = 0.1), and when the chi-square ``sum z_k^2`` is below its
``1 - CHI2_P`` quantile with ``K - P`` degrees of freedom if there are more
periods ``K`` than unknowns ``P`` (``CHI2_P`` = 0.001).  Used by
:mod:`bifilar.estimation.roots` (which solutions count) and
:mod:`bifilar.estimation.invert` (the printed answer's ``fit``).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import BifilarError
from .problem import Problem
from .prior_inertia import prior_period_columns

#: largest normalised residual |T_model - T_meas| / sigma of an exactly determined fit
FIT_Z = 0.1
#: an overdetermined fit is refused when P(chi2 >= observed) < CHI2_P
CHI2_P = 1e-3
#: a solution on the edge of the admissible set is accepted within this many sigma
EDGE_Z = 2.0
#: an overdetermined fit accepted on timing alone is warned below this P(chi2 >= observed)
#: (:func:`marginal_fit_warning`; 1 % of honest experiments)
WARN_P = 0.01
#: :func:`inputs_explain`'s further chord steps after the conditional mean, and the input change (in its
#: stds) below which it stops
EXPLAIN_STEPS = 4
EXPLAIN_TOL = 1e-3
#: a further step's explanation is accepted only where the full model's periods depart from the
#: linearisation by at most this fraction of each period's linearised spread (inputs, timing, amplitudes)
EXPLAIN_NONLINEAR = 0.05


def label_index(ms, label: str) -> int | None:
    """Index into ``ms.modes`` of the mode carrying ``label`` (or 1-based index), else None."""
    try:
        m = ms.get(label)
    except KeyError:
        return None
    return ms.modes.index(m)


def fit_statistics(z: np.ndarray, P: int) -> tuple[bool, float, str]:
    """(passes, chi2, threshold description) of normalised residuals ``z``
    for ``P`` unknowns (module docstring)."""
    z = np.asarray(z, float)
    K = len(z)
    chi2 = float(z @ z) if np.all(np.isfinite(z)) else math.inf
    if K <= P:
        return bool(np.all(np.abs(z) <= FIT_Z)), chi2, f"|residual| <= {FIT_Z:g} sigma"
    lim = chi2_limit(K, P)
    return chi2 <= lim, chi2, f"chi2 <= {lim:.4g} ({K - P} degrees of freedom, p = {CHI2_P:g})"


def marginal_fit_warning(pb: Problem, fit: dict, z: np.ndarray) -> str | None:
    """One line where an overdetermined fit (``fit``: the answer's fit
    check, ``z`` its normalised residuals) passes on the timing stds alone
    but only at ``P(chi2 >= observed) <`` :data:`WARN_P`: accepted down to
    :data:`CHI2_P`, such periods disagree more than their stated stds
    allow in 1 % of honest experiments, and a mistyped or mislabelled
    period hides there (audit19: one of two timings 0.2 % off at 1 ms,
    inputs exact: answered in 23 of 30 draws, 3 of them within the
    interval, z +2.6).  None otherwise (a fit that needed the inputs'
    uncertainty has its own note)."""
    if fit["dof"] <= 0 or fit.get("chi2_with_inputs") is not None or not np.all(np.isfinite(z)):
        return None
    from scipy.stats import chi2 as chi2_dist

    p = float(chi2_dist.sf(fit["chi2"], fit["dof"]))
    if not p < WARN_P:
        return None
    k = int(np.argmax(np.abs(z)))
    return (f"the measured periods agree only at p = {p:.2g} (chi2 {fit['chi2']:.3g} for {fit['dof']} "
            f"degree{'s' if fit['dof'] > 1 else ''} of freedom; refused below p = {CHI2_P:g}), the largest residual mode '{pb.term_labels()[k]}' at "
            f"{z[k]:+.3g} sigma: is a period mistyped, or timed on another mode? The std, widened by the Birge "
            "factor, assumes the periods scatter alike, not one of them wrong")


#: a measurement whose leverage in the weighted fit exceeds this is all but
#: unchecked by the others (:func:`unchecked_notes`): its residual shows at
#: most ``sqrt(1 - h)`` (10 %) of an error in its period
UNCHECKED_LEVERAGE = 0.99


def leverages(jacobian, stds) -> np.ndarray | None:
    """(K,) leverage ``h_kk`` of each measured period in the timing-weighted
    fit of the unknowns: the diagonal of the hat matrix ``A A^+`` with ``A
    = J / s`` (``jacobian`` ``J`` (K, P) the linear periods' derivatives in
    the unknowns at the estimate, s per SI unit of each unknown: the
    uncertainty budget's, :attr:`~bifilar.estimation.second_order.BudgetContext.jacobian`;
    ``stds`` ``s`` (K,) the periods' stds, s).  ``h_kk`` near 1: the
    fitted period follows the measured one whatever its error (the fit
    cannot check it); the ``h_kk`` sum to the fit's rank.  None where a
    period has no derivative (NaN)."""
    J = np.asarray(jacobian, float)
    if not np.all(np.isfinite(J)):
        return None
    A = J / np.asarray(stds, float)[:, None]
    U, sv, _ = np.linalg.svd(A, full_matrices=False)
    U = U[:, sv > 1e-9 * sv[0]] if sv.size and sv[0] > 0 else U[:, :0]
    return np.sum(U * U, axis=1)


def unchecked_notes(pb: Problem, jacobian, dof: int) -> list[str]:
    """One note per measured period that no other measurement checks (its
    leverage above :data:`UNCHECKED_LEVERAGE`, :func:`leverages`) in an
    overdetermined fit (``dof`` > 0): the chi-square's degrees of freedom
    test the other periods, not this one, so a mistyped period there gives
    chi2 0 and a wrong answer within its own std (audit19, row A1: the
    drone's torsion 2 % off among torsion, pitch and both swings, solving
    Izz and Iyy: Izz +4 %, chi2 0, "2 degrees of freedom").  None for an
    exactly determined fit (no check at all, which its ``dof`` 0 says).
    ``jacobian``: (K, P) the budget's d T_lin / d p at the estimate (s per
    SI unit), or None (no note)."""
    if dof <= 0 or jacobian is None:
        return []
    h = leverages(jacobian, [m.std for m in pb.measurements])
    if h is None:
        return []
    labels = pb.term_labels()
    return [f"the period of '{labels[k]}' is checked by no other measurement (leverage {h[k]:.3f}: an error in "
            f"it shows {100 * np.sqrt(max(1.0 - h[k], 0.0)):.0f} % in its residual), so the fit's {dof} degree"
            f"{'s' if dof > 1 else ''} of freedom test the other periods only: time it again, or time another "
            "mode that moves the same unknowns, to check it"
            for k in range(len(h)) if h[k] > UNCHECKED_LEVERAGE]


def chi2_limit(K: int, P: int) -> float:
    """The ``1 - CHI2_P`` quantile of chi-square with ``K - P`` degrees of freedom."""
    from scipy.stats import chi2 as chi2_dist

    return float(chi2_dist.ppf(1 - CHI2_P, K - P))


def _input_columns(pb: Problem, p, r=None) -> tuple[list, np.ndarray, np.ndarray]:
    """(input keys, (K, n) period sensitivities to them (s per SI unit,
    times the amplitude factors ``r``, NaN set to 0: no derivative), (n,)
    their standard uncertainties) of the modes carrying the measured labels
    at the unknowns ``p`` (:func:`~bifilar.estimation.budget.input_columns`)."""
    from .budget import input_columns
    from .uncertainty import default_uncertainty

    K = len(pb.measurements)
    r = np.ones(K) if r is None else np.asarray(r, float)

    def rows(h, ms, match, k):
        return label_index(ms, pb.measurements[k].label)

    unc = pb.unc if pb.unc else default_uncertainty()
    cols, sigmas = input_columns(pb, pb.values(p), r, unc, rows=rows)[:2]
    keys = list(cols)
    J = np.column_stack([np.where(np.isfinite(cols[n]), cols[n], 0.0) for n in keys]) if keys else np.zeros((K, 0))
    return keys, J, np.array([sigmas[n] for n in keys])


def input_period_covariance(pb: Problem, p, r=None) -> np.ndarray:
    """(K, K) covariance (s^2) of the measured periods caused by the measured
    inputs (wire lengths, anchor and attachment coordinates, mass, gravity,
    CoM) at their standard uncertainties ``pb.unc``, linearised at the
    unknowns ``p``: ``J_x diag(s^2) J_x^T``, ``J_x`` the periods' input
    sensitivities (times the amplitude factors ``r``) of the modes carrying
    the measured labels at ``p``.  Inputs without a derivative (a knife
    edge) are left out."""
    _, J, s = _input_columns(pb, p, r)
    Js = J * s
    return Js @ Js.T


def inputs_explain(pb: Problem, p, res: np.ndarray, other_var: np.ndarray, lim: float) -> bool:
    """Whether measured inputs off within their stated uncertainty explain
    the residuals ``res`` (K,) s (measured minus model, at the unknowns
    ``p`` held fixed) with the full model, not only its linearisation.

    The likeliest input error given the residuals (the conditional mean,
    ``dx = S^2 J^T C^-1 res``, ``C = J S^2 J^T + diag(other_var)``: timing
    and release amplitudes in ``other_var``, s^2) is applied to the
    hanging's scene, its rest pose and modes found again, and the misfit
    ``|dx / s|^2 + sum (res - dT)^2 / other_var`` with the periods' true
    change ``dT`` must be at most ``lim``.  Linearly it is ``res^T C^-1
    res``; where the periods are not linear over the inputs' uncertainty
    (four dependent wires, where 1 mm of a length moves a period by
    seconds in the linearisation, or leaves a wire slack) the linear test
    would accept any period: this one does not.

    Where that first step misses, up to :data:`EXPLAIN_STEPS` chord steps
    (Gauss-Newton with ``J`` held: ``dx = S^2 J^T C^-1 (res - dT(dx) + J
    dx)``) seek the least misfit, stopping when no input moves by
    :data:`EXPLAIN_TOL` of its std; such a step's explanation is accepted
    only where the full model's change departs from ``J dx`` by at most
    :data:`EXPLAIN_NONLINEAR` of each period's spread ``sqrt(C_kk)``, so
    that the budget's linear interval still holds there.  The thin plate's
    pitch period moves 0.17 ms from its linearisation over a 4 mm CoM error,
    1.7 stds of a 0.1 ms timing: the first step refused honest draws (11
    of 1000), at a 0.019 departure; a body hung 5 mm below its attachments
    with its CoM 3 mm off departs by 0.13 and stays refused
    (tests/test_refusal_hints.py; docs/design.md, "trust23, session 23")."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes
    from .budget import _perturbed_scene

    res = np.asarray(res, float)
    keys, J, s = _input_columns(pb, p)
    keep = s > 0  # an exact input cannot be off
    keys, J, s = [n for n, k in zip(keys, keep) if k], J[:, keep], s[keep]
    if not keys:
        return False
    C = (J * s ** 2) @ J.T + np.diag(other_var)
    vals = pb.values(p)
    base = labelled_periods(pb, p)

    def change(dx):
        """(K,) the periods' change (s) with every input moved by ``dx``, None where a scene cannot hang."""
        dT = np.zeros(len(res))
        for h, hm in enumerate(pb.models):
            ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
            if not ks:
                continue
            # every input key moved by dx (a shared one in each hanging it acts on; a CoM shift in the reference frame)
            scene = _perturbed_scene(pb, h, hm.scene(vals), list(zip(keys, dx)))
            try:
                ms = linear_modes(scene, rest_pose(scene, guess=hm.rest0))
            except (BifilarError, np.linalg.LinAlgError):
                return None
            for k in ks:
                i = label_index(ms, pb.measurements[k].label)
                if i is None or not ms.modes[i].period:
                    return None
                dT[k] = ms.modes[i].period - base[k]
        return dT

    # (K,) s: each period's linearised spread, the inputs' and the rest's (a period no input moves has none)
    spread = np.sqrt(np.diag(C))
    dx = np.zeros(len(s))
    dT = np.zeros(len(res))
    for step in range(1 + EXPLAIN_STEPS):
        # Gauss-Newton with the sensitivities J held (a chord step): the likeliest input error given what
        # the full model's periods at dx leave unexplained
        new = s ** 2 * (J.T @ np.linalg.solve(C, res - dT + J @ dx))
        small = bool(np.all(np.abs(new - dx) <= EXPLAIN_TOL * s))
        dx, dT = new, change(new)
        if dT is None:
            return False
        if float(np.sum((dx / s) ** 2) + np.sum((res - dT) ** 2 / other_var)) <= lim:
            # a further step's explanation only where the linearisation (the budget's) holds there
            return step == 0 or bool(np.all(np.abs(dT - J @ dx) <= EXPLAIN_NONLINEAR * spread))
        if small:
            break
    return False


def unstated_amplitude_variance(pb: Problem, p, rtol: float = 1e-10, shift: bool = False) -> np.ndarray:
    """(K,) second moment (s^2) of the lengthening of each period timed at an
    unstated release amplitude (``amplitude is None``; 0 for the others), as
    the budget assumes it (:func:`~bifilar.estimation.budget.amplitude_systematic`:
    amplitudes uniform in 0 .. A_max, ``T = T_lin (1 + (r_max - 1) w)``,
    ``w`` the mode's amplitude law's release weight, ``E[w^2] = 1/5`` for a
    quadratic law): ``(T_lin (r_max - 1))^2 E[w^2]``.
    Different modes are released independently.  Two simulations per such
    measurement at ``p`` (the law's, at A_max and A_max / 2, over its
    ``cycles``, as the budget's).  ``shift``: instead, (K,) the signed
    period shift (s) at the range's end, ``T_lin (r_max - 1)``: a release
    in the range shifts the period by ``w`` times it, ``w`` in 0 .. 1."""
    from .budget import default_amplitude_range
    from .solve import RELEASE_LAW_RATIO, amplitude_law_at

    vals = pb.values(p)
    out = np.zeros(len(pb.measurements))
    for k, m in enumerate(pb.measurements):
        if m.amplitude is not None:
            continue
        hm = pb.models[m.hanging]
        _, ms, match = hm.locate(hm.scene(vals))
        mode = ms.modes[match[pb.mode_index[k]]]
        if not mode.period:
            continue
        A = default_amplitude_range(hm.scene(vals), mode)
        try:
            law = amplitude_law_at(hm, vals, pb.mode_index[k], A, m.cycles, rtol, lam=RELEASE_LAW_RATIO)
        except BifilarError:
            continue
        mean_w, std_w = law.release_moments()
        end = mode.period * (float(law.factor(A)) - 1)
        out[k] = end if shift else end ** 2 * (mean_w ** 2 + std_w ** 2)
    return out


def period_covariance(pb: Problem, p, r=None, amp_var=None, extra_var=None) -> tuple[np.ndarray, np.ndarray, list]:
    """(C, C_pri, prior names): the measured periods' (K, K) covariance (s^2)
    at the unknowns ``p`` (amplitude factors ``r``): timing, ``amp_var`` and
    ``extra_var`` ((K,) s^2 or None) on the diagonal, the measured inputs'
    (:func:`input_period_covariance`) and, where ``inertia`` is stated, the
    priors' of the components not solved for (``C_pri``, also returned
    alone, and the names of those components): their errors shift the
    periods together, as an input's."""
    K = len(pb.measurements)
    sig = np.array([m.std for m in pb.measurements])
    C = np.diag(sig ** 2 + (np.zeros(K) if amp_var is None else np.asarray(amp_var, float))) \
        + input_period_covariance(pb, p, r)
    if extra_var is not None:
        C += np.diag(np.asarray(extra_var, float))
    pri_names, Jq, sq = prior_period_columns(pb, p, r)
    C_pri = (Jq * sq ** 2) @ Jq.T
    return C + C_pri, C_pri, pri_names


def input_fit_check(pb: Problem, p, z, r=None, extra_var=None, amp_var=None) -> tuple[bool, float, float, str]:
    """The fit check with the measured inputs' uncertainty counted: (passes,
    chi2 of the fit, distance of ``p`` from the fit, description).

    The periods' covariance is ``C = diag(sigma_T^2) + C_x`` (timing plus
    :func:`input_period_covariance`, the spread of periods timed at an
    unstated amplitude, :func:`unstated_amplitude_variance`, ``extra_var``
    (K,) s^2 on the diagonal, and, where ``inertia`` is stated, the priors'
    of the components not solved for,
    :func:`~bifilar.estimation.prior_inertia.prior_period_columns`, the
    description then naming them; ``amp_var``: the former when
    computed already, it hardly depends on ``p``).  With ``C = L L^T``, ``res = z
    sigma_T`` the residuals at ``p`` and ``J_p`` the periods' Jacobian in the
    unknowns:

    * the data must fit the model: ``min_dp |L^-1 (res + J_p dp)|^2`` (the
      generalised least-squares residual; with ``C_x = 0`` it equals ``sum
      z^2`` at the weighted least-squares solution) at most its 99.9 %
      quantile with ``K - P`` degrees of freedom;
    * ``p`` must be the fit, not only near a tensor that fits: the step
      ``d = G res`` from ``p`` to the weighted least-squares solution (``G``
      the budget's gain matrix, timing weights) in the metric of that
      estimate's covariance ``G C G^T``, ``d^T (G C G^T)^-1 d``, at most
      its 99.9 % quantile with ``P`` degrees of freedom (0 at the solution;
      the truth passes 99.9 % of the time), so that a point on the edge of
      the physical set away from the fit is not accepted.

    An input error shifts every period it touches together (a wire 1 mm
    long lengthens each swing period of that hanging), which timing alone
    calls a misfit."""
    from scipy.linalg import solve_triangular
    from scipy.stats import chi2 as chi2_dist

    from .uncertainty import gain_matrix

    K, P = len(pb.measurements), len(pb.unknowns)
    r = np.ones(K) if r is None else np.asarray(r, float)
    sig = np.array([m.std for m in pb.measurements])
    res = np.asarray(z, float) * sig
    if K > P:
        lim_fit, lim_p = chi2_limit(K, P), float(chi2_dist.ppf(1 - CHI2_P, P))
        test = (f"with the input uncertainties: fit chi2 <= {lim_fit:.4g} ({K - P} degrees of freedom) and the "
                f"estimate's distance from the fit <= {lim_p:.4g} ({P} degrees of freedom), p = {CHI2_P:g}")
    else:
        # as many periods as unknowns, missed only by an answer on the edge of the physical set (no tensor
        # inside fits): every set of periods fits; the edge is accepted as with timing alone, within EDGE_Z
        # sigma (for P unknowns the same probability, 95.4 %)
        lim_fit = math.inf
        lim_p = float(chi2_dist.ppf(chi2_dist.cdf(EDGE_Z ** 2, 1), P))
        test = (f"with the input uncertainties: the edge's distance from the exact fit <= {lim_p:.4g} ({P} degrees "
                f"of freedom, {EDGE_Z:g} sigma)")
    if not np.all(np.isfinite(res)):
        return False, math.inf, math.inf, test
    amp_var = unstated_amplitude_variance(pb, p) if amp_var is None else amp_var
    released = False
    if K <= P and np.any(np.asarray(amp_var) > 0):
        # an edge (no tensor inside fits): a release anywhere in the unstated range shifts the period by
        # w T_lin (r_max - 1), w in 0 .. 1, a bounded shift taken where it brings the model closest (the
        # budget's one-sided interval); timing and the inputs must bridge the rest.  Spread as a normal
        # second moment instead, a flat body on its limit timed with the inputs stated exact was refused in
        # 33 of 50 honest releases (the KTH table's torsion over 20 cycles; docs/design.md, "Estimation
        # audit, session 14")
        end = unstated_amplitude_variance(pb, p, shift=True)
        res = res + np.clip(-res, np.minimum(end, 0.0), np.maximum(end, 0.0))
        amp_var, released = np.zeros(K), True
    C, C_pri, pri_names = period_covariance(pb, p, r, amp_var, extra_var)
    if pri_names:
        test += (f"; counting the stated uncertainty of the components not solved for (inertia="
                 f"{float(pb.unc['inertia']):g}: {', '.join(pri_names)})")
    try:
        L = np.linalg.cholesky(C)
    except np.linalg.LinAlgError:  # sensitivities that overflow: no finite covariance to check against
        return False, math.inf, math.inf, test
    Jp = pb.jacobian(p) * r[:, None]
    with np.errstate(over="ignore", invalid="ignore"):  # a 1e300 s period: an infinite misfit, refused
        rw = solve_triangular(L, res, lower=True)
        Jw = solve_triangular(L, Jp, lower=True)
        e = rw - Jw @ np.linalg.lstsq(Jw, rw, rcond=None)[0]
        G = gain_matrix(Jp, sig)
        d = G @ res
        dist = float(d @ np.linalg.solve(G @ C @ G.T, d))
        chi2_fit = float(e @ e)
    ok = bool(chi2_fit <= lim_fit and dist <= lim_p)  # False for NaN
    if ok and K <= P:
        # no other tensor is fitted: the stated amplitudes' uncertainty (extra_var) with timing, or the inputs,
        # must bridge the residual, the inputs checked with the full model
        stated = sig ** 2 + (0.0 if extra_var is None else np.asarray(extra_var, float))
        other = stated + amp_var
        q = float(res @ np.linalg.solve(np.diag(stated) + C_pri, res)) if pri_names else float(np.sum(res ** 2 / stated))
        ok = bool((extra_var is not None or released or pri_names) and q <= lim_p) \
            or inputs_explain(pb, p, -res, other, lim_p)
    return ok, chi2_fit, dist, test


def prior_fit_hint(pb: Problem, p, z, r=None, extra_var=None, amp_var=None) -> str:
    """A refusal's hint where the components not solved for, taken as exact
    (or stated tighter than :data:`~bifilar.estimation.prior_inertia.PLAUSIBLE_PRIOR_ERROR`),
    would explain the misfit: :func:`input_fit_check` at ``p`` (residuals
    ``z`` in timing sigma, the rest as there) re-run with ``inertia`` at
    that error; where it passes, one clause naming the components that
    move the periods most and ``--uncertainty inertia=REL`` beside
    ``--solve-for`` (ending in "; "), else ``""``."""
    import copy

    from .prior_inertia import PLAUSIBLE_PRIOR_ERROR

    rel = float((pb.unc or {}).get("inertia", 0.0) or 0.0)
    if rel >= PLAUSIBLE_PRIOR_ERROR or not np.all(np.isfinite(z)):
        return ""
    trial = copy.copy(pb)
    trial.unc = {**(pb.unc or {}), "inertia": PLAUSIBLE_PRIOR_ERROR}
    try:
        ok = input_fit_check(trial, p, z, r, extra_var, amp_var)[0]
        names, Jq, sq = prior_period_columns(trial, p, r)
    except (BifilarError, np.linalg.LinAlgError):
        return ""
    w = np.max(np.abs(Jq) * sq[None, :], axis=0) if len(names) else np.zeros(0)
    if not ok or not np.any(w > 0):
        return ""
    movers = [names[q] for q in np.argsort(-w) if w[q] > 0.1 * np.max(w)]
    taken = "as exact" if rel == 0 else f"as known to {rel:g} (inertia={rel:g})"
    return (f"the components not solved for ({', '.join(movers)}) are taken {taken}, but with a "
            f"{100 * PLAUSIBLE_PRIOR_ERROR:g} % error of them counted (--uncertainty inertia="
            f"{PLAUSIBLE_PRIOR_ERROR:g}) the periods fit: state how well they are known (--uncertainty inertia=REL) "
            "or solve for them (--solve-for); ")


def labelled_periods(pb: Problem, p) -> np.ndarray:
    """(K,) linear periods (s) of the modes carrying the measured labels at ``p`` (NaN: no such mode)."""
    vals = pb.values(p)
    out = np.full(len(pb.measurements), np.nan)
    cache = {}
    for k, m in enumerate(pb.measurements):
        h = m.hanging
        if h not in cache:
            hm = pb.models[h]
            cache[h] = hm.locate(hm.scene(vals))[1]
        i = label_index(cache[h], m.label)
        if i is not None and cache[h].modes[i].period:
            out[k] = cache[h].modes[i].period
    return out
