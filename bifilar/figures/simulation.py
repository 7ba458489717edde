"""``simulate --plot``: a nonlinear run's timed coordinate and wire tensions."""

from __future__ import annotations

import numpy as np

from . import new_figure, save


def plot_simulation(path, res, name: str = "") -> None:
    """Draw a run to ``path`` (format from its ending): above, the timed
    coordinate relative to rest (rad or m) against time (s) with the upward
    crossings that timed the period; below, each wire's tension (N).

    ``res``: a simulation result (:class:`bifilar.analysis.simulate.SimulationResult`
    or the kane model's): ``t``, ``coordinate``, ``coordinate_name``,
    ``crossings``, ``period``, ``mode``, ``tensions`` (time x wires).
    ``name``: the scene's name, for the title."""
    fig, ax = new_figure(2, 1, size=(9, 6), sharex=True)
    ax[0].plot(res.t, res.coordinate, lw=1)
    ax[0].plot(res.crossings, np.zeros_like(res.crossings), "k|", ms=10, label="upward crossings")
    ax[0].set_ylabel(f"{res.coordinate_name} rel. rest")
    per = f"{res.period:.6f} s" if res.period else "n/a"
    ax[0].set_title(f"{name}: mode {res.mode}, measured period {per}")
    ax[0].legend(loc="upper right")
    tensions = np.asarray(res.tensions)
    for i in range(tensions.shape[1]):
        ax[1].plot(res.t, tensions[:, i], lw=1, label=f"wire {i + 1}")
    ax[1].axhline(0, color="r", lw=0.8)
    ax[1].set_ylabel("tension [N]")
    ax[1].set_xlabel("time [s]")
    ax[1].legend(loc="upper right")
    fig.tight_layout()
    save(fig, path, dpi=120)
