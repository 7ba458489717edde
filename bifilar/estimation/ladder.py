"""The lower rungs of the estimator ladder: the small-angle formula (thesis
5.2.18 and its multifilar analogue) and the thesis's section 7.1
linearisation of the Kane model.  The ``linear`` and ``nonlinear`` rungs are
:func:`bifilar.estimation.solve.solve_linear` and
:func:`~bifilar.estimation.solve.solve_nonlinear`.  SI units.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import NotApplicable
from ..models.kane_mapping import KaneMapping, kane_mapping, replace_params
from ..scene import Scene
from .problem import _IDX, HangingModel, Problem, basis, physical_interval
from .solve import solve_scalar

METHOD_TITLES = {
    "small-angle": "small-angle parallel-wire formula (thesis 5.2.18 / multifilar analogue)",
    "thesis": "thesis section 7.1 linearisation of the Kane model (2 of 5 angles)",
    "linear": "exact linearised model (all degrees of freedom)",
    "nonlinear": "full nonlinear model at the measured amplitude",
}


#: (indices of theta kept) for the thesis's linearisations 1, 2, 3 (0-based)
THESIS_COORDS = {1: (2, 3), 2: (1, 4), 3: (0, 2)}


#: the thesis's Table 7.1.1 results (I1, I2, I3), kg m^2, and the analytic values
THESIS_TABLE_7_1_1 = {1: (259.2135, 260.4167), 2: (201.8223, 208.333), 3: (52.1033, 52.0833)}


def small_angle_geometry(scene: Scene, rest) -> dict:
    """Geometry the small-angle formula uses, from the rest pose (m):
    ``D`` distance between the two attachment points (two wires), ``R`` mean
    horizontal distance of the attachment points from the vertical through
    the CoM, ``h`` mean vertical drop of the wires."""
    P = rest.com + scene.attachments @ rest.R.T
    h = float(np.mean(scene.anchors[:, 2] - P[:, 2]))
    Rm = float(np.mean(np.linalg.norm(P[:, :2] - rest.com[:2], axis=1)))
    D = float(np.linalg.norm(P[0] - P[1])) if scene.n_wires == 2 else float("nan")
    return {"D": D, "R": Rm, "h": h, "n": scene.n_wires}


def small_angle_vertical_inertia(scene: Scene, rest, T: float) -> tuple[float, dict]:
    """Moment of inertia about the vertical through the CoM, kg m^2, from a
    torsion period ``T`` (s) by (5.2.18) (two wires) or its multifilar analogue."""
    from ..models.reduced import small_angle_inertia

    geo = small_angle_geometry(scene, rest)
    m, g = scene.mass, scene.gravity
    if geo["n"] == 2:
        I = float(small_angle_inertia(m, g, geo["D"], geo["h"], T))
        geo["formula"] = "I = m g D^2 T^2 / (16 pi^2 h)"
    else:
        I = m * g * geo["R"] ** 2 * T**2 / (4 * math.pi**2 * geo["h"])
        geo["formula"] = "I = m g R^2 T^2 / (4 pi^2 h)"
    return I, geo


def thesis_linearisation_for(mapping: KaneMapping, rest, mode) -> int:
    """1, 2 or 3: the thesis linearisation for a mode rotating mostly about
    ntilde_1 (b1), ntilde_2 (b2) or ntilde_3 (b3).  Raises NotApplicable for
    a pure translation."""
    w = np.asarray(mode.shape[3:], float)
    if np.linalg.norm(w) < 1e-6:
        raise NotApplicable(f"mode '{mode.label}' is a pure swing; the thesis's linearisations are rotations "
                            "about b1, b2, b3")
    wn = mapping.C.T @ rest.R.T @ w
    return int(np.argmax(np.abs(wn))) + 1


def _thesis_cache(hm: HangingModel) -> dict:
    """What the thesis's models of one hanging share, kept on ``hm``: its
    Kane mapping and, at the prior rest pose, the mass matrix, forcing and
    the forcing's Jacobian in the five angles (:func:`_thesis_forcing`).
    They depend on the hanging only, not on the mode or component."""
    c = getattr(hm, "_thesis_cache", None)
    if c is None:
        c = hm._thesis_cache = {}
    if "mapping" not in c:
        c["mapping"] = kane_mapping(hm.scene0, hm.rest0)
    return c


def _thesis_forcing(hm: HangingModel):
    """(M_a, N0, dN) of :func:`_thesis_cache`: mass matrix and forcing at
    rest and d forcing / d theta (complex step)."""
    from ..models import kane

    c = _thesis_cache(hm)
    if "forcing" not in c:
        p, th0, z5 = c["mapping"].params, c["mapping"].theta0, np.zeros(5)
        c["state"] = kane.state_quantities(th0, z5, p)  # (its parts serve each component's mass matrix)
        M_a, N0 = c["state"]["M5"], c["state"]["N5"]
        dN = np.zeros((5, 5))
        hstep = 1e-30
        for j in range(5):
            e = np.zeros(5, complex)
            e[j] = 1j * hstep
            # (at rest rates the forcing is its gravity term alone: kane.rest_forcing, the numbers of
            # mass_matrix_and_forcing's N5 for ~40 % of its work)
            dN[:, j] = kane.rest_forcing(th0 + e, p).imag / hstep
        c["forcing"] = (M_a, N0, dN)
    return c["forcing"]


class ThesisModel:
    """Periods of the thesis's 2x2 linearisation as a function of one inertia
    component (reference frame) of a hanging, with the eigenvalue followed
    continuously from the one nearest the exact linear period at the prior."""

    def __init__(self, hm: HangingModel, mode_index: int, component: str):
        from ..models import kane

        if component not in _IDX:
            raise NotApplicable("the thesis's linearisation estimates inertia components only")
        self.mapping = _thesis_cache(hm)["mapping"]
        mode = hm.modes0.modes[mode_index]
        self.which = thesis_linearisation_for(self.mapping, hm.rest0, mode)
        self.idx = THESIS_COORDS[self.which]
        self._sub = np.ix_(self.idx, self.idx)  # (the kept block's index arrays, built once)
        p = self.mapping.params
        M_a, N0, dN = _thesis_forcing(hm)
        scale = p.mass * p.g * max(p.l, p.l_prime, p.b)
        if np.max(np.abs(N0[:4])) > 1e-7 * scale:
            raise NotApplicable("the thesis's model is not at equilibrium at this rest pose")
        self.dN = dN
        self.x0 = float(hm.I_ref0[_IDX[component]])
        # M5 is linear in the inertia: M5(x) = M_a + (x - x0) dM
        E_h = hm.R @ basis(component) @ hm.R.T
        I_b = p.inertia + self.mapping.C.T @ E_h @ self.mapping.C
        i, j = _IDX[component]
        if i != j:  # a product's unit step may leave the positive semi-definite cone: KaneParams refuses it
            I_b = replace_params(p, inertia=I_b).inertia  # (validated)
        # (a moment's adds C^T r r^T C, positive semi-definite: the checks KaneParams makes cannot fail, and it
        # keeps the same values)
        M_b = kane.mass_matrix_with_inertia(_thesis_cache(hm)["state"], I_b)  # = mass_matrix_and_forcing's
        self.M_a, self.dM = M_a, M_b - M_a
        lin_T = mode.period
        ev, V = self._eig(self.x0)
        osc = [k for k in range(2) if ev[k].real < 0]
        if not osc:
            raise NotApplicable("the thesis's 2x2 linearisation has no oscillatory eigenvalue here")
        k = min(osc, key=lambda k: abs(2 * math.pi / math.sqrt(-ev[k].real) - lin_T))
        self.v_ref = V[:, k]
        self._v_ref_norm = np.linalg.norm(self.v_ref)
        self.period0 = 2 * math.pi / math.sqrt(-ev[k].real)
        # period(x0): the same eigenproblem, so period0 where period()'s pick (made here as it makes it) is k
        self._at_x0 = self.period0 if self._pick(V) == k else None

    def _eig(self, x: float):
        M = self.M_a + (x - self.x0) * self.dM
        L = np.linalg.solve(M, self.dN)
        sub = L[self._sub]
        ev, V = np.linalg.eig(sub)
        return ev, V

    def _pick(self, V) -> int:
        """The eigenvector of ``V`` (columns) closest in direction to the reference one."""
        cos = [abs(np.vdot(V[:, k], self.v_ref)) / (np.linalg.norm(V[:, k]) * self._v_ref_norm) for k in range(2)]
        return int(np.argmax(cos))

    def period(self, x: float) -> float:
        """The linearisation's period (s) at component value ``x`` (kg m^2)."""
        if x == self.x0 and self._at_x0 is not None:  # (the root search starts here)
            return self._at_x0
        ev, V = self._eig(x)
        k = self._pick(V)
        return 2 * math.pi / math.sqrt(-ev[k].real) if ev[k].real < 0 else math.nan


def _scalar_rung(pb: Problem, name: str) -> dict:
    hm = pb.models[pb.measurements[0].hanging]
    m = pb.measurements[0]
    comp = pb.unknowns[0]
    k = pb.mode_index[0]
    if comp not in _IDX:
        raise NotApplicable(f"{name} estimates inertia components, not {comp}")
    x0 = float(pb.I_ref0[_IDX[comp]])
    if name == "small-angle":
        mode = hm.modes0.modes[k]
        if not mode.label.startswith("torsion"):
            raise NotApplicable(f"the formula describes torsion about the vertical; mode '{mode.label}' is not torsion")
        n_ref = hm.R.T @ hm.rest0.R.T @ np.array([0.0, 0.0, 1.0])
        i, j = _IDX[comp]
        coef = n_ref[i] * n_ref[j] * (1.0 if i == j else 2.0)
        if abs(coef) < 0.1:
            raise NotApplicable(f"the vertical at rest is far from the {comp} axis (the formula gives the "
                                "moment about the vertical)")
        I_v, geo = small_angle_vertical_inertia(hm.scene0, hm.rest0, m.period)
        x = x0 + (I_v - float(n_ref @ pb.I_ref0 @ n_ref)) / coef
        geo.update({"I_vertical": I_v, "coefficient": float(coef)})
        note = (f"{geo['formula']} with " + (f"D = {geo['D']:.6g} m" if geo["n"] == 2 else f"R = {geo['R']:.6g} m")
                + f", h = {geo['h']:.6g} m; ignores wire inclination, vertical motion and amplitude")
        return {"p": np.array([x]), "note": note, "geometry": geo}
    tm = ThesisModel(hm, k, comp)
    lo, hi = physical_interval(pb.I_ref0, comp)
    x = solve_scalar(tm.period, m.period, x0, lo, hi, float(pb.scales()[0]), m.field, comp)
    th_tab = None
    tab = THESIS_TABLE_7_1_1.get(tm.which)
    kp = tm.mapping.params
    thesis_case = (abs(kp.mass - 100) < 1e-9 and abs(kp.b_prime - 5) < 1e-9 and abs(kp.l - kp.l_prime) < 1e-9
                   and any(abs(kp.l - l) < 1e-9 and abs(kp.b - b) < 1e-9 for l, b in ((500, 505), (5, 10))))
    if tab is not None and thesis_case:  # the rig of the thesis's section 7.1
        th_tab = {"thesis_value": tab[0], "analytic": tab[1], "thesis_relative_error": tab[0] / tab[1] - 1}
    return {"p": np.array([x]), "linearisation": tm.which,
            "theta0": [float(v) for v in tm.mapping.theta0],
            "note": f"linearisation {tm.which}: theta{THESIS_COORDS[tm.which][0] + 1}, "
                    f"theta{THESIS_COORDS[tm.which][1] + 1} kept",
            "thesis_table": th_tab}
