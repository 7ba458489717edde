"""Cost of the period sensitivities of one scene: analytic against finite differences.

For the thesis plate (CoM on the attachment line: a neutral mode, some
inputs differenced one-sidedly), the thick plate (CoM 0.5 m below CD) and the
Solar Boat: ``period_sensitivity`` (analytic, :mod:`bifilar.analysis.derivatives`)
and ``period_sensitivity_fd`` (42-ish rest-pose + mode solves, the method
before issue 14) for every inertia component and measured input, rest pose
included; medians of CPU time, and the largest difference between the two
relative to each mode's largest derivative.

Usage: python scripts/bench_sensitivity.py [--repeat 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.config import load_scene, scene_from_dict  # noqa: E402
from bifilar.estimation.sensitivity import (INERTIA_COMPONENTS, measured_inputs, period_sensitivity,  # noqa: E402
                                            period_sensitivity_fd)


def _thick_plate():
    return scene_from_dict({"body": {"mass": 100.0, "inertia": {"principal": [100 * 25 / 12, 100 * 6.25 / 12,
                                                                              100 * 31.25 / 12]}},
                            "rig": {"anchors": [[0, -5, 0], [0, 5, 0]], "attachments": [[0, -2.5, 0.5], [0, 2.5, 0.5]],
                                    "lengths": [5.0, 5.0]}})


CASES = {
    "thesis plate (CoM on CD)": lambda: load_scene(ROOT / "configs" / "thesis_plate_rest.yaml"),
    "thick plate (CoM 0.5 m below CD)": _thick_plate,
    "Solar Boat": lambda: load_scene(ROOT / "configs" / "solar_boat.yaml"),
}


def _cpu(fn, repeat):
    out, ts = None, []
    for _ in range(repeat):
        c = time.process_time()
        out = fn()
        ts.append(time.process_time() - c)
    return out, statistics.median(ts)


def measure(repeat: int = 5) -> list[dict]:
    rows = []
    for name, make in CASES.items():
        scene = make()
        names = list(INERTIA_COMPONENTS) + measured_inputs(scene)
        an, t_an = _cpu(lambda: period_sensitivity(scene, names), repeat)
        fd, t_fd = _cpu(lambda: period_sensitivity_fd(scene, names), max(1, repeat // 2))
        live = np.isfinite(fd.periods)
        cols = [j for j, n in enumerate(names) if n not in fd.one_sided and n not in fd.undefined]
        A, F = an.jacobian[live][:, cols], fd.jacobian[live][:, cols]
        diff = float(np.max(np.abs(A - F) / np.max(np.abs(F), axis=1, keepdims=True)))
        rows.append({"case": name, "inputs": len(names), "analytic_ms": 1e3 * t_an, "fd_ms": 1e3 * t_fd,
                     "speedup": t_fd / t_an, "method": an.method, "max_rel_diff": diff})
    return rows


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    rows = measure(a.repeat)
    if a.json:
        print(json.dumps(rows))
    elif __name__ == "__main__":
        for r in rows:
            print(f"{r['case']:35s} {r['inputs']} inputs: analytic {r['analytic_ms']:.1f} ms, finite differences "
                  f"{r['fd_ms']:.1f} ms ({r['speedup']:.0f}x), max rel. difference {r['max_rel_diff']:.1e}")
    return rows


if __name__ == "__main__":
    main()
