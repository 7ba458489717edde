#!/usr/bin/env python
"""The CLI on one BLAS thread against two (docs/performance.md, "Session 25,
minor25"): each command as a subprocess, the CLI's default (one thread, set
by ``bifilar.cli.limit_blas_threads`` where the environment sets none)
alternating with ``OPENBLAS_NUM_THREADS=N`` (N = 2 by default: one a core
here), wall and CPU (the child's user + sys) medians of ``--pairs`` pairs,
and whether the two JSON documents agree but for ``runtime_s``.

    python scripts/bench_blas_threads.py [--pairs 5] [--threads 2] [--only period]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KTH = ROOT.parent / "shared" / "data" / "trifilar-kth-2014" / "10s" / "0.30.csv"
COMMANDS = {
    "period": ["period", str(KTH), "--sample-rate", "240", "--column", "x", "--json"],
    "invert": ["invert", "--measurements", "configs/measurements_example.yaml", "--json"],
    "sweep": ["sweep", "configs/trifilar_kth.yaml", "--param", "length=0.8:1.2:3", "--json"],
    "simulate": ["simulate", "configs/thesis_plate_rest.yaml", "--json"],
}
_BLAS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _run(args: list, threads: int | None) -> tuple[float, float, dict]:
    env = {k: v for k, v in os.environ.items() if k not in _BLAS}
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = str(threads)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "bifilar", *args], cwd=ROOT, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(args)}: exit {p.returncode}: {p.stderr.strip().splitlines()[-1:]}")
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), json.loads(p.stdout)


def _strip(doc):
    if isinstance(doc, dict):
        return {k: _strip(v) for k, v in doc.items() if k != "runtime_s"}
    if isinstance(doc, list):
        return [_strip(v) for v in doc]
    return doc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", choices=sorted(COMMANDS), action="append")
    a = ap.parse_args(argv)
    print(f"load {os.getloadavg()[0]:.1f}; default (one thread) vs OPENBLAS_NUM_THREADS={a.threads}, "
          f"{a.pairs} pairs alternating, medians")
    for name in a.only or COMMANDS:
        if name == "period" and not KTH.exists():
            print("period: ../shared/data absent, skipped")
            continue
        res = {"default": [], "n": []}
        same = True
        for _ in range(a.pairs):
            w1, c1, d1 = _run(COMMANDS[name], None)
            w2, c2, d2 = _run(COMMANDS[name], a.threads)
            res["default"].append((w1, c1))
            res["n"].append((w2, c2))
            same &= _strip(d1) == _strip(d2)
        med = {k: [statistics.median(x[i] for x in v) for i in (0, 1)] for k, v in res.items()}
        print(f"{name:9s} wall {med['default'][0]:.2f} / {med['n'][0]:.2f} s   CPU {med['default'][1]:.2f} / "
              f"{med['n'][1]:.2f} s ({100 * (med['default'][1] / med['n'][1] - 1):+.0f} %)   JSON equal but "
              f"runtime_s: {same}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
