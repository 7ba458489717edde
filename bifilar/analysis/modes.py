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


class LazyModeSet(ModeSet):
    """A :class:`ModeSet` (of one scene of a batch, :func:`~bifilar.analysis.batch_rest.modes_batch`
    with ``lazy=True``, or of :func:`modes_of_inertia` asked with ``lazy=True``)
    whose eigenvalues are all distinct and positive
    (no degenerate cluster, no neutral mode, with a margin, :func:`plain_order`),
    so its modes are in the eigensolver's order (slowest first): ``periods``
    (k,) s and ``shapes`` (k, 6) (each scaled as :func:`mode_set` scales it,
    the same numbers) are there at once, and the :class:`Mode` objects
    (labels, energy shares) are built on first read of ``modes`` by
    ``build()`` (:func:`mode_sets` of that scene alone, or :func:`mode_set`:
    the mode set the eager path makes, bit for bit).  The honest budget's sigma points
    read only the periods and shapes (MAC) of most of theirs.  Pickled as
    the plain :class:`ModeSet`."""

    def __init__(self, build, periods: np.ndarray, shapes: np.ndarray, mass_matrix: np.ndarray,
                 basis: np.ndarray):  # noqa: D107
        self.__dict__.update(periods=periods, shapes=shapes, mass_matrix=mass_matrix, basis=basis, _build=build)

    def __getattr__(self, name):  # only called for attributes not yet set: ``modes``
        if name != "modes" or "_build" not in self.__dict__:
            raise AttributeError(name)
        ms = self.__dict__["_build"]()
        object.__setattr__(self, "modes", ms.modes)
        return ms.modes

    def __reduce__(self):
        return (ModeSet, (self.modes, self.mass_matrix, self.basis))


def plain_order(w2: np.ndarray, Y: np.ndarray, K: np.ndarray) -> np.ndarray:
    """(B,) bool: which of a batch of solved eigenproblems (``w2`` (B, k)
    ascending, rad^2/s^2; ``Y`` (B, k, k); reduced stiffness ``K`` (B, k, k))
    :func:`mode_set` would leave in the eigensolver's order, untouched:
    every eigenvalue positive and apart from its neighbours by more than
    twice the resolution :func:`_noise` gives it (and than twice the neutral
    threshold), so no cluster is formed and none is neutral whatever the
    last bits of that resolution (here computed for the whole batch at once,
    which may round differently from :func:`mode_set`'s own).  Its periods
    2 pi / sqrt(w2) then fall strictly, which is :func:`_assemble`'s order."""
    w2 = np.asarray(w2, float)
    if w2.shape[1] == 0:
        return np.zeros(len(w2), bool)
    aY = np.abs(Y)
    tol = DEGENERATE_RTOL * np.maximum(np.einsum("bik,bij,bjk->bk", aY, np.abs(K), aY), 1e-300)
    scale = np.maximum(np.max(np.abs(w2), axis=1), 1e-300)
    floor = np.maximum(tol, NEUTRAL_RTOL * scale[:, None])
    ok = np.all(w2 > 2 * floor, axis=1)
    if w2.shape[1] > 1:
        ok &= np.all(np.diff(w2, axis=1) > 2 * np.maximum(tol[:, 1:], tol[:, :-1]), axis=1)
    return ok


def _plain_one(w2: np.ndarray, Y: np.ndarray, K: np.ndarray) -> bool:
    """:func:`plain_order` of one solved eigenproblem, exactly as :func:`mode_set`
    decides (its own resolution :func:`_noise` and clusters, on Python floats:
    the same doubles), so without a margin: no cluster and no neutral mode."""
    w = w2.tolist()
    t = _noise(w2, Y, K).tolist()
    if len(_cluster_ranges(w, t)) < len(w):
        return False
    floor = NEUTRAL_RTOL * max(max(abs(x) for x in w) if w else 0.0, 1e-300)
    return all(x > 0 and abs(x) > max(tj, floor) for x, tj in zip(w, t))


def _unit_shape_one(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`unit_shapes` of one scene's shapes ``S`` (6, k): (scaled shapes, unit components (k,))."""
    absS = np.abs(S)
    # first component within 1e-9 of the largest: independent of last-bit noise
    i = np.argmax(absS >= (1 - 1e-9) * absS.max(axis=0), axis=0)
    return S / S[i, np.arange(S.shape[1])], i


def unit_shapes(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(shapes, index of each one's unit component (B, k)): shapes ``S``
    (B, 6, k) scaled as :func:`mode_set` scales them, each column by its
    first component within 1e-9 of the largest magnitude."""
    absS = np.abs(S)
    i = np.argmax(absS >= (1 - 1e-9) * absS.max(axis=1, keepdims=True), axis=1)  # (B, k)
    return S / np.take_along_axis(S, i[:, None, :], axis=1), i


def linear_modes(scene: Scene, rest: RestPose) -> ModeSet:
    """All 6 - n linear modes about ``rest``, slowest first."""
    return modes_of_inertia(scene, rest)(scene.inertia)


def modes_of_inertia(scene: Scene, rest: RestPose):
    """A function ``inertia -> ModeSet``: the :func:`linear_modes` about
    ``rest`` of ``scene`` with its inertia tensor (3 x 3, body axes about
    the CoM, kg m^2) replaced.  The rest pose and the reduced stiffness do
    not depend on the inertia, so they are computed once; each call solves
    only the eigenproblem (the same operations as :func:`linear_modes`, so
    the same result to the last bit).  For a search over one inertia
    component at a fixed geometry.  An inertia asked for again (the same
    bytes) returns the mode set solved for it the first time (the same
    object: read only; a sweep point's consumers share one function).
    ``lazy=True``: a :class:`LazyModeSet` where :func:`plain_order` allows
    (periods and shapes at once, the :class:`Mode` objects by
    :func:`mode_set` when read: the same mode set), for callers that read
    only periods and shapes (:func:`~bifilar.estimation.sensitivity.matched_periods`)."""
    lam = rest.tensions / np.linalg.norm(rest.wire_vectors, axis=1)
    N, Kr, _, _ = reduced_stiffness(scene, rest.com, rest.R, lam)
    K = 0.5 * (Kr + Kr.T)
    M0 = np.zeros((6, 6))  # the translational block, the same for every inertia
    M0[:3, :3] = scene.mass * np.eye(3)
    solved: dict = {}

    def modes(inertia, lazy: bool = False) -> ModeSet:
        key = np.asarray(inertia, float).tobytes()
        ms = solved.get(key)
        if ms is None:
            ms = _solve(inertia, lazy)
            if len(solved) < 8:
                solved[key] = ms
        return ms

    def _solve(inertia, lazy: bool) -> ModeSet:
        M = M0.copy()
        M[3:, 3:] = rest.R @ np.asarray(inertia, float) @ rest.R.T
        if N.shape[1] == 0:
            return ModeSet([], M, N)
        Mr = N.T @ M @ N
        w2, Y = eigh_generalized(K, 0.5 * (Mr + Mr.T))
        if lazy and _plain_one(w2, Y, K):
            S, _ = _unit_shape_one(N @ Y)
            return LazyModeSet(lambda: mode_set(N, Y, w2, scene.mass, M, K=K), 2 * np.pi / np.sqrt(w2), S.T, M, N)
        return mode_set(N, Y, w2, scene.mass, M, K=K)

    return modes


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


#: eigenvalues closer than this, relative to the largest |omega^2|, form one
#: degenerate cluster (a symmetric rig's repeated modes).  Rounding differs
#: between machines at ~1e-15 and the rest pose is converged to ~1e-12; a
#: real asymmetry splits a pair by more (one wire of a trifilar 0.1 mm longer
#: in 2 m splits its swings by 1e-8), and that split is kept.
DEGENERATE_RTOL = 1e-10
#: an eigenvalue below this fraction of the largest |omega^2| is neutral (no period)
NEUTRAL_RTOL = 1e-13


def clusters(w2: np.ndarray, tol) -> list[tuple[int, int]]:
    """[start, stop) index ranges of the sorted eigenvalues ``w2`` (rad^2/s^2)
    that are equal within ``tol`` (rad^2/s^2: one number, or one per
    eigenvalue, the larger of the pair applying, see :func:`_noise`); chained
    from the first member, so the grouping does not depend on last-bit noise
    of the others."""
    # Python floats: the same IEEE doubles as numpy's scalars, a tenth of the cost in this loop
    tol = np.asarray(tol, float)
    t = (tol if tol.shape == np.shape(w2) else np.broadcast_to(tol, np.shape(w2))).tolist()
    return _cluster_ranges(np.asarray(w2, float).tolist(), t)


def _cluster_ranges(w: list, t: list) -> list[tuple[int, int]]:
    """:func:`clusters` of eigenvalues ``w`` and their resolutions ``t`` (Python floats)."""
    out = []
    k = 0
    while k < len(w):
        j = k + 1
        while j < len(w) and abs(w[j] - w[k]) <= max(t[k], t[j]):
            j += 1
        out.append((k, j))
        k = j
    return out


def _noise(w2: np.ndarray, Y: np.ndarray, K: np.ndarray | None) -> np.ndarray:
    """Resolution (rad^2/s^2) of each eigenvalue: ``DEGENERATE_RTOL`` times
    the size of the terms whose sum is omega^2 = y^T K y (M-normalised y),
    ``|y|^T |K| |y|``, when the reduced stiffness ``K`` is given; else
    ``DEGENERATE_RTOL`` times the largest |omega^2| for all.  The per-mode
    form matters for a stiff body: a thin rod (principal moments
    [1e-11, 1, 1]) has a roll mode 1e11 times stiffer than its swings, and a
    tolerance relative to it merged the swings and the torsion into one
    cluster (one mean period for all three) or called them neutral."""
    if K is None:
        scale = max(float(np.max(np.abs(w2))) if len(w2) else 0.0, 1e-300)
        return np.full(len(w2), DEGENERATE_RTOL * scale)
    aY = np.abs(Y)
    return DEGENERATE_RTOL * np.maximum(np.einsum("ik,ij,jk->k", aY, np.abs(K), aY), 1e-300)


def mode_set(N: np.ndarray, Y: np.ndarray, w2: np.ndarray, mass: float, M: np.ndarray,
             K: np.ndarray | None = None) -> ModeSet:
    """The :class:`ModeSet` of a solved eigenproblem ``K y = omega^2 M y``
    (``w2`` ascending, rad^2/s^2; ``Y`` its eigenvectors in the null-space
    coordinates ``N`` (6 x k); ``mass`` kg; ``M`` the 6 x 6 world-chart mass
    matrix), in a canonical form that does not depend on rounding:

    * a cluster of (nearly) equal eigenvalues (:func:`clusters`) gets one
      eigenvalue (the cluster mean) and the basis aligned with the world
      axes (:func:`_align_degenerate`), so its modes have identical periods;
    * modes are ordered slowest first, neutral ones last, and within equal
      periods by the world component that carries most of their kinetic
      energy (x, y, z, rx, ry, rz): a symmetric rig always lists swing-x
      before swing-y, whatever the BLAS kernel;
    * every shape is scaled so that its largest component is +1 (ties
      broken by the first component within 1e-9).

    ``K`` (k x k, optional): the reduced stiffness, for a per-mode resolution
    of the eigenvalues (:func:`_noise`); without it one resolution relative
    to the largest eigenvalue applies to all.
    """
    w2 = np.array(w2, float)
    Y = np.array(Y, float)
    tol = _noise(w2, Y, K)
    groups = clusters(w2, tol)
    if len(groups) < len(w2):  # a cluster of two or more
        Y = _align_degenerate(N, Y, w2, tol, groups)
        for a, b in groups:
            if b - a > 1:  # (the mean of one number is that number)
                w2[a:b] = np.mean(w2[a:b])
    S, i = _unit_shape_one(N @ Y)
    diagM = np.diag(M)[3:]
    share = np.concatenate([mass * S[:3] ** 2, diagM[:, None] * S[3:] ** 2], axis=0)
    share = share / share.sum(axis=0)
    # neutral: below the eigenvalue's own resolution, or below NEUTRAL_RTOL of
    # the largest |omega^2| (rounding leaves a neutral mode at ~1e-16 of it,
    # positive or negative; a real soft mode, a thin rod's swing beside its
    # 1e11 times stiffer roll, sits at >= 1e-11)
    scale = max(float(np.max(np.abs(w2))) if len(w2) else 0.0, 1e-300)
    zero = (np.abs(w2) <= np.maximum(tol, NEUTRAL_RTOL * scale)) | (w2 <= 0)
    periods = np.where(zero, np.nan, 2 * np.pi / np.sqrt(np.where(zero, 1.0, w2)))
    return _assemble(S, share, w2, zero, periods, i, M, N)


def _assemble(S, share, w2, zero, periods, i, M, N) -> ModeSet:
    """The :class:`ModeSet` of one solved eigenproblem from :func:`mode_set`'s
    arrays (shapes S (6, k), energy shares (6, k), omega^2, neutral flags,
    periods, index of each shape's unit component): ordered slowest first,
    neutral last, ties by the dominant world component; labelled."""
    # Python numbers of the small arrays (the same doubles; no numpy scalar per access)
    return _assemble_lists(S, share, np.argmax(share, axis=0).tolist(), periods.tolist(), zero.tolist(), w2.tolist(),
                           i.tolist(), M, N)


def _assemble_lists(S, share, dom_e, P, Z, W, I, M, N) -> ModeSet:
    """:func:`_assemble` with the dominant components, periods, neutral flags,
    omega^2 and unit-component indices as Python lists (the batch converts
    all its scenes' at once)."""
    order = sorted(range(len(W)), key=lambda j: (-(P[j] if not Z[j] else -1.0), dom_e[j]))
    seen: dict[str, int] = {}
    modes = []
    for j in order:
        base = _BASE_LABEL[COMPONENTS[dom_e[j]]]
        c = seen.get(base, 0) + 1
        seen[base] = c
        modes.append(Mode(base if c == 1 else f"{base}-{c}", None if Z[j] else P[j], W[j],
                          S[:, j].copy(), share[:, j].copy(), I[j]))
    return ModeSet(modes, M, N)


def mode_sets(N: np.ndarray, Y: np.ndarray, w2: np.ndarray, mass: np.ndarray, M: np.ndarray,
              K: np.ndarray, which=None) -> list[ModeSet]:
    """:func:`mode_set` of each of a batch of solved eigenproblems (leading
    axis B: ``N`` (B, 6, k), ``Y`` (B, k, k), ``w2`` (B, k) ascending,
    ``mass`` (B,) kg, ``M`` (B, 6, 6), ``K`` (B, k, k)), the same mode
    sets bit for bit with less numpy call overhead: each scene's
    resolution, clusters and energy-share sums are the very calls
    :func:`mode_set` makes on it, ``N @ Y`` a stacked product (each slice
    the same call); only elementwise operations and
    maxima, exact in any order, run on the whole batch.  A scene with a
    degenerate cluster has its cluster aligned and its eigenvalues set to
    the cluster means as :func:`mode_set` does, the scenes of one cluster
    structure together (:func:`_align_degenerate_batch`, each scene's
    numbers those of :func:`_align_degenerate` alone).  ``which``:
    the scenes to do (indices; the others' entries are None), default all.
    Each ModeSet holds ``N[b]`` and ``M[b]`` (views) as :func:`mode_set`
    given them does."""
    B = len(w2)
    out: list = [None] * B
    rows = [int(b) for b in (range(B) if which is None else which)]
    if not rows:
        return out
    w2r = np.array(np.asarray(w2)[rows], float)  # (R, k): each scene's eigenvalues (set to cluster means below)
    Yr = np.array(np.asarray(Y)[rows], float)  # (R, k, k)
    Nr = np.asarray(N)[rows]
    tols, by_groups = [], {}
    for q, b in enumerate(rows):
        tol = _noise(w2r[q], Yr[q], K[b])
        groups = _cluster_ranges(w2r[q].tolist(), tol.tolist())  # clusters(w2[b], tol)
        if len(groups) < w2r.shape[1]:  # a cluster of two or more
            by_groups.setdefault(tuple(groups), []).append(q)
        tols.append(tol)
    # mode_set's steps before N @ Y (a cluster aligned, its eigenvalues set to their mean), for the scenes of one
    # cluster structure at once (_align_degenerate_batch: each scene's numbers as _align_degenerate's alone)
    for groups, qs in by_groups.items():
        Yr[qs] = _align_degenerate_batch(Nr[qs], Yr[qs], groups)
        for a, j in groups:
            if j - a > 1:
                w2r[np.ix_(qs, range(a, j))] = np.mean(w2r[qs, a:j], axis=1)[:, None]
    S = Nr @ Yr  # (R, 6, k): the stacked product, each scene's N @ Y (the same bits)
    tol = np.array(tols)
    S, i = unit_shapes(S)  # (R, 6, k), (R, k)
    diagM = np.diagonal(np.asarray(M)[rows], axis1=1, axis2=2)[:, 3:]
    share = np.concatenate([np.asarray(mass, float)[rows, None, None] * S[:, :3] ** 2,
                            diagM[:, :, None] * S[:, 3:] ** 2], axis=1)
    share = np.array([sh / sh.sum(axis=0) for sh in share])  # each scene's own sum, as mode_set
    scale = np.maximum(np.max(np.abs(w2r), axis=1), 1e-300)
    zero = (np.abs(w2r) <= np.maximum(tol, NEUTRAL_RTOL * scale[:, None])) | (w2r <= 0)
    periods = np.where(zero, np.nan, 2 * np.pi / np.sqrt(np.where(zero, 1.0, w2r)))
    dom, P, Z, W, I = np.argmax(share, axis=1).tolist(), periods.tolist(), zero.tolist(), w2r.tolist(), i.tolist()
    for q, b in enumerate(rows):  # (_assemble of each scene, its lists converted for all at once)
        out[b] = _assemble_lists(S[q], share[q], dom[q], P[q], Z[q], W[q], I[q], M[b], N[b])
    return out


def _align_degenerate(N: np.ndarray, Y: np.ndarray, w2: np.ndarray, tol, groups=None) -> np.ndarray:
    """Within clusters of (nearly) equal eigenvalues the eigenvectors are
    arbitrary; pick the combination whose shapes are aligned with the world
    axes: greedy row pivoting on the cluster's shapes (the world component
    with the largest remaining norm, ties within 1e-6 going to the first
    component), then the basis that is the identity on those components.
    Deterministic: the same choice on every machine.  ``groups``:
    :func:`clusters` of ``w2`` and ``tol`` if already known.  One scene's
    steps; :func:`_align_degenerate_batch` the same on many scenes at once
    (without this function's ~25 us of indexing overhead on one scene)."""
    Y = Y.copy()
    for k, j in (groups if groups is not None else clusters(w2, tol)):
        if j - k < 2:
            continue
        S = N @ Y[:, k:j]  # (6, c)
        T = S
        rows: list[int] = []
        for step in range(j - k):
            norms = np.sqrt(np.add.reduce(T * T, axis=1))  # np.linalg.norm(T, axis=1): its operations
            norms[rows] = -1.0
            r = int(np.argmax(norms >= (1 - 1e-6) * norms.max()))
            rows.append(r)
            if step < j - k - 1:  # (the last pick's projection is never read)
                t = T[r]
                v = t / np.sqrt(t.dot(t))  # np.linalg.norm(t): its operations
                T = T - (T @ v)[:, None] * v[None, :]  # np.outer's product
        Y[:, k:j] = Y[:, k:j] @ np.linalg.inv(S[rows, :])
    return Y


def _align_degenerate_batch(N: np.ndarray, Y: np.ndarray, groups) -> np.ndarray:
    """:func:`_align_degenerate` of many scenes whose eigenvalues form the
    same clusters ``groups`` (``N`` (B, 6, k), ``Y`` (B, k, k)), on the
    stacked arrays: each scene's numbers are those of
    :func:`_align_degenerate` on it alone, bit for bit (the products are
    stacked matrix products, each slice the same BLAS call as one scene's;
    the reductions run along the same contiguous axis; a pick's own
    squared norm is taken scene by scene, ``t.dot(t)`` as there;
    tests/test_perf26b.py).  Returns the aligned Y (a copy)."""
    Y = Y.copy()
    B = len(Y)
    at = np.arange(B)
    for k, j in groups:
        if j - k < 2:
            continue
        S = N @ Y[:, :, k:j]  # (B, 6, c)
        T = S
        rows = np.empty((B, j - k), int)
        for step in range(j - k):
            norms = np.sqrt(np.add.reduce(T * T, axis=2))  # (B, 6)
            if step:
                norms[at[:, None], rows[:, :step]] = -1.0
            r = np.argmax(norms >= (1 - 1e-6) * norms.max(axis=1)[:, None], axis=1)
            rows[:, step] = r
            if step < j - k - 1:  # (the last pick's projection is never read)
                t = T[at, r]  # (B, c)
                v = t / np.array([np.sqrt(x.dot(x)) for x in t])[:, None]
                T = T - (T @ v[:, :, None]) * v[:, None, :]
        Y[:, :, k:j] = Y[:, :, k:j] @ np.linalg.inv(S[at[:, None], rows, :])
    return Y


def degenerate_clusters(w2: np.ndarray, scale: float, rel: float = 1e-8) -> list[tuple[int, int]]:
    """Index ranges [k, j) of clusters of two or more (nearly) equal
    eigenvalues in the ascending array ``w2`` (rad^2/s^2): neighbours within
    ``rel * scale`` of the cluster's first member.  A wider band than the
    canonical :func:`clusters` on purpose: eigenvalue perturbation
    (:mod:`bifilar.analysis.derivatives`) is unreliable for pairs this close
    and falls back to finite differences there."""
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
