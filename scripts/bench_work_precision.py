"""Work-precision benchmark: run time against error for every integrator and
model path the project offers, against a converged reference.

Usage::

    python scripts/bench_work_precision.py [--quick] [--out FILE.json]

Normally run through ``scripts/run_benchmarks.py``, which writes
docs/performance.md and the plots.  For every scene, method and tolerance
the script measures (median of repeated runs, wall clock and CPU time):

* the error of the measured period (upward crossings of the timed
  coordinate, as ``bifilar simulate`` measures it) against a converged
  reference (the project's DOP853 at rtol 1e-13, checked against LSODA
  at rtol 1e-13);
* the largest constraint violation | |d_i| - L_i | (m) and the energy drift
  max |E - E0| / |E0 - E_rest| the method itself reports;
* the final-state error: max(|dr| / L_max, 2 |dq|) at t_end against the
  reference (dimensionless, ~ radians);

over 10 periods (all methods) and 1000 periods (a few methods, one
tolerance each).  Methods:

* ``naive``: a deliberately straightforward per-wire Python/numpy
  implementation of the same equations (:func:`naive_rhs_factory`, checked
  against :func:`bifilar.models.maximal.rhs` at start-up) in a plain
  ``scipy.integrate.solve_ivp`` DOP853 loop -- the baseline every speed
  figure is divided by;
* ``scipy-RK45``, ``scipy-DOP853``, ``scipy-Radau``, ``scipy-LSODA``:
  ``solve_ivp`` on the compiled right-hand side (what
  :func:`bifilar.analysis.simulate.simulate` does);
* ``simulate``: :func:`bifilar.analysis.simulate.simulate` itself with
  solve_ivp's DOP853 (the default before issue 14); ``simulate-auto``: the
  same with ``method="auto"`` (the CLI's default since: LSODA through odeint);
* ``own-DOP853``: the project's DOP853 (:mod:`bifilar.integrators`) on
  Python floats, crossings on its dense output;
* ``odeint-LSODA``: LSODA through ``odeint`` (step loop in Fortran) on
  Python floats, crossings by degree-7 interpolation of 64 samples/period;
* ``batch-DOP853``, ``batch-LSODA``: the batched engines of
  :mod:`bifilar.analysis.batch` on B copies of the scene with slightly
  different wire lengths, time per scene.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.analysis import batch as bt  # noqa: E402
from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import initial_state, simulate  # noqa: E402
from bifilar.config import load_scene, scene_from_dict  # noqa: E402
from bifilar import integrators as itg  # noqa: E402
from bifilar.models import maximal as mx  # noqa: E402


# --------------------------------------------------------------------------
# the naive baseline
# --------------------------------------------------------------------------
def naive_rhs_factory(scene, anchor_shift=None, damping=0.0):
    """``f(t, y)`` of the maximal-coordinate model written the obvious way:
    3-vectors as numpy arrays, a Python loop over the wires, ``np.cross``,
    matrix products, ``np.linalg.solve`` -- the same equations (and
    Baumgarte rates) as :func:`bifilar.models.maximal.rhs`.

    ``damping`` (1/s): a viscous force ``-c m v`` on the CoM and torque
    ``-c I w`` on the body (mass-proportional damping, which the library's
    conservative model does not have): a mode of angular frequency omega
    then decays with the damping ratio ``c / (2 omega)``, Q = omega / c
    (tests/test_end_to_end_audit.py, a pendulum's free decay)."""
    m = scene.mass
    g = scene.gravity
    I = np.array(scene.inertia)
    Iinv = np.linalg.inv(I)
    anchors = np.array(scene.anchors) - (0.0 if anchor_shift is None else np.asarray(anchor_shift))
    att = np.array(scene.attachments)
    L = np.array(scene.lengths)
    alpha = beta = np.sqrt(g / L.min())
    n = len(L)

    def quat_to_R(q):
        q = q / np.linalg.norm(q)
        w, x, y, z = q
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])

    def rhs(t, y):
        r, q, v, w = y[0:3], y[3:7], y[7:10], y[10:13]
        R = quat_to_R(q)
        ww = R @ w
        tau = -np.cross(w, I @ w) - damping * (I @ w)
        Iinv_tau = Iinv @ tau
        ds, Jws, IJws, b = [], [], [], []
        for i in range(n):
            p = att[i]
            Rp = R @ p
            d = r + Rp - anchors[i]
            d_b = R.T @ d
            sdot = v + np.cross(ww, Rp)
            phi = 0.5 * (d @ d - L[i] ** 2)
            phidot = d @ sdot
            Jw = np.cross(p, d_b)
            IJw = Iinv @ Jw
            cen = d_b @ np.cross(w, np.cross(w, p))
            b.append(-(sdot @ sdot) - cen + g * d[2] + damping * (d @ v) - Jw @ Iinv_tau - 2 * alpha * phidot
                     - beta**2 * phi)
            ds.append(d)
            Jws.append(Jw)
            IJws.append(IJw)
        A = np.zeros((n, n))
        for i in range(n):
            for j in range(n):
                A[i, j] = ds[i] @ ds[j] / m + Jws[i] @ IJws[j]
        lam = np.linalg.solve(A, np.array(b))
        vdot = np.array([0.0, 0.0, -g]) - damping * v
        wdot = Iinv_tau.copy()
        for i in range(n):
            vdot = vdot + lam[i] * ds[i] / m
            wdot = wdot + lam[i] * IJws[i]
        qw, qx, qy, qz = q
        wx, wy, wz = w
        dq = 0.5 * np.array([-qx * wx - qy * wy - qz * wz, qw * wx + qy * wz - qz * wy,
                             qw * wy - qx * wz + qz * wx, qw * wz + qx * wy - qy * wx])
        dq = dq + (1.0 - q @ q) * q
        return np.concatenate([v, dq, vdot, wdot])

    return rhs


def check_naive(scene) -> float:
    """Largest relative difference between the naive and the library
    right-hand sides at random states (must be ~1e-15)."""
    f = naive_rhs_factory(scene)
    P = mx.params_from_scenes(scene)
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(20):
        y = rng.normal(size=13)
        a, b = f(0.0, y), mx.rhs(0.0, y, P)
        worst = max(worst, float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))))
    return worst


# --------------------------------------------------------------------------
# scenes
# --------------------------------------------------------------------------
def scenes() -> dict:
    """name -> (scene, mode, amplitude): the thesis reference trapezoid in
    torsion and a coupled case (unequal wires, CoM 0.5 m below the
    attachment line) in pitch."""
    plate = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    I = [100 * 5**2 / 12, 100 * 2.5**2 / 12, 100 * (5**2 + 2.5**2) / 12]
    coupled = scene_from_dict({
        "name": "unequal wires 5 / 4.8 m, CoM 0.5 m below CD",
        "body": {"mass": 100.0, "inertia": {"principal": I}},
        "rig": {"anchors": [[0, -5, 0], [0, 5, 0]], "attachments": [[0, -2.5, 0.5], [0, 2.5, 0.5]],
                "lengths": [5.0, 4.8]},
    })
    return {"plate-torsion": (plate, "torsion", 0.05), "coupled-pitch": (coupled, "pitch", 0.05)}


# --------------------------------------------------------------------------
# measurement helpers
# --------------------------------------------------------------------------
def timed(fn, repeats: int):
    """(result of the last call, median wall s, median CPU s)."""
    wall, cpu = [], []
    out = None
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return out, float(np.median(wall)), float(np.median(cpu))


def atol_vector(scene, T, amplitude, rtol):
    """The per-component absolute tolerance ``simulate`` uses."""
    om = 2 * np.pi / T
    Lmax = float(np.max(scene.lengths))
    a = max(abs(amplitude), 1e-6)
    return rtol * np.concatenate([np.full(3, a * Lmax), np.full(4, a), np.full(3, a * om * Lmax), np.full(3, a * om)])


def period_from_dense(sol, T, t_end, e, spp=64):
    """Measured period from a solve_ivp dense output: samples at ``spp`` per
    period, crossings of ``e . y`` by degree-7 interpolation."""
    K = max(int(np.ceil(spp * t_end / T)), 16)
    ts = np.linspace(0.0, t_end, K + 1)
    c = (e @ sol.sol(ts))[:, None]
    _, tx, _ = itg.sampled_crossings(c, ts[1] - ts[0])
    if len(tx) < 2:
        return None
    return float((tx[-1] - tx[0]) / (len(tx) - 1))


def scipy_run(scene, rest, md, amplitude, periods, method, rtol, naive=False):
    """One solve_ivp run (compiled or naive right-hand side), with its
    health at the solver steps: (period, violation, drift, y_end, nfev)."""
    T = md.period
    t_end = periods * T
    y0 = initial_state(scene, rest, md, amplitude)
    ys0 = y0.copy()
    ys0[:3] -= rest.com
    P = mx.params_from_scenes(scene)
    Ps = mx.RigParams(**{**{k: getattr(P, k) for k in P.__dataclass_fields__}, "anchors": P.anchors - rest.com})
    f = naive_rhs_factory(scene, rest.com) if naive else mx.make_flat_rhs(Ps)
    sol = solve_ivp(f, (0.0, t_end), ys0, method=method, rtol=rtol, atol=atol_vector(scene, T, amplitude, rtol),
                    dense_output=True)
    e = bt._coordinate_vector(md.dominant, rest.q)
    per = period_from_dense(sol, T, t_end, e)
    Y = sol.y.T
    viol = float(np.max(mx.constraint_violation(Y, Ps)))
    E = mx.energy(Y, Ps)
    drift = float(np.max(np.abs(E - E[0])) / abs(E[0]))
    yend = sol.y[:, -1].copy()
    yend[:3] += rest.com
    return per, viol, drift, yend, int(sol.nfev)


def pose_error(y, yref, Lmax) -> float:
    """max(|dr| / L_max, 2 |dq|) (q sign-aligned): ~ radians."""
    q, qr = y[3:7], yref[3:7]
    if np.dot(q, qr) < 0:
        q = -q
    return float(max(np.max(np.abs(y[:3] - yref[:3])) / Lmax, 2 * np.max(np.abs(q - qr))))


# --------------------------------------------------------------------------
# the benchmark
# --------------------------------------------------------------------------
METHODS_10 = {
    # method: tolerances (10-period runs); Radau and the naive loop are slow, so fewer
    "naive": [1e-6, 1e-8, 1e-9, 1e-10, 1e-12],
    "scipy-RK45": [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "scipy-DOP853": [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "scipy-Radau": [1e-5, 1e-6, 1e-7, 1e-8],
    "scipy-LSODA": [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "simulate": [1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "simulate-auto": [1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "own-DOP853": [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "odeint-LSODA": [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "batch-DOP853": [1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "batch-LSODA": [1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
}
LONG = [("own-DOP853", 1e-10), ("odeint-LSODA", 1e-10), ("scipy-DOP853", 1e-10), ("own-DOP853", 1e-12)]
BATCH = 200


def run_method(name, scene, rest, ms, md, amplitude, periods, rtol, repeats, batch_scenes=None):
    """(metrics dict) for one method and tolerance."""
    mode = md.label
    if name == "naive" or name.startswith("scipy-"):
        meth = "DOP853" if name == "naive" else name.split("-", 1)[1]
        (per, viol, drift, yend, nfev), wall, cpu = timed(
            lambda: scipy_run(scene, rest, md, amplitude, periods, meth, rtol, naive=(name == "naive")), repeats)
        return dict(period=per, viol=viol, drift=drift, y_end=yend, nfev=nfev, wall=wall, cpu=cpu)
    if name in ("simulate", "simulate-auto"):
        meth = "auto" if name == "simulate-auto" else "DOP853"
        r, wall, cpu = timed(lambda: simulate(scene, mode, amplitude, periods, rest=rest, modes=ms, rtol=rtol,
                                              method=meth), repeats)
        return dict(period=r.period, viol=r.max_constraint_violation, drift=r.energy_drift, y_end=None, nfev=r.nfev,
                    wall=wall, cpu=cpu)
    if name in ("own-DOP853", "odeint-LSODA"):
        meth = "dop853" if name == "own-DOP853" else "lsoda"
        r, wall, cpu = timed(lambda: bt.run_one(scene, rest, md, amplitude, periods, rtol, method=meth), repeats)
        return dict(period=r.period, viol=r.max_constraint_violation, drift=r.energy_drift, y_end=r.y_final,
                    nfev=r.nfev, wall=wall, cpu=cpu)
    if name.startswith("batch-"):
        meth = "dop853" if name == "batch-DOP853" else "lsoda"
        sc, rs, mss = batch_scenes
        B = len(sc)
        runs, wall, cpu = timed(lambda: bt.simulate_batch(sc, mode, amplitude, periods, rtol=rtol, rests=rs,
                                                         modes=mss, method=meth), max(1, repeats // 2))
        r = runs[0]  # scene 0 is the benchmark scene itself
        return dict(period=r.period, viol=max(x.max_constraint_violation for x in runs),
                    drift=max(x.energy_drift for x in runs), y_end=r.y_final, nfev=r.nfev, wall=wall / B,
                    cpu=cpu / B, batch=B)
    raise ValueError(name)


def reference(scene, rest, md, amplitude, periods):
    """Converged reference: own DOP853 at rtol 1e-13, and LSODA at 1e-13 as a check."""
    a = bt.run_one(scene, rest, md, amplitude, periods, 1e-13, method="dop853", lowest_point=False)
    b = bt.run_one(scene, rest, md, amplitude, periods, 1e-13, method="lsoda", lowest_point=False)
    return a, abs(a.period - b.period) / a.period


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer tolerances and repeats (smoke run)")
    ap.add_argument("--out", default=None, help="write the results as JSON here")
    args = ap.parse_args(argv)
    repeats = 1 if args.quick else 7
    t_all = time.perf_counter()
    results = {"rows": [], "long": [], "naive_check": {}, "references": {}}
    for key, (scene, mode, amp) in scenes().items():
        results["naive_check"][key] = check_naive(scene)
        rest = rest_pose(scene)
        ms = linear_modes(scene, rest)
        md = ms.get(mode)
        Lmax = float(np.max(scene.lengths))
        ref, ref_spread = reference(scene, rest, md, amp, 10)
        results["references"][key] = {"period": ref.period, "dop853_vs_lsoda": ref_spread, "linear_period": md.period,
                                      "mode": md.label, "amplitude": amp, "scene": scene.name}
        rng = np.random.default_rng(1)
        bsc = [scene] + [scene.with_changes(lengths=scene.lengths * (1 + 1e-3 * rng.uniform(-1, 1, scene.n_wires)))
                         for _ in range(BATCH - 1)]
        brs, bms = bt.rest_and_modes(bsc)
        for name, tols in METHODS_10.items():
            if args.quick:
                tols = tols[1::2] if name not in ("naive", "scipy-Radau") else tols[1:2]
            for rtol in tols:
                rep = 1 if name == "scipy-Radau" or args.quick else 3 if name == "naive" else repeats
                m = run_method(name, scene, rest, ms, md, amp, 10, rtol, rep, (bsc, brs, bms))
                row = {"scene": key, "method": name, "rtol": rtol, "periods": 10,
                       "period_err": None if m["period"] is None else abs(m["period"] - ref.period) / ref.period,
                       "viol": m["viol"], "drift": m["drift"],
                       "state_err": None if m["y_end"] is None else pose_error(m["y_end"], ref.y_final, Lmax),
                       "nfev": m["nfev"], "wall": m["wall"], "cpu": m["cpu"], "batch": m.get("batch", 1)}
                results["rows"].append(row)
                print(f"{key:14s} {name:13s} rtol={rtol:.0e}  err={row['period_err']!s:>22s}  "
                      f"wall={m['wall'] * 1e3:9.2f} ms  nfev={m['nfev']}", file=sys.stderr)
        if key == "plate-torsion":
            ref_long, spread = reference(scene, rest, md, amp, 1000)
            results["references"][key + "-1000"] = {"period": ref_long.period, "dop853_vs_lsoda": spread}
            for name, rtol in (LONG[:2] if args.quick else LONG):
                if name == "own-DOP853" and rtol < 1e-11 and args.quick:
                    continue
                m = run_method(name, scene, rest, ms, md, amp, 1000, rtol, 1)
                row = {"scene": key, "method": name, "rtol": rtol, "periods": 1000,
                       "period_err": abs(m["period"] - ref_long.period) / ref_long.period,
                       "viol": m["viol"], "drift": m["drift"],
                       "state_err": None if m["y_end"] is None else pose_error(m["y_end"], ref_long.y_final, Lmax),
                       "nfev": m["nfev"], "wall": m["wall"], "cpu": m["cpu"], "batch": 1}
                results["long"].append(row)
                print(f"{key:14s} {name:13s} rtol={rtol:.0e} 1000 periods err={row['period_err']:.2e} "
                      f"drift={m['drift']:.2e} wall={m['wall']:.2f} s", file=sys.stderr)
    results["total_s"] = time.perf_counter() - t_all
    results["repeats"] = repeats
    if args.out:
        Path(args.out).write_text(json.dumps(results, indent=1, default=float))
    return results


if __name__ == "__main__":
    main()
