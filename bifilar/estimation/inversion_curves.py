"""The data of ``invert --plot``: the model's period against one unknown
near the estimate, one panel per measured mode (drawn by
:func:`bifilar.figures.plot_inversion`).  Moved out of
:mod:`bifilar.estimation.invert` (which re-exports it) when that module
passed 800 lines.  Units: periods s, inertia kg m^2, lengths m."""

from __future__ import annotations

import numpy as np

from ..errors import BifilarError
from .problem import _IDX, physical_interval


def inversion_curves(res, span: float | None = None) -> list[dict]:
    """The model's period against one unknown near the estimate, one panel per
    measured mode (drawn by :func:`bifilar.figures.plot_inversion`);
    ``res`` an :class:`~bifilar.estimation.invert.InversionResult`.

    Each panel varies the unknown the mode's period is most sensitive to
    (the others at their estimate) over the estimate +- ``span`` (its unit;
    default 6 std, at least 5 % of the value), within the physical interval
    of an inertia component.  Keys: ``x`` (kg m^2 or m), ``linear`` (s, the
    linear model; NaN where it fails), ``nonlinear`` (s, times the mode's
    amplitude factor, or None when it is 1), ``small_angle`` (s, the
    small-angle formula for a single measurement where it applies, else
    None), ``measured``, ``measured_std`` (s), ``estimate``,
    ``estimate_std``, ``amplitude`` and the labels ``unknown``, ``unit``,
    ``title``."""
    pb = res.problem
    K = len(pb.measurements)
    Jp = pb.jacobian(res.values)
    sa = next((r for r in res.ladder if r["method"] == "small-angle" and r.get("applicable")), None)
    panels = []
    for k, m in enumerate(pb.measurements):
        j = int(np.argmax(np.abs(Jp[k]) * pb.scales()))
        name = pb.unknowns[j]
        x_hat = res.values[j]
        sd = res.std[j]
        w = span if span is not None else max(6 * sd, 0.05 * abs(x_hat) if x_hat else 0.05 * pb.scales()[j])
        xs = np.linspace(x_hat - w, x_hat + w, 41)
        if name in _IDX:
            lo, hi = physical_interval(pb.models[0].inertia_ref(pb.values(res.values)), name)
            xs = xs[(xs > lo) & (xs < hi)]
        Ts = []
        for x in xs:
            p = res.values.copy()
            p[j] = x
            try:
                Ts.append(pb.linear_periods(p)[k])
            except BifilarError:
                Ts.append(np.nan)
        Ts = np.array(Ts)
        small = None
        if sa is not None and K == 1:
            # T_sa ~ sqrt(I_vertical), I_vertical = I_v(x_sa) + coefficient (x - x_sa)
            geo = sa["geometry"]
            Iv = geo["I_vertical"] + geo["coefficient"] * (xs - sa["values"][name])
            small = m.period * np.sqrt(np.clip(Iv, 0, None) / geo["I_vertical"])
        panels.append({"x": xs, "linear": Ts, "nonlinear": Ts * res.factors[k] if res.factors[k] != 1.0 else None,
                       "small_angle": small, "measured": m.period, "measured_std": m.std, "estimate": x_hat,
                       "estimate_std": sd, "amplitude": m.amplitude, "unknown": name,
                       "unit": "kg m^2" if name in _IDX else "m",
                       "title": f"{pb.models[m.hanging].hanging.name}: {m.label}"})
    return panels
