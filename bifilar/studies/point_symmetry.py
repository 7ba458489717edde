"""A sweep or plan point's nonlinear runs that start on a symmetric subspace
of a symmetric rig (docs/design.md, "symreach, session 17").

``simulate`` checks such a start (:mod:`bifilar.analysis.symmetry_check`):
where the orbit is unstable across the subspace, the start's rounding grows
over the run until the motion leaves it, and the period (and what a point
takes from it: the amplitude bias, the swing's depth, the tensions) then
depends on the machine beyond the run's ``period_error``.  A point's runs
(the batched engine, no samples kept) are not checked that way; here the
offset's growth over each run is measured (the Floquet multiplier across
the subspace from a one-period run with samples, as ``simulate`` takes it)
and, where it reaches the check's gate, the point warns, naming the
``--periods`` below it.  Measured on the thesis plate's swing-y at 1.5 m
over 17 periods: the point's nonlinear period 3.2431368719 s on the default
BLAS kernel, 3.2431361030 s on Haswell, with a period_error of 6.0e-7 s,
and its depth 4.8689 m against 4.8598 m.

At the sweep's default 3 periods nothing is computed: the gate
(:data:`~bifilar.analysis.symmetry_check.GROWTH_GATE`, 1e6) would need a
multiplier of 100 a period, and the largest measured on the shipped
configs at any amplitude they reach is 7.9 (the plate's torsion at 1 rad;
its swing-y at 1.5 m 7.33: 394 over 3 periods)."""

from __future__ import annotations

import numpy as np

#: the runs' length (linear periods) up to which nothing is computed: the
#: gate's 1e6 over them needs a multiplier of 100 a period (module docstring)
SHORT_RUN_PERIODS = 3.0


def symmetric_run_warnings(scene, rest, ms, labels: list, amplitude: float, periods: float, rtol: float,
                           runs: list) -> None:
    """Add to the warnings of each of a point's runs ``runs`` (of the modes
    ``labels`` of ``ms``, released at ``amplitude`` for ``periods`` linear
    periods at ``rtol``) whose start is symmetric and whose offset from its
    subspace grows over the run to :data:`~bifilar.analysis.symmetry_check.GROWTH_GATE`
    one line saying so.  Nothing where ``periods`` is at most
    :data:`SHORT_RUN_PERIODS` or the rig has no symmetry; else ~2-5 ms a
    symmetric run (its first period again, with samples, and the
    multipliers)."""
    if not periods > SHORT_RUN_PERIODS:
        return
    from ..analysis.batch import run_one
    from ..analysis.symmetry_check import GROWTH_GATE, growth_over, rig_symmetries, run_multiplier

    syms = rig_symmetries(scene, rest)
    if not syms:
        return
    for lab, run in zip(labels, runs):
        m = ms.get(lab)
        if run.period is None or getattr(run, "error", None) or not m.period:
            continue
        # the run's first period again, with samples (its own period a little beyond, for the interpolants)
        short = run_one(scene, rest, m, amplitude, 1.1 * run.period / m.period + 0.1, rtol, samples_per_period=64,
                        health=False)
        if short.t is None or short.y is None:
            continue
        found = run_multiplier(scene, rest, syms, m, m.period, amplitude, short.t, short.y, run.period)
        if found is None:
            continue
        tr, rho = found
        growth = growth_over(rho, periods * m.period / run.period)
        if growth >= GROWTH_GATE:
            n = int(np.floor(np.log(GROWTH_GATE) / np.log(rho) * run.period / m.period))
            cure = (f"time at most {n} periods (--periods {n}) or release at a smaller amplitude" if n >= 2
                    else "release at a smaller amplitude")  # (--periods takes 2 at least)
            run.warnings.append(
                f"released symmetric under {tr.names}, the run stays so only up to rounding, and an offset grows by "
                f"{rho:.3g} a period ({growth:.1e} over the run): its period and what follows from it (amplitude "
                f"bias, depth, tensions) may depend on the machine's rounding beyond its period_error; `bifilar "
                f"simulate` checks it, or {cure}")
