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
from dataclasses import dataclass, replace

import numpy as np

from ..analysis.equilibrium import rest_pose
from ..analysis.modes import linear_modes
from ..errors import InputError
from ..scene import Scene
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


def triangle_ok(I: np.ndarray, rel: float = 1e-6) -> bool:
    """Principal moments satisfy the triangle inequality (a real body)."""
    ev = np.linalg.eigvalsh(I)
    return bool(ev[0] > 0 and ev[0] + ev[1] >= ev[2] * (1 - rel))


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
