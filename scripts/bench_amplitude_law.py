#!/usr/bin/env python
"""CPU time of one sweep point (``evaluate_point``, all default outputs)
with the stated amplitude's law and factor derivative (two more nonlinear
runs per component, docs/performance.md) against another checkout: the
thesis plate, the KTH trifilar and the Solar Boat (as scripts/bench_sweep.py)
at the default amplitude, and the Solar Boat at 0.3; and one ``invert
--period torsion=T --amplitude 0.3`` of the boat at spacing 1, length 2.

    python scripts/bench_amplitude_law.py --other /work/main [--rounds 3] [--repeats 7]

Each round runs both checkouts in fresh processes back to back (this tree,
then the other); per case the median over the repeats, then the median over
the rounds.  CPU time (``time.process_time``), the load-robust measure on a
shared machine.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, statistics, sys, time
import numpy as np
from bifilar.config import read_yaml, scene_from_dict
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import apply_params
from bifilar.analysis.simulate import simulate
from bifilar.estimation.invert import invert
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet
root, repeats = sys.argv[1], int(sys.argv[2])
cases = {"thesis plate": ("configs/thesis_plate_rest.yaml", {"spacing": 3.0}, None),
         "trifilar (KTH)": ("configs/trifilar_kth.yaml", {}, None),
         "Solar Boat": ("configs/solar_boat.yaml", {"spacing": 3.0}, None),
         "Solar Boat at 0.3": ("configs/solar_boat.yaml", {"spacing": 3.0}, 0.3)}
out = {}
for name, (path, params, amp) in cases.items():
    path = f"{root}/{path}"
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, **({"amplitude": amp} if amp else {}))
    sw.evaluate_point(cfg, path, params, st)
    ts = []
    for _ in range(repeats):
        c = time.process_time()
        sw.evaluate_point(cfg, path, params, st)
        ts.append(time.process_time() - c)
    out[name] = statistics.median(ts)
path = f"{root}/configs/solar_boat.yaml"
cfg = read_yaml(path)
scene = scene_from_dict(apply_params(cfg, {"spacing": 1.0, "length": 2.0}, path)[0], warn=False)
T = simulate(scene, "torsion", 0.3, 10, rtol=1e-10).period
ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                    [Measurement("torsion", T, 1e-3, "period", "--period", amplitude=0.3)])
ts = []
for _ in range(max(repeats // 2, 2)):
    c = time.process_time()
    invert(ms, solve_for=["Izz"], ladder=False)
    ts.append(time.process_time() - c)
out["invert --amplitude 0.3 (boat torsion)"] = statistics.median(ts)
print(json.dumps(out))
"""


def run(tree: Path, repeats: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    r = subprocess.run([sys.executable, "-c", CHILD, str(tree), str(repeats)], env=env, capture_output=True,
                       text=True, check=True, cwd=str(tree))
    return json.loads(r.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--other", required=True, help="the checkout to compare with (e.g. main's)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    here, other = [], []
    for _ in range(a.rounds):
        here.append(run(ROOT, a.repeats))
        other.append(run(Path(a.other).resolve(), a.repeats))
    for name in here[0]:
        h = statistics.median(r[name] for r in here)
        o = statistics.median(r[name] for r in other)
        print(f"{name:40s} other {1e3 * o:8.1f} ms  this {1e3 * h:8.1f} ms  ratio {h / o:.2f}")


if __name__ == "__main__":
    main()
