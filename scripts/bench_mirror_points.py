#!/usr/bin/env python
"""What taking a symmetric rig's mirror-image sigma points from their images
saves a sweep point (bifilar/estimation/mirror_points.py, sigma28): one
process, the same point evaluated alternately with the images (as shipped)
and without (``second_order.mirror_images`` returning none: every sigma
point computed, the code before sigma28), CPU time of each
``evaluate_point``, medians; the two points' JSON compared too (they must
be identical).  In-process pairs are robust to a loaded machine: both
sides see the same load in turn.

    python scripts/bench_mirror_points.py [--repeats 40]

Cases: bench_sweep's Solar Boat and trifilar points, and the drone (whose
Izz is not linear: the images are computed after all, so it pays the
check without the gain).
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
os.environ.setdefault("BIFILAR_NATIVE", "sync")

from bifilar.config import read_yaml  # noqa: E402
from bifilar.estimation import second_order as so  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

CASES = {"Solar Boat": (ROOT / "configs" / "solar_boat.yaml", {"spacing": 3.0}),
         "trifilar (KTH)": (ROOT / "configs" / "trifilar_kth.yaml", {}),
         "drone": (ROOT / "configs" / "drone_parallel.yaml", {})}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=40)
    args = ap.parse_args(argv)
    shipped = so.mirror_images
    print(f"load average at the start: {os.getloadavg()[0]:.1f}")
    for name, (path, params) in CASES.items():
        cfg = read_yaml(path)
        st = sw.resolve_settings(cfg)
        cpu = {"with images": [], "without": []}
        docs = {}
        for side in ("with images", "without") * 2:  # warm-up, both sides
            so.mirror_images = shipped if side == "with images" else (lambda pb, ctx, keys: {})
            docs[side] = json.dumps(sw.evaluate_point(cfg, str(path), params, st))
        for _ in range(args.repeats):
            for side in ("with images", "without"):
                so.mirror_images = shipped if side == "with images" else (lambda pb, ctx, keys: {})
                c0 = time.process_time()
                sw.evaluate_point(cfg, str(path), params, st)
                cpu[side].append(time.process_time() - c0)
        so.mirror_images = shipped
        a, b = statistics.median(cpu["with images"]), statistics.median(cpu["without"])
        diffs = statistics.median(x - y for x, y in zip(cpu["with images"], cpu["without"]))
        print(f"{name}: with images {1e3 * a:.2f} ms CPU, without {1e3 * b:.2f} ms (median of {args.repeats}); "
              f"median paired difference {1e3 * diffs:+.2f} ms; JSON identical: {docs['with images'] == docs['without']}")
    print(f"load average at the end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
