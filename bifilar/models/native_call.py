"""The call from odeint into a compiled kernel as a C-extension callable: an optional accelerator.

:mod:`.native_kernel` hands odeint ``f(y, t)`` (``y`` the state (13,), SI
units, world frame with body-axes angular velocity; ``t`` the time, s;
returns the derivatives (13,) in one reused array).  Through :mod:`ctypes`
that call costs ~1 us (a Solar Boat sweep point makes ~3100).  This module
builds, once per interpreter (cached per user, loaded once a process), one small generic Python extension
(:data:`_CALL_SOURCE`, module ``bifilar_kcall``): a callable type made from
the kernel's address, its parameter array, the output array, the state's
length, the ctypes ``f`` without ticks (for any state that is not one
C-contiguous row of doubles) and the tick schedule; its ``__call__(y, t)``
does what the ctypes ``f`` does (the tick check, the state copied, the
same C function called, the same array returned), ~0.1 us.  The same bits:
the same function on the same doubles.

It is cached beside the kernels (:func:`~.native_kernel.cache_dir`, the
same privacy rule, lock, atomic publish and ``.failed`` marker: the build
code is :mod:`.native_kernel`'s), named from the interpreter's SOABI and a
hash of the ABI tag, compiler, flags, platform, Python version, headers and
source; built in the background (in the foreground under
``BIFILAR_NATIVE=sync``) and checked on first use against the ctypes ``f``
bit for bit at two states.  No compiler, no ``Python.h`` (sysconfig's
include directory), a failed build, a module that does not load or
disagrees, ``BIFILAR_NATIVE=0``: the ctypes ``f``, a debug record on
``bifilar.native``, nothing printed.
"""
from __future__ import annotations

import os
import sys

from . import native_kernel as nk

log = nk.log

CALL_ABI = "bifilar-kcall-1"
"""Part of the call extension's hash and checked on load: a change of its constructor's layout changes it."""

_CALL_SOURCE = r"""/* bifilar's call extension: K(address, params, out, n, plain[, at, tick]) is odeint's f(y, t) */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

#define MAXN 64
typedef void (*kern_t)(const double *, double *, const double *);

typedef struct {
    PyObject_HEAD
    kern_t f;                 /* kern(y, o, p); NULL once cleared */
    Py_ssize_t n;             /* the state's length */
    Py_buffer p, o;           /* the parameters' and the output's buffers, held */
    int held;                 /* 1: p held, 2: o held */
    PyObject *out, *plain, *at, *tick;
} K;

static int doubles(const Py_buffer *b, Py_ssize_t n) {
    return b->ndim == 1 && b->itemsize == 8 && b->format != NULL && strcmp(b->format, "d") == 0
        && (n < 0 || b->len == n * 8);
}

static PyObject *K_call(PyObject *self, PyObject *args, PyObject *kw) {
    K *k = (K *)self;
    PyObject *y, *t;
    Py_buffer b;
    double ybuf[MAXN];
    if (k->f == NULL) {
        PyErr_SetString(PyExc_RuntimeError, "cleared");
        return NULL;
    }
    if (kw != NULL && PyDict_GET_SIZE(kw)) {
        PyErr_SetString(PyExc_TypeError, "f(y, t) takes no keyword arguments");
        return NULL;
    }
    if (!PyArg_UnpackTuple(args, "f", 2, 2, &y, &t))
        return NULL;
    if (k->at != NULL) {  /* the tick check first, as the Python f: if t >= at[0]: tick(t) */
        PyObject *a = PySequence_GetItem(k->at, 0), *r;
        int ge;
        if (a == NULL)
            return NULL;
        ge = PyObject_RichCompareBool(t, a, Py_GE);
        Py_DECREF(a);
        if (ge < 0)
            return NULL;
        if (ge) {
            if ((r = PyObject_CallFunctionObjArgs(k->tick, t, NULL)) == NULL)
                return NULL;
            Py_DECREF(r);
        }
    }
    if (PyObject_GetBuffer(y, &b, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Clear();  /* not a buffer, or not contiguous: numpy's conversion in the plain f */
        return PyObject_CallFunctionObjArgs(k->plain, y, t, NULL);
    }
    if (!doubles(&b, k->n)) {
        PyBuffer_Release(&b);
        return PyObject_CallFunctionObjArgs(k->plain, y, t, NULL);
    }
    memcpy(ybuf, b.buf, (size_t)b.len);
    PyBuffer_Release(&b);
    k->f(ybuf, (double *)k->o.buf, (const double *)k->p.buf);
    Py_INCREF(k->out);
    return k->out;
}

static int K_traverse(PyObject *self, visitproc visit, void *arg) {
    K *k = (K *)self;
    Py_VISIT(k->out);
    Py_VISIT(k->plain);
    Py_VISIT(k->at);
    Py_VISIT(k->tick);
    if (k->held & 1)
        Py_VISIT(k->p.obj);
    if (k->held & 2)
        Py_VISIT(k->o.obj);
    return 0;
}

static int K_clear(PyObject *self) {
    K *k = (K *)self;
    k->f = NULL;
    if (k->held & 1)
        PyBuffer_Release(&k->p);
    if (k->held & 2)
        PyBuffer_Release(&k->o);
    k->held = 0;
    Py_CLEAR(k->out);
    Py_CLEAR(k->plain);
    Py_CLEAR(k->at);
    Py_CLEAR(k->tick);
    return 0;
}

static void K_dealloc(PyObject *self) {
    PyObject_GC_UnTrack(self);
    K_clear(self);
    Py_TYPE(self)->tp_free(self);
}

static PyObject *K_new(PyTypeObject *type, PyObject *args, PyObject *kw) {
    PyObject *address, *params, *out, *plain, *at = Py_None, *tick = Py_None;
    Py_ssize_t n;
    void *f;
    K *k;
    static char *names[] = {"address", "params", "out", "n", "plain", "at", "tick", NULL};
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OOOnO|OO", names, &address, &params, &out, &n, &plain, &at, &tick))
        return NULL;
    f = PyLong_AsVoidPtr(address);
    if (f == NULL) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "address: a function's, not 0");
        return NULL;
    }
    if (n < 1 || n > MAXN || !PyCallable_Check(plain) || (at == Py_None) != (tick == Py_None)
            || (tick != Py_None && !PyCallable_Check(tick))) {
        PyErr_SetString(PyExc_ValueError, "n in 1..64, plain callable, at and tick both or neither");
        return NULL;
    }
    if ((k = (K *)type->tp_alloc(type, 0)) == NULL)
        return NULL;
    if (PyObject_GetBuffer(params, &k->p, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0)
        goto fail;
    k->held |= 1;
    if (PyObject_GetBuffer(out, &k->o, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | PyBUF_WRITABLE) < 0)
        goto fail;
    k->held |= 2;
    if (!doubles(&k->p, -1) || !doubles(&k->o, n)) {
        PyErr_SetString(PyExc_ValueError, "params: doubles; out: n writable doubles");
        goto fail;
    }
    k->f = (kern_t)(uintptr_t)f;
    k->n = n;
    Py_INCREF(out);
    k->out = out;
    Py_INCREF(plain);
    k->plain = plain;
    if (tick != Py_None) {
        Py_INCREF(at);
        k->at = at;
        Py_INCREF(tick);
        k->tick = tick;
    }
    return (PyObject *)k;
fail:
    Py_DECREF(k);
    return NULL;
}

static PyTypeObject KType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "bifilar_kcall.K",
    .tp_doc = "odeint's f(y, t) calling a C kernel kern(y, o, p) by its address",
    .tp_basicsize = sizeof(K),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_new = K_new,
    .tp_call = K_call,
    .tp_traverse = K_traverse,
    .tp_clear = K_clear,
    .tp_dealloc = K_dealloc,
};

static struct PyModuleDef M = {PyModuleDef_HEAD_INIT, "bifilar_kcall", NULL, -1, NULL};

PyMODINIT_FUNC PyInit_bifilar_kcall(void) {
    PyObject *m;
    if (PyType_Ready(&KType) < 0 || (m = PyModule_Create(&M)) == NULL)
        return NULL;
    Py_INCREF(&KType);
    if (PyModule_AddObject(m, "K", (PyObject *)&KType) < 0 || PyModule_AddStringConstant(m, "ABI", "@ABI@") < 0) {
        Py_DECREF(&KType);
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
""".replace("@ABI@", CALL_ABI)
"""The call extension's C source: one callable type ``K(address, params,
out, n, plain[, at, tick])`` (the kernel's address, its parameter array,
the output array of ``n`` doubles it returns, the ctypes ``f`` without
ticks for any other state, and the tick schedule of
:func:`~bifilar.integrators.ticker`) whose ``__call__(y, t)`` is the
ctypes ``f``'s: the tick check, the state copied, the kernel called, the
output returned.  Generic: one module for every kernel pattern."""

_call: list = []  # [the call extension's _Pattern] once looked for in this process


def callable_f(func, f, plain, pv, out, ticks):
    """The call extension's ``K(address of func, pv, out, 13, plain, *ticks)``
    where it is available (:func:`_call_type`), else ``f`` (the ctypes
    ``f(y, t)``).  Never raises: an error marks the extension failed for
    this process (a debug record) and gives ``f``."""
    try:
        call = _call_type(func, pv)
        if call is not None:
            return call(nk._address(func), pv, out, 13, plain, *(ticks or ()))
    except Exception as exc:  # noqa: BLE001 - an accelerator: the ctypes f is always there
        log.debug("call extension: %s: %s", type(exc).__name__, exc)
        _call[:] = [nk._Pattern("", "call", "failed")]
    return f


def _call_type(func, values: list):
    """The call extension's type ``K``, or None (off, not built yet, no
    Python headers, failed); checked on first use against the ctypes ``f``
    of ``func`` with ``values``, bit for bit at two states."""
    pat = nk.ready_pattern(_call, lambda: _start_call(nk.mode()))
    if pat is None:
        return None
    if not pat.checked:
        pat.checked = True
        if not _call_agrees(pat.func, func, values):
            log.debug("call extension %s disagrees with the ctypes call: not used", pat.path)
            pat.state, pat.func = "failed", None
            return None
    return pat.func


def _call_agrees(call, func, values: list) -> bool:
    """``call``'s callable and the ctypes ``f`` of ``func`` give the same bits
    at two states, into and as the same output array."""
    import numpy as np
    plain, _, pv, out = nk._ctypes_f(func, values, None)
    k = call(nk._address(func), pv, out, 13, plain)
    for y in nk._states():
        a = k(y, 0.0)
        if a is not out:
            return False
        a = a.copy()
        if not np.array_equal(a.view(np.int64), plain(y, 0.0).view(np.int64)):
            return False
    return True


def _start_call(m: str) -> "nk._Pattern":
    """Find the call extension: load it, or start (or wait for) its build;
    failed where ``BIFILAR_NATIVE`` is off or there is no compiler, ``sh``
    or ``Python.h``.  File ``kcall_<SOABI>_<hash>.so`` (hash of the ABI tag,
    compiler, flags, platform, Python version, headers and source)."""
    cc = nk._compiler()
    inc = _python_includes()
    if m == "off" or cc is None or nk._env.get("sh") is None or not inc:
        log.debug("call extension: off, or no C compiler, sh or Python headers")
        return nk._Pattern("", "call", "failed")
    import hashlib
    import sysconfig
    soabi = sysconfig.get_config_var("SOABI") or sys.implementation.cache_tag
    h = os.stat(os.path.join(inc[0], "Python.h"))
    ident = "\n".join([CALL_ABI, cc[1], " ".join(nk.FLAGS + _CALL_FLAGS), sys.platform, os.uname().machine,
                       sys.version, soabi, *inc, f"{h.st_size}:{h.st_mtime_ns}", _CALL_SOURCE])
    name = f"kcall_{soabi}_{hashlib.sha256(ident.encode()).hexdigest()[:24]}.so"
    pat = nk._Pattern(os.path.join(nk.cache_dir(), name), "call")
    pat.src, pat.flags, pat.open = _CALL_SOURCE, _CALL_FLAGS + tuple(f"-I{d}" for d in inc), _open
    return nk._find(pat, cc[0], m)


_CALL_FLAGS = ("-std=c11",)
"""The call extension's flags after :data:`~.native_kernel.FLAGS` (the last ``-std`` counts:
Python's headers may use C11; no floating-point operation is in it)."""


def _python_includes() -> tuple:
    """sysconfig's directories of ``Python.h`` and ``pyconfig.h``, or ()
    where ``Python.h`` is not there (no development headers)."""
    import sysconfig
    paths = sysconfig.get_paths()
    dirs = tuple(dict.fromkeys(d for d in (paths.get("include"), paths.get("platinclude")) if d))
    return dirs if dirs and os.path.isfile(os.path.join(dirs[0], "Python.h")) else ()


def _open(pat):
    """The call extension at ``pat.path`` imported (not into ``sys.modules``): its type ``K``."""
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.ExtensionFileLoader("bifilar_kcall", pat.path)
    mod = importlib.util.module_from_spec(importlib.util.spec_from_loader("bifilar_kcall", loader, origin=pat.path))
    loader.exec_module(mod)
    if getattr(mod, "ABI", None) != CALL_ABI:
        raise ImportError("layout differs")
    return mod.K
