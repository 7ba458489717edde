"""A validated config -> :class:`~bifilar.scene.Scene`: the body (mass and
inertia, or parts), its shape for the clearance, the rig.  Every problem in
one pass (:class:`~bifilar.errors.ConfigErrors`).  Part of
:mod:`bifilar.config`.
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigErrors, InputError
from ..rowwise import row_max
from ..scene import Scene
from .fields import BODY_KEYS, LIMITS, MAX_WIRES, RIG_KEYS, TOP_KEYS, _check_geometry, _Checker, _describe
from .inertia import INERTIA_NAMES, _check_gyration, _inertia, check_inertia_tensor, null_components
from .plausibility import plausibility_warnings
from .yaml_safe import read_yaml

log = logging.getLogger("bifilar.config")

def scene_from_dict(cfg: Any, source: str = "config", *, warn: bool = True, unknown: tuple | None = None) -> Scene:
    """Validate a config mapping and build the :class:`Scene` (SI units;
    anchors world frame, attachments body frame with origin at the CoM).

    ``warn=False`` skips the plausibility warnings (for studies that build
    many variants of one config; call :func:`plausibility_warnings` once).

    ``unknown``: for ``bifilar invert``, the inertia components being solved
    for (their values are starting guesses, not checked for plausibility)
    and permission to mark components unknown with ``null`` (see
    :func:`null_components`; the scene then holds a placeholder the
    inversion replaces).  None (every other command): a null is an error.

    Raises
    ------
    ConfigErrors
        With every problem found, each naming its field.
    """
    chk = _Checker()
    if not isinstance(cfg, dict):
        # the file's content is not quoted: it may not be a config at all (/etc/passwd)
        got = _describe(cfg) if cfg is None or isinstance(cfg, (list, tuple)) else (
            f"text of {len(cfg)} characters: is this a bifilar config?" if isinstance(cfg, str)
            else f"a {type(cfg).__name__}: is this a bifilar config?")
        raise ConfigErrors([InputError("config", f"must be a YAML mapping with keys body and rig, got {got}")])
    chk.keys("", cfg, TOP_KEYS, {"body", "rig"})

    name = cfg.get("name")
    if name is None:
        name = Path(source).stem if source != "config" else "scene"
    elif isinstance(name, (dict, list, tuple)):
        chk.error("name", f"must be text, got {_describe(name)}")
    name = str(name)
    gravity = 9.81
    if "gravity" in cfg:
        g = chk.number("gravity", cfg["gravity"], positive=True, limit="gravity", unit="m/s^2")
        gravity = g if g is not None else gravity

    mass = inertia = None
    support = None
    support_source = "attachments"
    parts_com = None
    body = cfg.get("body")
    if "body" in cfg and chk.keys("body", body, BODY_KEYS):
        if "parts" in body:
            if "mass" in body or "inertia" in body:
                chk.error("body", "give either parts or mass + inertia, not both")
            mass, inertia, support, parts_com = _body_from_parts(body["parts"], chk)
            support_source = "parts"
        else:
            for k in ("mass", "inertia"):
                if k not in body:
                    chk.error(f"body.{k}", "missing (required unless body.parts is given)")
            if "mass" in body:
                mass = chk.number("body.mass", body["mass"], positive=True, limit="mass", unit="kg")
            if "inertia" in body:
                inertia = _inertia(body["inertia"], chk, unknown)
        if "bounding_box" in body:
            bb = body["bounding_box"]
            if chk.keys("body.bounding_box", bb, {"min", "max"}, {"min", "max"}) and "min" in bb and "max" in bb:
                lo = chk.vector("body.bounding_box.min", bb["min"], limit="length", unit="m")
                hi = chk.vector("body.bounding_box.max", bb["max"], limit="length", unit="m")
                if lo is not None and hi is not None:
                    if np.any(hi <= lo):
                        k = int(np.argmax(hi <= lo))
                        chk.error("body.bounding_box",
                                  f"max must exceed min in every axis; axis {'xyz'[k]}: min {lo[k]:g}, max {hi[k]:g}")
                    elif support is None:
                        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
                        support = _points_support(corners)
                        support_source = "bounding_box"
    guessed = unknown is not None and (set(unknown) & set(INERTIA_NAMES) or null_components(cfg))
    if mass is not None and inertia is not None and not guessed:
        _check_gyration(mass, inertia, "body.parts" if body and "parts" in body else "body.inertia", chk)

    anchors = attachments = lengths = stiffness = None
    rig = cfg.get("rig")
    if "rig" in cfg and chk.keys("rig", rig, RIG_KEYS, {"anchors", "attachments", "lengths"}):
        if "anchors" in rig:
            anchors = chk.vectors("rig.anchors", rig["anchors"], limit="length", unit="m")
        if "attachments" in rig:
            attachments = chk.vectors("rig.attachments", rig["attachments"], limit="length", unit="m")
        if "lengths" in rig:
            L = rig["lengths"]
            if not isinstance(L, (list, tuple)) or len(L) == 0:
                chk.error("rig.lengths", f"must be a non-empty list of wire lengths in m, got {_describe(L)}")
            elif len(L) > 100:
                chk.error("rig.lengths", f"must list one length per wire (at most {MAX_WIRES}), got {len(L)} items")
            else:
                vals = [chk.number(f"rig.lengths.{i}", v, positive=True, limit="length", unit="m") for i, v in enumerate(L)]
                if all(v is not None for v in vals):
                    lengths = np.asarray(vals, float)
        stiffness = _stiffness(rig, chk)
        frame = rig.get("attachments_frame", "com")
        if not isinstance(frame, str) or frame not in ("com", "parts"):
            chk.error("rig.attachments_frame", f"must be 'com' or 'parts', got {_describe(frame)}")
        elif frame == "parts":
            if parts_com is None:
                if not (isinstance(body, dict) and "parts" in body):
                    chk.error("rig.attachments_frame", "'parts' needs body.parts")
            elif attachments is not None:
                attachments = attachments - parts_com

    if anchors is not None and attachments is not None and lengths is not None:
        n = {len(anchors), len(attachments), len(lengths)}
        if len(n) != 1:
            chk.error(
                "rig",
                f"counts disagree: {len(anchors)} anchors, {len(attachments)} attachments, {len(lengths)} lengths "
                "(one of each per wire)",
            )
        else:
            nw = len(lengths)
            if nw < 2:
                chk.error("rig.lengths", f"need at least 2 wires, got {nw}")
            elif nw > MAX_WIRES:
                chk.error(
                    "rig.lengths",
                    f"{nw} inextensible wires over-constrain a rigid body (6 degrees of freedom); at most {MAX_WIRES} are supported",
                )
            else:
                _check_geometry(anchors, attachments, lengths, chk)
                if stiffness is not None and stiffness.shape[0] not in (1, nw):
                    chk.error("rig.stiffness", f"must be one EA (N) for every wire or one per wire ({nw}), got "
                              f"{stiffness.shape[0]} items")

    if chk.errors:
        raise ConfigErrors(chk.errors)

    scene = Scene(
        name=name,
        gravity=float(gravity),
        mass=float(mass),
        inertia=np.asarray(inertia, float),
        anchors=np.asarray(anchors, float),
        attachments=np.asarray(attachments, float),
        lengths=np.asarray(lengths, float),
        support=support,
        support_source=support_source,
        config=cfg,
        parts_com=parts_com,
        stiffness=None if stiffness is None else np.broadcast_to(stiffness, lengths.shape).copy(),
    )
    if warn:
        for w in plausibility_warnings(scene):
            log.warning(w)
    return scene


#: bodies built from parts, by :func:`_spec_key` of the parts list: a sweep over rig parameters builds
#: one scene a point from the same parts (~0.5 ms a Solar Boat or drone body); at most this many kept
_BODY_CACHE_SIZE = 16
_body_cache: dict = {}


def _spec_key(spec: Any):
    """A hashable key equal for two parts lists exactly when they hold the same
    plain YAML values (mappings with string keys, in the same order; every
    float by its ``repr``, which tells -0.0 from 0.0 and round-trips; each
    value's type too, so 1 and 1.0 differ), or None when ``spec`` holds
    anything else (a numpy array, whose ``repr`` rounds: not cached)."""
    t = type(spec)
    if t is float:
        return repr(spec)
    if t is str or t is int or t is bool or spec is None:
        return (t, spec)
    if t is dict:
        out = [dict]
        for k, v in spec.items():
            kv = _spec_key(v)
            if kv is None or type(k) is not str:
                return None
            out += (k, kv)
        return tuple(out)
    if t is list or t is tuple:
        out = [t]
        for v in spec:
            kv = _spec_key(v)
            if kv is None:
                return None
            out.append(kv)
        return tuple(out)
    return None


def _body_from_parts(spec: Any, chk: _Checker):
    """(mass kg, inertia (3, 3) kg m^2 about the parts' CoM, support
    function, the parts' CoM (3,) m in the parts frame) of a ``body.parts``
    list, or Nones with the problems entered in ``chk``.  A list built
    before (the same values, :func:`_spec_key`) returns the body built then
    (copies of its arrays; the same support function): the same numbers."""
    key = _spec_key(spec)
    hit = _body_cache.get(key) if key is not None else None
    if hit is None:
        hit = _build_body_from_parts(spec, chk)
        if key is None or hit[0] is None:
            return hit
        if len(_body_cache) >= _BODY_CACHE_SIZE:
            _body_cache.pop(next(iter(_body_cache)))
        _body_cache[key] = hit
    mass, I, support, com = hit
    return mass, I.copy(), support, com.copy()


def _build_body_from_parts(spec: Any, chk: _Checker):
    from .. import parts as P  # local import: parts are optional

    if not isinstance(spec, (list, tuple)) or len(spec) == 0:
        chk.error("body.parts", f"must be a non-empty list of parts, got {_describe(spec)}")
        return None, None, None, None
    if len(spec) > 10_000:
        chk.error("body.parts", f"at most 10000 parts, got {len(spec)}")
        return None, None, None, None
    built = []
    for i, d in enumerate(spec):
        try:
            built.append(P.part_from_dict(d, f"body.parts.{i}"))
        except InputError as exc:
            chk.error(exc.field, exc.message)
        except (ArithmeticError, ValueError, TypeError) as exc:  # e.g. an integer too large for a float
            chk.error(f"body.parts.{i}", f"invalid part ({type(exc).__name__}: {exc})")
    if len(built) != len(spec):
        return None, None, None, None
    with np.errstate(all="ignore"):
        comp = P.composite(built)
    I = np.asarray(comp.inertia, float)
    com = np.asarray(comp.com, float)
    if not (math.isfinite(comp.mass) and np.all(np.isfinite(I)) and np.all(np.isfinite(com))):
        chk.error("body.parts", "the parts' total mass, centre of mass or inertia overflows; check the units")
        return None, None, None, None
    lo, hi = LIMITS["mass"]
    if not lo <= comp.mass <= hi:
        chk.error("body.parts", f"total mass must be within {lo:g} .. {hi:g} kg, got {comp.mass:g}")
        return None, None, None, None
    if not check_inertia_tensor(I, "body.parts", chk):
        return None, None, None, None

    def support(d: np.ndarray, _parts=tuple(built), _com=com) -> np.ndarray:
        d = np.atleast_2d(d)
        return np.asarray(P.support(list(_parts), d), float) - d @ _com

    return float(comp.mass), I, support, com


def _points_support(points: np.ndarray):
    pts = np.asarray(points, float)

    def support(d: np.ndarray) -> np.ndarray:
        return row_max(np.atleast_2d(d) @ pts.T)  # (np.max(..., axis=-1), by columns: bifilar/rowwise.py)

    return support


def load_scene(path: str | os.PathLike, *, warn: bool = True, unknown: tuple | None = None) -> Scene:
    """Read and validate a config file; see :func:`read_yaml` and :func:`scene_from_dict`."""
    cfg = read_yaml(path)
    return scene_from_dict(cfg, source=str(path), warn=warn, unknown=unknown)


def _stiffness(rig: dict, chk) -> np.ndarray | None:
    """``rig.stiffness``: the wires' axial stiffness EA (N), one number for
    every wire or a list of one per wire (its length checked against the
    wires' count by the caller); optional (None: rigid wires).  Each
    positive and finite."""
    if "stiffness" not in rig:
        return None
    v = rig["stiffness"]
    if isinstance(v, (list, tuple)):
        if len(v) == 0 or len(v) > 100:
            chk.error("rig.stiffness", f"must be one EA (N) for every wire or a list of one per wire, got {_describe(v)}")
            return None
        vals = [chk.number(f"rig.stiffness.{i}", x, positive=True, unit="N") for i, x in enumerate(v)]
    else:
        vals = [chk.number("rig.stiffness", v, positive=True, unit="N")]
    if any(x is None for x in vals):
        return None
    return np.asarray(vals, float)
