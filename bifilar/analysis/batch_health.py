"""Health of batched runs: the observer that gathers crossings, constraint
violation, energy drift, tension extremes and slack at the integrator's
steps (DOP853 engine) or samples (LSODA engine), and the lowest body point
as a running minimum (bounded memory however many scenes and steps).

Split from :mod:`bifilar.analysis.batch` (which calls it); SI units, world
frame z up.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .. import integrators as itg
from ..rowwise import row_max, row_sum
from ..scene import Scene


class LowestPoint:
    """Running minimum, per scene, of the world z of the lowest body point.

    States arrive in chunks (scene index, CoM world z, quaternion body ->
    world); they are buffered and folded into the minimum every ``limit``
    rows (default 2^18 rows, ~12 MB), so memory stays bounded for any batch
    size and run length.  A fold calls the body's support function
    (:meth:`~bifilar.scene.Scene.body_support`) once per distinct support
    function among the scenes (scenes copied from one scene share it) and
    takes the attachment points of all scenes at once.

    scenes : the batch; com0 : (B, 3) rest CoM, m (states given relative to
    it through :meth:`add_states`).  :attr:`z` (B,): the minimum so far, m
    (NaN for a scene with no state yet).
    """

    def __init__(self, scenes: Sequence[Scene], com0: np.ndarray, limit: int = 1 << 18):
        self.scenes = list(scenes)
        self.com0 = np.asarray(com0, float)
        self.limit = int(limit)
        self.att = np.array([s.attachments for s in self.scenes])  # (B, n, 3)
        groups: dict = {}
        for b, s in enumerate(self.scenes):
            if s.support is not None:
                groups.setdefault(id(s.support), (s.support, []))[1].append(b)
        # (f, its scenes' indices, whether they are all the batch's: every row then, without np.isin's search)
        self.groups = [(f, np.array(bs), len(bs) == len(self.scenes)) for f, bs in groups.values()]
        self._zmin = np.full(len(self.scenes), np.inf)
        self._buf: list = []
        self._rows = 0

    def add_states(self, idx: np.ndarray, y: np.ndarray) -> None:
        """States y (13, k) of scenes ``idx`` (k,), positions relative to the rest CoM."""
        idx = np.asarray(idx)
        self.add(idx, y[2] + self.com0[idx, 2], y[3:7].T)

    def add(self, idx: np.ndarray, z: np.ndarray, q: np.ndarray) -> None:
        """Scene indices (k,), CoM world z (k,) m, quaternions (k, 4)."""
        self._buf.append((np.array(idx, dtype=np.int32), np.array(z, float), np.array(q, float)))
        self._rows += len(idx)
        if self._rows >= self.limit:
            self.fold()

    def fold(self) -> None:
        """Fold the buffered states into the running minimum."""
        if not self._buf:
            return
        buf = self._buf
        self._buf, self._rows = [], 0
        if len(buf) == 1:  # (no concatenation copies)
            idx, z, q = buf[0]
        else:
            idx = np.concatenate([p[0] for p in buf])
            z = np.concatenate([p[1] for p in buf])
            q = np.concatenate([p[2] for p in buf])
        # q / |q| by columns: the values of q / np.linalg.norm(q, axis=-1, keepdims=True), without numpy's
        # reduction over a 4-long axis row by row (bifilar/rowwise.py)
        qw, qx, qy, qz = q.T
        nrm = np.sqrt(row_sum([qw * qw, qx * qx, qy * qy, qz * qz]))
        qw, qx, qy, qz = qw / nrm, qx / nrm, qy / nrm, qz / nrm
        # world -z in body axes: minus the third row of R (body -> world)
        down = -np.stack([2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)], -1)
        one = len(self.scenes) == 1  # one scene: its attachments broadcast, every row in its group (no gathers)
        att = np.broadcast_to(self.att[0], (len(idx),) + self.att.shape[1:]) if one else self.att[idx]
        # attachment points and the CoM (origin; in the hull of the mass: Scene.body_support)
        h = np.maximum(row_max(np.einsum("rnk,rk->rn", att, down)), 0.0)
        for f, bs, every in self.groups:
            if one or every:  # every row is this support function's (a sweep point's runs of one body)
                h = np.maximum(h, np.asarray(f(down), float))
                continue
            rows = np.nonzero(np.isin(idx, bs))[0]
            if len(rows):
                h[rows] = np.maximum(h[rows], np.asarray(f(down[rows]), float))
        if one:
            self._zmin[0] = np.minimum(self._zmin[0], np.min(z - h))  # (a NaN stays, as with minimum.at)
        else:
            np.minimum.at(self._zmin, idx, z - h)

    @property
    def z(self) -> np.ndarray:
        self.fold()
        return np.where(np.isfinite(self._zmin), self._zmin, np.nan)


class SharedLowestPoint:
    """Scenes ``rows`` of a :class:`LowestPoint` ``shared`` seen as a batch of
    their own (its index k is the shared batch's ``rows[k]``), for runs
    made a few at a time whose lowest points are folded together
    afterwards: one fold and one call of each support function for all of
    them (a sweep point's 2-3 runs of one body) instead of one a run.
    Every state is folded by the same expressions, row by row, so a run's
    minimum is what its own :class:`LowestPoint` gives
    (tests/test_run_cost.py).  :attr:`z` is NaN until the caller reads
    ``shared.z``."""

    def __init__(self, shared: LowestPoint, rows):
        self.shared, self.rows = shared, np.asarray(rows, int)

    def add_states(self, idx: np.ndarray, y: np.ndarray) -> None:
        self.shared.add_states(self.rows[np.asarray(idx)], y)

    def add(self, idx: np.ndarray, z: np.ndarray, q: np.ndarray) -> None:
        self.shared.add(self.rows[np.asarray(idx)], z, q)

    @property
    def z(self) -> np.ndarray:
        return np.full(len(self.rows), np.nan)


def refine_extremes(t: np.ndarray, T: np.ndarray):
    """Extremes of sampled tensions refined by the parabola through each
    interior local extremum and its two neighbours.

    t (K, B) sample times, T (n, K, B).  Returns (Tmin, tmin, Tmax) each
    (n, B) over the refined interior extremes (inf / nan where there are
    none).  A sampled extreme is off by ~(omega dt)^2 / 8 of the tension's
    swing; the vertex of the parabola by ~(omega dt)^3, which matters for a
    sharp dip near slack.
    """
    if T.shape[1] < 3:
        shape = (T.shape[0], T.shape[2])
        return np.full(shape, np.inf), np.full(shape, np.nan), np.full(shape, -np.inf)
    t0, t1, t2 = t[:-2], t[1:-1], t[2:]
    f0, f1, f2 = T[:, :-2], T[:, 1:-1], T[:, 2:]
    if T.shape[1] >= REFINE_SUBSET:
        return _refine_at_extrema(t0, t1, t2, f0, f1, f2)
    tv, fv, lo, hi = _vertices(t0, t1, t2, f0, f1, f2)
    vmin = np.where(lo, fv, np.inf)
    k = np.argmin(vmin, axis=1)  # (n, B)
    Tmin = np.take_along_axis(vmin, k[:, None, :], 1)[:, 0]
    tmin = np.take_along_axis(np.broadcast_to(tv, vmin.shape), k[:, None, :], 1)[:, 0]
    Tmax = np.max(np.where(hi, fv, -np.inf), axis=1)
    return Tmin, tmin, Tmax


REFINE_SUBSET = 256
"""From this many samples :func:`refine_extremes` fits its parabolas only at
the samples that are a local extremum (a few a period: the same values,
~1/3 of the cost on a long record; shorter ones, e.g. the DOP853 engine's
three steps, take every sample, which costs fewer numpy calls)."""


def _vertices(t0, t1, t2, f0, f1, f2):
    """(tv, fv, lo, hi): the vertex (time, value) of the parabola through
    (t0, f0), (t1, f1), (t2, f2), element by element, and whether it refines
    a local minimum (``lo``) or maximum (``hi``) at the middle sample: the
    middle one is the extreme of the three and the vertex lies between the
    outer two, beyond the middle value."""
    with np.errstate(all="ignore"):
        d0 = (f1 - f0) / (t1 - t0)
        d1 = (f2 - f1) / (t2 - t1)
        a = (d1 - d0) / (t2 - t0)
        b = d0 + a * (t1 - t0)
        tv = t1 - b / (2 * a)
        fv = f1 - b * b / (4 * a)
    inside = (tv >= t0) & (tv <= t2) & np.isfinite(fv)
    lo = (f1 <= f0) & (f1 <= f2) & inside & (fv <= f1)
    hi = (f1 >= f0) & (f1 >= f2) & inside & (fv >= f1)
    return tv, fv, lo, hi


def _refine_at_extrema(t0, t1, t2, f0, f1, f2):
    """:func:`refine_extremes`' result from the parabolas of the local extrema
    only (each vertex by the same expressions, element by element; ``tmin``
    is NaN, not a vertex time, where a wire has no refined minimum: no
    caller reads it there)."""
    ext = ((f1 <= f0) & (f1 <= f2)) | ((f1 >= f0) & (f1 >= f2))
    i, k, b = np.nonzero(ext)
    tv, fv, lo, hi = _vertices(t0[k, b], t1[k, b], t2[k, b], f0[i, k, b], f1[i, k, b], f2[i, k, b])
    vmin = np.full(f1.shape, np.inf)
    vmin[i[lo], k[lo], b[lo]] = fv[lo]
    tvs = np.full(f1.shape, np.nan)
    tvs[i[lo], k[lo], b[lo]] = tv[lo]
    vmax = np.full(f1.shape, -np.inf)
    vmax[i[hi], k[hi], b[hi]] = fv[hi]
    kk = np.argmin(vmin, axis=1)  # (n, B)
    Tmin = np.take_along_axis(vmin, kk[:, None, :], 1)[:, 0]
    tmin = np.take_along_axis(tvs, kk[:, None, :], 1)[:, 0]
    return Tmin, tmin, np.max(vmax, axis=1)


def merge_refined(obs, idx, Tmin, tmin, Tmax, T_scale=1.0) -> None:
    """Fold refined extremes (n, k) for scenes ``idx`` into the observer.
    A wire's slack time is the earliest evidence: a sample or step at or
    below zero, or the vertex of a refined dip below zero."""
    obs.Tmin[idx] = np.minimum(obs.Tmin[idx], Tmin.T)
    obs.Tmax[idx] = np.maximum(obs.Tmax[idx], Tmax.T)
    neg = Tmin.T <= 0
    if np.any(neg):
        st = obs.slack_t[idx]
        tv = (tmin.T * T_scale) if np.ndim(T_scale) == 0 else (tmin.T * T_scale[:, None])
        st[neg] = np.fmin(st[neg], tv[neg])
        obs.slack_t[idx] = st


class Health(itg.BatchObserver):
    """Per-scene crossings, constraint violation, energy, tensions, slack and
    the lowest point (a running minimum, :class:`LowestPoint`), gathered while
    the batch integrates.  ``health=False``: only the crossings and samples
    (and the tensions when ``on_slack == "stop"`` needs them); the health
    figures stay NaN."""

    def __init__(self, Bn, n, e, mass, grav, inertia, L2, on_slack: str, lowest: "LowestPoint | None", progress,
                 t_end, dense_times=None, health: bool = True, refine_steps: bool = True):
        self.n = n
        self.refine_steps = refine_steps  # False: extremes refined on the dense samples only
        self.e = e  # (13, B)
        self.mass, self.grav, self.inertia, self.L2 = mass, grav, inertia, L2
        self.cross: list[list] = [[] for _ in range(Bn)]
        self.health = health
        self.viol = np.zeros(Bn) if health else np.full(Bn, np.nan)
        self.E0 = np.zeros(Bn) if health else np.full(Bn, np.nan)
        self.dE = np.zeros(Bn) if health else np.full(Bn, np.nan)
        self.Tmin = np.full((Bn, n), np.inf if health else np.nan)
        self.Tmax = np.full((Bn, n), -np.inf if health else np.nan)
        self.slack_t = np.full((Bn, n), np.nan)
        self.stop_on_slack = on_slack == "stop"
        self.lowest = lowest
        self.progress = progress
        self.t_end = t_end
        self.tnow = np.zeros(Bn)
        self.dense_times = dense_times  # list of (B) arrays of sample times, or None
        self.next_k = np.zeros(Bn, int)  # index of each scene's next unused sample
        self.samples: list = [[] for _ in range(Bn)] if dense_times is not None else None
        self.sample_tensions: list | None = None  # per scene, the kept samples' physical tensions (LSODA, one scene)
        self.t_final = np.zeros(Bn)
        self.y_final = np.zeros((Bn, 13))
        # the state (relative to the rest CoM) where each scene's constraint violation was largest: what its
        # violation warning looks at where the run keeps no samples (a sweep's), not only the last state
        self.y_viol = np.zeros((Bn, 13))

    def _energy(self, idx, y):
        v = y[7:10]
        w = y[10:13]
        Iw = np.einsum("bij,jb->ib", self.inertia[idx], w)
        return 0.5 * self.mass[idx] * np.sum(v * v, 0) + 0.5 * np.sum(w * Iw, 0) + self.mass[idx] * self.grav[idx] * y[2]

    def _tension_viol(self, idx, ext):
        n = self.n
        lam, phi = ext[:n], ext[n:2 * n]
        L2 = self.L2[:, idx]
        dl = np.sqrt(L2 + 2.0 * phi)
        return -lam * dl, np.abs(2.0 * phi / (dl + np.sqrt(L2)))

    def _next_sample(self) -> np.ndarray:
        """(B,) time of each scene's next sample not yet taken (inf when done)."""
        return np.array([ts[k] if k < len(ts) else np.inf for ts, k in zip(self.dense_times, self.next_k)])

    def start(self, idx, y, ext):
        Bn = len(self.E0)
        if self.health:
            self.E0[idx] = self._energy(idx, y)
            T, v = self._tension_viol(idx, ext)
            self.Tmin[idx] = T.T
            self.Tmax[idx] = T.T
            self.prev_t = np.full((2, Bn), np.nan)
            self.prev_T = np.full((self.n, 2, Bn), np.nan)
            self.prev_t[1, idx] = 0.0
            self.prev_T[:, 1, idx] = T
            self.viol[idx] = v.max(axis=0)
            self.y_viol[idx] = y.T
        if self.lowest is not None:
            self.lowest.add_states(idx, y)
        if self.samples is not None:
            for k, b in enumerate(idx):
                if self.dense_times[b][0] == 0.0:
                    self.samples[b].append((np.zeros(1), y[:, k][None, :].copy()))
                    self.next_k[b] = 1

    def accepted(self, idx, t_old, t_new, y_old, y_new, ext_new, dense):
        T = self._step_health(idx, t_new, y_new, ext_new) if self.health else None
        if self.lowest is not None:
            self.lowest.add_states(idx, y_new)
        self._crossings_and_samples(idx, t_old, t_new, y_old, y_new, dense)
        self.tnow[idx] = t_new
        if self.progress is not None:
            self.progress(float(np.mean(np.minimum(self.tnow / self.t_end, 1.0))), 1.0)
        if self.stop_on_slack:
            if T is None:
                T = self._tension_viol(idx, ext_new)[0]
            return np.any(T <= 0, axis=0)
        return None

    def _step_health(self, idx, t_new, y_new, ext_new):
        """Energy, tensions (returned, (n, k) N), violation, slack and refined extremes at an accepted step."""
        E = self._energy(idx, y_new)
        self.dE[idx] = np.maximum(self.dE[idx], np.abs(E - self.E0[idx]))
        T, v = self._tension_viol(idx, ext_new)
        vmax = v.max(axis=0)
        larger = vmax > self.viol[idx]
        if larger.any():
            self.y_viol[idx[larger]] = y_new[:, larger].T
        self.viol[idx] = np.maximum(self.viol[idx], vmax)
        self.Tmin[idx] = np.minimum(self.Tmin[idx], T.T)
        self.Tmax[idx] = np.maximum(self.Tmax[idx], T.T)
        neg = T.T <= 0
        if np.any(neg):
            st = self.slack_t[idx]
            st[neg] = np.fmin(st[neg], np.broadcast_to(t_new[:, None], st.shape)[neg])
            self.slack_t[idx] = st
        # refine the extremes on the last three steps (parabola through them)
        tt = np.stack([self.prev_t[0, idx], self.prev_t[1, idx], t_new])
        TT = np.concatenate([self.prev_T[:, :, idx], T[:, None, :]], axis=1)
        if self.refine_steps and np.all(np.isfinite(tt[0])):
            merge_refined(self, idx, *refine_extremes(tt, TT))
        self.prev_t[0, idx] = self.prev_t[1, idx]
        self.prev_t[1, idx] = t_new
        self.prev_T[:, 0, idx] = self.prev_T[:, 1, idx]
        self.prev_T[:, 1, idx] = T
        return T

    def _crossings_and_samples(self, idx, t_old, t_new, y_old, y_new, dense):
        e = self.e[:, idx]
        c_old = itg.ordered_sum(e * y_old)  # in order: a scene's bits whatever its batch
        c_new = itg.ordered_sum(e * y_new)
        up = np.nonzero((c_old < 0) & (c_new >= 0))[0]
        need = up
        if self.samples is not None:
            has = self._next_sample()[idx] <= t_new  # the next unused sample time falls in this step
            need = np.union1d(up, np.nonzero(has)[0])
        if len(need):
            F = dense(need)
            pos = {int(j): k for k, j in enumerate(need)}
            if len(up):
                cols = [pos[int(j)] for j in up]
                Fc = itg.ordered_sum(np.swapaxes(F[:, :, cols] * e[None, :, up], 0, 1))  # (7, j)
                x = itg.crossing_on_step(Fc, c_old[up], c_new[up])
                tc = t_old[up] + x * (t_new[up] - t_old[up])
                for b, tt in zip(idx[up], tc):
                    self.cross[b].append(float(tt))
            if self.samples is not None:
                for j in need:
                    b = idx[j]
                    ts = self.dense_times[b]
                    sel = ts[(ts > t_old[j]) & (ts <= t_new[j])]
                    self.next_k[b] = int(np.searchsorted(ts, t_new[j], side="right"))
                    if len(sel):
                        x = (sel - t_old[j]) / (t_new[j] - t_old[j])
                        Fj = F[:, :, pos[int(j)]]
                        ys = itg.dense_eval(Fj[:, :, None], y_old[:, j][:, None], x[None, :]).T
                        self.samples[b].append((sel, ys))


def _stacked(cols) -> np.ndarray:
    """The kernel's outputs ``cols`` (arrays of one shape, or constants among
    them) as one array (len(cols), ...): ``np.array(np.broadcast_arrays(*cols))``,
    without broadcasting when every output is already an array of that shape."""
    shape = np.shape(cols[0])
    if all(type(c) is np.ndarray and c.shape == shape for c in cols):
        return np.array(cols)
    return np.array(np.broadcast_arrays(*cols))


_OFF_DIAGONAL = ([0, 0, 1, 1, 2, 2], [1, 2, 0, 2, 0, 1])


def _sample_energy(obs: Health, Yb, comps) -> np.ndarray:
    """Energy (kb, B), J, of states ``Yb`` (kb, B, 13) relative to the rest
    CoM, from their contiguous component rows ``comps`` (13 arrays (kb,) for
    one scene, else (kb, B)): the values of ``0.5 m |v|^2 + 0.5 w . (I w)
    + m g z`` with ``I w`` by :func:`numpy.einsum` and the sums over the
    3-long axis in numpy's order (bifilar/rowwise.py), without numpy's
    row-by-row reductions over that axis (~40 % of the samples' health;
    docs/design.md, "Session 14, perf16").  Principal body axes (every scene's
    off-diagonal products exactly 0): ``I w`` by component (the einsum's
    zero terms add nothing); else the einsum on the states."""
    kb, Bn = Yb.shape[:2]
    vx, vy, vz, wx, wy, wz = comps[7:13]
    inertia = obs.inertia
    if not np.any(inertia[:, _OFF_DIAGONAL[0], _OFF_DIAGONAL[1]]):
        rot = row_sum([wx * (inertia[:, 0, 0] * wx), wy * (inertia[:, 1, 1] * wy), wz * (inertia[:, 2, 2] * wz)])
    else:
        w = Yb[:, :, 10:13]
        rot = np.sum(w * np.einsum("bij,kbj->kbi", inertia, w), -1).reshape(np.shape(wx))
    E = 0.5 * obs.mass * row_sum([vx * vx, vy * vy, vz * vz]) + 0.5 * rot + obs.mass * obs.grav * comps[2]
    return E.reshape(kb, Bn)


def sample_health(Ys, tt, obs: Health, kx, n, com0, T_ref, stop_tau, on_slack, first, physical: bool = False):
    """Health figures at the samples of one window of the LSODA engine
    (blocks of ~50k values): Ys (k, B, 13) states relative to the rest CoM
    ``com0`` (B, 3), tt (k,) normalised times, ``kx`` the compiled kernel
    with extras; the lowest point into ``obs.lowest`` if it is set.
    ``physical``: ``kx`` also gives the unstabilised multipliers
    (``compiled_kernel(..., physical=True)``) and the physical tensions at
    the samples, (n, k, B) N, are returned (what
    :func:`~bifilar.models.maximal.tensions` gives, from the same kernel
    pass as the health's); else None."""
    K, Bn, _ = Ys.shape
    blk = max(1, int(5e4 // max(Bn, 1)))
    phys = []
    for s0 in range(0, K, blk):
        Yb = Ys[s0:s0 + blk]  # (kb, B, 13)
        tb = tt[s0:s0 + blk]
        valid = tb[:, None] <= stop_tau[None, :] + 1e-12  # (kb, B)
        comps = list(np.ascontiguousarray(np.moveaxis(Yb, -1, 0)))  # contiguous rows: a faster kernel
        if Bn == 1:
            comps = [cmp[:, 0] for cmp in comps]
        out = kx(*comps)
        lam = _stacked(out[13:13 + n]).reshape(n, len(tb), Bn)
        phi = _stacked(out[13 + n:13 + 2 * n]).reshape(n, len(tb), Bn)
        L2 = obs.L2[:, None, :]
        dl = np.sqrt(L2 + 2.0 * phi)
        T = -lam * dl  # (n, kb, B)
        if physical:
            phys.append(-_stacked(out[13 + 2 * n:13 + 3 * n]).reshape(n, len(tb), Bn) * dl)
        viol = np.abs(2.0 * phi / (dl + np.sqrt(L2)))
        if on_slack == "stop":
            slack_now = np.any(T <= 0, axis=0) & valid  # (kb, B)
            if np.any(slack_now):
                kfirst = np.where(np.any(slack_now, axis=0), np.argmax(slack_now, axis=0), -1)
                for b in np.nonzero(kfirst >= 0)[0]:
                    stop_tau[b] = min(stop_tau[b], tb[kfirst[b]])
                valid = tb[:, None] <= stop_tau[None, :] + 1e-12
        every = bool(valid.all())  # (no run stopped in this block: the masks below change nothing)
        vT = T if every else np.where(valid[None], T, np.nan)
        if len(tb) >= 3:
            rmin, rt_, rmax = refine_extremes(np.broadcast_to(tb[:, None], valid.shape), vT)
            merge_refined(obs, np.arange(Bn), np.where(np.isfinite(rmin), rmin, np.inf), rt_,
                           np.where(np.isfinite(rmax), rmax, -np.inf), T_ref)
        # extremes ignoring NaN (masked samples): fmin / fmax reductions, what nanmin / nanmax give, without
        # their copies
        with np.errstate(all="ignore"):
            obs.Tmin = np.fmin(obs.Tmin, np.fmin.reduce(vT, axis=1).T) if np.any(valid) else obs.Tmin
            obs.Tmax = np.fmax(obs.Tmax, np.fmax.reduce(vT, axis=1).T) if np.any(valid) else obs.Tmax
            vk = np.fmax.reduce(viol if every else np.where(valid[None], viol, np.nan), axis=0)  # (kb, B)
            vb = np.fmax.reduce(vk, axis=0)
            larger = np.nonzero(vb > obs.viol)[0]  # (none where NaN: no valid sample)
            if len(larger):  # the state of the largest error (Health.y_viol)
                obs.y_viol[larger] = Yb[np.nanargmax(vk[:, larger], axis=0), larger]
            obs.viol = np.fmax(obs.viol, vb)
        neg = (T <= 0) & valid[None]
        if np.any(neg):
            for i, kk, b in zip(*np.nonzero(neg)):
                obs.slack_t[b, i] = np.fmin(obs.slack_t[b, i], tb[kk] * T_ref[b])
        # energy relative to the rest pose (positions are relative to the rest CoM)
        E = _sample_energy(obs, Yb, comps)
        if first and s0 == 0:
            obs.E0 = E[0].copy()
        dE = np.abs(E - obs.E0)
        obs.dE = np.fmax(obs.dE, np.fmax.reduce(dE if every else np.where(valid, dE, np.nan), axis=0))
        if obs.lowest is not None:
            if every:  # every sample, in np.nonzero(valid)'s order, without its gathers
                kb = len(tb)
                obs.lowest.add(np.tile(np.arange(Bn), kb), (Yb[:, :, 2] + com0[:, 2]).reshape(-1),
                               Yb[:, :, 3:7].reshape(kb * Bn, 4))
            else:
                kk, bb = np.nonzero(valid)
                obs.lowest.add(bb, Yb[kk, bb, 2] + com0[bb, 2], Yb[kk, bb, 3:7])
    if physical:
        return phys[0] if len(phys) == 1 else np.concatenate(phys, axis=1) if phys else np.zeros((n, 0, Bn))
    return None
