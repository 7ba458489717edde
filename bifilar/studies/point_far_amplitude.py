"""A sweep point's stated-amplitude sigma where the timed mode's period lies
far from its linear one (:data:`~bifilar.analysis.run_accuracy.FAR_FROM_LINEAR`),
as ``invert`` budgets it there
(:mod:`bifilar.estimation.amplitude_secant`): the amplitude's share of the
period is a secant over the amplitude's 95 % range ``A +- 2 s_A`` (``s_A``
invert's default 10 % of ``A``), not the law's first-order slope, and a
range that reaches the mode's last reachable start (pi rad for a rotation:
the wires' half turn, where the period has no bound) gives no sigma, as
invert refuses it.

Before (sepinv, session 19; docs/design.md "Lead, session 19"): audit18's
trifilar plate swept at a torsion amplitude of 2.4 rad printed a sigma of
Izz of 0.0131 kg m^2 where ``invert`` of that period at that amplitude
prints 0.0239, and at ranges past pi a sigma where invert refuses.  Points
within 20 % of linear (every default amplitude) make no run and keep their
figures bit for bit.  SI units (s, rad or m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..analysis.run_accuracy import FAR_FROM_LINEAR
from ..errors import BifilarError
from ..estimation.amplitude_secant import amplitude_range

#: the end runs' length in linear periods, times the sweep's ``--periods``:
#: a mode near its separatrix runs several linear periods a cycle (the
#: plate's torsion at 2.9 rad 2.2x), so the point's own 3 periods may hold
#: fewer than two crossings at the range's upper end
END_RUN_PERIODS = 4.0


@dataclass
class FarAmplitude:
    """The amplitude's share at a point far from linear: ``slope`` the
    effective ``A dr/dA`` whose first-order term equals the secant (None:
    no sigma, ``note`` says why), ``secant`` the period's half spread over
    the range (s) or None."""

    slope: float | None
    secant: float | None
    note: str | None


def far_amplitude(pre, k: int, r: float, T_lin: float, rel: float, st) -> FarAmplitude | None:
    """The stated-amplitude share of the point ``pre``'s mode ``k`` (its
    factor ``r`` = T(A) / T_lin at the point's amplitude ``A``, ``T_lin`` s,
    ``rel`` the amplitude's relative std) where ``|r - 1|`` exceeds
    :data:`FAR_FROM_LINEAR`; None elsewhere (no run made).  Two runs of the
    mode at ``A +- 2 rel A`` (the point's rtol, :data:`END_RUN_PERIODS`
    times its periods, health off) and the one at ``A`` give the secant
    ``max |T(A +- 2 s_A) - T(A)| / 2`` (s) and the slope ``secant / (rel
    T_lin)``; a range reaching the mode's reachable start or a failed end
    run gives no sigma (``slope`` None) with the reason."""
    if not abs(r - 1.0) > FAR_FROM_LINEAR:
        return None
    from ..analysis.batch import simulate_batch

    A = abs(float(pre.amplitude))
    label = pre.labels[k]
    rng = amplitude_range(A, rel * A, pre.scene, pre.ms.modes[k])
    unit = rng.unit
    why = f"mode '{label}' at {rng.stated()} runs {r:.3g} x its linear period"
    if rng.reaches_limit:
        return FarAmplitude(None, None, (
            f"{why}, and its 95 % range reaches {rng.hi:.4g} {unit}, at or past its last reachable start "
            f"({rng.limit:.4g} {unit}): invert refuses this amplitude (no std holds), so no sigma"))
    amps = [A] + rng.ends()
    try:
        runs = simulate_batch([pre.scene] * len(amps), mode=[label] * len(amps), amplitude=amps,
                              periods=END_RUN_PERIODS * st.periods, rtol=st.rtol, rests=[pre.rest] * len(amps),
                              modes=[pre.ms] * len(amps), errors="return", health=False)
    except BifilarError as exc:
        return FarAmplitude(None, None, f"{why}, and the runs over its 95 % range failed ({exc}): no sigma")
    bad = [a for a, run in zip(amps, runs) if run.error or not run.period or not math.isfinite(run.period)]
    if bad:
        return FarAmplitude(None, None, f"{why}, and its run at {bad[0]:.4g} {unit} failed: no sigma")
    T0 = float(runs[0].period)
    secant = rng.secant(T0, [run.period for run in runs[1:]], T_lin)
    return FarAmplitude(secant / (rel * float(T_lin)), secant, None)
