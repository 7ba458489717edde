"""Output of a sweep: the flat CSV table of its points and its figures."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .ranking import point_separation
from .settings import Constraints
from .shorthands import ParamSpec



def csv_rows(points: list[dict], param_names: list[str], components: list[str]) -> tuple[list[str], list[list]]:
    """Flat table: one row per point (header, rows); strings for labels and reasons."""
    n_w = max((len(p["tension"]["rest"]) for p in points if p.get("valid")), default=0)
    header = list(param_names) + ["valid", "feasible", "rank", "objective"]
    for c in components:
        header += [f"{c}_mode", f"{c}_period_s", f"{c}_sigma", f"{c}_rel_sigma", f"{c}_rel_sens_period",
                   f"{c}_separation", f"{c}_bias_small_angle", f"{c}_bias_thesis", f"{c}_bias_linear",
                   f"{c}_nonlinear_period_s"]
    header += [f"tension_rest_{i + 1}" for i in range(n_w)] + [f"tension_max_{i + 1}" for i in range(n_w)]
    header += [f"tension_min_{i + 1}" for i in range(n_w)] + ["slack", "depth_rest_m", "depth_max_m", "separation",
                                                               "periods", "error"]
    rows = []
    for p in points:
        row = [p["params"].get(n) for n in param_names] + [p.get("valid"), p.get("feasible"), p.get("rank"), p.get("objective")]
        if not p.get("valid"):
            row += [None] * (len(header) - len(row) - 1) + [p.get("error") or "; ".join(p.get("violations", []))]
            rows.append(row)
            continue
        for c in components:
            e = p["components"].get(c, {})
            b = e.get("bias") or {}
            row += [e.get("mode"), e.get("period"), e.get("sigma"), e.get("rel_sigma"), e.get("rel_sensitivity_period"),
                    e.get("separation"), b.get("small_angle"), b.get("thesis"), b.get("linear"), e.get("nonlinear_period")]
        t = p["tension"]
        for key in ("rest", "max", "min"):
            vals = t.get(key) or [None] * n_w
            row += list(vals) + [None] * (n_w - len(vals))
        row += [t.get("slack"), p["depth"]["rest"], p["depth"]["max"], point_separation(p),
                ";".join(f"{k}={v:.10g}" if v is not None else f"{k}=" for k, v in p["periods"].items()),
                "; ".join(p.get("violations", []))]
        rows.append(row)
    return header, rows


def write_points_csv(path: Path, points: list[dict], param_names: list[str], components: list[str]) -> None:
    """CSV (header row) of :func:`csv_rows`, written atomically; empty cells for missing values."""
    from ..output import write_table_csv

    write_table_csv(path, *csv_rows(points, param_names, components))


# --------------------------------------------------------------------------
# figures


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _series(points, fn):
    out = []
    for p in points:
        try:
            v = fn(p) if p.get("valid") else None
        except (KeyError, TypeError):
            v = None
        out.append(np.nan if v is None else float(v))
    return np.asarray(out, float)


def plot_sweep(path: Path, points: list[dict], params: list[ParamSpec], zip_: bool, components: list[str],
               constraints: Constraints, rec: dict, title: str = "") -> None:
    """Figures of a sweep in one image: each figure against the swept
    parameter (1-D sweeps and ``--zip``), heatmaps with the feasible region
    outlined (2-D grids), the uncertainty-vs-peak-tension front (always)."""
    plt = _pyplot()
    from .shorthands import param_unit

    target = None if rec.get("target", "").startswith("worst") else rec.get("target")
    obj = _series(points, lambda p: p["objective"])
    peak = _series(points, lambda p: p["tension"]["peak"])
    dmax = _series(points, lambda p: p["depth"]["max"] if p["depth"]["max"] is not None else p["depth"]["rest"])
    feas = np.array([bool(p.get("feasible")) for p in points])
    two_d = len(params) == 2 and not zip_
    one_d = len(params) == 1 or zip_
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    ax = axes.ravel()
    if one_d:
        x = np.array([p["params"][params[0].name] for p in points], float)
        xl = f"{params[0].name} [{param_unit(params[0].name)}]"
        for c in components:
            y = 100 * _series(points, lambda p, c=c: p["components"][c]["rel_sigma"])
            ax[0].semilogy(x, y, "o-", ms=3, label=c if np.isfinite(y).any() else f"{c}: not identifiable")
            for m, ls in (("small_angle", "--"), ("thesis", ":"), ("linear", "-")):
                y = 100 * _series(points, lambda p, c=c, m=m: p["components"][c]["bias"][m])
                if np.any(np.isfinite(y)):
                    ax[1].plot(x, y, ls, marker=".", label=f"{c} {m.replace('_', '-')}")
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[1].set_ylabel("estimator bias vs full model [%]")
        ax[1].axhline(0, color="k", lw=0.5)
        ax[2].semilogy(x, 100 * _series(points, point_separation), "ko-", ms=3, label="timed modes")
        ax[2].set_ylabel("mode separation [%]")
        ax[2].set_title("smallest gap between a timed mode and any other", fontsize=9)
        if constraints.min_separation is not None:
            ax[2].axhline(100 * constraints.min_separation, color="r", lw=1, ls="--", label="minimum")
        rest_t = _series(points, lambda p: max(p["tension"]["rest"]))
        tmin = _series(points, lambda p: min(p["tension"]["min"]) if p["tension"]["min"] else None)
        ax[3].plot(x, rest_t, "k-", label="rest (largest wire)")
        ax[3].plot(x, peak, "r^-", ms=4, label="peak during excitation")
        ax[3].plot(x, tmin, "bv-", ms=4, label="minimum during excitation")
        if constraints.max_tension is not None:
            ax[3].axhline(constraints.max_tension, color="r", ls="--", lw=1, label="limit")
        ax[3].set_ylabel("wire tension [N]")
        ax[4].plot(x, _series(points, lambda p: p["depth"]["rest"]), "k-", label="at rest")
        ax[4].plot(x, dmax, "o-", ms=3, label="with swing")
        if constraints.max_depth is not None:
            ax[4].axhline(constraints.max_depth, color="r", ls="--", lw=1, label="limit")
        ax[4].set_ylabel("depth below ceiling [m]")
        for a in ax[:5]:
            a.set_xlabel(xl)
            if np.any(~feas):
                for xi, f in zip(x, feas):
                    if not f:
                        a.axvspan(xi - 1e-12, xi + 1e-12, color="0.85", lw=3, zorder=-1)
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
        if rec.get("best") is not None:
            for a in ax[:5]:
                a.axvline(x[rec["best"]], color="g", lw=1, alpha=0.6)
    elif two_d:
        p0, p1 = params
        nx, ny = len(p0.values), len(p1.values)
        X, Y = np.meshgrid(np.asarray(p1.values), np.asarray(p0.values))
        panels = [(np.log10(100 * obj), "log10 rel. uncertainty [%]" + (f" of {target}" if target else " (worst)")),
                  (peak, "peak wire tension [N]"), (dmax, "depth with swing [m]"),
                  (100 * _series(points, point_separation), "mode separation [%]"),
                  (np.log10(100 * _series(points, lambda p: (p["components"].get(components[0]) or {}).get("rel_sigma"))),
                   f"log10 rel. uncertainty of {components[0]} [%]")]
        F = feas.reshape(nx, ny).astype(float)
        for a, (Z, lab) in zip(ax[:5], panels):
            Z = np.asarray(Z, float).reshape(nx, ny)
            if np.all(~np.isfinite(Z)):
                a.text(0.5, 0.5, "n/a", ha="center", transform=a.transAxes)
            else:
                m = a.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading="nearest", cmap="viridis")
                fig.colorbar(m, ax=a, label=lab)
            if 0 < F.sum() < F.size and nx > 1 and ny > 1:
                a.contour(X, Y, F, levels=[0.5], colors="r", linewidths=1.5)
                a.contourf(X, Y, F, levels=[-0.5, 0.5], colors="none", hatches=["xx"])
            a.set_xlabel(f"{p1.name} [{param_unit(p1.name)}]")
            a.set_ylabel(f"{p0.name} [{param_unit(p0.name)}]")
            if rec.get("best") is not None:
                b = points[rec["best"]]["params"]
                a.plot(b[p1.name], b[p0.name], "r*", ms=14, mec="w")
        ax[0].set_title("red line: edge of the feasible region (hatched: infeasible)", fontsize=9)
    else:
        idx = np.arange(len(points))
        for c in components:
            ax[0].semilogy(idx, 100 * _series(points, lambda p, c=c: p["components"][c]["rel_sigma"]), "o", label=c)
        ax[0].set_xlabel("point")
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[0].legend()
        ax[1].plot(idx, peak, "r^")
        ax[1].set_ylabel("peak tension [N]")
        ax[2].plot(idx, dmax, "o")
        ax[2].set_ylabel("depth with swing [m]")
        for a in ax[3:5]:
            a.axis("off")
    # the trade-off front
    a = ax[5]
    ok = np.isfinite(obj) & np.isfinite(peak)
    a.semilogy(peak[ok & ~feas], 100 * obj[ok & ~feas], "x", color="0.6", label="infeasible")
    a.semilogy(peak[ok & feas], 100 * obj[ok & feas], "o", color="C0", ms=4, label="feasible")
    front = rec.get("pareto_front") or []
    if front:
        a.semilogy(peak[front], 100 * obj[front], "k-", lw=1, label="Pareto front")
    if rec.get("best") is not None and np.isfinite(peak[rec["best"]]):
        a.semilogy(peak[rec["best"]], 100 * obj[rec["best"]], "g*", ms=14, label="recommended")
    if constraints.max_tension is not None:
        a.axvline(constraints.max_tension, color="r", ls="--", lw=1)
    a.set_xlabel("peak wire tension [N]")
    a.set_ylabel("predicted rel. uncertainty [%]")
    a.set_title("uncertainty vs peak tension", fontsize=10)
    a.grid(alpha=0.3, which="both")
    if ok.any():
        a.legend(fontsize=7)
    else:
        why = ("no nonlinear runs (--no-tensions): no peak tensions" if not np.isfinite(peak).any() else
               "no point has a finite predicted uncertainty of " + (target or "the measurable components"))
        a.text(0.5, 0.5, "trade-off front empty:\n" + why, ha="center", va="center", transform=a.transAxes,
               fontsize=9, wrap=True)
    fig.suptitle(title)
    fig.tight_layout()
    from ..output import atomic_write

    fmt_ = Path(path).suffix.lstrip(".").lower() or "png"
    atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=110, format=fmt_))
    plt.close(fig)
