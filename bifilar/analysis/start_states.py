"""The state a run starts from: the body at rest displaced along one mode
(or several) by a stated amplitude, put back on the wires with the mode's
dominant coordinate held exactly and the rest the mass-weighted closest
pose (:mod:`bifilar.analysis.start_pose`), at zero velocity; the amplitude
a mode can reach.  States (13,) as :mod:`bifilar.models.maximal` packs them
(CoM position m, world frame; attitude quaternion; velocities m/s, rad/s).
Used by :func:`bifilar.analysis.simulate.simulate`, which re-exports them.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..models import maximal as mx
from ..scene import Scene
from .equilibrium import RestPose
from .modes import Mode
from .shared_batch import shared
from .start_pose import StartPoses, refusal, start_poses


def initial_state(scene: Scene, rest: RestPose, mode: Mode, amplitude: float) -> np.ndarray:
    """State (13,) at rest displaced by ``amplitude`` x the mode shape, put
    back on the wires with the mode's dominant coordinate held at exactly
    ``amplitude x shape[dominant]`` (as an experimenter sets the initial
    angle; measured by :func:`relative_pose`) and the other coordinates the
    mass-weighted closest on the wires (:mod:`bifilar.analysis.start_pose`),
    zero velocity.  Raises :class:`InputError` (``--amplitude``) when no such
    pose keeps every wire at its length, saying how far off the closest is."""
    sp = checked_start_poses(scene, rest, [mode], amplitude)
    return mx.pack(sp.com[0], sp.q[0])


def two_mode_state(scene: Scene, rest: RestPose, mode: Mode, amplitude: float, second: Mode,
                   second_amplitude: float) -> np.ndarray:
    """State (13,) of a release that starts two modes, as a hand release
    does: displaced along ``mode`` by ``amplitude`` (:func:`initial_state`,
    held and released at rest) and moving along ``second`` with the linear
    velocity of an oscillation of amplitude ``second_amplitude`` (units of
    its normalised shape, rad or m) passing its rest (``v = amplitude x
    omega x shape``, world frame), that velocity made tangent to the wires
    (the least kinetic-energy change that keeps every wire's length rate
    zero, so the run starts on the constraints).  The second mode then
    oscillates a quarter period out of phase with the first; its effect on
    the first mode's period is second order in its amplitude and, away from
    an internal resonance, independent of that phase."""
    return multi_mode_state(scene, rest, mode, amplitude, [(second, second_amplitude)])


def multi_mode_state(scene: Scene, rest: RestPose, mode: Mode, amplitude: float, others) -> np.ndarray:
    """State (13,) of a release that starts ``mode`` displaced by
    ``amplitude`` and every ``(Mode, amplitude)`` of ``others`` moving
    through its rest (:func:`two_mode_state`'s construction, the linear
    velocities summed before they are made tangent to the wires; a signed
    amplitude reverses that mode's velocity).  Units: each mode's normalised
    shape (rad or m); velocities world frame, the state's angular rate body
    axes."""
    y0 = initial_state(scene, rest, mode, amplitude)
    others = [(m, a) for m, a in others if a and m.period]
    if not others:
        return y0
    vel = np.zeros(6)
    for second, second_amplitude in others:
        omega = 2 * np.pi / second.period
        vel = vel + second_amplitude * omega * np.asarray(second.shape, float)  # [v (3), w_world (3)]
    P = mx.params_from_scenes(scene)
    kin = mx.kinematics(y0, P)
    d, Rp, R = kin["d"], kin["Rp"], kin["R"]
    G = np.concatenate([d, np.cross(Rp, d)], axis=1)  # phidot_i = G_i . [v, w_world]
    vel = tangent_to_wires(scene, R, G, vel)
    y0 = y0.copy()
    y0[7:10] = vel[:3]
    y0[10:13] = R.T @ vel[3:]  # body axes
    return y0


def reachable_amplitude(scene: Scene, mode: Mode) -> tuple[float, str]:
    """(limit, unit): the largest amplitude any start of ``mode`` can have
    in its dominant coordinate, pi rad for a rotation, twice the longest
    wire (m) for a translation; a larger one is refused before any pose is
    solved (:func:`checked_start_poses`)."""
    if mode.dominant >= 3:
        return float(np.pi), "rad"
    return 2.0 * float(np.max(scene.lengths)), "m"


def checked_start_poses(scene: Scene, rest: RestPose, modes: list[Mode], amplitude: float,
                        more=None) -> StartPoses:
    """Start poses of one scene displaced along each of ``modes`` (solved
    together, :func:`~bifilar.analysis.start_pose.start_poses`) with
    :func:`initial_state`'s checks: raises what :func:`initial_state` of
    each mode in turn raises first.  For a point's refusal check whose
    start poses then go to ``simulate_batch(..., starts=)``: solved once.
    ``more``: (scenes, rests, modes, amplitudes) of further runs with the
    same number of wires (a sweep point's amplitude laws' runs), solved in
    the same call and appended after ``modes``' rows, not checked (their
    ``feasible`` says; ``simulate_batch`` refuses them run by run).  Rows
    are solved independently (per-row iterations), so each row is what a
    call of its own gives (tests/test_point_cost.py)."""
    if not np.isfinite(amplitude):
        raise InputError("--amplitude", f"must be finite, got {amplitude}")
    beyond = None
    for j, mode in enumerate(modes):
        limit, unit = reachable_amplitude(scene, mode)
        if abs(amplitude) > limit:
            beyond = InputError("--amplitude", f"{amplitude:g} {unit} is beyond any reachable start of the "
                                               f"{mode.label} mode (|amplitude| <= {limit:.4g} {unit})")
            modes = modes[:j]  # the modes before it are checked first, as one by one
            break
    n = len(modes)
    if more is not None and beyond is None and n and len(more[0]):
        job = ([scene] * n + list(more[0]), [rest] * n + list(more[1]), list(modes) + list(more[2]),
               np.r_[np.full(n, float(amplitude)), np.asarray(more[3], float)])
    else:
        job = ([scene] * n, [rest] * n, list(modes), np.full(n, float(amplitude))) if modes else None
    # in a batch shared with other sweep points where there is one (rows solved independently: the same numbers)
    sp = None if job is None else shared("start poses", job)
    if sp is None and job is not None:
        sp = start_poses(*job)
    for j, mode in enumerate(modes):
        if not sp.feasible[j]:
            raise refusal(scene, mode, amplitude, float(sp.gap[j]), **sp.off_wires(j))
    if beyond is not None:
        raise beyond
    return sp


def tangent_to_wires(scene: Scene, R: np.ndarray, G: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The vector closest to ``u`` (6,: a CoM velocity or displacement, m/s
    or m, and an angular velocity or small rotation, rad/s or rad, both world
    frame) in the body's kinetic-energy metric (mass ``scene.mass``, inertia
    ``R I R^T``; ``R`` the attitude body -> world) that changes no wire's
    length to first order: ``G u' = 0`` with ``G`` (n, 6) the wires'
    constraint Jacobian ``[d_i, (R p_i) x d_i]`` at the pose
    (:func:`bifilar.analysis.equilibrium.constraint_jacobian`).  Used for a
    release's second-mode velocities (:func:`multi_mode_state`) and the
    symmetric-start check's offset (:func:`bifilar.analysis.symmetry_check.offset_start`)."""
    Wi = np.zeros((6, 6))  # the inverse of the kinetic-energy metric of [v, w_world]: 1/m, R I^-1 R^T
    Wi[:3, :3] = np.eye(3) / scene.mass
    Wi[3:, 3:] = R @ np.linalg.inv(np.asarray(scene.inertia, float)) @ R.T
    S = G @ Wi @ G.T
    return u - Wi @ G.T @ np.linalg.lstsq(S, G @ u, rcond=None)[0]
