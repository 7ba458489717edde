#!/usr/bin/env python
"""What invert's secant check (``bifilar.estimation.slope_check.secant_check``,
docs/design.md "secant, session 17" and "secant2, session 18") adds to an
inversion at a stated amplitude.

Each case is one ``invert --json`` run in-process (the CLI), timed as
process CPU, median of ``--repeats``, with the check and without it (the
check replaced by one that finds nothing, so no secant runs and no second
budget), alternated so that a change of the machine's load falls on both.
Also counted: the stated-amplitude runs the check makes (two per checked
(measurement, unknown) pair, one more for an end on the estimate; the
inputs' secants, one batch, are not among them).  Cases:

* audit17 row B3's draw k = 1 (the drone's swing-x near twice its pitch's
  period, 0.2 m +- 15 %, 20 cycles, Iyy; the inputs exact): the check runs
  and fires, and the budget is made again;
* the same with the inputs at their default stds: the inputs' secants
  (``input_secants``) run too, two an input (18 inputs);
* ``configs/measurements_example.yaml`` (three unknowns, three modes): the
  significance gate skips the pairs whose period does not depend on the
  unknown (no runs for them), the others are checked and agree;
* ``configs/trifilar_kth.yaml``'s torsion at 0.05 rad for 20 cycles, Izz:
  the flat table's estimate sits on the edge of the physical tensors, so
  the secant is one-sided (its end at the estimate run too).

    python scripts/bench_secant.py [--repeats 5] [--json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from test_secant_slope import DRONE, EXACT  # noqa: E402 (audit17 row B3's drone and exact inputs, one copy)


def cases(tmp: Path) -> list:
    drone = tmp / "drone.yaml"
    drone.write_text(DRONE)
    return [("B3 draw k = 1 (fires)", [str(drone), "--period", "swing-x=1.964393+-1e-4", "--amplitude", "0.2+-0.03",
                                      "--solve-for", "Iyy", "--cycles", "20", *EXACT]),
            ("B3 draw k = 1, default input stds (fires; the inputs' secants run)",
             [str(drone), "--period", "swing-x=1.964393+-1e-4", "--amplitude", "0.2+-0.03", "--solve-for", "Iyy",
              "--cycles", "20"]),
            ("measurements_example (gate skips some pairs)",
             ["--measurements", str(ROOT / "configs" / "measurements_example.yaml")]),
            ("trifilar_kth torsion, Izz (one-sided: on the edge)",
             [str(ROOT / "configs" / "trifilar_kth.yaml"), "--period", "torsion=1.4064+-1e-4", "--amplitude", "0.05",
              "--solve-for", "Izz", "--cycles", "20"])]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    from click.testing import CliRunner

    from bifilar.cli import main as cli
    from bifilar.estimation import slope_check

    real_check, real_factor = slope_check.secant_check, slope_check._unchecked_factor
    runs = [0]

    def counted(*a, **k):
        runs[0] += 1
        return real_factor(*a, **k)

    slope_check._unchecked_factor = counted
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for label, argv in cases(Path(d)):
            times = {"with": [], "without": []}
            n_runs, warned = 0, None
            for _ in range(args.repeats):
                for how in ("with", "without"):
                    slope_check.secant_check = real_check if how == "with" else (lambda *a, **k: ([], False))
                    runs[0] = 0
                    c0 = time.process_time()
                    r = CliRunner().invoke(cli, ["invert", *argv, "--json"])
                    times[how].append(time.process_time() - c0)
                    if r.exit_code != 0:
                        raise SystemExit(f"{label}: exit {r.exit_code}: {r.stderr.strip()[-300:]}")
                    if how == "with":
                        n_runs = runs[0]
                        warned = sum("not smooth" in w or "could not be checked" in w
                                     for w in json.loads(r.stdout)["warnings"])
            slope_check.secant_check = real_check
            rows.append({"case": label, "with_s": statistics.median(times["with"]),
                         "without_s": statistics.median(times["without"]), "secant_runs": n_runs,
                         "warnings": warned})
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    for r in rows:
        print(f"{r['case']}: invert {r['with_s']:.2f} s CPU with the check, {r['without_s']:.2f} s without "
              f"(+{r['with_s'] - r['without_s']:.2f} s; median of {args.repeats}); {r['secant_runs']} secant runs, "
              f"{r['warnings']} warning(s)")


if __name__ == "__main__":
    main()
