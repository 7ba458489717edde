"""What an inversion returns: :class:`InversionResult`, the estimates of the
unknowns (reference body frame, SI units) with their uncertainty budget, the
method ladder, the measurements' fit, notes and warnings, and its ``--json``
document (:meth:`InversionResult.to_json`, ../shared/interface.md); and
:func:`std_unavailable_text`, the words used where no std can be given.
Made by :func:`bifilar.estimation.invert.invert`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .budget import interval_95
from .ladder import METHOD_TITLES
from .problem import _IDX, Problem
from .roots import separating_measurement
from .solve import amplitude_factor
from .uncertainty import LinearBudget, MonteCarloSummary


@dataclass
class InversionResult:
    """Estimates of the unknowns (reference body frame, SI) with their budget.

    names, values : unknowns and estimates.  budget : LinearBudget (std,
    covariance, correlation, contributions).  method : rung used.
    ladder : list of dicts (method, value(s), applicable, note, difference
    from the best rung).  factors : amplitude factors r per measurement.
    """

    names: list
    values: np.ndarray
    budget: LinearBudget
    method: str
    best_method: str
    ladder: list
    measurements: list
    hangings: list
    linear_periods: np.ndarray
    factors: np.ndarray
    uncertainty: dict
    degenerate_inputs: list
    warnings: list
    notes: list
    runtime: float = 0.0
    monte_carlo: MonteCarloSummary | None = None
    interval: np.ndarray | None = None
    #: per unknown, why its interval was cut at a physical limit (``"triangle"``, ``"positive definite"``) or None
    interval_clipped: list | None = None
    #: the 95 % intervals before that cut
    interval_unclipped: np.ndarray | None = None
    #: why no std can be given (degenerate inputs), or None; then ``std`` is NaN
    std_unavailable: str | None = None
    problem: Problem | None = field(default=None, repr=False)
    fit: dict = field(default_factory=dict)
    roots: list = field(default_factory=list)
    ambiguous: bool = False
    separation: dict | None = None
    sims: list = field(default_factory=list, repr=False)
    #: per measurement its amplitude law (nonlinear method with a stated amplitude,
    #: :class:`~bifilar.estimation.solve.AmplitudeLaw`) or None
    amplitude_laws: list = field(default_factory=list, repr=False)
    #: {input key: (P,) what the amplitude factor's dependences add to that input's term} (nonlinear
    #: method: ``dr/dx`` and the full gain, :func:`~bifilar.estimation.budget._with_factor_gain`); the
    #: input's term without them, as the sweep and plan take it, is its contribution minus this
    input_factor_shift: dict = field(default_factory=dict, repr=False)
    #: the components not solved for (:class:`~bifilar.estimation.prior_inertia.PriorInertia`): priors,
    #: their stated uncertainty and the unknowns' sensitivity to them
    prior_inertia: object = field(default=None, repr=False)
    #: a period read across an avoided crossing, its intervals not to be trusted
    #: (:func:`~bifilar.estimation.crossing_partner.across_gap`), or None
    across_crossing: dict | None = None

    @property
    def std(self) -> np.ndarray:
        """Standard uncertainty of each unknown (NaN when it cannot be given,
        see ``std_unavailable``)."""
        if self.std_unavailable:
            return np.full(len(self.names), np.nan)
        return self.budget.std

    def value(self, name: str) -> float:
        return float(self.values[self.names.index(name)])

    def sigma(self, name: str) -> float:
        return float(self.std[self.names.index(name)])

    def to_json(self) -> dict:
        inertia, com = {}, {}
        for i, n in enumerate(self.names):
            d = {"value": float(self.values[i]), "std": float(self.std[i])}  # NaN -> null (std_unavailable)
            if self.interval is not None:
                d["interval_95"] = [float(self.interval[i, 0]), float(self.interval[i, 1])]
                if self.interval_clipped and self.interval_clipped[i]:
                    d["interval_clipped"] = self.interval_clipped[i]
                    d["interval_95_unclipped"] = [float(x) for x in self.interval_unclipped[i]]
                nu = float(self.budget.effective_dof[i])
                d["dof"] = nu if math.isfinite(nu) else None  # Welch-Satterthwaite; null: infinite (normal)
            if self.monte_carlo is not None and self.monte_carlo.n_ok > 1:
                d["std_monte_carlo"] = float(self.monte_carlo.std[i])
            if n in _IDX:
                d["unit"] = "kg m^2"
                inertia[n] = d
            else:
                d["unit"] = "m"
                com[n.split(".")[1]] = d
        budget = {}
        for i, n in enumerate(self.names):
            sh = self.budget.shares(i)
            top = self.budget.ranked(i, 12)
            budget[n] = {
                "groups": {g: {"share": s, "std": c} for g, (s, c) in self.budget.grouped(i).items()},
                "inputs": {k: {"share": sh[k], "std": float(abs(self.budget.contributions[k][i])),
                               "input_std": self.budget.sigmas.get(k)} for k in top},
            }
        res = []
        for k, m in enumerate(self.measurements):
            Tm = self.linear_periods[k] * self.factors[k]
            res.append({"mode": m.label, "hanging": self.hangings[m.hanging].name, "measured": m.period,
                        "model": float(Tm), "normalised_residual": float((Tm - m.period) / m.std),
                        "amplitude_factor": float(self.factors[k])})
            law = self.amplitude_laws[k] if k < len(self.amplitude_laws) else None
            if law is not None:  # the slope the budget's amplitude term uses (measured, not the quadratic rule)
                res[-1]["amplitude_slope"] = {"dT_dA": float(self.linear_periods[k] * law.slope()),
                                              "quadratic_rule": float(2 * Tm - 2 * self.linear_periods[k])
                                              / m.amplitude,
                                              "quartic_share": (law.quartic_share if math.isfinite(law.quartic_share)
                                                                else None)}
                if law.dr_dx is not None:  # the factor's derivative in each budgeted input (invert's budget)
                    res[-1]["factor_inputs"] = {"dr_dx": {key: float(v) for key, v in law.dr_dx.items()},
                                                "derived": dict(law.dr_dx_derived),
                                                "failed": list(law.dr_dx_failed)}
        doc = {
            "inertia": inertia,
            "method": self.method,
            "method_description": METHOD_TITLES[self.method],
            "best_method": self.best_method,
            "ladder": self.ladder,
            "budget": budget,
            "correlation": {"names": list(self.names), "matrix": self.budget.correlation.tolist()},
            "covariance": self.budget.covariance.tolist(),
            "measurements": [m.to_json() for m in self.measurements],
            "hangings": [{"name": h.name, "config": h.source, "rotation": np.asarray(h.rotation).tolist()}
                         for h in self.hangings],
            "residuals": res,
            "fit": self.fit,
            "ambiguous": bool(self.ambiguous),
            "roots": self.roots,
            "separating_measurement": self.separation,
            "assumed_uncertainty": self.uncertainty,
            "degenerate_inputs": self.degenerate_inputs,
            "monte_carlo": self.monte_carlo.to_json() if self.monte_carlo is not None else None,
            "std_unavailable": self.std_unavailable,
            "across_crossing": self.across_crossing,
            "prior_inertia": self.prior_inertia.to_json(self.std) if self.prior_inertia is not None else None,
            # which rig inputs the hangings share (one error for all of them) and under which model
            "rig": self.problem.links.to_json() if self.problem is not None else None,
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "runtime_s": self.runtime,
        }
        if com:
            doc["com"] = com
        return doc


def std_unavailable_text(inputs, option: str, dependent: bool | None = None) -> str:
    """Why no std can be given (``invert``'s ``std_unavailable``, a sweep
    point's ``sigma_unavailable``): ``inputs`` have no derivative; ``option``
    is the flag that states their uncertainty.  ``dependent``: True where
    the rig's wires are rigid and dependent at rest (four or five taut
    wires: :func:`rigid_dependent`), whose remedy is three wires or the
    wires' stiffness; False where they are not (a neutral mode, e.g. the
    CoM on the attachment line: hang it lower); None (not known): both
    causes, the latter's remedy."""
    if dependent:
        return ("the uncertainty cannot be given: these inputs have no derivative here: the rig has four "
                "or five dependent wires (taut at rest, their tensions not fixed by statics), and on rigid "
                "wires any change of one of them, however small, leaves a wire slack or removes a mode: "
                + ", ".join(inputs) + ". Hang the body on three wires (or two), or state the wires' stiffness "
                "(rig.stiffness, N: the tensions then follow from the wires' stretch; a sweep then says how often "
                "drawn configs leave a wire slack, docs/design.md \"elastic25, session 25\"); a smaller uncertainty "
                f"({option}) does not help unless it is 0, which takes those inputs as exact")
    why = ("a neutral mode, e.g. the CoM on the line through two attachment points" if dependent is False else
           "a neutral mode, e.g. the CoM on the line through two attachment points; or four or five dependent "
           "wires, where a change of one wire leaves a wire slack or removes a mode")
    return (f"the uncertainty cannot be given: these inputs have no derivative here (the scene is degenerate: {why}), "
            "so within their stated uncertainty the hanging changes qualitatively (it cannot hang, tilts far, or "
            "loses a mode): " + ", ".join(inputs) + ". Hang the body with its CoM clearly below the attachment line, "
            f"state those inputs' uncertainty ({option}) if it is smaller")


def rigid_dependent(pairs) -> bool:
    """Whether any of the (scene, rest pose) ``pairs`` has rigid wires
    (no ``rig.stiffness``) that are dependent as constraints at its rest
    pose (com m, R body -> world): four or five taut wires whose tensions
    statics does not fix (:func:`bifilar.analysis.equilibrium._wires_dependent`)."""
    from ..analysis.equilibrium import _wires_dependent

    return any(scene.stiffness is None and scene.n_wires > 3 and _wires_dependent(scene, rest.com, rest.R)
               for scene, rest in pairs)


def _assumed(unc: dict) -> dict:
    from .uncertainty import UNCERTAINTY_KEYS

    return {k: {"value": unc[k], "unit": UNCERTAINTY_KEYS[k]} for k in UNCERTAINTY_KEYS if k in unc}
