"""Monte Carlo of ``bifilar invert``: the batched path against the draw-by-draw loop.

Usage::

    python scripts/bench_monte_carlo.py [--n 200] [--repeats 3]

Same drawn scenes fed to both solvers (bifilar.estimation.invert.solve_draws_loop
and solve_draws_batched); reports the median wall time of ``--repeats`` runs
and the largest difference between the two sets of estimates.  Returns the
rows for scripts/run_benchmarks.py.
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
from bifilar.config import load_scene  # noqa: E402
from bifilar.estimation.invert import (  # noqa: E402
    draw_monte_carlo, invert, solve_draws_batched, solve_draws_loop)
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet  # noqa: E402

CASES = [("thesis plate (CoM 0.5 m below CD), torsion -> Izz", "thesis_lin2_pitch.yaml", "torsion", "Izz"),
         ("Solar Boat, torsion -> Izz", "solar_boat.yaml", "torsion", "Izz"),
         ("drone, torsion -> Izz", "drone_parallel.yaml", "torsion", "Izz")]


def _median_time(fn, repeats: int) -> float:
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def main(argv=None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="n = 40, one repeat")
    a = ap.parse_args(argv)
    n, reps = (40, 1) if a.quick else (a.n, a.repeats)
    rows = []
    for name, cfg, mode, comp in CASES:
        s = load_scene(ROOT / "configs" / cfg)
        T = linear_modes(s, rest_pose(s)).get(mode).period
        ms = MeasurementSet([Hanging("h", s, np.eye(3))], [Measurement(mode, T, 1e-3, "period", "--period")])
        res = invert(ms, solve_for=[comp], ladder=False)
        draws = draw_monte_carlo(res, n, np.random.default_rng(1))
        loop = solve_draws_loop(res, draws)
        batch = solve_draws_batched(res, draws)
        ok = np.isfinite(loop[:, 0]) & np.isfinite(batch[:, 0])
        diff = float(np.max(np.abs(loop[ok, 0] - batch[ok, 0]) / np.abs(loop[ok, 0]))) if ok.any() else float("nan")
        t_loop = _median_time(lambda: solve_draws_loop(res, draws), reps)
        t_batch = _median_time(lambda: solve_draws_batched(res, draws), reps)
        rows.append({"case": name, "n": n, "loop": t_loop, "batch": t_batch, "speedup": t_loop / t_batch,
                     "max_rel_diff": diff, "repeats": reps})
        print(f"{name}: n={n} loop {t_loop:.3f} s, batched {t_batch:.3f} s ({t_loop / t_batch:.1f}x), "
              f"max rel. difference {diff:.1e}", file=sys.stderr)
    return rows


if __name__ == "__main__":
    main()
