"""Uncertainty of inertia estimates: linear propagation and Monte Carlo.

Linear propagation
------------------
An estimate ``p`` (inertia components, optionally CoM coordinates) solves the
weighted least-squares problem ``min sum_k w_k (T_k(p, x) - T_k^meas)^2``
with ``w_k = 1 / sigma_k^2`` (one equation per measured period ``k``; with as
many periods as unknowns it is the exact solution ``T(p, x) = T^meas``).  To
first order

    dp = G (dT^meas - J_x dx),     G = (J_p^T W J_p)^-1 J_p^T W,

with ``J_p = dT/dp`` (K x P) and ``J_x = dT/dx`` (K x J) the period
sensitivities to the unknowns and to every measured input ``x`` (wire
lengths, anchor and attachment coordinates, mass, CoM position; see
:mod:`bifilar.estimation.sensitivity` for the names).  Each independent
input ``j`` with standard uncertainty ``s_j`` contributes the vector
``c_j = -G J_x[:, j] s_j`` (kg m^2) and each period ``k`` the vector
``G[:, k] sigma_k``; the covariance of ``p`` is ``sum c c^T`` and the share
of input ``j`` in the variance of ``p_i`` is ``c_ji^2 / var(p_i)``.  For one
period and one unknown this is exactly
:func:`bifilar.estimation.sensitivity.inertia_budget`.

Degenerate scenes
-----------------
A body whose CoM lies on the line through two attachment points (the
thesis's thin plate) has a neutral mode: moving an attachment point by a
micrometre makes it turn over.  Central differences then fail on one or both
sides; :func:`input_jacobian` falls back to a second-order one-sided
difference and, if both sides fail, reports the input as *degenerate* and
leaves it out of the budget (the outputs say so).

Monte Carlo
-----------
:func:`draw_scene` draws a scene whose measured inputs are perturbed by
independent normal errors with the standard uncertainties of
:data:`~bifilar.estimation.sensitivity.DEFAULT_UNCERTAINTY` (or overrides);
the inversion module re-estimates on each draw with the full (not
linearised) model and compares the spread with the linear result.

Units: SI (m, kg, s, kg m^2).  Positions: anchors in the world frame,
attachments and the CoM shift in the body frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..analysis.equilibrium import RestPose, _from_guess, rest_pose
from ..analysis.modes import ModeSet, linear_modes
from ..errors import BifilarError, UnstableRestError
from ..scene import Scene
from .sensitivity import (
    DEFAULT_UNCERTAINTY,
    INERTIA_COMPONENTS,
    Sensitivity,
    input_sigma,
    matched_periods,
    measured_inputs,
    perturb,
    stiffness_step,
)

#: default standard uncertainty of the oscillation amplitude, relative
DEFAULT_AMPLITUDE_REL = 0.10
#: default standard uncertainty of one trial's total time when a single
#: hand-timed trial is given (reaction time at start and stop), s
DEFAULT_TRIAL_TIME_SIGMA = 0.1

#: every key an uncertainty override may set, with its unit
UNCERTAINTY_KEYS = {
    "length": "m (each wire length)",
    "position": "m (each coordinate of every anchor and attachment point)",
    "mass": "relative (fraction of the mass)",
    "com": "m (each coordinate of the CoM relative to the attachments)",
    "gravity": "relative",
    "timing": "s (one period given without +-SIGMA)",
    "amplitude": "relative (fraction of the amplitude)",
    "trial_time": "s (reaction-time floor of one hand-timed trial's total time)",
    "release": "m (invert with a recording: the largest second mode its release started unseen, a swing's travel; "
               "an angle mode's this over the longest wire, rad)",
    "inertia": "relative (invert: each inertia component not solved for, the config's value its prior, known to "
               "this fraction of itself, a product to this fraction of sqrt(I_ii I_jj); 0: taken as exact)",
    "stiffness": "relative (the wires' axial stiffness EA, rig.stiffness: one factor common to every wire; "
                 "default 0.1 where rig.stiffness is stated, nothing without it)",
}

#: budget groups, in display order
GROUPS = ("timing", "lengths", "spacings", "mass", "com", "gravity", "stiffness", "amplitude", "second_mode",
          "hidden_second_mode", "tone_reading", "prior_inertia", "integration", "model bias", "offset", "degenerate")


def default_uncertainty(overrides: dict | None = None) -> dict:
    """The assumed standard uncertainties (see :data:`UNCERTAINTY_KEYS` for units)."""
    u = dict(DEFAULT_UNCERTAINTY)
    u.setdefault("amplitude", DEFAULT_AMPLITUDE_REL)
    u.setdefault("trial_time", DEFAULT_TRIAL_TIME_SIGMA)
    u.setdefault("inertia", 0.0)  # the components not solved for: exact unless stated (invert warns; prior_inertia.py)
    u.update(overrides or {})
    return u


def group_of(name: str) -> str:
    """Budget group of an input name: ``timing``, ``lengths``, ``spacings``
    (anchor and attachment coordinates), ``mass``, ``com``, ``gravity``,
    ``stiffness`` (the wires' EA, one factor), ``amplitude``, ``second_mode`` (the amplitude of a second mode a recording's release
    started, :mod:`~bifilar.estimation.signal_swing`), ``hidden_second_mode`` (the modes it may have started
    unseen, up to the stated ``release`` bound), ``tone_reading`` (the other reading of its tone: several modes
    released together within the bound), ``prior_inertia`` (an inertia component not solved for,
    ``prior_inertia[Ixx]``: its prior's stated error), ``integration`` (a nonlinear run that is not a regular
    motion: its check run's difference) or ``model bias``; ``offset`` (the mean offset of a
    second-order or amplitude term) and ``degenerate`` (the targeted Monte
    Carlo) otherwise.  Inputs may carry a hanging prefix
    (``"<hanging>:length.1"``), a second-order term the suffix `` (2nd
    order)``; per-measurement terms a bracketed suffix
    (``timing[<hanging>:torsion]``)."""
    name = name.removesuffix(" (2nd order)")
    head = name.split("[", 1)[0]
    if head in ("timing", "amplitude", "second_mode", "hidden_second_mode", "tone_reading", "prior_inertia",
                "integration", "model bias"):
        return head
    head = name.split(":", 1)[-1].split(".")[0]
    return {"length": "lengths", "anchor": "spacings", "attachment": "spacings"}.get(head, head)


# ---------------------------------------------------------------------------
# sensitivities that survive degenerate scenes
# ---------------------------------------------------------------------------

def _step(scene: Scene, name: str, rel_step: float) -> float:
    """Finite-difference step for input ``name`` (as in sensitivity.period_sensitivity)."""
    if name in INERTIA_COMPONENTS:
        return rel_step * float(np.max(np.linalg.eigvalsh(scene.inertia)))
    if name == "mass":
        return rel_step * scene.mass
    if name == "gravity":
        return rel_step * scene.gravity
    if name == "stiffness":
        return stiffness_step(rel_step)
    return rel_step * float(np.max(scene.lengths))


def _neighbour_periods(scene: Scene, base: ModeSet, rest: RestPose, degenerate: bool) -> np.ndarray:
    """Linear periods of a finite-difference neighbour in ``base``'s mode order
    (as :func:`~bifilar.estimation.sensitivity.periods_of`).  Newton from the
    base rest pose converges for any neighbour of a regular scene; for a
    degenerate base (a neutral mode) a failure means the neighbour cannot
    hang near the base pose, and the slow global search is skipped."""
    r = _from_guess(scene, rest)
    if r is None:
        if degenerate:
            raise UnstableRestError("body", "the neighbouring scene does not hang near the base pose")
        r = rest_pose(scene, guess=rest)
    return matched_periods(base, linear_modes(scene, r))


def input_jacobian(scene: Scene, names: list[str], rest: RestPose, modes: ModeSet,
                   rel_step: float = 1e-6, scheme: str = "central") -> tuple[np.ndarray, list[str]]:
    """dT_k/dx_j (K x J, s per SI unit of the input) for the modes of ``modes``
    (in that order, tracked by MAC), by finite differences with the steps of
    :func:`~bifilar.estimation.sensitivity.period_sensitivity`.

    ``scheme="central"``: ``(T(h) - T(-h)) / 2h`` (error ~h^2, about 1e-10
    relative); ``"forward"``: ``(T(h) - T(0)) / h`` at half the cost (error
    ~h, about 1e-6 relative: ample for an uncertainty budget).  Where one
    side cannot hang (a degenerate scene, see the module docstring) the
    other side is used (central: the second-order one-sided formula
    ``(-3 T(0) + 4 T(h) - T(2h)) / 2h``); where both fail the column is NaN
    and the name is returned in the second value.
    """
    if scheme not in ("central", "forward"):
        raise ValueError(f"unknown scheme {scheme!r}")
    T0 = np.array([m.period if m.period else np.nan for m in modes.modes])
    degenerate = bool(np.any(np.isnan(T0)))
    J = np.full((len(T0), len(names)), np.nan)
    failed = []

    def periods(name, d):
        try:
            return _neighbour_periods(perturb(scene, name, d), modes, rest, degenerate)
        except BifilarError:
            return None

    for j, name in enumerate(names):
        h = _step(scene, name, rel_step)
        if scheme == "forward":
            for side in (1, -1):
                Tp = periods(name, side * h)
                if Tp is not None:
                    J[:, j] = (Tp - T0) / (side * h)
                    break
            else:
                failed.append(name)
            continue
        vals = {k: periods(name, k * h) for k in (1, -1)}
        if vals[1] is not None and vals[-1] is not None:
            J[:, j] = (vals[1] - vals[-1]) / (2 * h)
            continue
        side = 1 if vals[1] is not None else (-1 if vals[-1] is not None else 0)
        T2 = periods(name, 2 * side * h) if side else None
        if T2 is not None:
            J[:, j] = side * (-3 * T0 + 4 * vals[side] - T2) / (2 * h)
        else:
            failed.append(name)
    return J, failed


def robust_sensitivity(scene: Scene, rest: RestPose, modes: ModeSet, names: list[str] | None = None,
                       rel_step: float = 1e-6, scheme: str = "central") -> tuple[Sensitivity, list[str]]:
    """A :class:`~bifilar.estimation.sensitivity.Sensitivity` over ``names``
    (default: the six inertia components and every measured input) that
    survives degenerate scenes; inputs whose derivative does not exist are
    dropped from it and returned as the second value.

    The Jacobian is analytic (:func:`bifilar.analysis.derivatives.analytic_period_jacobian`:
    one rest pose and one eigen-solve, exact to rounding); the inputs with
    no analytic derivative there (a neutral direction) are differenced by
    :func:`input_jacobian` (``rel_step``, ``scheme``), and so is every input
    when the modes have a nearly repeated pair (repeated eigenvalues are
    analytic: :mod:`bifilar.analysis.derivatives`)."""
    from ..analysis.derivatives import NotDifferentiable, analytic_period_jacobian

    names = list(names if names is not None else list(INERTIA_COMPONENTS) + measured_inputs(scene))
    try:
        J = analytic_period_jacobian(scene, rest, modes, names)
    except NotDifferentiable:  # a nearly repeated pair: finite differences with mode tracking for all
        J, failed = input_jacobian(scene, names, rest, modes, rel_step, scheme)
    else:
        live = np.array([m.period is not None for m in modes.modes], bool)
        fd = [j for j in range(len(names)) if live.any() and np.all(np.isnan(J[live, j]))]
        failed = []
        if fd:  # no analytic derivative (a neutral direction): finite differences, which may fail too
            Jf, failed = input_jacobian(scene, [names[j] for j in fd], rest, modes, rel_step, scheme)
            J[:, fd] = Jf
    keep = [j for j, n in enumerate(names) if n not in failed]
    T0 = np.array([m.period if m.period else np.nan for m in modes.modes])
    return Sensitivity([names[j] for j in keep], T0, J[:, keep], modes, rest), failed


#: the normal 97.5 % quantile
Z95 = 1.959963984540054


def equivalent_dof(k: float) -> float:
    """Degrees of freedom ``nu`` whose Student 97.5 % quantile is ``k``
    (``inf`` for ``k <= 1.96``, the normal one; ``k`` above ``t_{0.975, 0.5}``
    gives 0.5)."""
    from scipy import optimize, stats

    if not np.isfinite(k) or k <= Z95 * (1 + 1e-12):
        return math.inf
    def f(nu):
        return float(stats.t.ppf(0.975, nu)) - k

    if f(1e8) >= 0:
        return math.inf
    if f(0.5) <= 0:
        return 0.5
    return float(optimize.brentq(f, 0.5, 1e8, rtol=1e-10))


def combined_dof(terms) -> float:
    """Degrees of freedom of a std ``sqrt(sum s_j^2)`` made of independent
    terms ``(s_j, nu_j)`` (any unit; ``nu_j`` may be ``inf``), by the rule
    of :attr:`LinearBudget.coverage_factor`: the 95 % half-width is the
    quadrature of the terms' own Student half-widths ``t_{0.975, nu_j}
    s_j``, and the dof are those of its factor (:func:`equivalent_dof`;
    ``inf``: normal); one nonzero term keeps its own."""
    from scipy import stats

    terms = [(s, nu) for s, nu in terms if s > 0]
    if len(terms) == 1:  # one term: its own dof, exactly
        return float(terms[0][1])
    var = exp2 = 0.0
    for s, nu in terms:
        t = float(stats.t.ppf(0.975, nu)) if math.isfinite(nu) else Z95
        var += s * s
        exp2 += (t * s) ** 2
    return equivalent_dof(math.sqrt(exp2 / var)) if var > 0 else math.inf


# ---------------------------------------------------------------------------
# linear propagation
# ---------------------------------------------------------------------------

#: relative difference below which two inputs' shares of a variance are a
#: tie: the input sensitivities are forward differences good to ~1e-6 of
#: themselves (docs/invert.md, "Uncertainty"), so shares closer than that are
#: not told apart by the computation; kernels move them by ~1e-10 .. 1e-7
SHARE_TIE = 1e-6


def ranked_by_share(shares: dict, n: int | None = None) -> list:
    """The keys of ``shares`` ({input: share}), largest share first, the
    first ``n``; a run of neighbours each within :data:`SHARE_TIE` (relative)
    of the previous is a tie, ranked by name, so that rounding cannot swap
    an input with its equal (nor pick which of two equal inputs is cut)."""
    order = sorted(shares, key=lambda k: -shares[k])
    out, run = [], []
    for k in order:
        if run and abs(shares[run[-1]] - shares[k]) > SHARE_TIE * abs(shares[run[-1]]):
            out += sorted(run)
            run = []
        run.append(k)
    out += sorted(run)
    return out if n is None else out[:n]


@dataclass
class LinearBudget:
    """Linear uncertainty of the unknowns ``names`` (see module docstring).

    covariance : (P, P) in SI units squared.  std : (P,).
    contributions : {input: (P,) signed standard contribution c_j}.
    sigmas : {input: its standard uncertainty s_j (SI)}.
    dof : {input: degrees of freedom of its standard uncertainty}; a term
        not listed has infinitely many (a Type B input, a stated period
        sigma); a period from ``n`` timed trials has ``n - 1``.
    """

    names: list[str]
    covariance: np.ndarray
    contributions: dict
    sigmas: dict = field(default_factory=dict)
    dof: dict = field(default_factory=dict)

    @property
    def coverage_factor(self) -> np.ndarray:
        """(P,) ``k`` of the 95 % interval ``p +- k std`` of a linear budget:
        ``k std = sqrt(sum_j (t_j c_j)^2)``, each contribution ``c_j``
        expanded by its own Student factor ``t_j = t_{0.975, nu_j}`` (1.96
        for infinitely many dof) -- the quadrature of the terms' own 95 %
        half-widths.  One term alone: its exact Student interval; no finite
        dof: 1.96.  (docs/invert.md, "The 95 % interval", for why not
        Welch-Satterthwaite.)"""
        from scipy import stats

        var = np.zeros(len(self.names))
        exp2 = np.zeros(len(self.names))
        for k, c in self.contributions.items():
            c2 = np.asarray(c, float) ** 2
            nu = self.dof.get(k, math.inf)
            t = float(stats.t.ppf(0.975, nu)) if math.isfinite(nu) else Z95
            var += c2
            exp2 += t * t * c2
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(var > 0, np.sqrt(exp2 / np.where(var > 0, var, 1.0)), Z95)

    @property
    def effective_dof(self) -> np.ndarray:
        """(P,) degrees of freedom equivalent to :attr:`coverage_factor`: the
        ``nu`` with ``t_{0.975, nu} = k`` (``inf`` when ``k`` is 1.96)."""
        return np.array([equivalent_dof(k) for k in self.coverage_factor])

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.maximum(np.diag(self.covariance), 0.0))

    @property
    def correlation(self) -> np.ndarray:
        s = self.std
        with np.errstate(invalid="ignore", divide="ignore"):
            c = self.covariance / np.outer(s, s)
        c[~np.isfinite(c)] = 0.0
        np.fill_diagonal(c, 1.0)
        return c

    def shares(self, i: int) -> dict:
        """{input: fraction of var(p_i)}."""
        var = self.covariance[i, i]
        return {k: (float(c[i] ** 2 / var) if var > 0 else 0.0) for k, c in self.contributions.items()}

    def ranked(self, i: int, n: int | None = None) -> list:
        """The inputs by their share of var(p_i), largest first, the first
        ``n`` of them.  Shares equal to :data:`SHARE_TIE` relative (an
        input and its mirror image on a symmetric rig) are a tie, ranked by
        name: their order in floating point is rounding, which a BLAS
        kernel changes (docs/design.md, "audit29, session 29")."""
        return ranked_by_share(self.shares(i), n)

    def grouped(self, i: int) -> dict:
        """{group: (share of var(p_i), standard contribution)} over :data:`GROUPS`."""
        out: dict[str, list] = {}
        var = self.covariance[i, i]
        for k, c in self.contributions.items():
            g = group_of(k)
            out.setdefault(g, [0.0, 0.0])
            out[g][1] += float(c[i] ** 2)
        res = {}
        for g in GROUPS + tuple(sorted(set(out) - set(GROUPS))):
            if g in out:
                res[g] = (out[g][1] / var if var > 0 else 0.0, float(np.sqrt(out[g][1])))
        return res


def gain_matrix(Jp: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """G = (J_p^T W J_p)^-1 J_p^T W with W = diag(1/sigma^2): dp = G dT."""
    W = 1.0 / np.asarray(sigma, float) ** 2
    A = Jp.T @ (W[:, None] * Jp)
    return np.linalg.solve(A, Jp.T * W[None, :])


def propagate(names: list[str], Jp: np.ndarray, period_sigma: np.ndarray, Jx: np.ndarray,
              input_names: list[str], input_sigmas: np.ndarray, extra: dict | None = None,
              timing_names: list[str] | None = None, timing_dof=None, gain: np.ndarray | None = None) -> LinearBudget:
    """Linear propagation (module docstring).

    Parameters
    ----------
    names : the P unknowns.
    Jp : (K, P) dT/dp, s per unit.
    period_sigma : (K,) standard uncertainty of each measured period, s.
    Jx : (K, J) dT/dx, s per unit of each input.
    input_names, input_sigmas : the J inputs and their standard uncertainties.
    extra : {name: (P,) signed contribution} added as independent terms
        (amplitude effects computed elsewhere, model bias).
    timing_names : names of the K timing terms (default ``timing[k]``).
    timing_dof : (K,) degrees of freedom of each period's sigma (default:
        all infinite; ``n - 1`` for a period from ``n`` timed trials).
    gain : :func:`gain_matrix` ``(Jp, period_sigma)`` if the caller has it
        (the same numbers: budget._budget's).
    """
    Jp = np.atleast_2d(np.asarray(Jp, float))
    K = Jp.shape[0]
    sig = np.asarray(period_sigma, float)
    G = gain_matrix(Jp, sig) if gain is None else gain
    contrib: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    tn = timing_names or [f"timing[{k}]" for k in range(K)]
    dof: dict[str, float] = {}
    for k in range(K):
        contrib[tn[k]] = G[:, k] * sig[k]
        sigmas[tn[k]] = float(sig[k])
        if timing_dof is not None and math.isfinite(timing_dof[k]):
            dof[tn[k]] = float(timing_dof[k])
    # one period (K = 1, a planner's honest sigma): each input's G @ Jx[:, j] is one product per unknown, exactly
    # rounded however it is computed, so every input's column at once is the same numbers (tests/test_perf26b.py)
    cols = -(G @ Jx) if K == 1 else None
    for j, n in enumerate(input_names):
        s = float(input_sigmas[j])
        if s > 0:
            contrib[n] = (cols[:, j] if cols is not None else -(G @ Jx[:, j])) * s
            sigmas[n] = s
    for n, c in (extra or {}).items():
        contrib[n] = np.asarray(c, float).reshape(len(names))
    return LinearBudget(list(names), covariance_of(contrib, len(names)), contrib, sigmas, dof)


def covariance_of(contrib: dict, P: int) -> np.ndarray:
    """(P, P) sum of ``outer(c, c)`` over the (P,) contributions ``c`` of
    ``contrib`` (units of the unknowns squared), added in the dict's order;
    one unknown on Python floats (the same products and sums, ~1 us a term
    instead of ~4)."""
    if P == 1:
        acc = 0.0
        for c in contrib.values():
            x = float(c[0] if np.ndim(c) else c)
            acc += x * x
        return np.array([[acc]])
    cov = np.zeros((P, P))
    for c in contrib.values():
        cov += np.outer(c, c)
    return cov


# ---------------------------------------------------------------------------
# Monte Carlo draws
# ---------------------------------------------------------------------------

def perturb_many(scene: Scene, deltas: dict) -> Scene:
    """``scene`` with every input in ``deltas`` ({name: delta, SI}) changed."""
    for name, d in deltas.items():
        if d:
            scene = perturb(scene, name, float(d))
    return scene


def draw_deltas(scene: Scene, names: list[str], rng: np.random.Generator, unc: dict | None = None) -> dict:
    """Independent normal errors {name: delta} for inputs ``names`` with the
    standard uncertainties :func:`~bifilar.estimation.sensitivity.input_sigma`."""
    u = default_uncertainty(unc)
    return {n: float(rng.normal(0.0, input_sigma(scene, n, u))) for n in names}


@dataclass
class MonteCarloSummary:
    """Spread of ``n_ok`` re-estimates of each unknown (SI units).

    mean, std, low, high (2.5 % and 97.5 % quantiles) : (P,).
    linear_std : (P,) the linear propagation's std, for comparison;
    ratio = std / linear_std.  failed : draws whose inversion failed.
    timing_scale : the factor the periods' stated timing stds were drawn
    with (the Birge factor, :mod:`~bifilar.estimation.birge`; 1 where the
    periods scatter no more than stated).
    """

    names: list[str]
    n: int
    n_ok: int
    mean: np.ndarray
    std: np.ndarray
    low: np.ndarray
    high: np.ndarray
    linear_std: np.ndarray
    failed: int
    samples: np.ndarray = field(repr=False, default=None)
    timing_scale: float = 1.0

    @property
    def ratio(self) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.std / self.linear_std

    def to_json(self) -> dict:
        return {
            "draws": self.n, "ok": self.n_ok, "failed": self.failed, "timing_std_scale": float(self.timing_scale),
            "estimates": {n: {"mean": float(self.mean[i]), "std": float(self.std[i]),
                              "interval_95": [float(self.low[i]), float(self.high[i])],
                              "std_ratio_to_linear": float(self.ratio[i])}
                          for i, n in enumerate(self.names)},
        }


def summarise(names: list[str], samples: np.ndarray, linear_std: np.ndarray, n: int,
              timing_scale: float = 1.0) -> MonteCarloSummary:
    """Summary statistics of Monte Carlo re-estimates ``samples`` (n_ok, P);
    ``timing_scale`` the factor their periods' timing stds were drawn with."""
    S = np.asarray(samples, float).reshape(-1, len(names))
    if S.shape[0] < 2:
        nan = np.full(len(names), np.nan)
        return MonteCarloSummary(list(names), n, S.shape[0], nan, nan, nan, nan, np.asarray(linear_std), n - S.shape[0], S,
                                 timing_scale)
    return MonteCarloSummary(
        list(names), n, S.shape[0], S.mean(axis=0), S.std(axis=0, ddof=1),
        np.quantile(S, 0.025, axis=0), np.quantile(S, 0.975, axis=0), np.asarray(linear_std, float),
        n - S.shape[0], S, timing_scale,
    )
