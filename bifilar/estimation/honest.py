"""The honest uncertainty of several inertia components of one scene at
once, at a known truth: what :func:`bifilar.estimation.budget.component_std`
gives for each (the std :func:`bifilar.estimation.invert.invert` would print
for a period timed at the truth), for planners (``sweep``, ``plan``).

Why it is the same number, faster.  ``component_std`` builds a one-period
measurement at the scene's own period and runs a full inversion per
component: a root search (a 41-point mode grid and Brent) that lands on the
truth the planner already knows, then the budget there: the linear budget
(the input sensitivities of the scene) and, where it is wrong, the
second-order sigma points (each input at ``+-sqrt(3)`` sigma, the perturbed
scene's rest pose and modes, the unknown re-solved).  Here the budget is
taken directly at the truth (the estimate of an exact period is the truth,
to the root search's tolerance), and the per-scene work is done once for all
components: the sensitivities and the sigma points' (and pairs') rest poses
and modes are the same scenes for every component, only their mapping to
each component's estimate differs (:attr:`BudgetContext.cache`).  The
measured mode is the one carrying the label of the requested mode at the
truth (as in the inversion).  Given the scene's analytic sensitivity
(``sens``, a sweep point's), the linear budget takes from it both the input
columns and the unknown's d T / d I, which the inversion differences
centrally: the std then differs from ``component_std``'s by those
differences' error (~1e-9 relative, measured and tested against
Richardson-extrapolated differences in ``tests/test_point_cost.py``).  An inversion that would not give a std (a
degenerate input: no derivative) gives the ``fallback``, as ``component_std``
does.  Units SI (kg m^2).
"""

from __future__ import annotations

import numpy as np

from ..errors import BifilarError, ConvergenceError
from .budget import LINEAR_ENOUGH, component_std


def honest_stds(scene, requests, unc: dict, timing: float | None = None, amplitude: float | None = 0.0,
                fallbacks=None, rest=None, rtol: float = 1e-10, sens=None, at=None) -> list[float]:
    """The honest standard uncertainty (kg m^2) of each ``(component, mode)``
    of ``requests`` (body-axis inertia component, mode label or 1-based
    index) of ``scene``: :func:`~bifilar.estimation.budget.component_std`
    of each, with the same ``unc``, ``timing`` (s), ``amplitude`` and
    per-request ``fallbacks`` (kg m^2 or None; None raises where
    ``component_std`` raises), computed together (module docstring).
    ``rest``: the scene's rest pose if known.  ``rtol``: the tolerance of
    the nonlinear runs of an unstated amplitude (``amplitude=None``).
    ``sens``: the scene's :class:`~bifilar.estimation.sensitivity.Sensitivity`
    about ``rest`` if known (a sweep point's); where it is analytic in every
    measured input it serves the linear budget (the input Jacobian the budget
    would compute, and the unknown's d T / d I in place of its central
    differences, :func:`_seed_sensitivity`), and its modes serve as the
    scene's when it is about ``rest``.  ``at``: :func:`~bifilar.analysis.modes.modes_of_inertia`
    of ``scene`` about ``rest`` if built (the hanging model's stiffness)."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes
    from .invert import full_budget
    from .measurements import Hanging, Measurement, MeasurementSet
    from .problem import _IDX, admissible, build_problem
    from .uncertainty import default_uncertainty

    fallbacks = list(fallbacks) if fallbacks is not None else [None] * len(requests)
    out: list[float] = []
    cache: dict = {}
    if sens is not None:
        _seed_sensitivity(cache, scene, sens)
    ms = models = links = None
    for (comp, mode), fb in zip(requests, fallbacks):
        try:
            if ms is None:
                rest = rest if rest is not None else rest_pose(scene)
                ms = sens.modes if sens is not None and sens.rest is rest else linear_modes(scene, rest)
            if comp not in _IDX or not admissible(scene.inertia):
                # the inversion would start elsewhere (start guesses) or solve a CoM: its own way
                out.append(component_std(scene, comp, mode, unc, timing, amplitude, fb))
                continue
            md = ms.get(mode) if isinstance(mode, str) else ms.modes[int(mode) - 1]
            s = float(unc.get("timing", 1e-3) if timing is None else timing)
            s = max(s, 1e-15 * float(md.period))
            meas = MeasurementSet([Hanging("ref", scene, np.eye(3))],
                                  [Measurement(md.label, float(md.period), s, "period", "--period",
                                               amplitude=amplitude)])
            unc_all = default_uncertainty({**meas.uncertainty, **(unc or {})})
            pb = build_problem(meas, [comp], unc_all, rests=[rest], models=models, ats=[at])
            if links is not None and pb.models is models:
                pb._links = links  # rig_links of the same hangings (their configs' geometry, not the unknown)
            models = pb.models  # one hanging model (and its mode sets) for every component
            pb.unc = unc_all
            p = pb.prior
            r = np.ones(1)
            budget, _, degenerate, *_ = full_budget(pb, p, r, "linear", {"linear": {"p": p, "r": r}}, "linear",
                                                    unc_all, rtol, cache=cache)
            links = pb._links
            sd = np.nan if degenerate else float(budget.std[0])
            if not np.isfinite(sd):
                if fb is None:
                    raise ConvergenceError("no std: inputs without a derivative " + ", ".join(degenerate))
                out.append(float(fb))
            elif fb is not None and abs(sd - fb) <= LINEAR_ENOUGH * abs(fb):
                out.append(float(fb))
            else:
                out.append(sd)
        except (BifilarError, np.linalg.LinAlgError) as exc:
            if fb is None:
                if isinstance(exc, BifilarError):
                    raise
                raise ConvergenceError(f"{comp}: the period of mode {mode} does not depend on it") from None
            out.append(float(fb))
    return out


def _seed_sensitivity(cache: dict, scene, sens) -> None:
    """Enter ``sens`` into the budget's ``cache`` as the sensitivity the
    linear budget of ``scene`` looks up (:func:`bifilar.estimation.budget._budget`:
    every measured input, via :func:`~bifilar.estimation.uncertainty.robust_sensitivity`),
    when it is what that would compute: analytic in every measured input
    (no finite-difference column, no neutral mode), so equal to rounding;
    and each inertia component's column (by mode label) as the unknown's
    d T / d I (:func:`bifilar.estimation.budget._unknowns_jacobian`, central
    differences otherwise: the analytic value is the one they approximate).
    Anything else (a knife edge, a nearly repeated pair) is left to the
    budget's own differences."""
    from .budget import scene_key
    from .problem import _IDX
    from .sensitivity import Sensitivity, measured_inputs

    names = measured_inputs(scene)
    if (getattr(sens, "method", None) != "analytic" or sens.one_sided or sens.undefined
            or not set(names) <= set(sens.names) or not np.all(np.isfinite(sens.periods))):
        return
    idx = [sens.names.index(n) for n in names]
    jac = np.asarray(sens.jacobian, float)[:, idx]
    if not np.all(np.isfinite(jac)):
        return
    skey = scene_key(scene)
    cache[("sensitivity", skey, tuple(names))] = (
        Sensitivity(list(names), sens.periods, jac, sens.modes, sens.rest, method="analytic"), [])
    # the unknown's column too (budget._unknowns_jacobian: the linear budget's d T / d I of the
    # measured mode, by central differences otherwise): each inertia component's analytic
    # derivative, by mode label, where it is finite for every mode
    labels = [m.label for m in sens.modes.modes]
    for j, n in enumerate(sens.names):
        col = np.asarray(sens.jacobian, float)[:, j]
        if n in _IDX and np.all(np.isfinite(col)):
            cache[("period jacobian", skey, n)] = {lab: float(v) for lab, v in zip(labels, col)}
