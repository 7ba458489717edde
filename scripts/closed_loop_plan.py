"""Closed-loop check of a sweep point (docs/design.md, "Closed-loop check of
the planner, session 6"): do the experiment the planner describes and
compare with what it predicted.

For each component: the point's scene is built, the period of its mode is
timed with the sweep's timing std, every measured input of the
experimenter's config is drawn from its declared std, and the period is
inverted as a user would (``invert --period MODE=T+-TIMING --amplitude 0
--solve-for C``, the library path).  With ``--amplitude A`` the sweep runs
at that amplitude (its sigma then budgets the stated amplitude's 10 %), each
experiment's release amplitude is drawn about ``A`` with that 10 %, the
period is the one the true body shows at it (nonlinear, 10 cycles, rtol
1e-10) and the user states ``--amplitude A``.  Prints one JSON line per
component: the sweep's sigma (and its small-amplitude one), the realised sd
and their ratio, the mean error in standard errors, invert's median std over
the sweep's, the refused draws, and the point's predicted ``p_unphysical`` /
``p_refused``.

    python scripts/closed_loop_plan.py configs/solar_boat.yaml '{"spacing": 2.5, "length": 2.0}' \
        --components Ixx,Iyy,Izz --draws 200 --seed 1 [--amplitude 0.05]
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


def measured_scene(truth, rng, unc, errors: dict | None = None):
    """The scene an experimenter writes down: every measured input of the
    budget (:func:`~bifilar.estimation.sensitivity.measured_inputs`) off by a
    normal error of its declared std (tests/conftest.py draws the same
    errors array by array).  ``errors``, if given, receives each input's
    error in its own standard uncertainties, ``{input: (measured - true) /
    std}`` (scripts/crossing_partner_budget.py compares the estimate's error
    with the budget's model at these)."""
    s = truth
    for name in measured_inputs(truth):
        sd = input_sigma(truth, name, unc)
        if sd > 0:
            e = rng.normal(0.0, sd)
            s = perturb(s, name, e)
            if errors is not None:
                errors[name] = e / sd
    return s


def check(path: str, params: dict, comp: str, draws: int, seed: int, amplitude: float = 0.0) -> dict:
    from bifilar.analysis.batch import simulate_batch
    from bifilar.estimation.uncertainty import DEFAULT_AMPLITUDE_REL

    cfg = read_yaml(path)
    st = sw.resolve_settings(cfg, tensions=amplitude > 0, components=[comp],
                             **({"amplitude": amplitude} if amplitude > 0 else {}))
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
    if amplitude > 0:  # the period the true body shows at each experiment's release amplitude
        amps = amplitude * (1 + DEFAULT_AMPLITUDE_REL * rng.standard_normal(draws))
        periods = [r.period for r in simulate_batch([scene] * draws, mode=e["mode"], amplitude=list(amps),
                                                      periods=10, rtol=1e-10)]
    else:
        periods = [e["period"]] * draws
    for T in periods:
        ms = MeasurementSet([Hanging("reference", measured_scene(scene, rng, unc), np.eye(3))],
                            [Measurement(e["mode"], T + rng.normal(0, unc["timing"]), unc["timing"],
                                         "period", "--period", amplitude=amplitude)])
        ms.uncertainty = dict(unc)
        try:
            r = invert(ms, method="nonlinear" if amplitude > 0 else "linear", solve_for=[comp], ladder=False)
        except BifilarError:
            refused += 1
            continue
        est.append(r.value(comp))
        std.append(r.sigma(comp))
    est = np.array(est)
    sd = float(np.std(est, ddof=1)) if len(est) > 1 else float("nan")
    return {"params": params, "comp": comp, "mode": e["mode"], "value": e["value"], "sigma": e["sigma"],
            "amplitude": amplitude, "sigma_small_amplitude": (e.get("amplitude_budget") or {}).get("sigma_small_amplitude"),
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
    ap.add_argument("--amplitude", type=float, default=0.0,
                    help="release amplitude stated to invert (drawn with its 10 %%); 0: small (default)")
    a = ap.parse_args()
    for comp in a.components.split(","):
        print(json.dumps(check(a.config, json.loads(a.params), comp, a.draws, a.seed, a.amplitude)), flush=True)


if __name__ == "__main__":
    main()
