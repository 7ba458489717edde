#!/usr/bin/env python
"""CPU a sweep point spends in its nonlinear runs (``simulate_batch``'s
calls) and, of that, inside ``odeint`` and outside it (the Python around
the integrations: kernels' set-up, samples' health, crossings, each run's
figures), for ``bench_sweep.py``'s three cases.  Written for session 27
(runs27: issue 14's last target, the runs' Python around odeint).

Per case: ``--points`` points after 5 warm-up points in this process, CPU
time (``time.process_time``) of the whole point and of every
``simulate_batch`` call (timers wrapped around ``simulate_batch`` and
``scipy.integrate.odeint``; ~1 us a call of their own).  Run it from a
tree's root (that tree's ``bifilar`` is imported); for an A/B, alternate two
trees' runs in fresh processes and take medians::

    python scripts/bench_point_runs.py [--points 60] [--case "Solar Boat"]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path.cwd()
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import scipy.integrate as si  # noqa: E402

import bifilar  # noqa: E402  (this tree's, before bench_sweep puts its own tree first on the path)
from bifilar.analysis import batch  # noqa: E402
from bifilar.config import read_yaml  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

import bench_sweep as bs  # noqa: E402  (its CASES; run from another tree, this script's copy)

_SPENT = {"runs": 0.0, "odeint": 0.0}


def _timed(fn, key):
    def wrapped(*a, **k):
        c0 = time.process_time()
        try:
            return fn(*a, **k)
        finally:
            _SPENT[key] += time.process_time() - c0
    return wrapped


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=60)
    ap.add_argument("--case", action="append", help="a bench_sweep case (default: all three)")
    args = ap.parse_args(argv)
    si.odeint = _timed(si.odeint, "odeint")
    batch.simulate_batch = _timed(batch.simulate_batch, "runs")
    print("bifilar imported from", bifilar.__file__)
    for case in args.case or list(bs.CASES):
        path, params = bs.CASES[case]
        cfg = read_yaml(path)
        st = sw.resolve_settings(cfg)
        for _ in range(5):
            sw.evaluate_point(cfg, str(path), params, st)
        _SPENT.update(runs=0.0, odeint=0.0)
        c0 = time.process_time()
        for _ in range(args.points):
            sw.evaluate_point(cfg, str(path), params, st)
        n = args.points
        tot = time.process_time() - c0
        print(f"{case}: point {1e3 * tot / n:.3f} ms CPU; its runs {1e3 * _SPENT['runs'] / n:.3f} ms, of which odeint "
              f"{1e3 * _SPENT['odeint'] / n:.3f} and the rest {1e3 * (_SPENT['runs'] - _SPENT['odeint']) / n:.3f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
