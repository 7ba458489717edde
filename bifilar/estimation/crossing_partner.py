"""The label that carries a period across an avoided crossing's gap.

When the unknown inertia component changes, two interacting modes can
exchange character (an avoided crossing: :mod:`bifilar.estimation.roots`,
"Mode identity"): the label the experimenter measured passes from one
sorted mode to the other, and the labelled period jumps over a range of
periods no physical value gives it.  A period measured inside that gap is
refused, but the other mode of the exchanging pair carries it across: near
the crossing the timed oscillation may well be that mode (the two share
their motion there).  :func:`partner_hint` names it for the refusal and,
when certain, what reading the period under its label gives.

Units: periods in s, inertia components in kg m^2 (reference body axes).
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from .fit_check import label_index


def partner_hint(scan, target: float, exact: bool = False) -> str:
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
    mode).  ``""`` when ``target`` lies in no such gap."""
    if getattr(scan, "switches", None) is None:
        scan.attainable()
    hits = [sw for sw in scan.switches
            if np.isfinite(sw[4]) and np.isfinite(sw[5]) and min(sw[4], sw[5]) < target < max(sw[4], sw[5])]
    if not hits:
        return ""
    xa, xb, k0, k1, _, _ = hits[0]
    labels = []
    for x, k in ((xb, k0), (xa, k1)):  # the modes either side of the switch
        s = scan.at(x)
        if s is None or k >= len(s.modes) or label_index(s, scan.m.label) == k:
            continue
        if s.modes[k].label not in labels:
            labels.append(s.modes[k].label)
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
    return msg
