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
reading, run for the refusal (:func:`partner_reading`: the amplitude
factor is the partner mode's, so the timed label's target does not carry
over).  With several unknowns or periods, :func:`surface_hint` names such
a gap on a line through the best fit and that reading's answer
(docs/design.md, "partner28, session 28"); :func:`across_gap` finds, in an
answer, that it *is* such a reading given directly, whose intervals hold
only if the labels are right (docs/design.md, "cross29, session 29").

Units: periods in s, inertia components in kg m^2 (reference body axes).
"""

from __future__ import annotations

import copy
import dataclasses
from contextvars import ContextVar

import numpy as np

from ..errors import BifilarError
from .fit_check import label_index

#: True inside a partner reading's own ``invert`` (:func:`partner_reading`): its refusal, if any, names
#: the partner label but runs no reading of its own (the partner's partner is the label refused)
_IN_READING: ContextVar[bool] = ContextVar("bifilar_partner_reading", default=False)

#: what several unknowns' partner reading cannot promise (docs/design.md, "cross28, session 28"): its
#: intervals are a budget at the inputs as written, and the truth may lie across the reading's jump (a
#: conditional: cross29 measured such readings covering off the physical set's edge, not on it)
ACROSS = ("; its 95 % intervals hold only if the labels are right: if the inputs' errors moved the crossing past "
          "the timed oscillation, the truth lies across the jump the answer makes where the label passes, which a "
          "budget at the inputs as written does not hold")


def partner_reading(ms, run):
    """The partner reading of a refused measurement set ``ms``
    (:class:`~bifilar.estimation.measurements.MeasurementSet`) for
    :func:`partner_hint` and :func:`surface_hint`: a callable
    ``reading(relabel)`` giving ``(result, None)`` -- the
    :class:`~bifilar.estimation.inversion_result.InversionResult` of ``run``
    (``invert`` with the refused call's options) on a copy of ``ms`` whose
    measurements ``k`` carry the labels ``relabel[k]`` ({index into
    ``ms.measurements``: label}), amplitude, period, std, cycles and field
    unchanged -- or ``(None, reason)`` when that reading is refused or
    fails.  The same code as ``invert --period LABEL=...`` with the same
    amplitude runs, so a value named is the one that command answers, fit
    check included; a numerical failure of that run (a singular matrix
    escaping it) is a reason too, so that the refusal stands as a refusal.
    None inside a reading (no reading of a reading)."""
    if _IN_READING.get():
        return None

    def reading(relabel: dict):
        ms2 = [dataclasses.replace(m, label=relabel[k], details=copy.deepcopy(m.details), secondary=None, hidden=[])
               if k in relabel else m for k, m in enumerate(ms.measurements)]
        token = _IN_READING.set(True)
        try:
            return run(dataclasses.replace(ms, measurements=ms2)), None
        except BifilarError as exc:
            return None, str(exc)
        except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:  # the refusal stands, said so
            return None, f"its solve failed: {type(exc).__name__}: {exc}"
        finally:
            _IN_READING.reset(token)

    return reading


@dataclasses.dataclass
class _Gap:
    """A label switch of a :class:`~bifilar.estimation.roots.ScalarScan`
    whose period jump holds a target: the unknown's values either side
    ``xa``, ``xb`` (kg m^2), the labelled periods there ``Ta``, ``Tb`` (s),
    the candidate partner labels (those with a root first), their roots
    along the scan (kg m^2) and the modes where each carries its label."""

    xa: float
    xb: float
    Ta: float
    Tb: float
    labels: list
    found: dict
    side: dict

    @property
    def lab(self) -> str:
        return self.labels[0]


def _gap_partner(scan, target: float) -> _Gap | None:
    """The switch of ``scan`` whose period jump holds ``target`` (s) and
    the other mode of its exchanging pair (:func:`partner_hint`), or None."""
    if getattr(scan, "switches", None) is None:
        scan.attainable()
    hits = [sw for sw in scan.switches
            if np.isfinite(sw[4]) and np.isfinite(sw[5]) and min(sw[4], sw[5]) < target < max(sw[4], sw[5])]
    if not hits:
        return None
    xa, xb, k0, k1, Ta, Tb = hits[0]
    labels, side = [], {}
    for x, k in ((xb, k0), (xa, k1)):  # the modes either side of the switch
        s = scan.at(x)
        if s is None or k >= len(s.modes) or label_index(s, scan.m.label) == k:
            continue
        if s.modes[k].label not in labels:
            labels.append(s.modes[k].label)
            side[s.modes[k].label] = s  # the modes where the candidate carries its label
    if not labels:
        return None
    found = {}
    for lab in labels:
        other = copy.copy(scan)
        other.m = dataclasses.replace(scan.m, label=lab)
        found[lab] = other.roots(target)
    labels = [x for x in labels if found[x]] or labels  # the labels whose period passes through it, if any
    return _Gap(xa, xb, Ta, Tb, labels, found, side)


def _give(m, lab: str) -> str:
    """How to give measurement ``m``'s period under the label ``lab``."""
    return (f"--period {lab}={m.period:.9g}+-{m.std:.3g}" if m.field == "--period"
            else f"{m.field} under the label '{lab}'")


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
    ``reading`` (:func:`partner_reading`) answers for it, or the reason
    it refuses; no value without ``reading``.  ``""`` when ``target`` lies
    in no such gap."""
    g = _gap_partner(scan, target)
    if g is None:
        return ""
    lab = g.lab
    names = " or ".join(f"'{x}'" for x in g.labels)
    msg = (f"; {target:.9g} s lies in the gap where {scan.name} passes {0.5 * (g.xa + g.xb):.6g} kg m^2: there "
           f"the mode labelled {names} carries it across (the two modes exchange character near here), so if "
           f"the timed oscillation may be that mode, the period can be given under its label ({_give(scan.m, lab)})")
    xs = g.found[lab]
    if exact and xs:
        vals = ", ".join(f"{x:.6g}" for x in xs)
        msg += (f", which gives {scan.name} = {vals} kg m^2 (the mode labelled '{lab}' there has period "
                f"{target:.9g} s)")
    elif not exact and reading is not None:
        msg += _reading_clause(scan, lab, reading({0: lab}), g.side[lab])
    return msg


def _reading_clause(scan, lab: str, got, s) -> str:
    """The partner reading's value (kg m^2) at the stated amplitude, or its
    refusal's first clause, for :func:`partner_hint`.  ``s``: the modes on
    the side of the switch where ``lab`` was found; where the largest
    component of the two modes' normalised shapes (the amplitude's
    coordinate) differs there, the same number is another motion, and the
    clause says so (:func:`_amplitude_caution`)."""
    res, why = got
    amp = f"{scan.m.amplitude:.6g}"
    if res is not None:
        vals = ", ".join(f"{r['inertia'][scan.name]['value']:.6g}" for r in res.roots)
        out = (f", which at the same amplitude ({amp}) gives {scan.name} = {vals} kg m^2 (invert's answer to that "
               f"reading, run here with the amplitude factor of the mode labelled '{lab}'")
    else:
        out = f", which at the same amplitude ({amp}) is refused as well ({_head(why)}"
    return out + _amplitude_caution(s, scan.m.label, lab) + ")"


def _amplitude_caution(s, timed: str, lab: str) -> str:
    """Where the modes ``s`` (a ModeSet) give the labels ``timed`` and
    ``lab`` normalised shapes whose largest components (the coordinate an
    amplitude A is stated in) differ, the clause saying the same A is
    another motion under ``lab``; else ``""``."""
    from ..analysis.modes import COMPONENTS

    i, j = (label_index(s, x) if s is not None else None for x in (timed, lab))
    if i is None or j is None or s.modes[i].dominant == s.modes[j].dominant:
        return ""
    a, b = COMPONENTS[s.modes[i].dominant], COMPONENTS[s.modes[j].dominant]
    return (f"; an amplitude is A times the mode's normalised shape, whose largest component is {a} for "
            f"'{timed}' and {b} for '{lab}' here: an amplitude read in {a} is not that mode's A")


def _head(why: str) -> str:
    """A refusal's first clause, on one line, at most 240 characters."""
    return " ".join(why.split(";")[0].split())[:240]


def surface_hint(pb, p, z, targets, reading=None) -> str:
    """The hint (``"; ..."``) of a refusal of several unknowns or periods
    (:func:`~bifilar.estimation.roots.find_roots`) whose best admissible
    fit ``p`` (the unknowns, SI) leaves a measured period in an avoided
    crossing's gap.  With several unknowns the gap is a surface and the
    label is re-decided at every iterate, so the claim made is the one that
    can be checked: along one inertia unknown, the others held at the best
    fit, the labelled period jumps over the measurement's ``target`` (s;
    ``targets[k]``, the period over its amplitude factor where one is
    stated) -- a :class:`~bifilar.estimation.roots.ScalarScan` of a problem
    built at ``p`` with that measurement alone -- no value on that line
    gives the label the period (the one-unknown refusal's condition), and
    the period lies in the jump at one of its label switches.  The
    measurement tried is the one the refusal names, the largest normalised
    residual ``z``; of the unknowns' lines with such a gap, one whose
    partner label has a root on it is named first, then the switch nearest
    the best fit (relative to the line's admissible interval).  Then the reading (:func:`partner_reading`)
    with that measurement relabelled (and, where the partner label is timed
    too in the same hanging, that one given the refused label: the two
    told apart the other way) names ``invert``'s answer, or its refusal's
    first clause; without ``reading`` (inside a reading) only the exchange
    and how to give the period.  A gap whose partner has no root on the
    line is named as an exchange of character only.  ``""`` when the
    unknowns include a CoM coordinate (the rest pose moves with it: not
    scanned) or no period lies in such a gap."""
    from .problem import _IDX

    if any(n not in _IDX for n in pb.unknowns):
        return ""
    z = np.asarray(z, float)
    if not np.any(np.isfinite(z)):
        return ""
    k = int(np.nanargmax(np.where(np.isfinite(z), np.abs(z), -1.0)))  # the measurement the refusal names
    m, target = pb.measurements[k], float(targets[k])
    gaps = [(not g.found[g.lab], abs(0.5 * (g.xa + g.xb) - p[i]) / (b - a), i, name, g)
            for i, name, a, b, g in _line_gaps(pb, p, m, target)]
    if not gaps:  # a partner with a root on its line first, then the switch nearest the best fit
        return ""
    _, _, _, name, g = min(gaps, key=lambda t: t[:3])
    return _surface_message(pb, p, k, name, g, target, reading)


def _line_gaps(pb, p, m, target: float):
    """For measurement ``m`` (its label as given) of ``pb`` at the unknowns
    ``p`` (SI; inertia components only): each line along one inertia
    unknown, the others held at ``p``, on which no value gives ``m``'s
    label the period ``target`` (s) and ``target`` lies in the jump at one
    of its label switches (:func:`_gap_partner`): ``(i, name, a, b, gap)``
    with the line's admissible ends ``a``, ``b`` (kg m^2).  A line whose
    scan cannot be built is skipped.  Shared by :func:`surface_hint` (a
    refusal's best fit) and :func:`across_gap` (an answer)."""
    from .measurements import MeasurementSet
    from .problem import build_problem
    from .roots import ScalarScan

    I_p = pb.models[0].inertia_ref(pb.values(p))
    hangs = [dataclasses.replace(hm.hanging, scene=dataclasses.replace(hm.hanging.scene, inertia=hm.R @ I_p @ hm.R.T))
             for hm in pb.models]
    rests = [hm.rest0 for hm in pb.models]
    for i, name in enumerate(pb.unknowns):
        try:
            scan = ScalarScan(build_problem(MeasurementSet(hangs, [m], rig=pb.rig), [name], pb.unc, rests=rests))
            # a gap only where no value on the line gives the label the period (as one unknown's refusal)
            g = None if scan.roots(target) else _gap_partner(scan, target)
        except (BifilarError, np.linalg.LinAlgError):
            continue
        if g is not None:
            yield i, name, scan.a, scan.b, g


def _surface_message(pb, p, k: int, name: str, g: _Gap, target: float, reading) -> str:
    """:func:`surface_hint`'s words for measurement ``k``'s gap ``g`` along
    ``name`` at the best fit ``p``."""
    m, lab = pb.measurements[k], g.lab
    others = ", ".join(f"{n} = {v:.6g}" for n, v in zip(pb.unknowns, p) if n != name)
    what = f"{target:.9g} s" + (" (the period over its amplitude factor)" if target != m.period else "")
    msg = (f"; at the best fit no {name} gives the mode labelled '{m.label}' {what} with {others} as there: its "
           f"period jumps over {min(g.Ta, g.Tb):.9g} s .. {max(g.Ta, g.Tb):.9g} s where {name} passes "
           f"{0.5 * (g.xa + g.xb):.6g} kg m^2, the label passing to the mode labelled '{lab}' (the two modes "
           "exchange character near these values)")
    if not g.found[lab]:
        return msg  # no reading of that label reaches the period on the line: the exchange, and no more
    j = next((j for j, q in enumerate(pb.measurements) if j != k and q.hanging == m.hanging and q.label == lab), None)
    relabel = {k: lab}
    if j is None:
        msg += f"; if the timed oscillation may be that mode, the period can be given under its label ({_give(m, lab)})"
    else:
        q = pb.measurements[j]
        relabel[j] = m.label
        msg += (f", which is timed too ({q.period:.9g} s): if the two were told apart the other way, they can be "
                f"given swapped ({_give(m, lab)}, {_give(q, m.label)})")
    if any(pb.measurements[i].amplitude for i in relabel):
        msg += _amplitude_caution(g.side[lab], m.label, lab)
    if reading is None:
        return msg
    res, why = reading(relabel)
    same = ", at the same amplitudes," if any(q.amplitude for q in pb.measurements) else ","
    if res is None:
        return msg + f"; read so{same} they are refused as well ({_head(why)})"
    vals = ", ".join(f"{n} = {v:.6g} kg m^2" for n, v in zip(res.names, res.values))
    more = (f"; the first of {len(res.roots)} tensors that reproduce them, listed by that command"
            if len(res.roots) > 1 else "")
    return msg + f"; read so{same} the periods give {vals} (invert's answer to that reading, run here{more}){ACROSS}"


#: an answer's timed mode whose adjacent sorted modes' periods are all farther than this relative difference
#: (of the longer) is not scanned for a crossing by :func:`across_gap` (docs/design.md, "cross29, session 29")
NEAR_REL = 0.05


def across_gap(pb, p, targets) -> dict | None:
    """Whether an answer's period reads across an avoided crossing: the
    partner reading a refusal names (:func:`surface_hint`), given directly.
    ``pb``: the answer's problem (built at the estimate ``p``, SI: its
    modes are those at ``p``), ``targets``: the labelled modes' linear
    periods at ``p`` (K,), s (what the answer reproduces: the period over
    its amplitude factor; on the edge of the physical set, where no tensor
    reproduces it exactly, the edge's).  For each measurement of label L
    whose sorted mode at ``p`` has an adjacent mode (label N) within
    :data:`NEAR_REL` of its period (none: nothing is scanned), its target
    is read under N along each inertia unknown's line through ``p``
    (:func:`_line_gaps`): where no value on a line gives N that period and
    it lies in N's jump at a label switch that L carries it across, the
    command with L in place of N is the one a refusal would have named L
    for, and this answer is that reading (docs/design.md, "cross29,
    session 29"): its 95 % intervals are a budget at the inputs as
    written, which does not hold the jump the reading makes where the
    label passes.  Returns the first such finding, {``mode``, ``hanging``,
    ``period`` (s), ``partner``, ``unknown``, ``switch_at`` (kg m^2),
    ``gap`` ([s, s]), ``warning``}, or None.  Not scanned (None) when the
    unknowns include a CoM coordinate (as :func:`surface_hint`)."""
    from .problem import _IDX

    if _IN_READING.get() or any(n not in _IDX for n in pb.unknowns):  # a refusal's reading says it already
        return None
    for k, m in enumerate(pb.measurements):
        modes, i = pb.models[m.hanging].modes0.modes, pb.mode_index[k]
        T = modes[i].period
        near = [modes[j].label for j in (i - 1, i + 1) if 0 <= j < len(modes) and T and modes[j].period
                and abs(modes[j].period - T) <= NEAR_REL * max(T, modes[j].period) and modes[j].label != m.label]
        for lab in near:
            m2 = dataclasses.replace(m, label=lab, details=copy.deepcopy(m.details), secondary=None, hidden=[])
            target = float(targets[k])
            for _, name, _, _, g in _line_gaps(pb, p, m2, target):
                if g.found.get(m.label):
                    return _across_finding(pb, p, m, lab, name, g, target)
    return None


def _across_finding(pb, p, m, lab: str, name: str, g: _Gap, target: float) -> dict:
    """:func:`across_gap`'s finding and its warning's words."""
    hang = pb.models[m.hanging].hanging.name
    where = f"hanging '{hang}': " if len(pb.models) > 1 else ""
    others = ", ".join(f"{n} = {v:.6g}" for n, v in zip(pb.unknowns, p) if n != name)
    at = f" with {others} as here" if others else ""
    what = f"{target:.9g} s" + (" (the period over its amplitude factor)" if target != m.period else "")
    text = (f"{where}the period timed as '{m.label}' ({what}) lies in an avoided crossing's gap: no {name}{at} gives "
            f"the mode labelled '{lab}' that period, which jumps over {min(g.Ta, g.Tb):.9g} s .. "
            f"{max(g.Ta, g.Tb):.9g} s where {name} passes {0.5 * (g.xa + g.xb):.6g} kg m^2, and '{m.label}' "
            f"carries it across (the two modes exchange character near here): this answer is the reading that "
            f"invert's refusal of the period as '{lab}' names{ACROSS}")
    return {"mode": m.label, "hanging": hang, "period": float(m.period), "partner": lab, "unknown": name,
            "switch_at": float(0.5 * (g.xa + g.xb)), "gap": [float(min(g.Ta, g.Tb)), float(max(g.Ta, g.Tb))],
            "warning": text}
