"""The body against the ceiling at rest: a body whose shape (``body.parts``,
``body.bounding_box``) reaches above the highest anchor would pass through
the ceiling or the rig's beam, which the model does not see (it knows only
the wires).  SI units, world frame (z up)."""

from __future__ import annotations

from ..scene import Scene, highest_point_z
from .equilibrium import RestPose

#: how far above the highest anchor the body may reach before the warning, relative to the longest wire
#: (rounding of the rest pose, ~1e-15 of it, with a wide margin)
CEILING_TOL = 1e-9


def ceiling_warning(scene: Scene, rest: RestPose) -> str | None:
    """One line when the body at rest reaches above the highest anchor (the
    ceiling, :attr:`Scene.ceiling_z`), else None."""
    top = float(highest_point_z(scene, rest.com, rest.R))
    ceiling = scene.ceiling_z
    if top <= ceiling + CEILING_TOL * float(max(scene.lengths)):
        return None
    src = {"parts": "body.parts", "bounding_box": "body.bounding_box"}.get(scene.support_source, "rig.attachments")
    return (f"body: at rest it reaches z = {top:.4g} m, {top - ceiling:.3g} m above the highest anchor (the ceiling, "
            f"z = {ceiling:.4g} m; from {src}): a real body there would hit the ceiling or the rig, which the model "
            "does not see; check the body's shape and rig.anchors, or lengthen the wires")
