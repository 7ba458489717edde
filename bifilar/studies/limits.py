"""Where a component's estimate may leave what a real body can have: its
physical interval (positive definite, the triangle inequality) and the
fraction of experiments whose period no physical value reproduces, for a
normal estimate with the predicted sigma; and the scale a component's
relative sigma is taken against.  kg m^2.  Split from
:mod:`bifilar.studies.point`; used by the point, its stated-amplitude
sigma (:mod:`bifilar.studies.point_amplitude`), the multi-hanging planner
and the remedies.
"""

from __future__ import annotations

import math

import numpy as np

from .settings import _IDX


#: a component whose estimate falls outside its physical interval in at least this fraction of experiments
#: gets a ``physical_limit`` warning (see :func:`physical_limits`)
UNPHYSICAL_WARN = 0.01


def physical_limits(inertia, comp: str, budget, interval=None) -> dict:
    """Where the estimate of ``comp`` may fall outside what a real body can
    have: ``physical_interval`` [lo, hi] (kg m^2; positive definite and the
    triangle inequality with the other components as given,
    :func:`bifilar.estimation.problem.admissible_interval`), and for a
    normal estimate about the config's value with the predicted sigma
    ``p_unphysical``, the fraction of experiments whose period no physical
    value reproduces (``invert`` then gives the limit, when the period
    misfit there is within :data:`~bifilar.estimation.fit_check.EDGE_Z`
    sigmas of the period with the measured inputs' uncertainty counted,
    i.e. of the whole sigma, else refuses: ``p_refused``), and
    ``physical_limit``, a warning
    when ``p_unphysical`` >= :data:`UNPHYSICAL_WARN`.  A flat body (the
    trifilar table, the thesis plate: Izz = Ixx + Iyy) sits on the limit,
    so about half of its Izz estimates do: the closed-loop check found 13 %
    of the trifilar's refused and most of the rest clamped, under a sigma
    that promised a symmetric spread (docs/design.md).  ``interval``: the
    ``physical_interval`` if already computed (the same for every budget of
    the component)."""
    from ..estimation.problem import admissible_interval
    from ..estimation.fit_check import EDGE_Z
    from ..scene import TRIANGLE_SLACK

    lo, hi = admissible_interval(inertia, comp) if interval is None else interval
    out: dict = {"physical_interval": [lo, hi], "p_unphysical": None, "p_refused": None}
    sd = float(budget.value_sigma)
    if not (math.isfinite(sd) and sd > 0):
        return out
    I = float(inertia[_IDX[comp]])
    # the misfit invert accepts at the edge, kg m^2: EDGE_Z sigmas of the period with the measured inputs'
    # (and a stated amplitude's) uncertainty counted (invert._fit_check -> fit_check.input_fit_check), i.e.
    # EDGE_Z of the whole sigma.  EDGE_Z of the timing's part alone predicted 41 % refused for a thin rod's
    # Izz (timing 10 % of its variance) where 6 of 150 experiments were, 10 % for the KTH trifilar's where 0 of 80
    edge = EDGE_Z * sd

    def beyond(d):  # P(estimate more than d beyond either limit)
        return 0.5 * (math.erfc((I - lo + d) / (sd * math.sqrt(2))) + math.erfc((hi - I + d) / (sd * math.sqrt(2))))

    out["p_unphysical"], out["p_refused"] = beyond(0.0), beyond(edge)
    if out["p_unphysical"] >= UNPHYSICAL_WARN:
        near = lo if I - lo < hi - I else hi
        out["physical_limit"] = (
            f"the config's value {I:.6g} kg m^2 lies {abs(I - near) / sd:.2g} sigma from its physical limit "
            f"{near:.6g} kg m^2 (positive definite, triangle inequality, the other components as given"
            + ("; a flat body sits on it" if abs(I - near) <= 2 * TRIANGLE_SLACK * float(np.max(np.linalg.eigvalsh(inertia)))
               else "")
            + f"), so about {100 * out['p_unphysical']:.2g} % of experiments time a period no "
            f"physical {comp} reproduces: invert gives the limit there or, for about "
            f"{100 * out['p_refused']:.2g} %, refuses; the sigma describes the spread only away from the limit")
    return out


def component_scale(inertia, comp: str) -> float:
    """The scale a component's uncertainty is relative to (kg m^2): ``|I_ii|``
    for a moment; ``sqrt(I_ii I_jj)`` for a product ``I_ij`` (which may be
    zero, and whose size is bounded by that geometric mean)."""
    i, j = _IDX[comp]
    if i == j:
        return abs(float(inertia[i, i]))
    return float(np.sqrt(abs(inertia[i, i] * inertia[j, j])))
