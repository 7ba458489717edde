#!/usr/bin/env python
"""What the call into odeint's C kernel costs a sweep point: the ctypes
``f(y, t)`` against the C-extension callable (session 26: perf26a's probe,
which built its own extension; since perfcall26 the shipped
``bifilar.models.native_call``).

``bifilar.models.native_kernel`` hands odeint either a Python ``f(y, t)``
that copies the state into a buffer and calls the compiled kernel through
:mod:`ctypes` (~1 us a call; a Solar Boat point makes ~3100), or, where
``native_call``'s extension is built, its callable doing the same (the
state's buffer copied, the same C function called through its address, the
same output array returned) without ctypes' argument conversion.  This
script runs the points of ``scripts/bench_sweep.py`` both ways (the ctypes
arm by turning the extension off for the measurement), checks that
``evaluate_point``'s JSON is the same, and prints the CPU a point takes
either way (medians, the two alternating in one process) and a call's cost
alone.  Needs a C compiler and the Python headers; else it says so and
exits 0.

    python scripts/probe_kernel_call.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("BIFILAR_NATIVE", "sync")

import numpy as np  # noqa: E402

from bifilar.config import read_yaml  # noqa: E402
from bifilar.models import native_call as nc  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

POINTS = [("solar_boat.yaml", {"spacing": 3.0}), ("trifilar_kth.yaml", {}), ("thesis_plate_rest.yaml", {"spacing": 3.0})]

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    shipped = nc._call_type
    arms = {"ctypes f(y, t)": lambda *a: None, "extension callable": shipped}
    from bifilar.config import load_scene
    from bifilar.models import maximal as mx
    P = mx.params_from_scenes(load_scene(ROOT / "configs" / "solar_boat.yaml", warn=False))
    mx.compiled_kernel(P, signature="odeint")  # the C kernel's and the extension's builds (sync)
    if nc._call_type is not shipped or not nc._call or nc._call[0].state != "ready":
        print("no C compiler or Python headers: nothing to measure")
        return 0
    print(f"load {os.getloadavg()[0]:.1f}; CPU a point, medians of {args.repeats}, the two alternating:")
    try:
        for name, params in POINTS:
            cfg = read_yaml(ROOT / "configs" / name)
            st = sw.resolve_settings(cfg)
            docs, cpu = {}, {a: [] for a in arms}
            for arm, call_type in arms.items():
                nc._call_type = call_type
                doc = sw.evaluate_point(cfg, name, params, st)  # warm-up (and the C kernel's build)
                doc.pop("runtime_s", None)
                docs[arm] = json.dumps(doc, sort_keys=True, default=repr)
            for _ in range(args.repeats):
                for arm, call_type in arms.items():
                    nc._call_type = call_type
                    c0 = time.process_time()
                    sw.evaluate_point(cfg, name, params, st)
                    cpu[arm].append(time.process_time() - c0)
            same = len(set(docs.values())) == 1
            a, b = (statistics.median(cpu[k]) * 1e3 for k in arms)
            print(f"  {name} {params}: {a:.2f} -> {b:.2f} ms ({b - a:+.2f}); JSON {'identical' if same else 'DIFFERS'}")
        # a call alone, on the Solar Boat's kernel
        y = np.array([0.01, -0.02, -0.9, 0.99, 0.05, -0.08, 0.1, 0.3, -0.2, 0.05, 0.7, -1.1, 2.3])
        for arm, call_type in arms.items():
            nc._call_type = call_type
            f = mx.compiled_kernel(mx.RigParams(**{k: getattr(P, k) for k in P.__dataclass_fields__}), signature="odeint")
            t = min(timeit.repeat(lambda: f(y, 0.0), number=20000, repeat=5)) / 20000 * 1e6
            print(f"  one call, {arm} ({type(f).__name__}): {t:.3f} us")
    finally:
        nc._call_type = shipped
    return 0


if __name__ == "__main__":
    sys.exit(main())
