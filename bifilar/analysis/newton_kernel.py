"""One pass of the batched rest-pose Newton compiled as C at run time: an optional accelerator.

:func:`~bifilar.analysis.batch_rest._newton_batch` (Newton's method on the
KKT equations of many scenes at once: SI units, world frame z up) spends
its time in numpy calls on small stacked arrays (~60 a pass, ~1 us each;
a Solar Boat sweep point's 36 sigma-point scenes take 3-4 passes).  This
module renders that pass, all but the attitude update, as one C function
``nstep`` (:data:`SOURCE`), compiled and cached by
:mod:`bifilar.models.native_kernel`'s machinery (the same compiler
detection, flags without contraction or fast-math, private cache
directory, lock, atomic publish and ``.failed`` marker; built in the
background, in the foreground under ``BIFILAR_NATIVE=sync``, never under
``BIFILAR_NATIVE=0``), loaded through :mod:`ctypes` and called once a
pass.  The numpy pass stays and is the reference.  The same library's
``jacobians`` and ``hessians`` give :func:`~bifilar.analysis.batch_rest.
_jacobian` and ``_hessian`` of many scenes (the acceptance checks', the
modes' and the start pose's), the same bits as their numpy bodies.

Bit for bit the numpy pass's numbers:

* the elementwise expressions are the same IEEE operations in the same
  order (``-ffp-contract=off``);
* each ``einsum`` reduction is summed in the order numpy's own loop sums
  it (a 3-term dot over the contiguous last axis as numpy's baseline
  two-lane SIMD loop does: ``(t0 + t2) + t1``; a reduction over wires
  sequentially from zero; ``lam.sum`` sequentially);
* the linear solve calls the same LAPACK ``dgesv`` numpy's
  ``linalg.solve`` calls (numpy's own OpenBLAS, found by its symbol through
  numpy's ``_umath_linalg`` extension), on a matrix laid out as numpy lays
  it out (column-major, one buffer A | b | ipiv);
* the attitude update (``rotvec_to_matrix`` of the step's rotation
  vectors, ``@`` the attitudes) stays in numpy: its ``sin``/``cos`` may be
  numpy's SIMD loops, which no C library call is known to match.

Where C cannot be sure (a non-finite number, a singular matrix: numpy's
``solve`` raises and the pass falls back to ``lstsq``, more wires than
:data:`MAX_WIRES`), ``nstep`` changes nothing and says so, and that pass is
numpy's.  Each loaded library is checked, once a process and wire count,
against the numpy pass on a fixed batch (:func:`_agrees`: every scene's
CoM, attitude, multipliers and residual bit for bit); any difference (an
other numpy build whose ``einsum`` sums in another order, another LAPACK)
and the numpy pass is kept, with a debug record on ``bifilar.native``.
"""
from __future__ import annotations

import os

import numpy as np

from ..models import native_kernel as nk

ABI = "bifilar-newton-1"
"""Part of the library's hash and checked on load: a change of ``nstep``'s layout changes it."""

MAX_WIRES = 16
"""Most wires ``nstep`` takes (its per-scene buffers are on the stack); more: the numpy pass."""

_GESV_NAMES = (("scipy_dgesv_64_", 64), ("dgesv_64_", 64), ("dgesv64_", 64), ("scipy_dgesv_", 32), ("dgesv_", 32))
"""LAPACK ``dgesv``'s symbol in numpy's LAPACK and its integer width (bits), tried in this order."""

SOURCE = r"""/* bifilar's batched rest-pose Newton pass: see bifilar/analysis/newton_kernel.py */
#include <stdlib.h>
#include <stdint.h>
#include <math.h>

typedef @LINT@ lint;
typedef void (*gesv_t)(const lint *, const lint *, double *, const lint *, lint *, double *, const lint *, lint *);

#define MAXW @MAXW@
#define MAXN (6 + MAXW)

int nstep_abi(void) { return @ABIV@; }

/* einsum's 3-term dot over a contiguous last axis: numpy's baseline 2-lane loop (lanes t0 + t2 and t1, then
   their sum), each lane started from +0.0 and the result added to the zeroed output */
static double dot3(const double *x, const double *y) {
    double l0 = x[0] * y[0] + 0.0, l1 = x[1] * y[1] + 0.0;
    l0 = x[2] * y[2] + l0;
    l1 = 0.0 * 0.0 + l1;
    return 0.0 + (l0 + l1);
}

static int finite(double x) { return x - x == 0.0; }

/* np.maximum of two doubles (the first NaN) */
static double nmax(double x, double y) { return x != x ? x : (y != y ? y : (x >= y ? x : y)); }
static double nmin(double x, double y) { return x != x ? x : (y != y ? y : (x <= y ? x : y)); }
/* np.abs(v).max() over k doubles (NaN propagates) */
static double absmax(const double *v, long k) {
    double r = fabs(v[0]);
    for (long i = 1; i < k; i++)
        r = nmax(r, fabs(v[i]));
    return r;
}

/* batch_rest._jacobian of one scene: lever arms w = R p (einsum bij,bnj->bni), wire vectors d = (com + w) - a,
   G = [d, cross(w, d)] (n rows) */
static void jacobian1(long n, const double *ab, const double *pb, const double *Rb, const double *cb,
                      double (*w)[3], double (*d)[3], double (*G)[6]) {
    for (long j = 0; j < n; j++) {
        for (int i = 0; i < 3; i++)
            w[j][i] = dot3(Rb + 3 * i, pb + 3 * j);
        for (int i = 0; i < 3; i++)
            d[j][i] = (cb[i] + w[j][i]) - ab[3 * j + i];
        for (int i = 0; i < 3; i++)
            G[j][i] = d[j][i];
        G[j][3] = w[j][1] * d[j][2] - w[j][2] * d[j][1];
        G[j][4] = w[j][2] * d[j][0] - w[j][0] * d[j][2];
        G[j][5] = w[j][0] * d[j][1] - w[j][1] * d[j][0];
    }
}

/* batch_rest._hessian of one scene: sum_i lam_i H_i (6, 6) from d, w (n, 3) and the multipliers lb (n,) */
static void hessian1(long n, const double (*d)[3], const double (*w)[3], const double *lb, double H[6][6]) {
    double ls = lb[0], E1[3][3], E2[3][3], dw[MAXW], W[MAXW][3][3], Hrr[MAXW][3][3];
    for (long j = 1; j < n; j++)
        ls = ls + lb[j];                                                /* lam.sum(axis=1) */
    for (long j = 0; j < n; j++) {
        const double *v = w[j];
        W[j][0][0] = 0.0; W[j][0][1] = -v[2]; W[j][0][2] = v[1];
        W[j][1][0] = v[2]; W[j][1][1] = 0.0; W[j][1][2] = -v[0];
        W[j][2][0] = -v[1]; W[j][2][1] = v[0]; W[j][2][2] = 0.0;
        dw[j] = dot3(d[j], w[j]);
        for (int i = 0; i < 3; i++)
            for (int c = 0; c < 3; c++) {
                double ww = 0.0;                                        /* einsum bnij,bnjk->bnik */
                for (int q = 0; q < 3; q++)
                    ww = ww + W[j][i][q] * W[j][q][c];
                Hrr[j][i][c] = (-ww + 0.5 * (d[j][i] * w[j][c] + w[j][i] * d[j][c])) - dw[j] * (i == c ? 1.0 : 0.0);
            }
    }
    for (int i = 0; i < 3; i++)
        for (int c = 0; c < 3; c++) {
            double e1 = 0.0, e2 = 0.0;                                  /* einsum bn,bnij->bij */
            for (long j = 0; j < n; j++) {
                e1 = e1 + lb[j] * W[j][i][c];
                e2 = e2 + lb[j] * Hrr[j][i][c];
            }
            E1[i][c] = e1;
            E2[i][c] = e2;
        }
    for (int i = 0; i < 3; i++)
        for (int c = 0; c < 3; c++) {
            H[i][c] = ls * (i == c ? 1.0 : 0.0);
            H[i][3 + c] = -E1[i][c];
            H[3 + i][c] = E1[i][c];
            H[3 + i][3 + c] = E2[i][c];
        }
}

/* _jacobian and _hessian of B scenes (the arrays C-contiguous: a, p, d, w (B, n, 3), com (B, 3), R (B, 3, 3),
   G (B, n, 6), lam (B, n), H (B, 6, 6)); 0, or -1 (n too large) */
long jacobians(long B, long n, const double *a, const double *p, const double *com, const double *R,
               double *d, double *w, double *G) {
    if (n < 1 || n > MAXW)
        return -1;
    for (long b = 0; b < B; b++)
        jacobian1(n, a + b * n * 3, p + b * n * 3, R + b * 9, com + b * 3, (double (*)[3])(w + b * n * 3),
                  (double (*)[3])(d + b * n * 3), (double (*)[6])(G + b * n * 6));
    return 0;
}

long hessians(long B, long n, const double *d, const double *w, const double *lam, double *H) {
    if (n < 1 || n > MAXW)
        return -1;
    for (long b = 0; b < B; b++)
        hessian1(n, (const double (*)[3])(d + b * n * 3), (const double (*)[3])(w + b * n * 3), lam + b * n,
                 (double (*)[6])(H + b * 36));
    return 0;
}

/* One pass of batch_rest._newton_batch's loop over the scenes with active[b] != 0 (B scenes, n wires; a, p
   (B, n, 3), L (B, n), mg = m g (B,), Lmax (B,), com (B, 3), R (B, 3, 3), lam (B, n), res (B,), all
   C-contiguous doubles; SI, world frame).  Each active scene's residual goes to res; a converged one (res <
   1e-15) is made inactive; the others take the damped Newton step: com and lam updated, the step's rotation
   vector s dx[3:] written to rv[q] (q-th stepped scene, ascending b) and b to stepped[q].  Returns the number
   of stepped scenes (0: none left active, the loop ends), or -2 having changed nothing (a non-finite
   residual or step, a singular matrix: numpy's pass is taken), -1 (n too large).  final != 0: residuals
   only (the pass after the loop), returns 0. */
long nstep(long B, long n, unsigned char *active, const double *a, const double *p, const double *L,
           const double *mg, const double *Lmax, double *com, const double *R, double *lam, double *res,
           double *rv, long *stepped, long final, void *gesv_ptr) {
    gesv_t gesv = (gesv_t)(uintptr_t)gesv_ptr;
    long N = 6 + n, k = 0, nact = 0, ret;
    double *rn, *cn, *ln, *mem;
    unsigned char *cv;
    if (n < 1 || n > MAXW)
        return -1;
    /* scratch: new residuals, converged flags, new com and lam of each scene; numpy's solve buffer A | b | ipiv */
    mem = (double *)malloc(sizeof(double) * (size_t)(B * (1 + 3 + n)) + (size_t)B + 16);
    double *gbuf = (double *)malloc(sizeof(double) * (size_t)(N * N + N) + sizeof(lint) * (size_t)N);
    if (mem == NULL || gbuf == NULL) {
        free(mem);
        free(gbuf);
        return -2;
    }
    rn = mem;
    cn = rn + B;
    ln = cn + 3 * B;
    cv = (unsigned char *)(ln + B * n);
    ret = -2;
    for (long b = 0; b < B; b++) {
        const double *ab = a + b * n * 3, *pb = p + b * n * 3, *Lb = L + b * n, *Rb = R + b * 9, *cb = com + b * 3;
        const double *lb = lam + b * n;
        double w[MAXW][3], d[MAXW][3], G[MAXW][6], phi[MAXW], r1[6], rr, rp;
        cv[b] = 0;
        if (!active[b])
            continue;
        nact++;
        jacobian1(n, ab, pb, Rb, cb, w, d, G);
        for (long j = 0; j < n; j++)
            phi[j] = 0.5 * (dot3(d[j], d[j]) - Lb[j] * Lb[j]);
        for (int i = 0; i < 6; i++) {                                   /* gradV + einsum bni,bn->bi */
            double e = 0.0;
            for (long j = 0; j < n; j++)
                e = e + G[j][i] * lb[j];
            r1[i] = (i == 2 ? mg[b] : 0.0) + e;
        }
        rr = absmax(r1, 6) / mg[b];
        rp = absmax(phi, n) / (Lmax[b] * Lmax[b]);
        rn[b] = nmax(rr, rp);
        if (!finite(rn[b]))
            goto out;
        if (rn[b] < 1e-15 || final) {
            cv[b] = 1;
            continue;
        }
        /* K = [[H, G^T], [G, 0]] column-major in numpy's solve buffer; H as batch_rest._hessian */
        double *A = gbuf, *rhs = gbuf + N * N, step[MAXN];
        lint *ipiv = (lint *)(gbuf + N * N + N), nn = (lint)N, one = 1, info = 0;
        double H[6][6];
        hessian1(n, (const double (*)[3])d, (const double (*)[3])w, lb, H);
        for (long c = 0; c < N; c++)
            for (long r = 0; r < N; r++) {
                double v;
                if (r < 6 && c < 6) v = H[r][c];
                else if (r < 6) v = G[c - 6][r];
                else if (c < 6) v = G[r - 6][c];
                else v = 0.0;
                A[r + c * N] = v;
            }
        for (int i = 0; i < 6; i++)
            rhs[i] = -r1[i];
        for (long j = 0; j < n; j++)
            rhs[6 + j] = -phi[j];
        gesv(&nn, &one, A, &nn, ipiv, rhs, &nn, &info);
        if (info != 0)
            goto out;
        for (long i = 0; i < N; i++)
            step[i] = rhs[i];
        {
            double lim = 0.2 * Lmax[b];
            double s = nmin(1.0, nmin(lim / nmax(absmax(step, 3), 1e-300), 0.5 / nmax(absmax(step + 3, 3), 1e-300)));
            if (!finite(s))
                goto out;
            for (int i = 0; i < 3; i++) {
                cn[3 * b + i] = cb[i] + s * step[i];
                rv[3 * k + i] = s * step[3 + i];
            }
            for (long j = 0; j < n; j++)
                ln[b * n + j] = lb[j] + s * step[6 + j];
            for (long i = 0; i < N; i++)
                if (!finite(step[i]))
                    goto out;
        }
        stepped[k++] = b;
    }
    /* commit: the residuals of every active scene, the converged ones made inactive, the steps taken */
    for (long b = 0; b < B; b++) {
        if (!active[b])
            continue;
        res[b] = rn[b];
        if (cv[b]) {
            if (!final)
                active[b] = 0;
            continue;
        }
        for (int i = 0; i < 3; i++)
            com[3 * b + i] = cn[3 * b + i];
        for (long j = 0; j < n; j++)
            lam[b * n + j] = ln[b * n + j];
    }
    ret = final ? 0 : k;
out:
    free(mem);
    free(gbuf);
    return ret;
}
"""
"""``nstep``'s C source (``@LINT@``: LAPACK's integer type, ``@MAXW@``: :data:`MAX_WIRES`, ``@ABIV@``)."""

ABI_VERSION = 2
"""``nstep_abi()``'s answer (with :data:`ABI` in the hash)."""

log = nk.log

_lib: list = []  # [the library's _Pattern] once looked for in this process
_checked: dict = {}  # wire count -> whether the library agreed with the numpy pass (this process)
_gesv_found: list = []  # [(address, integer bits) or None] once looked for


def pass_for(active, a, p, L, mg, Lmax, com, R, lam, res):
    """The compiled Newton pass over these arrays (see ``nstep`` in
    :data:`SOURCE` for their shapes; SI, world frame), or None (off, not
    built yet, no compiler, no LAPACK symbol, too many wires, an array not
    C-contiguous float64 (``active``: bool), or a library that disagreed
    with the numpy pass): ``run(final=False) -> (k, rv, stepped)``, ``k``
    as ``nstep`` returns it, ``rv`` (k, 3) the stepped scenes' rotation
    vectors and ``stepped`` (k,) their indices.  The arrays are updated in
    place by each run, so they must stay the same objects.  Never raises:
    any error is a debug record and None."""
    try:
        lib = _library(L.shape[1])
        if lib is None:
            return None
        return _runner(lib.nstep, active, a, p, L, mg, Lmax, com, R, lam, res)
    except Exception as exc:  # noqa: BLE001 - an accelerator: the numpy pass is always there
        log.debug("newton kernel: %s: %s", type(exc).__name__, exc)
        _lib[:] = [nk._Pattern("", "newton", "failed")]
        return None


def _runner(func, active, a, p, L, mg, Lmax, com, R, lam, res):
    """``run(final)`` calling ``func`` on the arrays' buffers (None where one
    is not a C-contiguous array of its dtype)."""
    arrays = (active, a, p, L, mg, Lmax, com, R, lam, res)
    if not all(isinstance(x, np.ndarray) and x.flags.c_contiguous for x in arrays) or active.dtype != np.bool_ \
            or any(x.dtype != np.float64 for x in arrays[1:]):
        return None
    B, n = L.shape
    rv, stepped = np.empty((B, 3)), np.empty(B, np.int64)
    ptrs = [x.ctypes.data for x in (active, a, p, L, mg, Lmax, com, R, lam, res, rv, stepped)]
    gesv = _gesv_found[0][0]

    def run(final: bool = False, func=func, ptrs=ptrs, keep=arrays, rv=rv, stepped=stepped):
        k = func(B, n, *ptrs, 1 if final else 0, gesv)
        return k, rv[:max(k, 0)], stepped[:max(k, 0)]
    return run


def _kernel(n: int):
    """The loaded library (:class:`_Lib`, checked for ``n`` wires), or None."""
    pat = nk.ready_pattern(_lib, lambda: _start(nk.mode()))
    if pat is None:
        return None
    if n not in _checked:
        _checked[n] = False  # (the check's own numpy runs ask again: they get None)
        _checked[n] = _agrees(pat.func, n)
        if not _checked[n]:
            log.debug("newton kernel %s disagrees with the numpy pass on %d wires: not used", pat.path, n)
    return pat.func if _checked[n] else None


def _gesv():
    """(address, integer bits) of the LAPACK ``dgesv`` numpy's ``linalg``
    calls (a symbol of its ``_umath_linalg`` extension's libraries), or None."""
    if not _gesv_found:
        import ctypes

        import numpy.linalg._umath_linalg as ul
        found = None
        try:
            lib = ctypes.CDLL(ul.__file__)
            for name, bits in _GESV_NAMES:
                try:
                    found = (ctypes.cast(getattr(lib, name), ctypes.c_void_p).value, bits)
                    break
                except AttributeError:
                    continue
        except OSError as exc:
            log.debug("newton kernel: numpy's LAPACK not loadable (%s)", exc)
        _gesv_found.append(found)
    return _gesv_found[0]


def c_source(bits: int) -> str:
    """:data:`SOURCE` for LAPACK integers of ``bits`` (32 or 64)."""
    return (SOURCE.replace("@LINT@", f"int{bits}_t").replace("@MAXW@", str(MAX_WIRES))
            .replace("@ABIV@", str(ABI_VERSION)))


def _start(m: str) -> "nk._Pattern":
    """Find the library: load it, or start (or wait for) its build; failed
    where ``BIFILAR_NATIVE`` is off, or there is no compiler, ``sh`` or
    LAPACK symbol.  File ``newton_<hash>.so`` (hash of the ABI tag,
    compiler, flags, platform and source) in :func:`~bifilar.models.
    native_kernel.cache_dir`."""
    cc = nk._compiler()
    g = _gesv() if m != "off" else None
    if m == "off" or cc is None or nk._env.get("sh") is None or g is None:
        log.debug("newton kernel: off, or no C compiler, sh or LAPACK dgesv")
        return nk._Pattern("", "newton", "failed")
    import hashlib
    import sys
    src = c_source(g[1])
    ident = "\n".join([ABI, cc[1], " ".join(nk.FLAGS), sys.platform, os.uname().machine, src])
    pat = nk._Pattern(os.path.join(nk.cache_dir(), "newton_" + hashlib.sha256(ident.encode()).hexdigest()[:32] + ".so"),
                      "newton")
    pat.src, pat.open = src, _open
    return nk._find(pat, cc[0], m)


class _Lib:
    """The loaded library's three functions (ctypes): ``nstep``, ``jacobians``, ``hessians``."""

    def __init__(self, lib):
        import ctypes
        P, L = ctypes.c_void_p, ctypes.c_long
        self.nstep, self.jacobians, self.hessians = lib.nstep, lib.jacobians, lib.hessians
        for f, args in ((self.nstep, [L, L] + [P] * 12 + [L, P]), (self.jacobians, [L, L] + [P] * 7),
                        (self.hessians, [L, L] + [P] * 4)):
            f.restype, f.argtypes = L, args


def _open(pat):
    """The library at ``pat.path`` as a :class:`_Lib` (OSError: another layout)."""
    import ctypes
    lib = ctypes.CDLL(pat.path)
    if lib.nstep_abi() != ABI_VERSION:
        raise OSError("layout differs")
    return _Lib(lib)


def _plain(*arrays) -> bool:
    """Every array a C-contiguous float64 ndarray (what the C functions read)."""
    return all(type(x) is np.ndarray and x.dtype == np.float64 and x.flags.c_contiguous for x in arrays)


def jacobians(a, p, com, R):
    """:func:`~bifilar.analysis.batch_rest._jacobian` (d, w, G of scenes with
    anchors a, body attachments p (B, n, 3), CoMs com (B, 3), attitudes R
    (B, 3, 3); SI, world frame) by the library, the same bits; None where
    it is not there or an array is not plain float64 (numpy's then)."""
    if not _plain(a, p, com, R) or a.ndim != 3 or a.shape != p.shape or a.shape[2] != 3 \
            or com.shape != (a.shape[0], 3) or R.shape != (a.shape[0], 3, 3):
        return None
    lib = _library(a.shape[1])
    if lib is None:
        return None
    B, n = a.shape[:2]
    d, w, G = np.empty((B, n, 3)), np.empty((B, n, 3)), np.empty((B, n, 6))
    if lib.jacobians(B, n, a.ctypes.data, p.ctypes.data, com.ctypes.data, R.ctypes.data, d.ctypes.data, w.ctypes.data,
                     G.ctypes.data):
        return None
    return d, w, G


def hessians(d, w, lam):
    """:func:`~bifilar.analysis.batch_rest._hessian` (sum_i lam_i H_i (B, 6, 6)
    from wire vectors d and lever arms w (B, n, 3), multipliers lam (B, n);
    SI) by the library, the same bits; None as :func:`jacobians`."""
    if not _plain(d, w, lam) or d.ndim != 3 or d.shape != w.shape or lam.shape != d.shape[:2]:
        return None
    lib = _library(d.shape[1])
    if lib is None:
        return None
    H = np.empty((d.shape[0], 6, 6))
    if lib.hessians(d.shape[0], d.shape[1], d.ctypes.data, w.ctypes.data, lam.ctypes.data, H.ctypes.data):
        return None
    return H


def _library(n: int):
    """The checked library for ``n`` wires, or None (off, too many wires, not there)."""
    try:
        if n > MAX_WIRES or nk.mode() == "off":
            return None
        return _kernel(n)
    except Exception as exc:  # noqa: BLE001 - an accelerator: numpy is always there
        log.debug("newton kernel: %s: %s", type(exc).__name__, exc)
        _lib[:] = [nk._Pattern("", "newton", "failed")]
        return None


def check_batch(n: int):
    """A fixed batch of eight ``n``-wire scenes (anchors a, attachments p
    (8, n, 3), lengths L (8, n), masses m and gravities g (8,); SI, world
    frame z up): a ring of anchors over a smaller ring of attachments,
    each scene's lengths, rings and mass changed so that its Newton run
    takes its own number of passes."""
    k = np.arange(8.0)[:, None]
    t = 2 * np.pi * np.arange(n)[None, :] / n + 0.1 * k
    a = np.stack([np.cos(t) * (1.0 + 0.03 * k), np.sin(t) * (1.0 - 0.02 * k), 0.01 * np.sin(3 * t + k)], axis=-1)
    p = np.stack([0.4 * np.cos(t + 0.05 * k), 0.4 * np.sin(t - 0.02 * k), 0.1 + 0.0 * t], axis=-1)
    L = 1.5 + 0.05 * k * np.cos(t * (1 + k)) + 0.001 * k
    return a, p, L, 2.0 + k[:, 0], np.full(8, 9.81)


def _agrees(lib, n: int) -> bool:
    """The library's Newton passes (``lib.nstep``) and the numpy passes give
    every scene of :func:`check_batch` the same CoM, attitude, multipliers
    and residual bit for bit (and it stepped at all: a library that always
    declines proves nothing); its ``jacobians`` and ``hessians`` equal
    numpy's (``_jacobian``, ``_hessian_numpy``) at the start poses and at
    those ends."""
    from . import batch_rest as br
    a, p, L, m, g = check_batch(n)
    ran: list = []

    def counted(*args):
        k = lib.nstep(*args)
        ran.append(k)
        return k
    start = br.newton_start(a, p, L, m, g)
    outs = [br._newton_batch(a, p, L, m, g, *(x.copy() for x in start), native=f) for f in (False, counted)]
    pairs = list(zip(*outs))
    for com, R, lam in (start, outs[0][:3]):
        d, w, G = br._jacobian_numpy(a, p, com, R)
        H = np.empty((len(m), 6, 6))
        mine = (np.empty_like(d), np.empty_like(w), np.empty_like(G))
        lib.jacobians(len(m), n, a.ctypes.data, p.ctypes.data, com.ctypes.data, R.ctypes.data,
                      *(x.ctypes.data for x in mine))
        lib.hessians(len(m), n, d.ctypes.data, w.ctypes.data, lam.ctypes.data, H.ctypes.data)
        pairs += list(zip((d, w, G, br._hessian_numpy(d, w, lam)), (*mine, H)))
    return any(k > 0 for k in ran) and all(np.array_equal(np.asarray(x).view(np.int64), np.asarray(y).view(np.int64))
                                           for x, y in pairs)
