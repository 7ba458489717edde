"""The body against the ceiling at rest: a body whose shape (``body.parts``,
``body.bounding_box``) reaches above the highest anchor would pass through
the ceiling or the rig's beam, which the model does not see (it knows only
the wires).  SI units, world frame (z up)."""

from __future__ import annotations

import math

import numpy as np

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
    d, s, t = segment_distances(*(np.asarray(v, float)[None, :] for v in (p0, p1, q0, q1)))
    return float(d[0]), float(s[0]), float(t[0])


def segment_distances(p0, p1, q0, q1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`segment_distance` of many segment pairs: p0, p1, q0, q1 (k, 3), m;
    returns the distances (k,), m, and s, t (k,)."""
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = (np.einsum("ki,ki->k", u, v) for u, v in ((d1, d1), (d2, d2), (d2, r)))
    c, b = np.einsum("ki,ki->k", d1, r), np.einsum("ki,ki->k", d1, d2)
    den = a * e - b * b
    ok = den > 1e-14 * a * e
    s = np.where(ok, np.clip((b * f - c * e) / np.where(ok, den, 1.0), 0.0, 1.0), 0.0)
    t = (b * s + f) / e
    out = (t < 0.0) | (t > 1.0)
    t = np.clip(t, 0.0, 1.0)
    s = np.where(out, np.clip((b * t - c) / a, 0.0, 1.0), s)
    gap = p0 + s[:, None] * d1 - (q0 + t[:, None] * d2)
    return np.sqrt(np.einsum("ki,ki->k", gap, gap)), s, t


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


def run_clearance(scene: Scene, rest: RestPose, t: np.ndarray, Y: np.ndarray) -> tuple[dict, list[str]]:
    """The ceiling and crossing checks of :func:`clearance_warnings` along a
    run: ``t`` (k,) s and ``Y`` (k, 13) its samples (world frame, positions
    absolute, quaternions body -> world), vectorised over the samples.

    Returns (figures, warnings).  Figures: ``highest_point_z`` (m, the
    body's highest point over the samples), ``height_below_ceiling_min`` (m,
    the ceiling's z minus that: negative where the body rose through it),
    ``min_wire_distance`` (m, the closest two wires' segments came at a
    sample) and ``min_wire_distance_wires`` ([i, j], 1-based).  A warning,
    one line each, where the body rises above the ceiling
    (:data:`CEILING_TOL`) or two wires come closer than :data:`WIRE_CONTACT`
    away from their ends, or pass through each other between two samples
    (the sign of the volume their segments span flips with the closest
    points inside either and the distance at either no more than twice the
    two attachments' moves between them: coplanar wires far apart flip that
    sign too); none for what the rest pose already shows
    (:func:`clearance_warnings` says it once).  Cheap (docs/design.md,
    "simhealth, session 13"): numpy calls on contiguous component rows,
    the body's support function only where a bound does not rule the
    sample out (:func:`_highest`)."""
    rest_row = np.r_[rest.com, rest.q][:, None]  # (7, 1)
    cR, cR_rest = _rotation(np.ascontiguousarray(Y[:, :7].T)), _rotation(rest_row)
    top, k_top = _highest(scene, *cR)
    top_rest, _ = _highest(scene, *cR_rest)
    ceiling = float(scene.ceiling_z)
    doc = {"highest_point_z": top, "height_below_ceiling_min": ceiling - top,
           "min_wire_distance": None, "min_wire_distance_wires": None}
    warnings = []
    above = ceiling + CEILING_TOL * float(max(scene.lengths))
    if top > above and not top_rest > above:
        src = {"parts": "body.parts", "bounding_box": "body.bounding_box"}.get(scene.support_source,
                                                                               "rig.attachments")
        warnings.append(f"body: during the run it reaches z = {top:.4g} m at t = {t[k_top]:.4g} s, "
                        f"{top - ceiling:.3g} m above the highest anchor (the ceiling, z = {ceiling:.4g} m; from "
                        f"{src}): a real body would hit the ceiling or the rig there, which the model does not see; "
                        "reduce --amplitude")
    if scene.n_wires < 2:
        return doc, warnings
    best, hits = _closest_wires(scene, cR, cR_rest, t)
    doc["min_wire_distance"], doc["min_wire_distance_wires"] = best
    if hits:
        warnings.append(f"rig: during the run {'; '.join(hits)}: real wires would touch and rub there, which the "
                        "model does not see; reduce --amplitude")
    return doc, warnings


def _rotation(Z: np.ndarray):
    """(the CoM's rows, R's rows) of states ``Z`` (7, k): [com; quaternion]
    rows, R body -> world as three rows of three (k,) arrays (a quaternion of
    any norm)."""
    w, x, y, z = Z[3], Z[4], Z[5], Z[6]
    sc = 2.0 / (w * w + x * x + y * y + z * z)
    sx, sy, sz = sc * x, sc * y, sc * z
    xx, yy, zz, xy, xz, yz, wx, wy, wz = x * sx, y * sy, z * sz, x * sy, x * sz, y * sz, w * sx, w * sy, w * sz
    return Z[:3], ((1.0 - yy - zz, xy - wz, xz + wy), (xy + wz, 1.0 - xx - zz, yz - wx),
                   (xz - wy, yz + wx, 1.0 - xx - yy))


def _highest(scene: Scene, c, R) -> tuple[float, int]:
    """(highest z of the body, m, and its sample) over states with CoM rows
    ``c`` and rotation rows ``R`` (:func:`_rotation`).  The support function
    h is Lipschitz with the body's radius rho (|h(u) - h(v)| <= rho |u - v|,
    rho from h on the six axes), so com z + h(u_0) + rho |u - u_0| (u: world
    z in body axes, u_0 its value at the highest CoM, where the top is
    top_0) bounds each sample's top; h is evaluated only where that bound
    exceeds top_0 (a torsion, which hardly tilts the body: at none)."""
    ax = np.vstack([np.eye(3), -np.eye(3)])
    h_ax = scene.body_support(ax)
    rho = float(np.sqrt(np.sum(np.maximum(h_ax[:3], h_ax[3:]) ** 2)))
    up, cz = R[2], c[2]
    k0 = int(np.argmax(cz))
    u0 = np.array([up[0][k0], up[1][k0], up[2][k0]])
    top0 = float(cz[k0] + scene.body_support(u0[None, :])[0])
    e0, e1, e2 = up[0] - u0[0], up[1] - u0[1], up[2] - u0[2]
    gap = cz[k0] - cz  # what rho |u - u_0| must exceed for the sample's top to beat top_0
    cand = np.nonzero(rho * rho * (e0 * e0 + e1 * e1 + e2 * e2) > gap * gap)[0]
    if not len(cand):
        return top0, k0
    u = np.empty((len(cand), 3))
    u[:, 0], u[:, 1], u[:, 2] = up[0][cand], up[1][cand], up[2][cand]
    tops = cz[cand] + scene.body_support(u)
    j = int(np.argmax(tops))
    return (float(tops[j]), int(cand[j])) if tops[j] > top0 else (top0, k0)


def _closest_wires(scene: Scene, cR, cR_rest, t: np.ndarray):
    """((smallest distance between two wires over the samples, m; the pair,
    1-based), the crossing descriptions) for :func:`run_clearance`: ``cR``
    the samples' CoM and rotation rows (:func:`_rotation`), ``cR_rest`` the
    rest pose's, whose crossings are not repeated."""
    n = scene.n_wires
    A = np.asarray(scene.anchors, float)
    Pb = np.asarray(scene.attachments, float)

    def wires(c, R):  # each wire's vector from its anchor to its attachment, by component (zero terms skipped)
        out = []
        for i in range(n):
            d = []
            for r in range(3):
                v = c[r] - A[i, r]
                for k in range(3):
                    if Pb[i, k] != 0.0:
                        v = v + R[r][k] * Pb[i, k]
                d.append(v)
            out.append(d)
        return out

    D, D0 = wires(*cR), wires(*cR_rest)
    L2 = np.asarray(scene.lengths, float) ** 2
    best, hits = (np.inf, None), []
    for i in range(n):
        for j in range(i + 1, n):
            r = A[i] - A[j]
            d_rest, s_rest, u_rest, _ = _wire_pair(D0[i], D0[j], r, L2[i], L2[j])
            dist, s, u, vol = _wire_pair(D[i], D[j], r, L2[i], L2[j])
            m = int(np.argmin(dist))
            if dist[m] < best[0]:
                best = (float(dist[m]), [i + 1, j + 1])
            if d_rest[0] < WIRE_CONTACT and 0.0 < s_rest[0] < 1.0 and 0.0 < u_rest[0] < 1.0:
                continue  # crossing at rest: crossing_warning says so
            # the closest points inside both segments, every sample at once (a sample-by-sample test cost
            # ~3 us a period on the thesis plate, whose coplanar wires flip the volume's sign every swing)
            inside = (0.0 < s) & (s < 1.0) & (0.0 < u) & (u < 1.0)

            def met(kk):  # could the segments have met between samples kk and kk + 1?  Each point of a wire
                # moves by at most its attachment's displacement (anchors fixed): twice the chords for the arcs
                move = sum(math.sqrt(sum((D[w][q][kk + 1] - D[w][q][kk]) ** 2 for q in range(3))) for w in (i, j))
                return min(dist[kk], dist[kk + 1]) <= 2.0 * move + WIRE_CONTACT

            flips = [kk for kk in np.nonzero((vol[:-1] * vol[1:] <= 0.0) & (inside[:-1] | inside[1:]))[0] if met(kk)]
            touch = np.nonzero((dist < WIRE_CONTACT) & inside)[0]
            if flips:
                hits.append(f"wires {i + 1} and {j + 1} pass through each other between t = {t[flips[0]]:.4g} and "
                            f"{t[flips[0] + 1]:.4g} s")
            elif len(touch):
                kk = min(touch, key=lambda q: dist[q])
                hits.append(f"wires {i + 1} and {j + 1} come {dist[kk] * 1e3:.2g} mm apart at t = {t[kk]:.4g} s")
    return best, hits


def _wire_pair(d1, d2, r, a, e):
    """Distances (k,), m, between two wires' segments, the closest points'
    parameters s, u (k,) on each, and the volume (d1 x d2) . r (k,), m^3:
    ``d1``, ``d2`` the wires' vectors from their anchors (three (k,)
    component arrays), ``r`` (3,) the first anchor minus the second, ``a``,
    ``e`` their squared lengths (m^2, the wires': the states keep them to
    ~1e-10).  The clamped closed form of :func:`segment_distances`, by component."""
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    cc = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2]
    f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2]
    den = a * e - b * b
    ok = den > 1e-14 * a * e
    s = np.clip((b * f - cc * e) / np.where(ok, den, 1.0), 0.0, 1.0)
    s[~ok] = 0.0
    u = (b * s + f) / e
    out = (u < 0.0) | (u > 1.0)
    if out.any():
        u = np.clip(u, 0.0, 1.0)
        s[out] = np.clip((b[out] * u[out] - cc[out]) / a, 0.0, 1.0)
    g0, g1, g2 = r[0] + s * d1[0] - u * d2[0], r[1] + s * d1[1] - u * d2[1], r[2] + s * d1[2] - u * d2[2]
    vol = ((d1[1] * d2[2] - d1[2] * d2[1]) * r[0] + (d1[2] * d2[0] - d1[0] * d2[2]) * r[1]
           + (d1[0] * d2[1] - d1[1] * d2[0]) * r[2])
    return np.sqrt(g0 * g0 + g1 * g1 + g2 * g2), s, u, vol
