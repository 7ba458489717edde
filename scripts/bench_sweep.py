#!/usr/bin/env python
"""Sweep points per second: the cost of one sweep point (all default
outputs: sensitivities, uncertainty budget, nonlinear runs, estimator
biases) on the thesis plate and the Solar Boat, beside one naive rest pose +
linear modes solve of the same scene (the yardstick of issue 14); and the
time of the 2-parameter Solar Boat plan of issue 14,
``bifilar plan configs/solar_boat.yaml --param spacing=1:4 --param length=2:5 --json``
(a fresh process each time, start-up included).

    python scripts/bench_sweep.py [--repeats 5] [--json FILE] [--no-plan]

Medians of CPU time (the load-robust measure; wall clock alongside).
Deterministic points, so every repeat does the same work.
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
sys.path.insert(0, str(ROOT))

from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

CASES = {"thesis plate": (ROOT / "configs" / "thesis_plate_rest.yaml", {"spacing": 3.0}),
         "Solar Boat": (ROOT / "configs" / "solar_boat.yaml", {"spacing": 3.0})}


def timed(fn, repeats: int) -> tuple[float, float]:
    """(median CPU s, median wall s) of ``fn()``."""
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(cpu), statistics.median(wall)


def bench(repeats: int = 5) -> dict:
    out = {}
    for name, (path, params) in CASES.items():
        cfg = read_yaml(path)
        st = sw.resolve_settings(cfg)
        no_nl = sw.resolve_settings(cfg, tensions=False)
        scene = scene_from_dict(cfg, warn=False)
        sw.evaluate_point(cfg, str(path), params, st)  # warm-up (imports, compiled kernels)
        point = timed(lambda: sw.evaluate_point(cfg, str(path), params, st), repeats)
        linear = timed(lambda: sw.evaluate_point(cfg, str(path), params, no_nl), repeats)
        naive = timed(lambda: linear_modes(scene, rest_pose(scene)), max(repeats, 20))
        out[name] = {"point_cpu_s": point[0], "point_wall_s": point[1], "points_per_s_cpu": 1 / point[0],
                     "point_without_nonlinear_cpu_s": linear[0], "rest_and_modes_cpu_s": naive[0],
                     "ratio_to_rest_and_modes": point[0] / naive[0]}
    return out


PLAN_ARGS = ["plan", str(ROOT / "configs" / "solar_boat.yaml"), "--param", "spacing=1:4", "--param", "length=2:5",
             "--json"]


def bench_plan(repeats: int = 3) -> dict:
    """(median CPU s of the child process, median wall s, evaluations) of the issue-14 plan."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cpu, wall, evals = [], [], None
    for _ in range(repeats):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        w0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "bifilar", *PLAN_ARGS], env=env, capture_output=True,
                             text=True, check=True).stdout
        wall.append(time.perf_counter() - w0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
        evals = json.loads(out)["evaluations"]
    return {"plan_cpu_s": statistics.median(cpu), "plan_wall_s": statistics.median(wall), "evaluations": evals}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", default=None, help="also write the results to this file")
    ap.add_argument("--no-plan", action="store_true", help="leave out the plan timing")
    args = ap.parse_args(argv)
    res = bench(args.repeats)
    for name, r in res.items():
        print(f"{name}: {1e3 * r['point_cpu_s']:.0f} ms CPU a point ({r['points_per_s_cpu']:.2f} points/s; "
              f"{1e3 * r['point_without_nonlinear_cpu_s']:.0f} ms without the nonlinear runs); one rest pose + modes "
              f"{1e3 * r['rest_and_modes_cpu_s']:.2f} ms: a point costs {r['ratio_to_rest_and_modes']:.0f}x that")
    if not args.no_plan:
        res["plan"] = p = bench_plan(args.repeats)
        print(f"Solar Boat 2-parameter plan: {p['plan_cpu_s']:.2f} s CPU ({p['plan_wall_s']:.2f} s wall), "
              f"{p['evaluations']} evaluations")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
