"""The time series of a nonlinear run as a CSV table (its figure is
:func:`bifilar.figures.plot_simulation`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .output import write_csv


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
