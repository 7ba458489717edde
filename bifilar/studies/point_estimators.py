"""The simple estimators a sweep point's biases are measured with: the
exact linear model's estimate (:func:`linear_estimate`, a secant on the
linear period) and the rungs of the thesis's ladder (:class:`_Ladder`: the
small-angle formula and the thesis's section 7.1 linearisation), each fed
the period the nonlinear run (or the linear model) gives at the truth.
Split out of :mod:`bifilar.studies.point` (session 26).  SI units: inertia
kg m^2, periods s.
"""

from __future__ import annotations

import numpy as np

from ..errors import BifilarError, ConvergenceError, SlackWireError, UnstableRestError
from ..errors import one_line as _one_line
from .settings import _IDX


def linear_estimate(scene, comp: str, k: int, T_target: float, modes, rest, slope: float,
                    T0: float | None = None, at=None, matched=None) -> float | None:
    """The exact linear model's estimate of ``comp`` (kg m^2): the value for
    which the linear period of mode ``k`` of ``modes`` (tracked by MAC, rest
    poses warm-started from ``rest``) equals ``T_target`` (s), the other
    inputs as in ``scene``.  Secant iteration from ``slope`` = dT/dI (s per
    kg m^2) to 1e-13 in the period; ``T0`` the period at the scene's value
    (computed if None).  None if a step leaves the stable region.  The rest
    pose and the reduced stiffness do not depend on the inertia: the
    scene's (Newton from ``rest``) are found once and serve every step
    (:func:`~bifilar.analysis.modes.modes_of_inertia`).  ``at``: that
    function for ``scene`` if already built (``rest`` then is the scene's
    own rest pose, used as it is: one build serves every component of a
    sweep point).  ``matched``: :func:`~bifilar.estimation.sensitivity.
    period_matcher` of ``modes`` if already built (one serves every
    component: the same numbers)."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import modes_of_inertia
    from ..estimation.sensitivity import perturb, period_matcher

    I0 = float(scene.inertia[_IDX[comp]])
    if matched is None:
        matched = period_matcher(modes)
    try:
        if at is None:
            at = modes_of_inertia(scene, rest_pose(scene, guess=rest, local_only=True))

        def period(x):  # the linear period of mode k with comp changed by x (kg m^2); only periods and shapes read
            inertia = perturb(scene, comp, x).inertia if x else scene.inertia
            return float(matched(at(inertia, lazy=True))[k])

        if T0 is None:
            T0 = period(0.0)
        x0, f0 = 0.0, float(T0 - T_target)
        if f0 == 0.0:
            return I0
        x1 = -f0 / float(slope)
        for _ in range(12):
            f1 = period(x1) - T_target
            if abs(f1) <= 1e-13 * T_target or f1 == f0:
                return I0 + x1
            x0, f0, x1 = x1, f1, x1 - f1 * (x1 - x0) / (f1 - f0)
    except (UnstableRestError, SlackWireError, ConvergenceError):
        return None
    return None


class _Ladder:
    """The simple estimators of :mod:`bifilar.estimation.invert` applied to
    one point: the small-angle formula (thesis 5.2.18; two wires: D = the
    attachment spacing, h = the mean vertical drop of the wires at rest;
    n >= 3: the multifilar analogue with R = the mean horizontal distance of
    the attachments from the CoM's vertical) and the thesis's section 7.1
    linearisation of its Kane model (two wires, anchors at one height,
    inclined wires).  Falls back to :func:`bifilar.models.reduced.small_angle_inertia`
    (and marks the thesis's method pending) when that module is absent.
    """

    def __init__(self, scene, rest, at=None):
        self.scene, self.rest, self.at = scene, rest, at  # at: modes_of_inertia about rest, if built
        try:
            from ..estimation import invert as inv
            from ..estimation.measurements import Hanging
        except ImportError:
            inv = Hanging = None
        self.inv = inv if inv is not None and hasattr(inv, "ThesisModel") else None
        self._Hanging = Hanging
        self._hm = None
        self._scale = None  # the largest principal moment (kg m^2): the thesis rung's scale, one a point

    def small_angle(self, comp: str, T: float) -> float:
        """Estimate of ``comp`` (kg m^2): the formula gives the moment about the
        vertical; the other components keep their prior."""
        sc, rest = self.scene, self.rest
        if self.inv is not None:
            I_v, _ = self.inv.small_angle_vertical_inertia(sc, rest, T)
        else:
            from ..models.reduced import small_angle_inertia

            P = rest.com + sc.attachments @ rest.R.T
            h = float(np.mean(sc.anchors[:, 2] - P[:, 2]))
            if sc.n_wires == 2:
                D = float(np.linalg.norm(P[0] - P[1]))
            else:
                D = 2.0 * float(np.mean(np.linalg.norm(P[:, :2] - rest.com[:2], axis=1)))
            I_v = float(small_angle_inertia(sc.mass, sc.gravity, D, h, T))
        n = rest.R.T @ np.array([0.0, 0.0, 1.0])  # the vertical in body axes
        a = _IDX[comp][0]
        return float(sc.inertia[a, a] + (I_v - n @ sc.inertia @ n) / n[a] ** 2)

    def thesis(self, comp: str, mode_label: str, T: float) -> tuple[float | None, str]:
        """(estimate in kg m^2 or None, note)."""
        inv = self.inv
        if inv is None:
            return None, "pending: bifilar.estimation.invert (the thesis's linearisation) not available"
        try:
            if self._hm is None:
                self._hm = inv.HangingModel(self._Hanging("sweep point", self.scene, np.eye(3)), self.scene.inertia,
                                            rest=self.rest, at=self.at)  # the point's rest pose and stiffness
            hm = self._hm
            tm = inv.ThesisModel(hm, hm.mode_index(mode_label, "mode"), comp)
            lo, hi = inv.physical_interval(self.scene.inertia, comp)
            if self._scale is None:
                self._scale = float(np.max(np.linalg.eigvalsh(self.scene.inertia)))
            x = inv.solve_scalar(tm.period, T, float(self.scene.inertia[_IDX[comp]]), lo, hi, self._scale, "mode",
                                 comp)
            return float(x), f"linearisation {tm.which} of thesis section 7.1"
        except inv.NotApplicable as exc:
            return None, str(exc)
        except (BifilarError, ValueError, ArithmeticError) as exc:
            return None, _one_line(exc)

    def biases(self, comp: str, mode_label: str, T_ref: float, axis_vertical: bool) -> tuple[dict, dict]:
        """Relative bias of each estimator fed the reference period ``T_ref`` (s)."""
        I_true = float(self.scene.inertia[_IDX[comp]])
        bias: dict = {"small_angle": None, "thesis": None}
        notes: dict = {}
        if mode_label.startswith("torsion") and axis_vertical:
            bias["small_angle"] = self.small_angle(comp, T_ref) / I_true - 1
        else:
            notes["small_angle"] = "applies only to the torsion about the vertical axis"
        x, notes["thesis"] = self.thesis(comp, mode_label, T_ref)
        if x is not None:
            bias["thesis"] = x / I_true - 1
        return bias, notes
