#!/usr/bin/env python
"""Would invert's amplitude-factor runs be as accurate and cheaper on the
compiled LSODA path (``simulate(method="auto")``) than on solve_ivp's DOP853?

For each shipped config (configs/*.yaml but the measurements files) and each
of its timed-mode candidates (torsion, swing-x, swing-y, roll, pitch where the
rig has them), released from rest at amplitudes from small to large, the
amplitude factor ``r = T_sim / T_lin`` over ``--cycles`` linear periods
(as :func:`bifilar.estimation.amplitude_runs._factor_run` makes it, without
the second mode and the check run) from

  (a) DOP853 rtol 1e-10 (today's run: check=False, bound=True),
  (b) method "auto" (odeint LSODA, compiled kernel) at rtol 1e-10 and 1e-11,
  (c) the reference: DOP853 rtol 1e-13, checked against LSODA ("auto") 1e-13.

Prints, per case, |r - r_ref| of (a) and (b), the reference's own spread
|r_DOP853,1e-13 - r_LSODA,1e-13|, and the CPU time (``time.process_time``,
median of ``--repeats``) of one run of (a) and (b).  The yardstick for a
factor error is the timing's relative size ``0.0005 s / T_lin`` (a
stopwatch/fit std of 0.5 ms): an error below 1e-3 of it moves no answer.
A rig whose modes span more than STIFF_RATIO in period runs DOP853 under
"auto" too (simulate's rule): such a case is marked ``auto=DOP853``.

``--invert``: CPU of ``bifilar invert --measurements
configs/measurements_example.yaml --json`` with the amplitude runs as today
and with them switched to "auto" (a throw-away monkeypatch of
``bifilar.analysis.simulate.simulate`` in the child process: a call with
``bound=True`` and method DOP853, the amplitude runs' signature, is made
with "auto" at the same rtol, or, ``auto11``, at a tenth of it), fresh
processes alternating, medians; and the answers' differences in units of
their std.

``--sweep``: the same for the 28-point Solar Boat sweep (its recommended
point's amplitude advice), with the largest relative change of any figure.

    python scripts/factor_method_check.py [--quick] [--json] [--invert] [--sweep] [--pairs 5] [--repeats 3]

Run from the tree's root (so that this tree's bifilar is imported).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.analysis.simulate import STIFF_RATIO, _period_ratio, simulate  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.errors import BifilarError  # noqa: E402
from bifilar.analysis.equilibrium import rest_pose  # noqa: E402

TIMED = ("torsion", "swing-x", "swing-y", "roll", "pitch")
ROT_AMPS = (0.02, 0.1, 0.3, 0.5)  # rad
TRANS_AMPS = (0.02, 0.1, 0.3)  # m
SEPARATRIX = (2.5, 3.0)  # rad, torsion only (audit18's H2 looked at 2.5-3.1: the wires' turn at pi)
TIMING = 0.0005  # s, the yardstick's period std


def scene_of(path: Path):
    return scene_from_dict(read_yaml(str(path)), warn=False)


def run_r(scene, rest, ms, label, amp, cycles, method, rtol, budget=2e4):
    """(r, CPU s, method actually run) of one amplitude run; ``budget``
    evaluations a cycle (invert's RUN_EVALUATIONS_PER_CYCLE; the reference
    runs get 1e6: at rtol 1e-13 the 41.7 s swing-x of the thesis rigs needs
    more than 2e5 over 10 cycles)."""
    c = time.process_time()
    sim = simulate(scene, label, amp, cycles, rest=rest, modes=ms, method=method, rtol=rtol, check=False,
                   bound=(method == "DOP853"), max_evaluations=budget * max(cycles, 10.0))
    cpu = time.process_time() - c
    if sim.period is None:
        raise RuntimeError("no period")
    return sim.period / ms.get(label).period, cpu, sim.method


def cases(quick: bool):
    paths = sorted(p for p in (ROOT / "configs").glob("*.yaml") if not p.name.startswith("measurements"))
    if quick:
        paths = [p for p in paths if p.name == "thesis_lin2_pitch.yaml"]
    for p in paths:
        scene = scene_of(p)
        rest = rest_pose(scene)
        ms = linear_modes(scene, rest)
        stiff = _period_ratio(ms) > STIFF_RATIO
        for m in ms.modes:
            if m.label not in TIMED or m.period is None:
                continue
            rot = m.dominant >= 3
            amps = ROT_AMPS if rot else TRANS_AMPS
            if m.label == "torsion" and not quick:
                amps = amps + SEPARATRIX
            if quick:
                amps = (amps[0], amps[-1])
            for a in amps:
                yield p.stem, scene, rest, ms, m, a, stiff


def measure(quick: bool, cycles: float, repeats: int) -> list[dict]:
    rows = []
    for name, scene, rest, ms, m, a, stiff in cases(quick):
        row = dict(config=name, mode=m.label, amplitude=a, unit="rad" if m.dominant >= 3 else "m",
                   T_lin=m.period, auto_is_dop853=stiff)
        try:
            r_ref, _, _ = run_r(scene, rest, ms, m.label, a, cycles, "DOP853", 1e-13, 1e6)
            r_ref2, _, _ = run_r(scene, rest, ms, m.label, a, cycles, "auto", 1e-13, 1e6)
            res = {}
            for key, method, rtol in (("dop853_1e-10", "DOP853", 1e-10), ("auto_1e-10", "auto", 1e-10),
                                      ("auto_1e-11", "auto", 1e-11)):
                rs, cpus = [], []
                for _ in range(repeats):  # interleaved with the other methods' runs below is not needed:
                    r, cpu, _ = run_r(scene, rest, ms, m.label, a, cycles, method, rtol)  # same process, same load
                    rs.append(r)
                    cpus.append(cpu)
                res[key] = (rs[0], statistics.median(cpus))
        except (BifilarError, RuntimeError) as e:
            row["skipped"] = str(e).split("\n")[0][:160]
            rows.append(row)
            print(f"  {name} {m.label} {a:g}: skipped ({row['skipped'][:80]})", file=sys.stderr)
            continue
        row["r_ref"] = r_ref
        row["ref_spread"] = abs(r_ref - r_ref2)
        row["yardstick"] = TIMING / m.period  # the timing std's relative size
        for key, (r, cpu) in res.items():
            row[f"err_{key}"] = abs(r - r_ref)
            row[f"cpu_{key}"] = cpu
        rows.append(row)
        print(f"  {name} {m.label} {a:g}: r_ref {r_ref:.9f} spread {row['ref_spread']:.1e} | "
              + " ".join(f"{k} {row['err_' + k]:.1e} ({row['cpu_' + k] * 1e3:.0f} ms)" for k in res),
              file=sys.stderr)
    return rows


CHILD = r"""
import io, json, sys, time, contextlib
mode, args = sys.argv[1], sys.argv[2:]
import collections
import bifilar.analysis.simulate as S
calls = collections.Counter()
orig = S.simulate
def patched(*a, **kw):
    if kw.get("bound"):
        if mode != "DOP853" and kw.get("method", "DOP853") == "DOP853":
            kw["method"] = "auto"
            if mode == "auto11":  # a tenth of invert's rtol (1e-11 for its 1e-10 runs)
                kw["rtol"] = kw.get("rtol", 1e-10) / 10
        calls[f"{kw.get('method')} {kw.get('rtol'):g}"] += 1
    return orig(*a, **kw)
S.simulate = patched
from bifilar.cli import main
buf = io.StringIO()
c = time.process_time()
with contextlib.redirect_stdout(buf):
    try:
        main(args, standalone_mode=False)
    except SystemExit:
        pass
cpu = time.process_time() - c
print(json.dumps({"cpu": cpu, "out": buf.getvalue(), "calls": calls}))
"""


def cli_ab(args: list[str], pairs: int):
    """CPU (s) of the CLI command ``args`` in fresh processes, the three ways
    alternating ``pairs`` times; (CPU lists, the last JSON outputs, the
    amplitude runs counted by method and rtol)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cpu = {"DOP853": [], "auto": [], "auto11": []}
    outs, calls = {}, {}
    for _ in range(pairs):
        for mode in cpu:
            p = subprocess.run([sys.executable, "-c", CHILD, mode, *args], env=env, cwd=str(ROOT),
                               capture_output=True, text=True, check=True)
            d = json.loads(p.stdout.strip().splitlines()[-1])
            cpu[mode].append(d["cpu"])
            outs[mode] = json.loads(d["out"])
            calls[mode] = d["calls"]
    return cpu, outs, calls


def leaves(x, path=""):
    """(path, number) of every numeric leaf of a JSON document but run times."""
    if isinstance(x, dict):
        for k, v in x.items():
            if "runtime" not in k:
                yield from leaves(v, f"{path}/{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from leaves(v, f"{path}/{i}")
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        yield path, float(x)


def sweep_ab(pairs: int) -> dict:
    """``bifilar sweep configs/solar_boat.yaml --param spacing=1:4:7 --param
    length=2:5:4 --json`` (28 points and the recommended point's amplitude
    advice) the three ways: CPU medians, and the largest relative change of
    any figure of its JSON."""
    cpu, outs, calls = cli_ab(["sweep", str(ROOT / "configs" / "solar_boat.yaml"), "--param", "spacing=1:4:7",
                               "--param", "length=2:5:4", "--json"], pairs)
    base = dict(leaves(outs["DOP853"]))
    res = {"cpu_median": {m: statistics.median(v) for m, v in cpu.items()}, "cpu": cpu, "amplitude_runs": calls}
    for mode in ("auto", "auto11"):
        other = dict(leaves(outs[mode]))
        rel = [(abs(v - base[k]) / max(abs(base[k]), 1e-300), k) for k, v in other.items()
               if k in base and v != base[k]]
        res[mode] = {"figures_changed": len(rel), "figures": len(base), "same_keys": sorted(other) == sorted(base),
                     "max_relative_change": max(rel) if rel else None}
    return res


def invert_ab(pairs: int) -> dict:
    cpu, outs, calls = cli_ab(["invert", "--measurements", str(ROOT / "configs" / "measurements_example.yaml"),
                               "--json"], pairs)
    a = outs["DOP853"]
    res = {"cpu_median": {m: statistics.median(v) for m, v in cpu.items()}, "cpu": cpu, "amplitude_runs": calls}
    for mode in ("auto", "auto11"):
        b = outs[mode]
        res[mode] = {"value_diff_in_std": {k: (b["inertia"][k]["value"] - v["value"]) / v["std"]
                                           for k, v in a["inertia"].items()},
                     "std_relative_change": {k: b["inertia"][k]["std"] / v["std"] - 1.0
                                             for k, v in a["inertia"].items()},
                     "amplitude_factor_minus_dop853": {ra["mode"]: rb["amplitude_factor"] - ra["amplitude_factor"]
                                                       for ra, rb in zip(a["residuals"], b["residuals"])}}
    res["inertia_dop853"] = {k: (v["value"], v["std"]) for k, v in a["inertia"].items()}
    return res


def verdict(rows: list[dict]) -> dict:
    ok = [r for r in rows if "r_ref" in r]
    v = {"cases": len(ok), "skipped": len(rows) - len(ok)}
    for k in ("auto_1e-10", "auto_1e-11"):
        worse = [r for r in ok if r[f"err_{k}"] > r["err_dop853_1e-10"]]
        over = [r for r in ok if r[f"err_{k}"] > 1e-3 * r["yardstick"]]
        v[k] = {"worse_than_dop853": len(worse), "above_1e-3_of_yardstick": len(over),
                "above_cases": [f"{r['config']} {r['mode']} {r['amplitude']:g}" for r in over],
                "max_err_over_yardstick": max(r[f"err_{k}"] / r["yardstick"] for r in ok) if ok else None,
                "cpu_ratio_median": statistics.median(r["cpu_dop853_1e-10"] / r[f"cpu_{k}"] for r in ok) if ok
                else None}
    v["dop853_1e-10_above_1e-3_of_yardstick"] = sum(r["err_dop853_1e-10"] > 1e-3 * r["yardstick"] for r in ok)
    v["dop853_1e-10_max_err_over_yardstick"] = max(r["err_dop853_1e-10"] / r["yardstick"] for r in ok) if ok else None
    v["ref_spread_max_over_yardstick"] = max(r["ref_spread"] / r["yardstick"] for r in ok) if ok else None
    return v


def table(rows: list[dict]) -> str:
    head = ("| config | mode | A | T_lin s | r_ref - 1 | ref spread | a: DOP853 1e-10 | b: auto 1e-10 | auto 1e-11 "
            "| yardstick 5e-4/T | CPU a / b(1e-10) / b(1e-11) ms |")
    lines = [head, "|" + "---|" * 11]
    for r in rows:
        amp = f"{r['amplitude']:g} {r['unit']}"
        if "r_ref" not in r:
            lines.append(f"| {r['config']} | {r['mode']} | {amp} | {r['T_lin']:.4g} | skipped: {r['skipped'][:70]} "
                         "| | | | | | |")
            continue
        lines.append(f"| {r['config']} | {r['mode']}{' (auto=DOP853)' if r['auto_is_dop853'] else ''} | {amp} | "
                     f"{r['T_lin']:.4g} | {r['r_ref'] - 1:.3e} | {r['ref_spread']:.1e} | {r['err_dop853_1e-10']:.1e} | "
                     f"{r['err_auto_1e-10']:.1e} | {r['err_auto_1e-11']:.1e} | {r['yardstick']:.1e} | "
                     f"{r['cpu_dop853_1e-10'] * 1e3:.0f} / {r['cpu_auto_1e-10'] * 1e3:.0f} / "
                     f"{r['cpu_auto_1e-11'] * 1e3:.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="one config (thesis_lin2_pitch), two amplitudes a mode, "
                                                         "one repeat")
    ap.add_argument("--cycles", type=float, default=10.0, help="linear periods a run (default 10)")
    ap.add_argument("--repeats", type=int, default=3, help="runs a method a case for the CPU median (default 3)")
    ap.add_argument("--invert", action="store_true", help="also time invert of measurements_example.yaml both ways")
    ap.add_argument("--sweep", action="store_true", help="also time the 28-point Solar Boat sweep both ways")
    ap.add_argument("--pairs", type=int, default=5, help="alternating fresh-process rounds for --invert and --sweep "
                                                         "(default 5)")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    a = ap.parse_args()
    rows = measure(a.quick, a.cycles, 1 if a.quick else a.repeats)
    out = {"cycles": a.cycles, "load": os.getloadavg(), "rows": rows, "verdict": verdict(rows)}
    if a.invert:
        out["invert"] = invert_ab(a.pairs)
    if a.sweep:
        out["sweep"] = sweep_ab(a.pairs)
    if a.json:
        print(json.dumps(out, indent=1, default=float))
        return
    print(f"cycles {a.cycles:g}, load at the end {out['load'][0]:.1f}")
    print(table(rows))
    print(json.dumps(out["verdict"], indent=1, default=float))
    for k in ("invert", "sweep"):
        if k in out:
            print(json.dumps(out[k], indent=1, default=float))


if __name__ == "__main__":
    main()
