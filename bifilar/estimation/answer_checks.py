"""Checks of `invert`'s nonlinear answer against its own inputs.

Run after the nonlinear rung (:func:`~bifilar.estimation.invert.invert`):
a recording whose amplitude no start of its mode reaches, or whose own
period change between its halves the stated (or fitted) amplitude
contradicts, is refused (a unit slip: degrees, deg/s or mm read as rad or
m); amplitude runs that are not a regular motion, and a period that need
not be monotonic in the one unknown near the estimate, are warned.  Units:
periods in s, amplitudes in the mode's dominant coordinate (rad or m)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .problem import Problem
from .solve import GAIN_RANGE, factor_gains


#: a record contradicts its amplitude when the model's period change between its halves differs from the
#: record's own by more than this many of the halves' stds ...
AMPLITUDE_CONTRADICTION_Z = 5.0
#: ... and is more than this many times the record's change and its std together (a unit slip is 57x in a
#: degree's amplitude, ~3300x in the factor; a drone's linear record fitted at its true 0.026 rad misses the
#: model's 2.5e-5 s by 7 of its stds but only 2.6x its change and std)
AMPLITUDE_CONTRADICTION_RATIO = 20.0


def _half_amplitudes(fit) -> tuple[float, float] | None:
    """The envelope of ``fit`` (signal units) at the middles of the fit
    window's halves, where the split check's two periods refer; None for a
    fit without a decay rate."""
    d = fit.damping or {}
    sg = d.get("sigma")
    if sg is None or not np.isfinite(sg) or not np.isfinite(fit.amplitude):
        return None
    kap = d.get("kappa") or 0.0
    T_rec = float(fit.t1 - fit.t0)

    def env(tau):
        E = tau if abs(sg * tau) < 1e-12 else -math.expm1(-sg * tau) / sg
        return abs(fit.amplitude) * math.exp(-sg * tau) / (1.0 + kap * E)

    return env(0.25 * T_rec), env(0.75 * T_rec)


def refuse_unreachable_record_amplitudes(pb: Problem) -> None:
    """Raise InputError naming the recording where a recording's amplitude
    (the fit's, with ``--signal-quantity``, or as stated) is beyond any
    reachable start of its mode (:func:`~bifilar.analysis.simulate.reachable_amplitude`:
    pi rad, twice the longest wire).  A rate record in deg/s, or an angle
    record in degrees above ~3 degrees, read as rad(/s) gives such an
    amplitude (the drone's torsion at 5 degrees: 4.05 "rad"); the start
    check refused it as ``--amplitude`` although no amplitude was given,
    so the one line named an option the user never typed and not the
    likely unit slip."""
    from ..analysis.simulate import reachable_amplitude

    for k, m in enumerate(pb.measurements):
        if m.source != "signal" or not m.amplitude:
            continue
        hm = pb.models[m.hanging]
        limit, unit = reachable_amplitude(hm.scene0, hm.modes0.modes[pb.mode_index[k]])
        if abs(m.amplitude) > limit:
            src = "as stated" if (m.details.get("amplitude_source") or "").startswith("given") else "from its fit"
            raise InputError(m.field, f"the recording of '{m.label}' gives an amplitude of {abs(m.amplitude):.4g} "
                                      f"{unit} ({src}), beyond any reachable start of the mode (<= {limit:.4g} "
                                      f"{unit}): is the signal in degrees, deg/s or mm? give --signal-scale "
                                      "(e.g. 0.0174533 for degrees)")


def refuse_amplitude_the_record_contradicts(pb: Problem, est) -> None:
    """Raise InputError on a recording whose amplitude (stated, or the fit's
    with ``--signal-quantity``) the record's own period change contradicts.

    A pendulum's period follows its amplitude, so as a record decays its
    halves' periods differ by ``T_lin (r(A_1) - r(A_2))`` (the mode's
    amplitude law at the estimate, ``est.laws``; ``A_1``, ``A_2`` the
    envelope at the halves' middles in the model's unit).  A record in
    degrees read as radians (``--signal-quantity angle`` without
    ``--signal-scale``) puts the amplitude 57 times too high and the
    amplitude factor (~A^2) 3300 times: the quadcopter's torsion released
    at 1.7 degrees gave Izz 0.0171 +- 0.0009 kg m^2 for 0.022, exit 0.
    Refused when the model's change exceeds the record's (the viscous fit's
    halves, before any amplitude law) by more than
    :data:`AMPLITUDE_CONTRADICTION_Z` of the halves' stds and
    :data:`AMPLITUDE_CONTRADICTION_RATIO` times the record's change plus
    its std: the record shows the period far steadier than its amplitude
    allows.  A second mode the release started (``m.secondary``) may move
    the halves' difference by up to its whole period shift (it decays with
    the record, the model's does not), which both tests allow.  An
    amplitude too small, or a record that also drifts, is not caught."""
    T_lin = None
    for k, m in enumerate(pb.measurements):
        law = est.laws[k] if k < len(est.laws) else None
        fit = m.fit
        if law is None or fit is None or not m.amplitude or not (fit.amplitude_period > 0):
            continue
        al = fit.amplitude_law or {}
        halves = (al.get("without_law") or {}).get("half_periods") if al.get("used") else fit.half_periods
        amps = _half_amplitudes(fit)
        if not halves or len(halves) != 2 or amps is None:
            continue
        (T1, s1), (T2, s2) = halves
        scale = abs(m.amplitude) / fit.amplitude_period  # signal unit -> the mode's (rad or m)
        A1, A2 = amps[0] * scale, amps[1] * scale
        if T_lin is None:
            T_lin = pb.linear_periods(est.p)
        pred = float(T_lin[k] * (law.factor(A1) - law.factor(A2)))
        seen, s = float(T1 - T2), math.hypot(s1, s2)
        # a second mode the release started (m.secondary) shifts the period too, and the record's decays with
        # it: its part of the halves' difference is anything up to its whole shift at its start amplitude (the
        # model's shift is at the amplitude the period refers to, ``decay`` times it; the shift ~ a^2) (a damped
        # swing's decay cancelled the torsion's own chirp: 5.96e-4 s predicted, 1.6e-5 s seen, an honest
        # record refused as a unit slip; docs/design.md, session 13)
        sec = getattr(m, "secondary", None)
        free = abs(sec.shift) / sec.decay ** 2 if sec is not None and sec.shift is not None and \
            math.isfinite(sec.shift) else 0.0
        if (abs(pred - seen) - free > AMPLITUDE_CONTRADICTION_Z * s
                and abs(pred) > AMPLITUDE_CONTRADICTION_RATIO * (abs(seen) + free + s)):
            raise InputError(m.field, f"the amplitude of '{m.label}' ({abs(m.amplitude):.4g} in the model's unit, "
                                      f"rad or m) contradicts the record: decaying from {A1:.4g} to {A2:.4g} it "
                                      f"would change the period by {pred:.3g} s between the record's halves, which "
                                      f"differ by {seen:.3g} +- {s:.2g} s; is the signal in degrees or mm (give "
                                      "--signal-scale, e.g. 0.0174533 for degrees) or the amplitude stated in "
                                      "another unit?")


def irregular_warnings(pb: Problem, est) -> list[str]:
    """One warning per measurement whose amplitude runs at the nonlinear
    estimate ``est`` are not a regular motion (``law.irregular`` > 0, s: below
    a tenth of the period's std, else the runs were refused)."""
    out = []
    for k, law in enumerate(est.laws):
        if law is None or not law.irregular > 0:
            continue
        m, sim = pb.measurements[k], est.sims[k]
        spread = f"{sim.period_std:.1g} s" if sim is not None and sim.period_std is not None else "widely"
        out.append(f"mode '{m.label}' at amplitude {m.amplitude:g} over {m.cycles:g} cycles is not a regular motion: "
                   f"its single-cycle periods spread by {spread} and a second run from the same start differs by up "
                   f"to {law.irregular:.1g} s (below a tenth of the period's std {m.std:.1g} s); the nonlinear "
                   f"estimate's std includes it (the budget's integration term), and other starts as close may move it "
                   "further: time fewer cycles or release at a smaller amplitude to make it regular")
    return out


def monotonic_warnings(pb: Problem, est) -> list[str]:
    """Warnings where the nonlinear model's period need not be monotonic in
    the one unknown near the estimate ``est`` (its gain ``g``,
    :func:`~bifilar.estimation.solve.factor_gains`, outside
    :data:`~bifilar.estimation.solve.GAIN_RANGE`), and the other values the
    scan of the full model found (``est.other_roots``) where the fixed point
    did not settle."""
    out = []
    name = pb.unknowns[0] if len(pb.unknowns) == 1 else None
    for k, g in enumerate(factor_gains(pb, est)):
        if g is None or GAIN_RANGE[0] < g < GAIN_RANGE[1]:
            continue
        m = pb.measurements[k]
        how = ("falls as it grows" if g <= 0 else "barely follows it" if g < GAIN_RANGE[0]
               else f"changes {g:.2g} times as fast as the linear model's")
        out.append(f"mode '{m.label}' at amplitude {m.amplitude:g}: at the estimate the nonlinear model's period "
                   f"{how} in {name} (d(T_lin r)/d{name} = {g:.2g} r dT_lin/d{name}: the amplitude factor moves "
                   "with the body, near an internal resonance where the mode beats with another), so that period "
                   f"need not be monotonic in {name} and other values of {name} may reproduce the measured one; "
                   "release at a smaller amplitude")
    if est.other_roots:
        vals = ", ".join(f"{x:.6g}" for x in est.other_roots)
        out.append(f"the nonlinear model reproduces the measured period also at {name} = {vals} (found between the "
                   "runs of the fixed point T = T_lin r, which did not settle; there may be more): the period cannot "
                   "tell them apart at this amplitude; release at a smaller amplitude")
    return out


#: the mode that turns a hanging's body about each reference axis (:mod:`~bifilar.analysis.modes`' labels)
TURNING_MODE = {"Ixx": "roll", "Iyy": "pitch", "Izz": "torsion"}


def unmeasured_warning(pb: Problem, std) -> str | None:
    """The warning of an answer whose inertia unknowns the periods do not
    measure: those whose std (kg m^2, the answer's whole budget) exceeds
    the config's largest principal moment (:meth:`~bifilar.estimation.
    problem.Problem.scales`), so that their 95 % intervals are the physical
    limits rather than a measurement (audit29's b06: a trifilar's torsion and
    two swings for Ixx, Iyy, Izz, stds 23, 16 and 0.77 kg m^2 for a largest
    moment of 0.52).  None where every inertia std is within that scale or
    not finite (a std that cannot be given says why elsewhere).  CoM
    unknowns are not judged here (their scale, 1 % of the longest wire, is
    a resolution, not a physical range)."""
    sc = pb.scales()
    loose = [(n, float(s), float(c)) for n, s, c in zip(pb.unknowns, np.asarray(std, float), sc)
             if not n.startswith("com.") and np.isfinite(s) and s > c]
    if not loose:
        return None
    names = ", ".join(f"{n} (std {s:.3g} kg m^2)" for n, s, _ in loose)
    timed = {m.label for m in pb.measurements}
    turn = ", ".join(f"{TURNING_MODE[n]} for {n}" for n, _, _ in loose
                    if n in TURNING_MODE and TURNING_MODE[n] not in timed)
    turn = f" ({turn})" if turn else ""
    return (f"the periods do not measure {names}: each std exceeds the config's largest principal moment "
            f"({loose[0][2]:.3g} kg m^2), so the 95 % interval is the physical range, not a measurement; measure "
            f"them and solve for fewer components, or time modes that turn the body about their axes{turn} or add "
            f"a hanging turned so that such a mode moves them")
