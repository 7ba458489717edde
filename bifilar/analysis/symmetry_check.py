"""Runs that start on an invariant symmetric subspace of a symmetric rig
(docs/design.md, "symcheck, session 16").

A rig symmetric under a mirror or a turn about the vertical through its rest
CoM, released from a start that the same symmetry maps onto itself (the
thesis plate's swing-y: in the plate's symmetry plane), moves on that
plane for ever in exact arithmetic: the right-hand side maps symmetric
states to symmetric rates, bit for bit.  Where that orbit is unstable
transversally (parametrically: the plate's swing-y at 1.5 m), the start's
rounding (3e-16 m, different on another BLAS kernel) grows until the motion
leaves the plane, and the period depends on the machine beyond its stated
error, while nothing in the run shows it (a run at a tighter tolerance
keeps the symmetry too; the single-cycle spread can stay below
:data:`~bifilar.analysis.run_accuracy.IRREGULAR_SPREAD`).

What is done here (SI units, world frame; states are
:mod:`bifilar.models.maximal`'s 13 numbers with the position relative to
the rest CoM unless said otherwise):

* :func:`rig_symmetries`, :func:`start_symmetry`: the rig's symmetries
  (vertical mirrors and turns about the vertical through the rest CoM that
  map anchors, attachments at rest, lengths and inertia onto themselves),
  those that fix the start, and the directions that leave their fixed
  subspace (~0.3 ms; nothing more where the start has none);
* :func:`transverse_growth`: the Floquet multipliers of the orbit across
  that subspace, from the run's own samples over its first period (the
  variational equation restricted to the transverse directions, its matrix
  by differences of the compiled right-hand side at the samples, two
  kernel calls, integrated by Runge-Kutta steps; ~0.5 ms);
* where the predicted growth over the run reaches :data:`GROWTH_GATE`,
  :func:`check_symmetric_start` runs it again from a start moved off the
  subspace by :data:`START_OFFSET`; where the periods differ by more than
  the stated error, :func:`offset_error` of the two runs is folded into
  ``period_error`` with one warning.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import IntegrationError, InputError
from ..models import maximal as mx
from ..rotations import matrix_to_quat, quat_multiply, rotvec_to_quat
from ..scene import Scene
from .equilibrium import RestPose

SYMMETRY_TOL = 1e-9
"""Relative tolerance of a symmetry of the rig (anchors, attachments at rest
and lengths over the longest wire, inertia over its largest entry) and of
the start (each state component over the run's own tolerance scale): the
start pose solver's own tolerance (``FEASIBLE_TOL``).  A start further off
the subspace carries its asymmetry into the run, where a growth shows in
the run itself (its single-cycle spread, the check of a motion that is not
regular); one within it hides the growth to rounding."""


@dataclass(frozen=True)
class Symmetry:
    """One symmetry of a rig: ``S`` (3, 3) world map (a mirror in a vertical
    plane or a turn about the vertical, through the rest CoM), ``perm`` (n,)
    the wire each wire goes to, ``sigma`` (13, 13) its action on a state
    (position relative to the rest CoM), ``name`` for the messages."""

    S: np.ndarray
    perm: np.ndarray
    sigma: np.ndarray
    name: str


def _qmat_left(a: np.ndarray) -> np.ndarray:
    """L (4, 4) with L q = a * q (Hamilton product)."""
    w, x, y, z = a
    return np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])


def _qmat_right(b: np.ndarray) -> np.ndarray:
    """R (4, 4) with R q = q * b."""
    w, x, y, z = b
    return np.array([[w, -x, -y, -z], [x, w, z, -y], [y, -z, w, x], [z, y, -x, w]])


def _conj(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def state_action(S: np.ndarray, q0: np.ndarray, R0: np.ndarray, det: float | None = None) -> np.ndarray:
    """(13, 13) action on a state (position relative to the rest CoM, unit
    quaternion body -> world, CoM velocity, body-axes angular velocity) of
    the world map ``S`` (orthogonal, vertical kept; ``det`` its determinant,
    +-1, if known) that maps the rest pose (``q0``, ``R0``) onto itself:
    positions and velocities ``S x``; the attitude R -> S R B^T with
    B = R0^T S R0 the same map in body axes, on the quaternion
    q -> s * q * b^-1 with s, b the proper parts det(S) S, det(S) B (its
    sign fixed so the rest attitude is kept); body rates det(S) B w."""
    det = float(np.sign(np.linalg.det(S))) if det is None else float(det)
    Sp = det * S
    qs = matrix_to_quat(Sp)
    q0 = np.asarray(q0, float)
    qb = _qmat_left(_conj(q0)) @ _qmat_right(q0) @ qs  # q0^-1 s q0, the body-axes part, consistent sign
    Q = _qmat_left(qs) @ _qmat_right(_conj(qb))
    sig = np.zeros((13, 13))
    sig[0:3, 0:3] = S
    sig[3:7, 3:7] = Q
    sig[7:10, 7:10] = S
    sig[10:13, 10:13] = R0.T @ Sp @ R0
    return sig


def _candidates(pts: np.ndarray, n: int) -> tuple[np.ndarray, list]:
    """World maps that could be symmetries, (c, 3, 3), their names and determinants:
    mirrors in vertical planes through the rest CoM (normal along the
    horizontal part of a difference of two of the points ``pts`` (m, 3),
    anchors and attachments relative to the rest CoM, which such a mirror
    swaps, or across the plane holding the vertical and one of them, which
    it keeps) and turns about the vertical by 2 pi j / k, k <= n (the
    anchors' pattern repeats at most n times)."""
    i, j = np.triu_indices(len(pts), 1)
    h = np.concatenate([pts[i] - pts[j], np.stack([-pts[:, 1], pts[:, 0], np.zeros(len(pts))], axis=1)])[:, :2]
    nh = np.hypot(h[:, 0], h[:, 1])
    h = h[nh > 1e-9 * max(1.0, float(np.max(np.abs(pts))))]
    ang = np.unique(np.round(np.degrees(np.arctan2(h[:, 1], h[:, 0])) % 180.0, 9) % 180.0)
    a = np.radians(ang)
    nx, ny = np.cos(a), np.sin(a)
    mats = [np.array([[1 - 2 * x * x, -2 * x * y, 0.0], [-2 * x * y, 1 - 2 * y * y, 0.0], [0.0, 0.0, 1.0]])
            for x, y in zip(nx, ny)]
    names = [f"the mirror across the vertical plane normal to {g:.4g} deg from x" for g in ang]
    dets = [-1.0] * len(mats)
    for k in range(2, max(n, 2) + 1):
        for jj in range(1, k):
            if np.gcd(jj, k) != 1:
                continue  # (found with the smaller k)
            t = 2.0 * np.pi * jj / k
            mats.append(np.array([[np.cos(t), -np.sin(t), 0.0], [np.sin(t), np.cos(t), 0.0], [0.0, 0.0, 1.0]]))
            names.append(f"the turn by {360.0 * jj / k:.4g} deg about the vertical")
            dets.append(1.0)
    return np.array(mats), names, dets


def _none_possible(A: np.ndarray, W: np.ndarray, L: np.ndarray, tol: float) -> bool:
    """A quick sufficient test that a rig has no symmetry (~20 us, what an
    asymmetric rig pays): a symmetry keeps each wire's anchor and attachment
    distances from the vertical through the rest CoM, their heights and the
    length, so where no two wires agree in these it maps every wire onto
    itself, which only a mirror whose plane holds every anchor and
    attachment does (a turn moves every point off that vertical); so there
    is none where these do not lie in one vertical plane through it.
    ``A``, ``W`` (n, 3): anchors and attachments at rest relative to the
    rest CoM, m; ``L`` (n,) lengths, m; ``tol`` m."""
    key = np.stack([np.hypot(A[:, 0], A[:, 1]), A[:, 2], L, np.hypot(W[:, 0], W[:, 1]), W[:, 2]], axis=1)
    close = np.all(np.abs(key[:, None, :] - key[None, :, :]) <= tol, axis=2)
    if np.count_nonzero(close) > len(L):  # two wires alike: a swap is possible
        return False
    h = np.concatenate([A, W])[:, :2]
    k = int(np.argmax(np.hypot(h[:, 0], h[:, 1])))
    u = h[k] / max(float(np.hypot(*h[k])), 1e-300)
    return bool(np.max(np.abs(h[:, 0] * u[1] - h[:, 1] * u[0])) > tol)  # not all in the plane through u


def rig_symmetries(scene: Scene, rest: RestPose) -> list[Symmetry]:
    """The symmetries of ``scene`` hanging at ``rest`` (:class:`Symmetry`):
    each candidate of :func:`_candidates` that maps the anchors (relative to
    the rest CoM) onto themselves, the attachments at rest onto those of the
    same wires, keeps the lengths (and the wires' stiffness, if stated) and
    the inertia in world axes at rest, within :data:`SYMMETRY_TOL` (the
    model's right-hand side then respects its state action:
    tests/test_symcheck.py checks that on every shipped config).  Tested
    together (a few numpy calls: ~0.1 ms)."""
    A = np.asarray(scene.anchors, float) - rest.com
    W = np.asarray(scene.attachments, float) @ rest.R.T
    L = np.asarray(scene.lengths, float)
    tol = SYMMETRY_TOL * float(np.max(L))
    if _none_possible(A, W, L, tol):
        return []
    Ss, names, dets = _candidates(np.concatenate([A, W]), scene.n_wires)
    AS = A @ Ss.transpose(0, 2, 1)  # (c, n, 3): S a_i
    d = np.linalg.norm(AS[:, :, None, :] - A[None, None, :, :], axis=-1)  # (c, n, n)
    p = np.argmin(d, axis=2)  # (c, n): the anchor each goes to
    ok = np.all(np.take_along_axis(d, p[:, :, None], 2)[:, :, 0] <= tol, axis=1)
    ok &= np.array([len(set(x.tolist())) == len(A) for x in p])
    ok &= np.all(np.abs(W @ Ss.transpose(0, 2, 1) - W[p]) <= tol, axis=(1, 2))
    ok &= np.all(np.abs(L[None, :] - L[p]) <= tol, axis=1)
    if scene.stiffness is not None:
        k = np.asarray(scene.stiffness, float)
        ok &= np.all(np.abs(k[None, :] - k[p]) <= SYMMETRY_TOL * float(np.max(np.abs(k))), axis=1)
    Iw = rest.R @ np.asarray(scene.inertia, float) @ rest.R.T
    ok &= np.all(np.abs(Ss @ Iw @ Ss.transpose(0, 2, 1) - Iw) <= SYMMETRY_TOL * float(np.max(np.abs(Iw))), axis=(1, 2))
    return [Symmetry(S=Ss[c], perm=p[c], sigma=state_action(Ss[c], rest.q, rest.R, dets[c]), name=names[c])
            for c in np.nonzero(ok)[0]]


def shifted_params(scene: Scene, rest: RestPose) -> mx.RigParams:
    """The model's parameters with the anchors relative to the rest CoM (the
    frame the runs integrate in)."""
    P = mx.params_from_scenes(scene)
    return mx.RigParams(**{**P.__dict__, "anchors": P.anchors - rest.com})


BLOCKS = (slice(0, 3), slice(3, 7), slice(7, 10), slice(10, 13))
"""The state's blocks (position, quaternion, velocity, body rates), each of
which every symmetry maps into itself."""


@dataclass
class Transverse:
    """The symmetries of a rig that fix a start (``symmetries``) and the
    orthonormal directions (13, k) of the state that leave their common fixed
    subspace (``basis``), block by block (:data:`BLOCKS`): a symmetric start
    stays on that subspace, and a small offset along ``basis`` is what grows
    or not across it."""

    symmetries: list
    basis: np.ndarray

    @property
    def names(self) -> str:
        return " and ".join(s.name for s in self.symmetries)


def start_symmetry(syms: list, y_rel: np.ndarray, scale: np.ndarray) -> Transverse | None:
    """The symmetries of ``syms`` (:func:`rig_symmetries`) that fix the start
    ``y_rel`` (13,) within :data:`SYMMETRY_TOL` of ``scale`` (13,), the
    run's tolerance scale of each component, and the transverse directions
    of their fixed subspace (:class:`Transverse`); None where none fixes it
    (or the rig has none)."""
    y = np.asarray(y_rel, float)
    fix = [s for s in syms if np.all(np.abs(s.sigma @ y - y) <= SYMMETRY_TOL * np.asarray(scale, float))]
    if not fix:
        return None
    cols = []
    for b in BLOCKS:
        M = np.concatenate([s.sigma[b, b] - np.eye(b.stop - b.start) for s in fix])
        _, sv, Vt = np.linalg.svd(M)
        for v, x in zip(Vt, sv):
            if x > 1e-9:
                c = np.zeros(13)
                c[b] = v
                cols.append(c)
    if not cols:
        return None
    return Transverse(symmetries=fix, basis=np.array(cols).T)


def _rates(kernel, Y: np.ndarray) -> np.ndarray:
    """The model's rates (m, 13) at states ``Y`` (m, 13), one kernel call."""
    out = kernel(*np.ascontiguousarray(Y.T))
    return np.stack(np.broadcast_arrays(*out[:13]), axis=-1)


RK4_REACH = 0.5
"""Largest |eigenvalue of A| x step (rad) :func:`transverse_growth` takes.
The classical Runge-Kutta step damps an oscillation of that phase step by
~(that)^6 / 144 (1e-4 at 0.5; the plate's default runs, 0.11-0.43 at 64
samples a period, read a neutral multiplier as 0.9996-1) and is unstable
beyond 2.8; a grid beyond the reach is refined to half of it."""


def transverse_growth(P: mx.RigParams, t: np.ndarray, Y_rel: np.ndarray, period: float, basis: np.ndarray,
                      step: np.ndarray) -> np.ndarray:
    """Floquet multipliers (k,) across the fixed subspace of the orbit sampled
    at ``t`` (s, uniform from 0) as ``Y_rel`` (m, 13: positions relative to
    the rest CoM, the frame of ``P``) over its first ``period`` (s).

    The variational equation of the model's right-hand side f, restricted to
    the transverse directions ``basis`` (13, k) (f maps them into themselves
    along a symmetric orbit), dX/dt = A(t) X with A = B^T (df/dy) B, A's
    columns by one-sided differences of f along each direction (``step``
    (k,), in the state's units: 1e-7 of its natural size, where the
    difference's error, even in the offset for a mirror, is ~1e-14 and its
    rounding ~1e-8), on a uniform grid of the period as fine as the samples
    (the orbit there by cubic Hermite interpolants of the samples and their
    rates, which are exact at the samples and ~(2 pi / 64)^4 / 384 = 3e-7
    between them; one kernel call for all); X(period) from X(0) = I by
    classical Runge-Kutta steps of two grid intervals, 4th order: on the
    plate's orbits at 64 samples a period the multipliers' moduli agree with
    256 samples to ~1e-5.  Where the transverse motion is too fast for that
    grid (:data:`RK4_REACH`: the swing-x of the thesis 7.1 rigs, 42 s, beside
    a torsion of 2.7 s), the grid is refined up to 16 times.  The eigenvalues of
    X(period) are the multipliers; a modulus above 1 is a growth per period
    of an offset from the subspace.  NaN (not established) where the run has
    fewer than 3 samples in the period or even 16 times its rate is too
    coarse (a stiff body's fast modes)."""
    t = np.asarray(t, float)
    K = int(np.searchsorted(t, period, side="right")) - 1  # t[K] <= period < t[K + 1]
    k = basis.shape[1]
    if K < 2 or K + 1 >= len(t):
        return np.full(k, np.nan)
    kern = mx.compiled_kernel(P)
    F = _rates(kern, Y_rel[:K + 2])  # the rates at the samples, for the interpolants
    M = (K + 1) // 2  # Runge-Kutta steps of two grid intervals over the period
    for _ in range(2):
        A, h = _grid_matrices(kern, t, Y_rel, F, K, period, M, basis, step)
        need = _reach_factor(A, step, h)
        if need <= 1.0:
            break
        if need > 16.0:
            return np.full(k, np.nan)  # transverse motion too fast for the samples: not established
        M = int(np.ceil(M * need))
    else:
        return np.full(k, np.nan)
    # each Runge-Kutta step's propagator, all at once: Phi -> S Phi, S = I + h/6 (K1 + 2 K2 + 2 K3 + K4)
    A0, Am, A1 = A[0:-1:2], A[1::2], A[2::2]
    eye = np.eye(k)
    K1 = A0
    K2 = Am @ (eye + 0.5 * h * K1)
    K3 = Am @ (eye + 0.5 * h * K2)
    K4 = A1 @ (eye + h * K3)
    Sm = eye + h / 6.0 * (K1 + 2.0 * K2 + 2.0 * K3 + K4)
    Phi = Sm[0]
    for Si in Sm[1:]:
        Phi = Si @ Phi
    return np.linalg.eigvals(Phi)


def _grid_matrices(kern, t, Y_rel, F, K, period, M, basis, step):
    """A (2M + 1, k, k) of :func:`transverse_growth` on the uniform grid of
    2M intervals over [0, ``period``], and the Runge-Kutta step (s, two
    intervals)."""
    tg = np.linspace(0.0, period, 2 * M + 1)
    i = np.clip(np.searchsorted(t, tg, side="right") - 1, 0, K)
    h = (t[i + 1] - t[i])[:, None]
    sg = (tg[:, None] - t[i][:, None]) / h
    X = ((2 * sg**3 - 3 * sg**2 + 1) * Y_rel[i] + (sg**3 - 2 * sg**2 + sg) * h * F[i]
         + (-2 * sg**3 + 3 * sg**2) * Y_rel[i + 1] + (sg**3 - sg**2) * h * F[i + 1])  # cubic Hermite
    k = basis.shape[1]
    Fp = _rates(kern, np.concatenate([X, (X[:, None, :] + (basis * step).T[None, :, :]).reshape(-1, 13)]))
    D = (Fp[len(X):].reshape(len(X), k, 13) - Fp[:len(X), None, :]) @ basis  # (m, j, i): B^T (f(x + h b_j) - f(x))
    return D.transpose(0, 2, 1) / step[None, None, :], 2.0 * period / (2 * M)  # A[:, :, j]: direction j's column


def _reach_factor(A: np.ndarray, step: np.ndarray, h: float) -> float:
    """By how much the Runge-Kutta step ``h`` (s) must shrink for the
    eigenvalues of the matrices ``A`` (m, k, k) times it to stay within
    :data:`RK4_REACH` (at most 1: none).  First by the Frobenius norm of
    each in the directions' natural units (``step``), which bounds its
    eigenvalues, at once; where that exceeds the reach, by the eigenvalues
    of the largest such matrix, the first and the middle one (the transverse
    rates vary smoothly along the orbit; all 35 of a period cost ~1 ms, 3
    ~0.08 ms), with a margin of 2."""
    B = A * step[None, None, :] / step[None, :, None]  # D^-1 A D, D = diag(step): the same eigenvalues
    fro = np.sqrt(np.einsum("mij,mij->m", B, B))
    if float(np.max(fro)) * h <= RK4_REACH:
        return 1.0
    pick = sorted({0, len(A) // 2, int(np.argmax(fro))})
    lam = float(np.max(np.abs(np.linalg.eigvals(A[pick])))) * h
    return 1.0 if lam <= RK4_REACH else 2.0 * lam / RK4_REACH  # (to half the reach)


START_OFFSET = 1e-12
"""Size of the check run's offset from the symmetric subspace: each pose
coordinate moved by at most this many longest-wire lengths (m) or radians.
The start is not known better than that: the 1e-12 the project's error
bounds stop at (``PERIOD_ERROR_FLOOR``), 1e4 x the rounding of the rest
pose (3e-16 m between BLAS kernels on the thesis plate), which the check so
covers with a margin (in the linear regime the period moves as the
square of the offset)."""

GROWTH_GATE = 1e6
"""Growth of an offset over the run (the largest Floquet multiplier's
modulus to the power of the run's periods) from which the check run is
made.  Below it a start 1e-12 off ends the run at most 1e-6 off the
subspace, and the period of a symmetric orbit moves as the square of the
offset (the mirror image of a run times the same crossings): by ~1e-12 of
itself.  Measured on the plate's swing-y (docs/design.md, "symcheck,
session 16"): the check's difference over the error bound was 1e-7 .. 1e-5
at growths of 3e4 .. 1.5e8 (1.5 m) and 1e5 .. 4e7 (1.0 m), 0.014 .. 0.016
at 1e10, 37 at 6.6e11 (1.5 m, 13 periods): it exceeds the bound from ~1e11,
five decades above the gate.  (At 0.5 m, growths of 5e4 and 3e9, it was
0.004 and 0.03: the two runs' integration errors, their steps differing,
not the offset.)"""


def natural_sizes(Lmax: float, omega: float) -> np.ndarray:
    """(13,) the state components' natural sizes: the longest wire ``Lmax``
    (m) for positions, 1 for the quaternion, Lmax omega (m/s) and omega
    (rad/s, the mode's angular frequency) for the rates."""
    return np.r_[[Lmax] * 3, [1.0] * 4, [Lmax * omega] * 3, [omega] * 3]


def offset_start(scene: Scene, y0: np.ndarray, basis: np.ndarray, offset: float = START_OFFSET,
                 seed: int = 16) -> np.ndarray:
    """The start ``y0`` (13, absolute position, world frame) moved off its
    symmetric subspace: along a seeded random combination of the transverse
    directions ``basis`` (13, k) in position and attitude (velocities
    kept), made tangent to the wires (the kinetic-energy-closest such
    displacement, which stays transverse: the wires' constraints are as
    symmetric as the start), scaled so that its largest coordinate is
    ``offset`` of the longest wire (m) or ``offset`` rad.  The wires' lengths
    are then kept to ~offset^2 (1e-24 of a wire)."""
    from .equilibrium import constraint_jacobian
    from .start_states import tangent_to_wires

    rng = np.random.default_rng(seed)
    d = basis @ rng.standard_normal(basis.shape[1])
    com, q = y0[0:3], y0[3:7]
    Lmax = float(np.max(scene.lengths))
    dq = d[3:7]
    dth = 2.0 * quat_multiply(dq, _conj(q))[1:]  # world rotation of q -> q + dq (dq orthogonal to q)
    delta = np.r_[d[0:3] * Lmax, dth]
    R = mx.quat_to_matrix(q)
    _, _, G = constraint_jacobian(scene, com, R)
    delta = tangent_to_wires(scene, R, G, delta)
    size = max(float(np.max(np.abs(delta[:3]))) / Lmax, float(np.max(np.abs(delta[3:]))))
    if not size > 0:
        return y0.copy()
    delta *= offset / size
    y = np.asarray(y0, float).copy()
    y[0:3] += delta[:3]
    y[3:7] = quat_multiply(rotvec_to_quat(delta[3:]), q)
    return y


def reproducible_cycles(tc: np.ndarray, tc_check: np.ndarray, error: float) -> int:
    """How many of the run's first cycles (crossing times ``tc``, s) the
    check run (``tc_check``) reproduces: the largest n for which the mean
    period over the first m cycles of the two agrees within ``error`` (s)
    for every m <= n."""
    m = min(len(tc), len(tc_check)) - 1
    if m < 1:
        return 0
    n = np.arange(1, m + 1)
    d = np.abs((tc_check[1:m + 1] - tc_check[0]) - (tc[1:m + 1] - tc[0])) / n
    bad = np.nonzero(d > error)[0]
    return int(m if len(bad) == 0 else bad[0])


def offset_error(tc: np.ndarray, tc_check: np.ndarray) -> float:
    """How far the mean period of a run from a start between the run's
    (crossing times ``tc``, s, N cycles) and the check run's (``tc_check``,
    at least N cycles: it runs :data:`CHECK_EXTRA_PERIODS` longer) may move,
    s: the check's cycle-by-cycle differences from the run, their moduli
    summed over the N cycles plus the largest, over N.

    A start off the subspace by less than the check's offset leaves it along
    the same unstable direction (the dominant Floquet multiplier's, real;
    its mirror image times the same crossings), later by log(offset ratio)
    / log(multiplier) cycles, a whole number and a fraction: its cycles'
    differences are the check's profile of differences shifted to later
    cycles and sampled a fraction of a cycle apart from the check's (in the
    linear regime the check's scaled by the offsets' ratio squared), so
    their sum over the run is at most the sum of the moduli plus one
    cycle's difference.  Measured on the plate's swing-y at 1.5 m, 10-40
    periods (docs/design.md, "symcheck, session 16"): starts 1e-15..1e-13
    off moved the mean period by up to 0.63 of this; the means' difference
    alone missed them at 16 and 17 periods (0.00414 s against 0.00415 s,
    0.00382 against 0.00397), the moduli's sum alone at 16, where the check
    left the plane a fraction of a cycle before them (0.050 and 0.0094 s on
    its 15th and 16th cycles, 0.036 and 0.029 s on theirs)."""
    N = len(tc) - 1
    n = min(N, len(tc_check) - 1)
    if N < 1 or n < 1:
        return 0.0
    d = np.abs(np.diff(np.asarray(tc_check, float)[:n + 1]) - np.diff(np.asarray(tc, float)[:n + 1]))
    return float((np.sum(d) + np.max(d)) / N)


CHECK_EXTRA_PERIODS = 2.0
"""Linear periods the check run of :func:`check_symmetric_start` runs beyond
the run, so that it times as many cycles (a motion leaving the subspace
lengthens them: the plate's swing-y check timed 14 of the run's 15)."""


def _run_scale(scene: Scene, rest: RestPose, m, T_ref: float, amplitude: float, y0: np.ndarray) -> np.ndarray:
    """(13,) the tolerance scale of a run (``simulate``'s: the mode's
    amplitude, or for an explicit start without one its displacement from
    rest, as a wire angle; ``T_ref`` (s) the run's unit period)."""
    from .simulate import relative_pose, state_scale

    Lmax = float(np.max(scene.lengths))
    omega = 2 * np.pi / T_ref
    if m is not None and np.isfinite(amplitude) and amplitude != 0:
        return state_scale(amplitude, m.dominant, Lmax, omega)
    disp = relative_pose(y0[None, :], rest)[0]
    return state_scale(max(float(np.max(np.abs(disp[3:]))), float(np.max(np.abs(disp[:3]))) / Lmax), 3, Lmax, omega)


def run_multiplier(scene: Scene, rest: RestPose, syms: list, m, T_ref: float, amplitude: float, t: np.ndarray,
                   y: np.ndarray, period: float):
    """(:class:`Transverse`, the largest Floquet multiplier's modulus) of a
    run sampled at ``t`` (s, uniform from 0) as ``y`` (k, 13, absolute
    positions) from its start ``y[0]`` at ``amplitude`` of mode ``m`` (None:
    an explicit start; ``T_ref`` s the run's unit period) and timed at
    ``period`` (s): None where no symmetry of ``syms`` fixes the start; the
    modulus NaN where not established (:func:`transverse_growth`)."""
    y0 = np.asarray(y[0], float)
    y_rel = y0 - np.r_[rest.com, np.zeros(10)]
    tr = start_symmetry(syms, y_rel, _run_scale(scene, rest, m, T_ref, amplitude, y0))
    if tr is None:
        return None
    Lmax = float(np.max(scene.lengths))
    step = 1e-7 * (np.abs(tr.basis.T) @ natural_sizes(Lmax, 2 * np.pi / T_ref))
    Y = np.asarray(y, float) - np.r_[rest.com, np.zeros(10)]
    mu = transverse_growth(shifted_params(scene, rest), t, Y, period, tr.basis, step)
    return tr, float(np.max(np.abs(mu)))


def growth_over(rho: float, cycles: float) -> float:
    """``rho`` to the power ``cycles``: an offset's growth over a run (NaN where ``rho`` is not established)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return float(np.exp(cycles * np.log(rho))) if rho > 0 else float("nan")


def check_symmetric_start(res, scene: Scene, mode, amplitude: float, periods: float, kw: dict, rerun=None) -> None:
    """Check run ``res`` (a :class:`~bifilar.analysis.simulate.SimulationResult`
    of ``simulate(scene, mode, amplitude, periods, **kw)``, updated in place)
    for a start on a symmetric subspace of a symmetric rig whose orbit is
    unstable across it (module docstring).

    Nothing is done (a comparison) where the run timed no period, its error
    is not established, the rig has no symmetry or the start none of its
    symmetries (:func:`start_symmetry`).  Otherwise ``res.period_symmetry``
    gets the symmetry, the largest Floquet multiplier's modulus
    (:func:`transverse_growth`) and its power over the run's periods (the
    growth of an offset; None where not established: :data:`RK4_REACH`,
    then no check); from a growth of :data:`GROWTH_GATE` the run is
    made again from :func:`offset_start` (same method, tolerances and
    samples) and, where its period differs by more than ``res.period_error``,
    that error becomes the larger of the difference and
    :func:`offset_error` (``period_error_symmetry``), with one warning
    saying over how many periods the run is reproducible.

    ``rerun``: ``rerun(y_start)`` makes the check run from ``y_start`` (13,
    a maximal state, absolute position) for :data:`CHECK_EXTRA_PERIODS`
    linear periods more, on the run's own model (``--model kane``'s
    reduced coordinates: :func:`~bifilar.analysis.kane_run.simulate_kane`);
    None: :func:`simulate`'s engines (``kw`` its arguments)."""
    if res.period is None or not np.isfinite(res.period_error) or len(res.crossings) < 3:
        return
    from .equilibrium import rest_pose
    from .modes import linear_modes

    rest = kw.get("rest") or rest_pose(scene)
    syms = rig_symmetries(scene, rest)
    if not syms:
        return
    modes = kw.get("modes") or linear_modes(scene, rest)
    m = modes.get(mode) if mode is not None else None
    y0 = np.asarray(res.y[0], float)
    if m is not None and m.period is None:
        return
    # the unit of --periods: the mode's period, for an explicit start without one the shortest (simulate's T_ref)
    T_ref = m.period if m is not None else min((x.period for x in modes.modes if x.period), default=None)
    if T_ref is None:
        return
    found = run_multiplier(scene, rest, syms, m, T_ref, amplitude, res.t, res.y, res.period)
    if found is None:
        return
    tr, rho = found
    growth = growth_over(rho, float(res.t[-1] - res.t[0]) / res.period)
    res.period_symmetry = {"symmetry": tr.names, "multiplier": rho if np.isfinite(rho) else None,
                           "growth": growth if np.isfinite(growth) else None, "check": None}
    if not growth >= GROWTH_GATE:  # (NaN: not established, a stiff body's fast modes: its run is costly, and
        return                    # doubling it was measured at 2.3 s for a thin rod's torsion, whose check agreed)
    _offset_check(res, scene, rest, m, T_ref, amplitude, periods, kw, tr, y0, rho, growth, rerun)


def _offset_check(res, scene, rest, m, T_ref, amplitude, periods, kw, tr, y0, rho, growth, rerun=None) -> None:
    """The run of :func:`check_symmetric_start` from the offset start, and what follows from it."""
    yp = offset_start(scene, y0, tr.basis)
    try:
        chk = rerun(yp) if rerun is not None else _again(res, scene, rest, m, amplitude, periods, kw, yp)
    except (InputError, IntegrationError) as exc:
        res.warnings.append(f"the start is symmetric ({tr.names}) and an offset from it grows by {rho:.3g} a period, "
                            f"but the run checking the period from a start {START_OFFSET:g} off failed ({exc}): the "
                            "period may depend on the start's rounding beyond its error bound")
        return
    if chk.period is None:
        res.warnings.append(f"the start is symmetric ({tr.names}) and an offset from it grows by {rho:.3g} a period, "
                            f"but the run checking the period from a start {START_OFFSET:g} off timed no period: the "
                            "period may depend on the start's rounding beyond its error bound")
        return
    stated = float(res.period_error)
    tc, tk = np.asarray(res.crossings, float), np.asarray(chk.crossings, float)
    n = min(len(tc), len(tk)) - 1  # the run's cycles (the check runs longer), fewer if it timed fewer
    p_chk = float(tk[n] - tk[0]) / n
    diff = abs(float(tc[n] - tc[0]) / n - p_chk)
    kept = reproducible_cycles(tc, tk, stated)
    err = max(diff, offset_error(tc, tk))
    res.period_symmetry["check"] = {"offset": START_OFFSET, "period": p_chk, "cycles": n, "difference": diff,
                                    "reproducible_cycles": kept, "error": err if diff > stated else 0.0}
    if not diff > stated:
        return
    res.period_error = max(stated, err)
    res.period_error_symmetry = err
    n_lin = int(np.floor(kept * res.period / T_ref)) if kept else 0
    cure = (f"time at most {n_lin} periods (--periods {n_lin}) or release at a smaller amplitude" if n_lin >= 2
            else "release at a smaller amplitude")
    res.warnings.append(
        f"the motion is an unstable symmetric orbit: released symmetric under {tr.names}, it stays so only up to "
        f"rounding, and an offset grows by {rho:.3g} a period ({growth:.1e} over the run); a start {START_OFFSET:g} "
        f"off (of the longest wire, or rad) gives a period {diff:.1g} s away, {diff / stated:.3g} x the error bound of "
        f"{stated:.1g} s, reproducible over the first {kept} of {len(res.crossings) - 1} periods only, so the period "
        f"depends on the machine's rounding and its error is {res.period_error:.1g} s (period_error); {cure}")


def timed_index(res) -> int:
    """The index (0-5, dx dy dz rx ry rz) of the coordinate run ``res`` timed, for its check run to time
    the same (a run without a mode times the one that moves most, which leaving the subspace can change)."""
    from .modes import COMPONENTS

    return COMPONENTS.index(res.coordinate_name)


def _again(res, scene, rest, m, amplitude, periods, kw, y_start):
    """``res``'s run again from ``y_start`` (13, absolute), for
    :data:`CHECK_EXTRA_PERIODS` more: the batched engine's LSODA for an
    ``auto`` run (its samples a period), else ``simulate``'s path with the
    same method and tolerances."""
    from . import simulate as sim
    from .batch import run_one

    if m is None:  # an explicit start without a mode (DOP853 or a solve_ivp method): two timed cycles more
        T_ref = min(x.period for x in kw["modes"].modes if x.period)
        t_end = (kw.get("t_end") or periods * T_ref) + CHECK_EXTRA_PERIODS * res.period
        args = {**kw, "rest": rest, "y0": y_start, "method": res.method, "progress": None, "t_end": t_end,
                "timed": timed_index(res)}
        return sim._simulate_once(scene, None, amplitude, periods + CHECK_EXTRA_PERIODS, **args)
    if res.method.startswith("LSODA (scipy odeint"):
        spp = int(round(m.period / float(res.t[1] - res.t[0])))
        run = run_one(scene, rest, m, amplitude, periods + CHECK_EXTRA_PERIODS, res.rtol, kw.get("atol"), samples_per_period=spp,
                      method="lsoda", on_slack=kw.get("on_slack", "continue"), y0=y_start)
        failed = [w for w in run.warnings if w.startswith("integration failed")]
        if failed:
            raise IntegrationError(failed[0])
        return run
    t_end = kw.get("t_end")
    args = {**kw, "rest": rest, "y0": y_start, "method": res.method, "progress": None,
            "t_end": None if t_end is None else t_end + CHECK_EXTRA_PERIODS * m.period}
    return sim._simulate_once(scene, m.label, amplitude, periods + CHECK_EXTRA_PERIODS, **args)
