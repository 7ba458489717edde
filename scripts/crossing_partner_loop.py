"""Closed loop of the avoided-crossing refusal's partner hint (docs/design.md,
"label27, session 27" and "partner28, session 28"): audit27's case a03
(torsion and swing-x 0.4 % apart) drawn as :mod:`closed_loop_invert` draws
it (the truth's linear period of each of ``--modes`` timed with the
config's ``uncertainty.timing`` of white noise, every measured input drawn
from its default std), inverted for ``--components`` (default Izz from the
torsion) with ``--amplitude 0``; each refusal's message is searched for the
labels it says to give the periods under and the values it says that
reading gives, and the same periods in the same drawn config are inverted
again so.  With ``--amplitude A`` (rad or m, times the mode's normalised
shape, as for ``simulate``) each truth's period is its simulated one at
that amplitude (``simulate``'s crossings over the default 10 cycles) and
every inversion states the amplitude A (exact; the budget carries its
default relative std).

Prints one JSON document: answered / refused, the labels named (per draw,
the timed modes' labels as given again), how many partner readings were
answered, how many of their 95 % intervals hold the truth's values (kg m^2;
all of them, and per component; the misses' sides and the mean and sd of
(estimate - truth) / std), how many estimates equal the values the
refusal named (to their 6 printed digits), the refusals naming none and the
partner readings refused (first 300 / 200 characters), and the CPU seconds;
and under ``caution``, for the direct answers and the partner readings with
a std, how many carry invert's across-the-crossing caution
(``across_crossing``, docs/design.md "cross29, session 29") and how many
intervals hold the truth among those with and without it.

    python scripts/crossing_partner_loop.py --draws 200 --seed 4
    python scripts/crossing_partner_loop.py --draws 200 --seed 4 --amplitude 0.05
    python scripts/crossing_partner_loop.py --modes torsion,roll --components Ixx,Izz --draws 200 --seed 4
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's bifilar, not an installed copy

from bifilar.analysis.simulate import simulate  # noqa: E402
from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.errors import BifilarError  # noqa: E402
from bifilar.estimation.crossing_partner import NEAR_REL  # noqa: E402
from bifilar.estimation.invert import invert  # noqa: E402
from bifilar.estimation.measurements import DEFAULT_CYCLES, Hanging, Measurement, MeasurementSet  # noqa: E402
from bifilar.estimation.uncertainty import default_uncertainty  # noqa: E402
from closed_loop_invert import INDEX, linear_periods  # noqa: E402
from closed_loop_plan import measured_scene  # noqa: E402

NAMED = re.compile(r"--period ([^=]+)=\S+\)(?:, which (?:at the same amplitude \(\S+\) )?gives Izz = ([0-9.e+-]+) "
                   r"kg m\^2)?")
#: several unknowns or periods (surface_hint): the periods given under other labels, and the values read so
NAMED_MULTI = re.compile(r"(?:given under its label|given swapped) \(([^)]*)\)(?:; read so,(?: at the same "
                         r"amplitudes,)? the periods give (.*?) \(invert's answer)?")


def _invert(scene, labels: list, periods: list, unc: dict, amplitude: float, comps: list):
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(lab, T, unc["timing"], "period", "--period", amplitude=amplitude)
                         for lab, T in zip(labels, periods)])
    ms.uncertainty = dict(unc)
    return invert(ms, solve_for=list(comps), ladder=False)


def _named(msg: str, labels: list, periods: list, comps: list):
    """(the labels the refusal says to give the periods under, {component: value named} or None), or None."""
    hit = NAMED_MULTI.search(msg) if len(labels) > 1 or len(comps) > 1 else None
    if hit:
        given = dict((f"{float(T):.9g}", lab) for lab, T in re.findall(r"--period ([^=]+)=([0-9.e+-]+)\+-",
                                                                      hit.group(1)))
        new = [given.get(f"{T:.9g}", lab) for lab, T in zip(labels, periods)]
        vals = dict((n, float(v)) for n, v in re.findall(r"(\w+) = ([0-9.e+-]+) kg m\^2", hit.group(2) or ""))
        return new, vals or None
    hit = NAMED.search(msg) if len(labels) == 1 else None
    if hit:
        return [hit.group(1)], ({comps[0]: float(hit.group(2))} if hit.group(2) else None)
    return None


def _caution(c: dict, r, tv: list) -> None:
    """Count answer ``r`` in ``c`` (docs/design.md, "cross29, session 29"): whether it carries the
    across-the-crossing caution (``r.across_crossing``) and, if it has a std, whether each 95 % interval holds
    the truth ``tv`` (kg m^2), split by caution."""
    if r.std_unavailable is not None:
        return
    c["with_std"] += 1
    pb = r.problem
    close = False
    for k, m in enumerate(pb.measurements):  # a timed mode with an adjacent one within NEAR_REL at the estimate
        md, i = pb.models[m.hanging].modes0.modes, pb.mode_index[k]
        close |= any(0 <= j < len(md) and md[i].period and md[j].period and
                     abs(md[j].period - md[i].period) <= NEAR_REL * max(md[i].period, md[j].period) for j in (i - 1, i + 1))
    c["rows"].append({"edge": bool(r.roots[0]["edge"]), "close": bool(close), "cautioned": r.across_crossing is not None,
                      "covered": [bool(lo <= t <= hi) for (lo, hi), t in zip(r.interval, tv)]})
    c["cautioned"] += int(r.across_crossing is not None)
    key = "covered_cautioned" if r.across_crossing is not None else "covered_uncautioned"
    for comp, (lo, hi), t in zip(c[key], r.interval, tv):
        c[key][comp] += int(lo <= t <= hi)


def run(path: str, modes: list, draws: int, seed: int, amplitude: float = 0.0, comps=("Izz",)) -> dict:
    cfg = read_yaml(path)
    truth = scene_from_dict(cfg, warn=False)
    lin = linear_periods(truth)
    T = [simulate(truth, md, amplitude, DEFAULT_CYCLES).period if amplitude else lin[md] for md in modes]
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    tv = [float(truth.inertia[INDEX[c]]) for c in comps]
    rng = np.random.default_rng(seed)
    out = {"config": path, "modes": modes, "components": list(comps), "amplitude": amplitude, "truth_periods": T,
           "draws": draws, "seed": seed, "answered": 0, "refused": 0, "named": {}, "partner_answered": 0,
           "partner_covered": 0, "partner_covered_each": dict.fromkeys(comps, 0), "named_value_matches": 0,
           "partner_misses": {c: {"interval_above_truth": 0, "interval_below_truth": 0} for c in comps},
           "unnamed": [], "partner_refused": [], "partner_refused_said": 0, "partner_failed_at": [],
           "caution": {kind: {"with_std": 0, "cautioned": 0, "covered_cautioned": dict.fromkeys(comps, 0),
                              "covered_uncautioned": dict.fromkeys(comps, 0), "rows": []} for kind in ("answer", "partner")}}
    zs: dict = {}
    t0 = time.process_time()
    for d in range(draws):
        sc = measured_scene(truth, rng, unc)
        Tm = [t + rng.normal(0, unc["timing"]) for t in T]
        try:
            r = _invert(sc, modes, Tm, unc, amplitude, comps)
            out["answered"] += 1
            _caution(out["caution"]["answer"], r, tv)
            continue
        except BifilarError as e:
            msg = str(e)
        out["refused"] += 1
        got = _named(msg, modes, Tm, comps)
        if not got:
            out["unnamed"].append(msg[:300])
            continue
        labs, vals = got
        key = ",".join(labs)
        out["named"][key] = out["named"].get(key, 0) + 1
        try:
            r = _invert(sc, labs, Tm, unc, amplitude, comps)
        except (BifilarError, np.linalg.LinAlgError) as e:  # the latter: the refusal says its solve failed
            out["partner_refused"].append(f"{type(e).__name__}: {str(e)[:200]}")
            out["partner_refused_said"] += int("refused as well" in msg)
            if not isinstance(e, BifilarError):
                out["partner_failed_at"].append({"draw": d, "periods": Tm, "labels": labs})
            continue
        out["partner_answered"] += 1
        _caution(out["caution"]["partner"], r, tv)
        cov = [bool(lo <= t <= hi) for (lo, hi), t in zip(r.interval, tv)]
        for c, v, sd, (lo, hi), t in zip(comps, r.values, r.budget.std, r.interval, tv):
            zs.setdefault(c, []).append(float((v - t) / sd) if sd > 0 else float("nan"))
            side = "interval_above_truth" if t < lo else "interval_below_truth" if t > hi else None
            if side:
                out["partner_misses"][c][side] += 1
        out["partner_covered"] += int(all(cov))
        for c, ok in zip(comps, cov):
            out["partner_covered_each"][c] += int(ok)
        out["named_value_matches"] += int(vals is not None and all(
            f"{float(v):.6g}" == f"{vals.get(c, float('nan')):.6g}" for c, v in zip(r.names, r.values)))
    # the partner readings' (estimate - truth) / std per component: mean, sd, and the misses' sides
    out["partner_z"] = {c: {"mean": round(float(np.nanmean(z)), 3), "sd": round(float(np.nanstd(z)), 3)}
                        for c, z in zs.items()}
    out["cpu_s"] = round(time.process_time() - t0, 1)
    return out


def loop_arguments(description: str, modes: str = "torsion", components: str = "Izz") -> argparse.ArgumentParser:
    """The a03 loops' common options (this script's, and crossing_partner_budget.py's)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("config", nargs="?", default=str(ROOT / "tests" / "data" / "audit27" / "a03_neardegen.yaml"))
    ap.add_argument("--modes", default=modes, help="the timed modes, comma-separated (the first is a03's torsion)")
    ap.add_argument("--components", default=components, help="the unknowns, comma-separated")
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=4)
    return ap


def main() -> None:
    ap = loop_arguments(__doc__.split("\n\n")[0])
    ap.add_argument("--amplitude", type=float, default=0.0, help="the stated release amplitude (default 0: linear)")
    a = ap.parse_args()
    print(json.dumps(run(a.config, a.modes.split(","), a.draws, a.seed, a.amplitude, a.components.split(",")),
                     indent=1))


if __name__ == "__main__":
    main()
