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

from dataclasses import dataclass

import numpy as np

from ..analysis.run_accuracy import FAR_FROM_LINEAR
from ..errors import BifilarError, InputError
from .problem import Problem

#: the secant's half-width in standard uncertainties of the amplitude: the
#: 95 % range, so that the interval's upper end, where ``T(A)`` curves up,
#: is the period of the amplitude at its own 95 % end
SECANT_SIGMAS = 2.0


@dataclass(frozen=True)
class AmplitudeRange:
    """A stated amplitude's 95 % range ``A +- SECANT_SIGMAS s_A`` and the
    mode's last reachable start: ``amplitude`` ``A`` (>= 0), ``std`` ``s_A``,
    ``limit`` and ``unit`` (rad for a rotation, m for a translation,
    :func:`~bifilar.analysis.start_states.reachable_amplitude`).  The one
    reading of the secant's inputs that ``invert``
    (:func:`far_amplitude_stds`) and a sweep point
    (:func:`~bifilar.studies.point_far_amplitude.far_amplitude`) share."""

    amplitude: float
    std: float
    limit: float
    unit: str

    @property
    def hi(self) -> float:
        """The range's upper end ``A + 2 s_A`` (rad or m)."""
        return self.amplitude + SECANT_SIGMAS * self.std

    @property
    def lo(self) -> float:
        """The range's lower end ``A - 2 s_A`` (rad or m; may be <= 0)."""
        return self.amplitude - SECANT_SIGMAS * self.std

    @property
    def reaches_limit(self) -> bool:
        """Whether the upper end is at or past the mode's last reachable
        start, where the period has no bound (no std holds)."""
        return self.hi >= self.limit

    def ends(self) -> list[float]:
        """The amplitudes (rad or m) of the end runs: the upper end, and the
        lower one where it is above 0 (below, the linear period stands in
        for it: r(0) = 1)."""
        return [self.hi] + ([self.lo] if self.lo > 0 else [])

    def stated(self) -> str:
        """``A +- s_A unit``, as the messages print it."""
        return f"{self.amplitude:.4g} +- {self.std:.2g} {self.unit}"

    def secant(self, T0: float, T_ends, T_lin: float) -> float:
        """The secant (s): ``max |T(end) - T(A)| / SECANT_SIGMAS`` over the
        end runs' periods ``T_ends`` (s, in :meth:`ends`' order) and, where
        the lower end is not above 0, the linear period ``T_lin`` (s);
        ``T0`` the period at ``A`` (s)."""
        ends = [float(T) for T in T_ends] + ([] if self.lo > 0 else [float(T_lin)])
        return max(abs(T - T0) for T in ends) / SECANT_SIGMAS


def amplitude_range(amplitude: float, std: float, scene, mode) -> AmplitudeRange:
    """The :class:`AmplitudeRange` of ``mode`` of ``scene`` stated at
    ``amplitude`` (its magnitude is used) with standard uncertainty ``std``
    (rad or m, the mode's dominant coordinate)."""
    from ..analysis.start_states import reachable_amplitude

    limit, unit = reachable_amplitude(scene, mode)
    return AmplitudeRange(abs(float(amplitude)), float(std), limit, unit)


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
    from .amplitude_runs import measured_factor

    for k, m in enumerate(pb.measurements):
        law = laws[k] if laws is not None and k < len(laws) else None
        if law is None or not m.amplitude or not abs(law.factor(law.amplitude) - 1.0) > FAR_FROM_LINEAR:
            continue
        sA = float(amplitude_sigma(m, unc))
        if not sA > 0:
            continue
        key = (sA, tuple(np.asarray(p, float)))
        kept = getattr(law, "secant", None)
        if kept is not None and kept[0] == key:
            s_amp[k] = max(s_amp[k], kept[1])
            continue
        hm = pb.models[m.hanging]
        rng = amplitude_range(m.amplitude, sA, hm.scene0, hm.modes0.modes[pb.mode_index[k]])
        why = (f"mode '{m.label}' stated at {rng.stated()} runs {law.factor(law.amplitude):.3g} x its "
               "linear period")
        if rng.reaches_limit:
            raise InputError(amplitude_field(m), (
                f"{why}, and its 95 % range reaches {rng.hi:.4g} {rng.unit}, at or past the mode's last reachable "
                f"start ({rng.limit:.4g} {rng.unit}), towards which the period grows without bound: the motion "
                "there is no oscillation of that mode, so no std holds; state the amplitude more tightly (A+-SIGMA) "
                "or time the mode at a smaller amplitude"))
        T0 = float(T_lin[k]) * float(law.factor(law.amplitude))
        try:
            T_ends = [float(T_lin[k]) * measured_factor(pb, k, p, rtol, a)[0] for a in rng.ends()]
        except InputError:
            raise
        except BifilarError as exc:
            raise InputError(amplitude_field(m), f"{why}, and the run at its 95 % range's end failed ({exc}), so "
                                                 "the amplitude's share of the period cannot be given; state the "
                                                 "amplitude more tightly or time the mode at a smaller amplitude")
        secant = rng.secant(T0, T_ends, float(T_lin[k]))  # below 0 the linear period: r(0) = 1
        law.secant = (key, secant)
        s_amp[k] = max(s_amp[k], secant)
