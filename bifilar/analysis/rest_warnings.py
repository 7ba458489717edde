"""The rest pose's warnings, as `modes`, `simulate` and `tensions` give them.

Each is one line of text (no ``warning:`` prefix); SI units in the text
(tensions N, lengths m, angles deg).  The rest pose ``rest`` is
:func:`bifilar.analysis.equilibrium.rest_pose`'s, the modes
:func:`bifilar.analysis.modes.linear_modes`' at it.
"""

from __future__ import annotations

import numpy as np


def rest_warnings(scene, rest, modes, only: str | None = None) -> list[str]:
    """The warnings of ``scene`` at its rest pose ``rest``: dependent wires'
    tensions only one split of many
    (:func:`~bifilar.analysis.wire_statics.indeterminate_warning`), modes
    that stretch the wires (:func:`~bifilar.analysis.wire_statics.stretching_warning`,
    of the mode labelled ``only`` or of all ``modes``), elastic wires whose
    stretch the model's periods leave out
    (:func:`~bifilar.analysis.elastic_rest.stretch_coupling_warning`), the
    body through the ceiling and crossing wires
    (:func:`~bifilar.analysis.clearance.clearance_warnings`), the body
    hanging far turned from the configured orientation (:func:`turn_warning`),
    in that order; an empty list when none applies."""
    from .clearance import clearance_warnings
    from .elastic_rest import stretch_coupling_warning
    from .wire_statics import indeterminate_warning, stretching_warning

    ws = [indeterminate_warning(scene, rest), stretching_warning(scene, rest, modes, only=only),
          stretch_coupling_warning(scene, rest, modes, only=only)]
    ws += clearance_warnings(scene, rest) + [turn_warning(scene, rest)]
    return [w for w in ws if w is not None]


#: a rest pose turned more than this from the configured orientation (the body's axes along the world's,
#: which is where the rest pose search starts) is warned of, rad: 20 deg, 1.7x the largest turn of a rig meant
#: to hang turned among the shipped configs (the thesis's 6.4 cylinder on wires 2b / 1.8b: 11.54 deg); the
#: others hang within 0.001 deg of it; docs/design.md "minor25, session 25"
TURN_WARN = 20.0 * np.pi / 180.0

#: the head of :func:`turn_warning`'s text (``sweep``/``plan`` pass it on to their recommended point's cautions)
TURN_WARNING_HEAD = "at rest the body hangs turned"


def rest_turn(R) -> tuple[float, np.ndarray]:
    """The turn of the rest pose's rotation ``R`` (body -> world) from the
    configured orientation (the identity: body axes along world axes): its
    angle (rad, 0..pi) and unit axis (world frame; any unit vector at angle 0)."""
    from ..rotations import matrix_to_rotvec

    v = matrix_to_rotvec(np.asarray(R, float))
    a = float(np.linalg.norm(v))
    return a, (v / a if a > 0 else np.array([0.0, 0.0, 1.0]))


def turn_warning(scene, rest, threshold: float = TURN_WARN) -> str | None:
    """One line when the body of ``scene`` at its rest pose ``rest`` (com m,
    R body -> world) is turned from the configured orientation by more than
    ``threshold`` (rad), else None: the angle (deg), the axis in words (the
    vertical, a horizontal or an inclined world axis, with its world
    components) and the likely cause (:func:`_turn_cause`).  A body hanging on its side is a legitimate
    rig (the periods are those of that pose), but more often a mistyped wire
    length or attachment; the text says both."""
    angle, axis = rest_turn(rest.R)
    if not angle > threshold:
        return None
    az = abs(float(axis[2]))
    vertical = az >= np.cos(np.radians(20))
    kind = "the vertical" if vertical else "a horizontal axis" if az <= np.sin(np.radians(20)) else "an inclined axis"
    ax = ", ".join(f"{round(float(c), 2) + 0.0:.2f}" for c in axis)
    return (f"{TURN_WARNING_HEAD} {np.degrees(angle):.4g} deg from the configured orientation (body axes along the "
            f"world's) about {kind} (world x, y, z: {ax}): {_turn_cause(scene, threshold, vertical)}; the "
            "periods are those of that pose")


def _turn_cause(scene, threshold: float, vertical: bool) -> str:
    """The likely cause of a rest pose turned beyond ``threshold`` (rad), in
    words.  Each wire, hanging straight down from its anchor to a level
    body, would hold the CoM at its anchor's z minus its length minus its
    attachment's body z (m); where these heights differ and the rig with
    every wire's length changed to hold the CoM at their median hangs
    turned by at most half the threshold (one more rest pose, ~1 ms, only
    when the warning is given), the cause is the wire farthest from the
    others' median: its length or its attachment's height, whichever
    differs more from the others'.  Else, for a turn about the vertical
    (``vertical``), the attachments laid out turned against the anchors;
    else the attachments (body frame, origin at the CoM) or the CoM, with
    the attachments' centroid's offset from the CoM."""
    from dataclasses import replace

    from ..errors import BifilarError
    from .equilibrium import rest_pose

    L = np.asarray(scene.lengths, float)
    A, B = np.asarray(scene.anchors, float), np.asarray(scene.attachments, float)
    hold = A[:, 2] - L - B[:, 2]  # the CoM's z each wire would hold a level body at, m
    off = hold - float(np.median(hold))
    if np.max(np.abs(off)) > 1e-9 * float(L.max()):
        try:
            level = rest_turn(rest_pose(replace(scene, lengths=L + off)).R)[0]
        except BifilarError:
            level = np.inf
        if level <= 0.5 * threshold:
            n = len(L)
            med = lambda x, k: float(np.median(np.delete(x, k)))  # noqa: E731 - the other wires' median
            # the wire farthest from the others, the one holding the CoM lower on a tie (a bifilar's longer)
            k = max(range(n), key=lambda i: (abs(hold[i] - med(hold, i)), -hold[i]))
            d = hold[k] - med(hold, k)
            others = f"wire {2 - k}" if n == 2 else "the others"
            dL, dB = L[k] - med(L, k), B[k, 2] - med(B[:, 2], k)
            what = (f"wire {k + 1}'s length ({L[k]:.4g} m against {med(L, k):.4g} m: check rig.lengths)"
                    if abs(dL) >= abs(dB) else
                    f"wire {k + 1}'s attachment (body z {B[k, 2]:.4g} m against {med(B[:, 2], k):.4g} m: check "
                    "rig.attachments)")
            return (f"likely {what}: hanging straight, wire {k + 1} would hold the CoM {abs(d):.3g} m "
                    f"{'lower' if d < 0 else 'higher'} than {others}, and with every wire holding it at the same "
                    f"height the body would hang turned {np.degrees(level):.2g} deg; if that is not meant, correct it")
    if vertical:
        return ("likely the attachments laid out turned against the anchors: the body turns until its wires hang as "
                "the two layouts let them; if that is not meant, check rig.attachments (body frame) against "
                "rig.anchors (world frame)")
    c = B.mean(axis=0)
    return (f"likely an attachment or the CoM: the attachments' centroid lies {np.hypot(c[0], c[1]):.3g} m beside "
            f"the CoM and {c[2]:.3g} m above it (body frame); if that is not meant, check rig.attachments and the "
            "body's CoM")
