"""Sigma points that are mirror images of others (issue 14: a sweep point's
sigma points, most of which only confirm the linear budget).

Why they may be skipped.  A rig that a reflection in a vertical plane maps
onto itself (the Solar Boat in x and in y, the KTH trifilar in y) maps
every sigma point onto another: moving input ``x_j`` by ``d`` gives the
mirror image of the scene with input ``x_j'`` moved by ``+-d`` (``j' = j``
for an input on the plane, e.g. ``com.y`` under the y mirror, ``p(+d) =
p(-d)``).  Mirror-image scenes have the same rest pose up to the
reflection, the same periods, and their modes match the base modes (each
of them its own mirror image up to sign, where it is a simple eigenvalue)
in the same way; so the re-solved diagonal inertia estimate of one is that
of the other.  :func:`second_order` therefore computes one sigma point of
each set of images, takes the verdict ("the linear budget holds") from
them, and, only where that verdict is "linear" with no point lost, returns
the linear budget it would have returned anyway: the sigma points'
values never reach the output on that branch.  Otherwise the images are
computed too and everything goes on as without this module.

What is checked, to ``TOL`` relative (a rig symmetric only to that is
treated as symmetric: its images' estimates differ from the direct ones by
about ``TOL`` times the length scale over the sigma-point step, ~1e-10 of
the linear term, against verdict thresholds of 2 % and 10 %): one hanging
in its body axes, diagonal inertia unknowns, no amplitude-factor shift; a
vertical mirror plane normal to world x or y through the rest CoM,
mapping the anchors onto a permutation of themselves, whose body-frame
image is a coordinate reflection mapping the attachments onto the same
permutation and the inertia tensor onto itself, with equal wire lengths,
EA and input uncertainties under the permutation; every measured mode a
simple eigenvalue of the base modes (1e-6 relative from any other).
Which rest poses came from the global search is not known here, so a
verdict from images is never taken where a sigma point is lost.
"""

from __future__ import annotations

import numpy as np

from .problem import _IDX

#: relative tolerance of the symmetry checks (module docstring)
TOL = 1e-12
#: a measured mode's period must be this far (relative) from every other base period
SIMPLE = 1e-6
_DIAGONAL = {n for n, (i, j) in _IDX.items() if i == j}


def _permutation(a: np.ndarray, b: np.ndarray, tol: float):
    """The permutation ``pi`` with ``a[i] ~ b[pi[i]]`` (rows, max-norm
    within ``tol``), or None."""
    pi = []
    for row in a:
        hit = [j for j in range(len(b)) if np.max(np.abs(b[j] - row)) <= tol]
        if len(hit) != 1:
            return None
        pi.append(hit[0])
    return pi if sorted(pi) == list(range(len(b))) else None


def _mirrors(scene, rest, sigmas: dict, keys: list) -> list:
    """[{(key, sign): (image key, sign)}] of each world mirror (x, y) that
    maps the hanging ``scene`` at ``rest`` onto itself (module docstring)."""
    A = np.asarray(scene.anchors, float)
    B = np.asarray(scene.attachments, float)
    L = np.asarray(scene.lengths, float)
    I = np.asarray(scene.inertia, float)
    R = np.asarray(rest.R, float)
    c = np.asarray(rest.com, float)
    ell = max(float(np.max(np.abs(A - c))), float(np.max(np.abs(B))), float(np.max(L)))
    tol = TOL * ell
    out = []
    for axis in (0, 1):
        S = np.eye(3)
        S[axis, axis] = -1.0
        Sb = R.T @ S @ R  # the reflection in body axes
        sb = np.diag(Sb)
        if np.max(np.abs(Sb - np.diag(sb))) > TOL or np.max(np.abs(np.abs(sb) - 1)) > TOL:
            continue  # not a reflection of a body axis: its images are not single inputs
        sb = np.sign(sb)
        pi = _permutation((A - c) @ S, A - c, tol)
        if pi is None or _permutation(B * sb, B, tol) != pi:
            continue
        if np.max(np.abs(L - L[pi])) > tol or np.max(np.abs(sb[:, None] * I * sb[None, :] - I)) > TOL * np.max(np.abs(I)):
            continue
        if scene.stiffness is not None and np.any(np.asarray(scene.stiffness, float) != np.asarray(scene.stiffness, float)[pi]):
            continue
        m = {}
        for key in keys:
            parts = key.split(".")
            if key in ("mass", "gravity", "stiffness"):
                img = (key, 1.0)
            elif parts[0] == "length":
                img = (f"length.{pi[int(parts[1]) - 1] + 1}", 1.0)
            elif parts[0] in ("anchor", "attachment") and len(parts) == 3:
                ax = "xyz".index(parts[2])
                img = (f"{parts[0]}.{pi[int(parts[1]) - 1] + 1}.{parts[2]}",
                       S[ax, ax] if parts[0] == "anchor" else sb[ax])
            elif parts[0] == "com" and len(parts) == 2:
                img = (key, sb["xyz".index(parts[1])])
            else:
                return []  # an input this module does not know: no images at all
            if img[0] not in keys or sigmas[img[0]] != sigmas[key]:
                return []
            for s in (1, -1):
                m[(key, s)] = (img[0], int(s * img[1]))
        out.append(m)
    return out


def mirror_images(pb, ctx, keys: list) -> dict:
    """{sigma point id: the id of the point it is the mirror image of} for
    the points ``(key, +-1)`` of ``keys`` (:func:`~bifilar.estimation.second_order.second_order`'s),
    each set of images represented by its first point in the order of
    ``keys`` (+1 before -1); {} where the checks of the module docstring
    fail.  Only the single-input sigma points (not the pairs' corners)."""
    if (len(pb.models) != 1 or not np.array_equal(pb.models[0].R, np.eye(3))
            or any(n not in _DIAGONAL for n in pb.unknowns) or ctx.factor_shift or not keys):
        return {}
    if any(pb.links.moves(k, 0) != [(k, 1.0)] for k in keys if k not in ("mass", "gravity", "stiffness")
           and not k.startswith("com.")):
        return {}
    periods = np.array([m.period if m.period is not None else np.nan for m in ctx.modes[0].modes], float)
    for k in range(len(pb.measurements)):
        q = ctx.match[0][pb.mode_index[k]]
        if q is None or not np.isfinite(periods[q]):
            return {}
        if np.any(np.abs(np.delete(periods, q) / periods[q] - 1) <= SIMPLE):
            return {}
    cache = ctx.cache
    ck = None
    if cache is not None:  # the same scene's budgets of other components: the same images
        from .second_order import scene_key

        ck = ("mirror images", scene_key(ctx.scenes[0]), tuple(keys), tuple(ctx.sigmas[k] for k in keys))
        if ck in cache:
            return cache[ck]
    maps = _mirrors(ctx.scenes[0], ctx.rests[0], ctx.sigmas, keys)
    image: dict = {}
    for key in keys:
        for s in (1, -1):
            rep = (key, s)
            if rep in image:
                continue
            orbit, todo = {rep}, [rep]
            while todo:
                q = todo.pop()
                for m in maps:
                    r = m[q]
                    if r not in orbit:
                        orbit.add(r)
                        todo.append(r)
            for q in orbit - {rep}:
                image[q] = rep
    if ck is not None:
        cache[ck] = image
    return image
