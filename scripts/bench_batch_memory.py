"""Per-scene cost and peak memory of the batched DOP853 engine at 1000 and 10 000 scenes.

Each batch size runs in a fresh process (so its peak resident memory is its
own): Monte Carlo draws around the thesis plate (as scripts/bench_targets.py),
rest poses and modes computed first (not timed), then
``simulate_batch(method="dop853", rtol=1e-9)`` for 10 torsion periods, with
the default health and lowest point.  Reported: wall and CPU time per scene
(median of ``--repeat`` runs) and the process's peak resident set size
(VmHWM, MB, includes the interpreter, numpy and scipy: the baseline
before the run is reported too).  Issue 14's targets: per-scene cost at
10 000 scenes no higher than at 1000, peak memory below 250 MB.

Usage: python scripts/bench_batch_memory.py [--sizes 1000 10000] [--repeat 3] [--chunk N] [--json]
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _child(n: int, repeat: int, package_dir: str | None = None, chunk: int | None = None) -> dict:
    sys.path.insert(0, str(ROOT / "scripts"))
    sys.path.insert(0, str(package_dir or ROOT))
    from bifilar.analysis import batch as bt  # first: the package's other modules then come from the same place
    if chunk:
        bt.CHUNK = chunk

    from bench_targets import monte_carlo

    scenes = monte_carlo(n, seed=1)
    rests, modes = bt.rest_and_modes(scenes)
    base_mb = _peak_mb()
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        runs = bt.simulate_batch(scenes, "torsion", 0.05, 10, rtol=1e-9, rests=rests, modes=modes, method="dop853")
        walls.append((time.perf_counter() - t0) / n)
        cpus.append((time.process_time() - c0) / n)
        del runs
    return {"scenes": n, "wall_ms_per_scene": 1e3 * statistics.median(walls),
            "cpu_ms_per_scene": 1e3 * statistics.median(cpus), "baseline_mb": base_mb,
            "peak_mb": _peak_mb()}


def _peak_mb() -> float:
    """Peak resident set size of this process, MB: VmHWM of /proc/self/status (ru_maxrss would
    carry over the parent's peak across fork and exec); ru_maxrss where /proc is missing."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def measure(sizes=(1000, 10000), repeat: int = 3, package_dir: str | None = None,
            chunk: int | None = None) -> list[dict]:
    """One fresh process per size; ``package_dir``: the ``bifilar`` to run (e.g. an older revision);
    ``chunk``: the engine's ``batch.CHUNK`` (scenes a chunk) instead of the package's."""
    out = []
    for n in sizes:
        extra = ["--package-dir", str(package_dir)] if package_dir else []
        extra += ["--chunk", str(chunk)] if chunk else []
        r = subprocess.run([sys.executable, __file__, "--child", str(n), "--repeat", str(repeat), *extra],
                           capture_output=True, text=True, check=True, cwd=ROOT)
        out.append(json.loads(r.stdout.strip().splitlines()[-1]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--child", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--package-dir", default=None, help="run the bifilar package found in this directory")
    ap.add_argument("--chunk", type=int, default=None, help="the engine's batch.CHUNK instead of the package's")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if a.child is not None:
        print(json.dumps(_child(a.child, a.repeat, a.package_dir, a.chunk)))
        return
    res = measure(a.sizes, a.repeat, a.package_dir, a.chunk)
    if a.json:
        print(json.dumps(res))
        return
    for r in res:
        print(f"{r['scenes']:6d} scenes: {r['wall_ms_per_scene']:.3f} ms/scene wall, {r['cpu_ms_per_scene']:.3f} ms CPU; "
              f"peak {r['peak_mb']:.0f} MB (before the run {r['baseline_mb']:.0f} MB)")


if __name__ == "__main__":
    main()
