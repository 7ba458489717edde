"""Performance targets of issue 5, measured (medians of repeated runs).

Usage::

    python scripts/bench_targets.py [--quick] [--out FILE.json]

Normally run through ``scripts/run_benchmarks.py`` (writes docs/performance.md).

1. One scene (configs/thesis_plate_rest.yaml), 10 torsion periods at
   amplitude 0.05 rad, period error below 1e-9 relative: the whole pipeline
   from a loaded scene (rest pose, modes, start state, integration, measured
   period, health) against the naive baseline (same pipeline, the
   per-wire right-hand side of bench_work_precision.naive_rhs_factory in a
   plain solve_ivp DOP853 loop).  Each runs at the loosest tolerance of
   1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11 whose period error, against a
   converged reference measured in the same run, is below 1e-9.  Targets:
   >= 20x faster than the baseline and < 50 ms.
2. 1000 scenes (Monte Carlo draws around the thesis plate: wire lengths
   +-2 %, mass +-5 %, CoM 0.3..0.7 m below CD), 10 torsion periods each,
   batched from the scenes (rest poses and modes included), every checked
   scene's period error below 1e-9: < 5 s.
3. Rest pose and all modes: < 1 ms per scene batched (1000 scenes), < 20 ms
   for one scene.
4. ``bifilar --help``: < 0.3 s (fresh process).

Also measured: the batch engines' time per scene against the batch size
(where the vectorised engines overtake scene-by-scene runs), and the cost of
each rung of the fidelity ladder.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from bench_work_precision import atol_vector, naive_rhs_factory, period_from_dense, timed  # noqa: E402
from bifilar import __version__  # noqa: E402
from bifilar.analysis import batch as bt  # noqa: E402
from bifilar.analysis import fidelity as fd  # noqa: E402
from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import initial_state, simulate  # noqa: E402
from bifilar.config import load_scene  # noqa: E402

TOLS = [1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11]
TARGET_ERR = 1e-9


def naive_pipeline(scene, rtol, amplitude=0.05, periods=10):
    """The baseline: library rest pose, modes and start state, then the naive
    right-hand side in solve_ivp (DOP853), period from the dense output."""
    rest = rest_pose(scene)
    md = linear_modes(scene, rest).get("torsion")
    y0 = initial_state(scene, rest, md, amplitude)
    y0[:3] -= rest.com
    f = naive_rhs_factory(scene, rest.com)
    t_end = periods * md.period
    sol = solve_ivp(f, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol_vector(scene, md.period, amplitude, rtol),
                    dense_output=True)
    return period_from_dense(sol, md.period, t_end, bt._coordinate_vector(md.dominant, rest.q))


def ours(scene, rtol, amplitude=0.05, periods=10):
    return bt.simulate_batch([scene], "torsion", amplitude, periods, rtol=rtol)[0].period


def loosest(fn, scene, ref):
    """(rtol, error) of the loosest tolerance in TOLS meeting TARGET_ERR."""
    for rt in TOLS:
        err = abs(fn(scene, rt) - ref) / ref
        if err < TARGET_ERR:
            return rt, err
    return TOLS[-1], err


def monte_carlo(n, seed=0):
    base = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        L = base.lengths * (1 + 0.02 * rng.uniform(-1, 1, 2))
        h = rng.uniform(0.3, 0.7)
        att = base.attachments.copy()
        att[:, 2] = h
        out.append(base.with_changes(lengths=L, mass=base.mass * (1 + 0.05 * rng.uniform(-1, 1)),
                                     attachments=att, name=f"draw {len(out)}"))
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats and a smaller batch (smoke run)")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    rep = 3 if args.quick else 15
    out: dict = {"load_before": os.getloadavg()[0], "version": __version__}
    scene = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")

    # ---- 1. one scene
    ref = bt.simulate_batch([scene], "torsion", 0.05, 10, rtol=1e-13, method="dop853")[0].period
    ref2 = simulate(scene, "torsion", 0.05, 10, rtol=1e-13).period
    rt_ours, err_ours = loosest(ours, scene, ref)
    rt_naive, err_naive = loosest(naive_pipeline, scene, ref)
    _, w_ours, c_ours = timed(lambda: ours(scene, rt_ours), rep)
    _, w_naive, c_naive = timed(lambda: naive_pipeline(scene, rt_naive), max(3, rep // 3))
    _, w_sim, c_sim = timed(lambda: simulate(scene, "torsion", 0.05, 10, rtol=rt_naive), max(3, rep // 3))
    # where the time goes (one scene)
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    md = ms.get("torsion")
    _, w_rest, _ = timed(lambda: rest_pose(scene), rep)
    _, w_modes, _ = timed(lambda: linear_modes(scene, rest), rep)
    _, w_init, _ = timed(lambda: bt.initial_states([scene], [rest], [md], 0.05), rep)
    run1, w_run, _ = timed(lambda: bt.run_one(scene, rest, md, 0.05, 10, rt_ours), rep)
    run0, w_run0, _ = timed(lambda: bt.run_one(scene, rest, md, 0.05, 10, rt_ours, health=False), rep)
    out["breakdown"] = dict(rest=w_rest, modes=w_modes, init=w_init, run=w_run, run_no_health=w_run0,
                            nfev=run1.nfev)
    out["one_scene"] = dict(ref=ref, ref_check=abs(ref - ref2) / ref, rtol_ours=rt_ours, err_ours=err_ours,
                            rtol_naive=rt_naive, err_naive=err_naive, wall_ours=w_ours, cpu_ours=c_ours,
                            wall_naive=w_naive, cpu_naive=c_naive, wall_simulate=w_sim, cpu_simulate=c_sim,
                            speedup_wall=w_naive / w_ours, speedup_cpu=c_naive / c_ours)
    print(f"one scene: ours {w_ours * 1e3:.1f} ms (rtol {rt_ours:g}, err {err_ours:.1e}); naive {w_naive * 1e3:.0f} ms "
          f"(rtol {rt_naive:g}, err {err_naive:.1e}); x{w_naive / w_ours:.1f}", file=sys.stderr)

    # ---- 2. 1000 scenes
    nB = 200 if args.quick else 1000
    scenes = monte_carlo(nB)
    check = list(range(0, nB, nB // 20))
    refs = [bt.simulate_batch([scenes[k]], "torsion", 0.05, 10, rtol=1e-13, method="dop853")[0].period for k in check]
    chosen = None
    for rt in TOLS[1:]:
        runs = bt.simulate_batch(scenes, "torsion", 0.05, 10, rtol=rt)
        errs = [abs(runs[k].period - r) / r for k, r in zip(check, refs)]
        if max(errs) < TARGET_ERR:
            chosen = (rt, max(errs))
            break
    rt_b, err_b = chosen or (TOLS[-1], max(errs))
    _, w_b, c_b = timed(lambda: bt.simulate_batch(scenes, "torsion", 0.05, 10, rtol=rt_b), 1 if args.quick else 3)
    out["batch"] = dict(n=nB, rtol=rt_b, max_err=err_b, wall=w_b, cpu=c_b,
                        method=runs[0].method, health=dict(
                            viol=max(r.max_constraint_violation for r in runs),
                            drift=max(r.energy_drift for r in runs)))
    print(f"{nB} scenes: {w_b:.2f} s (rtol {rt_b:g}, max err {err_b:.1e})", file=sys.stderr)

    # ---- 3. rest pose and modes
    _, w_rm, c_rm = timed(lambda: bt.rest_and_modes(scenes), 3 if args.quick else 5)
    _, w_r1, c_r1 = timed(lambda: linear_modes(scene, rest_pose(scene)), rep * 3)
    _, w_r1b, c_r1b = timed(lambda: bt.rest_and_modes([scene]), rep * 3)
    out["rest_modes"] = dict(n=nB, wall_per_scene=w_rm / nB, cpu_per_scene=c_rm / nB, wall_one=w_r1, cpu_one=c_r1,
                             wall_one_batchapi=w_r1b)
    print(f"rest+modes: {w_rm / nB * 1e3:.3f} ms/scene batched, {w_r1 * 1e3:.2f} ms one", file=sys.stderr)

    # ---- 4. bifilar --help
    def helpcall():
        subprocess.run(["bifilar", "--help"], check=True, capture_output=True)

    _, w_h, _ = timed(helpcall, 7)
    out["help"] = dict(wall=w_h)
    print(f"bifilar --help: {w_h * 1e3:.0f} ms", file=sys.stderr)

    # ---- batch size scaling (time per scene), both engines, 10 periods at rtol 1e-10
    sizes = [1, 16, 32, 64, 200] + ([] if args.quick else [1000])  # >= SMALL_BATCH: the vectorised engines
    scal = []
    for B in sizes:
        sc = scenes[:B]
        rs, ms = bt.rest_and_modes(sc)
        for meth in ("dop853", "lsoda"):
            # below SMALL_BATCH "auto" runs scene by scene; force the vectorised engine to show the crossover
            def run(sc=sc, rs=rs, ms=ms, meth=meth):
                return bt._run_group(sc, rs, [m.get("torsion") for m in ms], np.full(len(sc), 0.05),
                                     np.full(len(sc), 10.0), 1e-10, None, "continue", None, True, None, meth, True) \
                    if len(sc) > 1 else bt.run_one(sc[0], rs[0], ms[0].get("torsion"), 0.05, 10, 1e-10, method=meth)
            _, w, c = timed(run, 1 if B >= 200 else 3)
            scal.append(dict(B=B, method=meth, wall_per_scene=w / B, cpu_per_scene=c / B))
            print(f"B={B:5d} {meth}: {w / B * 1e3:.2f} ms/scene", file=sys.stderr)
    out["scaling"] = scal

    # ---- fidelity ladder: cost of each rung (symmetric torsion / coupled pitch)
    sys.path.insert(0, str(ROOT / "tests"))
    from conftest import trapezoid  # the thesis-style scene builder of the tests
    sym = trapezoid(h=0.5)
    cpl = trapezoid(l1=5.0, l2=4.8, h=0.5)
    cases = [("closed-form", sym, "torsion", 1e-4, 1e-6), ("reduced-1dof", sym, "torsion", 0.1, 1e-9),
             ("linear", cpl, "torsion", 1e-4, 1e-6), ("full", cpl, "torsion", 0.05, 1e-9)]
    lad = []
    for name, s, mode, A, tol in cases:
        ans, w, c = timed(lambda: fd.period(s, mode, A, tol), rep)
        case = ("symmetric trapezoid" if s is sym else "unequal wires 5 / 4.8 m") + f" (CoM 0.5 m below CD), {mode}"
        lad.append(dict(expected=name, model=ans.model, tol=tol, amplitude=A, est=ans.est_error, wall=w, cpu=c,
                        case=case))
    out["ladder"] = lad
    out["load_after"] = os.getloadavg()[0]
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1, default=float))
    return out


if __name__ == "__main__":
    main()
