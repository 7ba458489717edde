#!/usr/bin/env python
"""What a sweep point's nonlinear runs would cost done another way, and how
far each way moves the point's figures (issue 14; docs/design.md, "perf24,
session 24").  A probe, not a benchmark of shipped code: each variant is
patched in for the measurement only.

* ``--stacked``: the runs of one ``_lsoda_joint`` call (a point's own runs;
  its amplitude laws' runs) stacked into one LSODA system, as the batched
  LSODA engine stacks a group (normalised time, tolerances / sqrt(B)), with
  a right-hand side that calls each run's float kernel in turn; variants
  ``laws`` (only the law runs), ``laws-rtol`` (the same with the tolerances
  not divided) and ``all`` (every run of the point).
* ``--compiled``: every ``odeint`` right-hand side of the point as the
  generated kernel's statements compiled as C (cffi, the system C compiler,
  ``-O2 -ffp-contract=off``: the same IEEE operations in the same order),
  called from a Python ``f(y, t)``.  cffi and a compiler are not
  dependencies of bifilar: the probe says so and exits 0 where either is
  missing.

For each variant: odeint calls and kernel evaluations a point, CPU medians
of the point interleaved with the shipped path in one process (A B A B ...),
and the largest relative change of any number in ``evaluate_point``'s JSON
over :data:`POINTS` against the shipped path.

    python scripts/probe_point_runs.py [--stacked] [--compiled] [--repeats 11]
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import scipy.integrate as si  # noqa: E402

from bifilar.analysis import batch, batch_lsoda as bl  # noqa: E402
from bifilar.config import read_yaml  # noqa: E402
from bifilar.models import maximal as mx  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

POINTS = [("solar_boat.yaml", {"spacing": 3.0}), ("solar_boat.yaml", {"spacing": 1.0, "length": 2.0}),
          ("solar_boat.yaml", {"spacing": 4.0, "length": 5.0}), ("trifilar_kth.yaml", {}),
          ("thesis_plate_rest.yaml", {"spacing": 3.0}), ("thesis_lin2_pitch.yaml", {}), ("drone_parallel.yaml", {})]
TIMED = POINTS[0], POINTS[3]  # the Solar Boat and the trifilar: issue 14's unmet points

_COUNT = {"calls": 0, "kernels": 0}
_ODEINT = si.odeint
_JOINT = bl._lsoda_joint
_KERNEL = mx.compiled_kernel


def _counting_odeint(f, y0, t, **kw):
    out = _ODEINT(f, y0, t, **kw)
    _COUNT["calls"] += 1
    if kw.get("full_output") and len(out[1]["nfe"]):  # a stacked call evaluates every run's kernel a call
        _COUNT["kernels"] += int(out[1]["nfe"][-1]) * (len(y0) // 13)
    return out


def _stacked(variant: str):
    """A replacement of ``_lsoda_joint``: the runs in one LSODA system."""
    def joint(P1, ys0, T_ref, pers, rtol, at, spp, obs, com0, health, on_slack):
        per_run = isinstance(P1, list)
        if variant != "all" and not per_run:
            return _JOINT(P1, ys0, T_ref, pers, rtol, at, spp, obs, com0, health, on_slack)
        Bn = len(T_ref)
        Ps = P1 if per_run else [P1] * Bn
        if np.any(pers != pers[0]):
            raise bl._NotJoint
        fields = mx.RigParams.__dataclass_fields__
        Pst = mx.RigParams(**{k: np.stack([np.asarray(getattr(p, k)) for p in Ps]) for k in fields})
        sq = 1.0 if variant == "laws-rtol" else math.sqrt(Bn)
        ks, Ts = [mx.compiled_kernel(p) for p in Ps], [float(x) for x in T_ref]

        def f(y, tau):  # normalised time: each run's derivatives times its period
            yl, out = y.tolist(), []
            for b in range(Bn):
                out += [v * Ts[b] for v in ks[b](*yl[13 * b:13 * b + 13])]
            return out
        kx = mx.compiled_kernel(Pst, extras=True) if health else None
        _, _, taus = bl._sample_grid(pers, spp)
        Y, info = si.odeint(f, ys0.ravel().copy(), taus, rtol=rtol / sq, atol=(at / sq).T.ravel(), full_output=True,
                            mxstep=100000, ml=12, mu=12)
        if info["message"] != "Integration successful.":
            raise bl._NotJoint
        Ys = Y.reshape(len(taus), Bn, 13)
        stop, cols, tx, status = pers.astype(float).copy(), [], [], np.zeros(Bn, int)
        bl._window(Ys, taus, obs, kx, int(Ps[0].lengths.shape[-1]), com0, T_ref, stop, on_slack, True, health, spp,
                   None, cols, tx)
        bl._close(obs, taus, Ys[-1], stop, T_ref, pers, status, cols, tx)
        return np.full(Bn, int(info["nfe"][-1])), np.full(Bn, int(info["nst"][-1])), status, {}
    return joint


def _c_source(n: int, zero: frozenset) -> tuple[str, list]:
    """The odeint kernel's generated statements as a C function
    ``kern(y, out, params)`` (the same expressions; Python's float
    operations are the C double ones)."""
    text, params = mx._kernel_source(n, zero, True, False, "odeint")
    body = text.split("y.tolist()\n", 1)[1].split("        return _out")[0]
    lines = [ln.strip() for ln in body.strip().splitlines()]
    outs, depth, cur = [], 0, ""
    for ch in lines.pop()[len("_pack(_buf, 0, "):-1]:  # the packed outputs, split at top-level commas
        depth += (ch == "(") - (ch == ")")
        if ch == "," and depth == 0:
            outs.append(cur.strip())
            cur = ""
        else:
            cur += ch
    outs.append(cur.strip())
    seen: set = set()
    stmts = []
    for ln in lines:
        tgt, expr = ln.split(" = ", 1)
        stmts.append(("" if tgt in seen else "double ") + f"{tgt} = {expr};")
        seen.add(tgt)
    src = ("void kern(const double *y, double *o, const double *p) {\n"
           + "".join(f"double {v} = y[{i}];\n" for i, v in enumerate(mx._STATE_NAMES))
           + "".join(f"double {v} = p[{i}];\n" for i, v in enumerate(params)) + "\n".join(stmts) + "\n"
           + "".join(f"o[{i}] = {e};\n" for i, e in enumerate(outs)) + "}\n")
    return src, params


def _compiled(build: str):
    """A replacement of ``compiled_kernel``: odeint's kernels (up to three
    wires) compiled as C, one module a wire count and zero pattern."""
    from cffi import FFI

    modules: dict = {}
    built: list = []
    failed: list = []

    def kernel(P, stabilise=True, extras=False, signature="args", physical=False, derivatives=True, ticks=None):
        n = int(P.lengths.shape[-1])
        if signature != "odeint" or ticks is not None or not stabilise or extras or n > mx.MAX_ELIMINATION_WIRES:
            return _KERNEL(P, stabilise, extras, signature, physical, derivatives, ticks)
        cache = P.__dict__.get("_kernels")
        if cache is None:
            cache = {}
            object.__setattr__(P, "_kernels", cache)
        if "C" not in cache:
            if "values" not in cache:
                vals = mx._param_values(P)
                cache["values"] = (vals, mx._zero_set(vals))
            vals, zero = cache["values"]
            if (n, zero) not in modules:
                t0 = time.perf_counter()
                src, params = _c_source(n, zero)
                name = f"_probe_kernel_{len(modules)}"
                ffi = FFI()
                ffi.cdef("void kern(const double *y, double *o, const double *p);")
                ffi.set_source(name, src, extra_compile_args=["-O2", "-ffp-contract=off", "-w"])
                try:
                    ffi.compile(tmpdir=build)
                    modules[n, zero] = (importlib.import_module(name), params)
                except Exception as exc:  # evaluate_point reports a point's error as an invalid point: kept here
                    failed.append(exc)
                    raise
                built.append(time.perf_counter() - t0)
            mod, params = modules[n, zero]
            pv, out = np.array([vals[p] for p in params], float), np.empty(13)
            pp, op = mod.ffi.from_buffer("double[]", pv), mod.ffi.from_buffer("double[]", out)

            def f(y, t, kern=mod.lib.kern, fb=mod.ffi.from_buffer, op=op, pp=pp, out=out, keep=pv):
                kern(fb("double[]", y), op, pp)
                return out
            cache["C"] = f
        return cache["C"]
    kernel.built, kernel.failed = built, failed
    return kernel


def _install(patch: dict) -> None:
    bl._lsoda_joint = batch._lsoda_joint = patch.get("joint", _JOINT)
    mx.compiled_kernel = patch.get("kernel", _KERNEL)


def _points(patch: dict) -> dict:
    _install(patch)
    try:
        out = {}
        for name, params in POINTS:
            cfg = read_yaml(ROOT / "configs" / name)
            r = sw.evaluate_point(cfg, name, params, sw.resolve_settings(cfg))
            r.pop("runtime_s", None)
            out[name + str(params)] = r
        return out
    finally:
        _install({})


def _max_change(a, b, path="") -> tuple[float, str]:
    """(largest relative change of a number, where) between two JSON trees;
    inf where their shapes or non-numbers differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        keys = set(a) | set(b)
        return max((_max_change(a.get(k), b.get(k), f"{path}.{k}") for k in keys), default=(0.0, path))
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return max((_max_change(u, v, f"{path}[{i}]") for i, (u, v) in enumerate(zip(a, b))), default=(0.0, path))
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool) and not isinstance(b, bool):
        if a == b or (a != a and b != b):
            return 0.0, path
        return abs(a - b) / max(abs(a), abs(b)), path
    return (0.0, path) if a == b else (math.inf, path)


def _ab(patch: dict, repeats: int) -> list[str]:
    """Per timed point: calls and kernel evaluations a point, CPU medians of
    the shipped path and the variant, interleaved."""
    lines = []
    for name, params in TIMED:
        cfg = read_yaml(ROOT / "configs" / name)
        st = sw.resolve_settings(cfg)
        cpu: dict = {"shipped": [], "variant": []}
        counts = {}
        for i in range(repeats + 1):
            for arm, p in (("shipped", {}), ("variant", patch)):
                _install(p)
                _COUNT.update(calls=0, kernels=0)
                c0 = time.process_time()
                sw.evaluate_point(cfg, name, params, st)
                if i:  # the first round warms the kernels (and builds the compiled ones)
                    cpu[arm].append(time.process_time() - c0)
                counts[arm] = dict(_COUNT)
        _install({})
        s, v = (statistics.median(cpu[k]) * 1e3 for k in ("shipped", "variant"))
        lines.append(f"  {name} {params}: odeint calls {counts['shipped']['calls']} -> {counts['variant']['calls']}, "
                     f"kernel evaluations {counts['shipped']['kernels']} -> {counts['variant']['kernels']}, "
                     f"point {s:.1f} -> {v:.1f} ms CPU (medians of {repeats}, interleaved)")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stacked", action="store_true")
    ap.add_argument("--compiled", action="store_true")
    ap.add_argument("--repeats", type=int, default=11)
    a = ap.parse_args(argv)
    si.odeint = _counting_odeint
    print(f"load average {os.getloadavg()[0]:.1f}")
    base = _points({})
    variants = []
    if a.stacked:
        variants += [(f"stacked ({v})", {"joint": _stacked(v)}) for v in ("laws", "laws-rtol", "all")]
    build = None
    if a.compiled:
        try:
            build = tempfile.mkdtemp(prefix="bifilar_probe_")
            sys.path.insert(0, build)
            kern = _compiled(build)
            _points({"kernel": kern})  # builds every pattern once (fails here without cffi or a compiler)
            if kern.failed:
                raise kern.failed[0]
            variants.append(("compiled C kernel", {"kernel": kern}))
        except Exception as exc:  # noqa: BLE001 - a probe: cffi or the compiler missing is a result
            print(f"compiled C kernel: not available here ({type(exc).__name__}: {exc})")
    try:
        for label, patch in variants:
            change, where = _max_change(base, _points(patch))
            print(f"{label}: largest relative change of evaluate_point's JSON over {len(POINTS)} points "
                  f"{change:.3g}{' (' + where + ')' if change else ''}")
            if label == "compiled C kernel":
                print("  kernels built: " + ", ".join(f"{t:.2f} s" for t in patch["kernel"].built))
            print("\n".join(_ab(patch, a.repeats)))
    finally:
        if build:
            shutil.rmtree(build, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
