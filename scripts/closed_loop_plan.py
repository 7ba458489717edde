"""Closed-loop check of a sweep point (docs/design.md, "Closed-loop check of
the planner, session 6"): do the experiment the planner describes and
compare with what it predicted.

For each component: the point's scene is built, the period of its mode is
timed with the sweep's timing std, every measured input of the
experimenter's config is drawn from its declared std, and the period is
inverted as a user would (``invert --period MODE=T+-TIMING --amplitude 0
--solve-for C``, the library path).  Prints one JSON line per component:
the sweep's sigma, the realised sd and their ratio, the mean error in
standard errors, invert's median std over the sweep's, the refused draws,
and the point's predicted ``p_unphysical`` / ``p_refused``.

    python scripts/closed_loop_plan.py configs/solar_boat.yaml '{"spacing": 2.5, "length": 2.0}' \
        --components Ixx,Iyy,Izz --draws 200 --seed 1
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.errors import BifilarError  # noqa: E402
from bifilar.estimation.invert import invert  # noqa: E402
from bifilar.estimation.measurements import Hanging, Measurement, MeasurementSet  # noqa: E402
from bifilar.estimation.sensitivity import input_sigma, measured_inputs, perturb  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402
from bifilar.studies.shorthands import apply_params  # noqa: E402


def measured_scene(truth, rng, unc):
    """The scene an experimenter writes down: every measured input of the
    budget (:func:`~bifilar.estimation.sensitivity.measured_inputs`) off by a
    normal error of its declared std (tests/conftest.py draws the same
    errors array by array)."""
    s = truth
    for name in measured_inputs(truth):
        sd = input_sigma(truth, name, unc)
        if sd > 0:
            s = perturb(s, name, rng.normal(0.0, sd))
    return s


def check(path: str, params: dict, comp: str, draws: int, seed: int) -> dict:
    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, tensions=False, components=[comp])
    p = sw.evaluate_point(cfg, path, params, st)
    if not p["valid"]:
        return {"params": params, "comp": comp, "error": p["error"]}
    e = p["components"][comp]
    if e.get("sigma") is None:
        return {"params": params, "comp": comp, "sigma": None, "reason": e.get("sigma_unavailable") or e.get("reason")}
    scene = scene_from_dict(apply_params(cfg, params, path)[0], warn=False)
    unc = st.unc
    rng = np.random.default_rng(seed)
    est, std, refused = [], [], 0
    t0 = time.process_time()
    for _ in range(draws):
        ms = MeasurementSet([Hanging("reference", measured_scene(scene, rng, unc), np.eye(3))],
                            [Measurement(e["mode"], e["period"] + rng.normal(0, unc["timing"]), unc["timing"],
                                         "period", "--period", amplitude=0.0)])
        ms.uncertainty = dict(unc)
        try:
            r = invert(ms, method="linear", solve_for=[comp], ladder=False)
        except BifilarError:
            refused += 1
            continue
        est.append(r.value(comp))
        std.append(r.sigma(comp))
    est = np.array(est)
    sd = float(np.std(est, ddof=1)) if len(est) > 1 else float("nan")
    return {"params": params, "comp": comp, "mode": e["mode"], "value": e["value"], "sigma": e["sigma"],
            "realised_sd": sd, "ratio": sd / e["sigma"],
            "mean_error_se": float((est.mean() - e["value"]) / (sd / np.sqrt(len(est)))) if len(est) > 1 else None,
            "invert_std_over_sigma": float(np.nanmedian(std) / e["sigma"]) if std else None,
            "refused": refused, "draws": draws, "p_unphysical": e.get("p_unphysical"),
            "p_refused": e.get("p_refused"), "cpu_s": time.process_time() - t0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("config")
    ap.add_argument("params", help="the point's parameters as JSON, e.g. '{\"spacing\": 2.5}'")
    ap.add_argument("--components", default="Ixx,Iyy,Izz")
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    for comp in a.components.split(","):
        print(json.dumps(check(a.config, json.loads(a.params), comp, a.draws, a.seed)), flush=True)


if __name__ == "__main__":
    main()
