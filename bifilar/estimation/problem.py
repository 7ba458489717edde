"""The inversion problem: hangings of one body as functions of the unknowns.

The unknowns are components of the inertia tensor about the CoM in the
*reference* body axes (``Ixx Iyy Izz Ixy Ixz Iyz``, kg m^2; for one hanging
the config's body axes) and optionally the CoM shift ``com.x com.y com.z``
(m, reference body axes, relative to the attachment points).  Everything not
solved for keeps the config's value (the prior).  Each hanging is a scene of
the same body with ``I_h = R_h I_ref R_h^T``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..analysis.equilibrium import rest_pose
from ..analysis.modes import modes_of_inertia
from ..errors import BifilarError, InputError
from ..scene import TRIANGLE_SLACK, Scene, obeys_triangle, scene_with
from .measurements import COM_UNKNOWNS, SOLVABLE, MeasurementSet
from .sensitivity import INERTIA_COMPONENTS, mac_match
from .uncertainty import default_uncertainty

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


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


def _psd_interval(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    """The closed interval of ``t`` for which ``A + t B`` (symmetric 3x3) is
    positive semi-definite (empty: ``lo > hi``).  Its ends are roots of
    ``det(A + t B) = 0`` (generalised eigenvalues of the pencil); the set is
    an interval because the smallest eigenvalue is concave in ``t``."""
    from scipy.linalg import eigvals

    with np.errstate(all="ignore"):
        ev = eigvals(A, -B)
    sc = max(float(np.max(np.abs(A))), float(np.max(np.abs(B))), 1e-300)
    cand = sorted({float(e.real) for e in ev if np.isfinite(e) and abs(e.imag) <= 1e-9 * max(1.0, abs(e.real))})

    def ok(t: float) -> bool:
        return bool(np.linalg.eigvalsh(A + t * B)[0] >= -1e-12 * sc * max(1.0, abs(t)))

    if not cand:
        return (-math.inf, math.inf) if ok(0.0) else (math.inf, -math.inf)
    probes = [cand[0] - max(1.0, abs(cand[0]))] + [0.5 * (a + b) for a, b in zip(cand, cand[1:])] \
        + [cand[-1] + max(1.0, abs(cand[-1]))]
    good = [i for i, t in enumerate(probes) if ok(t)]
    if not good:
        pts = [c for c in cand if ok(c)]
        return (pts[0], pts[-1]) if pts else (math.inf, -math.inf)
    lo = -math.inf if good[0] == 0 else cand[good[0] - 1]
    hi = math.inf if good[-1] == len(cand) else cand[good[-1]]
    return lo, hi


def admissible_interval(I: np.ndarray, name: str) -> tuple[float, float]:
    """Values of inertia component ``name`` (kg m^2; the other components
    fixed at ``I``, whose own value of ``name`` is ignored) for which the
    tensor is physical (:func:`admissible`): positive definite and its
    principal moments obey the triangle inequality ``I1 + I2 >= (1 - s) I3``,
    ``s`` = :data:`~bifilar.scene.TRIANGLE_SLACK`, the config loader's rule.

    The triangle inequality is ``lambda_max <= tr/(2 - s)`` (``I1 + I2 = tr -
    I3``), i.e. ``tr/(2 - s) Id - I`` positive semi-definite, and with one
    component free both that matrix and ``I`` are affine in it: each set is
    an interval whose ends are roots of a 3x3 determinant.  Returns ``(lo,
    hi)``; ``lo > hi`` when no value is physical.  The positive-definite ends
    are open (a singular tensor), the triangle ends closed; for a diagonal
    component the interval is bounded by the triangle inequality, for a
    product by definiteness or the triangle inequality.  Remembered for
    the last :data:`_ADMISSIBLE_KEEP` tensors asked (a pure function of the
    other components: a sweep over the rig's geometry asks the same ones at
    every point, each ~0.15 ms of eigenvalue solves)."""
    i, j = _IDX[name]
    I0 = np.array(I, float)
    I0[i, j] = I0[j, i] = 0.0
    key = (I0.tobytes(), name)
    got = _admissible_seen.get(key)
    if got is None:
        got = _admissible_interval(I0, name)
        if len(_admissible_seen) >= _ADMISSIBLE_KEEP:
            _admissible_seen.clear()
        _admissible_seen[key] = got
    return got


#: how many (tensor, component) answers :func:`admissible_interval` keeps
_ADMISSIBLE_KEEP = 64
_admissible_seen: dict = {}


def _admissible_interval(I0: np.ndarray, name: str) -> tuple[float, float]:
    """:func:`admissible_interval` of ``I0`` (component ``name`` set to 0), computed."""
    E = basis(name)
    lo1, hi1 = _psd_interval(I0, E)
    c = 1.0 / (2.0 - TRIANGLE_SLACK)
    J0 = c * np.trace(I0) * np.eye(3) - I0
    D = (c * np.trace(E)) * np.eye(3) - E
    lo2, hi2 = _psd_interval(J0, D)
    return max(lo1, lo2), min(hi1, hi2)


def admissible(I: np.ndarray) -> bool:
    """Positive definite with principal moments obeying the triangle
    inequality within the config loader's allowance for rounded values
    (:func:`bifilar.scene.obeys_triangle`): the tensors a config may state."""
    ev = np.linalg.eigvalsh(0.5 * (I + I.T))
    return bool(ev[0] > 0 and obeys_triangle(ev))


#: the physical limits' names (why an end of a 95 % interval was cut)
TRIANGLE_LIMIT, DEFINITE_LIMIT = "triangle", "positive definite"


def physical_limits(I: np.ndarray, name: str, free=()) -> tuple[tuple[float, str | None], tuple[float, str | None]]:
    """Bounds ``((lo, why), (hi, why))`` of inertia component ``name``
    (kg m^2) that hold for *every* physical tensor (:func:`admissible`)
    whose components are those of ``I`` except ``name`` and the components
    in ``free`` (other unknowns, any value); ``why`` names the limit
    (:data:`TRIANGLE_LIMIT`, :data:`DEFINITE_LIMIT`; None for an infinite
    end).  With no other component free this is the admissible interval
    itself (:func:`admissible_interval`, exact).  With others free it is
    what the fixed components alone imply, in any axes (``s`` =
    :data:`~bifilar.scene.TRIANGLE_SLACK`): a moment ``Ic`` lies in
    ``[max((1 - s) Ia - Ib, (1 - s) Ib - Ia), (Ia + Ib) / (1 - s)]`` when the
    other two moments are fixed (each diagonal entry is at most the largest
    principal moment, ``tr/(2 - s)``), else it is only positive; a product
    ``|Iij| <= min(sqrt(Iii Ijj), sqrt((c - Iii)(c - Ijj)))``, ``c = tr/(2 -
    s)`` (2x2 minors of ``I`` and of ``c Id - I``), each bound when the
    moments it needs are fixed.  The truth obeys these bounds whatever the
    other unknowns' truth is, so cutting an interval at them never
    uncovers it."""
    i, j = _IDX[name]
    free = {n for n in free if n in _IDX and n != name}
    scale = float(np.max(np.abs(np.linalg.eigvalsh(0.5 * (I + I.T)))))
    if not free:
        lo_a, hi_a = admissible_interval(I, name)
        lo_p, hi_p = physical_interval(I, name)

        def why(a, p):
            if not math.isfinite(a):
                return None
            return DEFINITE_LIMIT if math.isfinite(p) and abs(a - p) <= 1e-9 * scale else TRIANGLE_LIMIT

        return (lo_a, why(lo_a, lo_p)), (hi_a, why(hi_a, hi_p))
    diag = [float(I[k, k]) for k in range(3)]
    fixed = [f"I{c}{c}" not in free for c in "xyz"]
    if i == j:
        a, b = [k for k in range(3) if k != i]
        if fixed[a] and fixed[b]:
            lo = max((1 - TRIANGLE_SLACK) * diag[a] - diag[b], (1 - TRIANGLE_SLACK) * diag[b] - diag[a])
            hi = (diag[a] + diag[b]) / (1 - TRIANGLE_SLACK)
            return ((lo, TRIANGLE_LIMIT) if lo > 0 else (0.0, DEFINITE_LIMIT)), (hi, TRIANGLE_LIMIT)
        return (0.0, DEFINITE_LIMIT), (math.inf, None)
    bound, why_b = math.inf, None
    if fixed[i] and fixed[j]:
        bound, why_b = math.sqrt(diag[i] * diag[j]), DEFINITE_LIMIT
    if all(fixed):
        c = sum(diag) / (2 - TRIANGLE_SLACK)
        b_tr = math.sqrt(max(0.0, (c - diag[i]) * (c - diag[j])))
        if b_tr < bound:
            bound, why_b = b_tr, TRIANGLE_LIMIT
    return (-bound, why_b), (bound, why_b)


class HangingModel:
    """Linear periods of one hanging's modes as functions of the unknowns.

    ``values``: {unknown: value} in the reference body frame (missing ones
    keep the prior).  Rest poses are reused while only the inertia changes
    (the rest pose does not depend on it) and found anew otherwise (from the
    start pose, not the previous one: a rig may have two stable poses); modes
    are tracked by MAC against the modes at the prior.
    """

    def __init__(self, hanging, I_ref0: np.ndarray, like: "HangingModel | None" = None, rest=None, at=None):
        self.hanging = hanging
        self.R = np.asarray(hanging.rotation, float)
        self.I_ref0 = np.asarray(I_ref0, float)
        self.scene0 = replace(hanging.scene, inertia=self.R @ self.I_ref0 @ self.R.T)
        # ``rest``: the rest pose of this geometry (it does not depend on the inertia); ``at``: with it,
        # modes_of_inertia of this geometry about ``rest`` if already built (its reduced stiffness)
        self.rest0 = rest if rest is not None else rest_pose(self.scene0, guess=like.rest0 if like is not None else None)
        key = self._geom_key(self.scene0)
        # (geometry key, modes_of_inertia at the cached rest pose): built once here and reused by
        # locate at this geometry; modes0 is linear_modes(scene0, rest0), the same operations
        self._modes_at = (key, at if at is not None and rest is not None else modes_of_inertia(self.scene0, self.rest0))
        self.modes0 = self._modes_at[1](self.scene0.inertia)
        # for a perturbed copy, base-mode k of ``like`` is mode map_like[k] here
        self.map_like = mac_match(like.modes0, self.modes0) if like is not None else None
        self._rest_cache = (key, self.rest0)
        # the mode sets already solved at this geometry: inertia bytes -> ModeSet (a budget asks for the
        # prior's several times, and every component of one truth shares the model: honest.honest_stds)
        self._solved: dict = {self.scene0.inertia.tobytes(): self.modes0}
        self._matched: dict = {}  # inertia bytes -> (the modes0 matched against, the match)
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
            return scene_with(self.scene0, inertia=I, attachments=att)
        return scene_with(self.scene0, inertia=I)

    def locate(self, scene: Scene):
        """(rest, modes, match) with ``match[k]`` the index of base mode k.
        While only the inertia changes, the rest pose and the reduced
        stiffness are reused (:func:`~bifilar.analysis.modes.modes_of_inertia`:
        the same modes as :func:`linear_modes`, bit for bit)."""
        key = self._geom_key(scene)
        if key == self._rest_cache[0]:
            rest = self._rest_cache[1]
        else:
            rest = rest_pose(scene, guess=self._rest_cache[1])
            self._rest_cache = (key, rest)
        if self._modes_at[0] != key:
            self._modes_at = (key, modes_of_inertia(scene, rest))
            self._solved, self._matched = {}, {}
        ik = np.asarray(scene.inertia, float).tobytes()
        ms = self._solved.get(ik)
        if ms is None:
            ms = self._modes_at[1](scene.inertia)
            if len(self._solved) < 16:
                self._solved[ik] = ms
        self.evaluations += 1
        base, match = self._matched.get(ik, (None, None))
        if base is not self.modes0:  # (roots.relabel may replace modes0)
            match = mac_match(self.modes0, ms)
            self._matched[ik] = (self.modes0, match)
        return rest, ms, match

    def periods(self, values: dict) -> np.ndarray:
        """Linear periods (s) of the base modes (NaN if neutral) at ``values``."""
        _, ms, match = self.locate(self.scene(values))
        return np.array([ms.modes[i].period if ms.modes[i].period else np.nan for i in match])


@dataclass
class Problem:
    """Hanging models, measurements (with their base-mode indices) and unknowns."""

    models: list
    measurements: list
    mode_index: list
    unknowns: list
    I_ref0: np.ndarray
    unc: dict
    #: how the hangings' rig inputs are measured (:data:`~bifilar.estimation.rig.RIG_MODELS`)
    rig: str = "shared"
    _links: object = field(default=None, repr=False, compare=False)

    @property
    def links(self):
        """The hangings' rig and attachment inputs as independent measured
        quantities (:func:`~bifilar.estimation.rig.rig_links` of the
        configs' geometry under :attr:`rig`)."""
        if self._links is None or self._links.model != self.rig:
            from .rig import rig_links

            self._links = rig_links([hm.hanging.name for hm in self.models], [hm.hanging.scene for hm in self.models],
                                    [hm.R for hm in self.models], self.rig)
        return self._links

    @property
    def prior(self) -> np.ndarray:
        return np.array([self.I_ref0[_IDX[n]] if n in _IDX else 0.0 for n in self.unknowns])

    def scales(self) -> np.ndarray:
        Imax = float(np.max(np.linalg.eigvalsh(self.I_ref0)))
        Lmax = max(float(np.max(hm.scene0.lengths)) for hm in self.models)
        return np.array([Imax if n in _IDX else 1e-2 * Lmax for n in self.unknowns])

    def values(self, p) -> dict:
        return {n: float(v) for n, v in zip(self.unknowns, np.atleast_1d(p))}

    def term_labels(self) -> list[str]:
        """Each measurement's name in the budget's terms of one measurement
        (``timing[...]``, ``amplitude[...]``): its mode label, after
        ``<hanging>:`` with several hangings; the second and later
        measurements of one mode in one hanging numbered (``torsion#2``), so
        that each keeps its own, independent term (one name for two timings
        kept only the last one's: a std 1/sqrt(2) too small for two)."""
        multi = len(self.models) > 1
        out, seen = [], {}
        for m in self.measurements:
            lab = f"{self.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
            seen[lab] = seen.get(lab, 0) + 1
            out.append(lab if seen[lab] == 1 else f"{lab}#{seen[lab]}")
        return out

    def linear_periods(self, p) -> np.ndarray:
        """(K,) linear periods of the measured modes at unknowns ``p``, s."""
        return self.periods_at(self.values(p))

    def periods_at(self, vals: dict) -> np.ndarray:
        """(K,) linear periods of the measured modes at ``vals`` {component or
        CoM unknown: value} (reference body frame, SI; a component not in it
        keeps the prior), s."""
        out = np.empty(len(self.measurements))
        cache = {}
        for k, m in enumerate(self.measurements):
            h = m.hanging
            if h not in cache:
                cache[h] = self.models[h].periods(vals)
            out[k] = cache[h][self.mode_index[k]]
        return out

    def jacobian(self, p, rel_step: float = 1e-6) -> np.ndarray:
        """(K, P) d T_lin / d p (s per unit of each unknown) by central
        differences; one-sided, into the side where the modes can be
        solved, for an unknown whose step to one side gives a mass matrix that
        is not positive definite (``p`` on the physical set's edge, the
        Gauss-Newton solver's edge search: the step leaves the set there).
        Raises :class:`numpy.linalg.LinAlgError` where neither side can be
        solved."""
        p = np.asarray(p, float)
        sc = self.scales()
        J = np.empty((len(self.measurements), len(p)))
        for j in range(len(p)):
            h = rel_step * sc[j]
            e = np.zeros_like(p)
            e[j] = h
            try:
                J[:, j] = (self.linear_periods(p + e) - self.linear_periods(p - e)) / (2 * h)
            except np.linalg.LinAlgError:
                J[:, j] = self._one_sided(p, e, h)
        return J

    def _one_sided(self, p, e, h: float) -> np.ndarray:
        """(K,) d T_lin / d p_j by a forward difference ``(T(p + e) - T(p)) /
        h``, or the backward one where the forward step's modes cannot be
        solved (a mass matrix that is not positive definite)."""
        T0 = self.linear_periods(p)
        try:
            return (self.linear_periods(p + e) - T0) / h
        except np.linalg.LinAlgError:
            return (T0 - self.linear_periods(p - e)) / h


def build_problem(ms: MeasurementSet, solve_for: list | None = None, unc: dict | None = None,
                  like: Problem | None = None, rests: list | None = None, models: list | None = None,
                  ats: list | None = None) -> Problem:
    """Hanging models at the prior, mode indices and the unknowns (picked
    per measurement as the component its period is most sensitive to,
    relatively, when ``solve_for`` is empty).  ``rests``: the hangings'
    rest poses when known (the same geometry with another inertia).
    ``models``: the :class:`HangingModel` of each hanging of ``ms`` at
    this prior if already built (another problem of the same hangings:
    they are shared, with their caches).  ``ats``: with ``rests``, each
    hanging's :func:`~bifilar.analysis.modes.modes_of_inertia` about its
    rest pose if already built (None where not)."""
    h0 = ms.hangings[0]
    I_ref0 = h0.rotation.T @ h0.scene.inertia @ h0.rotation
    if models is None:
        models = [HangingModel(h, I_ref0, like=like.models[i] if like is not None else None,
                               rest=rests[i] if rests is not None else None, at=ats[i] if ats is not None else None)
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
    pb = Problem(models, ms.measurements, idx, unknowns, I_ref0, default_uncertainty(unc),
                 rig=like.rig if like is not None else ms.rig)
    if like is None and len(unknowns) > len(ms.measurements):
        raise InputError("--solve-for", f"{len(unknowns)} unknowns ({', '.join(unknowns)}) but only "
                                        f"{len(ms.measurements)} measured period(s): measure more modes or "
                                        "hangings, or solve for fewer components")
    return pb


#: relative change of a period over an unknown's whole admissible range
#: below which the period does not measure it (the periods' own rounding is
#: ~1e-13)
INSENSITIVE = 1e-6


def refuse_unmeasured(pb: Problem) -> None:
    """Raise an :class:`InputError` (``--solve-for``) for an unknown that no
    measured period depends on, e.g. Ixx from a torsion period: every
    measured period changes by less than :data:`INSENSITIVE` (relative) as
    the unknown moves over its admissible range (inertia: 10, 50 and 90 %
    of :func:`admissible_interval`; a CoM shift: +-5 % of the longest wire),
    the others at the prior -- a range, not a derivative, so a product of
    inertia that acts at second order at a symmetric prior counts as
    measured.  The message names the mode of the hangings in use whose
    period changes most, or says that none does.  Three mode computations
    per unknown and hanging (the rest pose is reused for inertia)."""
    p0 = pb.prior
    Lmax = max(float(np.max(hm.scene0.lengths)) for hm in pb.models)
    T0 = [hm.periods(pb.values(p0)) for hm in pb.models]
    for j, n in enumerate(pb.unknowns):
        if n in _IDX:
            lo, hi = admissible_interval(pb.I_ref0, n)
            if not (lo < hi and math.isfinite(lo) and math.isfinite(hi)):
                continue  # no range to sample: the solver's own checks decide
        else:
            lo, hi = p0[j] - 0.05 * Lmax, p0[j] + 0.05 * Lmax
        change = [np.zeros_like(T) for T in T0]  # per hanging and mode: largest relative change
        seen = 0
        for f in (0.1, 0.5, 0.9):
            p = p0.copy()
            p[j] = lo + f * (hi - lo)
            for h, hm in enumerate(pb.models):
                try:
                    T = hm.periods(pb.values(p))
                except BifilarError:  # a CoM shift that cannot hang: that point says nothing
                    continue
                seen += 1
                with np.errstate(invalid="ignore"):
                    change[h] = np.fmax(change[h], np.abs(T / T0[h] - 1))
        measured = [change[m.hanging][pb.mode_index[k]] for k, m in enumerate(pb.measurements)]
        if not seen or any(np.isfinite(c) and c >= INSENSITIVE for c in measured):
            continue
        what = ", ".join(sorted({f"'{m.label}'" for m in pb.measurements}))
        best = max(((float(c[i]), h, i) for h, c in enumerate(change) for i in range(len(c)) if np.isfinite(c[i])),
                   default=(0.0, 0, 0))
        if best[0] >= INSENSITIVE:
            hm = pb.models[best[1]]
            how = (f"time mode '{hm.modes0.modes[best[2]].label}' (hanging '{hm.hanging.name}'), whose period "
                   "depends on it, or do not solve for it")
        else:
            how = "no mode of these hangings depends on it: hang the body another way, or do not solve for it"
        raise InputError("--solve-for", f"{n} cannot be solved for: no measured period ({what}) depends on it "
                                        f"(they change by less than {INSENSITIVE:g} over its physical range); {how}")


def refuse_stretching_amplitudes(pb: Problem) -> None:
    """Raise an :class:`InputError` (the amplitude's field) for a measured
    period stated at an amplitude (the nonlinear method's input) of a mode
    that the rig's dependent wires cannot follow rigidly
    (:func:`~bifilar.analysis.wire_statics.stretching_modes`, at the prior):
    the rigid-wire model's run of it is not physical at any amplitude (a
    4-wire table on wires of unequal length: tensions of -734 N in a 98 N
    body, or no two crossings, exit 1 before), while a real rig's wires
    stretch and its small oscillations keep the linear periods, which the
    advised ``--amplitude LABEL=0`` (the linear model) estimates from."""
    from ..analysis.wire_statics import stretching_modes, stretching_reason

    for k, m in enumerate(pb.measurements):
        if not m.amplitude:
            continue
        hm = pb.models[m.hanging]
        mode = hm.modes0.modes[pb.mode_index[k]]
        if not stretching_modes(hm.scene0, hm.rest0, [mode]):
            continue
        fld = "--amplitude" if m.field.startswith("--") else m.field.rsplit(".", 1)[0] + ".amplitude"
        where = f" (hanging '{hm.hanging.name}')" if len(pb.models) > 1 else ""
        raise InputError(fld, f"mode '{m.label}'{where} at amplitude {m.amplitude:.3g}: "
                              f"{stretching_reason(hm.scene0, [mode.label])}, so the nonlinear model's period is not "
                              "physical at any amplitude; a real rig's wires stretch and its small oscillations keep "
                              f"the linear period: time it at a small amplitude and give --amplitude {m.label}=0 "
                              "(the linear model)")


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


def start_guesses(I_ref: np.ndarray, unknowns: list, given: dict | None = None) -> tuple[np.ndarray, list]:
    """A physical starting tensor for the solver (reference body axes,
    kg m^2) and notes saying what was assumed.

    The config's values of the components being solved for are guesses:
    ``given`` maps each unknown inertia component to its config value, or
    to None when the config marks it unknown (``null``).  While the tensor
    with these values is not physical (positive definite, triangle
    inequality), each unknown component in turn is set to the midpoint of
    its admissible interval (:func:`admissible_interval`, the others as
    they stand), nulls first; a null is set so in any case."""
    I = np.array(I_ref, float)
    given = dict(given or {})
    comps = [n for n in unknowns if n in _IDX]
    notes = []
    nulls = [n for n in comps if n in given and given[n] is None]
    order = nulls + [n for n in comps if n not in nulls]
    for n in order:
        if n not in nulls and admissible(I):
            break
        lo, hi = admissible_interval(I, n)
        if not lo <= hi:
            continue
        x = 0.5 * (lo + hi)
        old = I[_IDX[n]]
        I[_IDX[n]] = I[_IDX[n][::-1]] = x
        if n in nulls:
            notes.append(f"{n} is unknown in the config (null): the solver starts from {x:.6g} kg m^2, the middle of "
                         f"its physical range {lo:.6g} .. {hi:.6g} kg m^2 with the other components as given")
        else:
            notes.append(f"the config's {n} = {old:.6g} kg m^2 (a starting guess) makes the tensor unphysical: the "
                         f"solver starts from {x:.6g} kg m^2, the middle of its physical range")
    return I, notes


def problem_at(ms: MeasurementSet, pb: Problem, p, unc: dict | None = None) -> Problem:
    """``pb`` rebuilt around the solution ``p``: every hanging's scene carries
    the estimated tensor, the unknowns' reference values are the estimate
    and the measured modes are the ones carrying the measured labels there
    (so finite differences, the budget and Monte Carlo draws follow the
    mode the experimenter saw at the solution)."""
    from .roots import relabel

    I_hat = pb.models[0].inertia_ref(pb.values(p))
    hangs = [replace(h, scene=replace(h.scene, inertia=np.asarray(h.rotation) @ I_hat @ np.asarray(h.rotation).T))
             for h in ms.hangings]
    ms2 = replace(ms, hangings=hangs)
    pb2 = build_problem(ms2, list(pb.unknowns), unc if unc is not None else pb.unc,
                        rests=[hm.rest0 for hm in pb.models])
    pb2.unc = pb.unc
    if any(n not in _IDX for n in pb.unknowns):
        relabel(pb2, p)
    return pb2
