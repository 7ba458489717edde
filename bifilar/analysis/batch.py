"""Batched engine: rest poses, linear modes and nonlinear runs of many scenes at once.

For sweeps, Monte Carlo draws and amplitude ladders.  Every stage is
vectorised over the scenes (numpy arrays with a leading scene axis) and
gives the results of the single-scene functions
(:func:`~bifilar.analysis.equilibrium.rest_pose`,
:func:`~bifilar.analysis.modes.linear_modes`,
:func:`~bifilar.analysis.simulate.simulate`) to rounding or to the
integration tolerance:

* :func:`rest_poses`, :func:`modes_batch`, :func:`rest_and_modes`: rest
  poses (Newton on the KKT equations, all scenes at once) and linear modes,
  in :mod:`bifilar.analysis.batch_rest`, re-exported here.
* :func:`initial_states`: the start poses
  (:mod:`bifilar.analysis.start_pose`, the solver ``simulate`` uses).
* :func:`simulate_batch`: the maximal-coordinate model
  (:mod:`bifilar.models.maximal`, compiled kernel) integrated from each
  scene's displaced rest pose, with per-scene health (constraint violation,
  energy drift, tensions, slack wires, lowest point) and the measured
  period (upward crossings of the dominant coordinate, as ``simulate``
  times them).  Two engines, chosen by measurement (docs/performance.md):
  LSODA (``scipy.integrate.odeint``: the step loop in Fortran) on one scene
  -- on Python floats, no array overhead -- or on the whole group stacked
  into one ODE in normalised time with tolerances divided by sqrt(B), so
  each scene keeps the error bound it would have alone
  (:mod:`bifilar.analysis.batch_lsoda`); and the project's
  DOP853 (:mod:`bifilar.integrators`) with a step size and error test of
  its own for every scene (crossings on its order-7 dense output), fastest
  for large groups (:mod:`bifilar.analysis.batch_dop853`).  This module
  checks the inputs, groups the scenes by wire count, solves their start
  poses, picks the engine, and builds each scene's :class:`SceneRun` from
  the health the engine gathered (:mod:`bifilar.analysis.batch_health`).

How to call it (sweeps, Monte Carlo, amplitude ladders)::

    from bifilar.analysis.batch import simulate_batch
    runs = simulate_batch(scenes, "torsion", 0.05, 10, rtol=1e-10, errors="return")
    for r in runs:  # input order
        r.period, r.linear_period, r.max_constraint_violation, r.energy_drift,
        r.tension_min, r.tension_max, r.depth_max, r.slack, r.error, r.to_json()

``mode``, ``amplitude`` and ``periods`` may be one value or one per scene;
``rests=``/``modes=`` reuse precomputed rest poses and mode sets
(:func:`rest_and_modes`); ``health=False`` skips everything but the period
(the health figures are then NaN).  Memory is bounded: groups above
:data:`CHUNK` scenes run in chunks, and the lowest point is a running
minimum (:mod:`bifilar.analysis.batch_health`).

Units SI, world frame z up, as everywhere in the package.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ..errors import InputError
from ..models import maximal as mx
from ..scene import Scene
from .batch_dop853 import _dop853, _health_at_dense_samples
from .batch_health import Health, LowestPoint, SharedLowestPoint
from .batch_lsoda import _BatchFailed, _lsoda, _lsoda_joint, _NotJoint
from .batch_rest import _groups, modes_batch, rest_and_modes, rest_poses  # noqa: F401  (re-exported)
from .elastic_rest import loaded_scenes
from .equilibrium import RestPose
from .modes import COMPONENTS, Mode, ModeSet
from .simulate import (RunSummary, drift_floor, measured_period, no_period_warning, period_accuracy,
                       small_amplitude_period, state_scale, timed_crossings, untimed, violation_warning)
from .start_pose import StartPoses, refusal, start_poses

__all__ = [
    "rest_poses", "modes_batch", "rest_and_modes", "initial_states", "simulate_batch", "SceneRun", "run_one",
]


# --------------------------------------------------------------------------
# initial states
# --------------------------------------------------------------------------
def _start_poses(scenes, rests, modes, amplitude) -> StartPoses:
    """:func:`~bifilar.analysis.start_pose.start_poses` per wire-count group, in input order."""
    scenes = list(scenes)
    amp = np.broadcast_to(np.asarray(amplitude, float), (len(scenes),))
    parts = [(ii, start_poses([scenes[k] for k in ii], [rests[k] for k in ii], [modes[k] for k in ii], amp[ii]))
             for ii in _groups(scenes)]
    if len(parts) == 1:
        return parts[0][1]
    out = StartPoses(**{f: np.zeros((len(scenes),) + getattr(parts[0][1], f).shape[1:], getattr(parts[0][1], f).dtype)
                        for f in StartPoses.__dataclass_fields__})
    for ii, sp in parts:
        for f in StartPoses.__dataclass_fields__:
            getattr(out, f)[ii] = getattr(sp, f)
    return out


def initial_states(scenes: Sequence[Scene], rests: Sequence[RestPose], modes: Sequence[Mode], amplitude) -> np.ndarray:
    """States (B, 13) at rest displaced by ``amplitude`` (scalar or (B,)) x
    each scene's mode shape, put back on the wires with the mode's dominant
    coordinate held at its displaced value, at rest (zero velocity):
    :func:`~bifilar.analysis.simulate.initial_state` for many (the same
    solver, :mod:`bifilar.analysis.start_pose`).  Raises :class:`InputError`
    (``--amplitude``) when no such pose exists."""
    sp = _start_poses(scenes, rests, modes, amplitude)
    bad = np.nonzero(~sp.feasible)[0]
    if len(bad):
        b = int(bad[0])
        raise refusal(scenes[b], modes[b], float(sp.amplitude[b]), float(sp.gap[b]),
                      f"scene {b + 1} ('{scenes[b].name}')", **sp.off_wires(b))
    return sp.states()


def feasible_amplitudes(scenes: Sequence[Scene], rests: Sequence[RestPose], modes: Sequence[Mode], amplitude
                        ) -> np.ndarray:
    """(B,) bool: whether each displaced start pose can be reached with every
    wire at its length (what :func:`initial_states` needs;
    :data:`~bifilar.analysis.start_pose.FEASIBLE_TOL`)."""
    return _start_poses(scenes, rests, modes, amplitude).feasible


# --------------------------------------------------------------------------
# nonlinear runs
# --------------------------------------------------------------------------
@dataclass
class SceneRun(RunSummary):
    """Outcome of one scene of :func:`simulate_batch` (SI units, world frame).

    The fields mean what they mean in
    :class:`~bifilar.analysis.simulate.SimulationResult`; health figures are
    taken at the integrator's accepted steps (10-30 per period; the
    constraint violation and energy drift there are those of the solution,
    not of an interpolant), tensions from the multipliers at those steps.

    period : mean measured period, s (None if fewer than two upward
        crossings); period_std : std of single cycles, s; crossings (k,) s.
    linear_period : the mode's linear period, s.
    max_constraint_violation : max | |d_i| - L_i |, m.
    energy_drift : max |E - E0| / |E0 - E_rest| over the steps and, where
        samples are taken (``samples_per_period``, LSODA's own), the samples;
        nan when the release has no oscillation energy to speak of (``simulate.untimed``).
    tension_min, tension_max : (n,) N.  slack : [(wire 1-based, t s)].
    lowest_z_min : lowest world z of the body, m; depth_max : ceiling minus
        that, m.  t, y : dense samples (only with ``samples_per_period``);
        tensions (k, n) N the physical tensions at them where the run computed
        them with its health (LSODA, one scene; else None).
    t_final, y_final : time (s) and state (13,) where the run ended.
    error : message when the scene could not be run (``errors="return"``),
        else None.
    """

    nsteps: int
    t: np.ndarray | None = None
    y: np.ndarray | None = None
    tensions: np.ndarray | None = None
    t_final: float | None = None
    y_final: np.ndarray | None = None
    warnings: list = field(default_factory=list)
    error: str | None = None
    model: str = "maximal"
    method: str = "LSODA"
    energy_drift_resolution: float = float("nan")
    """As :attr:`SimulationResult.energy_drift_resolution` (nan without the health figures)."""
    period_error: float = float("nan")
    """As :attr:`SimulationResult.period_error`, s (nan without a period or without the health
    figures, whose energy drift is part of it)."""

    def to_json(self) -> dict:
        """The keys of :meth:`SimulationResult.to_json` (interface.md) where they apply."""
        from .simulate import health_json, run_json

        doc = run_json(self, {"method": self.method, "rtol": self.rtol, "nfev": int(self.nfev),
                              "steps": int(self.nsteps), "runtime_s": float(self.runtime)})
        doc["error"] = self.error
        doc.update(health_json(self))
        return doc



_METHOD_NAME = {"lsoda": "LSODA (scipy odeint, batch in normalised time)",
                "dop853": "DOP853 (bifilar.integrators, per-scene step control)"}


def _failed(err: str, mode, amplitude, n: int, rtol: float) -> SceneRun:
    nan = float("nan")
    return SceneRun(period=None, period_std=None, crossings=np.zeros(0), linear_period=None,
                    max_constraint_violation=nan, energy_drift=nan, tension_min=np.full(n, nan),
                    tension_max=np.full(n, nan), slack=[], lowest_z_min=nan, depth_max=nan,
                    mode=None if mode is None else str(mode), amplitude=float(amplitude), coordinate_name="",
                    rtol=float(rtol), nfev=0, nsteps=0, runtime=0.0, error=err)


def _coordinate_vector(dom: int, q0: np.ndarray) -> np.ndarray:
    """e (13,) with e . y = a quantity that has the sign of the dominant
    relative coordinate of :func:`~bifilar.analysis.simulate.relative_pose`
    and the same zeros: the CoM offset for a translation; for a rotation the
    vector part of q q_rest^-1 (linear in q; its zeros are those of the
    rotation vector while the relative rotation stays below pi)."""
    e = np.zeros(13)
    if dom < 3:
        e[dom] = 1.0
        return e
    w0, x0, y0, z0 = q0
    rows = {
        3: [-x0, w0, -z0, y0],  # x part of q * conj(q0), coefficients of (qw, qx, qy, qz)
        4: [-y0, z0, w0, -x0],
        5: [-z0, -y0, x0, w0],
    }
    e[3:7] = rows[dom]
    return e


def simulate_batch(
    scenes: Sequence[Scene] | Scene,
    mode: str | int | Sequence = "torsion",
    amplitude: float | Sequence[float] = 0.05,
    periods: float | Sequence[float] = 10.0,
    *,
    rtol: float = 1e-10,
    atol: float | None = None,
    rests: Sequence[RestPose] | None = None,
    modes: Sequence[ModeSet] | None = None,
    guess: RestPose | None = None,
    on_slack: str = "continue",
    errors: str = "raise",
    samples_per_period: int | None = None,
    lowest_point: bool = True,
    health: bool = True,
    method: str = "auto",
    progress: Callable | None = None,
    independent: bool = False,
    starts: StartPoses | None = None,
) -> list[SceneRun]:
    """Integrate the nonlinear motion of many scenes, each from ``amplitude``
    x its mode shape, for ``periods`` linear periods of that mode.

    Parameters
    ----------
    scenes : scenes (any mix of wire counts; grouped internally).
    mode : label or 1-based index, or one per scene.
    amplitude, periods : scalars or one per scene (rad or m; count).
    rtol : relative tolerance of every scene's own error test (the meaning
        of ``simulate``'s ``rtol``; the DOP853 engine takes scipy's DOP853
        steps).  ``atol`` defaults, as in ``simulate``, to ``rtol`` x the
        amplitude-scaled size of each state component.  Period error
        measured ~0.1-1 x rtol (docs/performance.md): rtol 1e-10 for a
        period good to 1e-10.
    rests, modes : precomputed rest poses and mode sets (else computed
        batched, each from its start pose: ``guess`` is not used, see ``batch_rest.rest_poses``).
    on_slack : ``continue`` or ``stop`` (end a scene's run at the first step
        -- lsoda: sample -- with a non-positive tension).
    errors : ``raise`` (the first bad scene raises its error, as the
        single-scene functions do) or ``return`` (its result has
        ``error`` set and NaN figures).
    samples_per_period : if given, also return dense samples ``t``, ``y``
        (absolute positions) at that rate (dop853: 3 extra evaluations on
        the steps that hold a sample; lsoda: at max(64, rate) per period);
        the tension extremes then use the samples too.
    lowest_point : compute the lowest point / depth.
    health : compute the constraint violation, energy drift, tensions and
        lowest point (False: only the period and the crossings, faster; the
        health figures are NaN and slack wires are not reported).
    method : ``"dop853"``: the project's DOP853 with a step size and error
        test per scene, health at its steps, crossings on the dense output;
        ``"lsoda"``: LSODA (``scipy.integrate.odeint``, step loop in
        Fortran) on the whole group as one ODE in normalised time, rtol and
        atol divided by sqrt(B) so each scene keeps its own error bound,
        health at 64 samples per period; ``"auto"`` (default, the fastest
        measured, docs/performance.md): LSODA, scene by scene on floats
        below :data:`SMALL_BATCH` scenes, stacked up to :data:`LARGE_BATCH`,
        and the DOP853 engine from there.  Results of the two agree to the
        tolerance (~1e-11 relative in the period at rtol 1e-10).
    progress : ``progress(done, total)`` called as the batch advances.
    independent : every scene through the vectorised DOP853 engine whatever
        the batch size (one scene included; ``method`` must be ``"auto"``
        or ``"dop853"``): a scene's results are then the same to the bit
        whatever other scenes share its batch or their order
        (tests/test_batch_determinism.py), which stacked LSODA (a shared
        step) and the one-scene float path (other arithmetic) do not give.
        For results that must not depend on how work was split (chunks of
        work under ``--workers`` or ``--resume``).  Tensions are checked at
        :data:`HEALTH_SAMPLES` a period (LSODA's rate).  Its cost pays from
        hundreds of scenes; at a few it is several times the float path's
        (docs/performance.md, "Batching across a sweep's points").
    starts : the scenes' start poses if already solved: what
        :func:`~bifilar.analysis.start_pose.start_poses` gives for these
        scenes, rest poses, modes and amplitudes (e.g.
        :func:`~bifilar.analysis.simulate.checked_start_poses`, the input
        checks of a point); used instead of solving them again.  Each start
        is solved once either way (its feasibility and the run's state).

    Returns a list of :class:`SceneRun` in input order.
    """
    if isinstance(scenes, Scene):
        scenes = [scenes]
    scenes = list(scenes)
    Bn = len(scenes)
    if on_slack not in ("continue", "stop"):
        raise InputError("--on-slack", "must be 'continue' or 'stop'")
    if errors not in ("raise", "return"):
        raise InputError("errors", "must be 'raise' or 'return'")
    if method not in ("auto", "lsoda", "dop853"):
        raise InputError("--method", f"batch method must be 'auto', 'lsoda' or 'dop853', got {method!r}")
    if independent:
        if method == "lsoda":
            raise InputError("--method", "independent runs need the DOP853 engine, not 'lsoda'")
        method = _STACKED
    if not (0 < rtol < 1e-2):
        raise InputError("--rtol", f"must be in (0, 1e-2), got {rtol}")
    modes_in = list(mode) if isinstance(mode, (list, tuple, np.ndarray)) else [mode] * Bn
    amps = np.broadcast_to(np.asarray(amplitude, float), (Bn,))
    pers = np.broadcast_to(np.asarray(periods, float), (Bn,))
    if len(modes_in) != Bn:
        raise InputError("mode", f"got {len(modes_in)} modes for {Bn} scenes")
    if not np.all(np.isfinite(amps)) or not np.all(np.isfinite(pers)) or np.any(pers <= 0):
        raise InputError("--periods", "amplitudes must be finite and periods positive")
    out: list = [None] * Bn
    for ii in _groups(scenes):
        nw = scenes[ii[0]].n_wires
        sub = [scenes[k] for k in ii]
        geo: list = []
        if rests is None:
            rs = rest_poses(sub, guess, errors=errors, geometry=geo)
        else:
            rs = [rests[k] for k in ii]
        ms: list = [None] * len(ii)
        good = [j for j, r in enumerate(rs) if isinstance(r, RestPose)]
        if modes is None:
            for j, x in zip(good, modes_batch([sub[j] for j in good], [rs[j] for j in good],
                                              geometry=geo[0] if geo else None)):
                ms[j] = x
        else:
            ms = [modes[k] for k in ii]
        geo.clear()  # (a 10 000-scene batch's arrays: not kept through the runs)
        runnable = []
        for j, k in enumerate(ii):
            if not isinstance(rs[j], RestPose):
                out[k] = _failed(f"{rs[j]}", modes_in[k], amps[k], nw, rtol)
                continue
            try:
                md = _mode_of(ms[j], modes_in[k])
            except InputError as exc:
                if errors != "return":
                    raise
                out[k] = _failed(str(exc), modes_in[k], amps[k], nw, rtol)
                continue
            runnable.append((k, j, md))
        if runnable:
            sub_md = [md for _, _, md in runnable]
            if starts is None:
                sp = _start_poses([scenes[k] for k, _, _ in runnable], [rs[j] for _, j, _ in runnable], sub_md,
                                  amps[[k for k, _, _ in runnable]])
            else:  # (every start, in order: as given, without take's copies)
                ks = [k for k, _, _ in runnable]
                sp = starts if ks == list(range(len(starts.feasible))) else starts.take(ks)
            ok = sp.feasible
            if not np.all(ok):
                for jr, ((k, _, md), good) in enumerate(zip(runnable, ok)):
                    if good:
                        continue
                    exc = refusal(scenes[k], md, float(amps[k]), float(sp.gap[jr]),
                                  f"scene {k + 1} ('{scenes[k].name}')", **sp.off_wires(jr))
                    if errors != "return":
                        raise exc
                    out[k] = _failed(str(exc), modes_in[k], amps[k], nw, rtol)
                runnable = [x for x, good in zip(runnable, ok) if good]
            y0 = sp.states()[ok]
        if runnable:
            res = _run_group([scenes[k] for k, _, _ in runnable], [rs[j] for _, j, _ in runnable],
                             [md for _, _, md in runnable], amps[[k for k, _, _ in runnable]],
                             pers[[k for k, _, _ in runnable]], rtol, atol, on_slack, samples_per_period,
                             lowest_point, progress, method, health, y0)
            for (k, _, _), r in zip(runnable, res):
                out[k] = r
    return out


def _mode_of(ms: ModeSet, key) -> Mode:
    try:
        md = ms.get(key)
    except KeyError as exc:
        raise InputError("--mode", str(exc.args[0])) from None
    if md.period is None:
        raise InputError("--mode", f"mode '{md.label}' has no restoring stiffness (no period); pick another")
    return md


def run_one(scene: Scene, rest: RestPose, md: Mode, amplitude: float, periods: float, rtol: float = 1e-10,
            atol=None, samples_per_period: int | None = None, lowest_point: bool = True, health: bool = True,
            method: str = "auto", on_slack: str = "continue", progress: Callable | None = None,
            y0: np.ndarray | None = None) -> SceneRun:
    """One scene through the float fast path (what :func:`simulate_batch` does
    for a batch of one), given its rest pose and mode (no input checks).
    ``progress(done, total)`` as in :func:`simulate_batch`.  ``y0`` (13,):
    start from this state (absolute position) instead of the mode's start
    at ``amplitude`` (which still scales the tolerances and times the run)."""
    return _run_group([scene], [rest], [md], np.array([amplitude], float), np.array([periods], float), rtol, atol,
                      on_slack, samples_per_period, lowest_point, progress, method, health,
                      None if y0 is None else np.asarray(y0, float)[None, :])[0]


SMALL_BATCH = 20
"""Below this many scenes a group runs scene by scene on Python floats: numpy
calls on arrays of a few elements cost more than the float arithmetic
(docs/performance.md, batch-size table)."""
LARGE_BATCH = 300
"""From this many scenes ``method="auto"`` uses the per-scene-step DOP853
engine, below it LSODA on the stacked system (measured crossover)."""
CHUNK = 1500
"""Larger groups run in chunks of this many scenes: the vectorised engines'
numpy overhead is amortised by then, while larger working arrays fall out of
the processor's cache and cost more per scene (docs/performance.md,
``scripts/bench_batch_memory.py``); memory stays bounded too.  1500, not
session 6's 2000: a chunk's DOP853 working set is ~39 kB a scene (10 torsion
periods of the thesis plate at rtol 1e-9), and at 2000 the 10 000-scene
benchmark peaked at 242-247 MB on an AMD EPYC, 3-8 MB under issue 14's
250 MB limit; at 1500 at 220-221 MB, for ~11 % more CPU a scene (0.57 ->
0.63-0.64 ms, still below the 1000-scene 0.75 ms the same target compares
with): ``python scripts/bench_batch_memory.py --sizes 10000 --chunk N``,
session 27, docs/performance.md."""


HEALTH_SAMPLES = 64
"""Samples a period at which ``simulate_batch(..., independent=True)``
checks the tensions (the LSODA engine's rate)."""
_STACKED = "dop853, stacked"
"""``method`` of :func:`_run_group`: the vectorised DOP853 engine for every
batch size (``simulate_batch(..., independent=True)``)."""


def _shifted_params(scenes, com0: np.ndarray) -> mx.RigParams:
    """:func:`~bifilar.models.maximal.params_from_scenes` with the anchors
    relative to each scene's rest CoM ``com0`` (B, 3), m: the frame the
    runs integrate in."""
    P = mx.params_from_scenes(scenes)
    return mx.RigParams(**{**{k: getattr(P, k) for k in P.__dataclass_fields__}, "anchors": P.anchors - com0[:, None, :]})


_SCENE_PARAMS: dict = {}
"""id(scene) -> (a weak reference to the scene, {its rest CoM's bytes: the
float parameters ``take(0)`` of :func:`_shifted_params`}): what
:func:`_scene_by_scene` gives the runs of one scene and rest pose, kept
while the scene lives, so a sweep point's later calls (its amplitude laws'
runs of its scene after its own runs) take the same parameters and so the
kernels compiled on them (one build a point fewer; a point builds its
scene anew, so nothing is shared between points).  Rows of one scene and
rest CoM are the same values whatever batch they were taken from
(tests/test_runs27.py); the entry goes with its scene."""


def _scene_params(scene, com_bytes: bytes, build):
    """The float parameters of ``scene`` about the rest CoM ``com_bytes``
    (:data:`_SCENE_PARAMS`), ``build()``'s the first time."""
    key = id(scene)
    entry = _SCENE_PARAMS.get(key)
    if entry is None or entry[0]() is not scene:
        entry = _SCENE_PARAMS[key] = (weakref.ref(scene, lambda _, k=key: _SCENE_PARAMS.pop(k, None)), {})
    got = entry[1].get(com_bytes)
    if got is None:
        got = entry[1][com_bytes] = build()
    return got


def _scene_by_scene(scenes, rests, mds, amps, pers, rtol, atol, on_slack, spp, lowest_point, progress, method,
                    health, y0) -> list[SceneRun]:
    """A small group (fewer than :data:`SMALL_BATCH` runs) run by run, each
    as it runs alone (its own ODE, on floats), in input order.  Runs of one
    scene from one rest pose (a sweep point's modes) share its parameters
    and compiled kernels and, on LSODA with one length and no samples
    kept, have their samples processed together
    (:func:`~bifilar.analysis.batch_lsoda._lsoda_joint`); without
    ``health`` (only the periods read: a point's amplitude laws' runs, some
    of them on stepped scenes) the runs of all the scenes go through that
    pass together, each integrated with its own scene's kernel; every run's
    lowest point goes into one fold at the end (one support-function call a
    body).  The same figures, bit for bit, as each
    run alone (tests/test_run_cost.py, tests/test_batch_determinism.py)."""
    scenes = loaded_scenes(scenes, rests)  # stated stiffness: the run's wires are the loaded ones
    Bn = len(scenes)
    out: list = [None] * Bn
    groups: dict = {}  # (scene, rest CoM) -> its runs
    for j in range(Bn):
        groups.setdefault((id(scenes[j]), np.asarray(rests[j].com, float).tobytes()), []).append(j)
    keys = {js[0]: key[1] for key, js in groups.items()}  # a group's first run -> its rest CoM's bytes
    low = LowestPoint(scenes, np.array([r.com for r in rests])) if (lowest_point and health) else None
    if len(groups) > 1 and method == "lsoda" and not spp and not health:
        # runs of several scenes whose periods only are read (a point's amplitude laws' stepped scenes): each
        # integrated as alone with its scene's kernel, their crossings taken together (tests/test_run_cost.py)
        Pg = _shifted_params(scenes, np.array([r.com for r in rests], float))
        P1: list = [None] * Bn
        for js in groups.values():
            # (a scene's rows: the same values; one kernel for its runs, and for its runs in earlier calls)
            p1 = _scene_params(scenes[js[0]], keys[js[0]], lambda j=js[0]: Pg.take(j))
            for j in js:
                P1[j] = p1
        try:
            runs = _run_group(scenes, rests, mds, amps, pers, rtol, atol, on_slack, spp, lowest_point, None, method,
                              health, y0, (Pg, P1), None, True)
        except _NotJoint:
            runs = None
        if runs is not None:
            if progress is not None:
                progress(1.0, 1.0)
            return runs
    done = 0
    for js in groups.values():
        Pg = _shifted_params([scenes[j] for j in js], np.array([rests[j].com for j in js], float))
        # one run's (rows of one scene and rest: the same values; the float ones as earlier calls took them)
        P0, P1 = Pg.take([0]), _scene_params(scenes[js[0]], keys[js[0]], lambda: Pg.take(0))

        def run(ii, params, joint=False):
            ii = list(ii)
            return _run_group([scenes[j] for j in ii], [rests[j] for j in ii], [mds[j] for j in ii], amps[ii], pers[ii],
                              rtol, atol, on_slack, spp, lowest_point, None, method, health,
                              None if y0 is None else y0[ii], params,
                              None if low is None else SharedLowestPoint(low, ii), joint)

        runs = None
        if len(js) > 1 and method == "lsoda" and not spp:
            try:
                runs = run(js, (Pg, P1), joint=True)
            except _NotJoint:
                runs = None
        if runs is None:
            runs = [run([j], (P0, P1))[0] for j in js]
        for j, r in zip(js, runs):
            out[j] = r
        done += len(js)
        if progress is not None:
            progress(done / Bn, 1.0)
    if low is not None:
        ceilings: dict = {}  # each scene's ceiling_z, once
        for r, s_, lz in zip(out, scenes, low.z.tolist()):
            if id(s_) not in ceilings:
                ceilings[id(s_)] = s_.ceiling_z
            r.lowest_z_min, r.depth_max = lz, ceilings[id(s_)] - lz
    return out


def _run_group(scenes, rests, mds, amps, pers, rtol, atol, on_slack, spp, lowest_point, progress,
               method: str = "auto", health: bool = True, y0: np.ndarray | None = None,
               params: tuple | None = None, lowest: SharedLowestPoint | None = None,
               joint: bool = False) -> list[SceneRun]:
    """Runs of scenes with one wire count; ``y0`` (B, 13) their start states
    if already solved (:func:`initial_states`' values), else solved here.
    ``params``: (the scenes' :func:`_shifted_params`, the float parameters
    ``take(0)`` of their one scene) if already built: runs of one scene
    from one rest pose (a sweep point's modes) share them and so the
    compiled kernels cached on them (tests/test_run_cost.py).
    ``lowest``: where their lowest points go (``lowest_z_min`` and
    ``depth_max`` are then left NaN for the caller to fill in from the
    shared fold).  ``joint``: LSODA runs of one scene and one length, each
    integrated as alone, their samples processed together
    (:func:`~bifilar.analysis.batch_lsoda._lsoda_joint`; raises
    :class:`~bifilar.analysis.batch_lsoda._NotJoint` where that does not
    apply)."""
    scenes = loaded_scenes(scenes, rests)  # stated stiffness: the run's wires are the loaded ones
    Bn = len(scenes)
    if method == "auto":
        method = "lsoda" if Bn < LARGE_BATCH else "dop853"
    stacked = method == _STACKED
    if 1 < Bn < SMALL_BATCH and not stacked and not joint:
        return _scene_by_scene(scenes, rests, mds, amps, pers, rtol, atol, on_slack, spp, lowest_point, progress,
                               method, health, y0)
    if Bn > CHUNK:  # chunks: the same cost per scene and bounded memory however many scenes
        out = []
        starts = list(range(0, Bn, CHUNK))
        for c, j in enumerate(starts):
            sl = slice(j, j + CHUNK)
            sub_progress = None
            if progress is not None:
                def sub_progress(done, total, c=c):
                    progress((c + done / total) / len(starts), 1.0)
            out += _run_group(scenes[sl], rests[sl], mds[sl], amps[sl], pers[sl], rtol, atol, on_slack, spp,
                              lowest_point, sub_progress, method, health, None if y0 is None else y0[sl])
        return out
    keep_samples = bool(spp)
    if stacked:
        # health at >= 64 samples a period, as LSODA's: the parabola through
        # coarse steps (~10 a period at rtol 1e-8) misplaces a tension peak
        # by ~1e-4 of it, the samples' by ~1e-6 (docs/performance.md)
        method = "dop853"
        if health:
            spp = max(HEALTH_SAMPLES, int(spp or 0))
    t_start = time.perf_counter()
    n = scenes[0].n_wires
    if y0 is None:
        y0 = initial_states(scenes, rests, mds, amps)
    com0 = np.array([r.com for r in rests])
    ys0 = y0.copy()
    ys0[:, :3] -= com0  # integrate relative to the rest CoM (tolerances apply to the oscillation)
    P, P1 = params if params is not None else (_shifted_params(scenes, com0), None)
    T_ref = np.array([md.period for md in mds])
    t_end = pers * T_ref
    omega = 2 * np.pi / T_ref
    Lmax = P.lengths.max(axis=1)
    rt = np.full(Bn, float(rtol))
    if atol is None:
        at = rt * state_scale(amps, np.array([md.dominant for md in mds]), Lmax, omega)
    else:
        at = np.broadcast_to(np.asarray(atol, float).reshape(-1, 1) if np.ndim(atol) else float(atol), (13, Bn)).copy()
    e = np.array([_coordinate_vector(md.dominant, r.q) for md, r in zip(mds, rests)]).T  # (13, B)
    L2 = (P.lengths**2).T
    if lowest is None and lowest_point and health:
        lowest = LowestPoint(scenes, com0)
    if method == "lsoda":
        obs = Health(Bn, n, e, P.mass, P.gravity, P.inertia, L2, on_slack, lowest, progress, t_end,
                     [None] * Bn if spp else None, health=health)
        try:
            if joint:
                nfev, nsteps, status, msgs = _lsoda_joint(P1, ys0, T_ref, pers, float(rtol), at, 64, obs, com0, health,
                                                          on_slack)
            else:
                nfev, nsteps, status, msgs = _lsoda(P, ys0, T_ref, pers, float(rtol), at, max(64, int(spp or 0)),
                                                    obs, com0, health, on_slack, progress, P1)
        except _BatchFailed:  # one scene spoils the shared run: run them one by one
            return [_run_group([s_], [r_], [m_], amps[j:j + 1], pers[j:j + 1], rtol, atol, on_slack, spp,
                               lowest_point, None, method, health, y0[j:j + 1])[0]
                    for j, (s_, r_, m_) in enumerate(zip(scenes, rests, mds))]
    else:
        dense_times = None
        if spp:
            dense_times = [np.linspace(0.0, te, max(int(spp * te / tr), 200) + 1) for te, tr in zip(t_end, T_ref)]
        obs = Health(Bn, n, e, P.mass, P.gravity, P.inertia, L2, on_slack, lowest, progress, t_end,
                     dense_times, health=health, refine_steps=not stacked)
        nfev, nsteps, status, msgs = _dop853(P, ys0, T_ref, t_end, rt, at, obs, on_slack, stacked)
    if method == "dop853" and obs.samples is not None and health:
        _health_at_dense_samples(obs, P, L2, n)
    runtime = (time.perf_counter() - t_start) / Bn
    lz = lowest.z if lowest is not None else np.full(Bn, np.nan)  # running minimum over the steps / samples
    # the per-run figures below from Python floats (tolist: each element's value, without a numpy scalar's
    # indexing and conversion per figure and run; docs/design.md, "runs27"): the same operations on the same doubles
    amp_l, Lmax_l, Tref_l, rt_l = amps.tolist(), Lmax.tolist(), T_ref.tolist(), rt.tolist()
    E0_l, dE_l, viol_l, tfin_l, lz_l = obs.E0.tolist(), obs.dE.tolist(), obs.viol.tolist(), obs.t_final.tolist(), lz.tolist()
    slack_l, status_l = obs.slack_t.tolist(), np.asarray(status).tolist()
    nfev_l, nsteps_l = ([int(v) for v in np.asarray(x).tolist()] for x in (nfev, nsteps))
    com_pad = np.zeros((Bn, 13))  # each run's rest CoM, padded to a state: its absolute positions
    com_pad[:, :3] = com0
    ceilings: dict = {}  # each scene's ceiling_z, once
    out = []
    for b in range(Bn):
        amp, dom, lmax = amp_l[b], mds[b].dominant, Lmax_l[b]
        tc = timed_crossings(np.array(obs.cross[b]), amp, dom, lmax)
        period, pstd = measured_period(tc)
        small = small_amplitude_period(amp, dom, lmax, Tref_l[b])
        E0 = E0_l[b]
        drift = (dE_l[b] / abs(E0) if E0 != 0 and not untimed(amp, dom, lmax)
                 else float("nan"))  # relative to no oscillation energy (or one at rounding): undefined
        # simulate's health figures: a few float operations on what the run measured
        res_ = drift_floor(P.mass[b], P.gravity[b], P.anchors[b], E0) if math.isfinite(drift) else float("nan")
        perr = (period_accuracy(period if small is None else small[0], "auto" if method == "lsoda" else method,
                                rt_l[b], amp, dom, lmax, linear_period=Tref_l[b], drift=drift)[0]
                if health else float("nan"))
        slack = [(i + 1, v) for i, v in enumerate(slack_l[b]) if math.isfinite(v)]
        warnings = [] if small is None else [small[1]]
        if small is not None:
            period = small[0]
        for w_, ts_ in slack:
            warnings.append(f"WIRE {w_} GOES SLACK at t = {ts_:.4g} s (tension {obs.Tmin[b, w_ - 1]:.3g} N): "
                            "the motion after that is not physical; reduce the amplitude")
        if status_l[b] == 1:
            warnings.append(f"run stopped at t = {tfin_l[b]:.4g} s because a wire went slack")
        if status_l[b] == -1:
            warnings.append(f"integration failed: {msgs.get(b, '')}")
        if period is None:
            warnings.append(no_period_warning(amp, status_l[b] == 1))
        t_s = y_s = T_s = None
        if obs.samples is not None and keep_samples:
            parts = obs.samples[b]
            if parts:
                # one part (LSODA's single window, any run shorter than ~4800 periods): its arrays are this
                # run's own copies, taken as they are (C order, as concatenate gives; ~1 % of a period saved)
                one = len(parts) == 1
                t_s = parts[0][0] if one else np.concatenate([p_[0] for p_ in parts])
                y_s = np.ascontiguousarray(parts[0][1]) if one else np.concatenate([p_[1] for p_ in parts])
                y_s[:, :3] += com0[b]
                if obs.sample_tensions is not None:
                    T_s = (np.ascontiguousarray(obs.sample_tensions[b][0]) if one
                           else np.concatenate(obs.sample_tensions[b]))
        if viol_l[b] > 1e-6 * lmax:
            # judged at the state of the largest error, the last one and the samples where the run kept them
            seen = np.stack([obs.y_viol[b], obs.y_final[b]]) + com_pad[b]
            seen = seen if y_s is None else np.concatenate([seen, y_s])
            warnings.insert(len(warnings) - (period is None), violation_warning(scenes[b], seen, viol_l[b]))
        sid = id(scenes[b])
        if sid not in ceilings:
            ceilings[sid] = scenes[b].ceiling_z
        out.append(SceneRun(
            period=period, period_std=pstd, crossings=tc, linear_period=Tref_l[b],
            max_constraint_violation=viol_l[b], energy_drift=drift,
            tension_min=obs.Tmin[b].copy(), tension_max=obs.Tmax[b].copy(), slack=slack,
            lowest_z_min=lz_l[b], depth_max=ceilings[sid] - lz_l[b],
            mode=mds[b].label, amplitude=amp, coordinate_name=COMPONENTS[dom],
            rtol=rt_l[b], nfev=nfev_l[b], nsteps=nsteps_l[b], runtime=runtime, t=t_s, y=y_s, tensions=T_s,
            t_final=tfin_l[b], y_final=obs.y_final[b] + com_pad[b],
            warnings=warnings, method=_METHOD_NAME[method], energy_drift_resolution=res_, period_error=perr,
        ))
    return out
