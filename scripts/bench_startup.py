"""Start-up cost of the CLI: ``bifilar modes CONFIG --json`` against ``python -c "import numpy"``.

Both commands are run alternately (so machine load hits both alike) as fresh
processes; the script reports medians of wall time and of CPU time (user +
system of the child, s) and their ratio.  The target of issue 14 is a wall-time
ratio of at most 3.  Uses the ``bifilar`` importable from this interpreter
(set PYTHONPATH to test a work tree).

Usage: python scripts/bench_startup.py [CONFIG] [--repeat N] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _run(argv: list[str], package_dir=None) -> tuple[float, float]:
    """Wall time and child CPU time (s) of one run of ``argv`` (in ``package_dir``, so that
    ``python -m bifilar`` finds that tree's package first; default this tree)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    env = None if package_dir is None else {**os.environ, "PYTHONPATH": str(package_dir)}
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, cwd=package_dir or ROOT, env=env)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def measure(config: str, repeat: int = 15, package_dir: str | None = None) -> dict:
    """Medians (s) of wall and CPU time of the two commands and their ratios.
    ``package_dir``: run the ``bifilar`` found there (e.g. an older revision)."""
    base = [sys.executable, "-c", "import numpy"]
    cmd = [sys.executable, "-m", "bifilar", "modes", str(ROOT / config), "--json"]
    _run(base), _run(cmd, package_dir)  # warm the file cache
    b, c = [], []
    for _ in range(repeat):
        b.append(_run(base))
        c.append(_run(cmd, package_dir))
    med = lambda xs, k: statistics.median(x[k] for x in xs)  # noqa: E731
    out = {
        "config": config, "repeat": repeat,
        "import_numpy_wall_s": med(b, 0), "import_numpy_cpu_s": med(b, 1),
        "modes_json_wall_s": med(c, 0), "modes_json_cpu_s": med(c, 1),
    }
    out["wall_ratio"] = out["modes_json_wall_s"] / out["import_numpy_wall_s"]
    out["cpu_ratio"] = out["modes_json_cpu_s"] / out["import_numpy_cpu_s"]
    return out


def heavy_modules(config: str) -> list[str]:
    """scipy / matplotlib modules loaded by ``modes CONFIG --json`` (should be none)."""
    code = ("import sys, runpy; sys.argv = ['bifilar', 'modes', %r, '--json']\n"
            "try:\n    runpy.run_module('bifilar', run_name='__main__')\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('scipy', 'matplotlib')), file=sys.stderr)"
            % config)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=os.environ)
    return eval(r.stderr.strip().splitlines()[-1])  # a printed list of str


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="?", default="configs/thesis_plate_rest.yaml")
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    res = measure(a.config, a.repeat)
    res["heavy_modules"] = heavy_modules(a.config)
    if a.json:
        print(json.dumps(res))
        return
    print(f"python -c 'import numpy'      wall {res['import_numpy_wall_s'] * 1e3:7.1f} ms   "
          f"cpu {res['import_numpy_cpu_s'] * 1e3:7.1f} ms")
    print(f"bifilar modes {a.config} --json  wall {res['modes_json_wall_s'] * 1e3:7.1f} ms   "
          f"cpu {res['modes_json_cpu_s'] * 1e3:7.1f} ms")
    print(f"ratio: wall {res['wall_ratio']:.2f}x  cpu {res['cpu_ratio']:.2f}x  (target: wall <= 3x)")
    print(f"scipy/matplotlib modules loaded: {len(res['heavy_modules'])}")


if __name__ == "__main__":
    main()
