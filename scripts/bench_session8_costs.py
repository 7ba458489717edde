"""Two costs quoted in session 8's docs, rerunnable:

* ``simulate``: the default run of the thesis plate's torsion (10 periods,
  amplitude 0.05, rtol 1e-10) against the alternative to the period's error
  model that docs/design.md ("Simulate's health at the edges") rejected: one
  more period at rtol / 100 from the same start;
* ``period``: the fit of a quantised record resting on a level (15 pixels
  of amplitude at 30 fps for 40 s, whole pixels about a pixel, through the
  calibration polynomial of tests/test_signal_quantisation.py), which makes
  40 more re-quantised copies about that level, against the same record
  half a pixel off the level (the copies about the fitted offset only).

CPU time (``time.process_time``), medians of alternating repeats.

    python scripts/bench_session8_costs.py [--repeats 7]
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

from bench_progress_ticks import plate_torsion  # noqa: E402
from bifilar.analysis.simulate import simulate  # noqa: E402
from bifilar.estimation.signal import fit_period  # noqa: E402


def _cpu(f):
    t0 = time.process_time()
    out = f()
    return time.process_time() - t0, out


def _record(offset: float) -> tuple[np.ndarray, np.ndarray]:
    """Whole pixels of a 1.2345 s oscillation of 15 px, light damping, at 30
    fps for 40 s, resting ``offset`` px from a pixel, mapped to an angle."""
    t = np.arange(0.0, 40.0, 1 / 30.0)
    px = np.round(offset + 15.0 * np.exp(-0.002 * t) * np.cos(2 * np.pi * t / 1.2345 + 0.3))
    x = px / 300.0
    return t, x + 0.08 * x ** 2 - 0.3 * x ** 3


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    scene, rest, ms, mode = plate_torsion()
    run, extra = [], []
    for _ in range(args.repeats):
        run.append(_cpu(lambda: simulate(scene, mode, 0.05, 10, rest=rest, modes=ms, method="auto"))[0])
        extra.append(_cpu(lambda: simulate(scene, mode, 0.05, 1, rest=rest, modes=ms, method="auto", rtol=1e-12))[0])
    out = {"simulate_default_s": statistics.median(run), "one_period_at_rtol_1e-12_s": statistics.median(extra)}
    out["extra_run_ratio"] = out["one_period_at_rtol_1e-12_s"] / out["simulate_default_s"]
    print(f"simulate, thesis plate torsion, CPU medians of {args.repeats}: default run "
          f"{out['simulate_default_s'] * 1e3:.1f} ms; one period at rtol 1e-12 "
          f"{out['one_period_at_rtol_1e-12_s'] * 1e3:.1f} ms ({out['extra_run_ratio']:.0%} of it)")

    on, off = [], []
    for _ in range(args.repeats):
        ta, fa = _cpu(lambda: fit_period(*_record(0.0), model="viscous", crossing_check=False))
        tb, fb = _cpu(lambda: fit_period(*_record(0.5), model="viscous", crossing_check=False))
        if not fa.uncertainty["quantisation_test"].get("rest_on_level"):
            raise SystemExit("the record on a level was not found resting on it")
        if fb.uncertainty["quantisation_test"].get("rest_on_level"):
            raise SystemExit("the record half a pixel off was found resting on a level")
        on.append(ta)
        off.append(tb)
    out.update(period_on_level_s=statistics.median(on), period_off_level_s=statistics.median(off))
    print(f"period, quantised record at 30 fps for 40 s, CPU medians of {args.repeats}: resting on a level "
          f"{out['period_on_level_s']:.3f} s, half a pixel off {out['period_off_level_s']:.3f} s "
          f"({out['period_on_level_s'] / out['period_off_level_s']:.2f}x)")
    return out


if __name__ == "__main__":
    main()
