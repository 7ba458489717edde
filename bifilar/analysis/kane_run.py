"""Running the thesis's Kane model (:mod:`bifilar.models.kane`) on a scene.

A scene qualifies when it has two wires whose anchors are at one height.
The mapping, exact and invertible:

* world <-> thesis frame: a rotation about z (and a shift) that puts anchor B
  (wire 1) at the origin and anchor A (wire 2) on +n2;
* body <-> ntilde frame: ntilde_3 = -(D - C)/|D - C| (C, D the attachments
  of wires 1 and 2), ntilde_1 along the CoM's offset from the line CD
  (the body's "down" when the CoM is on the line), ntilde_2 = ntilde_3 x ntilde_1;
  r and lambda from the CoM's position relative to C (5.1.14);
* the inertia tensor is rotated into the ntilde frame (full tensor kept).

Runs report in the world frame and the default model's vocabulary, so the
two formulations can be compared sample by sample.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import InputError, IntegrationError
from ..models import kane as kn
from ..models import maximal as mx
from ..rotations import matrix_to_quat, quat_to_matrix
from ..scene import Scene
from .elastic_rest import loaded_scene
from .equilibrium import RestPose
from .modes import ModeSet
from .simulate import check_period, check_rtol, initial_state, needs_period_check, summarise_run


@dataclass(frozen=True)
class KaneMap:
    """Scene <-> thesis coordinates.  Rz (3, 3): thesis frame -> world axes;
    origin: world position of anchor B; Q (3, 3): columns are ntilde_1..3 in
    body axes; p: the KaneParams (anchor B at the thesis origin)."""

    p: kn.KaneParams
    Rz: np.ndarray
    origin: np.ndarray
    Q: np.ndarray


def kane_map(scene: Scene) -> KaneMap:
    """Build the mapping; raises InputError when the scene is outside the thesis's model."""
    if scene.n_wires != 2:
        raise InputError("--model", f"the kane model needs exactly 2 wires, the scene has {scene.n_wires}")
    B, A = scene.anchors
    L = float(np.max(scene.lengths))
    if abs(A[2] - B[2]) > 1e-9 * L:
        raise InputError("--model", "the kane model needs both anchors at one height (rig.anchors z differ)")
    n2 = (A - B) / np.linalg.norm(A - B)
    n3 = np.array([0.0, 0.0, 1.0])
    n1 = np.cross(n2, n3)
    Rz = np.column_stack([n1, n2, n3])
    pC, pD = scene.attachments
    bp = float(np.linalg.norm(pD - pC))
    t3 = -(pD - pC) / bp
    off = -pC  # CoM relative to C, body axes
    perp = off - (off @ t3) * t3
    if np.linalg.norm(perp) > 1e-12 * max(bp, 1.0):
        t1 = perp / np.linalg.norm(perp)
    else:
        down = np.array([0.0, 0.0, -1.0]) - (-t3[2]) * t3
        if np.linalg.norm(down) < 1e-9:
            raise InputError("--model", "the attachment line is vertical in the body: outside the thesis's model")
        t1 = down / np.linalg.norm(down)
    t2 = np.cross(t3, t1)
    Q = np.column_stack([t1, t2, t3])
    r = float(np.linalg.norm(off))
    lam = float(np.arctan2(off @ t1, -(off @ t3))) if r > 0 else 0.0
    p = kn.KaneParams(b=float(np.linalg.norm(A - B)), b_prime=bp, l=float(scene.lengths[0]),
                      l_prime=float(scene.lengths[1]), mass=scene.mass, inertia=Q.T @ scene.inertia @ Q,
                      r=r, lam=lam, g=scene.gravity, anchor_B=(0.0, 0.0, 0.0))
    return KaneMap(p, Rz, B.copy(), Q)


def to_world(km: KaneMap, y: np.ndarray) -> np.ndarray:
    """Maximal states (k, 13) (world frame, body axes) of thesis states y (10,) or (10, k)."""
    y = np.asarray(y, float)
    Y = y[:, None] if y.ndim == 1 else y
    com, R = kn.pose(Y[:5], km.p)  # (3, k), (3, 3, k)
    v, w = kn.velocity(Y[:5], Y[5:], km.p)
    com = np.atleast_2d(com.T) if com.ndim > 1 else com[None, :]
    Rk = np.moveaxis(R, -1, 0) if R.ndim == 3 else R[None]
    v = v.T if v.ndim > 1 else v[None, :]
    w = w.T if w.ndim > 1 else w[None, :]
    Rw = np.einsum("ij,kjl,ml->kim", km.Rz, Rk, km.Q)  # Rz Rk Q^T : body -> world
    out = np.zeros((len(com), 13))
    out[:, 0:3] = com @ km.Rz.T + km.origin
    out[:, 3:7] = matrix_to_quat(Rw)
    out[:, 7:10] = v @ km.Rz.T
    out[:, 10:13] = np.einsum("kji,kj->ki", Rw, w @ km.Rz.T)  # body-axes angular velocity
    return out


def from_world(km: KaneMap, y13: np.ndarray) -> np.ndarray:
    """Thesis state (10,) of a maximal state (13,) (inverse of :func:`to_world`)."""
    com, q = y13[0:3], y13[3:7]
    R = quat_to_matrix(q)
    C = com + R @ (km.Q @ kn.attachment_points_body(km.p)[0])
    BC = km.Rz.T @ (C - km.origin)
    l, bp = km.p.l, km.p.b_prime
    th2 = float(np.arccos(np.clip(-BC[2] / l, -1, 1)))
    th3 = float(np.arctan2(BC[1], BC[0]))
    Rk = km.Rz.T @ R @ km.Q  # columns ntilde_i in thesis components
    CD = -bp * Rk[:, 2]
    th5 = float(np.arcsin(np.clip(CD[2] / bp, -1, 1)))
    th4 = float(np.arctan2(CD[0], CD[1]))
    th1 = float(np.arctan2(Rk[2, 1], -Rk[2, 0]))
    theta = np.array([th1, th2, th3, th4, th5])
    # rates: V thd = v and G thd = w (6 equations, 5 unknowns, consistent): least squares
    v = km.Rz.T @ y13[7:10]
    w = km.Rz.T @ (R @ y13[10:13])
    cols = []
    for j in range(5):
        e = np.zeros(5)
        e[j] = 1.0
        vj, wj = kn.velocity(theta, e, km.p)
        cols.append(np.concatenate([vj, wj]))
    thd = np.linalg.lstsq(np.column_stack(cols), np.concatenate([v, w]), rcond=None)[0]
    return np.concatenate([theta, thd])


def simulate_kane(scene: Scene, rest: RestPose, modes: ModeSet, *, mode=None, amplitude: float = 0.05,
                  periods: float = 10.0, theta=None, rtol: float = 1e-10, method: str = "DOP853",
                  samples_per_period: int = 64, progress=None, timing: float | None = None, check: bool = True):
    """Integrate the thesis's model; ``theta`` ("t1,t2,t3,t4" rad or a sequence)
    sets the initial angles (rates zero, theta5 from the constraint), otherwise
    the start is the same displaced rest as the default model's.  ``timing``
    (s): the stated timing uncertainty the period's error is held against
    (:func:`~bifilar.analysis.simulate.period_accuracy`).  ``check``: as
    :func:`~bifilar.analysis.simulate.simulate`'s, where the single-cycle
    periods spread by more than :data:`~bifilar.analysis.run_accuracy.IRREGULAR_SPREAD`
    of the period the same start is run again at rtol / 100
    (:func:`~bifilar.analysis.run_accuracy.check_period`: ``period_check``,
    ``period_error`` at least the difference, a warning for a motion that is
    not regular), and a start on a symmetric subspace of a symmetric rig is
    checked as the default model's is
    (:func:`~bifilar.analysis.symmetry_check.check_symmetric_start`, its
    check run on this model: ``period_symmetry``, ``period_error_symmetry``);
    False: the error model alone.

    Returns a :class:`~bifilar.analysis.simulate.SimulationResult` (world frame)
    with an extra attribute ``theta`` (k, 5).  Raises
    :class:`~bifilar.models.kane.KaneSingularityError` (exit 1) at vertical wires.
    """
    scene = loaded_scene(scene, rest)  # stated stiffness: the loaded wires
    km = kane_map(scene)
    check_rtol(rtol)
    rest_theta = from_world(km, mx.pack(rest.com, rest.q))
    if abs(np.sin(rest_theta[1])) < 1e-6:
        raise InputError("--model", "the thesis's kane coordinates are singular for this rig: wire 1 hangs "
                                    "vertically at rest (theta2 = 0); use --model maximal")
    m = None
    if theta is not None:
        if isinstance(theta, str):
            try:
                vals = [float(x) for x in theta.split(",")]
            except ValueError:
                raise InputError("--theta", f"must be 4 comma-separated angles in rad, got {theta!r}") from None
        else:
            vals = [float(x) for x in theta]
        if len(vals) != 4 or not all(np.isfinite(vals)):
            raise InputError("--theta", f"must be 4 finite angles theta1..theta4 in rad, got {theta!r}")
        y0 = kn.complete_initial_state(np.array(vals), np.zeros(4), km.p)
        if mode is not None:
            m = modes.get(mode)
    else:
        m = modes.pick(mode)
        if m.period is None:
            raise InputError("--mode", f"mode '{m.label}' has no restoring stiffness (no period); pick another")
        y0 = from_world(km, initial_state(scene, rest, m, amplitude))
        y0 = kn.complete_initial_state(y0[:4], y0[5:9], km.p, theta5_guess=y0[4])
    T_ref = (m.period if m is not None and m.period else None) or min(x.period for x in modes.modes if x.period)
    t_end = periods * T_ref
    amp = max(abs(amplitude), 1e-6) if theta is None else 0.1

    def once(method: str, rtol: float, atol, progress=None):
        return _integrate(scene, rest, km, m, y0, t_end, T_ref, amplitude if theta is None else float("nan"),
                          method, rtol, rtol * amp if atol is None else atol, samples_per_period, progress, timing)

    res = once(method, rtol, None, progress)
    if check and needs_period_check(res):
        check_period(res, once, method, None, timing)
    if check:  # a start on a symmetric subspace: the default model's check, on this model's runs
        from .symmetry_check import CHECK_EXTRA_PERIODS, check_symmetric_start, timed_index

        def rerun(y13: np.ndarray):
            yk = from_world(km, y13)
            yk = kn.complete_initial_state(yk[:4], yk[5:9], km.p, theta5_guess=yk[4])
            more = T_ref if m is not None else res.period  # (without a mode: two of the cycles it timed)
            return _integrate(scene, rest, km, m, yk, t_end + CHECK_EXTRA_PERIODS * more, T_ref,
                              amplitude if theta is None else float("nan"), method, rtol, rtol * amp,
                              samples_per_period, None, timing, timed_index(res))

        check_symmetric_start(res, scene, None if m is None else m.label,
                              amplitude if theta is None else float("nan"), periods, {"rest": rest, "modes": modes},
                              rerun=rerun)
    return res


def _integrate(scene: Scene, rest: RestPose, km: KaneMap, m, y0: np.ndarray, t_end: float, T_ref: float,
               amplitude: float, method: str, rtol: float, atol: float, samples_per_period: int, progress,
               timing: float | None, timed: int | None = None):
    """One run of :func:`simulate_kane` from the thesis state ``y0`` (10,) for
    ``t_end`` s (``T_ref`` the timed mode's period, s; ``m`` that mode or
    None), at ``rtol`` and ``atol`` (the angles' absolute tolerance, rad):
    a :class:`~bifilar.analysis.simulate.SimulationResult` in the world frame."""
    last = [-1.0]

    def f(t, y):
        if progress is not None and t - last[0] >= 0.005 * t_end:
            last[0] = t
            progress(t, t_end)
        return kn.rhs(t, y, km.p)

    t0 = time.perf_counter()
    sol = solve_ivp(f, (0.0, t_end), y0, method=method, rtol=rtol, atol=atol, dense_output=True)
    runtime = time.perf_counter() - t0
    if sol.status == -1:
        raise IntegrationError(f"integrator {method} failed on the kane model: {sol.message}")
    # health at the solver steps, in the thesis's own terms
    viol = float(np.max([abs(np.sqrt(kn.constraint(sol.y[:5, i], km.p) + km.p.l_prime**2) - km.p.l_prime)
                         for i in range(sol.y.shape[1])]))
    E = np.asarray(kn.energy(sol.y, km.p))
    z_rest = rest.com[2] - km.origin[2]
    denom = abs(E[0] - scene.mass * scene.gravity * z_rest)
    drift = float(np.max(np.abs(E - E[0])) / denom) if denom > 0 else 0.0
    k = max(int(samples_per_period * sol.t[-1] / T_ref), 200)
    ts = np.linspace(0.0, sol.t[-1], k + 1)
    th = sol.sol(ts)
    Y = to_world(km, th)
    T = np.array([kn.tensions(th[:, i], km.p)[:2] for i in range(th.shape[1])])
    res = summarise_run(scene, rest, m, amplitude, ts, Y, T, lambda tt: to_world(km, sol.sol(tt)), viol, drift,
                        "kane", method, rtol, atol, int(sol.nfev), runtime, [], timing=timing, timed=timed)
    res.theta = th.T
    return res
