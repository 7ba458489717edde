"""Nonlinear simulation from a displaced rest pose, with its own health report.

The motion is integrated with :func:`scipy.integrate.solve_ivp` (tolerances
explicit) on the maximal-coordinate model :mod:`bifilar.models.maximal`.
Positions are integrated relative to the rest CoM so that the relative
tolerance applies to the oscillation, not to the distance from the ceiling.

The result reports what an experimenter would measure (the period from
successive crossings of the rest value of the dominant coordinate) beside
the linear period, and the health of the run: constraint violation, energy
drift, minimum wire tension (a slack wire is reported with the time it goes
slack), and the lowest point of the body.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from .. import integrators as itg
from ..errors import IntegrationError, InputError
from ..models import maximal as mx
from ..rotations import quat_multiply, quat_to_rotvec
from ..rowwise import column_extremes
from ..scene import Scene, lowest_point_z
from .clearance import run_clearance
from .equilibrium import RestPose, rest_pose
from .modes import COMPONENTS, Mode, ModeSet, linear_modes
from .run_accuracy import (  # noqa: F401 (the names callers import from here)
    _small_amplitude,
    _SMALL_WHY,
    _timing_stated,
    below_resolution,
    check_period,
    check_rtol,
    CHECK_RTOL_RATIO,
    crossing_period_error,
    crossing_rows,
    CROSSING_SHARE,
    drift_floor,
    DRIFT_FLOOR_ULPS,
    drift_period_error,
    drift_resolution,
    IRREGULAR_FACTOR,
    IRREGULAR_SPREAD,
    MAX_SAMPLES_PER_PERIOD,
    MIN_RTOL,
    MIN_TIMED_ANGLE,
    needs_check,
    needs_period_check,
    period_accuracy,
    PERIOD_ERROR_FLOOR,
    PERIOD_ERROR_PER_RTOL,
    PERIOD_ERROR_PER_RTOL_KANE,
    PERIOD_ERROR_WARN,
    period_warn_threshold,
    SAMPLES_STEP,
    small_amplitude_period,
    TIMING_SHARE,
    untimed,
)
from .elastic_rest import dynamic_stretch_warning, loaded_scene
from .start_pose import refusal
from .start_states import (checked_start_poses, initial_state, multi_mode_state,  # noqa: F401 (re-exported)
                           reachable_amplitude, two_mode_state)


@dataclass
class RunSummary:
    """What every nonlinear run reports, single or batched (SI units, world frame).

    period : mean measured period, s (None if fewer than two crossings);
        period_std : std of single-cycle periods, s (None from one cycle); crossings : times, s.
    linear_period : the mode's linear period, s.
    max_constraint_violation : max | |d_i| - L_i | at the solver steps, m.
    energy_drift : max |E - E0| / |E0 - E_rest| over the solver's steps and
        the reported samples (dense output: its interpolation error included);
        nan when the release has no oscillation energy to speak of (:func:`untimed`).
    tension_min, tension_max : (n,) N.  slack : list of (wire 1-based, t).
    lowest_z_min : lowest world z reached by the body, m; depth_max the
        corresponding depth below the ceiling, m.
    mode, amplitude, coordinate_name : what was excited and what was timed.
    rtol, nfev, runtime : integrator tolerance, right-hand-side evaluations, s.
    """

    period: float | None
    period_std: float | None
    crossings: np.ndarray
    linear_period: float | None
    max_constraint_violation: float
    energy_drift: float
    tension_min: np.ndarray
    tension_max: np.ndarray
    slack: list
    lowest_z_min: float
    depth_max: float
    mode: str | None
    amplitude: float
    coordinate_name: str
    rtol: float
    nfev: int
    runtime: float


@dataclass
class SimulationResult(RunSummary):
    """Outcome of one nonlinear run: the :class:`RunSummary` fields plus

    t, y : dense samples (k,), (k, 13) of the state (positions absolute).
    coordinate : (k,) the timed coordinate (dominant component of the mode
        shape, relative to rest; m or rad); None from ``simulate(...,
        coordinate=False)``.
    tensions : (k, n) N at the samples.
    """

    t: np.ndarray
    y: np.ndarray
    coordinate: np.ndarray
    tensions: np.ndarray
    model: str
    method: str
    atol: float
    warnings: list = field(default_factory=list)
    energy_drift_resolution: float = float("nan")
    """Smallest relative energy drift the run can tell from rounding (:func:`drift_resolution`;
    nan where the drift is undefined)."""
    period_error: float = float("nan")
    """Bound on the numerical error of :attr:`period`, s (:func:`period_accuracy`; nan without a period;
    where the motion is not clean, at least the difference from a check run, :func:`check_period`)."""
    period_error_crossings: float = 0.0
    """The part of :attr:`period_error` that locating the crossings between samples adds, s
    (:func:`crossing_period_error`; the ``auto`` engine's runs only, 0 for the others, whose
    crossings are roots of the integrator's own continuous solution; NaN where it could not be estimated,
    and then :attr:`period_error` is NaN too, not established)."""
    clearance: dict | None = None
    """The ceiling and crossing-wire checks over the run's samples
    (:func:`~bifilar.analysis.clearance.run_clearance`): ``highest_point_z``,
    ``height_below_ceiling_min``, ``min_wire_distance`` (m) and
    ``min_wire_distance_wires`` (1-based)."""
    period_check: dict | None = None
    """The check run of a motion that is not clean (:func:`check_period`): ``method``, ``rtol``, its
    ``period`` (s), the ``difference`` from :attr:`period` (s) and the error model's ``model_bound`` (s);
    None where the single-cycle periods did not call for one."""
    period_symmetry: dict | None = None
    """A start on a symmetric subspace of a symmetric rig
    (:func:`~bifilar.analysis.symmetry_check.check_symmetric_start`): ``symmetry``, the Floquet
    ``multiplier`` across the subspace and its ``growth`` over the run, and the ``check`` run's
    ``offset``, ``period`` (s), ``difference`` (s), ``reproducible_cycles`` and ``error`` (s) where the
    growth called for one (else None); None where the start is not symmetric or not checked."""
    period_error_symmetry: float = 0.0
    """The part of :attr:`period_error` an unstable symmetric orbit's dependence on its start sets, s
    (:attr:`period_symmetry`; 0 where none): period_error is at least this."""

    @property
    def energy_drift_below_resolution(self) -> bool | None:
        """True when :attr:`energy_drift` is no larger than the rounding floor of the energy
        bookkeeping (a number that is not drift); None where either is undefined."""
        return below_resolution(self.energy_drift, self.energy_drift_resolution)

    def to_json(self) -> dict:
        doc = run_json(self, {"method": self.method, "rtol": self.rtol, "atol": self.atol, "nfev": int(self.nfev),
                              "runtime_s": float(self.runtime)})
        doc.update(health_json(self))
        doc["period_check"] = None if self.period_check is None else dict(self.period_check)
        doc["period_symmetry"] = None if self.period_symmetry is None else dict(self.period_symmetry)
        return doc


def health_json(r) -> dict:
    """The health keys a run adds to interface.md's (JSON null where undefined):
    ``energy_drift_resolution``, ``energy_drift_below_resolution``, ``period_error``
    (s), ``period_error_drift`` (s, the energy drift's part of it) and, for a
    :class:`SimulationResult`, ``period_error_crossings`` (s, the crossings' interpolation part), from a run
    with the fields of :class:`~bifilar.analysis.batch.SceneRun` (or a :class:`SimulationResult`)."""
    def f(x):
        return float(x) if x is not None and np.isfinite(x) else None

    perr = f(r.period_error)
    doc = {"energy_drift_resolution": f(r.energy_drift_resolution),
           "energy_drift_below_resolution": below_resolution(r.energy_drift, r.energy_drift_resolution),
           "period_error": perr,
           "period_error_drift": None if perr is None else drift_period_error(r.period, r.linear_period,
                                                                               r.energy_drift)}
    if hasattr(r, "period_error_crossings"):  # a SimulationResult (the batch's runs do not estimate it)
        doc["period_error_crossings"] = None if perr is None else f(r.period_error_crossings)
        doc["period_error_symmetry"] = None if perr is None else f(r.period_error_symmetry)
    if getattr(r, "clearance", None) is not None:  # a SimulationResult's checks along the run
        doc.update(r.clearance)
    return doc


def run_json(r, integrator: dict) -> dict:
    """The ``simulate --json`` document of interface.md (plus extras) from any
    run result with the fields of :class:`SimulationResult`."""

    def f(x):
        return None if x is None or (isinstance(x, float) and not np.isfinite(x)) else float(x)

    return {
        "period": f(r.period),
        "linear_period": f(r.linear_period),
        "max_constraint_violation": f(r.max_constraint_violation),
        "energy_drift": f(r.energy_drift),
        "tension": {"min": [float(v) for v in r.tension_min], "max": [float(v) for v in r.tension_max]},
        "period_std": f(r.period_std),
        "cycles": max(len(r.crossings) - 1, 0),
        "mode": r.mode,
        "amplitude": r.amplitude,
        "timed_coordinate": r.coordinate_name,
        "slack": [{"wire": w, "t": float(t)} for w, t in r.slack],
        "lowest_point_z": f(r.lowest_z_min),
        "depth_below_ceiling": f(r.depth_max),
        "model": r.model,
        "integrator": integrator,
        "warnings": list(r.warnings),
    }


def relative_pose(y: np.ndarray, rest: RestPose, component: int | None = None) -> np.ndarray:
    """(k, 6) [dx, dy, dz, rx, ry, rz]: CoM displacement and world rotation
    vector of R R_rest^T, for states y (k, 13); ``component`` (0-5): only
    that column (k,), the same values, without computing the other kind."""
    if component is not None and component < 3:
        return y[:, component] - rest.com[component]
    q0inv = rest.q * np.array([1, -1, -1, -1])
    dq = quat_multiply(y[:, 3:7], q0inv)
    if component is not None:
        return quat_to_rotvec(dq)[:, component - 3]
    return np.concatenate([y[:, 0:3] - rest.com, quat_to_rotvec(dq)], axis=1)


def crossings(t: np.ndarray, c: np.ndarray, fine) -> np.ndarray:
    """Times of upward zero crossings of a sampled coordinate, refined with
    Brent's method on the continuous interpolant ``fine(t) -> c``."""
    s = np.sign(c)
    idx = np.where((s[:-1] < 0) & (s[1:] >= 0))[0]
    out = []
    for i in idx:
        a, b = t[i], t[i + 1]
        if c[i + 1] == 0:
            out.append(b)
            continue
        out.append(brentq(fine, a, b, xtol=1e-14, rtol=1e-15, maxiter=200))
    return np.asarray(out)


def timed_crossings(tc: np.ndarray, amplitude: float | None, dominant: int = 3, Lmax: float = 1.0) -> np.ndarray:
    """The crossing times ``tc`` (s) a run times: none at amplitude 0 (a body
    released at rest stays there, and the sign changes of its coordinate are
    rounding: they gave a 'period' 44 % off the linear one with exit status
    0), none at an amplitude too small to time (:data:`MIN_TIMED_ANGLE`)."""
    if untimed(amplitude, dominant, Lmax):
        return np.zeros(0)
    return np.asarray(tc)


def measured_period(tc: np.ndarray) -> tuple[float | None, float | None]:
    """Mean period and single-cycle std (s) from successive upward crossing times
    (s); the std is None from a single cycle (no spread to measure, not zero)."""
    if len(tc) < 2:
        return None, None
    tc = np.asarray(tc)
    per = tc[1:] - tc[:-1]  # np.diff's subtraction
    return float((tc[-1] - tc[0]) / (len(tc) - 1)), float(sample_std(per)) if len(per) > 1 else None


def sample_std(a: np.ndarray) -> np.ndarray:
    """``a.std(ddof=1)`` of a 1-D array (its units) by the ufunc calls numpy's
    ``_var`` makes (the mean by ``add.reduce`` over the count, the squared
    deviations, their ``add.reduce`` over count - 1, ``sqrt``): the same
    bits for ~6 us instead of ~14 (a sweep point times 9 runs;
    tests/test_perf26a.py)."""
    n = a.shape[0]
    x = a - np.add.reduce(a, keepdims=True) / n
    x = np.multiply(x, x, out=x)
    return np.sqrt(np.add.reduce(x) / (n - 1))


def state_scale(amplitude, dominant, Lmax, omega) -> np.ndarray:
    """Size of each of the 13 state components' oscillation, (13,) or (13, B):
    the tolerance scale of a run (``atol = rtol x scale``).

    ``amplitude`` is in the mode's dominant coordinate: rad when ``dominant``
    (index into dx dy dz rx ry rz) is a rotation, m when it is a translation,
    where it is first turned into the wire angle ``amplitude / Lmax`` (rad);
    ``Lmax`` the longest wire (m), ``omega`` the mode's angular frequency
    (rad/s).  Rows: CoM position (m, angle x Lmax), quaternion (angle), CoM
    velocity (m/s), angular velocity (rad/s).  A swing's metres taken as
    radians made the position tolerance Lmax times too loose: the period of
    a 0.05 m swing on 500 m wires came out 2e-8 wrong at rtol 1e-10."""
    amp = np.maximum(np.abs(np.asarray(amplitude, float)), 1e-6)
    ang = np.where(np.asarray(dominant) >= 3, amp, amp / Lmax)
    return np.stack([ang * Lmax] * 3 + [ang] * 4 + [ang * omega * Lmax] * 3 + [ang * omega] * 3)


def simulate(
    scene: Scene,
    mode: str | int = 1,
    amplitude: float = 0.05,
    periods: float = 10.0,
    *,
    rest: RestPose | None = None,
    modes: ModeSet | None = None,
    y0: np.ndarray | None = None,
    t_end: float | None = None,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float | None = None,
    samples_per_period: int = 64,
    on_slack: str = "continue",
    progress=None,
    max_evaluations: float = 1e6,
    timing: float | None = None,
    check: bool = True,
    coordinate: bool = True,
    bound: bool = False,
) -> SimulationResult:
    """Integrate the nonlinear motion started from ``amplitude`` x a mode shape.

    Parameters
    ----------
    mode : label or 1-based index of the mode (see :func:`linear_modes`).
    amplitude : scale of the normalised mode shape (rad for rotation-dominated
        modes, m for translation-dominated ones).
    periods : number of linear periods of that mode to integrate.
    y0, t_end : start from an explicit state (13,) instead, for ``t_end`` s.
    method, rtol, atol : passed to :func:`scipy.integrate.solve_ivp`; ``atol``
        defaults to ``rtol`` times the amplitude-scaled size of each state
        component.  ``method="auto"`` (the CLI's default): LSODA
        (``scipy.integrate.odeint``, the step loop in Fortran) on the compiled
        right-hand side through the batched engine's one-scene path
        (:func:`bifilar.analysis.batch.run_one`): crossings on the samples
        (degree-7 interpolation), health at the samples; the cheapest method
        reaching a given period error in the work-precision tables
        (docs/performance.md: at rtol 1e-10 a period error ~2e-11, about a
        fifth of the cost of solve_ivp's DOP853).  With an explicit ``y0``
        ``auto`` means DOP853, and so it does for a stiff body (modes spanning
        over :data:`STIFF_RATIO` in period), whose cost is probed and bounded.
    on_slack : ``continue`` (report and go on with the bilateral model) or
        ``stop`` (end the run when a wire goes slack).
    progress : optional callable ``progress(t, t_end)`` called as the
        integration advances (for progress bars).
    max_evaluations : budget of right-hand-side evaluations of a stiff
        body's run (modes spanning over :data:`STIFF_RATIO` in period): a run
        projected beyond it is refused before integrating
        (:func:`_stiffness_check`), and one that exceeds it is stopped
        (:func:`_with_budget`), both with :class:`InputError` on ``--periods``.
    bound : bound every run of the DOP853 path by ``max_evaluations``, not only a
        stiff body's (``invert``'s amplitude runs: a body near a vanishing
        principal moment can make the constrained equations stiff while its
        linear modes span little in period, docs/design.md "Estimation audit,
        session 13").
    timing : the standard uncertainty of one measured period the user can reach,
        s (the config's ``uncertainty.timing``; None: not stated): the run warns
        where its period's numerical error exceeds a tenth of it
        (:func:`period_accuracy`).
    check : where the single-cycle periods spread by more than
        :data:`IRREGULAR_SPREAD` of the period, run again from the same start
        at a tighter tolerance and take the difference into ``period_error``
        (:func:`check_period`); where the start lies on a symmetric subspace
        of a symmetric rig and an offset from it would grow over the run,
        run again from a start 1e-12 off it and take that difference in too
        (:func:`~bifilar.analysis.symmetry_check.check_symmetric_start`;
        False: the error model alone, one run).
    coordinate : False: ``method="auto"``'s result leaves out the timed
        coordinate at the samples (:attr:`SimulationResult.coordinate` None;
        every other field the same, bit for bit), for a caller that reads
        only the summary figures (``bifilar simulate`` without ``--plot``):
        it is then computed only where the crossings' check reads it
        (:func:`~bifilar.analysis.run_accuracy.crossing_rows`), ~1.5 % of a
        run (docs/performance.md, session 13).  Other methods compute it
        anyway.
    """
    if check and rest is None:  # (the symmetric-start check reads them too: solved once for both)
        rest = rest_pose(scene)
    if check and modes is None:
        modes = linear_modes(scene, rest)
    kw = dict(rest=rest, modes=modes, y0=y0, t_end=t_end, method=method, rtol=rtol, atol=atol,
              samples_per_period=samples_per_period, on_slack=on_slack, max_evaluations=max_evaluations,
              timing=timing, coordinate=coordinate, bound=bound)
    res = _simulate_once(scene, mode, amplitude, periods, progress=progress, **kw)
    if check and needs_period_check(res):

        def again(method2: str, rtol2: float, atol2) -> SimulationResult:
            return _simulate_once(scene, mode, amplitude, periods, progress=None,
                                  **{**kw, "method": method2, "rtol": rtol2, "atol": atol2})

        check_period(res, again, method, atol, timing)
    if check:  # a start on a symmetric subspace, whose unstable orbit the run itself cannot show
        from .symmetry_check import check_symmetric_start

        check_symmetric_start(res, loaded_scene(scene, rest), mode, amplitude, periods, kw)
    if scene.stiffness is not None:  # the stretch's change with the swing, which the run leaves out
        w = dynamic_stretch_warning(scene, rest or rest_pose(scene), res.period, res.linear_period, res.period_error)
        if w is not None:
            res.warnings.append(w)
    return res


def _simulate_once(scene: Scene, mode, amplitude: float, periods: float, *, rest, modes, y0, t_end, method: str,
                   rtol: float, atol, samples_per_period: int, on_slack: str, progress, max_evaluations: float,
                   timing: float | None, coordinate: bool = True, bound: bool = False,
                   timed: int | None = None) -> SimulationResult:
    """One run of :func:`simulate` (its arguments), without the check of an irregular motion; ``timed``
    (0-5, dx dy dz rx ry rz) the coordinate an explicit start without a mode times (None: the one that
    moves most, :func:`summarise_run`)."""
    if on_slack not in ("continue", "stop"):
        raise InputError("--on-slack", "must be 'continue' or 'stop'")
    check_rtol(rtol)
    rest = rest or rest_pose(scene)
    modes = modes or linear_modes(scene, rest)
    scene = loaded_scene(scene, rest)  # stated stiffness: the run's wires are the loaded ones
    warnings: list[str] = []
    m = modes.get(mode) if y0 is None else (modes.get(mode) if mode is not None else None)
    if method == "auto" and y0 is not None:
        method = "DOP853"
    if method == "auto" and _period_ratio(modes) > STIFF_RATIO:
        # a stiff body: the DOP853 path, whose cost is probed and bounded
        # (_stiffness_check); LSODA needed 3x its evaluations on a thin rod
        method = "DOP853"
    if y0 is None:
        if m.period is None:
            raise InputError("--mode", f"mode '{m.label}' has no restoring stiffness (no period); pick another")
        if method == "auto":
            return _simulate_engine(scene, rest, m, amplitude, periods, rtol, atol, samples_per_period, on_slack,
                                    progress, timing, coordinate)
        y0 = initial_state(scene, rest, m, amplitude)
    T_ref = (m.period if m is not None else None) or min((x.period for x in modes.modes if x.period), default=1.0)
    if t_end is None:
        t_end = periods * T_ref
    P = mx.params_from_scenes(scene)
    # integrate relative to the rest CoM (origin shift of the anchors)
    Pshift = mx.RigParams(**{**P.__dict__, "anchors": P.anchors - rest.com})
    ys0 = y0.copy()
    ys0[0:3] -= rest.com
    omega = 2 * np.pi / T_ref
    Lmax = float(np.max(scene.lengths))
    if m is not None and np.isfinite(amplitude) and amplitude != 0:
        scale = state_scale(amplitude, m.dominant, Lmax, omega)
    else:  # explicit start: scale the tolerances by its displacement from rest (as an angle)
        disp = relative_pose(y0[None, :], rest)[0]
        scale = state_scale(max(float(np.max(np.abs(disp[3:]))), float(np.max(np.abs(disp[:3]))) / Lmax), 3, Lmax,
                            omega)
    if atol is None:
        atol_v = rtol * scale
    else:
        atol_v = atol
    f = mx.make_flat_rhs(Pshift)
    stiff = _stiffness_check(f, modes, ys0, t_end, method, rtol, atol_v, max_evaluations)
    if stiff:
        warnings.append(stiff)
    if stiff or bound:
        f = _with_budget(f, t_end, max_evaluations)
    if progress is not None:
        f = itg.with_progress(f, t_end, progress)
    events = None
    if on_slack == "stop":
        def slack_event(t, y):
            return float(np.min(mx.tensions(y, Pshift)))
        slack_event.terminal = True
        slack_event.direction = -1
        events = [slack_event]
    if on_slack == "stop":
        T0 = mx.tensions(ys0, Pshift)
        if float(np.min(T0)) <= 0.0:  # a wire is already slack at the release: nothing physical to integrate
            Y0 = y0[None, :].copy()
            warnings.append("run stopped at t = 0 s because a wire went slack")
            viol0 = float(np.max(mx.constraint_violation(Y0, P)))
            return summarise_run(scene, rest, m, amplitude, np.zeros(1), Y0, T0[None, :], lambda tt: Y0, viol0, 0.0,
                                 "maximal", method, rtol, float(np.min(atol_v)), 0, 0.0, warnings, timing=timing)
    t0 = time.perf_counter()
    sol = solve_ivp(f, (0.0, t_end), ys0, method=method, rtol=rtol, atol=atol_v, dense_output=True, events=events)
    runtime = time.perf_counter() - t0
    if sol.status == -1:
        raise IntegrationError(f"integrator {method} failed: {sol.message}")
    t_stop = sol.t[-1]
    # health at the solver's own steps (no interpolation error)
    Ys = sol.y.T.copy()
    Ys[:, 0:3] += rest.com
    cv = mx.constraint_violation(Ys, P).max(axis=1)
    viol = float(np.max(cv))
    E = mx.energy(Ys, P)
    E_rest = scene.mass * scene.gravity * rest.com[2]
    denom = abs(E[0] - E_rest)
    # relative to the oscillation's energy: undefined (nan, JSON null) for a body released at rest
    drift = float(np.max(np.abs(E - E[0])) / denom) if denom > 0 else float("nan")
    # dense samples for crossings, tensions, clearance
    k = max(int(samples_per_period * t_stop / T_ref), 200)
    ts = np.linspace(0.0, t_stop, k + 1)
    Y = sol.sol(ts).T
    Y[:, 0:3] += rest.com

    def state_at(tt: float) -> np.ndarray:
        yy = sol.sol(tt)[None, :].copy()
        yy[:, 0:3] += rest.com
        return yy

    # and at the samples: what the run reports (t, y, tensions, crossings) comes from the dense output, whose
    # interpolation error in the energy is 10-20x the drift at the steps with DOP853
    if denom > 0:
        drift = max(drift, float(np.max(np.abs(mx.energy(Y, P) - E[0])) / denom))
    T = mx.tensions(Y, P)
    stopped_slack = None
    if sol.status == 1:
        warnings.append(f"run stopped at t = {t_stop:.4g} s because a wire went slack")
        # the event stops where the tension reaches zero, which the samples there show as +0 or a hair above
        stopped_slack = (int(np.argmin(mx.tensions(sol.y[:, -1], Pshift))) + 1, float(t_stop))
    return summarise_run(scene, rest, m, amplitude, ts, Y, T, state_at, viol, drift, "maximal", method, rtol,
                         float(np.min(atol_v)), int(sol.nfev), runtime, warnings, stopped_slack, timing=timing,
                         viol_at=Ys[int(np.argmax(cv))], timed=timed)


STIFF_RATIO = 1e3
"""Ratio of the slowest to the fastest linear period above which a run is
probed for its cost before integrating (a body with a tiny principal moment,
e.g. a thin rod, has a mode tens of thousands of times faster than the
swing it is timed on, and an explicit method's steps follow the fast one)."""
PROBE_FRACTION = 0.01
"""Share of the run integrated by the cost probe."""


def _period_ratio(modes: ModeSet) -> float:
    """Slowest over fastest linear period of ``modes`` (1 with fewer than two periods)."""
    periods = [m.period for m in modes.modes if m.period]
    return max(periods) / min(periods) if len(periods) >= 2 else 1.0


def _stiffness_check(f, modes: ModeSet, y0: np.ndarray, t_end: float, method: str, rtol: float, atol,
                     max_evaluations: float) -> str | None:
    """Estimate the cost of a run whose modes span more than :data:`STIFF_RATIO`
    in period, by integrating its first :data:`PROBE_FRACTION` (same method
    and tolerances) and extrapolating the right-hand-side evaluations.

    Returns a warning with the estimate (None for a run that is not stiff);
    raises :class:`InputError` naming ``--periods`` when the estimate already
    exceeds ``max_evaluations`` (the probe costs 1 % of the run, so the
    refusal comes quickly).  The rate tends to grow during the run as the
    fast mode gets excited (a thin rod: 4x), so the run itself is also
    bounded (:func:`_with_budget`).  A stiff method chosen automatically was
    measured and rejected: on a thin rod (principal moments [1e-9, 1, 1])
    LSODA needed 3x and Radau 90x the evaluations of DOP853 at the default
    rtol = 1e-10, the fast mode being hardly excited.
    """
    if _period_ratio(modes) <= STIFF_RATIO:
        return None
    periods = [m.period for m in modes.modes if m.period]
    t_probe = PROBE_FRACTION * t_end
    probe = solve_ivp(f, (0.0, t_probe), y0, method=method, rtol=rtol, atol=atol)
    est = probe.nfev / PROBE_FRACTION
    msg = (f"stiff body: its fastest mode has a period of {min(periods):.3g} s against {max(periods):.3g} s "
           f"(ratio {max(periods) / min(periods):.3g}); the {method} run needs about {est:.2g} evaluations of the "
           f"equations at the rate of its first {PROBE_FRACTION:.0%}")
    if est > max_evaluations:
        raise InputError("--periods", f"{msg}, more than the budget of {max_evaluations:.2g}; integrate at most "
                                      f"{max_evaluations / est:.2g} of this length (fewer periods), or check the "
                                      "inertia (a principal moment much smaller than the others)")
    return msg


def _with_budget(f, t_end: float, max_evaluations: float):
    """``f`` that raises :class:`InputError` naming ``--periods`` once it has
    been evaluated ``max_evaluations`` times, with the time reached and the
    extrapolated cost of the whole run."""
    n = [0]

    def g(t, y):
        n[0] += 1
        if n[0] > max_evaluations:
            need = n[0] * t_end / max(t, 1e-300)
            raise InputError("--periods", f"stiff body: after {n[0] - 1:.3g} evaluations of the equations the run "
                                          f"reached t = {t:.4g} s of {t_end:.4g} s (it would need about {need:.2g}); "
                                          f"integrate at most {t / t_end:.2g} of this length (fewer periods), or "
                                          "check the inertia (a principal moment much smaller than the others)")
        return f(t, y)

    return g


def _simulate_engine(scene: Scene, rest: RestPose, m: Mode, amplitude: float, periods: float, rtol: float, atol,
                     samples_per_period: int, on_slack: str, progress, timing: float | None = None,
                     coordinate: bool = True) -> SimulationResult:
    """``simulate(method="auto")``: the batched engine's one-scene LSODA path,
    its samples turned into a :class:`SimulationResult` (tensions and, with
    ``coordinate``, the timed coordinate at the samples; period, crossings
    and health from the run)."""
    from .batch import run_one

    initial_state(scene, rest, m, amplitude)  # the input checks (InputError for an amplitude no pose can take)
    t_end = periods * m.period
    prog = None if progress is None else (lambda done, total: progress(done / total * t_end, t_end))
    Lmax = float(np.max(scene.lengths))
    t0 = time.perf_counter()
    spp = int(samples_per_period)
    while True:
        run = run_one(scene, rest, m, amplitude, periods, rtol, atol, samples_per_period=spp,
                      method="lsoda", on_slack=on_slack, progress=prog)
        failed = [w for w in run.warnings if w.startswith("integration failed")]
        if failed:
            reason = failed[0].split(": ", 1)[-1]  # "LSODA: <why>"
            raise IntegrationError("integrator " + reason.replace(": ", " failed: ", 1))
        if coordinate:
            c = relative_pose(run.y, rest, m.dominant)
        else:  # only the rows the crossings' check reads (each row's value is the same computed alone)
            c = np.full(len(run.y), np.nan)
            for rows in crossing_rows(run.t, run.crossings):
                c[rows] = relative_pose(run.y[rows], rest, m.dominant)
        model_err, _ = period_accuracy(run.period, "auto", rtol, amplitude, m.dominant, Lmax,
                                       linear_period=m.period, drift=run.energy_drift)
        # the crossings lie between samples: a motion with fast harmonics (a large swing of a double
        # pendulum) can put them off by more than the integration (session 12: 1e-7 s at 64 per period)
        cross = (0.0 if run.period is None or untimed(amplitude, m.dominant, Lmax)
                 or small_amplitude_period(amplitude, m.dominant, Lmax, m.period) is not None
                 else crossing_period_error(run.t, c, run.crossings))
        # NaN (the estimate failed: too few samples) is taken again too; still NaN, the error is not established
        if (np.isfinite(cross) and not cross > CROSSING_SHARE * model_err) or spp * SAMPLES_STEP > MAX_SAMPLES_PER_PERIOD:
            break
        spp *= SAMPLES_STEP
    runtime = time.perf_counter() - t0
    # the tensions at the samples: computed with the run's health (the same kernel pass) where it kept them
    T = run.tensions if run.tensions is not None else mx.tensions(run.y, mx.params_from_scenes(scene))
    scale = state_scale(amplitude, m.dominant, Lmax, 2 * np.pi / m.period)
    atol_min = float(np.min(atol)) if atol is not None else rtol * float(np.min(scale))
    perr, w = period_accuracy(run.period, "auto", rtol, amplitude, m.dominant, Lmax,
                              timing=timing, linear_period=m.period, drift=run.energy_drift,
                              crossing=cross)
    clear, clear_w = run_clearance(scene, rest, run.t, run.y)
    Tlo, Thi = column_extremes(T)  # (T.min(axis=0), T.max(axis=0), by columns: bifilar/rowwise.py)
    warnings = list(run.warnings) + ([w] if w else []) + clear_w
    return SimulationResult(
        t=run.t, y=run.y, coordinate=c if coordinate else None, coordinate_name=run.coordinate_name, tensions=T,
        period=run.period, period_std=run.period_std, crossings=run.crossings, linear_period=m.period,
        max_constraint_violation=run.max_constraint_violation, energy_drift=run.energy_drift,
        tension_min=np.minimum(run.tension_min, Tlo), tension_max=np.maximum(run.tension_max, Thi),
        slack=run.slack, lowest_z_min=run.lowest_z_min, depth_max=run.depth_max, mode=m.label,
        amplitude=float(amplitude), model="maximal", method=run.method, rtol=float(rtol), atol=atol_min,
        nfev=int(run.nfev), runtime=runtime, warnings=warnings,
        energy_drift_resolution=drift_resolution(scene, rest, run.y[0]) if np.isfinite(run.energy_drift) else np.nan,
        period_error=perr, period_error_crossings=cross if run.period is not None else 0.0, clearance=clear,
    )


def no_period_warning(amplitude: float | None, stopped: bool) -> str:
    """Why a run measured no period (fewer than two upward crossings):
    ``amplitude`` of the mode (None for an explicit start state), ``stopped``
    whether the run ended early (a wire went slack with ``on_slack="stop"``)."""
    if amplitude is not None and amplitude == 0:
        return ("amplitude 0: the body starts at rest and stays there; there is no oscillation to time "
                "(give a nonzero --amplitude)")
    if stopped:
        return "fewer than two crossings of the rest value before the run stopped: no period measured"
    return "fewer than two crossings of the rest value: no period measured; integrate longer"


def violation_warning(scene: Scene, Y: np.ndarray, viol: float) -> str:
    """The warning for a run whose wires' lengths erred by ``viol`` (m, above
    1e-6 of the longest; measured at its steps): an integration error
    (tighten rtol), or, where the wires are nearly dependent and all but
    1e-6 of it lies in the lengths the model leaves free there
    (:func:`~bifilar.analysis.wire_statics.held_violation`), what a real
    rig's stretch takes up.  ``Y`` (k, 13): the run's states to look at (the
    state of its largest error, and its samples or its last state); the
    error is attributed only when they show at least half of ``viol``."""
    Lmax = float(np.max(scene.lengths))
    if scene.n_wires >= 4:
        from .wire_statics import held_violation

        held = held_violation(scene, Y)
        seen = float(np.max(mx.constraint_violation(Y, mx.params_from_scenes(scene))))
        if held <= 1e-6 * Lmax and seen >= 0.5 * viol:
            return (f"constraint violation {viol:.2e} m, all but {held:.1e} m of it along the self-stress of wires "
                    "nearly dependent in the run, whose lengths the model leaves free there (a real rig's wires "
                    "stretch by as much): not an integration error, but the split of the tensions between those "
                    "wires then depends on their stiffness")
    return f"constraint violation {viol:.2e} m exceeds 1e-6 of the wire length; tighten rtol"


def summarise_run(scene: Scene, rest: RestPose, m: Mode | None, amplitude: float, ts: np.ndarray, Y: np.ndarray,
                  T: np.ndarray, state_at, viol: float, drift: float, model: str, method: str, rtol: float,
                  atol: float, nfev: int, runtime: float, warnings: list,
                  stopped_slack: tuple[int, float] | None = None, timing: float | None = None,
                  viol_at: np.ndarray | None = None, timed: int | None = None) -> SimulationResult:
    """Measured period, slack wires, clearance and health of a run, whatever the model.

    ts (k,) s and Y (k, 13) world-frame maximal states at dense samples; T (k, n)
    tensions, N; ``state_at(t) -> (1, 13)`` the continuous solution (for
    refining crossings); viol (m) and drift as measured by the caller.
    ``stopped_slack``: (wire, 1-based, and t, s) where an event stopped the run
    at a wire's zero tension (``on_slack="stop"``), reported as slack even
    when the samples there show the tension as a rounding above zero.
    ``timing``: the stated timing uncertainty, s (:func:`period_accuracy`).
    ``viol_at``: the state (13,) where ``viol`` was measured (the largest
    error, at a step the samples may miss), looked at with the samples by
    :func:`violation_warning`.  ``timed``: the coordinate (0-5) a run without a mode times (None: the
    one that moves most; a check run times the run's own).
    """
    rel = relative_pose(Y, rest)
    dom = m.dominant if m is not None else (timed if timed is not None else int(np.argmax(np.ptp(rel, axis=0))))
    c = rel[:, dom]

    def fine(tt: float) -> float:
        return float(relative_pose(state_at(tt), rest)[0, dom])

    Lmax = float(np.max(scene.lengths))
    tc = timed_crossings(crossings(ts, c, fine), amplitude if m is not None else None, dom, Lmax)
    period, pstd = measured_period(tc)
    small = small_amplitude_period(amplitude, dom, Lmax, m.period) if m is not None else None
    if small is not None:
        period = small[0]
        warnings.append(small[1])
    if m is not None and untimed(amplitude, dom, Lmax):
        drift = float("nan")
    slack = []
    for i in range(scene.n_wires):
        neg = np.where(T[:, i] <= 0)[0]
        if len(neg):
            slack.append((i + 1, float(ts[neg[0]])))
            warnings.append(f"WIRE {i + 1} GOES SLACK at t = {ts[neg[0]]:.4g} s (tension {T[:, i].min():.3g} N): "
                            "the motion after that is not physical; reduce the amplitude")
        elif stopped_slack is not None and stopped_slack[0] == i + 1:
            slack.append(stopped_slack)
            warnings.append(f"WIRE {i + 1} GOES SLACK at t = {stopped_slack[1]:.4g} s (its tension reaches 0 N "
                            "there): the motion after that is not physical; reduce the amplitude")
    lz = lowest_point_z(scene, Y[:, 0:3], mx.quat_to_matrix(Y[:, 3:7]))
    Tlo, Thi = column_extremes(T)
    clear, clear_w = run_clearance(scene, rest, ts, Y)
    warnings.extend(clear_w)
    if viol > 1e-6 * Lmax:
        warnings.append(violation_warning(scene, Y if viol_at is None else np.vstack([viol_at, Y]), viol))
    if period is None:
        stopped = any(w.startswith("run stopped at t = ") for w in warnings)
        warnings.append(no_period_warning(amplitude if m is not None else None, stopped))
    perr, w = period_accuracy(period, method, rtol, amplitude if m is not None else None, dom, Lmax, model, timing,
                              m.period if m is not None else None, drift)
    if w:
        warnings.append(w)
    return SimulationResult(
        t=ts, y=Y, coordinate=c, coordinate_name=COMPONENTS[dom], tensions=T,
        period=period, period_std=pstd, crossings=tc, linear_period=m.period if m is not None else None,
        max_constraint_violation=viol, energy_drift=drift,
        tension_min=Tlo, tension_max=Thi, slack=slack,
        lowest_z_min=float(lz.min()), depth_max=float(scene.ceiling_z - lz.min()),
        mode=m.label if m is not None else None, amplitude=float(amplitude), model=model, method=method,
        rtol=float(rtol), atol=float(atol), nfev=int(nfev), runtime=runtime, warnings=warnings,
        energy_drift_resolution=drift_resolution(scene, rest, Y[0]) if np.isfinite(drift) else np.nan,
        period_error=perr, clearance=clear,
    )

