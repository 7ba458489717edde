"""What a progress bar costs a `simulate` run: the thesis plate's torsion,
200 periods at amplitude 0.05, by the library with ``progress=None`` and
with a no-op progress callback (what the CLI passes when it draws a bar:
the right-hand side then ticks every 1 % of the run), CPU time, median of
alternating pairs.  The periods must be identical (the wrapper only
forwards the call).

    python scripts/bench_progress_ticks.py [--pairs 7]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import simulate  # noqa: E402
from bifilar.config import load_scene  # noqa: E402


def plate_torsion():
    """The thesis plate's scene, rest pose, modes and torsion's label (the
    benchmarks' ``simulate`` case)."""
    scene = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    return scene, rest, ms, ms.pick(None).label


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=7)
    args = ap.parse_args(argv)
    scene, rest, ms, mode = plate_torsion()

    def run(progress):
        t0 = time.process_time()
        r = simulate(scene, mode, 0.05, 200, rest=rest, modes=ms, progress=progress)
        return time.process_time() - t0, r.period

    plain, ticked = [], []
    for _ in range(args.pairs):
        ta, pa = run(None)
        tb, pb = run(lambda done, total: None)
        if pa != pb:
            raise SystemExit(f"the periods differ: {pa!r} without progress, {pb!r} with it")
        plain.append(ta)
        ticked.append(tb)
    out = {"without_s": statistics.median(plain), "with_s": statistics.median(ticked)}
    out["ratio"] = out["with_s"] / out["without_s"]
    print(f"200-period run, CPU medians of {args.pairs} pairs: without progress {out['without_s']:.4f} s, "
          f"with progress {out['with_s']:.4f} s, ratio {out['ratio']:.3f} (periods identical)")
    return out


if __name__ == "__main__":
    main()
