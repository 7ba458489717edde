#!/usr/bin/env python
"""The honest sigma of a sweep point and the fixed cost of a batch of sigma
points: CPU time (medians) and Python-level calls, optionally A/B against
another tree in alternating fresh processes.

    python scripts/bench_sigma_batch.py [--repeats 60] [--sizes 2,9,18,36] [--root TREE]
    python scripts/bench_sigma_batch.py --ab OTHER_TREE [--rounds 8]

Measured, warm, in one process (the tree imported is ``--root``, default
this script's tree; its first output line names it):

* ``honest``: :func:`bifilar.estimation.honest.honest_stds` as the Solar
  Boat's and the KTH trifilar's sweep point calls it (bench_sweep.py's
  points; the call captured from one :func:`evaluate_point`), and the whole
  point, CPU ms (medians of ``--repeats``);
* ``batch``: :func:`bifilar.estimation.second_order._solve_points` of the
  boat's first n sigma points (its first component's, the result cache
  off), n in ``--sizes``: the curve whose intercept is a batch's fixed cost
  (sigma28, session 28, hand-timed: 2 points 0.73 ms, 36 points 2.11);
* ``calls``: Python and C function calls (``sys.setprofile`` events) of
  one boat and one trifilar honest sigma: a count that no load moves.

``--ab OTHER``: runs this script ``--rounds`` times against each tree, the
two alternating (OTHER first), each run a fresh process, and prints each
figure's median over the rounds per tree and the change (this tree minus
OTHER).  Session 28 (fixed28).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
CASES = {"Solar Boat": ("solar_boat.yaml", {"spacing": 3.0}), "trifilar (KTH)": ("trifilar_kth.yaml", {})}


def _median_cpu(fn, repeats: int) -> float:
    """Median CPU s of ``fn()`` over ``repeats`` calls (after two warm-ups)."""
    fn(), fn()
    out = []
    for _ in range(repeats):
        c0 = time.process_time()
        fn()
        out.append(time.process_time() - c0)
    return statistics.median(out)


def _captured(root: Path, name: str, params: dict):
    """(honest_stds' args, kwargs, second_order's first call args, the point's
    callable) of a sweep point of ``configs/name``."""
    from bifilar.config import read_yaml
    from bifilar.estimation import honest, invert
    from bifilar.estimation import second_order as so
    from bifilar.studies import sweep as sw

    path = root / "configs" / name
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    got: dict = {}
    real_h, real_so = honest.honest_stds, so.second_order

    def rec_h(*a, **k):
        got.setdefault("honest", (a, k))
        return real_h(*a, **k)

    def rec_so(*a, **k):
        got.setdefault("second_order", a)
        return real_so(*a, **k)

    honest.honest_stds, so.second_order, invert.second_order = rec_h, rec_so, rec_so
    try:
        sw.evaluate_point(cfg, str(path), params, st)
    finally:
        honest.honest_stds, so.second_order, invert.second_order = real_h, real_so, real_so
    return got["honest"], got["second_order"], lambda: sw.evaluate_point(cfg, str(path), params, st)


def _calls(fn) -> int:
    """Python and C function calls made by ``fn()`` (``sys.setprofile``)."""
    n = 0

    def hook(frame, event, arg):
        nonlocal n
        if event in ("call", "c_call"):
            n += 1

    sys.setprofile(hook)
    try:
        fn()
    finally:
        sys.setprofile(None)
    return n - 1  # (setprofile(None) itself)


def measure(root: Path, repeats: int, sizes: list[int]) -> dict:
    """The figures of the module docstring, from the tree ``root``."""
    sys.path.insert(0, str(root))
    os.environ.setdefault("BIFILAR_NATIVE", "sync")
    import bifilar
    from bifilar.estimation import honest
    from bifilar.estimation import second_order as so

    out: dict = {"bifilar": bifilar.__file__}
    for case, (name, params) in CASES.items():
        (a, k), so_args, point = _captured(root, name, params)
        out[f"{case}: honest sigma, ms"] = 1e3 * _median_cpu(lambda: honest.honest_stds(*a, **k), repeats)
        out[f"{case}: point, ms"] = 1e3 * _median_cpu(point, max(5, repeats // 4))
        out[f"{case}: honest sigma, calls"] = _calls(lambda: honest.honest_stds(*a, **k))
        if case == "Solar Boat":
            pb, p, r, ctx, _ = so_args
            ctx = dataclasses.replace(ctx, cache=None)
            keys = [key for key in ctx.inputs if ctx.sigmas.get(key, 0) > 0]
            items = [((key, s), [(key, s * so.SIGMA_POINT * ctx.sigmas[key])]) for key in keys for s in (1, -1)]
            for n in sizes:
                pts = dict(items[:n])
                out[f"{case}: batch of {len(pts)} sigma points, ms"] = 1e3 * _median_cpu(
                    lambda: so._solve_points(pb, ctx, p, r, pts), repeats)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=60)
    ap.add_argument("--sizes", default="2,9,18,36", help="batch sizes (sigma points) of the fixed-cost curve")
    ap.add_argument("--root", default=str(HERE), help="the tree whose bifilar is measured")
    ap.add_argument("--ab", default=None, help="another tree: alternate fresh processes between it and --root")
    ap.add_argument("--rounds", type=int, default=8, help="with --ab: runs per tree")
    ap.add_argument("--json", action="store_true", help="print the figures as one JSON line")
    args = ap.parse_args(argv)
    sizes = [int(x) for x in args.sizes.split(",") if x]
    if args.ab is None:
        res = measure(Path(args.root).resolve(), args.repeats, sizes)
        if args.json:
            print(json.dumps(res))
        else:
            for key, v in res.items():
                print(f"{key}: {v:.3f}" if isinstance(v, float) else f"{key}: {v}")
        return 0
    trees = {"other": Path(args.ab).resolve(), "this": Path(args.root).resolve()}
    runs: dict = {t: [] for t in trees}
    load = []
    for _ in range(args.rounds):
        for t, root in trees.items():
            load.append(os.getloadavg()[0])
            cmd = [sys.executable, __file__, "--root", str(root), "--repeats", str(args.repeats), "--sizes",
                   args.sizes, "--json"]
            runs[t].append(json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
    print(f"this: {runs['this'][0]['bifilar']}\nother: {runs['other'][0]['bifilar']}")
    print(f"{args.rounds} rounds each, alternating fresh processes; load {min(load):.1f}-{max(load):.1f}")
    print(f"{'figure':50s} {'other':>9s} {'this':>9s} {'change':>9s}")
    for key in runs["this"][0]:
        if key == "bifilar":
            continue
        o = statistics.median(r[key] for r in runs["other"])
        n = statistics.median(r[key] for r in runs["this"])
        print(f"{key:50s} {o:9.3f} {n:9.3f} {n - o:+9.3f}" if "ms" in key else f"{key:50s} {o:9.0f} {n:9.0f} {n - o:+9.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
