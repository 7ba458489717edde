"""Remedies for inertia components a rig cannot measure, and other hangings.

A component is *not identifiable* at a point when no mode's period depends
on it (e.g. the pitch inertia of a plate on parallel wires: its in-plane
swing is a pure translation).  The model can show what would make it
measurable, from the cheapest change to the dearest:

1. ``inclined wires``: move the anchors (``ceiling_spacing`` x0.6 or x1.5)
   so that the wires lean and couple the rotation into the swing;
2. ``attachment height``: attachments higher above the CoM (10 % of the
   spacing), which gives the rotations about horizontal axes a stiffness;
3. ``hanging``: hang the body in another orientation (turned 90 or 45
   degrees about a body axis) on the same rig, so that another mode's
   period depends on the component.

Each candidate is evaluated (linear model, no nonlinear runs) at the given
point and reported with the mode to time and the predicted uncertainty of
the component (:func:`bifilar.studies.point.predicted_budget`, the same
formula the sweep ranks with).

A hanging (the convention of ``bifilar invert --measurements``): the rig is
unchanged, the body is re-fixed to it turned by ``R`` (body frame of the
hanging ``v_h = R v_ref``), so its inertia in the hanging's body axes is
``R I_ref R^T``; its mass, CoM, and attachment points relative to the CoM
are those of the point.  A reference component ``c`` enters the hanging's
periods through ``dT/dI_c = sum_h dT/dI_h (R E_c R^T)_h``.

Units SI; inertia components in the reference body axes (those of the
point's config).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import BifilarError
from .limits import component_scale
from .point import IDENTIFIABLE_MIN, _one_line, predicted_budget, point_sensitivity, rig_of
from .settings import _IDX, SweepSettings
from .shorthands import apply_params

#: (name, rotation vector in degrees about the reference body axes) of the hangings tried
HANGINGS = (("turned 90 deg about x", (90.0, 0.0, 0.0)), ("turned 90 deg about y", (0.0, 90.0, 0.0)),
            ("turned 90 deg about z", (0.0, 0.0, 90.0)), ("turned 45 deg about x", (45.0, 0.0, 0.0)),
            ("turned 45 deg about y", (0.0, 45.0, 0.0)), ("turned 45 deg about z", (0.0, 0.0, 45.0)))
#: cost order of the remedies (lower: cheaper)
COST = {"mode": 0, "inclined wires": 1, "attachment height": 1, "hanging": 2}
#: a remedy whose predicted relative uncertainty is below this counts as adequate
ADEQUATE = 0.05


def rotation(rotvec_deg) -> np.ndarray:
    """Rotation matrix of a rotation vector given in degrees."""
    from ..rotations import rotvec_to_matrix

    return rotvec_to_matrix(np.radians(np.asarray(rotvec_deg, float)))


def unit_tensor(comp: str) -> np.ndarray:
    """Symmetric basis tensor E_c of a component (1 at (i, j) and (j, i))."""
    E = np.zeros((3, 3))
    i, j = _IDX[comp]
    E[i, j] = E[j, i] = 1.0
    return E


def reference_column(sens, R: np.ndarray, comp: str) -> np.ndarray:
    """dT/dI_c (s per kg m^2) of every mode of a hanging turned by ``R``
    for the reference component ``comp`` (chain rule through R E_c R^T);
    ``sens`` must hold the six hanging components."""
    M = R @ unit_tensor(comp) @ R.T
    col = np.zeros(len(sens.periods))
    for h, (i, j) in _IDX.items():
        if M[i, j] != 0.0:
            col += sens.column(h) * M[i, j]
    return col


def hanging_config(scene, R: np.ndarray, name: str) -> dict:
    """Config of ``scene``'s body turned by ``R`` on the same rig (see the
    module docstring): mass and tensor form, attachments in the CoM frame,
    the body's extent (from its support function) as a bounding box."""
    body: dict = {"mass": float(scene.mass), "inertia": {"tensor": (R @ scene.inertia @ R.T).tolist()}}
    if scene.support is not None and scene.support_source != "attachments":
        e = np.eye(3)
        hi = np.asarray(scene.support(e), float).reshape(3)
        lo = -np.asarray(scene.support(-e), float).reshape(3)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) @ R.T
        body["bounding_box"] = {"min": corners.min(axis=0).tolist(), "max": corners.max(axis=0).tolist()}
    return {"name": name, "gravity": float(scene.gravity), "body": body,
            "rig": {"anchors": np.asarray(scene.anchors).tolist(), "attachments": np.asarray(scene.attachments).tolist(),
                    "lengths": np.asarray(scene.lengths).tolist()}}


def hanging_sensitivity(cfg: dict, source: str = "hanging"):
    """(scene, Sensitivity over the six components and the measured inputs, notes)
    of a hanging config; raises :class:`~bifilar.errors.BifilarError` if it cannot hang."""
    from ..analysis.equilibrium import rest_pose
    from ..config import scene_from_dict
    from ..estimation.sensitivity import INERTIA_COMPONENTS, measured_inputs

    scene = scene_from_dict(cfg, source, warn=False)
    rest = rest_pose(scene)
    sens, notes = point_sensitivity(scene, list(INERTIA_COMPONENTS) + measured_inputs(scene), rest)
    return scene, sens, notes


def best_measurement(scene, sens, column, comp: str, scale: float, unc: dict) -> dict | None:
    """The mode most sensitive to a component (given its dT/dI column) and
    its predicted uncertainty; None if no mode's period depends on it."""
    T = sens.periods
    rel = np.abs(column) * scale / np.where(np.isfinite(T), T, np.inf)
    rel = np.where(np.isfinite(rel), rel, 0.0)
    if rel.max() < IDENTIFIABLE_MIN:
        return None
    k = int(np.argmax(rel))
    b = predicted_budget(sens, scene, comp, k, unc, column=column)
    return {"mode": sens.modes.modes[k].label, "period": float(T[k]), "sigma": b.value_sigma,
            "rel_sigma": b.value_sigma / scale if scale else math.inf}


def candidates(base_cfg: dict, source: str, params: dict, settings: SweepSettings, comps: list[str]) -> list[dict]:
    """Every remedy tried (see the module docstring) for each of ``comps`` at
    the point ``params``: dicts with ``component``, ``kind``, ``change``
    (parameters or rotation), ``mode``, ``period`` s, ``sigma`` kg m^2,
    ``rel_sigma``; a candidate that cannot hang is left out."""
    from ..config import scene_from_dict
    from .point import point_uncertainty
    from .shorthands import base_value

    cfg, _ = apply_params(base_cfg, params, source)
    scene = scene_from_dict(cfg, source, warn=False)
    unc = point_uncertainty(settings, params)
    out: list[dict] = []
    rig_changes = []
    cs = base_value(cfg, "ceiling_spacing", source)
    if cs:
        rig_changes += [("inclined wires", {"ceiling_spacing": f * cs}) for f in (0.6, 1.5)]
    sp, h = base_value(cfg, "spacing", source), base_value(cfg, "height", source)
    if sp and h is not None:
        rig_changes.append(("attachment height", {"height": h + 0.1 * sp}))
    for kind, change in rig_changes:
        try:
            c2, _ = apply_params(cfg, change, source)
            sc, sens, _ = hanging_sensitivity(c2, source)
        except BifilarError:
            continue
        for comp in comps:
            m = best_measurement(sc, sens, sens.column(comp), comp, component_scale(sc.inertia, comp), unc)
            if m is not None:
                out.append({"component": comp, "kind": kind, "change": {**params, **change}, **m})
    for name, rv in HANGINGS:
        R = rotation(rv)
        try:
            sc, sens, _ = hanging_sensitivity(hanging_config(scene, R, name), source)
        except BifilarError:
            continue
        for comp in comps:
            m = best_measurement(sc, sens, reference_column(sens, R, comp), comp,
                                 component_scale(scene.inertia, comp), unc)
            if m is not None:
                out.append({"component": comp, "kind": "hanging", "change": {"hanging": name, "rotation_deg": list(rv)},
                            **m})
    return out


def cheapest(cands: list[dict], comp: str) -> dict | None:
    """The cheapest adequate remedy of ``comp`` (:data:`COST` order, then the
    smallest uncertainty; adequate: below :data:`ADEQUATE`), else the most
    accurate one; None if nothing the model tried helps."""
    mine = [c for c in cands if c["component"] == comp]
    if not mine:
        return None
    ok = [c for c in mine if c["rel_sigma"] < ADEQUATE]
    if ok:
        return min(ok, key=lambda c: (COST[c["kind"]], c["rel_sigma"]))
    return min(mine, key=lambda c: c["rel_sigma"])


def describe(r: dict) -> str:
    """One line: what to change, which mode to time, the predicted uncertainty."""
    if r["kind"] == "hanging":
        what = f"hang the body {r['change']['hanging']} (same rig)"
    else:
        ch = {k: v for k, v in r["change"].items() if k in ("ceiling_spacing", "height")}
        what = f"{r['kind']}: " + ", ".join(f"{k} = {v:.4g} m" for k, v in ch.items())
    return f"{what}; time the {r['mode']} mode (T = {r['period']:.4g} s): +- {100 * r['rel_sigma']:.3g} %"


def add_remedies(rec: dict, base_cfg: dict, source: str, params: dict, settings: SweepSettings,
                 comps: list[str]) -> dict:
    """Fill ``rec["identifiability"][c]["remedy"]`` (and ``alternatives``)
    for each of ``comps`` at the point ``params``; returns ``rec``."""
    if not comps:
        return rec
    try:
        cands = candidates(base_cfg, source, params, replace(settings, tensions=False), comps)
    except BifilarError as exc:
        for c in comps:
            rec["identifiability"][c]["remedy_error"] = _one_line(exc)
        return rec
    for c in comps:
        r = cheapest(cands, c)
        ent = rec["identifiability"][c]
        ent["remedy"] = None if r is None else {**r, "text": describe(r)}
        ent["alternatives"] = sorted((x for x in cands if x["component"] == c),
                                     key=lambda x: (COST[x["kind"]], x["rel_sigma"]))
    return rec


__all__ = ["add_remedies", "candidates", "cheapest", "hanging_config", "hanging_sensitivity", "reference_column",
           "rig_of", "rotation"]
