"""What the config geometry's std costs `tensions --motion`: a 12 801-sample
record (the 1000 kg bifilar of docs/invert.md's tensions audit, torsion at
0.05 for 32 periods, 400 samples a period, 0.5 % load-cell noise), the fit
alone (``inertia_from_tensions``) against the fit with the geometry
(``geometry={}``) and its std (``record_std``), CPU time, medians.

    OPENBLAS_NUM_THREADS=1 python scripts/bench_tension_geometry.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import simulate  # noqa: E402
from bifilar.config import scene_from_dict  # noqa: E402
from bifilar.estimation.from_tensions import inertia_from_tensions, record_std  # noqa: E402
from bifilar.models import maximal as mx  # noqa: E402
from bifilar.rotations import quat_to_matrix  # noqa: E402


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    truth = scene_from_dict({"body": {"mass": 1000.0, "inertia": {"principal": [300.0, 500.0, 700.0]}},
                             "rig": {"anchors": [[-1.5, 0, 3.1], [1.5, 0, 3.1]],
                                     "attachments": [[-1.2, 0, 0.1], [1.2, 0, 0.1]], "lengths": [3.0, 3.0]}},
                            "heavy", warn=False)
    rest = rest_pose(truth)
    run = simulate(truth, "torsion", 0.05, 32, rest=rest, modes=linear_modes(truth, rest), rtol=1e-11,
                   samples_per_period=400)
    _, alpha, _, _ = mx.solve_dynamics(run.y, mx.params_from_scenes(truth), stabilise=False)
    com, R, omega = run.y[:, 0:3], quat_to_matrix(run.y[:, 3:7]), run.y[:, 10:13]
    T = run.tensions + np.random.default_rng(1).standard_normal(run.tensions.shape) * 5e-3 * run.tensions.mean(0)

    def fit_alone():
        inertia_from_tensions(truth, run.t, com, R, omega, T, alpha=alpha)

    def fit_with_geometry():
        est = inertia_from_tensions(truth, run.t, com, R, omega, T, alpha=alpha, geometry={})
        record_std(est, est)

    out = {"samples": len(run.t)}
    for name, fn in (("fit_alone_s", fit_alone), ("with_geometry_s", fit_with_geometry)):
        ts = []
        for _ in range(args.repeats):
            t0 = time.process_time()
            fn()
            ts.append(time.process_time() - t0)
        out[name] = statistics.median(ts)
    print(f"{out['samples']}-sample record, CPU medians of {args.repeats}: fit alone {out['fit_alone_s']:.3f} s, "
          f"with the geometry's std {out['with_geometry_s']:.3f} s")
    return out


if __name__ == "__main__":
    main()
