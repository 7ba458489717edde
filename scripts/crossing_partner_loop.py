"""Closed loop of the avoided-crossing refusal's partner hint (docs/design.md,
"label27, session 27"): audit27's case a03 (torsion and swing-x 0.4 % apart)
drawn as :mod:`closed_loop_invert` draws it (the truth's linear period of
``--mode`` timed with the config's ``uncertainty.timing`` of white noise,
every measured input drawn from its default std), inverted for Izz with
``--amplitude 0``; each refusal's message is searched for the partner label
it names (``--period LABEL=``) and the Izz it says that reading gives, and
the same period in the same drawn config is inverted again under that label.
With ``--amplitude A`` (rad or m, times the mode's normalised shape, as for
``simulate``; docs/design.md, "partner28, session 28") the truth's period is
its simulated one at that amplitude (``simulate``'s crossings over the
default 10 cycles) and every inversion states the amplitude A (exact; the
budget carries its default relative std).

Prints one JSON document: answered / refused, the labels named, how many
partner readings were answered, how many of their 95 % intervals hold the
truth's Izz (kg m^2), how many estimates equal the Izz the refusal named (to
its 6 printed digits), the refusals naming none and the partner readings
refused (first 300 / 200 characters), and the CPU seconds.

    python scripts/crossing_partner_loop.py --draws 200 --seed 4
    python scripts/crossing_partner_loop.py --draws 100 --seed 4 --amplitude 0.05
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
from bifilar.estimation.invert import invert  # noqa: E402
from bifilar.estimation.measurements import DEFAULT_CYCLES, Hanging, Measurement, MeasurementSet  # noqa: E402
from bifilar.estimation.uncertainty import default_uncertainty  # noqa: E402
from closed_loop_invert import linear_periods  # noqa: E402
from closed_loop_plan import measured_scene  # noqa: E402

NAMED = re.compile(r"--period ([^=]+)=\S+\)(?:, which (?:at the same amplitude \(\S+\) )?gives Izz = ([0-9.e+-]+) "
                   r"kg m\^2)?")


def _invert(scene, label: str, period: float, unc: dict, amplitude: float = 0.0):
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(label, period, unc["timing"], "period", "--period", amplitude=amplitude)])
    ms.uncertainty = dict(unc)
    return invert(ms, solve_for=["Izz"], ladder=False)


def run(path: str, mode: str, draws: int, seed: int, amplitude: float = 0.0) -> dict:
    cfg = read_yaml(path)
    truth = scene_from_dict(cfg, warn=False)
    T = simulate(truth, mode, amplitude, DEFAULT_CYCLES).period if amplitude else linear_periods(truth)[mode]
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    izz = float(truth.inertia[2, 2])
    rng = np.random.default_rng(seed)
    out = {"config": path, "mode": mode, "amplitude": amplitude, "truth_period": T, "draws": draws, "seed": seed,
           "answered": 0, "refused": 0, "named": {},
           "partner_answered": 0, "partner_covered": 0, "named_izz_matches": 0, "unnamed": [], "partner_refused": []}
    t0 = time.process_time()
    for _ in range(draws):
        sc = measured_scene(truth, rng, unc)
        Tm = T + rng.normal(0, unc["timing"])
        try:
            _invert(sc, mode, Tm, unc, amplitude)
            out["answered"] += 1
            continue
        except BifilarError as e:
            msg = str(e)
        out["refused"] += 1
        hit = NAMED.search(msg)
        if not hit:
            out["unnamed"].append(msg[:300])
            continue
        lab = hit.group(1)
        out["named"][lab] = out["named"].get(lab, 0) + 1
        try:
            r = _invert(sc, lab, Tm, unc, amplitude)
        except BifilarError as e:
            out["partner_refused"].append(str(e)[:200])
            continue
        out["partner_answered"] += 1
        lo, hi = r.interval[0]
        out["partner_covered"] += int(lo <= izz <= hi)
        out["named_izz_matches"] += int(hit.group(2) is not None and f"{float(r.values[0]):.6g}" == hit.group(2))
    out["cpu_s"] = round(time.process_time() - t0, 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("config", nargs="?", default=str(ROOT / "tests" / "data" / "audit27" / "a03_neardegen.yaml"))
    ap.add_argument("--mode", default="torsion")
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=4)
    ap.add_argument("--amplitude", type=float, default=0.0, help="the stated release amplitude (default 0: linear)")
    a = ap.parse_args()
    print(json.dumps(run(a.config, a.mode, a.draws, a.seed, a.amplitude), indent=1))


if __name__ == "__main__":
    main()
