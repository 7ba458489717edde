#!/usr/bin/env python
"""Sweep points per second: the cost of one sweep point (all default
outputs: sensitivities, uncertainty budget, nonlinear runs, estimator
biases) on the thesis plate, the Solar Boat and the KTH trifilar, beside one naive rest pose +
linear modes solve of the same scene (the yardstick of issue 14); and the
time of the 2-parameter Solar Boat plan of issue 14,
``bifilar plan configs/solar_boat.yaml --param spacing=1:4 --param length=2:5 --json``
(a fresh process each time, start-up included); the cost per point of a
whole 2-parameter Solar Boat sweep (``--param spacing=1:4:7 --param
length=2:5:4``, 28 points, one process: total CPU / points); and, for that
sweep, what batching across its points would give (``--engines``): its
nonlinear runs scene by scene (what a point does) against the batched
DOP853 engine (per-scene steps) on all of them at once, and its
sigma-point scenes' rest poses + modes batched per point (what a point
does) against all in one batch, with whether each scene's figures are
bit-for-bit the same whatever else shares its batch (what ``--workers``
and ``--resume`` need).

    python scripts/bench_sweep.py [--repeats 5] [--json FILE] [--no-plan] [--engines] [--parts] [--grid-points]
    python scripts/bench_sweep.py --grid-points --other DIR [--rounds 3] [--repeats 5]

``--parts``: where one point's CPU goes (its sensitivity, the honest
sigma with its sigma points, the nonlinear runs, the biases).
``--grid-points``: each of the whole sweep's points alone beside the
default point, the whole sweep as ``run_sweep`` evaluates it (one
process: its points in chunks sharing their sigma-point batch, checked
bit for bit against each point alone), and the JSON a point adds
(:func:`bench_grid_points`);
with ``--other DIR`` only that, for this checkout's bifilar and DIR's, in
fresh processes alternating (:func:`bench_grid_points_ab`).

Medians of CPU time (the load-robust measure; wall clock alongside).
Deterministic points, so every repeat does the same work.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# the checkout whose bifilar is measured: this one, or another's for --grid-points --other (its children); the
# configs are always this checkout's
PACKAGE = Path(os.environ.get("BENCH_SWEEP_PACKAGE", ROOT))
sys.path.insert(0, str(PACKAGE))
# odeint's C kernel (bifilar.models.native_kernel) built in the foreground on the warm-up, so the timed
# repeats measure the steady state; BIFILAR_NATIVE=0 in the environment measures the Python kernel
os.environ.setdefault("BIFILAR_NATIVE", "sync")

from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

CASES = {"thesis plate": (ROOT / "configs" / "thesis_plate_rest.yaml", {"spacing": 3.0}),
         "Solar Boat": (ROOT / "configs" / "solar_boat.yaml", {"spacing": 3.0}),
         # the shipped KTH table: its two swings are a repeated eigenvalue (analytic derivatives since session 5)
         "trifilar (KTH)": (ROOT / "configs" / "trifilar_kth.yaml", {})}


def timed(fn, repeats: int) -> tuple[float, float]:
    """(median CPU s, median wall s) of ``fn()``."""
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return statistics.median(cpu), statistics.median(wall)


def bench(repeats: int = 5) -> dict:
    out = {}
    for name, (path, params) in CASES.items():
        cfg = read_yaml(path)
        st = sw.resolve_settings(cfg)
        no_nl = sw.resolve_settings(cfg, tensions=False)
        scene = scene_from_dict(cfg, warn=False)
        sw.evaluate_point(cfg, str(path), params, st)  # warm-up (imports, compiled kernels)
        point = timed(lambda: sw.evaluate_point(cfg, str(path), params, st), repeats)
        linear = timed(lambda: sw.evaluate_point(cfg, str(path), params, no_nl), repeats)
        naive = timed(lambda: linear_modes(scene, rest_pose(scene)), max(repeats, 20))
        out[name] = {"point_cpu_s": point[0], "point_wall_s": point[1], "points_per_s_cpu": 1 / point[0],
                     "point_without_nonlinear_cpu_s": linear[0], "rest_and_modes_cpu_s": naive[0],
                     "ratio_to_rest_and_modes": point[0] / naive[0]}
    return out


PLAN_ARGS = ["plan", str(ROOT / "configs" / "solar_boat.yaml"), "--param", "spacing=1:4", "--param", "length=2:5",
             "--json"]


def _child(args: list[str], tree: Path | None = None) -> tuple[float, float, str]:
    """(CPU s, wall s, stdout) of ``python -m bifilar ARGS`` in a fresh process run
    from the configs of ``tree`` (default this checkout) with ``tree`` first on
    PYTHONPATH, so that a ``git archive`` of another revision measures that
    revision (the installed copy is never the one timed)."""
    tree = Path(tree or ROOT)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "bifilar", *args], env=env, capture_output=True, text=True,
                         check=True, cwd=tree).stdout
    wall = time.perf_counter() - w0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), wall, out


def bench_plan(repeats: int = 3, tree: Path | None = None) -> dict:
    """(median CPU s of the child process, median wall s, evaluations) of the
    issue-14 plan, run from ``tree`` (default this checkout)."""
    cpu, wall, evals = [], [], None
    args = ["plan", "configs/solar_boat.yaml", *PLAN_ARGS[2:]]
    for _ in range(repeats):
        c, w, out = _child(args, tree)
        cpu.append(c)
        wall.append(w)
        evals = json.loads(out)["evaluations"]
    return {"plan_cpu_s": statistics.median(cpu), "plan_wall_s": statistics.median(wall), "evaluations": evals}


_YARDSTICK = """
import json, statistics, sys, time
sys.path.insert(0, ".")
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import read_yaml, scene_from_dict
out = {}
for case, path in json.loads(sys.argv[1]).items():
    scene = scene_from_dict(read_yaml(path), warn=False)
    linear_modes(scene, rest_pose(scene))  # warm-up (imports)
    cpu = []
    for _ in range(int(sys.argv[2])):
        c0 = time.process_time()
        linear_modes(scene, rest_pose(scene))
        cpu.append(time.process_time() - c0)
    out[case] = statistics.median(cpu)
print(json.dumps(out))
"""


def bench_yardstick(tree: Path, repeats: int = 20) -> dict:
    """Issue 14's yardstick as it was filed: one rest pose + linear modes solve
    (``linear_modes(scene, rest_pose(scene))``, CPU s, median of ``repeats``)
    of each :data:`CASES` config, by the code of ``tree`` (a ``git archive`` of
    the revision the issue was filed against), in a fresh process.  The
    issue's "at most 3x one naive rest-pose + modes solve" is read against
    this: the solve of today (:func:`bench`'s ``rest_and_modes_cpu_s``) got
    ~10x cheaper through the issue's own work, so a ratio to it measures that
    work twice."""
    cases = {case: str(Path("configs") / path.name) for case, (path, _) in CASES.items()}
    r = subprocess.run([sys.executable, "-c", _YARDSTICK, json.dumps(cases), str(repeats)], cwd=tree,
                       env={**os.environ, "PYTHONPATH": str(tree)}, capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def bench_sweep_cli(repeats: int = 3, tree: Path | None = None) -> dict:
    """CPU s a point of ``bifilar sweep configs/solar_boat.yaml`` over :data:`GRID`
    (28 points) as a user runs it, in fresh processes from ``tree`` (default this
    checkout): (CPU of the 28-point sweep - CPU of the 1-point sweep
    ``--param spacing=3``) / 27, so that start-up and the journal's set-up cancel;
    medians over ``repeats`` alternating pairs.  Any revision whose ``sweep``
    takes ``--param`` and ``--json`` can be measured, so the figure before issue
    14 is the same measurement."""
    grid = ["sweep", "configs/solar_boat.yaml", *[a for p in GRID for a in ("--param", p)], "--json"]
    one = ["sweep", "configs/solar_boat.yaml", "--param", "spacing=3", "--json"]
    per_point, points = [], None
    for _ in range(repeats):
        c28, _, out = _child(grid, tree)
        c1, _, _ = _child(one, tree)
        points = len(json.loads(out)["points"])
        per_point.append((c28 - c1) / (points - 1))
    return {"sweep_cli_points": points, "sweep_cli_point_cpu_s": statistics.median(per_point),
            "sweep_cli_points_per_s_cpu": 1 / statistics.median(per_point)}


GRID = ["spacing=1:4:7", "length=2:5:4"]


def _grid(cfg: dict, path: Path) -> list[dict]:
    from bifilar.studies.shorthands import check_param, parse_param

    specs = [parse_param(p) for p in GRID]
    for sp in specs:
        check_param(cfg, sp.name, sp.values)
    return sw.build_grid(specs)


def bench_grid(repeats: int = 3) -> dict:
    """CPU per point of the whole Solar Boat sweep (:data:`GRID`), one process."""
    path = CASES["Solar Boat"][0]
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    grid = _grid(cfg, path)
    sw.evaluate_point(cfg, str(path), grid[0], st)  # warm-up
    pts = []
    cpu, wall = timed(lambda: pts.append(sw.run_sweep(cfg, str(path), grid, st)), repeats)
    valid = sum(p["valid"] for p in pts[-1])
    return {"sweep_points": len(grid), "sweep_valid_points": valid, "sweep_cpu_s": cpu, "sweep_wall_s": wall,
            "sweep_point_cpu_s": cpu / len(grid)}


def bench_grid_points(repeats: int = 5) -> dict:
    """Where the whole sweep's CPU a point (:func:`bench_sweep_cli`) parts from
    the single point's (:func:`bench`): each of the :data:`GRID` sweep's 28
    points and the default Solar Boat point (``spacing = 3``) timed alone
    in one warm process, round after round (the default point first in
    each round, so that the load moves both alike), CPU medians of
    ``repeats`` a point; the calls of the batched engine a point makes
    (2: its own runs and its amplitude laws'; 3 where a law's ``dr/dI`` is
    run again at a tighter rtol, ``point_amplitude._refine_dr_dI``); and
    what ``sweep --json`` adds a point: its points made plain
    (``to_jsonable``) and written (``json.dumps``), CPU ms a point; and,
    in each round after the points alone, the 28 points by ``run_sweep``
    (one process, no journal; since sigbatch29 in chunks whose sigma
    points share one batch), CPU a point, its points checked to be each
    point's own JSON, byte for byte (raises otherwise)."""
    from bifilar.analysis import batch
    from bifilar.jsonable import to_jsonable

    path, params = CASES["Solar Boat"]
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    grid = _grid(cfg, path)
    todo = [dict(params)] + grid
    calls = [0]
    real = batch.simulate_batch

    def counted(*a, **k):
        calls[0] += 1
        return real(*a, **k)

    cpu: list = [[] for _ in todo]
    whole: list = []  # the 28 points as the sweep evaluates them (run_sweep, one process), CPU s a point
    ncalls = [0] * len(todo)
    points = []
    batch.simulate_batch = counted
    try:
        for p in todo:  # warm-up (imports, compiled kernels of every pattern)
            sw.evaluate_point(cfg, str(path), p, st)
        sw.run_sweep(cfg, str(path), grid, st)
        gc.collect()
        for _ in range(repeats):
            points = []
            for i, p in enumerate(todo):
                calls[0] = 0
                c0 = time.process_time()
                points.append(sw.evaluate_point(cfg, str(path), p, st))
                cpu[i].append(time.process_time() - c0)
                ncalls[i] = calls[0]
            c0 = time.process_time()
            swept = sw.run_sweep(cfg, str(path), grid, st)
            whole.append((time.process_time() - c0) / len(grid))
            if json.dumps(to_jsonable(swept)) != json.dumps(to_jsonable(points[1:])):
                raise RuntimeError("run_sweep's points are not each point's own, bit for bit")
    finally:
        batch.simulate_batch = real
    med = [statistics.median(c) for c in cpu]
    js = []
    for _ in range(repeats):
        c0 = time.process_time()
        json.dumps(to_jsonable({"points": points[1:]}), allow_nan=False)
        js.append((time.process_time() - c0) / len(grid))
    by_calls: dict = {}
    for m, n in zip(med[1:], ncalls[1:]):
        by_calls.setdefault(str(n), []).append(m)
    return {"default_point_cpu_s": med[0], "grid_points": len(grid),
            "grid_point_mean_cpu_s": statistics.mean(med[1:]), "sweep_point_cpu_s": statistics.median(whole),
            "grid_by_engine_calls": {k: {"points": len(v), "mean_cpu_s": statistics.mean(v)}
                                     for k, v in sorted(by_calls.items())},
            "grid_point_cpu_s": {sw.point_key(p): m for p, m in zip(grid, med[1:])},
            "json_cpu_s_a_point": statistics.median(js)}


def bench_grid_points_ab(other: Path, rounds: int = 3, repeats: int = 5) -> dict:
    """:func:`bench_grid_points` of this checkout's bifilar and of ``other``'s
    (a checkout, e.g. ``git worktree add --detach DIR main``), each in a
    fresh process running this script (so the same harness and configs),
    the two alternating over ``rounds`` (the first tree of a round
    alternating too); returns {tree: [each round's result]}."""
    trees = {"this": ROOT, "other": Path(other).resolve()}
    out: dict = {k: [] for k in trees}
    for r in range(rounds):
        for label in (["this", "other"] if r % 2 == 0 else ["other", "this"]):
            env = {**os.environ, "BENCH_SWEEP_PACKAGE": str(trees[label])}
            res = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--grid-points-child", "--repeats",
                                  str(repeats)], env=env, cwd=ROOT, capture_output=True, text=True, check=True)
            doc = json.loads(res.stdout.strip().splitlines()[-1])
            if not Path(doc["package"]).resolve().is_relative_to(trees[label]):
                raise RuntimeError(f"measured {doc['package']}, not {trees[label]}")
            out[label].append(doc)
            print(f"[round {r + 1}, {label} {trees[label]}] " + _grid_points_line(doc), flush=True)
    return out


def _refine_excess(gp: dict) -> float | None:
    """CPU s the points with a third engine call cost above the others (None: no such point)."""
    by = gp["grid_by_engine_calls"]
    return by["3"]["mean_cpu_s"] - by["2"]["mean_cpu_s"] if "3" in by and "2" in by else None


def _grid_points_line(gp: dict) -> str:
    ex = _refine_excess(gp)
    return (f"the default point (spacing = 3) {1e3 * gp['default_point_cpu_s']:.2f} ms, the {gp['grid_points']} "
            f"points of the sweep {1e3 * gp['grid_point_mean_cpu_s']:.2f} ms on average ("
            + ", ".join(f"{v['points']} with {k} calls of the batched engine {1e3 * v['mean_cpu_s']:.2f}"
                        for k, v in gp["grid_by_engine_calls"].items())
            + (f"; a point with 3 calls {1e3 * ex:.2f} ms above the others" if ex is not None else "")
            + f"); sweep --json's to_jsonable + json.dumps {1e3 * gp['json_cpu_s_a_point']:.3f} ms a point"
            + (f"; the sweep (run_sweep, one process) {1e3 * gp['sweep_point_cpu_s']:.2f} ms a point"
               if "sweep_point_cpu_s" in gp else ""))


def _run_figures(r) -> tuple:
    return (r.period, r.crossings.tobytes(), r.tension_min.tobytes(), r.tension_max.tobytes(), r.depth_max,
            r.max_constraint_violation, r.energy_drift)


def bench_engines() -> dict:
    """Batching across the points of the :data:`GRID` sweep: cost and batch
    independence of its nonlinear runs and of its sigma points' rest poses +
    modes (module docstring).  CPU s, one pass each."""
    import numpy as np

    from bifilar.analysis.batch import modes_batch, rest_poses, simulate_batch
    from bifilar.estimation import second_order as budget  # where the sigma points' periods are computed
    from bifilar.studies import point as pt

    path = CASES["Solar Boat"][0]
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg)
    grid = _grid(cfg, path)
    # the points' own nonlinear runs and sigma-point batches, recorded as the sweep makes them
    jobs, sigma = [], []
    real = budget._hanging_periods

    def record(scenes, rest, base_modes, *more):  # (more: the poses, batch geometry and mode sets if computed)
        sigma.append((list(scenes), rest))
        return real(scenes, rest, base_modes, *more)

    budget._hanging_periods = record
    try:
        for params in grid:
            try:
                _, pre = pt._prepare(cfg, str(path), params, st)
            except Exception:  # noqa: BLE001 - an invalid point has no runs
                continue
            jobs += [(pre.scene, pre.rest, pre.ms, pre.labels[k], pre.amplitude) for k in pre.runs]
    finally:
        budget._hanging_periods = real

    def runs(sel, method):
        return simulate_batch([jobs[i][0] for i in sel], mode=[jobs[i][3] for i in sel],
                              amplitude=[jobs[i][4] for i in sel], periods=st.periods, rtol=st.rtol,
                              rests=[jobs[i][1] for i in sel], modes=[jobs[i][2] for i in sel], method=method,
                              errors="return", independent=method == "dop853")

    n = len(jobs)
    c0 = time.process_time()
    single = [runs([i], "auto")[0] for i in range(n)]  # a point's engine: LSODA scene by scene
    c1 = time.process_time()
    dop = runs(list(range(n)), "dop853")
    c2 = time.process_time()
    by_size = {}
    for size in (3, 24):  # one point's runs; a chunk of 8 points
        c_ = time.process_time()
        for j in range(0, n, size):
            runs(list(range(j, min(n, j + size))), "dop853")
        by_size[size] = (time.process_time() - c_) / n
    dop_rev = runs(list(range(n))[::-1], "dop853")[::-1]
    dop_half = runs(list(range(0, n, 2)), "dop853")
    same_rev = sum(_run_figures(a) == _run_figures(b) for a, b in zip(dop, dop_rev))
    same_half = sum(_run_figures(dop[i]) == _run_figures(r) for i, r in zip(range(0, n, 2), dop_half))
    alone = list(range(0, n, 7))
    same_alone = sum(_run_figures(dop[i]) == _run_figures(runs([i], "dop853")[0]) for i in alone)
    dT = max(abs(a.period / b.period - 1) for a, b in zip(dop, single))
    dTen = max(float(np.max(np.abs(a.tension_max / b.tension_max - 1))) for a, b in zip(dop, single))
    # sigma points: per point (as now) against all of the sweep's in one batch
    scenes = [s for sc, _ in sigma for s in sc]
    guesses = [r for sc, r in sigma for _ in sc]
    c3 = time.process_time()
    for sc, r in sigma:
        modes_batch(sc, rest_poses(sc, r, errors="return"))
    c4 = time.process_time()
    rs = rest_poses(scenes, guesses, errors="return")
    modes_batch(scenes, rs)
    c5 = time.process_time()
    return {"runs": n, "runs_scene_by_scene_cpu_s": c1 - c0, "runs_dop853_one_batch_cpu_s": c2 - c1,
            "run_dop853_cpu_s_in_batches_of": {str(k): v for k, v in by_size.items()},
            "dop853_same_reversed": same_rev, "dop853_same_in_half_batch": same_half, "dop853_half_batch": len(dop_half),
            "dop853_same_alone": same_alone, "dop853_alone": len(alone),
            "dop853_vs_single_max_rel_period": dT, "dop853_vs_single_max_rel_tension_max": dTen,
            "sigma_batches": len(sigma), "sigma_scenes": len(scenes), "sigma_per_point_cpu_s": c4 - c3,
            "sigma_one_batch_cpu_s": c5 - c4}


#: the parts of a point timed by ``--parts``: (label, module, attribute); nested parts are inside the outer ones
PARTS = [("sensitivity", "bifilar.studies.point", "point_sensitivity"),
         ("honest sigma (all components)", "bifilar.estimation.honest", "honest_stds"),
         # (module second_order, where the budget calls them since session 16's split: patched on budget, which
         # only re-exports them, these rows read 0; the rest poses are taken in _solve_points since session 24)
         ("  of which sigma points: rest poses, modes, re-solve", "bifilar.estimation.second_order", "_solve_points"),
         ("    of which their modes", "bifilar.estimation.second_order", "_hanging_periods"),
         ("    of which re-solved", "bifilar.estimation.second_order", "_resolve"),
         ("    of which re-solved", "bifilar.estimation.second_order", "_one_step"),  # their first steps, batched
         ("start poses of the runs (checked)", "bifilar.analysis.simulate", "checked_start_poses"),
         ("amplitude laws' stepped scenes and their modes", "bifilar.studies.point", "_law_runs"),
         ("nonlinear runs (the point's and its amplitude laws')", "bifilar.studies.point", "_runs_at"),
         ("bias: thesis rung", "bifilar.studies.point", "_Ladder.thesis"),
         ("bias: linear estimate", "bifilar.studies.point", "linear_estimate")]


def bench_parts(repeats: int = 5) -> dict:
    """CPU s a point spent in each of :data:`PARTS` (means over ``repeats``
    points; the point's own rest pose, the small-angle rung and the
    bookkeeping are the rest of the total)."""
    import functools
    import importlib

    spent: dict = {}
    undo = []
    for label, mod, attr in PARTS:
        owner = importlib.import_module(mod)
        *path, name = attr.split(".")
        for p in path:
            owner = getattr(owner, p)
        real = getattr(owner, name)

        def wrapped(*a, _real=real, _label=label, **k):
            c0 = time.process_time()
            try:
                return _real(*a, **k)
            finally:
                spent[_label] = spent.get(_label, 0.0) + time.process_time() - c0

        setattr(owner, name, functools.wraps(real)(wrapped))
        undo.append((owner, name, real))
    out = {}
    try:
        for case, (path, params) in CASES.items():
            cfg = read_yaml(path)
            st = sw.resolve_settings(cfg)
            sw.evaluate_point(cfg, str(path), params, st)
            spent.clear()
            # the objects the runs before left pending (this script's earlier results) collected here, not by a
            # full collection inside a timed part (~23 ms: it read as the trifilar's sigma points' modes 4.7 ms a
            # point where they cost 1.9, perf26b); a point itself triggers none in a 84-point sweep
            gc.collect()
            total = timed(lambda: sw.evaluate_point(cfg, str(path), params, st), repeats)[0]
            n = repeats
            out[case] = {"point_cpu_s": total, **{k: v / n for k, v in spent.items()}}
    finally:
        for owner, name, real in undo:
            setattr(owner, name, real)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", default=None, help="also write the results to this file")
    ap.add_argument("--no-plan", action="store_true", help="leave out the plan timing")
    ap.add_argument("--engines", action="store_true", help="also measure batching across the sweep's points")
    ap.add_argument("--parts", action="store_true", help="also time the parts of one point")
    ap.add_argument("--grid-points", action="store_true",
                    help="also time each point of the 28-point sweep alone beside the default point, and the "
                         "JSON a sweep point adds (where the whole sweep's CPU a point parts from one point's)")
    ap.add_argument("--other", type=Path, default=None,
                    help="with --grid-points: also another checkout's bifilar, in fresh processes alternating with "
                         "this one's (--rounds); only that is measured")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of --other (default 3)")
    ap.add_argument("--grid-points-child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.grid_points_child:  # one tree's figures for --other (BENCH_SWEEP_PACKAGE names the tree)
        import bifilar

        print(json.dumps({"package": bifilar.__file__, **bench_grid_points(args.repeats)}))
        return 0
    if args.other is not None:
        if not args.grid_points:
            ap.error("--other goes with --grid-points")
        ab = bench_grid_points_ab(args.other, args.rounds, args.repeats)
        for label, docs in ab.items():
            ex = [e for e in map(_refine_excess, docs) if e is not None]
            print(f"{label} ({len(docs)} rounds, medians): the default point "
                  f"{1e3 * statistics.median(d['default_point_cpu_s'] for d in docs):.2f} ms, the sweep's mean point "
                  f"{1e3 * statistics.median(d['grid_point_mean_cpu_s'] for d in docs):.2f} ms, the whole sweep "
                  f"(run_sweep) {1e3 * statistics.median(d['sweep_point_cpu_s'] for d in docs):.2f} ms a point"
                  + (f", a point with 3 engine calls {1e3 * statistics.median(ex):.2f} ms above the others" if ex else "")
                  + f", the JSON {1e3 * statistics.median(d['json_cpu_s_a_point'] for d in docs):.3f} ms a point")
        if args.json:
            Path(args.json).write_text(json.dumps(ab, indent=1), encoding="utf-8")
        return 0
    res = bench(args.repeats)
    print(f"BIFILAR_NATIVE={os.environ['BIFILAR_NATIVE']} (odeint's C kernel: 0 = off)")
    for name, r in res.items():
        print(f"{name}: {1e3 * r['point_cpu_s']:.0f} ms CPU a point ({r['points_per_s_cpu']:.2f} points/s; "
              f"{1e3 * r['point_without_nonlinear_cpu_s']:.0f} ms without the nonlinear runs); one rest pose + modes "
              f"{1e3 * r['rest_and_modes_cpu_s']:.2f} ms: a point costs {r['ratio_to_rest_and_modes']:.0f}x that")
    res["sweep"] = g = bench_grid(args.repeats)
    print(f"Solar Boat sweep {' '.join('--param ' + p for p in GRID)}: {g['sweep_points']} points "
          f"({g['sweep_valid_points']} valid), {g['sweep_cpu_s']:.2f} s CPU ({g['sweep_wall_s']:.2f} s wall): "
          f"{1e3 * g['sweep_point_cpu_s']:.0f} ms CPU a point")
    if args.engines:
        res["engines"] = e = bench_engines()
        print(f"its {e['runs']} nonlinear runs: scene by scene {1e3 * e['runs_scene_by_scene_cpu_s'] / e['runs']:.1f} "
              f"ms a run, batched DOP853 {1e3 * e['runs_dop853_one_batch_cpu_s'] / e['runs']:.1f} ms a run in one batch ("
              + ", ".join(f"{1e3 * v:.1f} in batches of {k}" for k, v in e['run_dop853_cpu_s_in_batches_of'].items())
              + "); "
              f"DOP853 bit-identical when the batch is reversed: {e['dop853_same_reversed']} of {e['runs']}, "
              f"in half the batch: {e['dop853_same_in_half_batch']} of {e['dop853_half_batch']}, "
              f"alone: {e['dop853_same_alone']} of {e['dop853_alone']}; "
              f"DOP853 vs scene by scene: period {e['dop853_vs_single_max_rel_period']:.1e}, "
              f"peak tension {e['dop853_vs_single_max_rel_tension_max']:.1e} (max relative)")
        print(f"its sigma points: {e['sigma_scenes']} scenes in {e['sigma_batches']} batches, rest poses + modes "
              f"{1e3 * e['sigma_per_point_cpu_s'] / e['sigma_scenes']:.3f} ms a scene batched per point, "
              f"{1e3 * e['sigma_one_batch_cpu_s'] / e['sigma_scenes']:.3f} ms in one batch")
    if args.parts:
        res["parts"] = bench_parts(args.repeats)
        for case, r in res["parts"].items():
            print(f"{case} point, {1e3 * r['point_cpu_s']:.1f} ms CPU (median), where it goes (mean ms): "
                  + "; ".join(f"{k.strip()} {1e3 * r.get(k, 0.0):.1f}" for k in dict.fromkeys(k for k, _, _ in PARTS)))
    if args.grid_points:
        res["grid_points"] = gp = bench_grid_points(args.repeats)
        print(f"Solar Boat, each point alone (CPU medians of {args.repeats}): " + _grid_points_line(gp))
    if not args.no_plan:
        res["plan"] = p = bench_plan(args.repeats)
        print(f"Solar Boat 2-parameter plan: {p['plan_cpu_s']:.2f} s CPU ({p['plan_wall_s']:.2f} s wall), "
              f"{p['evaluations']} evaluations")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
