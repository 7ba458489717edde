"""Candidate 95 % interval rules for invert's second-order budget, on a
closed loop's answers (docs/design.md, "profile29, session 29"): the
draws of :func:`closed_loop_invert.run` (the same seeds and draws), each
answer's second-order error model kept as ``budget.interval_95`` receives it,
and every rule's interval computed for that model and compared with the
truth.  Rules (offsets from the estimate, SI):

``now``      the interval invert prints (before any cut at the physical
             limits): session 28's hull of the mirrored ``+- t`` and the
             model's own 2.5-97.5 % quantiles (``budget.interval_95``).
``profile``  the range of the model's quadratic part ``g.z + z^T B z`` over
             the ball ``|z| <= 1.96`` of the standardised input errors
             (:func:`profile_range`: a trust-region problem, solved exactly
             from ``B``'s eigen-decomposition and the secular equation).
             ``g``: each input's linear coefficient ``a_j`` and each linear
             term (a period with ``nu`` finite dof scaled by ``t_nu / 1.96``);
             ``B``: ``b_j`` on the diagonal, half of each pair's ``k11`` off
             it; the pairs' ``z_i^2 z_j``, ``z_i z_j^2``, ``z_i^2 z_j^2``
             terms are left out (a01: 0.03-0.3 std at the ends).
``equal``    the model's own 2.5 / 97.5 % quantiles (``budget.model_samples``,
             as ``interval_95`` draws them, without the random sign).
``sym``      ``+- max |profile|`` (the profile and its mirror image).
``hull``     the profile joined with the mirrored ``+- t``.

A budget without second-order inputs (no surrogate) keeps ``now`` under every
rule (the rules differ only there).  Only models with neither an unstated
amplitude nor a stated prior's quadratic terms are compared (those keep
``now``; a01, a02, a04 and the wheel have neither).  Prints one JSON
document: per rule the coverage, its binomial se, the misses below / above
and the median width over ``now``'s; and, per input the second-order step
flagged, how many answered draws had its drawn error beyond -1.96 / +1.96
stds and the smallest and median drawn error of the refused draws (the
answered sample's censoring).  One unknown (the first of ``--components``).

    python scripts/interval_rules_compare.py tests/data/audit27/a01_offcentre.yaml --draws 300 --seed 1
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's bifilar, not an installed copy

import bifilar.estimation.invert as _invert  # noqa: E402
from bifilar.estimation.budget import model_samples  # noqa: E402
from closed_loop_invert import loop_arguments, run  # noqa: E402

#: the profile's radius: sqrt of chi2_1's 95 % point (a linear model's +- 1.96 std)
RADIUS = 1.959963984540054


def _trs_max(g, B, r: float):
    """(max, maximiser) of ``g.z + z^T B z`` over ``|z| <= r`` (any units
    of ``g``, ``B``; ``z`` dimensionless): the trust-region subproblem,
    exact.  With ``B = Q diag(beta) Q^T`` and ``gamma = Q^T g`` the
    maximiser is ``z(mu) = Q gamma / (2 (mu - beta))`` with ``mu >=
    max(beta_max, 0)``: inside the ball where ``B`` is negative definite and
    ``z(0)`` lies within it, else on the sphere, ``|z(mu)| = r`` (the
    secular equation, ``1/r - 1/|z(mu)|`` increasing in ``mu``, by brentq),
    or in the hard case (``g`` orthogonal to ``beta_max``'s eigenvectors and
    ``|z(beta_max)| <= r``) ``z(beta_max)`` plus that eigenvector to the
    sphere."""
    from scipy import optimize

    g = np.asarray(g, float)
    B = 0.5 * (np.asarray(B, float) + np.asarray(B, float).T)
    beta, Q = np.linalg.eigh(B)
    gam = Q.T @ g
    bmax = float(beta[-1])
    gn = float(np.linalg.norm(g))
    scale = max(gn / r, float(np.max(np.abs(beta))), 1e-300)

    def val(z):
        return float(g @ z + z @ B @ z)

    if bmax < 0:
        z0 = Q @ (gam / (-2 * beta))
        if np.linalg.norm(z0) <= r:
            return val(z0), z0
        left = 0.0
    else:
        top = beta >= bmax - 1e-13 * scale
        w = np.zeros(len(g))
        w[~top] = gam[~top] / (2 * (bmax - beta[~top]))
        if np.linalg.norm(gam[top]) <= 1e-13 * max(gn, 1e-300) and np.linalg.norm(w) <= r:
            q = Q[:, int(np.nonzero(top)[0][0])]
            tau = math.sqrt(max(r * r - w @ w, 0.0))
            zs = [Q @ w + s * tau * q for s in (1.0, -1.0)]
            vs = [val(z) for z in zs]
            k = int(np.argmax(vs))
            return vs[k], zs[k]
        left = bmax + 1e-15 * scale  # just off the pole, where |z| > r
    right = max(bmax, 0.0) + gn / (2 * r) * (1 + 1e-9) + 1e-300  # |z(mu)| <= |g| / (2 (mu - bmax)) <= r

    def phi(mu):
        return 1.0 / r - 1.0 / math.sqrt(float(np.sum((gam / (2 * (mu - beta))) ** 2)))

    mu = left if phi(left) <= 0 else optimize.brentq(phi, left, right, xtol=1e-15 * scale, rtol=1e-15, maxiter=500)
    z = Q @ (gam / (2 * (mu - beta)))
    return val(z), z


def profile_range(g, B, r: float = RADIUS) -> tuple[float, float]:
    """(min, max) of ``g.z + z^T B z`` over the ball ``|z| <= r``, exact
    (:func:`_trs_max` of ``f`` and of ``-f``): for a linear ``f`` ``+- r
    |g|``; for one input ``a z + b z^2`` the image of ``[-r, r]``."""
    hi, _ = _trs_max(g, B, r)
    lo, _ = _trs_max(-np.asarray(g, float), -np.asarray(B, float), r)
    return -lo, hi


def quadratic_model(budget, ctx, i: int):
    """(keys, g, B) of unknown ``i``'s error model (module docstring):
    the second-order inputs ``ctx.surrogate`` first, then the budget's linear
    terms; SI units of the unknown per standard uncertainty."""
    from scipy import stats

    sur = ctx.surrogate
    skip = set(sur) | {f"amplitude[{lab}]" for lab in ctx.amplitude} | {"offset"}
    keys = list(sur)
    g = [float(sur[k][0][i]) for k in keys]
    for k, c in budget.contributions.items():
        if k in skip or k.endswith("(2nd order)"):
            continue
        nu = budget.dof.get(k, math.inf)
        f = stats.t.ppf(0.975, nu) / stats.norm.ppf(0.975) if math.isfinite(nu) else 1.0
        keys.append(k)
        g.append(float(np.asarray(c)[i]) * f)
    idx = {k: m for m, k in enumerate(keys)}
    B = np.zeros((len(keys), len(keys)))
    for k in sur:
        B[idx[k], idx[k]] = float(sur[k][1][i])
    for (ki, kj), (k11, _, _, _) in ctx.cross.items():
        B[idx[ki], idx[kj]] += 0.5 * float(k11[i])
        B[idx[kj], idx[ki]] += 0.5 * float(k11[i])
    return keys, np.array(g), B


def rules(budget, ctx, now, i: int, n: int) -> dict:
    """{rule: (lo, hi)} offsets from the estimate (SI) of unknown ``i``."""
    out = {"now": tuple(now)}
    if not ctx.surrogate or ctx.amplitude or (ctx.prior is not None and ctx.prior.quadratic_terms(budget)):
        return {k: tuple(now) for k in ("now", "profile", "equal", "sym", "hull")}
    _, g, B = quadratic_model(budget, ctx, i)
    lo, hi = profile_range(g, B)
    out["profile"] = (lo, hi)
    e = model_samples(budget, ctx, np.random.default_rng(20261123), n)[:, i]
    out["equal"] = tuple(np.quantile(e, [0.025, 0.975]))
    m = max(-lo, hi)
    out["sym"] = (-m, m)
    t = float(np.quantile(np.abs(e), 0.95))
    out["hull"] = (min(lo, -t), max(hi, t))
    return out


def compare(path: str, modes: list, comps: list, draws: int, seed: int, samples: int = 4000) -> dict:
    """The JSON document of the module docstring."""
    last: dict = {}
    orig = _invert.interval_95

    def keep_model(p_hat, budget, ctx, mc_samples=None):
        out = orig(p_hat, budget, ctx, mc_samples)
        last.update(budget=budget, ctx=ctx, interval=out, p=np.array(p_hat, float))
        return out

    class Keep(list):  # each draw's record with the model of its last interval_95 call
        def append(self, row):
            row["model"] = dict(last)
            last.clear()
            super().append(row)

    keep = Keep()
    _invert.interval_95 = keep_model
    try:
        summary = run(path, modes, comps, draws, seed, keep=keep)
    finally:
        _invert.interval_95 = orig
    c = comps[0]
    truth = summary[c]["truth"]
    stats_: dict = {}
    unmatched = 0
    flagged: set = set()
    for row in keep:
        if "result" not in row:
            continue
        res, mod = row["result"], row["model"]
        i = list(res.names).index(c)
        if not np.isfinite(res.std[i]):
            continue
        if not mod or not np.allclose(mod["interval"][i], res.interval_unclipped[i], rtol=0, atol=0):
            unmatched += 1  # the last interval_95 call was not this answer's (none seen on a01-a04)
            continue
        flagged |= set(mod["ctx"].nonlinear)
        p = float(res.values[i])
        now = res.interval_unclipped[i] - p
        e = truth - p
        for k, (lo, hi) in rules(mod["budget"], mod["ctx"], now, i, samples).items():
            s = stats_.setdefault(k, {"n": 0, "miss_low": 0, "miss_high": 0, "w": []})
            s["n"] += 1
            s["miss_low"] += int(e < lo)
            s["miss_high"] += int(e > hi)
            s["w"].append((hi - lo) / (now[1] - now[0]))
    out = {"config": path, "component": c, "draws": draws, "seed": seed, "answered": summary["answered"],
           "refused": summary["refused"], "unmatched": unmatched, "rules": {}}
    for k, s in stats_.items():
        cov = 1 - (s["miss_low"] + s["miss_high"]) / s["n"]
        out["rules"][k] = {"n": s["n"], "coverage": round(cov, 4),
                           "se": round(math.sqrt(max(cov * (1 - cov), 0.0475) / s["n"]), 4),
                           "miss_low": s["miss_low"], "miss_high": s["miss_high"],
                           "median_width_over_now": round(float(np.median(s["w"])), 3)}
    cens = {}
    for key in sorted(flagged):
        ans = np.array([r["errors"].get(key, 0.0) for r in keep if "result" in r])
        ref = np.array([r["errors"].get(key, 0.0) for r in keep if "refused" in r])
        cens[key] = {"answered_below_-1.96": int(np.sum(ans < -RADIUS)), "answered_above_1.96": int(np.sum(ans > RADIUS)),
                     "refused_min": round(float(ref.min()), 2) if len(ref) else None,
                     "refused_median": round(float(np.median(ref)), 2) if len(ref) else None}
    out["drawn_errors_of_flagged_inputs"] = cens
    return out


def main() -> None:
    ap = loop_arguments(__doc__.split("\n\n")[0] + "  The first of --components is compared.")
    ap.add_argument("--samples", type=int, default=4000, help="model samples for the equal and hull rules")
    a = ap.parse_args()
    print(json.dumps(compare(a.config, a.modes.split(","), a.components.split(","), a.draws, a.seed, a.samples),
                     indent=1))


if __name__ == "__main__":
    main()
