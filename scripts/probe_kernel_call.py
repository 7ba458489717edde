#!/usr/bin/env python
"""What the call into odeint's C kernel costs a sweep point, and what a
C-extension callable would save (session 26, perf26a; a probe: nothing in
``bifilar`` changes).

``bifilar.models.native_kernel`` hands odeint a Python ``f(y, t)`` that
copies the state into a buffer and calls the compiled kernel through
:mod:`ctypes` (~1 us a call; a Solar Boat point makes ~3100).  This script
builds, in a temporary directory, a small Python extension whose callable
object does the same (the state's buffer copied, the same C function
called through its address, the same output array returned) without
ctypes' argument conversion, patches ``native_kernel._wrap`` with it for the
measurement only, checks that ``evaluate_point``'s JSON is unchanged on the
points of ``scripts/bench_sweep.py``, and prints the CPU a point takes either
way (medians, the two alternating in one process) and a call's cost alone.
Needs a C compiler and the Python headers; else it says so and exits 0.

    python scripts/probe_kernel_call.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import ctypes
import importlib.util
import json
import os
import shutil
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("BIFILAR_NATIVE", "sync")

import numpy as np  # noqa: E402

from bifilar.config import read_yaml  # noqa: E402
from bifilar.models import native_kernel as nk  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

POINTS = [("solar_boat.yaml", {"spacing": 3.0}), ("trifilar_kth.yaml", {}), ("thesis_plate_rest.yaml", {"spacing": 3.0})]

SOURCE = r"""
#include <Python.h>
#include <string.h>
#include <stdint.h>
typedef void (*kern_t)(const double *, double *, const double *);
typedef struct { PyObject_HEAD kern_t f; const double *p; double *o; PyObject *out; PyObject *keep; } K;
static PyObject *K_call(PyObject *s, PyObject *args, PyObject *kw) {
    K *k = (K *)s;
    Py_buffer b;
    double y[13];
    if (PyTuple_GET_SIZE(args) < 1 || PyObject_GetBuffer(PyTuple_GET_ITEM(args, 0), &b, PyBUF_C_CONTIGUOUS) < 0)
        return NULL;
    if (b.len != (Py_ssize_t)sizeof y) { PyBuffer_Release(&b); PyErr_SetString(PyExc_ValueError, "y: 13 doubles"); return NULL; }
    memcpy(y, b.buf, sizeof y);
    PyBuffer_Release(&b);
    k->f(y, k->o, k->p);
    Py_INCREF(k->out);
    return k->out;
}
static void K_dealloc(PyObject *s) { K *k = (K *)s; Py_XDECREF(k->out); Py_XDECREF(k->keep); Py_TYPE(s)->tp_free(s); }
static PyObject *K_new(PyTypeObject *t, PyObject *args, PyObject *kw) {
    unsigned long long f, p, o; PyObject *out, *keep; K *k;
    if (!PyArg_ParseTuple(args, "KKKOO", &f, &p, &o, &out, &keep)) return NULL;
    if (!(k = (K *)t->tp_alloc(t, 0))) return NULL;
    k->f = (kern_t)(uintptr_t)f; k->p = (const double *)(uintptr_t)p; k->o = (double *)(uintptr_t)o;
    Py_INCREF(out); k->out = out; Py_INCREF(keep); k->keep = keep;
    return (PyObject *)k;
}
static PyTypeObject KType = {PyVarObject_HEAD_INIT(NULL, 0) .tp_name = "probe_kcall.K", .tp_basicsize = sizeof(K),
    .tp_flags = Py_TPFLAGS_DEFAULT, .tp_new = K_new, .tp_call = K_call, .tp_dealloc = K_dealloc};
static struct PyModuleDef M = {PyModuleDef_HEAD_INIT, "probe_kcall", NULL, -1, NULL};
PyMODINIT_FUNC PyInit_probe_kcall(void) {
    PyObject *m;
    if (PyType_Ready(&KType) < 0 || !(m = PyModule_Create(&M))) return NULL;
    Py_INCREF(&KType);
    PyModule_AddObject(m, "K", (PyObject *)&KType);
    return m;
}
"""


def _build(tmp: str):
    """The extension module, or None (no compiler or headers)."""
    cc = shutil.which(os.environ.get("CC", "") or "cc") or shutil.which("gcc")
    inc = sysconfig.get_paths()["include"]
    if cc is None or not os.path.exists(os.path.join(inc, "Python.h")):
        return None
    src, lib = os.path.join(tmp, "probe_kcall.c"), os.path.join(tmp, "probe_kcall" + sysconfig.get_config_var("EXT_SUFFIX"))
    Path(src).write_text(SOURCE)
    if subprocess.run([cc, *nk.FLAGS, f"-I{inc}", "-o", lib, src], capture_output=True).returncode:
        return None
    spec = importlib.util.spec_from_file_location("probe_kcall", lib)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        ext = _build(tmp)
        if ext is None:
            print("no C compiler or Python headers: nothing to measure")
            return 0
        shipped = nk._wrap

        def ext_wrap(func, values, ticks):
            if ticks is not None:
                return shipped(func, values, ticks)
            pv, out = np.array(values, dtype=float).reshape(-1), np.empty(13)
            return ext.K(ctypes.cast(func, ctypes.c_void_p).value, pv.ctypes.data, out.ctypes.data, out, (pv, func))

        arms = {"ctypes f(y, t)": shipped, "extension callable": ext_wrap}
        print(f"load {os.getloadavg()[0]:.1f}; CPU a point, medians of {args.repeats}, the two alternating:")
        for name, params in POINTS:
            cfg = read_yaml(ROOT / "configs" / name)
            st = sw.resolve_settings(cfg)
            docs, cpu = {}, {a: [] for a in arms}
            for arm, wrap in arms.items():
                nk._wrap = wrap
                doc = sw.evaluate_point(cfg, name, params, st)  # warm-up (and the C kernel's build)
                doc.pop("runtime_s", None)
                docs[arm] = json.dumps(doc, sort_keys=True, default=repr)
            for _ in range(args.repeats):
                for arm, wrap in arms.items():
                    nk._wrap = wrap
                    c0 = time.process_time()
                    sw.evaluate_point(cfg, name, params, st)
                    cpu[arm].append(time.process_time() - c0)
            nk._wrap = shipped
            same = len(set(docs.values())) == 1
            a, b = (statistics.median(cpu[k]) * 1e3 for k in arms)
            print(f"  {name} {params}: {a:.2f} -> {b:.2f} ms ({b - a:+.2f}); JSON {'identical' if same else 'DIFFERS'}")
        # a call alone, on the Solar Boat's kernel
        from bifilar.config import load_scene
        from bifilar.models import maximal as mx
        P = mx.params_from_scenes(load_scene(ROOT / "configs" / "solar_boat.yaml", warn=False))
        y = np.array([0.01, -0.02, -0.9, 0.99, 0.05, -0.08, 0.1, 0.3, -0.2, 0.05, 0.7, -1.1, 2.3])
        for arm, wrap in arms.items():
            nk._wrap = wrap
            f = mx.compiled_kernel(mx.RigParams(**{k: getattr(P, k) for k in P.__dataclass_fields__}), signature="odeint")
            t = min(timeit.repeat(lambda: f(y, 0.0), number=20000, repeat=5)) / 20000 * 1e6
            print(f"  one call, {arm}: {t:.3f} us")
        nk._wrap = shipped
    return 0


if __name__ == "__main__":
    sys.exit(main())
