#!/usr/bin/env python
"""What session 13 (perf15) tried on issue 14's two unmet targets, rerunnable.

* ``--h0``: a sweep point's LSODA runs started with odeint's first step
  ``h0`` set to FRAC x the sample spacing (1/64 of the mode's period):
  right-hand-side calls of the whole point, CPU, and the relative change
  of every component's sigma, the amplitude law's slope / factor gain and
  the amplitude factor r against the default start.
* ``--law-periods``: the amplitude laws' runs (the 0.9 A run and the
  stepped scenes' runs) over 2 or 4 periods instead of the point's 3: CPU
  and the same relative changes (the thesis plate, the Solar Boat, the
  trifilar, the 6.4 cylinder, thesis lin2).
* ``--rtol``: the stated-amplitude sigma of every component over the
  runs' (periods, rtol): 3 periods at 1e-8 (the sweep's), 10 at 1e-10
  (``invert``'s), and three more; the cylinder's Ixx, whose factor gain
  comes from a 1e-4 step that moves r by less than rtol 1e-8 resolves.
* ``--post``: ``simulate``'s marginal period without the integration
  (odeint's result replayed): the samples' health, crossings, copies and
  coordinate; with ``coordinate=False`` beside it (the CLI without
  ``--plot``).

What session 15 (perf17) measured, rerunnable:

* ``--point-batch``: a point's runs (its own with their health, its laws'
  without) as the point makes them (odeint's LSODA run by run) against all
  in one call of the batched DOP853 engine (``independent=True``), CPU and
  the largest relative period difference.
* ``--calls``: right-hand-side calls of a point's own runs and its law
  runs over 1, 2, 3 and 10 periods (LSODA's start against a period's
  calls: what a one-period run, its period from a Poincare return, could
  save).
* ``--two-term``: idea A's premise without its normal form: were the
  small-amplitude coefficient ``a`` of ``r = 1 + a A^2 + b A^4`` known
  exactly (here: fitted through runs at 0.25 A and 0.5 A, the point's
  periods, rtol 1e-12), the law's slope from the point's own run alone
  would be ``4 (r - 1) - 2 a A^2``; printed per component: the relative
  slope difference against the point's two-run slope and the sigma change
  it makes, ``delta (c_a / sigma)^2``, against the 1e-6 asked.

Each section monkeypatches the code it varies inside this process only.
CPU medians (``time.process_time``); compare only figures of one run.

    python scripts/bench_law_runs.py [--h0] [--law-periods] [--rtol] [--post]
                                     [--point-batch] [--calls] [--two-term]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import scipy.integrate as si  # noqa: E402

from bifilar.analysis import batch as bt  # noqa: E402
from bifilar.config import read_yaml  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

CONFIGS = ROOT / "configs"
POINTS = {"thesis plate": ("thesis_plate_rest.yaml", {"spacing": 3.0}),
          "Solar Boat": ("solar_boat.yaml", {"spacing": 3.0}),
          "trifilar (KTH)": ("trifilar_kth.yaml", {}),
          "6.4 cylinder": ("thesis_cylinder_6_4.yaml", {}),
          "thesis lin2": ("thesis_lin2_pitch.yaml", {})}
#: every shipped single-hanging config (--two-term, --calls)
EVERY = {**POINTS, "drone": ("drone_parallel.yaml", {}), "thesis lin1": ("thesis_lin1_torsion.yaml", {}),
         "thesis lin3": ("thesis_lin3_roll.yaml", {})}


def _cpu(fn, repeats: int = 5) -> float:
    out = []
    for _ in range(repeats):
        c0 = time.process_time()
        fn()
        out.append(time.process_time() - c0)
    return statistics.median(out)


def _figures(res: dict) -> dict:
    out = {}
    for c, e in res.get("components", {}).items():
        ab = e.get("amplitude_budget", {})
        out[c] = (e.get("sigma"), ab.get("slope"), ab.get("factor_gain"), ab.get("period_factor"))
    return out


def _changes(f: dict, base: dict) -> str:
    def rel(a, b):
        return abs(a / b - 1) if a is not None and b else 0.0

    worst = [max((rel(f[c][i], base[c][i]) for c in f), default=0.0) for i in range(4)]
    return f"sigma {worst[0]:.1e}, slope {worst[1]:.1e}, gain {worst[2]:.1e}, r {worst[3]:.1e} (max relative change)"


def _point(name):
    path, params = EVERY[name]
    cfg = read_yaml(CONFIGS / path)
    return cfg, str(CONFIGS / path), params


def _variants(names, values, state: dict, key: str, describe) -> None:
    """Each point of ``names`` evaluated with ``state[key]`` set to None (the
    code as shipped) and then to each of ``values``: CPU and the figures'
    changes against the first, one line each (``describe(value, st, calls)``
    names the variant)."""
    for name in names:
        cfg, path, params = _point(name)
        st = sw.resolve_settings(cfg)
        base = None
        for v in (None,) + tuple(values):
            state.update({key: v, "nfe": 0})
            f = _figures(sw.evaluate_point(cfg, path, params, st))
            calls = state["nfe"]
            cpu = _cpu(lambda: sw.evaluate_point(cfg, path, params, st))
            base = f if base is None else base
            print(f"{name}: {describe(v, st, calls)}: {cpu * 1e3:.1f} ms CPU; {_changes(f, base)}", flush=True)


def bench_h0(fracs=(0.01, 0.1, 0.3)) -> None:
    real = si.odeint
    state = {"frac": None, "nfe": 0}

    def patched(f, y0, t, *a, **k):
        if state["frac"] is not None:
            k["h0"] = state["frac"] * (t[1] - t[0])
        out = real(f, y0, t, *a, **k)
        state["nfe"] += int(out[1]["nfe"][-1])
        return out

    si.odeint = patched
    try:
        _variants(("thesis plate", "Solar Boat"), fracs, state, "frac",
                  lambda v, st, calls: f"h0 = {v if v is not None else 'LSODA default'} x spacing, {calls} calls")
    finally:
        si.odeint = real


def bench_law_periods(lengths=(2.0, 4.0)) -> None:
    real = bt.simulate_batch
    state = {"periods": None, "nfe": 0}

    def patched(scenes, **k):
        if state["periods"] is not None and k.get("health") is False:  # the laws' runs (point_amplitude._runs_at)
            k["periods"] = state["periods"]
        return real(scenes, **k)

    bt.simulate_batch = patched
    try:
        _variants(POINTS, lengths, state, "periods",
                  lambda v, st, calls: f"the laws' runs over {v if v is not None else st.periods:g} periods")
    finally:
        bt.simulate_batch = real


def bench_rtol(runs=((3, 1e-8), (10, 1e-10), (3, 1e-10), (10, 1e-8), (3, 1e-11))) -> None:
    for name in ("6.4 cylinder", "Solar Boat"):
        cfg, path, params = _point(name)
        rows = {}
        for per, rt in runs:
            res = sw.evaluate_point(cfg, path, params, sw.resolve_settings(cfg, periods=per, rtol=rt))
            for c, e in res["components"].items():
                rows.setdefault(c, []).append(f"{per} x {rt:.0e}: {e['sigma']:.4g}")
        for c, r in rows.items():
            print(f"stated-amplitude sigma {name} {c} (periods x rtol: kg m^2): " + ", ".join(r), flush=True)


def bench_post(repeats: int = 21) -> None:
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import simulate
    from bifilar.config import load_scene

    scene = load_scene(CONFIGS / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    real = si.odeint
    cache: dict = {}

    def replay(f, y0, t, *a, **k):
        if len(t) not in cache:
            cache[len(t)] = real(f, y0, t, *a, **k)
        Y, info = cache[len(t)]
        return Y.copy(), info

    def run(n, coordinate):
        return simulate(scene, "torsion", 0.05, n, rest=rest, modes=ms, rtol=1e-9, method="auto",
                        coordinate=coordinate)

    si.odeint = replay
    try:
        for coordinate in (True, False):
            run(210, coordinate), run(10, coordinate)
            c210 = _cpu(lambda: run(210, coordinate), repeats)
            c10 = _cpu(lambda: run(10, coordinate), repeats)
            print(f"simulate without odeint (replayed), coordinate={coordinate}: "
                  f"{(c210 - c10) / 200 * 1e6:.1f} us a period", flush=True)
    finally:
        si.odeint = real


def _prepared(name):
    """(settings, the point's _Prepared with its law's runs planned) of ``name``."""
    from bifilar.studies import point as pt

    cfg, path, params = _point(name)
    st = sw.resolve_settings(cfg)
    return st, pt._prepare(cfg, path, params, st)[1]


def bench_point_batch(repeats: int = 5) -> None:
    from bifilar.studies import point_amplitude as pa

    for name in ("thesis plate", "Solar Boat", "trifilar (KTH)"):
        st, pre = _prepared(name)
        law, labels = pre.law, [pre.labels[k] for k in pre.runs]
        n = len(labels)
        own = (pre.scene, pre.rest, pre.ms, labels, pre.amplitude, pre.starts)

        def batched(health):
            return bt.simulate_batch([pre.scene] * n + law.scenes, mode=labels + law.labels,
                                     amplitude=[pre.amplitude] * n + law.amplitudes, periods=st.periods,
                                     rtol=st.rtol, rests=[pre.rest] * n + law.rests, modes=[pre.ms] * n + law.mode_sets,
                                     errors="return", independent=True, health=health)

        ref, dop = pa._runs_at(law, st, own=own), batched(True)
        dT = max(abs(a.period / b.period - 1) for a, b in zip(dop, ref) if a.period and b.period)
        print(f"{name}: its {n + len(law.scenes)} runs as the point makes them (LSODA run by run) "
              f"{_cpu(lambda: pa._runs_at(law, st, own=own), repeats) * 1e3:.1f} ms CPU; batched DOP853 in one call "
              f"{_cpu(lambda: batched(True), repeats) * 1e3:.1f} ms with the health, "
              f"{_cpu(lambda: batched(False), repeats) * 1e3:.1f} without; periods {dT:.1e} apart (max relative)",
              flush=True)


def bench_calls(lengths=(1, 2, 3, 10)) -> None:
    for name in ("thesis plate", "Solar Boat", "trifilar (KTH)"):
        st, pre = _prepared(name)
        law, n = pre.law, len(pre.runs)
        row = []
        for per in lengths:
            runs = bt.simulate_batch([pre.scene] * n + law.scenes, mode=[pre.labels[k] for k in pre.runs] + law.labels,
                                     amplitude=[pre.amplitude] * n + law.amplitudes, periods=per, rtol=st.rtol,
                                     rests=[pre.rest] * n + law.rests, modes=[pre.ms] * n + law.mode_sets,
                                     errors="return", health=False)
            row.append(f"{per:g} periods {sum(int(r.nfev) for r in runs[:n])} + {sum(int(r.nfev) for r in runs[n:])}")
        print(f"{name}: right-hand-side calls of its {n} own runs + its {len(law.scenes)} law runs: " + ", ".join(row),
              flush=True)


def _two_term_dr_dI(pre, comp: str, k: int, st, tight: float, fr, rel_step: float = 1e-2) -> tuple:
    """(a' A^2, the converged dr/dI): ``a'`` the derivative of the
    small-amplitude coefficient ``a`` in ``comp`` (central, over
    ``rel_step`` of the largest moment; ``a`` through runs at ``fr`` x A),
    against the central difference of the factor at A itself (rtol
    ``tight``), 1 / kg m^2."""
    from dataclasses import replace

    import numpy as np

    from bifilar.studies.settings import _IDX

    A = pre.amplitude
    H = rel_step * float(np.max(np.linalg.eigvalsh(pre.scene.inertia)))
    scenes, mss = [], []
    for sgn in (1.0, -1.0):
        I = np.array(pre.scene.inertia, float)
        i, j = _IDX[comp]
        I[i, j] += sgn * H
        if i != j:
            I[j, i] += sgn * H
        scenes += [replace(pre.scene, inertia=I)] * 3
        mss += [pre.at(I)] * 3
    amps = [f * A for f in fr] + [A]
    runs = bt.simulate_batch(scenes, mode=pre.labels[k], amplitude=amps * 2, periods=st.periods, rtol=tight,
                             rests=[pre.rest] * 6, modes=mss, errors="return", health=False)
    d = [r.period / r.linear_period - 1.0 for r in runs]
    x1, x2 = amps[0] ** 2, amps[1] ** 2

    def a_of(d1, d2):
        b = (d2 / x2 - d1 / x1) / (x2 - x1)
        return d1 / x1 - b * x1

    da = (a_of(d[0], d[1]) - a_of(d[3], d[4])) / (2 * H)
    return da * A * A, (d[2] - d[5]) / (2 * H)


def bench_two_term(tight: float = 1e-12) -> None:
    from bifilar.estimation.solve import STATED_LAW_RATIO, amplitude_law
    from bifilar.estimation.uncertainty import DEFAULT_AMPLITUDE_REL
    from bifilar.studies.point_amplitude import stated_amplitude_budget

    for name in EVERY:
        cfg, path, params = _point(name)
        st = sw.resolve_settings(cfg)
        res = sw.evaluate_point(cfg, path, params, st)
        if not res["valid"]:
            print(f"{name}: invalid point ({res['error']})")
            continue
        _, pre = _prepared(name)
        A = pre.amplitude
        for comp, k in pre.chosen.items():
            e = res["components"][comp]
            ab = e.get("amplitude_budget") or {}
            if not ab.get("budgeted"):
                print(f"{name} {comp}: no stated-amplitude budget")
                continue
            fr = (0.25, 0.5, STATED_LAW_RATIO, 1.0)
            runs = bt.simulate_batch([pre.scene] * 4, mode=pre.labels[k], amplitude=[f * A for f in fr],
                                     periods=st.periods, rtol=tight, rests=[pre.rest] * 4, modes=[pre.ms] * 4,
                                     errors="return", health=False)
            d = [r.period / float(pre.periods[k]) - 1.0 for r in runs]
            a1, a2 = (fr[0] * A) ** 2, (fr[1] * A) ** 2
            b = (d[1] / a2 - d[0] / a1) / (a2 - a1)  # d = a x + b x^2 through the two small amplitudes
            a = d[0] / a1 - b * a1
            slope = ab["slope"]
            two_term = 4.0 * (ab["period_factor"] - 1.0) - 2.0 * a * A * A
            slope_tight = A * amplitude_law(A, 1.0 + d[3], STATED_LAW_RATIO, 1.0 + d[2]).slope()  # the tight runs' law
            share = (ab["contribution"] / e["sigma"]) ** 2
            delta = abs(two_term / slope - 1.0)
            drdI = _two_term_dr_dI(pre, comp, k, st, tight, fr[:2])
            T_lin, r, b_ = float(pre.periods[k]), ab["period_factor"], pre.budgets[comp]
            drdI_pt = (ab["factor_gain"] - r) / (T_lin * float(b_.dI_dT))
            sd = [stated_amplitude_budget(b_, T_lin, r, DEFAULT_AMPLITUDE_REL, sl, dr)[0]
                  for sl, dr in ((slope, drdI_pt), (two_term, drdI_pt), (slope, drdI[0]), (two_term, drdI[0]))]
            print(f"{name} {comp}: dr/dI {drdI_pt:.4e} (the point's), {drdI[1]:.4e} (central, rtol {tight:g}), a' A^2 "
                  f"{drdI[0]:.4e}; sigma {e['sigma']:.6g} (recomputed {sd[0]:.6g}), with the two-term slope "
                  f"{abs(sd[1] / sd[0] - 1):.1e}, with a' A^2 {abs(sd[2] / sd[0] - 1):.1e}, both {abs(sd[3] / sd[0] - 1):.1e}"
                  f" (relative)", flush=True)
            print(f"{name} {comp} ({pre.labels[k]}, A = {A:g}): (c_a/sigma)^2 {share:.1e}, so the slope is needed "
                  f"to {1e-6 / share:.1e}; two-term slope vs the point's {delta:.1e} (sigma {delta * share:.1e}); "
                  f"the point's slope vs its law at rtol {tight:g} {abs(slope / slope_tight - 1):.1e}, the two-term "
                  f"slope from that run {abs((4.0 * d[3] - 2.0 * a * A * A) / slope_tight - 1):.1e}", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sections = {"--h0": bench_h0, "--law-periods": bench_law_periods, "--rtol": bench_rtol, "--post": bench_post,
                "--point-batch": bench_point_batch, "--calls": bench_calls, "--two-term": bench_two_term}
    for flag in sections:
        ap.add_argument(flag, action="store_true")
    a = vars(ap.parse_args(argv))
    chosen = [fn for flag, fn in sections.items() if a[flag[2:].replace("-", "_")]]
    for fn in chosen or sections.values():
        fn()

if __name__ == "__main__":
    main()
