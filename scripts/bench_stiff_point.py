#!/usr/bin/env python
"""The cost of one sweep point on a rig with ``rig.stiffness`` (docs/design.md
"eaunc, session 18"): a 200 kg trifilar and a 100 kg bifilar on 2 m wires of
EA 1e5 N (strain 6.5e-3 / 4.9e-3), each point's CPU (median of ``--repeats``)
beside the same rig without EA, and how many elastic rest poses
(:func:`bifilar.analysis.elastic_rest.elastic_rest`) one point solves, split
by the stage that asks for them (the point's sensitivity, the honest sigma's
budget and sigma points, the nonlinear runs and the rest).

    python scripts/bench_stiff_point.py [--repeats 5] [--no-tensions]
"""

from __future__ import annotations

import argparse
import math
import sys
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.analysis import elastic_rest as er  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

sys.path.insert(0, str(ROOT / "scripts"))
from bench_sweep import timed  # noqa: E402  (median CPU and wall s of a call)


def rig(n: int, mass: float, stiffness) -> dict:
    """n vertical 2 m wires on a 0.4 m circle, attachments 5 cm above the CoM (tests' audit16 rig)."""
    ang = [2 * math.pi * k / n + 0.3 for k in range(n)]
    pts = [[0.4 * math.cos(a), 0.4 * math.sin(a)] for a in ang]
    r = {"anchors": [[x, y, 0.0] for x, y in pts], "attachments": [[x, y, 0.05] for x, y in pts], "lengths": [2.0] * n}
    if stiffness is not None:
        r["stiffness"] = stiffness
    return {"name": f"heavy{n}", "body": {"mass": mass, "inertia": {"principal": [12.0, 14.0, 20.0]}}, "rig": r}


STAGES = {"point_sensitivity": "sensitivity", "honest_stds": "honest sigma", "simulate_batch": "runs",
          "_law_runs": "amplitude laws", "checked_start_poses": "start poses"}


def count_rests(fn) -> dict:
    """{stage: elastic rests solved} during ``fn()`` (the innermost named caller on the stack)."""
    counts: dict = {}
    orig = er.elastic_rest

    def counted(*a, **k):
        stage = "other"
        for fr in reversed(traceback.extract_stack()[:-1]):
            if fr.name in STAGES:
                stage = STAGES[fr.name]
                break
        counts[stage] = counts.get(stage, 0) + 1
        return orig(*a, **k)

    er.elastic_rest = counted
    try:
        fn()
    finally:
        er.elastic_rest = orig
    return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-tensions", action="store_true", help="leave out the nonlinear runs")
    a = ap.parse_args()
    for n, m in ((3, 200.0), (2, 100.0)):
        for ea in (1e5, None):
            cfg = rig(n, m, ea)
            st = sw.resolve_settings(cfg, components=["Izz"], tensions=not a.no_tensions)
            pt = sw.evaluate_point(cfg, "bench", {}, st)  # warm-up
            assert pt["valid"], pt["error"]
            t = timed(lambda: sw.evaluate_point(cfg, "bench", {}, st), a.repeats)[0]
            rests = count_rests(lambda: sw.evaluate_point(cfg, "bench", {}, st)) if ea else {}
            print(f"{n} wires, EA {ea}: point {t * 1e3:.0f} ms CPU, sigma(Izz) {pt['components']['Izz']['sigma']:.5g}, "
                  f"elastic rests {sum(rests.values())} {rests}")


if __name__ == "__main__":
    main()
