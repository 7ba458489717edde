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

Each section monkeypatches the code it varies inside this process only.
CPU medians (``time.process_time``); compare only figures of one run.

    python scripts/bench_law_runs.py [--h0] [--law-periods] [--rtol] [--post]
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
    path, params = POINTS[name]
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


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    for flag in ("--h0", "--law-periods", "--rtol", "--post"):
        ap.add_argument(flag, action="store_true")
    a = ap.parse_args(argv)
    every = not (a.h0 or a.law_periods or a.rtol or a.post)
    if a.h0 or every:
        bench_h0()
    if a.law_periods or every:
        bench_law_periods()
    if a.rtol or every:
        bench_rtol()
    if a.post or every:
        bench_post()


if __name__ == "__main__":
    main()
