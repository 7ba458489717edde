"""The thesis's Kane-method model of a two-wire (bifilar) pendulum, section 5.1.

A faithful numpy implementation of section 5.1 of the thesis (after Kane &
Tseng 1967).  It exists to reproduce the thesis's results and to cross-check
the package's general model; it is not the default model, because its
coordinates are singular for vertical (parallel) wires, theta2 = 0.  This
module holds the parameters, the geometry of the angles and the equations of
motion; :mod:`bifilar.models.kane` (which re-exports them) the initial state,
the pose, energy and tensions of a state, and the integration.

Frames and conventions (SI units throughout: m, kg, s, rad, N)
----------------------------------------------------------------
* Earth (world) frame ``n1, n2, n3`` with ``n3`` up; gravity is ``-g n3``.
* Ceiling anchors B and A at one height, ``A - B = +b n2`` (the thesis writes
  ``AB = -b n2``: the vector *from A to B*).  B sits at ``p.anchor_B``
  (default ``(0, -b/2, 0)``), so the anchors are symmetric about the origin.
* Five angles ``theta = (theta1 .. theta5)`` (rad):
  ``BC = l (s2 c3, s2 s3, -c2)``  (wire 1, B -> C, length l),
  ``CD = b' (s4 c5, c4 c5, s5)``  (body segment between the attachments),
  wire 2 runs D -> A with length l'.  Loop closure gives the holonomic
  constraint ``g(theta) = |B + BC + CD - A|^2 = l'^2``  (5.1.2).
* Body frame ``ntilde_1..3``: the COLUMNS of the matrix printed in (5.1.5),
  so ``ntilde_3 = -CD / b'``.  ``R = [ntilde_1 ntilde_2 ntilde_3]`` maps
  body (ntilde) components to world components.  theta1 rolls the body about
  CD, theta4 yaws CD, theta5 pitches CD.
* Angular velocity (5.1.8)-(5.1.10), world components:
  ``omega = thetadot1 ntilde_3 - thetadot4 n3 + thetadot5 (c4 n1 - s4 n2)``.
* Centre of mass (5.1.14): ``R* = C + r sin(lam) ntilde_1 - r cos(lam) ntilde_3``.
* Inertia tensor about the CoM in the ntilde frame (kg m^2); the thesis's
  case is diagonal (principal axes along ntilde), any symmetric tensor works.

Equations of motion (5.1.30): ``M5(theta) thetaddot = N5(theta, thetadot)``.
Rows 1..4 are Kane's equations ``F_r + F_r* = 0`` with the partial
velocities taken after eliminating thetadot5 with gamma (5.1.4); row 5 is the
twice time-differentiated constraint ``beta . thetaddot + betadot . thetadot
= 0`` with ``beta = dg/dtheta``.  All kinematic derivatives, including the
velocity-product terms, are analytic (they are checked against complex-step
differentiation in the tests).

The state vector used by :func:`rhs` is ``y = [theta(5), thetadot(5)]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np

from bifilar.errors import InputError, SingularCoordinatesError


#: |sin(theta2)| below which the thesis's coordinates are declared singular.
SIN_THETA2_MIN = 1e-6
#: Largest accepted condition number of the (non-dimensionalised) M5.
COND_MAX = 1e12

_THETA2_ADVICE = (
    "the thesis's coordinates are singular for vertical wires (theta2 = 0); "
    "use the default model"
)


class KaneSingularityError(SingularCoordinatesError):
    """The thesis's angles cannot describe the motion at this state.

    Raised when |sin(theta2)| < :data:`SIN_THETA2_MIN` (wire BC vertical, so
    theta3 is undefined and M5 has a zero row and column), when the
    non-dimensionalised M5 has condition number above :data:`COND_MAX`, or
    when dg/dtheta5 = 0 so that theta5 cannot be eliminated by (5.1.4).
    Subclass of :class:`ArithmeticError` (via
    :class:`bifilar.errors.SingularCoordinatesError`).
    """


@dataclass(frozen=True, eq=False)
class KaneParams:
    """Parameters of the thesis's bifilar pendulum (section 5.1), SI units.

    Attributes
    ----------
    b : float
        Distance between the ceiling anchors A and B, m (``A - B = b n2``).
    b_prime : float
        Distance between the body attachment points C and D, m.
    l : float
        Length of wire 1 (B -> C), m.
    l_prime : float
        Length of wire 2 (D -> A), m.
    mass : float
        Body mass, kg.
    inertia : ndarray (3, 3)
        Inertia tensor about the CoM in the ntilde body frame, kg m^2
        (diag(I1, I2, I3) in the thesis).  Stored as a read-only copy.
    r : float
        Distance from C to the CoM, m (5.1.14).
    lam : float
        Angle lambda of (5.1.14), rad: CoM offset from C is
        ``r sin(lam) ntilde_1 - r cos(lam) ntilde_3``.
    g : float
        Gravitational acceleration, m/s^2, along world -n3.
    anchor_B : (3,) or None
        World position of anchor B, m; ``None`` means ``(0, -b/2, 0)``.
        A is always ``anchor_B + (0, b, 0)``.
    """

    b: float
    b_prime: float
    l: float
    l_prime: float
    mass: float
    inertia: np.ndarray
    r: float
    lam: float
    g: float = 9.81
    anchor_B: Optional[Sequence[float]] = None

    def __post_init__(self) -> None:
        for name in ("b", "b_prime", "l", "l_prime", "mass"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0.0):
                raise InputError(name, f"must be a positive finite number, got {v!r}")
            object.__setattr__(self, name, v)
        for name in ("r", "lam", "g"):
            v = float(getattr(self, name))
            if not math.isfinite(v):
                raise InputError(name, f"must be finite, got {v!r}")
            object.__setattr__(self, name, v)
        I = np.array(self.inertia, dtype=float)
        if I.shape != (3, 3) or not np.all(np.isfinite(I)):
            raise InputError("inertia", f"must be a finite 3x3 array, got shape {I.shape}")
        if not np.allclose(I, I.T, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(I).max())):
            raise InputError("inertia", "must be symmetric")
        if np.linalg.eigvalsh(I).min() < -1e-12 * max(1.0, np.abs(I).max()):
            raise InputError("inertia", "must be positive semi-definite")
        I.setflags(write=False)
        object.__setattr__(self, "inertia", I)
        B = (0.0, -0.5 * self.b, 0.0) if self.anchor_B is None else self.anchor_B
        B = np.array(B, dtype=float)
        if B.shape != (3,) or not np.all(np.isfinite(B)):
            raise InputError("anchor_B", "must be a finite 3-vector")
        B.setflags(write=False)
        object.__setattr__(self, "anchor_B", B)

    @property
    def anchor_A(self) -> np.ndarray:
        """World position of anchor A, m: ``anchor_B + (0, b, 0)``."""
        return self.anchor_B + np.array([0.0, self.b, 0.0])


# ---------------------------------------------------------------------------
# Geometry shared by the public functions.  Every helper here is elementwise
# in the angles: theta may be (5,) or (5, ...) (a batch along trailing axes)
# and may be complex (complex-step differentiation in the tests).  Vectors
# come back as (3, ...) and matrices as (3, 3, ...).
# ---------------------------------------------------------------------------


def _sc(theta):
    th = np.asarray(theta)
    return np.sin(th), np.cos(th)


def _frame(s, c):
    """R = [ntilde_1 ntilde_2 ntilde_3] (columns) of (5.1.5), shape (3, 3, ...)."""
    s1, s4, s5 = s[0], s[3], s[4]
    c1, c4, c5 = c[0], c[3], c[4]
    return np.array(
        [
            [s1 * c4 + c1 * s4 * s5, c1 * c4 - s1 * s4 * s5, -s4 * c5],
            [-s1 * s4 + c1 * c4 * s5, -c1 * s4 - s1 * c4 * s5, -c4 * c5],
            [-c1 * c5, s1 * c5, -s5],
        ]
    )


def _bc(s, c, p):
    return p.l * np.array([s[1] * c[2], s[1] * s[2], -c[1]])


def _cd(s, c, p):
    return p.b_prime * np.array([s[3] * c[4], c[3] * c[4], s[4]])


def _com_offset_body(p) -> np.ndarray:
    """CoM minus C in ntilde components (5.1.14), m."""
    return np.array([p.r * math.sin(p.lam), 0.0, -p.r * math.cos(p.lam)])


def _cross(a, b):
    """a x b for vectors stored along axis 0 (any trailing batch shape)."""
    return np.array(
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    )


def _rot(R, v):
    """R v for R (3, 3, ...) and v (3, ...) or v (3,)."""
    if np.ndim(v) == 1 and np.ndim(R) > 2:
        v = v.reshape((3,) + (1,) * (np.ndim(R) - 2))
    return np.einsum("ij...,j...->i...", R, v) if np.ndim(R) > 2 else R @ v


def _pose_vel(theta, thetadot, p):
    """com (3,...), R (3,3,...), com velocity (3,...), omega (3,...), world frame."""
    s, c = _sc(theta)
    R = _frame(s, c)
    rN = _rot(R, _com_offset_body(p))
    B = p.anchor_B.reshape((3,) + (1,) * (np.ndim(s) - 1))
    com = B + _bc(s, c, p) + rN
    if thetadot is None:
        return com, R, None, None
    td = np.asarray(thetadot)
    l = p.l
    vC = l * np.array(
        [
            c[1] * c[2] * td[1] - s[1] * s[2] * td[2],
            c[1] * s[2] * td[1] + s[1] * c[2] * td[2],
            s[1] * td[1],
        ]
    )
    zero = np.zeros_like(s[0])
    q3 = np.array([c[3], -s[3], zero])  # c4 n1 - s4 n2
    n3 = np.array([zero, zero, zero + 1.0])
    omega = td[0] * R[:, 2] - td[3] * n3 + td[4] * q3
    v = vC + _cross(omega, rN)
    return com, R, v, omega


# ---------------------------------------------------------------------------
# Kane's equations for one state (real, (5,) arrays).  Kept lean: the RHS is
# evaluated O(1e4) times per simulation.
# ---------------------------------------------------------------------------


def _geometry(theta, p, check=True):
    """The quantities of :func:`_core` that depend on the angles alone (not
    on the rates): sines and cosines, the frame R, the CoM offset rN, BC,
    CD, E = D - A, the Jacobians JC, JCD, JE, G and V, beta = dg/dtheta and
    gamma (5.1.4), with its checks; the same expressions, so the same
    numbers (complex angles allowed: the complex step)."""
    theta = np.asarray(theta)
    s, c = _sc(theta)
    s1, s2, s3, s4, s5 = s
    c1, c2, c3, c4, c5 = c
    l, bp = p.l, p.b_prime
    R = _frame(s, c)
    nt3 = R[:, 2]
    rN = R @ _com_offset_body(p)  # CoM - C, world
    BC = l * np.array([s2 * c3, s2 * s3, -c2])
    CD = bp * np.array([s4 * c5, c4 * c5, s5])
    E = BC + CD - np.array([0.0, p.b, 0.0])  # D - A, world

    z = 0.0 * s1  # keeps the dtype (complex-step in the tests)
    # Jacobian of C (5.1.16) and of CD, 3 x 5.
    JC = np.array(
        [
            [z, l * c2 * c3, -l * s2 * s3, z, z],
            [z, l * c2 * s3, l * s2 * c3, z, z],
            [z, l * s2, z, z, z],
        ]
    )
    JCD = np.array(
        [
            [z, z, z, bp * c4 * c5, -bp * s4 * s5],
            [z, z, z, -bp * s4 * c5, -bp * c4 * s5],
            [z, z, z, z, bp * c5],
        ]
    )
    # omega = G thetadot (5.1.10), columns: ntilde_3, 0, 0, -n3, c4 n1 - s4 n2.
    G = np.array(
        [
            [nt3[0], z, z, z, c4],
            [nt3[1], z, z, z, -s4],
            [nt3[2], z, z, z - 1.0, z],
        ]
    )
    # V = C + W (5.1.17); W e_i = G e_i x r  ->  W = -skew(r) G.
    skr = np.array([[z, -rN[2], rN[1]], [rN[2], z, -rN[0]], [-rN[1], rN[0], z]])
    V = JC - skr @ G
    JE = JC + JCD
    beta = 2.0 * (E @ JE)  # dg/dtheta (5.1.3)

    if check and not np.all(np.isfinite(beta)):
        raise FloatingPointError(f"non-finite state theta = {theta!r}")
    b5 = beta[4]
    if check and abs(b5) <= 1e-12 * max(np.abs(beta).max(), 1e-300):
        raise KaneSingularityError(
            f"dg/dtheta5 = 0 at theta = {np.array2string(np.real(theta), precision=6)}: "
            "theta5 cannot be eliminated with (5.1.4) (CD is perpendicular to the "
            "closing vector D - A); the thesis's coordinates are singular here; "
            "use the default model"
        )
    gamma = -beta[:4] / b5  # (5.1.4)

    return s, c, R, rN, BC, CD, E, z, JC, JCD, G, V, JE, beta, gamma


def _core(theta, thetadot, p, *, check=True):
    """All quantities of section 5.1 at one state; see mass_matrix_and_forcing."""
    td = np.asarray(thetadot)
    s, c, R, rN, BC, CD, E, z, JC, JCD, G, V, JE, beta, gamma = _geometry(theta, p, check)
    _, s2, s3, s4, s5 = s
    _, c2, c3, c4, c5 = c
    l, bp = p.l, p.b_prime
    nt3 = R[:, 2]

    omega = G @ td
    v = V @ td
    Edot = JE @ td
    t1d, t2d, t3d, t4d, t5d = td
    # Velocity-product (quadratic) parts of the second derivatives.
    kC = l * np.array(
        [
            -s2 * c3 * (t2d * t2d + t3d * t3d) - 2.0 * c2 * s3 * t2d * t3d,
            -s2 * s3 * (t2d * t2d + t3d * t3d) + 2.0 * c2 * c3 * t2d * t3d,
            c2 * t2d * t2d,
        ]
    )
    kCD = bp * np.array(
        [
            -s4 * c5 * (t4d * t4d + t5d * t5d) - 2.0 * c4 * s5 * t4d * t5d,
            -c4 * c5 * (t4d * t4d + t5d * t5d) + 2.0 * s4 * s5 * t4d * t5d,
            -s5 * t5d * t5d,
        ]
    )
    # Gdot thetadot: d(ntilde_3)/dt = omega x ntilde_3; d(c4, -s4, 0)/dt = thetadot4 (-s4, -c4, 0).
    Gdtd = t1d * _cross(omega, nt3) + t4d * t5d * np.array([-s4, -c4, z])
    # Vdot thetadot = kC + (Gdot thetadot) x r + omega x (omega x r).
    Vdtd = kC + _cross(Gdtd, rN) + _cross(omega, _cross(omega, rN))
    betadot_td = 2.0 * (Edot @ Edot) + 2.0 * (E @ (kC + kCD))

    # Partial velocities with thetadot5 eliminated (5.1.19), (5.1.21).
    Vn = V[:, :4] + np.outer(V[:, 4], gamma)
    Gn = G[:, :4] + np.outer(G[:, 4], gamma)
    Iw = R @ p.inertia @ R.T  # inertia about the CoM, world components

    m = p.mass
    M5 = np.empty((5, 5), dtype=np.result_type(s, td))
    N5 = np.empty(5, dtype=M5.dtype)
    MV = m * (Vn.T @ V)  # the translational part (the inertia enters through Gn^T Iw G only)
    M5[:4] = MV + Gn.T @ (Iw @ G)
    N5[:4] = -m * (Vn.T @ Vdtd) - Gn.T @ (Iw @ Gdtd + _cross(omega, Iw @ omega)) - m * p.g * Vn[2]
    M5[4] = beta
    N5[4] = -betadot_td
    return dict(
        R=R, rN=rN, BC=BC, CD=CD, E=E, V=V, G=G, beta=beta, gamma=gamma,
        omega=omega, v=v, Vdtd=Vdtd, Gdtd=Gdtd, M5=M5, N5=N5, Iw=Iw, Gn=Gn, MV=MV,
    )


def rest_forcing(theta, p: KaneParams) -> np.ndarray:
    """N5 (5,) of :func:`mass_matrix_and_forcing` at ``theta`` with every
    rate zero (rows 1..4 N m, row 5 m^2/s^2): with the rates zero every
    velocity term of rows 1..4 is an exact zero and row 5 (-betadot .
    thetadot) is zero, so N5 is the gravity term ``-m g Vn[2]`` alone, from
    the same expressions (:func:`_geometry`), so the same numbers but for
    the sign of an exact zero.  Complex ``theta`` allowed: the thesis rung's
    forcing Jacobian by complex step (:func:`bifilar.estimation.ladder._thesis_forcing`)
    needs only this, ~40 % of a full :func:`_core` on complex numbers."""
    s, *_, V, _, _, gamma = _geometry(theta, p)
    Vn = V[:, :4] + np.outer(V[:, 4], gamma)
    N5 = np.zeros(5, dtype=np.result_type(s, float))
    N5[:4] = -(p.mass * p.g * Vn[2])
    return N5


def state_quantities(theta, thetadot, p: KaneParams) -> dict:
    """Every quantity of section 5.1 at one state (theta rad, thetadot
    rad/s, (5,) each), as :func:`mass_matrix_and_forcing` computes them:
    ``M5``, ``N5`` and their parts, for :func:`mass_matrix_with_inertia`."""
    return _core(theta, thetadot, p)


def mass_matrix_with_inertia(k: dict, inertia) -> np.ndarray:
    """M5 (5, 5) of the state whose quantities are ``k``
    (:func:`state_quantities` with params ``p``) for params that differ
    from ``p`` only in the inertia (3, 3, kg m^2, ntilde axes, about the
    CoM): the inertia enters M5 only through ``Gn^T (R I R^T) G``, so the
    rest is reused; the same expressions as :func:`_core`, so the same
    numbers as :func:`mass_matrix_and_forcing` with those params."""
    R, G = k["R"], k["G"]
    Iw = R @ inertia @ R.T
    M5 = np.empty_like(k["M5"])
    M5[:4] = k["MV"] + k["Gn"].T @ (Iw @ G)
    M5[4] = k["beta"]
    return M5


def _state(y):
    y = np.asarray(y, dtype=float)
    if y.shape != (10,):
        raise InputError("y", f"state must have shape (10,), got {y.shape}")
    return y[:5], y[5:]


# ---------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------


def constraint(theta, p: KaneParams):
    """Loop-closure residual ``g(theta) - l'^2`` of (5.1.2), m^2.

    Parameters
    ----------
    theta : array (5,) or (5, ...)
        The thesis's angles theta1..theta5, rad (a batch along trailing axes
        is allowed; complex input is allowed for complex-step derivatives).
    p : KaneParams

    Returns
    -------
    float (or array over the batch)
        ``|B + BC + CD - A|^2 - l'^2`` in m^2; zero on the constraint manifold.
    """
    s, c = _sc(theta)
    E = _bc(s, c, p) + _cd(s, c, p)
    E = E - np.array([0.0, p.b, 0.0]).reshape((3,) + (1,) * (np.ndim(s) - 1))
    res = E[0] * E[0] + E[1] * E[1] + E[2] * E[2] - p.l_prime**2
    return float(res) if np.ndim(res) == 0 and not np.iscomplexobj(res) else res


def mass_matrix_and_forcing(theta, thetadot, p: KaneParams) -> Tuple[np.ndarray, np.ndarray]:
    """M5(theta) and N5(theta, thetadot) of (5.1.30): ``M5 thetaddot = N5``.

    Rows 1..4 are Kane's equations ``F_r + F_r* = 0`` (5.1.28), written as
    ``m v_r . a + omega_r . (I alpha + omega x I omega) = v_r . (-m g n3)``
    with the partial velocities ``v_r``, ``omega_r`` the columns of V_new,
    G_new (thetadot5 eliminated with gamma, (5.1.4)), ``a = V thetaddot +
    Vdot thetadot`` and ``alpha = G thetaddot + Gdot thetadot`` (world
    frame).  Row 5 is ``beta . thetaddot = -betadot . thetadot``, the second
    time derivative of the constraint g(theta) = l'^2.

    Parameters
    ----------
    theta : array (5,)
        Angles, rad.
    thetadot : array (5,)
        Angle rates, rad/s (should satisfy beta . thetadot = 0).
    p : KaneParams

    Returns
    -------
    M5 : ndarray (5, 5)
        Rows 1..4 in kg m^2 (N m per rad/s^2), row 5 in m^2 (per rad/s^2).
    N5 : ndarray (5,)
        Rows 1..4 in N m, row 5 in m^2/s^2.

    Raises
    ------
    KaneSingularityError
        If dg/dtheta5 = 0 (theta5 cannot be eliminated).  M5 is returned even
        when theta2 = 0 (it then has a zero third row and column, as the
        thesis notes in section 6.2); :func:`rhs` refuses to invert it.
    """
    k = _core(theta, thetadot, p)
    return k["M5"], k["N5"]


def _solve_accel(theta, thetadot, p):
    theta = np.asarray(theta, dtype=float)
    thetadot = np.asarray(thetadot, dtype=float)
    if not (np.all(np.isfinite(theta)) and np.all(np.isfinite(thetadot))):
        raise FloatingPointError(f"non-finite state: theta = {theta!r}, thetadot = {thetadot!r}")
    s2 = math.sin(theta[1])
    if abs(s2) < SIN_THETA2_MIN:
        raise KaneSingularityError(
            f"|sin(theta2)| = {abs(s2):.3g} < {SIN_THETA2_MIN:g} (theta2 = {theta[1]:.6g} rad): "
            + _THETA2_ADVICE
        )
    k = _core(theta, thetadot, p)
    M5, N5 = k["M5"], k["N5"]
    # Non-dimensionalise the rows (1-4 in kg m^2, 5 in m^2) before judging the
    # conditioning, so that the test does not depend on the choice of units.
    L = max(p.l, p.l_prime, p.b, p.b_prime, abs(p.r))
    row_scale = np.array([1.0, 1.0, 1.0, 1.0, p.mass]) / (p.mass * L * L)
    cond = np.linalg.cond(row_scale[:, None] * M5)
    if not cond <= COND_MAX:
        raise KaneSingularityError(
            f"M5 is ill-conditioned (cond = {cond:.3g} > {COND_MAX:g}) at theta2 = "
            f"{theta[1]:.6g} rad: " + _THETA2_ADVICE
        )
    qdd = np.linalg.solve(M5, N5)
    if not np.all(np.isfinite(qdd)):
        raise FloatingPointError(f"non-finite accelerations at theta = {theta!r}")
    return qdd, k


def rhs(t, y, p: KaneParams) -> np.ndarray:
    """Right-hand side of the first-order system, for scipy's solve_ivp.

    Parameters
    ----------
    t : float
        Time, s (unused: the system is autonomous).
    y : array (10,)
        State ``[theta1..theta5 (rad), thetadot1..thetadot5 (rad/s)]``.
    p : KaneParams

    Returns
    -------
    ndarray (10,)
        ``[thetadot (rad/s), thetaddot (rad/s^2)]`` with thetaddot solving
        ``M5 thetaddot = N5`` (5.1.30).

    Raises
    ------
    KaneSingularityError
        When |sin(theta2)| < 1e-6, when the non-dimensionalised M5 (rows 1-4
        divided by m L^2, row 5 by L^2, L the largest length of the rig) has
        condition number above 1e12, or when dg/dtheta5 = 0.
    FloatingPointError
        On a non-finite state or result (never returns NaN silently).
    """
    theta, thetadot = _state(y)
    qdd, _ = _solve_accel(theta, thetadot, p)
    return np.concatenate([thetadot, qdd])
