"""LSODA engine of batched runs (:func:`~bifilar.analysis.batch.simulate_batch`
with ``method="lsoda"``, and what ``"auto"`` picks below
:data:`~bifilar.analysis.batch.LARGE_BATCH` scenes).

* :func:`_lsoda`: one scene in physical time, or the whole group stacked
  into one ODE in normalised time with tolerances divided by sqrt(B) (each
  scene keeps the error bound it would have alone), integrated by
  ``scipy.integrate.odeint`` (the step loop in Fortran), in windows of
  samples so memory stays bounded.
* :func:`_lsoda_joint`: runs of one scene (a sweep point's modes), each
  integrated as alone, their samples taken through the crossings and the
  health together.
* :func:`_window`, :func:`_close`: the crossings (degree-7 local
  interpolation of the samples), health (:mod:`bifilar.analysis.batch_health`)
  and kept samples of a window, and the end of the runs.

Split from :mod:`bifilar.analysis.batch` (which dispatches to it and builds
the :class:`~bifilar.analysis.batch.SceneRun` results); states relative to
each scene's rest CoM, SI units, world frame z up.
"""

from __future__ import annotations

import numpy as np

from .. import integrators as itg
from ..models import maximal as mx
from .batch_health import Health, sample_health


def _lsoda(P: mx.RigParams, ys0, T_ref, pers, rtol: float, at, spp: int, obs: Health, com0,
           health: bool, on_slack: str, progress, P1: mx.RigParams | None = None):
    """The whole group as one ODE in normalised time tau = t / T_ref (every
    scene oscillates at ~1 per unit tau, so one step sequence suits all; a
    single scene in physical time, which is the same ODE without the scaling),
    integrated by LSODA (:func:`scipy.integrate.odeint`: the step loop runs in
    Fortran, only the compiled right-hand side is Python).

    Per-scene accuracy: LSODA's error test bounds the root-mean-square of
    the weighted local errors of all 13 B components; dividing rtol and
    atol by sqrt(B) makes every scene's own weighted RMS error obey the
    bound it would have alone (RMS over 13 <= sqrt(B) x RMS over 13 B).
    The state is stored scene-major, so the Jacobian is banded (12 + 12) if
    LSODA ever switches to its stiff method.

    Samples at ``spp`` per period feed the crossings (degree-7 local
    interpolation, :func:`~bifilar.integrators.sampled_crossings`) and,
    with ``health``, the constraint violation, energy drift, tensions and
    lowest point.  Long runs go in windows so memory stays ~50 MB.
    """
    from scipy.integrate import odeint

    Bn = len(T_ref)
    n = int(P.lengths.shape[-1])
    sq = np.sqrt(Bn)
    rte = rtol / sq
    ate = (at / sq).T.ravel()  # scene-major
    if Bn == 1:  # in physical time t = tau T: the kernel itself is odeint's f(y, t) (no wrapper, no scaling)
        # kept samples: their physical tensions from the health's kernel pass (SceneRun.tensions)
        physical = health and obs.samples is not None
        f, kx = _one_scene_kernels(P.take(0) if P1 is None else P1, physical)
        if physical:
            obs.sample_tensions = [[]]
        tscale = float(T_ref[0])
    else:
        kb = mx.compiled_kernel(P)
        Tcol = T_ref[:, None]
        tscale = 1.0

        def f(y, tau):
            out = kb(*y.reshape(Bn, 13).T)
            return (np.array(out).T * Tcol).ravel()
        kx = mx.compiled_kernel(P, extras=True)
    tau_end, K_total, taus = _sample_grid(pers, spp)
    if progress is not None:
        # a one-scene window holds ~4800 periods: without ticks from the right-hand side a `simulate`
        # progress bar sat at 0 % for a whole typical run; one scene's kernel ticks itself (a wrapper's
        # extra Python call per right-hand side cost 3.6 % of a run, docs/performance.md, session 12)
        if Bn == 1:
            f = mx.compiled_kernel(P.take(0) if P1 is None else P1, signature="odeint",
                                   ticks=itg.ticker(tau_end * tscale, progress, step=0.01))
        else:
            f = itg.with_progress(f, tau_end * tscale, progress, step=0.01, time_first=False)
    stop_tau = pers.astype(float).copy()  # per-scene end (earlier if a wire goes slack and on_slack == "stop")
    chunk = _window_samples(spp, Bn)
    y = ys0.ravel().copy()
    tail_c = None  # last 7 samples of the previous window (crossing stencils)
    nfe = nst = 0
    status = np.zeros(Bn, int)
    msgs: dict = {}
    first = True
    k0 = 0
    cross_cols, cross_t = [], []
    while k0 < K_total:
        k1_ = min(K_total, k0 + chunk)
        tt = taus[k0:k1_ + 1]
        Y, info = odeint(f, y, tt * tscale, rtol=rte, atol=ate, full_output=True, mxstep=100000, ml=12, mu=12)
        message = info["message"]
        if message == "Integration successful." and not np.all(np.isfinite(Y)):
            message = "the solution is not finite (NaN or inf)"
        if message != "Integration successful.":
            if Bn > 1:
                raise _BatchFailed(message)
            status[0] = -1
            msgs[0] = f"LSODA: {message}"
            good = np.nonzero(np.all(np.isfinite(Y), axis=1))[0]
            Y = Y[: (good[-1] + 1) if len(good) else 1]
            tt = tt[: len(Y)]
            stop_tau[0] = min(stop_tau[0], tt[-1])
        nfe += int(info["nfe"][-1]) if len(info["nfe"]) else 0
        nst += int(info["nst"][-1]) if len(info["nst"]) else 0
        y = Y[-1].copy()
        Ys = Y.reshape(len(tt), Bn, 13)
        if not first:  # the window's first sample repeats the previous window's last
            Ys, tt = Ys[1:], tt[1:]
        tail_c = _window(Ys, tt, obs, kx, n, com0, T_ref, stop_tau, on_slack, first, health, spp, tail_c,
                         cross_cols, cross_t)
        if progress is not None:
            progress(min(float(tt[-1]) / tau_end, 1.0), 1.0)
        first = False
        k0 = k1_
        if status[0] == -1 and Bn == 1:
            break
    _close(obs, tt, y.reshape(Bn, 13), stop_tau, T_ref, pers, status, cross_cols, cross_t)
    return np.full(Bn, nfe), np.full(Bn, nst), status, msgs


def _one_scene_kernels(P1: mx.RigParams, physical: bool = False):
    """(odeint's ``f(y, t)``, the health's kernel with extras) of one scene's
    float parameters ``P1`` (the kernels cached on it): what :func:`_lsoda`
    integrates a scene alone with, and :func:`_lsoda_joint` each of its runs.
    ``physical``: the health's kernel also gives the unstabilised multipliers
    (the record's tensions, :func:`~bifilar.analysis.batch_health.sample_health`)."""
    kx = mx.compiled_kernel(P1, extras=True, physical=physical, derivatives=False)  # sample_health reads the extras
    return mx.compiled_kernel(P1, signature="odeint"), mx.chunked(kx, first=13)  # the samples' extras, chunked


def _sample_grid(pers, spp: int):
    """(tau_end, K, taus (K + 1,)): the LSODA engine's sample times in
    normalised time, ``spp`` a period, up to the longest run."""
    tau_end = float(np.max(pers))
    K_total = int(np.ceil(tau_end * spp - 1e-9))
    taus = np.arange(K_total + 1) / spp
    taus[-1] = min(taus[-1], tau_end) if K_total else tau_end
    return tau_end, K_total, taus


def _window_samples(spp: int, Bn: int) -> int:
    """Samples a window of the LSODA engine holds (~50 MB of states)."""
    return max(4 * spp, int(4e6 / (13 * Bn)))


def _window(Ys, tt, obs: Health, kx, n, com0, T_ref, stop_tau, on_slack, first, health, spp, tail_c, cross_cols,
            cross_t):
    """The crossings (appended to ``cross_cols``, ``cross_t``), health and
    kept samples of one window of the LSODA engine: Ys (k, B, 13) at
    normalised times tt (k,); returns the tail the next window's crossing
    stencils need."""
    # crossings of the timed coordinate
    c = np.einsum("kbm,mb->kb", Ys, obs.e)
    cc = c if tail_c is None else np.concatenate([tail_c, c])
    base = 0 if tail_c is None else len(tail_c)
    tau0 = tt[0] - base / spp
    col, tx, kl = itg.sampled_crossings(cc, 1.0 / spp)
    keep = kl >= base - 1  # pairs ending in this window (earlier ones were found before)
    cross_cols.append(col[keep])
    cross_t.append(tx[keep] + tau0)
    Tp = None
    if health:
        Tp = sample_health(Ys, tt, obs, kx, n, com0, T_ref, stop_tau, on_slack, first,
                           physical=obs.sample_tensions is not None)
    if obs.samples is not None:
        for b in range(Ys.shape[1]):
            sel = tt <= stop_tau[b] + 1e-12
            if np.any(sel):
                # a boolean index already copies (a second copy of a 210-period record cost ~1 % of a period);
                # com0 is added at the end, in place (SceneRun.y)
                obs.samples[b].append((tt[sel] * T_ref[b], Ys[sel, b, :]))
                if Tp is not None:
                    obs.sample_tensions[b].append(Tp[:, sel, b].T)
    return cc[-7:]


def _close(obs: Health, tt, y_last, stop_tau, T_ref, pers, status, cross_cols, cross_t) -> None:
    """End of the LSODA engine's runs: final times and states, each scene's
    crossings (s) up to its end, status 1 for a run stopped early."""
    obs.t_final[:] = np.minimum(tt[-1], stop_tau) * T_ref
    obs.y_final[:] = y_last
    cols = np.concatenate(cross_cols) if cross_cols else np.zeros(0, int)
    tcs = np.concatenate(cross_t) if cross_t else np.zeros(0)
    # every run's crossings up to its end, in time order, scaled to seconds, in one pass of array operations
    # (each element's comparison and product as run by run; a run's times sorted as np.sort sorts them)
    keep = tcs <= stop_tau[cols] + 1e-12
    cols, tcs = cols[keep], tcs[keep]
    order = np.lexsort((tcs, cols))
    cols, secs = cols[order], tcs[order] * T_ref[cols[order]]
    for b, part in enumerate(np.split(secs, np.searchsorted(cols, np.arange(1, len(T_ref))))):
        obs.cross[b] = part  # (an array: the run's SceneRun takes it as its crossings)
        if stop_tau[b] < pers[b] - 1e-12 and status[b] == 0:
            status[b] = 1


def _lsoda_joint(P1, ys0, T_ref, pers, rtol: float, at, spp: int, obs: Health, com0, health: bool,
                 on_slack: str):
    """Runs of one scene (its float parameters ``P1``: one compiled kernel
    for all), each integrated as :func:`_lsoda` integrates a scene alone
    (its own ODE in physical time, the same odeint call: the same steps and
    samples, bit for bit), their samples then taken through the crossings
    and the health together: one pass of numpy calls for the 2-3 runs of a
    sweep point instead of one a run, row by row the same expressions
    (tests/test_run_cost.py, tests/test_batch_determinism.py).  ``P1`` may
    also be a list, each run's float parameters (runs of several scenes
    with one wire count, e.g. a point's amplitude laws' stepped scenes;
    each list entry's kernels serve the runs that share it): only without
    ``health`` (the health's kernel is one scene's), so only the crossings
    are taken together.  Needs runs
    of one length in one window of samples that all succeed: else raises
    :class:`_NotJoint` before anything is recorded (the caller runs them
    one by one)."""
    from scipy.integrate import odeint

    Bn = len(T_ref)
    per_run = isinstance(P1, list)
    if per_run and health:
        raise ValueError("runs of several scenes go through the crossings together only without their health")
    n = int((P1[0] if per_run else P1).lengths.shape[-1])
    if np.any(pers != pers[0]):
        raise _NotJoint
    tau_end, K_total, taus = _sample_grid(pers, spp)
    if not 0 < K_total <= _window_samples(spp, 1):
        raise _NotJoint
    if per_run:
        kernels: dict = {}  # id -> (its parameters, kept alive while the id is a key; its kernel), one a scene
        for p in P1:
            if id(p) not in kernels:
                kernels[id(p)] = (p, mx.compiled_kernel(p, signature="odeint"))
        fs = [kernels[id(p)][1] for p in P1]
        kx = None
    else:
        f, kx = _one_scene_kernels(P1)
        fs = [f] * Bn
    Ys = np.empty((K_total + 1, Bn, 13))
    nfe, nst = np.zeros(Bn, int), np.zeros(Bn, int)
    atT = np.ascontiguousarray(at.T)  # each run's tolerances, a contiguous row (the column's values)
    for b, f in enumerate(fs):  # (odeint copies the start state)
        Y, info = odeint(f, ys0[b], taus * float(T_ref[b]), rtol=rtol, atol=atT[b], full_output=True, mxstep=100000,
                         ml=12, mu=12)
        if info["message"] != "Integration successful.":
            raise _NotJoint
        Ys[:, b] = Y
        nfe[b] = int(info["nfe"][-1]) if len(info["nfe"]) else 0
        nst[b] = int(info["nst"][-1]) if len(info["nst"]) else 0
    if not np.all(np.isfinite(Ys)):  # every run's samples at once (nothing is recorded before this)
        raise _NotJoint
    stop_tau = pers.astype(float).copy()
    cross_cols: list = []
    cross_t: list = []
    status = np.zeros(Bn, int)
    _window(Ys, taus, obs, kx, n, com0, T_ref, stop_tau, on_slack, True, health, spp, None, cross_cols, cross_t)
    _close(obs, taus, Ys[-1], stop_tau, T_ref, pers, status, cross_cols, cross_t)
    return nfe, nst, status, {}


class _BatchFailed(Exception):
    pass


class _NotJoint(Exception):
    """Runs :func:`_lsoda_joint` cannot take together (run them one by one)."""
