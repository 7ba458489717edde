#!/usr/bin/env python
"""What the symmetric-start check (``bifilar.analysis.symmetry_check``,
docs/design.md "symcheck, session 16") adds to a ``simulate`` run.

For each case, ``simulate(...)`` with ``check=True`` (the default) and with
``check=False`` are timed alternately in one process (rest pose and modes
given, so both time the run alone), and the script prints the medians of
CPU time and their difference: the check's cost on that run.  The cases:
the thesis plate's torsion and the Solar Boat's torsion at the default
10 periods and 0.05 rad (symmetric starts whose orbit is stable: the
multipliers are computed, no check run), and the plate's swing-y at 1.5 m
over 17 periods (unstable: a check run is made and folded in).  A regular
small run makes no period check (``needs_check``), so the difference is the
symmetric-start check's alone; the script says so per case.

    python scripts/bench_symcheck.py [--repeats 15] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's bifilar, not an installed copy
CASES = [("thesis plate torsion", "thesis_plate_rest.yaml", "torsion", 0.05, 10),
         ("Solar Boat torsion", "solar_boat.yaml", "torsion", 0.05, 10),
         ("thesis plate swing-y 1.5 m (unstable)", "thesis_plate_rest.yaml", "swing-y", 1.5, 17)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import needs_check, simulate
    from bifilar.config import load_scene

    out = []
    for name, cfg, mode, amp, periods in CASES:
        scene = load_scene(ROOT / "configs" / cfg, warn=False)
        rest = rest_pose(scene)
        ms = linear_modes(scene, rest)
        times = {True: [], False: []}
        res = None
        for _ in range(args.repeats):
            for check in (False, True):
                c = time.process_time()
                r = simulate(scene, mode, amp, periods, rest=rest, modes=ms, check=check)
                times[check].append(time.process_time() - c)
                if check:
                    res = r
        sym = res.period_symmetry or {}
        row = {"case": name, "cpu_check_ms": 1e3 * statistics.median(times[True]),
               "cpu_without_ms": 1e3 * statistics.median(times[False]),
               "check_run": sym.get("check") is not None, "multiplier": sym.get("multiplier"),
               "period_check": bool(needs_check(res))}
        row["added_ms"] = row["cpu_check_ms"] - row["cpu_without_ms"]
        out.append(row)
    if args.json:
        print(json.dumps(out, indent=1))
        return
    for r in out:
        print(f"{r['case']}: {r['cpu_without_ms']:.2f} ms without the check, {r['cpu_check_ms']:.2f} ms with it "
              f"(+{r['added_ms']:.2f} ms; multiplier {r['multiplier']}, check run {r['check_run']}, "
              f"period check {r['period_check']}; CPU medians of {args.repeats})")


if __name__ == "__main__":
    main()
