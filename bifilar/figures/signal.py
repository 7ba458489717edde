"""``period --plot`` (and ``invert --plot``, one per recording): a period fit."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import new_figure, save


def plot_fit(path, fit, t, y, title: str | None = None) -> Path:
    """Draw a period fit to ``path`` (format from its ending): the signal with
    the fitted model and its envelope on top (the samples outside the fit
    window shaded, the upward crossings marked), the residuals below.

    ``fit``: a :class:`bifilar.estimation.signal.PeriodFit`; ``t`` (s) and
    ``y`` (signal units): the whole recording.  Returns ``path``."""
    t = np.asarray(t, float).ravel()
    y = np.asarray(y, float).ravel()
    fig, (ax, axr) = new_figure(2, 1, size=(10, 6.5), layout="constrained", sharex=True,
                                gridspec_kw={"height_ratios": [2.2, 1]})
    lw = 0.6 if t.size > 3000 else 0.9
    ax.plot(t, y, color="0.55", lw=lw, label="signal")
    if fit.model != "crossings":
        tt = fit.t_used
        ax.plot(tt, fit.predict(tt), color="C3", lw=lw, label=f"{fit.model} fit")
        base = fit.offset + fit.drift * (tt - fit.t_ref)
        env = fit.envelope(tt)
        ax.plot(tt, base + env, color="C0", lw=0.8, ls="--", label="envelope")
        ax.plot(tt, base - env, color="C0", lw=0.8, ls="--")
        axr.plot(tt, fit.residuals, color="C3", lw=lw)
        axr.axhline(0, color="k", lw=0.5)
    for lo, hi in ((t[0], fit.t0), (fit.t1, t[-1])):
        if hi > lo:
            ax.axvspan(lo, hi, color="0.9", zorder=0)
            axr.axvspan(lo, hi, color="0.9", zorder=0)
    if fit.crossing is not None:
        ax.plot(fit.crossing.up_times, np.full(fit.crossing.up_times.size, fit.crossing.level), "|",
                color="k", ms=8, label="upward crossings")
    txt = f"T = {fit.period:.6f} ± {fit.std:.2g} s"
    if np.isfinite(fit.damping_ratio):
        txt += f"\nζ = {fit.damping_ratio:.4g}"
    if np.isfinite(fit.r_squared):
        txt += f",  r² = {fit.r_squared:.5f}"
    if fit.uncertainty.get("dominant", "noise") != "noise":
        txt += f"\nstd dominated by {fit.uncertainty['dominant'].replace('_', ' ')}"
    ax.text(0.99, 0.97, txt, transform=ax.transAxes, ha="right", va="top", fontsize=9,
            bbox={"boxstyle": "round", "fc": "white", "ec": "0.7", "alpha": 0.9})
    ax.set_ylabel("signal")
    axr.set_ylabel("residual")
    axr.set_xlabel("t [s]")
    ax.legend(loc="upper left", fontsize=8)
    if title:
        ax.set_title(title)
    return save(fig, path)
