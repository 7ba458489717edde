"""The thesis's Kane-method model of a two-wire (bifilar) pendulum, section 5.1:
its states and solutions.

The model itself -- frames and conventions, the parameters, the geometry of
the five angles and the equations of motion (5.1.30) -- is in
:mod:`bifilar.models.kane_equations`, whose public names this module
re-exports, so that ``bifilar.models.kane`` stays the model's one entry point.
Here: the consistent initial state (theta5 and its rate from the constraint),
what a state means in the world (pose, velocities, wire vectors, attachment
points), its energy and wire tensions, and the integration of the equations.
SI units throughout (m, kg, s, rad, N).
"""

from __future__ import annotations

import math
from typing import Tuple

import numpy as np
from scipy.integrate import solve_ivp

from bifilar.errors import ConvergenceError, InputError

from .kane_equations import (  # noqa: F401 (re-exported: the model's public names and what the tests use)
    COND_MAX,
    SIN_THETA2_MIN,
    KaneParams,
    KaneSingularityError,
    _bc,
    _cd,
    _com_offset_body,
    _core,
    _frame,
    _pose_vel,
    _sc,
    _solve_accel,
    _state,
    constraint,
    mass_matrix_and_forcing,
    mass_matrix_with_inertia,
    rest_forcing,
    rhs,
    state_quantities,
)

__all__ = [
    "KaneParams",
    "KaneSingularityError",
    "constraint",
    "mass_matrix_and_forcing",
    "rhs",
    "complete_initial_state",
    "pose",
    "velocity",
    "wire_vectors",
    "attachment_points_body",
    "energy",
    "tensions",
    "simulate",
    "SIN_THETA2_MIN",
    "COND_MAX",
]


def complete_initial_state(theta1to4, thetadot1to4, p: KaneParams, theta5_guess: float = 0.0) -> np.ndarray:
    """Complete (theta1..4, thetadot1..4) to a consistent state y0 (10,).

    theta5 solves the constraint (5.1.2) exactly: for fixed theta1..4,
    ``g = K + 2 b' rho cos(theta5 - phi)``, so the two roots are found in
    closed form, the one nearest ``theta5_guess`` is kept and polished by
    Newton's method to ``|g - l'^2| <= 1e-14 l'^2`` (or to the round-off
    floor).  thetadot5 then follows from (5.1.4): ``thetadot5 = gamma .
    thetadot1..4``.

    Parameters
    ----------
    theta1to4 : array (4,)
        theta1..theta4, rad.
    thetadot1to4 : array (4,)
        Their rates, rad/s.
    p : KaneParams
    theta5_guess : float
        Selects the root, rad.

    Returns
    -------
    ndarray (10,)
        ``[theta1..5 (rad), thetadot1..5 (rad/s)]``.

    Raises
    ------
    InputError
        If no theta5 closes the loop (the wires cannot reach).
    KaneSingularityError
        If dg/dtheta5 = 0 at the solution (tangent root).
    ConvergenceError
        If the Newton polish fails to reach 1e-12 relative.
    """
    th = np.asarray(theta1to4, dtype=float).reshape(4)
    thd = np.asarray(thetadot1to4, dtype=float).reshape(4)
    s2, c2, s3, c3, s4, c4 = (math.sin(th[1]), math.cos(th[1]), math.sin(th[2]),
                              math.cos(th[2]), math.sin(th[3]), math.cos(th[3]))
    l, bp, lp = p.l, p.b_prime, p.l_prime
    E0 = np.array([l * s2 * c3, -p.b + l * s2 * s3, -l * c2])  # C - A
    P = E0[0] * s4 + E0[1] * c4
    Q = E0[2]
    rho = math.hypot(P, Q)
    K = float(E0 @ E0) + bp * bp
    arg = (lp * lp - K) / (2.0 * bp * rho) if rho > 0 else math.inf
    if not abs(arg) <= 1.0:
        raise InputError(
            "theta1to4",
            f"no theta5 closes the loop for theta1..4 = {th.tolist()} "
            f"(|D - A| cannot equal l' = {lp}); choose another pose",
        )
    phi = math.atan2(Q, P)
    acs = math.acos(arg)
    best = None
    for root in (phi + acs, phi - acs):
        root = root + 2.0 * math.pi * round((theta5_guess - root) / (2.0 * math.pi))
        if best is None or abs(root - theta5_guess) < abs(best - theta5_guess):
            best = root
    t5 = best
    target = lp * lp
    theta = np.append(th, t5)
    for _ in range(50):
        res = constraint(theta, p)
        if abs(res) <= 1e-14 * target:
            break
        dg = 2.0 * bp * (-P * math.sin(theta[4]) + Q * math.cos(theta[4]))
        if dg == 0.0:
            break
        step = res / dg
        theta[4] -= step
        if abs(step) <= 4.0 * np.finfo(float).eps * max(1.0, abs(theta[4])):
            break
    res = constraint(theta, p)
    if not abs(res) <= 1e-12 * target:
        raise ConvergenceError(
            f"theta5 Newton iteration stalled at |g - l'^2| = {abs(res):.3g} m^2"
        )
    k = _core(theta, np.append(thd, 0.0), p)
    t5d = float(k["gamma"] @ thd)
    return np.concatenate([theta, thd, [t5d]])


def pose(theta, p: KaneParams) -> Tuple[np.ndarray, np.ndarray]:
    """Pose of the body: CoM position and orientation.

    Parameters
    ----------
    theta : array (5,) (or (5, ...) batch; complex allowed)
        Angles, rad.
    p : KaneParams

    Returns
    -------
    com : ndarray (3,)
        CoM position, world frame, m: ``B + BC + r sin(lam) ntilde_1 - r cos(lam) ntilde_3``.
    R : ndarray (3, 3)
        Rotation body (ntilde) components -> world components; its columns
        are ntilde_1, ntilde_2, ntilde_3 (5.1.5).
    """
    com, R, _, _ = _pose_vel(theta, None, p)
    return com, R


def velocity(theta, thetadot, p: KaneParams) -> Tuple[np.ndarray, np.ndarray]:
    """CoM velocity and angular velocity of the body, world frame.

    Parameters
    ----------
    theta : array (5,) (or (5, ...) batch; complex allowed)
        Angles, rad.
    thetadot : array like theta
        Angle rates, rad/s.
    p : KaneParams

    Returns
    -------
    com_velocity : ndarray (3,)
        m/s, world frame (5.1.17).
    omega_world : ndarray (3,)
        rad/s, world frame: ``thetadot1 ntilde_3 - thetadot4 n3 + thetadot5 (c4 n1 - s4 n2)``.
    """
    _, _, v, w = _pose_vel(theta, thetadot, p)
    return v, w


def wire_vectors(theta, p: KaneParams) -> Tuple[np.ndarray, np.ndarray]:
    """Wire vectors, world frame, m.

    Parameters
    ----------
    theta : array (5,)
        Angles, rad.
    p : KaneParams

    Returns
    -------
    BC : ndarray (3,)
        From anchor B to attachment C (wire 1, length l).
    DA : ndarray (3,)
        From attachment D to anchor A (wire 2; length l' when the constraint holds).
    """
    s, c = _sc(theta)
    BC = _bc(s, c, p)
    CD = _cd(s, c, p)
    A = p.anchor_A.reshape((3,) + (1,) * (np.ndim(s) - 1))
    B = p.anchor_B.reshape((3,) + (1,) * (np.ndim(s) - 1))
    DA = A - (B + BC + CD)
    return BC, DA


def attachment_points_body(p: KaneParams) -> Tuple[np.ndarray, np.ndarray]:
    """Attachment points C and D in the ntilde body frame, origin at the CoM, m.

    Returns
    -------
    p_C : ndarray (3,)
        ``-(r sin(lam), 0, -r cos(lam))``.
    p_D : ndarray (3,)
        ``p_C + (0, 0, -b')`` (since ``CD = -b' ntilde_3``).
    """
    pC = -_com_offset_body(p)
    pD = pC + np.array([0.0, 0.0, -p.b_prime])
    return pC, pD


def energy(y, p: KaneParams):
    """Total mechanical energy, J.

    ``0.5 m |v|^2 + 0.5 omega . I omega + m g z_com`` with the potential zero
    at world height z = 0 (the default anchors lie at z = 0).

    Parameters
    ----------
    y : array (10,) or (10, n)
        State(s) ``[theta (rad), thetadot (rad/s)]``; a batch of n states
        along the trailing axis (e.g. ``solve_ivp(...).y``) gives an array (n,).
    p : KaneParams

    Returns
    -------
    float or ndarray (n,)
    """
    y = np.asarray(y, dtype=float)
    com, R, v, w = _pose_vel(y[:5], y[5:], p)
    if R.ndim == 2:
        wb = R.T @ w
        rot = wb @ p.inertia @ wb
    else:
        wb = np.einsum("ji...,j...->i...", R, w)
        rot = np.einsum("i...,ij,j...->...", wb, p.inertia, wb)
    e = 0.5 * p.mass * np.sum(v * v, axis=0) + 0.5 * rot + p.mass * p.g * com[2]
    return float(e) if np.ndim(e) == 0 else e


def tensions(y, p: KaneParams) -> Tuple[float, float, float]:
    """Wire tensions from Newton's second law (section 7.2, general case).

    Solves ``F1 u_CB + F2 u_DA = m a + m g n3`` (3 equations, 2 unknowns) in
    the least-squares sense, with ``u_CB``, ``u_DA`` the unit vectors from C
    to B and from D to A and ``a = V thetaddot + Vdot thetadot`` the CoM
    acceleration (world frame, m/s^2) with thetaddot from :func:`rhs`.

    Parameters
    ----------
    y : array (10,)
        State ``[theta (rad), thetadot (rad/s)]``.
    p : KaneParams

    Returns
    -------
    F1 : float
        Tension of wire 1 (B-C), N, positive = taut.
    F2 : float
        Tension of wire 2 (D-A), N, positive = taut.
    residual : float
        Norm of the least-squares residual, N (zero for exact dynamics; a
        measure of consistency).
    """
    theta, thetadot = _state(y)
    qdd, k = _solve_accel(theta, thetadot, p)
    a = k["V"] @ qdd + k["Vdtd"]
    u1 = -k["BC"] / p.l
    u2 = -k["E"] / np.linalg.norm(k["E"])
    A = np.column_stack([u1, u2])
    rhs_f = p.mass * (a + np.array([0.0, 0.0, p.g]))
    F, *_ = np.linalg.lstsq(A, rhs_f, rcond=None)
    resid = float(np.linalg.norm(A @ F - rhs_f))
    return float(F[0]), float(F[1]), resid


def simulate(
    p: KaneParams,
    y0,
    t_end: float,
    rtol: float = 1e-12,
    atol: float = 1e-12,
    method: str = "DOP853",
    t_eval=None,
):
    """Integrate (5.1.30) from ``y0`` over ``[0, t_end]`` s with solve_ivp.

    Parameters
    ----------
    p : KaneParams
    y0 : array (10,)
        Consistent initial state (see :func:`complete_initial_state`).
    t_end : float
        Final time, s.
    rtol, atol : float
        solve_ivp tolerances (atol in rad and rad/s).
    method : str
        solve_ivp method; DOP853 is the default (explicit, high order, no
        Jacobian needed).
    t_eval : array or None
        Output times, s; ``None`` returns the solver's own steps.

    Returns
    -------
    scipy OdeResult
        The solve_ivp result with three extra fields:
        ``max_constraint`` (max |g - l'^2| over the output points, m^2),
        ``max_energy_drift`` (max |E(t) - E(0)|, J) and
        ``max_relative_energy_drift`` (that drift divided by the largest
        kinetic energy seen on the output points, i.e. relative to the
        oscillation energy; if the body never moves it is divided by
        ``m g max(l, l')`` instead).

    Raises
    ------
    KaneSingularityError
        Propagated from :func:`rhs` when the path reaches a singular pose.
    """
    y0 = np.asarray(y0, dtype=float)
    sol = solve_ivp(rhs, (0.0, float(t_end)), y0, method=method, rtol=rtol,
                    atol=atol, t_eval=t_eval, args=(p,))
    Y = sol.y
    if Y.size:
        sol.max_constraint = float(np.max(np.abs(constraint(Y[:5], p))))
        E = energy(Y, p)
        E0 = energy(y0, p)
        drift = float(np.max(np.abs(E - E0)))
        _, _, v, w = _pose_vel(Y[:5], Y[5:], p)
        wb = np.einsum("ji...,j...->i...", _frame(*_sc(Y[:5])), w)
        ke = 0.5 * p.mass * np.sum(v * v, axis=0) + 0.5 * np.einsum("i...,ij,j...->...", wb, p.inertia, wb)
        scale = float(np.max(ke))
        if not scale > 0.0:
            scale = p.mass * p.g * max(p.l, p.l_prime)
        sol.max_energy_drift = drift
        sol.max_relative_energy_drift = drift / scale
    else:
        sol.max_constraint = math.nan
        sol.max_energy_drift = math.nan
        sol.max_relative_energy_drift = math.nan
    return sol
