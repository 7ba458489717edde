"""Shared parts of the thesis reproduction (:mod:`bifilar.studies.reproduce`):
constants, the thesis's printed numbers, :class:`Result`, rows and helpers."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
CONFIGS = ROOT / "configs"
G = 9.81
PI = math.pi
THETA_REST = (0.0, PI / 6, PI / 2, 0.0, 0.0)  # the thesis's reference rest pose
DATA_TAG = "reproduce-thesis-data"

#: the thesis's printed numbers (section -> value), SI
THESIS = {
    "dumbbell": 1514 / 12000,
    "sway_T_analytic": 4.1744,
    "sway_T_sim": 4.2,
    "sway_rel_mean": -2.0496e-7,
    "sway_rel_var": 2.0200e-13,
    "torsion_mae": 3.9453e-5,
    "table_7_1_1": {1: (260.4167, 259.2135), 2: (208.333, 201.8223), 3: (52.0833, 52.1033)},
    "rest_tension": 566.0,  # "a little over 566 N"
    "lhs_rhs_5": ((610.55, -3.5003e-4, -1.064e-4), (611.97, -1.4786e-6, 1.0291e-6)),
    "lhs_rhs_900": ((-612.10, 4.30e-2, -5.1774e-2), (-612.33, 1.1257, 3.4258e-2)),
    "solar_geometric": {"Izz": 317.278, "Iyy": 317.154, "Ixx": 83.143},
    "table_8_3_4": {"Izz": (-11.49, 25.05, 34.68), "Iyy": (11.95, -86.39, -132.80), "Ixx": (-0.162, -0.162, -0.162)},
}


@dataclass
class Result:
    """One reproduced result: rows for the summary table, the reading taken
    (markdown), figure paths, raw numbers for tests, runtime (s)."""

    key: str
    title: str
    rows: list
    reading: str
    figures: list = field(default_factory=list)
    data: dict = field(default_factory=dict)
    runtime: float = 0.0


def row(key: str, section: str, quantity: str, thesis, ours, verdict: str, note: str = "", unit: str = "",
        stale_tol: float | None = None) -> dict:
    """A summary-table row.  ``thesis``/``ours``: number or text; ``stale_tol``:
    relative tolerance within which a fast run must reproduce ``ours`` (None:
    the value depends on the run length or tolerance)."""
    return {"key": key, "section": section, "quantity": quantity, "thesis": thesis, "ours": ours, "unit": unit,
            "verdict": verdict, "note": note, "stale_tol": stale_tol}


def fmt(x, digits: int = 6) -> str:
    """Number for the report: ``digits`` significant digits, scientific outside [1e-3, 1e6)."""
    if isinstance(x, str):
        return x
    if x is None:
        return "-"
    x = float(x)
    if not math.isfinite(x):
        return str(x)
    if x != 0 and not 1e-3 <= abs(x) < 1e6:
        return f"{x:.{max(digits - 3, 2)}e}"
    return f"{x:.{digits}g}"


# --------------------------------------------------------------------------
# helpers


def _times(ratio: float) -> str:
    """'~1e5 x' for a ratio of 1.3e5."""
    return f"~1e{round(math.log10(abs(ratio)))} x"


def _figure(figdir: Path | None, name: str, out: list, draw: Callable, *args) -> None:
    """Draw ``figdir/thesis_<name>.png`` with ``draw(path, *args)`` (a function of
    :mod:`bifilar.figures.thesis`) and list it in ``out``; nothing without ``figdir``."""
    if figdir is None:
        return
    figdir = Path(figdir)
    figdir.mkdir(parents=True, exist_ok=True)
    path = figdir / f"thesis_{name}.png"
    draw(path, *args)
    out.append(path)


def _figures():
    """:mod:`bifilar.figures.thesis` (imported only when a figure is drawn)."""
    from ..figures import thesis

    return thesis


def _scene(name: str):
    from ..config import load_scene

    return load_scene(CONFIGS / name, warn=False)


def _trapezoid(b: float, bp: float, l: float, inertia, h: float = 0.0, mass: float = 100.0):
    """Thesis-style two-wire scene: anchors b apart along world y at z = 0,
    attachments b' apart, h (m) above the CoM; principal inertia (body x, y, z)."""
    from ..config import scene_from_dict

    return scene_from_dict({
        "name": f"trapezoid b={b:g} b'={bp:g} l={l:g}", "gravity": G,
        "body": {"mass": mass, "inertia": {"principal": [float(v) for v in inertia]}},
        "rig": {"anchors": [[0, -b / 2, 0], [0, b / 2, 0]], "attachments": [[0, -bp / 2, h], [0, bp / 2, h]],
                "lengths": [l, l]},
    }, "reproduce", warn=False)


def _plate_inertia() -> list:
    """The thesis's 100 kg plate 5 m (along CD, body y) x 2.5 m (body x), body
    (x, y, z) principal moments; the thesis ignores the thickness (NOTES.md)."""
    return [100 * 5**2 / 12, 100 * 2.5**2 / 12, 100 * (5**2 + 2.5**2) / 12]


def _amp_for(scene, mode) -> float:
    """The thesis's amplitude pi/80: a rotation (rad) for a rotation-dominated
    mode, else a wire angle pi/80, i.e. l pi/80 of CoM travel (m)."""
    return PI / 80 if mode.dominant >= 3 else float(np.mean(scene.lengths)) * PI / 80


def _kane_world_start(scene, theta1to4, rates=(0.0, 0.0, 0.0, 0.0)):
    """Maximal state (13,) of the thesis's angles theta1..4 (theta5 from the
    constraint) and the KaneMap; raises InputError when no theta5 closes the loop."""
    from ..analysis.kane_run import kane_map, to_world
    from ..models import kane as kn

    km = kane_map(scene)
    y10 = kn.complete_initial_state(np.asarray(theta1to4, float), np.asarray(rates, float), km.p)
    return to_world(km, y10)[0], km, y10


def _invert(scene, label: str, comp: str, period: float, method: str, amplitude=None, cycles: float = 10):
    """One rung of :func:`bifilar.estimation.invert.invert` for one period:
    the estimate (kg m^2) or the reason it does not apply (str)."""
    from ..errors import InputError
    from ..estimation import invert as inv
    from ..estimation import measurements as mm

    meas = mm.Measurement(label=label, period=float(period), std=1e-4, source="period", field="--period",
                          amplitude=amplitude if method == "nonlinear" else None, cycles=cycles)
    ms = mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3), scene.name)], [meas], solve_for=[comp])
    try:
        # physical_only=False: the rung's own answer even where it leaves the
        # physical set (the thin plates' linear estimates, lengthened by the amplitude)
        return float(inv.invert(ms, method=method, ladder=False, physical_only=False).value(comp))
    except InputError as exc:
        return str(exc).split(": ", 1)[-1]


_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2)}


def _quat_R(q):
    from ..rotations import quat_to_matrix

    return quat_to_matrix(q)
