"""A stated amplitude's share of the model period's std where the period
lies far from the linear one (:data:`~bifilar.analysis.run_accuracy.FAR_FROM_LINEAR`):
there the first-order term ``T_lin (dr/dA) s_A`` of
:func:`~bifilar.estimation.budget.stated_amplitude_period_std` no longer
holds the period's spread over the amplitude's range, because ``T(A)``
curves up towards a separatrix (the plate's torsion towards the wires' turn
at pi rad, an unstable equilibrium, where the period grows as ``-ln(pi -
A)``).  Measured (docs/design.md, "sepinv, session 19"): audit18's trifilar
plate, torsion stated at 2.8 / 3.0 rad +- 2 %, the truth drawn with it:
coverage 0.79 / 0.83 of the 95 % interval, z down to -3.2.

Here the share is a secant over the amplitude's 95 % range: two more runs
of the measurement's mode (as :func:`~bifilar.estimation.amplitude_runs.measured_factor`
makes them) at ``A +- 2 s_A``, half the larger period difference from the
run at ``A``; and an amplitude whose range reaches the mode's last
reachable start (pi rad for a rotation: the wires' half turn, twice the
longest wire for a translation) is refused on its field, since the motion
there is no oscillation of that mode and its period has no bound.  Runs
within 20 % of the linear period (every default amplitude) keep the
first-order term, bit for bit, and make no run.  SI units (s, rad or m).
"""

from __future__ import annotations

import numpy as np

from ..analysis.run_accuracy import FAR_FROM_LINEAR
from ..errors import BifilarError, InputError
from .problem import Problem

#: the secant's half-width in standard uncertainties of the amplitude: the
#: 95 % range, so that the interval's upper end, where ``T(A)`` curves up,
#: is the period of the amplitude at its own 95 % end
SECANT_SIGMAS = 2.0


def amplitude_sigma(m, unc: dict) -> float:
    """Standard uncertainty of measurement ``m``'s stated amplitude (rad or
    m): its own (``m.amplitude_std``) or ``unc["amplitude"]`` relative
    (invert's default 10 %)."""
    return m.amplitude_std if m.amplitude_std is not None else unc["amplitude"] * abs(m.amplitude)


def amplitude_field(m) -> str:
    """The option or file field that states measurement ``m``'s amplitude."""
    return "--amplitude" if m.field.startswith("--") else m.field.rsplit(".", 1)[0] + ".amplitude"


def far_amplitude_stds(pb: Problem, p, T_lin, laws, unc: dict, s_amp: np.ndarray, rtol: float = 1e-10) -> None:
    """Replace in ``s_amp`` (K,) (s, the first-order stds of each model
    period from its stated amplitude) those of measurements whose amplitude
    factor at the estimate ``p`` lies more than :data:`FAR_FROM_LINEAR`
    from 1 (``laws[k]``, its ``factor`` at the amplitude: the run's) by the
    secant over ``A +- SECANT_SIGMAS s_A``: ``max(first order, max|T(A +-
    2 s_A) - T(A)| / 2)``, the end runs made at ``rtol`` and checked as
    the measurement's own (``T_lin`` (K,) s, the linear periods at ``p``).
    The result is kept on the law (a later budget at the same estimate
    makes no run).  Raises :class:`InputError` on the amplitude's field
    where ``A + 2 s_A`` reaches the mode's last reachable start or an end
    run cannot be made."""
    from ..analysis.start_states import reachable_amplitude
    from .amplitude_runs import measured_factor

    for k, m in enumerate(pb.measurements):
        law = laws[k] if laws is not None and k < len(laws) else None
        if law is None or not m.amplitude or not abs(law.factor(law.amplitude) - 1.0) > FAR_FROM_LINEAR:
            continue
        A, sA = abs(float(m.amplitude)), float(amplitude_sigma(m, unc))
        if not sA > 0:
            continue
        key = (sA, tuple(np.asarray(p, float)))
        kept = getattr(law, "secant", None)
        if kept is not None and kept[0] == key:
            s_amp[k] = max(s_amp[k], kept[1])
            continue
        hm = pb.models[m.hanging]
        limit, unit = reachable_amplitude(hm.scene0, hm.modes0.modes[pb.mode_index[k]])
        hi, lo = A + SECANT_SIGMAS * sA, A - SECANT_SIGMAS * sA
        why = (f"mode '{m.label}' stated at {A:.4g} +- {sA:.2g} {unit} runs {law.factor(law.amplitude):.3g} x its "
               f"linear period")
        if hi >= limit:
            raise InputError(amplitude_field(m), (
                f"{why}, and its 95 % range reaches {hi:.4g} {unit}, at or past the mode's last reachable start "
                f"({limit:.4g} {unit}), towards which the period grows without bound: the motion there is no "
                "oscillation of that mode, so no std holds; state the amplitude more tightly (A+-SIGMA) or time "
                "the mode at a smaller amplitude"))
        T0 = float(T_lin[k]) * float(law.factor(law.amplitude))
        ends = [hi] + ([lo] if lo > 0 else [])
        try:
            T_ends = [float(T_lin[k]) * measured_factor(pb, k, p, rtol, a)[0] for a in ends]
        except InputError:
            raise
        except BifilarError as exc:
            raise InputError(amplitude_field(m), f"{why}, and the run at its 95 % range's end failed ({exc}), so "
                                                 "the amplitude's share of the period cannot be given; state the "
                                                 "amplitude more tightly or time the mode at a smaller amplitude")
        if lo <= 0:
            T_ends.append(float(T_lin[k]))  # r(0) = 1: the linear period
        secant = max(abs(T - T0) for T in T_ends) / SECANT_SIGMAS
        law.secant = (key, secant)
        s_amp[k] = max(s_amp[k], secant)
