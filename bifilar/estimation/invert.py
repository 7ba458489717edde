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
from dataclasses import dataclass, field, replace

import numpy as np

from ..analysis.equilibrium import rest_pose
from ..analysis.modes import linear_modes
from ..errors import BifilarError, ConvergenceError, InputError
from ..scene import Scene
from .measurements import COM_UNKNOWNS, METHODS, SOLVABLE, MeasurementSet
from .sensitivity import INERTIA_COMPONENTS, input_sigma, mac_match, measured_inputs
from .uncertainty import (
    LinearBudget,
    MonteCarloSummary,
    default_uncertainty,
    gain_matrix,
    propagate,
    robust_sensitivity,
    summarise,
)

METHOD_TITLES = {
    "small-angle": "small-angle parallel-wire formula (thesis 5.2.18 / multifilar analogue)",
    "thesis": "thesis section 7.1 linearisation of the Kane model (2 of 5 angles)",
    "linear": "exact linearised model (all degrees of freedom)",
    "nonlinear": "full nonlinear model at the measured amplitude",
}
_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
#: (indices of theta kept) for the thesis's linearisations 1, 2, 3 (0-based)
THESIS_COORDS = {1: (2, 3), 2: (1, 4), 3: (0, 2)}
#: the thesis's Table 7.1.1 results (I1, I2, I3), kg m^2, and the analytic values
THESIS_TABLE_7_1_1 = {1: (259.2135, 260.4167), 2: (201.8223, 208.333), 3: (52.1033, 52.0833)}


class NotApplicable(Exception):
    """A rung of the ladder does not apply to this scene or mode (message says why)."""


def basis(name: str) -> np.ndarray:
    """Symmetric unit matrix of inertia component ``name`` (1 at (i,j) and (j,i))."""
    i, j = _IDX[name]
    E = np.zeros((3, 3))
    E[i, j] = E[j, i] = 1.0
    return E


def physical_interval(I: np.ndarray, name: str) -> tuple[float, float]:
    """Open interval of values of component ``name`` (others fixed at ``I``)
    for which the tensor stays positive definite, kg m^2."""
    i, j = _IDX[name]
    x0 = float(I[i, j])
    mu = np.linalg.eigvals(np.linalg.solve(I, basis(name))).real
    lo = max([-1.0 / m for m in mu if m > 1e-15] or [-math.inf])
    hi = min([-1.0 / m for m in mu if m < -1e-15] or [math.inf])
    return x0 + lo, x0 + hi


def triangle_ok(I: np.ndarray, rel: float = 1e-6) -> bool:
    """Principal moments satisfy the triangle inequality (a real body)."""
    ev = np.linalg.eigvalsh(I)
    return bool(ev[0] > 0 and ev[0] + ev[1] >= ev[2] * (1 - rel))


# ---------------------------------------------------------------------------
# the model of one hanging as a function of the unknowns
# ---------------------------------------------------------------------------

class HangingModel:
    """Linear periods of one hanging's modes as functions of the unknowns.

    ``values``: {unknown: value} in the reference body frame (missing ones
    keep the prior).  Rest poses are reused while only the inertia changes
    (the rest pose does not depend on it) and warm-started otherwise; modes
    are tracked by MAC against the modes at the prior.
    """

    def __init__(self, hanging, I_ref0: np.ndarray, like: "HangingModel | None" = None):
        self.hanging = hanging
        self.R = np.asarray(hanging.rotation, float)
        self.I_ref0 = np.asarray(I_ref0, float)
        self.scene0 = replace(hanging.scene, inertia=self.R @ self.I_ref0 @ self.R.T)
        self.rest0 = rest_pose(self.scene0, guess=like.rest0 if like is not None else None)
        self.modes0 = linear_modes(self.scene0, self.rest0)
        # for a perturbed copy, base-mode k of ``like`` is mode map_like[k] here
        self.map_like = mac_match(like.modes0, self.modes0) if like is not None else None
        self._rest_cache = (self._geom_key(self.scene0), self.rest0)
        self.evaluations = 0

    @staticmethod
    def _geom_key(s: Scene):
        return (s.mass, s.gravity, s.lengths.tobytes(), s.anchors.tobytes(), s.attachments.tobytes())

    def mode_index(self, label: str, fld: str) -> int:
        """Index into ``modes0`` of a mode label / 1-based index (InputError naming ``fld``)."""
        try:
            m = self.modes0.get(label)
        except KeyError as exc:
            raise InputError(fld, f"{exc.args[0]} (hanging '{self.hanging.name}')") from None
        if m.period is None:
            raise InputError(fld, f"mode '{m.label}' has no restoring stiffness (no period) in hanging "
                                  f"'{self.hanging.name}'; it cannot be timed")
        return self.modes0.modes.index(m)

    def inertia_ref(self, values: dict) -> np.ndarray:
        I = self.I_ref0.copy()
        for n, v in values.items():
            if n in _IDX:
                i, j = _IDX[n]
                I[i, j] = I[j, i] = v
        return I

    def scene(self, values: dict) -> Scene:
        """The hanging's scene for the unknowns ``values``."""
        I = self.R @ self.inertia_ref(values) @ self.R.T
        d = np.array([values.get(c, 0.0) for c in COM_UNKNOWNS])
        if np.any(d):
            att = self.scene0.attachments - (self.R @ d)[None, :]
            return replace(self.scene0, inertia=I, attachments=att)
        return replace(self.scene0, inertia=I)

    def locate(self, scene: Scene):
        """(rest, modes, match) with ``match[k]`` the index of base mode k."""
        key = self._geom_key(scene)
        if key == self._rest_cache[0]:
            rest = self._rest_cache[1]
        else:
            rest = rest_pose(scene, guess=self._rest_cache[1])
            self._rest_cache = (key, rest)
        ms = linear_modes(scene, rest)
        self.evaluations += 1
        return rest, ms, mac_match(self.modes0, ms)

    def periods(self, values: dict) -> np.ndarray:
        """Linear periods (s) of the base modes (NaN if neutral) at ``values``."""
        _, ms, match = self.locate(self.scene(values))
        return np.array([ms.modes[i].period if ms.modes[i].period else np.nan for i in match])


# ---------------------------------------------------------------------------
# scalar root finding
# ---------------------------------------------------------------------------

def solve_scalar(T_of_x, target: float, x0: float, lo: float, hi: float, scale: float, fld: str, what: str,
                 rtol: float = 1e-12) -> float:
    """Solve ``T(x) = target`` (s) for ``x`` in ``(lo, hi)`` starting at ``x0``.

    Newton/secant on ``T^2 - target^2`` (close to linear in an inertia),
    kept inside the interval; once a sign change is bracketed, Brent's
    method to ``|T - target| <= rtol target``.  Raises :class:`InputError`
    naming ``fld`` with the achievable range when no ``x`` gives ``target``.
    """
    from scipy.optimize import brentq

    memo: dict[float, float] = {}
    margin = 1e-9 * scale

    def f(x: float) -> float:
        if x not in memo:
            T = float(T_of_x(x))
            memo[x] = T * T - target * target if math.isfinite(T) else math.nan
        return memo[x]

    lo_m = lo + margin if math.isfinite(lo) else -math.inf
    hi_m = hi - margin if math.isfinite(hi) else math.inf
    x = min(max(x0, lo_m + margin), hi_m - margin) if math.isfinite(lo_m) or math.isfinite(hi_m) else x0
    fx = f(x)
    tol = 2 * rtol * target * target
    if not math.isfinite(fx):
        raise ConvergenceError(f"the model has no period for this mode at {what} = {x:.6g}")
    if abs(fx) <= tol:
        return x
    h = 1e-6 * scale
    xh = x - h if x + h >= hi_m else x + h
    d = (f(xh) - fx) / (xh - x)
    for _ in range(80):
        if d != 0 and math.isfinite(d):
            xn = x - fx / d
        else:
            xn = x + (10 * scale if fx < 0 else -10 * scale)
        # stay inside the interval; never jump more than 100 scales
        xn = min(max(xn, x - 100 * scale), x + 100 * scale)
        if xn <= lo_m:
            xn = x - 0.9 * (x - lo_m)
        if xn >= hi_m:
            xn = x + 0.9 * (hi_m - x)
        fn = f(xn)
        if not math.isfinite(fn):
            xn = 0.5 * (x + xn)
            fn = f(xn)
            if not math.isfinite(fn):
                break
        if abs(fn) <= tol:
            return xn
        if fn * fx < 0:
            a, b = (x, xn) if x < xn else (xn, x)
            return brentq(f, a, b, xtol=max(1e-15 * scale, 1e-300), rtol=4 * np.finfo(float).eps, maxiter=200)
        if xn == x:
            break
        d = (fn - fx) / (xn - x)
        x, fx = xn, fn
    raise InputError(fld, _range_message(T_of_x, target, x0, lo_m, hi_m, scale, what))


def _range_message(T_of_x, target, x0, lo, hi, scale, what) -> str:
    xs = []
    a = lo if math.isfinite(lo) else x0 - 1e3 * scale
    b = hi if math.isfinite(hi) else x0 + 1e4 * scale
    for x in np.concatenate([np.linspace(a, b, 41), [x0]]):
        try:
            T = float(T_of_x(float(x)))
        except BifilarError:
            continue
        if math.isfinite(T):
            xs.append((x, T))
    if not xs:
        return f"no {what} gives a period of {target:.6g} s for this mode"
    Ts = [t for _, t in xs]
    tmin, tmax = min(Ts), max(Ts)
    up = "" if math.isfinite(hi) else " and beyond, growing without bound" if tmax > 10 * tmin else ""
    return (f"no physical {what} gives a period of {target:.9g} s: this mode's period can only range over "
            f"{tmin:.9g} s .. {tmax:.9g} s{up} ({what} from {a:.4g} to "
            f"{'infinity' if not math.isfinite(hi) else f'{b:.4g}'} with the rest of the tensor at its prior)")


# ---------------------------------------------------------------------------
# rung 1: the small-angle formula
# ---------------------------------------------------------------------------

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


# ---------------------------------------------------------------------------
# rung 2: the thesis's section 7.1 linearisation of the Kane model
# ---------------------------------------------------------------------------

@dataclass
class KaneMapping:
    """A two-wire scene in the thesis's Kane coordinates.

    params : KaneParams (inertia in the ntilde frame).  theta0 : rest angles, rad.
    C : (3, 3) columns ntilde_1..3 in the scene's body components.
    yaw : (3, 3) world -> thesis earth frame (a rotation about z putting the
    anchors along n2).
    """

    params: object
    theta0: np.ndarray
    C: np.ndarray
    yaw: np.ndarray


def kane_mapping(scene: Scene, rest) -> KaneMapping:
    """Express a two-wire scene and its rest pose in the thesis's angles.

    Wire 1 is B -> C (anchor 1, attachment 1, length l), wire 2 D -> A.
    ntilde_3 = -CD/b'; ntilde_1 is the direction of the CoM offset from C
    perpendicular to CD (or, with the CoM on CD, the downward vertical at
    rest); ntilde_2 = ntilde_3 x ntilde_1.  Raises :class:`NotApplicable`.
    """
    from ..models import kane

    if scene.n_wires != 2:
        raise NotApplicable("the thesis's Kane model has two wires")
    A0, B0 = scene.anchors[1], scene.anchors[0]
    Lmax = float(np.max(scene.lengths))
    if abs(A0[2] - B0[2]) > 1e-9 * Lmax:
        raise NotApplicable("the thesis's Kane model needs both anchors at one height")
    u = A0 - B0
    b = float(np.linalg.norm(u))
    u = u / b
    ex = np.cross(u, [0.0, 0.0, 1.0])
    yaw = np.array([ex, u, [0.0, 0.0, 1.0]])  # rows: new axes in world components
    pC, pD = scene.attachments[0], scene.attachments[1]
    bp = float(np.linalg.norm(pD - pC))
    if bp <= 0:
        raise NotApplicable("the attachment points coincide")
    nt3 = -(pD - pC) / bp
    off = -pC  # CoM - C, body components
    along = float(off @ nt3)
    perp = off - along * nt3
    if np.linalg.norm(perp) > 1e-9 * max(bp, 1e-300):
        nt1 = perp / np.linalg.norm(perp)
    else:
        down = rest.R.T @ np.array([0.0, 0.0, -1.0])
        down = down - (down @ nt3) * nt3
        if np.linalg.norm(down) < 1e-9:
            raise NotApplicable("the attachment line is vertical at rest")
        nt1 = down / np.linalg.norm(down)
    nt2 = np.cross(nt3, nt1)
    C = np.column_stack([nt1, nt2, nt3])
    r = float(np.linalg.norm(off))
    lam = math.atan2(float(off @ nt1), -along) if r > 0 else 0.0
    p = kane.KaneParams(b=b, b_prime=bp, l=float(scene.lengths[0]), l_prime=float(scene.lengths[1]),
                        mass=scene.mass, inertia=C.T @ scene.inertia @ C, r=r, lam=lam, g=scene.gravity,
                        anchor_B=yaw @ B0)
    Rk = yaw @ rest.R @ C  # ntilde -> thesis earth
    BC = yaw @ (rest.com + rest.R @ pC - B0)
    CD = yaw @ (rest.R @ (pD - pC))
    th2 = math.acos(max(-1.0, min(1.0, -BC[2] / p.l)))
    th3 = math.atan2(BC[1], BC[0])
    th4 = math.atan2(CD[0], CD[1])
    th5 = math.asin(max(-1.0, min(1.0, CD[2] / bp)))
    th1 = math.atan2(Rk[2, 1], -Rk[2, 0])
    theta0 = np.array([th1, th2, th3, th4, th5])
    if abs(math.sin(th2)) < kane.SIN_THETA2_MIN:
        raise NotApplicable("vertical wires: the thesis's coordinates are singular at theta2 = 0 (its section 6.2)")
    com_k, R_k = kane.pose(theta0, p)
    if np.max(np.abs(com_k - yaw @ rest.com)) > 1e-7 * Lmax or np.max(np.abs(R_k - Rk)) > 1e-7:
        raise NotApplicable("the thesis's angles do not reproduce this rest pose")
    return KaneMapping(p, theta0, C, yaw)


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


class ThesisModel:
    """Periods of the thesis's 2x2 linearisation as a function of one inertia
    component (reference frame) of a hanging, with the eigenvalue followed
    continuously from the one nearest the exact linear period at the prior."""

    def __init__(self, hm: HangingModel, mode_index: int, component: str):
        from ..models import kane

        if component not in _IDX:
            raise NotApplicable("the thesis's linearisation estimates inertia components only")
        self.mapping = kane_mapping(hm.scene0, hm.rest0)
        mode = hm.modes0.modes[mode_index]
        self.which = thesis_linearisation_for(self.mapping, hm.rest0, mode)
        self.idx = THESIS_COORDS[self.which]
        p = self.mapping.params
        th0 = self.mapping.theta0
        z5 = np.zeros(5)
        M_a, N0 = kane.mass_matrix_and_forcing(th0, z5, p)
        scale = p.mass * p.g * max(p.l, p.l_prime, p.b)
        if np.max(np.abs(N0[:4])) > 1e-7 * scale:
            raise NotApplicable("the thesis's model is not at equilibrium at this rest pose")
        dN = np.zeros((5, 5))
        hstep = 1e-30
        for j in range(5):
            e = np.zeros(5, complex)
            e[j] = 1j * hstep
            _, Nc = kane.mass_matrix_and_forcing(th0 + e, z5.astype(complex), p)
            dN[:, j] = Nc.imag / hstep
        self.dN = dN
        self.x0 = float(hm.I_ref0[_IDX[component]])
        # M5 is linear in the inertia: M5(x) = M_a + (x - x0) dM
        E_h = hm.R @ basis(component) @ hm.R.T
        p1 = replace_params(p, inertia=p.inertia + self.mapping.C.T @ E_h @ self.mapping.C)
        M_b, _ = kane.mass_matrix_and_forcing(th0, z5, p1)
        self.M_a, self.dM = M_a, M_b - M_a
        lin_T = mode.period
        ev, V = self._eig(self.x0)
        osc = [k for k in range(2) if ev[k].real < 0]
        if not osc:
            raise NotApplicable("the thesis's 2x2 linearisation has no oscillatory eigenvalue here")
        k = min(osc, key=lambda k: abs(2 * math.pi / math.sqrt(-ev[k].real) - lin_T))
        self.v_ref = V[:, k]
        self.period0 = 2 * math.pi / math.sqrt(-ev[k].real)

    def _eig(self, x: float):
        M = self.M_a + (x - self.x0) * self.dM
        L = np.linalg.solve(M, self.dN)
        sub = L[np.ix_(self.idx, self.idx)]
        ev, V = np.linalg.eig(sub)
        return ev, V

    def period(self, x: float) -> float:
        """The linearisation's period (s) at component value ``x`` (kg m^2)."""
        ev, V = self._eig(x)
        cos = [abs(np.vdot(V[:, k], self.v_ref)) / (np.linalg.norm(V[:, k]) * np.linalg.norm(self.v_ref))
               for k in range(2)]
        k = int(np.argmax(cos))
        return 2 * math.pi / math.sqrt(-ev[k].real) if ev[k].real < 0 else math.nan


def replace_params(p, **kw):
    """A copy of a frozen KaneParams with fields changed."""
    from ..models.kane import KaneParams

    d = {f: getattr(p, f) for f in ("b", "b_prime", "l", "l_prime", "mass", "inertia", "r", "lam", "g", "anchor_B")}
    d.update(kw)
    return KaneParams(**d)


# ---------------------------------------------------------------------------
# rung 4: the amplitude factor of the nonlinear model
# ---------------------------------------------------------------------------

def amplitude_factor(hm: HangingModel, values: dict, mode_index: int, amplitude: float, cycles: float,
                     rtol: float = 1e-10):
    """r = T_sim / T_lin of base mode ``mode_index`` at ``values``, simulated
    from rest displaced by ``amplitude`` x the mode shape for ``cycles``
    linear periods.  Returns (r, SimulationResult)."""
    from ..analysis.simulate import simulate

    scene = hm.scene(values)
    rest, ms, match = hm.locate(scene)
    k = int(match[mode_index])
    sim = simulate(scene, k + 1, amplitude, cycles, rest=rest, modes=ms, rtol=rtol)
    if sim.period is None:
        raise ConvergenceError(f"the simulated {ms.modes[k].label} motion showed fewer than two crossings")
    return sim.period / ms.modes[k].period, sim


# ---------------------------------------------------------------------------
# the problem and its solution
# ---------------------------------------------------------------------------

@dataclass
class Problem:
    """Hanging models, measurements (with their base-mode indices) and unknowns."""

    models: list
    measurements: list
    mode_index: list
    unknowns: list
    I_ref0: np.ndarray
    unc: dict

    @property
    def prior(self) -> np.ndarray:
        return np.array([self.I_ref0[_IDX[n]] if n in _IDX else 0.0 for n in self.unknowns])

    def scales(self) -> np.ndarray:
        Imax = float(np.max(np.linalg.eigvalsh(self.I_ref0)))
        Lmax = max(float(np.max(hm.scene0.lengths)) for hm in self.models)
        return np.array([Imax if n in _IDX else 1e-2 * Lmax for n in self.unknowns])

    def values(self, p) -> dict:
        return {n: float(v) for n, v in zip(self.unknowns, np.atleast_1d(p))}

    def linear_periods(self, p) -> np.ndarray:
        """(K,) linear periods of the measured modes at unknowns ``p``, s."""
        vals = self.values(p)
        out = np.empty(len(self.measurements))
        cache = {}
        for k, m in enumerate(self.measurements):
            h = m.hanging
            if h not in cache:
                cache[h] = self.models[h].periods(vals)
            out[k] = cache[h][self.mode_index[k]]
        return out

    def jacobian(self, p, rel_step: float = 1e-6) -> np.ndarray:
        """(K, P) d T_lin / d p by central differences."""
        p = np.asarray(p, float)
        sc = self.scales()
        J = np.empty((len(self.measurements), len(p)))
        for j in range(len(p)):
            h = rel_step * sc[j]
            e = np.zeros_like(p)
            e[j] = h
            J[:, j] = (self.linear_periods(p + e) - self.linear_periods(p - e)) / (2 * h)
        return J


def build_problem(ms: MeasurementSet, solve_for: list | None = None, unc: dict | None = None,
                  like: Problem | None = None) -> Problem:
    """Hanging models at the prior, mode indices and the unknowns (picked
    per measurement as the component its period is most sensitive to,
    relatively, when ``solve_for`` is empty)."""
    h0 = ms.hangings[0]
    I_ref0 = h0.rotation.T @ h0.scene.inertia @ h0.rotation
    models = [HangingModel(h, I_ref0, like=like.models[i] if like is not None else None)
              for i, h in enumerate(ms.hangings)]
    idx = []
    for k, m in enumerate(ms.measurements):
        if like is not None:
            idx.append(int(models[m.hanging].map_like[like.mode_index[k]]))
        else:
            idx.append(models[m.hanging].mode_index(m.label, m.field))
    if like is not None:
        unknowns = list(like.unknowns)
    elif solve_for:
        unknowns = [n for n in SOLVABLE if n in solve_for]
        bad = [n for n in solve_for if n not in SOLVABLE]
        if bad:
            raise InputError("--solve-for", f"unknown component {bad[0]!r}; choose from {', '.join(SOLVABLE)}")
    else:
        tmp = Problem(models, ms.measurements, idx, list(INERTIA_COMPONENTS), I_ref0, unc or {})
        unknowns = []
        for k, m in enumerate(ms.measurements):
            unknowns.append(best_component(tmp, k))
        unknowns = [n for n in SOLVABLE if n in unknowns]
    pb = Problem(models, ms.measurements, idx, unknowns, I_ref0, default_uncertainty(unc))
    if like is None and len(unknowns) > len(ms.measurements):
        raise InputError("--solve-for", f"{len(unknowns)} unknowns ({', '.join(unknowns)}) but only "
                                        f"{len(ms.measurements)} measured period(s): measure more modes or "
                                        "hangings, or solve for fewer components")
    return pb


def relative_sensitivities(pb: Problem, k: int) -> dict:
    """{component: |dT/dI_c| s_c / T} for measurement ``k`` at the prior;
    ``s_c`` = I_cc for moments, sqrt(I_ii I_jj) for products."""
    p0 = pb.prior
    J = pb.jacobian(p0)
    T = pb.linear_periods(p0)[k]
    out = {}
    for j, n in enumerate(pb.unknowns):
        i1, i2 = _IDX[n]
        s = pb.I_ref0[i1, i1] if i1 == i2 else math.sqrt(pb.I_ref0[i1, i1] * pb.I_ref0[i2, i2])
        out[n] = abs(J[k, j]) * s / T
    return out


def best_component(pb: Problem, k: int) -> str:
    """The inertia component measurement ``k``'s period is most sensitive to
    (relatively): :func:`bifilar.estimation.sensitivity.best_mode_for` inverted."""
    rel = relative_sensitivities(pb, k)
    best = max(rel, key=rel.get)
    if not rel[best] > 1e-9:
        m = pb.measurements[k]
        raise InputError(m.field, f"mode '{m.label}' does not depend on the inertia; time a rotational mode")
    return best


@dataclass
class Estimate:
    p: np.ndarray
    method: str
    r: np.ndarray  # amplitude factors (1 when linear)
    iterations: int = 0
    sims: list = field(default_factory=list)


def _targets(pb: Problem, r: np.ndarray) -> np.ndarray:
    return np.array([m.period for m in pb.measurements]) / r


def solve_linear(pb: Problem, targets: np.ndarray | None = None, p0=None) -> np.ndarray:
    """Unknowns for which the linear periods equal ``targets`` (default: the
    measured periods): scalar root finding for one unknown and one period,
    else Gauss-Newton least squares."""
    targets = np.array([m.period for m in pb.measurements]) if targets is None else targets
    p0 = pb.prior if p0 is None else np.asarray(p0, float)
    sc = pb.scales()
    if len(pb.unknowns) == 1 and len(pb.measurements) == 1:
        name = pb.unknowns[0]
        m = pb.measurements[0]
        if name in _IDX:
            lo, hi = physical_interval(pb.I_ref0, name)
        else:
            lo, hi = -math.inf, math.inf
        x = solve_scalar(lambda x: pb.linear_periods([x])[0], float(targets[0]), float(p0[0]), lo, hi,
                         float(sc[0]), m.field, name)
        return np.array([x])
    return gauss_newton(pb, targets, p0)


def gauss_newton(pb: Problem, targets: np.ndarray, p0: np.ndarray, max_iter: int = 40) -> np.ndarray:
    """Weighted least squares ``min sum ((T_k(p) - target_k) / sigma_k)^2``."""
    sig = np.array([m.std for m in pb.measurements])
    sc = pb.scales()
    p = np.asarray(p0, float).copy()

    def cost(p):
        try:
            r = (pb.linear_periods(p) - targets) / sig
        except BifilarError:
            return math.inf, None
        return (float(r @ r) if np.all(np.isfinite(r)) else math.inf), r

    c, res = cost(p)
    if not math.isfinite(c):
        raise ConvergenceError("the model has no period for a measured mode at the prior")
    for it in range(max_iter):
        J = pb.jacobian(p) / sig[:, None] * sc[None, :]
        _check_identifiable(pb, J)
        step = -np.linalg.lstsq(J, res, rcond=None)[0] * sc
        t = 1.0
        for _ in range(30):
            pn = p + t * step
            if _physical(pb, pn):
                cn, rn = cost(pn)
                if cn <= c * (1 + 1e-12) or cn < 1e-24:
                    break
            t *= 0.5
        else:
            # the Gauss-Newton direction descends unless the misfit is at the
            # rounding floor of the periods (~1e-13 relative): converged
            if np.max(np.abs(step) / sc) < 1e-6:
                break
            raise ConvergenceError("Gauss-Newton found no step that lowers the misfit")
        small = np.max(np.abs(t * step) / sc) < 1e-12
        p, c, res = pn, cn, rn
        if small:
            break
    return p


def _physical(pb: Problem, p) -> bool:
    I = pb.models[0].inertia_ref(pb.values(p))
    return bool(np.linalg.eigvalsh(I)[0] > 0)


def _check_identifiable(pb: Problem, Js: np.ndarray) -> None:
    s = np.linalg.svd(Js, compute_uv=False)
    if s.size and (s[-1] <= 1e-9 * s[0] or not np.all(np.isfinite(s))):
        _, _, Vt = np.linalg.svd(Js)
        v = Vt[-1]
        worst = [pb.unknowns[i] for i in np.argsort(-np.abs(v))[:2]]
        raise InputError("--solve-for", f"the measured periods cannot separate {' and '.join(worst)} "
                                        "(their effects on the periods are (nearly) the same or zero): add "
                                        "modes or hangings that tell them apart, or solve for fewer components")


def solve_nonlinear(pb: Problem, p_lin: np.ndarray, rtol: float = 1e-10, tol: float = 1e-9,
                    max_sims: int = 6, progress=None) -> Estimate:
    """Fixed point ``p = solve_linear(T_meas / r(p))`` with the amplitude
    factors ``r`` simulated at each iterate (measurements without an
    amplitude keep r = 1)."""
    K = len(pb.measurements)
    r = np.ones(K)
    p = np.asarray(p_lin, float)
    sc = pb.scales()
    sims = [None] * K
    it = 0
    for it in range(1, max_sims + 1):
        vals = pb.values(p)
        for k, m in enumerate(pb.measurements):
            if m.amplitude:
                r[k], sims[k] = amplitude_factor(pb.models[m.hanging], vals, pb.mode_index[k], m.amplitude,
                                                 m.cycles, rtol)
            if progress:
                progress(it - 1 + (k + 1) / K, 3)
        pn = solve_linear(pb, _targets(pb, r), p0=p)
        done = np.max(np.abs(pn - p) / sc) < tol
        p = pn
        if done:
            break
    return Estimate(p, "nonlinear", r.copy(), it, sims)


# ---------------------------------------------------------------------------
# the result
# ---------------------------------------------------------------------------

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
    problem: Problem | None = field(default=None, repr=False)
    sims: list = field(default_factory=list, repr=False)

    @property
    def std(self) -> np.ndarray:
        return self.budget.std

    def value(self, name: str) -> float:
        return float(self.values[self.names.index(name)])

    def sigma(self, name: str) -> float:
        return float(self.std[self.names.index(name)])

    def to_json(self) -> dict:
        inertia, com = {}, {}
        for i, n in enumerate(self.names):
            d = {"value": float(self.values[i]), "std": float(self.std[i])}
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
            top = sorted(sh, key=lambda k: -sh[k])[:12]
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
            "assumed_uncertainty": self.uncertainty,
            "degenerate_inputs": self.degenerate_inputs,
            "monte_carlo": self.monte_carlo.to_json() if self.monte_carlo is not None else None,
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "runtime_s": self.runtime,
        }
        if com:
            doc["com"] = com
        return doc


def _assumed(unc: dict) -> dict:
    from .uncertainty import UNCERTAINTY_KEYS

    return {k: {"value": unc[k], "unit": UNCERTAINTY_KEYS[k]} for k in UNCERTAINTY_KEYS if k in unc}


def invert(ms: MeasurementSet, *, method: str | None = None, solve_for: list | None = None,
           unc: dict | None = None, monte_carlo: int | None = None, seed: int | None = None,
           ladder: bool = True, rtol: float = 1e-10, progress=None, journal=None,
           resume: bool = False) -> InversionResult:
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

    Raises
    ------
    InputError : unknown mode, a period no inertia can produce (message
        gives the achievable range), unidentifiable unknowns, a rung that
        does not apply when forced.
    ConvergenceError : a solver failed.
    """
    t0 = time.perf_counter()
    method = method or ms.method or "auto"
    if method not in ("auto",) + METHODS:
        raise InputError("--method", f"unknown method {method!r}; choose auto, {', '.join(METHODS)}")
    unc_all = default_uncertainty({**ms.uncertainty, **(unc or {})})
    warnings: list[str] = []
    notes: list[str] = list(ms.notes)
    pb = build_problem(ms, solve_for or ms.solve_for, unc_all)
    pb.unc = unc_all
    K, P = len(pb.measurements), len(pb.unknowns)
    scalar = K == 1 and P == 1
    has_amp = any(m.amplitude for m in pb.measurements)
    best = "nonlinear" if has_amp else "linear"
    if method == "auto":
        method = best
    if method in ("small-angle", "thesis") and not scalar:
        raise InputError("--method", f"{method} estimates one component from one period; this problem has "
                                     f"{P} unknown(s) and {K} period(s): use linear or nonlinear")
    if method == "nonlinear" and not has_amp:
        raise InputError("--method", "the nonlinear method needs the oscillation amplitude (--amplitude)")
    for m in pb.measurements:
        if m.amplitude is None and has_amp:
            notes.append(f"no amplitude for mode '{m.label}': treated as small (no amplitude correction)")
    if not has_amp:
        notes.append("no amplitude given: periods are treated as small-amplitude (linear) periods; "
                     "give --amplitude for the nonlinear correction")
    for m in pb.measurements:
        if m.source != "signal":
            notes.append(f"mode '{m.label}': damping unknown (timed period); a damping ratio zeta lengthens "
                         "the period by 1/sqrt(1-zeta^2), ~zeta^2/2 (5e-5 for zeta = 0.01)")
            break

    # -- the ladder -------------------------------------------------------
    p_lin = solve_linear(pb)
    rungs: dict[str, dict] = {}
    rungs["linear"] = {"p": p_lin, "r": np.ones(K)}
    est_nl = None
    if has_amp and (method == "nonlinear" or ladder or method != best):
        est_nl = solve_nonlinear(pb, p_lin, rtol=rtol, progress=progress)
        rungs["nonlinear"] = {"p": est_nl.p, "r": est_nl.r, "iterations": est_nl.iterations}
        for s in est_nl.sims:
            if s is not None:
                warnings.extend(f"nonlinear simulation: {w}" for w in s.warnings)
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

    # -- the budget -------------------------------------------------------
    budget, degenerate, T_lin_hat = _budget(pb, p_hat, r_hat, method, rungs, best, unc_all)
    if degenerate:
        warnings.append("these inputs have no derivative here (the scene is degenerate: a neutral mode, e.g. the "
                        "CoM on the line through two attachment points) and are left out of the budget: "
                        + ", ".join(degenerate))
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
    for i, n in enumerate(pb.unknowns):
        if n in _IDX:
            I = pb.models[0].inertia_ref(pb.values(p_hat))
            if not triangle_ok(I):
                warnings.append(f"with {n} = {p_hat[i]:.6g} and the other components at their prior the tensor "
                                "violates the triangle inequality (no real body has it): check the config's "
                                "inertia or solve for more components")
                break
    res = InversionResult(list(pb.unknowns), np.asarray(p_hat, float), budget, method, best, ladder_rows,
                          list(pb.measurements), list(ms.hangings), T_lin_hat, np.asarray(r_hat, float),
                          _assumed(unc_all), degenerate, warnings, notes, problem=pb,
                          sims=(est_nl.sims if est_nl is not None else []))
    n_mc = ms.monte_carlo if monte_carlo is None else monte_carlo
    if n_mc:
        if journal is not None:
            res.monte_carlo = monte_carlo_journaled(res, n_mc, journal, seed=seed if seed is not None else ms.seed,
                                                    resume=resume, progress=progress)
        else:
            res.monte_carlo = monte_carlo_check(res, n_mc, np.random.default_rng(seed if seed is not None else ms.seed),
                                                progress=progress)
        bad = [n for i, n in enumerate(res.names)
               if np.isfinite(res.monte_carlo.ratio[i]) and not 0.8 < res.monte_carlo.ratio[i] < 1.25]
        if bad:
            warnings.append(f"Monte Carlo spread differs from the linear std by more than 20 % for {', '.join(bad)}: "
                            "the model is not linear over the input uncertainties; quote the Monte Carlo interval")
    res.runtime = time.perf_counter() - t0
    return res


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


def _budget(pb: Problem, p_hat, r_hat, method, rungs, best, unc):
    """Linear budget at the estimate; returns (LinearBudget, degenerate inputs, T_lin at p_hat)."""
    K, P = len(pb.measurements), len(pb.unknowns)
    vals = pb.values(p_hat)
    T_lin = pb.linear_periods(p_hat)
    Jp = pb.jacobian(p_hat) * r_hat[:, None]
    sig = np.array([m.std for m in pb.measurements])
    multi = len(pb.models) > 1
    cols: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    degenerate: list[str] = []
    solved_com = {n for n in pb.unknowns if n in COM_UNKNOWNS}
    for h, hm in enumerate(pb.models):
        ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
        if not ks:
            continue
        scene = hm.scene(vals)
        rest, ms_h, match = hm.locate(scene)
        names = [n for n in measured_inputs(scene) if not n.startswith("com.")]
        names += list(COM_UNKNOWNS)
        sens, failed = robust_sensitivity(scene, rest, ms_h, names, scheme="forward")
        pre = f"{hm.hanging.name}:" if multi else ""
        degenerate += [pre + n for n in failed]
        for j, n in enumerate(sens.names):
            col = np.zeros(K)
            for k in ks:
                col[k] = sens.jacobian[match[pb.mode_index[k]], j] * r_hat[k]
            if n.startswith("com."):
                # shared: a CoM shift in the reference frame (com_h = R com_ref)
                ax = "xyz".index(n[-1])
                for a in range(3):
                    key = f"com.{'xyz'[a]}"
                    if key in solved_com:
                        continue
                    cols[key] = cols.get(key, np.zeros(K)) + col * hm.R[ax, a]
                    sigmas[key] = input_sigma(scene, key, unc)
            elif n in ("mass", "gravity"):
                cols[n] = cols.get(n, np.zeros(K)) + col
                sigmas[n] = input_sigma(scene, n, unc)
            else:
                cols[pre + n] = col
                sigmas[pre + n] = input_sigma(scene, n, unc)
    in_names = list(cols)
    Jx = np.column_stack([cols[n] for n in in_names]) if in_names else np.zeros((K, 0))
    in_sig = np.array([sigmas[n] for n in in_names])
    G = gain_matrix(Jp, sig)
    extra = {}
    for k, m in enumerate(pb.measurements):
        lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
        if method == "nonlinear" and m.amplitude:
            sA = m.amplitude_std if m.amplitude_std is not None else unc["amplitude"] * m.amplitude
            dT_dA = T_lin[k] * 2 * (r_hat[k] - 1) / m.amplitude
            extra[f"amplitude[{lab}]"] = -G[:, k] * dT_dA * sA
    if method != best and best in rungs and "p" in rungs[best]:
        extra["model bias"] = np.abs(np.asarray(p_hat) - rungs[best]["p"])
    tn = []
    for m in pb.measurements:
        lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
        tn.append(f"timing[{lab}]")
    budget = propagate(list(pb.unknowns), Jp, sig, Jx, in_names, in_sig, extra=extra, timing_names=tn)
    return budget, degenerate, T_lin


# ---------------------------------------------------------------------------
# Monte Carlo check with the full model
# ---------------------------------------------------------------------------

def draw_monte_carlo(res: InversionResult, n: int, rng: np.random.Generator) -> list:
    """``n`` perturbed measurement sets for :func:`monte_carlo_check`: inputs,
    periods and amplitudes drawn from their assumed distributions (centred on
    the measured values); the amplitude factor is scaled as ``r(A) = 1 + (r -
    1)(A/A0)^2`` (nonlinear method) and each drawn period is divided by it,
    so every draw is a linear-model problem.  Inputs left out of the linear
    budget (degenerate) are not perturbed.  A draw that cannot even be built
    is ``None``.  Reproducible for a given generator state."""
    pb = res.problem
    unc = pb.unc
    multi = len(pb.models) > 1
    degenerate = set(res.degenerate_inputs)
    solved_com = {x for x in pb.unknowns if x in COM_UNKNOWNS}
    draws: list = []
    for _ in range(n):
        try:
            # shared inputs: mass (relative), gravity, CoM (reference frame)
            dm = rng.normal(0.0, unc["mass"])
            dg = rng.normal(0.0, unc.get("gravity", 0.0))
            dcom = np.array([0.0 if f"com.{a}" in solved_com or f"com.{a}" in degenerate else rng.normal(0.0, unc["com"])
                             for a in "xyz"])
            hangs = []
            for hm in pb.models:
                s = hm.hanging.scene
                pre = f"{hm.hanging.name}:" if multi else ""
                att = s.attachments - (hm.R @ dcom)[None, :]
                an = s.anchors.copy()
                L = s.lengths.copy()
                for i in range(s.n_wires):
                    if pre + f"length.{i + 1}" not in degenerate:
                        L[i] += rng.normal(0.0, unc["length"])
                    for a in range(3):
                        if pre + f"anchor.{i + 1}.{'xyz'[a]}" not in degenerate:
                            an[i, a] += rng.normal(0.0, unc["position"])
                        if pre + f"attachment.{i + 1}.{'xyz'[a]}" not in degenerate:
                            att[i, a] += rng.normal(0.0, unc["position"])
                s2 = replace(s, mass=s.mass * (1 + dm), gravity=s.gravity * (1 + dg), lengths=L, anchors=an,
                             attachments=att)
                hangs.append(replace(hm.hanging, scene=s2))
            meas = []
            for k, m in enumerate(pb.measurements):
                T = m.period + rng.normal(0.0, m.std)
                r = res.factors[k]
                if m.amplitude and res.method == "nonlinear":
                    sA = m.amplitude_std if m.amplitude_std is not None else unc["amplitude"] * m.amplitude
                    A = m.amplitude + rng.normal(0.0, sA)
                    r = 1 + (r - 1) * (A / m.amplitude) ** 2
                meas.append(replace(m, period=T / r))
            draws.append(MeasurementSet(hangs, meas))
        except BifilarError:
            draws.append(None)
    return draws


def batched_applies(pb: Problem) -> bool:
    """Whether :func:`solve_draws_batched` handles draws of ``pb``: one
    hanging, one measured period, one unknown that is an inertia component."""
    return len(pb.models) == 1 and len(pb.measurements) == 1 and len(pb.unknowns) == 1 and pb.unknowns[0] in _IDX


def solve_draws_loop(res: InversionResult, draws: list, progress=None) -> np.ndarray:
    """(n, P) re-estimates of the unknowns, one :func:`solve_linear` of the
    full perturbed problem per draw (NaN rows: draws whose inversion failed).
    Any problem shape; ~30 ms a draw."""
    pb = res.problem
    out = np.full((len(draws), len(pb.unknowns)), np.nan)
    for it, ms2 in enumerate(draws):
        if ms2 is not None:
            try:
                pb2 = build_problem(ms2, unc=None, like=pb)
                pb2.I_ref0 = pb.I_ref0
                out[it] = solve_linear(pb2, p0=res.values)
            except BifilarError:
                pass
        if progress:
            progress(it + 1, len(draws))
    return out


def _mac_track(base_shapes: np.ndarray, base_M: np.ndarray, shapes: np.ndarray, k0: np.ndarray) -> np.ndarray:
    """Index of the mode of each draw matching mode ``k0[b]`` of the draw's
    base set: :func:`~bifilar.estimation.sensitivity.mac_match` (the MAC
    matrix of all modes, then the best one-to-one assignment, which keeps
    two near-degenerate modes apart where a row-wise argmax would swap
    them), with the MAC matrices of all draws computed at once.

    base_shapes, shapes : (B, K, 6) mode shapes; base_M : (B, 6, 6) mass
    matrices (world chart) of the base sets; k0 : (B,) ints."""
    from scipy.optimize import linear_sum_assignment

    MA = np.einsum("bij,bkj->bki", base_M, base_shapes)  # (B, K, 6)
    num = np.einsum("bki,bli->bkl", MA, shapes) ** 2
    da = np.einsum("bki,bki->bk", base_shapes, MA)
    db = np.einsum("bki,bij,bkj->bk", shapes, base_M, shapes)
    mac = num / np.maximum(da[:, :, None] * db[:, None, :], 1e-300)
    out = np.empty(len(k0), int)
    for q in range(len(k0)):
        _, col = linear_sum_assignment(-mac[q])
        out[q] = col[k0[q]]
    return out


def solve_draws_batched(res: InversionResult, draws: list, progress=None, rtol: float = 1e-12,
                        max_iter: int = 20) -> np.ndarray:
    """(n, 1) re-estimates, all draws solved in lockstep with the batched
    engine (:mod:`bifilar.analysis.batch`); NaN rows: failed draws.  Only for
    problems with :func:`batched_applies`.

    Each draw solves the same equation as :func:`solve_linear` does for it:
    ``T_lin(x) = T_draw`` (s) for the unknown inertia component ``x``
    (kg m^2, reference body axes) in its physical interval, the mode tracked
    as :func:`build_problem` and :class:`HangingModel` track it (MAC against
    the estimate's base modes, then against the draw's own modes at the
    prior).  The rest poses do not depend on the inertia, so they are found
    once (:func:`~bifilar.analysis.batch.rest_poses`, warm-started from the
    estimate's); every iteration then computes the modes of all unconverged
    draws in one :func:`~bifilar.analysis.batch.modes_batch` call and makes
    one secant step per draw on ``f = T^2 - T_draw^2`` (close to linear in an
    inertia), the first slope from a forward difference, steps limited and
    kept inside the interval as :func:`solve_scalar` does, until
    ``|f| <= 2 rtol T_draw^2`` (``|T - T_draw| <= rtol T_draw``).  A draw
    whose rest pose fails, whose mode has no period, or that has not
    converged after ``max_iter`` steps is dropped (NaN), as the loop drops
    draws that raise.  Where the measured mode nearly coincides with another
    one, the tracked period can jump (avoided crossing) with no root; the
    loop's Brent step then returns the jump's location, this path drops the
    draw (no inertia gives ``|T - T_draw| <= rtol T_draw``)."""
    from ..analysis.batch import modes_batch, rest_poses

    pb = res.problem
    if not batched_applies(pb):
        raise ValueError("solve_draws_batched needs one hanging, one period and one inertia unknown")
    hm = pb.models[0]
    name = pb.unknowns[0]
    i, j = _IDX[name]
    R = hm.R
    I0 = np.asarray(pb.I_ref0, float)
    I0w = R @ I0 @ R.T
    n = len(draws)
    out = np.full((n, 1), np.nan)
    ok = [b for b, d in enumerate(draws) if d is not None]
    scenes0 = [replace(draws[b].hangings[0].scene, inertia=I0w) for b in ok]
    targets = np.array([draws[b].measurements[0].period for b in ok], float)
    rests = rest_poses(scenes0, hm.rest0, errors="return") if scenes0 else []
    keep = [q for q, r in enumerate(rests) if not isinstance(r, BaseException)]
    ok = [ok[q] for q in keep]
    scenes0 = [scenes0[q] for q in keep]
    rests = [rests[q] for q in keep]
    targets = targets[keep]
    B = len(ok)
    if B == 0:
        if progress:
            progress(n, n)
        return out

    def shapes_of(mss):
        return np.array([[m.shape for m in ms.modes] for ms in mss])

    # the draws' own base modes (at the prior inertia) and the measured mode in them
    ms0 = _modes_or_none(modes_batch, scenes0, rests)
    alive = np.array([m is not None for m in ms0])
    nk = len(hm.modes0.modes)
    alive &= np.array([m is not None and len(m.modes) == nk for m in ms0])
    S0 = np.zeros((B, nk, 6))
    M0 = np.zeros((B, 6, 6))
    for b in np.nonzero(alive)[0]:
        S0[b] = shapes_of([ms0[b]])[0]
        M0[b] = ms0[b].mass_matrix
    Sbase = np.broadcast_to(np.array([m.shape for m in hm.modes0.modes]), (B, nk, 6))
    Mbase = np.broadcast_to(hm.modes0.mass_matrix, (B, 6, 6))
    k0 = _mac_track(Sbase, Mbase, S0, np.full(B, pb.mode_index[0]))

    def f_of(idx: np.ndarray, x: np.ndarray) -> np.ndarray:
        """T^2 - target^2 (s^2) of draws ``idx`` at component values ``x``."""
        if not len(idx):
            return np.zeros(0)
        I = np.broadcast_to(I0, (len(idx), 3, 3)).copy()
        I[:, i, j] = x
        I[:, j, i] = x
        Iw = R @ I @ R.T
        scs = [replace(scenes0[b], inertia=Iw[q]) for q, b in enumerate(idx)]
        mss = _modes_or_none(modes_batch, scs, [rests[b] for b in idx])
        T = np.full(len(idx), np.nan)
        good = [q for q, m in enumerate(mss) if m is not None and len(m.modes) == nk]
        if good:
            g = np.array(good)
            kk = _mac_track(S0[idx[g]], M0[idx[g]], shapes_of([mss[q] for q in good]), k0[idx[g]])
            for q, k in zip(good, kk):
                per = mss[q].modes[k].period
                T[q] = per if per else np.nan
        return T * T - targets[idx] ** 2

    lo, hi = physical_interval(I0, name)
    scale = float(pb.scales()[0])
    margin = 1e-9 * scale
    lo_m = lo + margin if math.isfinite(lo) else -math.inf
    hi_m = hi - margin if math.isfinite(hi) else math.inf
    x0 = float(res.values[0])
    if math.isfinite(lo_m) or math.isfinite(hi_m):
        x0 = min(max(x0, lo_m + margin), hi_m - margin)
    tol = 2 * rtol * targets ** 2
    h = 1e-6 * scale
    xh0 = x0 - h if x0 + h >= hi_m else x0 + h
    # first evaluation: x0 and x0 + h for every draw, in one batched call
    idx = np.nonzero(alive)[0]
    fb = f_of(np.concatenate([idx, idx]), np.concatenate([np.full(len(idx), x0), np.full(len(idx), xh0)]))
    x = np.full(B, x0)
    fx = np.full(B, np.nan)
    fx[idx] = fb[:len(idx)]
    d = np.full(B, np.nan)
    d[idx] = (fb[len(idx):] - fb[:len(idx)]) / (xh0 - x0)
    alive &= np.isfinite(fx)
    result = np.full(B, np.nan)
    done = alive & (np.abs(fx) <= tol)
    result[done] = x[done]
    active = alive & ~done
    xt = np.full(B, np.nan)  # trial points

    def newton(a):
        with np.errstate(all="ignore"):
            good = (d[a] != 0) & np.isfinite(d[a])
            xn = np.where(good, x[a] - fx[a] / np.where(good, d[a], 1.0), x[a] + np.where(fx[a] < 0, 10, -10) * scale)
            xn = np.clip(xn, x[a] - 100 * scale, x[a] + 100 * scale)
            xn = np.where(xn <= lo_m, x[a] - 0.9 * (x[a] - lo_m), xn)
            xn = np.where(xn >= hi_m, x[a] + 0.9 * (hi_m - x[a]), xn)
        return xn

    a = np.nonzero(active)[0]
    xt[a] = newton(a)
    for _ in range(max_iter):
        a = np.nonzero(active)[0]
        if not len(a):
            break
        if progress:
            progress(n - len(a), n)
        ft = f_of(a, xt[a])
        fin = np.isfinite(ft)
        conv = fin & (np.abs(ft) <= tol[a])
        result[a[conv]] = xt[a[conv]]
        active[a[conv]] = False
        # no period at the trial point: halve the step
        bad = a[~fin]
        xt[bad] = 0.5 * (x[bad] + xt[bad])
        # secant update where the trial point has a period but is not yet a root
        up = a[fin & ~conv]
        fu = ft[fin & ~conv]
        stalled = xt[up] == x[up]
        active[up[stalled]] = False
        up, fu = up[~stalled], fu[~stalled]
        d[up] = (fu - fx[up]) / (xt[up] - x[up])
        x[up], fx[up] = xt[up], fu
        xt[up] = newton(up)
    out[np.array(ok), 0] = result
    if progress:
        progress(n, n)
    return out


def _modes_or_none(modes_batch, scenes, rests) -> list:
    """modes_batch, or scene by scene with None for scenes whose modes fail."""
    try:
        return modes_batch(scenes, rests)
    except (np.linalg.LinAlgError, BifilarError):
        out = []
        for s, r in zip(scenes, rests):
            try:
                out.append(modes_batch([s], [r])[0])
            except (np.linalg.LinAlgError, BifilarError):
                out.append(None)
        return out


def monte_carlo_journaled(res: InversionResult, n: int, journal, *, seed: int | None = None, resume: bool = False,
                          chunk: int = 100, progress=None, stop_after: int | None = None) -> MonteCarloSummary:
    """:func:`monte_carlo_check` in chunks of ``chunk`` draws, each appended to
    the JSON-lines file ``journal`` as it finishes, so an interrupted run keeps
    what it finished and ``resume=True`` continues it with identical results.

    Chunk c draws from its own generator, spawned from ``seed`` (stored in the
    journal's first line with a key of the problem), so the draws do not depend
    on which chunks ran in which session.  ``stop_after``: finish at most that
    many chunks in this call (tests simulate an interruption with it).
    """
    import hashlib
    import json
    from pathlib import Path

    from ..errors import InputError
    from ..output import JournalWriter, read_journal

    path = Path(journal)
    key = hashlib.sha256(json.dumps([list(res.names), [float(v) for v in res.values], [float(v) for v in res.std],
                                     int(n), int(chunk), res.method], sort_keys=True).encode()).hexdigest()[:16]
    n_chunks = (n + chunk - 1) // chunk
    done: dict[int, np.ndarray] = {}
    if path.exists():
        if not resume:
            raise InputError("--journal", f"{path} exists; pass --resume to continue it or choose another name")

        def check_header(head) -> None:
            if not isinstance(head, dict) or head.get("kind") != "bifilar-monte-carlo" or type(head.get("seed")) is not int:
                raise InputError("--journal", f"{path} is not a bifilar Monte Carlo journal")
            if head.get("key") != key:
                raise InputError("--journal", f"{path} belongs to another problem or settings; it cannot be resumed here")

        def is_record(rec) -> bool:
            return (isinstance(rec, dict) and type(rec.get("chunk")) is int and 0 <= rec["chunk"] < n_chunks
                    and isinstance(rec.get("samples"), list)
                    and all(isinstance(row, list) and len(row) == len(res.names)
                            and all(v is None or type(v) in (int, float) for v in row) for row in rec["samples"]))

        head, records = read_journal(path, check_header, is_record)
        if not head:
            raise InputError("--journal", f"{path} is not a bifilar Monte Carlo journal")
        if seed is not None and seed != head["seed"]:
            raise InputError("--seed", f"differs from the journal's seed {head['seed']}")
        seed = int(head["seed"])
        for rec in records:
            done[int(rec["chunk"])] = np.array([[np.nan if v is None else v for v in row] for row in rec["samples"]],
                                               float).reshape(-1, len(res.names))
        writer = JournalWriter(path, None, append=True)
    else:
        if resume:
            raise InputError("--resume", f"no journal {path} to resume")
        if seed is None:
            seed = int(np.random.SeedSequence().entropy % 2**63)
        writer = JournalWriter(path, {"kind": "bifilar-monte-carlo", "key": key, "seed": seed, "n": n, "chunk": chunk},
                               append=False)
    sizes = [min(chunk, n - c * chunk) for c in range((n + chunk - 1) // chunk)]
    children = np.random.SeedSequence(seed).spawn(len(sizes))
    ran = 0
    try:
        for c, size in enumerate(sizes):
            if c in done:
                continue
            if stop_after is not None and ran >= stop_after:
                break
            draws = draw_monte_carlo(res, size, np.random.default_rng(children[c]))
            use_batch = batched_applies(res.problem)
            est = solve_draws_batched(res, draws, None) if use_batch else solve_draws_loop(res, draws, None)
            done[c] = est
            writer.add({"chunk": c, "samples": [[None if not np.isfinite(v) else float(v) for v in row] for row in est]})
            ran += 1
            if progress:
                progress(sum(len(v) for v in done.values()), n)
    finally:
        writer.close()
    est = np.concatenate([done[c] for c in sorted(done)]) if done else np.zeros((0, len(res.names)))
    good = np.all(np.isfinite(est), axis=1)
    return summarise(list(res.problem.unknowns), est[good], res.std, sum(len(v) for v in done.values()))


def monte_carlo_check(res: InversionResult, n: int, rng: np.random.Generator, progress=None,
                      batched: bool | None = None) -> MonteCarloSummary:
    """Re-estimate the unknowns ``n`` times with inputs, periods and
    amplitudes drawn from their assumed distributions (:func:`draw_monte_carlo`),
    each time solving the full (not linearised) model: the rest pose, modes
    and root finding / Gauss-Newton of the perturbed scene.

    One hanging, one period and one inertia unknown (the common case) go
    through the batched engine, all draws at once
    (:func:`solve_draws_batched`, 8-15x faster: docs/performance.md); anything else, or
    ``batched=False``, draw by draw (:func:`solve_draws_loop`).  Draws
    whose inversion fails are counted in ``failed``."""
    draws = draw_monte_carlo(res, n, rng)
    use_batch = batched_applies(res.problem) if batched is None else bool(batched)
    est = solve_draws_batched(res, draws, progress) if use_batch else solve_draws_loop(res, draws, progress)
    good = np.all(np.isfinite(est), axis=1)
    return summarise(list(res.problem.unknowns), est[good], res.std, n)


# ---------------------------------------------------------------------------
# plots
# ---------------------------------------------------------------------------

def plot_inversion(res: InversionResult, path, span: float | None = None) -> None:
    """Period against each unknown (others at their estimate) for every
    measured mode, with the measurement (and its +-1 sigma band) and the
    estimate marked; the small-angle curve too when it applies.
    matplotlib (Agg) is imported here."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    pb = res.problem
    K = len(pb.measurements)
    ncol = min(K, 3)
    nrow = math.ceil(K / ncol)
    fig = Figure(figsize=(5.2 * ncol, 4.0 * nrow), constrained_layout=True)
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False)).ravel()
    Jp = pb.jacobian(res.values)
    for k, m in enumerate(pb.measurements):
        ax = axes[k]
        j = int(np.argmax(np.abs(Jp[k]) * pb.scales()))
        name = pb.unknowns[j]
        x_hat = res.values[j]
        sd = res.std[j]
        w = span if span is not None else max(6 * sd, 0.05 * abs(x_hat) if x_hat else 0.05 * pb.scales()[j])
        xs = np.linspace(x_hat - w, x_hat + w, 41)
        if name in _IDX:
            lo, hi = physical_interval(pb.models[0].inertia_ref(pb.values(res.values)), name)
            xs = xs[(xs > lo) & (xs < hi)]
        Ts = []
        for x in xs:
            p = res.values.copy()
            p[j] = x
            try:
                Ts.append(pb.linear_periods(p)[k])
            except BifilarError:
                Ts.append(np.nan)
        Ts = np.array(Ts)
        ax.plot(xs, Ts, color="C0", label="linear model")
        if res.factors[k] != 1.0:
            ax.plot(xs, Ts * res.factors[k], color="C3", label=f"nonlinear (amplitude {m.amplitude:.3g})")
        sa = next((r for r in res.ladder if r["method"] == "small-angle" and r.get("applicable")), None)
        if sa is not None and K == 1:
            # T_sa ~ sqrt(I_vertical), I_vertical = I_v(x_sa) + coefficient (x - x_sa)
            geo = sa["geometry"]
            x_sa = sa["values"][name]
            Iv = geo["I_vertical"] + geo["coefficient"] * (xs - x_sa)
            ax.plot(xs, m.period * np.sqrt(np.clip(Iv, 0, None) / geo["I_vertical"]), color="C2", ls="--",
                    label="small-angle formula")
        ax.axhline(m.period, color="k", lw=0.8, label="measured")
        ax.axhspan(m.period - m.std, m.period + m.std, color="0.85", zorder=0)
        ax.axvline(x_hat, color="C1", lw=0.8, label=f"estimate {x_hat:.6g}")
        ax.axvspan(x_hat - sd, x_hat + sd, color="C1", alpha=0.15, zorder=0)
        ax.set_xlabel(f"{name} [{'kg m^2' if name in _IDX else 'm'}]")
        ax.set_ylabel("period [s]")
        ax.set_title(f"{pb.models[m.hanging].hanging.name}: {m.label}")
        ax.legend(fontsize=7)
    for ax in axes[K:]:
        ax.set_visible(False)
    fig.savefig(str(path), dpi=110)
