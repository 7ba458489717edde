"""Closed loop of `invert` on a known truth (docs/design.md, "audit27,
session 27"): the config is the truth; its linear periods of the named
modes are timed with the config's ``uncertainty.timing`` (s) of white
noise, every measured input the budget knows is drawn from its default (or
stated) std as :func:`closed_loop_plan.measured_scene` draws it, and the
periods are inverted as ``invert CONFIG --period MODE=T+-TIMING --amplitude 0
--solve-for C,...`` does (the library path).  Each answer's estimate is put
back into its drawn config and re-solved by ``linear_modes`` (independently
of invert's own residuals): the largest |model - measured| / timing is
printed, with every warning that draws got, so an answer that does not
reproduce its periods can be matched with the words that say so.

Prints one JSON document: per component the truth, z = (estimate - truth)
/ std (mean, sd, range), the coverage of the printed ``interval_95`` with
its binomial se, the misses below / above, the median std and the median
width of the printed interval (after any cut at the physical limit); the refusals
(first 90 characters of each message, counted), the warnings (first 80),
and the CPU seconds.

    python scripts/closed_loop_invert.py tests/data/audit27/a02_heavy3.yaml \
        --modes torsion,swing-x,swing-y --components Izz,Ixx,Iyy --draws 200 --seed 3
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's bifilar, not an installed copy

from bifilar.analysis.equilibrium import rest_pose  # noqa: E402
from bifilar.analysis.modes import linear_modes  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.errors import BifilarError  # noqa: E402
from bifilar.estimation.invert import invert  # noqa: E402
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet  # noqa: E402
from bifilar.estimation.sensitivity import input_sigma, perturb  # noqa: E402
from bifilar.estimation.uncertainty import default_uncertainty  # noqa: E402
from closed_loop_plan import measured_scene  # noqa: E402

#: (row, column) of each inertia component in the body-frame tensor, kg m^2
INDEX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


def linear_periods(scene) -> dict:
    """{label: linear period, s} of the scene at its rest pose."""
    return {m.label: m.period for m in linear_modes(scene, rest_pose(scene)).modes}


def run(path: str, modes: list, comps: list, draws: int, seed: int, keep: list | None = None) -> dict:
    """The closed loop's summary (module docstring).  ``keep``, if given,
    receives a dict a draw, in order: ``errors`` (each measured input's
    drawn error in its own stds, :func:`closed_loop_plan.measured_scene`)
    and either ``refused`` (the message) or ``result`` (invert's answer);
    scripts/interval_rules_compare.py reads the second-order models of the
    answers from it."""
    cfg = read_yaml(path)
    truth = scene_from_dict(cfg, warn=False)
    T = linear_periods(truth)
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    tv = {c: float(truth.inertia[INDEX[c]]) for c in comps if c in INDEX}
    rng = np.random.default_rng(seed)
    rows, refusals, warns, t0 = [], {}, {}, time.process_time()
    for _ in range(draws):
        errs: dict = {}
        sc = measured_scene(truth, rng, unc, errs)
        for c in comps:  # a CoM unknown's truth: the shift that undoes the drawn CoM error (m)
            if c not in INDEX:
                tv[c] = -errs.get(c, 0.0) * input_sigma(truth, c, unc)
        meas = [Measurement(m, T[m] + rng.normal(0, unc["timing"]), unc["timing"], "period", "--period",
                            amplitude=0.0) for m in modes]
        ms = MeasurementSet([Hanging("reference", sc, np.eye(3))], meas)
        ms.uncertainty = dict(unc)
        try:
            r = invert(ms, solve_for=comps, ladder=False)
        except BifilarError as e:
            refusals[str(e)[:90]] = refusals.get(str(e)[:90], 0) + 1
            if keep is not None:
                keep.append({"errors": errs, "refused": str(e)})
            continue
        if keep is not None:
            keep.append({"errors": errs, "result": r})
        for w in r.warnings:
            warns[w[:80]] = warns.get(w[:80], 0) + 1
        row = {}
        inertia = sc.inertia.copy()
        for c in comps:
            i = list(r.names).index(c)
            row[c] = (float(r.values[i]), float(r.std[i]), *map(float, r.interval[i]), tv[c])
            if c in INDEX:
                a, b = INDEX[c]
                inertia[a, b] = inertia[b, a] = r.values[i]
        solved = sc.with_changes(inertia=inertia)
        for c in comps:
            if c not in INDEX:
                solved = perturb(solved, c, float(r.values[list(r.names).index(c)]))
        Tm = linear_periods(solved)
        row["resid"] = max(abs(Tm[m] - x.period) / unc["timing"] for m, x in zip(modes, meas))
        row["warned"] = [w[:60] for w in r.warnings]
        rows.append(row)
    out = {"config": path, "modes": modes, "draws": draws, "seed": seed, "answered": len(rows),
           "refused": sum(refusals.values()), "refusals": refusals, "warnings": warns,
           "max_resid_over_timing": max((r["resid"] for r in rows), default=None),
           # answers more than 3 timing stds off their periods, the worst 8, with the words each got
           "off_answers": [(round(r["resid"], 2), r["warned"]) for r in
                           sorted((r for r in rows if r["resid"] > 3), key=lambda r: -r["resid"])[:8]],
           "off_count": sum(r["resid"] > 3 for r in rows)}
    for c in comps:
        a = np.array([r[c] for r in rows if np.isfinite(r[c][1])]).reshape(-1, 5)
        if not len(a):  # no answer with a std: the refusals and warnings say why
            out[c] = {"truth": tv.get(c), "with_std": 0}
            continue
        v, s, lo, hi, t = a.T
        z, cov, n = (v - t) / s, float(np.mean((lo <= t) & (t <= hi))), len(a)
        out[c] = {"truth": tv[c] if c in INDEX else "minus each draw's CoM error", "with_std": n, "z_mean": float(z.mean()), "z_sd": float(z.std(ddof=1)),
                  "z_range": [float(z.min()), float(z.max())], "coverage": cov,
                  "se": float(np.sqrt(max(cov * (1 - cov), 0.0475) / n)),
                  "miss_low": int(np.sum(t < lo)), "miss_high": int(np.sum(t > hi)),
                  "median_std": float(np.median(s)), "median_width": float(np.median(hi - lo))}
    out["cpu_s"] = round(time.process_time() - t0, 1)
    return out


def loop_arguments(description: str) -> argparse.ArgumentParser:
    """The closed loop's command line (config, --modes, --components,
    --draws, --seed), shared with scripts/interval_rules_compare.py."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("config")
    ap.add_argument("--modes", default="torsion", help="mode labels timed, comma-separated")
    ap.add_argument("--components", default="Izz", help="unknowns, comma-separated")
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    return ap


def main() -> None:
    a = loop_arguments(__doc__.split("\n\n")[0]).parse_args()
    print(json.dumps(run(a.config, a.modes.split(","), a.components.split(","), a.draws, a.seed), indent=1))


if __name__ == "__main__":
    main()
