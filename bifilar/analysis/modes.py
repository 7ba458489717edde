"""Small oscillations about the rest pose: periods, shapes and labels.

Linearisation on the constraint manifold: in the world chart
``x = (dr, dtheta)`` (CoM displacement, small world rotation vector) the
constraint Jacobian ``G`` has null space ``N`` (6 x (6-n)); the reduced mass
``N^T M N`` and stiffness ``N^T K N`` (``K`` the Hessian of the Lagrangian
``m g z + sum lam_i phi_i``, which carries the geometric stiffness of the
tensioned wires) give the generalised eigenproblem ``K y = omega^2 M y``.
Shapes ``N y`` are scaled so that the largest absolute component is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Scene
from .equilibrium import RestPose, reduced_stiffness

COMPONENTS = ("x", "y", "z", "rx", "ry", "rz")
_BASE_LABEL = {"x": "swing-x", "y": "swing-y", "z": "bounce", "rx": "roll", "ry": "pitch", "rz": "torsion"}


@dataclass(frozen=True)
class Mode:
    """One linear free-vibration mode.

    label : readable name (torsion, swing-x, swing-y, bounce, roll, pitch;
        a suffix -2, -3 when a name repeats).
    period : s, or None when the stiffness is zero (neutral) .
    omega2 : rad^2/s^2 (may be ~0).
    shape : (6,) [dx, dy, dz, rx, ry, rz], world frame, m and rad, max |.| = 1.
    energy_share : (6,) kinetic-energy fraction per component.
    dominant : index into ``shape`` of the largest-magnitude component
        (the coordinate an experimenter would time).
    """

    label: str
    period: float | None
    omega2: float
    shape: np.ndarray
    energy_share: np.ndarray
    dominant: int

    @property
    def description(self) -> str:
        order = np.argsort(self.energy_share)[::-1]
        main = [f"{COMPONENTS[i]} {100 * self.energy_share[i]:.0f}%" for i in order[:2] if self.energy_share[i] > 0.01]
        return ", ".join(main)


@dataclass(frozen=True)
class ModeSet:
    modes: list[Mode]
    mass_matrix: np.ndarray  # (6, 6) world chart
    basis: np.ndarray  # (6, k) null-space basis

    def get(self, key: str | int) -> Mode:
        """A mode by label (exact, or unique prefix) or by 1-based index."""
        if isinstance(key, int) or (isinstance(key, str) and key.isdigit()):
            k = int(key)
            if not 1 <= k <= len(self.modes):
                raise KeyError(f"mode index {k} out of range 1..{len(self.modes)}")
            return self.modes[k - 1]
        for m in self.modes:
            if m.label == key:
                return m
        hits = [m for m in self.modes if m.label.startswith(key)]
        if len(hits) == 1:
            return hits[0]
        raise KeyError(f"no mode '{key}'; modes are {', '.join(m.label for m in self.modes)}")

    def pick(self, key: str | int | None, option: str = "--mode") -> Mode:
        """The mode the user asked for (default: torsion, else the slowest);
        an unknown key is an :class:`~bifilar.errors.InputError` naming ``option``."""
        from ..errors import InputError

        if key is None:
            key = "torsion" if "torsion" in self.labels else 1
        try:
            return self.get(key)
        except KeyError as exc:
            raise InputError(option, str(exc.args[0])) from None

    @property
    def labels(self) -> list[str]:
        return [m.label for m in self.modes]


def linear_modes(scene: Scene, rest: RestPose) -> ModeSet:
    """All 6 - n linear modes about ``rest``, slowest first."""
    lam = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
    N, Kr, Mr, rank = reduced_stiffness(scene, rest.com, rest.R, lam)
    M = np.zeros((6, 6))
    M[:3, :3] = scene.mass * np.eye(3)
    M[3:, 3:] = rest.R @ scene.inertia @ rest.R.T
    if N.shape[1] == 0:
        return ModeSet([], M, N)
    w2, Y = eigh_generalized(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T))
    scale = max(abs(w2).max(), 1e-300)
    Y = _align_degenerate(N, Y, w2, scale)
    modes = []
    for k in range(len(w2)):
        shape = N @ Y[:, k]
        i = int(np.argmax(np.abs(shape)))
        shape = shape / shape[i]
        share = np.concatenate([scene.mass * shape[:3] ** 2, np.diag(M[3:, 3:]) * shape[3:] ** 2])
        share = share / share.sum()
        zero = abs(w2[k]) <= 1e-10 * scale or w2[k] <= 0
        period = None if zero else float(2 * np.pi / np.sqrt(w2[k]))
        dom_energy = int(np.argmax(share))
        modes.append(Mode(_BASE_LABEL[COMPONENTS[dom_energy]], period, float(w2[k]), shape, share, i))
    # slowest first; neutral (None) modes last
    modes.sort(key=lambda m: -(m.period if m.period is not None else -1.0))
    seen: dict[str, int] = {}
    out = []
    for m in modes:
        c = seen.get(m.label, 0) + 1
        seen[m.label] = c
        out.append(m if c == 1 else Mode(f"{m.label}-{c}", m.period, m.omega2, m.shape, m.energy_share, m.dominant))
    return ModeSet(out, M, N)


def eigh_generalized(K: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors Y of ``K y = w M y`` for
    symmetric K and symmetric positive definite M, normalised Y^T M Y = I
    (as ``scipy.linalg.eigh(K, M)``), in numpy alone: with M = C C^T
    (Cholesky), the standard problem C^-1 K C^-T z = w z and y = C^-T z.
    Units: w in units of K over M (rad^2/s^2 for a stiffness and a mass)."""
    C = np.linalg.cholesky(M)
    Ci = np.linalg.inv(C)
    A = Ci @ K @ Ci.T
    w, Z = np.linalg.eigh(0.5 * (A + A.T))
    return w, Ci.T @ Z


def _pivot_rows(S: np.ndarray, k: int) -> np.ndarray:
    """Indices of ``k`` rows of S (6, c) picked as a column-pivoted QR of S^T
    picks them: each time the row with the largest norm once the span of the
    rows already picked is removed (first index on a tie)."""
    R = np.array(S, dtype=float)
    picked = []
    for _ in range(k):
        norms = np.einsum("ij,ij->i", R, R)
        norms[picked] = -1.0
        i = int(np.argmax(norms))
        picked.append(i)
        u = R[i] / np.sqrt(norms[i])
        R = R - np.outer(R @ u, u)
    return np.array(picked)


def degenerate_clusters(w2: np.ndarray, scale: float, rel: float = 1e-8) -> list[tuple[int, int]]:
    """Index ranges [k, j) of clusters of two or more (nearly) equal
    eigenvalues in the ascending array ``w2`` (rad^2/s^2): neighbours within
    ``rel * scale`` of the cluster's first member."""
    out = []
    k = 0
    while k < len(w2):
        j = k + 1
        while j < len(w2) and abs(w2[j] - w2[k]) <= rel * scale:
            j += 1
        if j - k > 1:
            out.append((k, j))
        k = j
    return out


def _align_degenerate(N: np.ndarray, Y: np.ndarray, w2: np.ndarray, scale: float) -> np.ndarray:
    """Within clusters of (nearly) equal eigenvalues the eigenvectors are
    arbitrary; pick the combination whose shapes are aligned with the world
    axes (pivoted QR on the shapes), so a symmetric rig gets clean labels,
    ordered by world component (swing-x before swing-y) within the cluster."""
    Y = Y.copy()
    for k, j in degenerate_clusters(w2, scale):
        S = N @ Y[:, k:j]  # (6, c)
        rows = np.sort(_pivot_rows(S, j - k))  # world-axis order within the cluster (x before y ...)
        Y[:, k:j] = Y[:, k:j] @ np.linalg.inv(S[rows, :])
    return Y
