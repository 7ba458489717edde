"""Output of a sweep: the flat CSV table of its points and the data of its
figure (drawn by :func:`bifilar.figures.plot_sweep`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .ranking import guarded_limits, point_separation
from .settings import Constraints
from .shorthands import ParamSpec



def csv_rows(points: list[dict], param_names: list[str], components: list[str],
             among=None) -> tuple[list[str], list[list]]:
    """Flat table: one row per point (header, rows); strings for labels and reasons.
    ``separation``: the mode-separation guard over the modes of the ranked
    components ``among`` (the recommendation's ``measurable``; default every
    component's: :func:`~bifilar.studies.ranking.point_separation`).
    ``tension_range_peak`` (N) and its wire: the most a wire of 4-5
    dependent wires may carry in the runs under statics (empty where the
    tensions are determined), the figure ``--max-tension``'s caution uses;
    ``ceiling_clash`` and ``wires_cross``: the body reaches above the
    ceiling, the wires cross, at rest (such points rank after every clean one)."""
    n_w = max((len(p["tension"]["rest"]) for p in points if p.get("valid")), default=0)
    header = list(param_names) + ["valid", "feasible", "rank", "objective"]
    for c in components:
        header += [f"{c}_mode", f"{c}_period_s", f"{c}_sigma", f"{c}_rel_sigma", f"{c}_rel_sens_period",
                   f"{c}_separation", f"{c}_bias_small_angle", f"{c}_bias_thesis", f"{c}_bias_linear",
                   f"{c}_nonlinear_period_s"]
    header += [f"tension_rest_{i + 1}" for i in range(n_w)] + [f"tension_max_{i + 1}" for i in range(n_w)]
    header += [f"tension_min_{i + 1}" for i in range(n_w)] + ["slack", "tension_range_peak", "tension_range_peak_wire",
                                                               "ceiling_clash", "wires_cross",
                                                               "depth_rest_m", "depth_max_m", "separation",
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
        row += [t.get("slack"), t.get("range_peak"), t.get("range_peak_wire"), p.get("ceiling_clash"),
                p.get("wires_cross"), p["depth"]["rest"], p["depth"]["max"], point_separation(p, among),
                ";".join(f"{k}={v:.10g}" if v is not None else f"{k}=" for k, v in p["periods"].items()),
                "; ".join(p.get("violations", []))]
        rows.append(row)
    return header, rows


def write_points_csv(path: Path, points: list[dict], param_names: list[str], components: list[str],
                     among=None) -> None:
    """CSV (header row) of :func:`csv_rows`, written atomically; empty cells for missing values."""
    from ..output import write_table_csv

    write_table_csv(path, *csv_rows(points, param_names, components, among))


# --------------------------------------------------------------------------
# the data of the sweep's figure (drawn by bifilar.figures.plot_sweep)


def _series(points, fn):
    out = []
    for p in points:
        try:
            v = fn(p) if p.get("valid") else None
        except (KeyError, TypeError):
            v = None
        out.append(np.nan if v is None else float(v))
    return np.asarray(out, float)


def sweep_figure_data(points: list[dict], params: list[ParamSpec], zip_: bool, components: list[str],
                      constraints: Constraints, rec: dict) -> dict:
    """The series :func:`bifilar.figures.plot_sweep` draws, one value per
    point (NaN where a point is invalid or lacks it), SI units.

    Keys: ``layout`` ("line": one swept parameter or ``--zip``; "grid": a
    2-D grid; "points": anything else), ``params`` (name, unit, values) per
    swept parameter, ``param_values`` (name -> value per point),
    ``components``, ``rel_sigma`` (component -> relative std, 1),
    ``bias`` (component -> estimator -> relative bias vs the full model, 1;
    estimators small_angle, thesis, linear), ``separation`` (the point's
    mode-separation guard over the modes of ``rec``'s ranked components, 1), ``tension_rest`` (largest wire at rest, N),
    ``tension_peak``, ``tension_min`` (during the excitation, N),
    ``depth_rest``, ``depth_max`` (below the ceiling, m; the rest depth
    where no run gave a swing), ``objective`` (the ranked relative std, 1),
    ``feasible`` (bool), ``limits`` (max_tension N, max_depth m,
    min_separation 1, or None), ``best`` (index or None), ``pareto_front``
    (indices), ``target`` (the ranked component, None for the worst)."""
    from .shorthands import param_unit

    def comp(c, key):
        return _series(points, lambda p: (p["components"].get(c) or {}).get(key))

    return {
        "layout": "line" if len(params) == 1 or zip_ else "grid" if len(params) == 2 else "points",
        "params": [(sp.name, param_unit(sp.name), np.asarray(sp.values, float)) for sp in params],
        "param_values": {sp.name: np.array([p["params"][sp.name] for p in points], float) for sp in params},
        "components": list(components),
        "rel_sigma": {c: comp(c, "rel_sigma") for c in components},
        "bias": {c: {m: _series(points, lambda p, c=c, m=m: p["components"][c]["bias"][m])
                     for m in ("small_angle", "thesis", "linear")} for c in components},
        "separation": _series(points, lambda p: point_separation(p, rec.get("measurable"))),
        "tension_rest": _series(points, lambda p: max(p["tension"]["rest"])),
        "tension_peak": _series(points, lambda p: guarded_limits(p, rec.get("measurable"))["peak"]),
        "tension_min": _series(points, lambda p: min(p["tension"]["min"]) if p["tension"]["min"] else None),
        "depth_rest": _series(points, lambda p: p["depth"]["rest"]),
        "depth_max": _series(points, lambda p: d if (d := guarded_limits(p, rec.get("measurable"))["depth"]) is not None
                             else p["depth"]["rest"]),
        "objective": _series(points, lambda p: p["objective"]),
        "feasible": np.array([bool(p.get("feasible")) for p in points]),
        "limits": {"max_tension": constraints.max_tension, "max_depth": constraints.max_depth,
                   "min_separation": constraints.min_separation},
        "best": rec.get("best"),
        "pareto_front": list(rec.get("pareto_front") or []),
        "target": None if rec.get("target", "").startswith("worst") else rec.get("target"),
    }
