"""Modes whose periods nearly coincide: a timing cannot tell which was measured.

Two linear modes whose periods lie within :data:`CLOSE_REL` (0.1 %) of each
other beat slowly (a beat period of ``T / 0.001`` = 1000 swings) and a
release excites both; a stopwatch or a fitted period reads either, and an
inversion that assumes one of them may be fitted to the other's period,
its answer then confidently wrong.  ``modes`` warns of every such pair; ``invert``
of a pair one of whose modes was timed.  Periods in s.
"""

from __future__ import annotations

#: two periods within this relative difference (of the longer) are warned as indistinguishable
CLOSE_REL = 1e-3


def close_pairs(modes, rel: float = CLOSE_REL) -> list[tuple[int, int]]:
    """(i, j), i < j, of the ``modes`` (objects with ``period``, s, None for
    a neutral mode) whose periods differ by at most ``rel`` of the longer."""
    out = []
    for i, a in enumerate(modes):
        for j in range(i + 1, len(modes)):
            b = modes[j]
            if a.period and b.period and abs(a.period - b.period) <= rel * max(a.period, b.period):
                out.append((i, j))
    return out


def difference_text(Ta: float, Tb: float) -> str:
    """How two periods ``Ta``, ``Tb`` (s) differ, in words: ``equal`` (to
    the last bit: a degenerate pair, e.g. a symmetric rig's two swings, which
    do not beat) or their relative difference ``d`` (of the longer; in % from
    1e-4 up, else in scientific notation, so a rounding-level difference
    does not print as "0 %") and the beat, one in ``1 / d`` periods."""
    d = abs(Ta - Tb) / max(Ta, Tb)
    if d == 0:
        return "equal: a release excites both, and with equal periods they do not beat: the motion keeps the mix the release gave"
    size = f"{100 * d:.2g} %" if d >= 1e-4 else f"{d:.2g} of the longer"
    beat = f"{float(f'{1 / d:.2g}'):.0f}" if d >= 1e-6 else f"{1 / d:.2g}"  # two digits, no exponent below 1e6
    return f"they differ by {size}: a release excites both and they beat slowly, a beat every {beat} periods"


def close_mode_warnings(modes, timed=None, where: str = "") -> list[str]:
    """One warning per pair of :func:`close_pairs` of ``modes`` (with
    ``label``, ``period`` s); ``timed``: only pairs with a mode of these
    labels (the measured ones), the warning then saying the timing cannot
    tell which was measured.  ``where``: a prefix naming the hanging."""
    out = []
    for i, j in close_pairs(modes):
        a, b = modes[i], modes[j]
        if timed is not None and a.label not in timed and b.label not in timed:
            continue
        text = (f"{where}modes '{a.label}' ({a.period:.6g} s) and '{b.label}' ({b.period:.6g} s) have periods within "
                f"{100 * CLOSE_REL:g} % of each other ({difference_text(a.period, b.period)}), so a timing reads "
                "either")
        if timed is not None:
            which = [lab for lab in (a.label, b.label) if lab in timed]
            text += (f"; the period timed as '{which[0]}' cannot tell which was measured: time a mode whose period "
                     "stands apart, or change the rig (wire length or spacing) to separate them")
        else:
            text += ": do not time either alone, or change the rig (wire length or spacing) to separate them"
        out.append(text)
    return out
