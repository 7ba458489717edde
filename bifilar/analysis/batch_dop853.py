"""DOP853 engine of batched runs (:func:`~bifilar.analysis.batch.simulate_batch`
with ``method="dop853"``, ``independent=True``, and what ``"auto"`` picks
from :data:`~bifilar.analysis.batch.LARGE_BATCH` scenes): the project's
DOP853 (:mod:`bifilar.integrators`) with a step size and error test of its
own for every scene, crossings on its order-7 dense output.

* :func:`_dop853`: one scene on Python floats (:func:`_single`, the
  observer fed afterwards in one vectorised pass over the accepted steps) or
  the group vectorised (:func:`~bifilar.integrators.integrate_batch`, the
  observer at every step).
* :func:`_health_at_dense_samples`: the tensions and energy at kept dense samples too.

Split from :mod:`bifilar.analysis.batch` (which dispatches to it and builds
the :class:`~bifilar.analysis.batch.SceneRun` results); health gathered by
:class:`~bifilar.analysis.batch_health.Health`; states relative to each
scene's rest CoM, SI units, world frame z up.
"""

from __future__ import annotations

import numpy as np

from .. import integrators as itg
from ..models import maximal as mx
from .batch_health import Health, merge_refined, refine_extremes


def _h0(T_ref: np.ndarray, rtol: np.ndarray) -> np.ndarray:
    """First step, s: about the step the controller settles on (DOP853 takes
    ~15-40 steps per period at rtol 1e-8..1e-12), a little smaller."""
    return T_ref * 0.2 * np.asarray(rtol) ** 0.125


def _dop853(P: mx.RigParams, ys0, T_ref, t_end, rt, at, obs: Health, on_slack: str, stacked: bool):
    """The group's runs (B scenes, parameters ``P`` relative to each rest
    CoM, start states ``ys0`` (B, 13), linear periods ``T_ref`` and ends
    ``t_end`` (B,) s, tolerances ``rt`` (B,) and ``at`` (13, B)) fed to
    ``obs``: one scene on floats unless ``stacked`` (the vectorised engine
    for every batch size).  Returns (nfev, nsteps, status, messages)."""
    Bn = len(T_ref)
    h0 = _h0(T_ref, rt)
    if Bn == 1 and not stacked:
        nfev, nsteps, status, msg = _single(P.take(0), ys0[0], float(t_end[0]), float(rt[0]), at[:, 0],
                                            float(h0[0]), obs, on_slack)
        nfev, nsteps, status, msgs = np.array([nfev]), np.array([nsteps]), np.array([status]), {0: msg} if msg else {}
    else:
        def make_f(idx):
            return mx.compiled_kernel(P.take(idx), extras=True)

        run = itg.integrate_batch(make_f, ys0.T, t_end, rt, at, h0, obs)
        nfev, nsteps, status, msgs = run.nfev, run.nsteps, run.status, run.messages
        obs.t_final[:] = run.t
        obs.y_final[:] = run.y.T
    return nfev, nsteps, status, msgs


def _health_at_dense_samples(obs: Health, P: mx.RigParams, L2, n: int) -> None:
    """The tension extremes and energy drift of ``obs`` taken at its kept
    dense samples too (``L2`` (n, B) the squared wire lengths, m^2)."""
    Bn = len(obs.samples)
    # tensions at the requested samples too (a finer resolution of the extremes)
    for b in range(Bn):
        if obs.samples[b]:
            ts_ = np.concatenate([p_[0] for p_ in obs.samples[b]])
            ys_ = np.concatenate([p_[1] for p_ in obs.samples[b]])
            out_ = mx.compiled_kernel(P.take(b), extras=True)(*ys_.T)
            lam_ = np.array(np.broadcast_arrays(*out_[13:13 + n]))
            phi_ = np.array(np.broadcast_arrays(*out_[13 + n:13 + 2 * n]))
            T_ = -lam_ * np.sqrt(L2[:, b:b + 1] + 2 * phi_)  # (n, k)
            obs.Tmin[b] = np.minimum(obs.Tmin[b], T_.min(axis=1))
            obs.Tmax[b] = np.maximum(obs.Tmax[b], T_.max(axis=1))
            merge_refined(obs, np.array([b]), *refine_extremes(ts_[:, None], T_[:, :, None]))
            # the energy at the samples too (dense output: interpolation error included)
            E_ = obs._energy(np.full(len(ts_), b), ys_.T)
            obs.dE[b] = max(obs.dE[b], float(np.max(np.abs(E_ - obs.E0[b]))))


def _single(P1: mx.RigParams, y0, t_end, rtol, atol, h0, obs: Health, on_slack: str):
    """One scene on Python floats; the observer is fed afterwards, in one
    vectorised pass over the accepted steps."""
    k = mx.compiled_kernel(P1, extras=True)
    n = int(P1.lengths.shape[-1])
    stop = None
    if on_slack == "stop":
        L2 = P1.lengths**2

        def stop(t, y, ext):
            lam = np.asarray(ext[:n])
            return bool(np.any(-lam * np.sqrt(L2 + 2.0 * np.asarray(ext[n:2 * n])) <= 0))

    run = itg.integrate_single(k, y0, t_end, rtol, atol, h0, stop=stop)
    idx0 = np.zeros(1, int)
    Y = run.y.T  # (13, k+1)
    obs.start(idx0, Y[:, :1], run.ext[:1].T)
    if len(run.t) > 1:
        # all steps at once: health over the steps; crossings located step by step
        ns = len(run.t) - 1
        idx = np.zeros(ns, int)
        e = obs.e[:, 0]
        c = e @ Y
        up = np.nonzero((c[:-1] < 0) & (c[1:] >= 0))[0]
        if obs.health:
            _single_health(obs, run, idx, idx0, Y, n, ns)
        if obs.lowest is not None:
            obs.lowest.add_states(idx, Y[:, 1:])
        steps = set(up.tolist())
        samp_step = None
        if obs.samples is not None:
            ts = obs.dense_times[0]
            ts = ts[(ts > 0) & (ts <= run.t[-1])]
            samp_step = np.clip(np.searchsorted(run.t, ts, side="left") - 1, 0, ns - 1)
            steps |= set(samp_step.tolist())
        for jstep in sorted(steps):
            F = run.dense(k, jstep)
            if jstep in up:
                Fc = (e @ F.reshape(7, 13).T)[:, None]
                x = itg.crossing_on_step(Fc, np.array([c[jstep]]), np.array([c[jstep + 1]]))
                obs.cross[0].append(float(run.t[jstep] + x[0] * (run.t[jstep + 1] - run.t[jstep])))
            if samp_step is not None:
                sel = ts[samp_step == jstep]
                if len(sel):
                    x = (sel - run.t[jstep]) / (run.t[jstep + 1] - run.t[jstep])
                    ys = itg.dense_eval(F[:, :, None], run.y[jstep][:, None], x[None, :]).T
                    obs.samples[0].append((sel, ys))
        obs.cross[0].sort()
    obs.t_final[0] = run.t[-1]
    obs.y_final[0] = run.y[-1]
    return run.nfev, len(run.t) - 1, run.status, run.message


def _single_health(obs: Health, run, idx, idx0, Y, n: int, ns: int) -> None:
    """Health over all accepted steps of a one-scene run at once."""
    E = obs._energy(idx, Y[:, 1:])
    obs.dE[0] = np.max(np.abs(E - obs.E0[0]))
    T, v = obs._tension_viol(idx, run.ext[1:].T)
    vk = v.max(axis=0)
    k = int(np.argmax(vk))
    if vk[k] > obs.viol[0]:  # the state of the largest error (Health.y_viol)
        obs.y_viol[0] = Y[:, 1 + k]
    obs.viol[0] = max(obs.viol[0], float(vk[k]))
    obs.Tmin[0] = np.minimum(obs.Tmin[0], T.min(axis=1))
    obs.Tmax[0] = np.maximum(obs.Tmax[0], T.max(axis=1))
    for i in range(n):
        neg = np.nonzero(T[i] <= 0)[0]
        if len(neg):
            obs.slack_t[0, i] = run.t[neg[0] + 1]
    T_all = obs._tension_viol(np.zeros(ns + 1, int), run.ext.T)[0]  # (n, k+1) including t = 0
    merge_refined(obs, idx0, *refine_extremes(run.t[:, None], T_all[:, :, None]))
