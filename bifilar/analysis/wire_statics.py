"""Statics of dependent wires: the linear programmes over the splits of a
wrench that 4 or 5 wires statics cannot split (rank below n) leave open,
the warnings for such rigs (:func:`indeterminate_warning`) and the modes
their wires cannot follow without stretching (:func:`stretching_modes`).

:func:`tension_range` (each wire's least and
greatest tension at rest) and :func:`~bifilar.studies.point.statics_range`
(the greatest a wire can reach in the runs) use them; scipy's ``linprog``
is imported only here.  :func:`held_violation`: a run's length error in the
directions the model holds (nearly dependent wires' self-stresses left
free).  SI units (N, m), world frame.
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from .equilibrium import (RestPose, constraint_hessians, constraint_jacobian, constraint_rank, multiplier_matrix,
                          tensions_determined)


def reduced_statics(scene: Scene, rest: RestPose) -> tuple[np.ndarray, np.ndarray]:
    """(A, P) at the rest pose: A (6, n) the wrench of unit wire tensions
    (rows force, moment about the CoM; ``A T = -grad V`` at rest, world
    frame) and P (rank, 6) the projection on its range, so that ``P A T =
    P f`` are the equilibrium equations without their dependent rows
    (rounding apart; nearly dependent ones too, by the run's rule,
    :func:`~bifilar.analysis.equilibrium.constraint_rank`)."""
    d, _, G = constraint_jacobian(scene, rest.com, rest.R)
    A = (G / np.linalg.norm(d, axis=1)[:, None]).T
    U, sv, _ = np.linalg.svd(A)
    return A, U[:, :constraint_rank(scene, rest.R, G, sv)].T


def split_bounds(A: np.ndarray, P: np.ndarray, f: np.ndarray, fallback: np.ndarray, lower: bool = True) -> np.ndarray:
    """The least and greatest tension (n, 2), in the units of ``f``, each
    wire can carry in a split of the wrench ``f`` (6,) over the wires of
    :func:`reduced_statics` ``(A, P)`` with every wire pulling: a linear
    programme per bound (scipy's HiGHS, ~1 ms each); ``fallback`` (n,) a
    feasible split, kept where a programme fails (never met); ``lower``
    False: the greatest only (the first column is ``fallback``)."""
    from scipy.optimize import linprog  # only for dependent wires

    Ar, br = P @ A, P @ f
    n = A.shape[1]
    out = np.column_stack([fallback, fallback]).astype(float)
    for i in range(n):
        for col, sign in ((0, 1.0), (1, -1.0))[(0 if lower else 1):]:
            c = np.zeros(n)
            c[i] = sign
            res = linprog(c, A_eq=Ar, b_eq=br, bounds=(0, None), method="highs")
            if res.status == 0:
                out[i, col] = float(res.x[i])
    return out


def held_violation(scene: Scene, Y: np.ndarray) -> float:
    """The largest error of the wires' lengths (m) over states ``Y`` (k, 13)
    (world frame, the maximal model's layout) in the directions the model
    holds: each state's constraint errors ``phi_i = (|d_i|^2 - L_i^2) / 2``
    with their components along the eigen-directions of ``J M^-1 J^T`` below
    :data:`~bifilar.models.maximal.MIN_NORM_RCOND` of the largest removed
    (the nearly dependent wires' self-stresses, which
    :func:`~bifilar.models.maximal._min_norm` leaves free: a real rig's wires
    stretch there, docs/design.md "offcentre, session 14"), as lengths
    (``phi_i / L_i``).  On rigs with independent wires, the whole error."""
    from ..models.maximal import held_directions
    from ..rotations import quat_to_matrix

    Y = np.asarray(Y, float)
    R = quat_to_matrix(Y[:, 3:7])  # (k, 3, 3)
    w = np.einsum("kij,nj->kni", R, scene.attachments)  # lever arms, world (k, n, 3)
    d = Y[:, None, :3] + w - scene.anchors  # (k, n, 3)
    L = np.asarray(scene.lengths, float)
    phi = 0.5 * (np.einsum("kni,kni->kn", d, d) - L ** 2)
    G = np.concatenate([d, np.cross(w, d)], axis=2)  # d phi / d(dr, dtheta_world) (k, n, 6)
    ev, V = np.linalg.eigh(multiplier_matrix(scene.mass, scene.inertia, R, G))
    held = held_directions(ev)  # (k, n)
    kept = np.einsum("knj,kj->kn", V, np.where(held, np.einsum("knj,kn->kj", V, phi), 0.0))
    return float(np.max(np.abs(kept) / L))


def tension_range(scene: Scene, rest: RestPose) -> np.ndarray:
    """The least and greatest tension (n, 2) N each wire can carry at the
    rest pose ``rest`` with every wire pulling (``T >= 0``) and the body
    balanced (``sum_i T_i u_i`` and its moment equal to the weight's, ``u_i``
    the wire directions): what statics alone says of the split.  A rig whose
    tensions are determined (:func:`tensions_determined`) has one split, its
    rest tensions in both columns; on dependent wires (4 or 5, rank below n)
    the tensions can move along the self-stresses until a wire goes slack:
    a level table on four vertical wires at the corners of a rectangle,
    CoM at its centre, allows 0 .. m g / 2 for every wire.  A linear
    programme per bound (scipy's HiGHS, ~1 ms each), on the equilibrium
    equations reduced to their rank (dependent rows are rounding apart)."""
    T0 = np.asarray(rest.tensions, float)
    if tensions_determined(scene, rest):
        return np.column_stack([T0, T0])

    W = scene.mass * scene.gravity
    A, P = reduced_statics(scene, rest)
    out = W * split_bounds(A, P, np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0]), T0 / W)  # per unit weight
    return np.where(out < 1e-9 * W, 0.0, out)  # a bound at zero, not the solver's rounding about it


def indeterminate_warning(scene: Scene, rest: RestPose) -> str | None:
    """The warning for a rig whose tensions statics cannot fix (see
    :func:`tensions_determined`), or None.  It says which split the model
    reports (the minimum-norm multipliers ``lambda_i = T_i / L_i``: least
    squares of the tension per unit length, not of the tensions) and the
    range statics leaves each wire (:func:`tension_range`)."""
    if scene.stiffness is not None and scene.n_wires > 3:
        return run_split_warning(scene, rest)
    if tensions_determined(scene, rest):
        return None
    rng = tension_range(scene, rest)
    spans = ", ".join(f"wire {i + 1} {lo:.4g} .. {hi:.4g} N" for i, (lo, hi) in enumerate(rng))
    return (f"rig: the {scene.n_wires} wires are {dependence_words(scene, rest)} at rest, so their tensions are "
            "statically indeterminate: "
            f"statics allows {spans} (any split in these ranges with the same resultant holds the body); those shown "
            "are the model's split, the least-squares multipliers T_i / L_i (tension per metre of wire, not the "
            "tensions themselves: on wires of unequal length it favours the longer ones, where equal elastic "
            "wires favour the shorter); the real split is set by the wires' stretch and their lengths' tolerances")


#: the run's split at rest is "different" from the elastic one where a wire's tension differs by more than this
#: fraction of the mean load W / n (0.025 N on the test table: 0.1 % of a wire's load, above the two's rounding)
RUN_SPLIT_REL = 1e-3


def run_split_warning(scene: Scene, rest: RestPose) -> str | None:
    """On 4 or 5 wires of a stated stiffness (``rig.stiffness``, whose rest
    pose is the elastic one), the warning that the run (the rigid-wire
    model, :mod:`bifilar.models.maximal`: the nearly dependent directions'
    split by its minimum-norm rule) starts with another split than the
    rest pose's elastic one, or None when they agree to
    :data:`RUN_SPLIT_REL` of the mean load."""
    import bifilar.models.maximal as mx
    from ..rotations import matrix_to_quat
    from .elastic_rest import loaded_scene
    from .equilibrium import _newton_kkt

    scene = loaded_scene(scene, rest)  # the run's wires: loaded, the elastic pose on them
    # the run starts on rigid wires: at the pose nearest the elastic one with every wire at its length (the
    # start of a run of zero amplitude), its multipliers
    c, R, _, kkt = _newton_kkt(scene, rest.com, rest.R, iters=30)
    if not kkt < 1e-9:
        c, R = rest.com, rest.R
    P = mx.params_from_scenes(scene)
    run0 = np.asarray(mx.tensions(mx.pack(c, matrix_to_quat(R))[None], P)[0], float)
    T = np.asarray(rest.tensions, float)
    load = scene.mass * scene.gravity / scene.n_wires
    k = int(np.argmax(np.abs(run0 - T)))
    if not abs(run0[k] - T[k]) > RUN_SPLIT_REL * load:
        return None
    return (f"rig.stiffness: the rest pose's tensions are the elastic wires' split (wire {k + 1} {T[k]:.4g} N), but "
            f"the run (simulate, tensions, sweep's and plan's tensions) is the rigid-wire model, whose split on the loaded "
            f"wires differs (wire {k + 1} {run0[k]:.4g} N): its tensions are not the elastic wires'; the motion and "
            "the periods are the rigid model's about the loaded rig")


def dependence_words(scene: Scene, rest: RestPose) -> str:
    """'dependent' for wires whose constraint Jacobian at rest has rank below
    n (singular values at 1e-12 of the largest: parallel vertical wires),
    'nearly dependent (...)' for those the model treats as dependent by the
    run's rule though geometry holds them independent (anchors off by less
    than a length tolerance, :func:`~bifilar.analysis.equilibrium.constraint_rank`),
    with their smallest singular value relative to the largest."""
    _, _, G = constraint_jacobian(scene, rest.com, rest.R)
    sv = np.linalg.svd(G, compute_uv=False)
    if sv[-1] <= 1e-12 * sv[0]:
        return "dependent"
    return (f"nearly dependent (independent by geometry, but the smallest singular value of their directions is "
            f"{sv[-1] / sv[0]:.2g} of the largest: the model takes them as dependent, as the run does)")


#: a mode of a dependent rig whose second-order change of the wires' lengths has a self-stress component
#: above this fraction of its size cannot be followed with every wire at its length (see :func:`stretching_modes`);
#: a symmetric rig's modes give rounding there (1e-16), a 4-wire table with wires of 1.0 .. 1.6 m 0.03 .. 0.06
STRETCH_REL = 1e-6


def stretching_modes(scene: Scene, rest: RestPose, modes) -> list[tuple[str, float]]:
    """The linear modes of a rig with dependent wires (4 or 5 at rest,
    :func:`tensions_determined` false) along which the wires cannot all keep
    their lengths: (label, share) for each, ``share`` the part of the second-
    order change of the constraints along the mode's shape ``v``
    (``q_i = v^T H_i v``, :func:`constraint_hessians`) in the rig's
    self-stress directions (the null space of ``G^T``), relative to ``|q|``.

    Where it is zero (a symmetric rig: a twist lifts every corner of a
    table on equal vertical wires alike) the body follows the mode on the
    wires; where not (the same table on wires of unequal length: a twist
    lifts each corner by ``r^2 theta^2 / 2 L_i``, which no rigid tilt fits),
    rigid wires admit no motion along the mode alone: the model's body must
    swing as well, at first order, and hold the wires by tensions that push
    (measured on such a table: tensions of -734 N at 0.001 rad for a 98 N
    body, a period 0.1 % off the linear one at 1e-5 rad).  A real rig's
    wires stretch by that second-order amount instead, so its small
    oscillations are the linear modes, and the rigid model's nonlinear runs
    of such a mode are not physical at any amplitude.  [] when the wires
    are independent."""
    d, w, G = constraint_jacobian(scene, rest.com, rest.R)
    U, sv, _ = np.linalg.svd(G)
    rank = constraint_rank(scene, rest.R, G, sv)
    if rank >= scene.n_wires:
        return []
    S = U[:, rank:]  # orthonormal self-stresses (n, n - rank)
    H = constraint_hessians(d, w)
    out = []
    for m in modes:
        v = np.asarray(m.shape, float)
        q = np.einsum("i,nij,j->n", v, H, v)
        nq = float(np.linalg.norm(q))
        share = float(np.linalg.norm(S.T @ q)) / nq if nq > 0 else 0.0
        if share > STRETCH_REL:
            out.append((m.label, share))
    return out


def stretching_warning(scene: Scene, rest: RestPose, modes, only: str | None = None) -> str | None:
    """The warning for the modes :func:`stretching_modes` finds (``only``: a
    mode label, warned about alone), or None."""
    hits = [lb for lb, s in stretching_modes(scene, rest, modes) if only is None or lb == only]
    return stretching_text(scene, hits) if hits else None


def stretching_text(scene: Scene, labels: list) -> str:
    """The warning of :func:`stretching_warning` for modes ``labels``."""
    return (f"rig: {stretching_reason(scene, labels)}, so its nonlinear runs of it (simulate, invert --amplitude, "
            "tensions, sweep's and plan's tensions and amplitude terms) are not physical at any amplitude; a real "
            "rig's wires stretch instead and its small oscillations keep the linear periods: time them at a small "
            "amplitude and give invert --amplitude 0")


def stretching_reason(scene: Scene, labels: list) -> str:
    """Why the rigid-wire model cannot follow modes ``labels`` (found by
    :func:`stretching_modes`) of ``scene``: the words every command's
    warning or refusal of it shares."""
    names = ", ".join(f"'{lb}'" for lb in labels)
    return (f"the {scene.n_wires} wires are dependent at rest and mode{'s' if len(labels) > 1 else ''} {names} "
            "would stretch them at second order (a twist or swing lifts their ends by unequal amounts that no tilt "
            "of the body fits): the rigid-wire model follows such a motion only with the body swinging as well and "
            "wires that push")
