"""Is the partner reading's under-coverage selection or a budget flaw?
(docs/design.md, "cross28, session 28").  audit27's case a03 drawn as
:mod:`crossing_partner_loop` draws it (the same random stream), with each
draw's input errors kept (``measured_scene(..., errors=)``); every answer --
the direct one, or the partner reading a refusal names -- is compared with
what the budget's *own* error model says its error is, given those errors.

The model (:mod:`bifilar.estimation.second_order`): the contributions are the
coefficients of orthonormal Hermite terms in ``z_j`` (the input's error in
its own stds about the *measured* value) -- ``z`` for a linear key,
``(z^2 - 1)/sqrt 2`` for ``KEY (2nd order)``, products for the pair keys
``A x B``, ``A^2 x B``, ... -- plus ``offset``; ``e(z)`` is the truth's
estimate minus the printed one, so the printed estimate's error is
``-e(-u)`` with ``u = (measured - true) / std`` of every input and of each
period's timing.  On answered draws this reproduces the realised error to
a few hundredths of a std (checked: 0.03 rms on 284 answers); where it does
not, the budget does not describe the estimate's dependence on the inputs.

Prints one JSON document, per kind of answer ("answer": invert answered;
"partner": refused, and the reading the refusal named answered) and per
component: how many carry a std, the printed 95 % intervals' coverage, the
z = (estimate - truth) / std's mean and sd, the model's z (the inputs'
errors known) and the realised minus the model (in stds; also with the
timing noise removed: the same drawn config inverted at the truth's
periods), and the coverage the printed intervals would have if the error
were the model's (selection alone); and the whole procedure's coverage
("answer; if refused with a partner named, that reading").  ``--path N``
walks the first N partner readings' inputs back to the truth's
(:func:`path`), showing where the reading jumps.

    python scripts/crossing_partner_budget.py --modes torsion,roll --components Ixx,Izz --draws 200 --seed 4
    python scripts/crossing_partner_budget.py --draws 12 --seed 4 --path 6
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's bifilar, not an installed copy

from bifilar.config import read_yaml, scene_from_dict  # noqa: E402
from bifilar.errors import BifilarError  # noqa: E402
from bifilar.estimation.uncertainty import default_uncertainty  # noqa: E402
from closed_loop_invert import INDEX, linear_periods  # noqa: E402
from closed_loop_plan import measured_scene  # noqa: E402
from crossing_partner_loop import _invert, _named, loop_arguments  # noqa: E402


def model_error(contrib: dict, u: dict, i: int) -> float:
    """The printed estimate's error (SI) of unknown ``i`` that the budget's
    contributions ``contrib`` (Hermite coefficients, module docstring) give
    when each input is off by ``u[input]`` of its own stds: ``-e(-u)``."""
    z = {k: -v for k, v in u.items()}

    def h(key: str) -> float:  # z, or (z^2 - 1)/sqrt 2 for KEY^2
        return (z[key[:-2]] ** 2 - 1) / math.sqrt(2) if key.endswith("^2") else z[key]

    e = 0.0
    for key, c in contrib.items():
        c = float(np.asarray(c)[i])
        if key == "offset":
            e += c
        elif key.endswith(" (2nd order)"):
            base = key.removesuffix(" (2nd order)")
            a, _, b = base.partition(" x ")
            e += c * (h(a) * h(b) if b else h(base + "^2"))
        else:
            e += c * z[key]
    return -e


def draws(path: str, modes: list, comps: list, n: int, seed: int) -> list:
    """One row per draw: its kind, and for an answer its values, stds,
    intervals, realised errors, the model's errors, and the inputs-only
    realised and model errors (kg m^2)."""
    cfg = read_yaml(path)
    truth = scene_from_dict(cfg, warn=False)
    lin = linear_periods(truth)
    T = [lin[md] for md in modes]
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    tv = np.array([float(truth.inertia[INDEX[c]]) for c in comps])
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        u: dict = {}
        sc = measured_scene(truth, rng, unc, errors=u)
        Tm = [t + rng.normal(0, unc["timing"]) for t in T]
        labs, kind = list(modes), "answer"
        try:
            r = _invert(sc, labs, Tm, unc, 0.0, comps)
        except BifilarError as e:
            got = _named(str(e), list(modes), Tm, list(comps))
            kind = "partner" if got else "refused, no partner named"
            r = None
            if got:
                labs = got[0]
                try:
                    r = _invert(sc, labs, Tm, unc, 0.0, comps)
                except (BifilarError, np.linalg.LinAlgError):
                    kind = "partner refused"
        row = {"kind": kind, "labels": labs, "periods": Tm, "u": u}
        if r is not None:
            ut = dict(u, **{f"timing[{lab}]": (t - t0) / unc["timing"] for lab, t, t0 in zip(labs, Tm, T)})
            u0 = dict(u, **{f"timing[{lab}]": 0.0 for lab in labs})
            try:  # the inputs' error alone: the same drawn config at the truth's periods
                e0 = _invert(sc, labs, T, unc, 0.0, comps).values - tv
            except (BifilarError, np.linalg.LinAlgError):
                e0 = np.full(len(comps), np.nan)
            row.update(has_std=r.std_unavailable is None, value=r.values.tolist(), std=r.budget.std.tolist(),
                       interval=np.asarray(r.interval, float).tolist(), err=(r.values - tv).tolist(),
                       model=[model_error(r.budget.contributions, ut, i) for i in range(len(comps))],
                       err_inputs=e0.tolist(),
                       model_inputs=[model_error(r.budget.contributions, u0, i) for i in range(len(comps))])
        rows.append(row)
    return rows


def summary(rows: list, comps: list) -> dict:
    """Per kind and component: the figures the module docstring lists."""
    out: dict = {"kinds": {}}
    for row in rows:
        out["kinds"][row["kind"]] = out["kinds"].get(row["kind"], 0) + 1
    for kind in ("answer", "partner", "whole procedure"):
        R = [r for r in rows if r.get("has_std") and (kind == "whole procedure" or r["kind"] == kind)]
        if not R:
            continue
        out[kind] = {"with_std": len(R)}
        for i, c in enumerate(comps):
            err, sd, m = (np.array([r[f][i] for r in R]) for f in ("err", "std", "model"))
            lo, hi = (np.array([r["interval"][i][s] for r in R]) for s in (0, 1))
            t = np.array([r["value"][i] for r in R]) - err
            ei, mi = (np.array([r[f][i] for r in R]) for f in ("err_inputs", "model_inputs"))
            tm = t + err - m  # the truth, were the error the model's
            out[kind][c] = {
                "coverage": round(float(np.mean((lo <= t) & (t <= hi))), 3),
                "z_mean": round(float(np.mean(err / sd)), 2), "z_sd": round(float(np.std(err / sd)), 2),
                "model_z_mean": round(float(np.mean(m / sd)), 2), "model_z_sd": round(float(np.std(m / sd)), 2),
                "realised_minus_model_mean": round(float(np.mean((err - m) / sd)), 3),
                "realised_minus_model_rms": round(float(np.sqrt(np.mean(((err - m) / sd) ** 2))), 3),
                "inputs_only_minus_model_rms": round(float(np.sqrt(np.nanmean(((ei - mi) / sd) ** 2))), 3),
                "coverage_if_the_error_were_the_models": round(float(np.mean((lo <= tm) & (tm <= hi))), 3),
            }
    return out


def path(cfg_path: str, row: dict, modes: list, comps: list, steps=(0.0, 0.25, 0.5, 0.75, 1.0)) -> list:
    """A refused draw's inputs moved back to the truth's on a straight line
    (``t`` = 0: as drawn; 1: the truth's), each point inverted at the draw's
    periods under the partner labels and under the timed ones: [(t, {label
    set: [values (kg m^2)] or "refused"})].  Where the reading jumps, the
    budget at t = 0 cannot follow it."""
    from bifilar.estimation.sensitivity import input_sigma, perturb

    cfg = read_yaml(cfg_path)
    truth = scene_from_dict(cfg, warn=False)
    unc = default_uncertainty(dict(cfg.get("uncertainty") or {}))
    out = []
    for t in steps:
        sc = truth
        for name, u in row["u"].items():
            sc = perturb(sc, name, (1 - t) * u * input_sigma(truth, name, unc))
        got = {}
        for labs in (row["labels"], modes):
            try:
                got[",".join(labs)] = [round(float(v), 6) for v in
                                       _invert(sc, labs, row["periods"], unc, 0.0, comps).values]
            except (BifilarError, np.linalg.LinAlgError):
                got[",".join(labs)] = "refused"
        out.append((t, got))
    return out


def main() -> None:
    ap = loop_arguments(__doc__.split("\n\n")[0], "torsion,roll", "Ixx,Izz")
    ap.add_argument("--path", type=int, default=0, help="also walk the first N partner readings' inputs to the truth's")
    a = ap.parse_args()
    comps, modes = a.components.split(","), a.modes.split(",")
    t0 = time.process_time()
    rows = draws(a.config, modes, comps, a.draws, a.seed)
    out = summary(rows, comps)
    walked = [(d, r) for d, r in enumerate(rows) if r["kind"] == "partner" and r["has_std"]][:a.path]
    out["paths"] = {d: {"z": [round(e / s, 2) for e, s in zip(r["err"], r["std"])],
                        "model_z": [round(m / s, 2) for m, s in zip(r["model"], r["std"])],
                        "path": path(a.config, r, modes, comps)} for d, r in walked}
    out["cpu_s"] = round(time.process_time() - t0, 1)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
