"""The uncertainty budget of an inversion at its estimate: the linear budget
(period and input sensitivities, the gain matrix and each input's
contribution, :func:`bifilar.estimation.uncertainty.propagate`), its
second-order check and correction by sigma points, the systematic term of an
unstated release amplitude, and the 95 % interval.  SI units.

The second-order step (sigma points, symmetric pairs, the budget context it
reads) lives in :mod:`bifilar.estimation.second_order`; the names are
re-exported here.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import BifilarError, ConvergenceError
from .amplitude_secant import amplitude_sigma, far_amplitude_stds
from .measurements import COM_UNKNOWNS
from .problem import _IDX, Problem, physical_limits
from .sensitivity import input_sigma, measured_inputs, stiff_inputs
from .uncertainty import LinearBudget, covariance_of, gain_matrix, propagate, robust_sensitivity
from .second_order import (LINEAR_ENOUGH, OFFSET_ENOUGH, SIGMA_POINT, BudgetContext,  # noqa: F401 (re-exported)
                           _coefs3, _hanging_periods, _key_hanging, _one_step, _pair_terms, _perturbed_scene,
                           _release_moments, _resolve, _solve_points, scene_key, second_order)

#: default range of release amplitudes when none is given: uniform in 0 .. this
#: many degrees of the mode's dominant rotation (a swing: the wires' angle)
DEFAULT_AMPLITUDE_RANGE_DEG = 10.0
#: samples of the second-order surrogate for the 95 % interval
_SURROGATE_SAMPLES = 20000


def interval_95(p_hat, budget: LinearBudget, ctx: BudgetContext | None, mc_samples=None) -> np.ndarray:
    """(P, 2) 95 % intervals of the unknowns (SI).  Linear budget: ``p +-
    k std``, ``k std = sqrt(sum_j (t_j c_j)^2)`` with each contribution
    expanded by its own Student factor (:attr:`LinearBudget.coverage_factor`;
    1.96 when every term has infinitely many dof: only a period from ``n``
    timed trials has ``n - 1``).  Second-order budget: the 2.5-97.5 % quantiles of the error
    model ``e = sum_j (a_j z_j + b_j z_j^2)`` plus the pair interactions of
    ``ctx.cross`` (:func:`_pair_terms`) plus normal terms for the linear inputs and
    periods (a period with ``nu`` finite degrees of freedom: ``c T_nu``, a
    Student variate, whose 97.5 % quantile is ``c t_{0.975, nu}``), taken with a random
    sign ``s = +-1`` (the model and its mirror image, equally likely), plus
    ``D w`` with ``w = (r(A) - 1) / (r(A_max) - 1)`` of the mode's amplitude
    law (``u = (A/A_max)^2`` for a quadratic one), ``A`` uniform, for an unstated
    amplitude, plus a stated prior's ``a_c z + b_c z^2`` (``ctx.prior.quadratic``, unmirrored: the truth
    spreads about the prior; :func:`~bifilar.estimation.prior_inertia.with_prior_curvature`).  Why the mirror: the model is built around the *measured*
    inputs (the truth spread about them), but where the truth sits at the
    extremum of the response (the symmetric wheel) the error the
    experimenter makes is ``-e`` (the measured inputs spread about the
    truth); the interval ``p +- t`` with ``P(|e| <= t) = 0.95`` covers 95 %
    in both readings, and is ``p +- 1.96 std`` for a normal ``e``
    (docs/invert.md, "The 95 % interval").  Since session 28 the interval is
    the hull of that symmetric one and the unmirrored model's own 2.5-97.5 %
    quantiles (:func:`_readings_quantiles`): where the response is monotone
    over the inputs' 95 % range and skewed (a slope that grows towards one
    side), the unmirrored quantiles are the image of that range, and the
    symmetric ``+- t`` cut their long tail (audit27's a01: 0.929 -> 0.949 of
    564 answers; docs/design.md, "shift28, session 28").  The unstated amplitude's term
    keeps its sign (an assumed distribution of the release amplitude,
    independent of the inputs).  With Monte Carlo re-estimates
    ``mc_samples`` (n, P): the linear interval joined with their 2.5-97.5 %
    quantiles."""
    p = np.asarray(p_hat, float)
    sd = budget.std
    half = budget.coverage_factor * sd
    lo, hi = p - half, p + half
    quad = ctx.prior.quadratic_terms(budget) if ctx is not None and ctx.prior is not None else {}
    skewed = ctx is not None and (ctx.surrogate or ctx.amplitude or quad)
    if mc_samples is not None and len(mc_samples) > 1:
        q = np.quantile(np.asarray(mc_samples, float), [0.025, 0.975], axis=0)
        lo, hi = np.minimum(lo, q[0]), np.maximum(hi, q[1])
    elif skewed:
        rng = np.random.default_rng(20261123)
        N = _SURROGATE_SAMPLES
        err = model_samples(budget, ctx, rng, N, skip=set(quad))
        amp = np.zeros_like(err)
        for lab, D in ctx.amplitude.items():
            u = rng.uniform(0.0, 1.0, N)[:, None] ** 2
            law = ctx.amplitude_law.get(lab)
            amp += D[None, :] * (law.release_weight(u) if law is not None else u)
        post = err  # the model as built: the truth spread about the measured inputs
        if ctx.surrogate:
            err = err * rng.choice([-1.0, 1.0], N)[:, None]
        pri = np.zeros_like(err)
        for key, (a, b) in quad.items():  # a stated prior's a z + b z^2, unmirrored: the truth spreads about it
            z = rng.standard_normal(N)[:, None]
            pri += a[None, :] * z + b[None, :] * z * z
        q = _readings_quantiles(err, post, amp + pri, bool(ctx.surrogate))
        if quad:
            # and where the priors are right (z = 0): the b z^2 terms put half their mass within a few
            # percent of 0, so the mixture's quantile on their far side ends ~1e-3 of the other terms'
            # spread from the value, and a prior that is right left half the honest timings outside
            # (audit15: the Solar Boat's Izz, [value - 5e-4, value + 29] kg m^2 with a timing std of 0.034)
            q0 = _readings_quantiles(err, post, amp, bool(ctx.surrogate))
            q = np.array([np.minimum(q[0], q0[0]), np.maximum(q[1], q0[1])])
        lo, hi = p + q[0], p + q[1]
    return np.column_stack([lo, hi])


def model_samples(budget: LinearBudget, ctx: BudgetContext, rng, n: int, skip=()) -> np.ndarray:
    """(n, P) samples of the inputs' second-order error model (SI, the
    truth minus the estimate as built about the measured inputs, no random
    sign): each linear term's coefficient times a normal variate (a term
    with ``nu`` finite dof: a stratified Student variate), each
    second-order input's ``a z + b z^2`` (``ctx.surrogate``) and the pairs'
    interactions (``ctx.cross``), drawn from ``rng`` in that order.  Left
    out: an unstated amplitude's terms, the mean offset, every ``(2nd
    order)`` contribution (the surrogate holds them) and the keys of
    ``skip`` (a stated prior's).  :func:`interval_95` draws its samples so;
    scripts/interval_rules_compare.py reads the same model."""
    from scipy import stats

    err = np.zeros((n, len(budget.std)))
    skip = set(ctx.surrogate) | {f"amplitude[{lab}]" for lab in ctx.amplitude} | {"offset"} | set(skip)
    for k, c in budget.contributions.items():
        if k in skip or k.endswith("(2nd order)"):
            continue
        nu = budget.dof.get(k, math.inf)
        if math.isfinite(nu):
            # stratified Student variates (one per probability stratum, in
            # random order): the heavy tail of 1-2 dof is sampled evenly
            # (plain draws: ~5 % error in the 97.5 % quantile for nu = 1)
            z = stats.t.ppf((rng.permutation(n) + rng.uniform(size=n)) / n, nu)
        else:
            z = rng.standard_normal(n)
        err += z[:, None] * np.asarray(c)[None, :]
    zs = {}
    for key, (a, b) in ctx.surrogate.items():
        z = zs[key] = rng.standard_normal(n)[:, None]
        err += a[None, :] * z + b[None, :] * z * z
    for (ki, kj), (k11, k21, k12, k22) in ctx.cross.items():
        zi, zj = zs[ki], zs[kj]
        err += zi * zj * (k11 + k21 * zi + k12 * zj + k22 * zi * zj)
    return err


def _readings_quantiles(mirrored, post, rest, both: bool) -> np.ndarray:
    """(2, P) 2.5 and 97.5 % quantiles (SI, offsets from the estimate) of
    the second-order error model's samples, the hull of its two readings
    when ``both`` (docs/invert.md, "The 95 % interval"): ``mirrored + rest``
    (the inputs' error ``e`` taken with a random sign: ``+- t`` with ``P(|e|
    <= t) = 0.95``, right where the truth sits at an even response's
    extremum, the wheel) and ``post + rest`` (``e`` as built about the
    measured inputs, its equal-tailed quantiles: the image of the inputs'
    95 % range where the response is monotone over it, so right whatever
    its curvature; the symmetric interval cuts its long tail, audit27's a01,
    whose ``com.z`` response steepens towards a mode crossing: 0.929).
    ``rest``: terms outside the mirror (an unstated amplitude's, a stated
    prior's), added to both.  Without ``both`` (no second-order inputs) the
    two are one sample."""
    q = np.quantile(mirrored + rest, [0.025, 0.975], axis=0)
    if not both:
        return q
    qp = np.quantile(post + rest, [0.025, 0.975], axis=0)
    return np.array([np.minimum(q[0], qp[0]), np.maximum(q[1], qp[1])])


def clip_interval(interval, p_hat, names, I_hat, uncertain=()) -> tuple[np.ndarray, list]:
    """The 95 % intervals (P, 2) cut at the physical limits of the inertia
    components (kg m^2; :func:`~bifilar.estimation.problem.physical_limits`
    at the estimate ``I_hat``, reference body axes, with the other inertia
    unknowns free), and per unknown why it was cut (``"triangle"``,
    ``"positive definite"``, both joined by " and ", or None).  The truth is
    a physical tensor, so it lies within the limits: the cut interval covers
    it exactly when the uncut one does, and is never wider (docs/invert.md,
    "The 95 % interval").  Values and stds are not touched; an estimate
    outside the limits (a method that may leave the physical set, which
    then warns) keeps its interval.  ``uncertain``: components not solved
    for with a stated uncertainty (``prior_inertia``), free as the unknowns."""
    out = np.array(interval, float)
    why: list = [None] * len(names)
    free = [n for n in list(names) + list(uncertain) if n in _IDX]
    tol = 1e-9 * float(np.max(np.abs(np.linalg.eigvalsh(0.5 * (I_hat + I_hat.T)))))
    for i, n in enumerate(names):
        if n not in _IDX or not np.all(np.isfinite(out[i])):
            continue
        (lo, why_lo), (hi, why_hi) = physical_limits(I_hat, n, free)
        v = float(p_hat[i])
        if not lo - tol <= v <= hi + tol:
            continue
        cut = ([why_lo] if out[i, 0] < lo - tol else []) + ([why_hi] if out[i, 1] > hi + tol else [])
        out[i] = np.clip(out[i], min(lo, v), max(hi, v))
        why[i] = " and ".join(dict.fromkeys(cut)) or None
    return out, why


def default_amplitude_range(scene, mode) -> float:
    """Upper end ``A_max`` of the assumed release amplitudes of ``mode`` (in
    the unit of ``--amplitude``: the mode's dominant coordinate, rad or m):
    :data:`DEFAULT_AMPLITUDE_RANGE_DEG` of rotation when the dominant
    coordinate is a rotation, else the sideways displacement of a wire
    swung by that angle, ``mean(L) sin(angle)``."""
    ang = math.radians(DEFAULT_AMPLITUDE_RANGE_DEG)
    if mode.dominant >= 3:
        return ang
    return float(np.mean(scene.lengths)) * math.sin(ang)


def amplitude_systematic(pb: Problem, p_hat, r_hat, ctx: BudgetContext, rtol: float = 1e-10) -> dict:
    """The systematic term of periods timed at an unstated amplitude
    (measurements whose ``amplitude is None``): release amplitudes assumed
    uniform in 0 .. A_max (:func:`default_amplitude_range`), the amplitude
    factor ``r(A) = 1 + a A^2 + b A^4`` of the mode's amplitude law
    (:func:`~bifilar.estimation.solve.amplitude_law_at`: the nonlinear model
    at A_max and A_max / 2, each over the measurement's ``cycles``, as
    they were timed), so the truth is ``p + D w``
    with ``w = (r(A) - 1) / (r_max - 1)`` (``(A/A_max)^2`` for a quadratic
    law: mean 1/3, std 2/sqrt(45); :meth:`~bifilar.estimation.solve.AmplitudeLaw.release_moments`)
    and ``D = -G T (r_max - 1) / r_max``.  The estimate is kept (it is the
    small-amplitude one the user asked for); :func:`second_order` puts
    the term's mean ``D E[w]`` into ``offset`` and its spread ``D sd(w)``
    into ``amplitude[label]``.  Fills ``ctx.amplitude`` {label: D} and
    ``ctx.amplitude_law``; returns {label: (A_max, r_max)}."""
    from .solve import RELEASE_LAW_RATIO, amplitude_law_at

    out = {}
    labels = pb.term_labels()
    for k, m in enumerate(pb.measurements):
        if m.amplitude is not None:
            continue
        hm = pb.models[m.hanging]
        scene = ctx.scenes[m.hanging]
        mode = ctx.modes[m.hanging].modes[ctx.match[m.hanging][pb.mode_index[k]]]
        A = default_amplitude_range(scene, mode)
        try:
            # over the cycles the period was timed (3 short of a beating mode's: the Solar Boat's roll at 20
            # cycles lengthens 11.5 % more than over 3, and the interval covered 91.9 %, not 95 %)
            law = amplitude_law_at(hm, pb.values(p_hat), pb.mode_index[k], A, m.cycles, rtol,
                                   lam=RELEASE_LAW_RATIO)
        except BifilarError:
            continue
        r_max = float(law.factor(A))
        lab = labels[k]
        e = np.zeros(len(pb.measurements))
        e[k] = ctx.T_hat[k] * (r_max - 1) / r_max
        D = -(ctx.G @ e)
        ctx.amplitude[lab] = D
        ctx.amplitude_law[lab] = law
        out[lab] = (A, float(r_max))
    return out


def input_columns(pb: Problem, vals: dict, r, unc: dict, cache: dict | None = None, rows=None):
    """The input sensitivities of the measured periods at the unknowns
    ``vals``: ({input key: (K,) dT_k/dx, s per SI unit, times the amplitude
    factor ``r[k]``}, {key: standard uncertainty}, degenerate keys (no
    derivative; solved CoM components left out), and per hanging the scene,
    rest pose, modes and base-mode match at ``vals``).  Keys as in the
    budget (``length.1``, ``<hanging>:length.1`` with several hangings;
    ``mass``, ``gravity`` and ``com.*`` shared by every hanging, a CoM shift
    in the reference frame).  ``rows(h, modes, match, k)``: the index in
    hanging ``h``'s modes of measurement ``k``'s mode (default: the base
    mode ``pb.mode_index[k]`` tracked by MAC)."""
    K = len(pb.measurements)
    r = np.asarray(r, float)
    cols: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    degenerate: list[str] = []
    solved_com = {n for n in pb.unknowns if n in COM_UNKNOWNS}
    scenes, rests, modes, matches = [], [], [], []
    for h, hm in enumerate(pb.models):
        scene = hm.scene(vals)
        rest, ms_h, match = hm.locate(scene)
        scenes.append(scene)
        rests.append(rest)
        modes.append(ms_h)
        matches.append(match)
        ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
        if not ks:
            continue
        names = [n for n in measured_inputs(scene) if not n.startswith("com.")]
        if input_sigma(scene, "gravity", unc) > 0:  # a stated uncertainty of g (default 0: known)
            names.append("gravity")
        names += stiff_inputs(scene, unc)  # EA's factor, where rig.stiffness is stated (its own, shared by hangings)
        names += list(COM_UNKNOWNS)
        ck = ("sensitivity", scene_key(scene), tuple(names))
        if cache is not None and ck in cache:
            sens, failed = cache[ck]
        else:
            sens, failed = robust_sensitivity(scene, rest, ms_h, names, scheme="forward")
            if cache is not None:
                cache[ck] = (sens, failed)
        links = pb.links
        degenerate += [d for n in failed
                       for d in ([n] if n.startswith("com.") or n in ("mass", "gravity", "stiffness") else
                                 [key for key, _ in links.of(h, n)])]
        row = {k: (match[pb.mode_index[k]] if rows is None else rows(h, ms_h, match, k)) for k in ks}
        for j, n in enumerate(sens.names):
            col = np.zeros(K)
            for k in ks:
                col[k] = (sens.jacobian[row[k], j] if row[k] is not None else np.nan) * r[k]
            if n.startswith("com."):
                # shared: a CoM shift in the reference frame (com_h = R com_ref)
                ax = "xyz".index(n[-1])
                for a in range(3):
                    key = f"com.{'xyz'[a]}"
                    if key in solved_com:
                        continue
                    cols[key] = cols.get(key, np.zeros(K)) + col * hm.R[ax, a]
                    sigmas[key] = input_sigma(scene, key, unc)
            elif n in ("mass", "gravity", "stiffness"):
                cols[n] = cols.get(n, np.zeros(K)) + col
                sigmas[n] = input_sigma(scene, n, unc)
            else:
                # a rig or attachment input: its keys (one per hanging, or one shared by the hangings
                # that measured it once: their effects add before squaring)
                for key, c in links.of(h, n):
                    cols[key] = cols.get(key, np.zeros(K)) + col * c
                    sigmas[key] = input_sigma(scene, n, unc)
    degenerate = [d for d in dict.fromkeys(degenerate) if d not in solved_com]
    return cols, sigmas, degenerate, scenes, rests, modes, matches


def _unknowns_jacobian(pb: Problem, p_hat, cache: dict | None = None) -> np.ndarray:
    """(K, P) d T_lin / d p of the measured modes at ``p_hat``: the
    analytic derivative where ``cache`` holds one for this scene (a sweep
    point's, :func:`bifilar.estimation.honest._seed_sensitivity`: one
    hanging in body axes, inertia unknowns, {mode label: dT/dI} per
    component), else :meth:`~bifilar.estimation.problem.Problem.jacobian`
    (central differences).  The two differ by the differences' truncation
    and rounding error (~1e-9 relative; docs/performance.md, session 6)."""
    if (cache is not None and len(pb.models) == 1 and all(n in _IDX for n in pb.unknowns)
            and np.array_equal(pb.models[0].R, np.eye(3))):  # (reference axes = the scene's body axes)
        hm = pb.models[0]
        skey = scene_key(hm.scene(pb.values(p_hat)))
        cols = [cache.get(("period jacobian", skey, n)) for n in pb.unknowns]
        labels = [hm.modes0.modes[pb.mode_index[k]].label for k in range(len(pb.measurements))]
        if all(c is not None and all(lab in c for lab in labels) for c in cols):
            return np.array([[c[lab] for c in cols] for lab in labels], float).reshape(len(labels), len(cols))
    return pb.jacobian(p_hat)


def stated_amplitude_period_std(pb: Problem, T_lin, laws, unc: dict) -> np.ndarray:
    """(K,) standard uncertainty (s) of each model period from its stated
    amplitude's own uncertainty (nonlinear method; 0 without an amplitude):
    ``dT/dA s_A`` with ``dT/dA = T_lin dr/dA`` from the mode's amplitude
    law (``laws[k]``, :class:`~bifilar.estimation.solve.AmplitudeLaw`: the
    slope measured by a second run at half the amplitude, not the quadratic
    rule ``2 T_lin (r - 1) / A``) and ``s_A`` the stated std or
    ``unc["amplitude"]`` relative (invert's default 10 %)."""
    out = np.zeros(len(pb.measurements))
    for k, m in enumerate(pb.measurements):
        if m.amplitude:
            out[k] = abs(T_lin[k] * laws[k].slope()) * amplitude_sigma(m, unc)
    return out


def _with_factor_gain(budget: LinearBudget, Jp, T_lin, laws, sig, s_amp, timing_names, pb: Problem,
                      multi: bool, Jx, in_names, in_sig) -> tuple[LinearBudget, dict]:
    """The nonlinear rung's budget with the amplitude factor's dependence on
    the unknowns and on the inputs: the model period is ``T_lin(p, x) r(A;
    p, x)``, so the periods' derivative in the unknowns is ``J_full = r
    dT_lin/dp + T_lin dr/dp`` (``laws[k].dr_dp``), in the inputs ``r
    dT_lin/dx + T_lin dr/dx`` (``Jx``, the factor's part from
    ``laws[k].dr_dx``, :func:`~bifilar.estimation.factor_inputs.factor_input_derivatives`), and a change of
    the measured period (timing), of the release amplitude or of an input
    moves the estimate by the gain of ``J_full``, not of ``r dT_lin/dp``.
    (Before session 10 the inputs kept ``r dT_lin/dx`` over ``r
    dT_lin/dp``, right only where the factor depends on an input as on the
    unknowns: the Solar Boat at spacing 1, length 2, torsion at 0.3 rad,
    the wire lengths' and the anchors' and attachments' x terms 1.11-1.21
    too small; docs/design.md, "The stated amplitude".)  Returns the budget,
    {input key: its contribution's change} (what the factor's
    dependences add to the linear term of an input, for
    :func:`second_order`'s sigma points, which re-solve with the factor
    held) and the full gain (P, K).  A law
    whose runs are not a regular motion (``law.irregular``, s: the check
    run's difference) adds ``integration[mode]``, that difference in the
    model period through the same gain."""
    from .uncertainty import gain_matrix

    P = Jp.shape[1]
    dr = np.array([law.dr_dp if law is not None and law.dr_dp is not None else np.zeros(P) for law in laws])
    Gf = gain_matrix(Jp + np.asarray(T_lin, float)[:, None] * dr, sig)
    contrib = dict(budget.contributions)
    shift = {}
    for j, n in enumerate(in_names):
        if in_sig[j] > 0:
            contrib[n] = -(Gf @ Jx[:, j]) * in_sig[j]
            shift[n] = contrib[n] - budget.contributions[n]
    labels = pb.term_labels()
    for k, m in enumerate(pb.measurements):
        contrib[timing_names[k]] = Gf[:, k] * sig[k]
        if m.amplitude:
            lab = labels[k]
            contrib[f"amplitude[{lab}]"] = -Gf[:, k] * s_amp[k]
            if laws[k] is not None and laws[k].irregular > 0:
                # a motion that is not regular: its model period known only to the check run's difference
                contrib[f"integration[{lab}]"] = Gf[:, k] * laws[k].irregular
            if laws[k] is not None and laws[k].secondary_std > 0:
                # the second mode the record's release started: its amplitude known to its std
                contrib[f"second_mode[{lab}]"] = Gf[:, k] * laws[k].secondary_std
            if laws[k] is not None and laws[k].hidden_std > 0:
                # the modes the record's release may have started unseen, up to the stated bound
                contrib[f"hidden_second_mode[{lab}]"] = Gf[:, k] * laws[k].hidden_std
            if laws[k] is not None and laws[k].reading_std > 0:  # the tone's other reading (several modes)
                contrib[f"tone_reading[{lab}]"] = Gf[:, k] * laws[k].reading_std
    cov = covariance_of(contrib, len(budget.names))
    return LinearBudget(list(budget.names), cov, contrib, dict(budget.sigmas), dict(budget.dof)), shift, Gf


def _budget(pb: Problem, p_hat, r_hat, method, rungs, best, unc, cache: dict | None = None, laws=None,
            rtol: float = 1e-10):
    """Linear budget at the estimate; returns (LinearBudget, degenerate
    inputs, T_lin at p_hat, BudgetContext for :func:`second_order`).
    ``cache``: a dict shared by budgets of other unknowns at the same
    scenes (:attr:`BudgetContext.cache`), or None.  ``laws``: the amplitude
    law of each measurement with a stated amplitude (nonlinear method;
    :func:`stated_amplitude_period_std`; their ``dr_dx`` measured here,
    :func:`~bifilar.estimation.factor_inputs.factor_input_derivatives`, runs at ``rtol``)."""
    K = len(pb.measurements)
    vals = pb.values(p_hat)
    T_lin = pb.linear_periods(p_hat)
    J_lin = _unknowns_jacobian(pb, p_hat, cache)
    Jp = J_lin * r_hat[:, None]
    sig = np.array([m.std for m in pb.measurements])
    multi = len(pb.models) > 1
    cols, sigmas, degenerate, scenes, rests, modes, matches = input_columns(pb, vals, r_hat, unc, cache)
    in_names = list(cols)
    Jx = np.column_stack([cols[n] for n in in_names]) if in_names else np.zeros((K, 0))
    in_sig = np.array([sigmas[n] for n in in_names])
    G = gain_matrix(Jp, sig)
    extra = {}
    s_amp = stated_amplitude_period_std(pb, T_lin, laws, unc) if method == "nonlinear" else np.zeros(K)
    if method == "nonlinear":  # far from linear: a secant over the amplitude's 95 % range
        far_amplitude_stds(pb, p_hat, T_lin, laws, unc, s_amp, rtol)
    labels = pb.term_labels()  # one name per measurement: two timings of one mode are two terms
    for k, m in enumerate(pb.measurements):
        lab = labels[k]
        if method == "nonlinear" and m.amplitude:
            extra[f"amplitude[{lab}]"] = -G[:, k] * s_amp[k]
    if method != best and best in rungs and "p" in rungs[best]:
        extra["model bias"] = np.abs(np.asarray(p_hat) - rungs[best]["p"])
    tn = [f"timing[{lab}]" for lab in labels]
    budget = propagate(list(pb.unknowns), Jp, sig, Jx, in_names, in_sig, extra=extra, timing_names=tn,
                       timing_dof=[m.dof for m in pb.measurements], gain=G)  # (G: gain_matrix of the same Jp, sig)
    shift, gain = {}, G
    if method == "nonlinear" and laws is not None and any(law is not None for law in laws):
        if any(law is not None and law.dr_dp is not None and law.dr_dx is None for law in laws):
            from .factor_inputs import factor_input_derivatives

            factor_input_derivatives(pb, laws, in_names, sigmas, scenes, rests, modes, matches, rtol)
        Jr = np.array([[(law.dr_dx or {}).get(n, 0.0) if law is not None else 0.0 for n in in_names]
                       for law in laws], float).reshape(K, len(in_names))
        budget, shift, gain = _with_factor_gain(budget, Jp, T_lin, laws, sig, s_amp, tn, pb, multi,
                                          Jx + T_lin[:, None] * Jr, in_names, in_sig)
    # every input, degenerate ones too, with its standard uncertainty
    all_sig = dict(sigmas)
    for d in degenerate:
        if d.startswith("com."):
            all_sig[d] = float(unc["com"])
        else:
            h = next(iter(_key_hanging(pb, d)))
            all_sig[d] = input_sigma(scenes[h], pb.links.moves(d, h)[0][0]
                                     if d not in ("mass", "gravity", "stiffness") else d, unc)
    ctx = BudgetContext(in_names + [d for d in degenerate if d not in cols], all_sig, G, T_lin * r_hat,
                        list(degenerate), scenes, rests, modes, matches, cache=cache, factor_shift=shift,
                        gain=gain, jacobian=J_lin)
    return budget, degenerate, T_lin, ctx


def component_std(scene, component: str, mode: str | int, unc: dict, timing: float | None = None,
                  amplitude: float | None = 0.0, fallback: float | None = None) -> float:
    """The honest standard uncertainty (kg m^2) of inertia ``component``
    (body axes) estimated from the linear period of ``mode`` (label or
    1-based index) of ``scene``, with input uncertainties ``unc`` (as
    :func:`~bifilar.estimation.uncertainty.default_uncertainty`) and period
    uncertainty ``timing`` (s; default ``unc['timing']``): the budget
    :func:`bifilar.estimation.invert.invert` prints, second order where the
    linear one is wrong, degenerate inputs by the targeted Monte Carlo.
    ``amplitude``: as ``--amplitude`` (0: small, None: the assumed default
    range).  ``fallback``: the planner's own linear sigma (kg m^2); returned
    when the inversion fails, and also when the honest std is within
    :data:`LINEAR_ENOUGH` of it (the linear budget holds; the two linear
    budgets differ only by their finite-difference error, ~1e-6).  For
    planners (``sweep``)."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes
    from .invert import invert
    from .measurements import Hanging, Measurement, MeasurementSet

    try:
        ms = linear_modes(scene, rest_pose(scene))
        md = ms.get(mode) if isinstance(mode, str) else ms.modes[int(mode) - 1]
        s = float(unc.get("timing", 1e-3) if timing is None else timing)
        s = max(s, 1e-15 * float(md.period))  # an exact period: the gain needs a positive weight
        meas = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                              [Measurement(md.label, float(md.period), s, "period", "--period", amplitude=amplitude)])
        res = invert(meas, method="linear", solve_for=[component], unc=unc, ladder=False)
        sd = float(res.sigma(component))
        if not np.isfinite(sd):
            # a knife edge (res.std_unavailable): invert prints no std there;
            # the planner keeps its linear figure so the rig can still be
            # compared (known limit: it understates such a point's sigma)
            if fallback is None:
                raise ConvergenceError(res.std_unavailable or "no std")
            return float(fallback)
        if fallback is not None and abs(sd - fallback) <= LINEAR_ENOUGH * abs(fallback):
            return float(fallback)
        return sd
    except BifilarError:
        if fallback is None:
            raise
        return float(fallback)
