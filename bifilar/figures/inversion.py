"""``invert --plot``: the period against each unknown near the estimate."""

from __future__ import annotations

import math

import numpy as np

from . import new_figure, save


def plot_inversion(path, panels: list[dict]) -> None:
    """Draw one panel per measured mode to ``path`` (format from its ending):
    the model's period (s) against the unknown it is most sensitive to, with
    the measurement and its +-1 std band, the estimate and its +-1 std band,
    the nonlinear (amplitude) and small-angle curves where given.

    ``panels``: :func:`bifilar.estimation.invert.inversion_curves` (its keys
    and units)."""
    K = len(panels)
    ncol = min(K, 3)
    nrow = math.ceil(K / ncol)
    fig, axes = new_figure(nrow, ncol, size=(5.2 * ncol, 4.0 * nrow), layout="constrained", squeeze=False)
    axes = np.atleast_1d(axes).ravel()
    for ax, c in zip(axes, panels):
        xs = c["x"]
        ax.plot(xs, c["linear"], color="C0", label="linear model")
        if c.get("nonlinear") is not None:
            ax.plot(xs, c["nonlinear"], color="C3", label=f"nonlinear (amplitude {c['amplitude']:.3g})")
        if c.get("small_angle") is not None:
            ax.plot(xs, c["small_angle"], color="C2", ls="--", label="small-angle formula")
        ax.axhline(c["measured"], color="k", lw=0.8, label="measured")
        ax.axhspan(c["measured"] - c["measured_std"], c["measured"] + c["measured_std"], color="0.85", zorder=0)
        x_hat, sd = c["estimate"], c["estimate_std"]
        ax.axvline(x_hat, color="C1", lw=0.8, label=f"estimate {x_hat:.6g}")
        ax.axvspan(x_hat - sd, x_hat + sd, color="C1", alpha=0.15, zorder=0)
        ax.set_xlabel(f"{c['unknown']} [{c['unit']}]")
        ax.set_ylabel("period [s]")
        ax.set_title(c["title"])
        ax.legend(fontsize=7)
    for ax in axes[K:]:
        ax.set_visible(False)
    save(fig, path)
