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


#: wires whose straight segments come closer than this at rest are reported as touching, m (real wires
#: are 0.1-2 mm thick; the model's wires have no thickness and pass through each other unseen)
WIRE_CONTACT = 1e-3


def segment_distance(p0, p1, q0, q1) -> tuple[float, float, float]:
    """Closest distance (m) between the segments p0-p1 and q0-q1 (3-vectors,
    m) and the parameters s, t in [0, 1] of the closest points
    (p0 + s (p1 - p0), q0 + t (q1 - q0)); the clamped closed form of the two
    lines' closest points (parallel segments: s at the nearer end)."""
    import numpy as np

    p0, p1, q0, q1 = (np.asarray(v, float) for v in (p0, p1, q0, q1))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = d1 @ d1, d2 @ d2, d2 @ r
    c, b = d1 @ r, d1 @ d2
    den = a * e - b * b
    s = float(np.clip((b * f - c * e) / den, 0.0, 1.0)) if den > 1e-14 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0 or t > 1.0:
        t = float(np.clip(t, 0.0, 1.0))
        s = float(np.clip((b * t - c) / a, 0.0, 1.0))
    return float(np.linalg.norm(p0 + s * d1 - (q0 + t * d2))), s, float(t)


def crossing_warning(scene: Scene, rest: RestPose) -> str | None:
    """One line naming every pair of wires (1-based, as in ``rig.lengths``)
    whose segments at rest come closer than :data:`WIRE_CONTACT` (crossing
    or touching wires) away from their ends, or that run side by side
    within it along their whole length (both pairs of ends within it),
    else None."""
    import numpy as np

    P = rest.com + scene.attachments @ rest.R.T
    A = scene.anchors
    hits, along = [], False
    for i in range(scene.n_wires):
        for j in range(i + 1, scene.n_wires):
            dist, s, _ = segment_distance(A[i], P[i], A[j], P[j])
            if dist >= WIRE_CONTACT:
                continue
            # side by side: both pairs of ends closer than the contact distance, so every pair of points at the
            # same share of the two wires is (the difference is linear in the share): they touch all along.
            # Closest at one end only (0.5 mm apart at the ceiling, spreading from there) is no contact reported
            ends = max(np.linalg.norm(A[i] - A[j]), np.linalg.norm(P[i] - P[j]))
            if ends < WIRE_CONTACT:
                along = True
                hits.append(f"wires {i + 1} and {j + 1} (side by side, at most {ends * 1e3:.2g} mm apart along "
                            "their whole length)")
            elif 0.0 < s < 1.0:
                z = float(A[i][2] + s * (P[i][2] - A[i][2]))
                gap = f"{dist * 1e3:.2g} mm apart" if dist >= 1e-6 else "meeting"
                hits.append(f"wires {i + 1} and {j + 1} ({gap} at z = {z:.4g} m)")
    if not hits:
        return None
    return (f"rig: at rest {'; '.join(hits)} {'touch or cross' if along else 'cross'}: real wires would touch and "
            "rub there, which the model does not see; check the order of rig.anchors against rig.attachments")


def clearance_warnings(scene: Scene, rest: RestPose | None = None) -> list[str]:
    """:func:`ceiling_warning` and :func:`crossing_warning` of ``scene`` at
    rest (``rest``, or its rest pose; none where no rest pose is found: a
    rig that cannot hang is refused, or its failure reported, elsewhere)."""
    from ..errors import BifilarError
    from .equilibrium import rest_pose

    if rest is None:
        try:
            rest = rest_pose(scene)
        except BifilarError:
            return []
    return [w for w in (ceiling_warning(scene, rest), crossing_warning(scene, rest)) if w is not None]
