"""Marginal cost of a simulated period: ``simulate`` against the naive baseline.

Thesis plate (configs/thesis_plate_rest.yaml), torsion, amplitude 0.05 rad.
For each contender the loosest tolerance of TOLS whose 210-period run gives
the period within 1e-9 (relative) of a converged run from the same start
(the project's DOP853 at rtol 1e-13) is chosen; the marginal cost per period
is then (time of a 210-period run - time of a 10-period run) / 200, CPU time
(and wall time), medians of repeated runs.  Contenders:

* ``simulate`` with ``method="auto"`` (the CLI's default since issue 14:
  LSODA through odeint on the compiled model, via the batched engine's
  one-scene path);
* the same with a progress callback, as ``bifilar simulate`` calls it
  (a bar on a terminal, the stop check elsewhere: the callback the CLI
  passes when stderr is not a terminal); since session 12 the kernel ticks
  itself, before it was wrapped; since session 13 without the timed
  coordinate at every sample (``coordinate=False``: the CLI without
  ``--plot``);
* ``simulate`` with ``method="DOP853"`` (solve_ivp, the default before);
* ``naive``: the per-wire numpy right-hand side of
  ``bench_work_precision.naive_rhs_factory`` in a plain solve_ivp DOP853
  loop, period from the dense output.

Issue 14's target: simulate at least 100x cheaper per period than the naive
baseline.

``--scan``: instead, the period error (signed, against the converged run)
and right-hand-side calls a period of ``simulate`` (auto) over a grid of
rtol and amplitudes around the benchmark's: LSODA's error is not monotonic
in rtol (it settles on order 7 or 8), which decides the rtol the
benchmark's rule picks (docs/design.md, "Session 12, perf14").

Usage: python scripts/bench_simulate_marginal.py [--quick] [--json] [--scan]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
# odeint's C kernel (bifilar.models.native_kernel) built in the foreground on the warm-up, so the timed
# repeats measure the steady state; BIFILAR_NATIVE=0 in the environment measures the Python kernel
os.environ.setdefault("BIFILAR_NATIVE", "sync")
sys.path.insert(0, str(ROOT / "scripts"))

from bench_work_precision import scipy_run  # noqa: E402
from bifilar.analysis import batch as bt  # noqa: E402
from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import simulate  # noqa: E402
from bifilar.config import load_scene  # noqa: E402
from bifilar.interrupts import raise_if_stop_requested  # noqa: E402

TOLS = [1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11]
TARGET = 1e-9
AMP = 0.05


def _contenders(scene, rest, ms):
    md = ms.get("torsion")
    return {
        "simulate (auto: odeint LSODA)": lambda n, rt: simulate(scene, "torsion", AMP, n, rest=rest, modes=ms,
                                                                 rtol=rt, method="auto").period,
        "simulate, CLI path (auto, progress callback)": lambda n, rt: simulate(
            scene, "torsion", AMP, n, rest=rest, modes=ms, rtol=rt, method="auto",
            progress=lambda done, total: raise_if_stop_requested(), coordinate=False).period,
        "simulate (solve_ivp DOP853)": lambda n, rt: simulate(scene, "torsion", AMP, n, rest=rest, modes=ms,
                                                               rtol=rt, method="DOP853").period,
        "naive (per-wire numpy, solve_ivp DOP853)": lambda n, rt: scipy_run(scene, rest, md, AMP, n, "DOP853", rt,
                                                                            naive=True)[0],
    }


def _timed(fn, repeat):
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(walls), statistics.median(cpus)


def measure(quick: bool = False) -> dict:
    scene = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    ref = bt.run_one(scene, rest, ms.get("torsion"), AMP, 210, 1e-13, method="dop853").period
    out = {"reference_period_s": ref, "rows": []}
    for name, fn in _contenders(scene, rest, ms).items():
        naive = name.startswith("naive")
        rep = 1 if (quick or naive) else 3
        rt, err = TOLS[-1], None
        for tol in TOLS:
            err = abs(fn(210, tol) / ref - 1)
            if err <= TARGET:
                rt = tol
                break
        w210, c210 = _timed(lambda: fn(210, rt), rep)
        w10, c10 = _timed(lambda: fn(10, rt), 3 if not quick else 1)
        out["rows"].append({"method": name, "rtol": rt, "period_error": err,
                            "wall_ms_per_period": 1e3 * (w210 - w10) / 200,
                            "cpu_ms_per_period": 1e3 * (c210 - c10) / 200})
    naive = out["rows"][-1]
    for r in out["rows"]:
        r["speedup_cpu"] = naive["cpu_ms_per_period"] / r["cpu_ms_per_period"]
        r["speedup_wall"] = naive["wall_ms_per_period"] / r["wall_ms_per_period"]
    return out


SCAN_RTOLS = [3e-9, 2e-9, 1.5e-9, 1.2e-9, 1e-9, 8e-10, 6e-10, 4e-10, 3e-10]
SCAN_AMPS = [0.045, 0.05, 0.055]


def scan() -> dict:
    """{amplitude: [(rtol, signed period error, calls a period)]} of the
    210-period ``simulate`` (auto) run (``--scan``)."""
    scene = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    out = {}
    for amp in SCAN_AMPS:
        ref = bt.run_one(scene, rest, ms.get("torsion"), amp, 210, 1e-13, method="dop853").period
        out[amp] = [(rt, r.period / ref - 1, r.nfev / 210) for rt in SCAN_RTOLS
                    for r in [simulate(scene, "torsion", amp, 210, rest=rest, modes=ms, rtol=rt, method="auto")]]
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--scan", action="store_true", help="period error and calls a period over rtol and amplitude")
    a = ap.parse_args(argv)
    if a.scan:
        res = scan()
        if a.json:
            print(json.dumps({str(k): v for k, v in res.items()}))
        else:
            for amp, rows in res.items():
                print(f"amplitude {amp}: " + "  ".join(f"{rt:.1e}: {e:+.1e}/{n:.0f}" for rt, e, n in rows))
        return res
    res = measure(a.quick)
    if a.json:
        print(json.dumps(res))
    elif __name__ == "__main__":
        for r in res["rows"]:
            print(f"{r['method']:45s} rtol {r['rtol']:.0e} err {r['period_error']:.1e}: "
                  f"{r['cpu_ms_per_period']:.3f} ms/period CPU ({r['wall_ms_per_period']:.3f} wall), "
                  f"{r['speedup_cpu']:.0f}x")
    return res


if __name__ == "__main__":
    main()
