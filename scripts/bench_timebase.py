#!/usr/bin/env python
"""What the time-base check (``bifilar.estimation.signal_timebase.check_time_base``,
docs/design.md "dropfix, session 17") adds to a record read without its
time column (``--sample-rate``).

Each case is a seeded synthetic camera record at 30 fps (a lightly damped
sinusoid of 0.1 rad with white noise, as dropfix's harness draws them),
fitted once by ``fit_period(model="auto")``; then ``check_time_base`` is
timed alone (process CPU, median of ``--repeats``), its ``refit`` the same
fit on the time base it proposes.  The cases: a clean record (the fit
leaves ~1x the white noise, so the frames' lattice is not searched:
``SEARCH_RESIDUAL_EXCESS``), and records with 1 % of their frames dropped
(the lattice searched, the frames put back and the record refitted).  The
script also prints the fit's own median CPU, for scale.  ``--ungated``
searches the lattice on every record (the gate set to 0), as before the
gate: what the gate saves on a clean record.

    python scripts/bench_timebase.py [--repeats 7] [--ungated] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's bifilar, not an installed copy

FS = 30.0
#: (label, period s, cycles, noise rad, share of frames dropped, seed)
CASES = [("clean, 1.0 s, 30 cycles", 1.0, 30, 1e-3, 0.0, 1),
         ("1 % dropped, 1.0 s, 30 cycles", 1.0, 30, 1e-3, 0.01, 2),
         ("1 % dropped, 2.0 s, 35 cycles", 2.0, 35, 1e-3, 0.01, 3)]


def record(T: float, cycles: int, noise: float, drop: float, seed: int):
    """(t on the nominal time base, s; y, rad; frames dropped)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, cycles * T, 1.0 / FS)
    y = 0.1 * np.exp(-0.01 * t) * np.cos(2 * np.pi * t / T + 0.3) + noise * rng.standard_normal(t.size)
    keep = rng.uniform(size=t.size) >= drop
    yk = y[keep]
    return np.arange(yk.size) / FS, yk, int((~keep).sum())


def cpu(f) -> tuple[float, object]:
    c0 = time.process_time()
    out = f()
    return time.process_time() - c0, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--ungated", action="store_true")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    from bifilar.estimation import signal_timebase
    from bifilar.estimation.signal import fit_period
    from bifilar.estimation.signal_timebase import check_time_base

    if args.ungated:
        signal_timebase.SEARCH_RESIDUAL_EXCESS = 0.0

    rows = []
    for label, T, cyc, nz, drop, seed in CASES:
        t, y, nd = record(T, cyc, nz, drop, seed)
        fits, checks, out = [], [], None
        for _ in range(args.repeats):
            dt_fit, fit = cpu(lambda: fit_period(t, y, model="auto"))
            dt_chk, out = cpu(lambda: check_time_base(t, y, fit, "sample_rate",
                                                      lambda tn: fit_period(tn, y, model="auto")))
            fits.append(dt_fit)
            checks.append(dt_chk)
        rows.append({"case": label, "samples": int(y.size), "dropped": nd,
                     "method": out["time_base"]["method"] if out else None,
                     "fit_ms": 1e3 * statistics.median(fits), "check_ms": 1e3 * statistics.median(checks)})
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    for r in rows:
        print(f"{r['case']}: {r['samples']} samples, {r['dropped']} dropped; fit {r['fit_ms']:.1f} ms CPU, "
              f"time-base check {r['check_ms']:.1f} ms CPU (median of {args.repeats}; outcome: "
              f"{r['method'] or 'no sign of dropped frames'})")


if __name__ == "__main__":
    main()
