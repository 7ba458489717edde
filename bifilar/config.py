"""Config files (YAML) -> validated :class:`~bifilar.scene.Scene`.

The format is fixed in ``../shared/interface.md``; this module adds:

* ``body.parts``: a composite body of primitives (see :mod:`bifilar.parts`);
  with parts, ``rig.attachments_frame: parts`` lets attachments be given in
  the parts' build frame instead of relative to the (computed) CoM.
* ``body.bounding_box: {min: [x, y, z], max: [x, y, z]}``: body frame (CoM
  origin) box used for the clearance when there are no parts.

Every problem found is collected and reported together, one line each,
naming the field.  YAML is read with a ``SafeLoader`` subclass that also
rejects duplicate keys (plain PyYAML silently keeps the last one).
"""

from __future__ import annotations

import difflib
import logging
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import ConfigErrors, InputError
from .scene import Scene

log = logging.getLogger(__name__)

MAX_CONFIG_BYTES = 1_000_000
MAX_WIRES = 5

TOP_KEYS = {"name", "gravity", "body", "rig", "measurements", "uncertainty", "plan", "notes"}
BODY_KEYS = {"mass", "inertia", "parts", "bounding_box", "name"}
INERTIA_KEYS = {"tensor", "principal"}
RIG_KEYS = {"anchors", "attachments", "lengths", "attachments_frame"}


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses duplicate mapping keys."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False):
    seen: dict[Any, Any] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise InputError(
                f"line {key_node.start_mark.line + 1}",
                f"duplicate key '{key}' (first at line {seen[key]}); YAML would silently keep only the last",
            )
        seen[key] = key_node.start_mark.line + 1
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def read_yaml(path: str | os.PathLike) -> Any:
    """Read a YAML file safely (no object construction, no duplicate keys, size-limited)."""
    p = Path(path)
    if not p.exists():
        raise InputError("config", f"file not found: {p}")
    if p.is_dir():
        raise InputError("config", f"is a directory, not a config file: {p}")
    size = p.stat().st_size
    if size > MAX_CONFIG_BYTES:
        raise InputError("config", f"file is {size} bytes; configs are limited to {MAX_CONFIG_BYTES} bytes")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError("config", f"not UTF-8 text ({exc.reason})") from None
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 - SafeLoader subclass
    except InputError:
        raise
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "config"
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise InputError(where, f"YAML syntax error: {problem}") from None


class _Checker:
    """Collects validation errors; each helper returns a value or None."""

    def __init__(self) -> None:
        self.errors: list[InputError] = []

    def error(self, field: str, message: str) -> None:
        self.errors.append(InputError(field, message))

    def keys(self, path: str, mapping: Any, allowed: set[str], required: set[str] = frozenset()) -> bool:
        if not isinstance(mapping, dict):
            self.error(path or "config", f"must be a mapping, got {_describe(mapping)}")
            return False
        for k in mapping:
            if k not in allowed:
                hint = difflib.get_close_matches(str(k), sorted(allowed), n=1)
                extra = f"; did you mean '{hint[0]}'?" if hint else f"; allowed: {', '.join(sorted(allowed))}"
                self.error(_join(path, k), f"unknown key{extra}")
        for k in sorted(required):
            if k not in mapping:
                self.error(_join(path, k), "missing (required)")
        return True

    def number(self, path: str, value: Any, *, positive: bool = False, nonneg: bool = False) -> float | None:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.error(path, f"must be a number, got {_describe(value)}")
            return None
        v = float(value)
        if not math.isfinite(v):
            self.error(path, f"must be finite, got {value}")
            return None
        if positive and v <= 0:
            self.error(path, f"must be positive, got {value}")
            return None
        if nonneg and v < 0:
            self.error(path, f"must not be negative, got {value}")
            return None
        return v

    def vector(self, path: str, value: Any, n: int = 3, **kw: Any) -> np.ndarray | None:
        if not isinstance(value, (list, tuple)) or len(value) != n:
            self.error(path, f"must be a list of {n} numbers, got {_describe(value)}")
            return None
        out = [self.number(_join(path, i), v, **kw) for i, v in enumerate(value)]
        if any(o is None for o in out):
            return None
        return np.asarray(out, dtype=float)

    def vectors(self, path: str, value: Any, **kw: Any) -> np.ndarray | None:
        if not isinstance(value, (list, tuple)) or len(value) == 0:
            self.error(path, f"must be a non-empty list of [x, y, z] points, got {_describe(value)}")
            return None
        out = [self.vector(_join(path, i), v, **kw) for i, v in enumerate(value)]
        if any(o is None for o in out):
            return None
        return np.asarray(out, dtype=float)


def _join(path: str, key: Any) -> str:
    return f"{path}.{key}" if path else str(key)


def _describe(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, (dict, list, tuple)):
        return f"a {type(value).__name__} of {len(value)} item(s)"
    return f"{type(value).__name__} {value!r}"


def check_inertia_tensor(I: np.ndarray, path: str, chk: _Checker) -> bool:
    """Symmetric, positive definite, principal moments obey the triangle inequality."""
    scale = float(np.max(np.abs(I))) or 1.0
    if np.max(np.abs(I - I.T)) > 1e-9 * scale:
        chk.error(path, "inertia tensor must be symmetric (Ixy in row 1 must equal Ixy in row 2, ...)")
        return False
    ev = np.linalg.eigvalsh(I)
    if ev[0] <= 1e-12 * scale:
        chk.error(path, f"inertia tensor must be positive definite; principal moments are {_fmt(ev)} kg m^2")
        return False
    if ev[0] + ev[1] < ev[2] * (1 - 1e-5):  # slack for values rounded to ~6 digits (a thin plate sits exactly on the limit)
        chk.error(
            path,
            f"principal moments {_fmt(ev)} kg m^2 break the triangle inequality I1 + I2 >= I3 "
            "(no real mass distribution has them)",
        )
        return False
    return True


def _fmt(a: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.6g}" for x in np.atleast_1d(a)) + "]"


def scene_from_dict(cfg: Any, source: str = "config") -> Scene:
    """Validate a config mapping and build the :class:`Scene`.

    Raises
    ------
    ConfigErrors
        With every problem found, each naming its field.
    """
    chk = _Checker()
    if not isinstance(cfg, dict):
        raise ConfigErrors([InputError("config", f"must be a YAML mapping with keys body and rig, got {_describe(cfg)}")])
    chk.keys("", cfg, TOP_KEYS, {"body", "rig"})

    name = cfg.get("name", Path(source).stem if source != "config" else "scene")
    name = str(name)
    gravity = 9.81
    if "gravity" in cfg:
        g = chk.number("gravity", cfg["gravity"], positive=True)
        gravity = g if g is not None else gravity

    mass = inertia = None
    support = None
    support_source = "attachments"
    parts_com = None
    body = cfg.get("body")
    if body is not None and chk.keys("body", body, BODY_KEYS):
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
                mass = chk.number("body.mass", body["mass"], positive=True)
            if "inertia" in body:
                inertia = _inertia(body["inertia"], chk)
        if "bounding_box" in body:
            bb = body["bounding_box"]
            if chk.keys("body.bounding_box", bb, {"min", "max"}, {"min", "max"}):
                lo = chk.vector("body.bounding_box.min", bb.get("min"))
                hi = chk.vector("body.bounding_box.max", bb.get("max"))
                if lo is not None and hi is not None:
                    if np.any(hi <= lo):
                        chk.error("body.bounding_box", "max must exceed min in every axis")
                    elif support is None:
                        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
                        support = _points_support(corners)
                        support_source = "bounding_box"

    anchors = attachments = lengths = None
    rig = cfg.get("rig")
    if rig is not None and chk.keys("rig", rig, RIG_KEYS, {"anchors", "attachments", "lengths"}):
        if "anchors" in rig:
            anchors = chk.vectors("rig.anchors", rig["anchors"])
        if "attachments" in rig:
            attachments = chk.vectors("rig.attachments", rig["attachments"])
        if "lengths" in rig:
            L = rig["lengths"]
            if not isinstance(L, (list, tuple)) or len(L) == 0:
                chk.error("rig.lengths", f"must be a non-empty list of wire lengths in m, got {_describe(L)}")
            else:
                vals = [chk.number(f"rig.lengths.{i}", v, positive=True) for i, v in enumerate(L)]
                if all(v is not None for v in vals):
                    lengths = np.asarray(vals, float)
        frame = rig.get("attachments_frame", "com")
        if frame not in ("com", "parts"):
            chk.error("rig.attachments_frame", f"must be 'com' or 'parts', got {frame!r}")
        elif frame == "parts":
            if parts_com is None:
                if body is not None and "parts" not in body:
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

    if chk.errors:
        raise ConfigErrors(chk.errors)

    _warn_implausible(mass, lengths, anchors)
    return Scene(
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
    )


def _inertia(spec: Any, chk: _Checker) -> np.ndarray | None:
    if not chk.keys("body.inertia", spec, INERTIA_KEYS):
        return None
    present = [k for k in ("tensor", "principal") if k in spec]
    if len(present) != 1:
        chk.error("body.inertia", "give exactly one of 'tensor' (3x3) or 'principal' ([I1, I2, I3])")
        return None
    if "principal" in spec:
        v = chk.vector("body.inertia.principal", spec["principal"], positive=True)
        if v is None:
            return None
        I = np.diag(v)
        path = "body.inertia.principal"
    else:
        rows = spec["tensor"]
        if not isinstance(rows, (list, tuple)) or len(rows) != 3:
            chk.error("body.inertia.tensor", f"must be a 3x3 list of lists, got {_describe(rows)}")
            return None
        vals = [chk.vector(f"body.inertia.tensor.{i}", r) for i, r in enumerate(rows)]
        if any(v is None for v in vals):
            return None
        I = np.asarray(vals)
        path = "body.inertia.tensor"
    return I if check_inertia_tensor(I, path, chk) else None


def _body_from_parts(spec: Any, chk: _Checker):
    from . import parts as P  # local import: parts are optional

    if not isinstance(spec, (list, tuple)) or len(spec) == 0:
        chk.error("body.parts", f"must be a non-empty list of parts, got {_describe(spec)}")
        return None, None, None, None
    built = []
    for i, d in enumerate(spec):
        try:
            built.append(P.part_from_dict(d, f"body.parts.{i}"))
        except P.PartError as exc:
            chk.error(exc.path, exc.message)
    if len(built) != len(spec):
        return None, None, None, None
    comp = P.composite(built)
    I = np.asarray(comp.inertia, float)
    if not check_inertia_tensor(I, "body.parts", chk):
        return None, None, None, None
    com = np.asarray(comp.com, float)

    def support(d: np.ndarray, _parts=tuple(built), _com=com) -> np.ndarray:
        d = np.atleast_2d(d)
        return np.asarray(P.support(list(_parts), d), float) - d @ _com

    return float(comp.mass), I, support, com


def _points_support(points: np.ndarray):
    pts = np.asarray(points, float)

    def support(d: np.ndarray) -> np.ndarray:
        return np.max(np.atleast_2d(d) @ pts.T, axis=-1)

    return support


def _check_geometry(a: np.ndarray, p: np.ndarray, L: np.ndarray, chk: _Checker) -> None:
    """Necessary conditions for the wires to reach; the rest-pose solver decides the rest."""
    n = len(L)
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(a[i] - a[j]) < 1e-9:
                chk.error(f"rig.anchors.{j}", f"coincides with rig.anchors.{i}")
            if np.linalg.norm(p[i] - p[j]) < 1e-9:
                chk.error(f"rig.attachments.{j}", f"coincides with rig.attachments.{i}")
            da = np.linalg.norm(a[i] - a[j])
            dp = np.linalg.norm(p[i] - p[j])
            if da > dp + L[i] + L[j] * (1 + 1e-12):
                chk.error(
                    "rig.lengths",
                    f"wires {i + 1} and {j + 1} cannot reach: anchors are {da:.6g} m apart but attachments "
                    f"{dp:.6g} m apart plus wires {L[i]:.6g} + {L[j]:.6g} m only span {dp + L[i] + L[j]:.6g} m",
                )
            if dp > da + L[i] + L[j] * (1 + 1e-12):
                chk.error(
                    "rig.lengths",
                    f"wires {i + 1} and {j + 1} cannot reach: attachments are {dp:.6g} m apart but anchors "
                    f"{da:.6g} m apart plus wires only span {da + L[i] + L[j]:.6g} m",
                )
    if n >= 3:
        # all attachments (or all anchors) on one line: the suspension is degenerate
        for pts, key in ((p, "attachments"), (a, "anchors")):
            c = pts - pts.mean(axis=0)
            sv = np.linalg.svd(c, compute_uv=False)
            if sv[1] < 1e-9 * max(sv[0], 1e-12) and key == "attachments":
                chk.error(f"rig.{key}", f"all {n} {key} lie on one line: the body could spin freely about it")


def _warn_implausible(mass, lengths, anchors) -> None:
    if mass is not None and mass > 1e5:
        log.warning("body.mass = %g kg is implausibly large for a pendulum rig; is it in grams?", mass)
    if lengths is not None:
        if np.max(lengths) > 1000:
            log.warning("rig.lengths up to %g m are implausibly long; are they in millimetres?", np.max(lengths))
        elif np.max(lengths) > 100:
            log.warning("rig.lengths up to %g m: unusually long wires", np.max(lengths))


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a config file; see :func:`scene_from_dict`."""
    cfg = read_yaml(path)
    return scene_from_dict(cfg, source=str(path))
