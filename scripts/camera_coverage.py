"""Coverage of `bifilar period`'s 95 % interval on KTH-like camera records
(dev tool; docs/design.md "camera23, session 23", "camera26, session 26" and
"camera28, session 28").

Draws ``tests/test_readers20._camera_like(seed, dur)`` (a laser dot seen by a
240 fps camera: the torsion, its 2nd and 3rd harmonics, the ~2 s swing
leaking in with its own 2nd harmonic near the torsion's frequency, AR(1) and
white noise, a drift) with the duration fixed, fits each with
``fit_period(t, x, "auto")`` and counts the draws whose interval
``period +- q std`` holds the generated period (``q`` Student's 97.5 % point
where ``uncertainty["dof"]`` is given, else 1.959964).  Seeds are fixed:
``--first S`` ``--draws N`` uses seeds S .. S+N-1 (camera23 used 0-99;
camera26's independent check 1000-1299).

Printed per duration: coverage, its binomial se under the target
``sqrt(0.95 0.05 / N)``, the z of the coverage against 0.95 (negative:
under), the sd of ``(period - T) / std`` (1 for a calibrated std), the
median std, and how many draws got a nonzero 2nd-harmonic term.
``--rows FILE`` writes one JSON line a draw (the generator's own draws of
the swing and its 2nd harmonic, the fit's ``second_harmonic_fit``) for the
analysis of which draws miss.

    python scripts/camera_coverage.py --draws 300 --durations 10
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))  # this tree's bifilar, not an installed copy

from test_readers20 import _camera_like  # noqa: E402

from bifilar.estimation.signal import fit_period  # noqa: E402


def generator_draws(seed: int) -> dict:
    """The draws of ``_camera_like(seed)`` that fix the torsion, the swing and
    its 2nd harmonic (the same generator, the same order of draws; the
    noise's draws follow and depend on the duration): periods s, amplitudes px."""
    g = np.random.default_rng(20000 + seed)
    g.choice([5.0, 10.0, 20.0])
    T1, A1, Q1 = g.uniform(1.04, 1.07), g.uniform(70, 140), g.uniform(300, 1500)
    g.uniform(0, 2 * math.pi)
    h2, _, h3, _ = g.uniform(1, 4), g.uniform(0, 6.3), g.uniform(1, 4), g.uniform(0, 6.3)
    T2, _ = g.uniform(1.97, 2.0), g.uniform(0, 6.3)
    A2, B2, _ = g.uniform(2, 10), g.uniform(0, 1.5), g.uniform(0, 6.3)
    return {"T1": T1, "A1": A1, "Q1": Q1, "h2": h2, "h3": h3, "T2": T2, "A2": A2, "B2": B2}


def one(seed: int, dur: float) -> dict:
    """Fit one draw; the row of ``--rows`` (s, px; ``sep`` is ``2 f2 - f1``
    in units of ``1 / dur``)."""
    t, x, T = _camera_like(seed, dur)
    fit = fit_period(t, x, "auto")
    dof = fit.uncertainty.get("dof")
    q = float(stats.t.ppf(0.975, dof)) if dof else 1.959963984540054
    d = generator_draws(seed)
    assert abs(d["T1"] - T) < 1e-15  # the same draws as the generator's
    h2 = fit.uncertainty.get("second_harmonic_fit") or {}
    return {"seed": seed, "dur": dur, "model": fit.model, "T": T, "period": fit.period, "std": fit.std,
            "q": q, "z": (fit.period - T) / fit.std, "term": fit.uncertainty.get("second_harmonic", 0.0),
            "shift": h2.get("period_shift"), "shift_noise": h2.get("shift_noise"),
            "h2_amplitude": h2.get("amplitude"), "floor": h2.get("floor"), "leakage": h2.get("leakage"),
            "sep": (2 / d["T2"] - 1 / d["T1"]) * dur,
            **{k: d[k] for k in ("A1", "A2", "B2")}}


def summary(rows: list[dict]) -> str:
    """One line: coverage, se, z against 0.95, z sd, median std, draws with the term."""
    n = len(rows)
    cov = sum(abs(r["z"]) <= r["q"] for r in rows) / n
    se = math.sqrt(0.95 * 0.05 / n)
    zsd = float(np.sqrt(np.mean([r["z"] ** 2 for r in rows])))
    return (f"coverage {cov:.3f} (se {se:.3f}, z vs 0.95 {(cov - 0.95) / se:+.1f}), z sd {zsd:.2f}, "
            f"median std {np.median([r['std'] for r in rows]):.3g} s, term > 0 in "
            f"{sum(r['term'] > 0 for r in rows)} of {n}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--draws", type=int, default=100)
    ap.add_argument("--first", type=int, default=0, help="first seed")
    ap.add_argument("--durations", type=float, nargs="+", default=[5.0, 10.0, 20.0])
    ap.add_argument("--rows", help="write one JSON line a draw to this file")
    a = ap.parse_args(argv)
    out = open(a.rows, "w") if a.rows else None
    for dur in a.durations:
        t0 = time.process_time()
        rows = []
        for s in range(a.first, a.first + a.draws):
            rows.append(one(s, dur))
            if out:
                out.write(json.dumps(rows[-1]) + "\n")
                out.flush()
        print(f"{dur:g} s, seeds {a.first}-{a.first + a.draws - 1}: {summary(rows)}; "
              f"{time.process_time() - t0:.0f} s CPU", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
