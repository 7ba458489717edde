"""The rest pose's warnings, as `modes`, `simulate` and `tensions` give them.

Each is one line of text (no ``warning:`` prefix); SI units in the text
(tensions N, lengths m).  The rest pose ``rest`` is
:func:`bifilar.analysis.equilibrium.rest_pose`'s, the modes
:func:`bifilar.analysis.modes.linear_modes`' at it.
"""

from __future__ import annotations


def rest_warnings(scene, rest, modes, only: str | None = None) -> list[str]:
    """The warnings of ``scene`` at its rest pose ``rest``: dependent wires'
    tensions only one split of many
    (:func:`~bifilar.analysis.wire_statics.indeterminate_warning`), modes
    that stretch the wires (:func:`~bifilar.analysis.wire_statics.stretching_warning`,
    of the mode labelled ``only`` or of all ``modes``), elastic wires whose
    stretch the model's periods leave out
    (:func:`~bifilar.analysis.elastic_rest.stretch_coupling_warning`), the
    body through the ceiling and crossing wires
    (:func:`~bifilar.analysis.clearance.clearance_warnings`), in that order;
    an empty list when none applies."""
    from .clearance import clearance_warnings
    from .elastic_rest import stretch_coupling_warning
    from .wire_statics import indeterminate_warning, stretching_warning

    ws = [indeterminate_warning(scene, rest), stretching_warning(scene, rest, modes, only=only),
          stretch_coupling_warning(scene, rest, modes, only=only)]
    return [w for w in ws if w is not None] + clearance_warnings(scene, rest)
