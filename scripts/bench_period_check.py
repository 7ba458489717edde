"""Cost of simulate's check of an irregular motion (docs/design.md, "A motion
that is not regular"), against another checkout without it.

Cases (``method="auto"``, the CLI's default, rtol 1e-10): the thesis plate's
torsion at 0.05 rad over 10 periods (the default run, clean: never checked);
the Solar Boat's roll at 0.05 rad over 10 periods (a default run that beats:
checked, agrees); the 6.4 cylinder's pitch at 0.3 rad over 40 periods
(beating, checked); the plate's swing-y at 1.5 m over 40 periods (irregular:
checked, warns); a trifilar plate's torsion at 3.0 rad over 10 periods
(audit18's row H2, the wires' turn at pi near: its cycles agree, but its
period lies 150 % from the linear one, so the run is checked by DOP853 since
session 18: ``run_accuracy.FAR_FROM_LINEAR``).  Each case is timed in a fresh process of each tree, the
trees alternating, CPU time (``time.process_time``) of ``simulate`` alone
(configs loaded, rest pose and modes solved before), medians over repeats.

    python scripts/bench_period_check.py --other /work/main [--rounds 3 --repeats 9] [--only CONFIG]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from conftest import plate3_yaml  # noqa: E402  audit18's row-H2 trifilar plate (not a shipped config)
CASES = [("thesis_plate_rest.yaml", "torsion", 0.05, 10), ("solar_boat.yaml", "roll", 0.05, 10),
         ("thesis_cylinder_6_4.yaml", "pitch", 0.3, 40), ("thesis_plate_rest.yaml", "swing-y", 1.5, 40),
         ("plate3 (audit18 H2)", "torsion", 3.0, 10)]

CHILD = r"""
import json, sys, time
from bifilar.config import load_scene
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
cfg, mode, amp, per, rep = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
sc = load_scene(cfg); rest = rest_pose(sc); ms = linear_modes(sc, rest)
simulate(sc, mode, amp, per, rest=rest, modes=ms, method="auto")  # warm-up (kernel built, caches)
out = []
for _ in range(rep):
    t0 = time.process_time()
    simulate(sc, mode, amp, per, rest=rest, modes=ms, method="auto")
    out.append(time.process_time() - t0)
print(json.dumps(out))
"""


def run(tree: Path, case, repeats: int, tmp: Path) -> list[float]:
    cfg, mode, amp, per = case
    path = ROOT / "configs" / cfg
    if cfg.startswith("plate3"):
        path = tmp / "plate3.yaml"
        path.write_text(plate3_yaml())
    env = {**os.environ, "PYTHONPATH": str(tree)}
    p = subprocess.run([sys.executable, "-c", CHILD, str(path), mode, str(amp), str(per),
                        str(repeats)], env=env, capture_output=True, text=True, check=True, cwd=str(tree))
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", required=True, type=Path, help="checkout to compare with (e.g. main)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--only", default=None, help="time only the cases whose config name starts with this")
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    for case in CASES:
        if a.only and not case[0].startswith(a.only):
            continue
        times = {"other": [], "this": []}
        for _ in range(a.rounds):
            times["other"] += run(a.other, case, a.repeats, tmp)
            times["this"] += run(ROOT, case, a.repeats, tmp)
        mo, mt = statistics.median(times["other"]), statistics.median(times["this"])
        print(f"{case[0]:26s} {case[1]:8s} A={case[2]:<5g} {case[3]:>3g} periods: other {1e3 * mo:7.1f} ms, "
              f"this {1e3 * mt:7.1f} ms CPU ({mt / mo:.2f}x)", flush=True)


if __name__ == "__main__":
    main()
