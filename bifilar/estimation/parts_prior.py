"""A solved moment far from what the config's body description gives: a
period timed over half a swing or two swings.

A config that describes the body (``body.parts``, or ``body.inertia`` with a
value, not null) gives each moment of inertia before any timing.  A
measured period half or double the true one (counting half-swings, or two
swings as one) gives a moment about 1/4 or 4 times the true one (the
torsion's ``T ~ sqrt(I)``), and the fit cannot tell where that period is
the only one of its mode.  Where a solved principal-axis moment (Ixx, Iyy,
Izz in the reference body axes) is at least :data:`FACTOR` times or at
most 1 / :data:`FACTOR` of the described one, one warning says so.  A
description off by a factor 3 is far beyond a parts model's usual error
(the Solar Boat's model matches the thesis's to 2e-5; docs/design.md, "Fit
check and interval honesty, session 20"), so honest data do not raise it.
Units: kg m^2.
"""

from __future__ import annotations

import numpy as np

#: a solved moment this many times (or 1 / this of) the described one is warned
FACTOR = 3.0

_IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2)}


def described_moments(ms) -> dict:
    """{component: kg m^2} the config of the first hanging of ``ms`` (a
    :class:`~bifilar.estimation.measurements.MeasurementSet`, before any
    start guess replaces nulls) describes, in the reference body axes;
    components marked unknown (null) are left out."""
    from ..config import null_components

    h0 = ms.hangings[0]
    nulls = set(null_components(h0.scene))
    R0 = np.asarray(h0.rotation)
    I_ref = R0.T @ np.asarray(h0.scene.inertia, float) @ R0
    return {n: float(I_ref[ij]) for n, ij in _IDX.items() if n not in nulls and np.isfinite(I_ref[ij])}


def parts_prior_warnings(described: dict, names, values, source: str = "the config's body description") -> list[str]:
    """One warning per solved moment ``names[i]`` = ``values[i]`` (kg m^2)
    at least :data:`FACTOR` times or at most 1 / :data:`FACTOR` of its
    ``described`` value ({component: kg m^2}, :func:`described_moments`)."""
    out = []
    for n, v in zip(names, values):
        d = described.get(n)
        if n not in _IDX or d is None or not d > 0 or not np.isfinite(v) or v <= 0:
            continue
        ratio = float(v) / d
        if ratio >= FACTOR or ratio <= 1.0 / FACTOR:
            out.append(f"{n} = {float(v):.6g} kg m^2 is {ratio:.3g} times the {d:.6g} kg m^2 of {source}: "
                       f"the measured period may be {'double' if ratio > 1 else 'half'} the true one (two swings "
                       f"counted as one, or half-swings counted as swings; the moment goes as the period squared): "
                       "check how the period was counted, or the body description")
    return out
