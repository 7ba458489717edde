"""The label that carries a period across an avoided crossing's gap.

When the unknown inertia component changes, two interacting modes can
exchange character (an avoided crossing: :mod:`bifilar.estimation.roots`,
"Mode identity"): the label the experimenter measured passes from one
sorted mode to the other, and the labelled period jumps over a range of
periods no physical value gives it.  A period measured inside that gap is
refused, but the other mode of the exchanging pair carries it across: near
the crossing the timed oscillation may well be that mode (the two share
their motion there).  :func:`partner_hint` names it for the refusal and,
when certain, what reading the period under its label gives: without an
amplitude factor the root of that label's linear period (what ``invert``
answers then), with a stated amplitude ``invert``'s own answer to that
reading, run for the refusal (:func:`amplitude_reading`: the amplitude
factor is the partner mode's, so the timed label's target does not carry
over; docs/design.md, "partner28, session 28").

Units: periods in s, inertia components in kg m^2 (reference body axes).
"""

from __future__ import annotations

import copy
import dataclasses
from contextvars import ContextVar

import numpy as np

from ..errors import BifilarError
from .fit_check import label_index

#: True inside a partner reading's own ``invert`` (:func:`amplitude_reading`): its refusal, if any, names
#: the partner label but runs no reading of its own (the partner's partner is the label refused)
_IN_READING: ContextVar[bool] = ContextVar("bifilar_partner_reading", default=False)


def amplitude_reading(ms, run):
    """The partner reading of a refused one-period measurement set ``ms``
    (:class:`~bifilar.estimation.measurements.MeasurementSet`, its period
    with a stated amplitude) for :func:`partner_hint`: a callable
    ``reading(label)`` giving ``(values, None)`` -- the unknown's values
    (kg m^2; the answer first, then any further roots of an ambiguous
    answer) of ``run`` (``invert`` with the refused call's options) on a
    copy of ``ms`` whose measurement carries ``label``, amplitude, period,
    std, cycles and field unchanged -- or ``(None, reason)`` when that
    reading is refused or fails.  The same code as ``invert --period
    LABEL=...`` with the same amplitude runs, so the value named is the
    one that command answers, fit check included.  None inside a reading
    (no reading of a reading)."""
    if _IN_READING.get():
        return None

    def reading(label: str):
        m = ms.measurements[0]
        other = dataclasses.replace(m, label=label, details=copy.deepcopy(m.details), secondary=None, hidden=[])
        token = _IN_READING.set(True)
        try:
            res = run(dataclasses.replace(ms, measurements=[other]))
        except BifilarError as exc:
            return None, str(exc)
        finally:
            _IN_READING.reset(token)
        name = res.names[0]
        return [float(r["inertia"][name]["value"]) for r in res.roots], None

    return reading


def partner_hint(scan, target: float, exact: bool = False, reading=None) -> str:
    """The refusal's hint (``"; ..."``) for a ``target`` period (s) that
    the labelled mode's period jumps over where the label passes to another
    mode: ``scan`` is the refusing
    :class:`~bifilar.estimation.roots.ScalarScan`, whose
    :meth:`~bifilar.estimation.roots.ScalarScan.attainable` records each
    switch (the unknown's values either side, the sorted modes carrying
    the label there, their periods).  The candidates are the labels of the
    other mode of the exchanging pair: the one the sorted mode that
    carried the measured label takes just past the switch, and the one the
    mode it passes to had just before it.  Each is tried as the measured
    label (:meth:`~bifilar.estimation.roots.ScalarScan.roots`: the same
    grid and refinement, the mode identity decided at the root, so a root
    named is one ``invert`` finds); when any has a root only those are
    named, with their values (kg m^2) when ``exact`` (the target is the
    measured period itself: no amplitude factor, which depends on the
    mode).  Otherwise (a stated amplitude: ``target`` is the period over the
    timed label's amplitude factor) the first label named gets the value
    ``reading`` (:func:`amplitude_reading`) answers for it, or the reason
    it refuses; no value without ``reading``.  ``""`` when ``target`` lies
    in no such gap."""
    if getattr(scan, "switches", None) is None:
        scan.attainable()
    hits = [sw for sw in scan.switches
            if np.isfinite(sw[4]) and np.isfinite(sw[5]) and min(sw[4], sw[5]) < target < max(sw[4], sw[5])]
    if not hits:
        return ""
    xa, xb, k0, k1, _, _ = hits[0]
    labels, side = [], {}
    for x, k in ((xb, k0), (xa, k1)):  # the modes either side of the switch
        s = scan.at(x)
        if s is None or k >= len(s.modes) or label_index(s, scan.m.label) == k:
            continue
        if s.modes[k].label not in labels:
            labels.append(s.modes[k].label)
            side[s.modes[k].label] = s  # the modes where the candidate carries its label
    if not labels:
        return ""
    found = {}
    for lab in labels:
        other = copy.copy(scan)
        other.m = dataclasses.replace(scan.m, label=lab)
        found[lab] = other.roots(target)
    labels = [x for x in labels if found[x]] or labels  # the labels whose period passes through it, if any
    lab = labels[0]
    names = " or ".join(f"'{x}'" for x in labels)
    give = (f"--period {lab}={scan.m.period:.9g}+-{scan.m.std:.3g}" if scan.m.field == "--period"
            else f"{scan.m.field} under the label '{lab}'")
    msg = (f"; {target:.9g} s lies in the gap where {scan.name} passes {0.5 * (xa + xb):.6g} kg m^2: there "
           f"the mode labelled {names} carries it across (the two modes exchange character near here), so if "
           f"the timed oscillation may be that mode, the period can be given under its label ({give})")
    xs = found[lab]
    if exact and xs:
        vals = ", ".join(f"{x:.6g}" for x in xs)
        msg += (f", which gives {scan.name} = {vals} kg m^2 (the mode labelled '{lab}' there has period "
                f"{target:.9g} s)")
    elif not exact and reading is not None:
        msg += _reading_clause(scan, lab, reading(lab), side[lab])
    return msg


def _reading_clause(scan, lab: str, got, s) -> str:
    """The partner reading's value (kg m^2) at the stated amplitude, or its
    refusal's first clause, for :func:`partner_hint`.  ``s``: the modes on
    the side of the switch where ``lab`` was found; where the largest
    component of the two modes' normalised shapes (the amplitude's
    coordinate) differs there, the same number is another motion, and the
    clause says so."""
    from ..analysis.modes import COMPONENTS

    vals, why = got
    amp = f"{scan.m.amplitude:.6g}"
    if vals:
        out = (f", which at the same amplitude ({amp}) gives {scan.name} = {', '.join(f'{x:.6g}' for x in vals)} "
               f"kg m^2 (invert's answer to that reading, run here with the amplitude factor of the mode labelled "
               f"'{lab}'")
    else:
        head = " ".join(why.split(";")[0].split())
        out = f", which at the same amplitude ({amp}) is refused as well ({head[:240]}"
    i, j = (label_index(s, x) if s is not None else None for x in (scan.m.label, lab))
    if i is not None and j is not None and s.modes[i].dominant != s.modes[j].dominant:
        a, b = COMPONENTS[s.modes[i].dominant], COMPONENTS[s.modes[j].dominant]
        out += (f"; an amplitude is A times the mode's normalised shape, whose largest component is {a} for "
                f"'{scan.m.label}' and {b} for '{lab}' here: an amplitude read in {a} is not that mode's A")
    return out + ")"
