"""``sweep --plot``: every figure of a sweep in one image."""

from __future__ import annotations

import numpy as np

from . import new_figure, save


def plot_sweep(path, data: dict, title: str = "") -> None:
    """Draw a sweep to ``path`` (format from its ending): each figure against
    the swept parameter (one parameter, or ``--zip``), heatmaps with the
    feasible region outlined (a 2-D grid), or against the point index
    (otherwise); always the uncertainty-vs-peak-tension front.

    ``data``: :func:`bifilar.studies.sweep_output.sweep_figure_data` (its
    keys and units); relative quantities are shown in %."""
    d = data
    obj, peak, dmax, feas = d["objective"], d["tension_peak"], d["depth_max"], d["feasible"]
    lim, best, target, components = d["limits"], d["best"], d["target"], d["components"]
    fig, axes = new_figure(2, 3, size=(15, 8.5))
    ax = axes.ravel()
    if d["layout"] == "line":
        name, unit, _ = d["params"][0]
        x = d["param_values"][name]
        xl = f"{name} [{unit}]"
        for c in components:
            y = 100 * d["rel_sigma"][c]
            ax[0].semilogy(x, y, "o-", ms=3, label=c if np.isfinite(y).any() else f"{c}: not identifiable")
            for m, ls in (("small_angle", "--"), ("thesis", ":"), ("linear", "-")):
                y = 100 * d["bias"][c][m]
                if np.any(np.isfinite(y)):
                    ax[1].plot(x, y, ls, marker=".", label=f"{c} {m.replace('_', '-')}")
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[1].set_ylabel("estimator bias vs full model [%]")
        ax[1].axhline(0, color="k", lw=0.5)
        ax[2].semilogy(x, 100 * d["separation"], "ko-", ms=3, label="timed modes")
        ax[2].set_ylabel("mode separation [%]")
        ax[2].set_title("smallest gap between a timed mode and any other", fontsize=9)
        if lim["min_separation"] is not None:
            ax[2].axhline(100 * lim["min_separation"], color="r", lw=1, ls="--", label="minimum")
        ax[3].plot(x, d["tension_rest"], "k-", label="rest (largest wire)")
        ax[3].plot(x, peak, "r^-", ms=4, label="peak during excitation")
        ax[3].plot(x, d["tension_min"], "bv-", ms=4, label="minimum during excitation")
        if lim["max_tension"] is not None:
            ax[3].axhline(lim["max_tension"], color="r", ls="--", lw=1, label="limit")
        ax[3].set_ylabel("wire tension [N]")
        ax[4].plot(x, d["depth_rest"], "k-", label="at rest")
        ax[4].plot(x, dmax, "o-", ms=3, label="with swing")
        if lim["max_depth"] is not None:
            ax[4].axhline(lim["max_depth"], color="r", ls="--", lw=1, label="limit")
        ax[4].set_ylabel("depth below ceiling [m]")
        for a in ax[:5]:
            a.set_xlabel(xl)
            if np.any(~feas):
                for xi, f in zip(x, feas):
                    if not f:
                        a.axvspan(xi - 1e-12, xi + 1e-12, color="0.85", lw=3, zorder=-1)
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
        if best is not None:
            for a in ax[:5]:
                a.axvline(x[best], color="g", lw=1, alpha=0.6)
    elif d["layout"] == "grid":
        (n0, u0, v0), (n1, u1, v1) = d["params"]
        nx, ny = len(v0), len(v1)
        X, Y = np.meshgrid(v1, v0)
        panels = [(np.log10(100 * obj), "log10 rel. uncertainty [%]" + (f" of {target}" if target else " (worst)")),
                  (peak, "peak wire tension [N]"), (dmax, "depth with swing [m]"),
                  (100 * d["separation"], "mode separation [%]"),
                  (np.log10(100 * d["rel_sigma"][components[0]]), f"log10 rel. uncertainty of {components[0]} [%]")]
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
            a.set_xlabel(f"{n1} [{u1}]")
            a.set_ylabel(f"{n0} [{u0}]")
            if best is not None:
                a.plot(d["param_values"][n1][best], d["param_values"][n0][best], "r*", ms=14, mec="w")
        ax[0].set_title("red line: edge of the feasible region (hatched: infeasible)", fontsize=9)
    else:
        idx = np.arange(len(obj))
        for c in components:
            ax[0].semilogy(idx, 100 * d["rel_sigma"][c], "o", label=c)
        ax[0].set_xlabel("point")
        ax[0].set_ylabel("predicted rel. uncertainty [%]")
        ax[0].legend()
        ax[1].plot(idx, peak, "r^")
        ax[1].set_ylabel("peak tension [N]")
        ax[2].plot(idx, dmax, "o")
        ax[2].set_ylabel("depth with swing [m]")
        for a in ax[3:5]:
            a.axis("off")
    _front(ax[5], d)
    fig.suptitle(title)
    fig.tight_layout()
    save(fig, path)


def _front(a, d: dict) -> None:
    """The trade-off: predicted relative uncertainty against peak tension."""
    obj, peak, feas, best = d["objective"], d["tension_peak"], d["feasible"], d["best"]
    ok = np.isfinite(obj) & np.isfinite(peak)
    a.semilogy(peak[ok & ~feas], 100 * obj[ok & ~feas], "x", color="0.6", label="infeasible")
    a.semilogy(peak[ok & feas], 100 * obj[ok & feas], "o", color="C0", ms=4, label="feasible")
    front = d["pareto_front"]
    if front:
        a.semilogy(peak[front], 100 * obj[front], "k-", lw=1, label="Pareto front")
    if best is not None and np.isfinite(peak[best]):
        a.semilogy(peak[best], 100 * obj[best], "g*", ms=14, label="recommended")
    if d["limits"]["max_tension"] is not None:
        a.axvline(d["limits"]["max_tension"], color="r", ls="--", lw=1)
    a.set_xlabel("peak wire tension [N]")
    a.set_ylabel("predicted rel. uncertainty [%]")
    a.set_title("uncertainty vs peak tension", fontsize=10)
    a.grid(alpha=0.3, which="both")
    if ok.any():
        a.legend(fontsize=7)
    else:
        why = ("no nonlinear runs (--no-tensions): no peak tensions" if not np.isfinite(peak).any() else
               "no point has a finite predicted uncertainty of " + (d["target"] or "the measurable components"))
        a.text(0.5, 0.5, "trade-off front empty:\n" + why, ha="center", va="center", transform=a.transAxes,
               fontsize=9, wrap=True)
