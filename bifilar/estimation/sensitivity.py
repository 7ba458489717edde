"""Sensitivities of the linear mode periods to every scene input, and the
linear uncertainty budget of an inertia estimate.

The inputs an experimenter measures (SI units) are named like this:

* ``Ixx Iyy Izz Ixy Ixz Iyz``: inertia tensor components, body axes, kg m^2;
* ``mass`` (kg), ``gravity`` (m/s^2);
* ``length.i`` wire i (1-based) length, m;
* ``anchor.i.x`` (``.y``, ``.z``): ceiling point coordinates, world frame, m;
* ``attachment.i.x`` ...: body point coordinates, body frame, m;
* ``com.x`` ...: position of the CoM relative to the attachment points, m
  (moving the CoM by +d moves every attachment by -d in the body frame);
* ``stiffness``: one relative factor on every wire's axial stiffness EA
  (``rig.stiffness``; +d scales each EA_i by 1 + d), dimensionless; an input
  only of a scene that states EA (docs/design.md "eaunc, session 18").

Sensitivities are analytic (:mod:`bifilar.analysis.derivatives`: implicit
differentiation of the rest pose and first-order eigenvalue perturbation, at
one rest pose), with central finite differences of the exact linear periods
(:func:`bifilar.analysis.modes.linear_modes`, accurate to ~1e-13, so a
relative step of ~1e-6 leaves an error of ~1e-9 in each derivative) as the
reference and the fallback where no analytic derivative exists.  Modes are
tracked across a finite-difference perturbation by the modal assurance
criterion (MAC) so that two modes that swap order (torsion and roll near
coincidence) are not confused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.equilibrium import RestPose, rest_pose
from ..analysis.modes import ModeSet, linear_modes
from ..scene import Scene, scene_with

INERTIA_COMPONENTS = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}
_AX = {"x": 0, "y": 1, "z": 2}

#: default standard uncertainties of measured inputs (stated in every output)
DEFAULT_UNCERTAINTY = {
    "length": 1e-3,       # m, each wire length (tape measure)
    "position": 1e-3,     # m, each coordinate of every anchor and attachment point
    "mass": 1e-3,         # relative (scale accuracy 0.1 %)
    "com": 2e-3,          # m, each coordinate of the CoM relative to the attachments
    "gravity": 0.0,       # relative; local g is usually known to 1e-4 or better
    "timing": 1e-3,       # s, standard uncertainty of one measured period (if not given)
}

#: the default relative standard uncertainty of the wires' axial stiffness EA, where ``rig.stiffness`` is
#: stated (a steel rope's effective modulus, a fibre line's creep: 5-20 %); not in
#: :data:`DEFAULT_UNCERTAINTY`, so that a scene without EA lists and budgets nothing new.  One factor shared by
#: every wire (the wires cut from one line: its modulus's error is common to them)
DEFAULT_STIFFNESS_REL = 0.1

#: the input uncertainty keys a planner (sweep, plan: ``--sigma``, the config's ``uncertainty:`` block,
#: ``uncertainty.KEY`` parameters) takes: the defaults' and EA's
PLANNER_UNCERTAINTY_KEYS = tuple(DEFAULT_UNCERTAINTY) + ("stiffness",)

#: the largest standard uncertainty each kind of input may be given (its unit
#: as in :data:`DEFAULT_UNCERTAINTY`): a length's at most the longest length a
#: config holds (1e5 m, ``bifilar.parts.MAX_SIZE``), a time's 1e5 s, a
#: relative one 1 (100 % of the quantity, which is positive).  Beyond them a
#: budget says nothing, and far beyond (1e160) its squares overflowed:
#: ``invert`` ended in exit 1 (an internal error) and ``sweep`` printed
#: overflow warnings
MAX_UNCERTAINTY = {"length": 1e5, "position": 1e5, "com": 1e5, "mass": 1.0, "gravity": 1.0, "amplitude": 1.0,
                   "timing": 1e5, "trial_time": 1e5, "release": 1e5, "inertia": 1.0,
                   "stiffness": 0.5}  # EA's: the sigma points at sqrt(3) of it keep every EA positive


def uncertainty_too_large(key: str, value: float) -> str | None:
    """The refusal (text) of a standard uncertainty ``value`` of input
    ``key`` above :data:`MAX_UNCERTAINTY`, None when it is within it."""
    hi = MAX_UNCERTAINTY.get(key)
    if hi is None or value <= hi:
        return None
    unit = {"mass": "relative", "gravity": "relative", "amplitude": "relative", "inertia": "relative",
            "stiffness": "relative", "timing": "s", "trial_time": "s"}.get(key, "m")
    what = "(100 % of the quantity)" if unit == "relative" else "(beyond it a budget says nothing)"
    if key == "stiffness":
        what = "(the budget's sigma points at sqrt(3) of it must keep every EA positive)"
    return f"{key} must be at most {hi:g} {unit} {what}, got {value:g}"


def perturb(scene: Scene, name: str, delta: float) -> Scene:
    """Return ``scene`` with input ``name`` changed by ``delta`` (SI units)."""
    if name in _IDX:
        i, j = _IDX[name]
        I = scene.inertia.copy()
        I[i, j] += delta
        if i != j:
            I[j, i] += delta
        return scene_with(scene, inertia=I)
    if name == "mass":
        return scene_with(scene, mass=scene.mass + delta)
    if name == "gravity":
        return scene_with(scene, gravity=scene.gravity + delta)
    if name == "stiffness":  # a relative change of every wire's EA (a scene without EA has none to change)
        if scene.stiffness is None:
            return scene
        return scene_with(scene, stiffness=np.asarray(scene.stiffness, float) * (1.0 + delta))
    parts = name.split(".")
    if parts[0] == "length":
        L = scene.lengths.copy()
        L[int(parts[1]) - 1] += delta
        return scene_with(scene, lengths=L)
    if parts[0] in ("anchor", "attachment"):
        arr = (scene.anchors if parts[0] == "anchor" else scene.attachments).copy()
        arr[int(parts[1]) - 1, _AX[parts[2]]] += delta
        return scene_with(scene, **{"anchors" if parts[0] == "anchor" else "attachments": arr})
    if parts[0] == "com":
        arr = scene.attachments.copy()
        arr[:, _AX[parts[1]]] -= delta
        return scene_with(scene, attachments=arr)
    raise KeyError(f"unknown input {name!r}")


def input_value(scene: Scene, name: str) -> float:
    """Current value of input ``name`` (0 for ``com.*`` and ``stiffness``, which are shifts)."""
    if name in _IDX:
        return float(scene.inertia[_IDX[name]])
    if name in ("mass", "gravity"):
        return float(getattr(scene, name))
    parts = name.split(".")
    if parts[0] == "length":
        return float(scene.lengths[int(parts[1]) - 1])
    if parts[0] == "anchor":
        return float(scene.anchors[int(parts[1]) - 1, _AX[parts[2]]])
    if parts[0] == "attachment":
        return float(scene.attachments[int(parts[1]) - 1, _AX[parts[2]]])
    if parts[0] in ("com", "stiffness"):
        return 0.0
    raise KeyError(name)


def measured_inputs(scene: Scene) -> list[str]:
    """All geometric and mass inputs an experimenter measures."""
    names = ["mass"]
    n = scene.n_wires
    names += [f"length.{i + 1}" for i in range(n)]
    names += [f"anchor.{i + 1}.{a}" for i in range(n) for a in "xyz"]
    names += [f"attachment.{i + 1}.{a}" for i in range(n) for a in "xyz"]
    names += [f"com.{a}" for a in "xyz"]
    return names


def input_sigma(scene: Scene, name: str, unc: dict | None = None) -> float:
    """Standard uncertainty of input ``name`` from a dict like :data:`DEFAULT_UNCERTAINTY`."""
    unc = unc or {}

    def u(key):  # unc's value, else the default (as {**DEFAULT_UNCERTAINTY, **unc}[key], without the merge)
        return unc[key] if key in unc else DEFAULT_UNCERTAINTY[key]

    if name == "mass":
        return u("mass") * scene.mass
    if name == "gravity":
        return u("gravity") * scene.gravity
    if name == "stiffness":  # relative; only where EA is stated (default DEFAULT_STIFFNESS_REL there)
        return 0.0 if scene.stiffness is None else float(unc.get("stiffness", DEFAULT_STIFFNESS_REL))
    head = name.split(".")[0]
    if head == "length":
        return u("length")
    if head in ("anchor", "attachment"):
        return u("position")
    if head == "com":
        return u("com")
    return 0.0  # inertia components: the unknowns


def stiffness_step(rel_step: float) -> float:
    """The finite-difference step of the ``stiffness`` factor for a relative
    step ``rel_step`` of the other inputs: ``100 rel_step``, at most 0.01.
    A relative change ``d`` of EA moves the loaded lengths by only ``strain
    x d`` of themselves (strain 1e-5 .. 1e-2), so the lengths' ``rel_step``
    (1e-6) would move the periods by ~1e-10 of themselves, near the rest
    pose's and the eigen-solve's rounding; 1e-4 leaves a forward
    difference's truncation ~1e-4 of the derivative (``1 / (1 + d)`` is
    smooth) and its rounding ~2e-9 / strain of it."""
    return min(100.0 * rel_step, 1e-2)


def stiff_inputs(scene: Scene, unc: dict | None) -> list[str]:
    """``["stiffness"]`` where ``scene`` states EA and its uncertainty
    (``unc``, default :data:`DEFAULT_STIFFNESS_REL`) is not 0, else ``[]``:
    the budgeted inputs beyond :func:`measured_inputs`."""
    return ["stiffness"] if input_sigma(scene, "stiffness", unc) > 0 else []


def _mac_base(base: ModeSet) -> tuple:
    """The base side of :func:`_mac_assignment`'s MAC matrix: (A @ M, the
    diagonal A M A^T, M) of ``base``'s shapes A (k, 6) and mass matrix M
    (6, 6, world chart); one tuple serves every ``other`` matched to
    ``base`` (:func:`period_matcher`), with the same products as computed
    per call (``A @ M @ B.T`` is ``(A @ M) @ B.T``)."""
    M = base.mass_matrix
    A = np.array([m.shape for m in base.modes])
    return A @ M, np.einsum("ij,jk,ik->i", A, M, A), M


def _mac_assignment(base: ModeSet, other: ModeSet, side: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(rows into ``base.modes``, columns into ``other.modes``) of the best
    one-to-one MAC matching; every mode of the smaller set is matched.
    ``side``: :func:`_mac_base` of ``base`` if already computed."""
    from scipy.optimize import linear_sum_assignment

    AM, da, M = _mac_base(base) if side is None else side
    B = np.array(_shapes(other))
    num = (AM @ B.T) ** 2
    den = np.outer(da, np.einsum("ij,jk,ik->i", B, M, B))
    mac = num / np.maximum(den, 1e-300)
    return linear_sum_assignment(-mac)


def mac_match(base: ModeSet, other: ModeSet) -> np.ndarray:
    """Index into ``other.modes`` of the mode matching each base mode (MAC)."""
    return _mac_assignment(base, other)[1]


def n_modes(ms: ModeSet) -> int:
    """Number of modes of ``ms`` (a :class:`~bifilar.analysis.modes.LazyModeSet`'s without building them)."""
    P = getattr(ms, "periods", None)
    return len(P) if P is not None else len(ms.modes)


def _shapes(ms: ModeSet):
    """The shapes of ``ms``'s modes, (k, 6) (a LazyModeSet's without building its modes: the same numbers)."""
    S = getattr(ms, "shapes", None)
    return S if S is not None else [m.shape for m in ms.modes]


def mac_matches(base: ModeSet, others: list) -> list:
    """:func:`mac_match` of ``base`` with each of ``others``, the MAC
    matrices of those with as many modes as ``base`` in one stacked product
    (the rest one by one).  The products are grouped as in
    :func:`_mac_assignment` (the MAC matrices came out bit for bit the same
    on 93 sigma-point scenes of five rigs); a stacked product could round
    differently in the last bits on another BLAS, which moves no assignment
    but an exact tie's (tests/test_point_cost.py: the same assignments)."""
    from scipy.optimize import linear_sum_assignment

    k = len(base.modes)
    same = [q for q, o in enumerate(others) if n_modes(o) == k]
    out = [None] * len(others)
    if same and k:
        AM, da, M = _mac_base(base)
        B = np.array([_shapes(others[q]) for q in same])  # (S, k, 6)
        num = (AM @ np.swapaxes(B, 1, 2)) ** 2
        den = da[None, :, None] * np.einsum("sij,jk,sik->si", B, M, B)[:, None, :]
        mac = num / np.maximum(den, 1e-300)
        for q, m in zip(same, mac):
            out[q] = linear_sum_assignment(-m)[1]
    for q, o in enumerate(others):
        if out[q] is None:
            out[q] = mac_match(base, o)
    return out


def matched_periods(base: ModeSet, other: ModeSet, side: tuple | None = None) -> np.ndarray:
    """Periods (s) of ``other``'s modes in the order of ``base``'s (MAC
    matching), NaN for a neutral mode and for a base mode that ``other`` does
    not have.  The second happens on a rig with four or five wires all taut
    and dependent (a symmetric rig: the rest pose has fewer independent
    constraints than wires): changing one wire's length or point makes the
    wires independent and, with inextensible wires, removes a mode, so that
    mode's period has no derivative with respect to that input.  ``side``:
    :func:`_mac_base` of ``base`` if already computed (:func:`period_matcher`)."""
    out = np.full(len(base.modes), np.nan)
    P = getattr(other, "periods", None)  # a LazyModeSet's, without building its modes (all finite)
    for r, i in zip(*_mac_assignment(base, other, side)):
        out[r] = P[i] if P is not None else (other.modes[i].period if other.modes[i].period else np.nan)
    return out


def period_matcher(base: ModeSet):
    """``f(other)`` = :func:`matched_periods` ``(base, other)`` (s), the MAC's
    base-side products computed once for every call: the same numbers.
    Kept by the caller (not on ``base``: a ModeSet's attributes are in
    invert's pickled run-memo keys)."""
    side = _mac_base(base)
    return lambda other: matched_periods(base, other, side)


def periods_of(scene: Scene, base: ModeSet | None = None, guess: RestPose | None = None) -> np.ndarray:
    """Linear periods (s) in the order of ``base``'s modes (NaN for neutral
    modes and for modes the scene lacks, see :func:`matched_periods`)."""
    rest = rest_pose(scene, guess=guess, local_only=guess is not None)
    ms = linear_modes(scene, rest)
    if base is None:
        return np.array([m.period if m.period else np.nan for m in ms.modes])
    return matched_periods(base, ms)


@dataclass(frozen=True)
class Sensitivity:
    """dT_k/dx_j for every mode k of ``modes`` and every input j of ``names``.

    periods : (K,) s.  jacobian : (K, J) s per unit of input.  A scene on the
    edge of stability (CoM exactly on the attachment line, a neutral mode) has
    inputs whose perturbation one way makes it unable to hang: those are
    differentiated one-sidedly and listed in ``one_sided``.  ``method``:
    how the Jacobian was obtained (:func:`period_sensitivity`).
    """

    names: list[str]
    periods: np.ndarray
    jacobian: np.ndarray
    modes: ModeSet
    rest: RestPose
    one_sided: tuple = ()  # inputs differentiated one-sidedly (one neighbour cannot hang)
    undefined: tuple = ()  # inputs whose neighbours on both sides cannot hang (column NaN)
    method: str = "finite-difference"  # "analytic", or "finite-difference" and why (see period_sensitivity)

    def column(self, name: str) -> np.ndarray:
        return self.jacobian[:, self.names.index(name)]


def period_sensitivity(scene: Scene, names: list[str] | None = None, rel_step: float = 1e-6, *,
                       rest: RestPose | None = None, method: str = "analytic", modes: ModeSet | None = None) -> Sensitivity:
    """Sensitivities dT_k/dx_j (s per unit input) of all linear periods to ``names``.

    ``method="analytic"`` (default): derivatives of the rest pose and of the
    eigenvalues at the one rest pose (:mod:`bifilar.analysis.derivatives`),
    exact to rounding; inputs without a derivative there (a neutral
    direction: the CoM on the attachment line) are differenced as
    :func:`period_sensitivity_fd` does (listed in ``one_sided`` /
    ``undefined``); repeated eigenvalues (a symmetric trifilar's two swings)
    are analytic too (degenerate perturbation theory), and a scene with a
    nearly repeated pair (split 1e-10 .. 1e-8, kept apart by the modes)
    falls back to :func:`period_sensitivity_fd` for the whole Jacobian.  ``method="fd"``: :func:`period_sensitivity_fd`.
    ``rest``: the rest pose of ``scene`` if already known; ``modes``: its
    :func:`~bifilar.analysis.modes.linear_modes` about ``rest`` if already
    solved.  The method used is in ``Sensitivity.method``.
    """
    from ..analysis.derivatives import NotDifferentiable, analytic_period_jacobian

    names = list(names if names is not None else list(INERTIA_COMPONENTS) + measured_inputs(scene))
    if method not in ("analytic", "fd"):
        raise ValueError(f"method must be 'analytic' or 'fd', not {method!r}")
    rest = rest if rest is not None else rest_pose(scene)
    ms = modes if modes is not None else linear_modes(scene, rest)
    T0 = np.array([m.period if m.period else np.nan for m in ms.modes])
    if method == "fd":
        return _fd_sensitivity(scene, names, rel_step, rest, ms, T0, "finite-difference")
    try:
        jac = analytic_period_jacobian(scene, rest, ms, names)
    except NotDifferentiable as exc:
        return _fd_sensitivity(scene, names, rel_step, rest, ms, T0, f"finite-difference ({exc})")
    live = np.isfinite(T0)
    bad = [j for j in range(len(names)) if live.any() and np.all(np.isnan(jac[live, j]))]
    one: tuple = ()
    undef: tuple = ()
    if bad:
        sub = _fd_sensitivity(scene, [names[j] for j in bad], rel_step, rest, ms, T0, "")
        jac[:, bad] = sub.jacobian
        one, undef = sub.one_sided, sub.undefined
    return Sensitivity(names, T0, jac, ms, rest, one, undef, "analytic")


def period_sensitivity_fd(scene: Scene, names: list[str] | None = None, rel_step: float = 1e-6) -> Sensitivity:
    """Central-difference sensitivities of all linear periods to ``names``
    (the reference for :func:`period_sensitivity` and its fallback).

    Steps: relative ``rel_step`` of the input's natural scale (inertia: the
    largest principal moment; lengths and positions: the longest wire; mass,
    gravity: their value).  Each neighbour's rest pose by Newton from the
    base pose, modes matched by MAC.
    """
    return period_sensitivity(scene, names, rel_step, method="fd")


def _fd_sensitivity(scene: Scene, names: list[str], rel_step: float, rest: RestPose, ms: ModeSet, T0: np.ndarray,
                    method: str) -> Sensitivity:
    Jac = np.zeros((len(T0), len(names)))
    Lmax = float(np.max(scene.lengths))
    Imax = float(np.max(np.linalg.eigvalsh(scene.inertia)))
    one: list[str] = []
    undef: list[str] = []
    for j, name in enumerate(names):
        if name in _IDX:
            h = rel_step * Imax
        elif name == "mass":
            h = rel_step * scene.mass
        elif name == "gravity":
            h = rel_step * scene.gravity
        elif name == "stiffness":
            h = stiffness_step(rel_step)
        else:
            h = rel_step * Lmax
        Tp = _periods_or_none(perturb(scene, name, h), ms, rest)
        Tm = _periods_or_none(perturb(scene, name, -h), ms, rest)
        if Tp is not None and Tm is not None:
            Jac[:, j] = (Tp - Tm) / (2 * h)
        elif Tp is not None or Tm is not None:
            one.append(name)
            Jac[:, j] = (Tp - T0) / h if Tp is not None else (T0 - Tm) / h
        else:
            undef.append(name)
            Jac[:, j] = np.nan
    return Sensitivity(names, T0, Jac, ms, rest, tuple(one), tuple(undef), method)


def _periods_or_none(scene: Scene, base: ModeSet, guess: RestPose):
    from ..errors import BifilarError

    try:
        return periods_of(scene, base, guess)
    except BifilarError:
        return None


@dataclass(frozen=True)
class Budget:
    """Linear uncertainty of an inertia component estimated from one mode.

    value_sigma : standard uncertainty of the estimate, kg m^2.
    shares : {input: fraction of the variance}; contributions : {input: sigma
    contribution, kg m^2}; dI_dT : kg m^2 per s; rel_sensitivity : (dI/I) / (dT/T).
    """

    component: str
    mode: str
    value_sigma: float
    contributions: dict
    shares: dict
    dI_dT: float
    rel_sensitivity: float


def inertia_budget(sens: Sensitivity, scene: Scene, component: str, mode_index: int, period_sigma: float,
                   unc: dict | None = None, extra: dict | None = None) -> Budget:
    """Propagate input uncertainties to the estimate of ``component`` from mode ``mode_index``.

    The estimate solves T_k(I_c, x) = T_measured for I_c, so
    dI_c/dT = 1 / (dT_k/dI_c) and dI_c/dx_j = -(dT_k/dx_j) / (dT_k/dI_c).
    ``extra``: additional independent contributions {name: sigma in kg m^2}
    (e.g. amplitude or model bias).
    """
    k = mode_index
    sI = sens.column(component)[k]
    if not np.isfinite(sI) or sI == 0:
        raise ValueError(f"mode {sens.modes.modes[k].label} is insensitive to {component}")
    contrib = {"timing": abs(period_sigma / sI)}
    for j, name in enumerate(sens.names):
        if name in _IDX:
            continue
        s = input_sigma(scene, name, unc)
        if s > 0:
            contrib[name] = abs(sens.jacobian[k, j] * s / sI)
    for name, s in (extra or {}).items():
        contrib[name] = abs(s)
    var = sum(c**2 for c in contrib.values())
    shares = {k2: (c**2 / var if var > 0 else 0.0) for k2, c in contrib.items()}
    Ic = float(scene.inertia[_IDX[component]])
    T = sens.periods[k]
    rel = (T / Ic) / sI if Ic != 0 else float("nan")
    return Budget(component, sens.modes.modes[k].label, float(np.sqrt(var)), contrib, shares, float(1 / sI), float(rel))


def grouped_shares(b: Budget, sigma: float | None = None, linear_var: float | None = None) -> dict:
    """Variance shares grouped by kind: timing, lengths, anchors, attachments, mass, com, other.

    ``sigma`` (kg m^2): the std the shares are of, where it is not the
    linear budget's (the second-order std invert prints, ``linear_var`` the
    linear budget's variance, kg^2 m^4 (default: of ``b.contributions``)).
    Where ``sigma`` exceeds the linear std by more than
    :data:`~bifilar.estimation.second_order.LINEAR_ENOUGH` the linear shares
    are scaled to the linear variance's part of ``sigma^2`` and the rest is
    the group ``second_order`` (a 1 cm deep CoM's tilt from its 2 mm std:
    75 % of a bifilar's Izz variance, none of it in the linear shares;
    docs/design.md, "audit24, session 24")."""
    out: dict[str, float] = {}
    for name, sh in b.shares.items():
        head = name.split(".")[0]
        key = {"length": "lengths", "anchor": "anchors", "attachment": "attachments"}.get(head, head)
        out[key] = out.get(key, 0.0) + sh
    if sigma is None or not np.isfinite(sigma) or sigma <= 0:
        return out
    from .second_order import LINEAR_ENOUGH

    lin = sum(float(c) ** 2 for c in b.contributions.values()) if linear_var is None else float(linear_var)
    if sigma * sigma <= lin * (1.0 + LINEAR_ENOUGH) ** 2:
        return out
    part = lin / (sigma * sigma)
    out = {k: v * part for k, v in out.items()}
    out["second_order"] = 1.0 - part
    return out


def best_mode_for(sens: Sensitivity, component: str) -> int:
    """Index of the mode whose period is most sensitive (relatively) to ``component``."""
    col = np.abs(sens.column(component)) / np.where(np.isfinite(sens.periods), sens.periods, np.inf)
    col = np.where(np.isfinite(col), col, -1)
    return int(np.argmax(col))
