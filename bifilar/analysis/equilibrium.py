"""Rest pose: static equilibrium of the body on taut wires.

The rest pose minimises the potential energy ``m g z_com`` over poses in
which no wire is longer than its length (wires can go slack, never stretch).
It is found in three stages:

1. translate the body (axes aligned with the world, as ``interface.md``
   prescribes for the start) below the anchors;
2. Newton's method on the KKT equations with every wire taut, from that
   start; its pose is taken when it is a strict local minimum of the
   inequality-constrained problem (every tension positive, reduced stiffness
   positive definite: the second-order sufficient conditions) within the
   start orientation's 90-degree box, which is the common case and needs no
   scipy;
3. otherwise SLSQP over the 6 pose coordinates with the inequality
   constraints ``|d_i| <= L_i`` (exact constraint Jacobian), the rotation
   kept within 90 degrees of the start so that a body that would rather flip
   over is caught, not silently flipped; then Newton on the KKT equations
   with every wire taut, to machine precision, giving the multipliers, hence
   the tensions.

A wire left slack by stage 2, or a negative tension in stage 3, is a
:class:`~bifilar.errors.SlackWireError` naming the wire and by how much to
shorten it; a reduced stiffness that is not positive definite is an
:class:`~bifilar.errors.UnstableRestError`.

A knife edge (CoM on the line through every attachment point) rests anywhere
on a circle of turns about that line; its rest pose is the turn nearest the
start orientation (:func:`canonical_attitude`), whatever the start.
"""

from __future__ import annotations

import contextvars
import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConvergenceError, InputError, SlackWireError, UnstableRestError
from ..rotations import cross, matrix_to_quat, matrix_to_rotvec, rotvec_to_matrix, skew
from ..models.maximal import MAX_ELIMINATION_WIRES, held_directions, min_norm_multipliers
from ..scene import Scene, lowest_point_z
from .stretch_held import held_mask, soft_reduction, stretch_split


@dataclass(frozen=True)
class RestPose:
    """Static equilibrium of a scene (SI units, world frame).

    com : (3,) CoM position, m.  R : (3, 3) rotation body -> world.
    q : (4,) the same as a quaternion.  tensions : (n,) N.
    wire_vectors : (n, 3) anchor -> attachment, m.
    lowest_z : world z of the lowest body point, m; depth : ceiling height
    minus lowest_z, m (room height needed below the ceiling at rest).
    kkt_residual : max-norm of the equilibrium equations, N (force) scale.
    """

    com: np.ndarray
    R: np.ndarray
    q: np.ndarray
    tensions: np.ndarray
    wire_vectors: np.ndarray
    lowest_z: float
    depth: float
    kkt_residual: float


def constraint_jacobian(scene: Scene, com: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wire vectors d (n,3), world lever arms w = R p (n,3) and the Jacobian
    G (n, 6) of phi_i = (|d_i|^2 - L_i^2)/2 with respect to (dr, dtheta),
    dtheta a small world-frame rotation vector (R -> exp(dtheta) R)."""
    w = scene.attachments @ R.T
    d = com + w - scene.anchors
    # [d, w x d], the cross product written out with np.cross's own operations (a1 b2 - a2 b1, ...:
    # the same numbers) without its per-call overhead (every Newton step and stiffness calls this)
    G = np.empty((d.shape[0], 6), dtype=np.result_type(d, w))
    G[:, :3] = d
    G[:, 3] = w[:, 1] * d[:, 2] - w[:, 2] * d[:, 1]
    G[:, 4] = w[:, 2] * d[:, 0] - w[:, 0] * d[:, 2]
    G[:, 5] = w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]
    return d, w, G


def constraint_hessians(d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Hessians (n, 6, 6) of phi_i in the (dr, dtheta) chart at the current pose."""
    n = d.shape[0]
    H = np.zeros((n, 6, 6))
    eye = np.eye(3)
    for i in range(n):
        x, y, z = w[i].tolist()
        W = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])  # skew(w[i]), built without np.stack
        H[i, :3, :3] = eye
        H[i, :3, 3:] = -W
        H[i, 3:, :3] = W
        H[i, 3:, 3:] = -W @ W + 0.5 * (np.outer(d[i], w[i]) + np.outer(w[i], d[i])) - np.dot(d[i], w[i]) * eye
    return H


def multiplier_matrix(mass, inertia, R: np.ndarray, G: np.ndarray) -> np.ndarray:
    """``G M^-1 G^T`` (..., n, n) (m^2 / kg): the
    run's multiplier matrix ``J M^-1 J^T`` at poses with attitudes ``R``
    (..., 3, 3) (body -> world), ``G`` (..., n, 6) the constraint Jacobian
    of :func:`constraint_jacobian`, M the body's mass (kg, scalar or (...,))
    and its inertia (kg m^2, body frame, (3, 3) or (..., 3, 3)) turned to
    the world.  Vectorised over leading axes."""
    Gt = np.swapaxes(G, -1, -2)
    Iw = R @ np.linalg.inv(np.asarray(inertia, float)) @ np.swapaxes(R, -1, -2)
    return G[..., :3] @ Gt[..., :3, :] / np.asarray(mass, float)[..., None, None] + G[..., 3:] @ Iw @ Gt[..., 3:, :]


def constraint_rank(scene: Scene, R: np.ndarray, G: np.ndarray, sv: np.ndarray | None = None) -> int:
    """The number of wire constraints the model holds at a pose (attitude
    ``R``, Jacobian ``G`` (n, 6); ``sv`` G's singular values if known).
    Up to :data:`~bifilar.models.maximal.MAX_ELIMINATION_WIRES` wires (the
    run's exact elimination): G's rank (singular values above 1e-12 of the
    largest).  More wires: the run's rule (:func:`~bifilar.models.maximal.
    held_directions`, eigenvalues of ``G M^-1 G^T`` at or above 1e-6 of the
    largest), so that a rig whose wires are only nearly dependent (anchors
    splayed by less than a length tolerance) is dependent at rest as in the
    run (docs/design.md "restrank, session 14").  Elastic wires
    (``rig.stiffness``) on 4 or 5: the directions whose stretch stiffness is
    at least :data:`~bifilar.analysis.stretch_held.STRETCH_HOLD` times their
    geometric one (:func:`~bifilar.analysis.stretch_held.held_mask`); a
    direction the wires resist only by a little stretch (a splay of 1 mm on
    1.2 m wires: 3.5e-5 .. 3.5e-4 of its geometric stiffness at EA 2 .. 20
    kN) is a pendulum direction, its stretch carried elastically by
    :func:`reduced_stiffness` (docs/design.md "elastic26, session 26";
    before, the run's eigenvalue rule, which held it where a millimetre
    splayed the wires)."""
    if G.shape[0] > MAX_ELIMINATION_WIRES and scene.stiffness is not None:
        mu, kappa, _, _ = stretch_split(scene, R, G)
        if mu[0] > 0:  # (a pose with no wire stretched, the rigid all-taut start: the eigenvalue rule, below)
            return int(np.sum(held_mask(mu, kappa)))
    if sv is None:
        sv = np.linalg.svd(G, compute_uv=False)
    if G.shape[0] > MAX_ELIMINATION_WIRES and (near_dependent(sv) or scene.stiffness is not None):
        return int(np.sum(held_directions(np.linalg.eigvalsh(multiplier_matrix(scene.mass, scene.inertia, R, G)))))
    return int(np.sum(sv > 1e-12 * sv[0]))


#: wires whose Jacobian's smallest singular value is below this fraction of its largest (a splay of ~1e-5 of
#: the wires' length: less than their stretch under load) take the run's rank rule at rest; above it the
#: rank is geometric.  The run's rule weighs by the body's mass and inertia, so on its own it made the
#: rest's rank jump with the inertia invert solves for (random 4-wire rigs with singular values 1e-4 .. 3e-3
#: gained and lost a mode across the cut-off; docs/design.md "restrank, session 14")
NEAR_DEPENDENT_SV = 1e-5


def near_dependent(sv: np.ndarray) -> np.ndarray:
    """Whether wires with constraint-Jacobian singular values ``sv`` (..., n),
    descending, are within :data:`NEAR_DEPENDENT_SV` of dependent."""
    sv = np.asarray(sv, float)
    return sv[..., -1] < NEAR_DEPENDENT_SV * sv[..., 0]


def rest_multipliers(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The multipliers (n,) N/m (``T_i / |d_i|``) the run takes at a rest
    pose (com m, R body -> world) whose equilibrium equations Newton solved
    with ``lam``: on more than :data:`~bifilar.models.maximal.
    MAX_ELIMINATION_WIRES` wires the run's minimum-norm solution with its
    cut-off (:func:`~bifilar.models.maximal.min_norm_multipliers` of
    ``G M^-1 G^T lam = G M^-1 (-grad V)``), so nearly dependent wires get
    the dependent-wire split at rest too; ``lam`` itself where that differs
    from it by rounding only (1e-12 of the largest: independent and exactly
    dependent rigs keep their poses' numbers bit for bit) and on fewer
    wires."""
    if scene.n_wires <= MAX_ELIMINATION_WIRES:
        return lam
    _, _, G = constraint_jacobian(scene, com, R)
    if not near_dependent(np.linalg.svd(G, compute_uv=False)):
        return lam
    A = multiplier_matrix(scene.mass, scene.inertia, R, G)
    Minv_f = np.concatenate([np.zeros(2), [-scene.gravity], np.zeros(3)])  # M^-1 (-grad V): gravity's acceleration
    split = min_norm_multipliers(A, G @ Minv_f)
    if np.max(np.abs(split - lam)) <= 1e-12 * np.max(np.abs(lam)):
        return lam
    return split


def start_coms(anchors: np.ndarray, attachments: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """CoM (..., 3) of the start pose (world, m): the body, axes along the
    world axes (interface.md), centred below the anchors (anchors,
    attachments (..., n, 3), m; lengths (..., n), m) and low enough that
    every wire is at most its length.  Vectorised over leading axes (the
    batched rest poses start from the same pose as :func:`rest_pose`)."""
    a, p, L = anchors, attachments, lengths
    xy = np.mean(a[..., :2] - p[..., :2], axis=-2)
    horiz = np.linalg.norm(a[..., :2] - (xy[..., None, :] + p[..., :2]), axis=-1)
    drop = np.sqrt(np.maximum(L**2 - horiz**2, (0.5 * L) ** 2))
    z = np.min(a[..., 2] - p[..., 2] - drop, axis=-1)  # every wire at most its length
    return np.concatenate([xy, z[..., None]], axis=-1)


def _initial_pose(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    return start_coms(scene.anchors, scene.attachments, scene.lengths), np.eye(3)


def _left_jacobian(x: np.ndarray) -> np.ndarray:
    """Left Jacobian J of SO(3) at rotation vector ``x`` (rad):
    exp(x + dx) = exp(J dx) exp(x) to first order."""
    th = float(np.linalg.norm(x))
    K = skew(x)
    if th < 1e-6:
        return np.eye(3) + 0.5 * K + K @ K / 6.0
    return np.eye(3) + (1 - np.cos(th)) / th**2 * K + (th - np.sin(th)) / th**3 * (K @ K)


def _slsqp(scene: Scene, com0: np.ndarray, R0: np.ndarray, jacobian: bool = True):
    """SLSQP stage; ``jacobian=False`` lets SLSQP difference the constraints
    itself (slower; tests compare the two)."""
    from scipy.optimize import minimize  # only when the Newton start fails (slack wire, flip, ...)

    L = scene.lengths
    scale = float(np.max(L))

    def pose(x):
        return com0 + scale * x[:3], rotvec_to_matrix(x[3:]) @ R0

    def fun(x):
        return x[2]

    def jac_f(x):
        g = np.zeros(6)
        g[2] = 1.0
        return g

    def cons(x):
        c, R = pose(x)
        d = c + scene.attachments @ R.T - scene.anchors
        return 0.5 * (L**2 - np.einsum("ij,ij->i", d, d)) / scale**2

    def cons_jac(x):
        c, R = pose(x)
        _, _, G = constraint_jacobian(scene, c, R)
        # chain rule: translation scaled by ``scale``; rotation exp(x) R0 with the left Jacobian of SO(3)
        Jr = -G[:, :3] / scale
        Jt = -(G[:, 3:] @ _left_jacobian(x[3:])) / scale**2
        return np.hstack([Jr, Jt])

    bounds = [(None, None)] * 3 + [(-np.pi / 2, np.pi / 2)] * 3
    res = minimize(
        fun, np.zeros(6), jac=jac_f, method="SLSQP", bounds=bounds,
        constraints=[{"type": "ineq", "fun": cons, **({"jac": cons_jac} if jacobian else {})}], options={"maxiter": 500, "ftol": 1e-14},
    )
    c, R = pose(res.x)
    at_bound = bool(np.any(np.abs(res.x[3:]) > START_BOX))
    return c, R, res, at_bound


#: margin (rad) of the 90-degree box about the start orientation: a rest pose
#: whose rotation vector from the start has a component beyond ``START_BOX`` =
#: pi/2 - this margin is refused (the body would turn over), by the global
#: search (SLSQP at its bound) and by every other path alike (:func:`_finish`)
START_BOX_MARGIN = 1e-3
START_BOX = np.pi / 2 - START_BOX_MARGIN

#: a two-wire rig's CoM is taken to hang straight below its attachment line
#: when the turn about that line which would put it there is at most this
#: (rad); a larger one (a Newton end with the CoM beside the line, e.g. level
#: with it, where that turn has no stiffness, or straight above it, where the
#: stiffness m g h is negative but too small for the eigenvalue test when h
#: is) is turned about the line in closed form (:func:`_hang_below_line`)
#: and polished again
LINE_TURN_TOL = 1e-6


#: smallest sine of the steepest wire's angle to horizontal at rest: below it every wire is straight across
#: (tension > weight / (n 1e-5)), the sag below the solver's length tolerance, the pose set by rounding
MIN_WIRE_SLOPE = 1e-5

#: largest turn (rad) from the start orientation at which the Newton start's
#: pose is taken without the global search
NEWTON_START_MAX_TURN = 0.5


def _newton_start(scene: Scene, com0: np.ndarray, R0: np.ndarray) -> RestPose | None:
    """Stage 2: Newton on the all-taut KKT equations from the start pose.

    Returns the rest pose when Newton converges to a strict local minimum of
    the inequality-constrained problem (KKT residual < 1e-9, every multiplier
    positive, reduced stiffness positive definite: second-order sufficient
    conditions, checked by :func:`_finish`) whose rotation from the start
    is at most :data:`NEWTON_START_MAX_TURN`; else None (the caller runs
    SLSQP, which names slack wires and flips, and finds the pose a larger
    turn leads to)."""
    try:
        c, R, lam, kkt = _polish(scene, com0.copy(), R0.copy(), iters=40)
    except np.linalg.LinAlgError:
        return None
    if not (kkt < 1e-9) or not np.all(lam > 0):
        return None
    if np.linalg.norm(matrix_to_rotvec(R @ R0.T)) > NEWTON_START_MAX_TURN:
        # far from the start orientation another stable equilibrium may be
        # the one the global search finds (the fuzzing found a 3-wire rig with
        # two): leave such bodies to it
        return None
    try:
        return _finish(scene, c, R, lam, kkt)
    except Exception:  # noqa: BLE001 - unstable or slack here: SLSQP decides and explains
        return None


def _newton_kkt(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray | None = None, iters: int = 60):
    """Newton on grad V + G^T lam = 0, phi = 0.  Returns com, R, lam, residual."""
    m, g = scene.mass, scene.gravity
    n = scene.n_wires
    gradV = np.array([0, 0, m * g, 0, 0, 0], float)
    L = scene.lengths
    d, w, G = constraint_jacobian(scene, com, R)
    if lam is None:
        lam = -np.linalg.lstsq(G.T, gradV, rcond=None)[0]
    force_scale = m * g
    # solved dimensionless (unknowns dr / L, dtheta, dlam L^2 / (m g); rows force / (m g), moment / (m g L),
    # phi / L^2), by least squares: the Newton step when K is regular, the minimum-norm step when a
    # neutral direction (CoM on the attachment line) or dependent wires make it singular; the scales
    # (and L^2) once, not every step
    Ls = float(np.max(L))
    cs = np.concatenate([np.full(3, Ls), np.ones(3), np.full(n, force_scale / Ls**2)])
    rs = np.concatenate([np.full(3, 1 / force_scale), np.full(3, 1 / (force_scale * Ls)), np.full(n, 1 / Ls**2)])
    L2, Lsq, lim = L**2, np.max(L) ** 2, 0.2 * np.max(L)  # lim: the largest CoM step (damping)
    prev = np.inf
    for _ in range(iters):
        d, w, G = constraint_jacobian(scene, com, R)
        phi = 0.5 * (np.einsum("ij,ij->i", d, d) - L2)
        r1 = gradV + G.T @ lam
        res = max(np.max(np.abs(r1)) / force_scale, np.max(np.abs(phi)) / Lsq)
        # converged, or at the rounding floor (a singular system: dependent
        # wires or a neutral direction stall at ~1e-14 instead of 1e-15)
        if res < 1e-15 or (res < 1e-12 and res > 0.5 * prev):
            break
        prev = res
        H = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
        K = np.zeros((6 + n, 6 + n))
        K[:6, :6] = H
        K[:6, 6:] = G.T
        K[6:, :6] = G
        step = cs * np.linalg.lstsq(rs[:, None] * K * cs[None, :], -rs * np.concatenate([r1, phi]), rcond=None)[0]
        # damp huge steps (far from the solution)
        dx = step[:6]
        s = min(1.0, lim / max(np.max(np.abs(dx[:3])), 1e-300), 0.5 / max(np.max(np.abs(dx[3:])), 1e-300))
        com = com + s * dx[:3]
        R = rotvec_to_matrix(s * dx[3:]) @ R
        lam = lam + s * step[6:]
    d, w, G = constraint_jacobian(scene, com, R)
    phi = 0.5 * (np.einsum("ij,ij->i", d, d) - L**2)
    res = max(np.max(np.abs(gradV + G.T @ lam)) / force_scale, np.max(np.abs(phi)) / np.max(L) ** 2)
    return com, R, lam, res


def _polish(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray | None = None, iters: int = 60):
    """:func:`_newton_kkt`; where it leaves a two-wire rig's CoM beside the
    attachment line (not straight below or above it: no equilibrium, though
    the residual may be within tolerance when the CoM is level with the line,
    where the turn about it has no stiffness and gravity's moment is only
    m g times the offset), the closed-form turn about the line
    (:func:`_hang_below_line`) and Newton again from there.  Same returns."""
    c, R, lam, kkt = _newton_kkt(scene, com, R, lam, iters=iters)
    turned = _hang_below_line(scene, c, R)
    if turned is not None:
        c, R, lam, kkt = _newton_kkt(scene, *turned, iters=iters)
    return c, R, rest_multipliers(scene, c, R, lam), kkt


def reduced_stiffness(scene: Scene, com: np.ndarray, R: np.ndarray, lam: np.ndarray):
    """Null-space basis N (6, k) of the constraint Jacobian, the reduced
    stiffness N^T K N and mass N^T M N (k, k) at an equilibrium, in the
    (dr, dtheta) world chart; K is the Hessian of the Lagrangian V + lam.phi."""
    d, w, G = constraint_jacobian(scene, com, R)
    K = np.einsum("i,ijk->jk", lam, constraint_hessians(d, w))
    M = np.zeros((6, 6))
    M[:3, :3] = scene.mass * np.eye(3)
    M[3:, 3:] = R @ scene.inertia @ R.T
    if G.shape[0] > MAX_ELIMINATION_WIRES and scene.stiffness is not None:
        soft = soft_reduction(scene, R, G, lam, K)
        if soft is not None:  # held rigidly: the strong stretches; the others' springs in K
            N, K, rank = soft
            return N, N.T @ K @ N, N.T @ M @ N, rank
    _, s, vt = np.linalg.svd(G)
    rank = constraint_rank(scene, R, G, s)
    N = vt[rank:].T
    return N, N.T @ K @ N, N.T @ M @ N, rank


def tensions_determined(scene: Scene, rest: RestPose) -> bool:
    """Whether the wire tensions at rest follow from statics alone: the wire
    directions' constraint Jacobian has full rank n (else 4 or 5 dependent
    wires, e.g. parallel vertical ones, admit a self-stress and the tensions
    printed are only one split
    (:func:`~bifilar.analysis.wire_statics.indeterminate_warning`); the real
    one depends on the wires' stretch).  Same rank rule as :func:`reduced_stiffness` (:func:`constraint_rank`).
    True on 4 or 5 wires of a stated stiffness (``rig.stiffness``): their
    elastic statics fixes the split (:func:`~bifilar.analysis.elastic_rest.elastic_rest_pose`)."""
    if scene.stiffness is not None and scene.n_wires > MAX_ELIMINATION_WIRES:
        return True
    return not _wires_dependent(scene, rest.com, rest.R)


def _wires_dependent(scene: Scene, com: np.ndarray, R: np.ndarray) -> bool:
    """Whether the wire directions in the pose (com m, R body -> world) are
    linearly dependent as constraints (:func:`constraint_rank` below n)."""
    _, _, G = constraint_jacobian(scene, com, R)
    return constraint_rank(scene, R, G) < scene.n_wires


def rest_pose(scene: Scene, guess: RestPose | None = None, local_only: bool = False,
              global_search: bool = False) -> RestPose:
    """Find the static equilibrium of ``scene`` with every wire taut.

    The rest pose is the stable equilibrium reached from the start pose (the
    body's axes along the world axes, below the anchors): a rig may have
    more than one (a trifilar with strongly leaning wires, a CoM far off
    centre), and which one a search ends at depends on where it starts.

    ``guess``: the rest pose of a nearby scene (a finite-difference
    neighbour), used only with ``local_only``: Newton starts from it and the
    equilibrium on the guess's branch is returned, or
    :class:`ConvergenceError` (finite differences want the neighbouring
    equilibrium or nothing).  Without ``local_only`` the guess is ignored:
    a neighbour's pose could lead to another stable equilibrium than the
    start pose does (tests/test_multi_equilibria.py), and the search from
    the start pose costs little more (~1 ms).
    ``global_search``: skip the Newton start (stage 2) and always run SLSQP
    (tests compare the two).

    Raises
    ------
    SlackWireError
        A wire cannot be taut at rest (names it, says how much to shorten it).
    UnstableRestError
        The equilibrium near the start orientation is unstable (e.g. CoM
        above the attachment points).
    ConvergenceError
        The solver failed.
    """
    if scene.stiffness is not None:
        from .elastic_rest import elastic_rest_pose

        return elastic_rest_pose(scene, guess if local_only else None)
    if guess is not None and local_only:
        quick = _from_guess(scene, guess)
        if quick is not None:
            return quick
        raise ConvergenceError("no taut, stable rest pose near the guess")
    com0, R0 = _initial_pose(scene)
    if not global_search:
        quick = _newton_start(scene, com0, R0)
        if quick is not None:
            return quick
    c, R, res, at_bound = _slsqp(scene, com0, R0)
    L = scene.lengths
    d = c + scene.attachments @ R.T - scene.anchors
    stretch = np.linalg.norm(d, axis=1) - L
    tol = 1e-6 * np.max(L)
    if np.max(stretch) > tol:  # no pose found with every wire within its length
        _check_reach(scene, c, R, tol)  # InputError if there is none
        if at_bound:
            # the only poses within reach are turned by 90 degrees or more from
            # the start orientation: an input problem, like turning over
            raise UnstableRestError("rig.attachments", "the body cannot hang within 90 degrees of its start "
                                    "orientation (body axes along the world axes): the attachments do not face "
                                    "the anchors; check their order and the body frame")
        if np.isfinite(line_turns(scene.attachments, R)[0]):
            # two wires, CoM off their line: SLSQP fails where the turn about the line is all but free (CoM
            # within a hair of the line), but that turn is known in closed form (_polish): Newton from here
            c, R, lam, kkt = _polish(scene, c, R)
            if kkt < 1e-9 and np.all(lam > 0):
                return _finish(scene, c, R, lam, kkt)
        raise ConvergenceError(f"rest pose search failed: {res.message}")
    if at_bound:
        raise _turn_refusal(scene, R0, R)
    slack = np.where(stretch < -tol)[0]
    if len(slack):
        try:
            c2, R2, lam2, kkt2 = _polish(scene, c, R)  # the pose with every wire at its length
        except np.linalg.LinAlgError:
            kkt2 = np.inf
        if kkt2 < 1e-9:
            from .elastic_rest import refuse_nearly_dependent

            refuse_nearly_dependent(scene, slack, -stretch[slack], c2, R2, lam2)
        _raise_slack(scene, slack, -stretch[slack], L, pose=(c, R))
    return _finish(scene, *_polish(scene, c, R))


def _from_guess(scene: Scene, guess: RestPose) -> RestPose | None:
    if scene.stiffness is not None:  # elastic wires: their equilibrium from the neighbour's (Newton on the potential)
        from .elastic_rest import elastic_rest_pose

        try:
            r = elastic_rest_pose(scene, guess)
        except (SlackWireError, UnstableRestError, ConvergenceError, InputError, np.linalg.LinAlgError):
            return None
        turn = np.arccos(np.clip((np.trace(r.R @ guess.R.T) - 1) / 2, -1, 1))
        return r if turn <= 0.05 else None
    lam0 = guess.tensions / np.linalg.norm(guess.wire_vectors, axis=1)
    if lam0.shape[0] != scene.n_wires:
        return None
    c, R, lam, kkt = _polish(scene, guess.com.copy(), guess.R.copy(), lam0.copy(), iters=30)
    if not kkt < 1e-9 or np.any(lam <= 0):
        return None
    # a neutral direction (CoM on the attachment line) lets Newton wander to a far pose:
    # that is not the neighbour's equilibrium
    turn = np.arccos(np.clip((np.trace(R @ guess.R.T) - 1) / 2, -1, 1))
    if turn > 0.05:
        return None
    try:
        return _finish(scene, c, R, lam, kkt)
    except Exception:  # noqa: BLE001 - fall back to the global search
        return None


#: the CoM and every attachment point lie on one line (a knife edge) when each
#: attachment is off the line through the CoM and the farthest attachment by at
#: most this fraction of that farthest one's distance from the CoM: turning the
#: body about the line then moves the wire ends by less than the rest pose's tolerance
KNIFE_EDGE_RTOL = 1e-12


def knife_edge_axes(attachments: np.ndarray) -> np.ndarray:
    """Unit body-frame direction (..., 3) of the line through the CoM (the
    body origin) and every attachment point, for attachments (..., n, 3)
    (body frame, m); NaN where they are not on one line (within
    :data:`KNIFE_EDGE_RTOL`).  On such a rig (the thesis plate, CoM on CD)
    turning the body about that line changes neither a wire nor the CoM
    height: a neutral direction, every turn an equilibrium (see
    :func:`canonical_attitude`).  The sign of the direction is immaterial
    there.  Vectorised over leading axes."""
    p = np.asarray(attachments, float)
    r = np.sqrt(np.einsum("...ni,...ni->...n", p, p))
    k = np.argmax(r, axis=-1)
    rk = np.take_along_axis(r, k[..., None], axis=-1)  # (..., 1)
    u = np.take_along_axis(p, k[..., None, None], axis=-2)[..., 0, :] / np.where(rk > 0, rk, 1.0)
    off = p - np.einsum("...ni,...i->...n", p, u)[..., None] * u[..., None, :]
    on = (rk[..., 0] > 0) & np.all(np.sqrt(np.einsum("...ni,...ni->...n", off, off)) <= KNIFE_EDGE_RTOL * rk, axis=-1)
    return np.where(on[..., None], u, np.nan)


def canonical_attitude(R: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """The rest attitude of a knife edge: ``R`` (..., 3, 3, body -> world)
    turned about the body axis ``axis`` (..., 3, unit, from
    :func:`knife_edge_axes`) to the turn nearest the start orientation (body
    axes along the world axes): largest trace, i.e. least rotation angle from
    the identity.  Closed form: tr(R exp(phi [n]x)) = tr R + A sin(phi) +
    B (1 - cos(phi)), A = tr(R [n]x), B = n.R n - tr R, largest at
    phi = atan2(A, -B).  It depends on the scene alone, not on the pose
    Newton ended at on the neutral circle (a neighbour's warm start, the
    batch, rounding).  Wire vectors, CoM and multipliers are unchanged to
    rounding (the attachments are on the axis).  Vectorised over leading axes."""
    R = np.asarray(R, float)
    n = np.asarray(axis, float)
    A = np.einsum("...ij,...ji->...", R, skew(n))
    B = np.einsum("...i,...ij,...j->...", n, R, n) - np.einsum("...ii->...", R)
    phi = np.arctan2(A, -B)
    return R @ rotvec_to_matrix(phi[..., None] * n)


#: a two-wire rig's attachment line counts as vertical (no "below" across it) when
#: the sine of its angle to the vertical is below this
_VERTICAL_LINE = 1e-6


def _line_frame(attachments: np.ndarray, R: np.ndarray):
    """World frame of a two-wire rig's attachment line in attitude ``R``
    (..., 3, 3, body -> world; attachments (..., 2, 3), body frame, m):
    n, the line's direction (attachment 1 to 2); down, the unit vector across
    the line in the vertical plane through it, pointing down; side = n x down
    (horizontal); and v, the CoM minus its foot on the line (m, across the
    line).  Vectorised over leading axes."""
    p = np.asarray(attachments, float)
    u = p[..., 1, :] - p[..., 0, :]
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    foot = p[..., 0, :] - np.einsum("...i,...i->...", p[..., 0, :], u)[..., None] * u  # CoM -> line, body
    n = np.einsum("...ij,...j->...i", R, u)
    v = -np.einsum("...ij,...j->...i", R, foot)
    zp = np.array([0.0, 0.0, 1.0]) - n[..., 2:3] * n  # vertical, across the line
    nz = np.linalg.norm(zp, axis=-1, keepdims=True)
    down = -zp / np.where(nz > 0, nz, 1.0)
    return n, down, cross(n, down), v, nz[..., 0]


def line_turns(attachments: np.ndarray, R: np.ndarray, edge_axes: np.ndarray | None = None):
    """Two-wire rig (attachments (..., 2, 3), body frame, m) in attitude
    ``R`` (..., 3, 3, body -> world): the turn psi (rad, in (-pi, pi],
    right-handed about n) that brings the CoM straight below the attachment
    line, and n (..., 3), the line's world direction (attachment 1 to 2).

    The wires pull on points of that line only, so at rest gravity has no
    moment about it: the CoM lies in the vertical plane through the line,
    and below it when stable (the stiffness of the turn about the line is
    m g times the CoM's depth below it, whatever the wires).  psi is NaN for
    3+ wires, a knife edge (CoM on the line, :func:`knife_edge_axes`: no
    turn is preferred) and a line within :data:`_VERTICAL_LINE` of vertical.
    Vectorised over leading axes.  ``edge_axes``: :func:`knife_edge_axes`
    of ``attachments`` if the caller has it (else computed here)."""
    p = np.asarray(attachments, float)
    R = np.asarray(R, float)
    shape = np.broadcast_shapes(p.shape[:-2], R.shape[:-2])
    if p.shape[-2] != 2:
        return np.full(shape, np.nan), np.full(shape + (3,), np.nan)
    n, down, side, v, nz = _line_frame(p, R)
    psi = np.arctan2(-np.einsum("...i,...i->...", v, side), np.einsum("...i,...i->...", v, down))
    edge = knife_edge_axes(p) if edge_axes is None else edge_axes
    bad = ~np.all(np.isnan(edge), axis=-1) | (nz < _VERTICAL_LINE)
    return np.where(bad, np.nan, psi), n


def _line_turn_one(p: np.ndarray, R: np.ndarray) -> float:
    """psi of :func:`line_turns` for one two-wire pose (p (2, 3), R (3, 3)),
    in plain floats, without its NaN cases (knife edge: psi is rounding there;
    vertical line: 0).  A filter for :func:`_hang_below_line`."""
    (x0, y0, z0), (x1, y1, z1) = p.tolist()
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    ux, uy, uz = x1 - x0, y1 - y0, z1 - z0
    t = (x0 * ux + y0 * uy + z0 * uz) / (ux * ux + uy * uy + uz * uz)
    fx, fy, fz = x0 - t * ux, y0 - t * uy, z0 - t * uz  # CoM -> its foot on the line, body
    vx, vy, vz = -(r00 * fx + r01 * fy + r02 * fz), -(r10 * fx + r11 * fy + r12 * fz), -(r20 * fx + r21 * fy + r22 * fz)
    nx, ny, nz = r00 * ux + r01 * uy + r02 * uz, r10 * ux + r11 * uy + r12 * uz, r20 * ux + r21 * uy + r22 * uz
    # down across the line ~ -(z - (z.n) n / |n|^2); side = n x down: only their directions matter for atan2
    nn = nx * nx + ny * ny + nz * nz
    dx, dy, dz = nz * nx / nn, nz * ny / nn, nz * nz / nn - 1.0
    sx, sy, sz = ny * dz - nz * dy, nz * dx - nx * dz, nx * dy - ny * dx
    return math.atan2(-(vx * sx + vy * sy + vz * sz) / math.sqrt(nn), vx * dx + vy * dy + vz * dz)


def _hang_below_line(scene: Scene, c: np.ndarray, R: np.ndarray):
    """The pose (com, R) turned about a two-wire rig's attachment line (the
    line through its attachment points, fixed in the world) so that the CoM
    hangs straight below it, when that turn (:func:`line_turns`) exceeds
    :data:`LINE_TURN_TOL`; else None.  The wires are unchanged (their ends
    are on the axis of the turn)."""
    if scene.n_wires != 2 or not abs(_line_turn_one(scene.attachments, R)) > LINE_TURN_TOL:
        return None  # the common case, decided without the vectorised machinery (a Newton end costs ~20 of these)
    psi, n = line_turns(scene.attachments, R)
    if not abs(psi) > LINE_TURN_TOL:  # NaN: knife edge, vertical line
        return None
    Q = rotvec_to_matrix(float(psi) * n)
    a1 = c + R @ scene.attachments[0]
    return a1 + Q @ (c - a1), Q @ R


def _finish(scene: Scene, c, R, lam, kkt, phi_checked: bool = True) -> RestPose:
    """The :class:`RestPose` at (c, R) with multipliers ``lam`` N/m and KKT
    residual ``kkt``, after the checks (slack, straight across, stable, the
    start box).  ``phi_checked`` False: an elastic pose, its wires longer
    than their lengths (no slack refusal by the nearly dependent rule)."""
    if not (kkt < 1e-9):
        raise ConvergenceError(f"rest pose did not converge (KKT residual {kkt:.2e})")
    axis = knife_edge_axes(scene.attachments)
    if np.all(np.isfinite(axis)):  # a neutral circle of equilibria: take its canonical member
        R = canonical_attitude(R, axis)
    L = scene.lengths
    d, w, G = constraint_jacobian(scene, c, R)
    T = lam * np.linalg.norm(d, axis=1)
    weight = scene.mass * scene.gravity
    bad = np.where(T < 1e-9 * weight)[0]
    if len(bad):
        if phi_checked:
            from .elastic_rest import refuse_nearly_dependent

            refuse_nearly_dependent(scene, bad, None, c, R, lam)
        _raise_slack(scene, bad, None, L, tensions=T, pose=(c, R))
    steep = float(np.max(np.abs(d[:, 2]) / np.linalg.norm(d, axis=1)))  # largest sine of a wire's angle to horizontal
    if steep < MIN_WIRE_SLOPE:
        # every wire straight across: inextensible wires would need infinite tension; the sag found is rounding
        raise InputError("rig.lengths", f"the wires are straight across: every wire is within {steep:.2g} rad of "
                         f"horizontal at rest, so each carries ~{np.max(T) / weight:.3g} times the body's weight, "
                         "a sag set by rounding; lengthen them so that they hang, or move the anchors up")
    N, Kr, Mr, rank = reduced_stiffness(scene, c, R, lam)
    if Kr.size:
        ev, vec = np.linalg.eigh(0.5 * (Kr + Kr.T))
        if ev[0] < -1e-9 * max(abs(ev[-1]), 1e-300):
            x = N @ vec[:, 0]  # the unstable direction: (dr, dtheta), world
            if _yaw_share(scene, R, x[:3], x[3:]) > 0.5:
                hint = (": the unstable mode turns the body about the vertical, which no height of the attachments "
                        "cures: the wires cross or twist on their way down (an anchor on the other side from its "
                        "attachment); check the order of rig.anchors against rig.attachments")
            else:
                hint = _com_height_hint(scene, R)
            raise UnstableRestError("rig.attachments", _UNSTABLE + hint)
    if (np.trace(R) - 1) / 2 < math.cos(START_BOX) and np.max(np.abs(matrix_to_rotvec(R))) > START_BOX:
        # the rotation from the start orientation (the identity, _initial_pose) leaves the 90-degree box
        # the global search is confined to: refused there (SLSQP at its bound), so here too, whichever
        # path (a warm start, a Newton start, a turn about the attachment line) led to it
        raise _turn_refusal(scene, np.eye(3), R)
    lz = float(lowest_point_z(scene, c, R))
    return RestPose(
        com=c, R=R, q=matrix_to_quat(R), tensions=T, wire_vectors=d,
        lowest_z=lz, depth=scene.ceiling_z - lz, kkt_residual=float(kkt),
    )


_NO_ADVICE = contextvars.ContextVar("bifilar_no_slack_advice", default=False)


def _raise_slack(scene: Scene, idx, gap, L, tensions=None, pose=None):
    """Raise the :class:`SlackWireError` of wires ``idx`` (0-based): slack by
    ``gap`` (m, per wire; None: straight at rest but without load,
    ``tensions`` N) in ``pose`` (com, R) if given.  Its advice (computed
    when the message is first read, :func:`slack_advice`) is an amount
    checked by solving the changed rig, or a lower bound where no amount
    passes that check."""
    idx = [int(i) for i in idx]
    gap = np.zeros(len(idx)) if gap is None else np.asarray(gap, float)
    heads, parts = [], []
    for k, i in enumerate(idx):
        if gap[k] > 0:
            heads.append(f"wire {i + 1} is slack at rest by {gap[k] * 1000:.3g} mm")
            parts.append(f"{heads[-1]}: with the other wires as they are it needs shortening by more than that, to "
                         f"less than {L[i] - gap[k]:.6g} m, to carry any load (by exactly that much it is straight "
                         "but carries none)")
        else:
            heads.append(f"wire {i + 1} carries no tension at rest ({tensions[i]:.3g} N)")
            parts.append(f"{heads[-1]}: it needs shortening to carry load")
    plain = "; ".join(parts)
    advise = None
    if pose is not None and not _NO_ADVICE.get():
        from .slack_advice import slack_advice
        advise = lambda: slack_advice(scene, idx, gap, *pose, plain, heads)  # noqa: E731
    raise SlackWireError([i + 1 for i in idx], plain, advise, gaps=gap)


def _yaw_share(scene: Scene, R: np.ndarray, dr: np.ndarray, dtheta: np.ndarray) -> float:
    """Share of a pose change's kinetic-energy norm (translation dr, m, and small
    rotation dtheta, rad, both world) in the turn about the vertical."""
    Iw = R @ scene.inertia @ R.T
    total = scene.mass * float(dr @ dr) + float(dtheta @ Iw @ dtheta)
    return Iw[2, 2] * float(dtheta[2]) ** 2 / max(total, 1e-300)


_UNSTABLE = "the rest pose is unstable (a mode has negative stiffness: a small push makes the body turn over)"


def _turn_refusal(scene: Scene, R0: np.ndarray, R: np.ndarray) -> UnstableRestError:
    """The refusal of a body whose rest attitude ``R`` is turned from its
    start orientation ``R0`` by 90 degrees or more (beyond :data:`START_BOX`)."""
    if abs(line_turns(scene.attachments, R0)[0]) > np.pi - LINE_TURN_TOL:
        # two wires, the CoM straight above their line at the start: that pose balances, unstably (the turn about
        # the line has stiffness -m g h), and is the one the search meets: said as the stiffness test says it
        return UnstableRestError("rig.attachments", _UNSTABLE + _com_height_hint(scene, R0))
    if _yaw_share(scene, R0, np.zeros(3), matrix_to_rotvec(R @ R0.T)) > 0.5:
        # it turns about the vertical by more than 90 degrees to hang: the anchors are turned against the attachments
        return UnstableRestError("rig.attachments", "the body cannot hang within 90 degrees of its start orientation: "
                                 "it would turn about the vertical by more than that, as wires that cross or twist on "
                                 "their way down make it (an anchor on the other side from its attachment); check the "
                                 "order of rig.anchors against rig.attachments")
    # the body wants to turn over rather than hang in its start orientation
    return UnstableRestError("rig.attachments", "the body cannot hang in its start orientation (it would turn over)"
                             + _com_height_hint(scene, R0))


def _com_height_hint(scene: Scene, R: np.ndarray) -> str:
    """Message tail: where the CoM is relative to the attachment points (world z, attitude ``R``);
    for two wires whose CoM is not straight below their attachment line, where it is relative to
    that line and the turn about it the body would make."""
    h = -float(np.mean(scene.attachments @ R.T, axis=0)[2])  # CoM height above the attachments' mean, m
    if h > 0:
        return (f": the centre of mass is {h:.3g} m above the attachment points (their mean); "
                "attach the wires above the centre of mass")
    psi, _ = line_turns(scene.attachments, R)
    if abs(psi) > LINE_TURN_TOL:  # two wires, CoM not below their line: it hangs straight below it, whatever the anchors
        _, down, side, v, _ = _line_frame(scene.attachments, R)
        below, beside = float(v @ down), abs(float(v @ side))
        level = abs(below) <= KNIFE_EDGE_RTOL * float(np.max(np.linalg.norm(scene.attachments, axis=1)))
        where = "level with" if level else f"{abs(below):.3g} m {'below' if below > 0 else 'above'}"
        return (f": the centre of mass is {where} the attachment line and {beside:.3g} m beside it, and hangs "
                f"straight below that line, so the body would turn about it by {np.degrees(abs(float(psi))):.3g} "
                "degrees; attach the wires above the centre of mass")
    return (f": the centre of mass is only {-h:.3g} m below the attachment points (their mean), too little for "
            "this wire layout; attach the wires higher on the body or bring the anchors further apart")


def _check_reach(scene: Scene, com: np.ndarray, R: np.ndarray, tol: float) -> None:
    """Raise :class:`InputError` (``rig.lengths``) if no pose lets every wire
    reach its attachment point: least squares on the excess max(|d_i| - L_i, 0)
    (m) from the pose ``com``, ``R``; returns if the excess can vanish."""
    from scipy.optimize import least_squares

    L = scene.lengths
    scale = float(np.max(L))

    def excess(x):
        Rx = rotvec_to_matrix(x[3:]) @ R
        d = com + scale * x[:3] + scene.attachments @ Rx.T - scene.anchors
        return np.maximum(np.linalg.norm(d, axis=1) - L, 0.0)

    sol = least_squares(excess, np.zeros(6), xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=2000)
    e = excess(sol.x)
    if np.max(e) <= tol:
        return
    short = [f"wire {i + 1} {e[i]:.3g} m" for i in np.where(e > tol)[0]]
    raise InputError(
        "rig.lengths",
        "the wires cannot reach all their attachment points at once: even in the closest pose they are too short "
        "by " + ", ".join(short) + "; lengthen them or match the anchor layout to the attachment layout",
    )
