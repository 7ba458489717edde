"""Files for people and programs: time-series CSV and figures.

matplotlib is imported lazily (Agg backend) so the CLI starts fast.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .output import atomic_write, write_csv


def write_timeseries_csv(path: Path, scene, rest, res) -> None:
    """time (s), CoM x, y, z (m, world), attitude rotation vector relative to
    rest (rad, world), quaternion w, x, y, z (body -> world), tensions (N),
    and the thesis angles theta1..theta5 (rad) when the run used the kane model."""
    from .analysis.simulate import relative_pose

    rel = relative_pose(res.y, rest)
    cols = [res.t, *res.y[:, 0:3].T, *rel[:, 3:].T, *res.y[:, 3:7].T, *res.tensions.T]
    header = ["t", "com_x", "com_y", "com_z", "rot_x", "rot_y", "rot_z", "q_w", "q_x", "q_y", "q_z"]
    header += [f"tension_{i + 1}" for i in range(scene.n_wires)]
    theta = getattr(res, "theta", None)
    if theta is not None:
        cols += list(np.asarray(theta).T)
        header += [f"theta{i + 1}" for i in range(5)]
    write_csv(path, header, np.column_stack(cols))


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_simulation(path: Path, scene, res) -> None:
    """Timed coordinate, wire tensions and constraint health against time."""
    plt = _pyplot()
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax[0].plot(res.t, res.coordinate, lw=1)
    ax[0].plot(res.crossings, np.zeros_like(res.crossings), "k|", ms=10, label="upward crossings")
    ax[0].set_ylabel(f"{res.coordinate_name} rel. rest")
    per = f"{res.period:.6f} s" if res.period else "n/a"
    ax[0].set_title(f"{scene.name}: mode {res.mode}, measured period {per}")
    ax[0].legend(loc="upper right")
    for i in range(scene.n_wires):
        ax[1].plot(res.t, res.tensions[:, i], lw=1, label=f"wire {i + 1}")
    ax[1].axhline(0, color="r", lw=0.8)
    ax[1].set_ylabel("tension [N]")
    ax[1].set_xlabel("time [s]")
    ax[1].legend(loc="upper right")
    fig.tight_layout()
    atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png"))
    plt.close(fig)
