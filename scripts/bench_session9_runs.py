#!/usr/bin/env python
"""The figures of docs/performance.md, "Session 9" (issue 14, a sweep point's
runs), rerunnable:

* ``runs``: per bench case of ``scripts/bench_sweep.py`` (thesis plate,
  Solar Boat, KTH trifilar), the CPU a point spends in its nonlinear runs
  (``point._runs_at``: its own runs and its amplitude laws') and how much
  of that is not ``odeint`` (the engine's bookkeeping: parameters,
  kernels, health, crossings, results); medians over ``--repeats`` points.
  With ``--other DIR`` the same is measured for the checkout in DIR, in
  fresh processes alternating with this one (``--rounds``), the way the
  session compared its branch with ``main``.
* ``lsoda``: LSODA's start-up on a Solar Boat point's first runs: the
  right-hand-side calls in each of the three periods, and the calls and
  the error (against an rtol 1e-13 run, in units of the state's scale)
  with a first step ``h0`` from 1e-4 to 1e-2 of a period, or the Adams
  order capped (``mxordn``): the options the session weighed and left.

    python scripts/bench_session9_runs.py [runs|lsoda|all] [--repeats 41] [--other DIR] [--rounds 3]

CPU time (``time.process_time``), the load-robust measure on a shared machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CASES = {"thesis plate": ("configs/thesis_plate_rest.yaml", {"spacing": 3.0}),
         "Solar Boat": ("configs/solar_boat.yaml", {"spacing": 3.0}),
         "trifilar (KTH)": ("configs/trifilar_kth.yaml", {})}


def runs_cost(repeats: int) -> str:
    """One line: per case the median CPU ms of a point's runs and of the part not in odeint."""
    import scipy.integrate as si

    import bifilar.studies.point as pt
    from bifilar.config import read_yaml
    from bifilar.studies import sweep as sw

    real, odeint = pt._runs_at, si.odeint
    cur = {"runs": 0.0, "odeint": 0.0}

    def timing(fn, key):  # fn, its CPU added to cur[key]
        def timed(*a, **kw):
            c0 = time.process_time()
            try:
                return fn(*a, **kw)
            finally:
                cur[key] += time.process_time() - c0
        return timed

    pt._runs_at, si.odeint = timing(real, "runs"), timing(odeint, "odeint")
    out = []
    try:
        for name, (path, params) in CASES.items():
            cfg = read_yaml(Path.cwd() / path)  # (the measured checkout's configs)
            st = sw.resolve_settings(cfg)
            sw.evaluate_point(cfg, path, params, st)  # warm-up (imports, kernels)
            tot, rest = [], []
            for _ in range(repeats):
                cur["runs"] = cur["odeint"] = 0.0
                sw.evaluate_point(cfg, path, params, st)
                tot.append(cur["runs"])
                rest.append(cur["runs"] - cur["odeint"])
            out.append(f"{name}: runs {1e3 * statistics.median(tot):.2f} ms, not odeint "
                       f"{1e3 * statistics.median(rest):.2f} ms")
    finally:
        pt._runs_at, si.odeint = real, odeint
    return "; ".join(out)


def lsoda_startup() -> str:
    """LSODA's calls per period and the h0 / mxordn variants on a Solar Boat point's first three runs."""
    import numpy as np
    import scipy.integrate as si

    from bifilar.config import read_yaml
    from bifilar.studies import sweep as sw

    path, params = CASES["Solar Boat"]
    cfg = read_yaml(ROOT / path)
    st = sw.resolve_settings(cfg)
    got, odeint = [], si.odeint

    def record(f, y, t, **kw):
        got.append((f, np.array(y, copy=True), np.array(t, copy=True), dict(kw)))
        return odeint(f, y, t, **kw)

    si.odeint = record
    try:
        sw.evaluate_point(cfg, path, params, st)
    finally:
        si.odeint = odeint
    lines = []
    for f, y, t, kw in got[:3]:
        T = float(t[-1]) / st.periods
        calls = []

        def counted(y_, t_, f=f, calls=calls):
            calls.append(t_)
            return f(y_, t_)

        Y, info = odeint(counted, y, t, **kw)
        per = np.array(calls) / T
        by_period = [int(np.sum((per >= k) & (per < k + 1))) for k in range(int(np.ceil(st.periods)))]
        ref, _ = odeint(f, y, t, **{**kw, "rtol": 1e-13, "atol": kw["atol"] * 1e-5})
        scale = kw["atol"] / kw["rtol"]

        def err(Y_):
            return float(np.max(np.abs(Y_ - ref) / scale))

        line = [f"run T = {T:.3f} s: {int(info['nfe'][-1])} calls (per period {by_period}), error {err(Y):.2e}"]
        for extra in [{"h0": x * T} for x in (1e-4, 1e-3, 1e-2)] + [{"mxordn": m} for m in (5, 6)]:
            Yx, ix = odeint(f, y, t, **kw, **extra)
            key = next(iter(extra))
            val = f"{extra[key] / T:g} T" if key == "h0" else extra[key]
            line.append(f"{key} {val}: {int(ix['nfe'][-1])} calls, error {err(Yx):.2e}")
        lines.append("; ".join(line))
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", nargs="?", default="all", choices=["runs", "lsoda", "all"])
    ap.add_argument("--repeats", type=int, default=41)
    ap.add_argument("--other", type=Path, help="another checkout measured alternately (runs only)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:  # the package of the checkout on PYTHONPATH, its configs from the working directory
        print(runs_cost(args.repeats))
        return
    sys.path.insert(0, str(ROOT))
    if args.what in ("runs", "all"):
        trees = [("this", ROOT)] + ([("other", args.other.resolve())] if args.other else [])
        for r in range(args.rounds if args.other else 1):
            for label, tree in trees:
                env = {**os.environ, "PYTHONPATH": str(tree)}
                out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", "--repeats",
                                      str(args.repeats)], env=env, cwd=tree, capture_output=True, text=True,
                                     check=True).stdout.strip()
                print(f"[{label} {tree}, round {r + 1}] {out}")
    if args.what in ("lsoda", "all"):
        print(lsoda_startup())


if __name__ == "__main__":
    main()
