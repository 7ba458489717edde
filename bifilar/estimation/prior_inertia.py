"""The inertia components not solved for: their priors' effect on the answer.

``invert`` solves for some components of the inertia tensor (reference body
frame, kg m^2); the others keep the config's values, the *prior* (usually a
CAD estimate or a guess).  Where the rig couples them into a measured mode
(a tilted rig, an off-centre CoM, a trifilar with tilted anchors) the
answer depends on them: the estimate ``p`` solves ``T(p, I_c) = T_meas``,
so to first order

    dp / dI_c = -G_full dT/dI_c,    dT_k/dI_c = r_k dT_lin,k/dI_c + T_lin,k dr_k/dI_c,

with ``G_full`` the gain of the periods' full derivative in the unknowns
(:attr:`~bifilar.estimation.budget.BudgetContext.gain`, the same that moves
the estimate for a timing or input error) and ``r`` the amplitude factor
(1 for the linear method).  ``dT_lin/dI_c`` by central differences of the
linear periods (the unknowns' own step, 1e-6 of the largest moment, the
measured modes tracked by MAC: :meth:`~bifilar.estimation.problem.Problem.periods_at`);
``dr/dI_c`` (nonlinear method with a stated amplitude) by one forward-
difference run per component with a non-zero uncertainty, as the inputs'
``dr/dx`` (:func:`~bifilar.estimation.factor_inputs.stepped_factor_runs`).

The priors' uncertainty is stated with ``--uncertainty inertia=REL``: each
component not solved for has the standard uncertainty ``REL`` times its
scale (:func:`prior_scales`): a moment's own ``|I_cc|``, a product's
``sqrt(I_ii I_jj)`` (the Cauchy-Schwarz bound on a product, so a product
the config gives as 0 is not exact: a body "symmetric" to 1 % has products
of ~1 % of it), and enters the budget as ``prior_inertia[I_c]`` (group
``prior_inertia``).  The fit check counts the same variance
(:func:`prior_period_columns`, ``fit_check.input_fit_check``).  The
default is 0 (the answer as before: the config's values are taken as exact),
and where a plausible prior error, :data:`PLAUSIBLE_PRIOR_ERROR` of each
component, would move a solved component by more than
:data:`WARN_SHIFT` of its std, ``invert`` warns (:func:`prior_warning`),
naming ``--uncertainty inertia=`` and ``--solve-for``.  Why not a default
of 10 %: the prior's error is what the user knows of the body, not a
measurement the tool can bound, and a default would change every coupled
answer and the std ``sweep`` and ``plan`` predict (docs/design.md,
"priorunc, session 14").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import BifilarError
from .problem import _IDX, Problem
from .sensitivity import INERTIA_COMPONENTS

#: a plausible relative error of a prior a user did not state (a CAD model's mass distribution, a guess)
PLAUSIBLE_PRIOR_ERROR = 0.10
#: warn where that error would move a solved component by more than this fraction of its std
WARN_SHIFT = 1.0 / 3.0
#: central-difference step of dT_lin / dI_c, relative to the largest principal moment (Problem.jacobian's)
PRIOR_STEP = 1e-6


@dataclass
class PriorInertia:
    """The components not solved for at an estimate (reference body frame).

    names : the components (``Ixx`` ...), values : their priors (kg m^2),
    scales : their uncertainties' scales (kg m^2, :func:`prior_scales`),
    sigmas : their standard uncertainties (kg m^2, ``rel * scales``),
    rel : the stated relative uncertainty, stated : whether the user stated
    it, unknowns : the solved names, sensitivity : (P, Q) ``dp_i / dI_c``
    (kg m^2 per kg m^2, or m per kg m^2 for a CoM unknown; NaN where the
    periods could not be evaluated on either side), dr : (K, Q) ``dr_k /
    dI_c`` per kg m^2 (0 where not measured), dr_failed : components whose
    stepped run failed (their ``dr`` left at 0)."""

    names: list
    values: np.ndarray
    scales: np.ndarray
    sigmas: np.ndarray
    rel: float
    stated: bool
    unknowns: list
    sensitivity: np.ndarray
    dr: np.ndarray
    dr_failed: list = field(default_factory=list)
    #: {component: (P,) ``b_c``} the second-order term of a component with a stated uncertainty whose
    #: first-order term does not carry it (:func:`prior_curvature`): the estimate's error is ``a_c z + b_c
    #: z^2``, ``z ~ N(0, 1)``, ``a_c`` the linear term (SI)
    quadratic: dict = field(default_factory=dict)
    #: whether :attr:`quadratic` is in the budget (:func:`with_prior_curvature`: where it changes the std by
    #: more than ``LINEAR_ENOUGH`` or its offset exceeds ``OFFSET_ENOUGH`` of it, as the inputs' sigma points)
    budgeted: bool = False
    #: {component: (P,) ``b_c``} where the user did not state the priors' uncertainty: the second-order
    #: term of each component at a :data:`PLAUSIBLE_PRIOR_ERROR` error (:func:`prior_curvature`), for the
    #: warning of :func:`prior_warning` (a product of inertia given as 0 on a level rig moves the periods
    #: only at second order: the Solar Boat's Ixz at 10 % moves its torsion by 9e-3, Izz by 16 std)
    plausible_quadratic: dict = field(default_factory=dict)

    def quadratic_terms(self, budget) -> dict:
        """{``prior_inertia[c]``: ((P,) ``a_c``, (P,) ``b_c``)} of the
        budgeted second-order terms, ``a_c`` the linear term in ``budget``
        (SI; empty where :attr:`budgeted` is False): the 95 % interval's
        draws (:func:`~bifilar.estimation.budget.interval_95`)."""
        if not self.budgeted:
            return {}
        zero = np.zeros(len(self.unknowns))
        return {f"prior_inertia[{c}]": (np.asarray(budget.contributions.get(f"prior_inertia[{c}]", zero), float),
                                        np.asarray(b, float)) for c, b in self.quadratic.items()}

    def quadratic_contributions(self) -> tuple[dict, np.ndarray]:
        """({``prior_inertia[c] (2nd order)``: (P,) ``sqrt(2) b_c``}, (P,) the
        mean offset ``sum_c b_c``) of :attr:`quadratic` (SI)."""
        P = len(self.unknowns)
        if not self.budgeted:
            return {}, np.zeros(P)
        terms = {f"prior_inertia[{c}] (2nd order)": np.sqrt(2.0) * b for c, b in self.quadratic.items()}
        return terms, sum(self.quadratic.values(), np.zeros(P))

    def contributions(self) -> dict:
        """{``prior_inertia[c]``: (P,) signed standard contribution} of the
        components with a non-zero uncertainty and a derivative."""
        return {f"prior_inertia[{c}]": self.sensitivity[:, q] * self.sigmas[q] for q, c in enumerate(self.names)
                if self.sigmas[q] > 0 and np.all(np.isfinite(self.sensitivity[:, q]))}

    def shift(self, rel: float) -> np.ndarray:
        """(P,) the std each unknown would gain from independent errors of
        ``rel`` times each prior's scale (SI)."""
        S = np.nan_to_num(self.sensitivity) * (rel * self.scales)[None, :]
        return np.sqrt(np.sum(S ** 2, axis=1)) if S.size else np.zeros(len(self.unknowns))

    def plausible_parts(self) -> np.ndarray:
        """(P, Q) the RMS distance (SI) a :data:`PLAUSIBLE_PRIOR_ERROR`
        error of each component alone (``z ~ N(0, 1)`` of it) would move each
        unknown by: ``sqrt(a^2 + 3 b^2)`` of the error ``a z + b z^2``,
        ``a`` the first-order term, ``b`` :attr:`plausible_quadratic`'s."""
        A = np.nan_to_num(self.sensitivity) * (PLAUSIBLE_PRIOR_ERROR * self.scales)[None, :]
        B = np.zeros_like(A)
        for q, c in enumerate(self.names):
            if c in self.plausible_quadratic:
                B[:, q] = np.nan_to_num(np.asarray(self.plausible_quadratic[c], float))
        return np.sqrt(A ** 2 + 3 * B ** 2)

    def plausible_shift(self) -> np.ndarray:
        """(P,) the RMS distance (SI) independent :data:`PLAUSIBLE_PRIOR_ERROR`
        errors of every component would move each unknown by: first order
        and, where computed (:attr:`plausible_quadratic`), second order
        (``E[(sum_c a_c z_c + b_c z_c^2)^2] = sum a^2 + 2 sum b^2 + (sum b)^2``)."""
        sh = self.shift(PLAUSIBLE_PRIOR_ERROR)
        if not self.plausible_quadratic:
            return sh
        b = [np.nan_to_num(np.asarray(v, float)) for v in self.plausible_quadratic.values()]
        return np.sqrt(sh ** 2 + 2 * sum(x ** 2 for x in b) + sum(b) ** 2)

    def to_json(self, std) -> dict:
        """The JSON's ``prior_inertia``: per component its prior, std and
        sensitivity of every unknown; per unknown the std a
        :data:`PLAUSIBLE_PRIOR_ERROR` error of every prior would add and
        its ratio to the answer's std."""
        comps = {}
        for q, c in enumerate(self.names):
            b = self.quadratic.get(c)
            comps[c] = {"prior": float(self.values[q]), "std": float(self.sigmas[q]), "scale": float(self.scales[q]),
                         "unit": "kg m^2",
                        "sensitivity": {n: (float(self.sensitivity[i, q]) if np.isfinite(self.sensitivity[i, q])
                                            else None) for i, n in enumerate(self.unknowns)},
                        "second_order_shift": ({n: float(b[i]) for i, n in enumerate(self.unknowns)}
                                               if b is not None else None)}
        sh = self.plausible_shift()
        return {"relative_std": float(self.rel), "stated": bool(self.stated), "components": comps,
                "second_order_budgeted": bool(self.budgeted),
                "plausible_error": PLAUSIBLE_PRIOR_ERROR,
                "plausible_shift": {n: {"std": float(sh[i]),
                                        "in_std": (float(sh[i] / std[i]) if np.isfinite(std[i]) and std[i] > 0
                                                   else None)}
                                    for i, n in enumerate(self.unknowns)}}


def prior_scales(I, names) -> np.ndarray:
    """(Q,) the scale of each component's prior uncertainty (kg m^2): a
    moment's own ``|I_cc|``; a product ``I_ij``'s ``sqrt(|I_ii I_jj|)``,
    the tensor ``I`` (3, 3) the one at the estimate (reference body frame).
    A product is bounded by it (Cauchy-Schwarz on the second moments ``M =
    tr(I)/2 - I``: ``|I_ij| = |M_ij| <= sqrt(M_ii M_jj) <= sqrt(I_ii I_jj)``),
    so it is the product's natural unit; a product's own value (0 for a
    symmetry) says nothing of how well it is known."""
    I = np.asarray(I, float)
    out = []
    for c in names:
        i, j = _IDX[c]
        out.append(abs(I[i, i]) if i == j else float(np.sqrt(abs(I[i, i] * I[j, j]))))
    return np.array(out, float)


def prior_period_columns(pb: Problem, p, r=None) -> tuple[list, np.ndarray, np.ndarray]:
    """(components, (K, Q) ``r_k dT_lin,k / dI_c`` (s per kg m^2, NaN set to
    0), (Q,) their standard uncertainties ``unc["inertia"]`` times
    :func:`prior_scales`, kg m^2) of the components not solved for, at the
    unknowns ``p``, for the fit check; only the components with a non-zero
    uncertainty (none where ``inertia`` is 0 or not stated).  Linear (the
    amplitude factor's derivative, a small correction, left out)."""
    rel = float((pb.unc or {}).get("inertia", 0.0) or 0.0)
    K = len(pb.measurements)
    names = [c for c in INERTIA_COMPONENTS if c not in pb.unknowns]
    if rel <= 0 or not names:
        return [], np.zeros((K, 0)), np.zeros(0)
    vals = pb.values(p)
    I = pb.models[0].inertia_ref(vals)
    sig = rel * prior_scales(I, names)
    keep = [q for q in range(len(names)) if sig[q] > 0]
    names, sig = [names[q] for q in keep], sig[keep]
    h = PRIOR_STEP * float(np.max(np.linalg.eigvalsh(I)))
    r = np.ones(K) if r is None else np.asarray(r, float)
    J = np.column_stack([_dT_lin(pb, vals, c, float(I[_IDX[c]]), h) for c in names]) if names else np.zeros((K, 0))
    return names, np.nan_to_num(J) * r[:, None], sig


def _dT_lin(pb: Problem, vals: dict, c: str, v0: float, h: float) -> np.ndarray:
    """(K,) d T_lin / d I_c at ``vals`` with ``I_c`` at ``v0``: central
    differences, one-sided where a side cannot be evaluated, NaN where
    neither can."""
    side = {}
    for s in (1, -1):
        try:
            side[s] = pb.periods_at({**vals, c: v0 + s * h})
        except (BifilarError, np.linalg.LinAlgError):
            side[s] = None
    if side[1] is not None and side[-1] is not None:
        return (side[1] - side[-1]) / (2 * h)
    T0 = pb.periods_at(vals)
    for s in (1, -1):
        if side[s] is not None:
            return s * (side[s] - T0) / h
    return np.full(len(pb.measurements), np.nan)


def prior_curvature(pb: Problem, p, names: list, values, sigmas, r, G) -> dict:
    """{component: (P,) ``b_c``} the second-order term of each component
    with a non-zero standard uncertainty ``sigmas[q]`` (kg m^2), as the
    budget's sigma points (:func:`~bifilar.estimation.budget.second_order`):
    the estimate ``p`` re-solved with the prior at ``I_c +- d`` (``d =
    sqrt(3) sigma``, halved until the tensor stays positive definite; two
    Gauss-Newton steps with the full gain ``G`` (P, K), the periods the
    linear ones times the amplitude factors ``r``), ``p_+-``, gives the
    error ``a z + b z^2`` over ``I_c + sigma z`` with ``b = (p_+ + p_- - 2
    p) sigma^2 / (2 d^2)``.  A component whose pair cannot be evaluated is
    left out.  Linear periods only (the amplitude factor's own curvature in
    ``I_c`` is left out)."""
    from .budget import SIGMA_POINT

    out = {}
    p = np.asarray(p, float)
    r = np.asarray(r, float)
    G = np.asarray(G, float)
    vals = pb.values(p)
    T0 = pb.periods_at(vals) * r

    def resolved(c, v):
        q = p
        for _ in range(2):  # the first step is the linear gain's; the second corrects the periods' curvature in p
            T = pb.periods_at({**pb.values(q), c: v}) * r
            if not np.all(np.isfinite(T)):
                return None
            q = q - G @ (T - T0)
        return q

    for q, c in enumerate(names):
        if not sigmas[q] > 0:
            continue
        d = SIGMA_POINT * float(sigmas[q])
        for _ in range(8):
            sides = [float(values[q]) + s * d for s in (1, -1)]
            if all(np.linalg.eigvalsh(pb.models[0].inertia_ref({**vals, c: v}))[0] > 0 for v in sides):
                try:
                    pp, pm = (resolved(c, v) for v in sides)
                except (BifilarError, np.linalg.LinAlgError):
                    pp = pm = None
                if pp is not None and pm is not None:
                    break
            d /= 2
        else:
            continue
        out[c] = (pp + pm - 2 * p) * float(sigmas[q]) ** 2 / (2 * d ** 2)
    return out


def _factor_derivatives(pb: Problem, vals: dict, names: list, values, sigmas, laws, ctx, rtol: float):
    """((K, Q) ``dr_k / dI_c`` per kg m^2 for each measurement with a stated
    amplitude's law and each component with a non-zero uncertainty, the
    components whose stepped run failed): one forward-difference run per
    component (:data:`~bifilar.estimation.solve.FACTOR_STEP` of the largest
    moment), all in one batch with each measurement's own run."""
    from .factor_inputs import SteppedFactors, stated_laws, stepped_factor_runs
    from .solve import FACTOR_STEP

    K, Q = len(pb.measurements), len(names)
    dr = np.zeros((K, Q))
    d = FACTOR_STEP * float(np.max(np.linalg.eigvalsh(pb.I_ref0)))
    plans = {}
    for k, m, _ in stated_laws(pb, laws):
        h = m.hanging
        steps = [(c, d, pb.models[h].scene({**vals, c: values[q] + d})) for q, c in enumerate(names) if sigmas[q] > 0]
        if not steps:
            continue
        j = int(ctx.match[h][pb.mode_index[k]])
        plans[k] = (j, SteppedFactors(ctx.scenes[h], ctx.rests[h], ctx.modes[h], [j], m.amplitude, m.cycles, steps))
    if not plans:
        return dr, []
    stepped_factor_runs([g for _, g in plans.values()], rtol)
    failed = []
    for k, (j, g) in plans.items():
        for q, c in enumerate(names):
            if c in g.dr_dx.get(j, {}):
                dr[k, q] = g.dr_dx[j][c]
            elif sigmas[q] > 0:
                failed.append(c)
    return dr, list(dict.fromkeys(failed))


def prior_terms(pb: Problem, p_hat, r_hat, T_lin, ctx, unc: dict, stated: bool, laws=None,
                rtol: float = 1e-10) -> PriorInertia:
    """The components of the tensor not solved for at the estimate ``p_hat``
    (module docstring): their priors (``pb.I_ref0``: ``pb`` built about the
    estimate, :func:`~bifilar.estimation.problem.problem_at`), standard
    uncertainties ``unc["inertia"]`` times :func:`prior_scales`, the unknowns' sensitivity to
    each and (nonlinear, a non-zero uncertainty) the amplitude factor's
    derivative in them.  ``r_hat`` (K,) the amplitude factors, ``T_lin``
    (K,) the linear periods at ``p_hat`` (s), ``ctx`` the budget's
    :class:`~bifilar.estimation.budget.BudgetContext` (its ``gain``,
    scenes, rest poses, modes), ``stated``: whether the user stated
    ``inertia``."""
    names = [c for c in INERTIA_COMPONENTS if c not in pb.unknowns]
    K, P, Q = len(pb.measurements), len(pb.unknowns), len(names)
    rel = float(unc.get("inertia", 0.0) or 0.0)
    vals = pb.values(p_hat)
    I = pb.models[0].inertia_ref(vals)
    values = np.array([I[_IDX[c]] for c in names], float)
    scales = prior_scales(I, names)
    sigmas = rel * scales
    h = PRIOR_STEP * float(np.max(np.linalg.eigvalsh(pb.I_ref0)))
    J = np.column_stack([_dT_lin(pb, vals, c, values[q], h) for q, c in enumerate(names)]) if Q else np.zeros((K, 0))
    J = J * np.asarray(r_hat, float)[:, None]
    dr, failed = np.zeros((K, Q)), []
    if np.any(sigmas > 0) and laws is not None and any(law is not None for law in laws):
        dr, failed = _factor_derivatives(pb, vals, names, values, sigmas, laws, ctx, rtol)
        J = J + np.asarray(T_lin, float)[:, None] * dr
    G = ctx.gain if ctx.gain is not None else ctx.G
    S = -(np.asarray(G, float) @ J) if Q else np.zeros((P, 0))
    quad = prior_curvature(pb, p_hat, names, values, sigmas, r_hat, G) if np.any(sigmas > 0) else {}
    # unstated: the warning's plausible error to second order too (a component whose first-order term
    # vanishes by symmetry can still move the answer by many stds); 4 linear-period evaluations a component
    plaus = (prior_curvature(pb, p_hat, names, values, PLAUSIBLE_PRIOR_ERROR * scales, r_hat, G)
             if not stated and Q else {})
    return PriorInertia(names, values, scales, sigmas, rel, bool(stated), list(pb.unknowns), S, dr, failed, quad,
                        plausible_quadratic=plaus)


def with_prior(budget, pri: PriorInertia):
    """``budget`` (:class:`~bifilar.estimation.uncertainty.LinearBudget`)
    with the priors' terms added (itself where there are none)."""
    from .uncertainty import LinearBudget, covariance_of

    extra = pri.contributions()
    if not extra:
        return budget
    contrib = {**budget.contributions, **extra}
    cov = covariance_of(contrib, len(budget.names))
    sig = {**budget.sigmas, **{f"prior_inertia[{c}]": float(pri.sigmas[q]) for q, c in enumerate(pri.names)
                               if f"prior_inertia[{c}]" in extra}}
    return LinearBudget(list(budget.names), cov, contrib, sig, dict(budget.dof))


def with_prior_curvature(budget, pri: PriorInertia):
    """``budget`` with the stated priors' second-order terms
    (:attr:`PriorInertia.quadratic`) where they matter, by the rule of the
    inputs' sigma points (:func:`~bifilar.estimation.budget.second_order`:
    the std changes by more than ``LINEAR_ENOUGH`` or the mean offset
    exceeds ``OFFSET_ENOUGH`` of it): each component's ``sqrt(2) b_c`` as
    ``prior_inertia[c] (2nd order)`` and ``sum b_c`` added to ``offset`` (so
    the std is the RMS distance of the truth from the estimate; the value
    is kept, the interval is the quadratic's, :func:`~bifilar.estimation.budget.interval_95`).
    Sets ``pri.budgeted``; itself where nothing is added."""
    from .budget import LINEAR_ENOUGH, OFFSET_ENOUGH
    from .uncertainty import LinearBudget, covariance_of

    if not pri.quadratic:
        return budget
    pri.budgeted = True
    terms, off = pri.quadratic_contributions()
    std1 = budget.std
    old_off = np.asarray(budget.contributions.get("offset", np.zeros(len(std1))), float)
    var2 = std1 ** 2 + sum(t ** 2 for t in terms.values()) + (old_off + off) ** 2 - old_off ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        change, off_rel = np.abs(np.sqrt(var2) / std1 - 1), np.abs(off) / std1
    if np.all(change < LINEAR_ENOUGH) and np.all(off_rel < OFFSET_ENOUGH):
        pri.budgeted = False
        return budget
    contrib = {**budget.contributions, **terms, "offset": old_off + off}
    cov = covariance_of(contrib, len(budget.names))
    return LinearBudget(list(budget.names), cov, contrib, dict(budget.sigmas), dict(budget.dof))


def past_prior_edge(pb: Problem, roots: list, targets, unc: dict) -> tuple[list, bool]:
    """(roots, whether the first was moved) for one unknown from one
    period whose root is on the edge of the physical set: the triangle
    limit there is set by the other components' priors, so where their
    uncertainty is stated (``unc["inertia"] > 0``) it is as uncertain as
    they are, and the answer is the period's own root past it (positive
    definite only, :func:`~bifilar.estimation.solve.solve_linear` from the
    edge; ``targets`` (1,) the periods the linear model must give, s, or
    None), the estimate the budget, counting the priors, describes, not the
    limit (docs/design.md, "priors2, session 15")."""
    from .roots import Root
    from .solve import solve_linear

    if not float(unc.get("inertia", 0.0) or 0.0) > 0:
        return roots, False
    try:
        return [Root(solve_linear(pb, targets, p0=roots[0].p))] + list(roots[1:]), True
    except BifilarError:
        return roots, False


def past_limit_warning(I, name: str, value: float, std: float) -> str:
    """The warning of an answer past the triangle limit the priors set
    (:func:`past_prior_edge`): ``I`` the tensor at it (reference body axes,
    kg m^2), ``value`` and ``std`` the unknown ``name``'s (kg m^2)."""
    from .problem import admissible_interval

    lo, hi = admissible_interval(I, name)
    lim = lo if value < lo else hi
    return (f"{name} = {value:.6g} lies past the triangle limit the other components' priors set ({lim:.6g}), by "
            f"{abs(value - lim) / std:.2g} of its std: their stated uncertainty (--uncertainty inertia) allows a "
            "real body there, so the value is the period's, not cut at the limit; its std counts them")


def prior_warning(pri: PriorInertia, std, partial: bool = False) -> str | None:
    """One line where the user did not state the priors' uncertainty and a
    :data:`PLAUSIBLE_PRIOR_ERROR` error of each would move a solved
    component by more than :data:`WARN_SHIFT` of its std (``std`` (P,),
    SI), else None.  ``partial``: no std is printed (inputs without a
    derivative, ``std_unavailable``): ``std`` is the budget without them,
    and the line gives the shift in SI units beside that ratio."""
    if pri.stated or not pri.names:
        return None
    sh = pri.plausible_shift()
    std = np.asarray(std, float)
    hit = [i for i in range(len(pri.unknowns)) if np.isfinite(std[i]) and std[i] > 0 and sh[i] > WARN_SHIFT * std[i]]
    if not hit:
        return None
    i0 = max(hit, key=lambda i: sh[i] / std[i])
    contrib = pri.plausible_parts()[i0]
    movers = [pri.names[q] for q in np.argsort(-contrib) if contrib[q] > 0.1 * sh[i0]]
    if partial:
        moved = ", ".join(f"{pri.unknowns[i]} by {sh[i]:.3g} (SI), {sh[i] / std[i]:.2g} x the std the budget gives "
                          "without the inputs that have no derivative" for i in hit)
    else:
        moved = ", ".join(f"{pri.unknowns[i]} by {sh[i] / std[i]:.2g} of its std" for i in hit)
    return (f"the config's {', '.join(movers)} (not solved for) {'is' if len(movers) == 1 else 'are'} taken as "
            "exact, but the measured period(s) "
            f"depend on them: a {100 * PLAUSIBLE_PRIOR_ERROR:g} % error in them would move {moved}; state how well "
            "they are known with --uncertainty inertia=REL (relative; budgeted as prior_inertia) or solve for them "
            "(--solve-for)")


def planned_prior_shift(scene, rest, comp: str, label: str) -> tuple[float, list]:
    """For a planned measurement (``sweep``/``plan``): the std (kg m^2, or
    NaN where the period has no derivative) that a :data:`PLAUSIBLE_PRIOR_ERROR`
    error of each other component's prior (its :func:`prior_scales`,
    independent) would add to ``comp`` estimated from mode ``label``'s
    linear period at ``scene``'s rest pose ``rest``, and the components
    that carry it (largest first, those above a tenth of it).  ``invert``'s
    sensitivity with the timing gain alone: ``dI_comp/dI_c = -(dT/dI_c) /
    (dT/dI_comp)``, central differences (:data:`PRIOR_STEP` of the largest
    moment) of the linear periods, the mode tracked by MAC; and the
    second-order term of each at the plausible error (its period's second
    difference over +- that error), combined as :meth:`PriorInertia.plausible_shift`."""
    from ..analysis.modes import modes_of_inertia
    from .sensitivity import matched_periods, perturb

    at = modes_of_inertia(scene, rest)
    base = at(scene.inertia)
    k = next(i for i, m in enumerate(base.modes) if m.label == label)
    h = PRIOR_STEP * float(np.max(np.linalg.eigvalsh(scene.inertia)))

    def dT(c):
        return float(matched_periods(base, at(perturb(scene, c, h).inertia))[k]
                     - matched_periods(base, at(perturb(scene, c, -h).inertia))[k]) / (2 * h)

    def dT2(c, d):  # the period's second difference over +-d (s), None where a side is not a body
        sides = [perturb(scene, c, s * d).inertia for s in (1, -1)]
        if any(np.linalg.eigvalsh(I)[0] <= 0 for I in sides):
            return None
        Tp, Tm = (float(matched_periods(base, at(I))[k]) for I in sides)
        return Tp + Tm - 2 * float(base.modes[k].period)

    others = [c for c in INERTIA_COMPONENTS if c != comp]
    d0 = dT(comp)
    sig = PLAUSIBLE_PRIOR_ERROR * prior_scales(scene.inertia, others)
    S = np.array([-dT(c) / d0 for c in others]) * sig
    # second order (invert's unstated warning, session 15): a product given as 0 on a level rig moves the
    # period only as its square; b_c = -(T(+s) + T(-s) - 2 T) / (2 dT/dI_comp) at s = the plausible error
    B = np.zeros_like(S)
    for q, c in enumerate(others):
        t2 = dT2(c, float(sig[q]))
        B[q] = 0.0 if t2 is None else -t2 / (2 * d0)
    parts = np.sqrt(S ** 2 + 3 * B ** 2)
    shift = float(np.sqrt(np.sum(S ** 2) + 2 * np.sum(B ** 2) + np.sum(B) ** 2))
    movers = [others[q] for q in np.argsort(-parts) if parts[q] > 0.1 * shift] if shift > 0 else []
    return shift, movers
