"""What a compiled right-hand side would cost: numba's import, first
compilation and call overhead (docs/performance.md, "Cost per simulated
period", Session 6).  numba is not a dependency of bifilar; this probe runs
only where it is installed (``pip install numba`` in a throw-away venv) and
exits 0 with a message otherwise.  Each figure is the median of ``--repeat``
fresh processes (import and compilation) or of the calls' per-call times.

Usage: python scripts/probe_numba.py [--repeat 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

CHILD = r'''
import time
t0 = time.process_time()
import numba
import numpy as np
t1 = time.process_time()

@numba.njit
def f(y, t):
    out = np.empty(13)
    a = y[0] * y[1] + y[2]
    for i in range(13):
        out[i] = a * y[i] - t
    return out

y = np.ones(13)
f(y, 0.0)
t2 = time.process_time()
n = 100000
t3 = time.perf_counter()
for _ in range(n):
    f(y, 0.0)
t4 = time.perf_counter()
print(numba.__version__, t1 - t0, t2 - t1, (t4 - t3) / n)
'''


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    try:
        import numba  # noqa: F401
    except ImportError:
        print("numba is not installed here: nothing to probe (pip install numba in a throw-away venv)")
        return 0
    rows = []
    for _ in range(a.repeat):
        out = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True, check=True).stdout.split()
        rows.append((out[0], *map(float, out[1:])))
    med = {"numba": rows[0][0],
           "import_s_cpu": statistics.median(r[1] for r in rows),
           "first_compile_s_cpu": statistics.median(r[2] for r in rows),
           "call_us": 1e6 * statistics.median(r[3] for r in rows)}
    if a.json:
        print(json.dumps(med))
    else:
        print(f"numba {med['numba']}: import {med['import_s_cpu']:.3f} s CPU, first compilation "
              f"{med['first_compile_s_cpu']:.3f} s CPU, a call from Python {med['call_us']:.2f} us "
              f"(medians of {a.repeat} processes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
