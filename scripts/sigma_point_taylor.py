#!/usr/bin/env python
"""Would a base-point curvature rule have skipped a sweep point's sigma points
safely?  For a set of rigs, each sweep point's honest sigma is computed as
today (:func:`bifilar.studies.sweep.evaluate_point`), and at every call of
:func:`bifilar.estimation.second_order.second_order` (one per inertia
component) two verdicts are printed side by side:

* the sigma points' own (what the code decides: every input at ``+-sqrt(3)``
  sigma, the unknown re-solved; "linear" when the second-order std is within
  ``LINEAR_ENOUGH`` of the linear one and the summed offset below
  ``OFFSET_ENOUGH`` of it), with its two figures (``chg``: the std's relative
  change, ``off``: ``|sum b_j| / std``);
* the verdict of the rule a cheap skip would use: each input's first-order
  term exactly linear (``a_j = c_j``, its linear contribution) and its
  quadratic term ``b_j`` from the response's curvature at the base point
  (what second derivatives by the implicit-function machinery would give;
  here measured, not derived: the same sigma points at ``sigma / K``, their
  ``b_j`` times ``K^2``, default ``K = 10``).

``FALSE SKIP`` marks a component the curvature rule calls linear where the
sigma points do not: a skip there would change the printed sigma.  ``--detail
N``: for the case of index N, each input's ``b_j / std`` at ``sigma / K`` for
K = 1, 2, 4, 10, 30 (the terms above 3e-3 of the std), and each sigma point
whose measured period moves by more than 0.3 % (1 %: past the one-step
re-solve, :func:`~bifilar.estimation.second_order._one_step`).

    python scripts/sigma_point_taylor.py [--scale K] [--detail N]

Written for session 28 (sigma28: the negative result of docs/design.md
"sigma28, session 28"); it changes nothing, ~30 s.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import bifilar.estimation.invert as iv  # noqa: E402
from bifilar.config import read_yaml  # noqa: E402
from bifilar.estimation import second_order as so  # noqa: E402
from bifilar.studies import sweep as sw  # noqa: E402

C, A = ROOT / "configs", ROOT / "tests" / "data" / "audit27"
#: the shipped rigs with sigma points, audit27's four, and the boat towards its knife edge (height: the
#: attachments' height above the CoM, 0.205 m as shipped)
CASES = ([(C / "solar_boat.yaml", {"spacing": 3.0}), (C / "trifilar_kth.yaml", {}), (C / "drone_parallel.yaml", {}),
          (C / "thesis_cylinder_6_4.yaml", {})]
         + [(A / f, {}) for f in ("a01_offcentre.yaml", "a02_heavy3.yaml", "a03_neardegen.yaml",
                                  "a04_quad_elastic.yaml")]
         + [(C / "solar_boat.yaml", {"spacing": 3.0, "height": h})
            for h in (0.1, 0.05, 0.03, 0.02, 0.015, 0.012, 0.01, 0.008, 0.006)])


def verdict(lin, coefs: dict) -> tuple[bool, float, float]:
    """(linear?, relative std change, |offset| / std) of the quadratic
    surrogate ``coefs`` {input: (a, b)}, as :func:`second_order` decides."""
    std1 = lin.std
    contrib = {k: v for k, v in lin.contributions.items() if k not in coefs}
    off = np.zeros_like(std1)
    for k, (a, b) in coefs.items():
        contrib[k], contrib[k + " (2nd order)"] = a, math.sqrt(2) * b
        off = off + b
    var2 = sum((np.asarray(c) ** 2 for c in contrib.values()), np.zeros_like(std1)) + off ** 2
    chg, orel = np.abs(np.sqrt(var2) / std1 - 1), np.abs(off) / std1
    return bool(np.all(chg < so.LINEAR_ENOUGH) and np.all(orel < so.OFFSET_ENOUGH)), float(np.max(chg)), float(np.max(orel))


def coefficients(pb, ctx, p_hat, r_hat, keys, scale: float):
    """{input: (a, b)} from sigma points at ``sigma / scale``, scaled back
    (``a`` times ``scale``, ``b`` times ``scale^2``); None if one cannot hang."""
    h = so.SIGMA_POINT
    sol = so._solve_points(pb, ctx, p_hat, r_hat, {(k, s): [(k, s * h * ctx.sigmas[k] / scale)]
                                                   for k in keys for s in (1, -1)})
    p0 = np.asarray(p_hat, float)
    out = {}
    for k in keys:
        pp, pm = sol[(k, 1)], sol[(k, -1)]
        if pp is None or pm is None:
            return None
        out[k] = ((pp - pm) / (2 * h) * scale + ctx.factor_shift.get(k, 0.0), (pp + pm - 2 * p0) / 6 * scale ** 2)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=10.0, help="K: the curvature from sigma points at sigma / K")
    ap.add_argument("--detail", type=int, default=None, help="per-input figures of case N (0-based)")
    args = ap.parse_args(argv)
    orig = so.second_order
    rows: list = []
    detail = [False]

    def spy(pb, p_hat, r_hat, ctx, lin):
        res = orig(pb, p_hat, r_hat, ctx, lin)
        keys = [k for k in ctx.inputs if ctx.sigmas.get(k, 0) > 0]
        if not keys or any(any(m.period is None for m in ms.modes) for ms in ctx.modes):
            rows.append((pb.unknowns[0], None, None))
            return res
        act, base = coefficients(pb, ctx, p_hat, r_hat, keys, 1.0), coefficients(pb, ctx, p_hat, r_hat, keys, args.scale)
        rows.append((pb.unknowns[0], verdict(lin, act) if act else (False, math.inf, math.inf),
                     verdict(lin, {k: (lin.contributions[k], b) for k, (_, b) in base.items()}) if base else None))
        if detail[0]:
            std1 = float(lin.std[0])
            print(f"  {pb.unknowns[0]} (mode {pb.measurements[0].label}), std {std1:.4g}")
            for K in (1, 2, 4, 10, 30):
                cf = coefficients(pb, ctx, p_hat, r_hat, keys, K) or {}
                big = [f"{k} {float(b[0]) / std1:+.2e}" for k, (_, b) in cf.items() if abs(float(b[0])) > 3e-3 * std1]
                print(f"    K {K:>2}: b/std " + ", ".join(big))
            h = so.SIGMA_POINT
            for k in keys:
                for s in (1, -1):
                    scene = so._perturbed_scene(pb, 0, ctx.scenes[0], [(k, s * h * ctx.sigmas[k])])
                    hit = so._hanging_periods([scene], ctx.rests[0], ctx.modes[0])[0]
                    if hit is not None:
                        rel = float(hit[0][ctx.match[0][pb.mode_index[0]]] / ctx.T_hat[0] - 1)
                        if abs(rel) > 3e-3:
                            print(f"    {k} {'+' if s > 0 else '-'}: period moves {rel:+.2e} "
                                  f"({'one step' if abs(rel) < 1e-2 else 'multi-step re-solve'})")
        return res

    iv.second_order = spy
    false_skips = 0
    for n, (path, params) in enumerate(CASES):
        if args.detail is not None and n != args.detail:
            continue
        detail[0] = args.detail is not None
        cfg = read_yaml(path)
        rows.clear()
        out = sw.evaluate_point(cfg, str(path), params, sw.resolve_settings(cfg))
        print(f"[{n}] {path.name} {params}: {'valid' if out['valid'] else out['error']}")
        for comp, act, base in rows:
            if act is None:
                print(f"   {comp}: no sigma points")
                continue
            fs = base is not None and base[0] and not act[0]
            false_skips += fs
            b = f"{'linear' if base[0] else 'NONLIN'} (chg {base[1]:.2e}, off {base[2]:.2e})" if base else "n/a"
            print(f"   {comp}: sigma points {'linear' if act[0] else 'NONLIN'} (chg {act[1]:.2e}, off {act[2]:.2e});"
                  f" base curvature {b}{'  FALSE SKIP' if fs else ''}")
    print(f"false skips: {false_skips}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
