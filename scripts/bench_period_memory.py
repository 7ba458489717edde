#!/usr/bin/env python
"""Peak memory and time of ``bifilar period`` on a very long recording.

Writes (in a temporary directory, deleted afterwards) a CSV of ``--rows``
rows (default 10 million: t at 1 kHz and a slowly damped 1.3 s oscillation
with noise), then runs ``python -m bifilar period FILE --json`` in a child
process and reports its peak resident memory (``resource.getrusage``,
RUSAGE_CHILDREN, ru_maxrss in KiB on Linux) and wall time.  With
``--noise`` the samples are pure noise and the command must refuse them
(exit 2).

Usage::

    python scripts/bench_period_memory.py [--rows N] [--noise]

The file itself is not kept (10 million rows are ~400 MB of text).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def write_csv(path: Path, rows: int, noise_only: bool, chunk: int = 1_000_000):
    rng = np.random.default_rng(1)
    with open(path, "w") as fh:
        fh.write("t,x\n")
        for a in range(0, rows, chunk):
            t = np.arange(a, min(rows, a + chunk)) / 1000.0
            if noise_only:
                y = rng.standard_normal(t.size)
            else:
                y = np.exp(-1e-4 * t) * np.cos(2 * np.pi * t / 1.3) + 0.05 * rng.standard_normal(t.size)
            np.savetxt(fh, np.column_stack([t, y]), fmt="%.6f", delimiter=",")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--noise", action="store_true", help="pure noise: must exit 2")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "long.csv"
        t0 = time.time()
        write_csv(p, a.rows, a.noise)
        size = p.stat().st_size
        print(f"wrote {a.rows} rows ({size / 1e6:.0f} MB) in {time.time() - t0:.0f} s", file=sys.stderr)
        env = dict(os.environ, PYTHONPATH=str(REPO))
        t0 = time.time()
        r = subprocess.run([sys.executable, "-m", "bifilar", "period", str(p), "--json"], env=env,
                           capture_output=True, text=True)
        wall = time.time() - t0
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"rows {a.rows}, exit {r.returncode}, peak RSS {peak_mb:.0f} MiB, wall {wall:.1f} s")
    if r.returncode != 0:
        print(r.stderr.strip()[-400:])
    else:
        import json

        doc = json.loads(r.stdout)
        print(f"period {doc['period']:.7f} +- {doc['std']:.2g} s, model {doc['model']}")
    return 0 if (r.returncode == 2) == a.noise else 1


if __name__ == "__main__":
    sys.exit(main())
