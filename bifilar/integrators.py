"""The project's own explicit Runge-Kutta integrator: DOP853 without the overhead.

Hairer's DOP853 (order 8, error estimators of orders 5 and 3, dense output of
order 7), with the coefficients and the step-size control of
:class:`scipy.integrate.DOP853` (safety 0.9, step factor in [0.2, 10], the
combined 5/3 error norm, root-mean-square over the components), in two
drivers:

* :func:`integrate_single` for one system whose right-hand side takes and
  returns Python floats (the compiled kernel of :mod:`bifilar.models.maximal`):
  stages are combined with one BLAS call each and nothing else is done per
  stage, which removes the per-step overhead of ``solve_ivp`` (several times
  the cost of a compiled right-hand side);
* :func:`integrate_batch` for many independent systems at once, the state
  stored component-major ``(m, B)`` so that the right-hand side works on
  contiguous rows; every system has its *own* step size, error test and end
  time (a rejected step is retried only where it failed), systems that finish
  drop out of the arrays, and an observer sees every accepted step.

Both accept the same tolerances as ``solve_ivp`` (``rtol`` scalar, ``atol``
per component) and take the same steps as scipy's DOP853 for the same
initial step, so their accuracy is scipy's (checked in the tests).
:func:`dense_coefficients` / :func:`dense_eval` give the order-7 continuous
extension on any accepted step (three extra evaluations, paid only where it
is asked for) and :func:`crossing_on_step` the time where a linear functional
``e . y`` of the interpolant crosses zero; :func:`sampled_crossings` does the
same for uniformly sampled signals (degree-7 local interpolation) and
:func:`poly_root_unit` is the vectorised safeguarded Newton solver both use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as _dc

N_STAGES = 12
A = _dc.A  # (16, 16): rows 0..11 the method, 12 = B, 13..15 the dense-output stages
B = _dc.B
C = _dc.C
E3 = _dc.E3
E5 = _dc.E5
D = _dc.D
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EXPONENT = -1.0 / 8.0  # error estimator of order 7


def ordered_sum(X: np.ndarray) -> np.ndarray:
    """Sum over the first axis of ``X``, term by term in order: the same
    bits for a column whatever the other columns or their number
    (``np.sum(X, 0)`` switches to a pairwise, unrolled order when the
    other axes have length 1)."""
    out = np.array(X[0], float, copy=True)
    for i in range(1, len(X)):
        out += X[i]
    return out


def _combine(c: np.ndarray, Kf: np.ndarray) -> np.ndarray:
    """``c @ Kf`` for stage coefficients ``c`` (s,) or (r, s) and stages ``Kf``
    (s, N), summed term by term in stage order: every column gets the same
    operations in the same order, so a system's bits do not depend on its
    column or on the batch's other systems (a BLAS product's do: its
    kernels treat a block of columns and the tail differently, with or
    without fused multiply-adds; tests/test_batch_determinism.py)."""
    c = np.asarray(c, float)
    if c.ndim == 2:  # all rows at once, each entry the 1-D sum's operations in its order (no BLAS)
        out = c[:, :1] * Kf[0]
        for i in range(1, c.shape[1]):
            out += c[:, i:i + 1] * Kf[i]
        return out
    out = c[0] * Kf[0]
    for i in range(1, len(c)):
        out += c[i] * Kf[i]
    return out


def _error_norm(K13: np.ndarray, h, scale: np.ndarray, m: int):
    """scipy's DOP853 error norm; K13 (13, m, ...) stages, scale (m, ...)."""
    s = K13.shape[0]
    Kf = K13.reshape(s, -1)
    e5 = _combine(E5, Kf).reshape(scale.shape) / scale
    e3 = _combine(E3, Kf).reshape(scale.shape) / scale
    n5 = ordered_sum(e5 * e5)
    n3 = ordered_sum(e3 * e3)
    den = n5 + 0.01 * n3
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.abs(h) * n5 / np.sqrt(den * m)
    return np.where(den > 0, out, 0.0)


def dense_coefficients(f: Callable, K: np.ndarray, y_old: np.ndarray, y_new: np.ndarray, h) -> np.ndarray:
    """Coefficients F (7, m, ...) of the order-7 interpolant on one step.

    ``K`` (13, m, ...) the stages of the accepted step (row 0 = f(y_old),
    row 12 = f(y_new)), ``h`` the step (scalar or per system), ``f(*rows)``
    the right-hand side (3 extra evaluations).  See :func:`dense_eval`.
    """
    m = y_old.shape[0]
    Kx = np.empty((16,) + K.shape[1:])
    Kx[:13] = K
    for s in range(13, 16):
        dy = _combine(A[s, :s], Kx[:s].reshape(s, -1)).reshape(y_old.shape)
        Kx[s] = np.asarray(f(*(y_old + h * dy))[:m], dtype=float).reshape(y_old.shape)
    dlt = y_new - y_old
    F = np.empty((7,) + y_old.shape)
    F[0] = dlt
    F[1] = h * K[0] - dlt
    F[2] = 2.0 * dlt - h * (K[12] + K[0])
    F[3:] = h * _combine(D, Kx.reshape(16, -1)).reshape((4,) + y_old.shape)
    return F


def dense_eval(F: np.ndarray, y_old: np.ndarray, x) -> np.ndarray:
    """Interpolant at the fraction ``x`` in [0, 1] of the step (broadcasts
    against the trailing shape of ``F[0]``)."""
    y = np.zeros(np.broadcast_shapes(F.shape[1:], np.shape(x)))
    for i, fi in enumerate(F[::-1]):
        y = y + fi
        y = y * (x if i % 2 == 0 else 1.0 - x)
    return y + y_old


def _monomial(Fc: np.ndarray) -> np.ndarray:
    """Ascending power coefficients (8, k) of the nested interpolant form
    (without the ``y_old`` term) of :func:`dense_eval`."""
    P = np.zeros((8,) + Fc.shape[1:])
    for i, fi in enumerate(Fc[::-1]):
        P[0] = P[0] + fi
        if i % 2 == 0:  # times x
            P[1:] = P[:-1].copy()
            P[0] = 0.0
        else:  # times (1 - x)
            sh = np.zeros_like(P)
            sh[1:] = P[:-1]
            P = P - sh
    return P


def crossing_on_step(Fc: np.ndarray, c_old: np.ndarray, c_new: np.ndarray, iters: int = 30) -> np.ndarray:
    """Fractions x in (0, 1] where the interpolated scalar ``c`` crosses zero.

    ``Fc`` (7, k): the dense coefficients of ``c = e . y`` (``e @ F``),
    ``c_old < 0 <= c_new`` (k,).  See :func:`poly_root_unit`.
    """
    c_old = np.asarray(c_old, float)
    P = _monomial(np.asarray(Fc, float))
    P[0] = P[0] + c_old
    return poly_root_unit(P, c_old, np.asarray(c_new, float), iters)


def poly_root_unit(P: np.ndarray, v0: np.ndarray, v1: np.ndarray, iters: int = 30) -> np.ndarray:
    """Root x in [0, 1] of the polynomials with ascending coefficients P
    (d+1, k), which change sign from ``v0 = p(0) < 0`` to ``v1 = p(1) >= 0``.

    Newton's method from the secant guess, kept inside the shrinking bracket
    (bisection when a step leaves it), to |dx| < 1e-15; vectorised over k.
    (An oscillation resolved by ~10 or more points per period is monotone
    between two neighbouring points at a crossing, so the root is unique.)
    """
    d = P.shape[0] - 1
    dP = P[1:] * np.arange(1, d + 1)[:, None]
    if P.shape[1] <= SCALAR_ROOTS:
        # each root's coefficients as lists of floats in one tolist a matrix (not two a root)
        return np.array([_root_unit_scalar(p, dp, a, b, iters) for p, dp, a, b in
                         zip(P.T.tolist(), dP.T.tolist(), np.asarray(v0, float).tolist(), np.asarray(v1, float).tolist())],
                        float)
    a = np.zeros(P.shape[1])
    b = np.ones(P.shape[1])
    den = v1 - v0
    x = np.clip(np.where(den != 0, -v0 / np.where(den != 0, den, 1.0), 0.5), 0.0, 1.0)
    live = np.ones(len(x), bool)  # each root stops on its own test: its bits do not depend on the others'
    for _ in range(iters):
        v = np.zeros_like(x)
        for cf in P[::-1]:
            v = v * x + cf
        dv = np.zeros_like(x)
        for cf in dP[::-1]:
            dv = dv * x + cf
        a = np.where(v < 0, x, a)
        b = np.where(v >= 0, x, b)
        with np.errstate(divide="ignore", invalid="ignore"):
            xn = x - v / dv
        out = ~np.isfinite(xn) | (xn < a) | (xn > b)
        xn = np.where(out, 0.5 * (a + b), xn)
        dx = np.abs(xn - x)
        x = np.where(live, xn, x)
        live &= ~((dx < 1e-15) | (v == 0))
        if not np.any(live):
            break
    return x


SCALAR_ROOTS = 28
"""Up to this many roots :func:`poly_root_unit` iterates on Python floats,
root by root (:func:`_root_unit_scalar`): the same IEEE operations in the
same order as the vectorised iteration (a root's bits do not depend on the
path), without ~15 numpy calls an iteration on a few elements (a sweep
point's 2-3 runs of 3 periods have ~6-10 crossings, its 6 law runs on the
Solar Boat 18).  Measured on a boat point's roots (session 26, perf26a):
vectorised ~100 us whatever the count from 9 to 54, floats ~3.4 us a root
(9: 34 / 34 us, 18: 101 / 62, 36: 102 / 119): break-even ~30."""


def _root_unit_scalar(p: list, dp: list, v0: float, v1: float, iters: int) -> float:
    """One root of :func:`poly_root_unit` on floats: ``p`` ascending
    coefficients, ``dp`` those of its derivative, ``v0 = p(0) < 0 <= v1 = p(1)``."""
    a, b = 0.0, 1.0
    den = v1 - v0
    x = min(max(-v0 / den if den != 0 else 0.5, 0.0), 1.0)
    inf = float("inf")
    seven = len(p) == 8  # sampled_crossings' degree: Horner's steps written out (no loop), the same operations
    if seven:
        p0, p1, p2, p3, p4, p5, p6, p7 = p
        d0, d1, d2, d3, d4, d5, d6 = dp
    for _ in range(iters):
        if seven:
            v = ((((((((0.0 * x + p7) * x + p6) * x + p5) * x + p4) * x + p3) * x + p2) * x + p1) * x + p0)
            dv = (((((((0.0 * x + d6) * x + d5) * x + d4) * x + d3) * x + d2) * x + d1) * x + d0)
        else:
            v = 0.0
            for cf in reversed(p):
                v = v * x + cf
            dv = 0.0
            for cf in reversed(dp):
                dv = dv * x + cf
        if v < 0:
            a = x
        if v >= 0:
            b = x
        if dv != 0:
            xn = x - v / dv
        else:  # numpy's x - v / 0: -+inf, or NaN for 0 / 0
            xn = x - (v * inf if v != 0 else float("nan"))
        if not math.isfinite(xn) or xn < a or xn > b:
            xn = 0.5 * (a + b)
        dx = abs(xn - x)
        x = xn
        if dx < 1e-15 or v == 0:
            break
    return x


# Lagrange interpolation of uniformly spaced samples: the degree-7 polynomial
# through the samples at offsets -3..4 (in sample spacings) from a sign change
# between offsets 0 and 1, in ascending powers of the offset.
_STENCIL = np.arange(-3, 5)
_VINV = np.linalg.inv(np.vander(_STENCIL.astype(float), 8, increasing=True))


def sampled_crossings(c: np.ndarray, dt: float | np.ndarray = 1.0):
    """Upward zero crossings of uniformly sampled signals, located on the
    degree-7 interpolating polynomial of the 8 samples around each.

    c : (K, B) B signals at K equally spaced samples (spacing ``dt``, a
    scalar or (B,)).  Returns (col, t, k) arrays: column index, time
    (``(k + x) dt`` from the first sample) and left sample k of each
    crossing ``c[k] < 0 <= c[k+1]``, sorted by column then time.  With ~64 samples per period of a
    smooth oscillation the interpolation error is ~1e-12 of a period
    (error ~ (omega dt)^8 / 8! times a stencil factor ~40); records shorter
    than 8 samples fall back to linear interpolation.
    """
    c = np.asarray(c, float)
    K, Bn = c.shape
    dtb = np.broadcast_to(np.asarray(dt, float), (Bn,))
    kk, bb = np.nonzero((c[:-1] < 0) & (c[1:] >= 0))
    v0, v1 = c[kk, bb], c[kk + 1, bb]
    if K < 8:
        den = v1 - v0
        x = -v0 / np.where(den != 0, den, 1.0)
    else:
        start = np.clip(kk - 3, 0, K - 8)  # stencil start, shifted inside the record
        off = kk - start  # 3 unless shifted at an end of the record
        S = c[start[None, :] + np.arange(8)[:, None], bb[None, :]]  # (8, k)
        P = _combine(_VINV, S)  # powers of (index - k) when off == 3
        edge = np.nonzero(off != 3)[0]
        if len(edge):
            for j in edge:  # powers of (index - start) shifted to powers of (index - k)
                P[:, j] = _shift_poly(_V0INV @ S[:, j], float(off[j]))
        x = poly_root_unit(P, v0, v1)
    t = (kk + x) * dtb[bb]
    order = np.lexsort((t, bb))
    return bb[order], t[order], kk[order]


_V0INV = np.linalg.inv(np.vander(np.arange(8.0), 8, increasing=True))


def crossing_interpolation_error(c: np.ndarray, k: np.ndarray, dt: float = 1.0) -> np.ndarray:
    """Estimated error of the crossings :func:`sampled_crossings` locates in
    one uniformly sampled signal ``c`` (K,): for each left sample ``k``
    (``c[k] < 0 <= c[k+1]``), the larger difference between the root on the
    stencil :func:`sampled_crossings` uses and the roots on the stencils
    shifted by one sample either way (as far as the record allows), times
    ``dt`` (the sample spacing; the result in its units).  Each stencil's
    root is off the true crossing by about as much as the others (the
    degree-7 interpolation's error, ~(omega dt)^8 of the signal's highest
    harmonics), so the difference measures it: on strongly anharmonic runs
    (a double pendulum's roll at 0.3 rad, harmonics to 20 times the
    fundamental) it was 2-4 times the true error of each crossing
    (docs/design.md, "Forward-model and CLI audit, session 12").  Records of
    fewer than 9 samples: NaN."""
    c = np.asarray(c, float)
    k = np.atleast_1d(np.asarray(k, int))
    K = len(c)
    out = np.full(len(k), np.nan)
    if K < 9:
        return out

    def root(kk: int, start: int) -> float:
        P = _shift_poly(_V0INV @ c[start:start + 8], float(kk - start))
        return float(poly_root_unit(P[:, None], c[kk:kk + 1], c[kk + 1:kk + 2])[0])

    for j, kk in enumerate(k):
        if not (0 <= kk < K - 1 and c[kk] < 0 <= c[kk + 1]):
            continue
        s0 = int(np.clip(kk - 3, 0, K - 8))
        x0 = root(kk, s0)
        alt = {int(np.clip(s0 + d, 0, K - 8)) for d in (-1, 1)} - {s0}
        out[j] = max(abs(root(kk, s) - x0) for s in alt) * dt
    return out


def _shift_poly(p: np.ndarray, s: float) -> np.ndarray:
    """Coefficients of q(x) = p(x + s) (ascending powers)."""
    from math import comb

    d = len(p)
    q = np.zeros(d)
    for i in range(d):
        for j in range(i + 1):
            q[j] += p[i] * comb(i, j) * s ** (i - j)
    return q


@dataclass
class SingleRun:
    """Accepted steps of :func:`integrate_single` (SI units as the system's).

    t (k+1,), y (k+1, m), ext (k+1, e) the right-hand side's extra outputs
    at the steps, K (k, 13, m) the stages of each step (for dense output),
    nfev, nrejected.
    """

    t: np.ndarray
    y: np.ndarray
    ext: np.ndarray
    K: np.ndarray
    nfev: int
    nrejected: int
    status: int = 0
    message: str = ""

    def dense(self, f: Callable, j: int) -> np.ndarray:
        """Dense coefficients (7, m) on step j (from t[j] to t[j+1])."""
        h = self.t[j + 1] - self.t[j]
        return dense_coefficients(f, self.K[j], self.y[j], self.y[j + 1], h)


def integrate_single(f: Callable, y0, t_end: float, rtol: float, atol, h0: float, m: int = 13,
                     max_steps: int = 10**6, stop: Callable | None = None) -> SingleRun:
    """DOP853 on one system ``y' = f(*y)`` from t = 0 to ``t_end``.

    ``f`` takes the m components as Python floats and returns a tuple whose
    first m entries are the derivatives (further entries, e.g. multipliers,
    are kept as ``ext``).  ``atol`` scalar or (m,); ``h0`` first step.
    ``stop(t, y, ext) -> bool`` ends the run after an accepted step.
    """
    y = np.array(y0, dtype=float)
    atol = np.broadcast_to(np.asarray(atol, float), (m,))
    out = f(*y.tolist())
    ne = len(out) - m
    K = np.empty((13, m))
    K[0] = out[:m]
    ts, ys, es, Ks = [0.0], [y.copy()], [out[m:]], []
    t = 0.0
    h = float(h0)
    nfev, nrej = 1, 0
    A12 = np.ascontiguousarray(A[:N_STAGES, :N_STAGES])
    Kv = [K[:s] for s in range(14)]
    EE = np.stack([E5, E3])  # both error estimators in one product
    dot = np.dot
    sqrt = np.sqrt
    status, message = 0, ""
    tiny = 1e-14 * max(t_end, 1.0)
    while t < t_end:
        if len(Ks) >= max_steps:
            status, message = -1, f"more than {max_steps} steps"
            break
        rejected = False
        while True:
            hs = min(h, t_end - t)
            hA = hs * A12
            for s in range(1, N_STAGES):
                K[s] = f(*(dot(hA[s, :s], Kv[s]) + y).tolist())[:m]
            y_new = dot(hs * B, Kv[12]) + y
            out = f(*y_new.tolist())
            K[12] = out[:m]
            nfev += 12
            ee = dot(EE, K) / (atol + rtol * np.maximum(np.abs(y), np.abs(y_new)))
            n5, n3 = (ee * ee).sum(axis=1).tolist()
            den = n5 + 0.01 * n3
            err = hs * n5 / sqrt(den * m) if den > 0 else 0.0
            if not err < 1e300:  # nan or inf: reject hard
                err = 1e300
            if err < 1.0:
                fac = MAX_FACTOR if err == 0 else min(MAX_FACTOR, SAFETY * err**EXPONENT)
                if rejected:
                    fac = min(1.0, fac)
                h = hs * fac
                break
            nrej += 1
            rejected = True
            h = hs * max(MIN_FACTOR, SAFETY * err**EXPONENT)
            if h < tiny:
                status, message = -1, "step size underflow or non-finite state"
                break
        if status == -1:
            break
        Ks.append(K.copy())
        t = t + hs
        if t_end - t <= 4 * np.spacing(t_end):
            t = t_end
        y = y_new
        K[0] = K[12]
        ts.append(t)
        ys.append(y)
        es.append(out[m:])
        if stop is not None and stop(t, y, out[m:]):
            status, message = 1, "stopped by event"
            break
    return SingleRun(
        t=np.array(ts), y=np.array(ys), ext=np.array(es, dtype=float).reshape(len(ts), ne),
        K=np.array(Ks).reshape(len(Ks), 13, m), nfev=nfev, nrejected=nrej, status=status, message=message,
    )


class BatchObserver:
    """Callbacks of :func:`integrate_batch` (override what you need).

    Indices ``idx`` are positions in the original batch; arrays are
    component-major ``(m, k)`` / ``(e, k)`` for the k systems concerned.
    """

    def start(self, idx, y, ext) -> None:  # noqa: D102
        pass

    def accepted(self, idx, t_old, t_new, y_old, y_new, ext_new, dense) -> np.ndarray | None:
        """Called once per batch iteration with the systems whose step was
        accepted.  ``dense(sel)`` returns the interpolant coefficients
        (7, m, len(sel)) for the positions ``sel`` into ``idx`` (3 extra
        evaluations for those systems only).  Return a boolean mask (k,) of
        systems to stop now, or None."""
        return None


@dataclass
class BatchRun:
    """Final times and states of :func:`integrate_batch` and its cost."""

    t: np.ndarray
    y: np.ndarray
    nfev: np.ndarray
    nsteps: np.ndarray
    nrejected: np.ndarray
    iterations: int
    status: np.ndarray  # 0 reached t_end, 1 stopped by the observer, -1 failed
    messages: dict = field(default_factory=dict)


def integrate_batch(make_f: Callable, y0: np.ndarray, t_end, rtol, atol, h0, observer: BatchObserver | None = None,
                    max_steps: int = 10**6) -> BatchRun:
    """DOP853 on B independent systems, each with its own step size.

    Parameters
    ----------
    make_f : ``make_f(idx) -> f`` returning the right-hand side for the
        systems ``idx`` (indices into the batch): ``f(*rows)`` takes the m
        component arrays (k,) and returns a tuple of at least m arrays (the
        derivatives, then optional extras passed to the observer).
    y0 : (m, B) initial states (component-major).
    t_end, rtol, h0 : scalars or (B,) end times (from t = 0), relative
        tolerances, first steps.  atol : scalar, (m,) or (m, B).

    Systems that finish (or fail, or are stopped by the observer) leave the
    arrays at once and ``make_f`` is called again for those still running.
    """
    y0 = np.asarray(y0, float)
    m, Bn = y0.shape
    obs = observer or BatchObserver()
    idx = np.arange(Bn)
    Y = y0.copy()
    tend = np.broadcast_to(np.asarray(t_end, float), (Bn,)).copy()
    rt = np.broadcast_to(np.asarray(rtol, float), (Bn,)).copy()
    at = np.asarray(atol, float)
    at = np.broadcast_to(at[:, None] if at.ndim == 1 else at, (m, Bn)).copy()
    h = np.broadcast_to(np.asarray(h0, float), (Bn,)).copy()
    t = np.zeros(Bn)
    rej = np.zeros(Bn, bool)
    f = make_f(idx)
    out = f(*Y)
    K = np.empty((13, m, Bn))
    K[0] = _rows(out, m, Bn)
    obs.start(idx, Y, _ext(out, m, Bn))
    nfev = np.ones(Bn, int)
    nsteps = np.zeros(Bn, int)
    nrej = np.zeros(Bn, int)
    status = np.zeros(Bn, int)
    t_fin = np.zeros(Bn)
    y_fin = y0.copy()
    messages: dict = {}
    it = 0
    Ab = [A[s, :s].copy() for s in range(N_STAGES)]
    while len(idx):
        it += 1
        k = len(idx)
        hs = np.minimum(h, tend - t)
        for s in range(1, N_STAGES):
            Ys = Y + hs * _combine(Ab[s], K[:s].reshape(s, -1)).reshape(m, k)
            K[s] = _rows(f(*Ys), m, k)
        y_new = Y + hs * _combine(B, K[:12].reshape(12, -1)).reshape(m, k)
        out = f(*y_new)
        K[12] = _rows(out, m, k)
        nfev[idx] += 12
        scale = at + rt * np.maximum(np.abs(Y), np.abs(y_new))
        err = _error_norm(K, hs, scale, m)
        bad = ~np.isfinite(err)
        acc = (err < 1.0) & ~bad
        fac = np.where(err == 0, MAX_FACTOR, SAFETY * np.where(err > 0, err, 1.0) ** EXPONENT)
        fac = np.where(acc, np.minimum(np.where(rej, 1.0, MAX_FACTOR), fac), np.maximum(MIN_FACTOR, np.minimum(fac, 1.0)))
        fac = np.where(bad, MIN_FACTOR, fac)
        h = hs * fac
        rej = ~acc
        nrej[idx[~acc]] += 1
        stop_now = np.zeros(k, bool)
        if np.any(acc):
            sel = np.nonzero(acc)[0]
            t_old = t[sel]
            t_new = np.where(tend[sel] - (t_old + hs[sel]) <= 4 * np.spacing(tend[sel]), tend[sel], t_old + hs[sel])
            ext_new = _ext(out, m, k)[:, sel]
            K_acc = K[:, :, sel]
            Yo = Y[:, sel]
            Yn = y_new[:, sel]
            hsel = hs[sel]

            def dense(pos, _K=K_acc, _Yo=Yo, _Yn=Yn, _h=hsel, _sel=sel):
                fsub = make_f(idx[_sel[pos]])
                return dense_coefficients(fsub, _K[:, :, pos], _Yo[:, pos], _Yn[:, pos], _h[pos])

            mask = obs.accepted(idx[sel], t_old, t_new, Yo, Yn, ext_new, dense)
            if mask is not None:
                stop_now[sel[np.asarray(mask, bool)]] = True
            t[sel] = t_new
            Y[:, sel] = Yn
            K[0][:, sel] = K[12][:, sel]
            nsteps[idx[sel]] += 1
        too_small = h < 1e-14 * np.maximum(tend, 1.0)
        fail = (bad | too_small) & ~acc
        fail |= nsteps[idx] >= max_steps
        done = (t >= tend) | stop_now | fail
        if np.any(done):
            d = np.nonzero(done)[0]
            gi = idx[d]
            t_fin[gi] = t[d]
            y_fin[:, gi] = Y[:, d]
            status[gi] = np.where(fail[d], -1, np.where(stop_now[d], 1, 0))
            for g, fl in zip(gi, fail[d]):
                if fl:
                    messages[int(g)] = "step size underflow or non-finite state"
            keep = ~done
            idx, Y, K, t, h, tend, rt, at, rej = (idx[keep], Y[:, keep], K[:, :, keep], t[keep], h[keep], tend[keep],
                                                  rt[keep], at[:, keep], rej[keep])
            f = make_f(idx) if len(idx) else f
    return BatchRun(t=t_fin, y=y_fin, nfev=nfev, nsteps=nsteps, nrejected=nrej, iterations=it, status=status,
                    messages=messages)


def _rows(out, m: int, k: int) -> np.ndarray:
    return np.array(np.broadcast_arrays(*out[:m], np.empty(k))[:m])


def _ext(out, m: int, k: int) -> np.ndarray:
    if len(out) == m:
        return np.empty((0, k))
    return np.array(np.broadcast_arrays(*out[m:], np.empty(k))[:-1]).reshape(len(out) - m, k)


def ticker(t_end: float, progress, step: float = 0.005):
    """``(at, tick)``: the schedule of a long run's progress ticks.  Whoever
    sees the integrator's time ``t`` calls ``tick(t)`` once ``t >= at[0]``;
    ``tick`` moves ``at[0]`` to ``t + step * t_end`` and calls
    ``progress(t, t_end)`` (which may raise to stop the run).  Used by
    :func:`with_progress` and, without a wrapper's extra Python call a
    right-hand side, by the compiled kernel itself
    (:func:`~bifilar.models.maximal.compiled_kernel`'s ``ticks``)."""
    at = [0.0]
    dt = step * t_end

    def tick(t):
        at[0] = t + dt
        progress(t, t_end)

    return at, tick


def with_progress(f, t_end: float, progress, step: float = 0.005, time_first: bool = True):
    """``f`` (``f(t, y)``, or ``f(y, t)`` as odeint calls it with
    ``time_first=False``) that also calls ``progress(t, t_end)`` each time the
    integrator's time ``t`` advances by ``step * t_end`` (a long run's progress
    bar moves; ``progress`` may raise to stop the run; :func:`ticker`).  It
    only forwards the call: the numbers do not depend on whether progress is
    asked for."""
    at, tick = ticker(t_end, progress, step)

    def g_ty(t, y):
        if t >= at[0]:
            tick(t)
        return f(t, y)

    def g_yt(y, t):
        if t >= at[0]:
            tick(t)
        return f(y, t)

    return g_ty if time_first else g_yt
