"""Config files (YAML) -> validated :class:`~bifilar.scene.Scene`.

The format is fixed in ``../shared/interface.md``; this module adds:

* ``body.parts``: a composite body of primitives (see :mod:`bifilar.parts`);
  with parts, ``rig.attachments_frame: parts`` lets attachments be given in
  the parts' build frame instead of relative to the (computed) CoM.
* ``body.bounding_box: {min: [x, y, z], max: [x, y, z]}``: body frame (CoM
  origin) box used for the clearance when there are no parts.

Validation reports every problem in one pass (:class:`~bifilar.errors.ConfigErrors`),
one line each: the field's dotted path (``rig.lengths.1``, counting list
items from 0), the value found and what was expected.  Values that are
valid but implausible (a 5 km wire, a 1000 t body, wire lengths that look
like millimetres) are logged as warnings on stderr and do not fail; see
:func:`plausibility_warnings`.

Reading is defensive (:func:`read_yaml`, :func:`parse_yaml`): a
``SafeLoader`` subclass (no Python object construction: ``!!python/...``
tags are an error), duplicate keys rejected (plain PyYAML silently keeps the
last one), files limited to :data:`MAX_CONFIG_BYTES`, alias expansion
("billion laughs") limited to :data:`MAX_YAML_VALUES` values, recursive
aliases and absurd nesting rejected.  Exponent floats without a dot or an
exponent sign (``1e-3``, ``2E5``), which YAML 1.1 reads as text, are read
as numbers (YAML 1.2).

Hard limits (errors, not warnings) keep the numbers inside the range the
solvers handle in double precision: see :data:`LIMITS`.
"""

from __future__ import annotations

import difflib
import logging
import math
import os
import re
import stat
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import ConfigErrors, InputError
from .scene import Scene, obeys_triangle

log = logging.getLogger(__name__)

MAX_CONFIG_BYTES = 1_000_000
"""Largest config file read, bytes (a real config is ~1-10 kB)."""
MAX_YAML_VALUES = 100_000
"""Most values (scalars, lists, mappings) a config may hold once YAML
aliases are expanded; guards every consumer against alias bombs."""
MAX_WIRES = 5

LIMITS = {
    # quantity: (smallest, largest) magnitude accepted, SI units.  Outside these the
    # rest-pose search (relative tolerance 1e-6 .. 1e-15 of the wire length) and the
    # integrator lose their meaning; plausibility warnings start far inside them.
    "length": (1e-4, 1e5),  # wire length and rig size, m: 0.1 mm .. 100 km
    "mass": (1e-6, 1e9),  # kg: 1 mg .. 1 Mt
    "gravity": (1e-3, 1e4),  # m/s^2
    "gyration": (1e-6, 1e5),  # radius of gyration sqrt(I/m), m
}
SCALE_RATIO = 1e4
"""Largest ratio between the longest and the shortest wire, and between the
rig's size and the longest wire (beyond it the wires cannot reach anyway or
relative tolerances no longer resolve the short one)."""

TOP_KEYS = {"name", "gravity", "body", "rig", "measurements", "uncertainty", "plan", "notes"}
BODY_KEYS = {"mass", "inertia", "parts", "bounding_box", "name"}
INERTIA_KEYS = {"tensor", "principal"}
RIG_KEYS = {"anchors", "attachments", "lengths", "attachments_frame"}

# --------------------------------------------------------------------------
# reading YAML

_FLOAT_12 = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
_SAFE_TAGS = set(yaml.SafeLoader.yaml_constructors) | {
    "tag:yaml.org,2002:merge", "tag:yaml.org,2002:value",
}


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that also reads YAML 1.2 exponent floats (``1e-3``).

    Duplicate keys, unsafe tags and alias bombs are found on the composed
    node graph (:func:`_scan_nodes`) before anything is constructed, so that
    each problem can be reported with its dotted path."""


_UniqueKeyLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789."))


def read_yaml(path: str | os.PathLike) -> Any:
    """Read a YAML file safely: a regular UTF-8 file of at most
    :data:`MAX_CONFIG_BYTES` bytes, parsed by :func:`parse_yaml`.

    Raises :class:`~bifilar.errors.InputError` (field ``config``) for a file
    that cannot be read and :class:`~bifilar.errors.ConfigErrors` for YAML
    problems."""
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise InputError("config", f"file not found: {p}") from None
    except OSError as exc:
        raise InputError("config", f"cannot read {p}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError("config", f"is a directory, not a config file: {p}")
    if not stat.S_ISREG(st.st_mode):
        raise InputError("config", f"not a regular file: {p}")
    if st.st_size > MAX_CONFIG_BYTES:
        raise InputError("config", f"file is {st.st_size} bytes; configs are limited to {MAX_CONFIG_BYTES} bytes")
    try:
        with open(p, "rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
    except OSError as exc:
        raise InputError("config", f"cannot read {p}: {exc.strerror or exc}") from None
    if len(data) > MAX_CONFIG_BYTES:  # grew while we looked
        raise InputError("config", f"file is over {MAX_CONFIG_BYTES} bytes; configs are limited to {MAX_CONFIG_BYTES} bytes")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputError("config", f"not UTF-8 text (line {line}: {exc.reason} 0x{data[exc.start]:02x}); "
                                   "save the file as UTF-8") from None
    return parse_yaml(text)


def parse_yaml(text: str) -> Any:
    """Parse YAML text into plain data (dict, list, str, int, float, bool, None).

    Raises
    ------
    ConfigErrors
        Every duplicate key, unsupported tag (``!!python/object`` ...),
        non-scalar key, recursive alias or oversized alias expansion, each
        with its dotted path; or one syntax error with its line and column.
    """
    if len(text) > MAX_CONFIG_BYTES:
        raise InputError("config", f"text is {len(text)} characters; configs are limited to {MAX_CONFIG_BYTES}")
    try:
        loader = _UniqueKeyLoader(text)
    except yaml.reader.ReaderError as exc:  # the reader rejects control characters up front
        line = text.count("\n", 0, exc.position) + 1
        col = exc.position - (text.rfind("\n", 0, exc.position) + 1) + 1
        raise InputError(f"line {line}, column {col}",
                         f"YAML syntax error: control character #x{exc.character:04x} is not allowed") from None
    try:
        try:
            node = loader.get_single_node()
        except yaml.YAMLError as exc:
            raise _yaml_error(exc) from None
        except RecursionError:
            raise InputError("config", "nested too deeply (lists or mappings inside each other hundreds of levels deep)") from None
        if node is None:
            return None
        problems = _scan_nodes(node)
        if problems:
            raise ConfigErrors(problems)
        try:
            return _unshare(loader.construct_document(node))
        except yaml.YAMLError as exc:
            raise _yaml_error(exc) from None
        except RecursionError:
            raise InputError("config", "nested too deeply") from None
        except Exception as exc:  # noqa: BLE001 - PyYAML's scalar constructors fail on e.g. "!!int abc", "!!int "
            raise InputError("config", f"cannot read a value ({type(exc).__name__}: {_clip(str(exc), 80)}); "
                                       "check explicit tags such as !!int") from None
    finally:
        loader.dispose()


def _unshare(data: Any) -> Any:
    """A copy of constructed YAML data in which no list or mapping appears
    twice.  PyYAML builds one object per anchor and hands it to every alias
    (``*p0``), so without this an edit of one place (a sweep of
    ``rig.attachments.0.1``) would silently edit every place that named the
    same anchor.  :func:`copy.deepcopy` keeps such sharing (its memo), hence
    the explicit rebuild; the size is bounded by :data:`MAX_YAML_VALUES` and
    recursive aliases were rejected before."""
    if isinstance(data, dict):
        return {k: _unshare(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_unshare(v) for v in data]
    return data


def _short_tag(tag: str) -> str:
    return "!!" + tag[len("tag:yaml.org,2002:"):] if tag.startswith("tag:yaml.org,2002:") else tag


def _yaml_error(exc: yaml.YAMLError) -> InputError:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "config"
    problem = getattr(exc, "problem", None) or str(exc)
    context = getattr(exc, "context", None)
    msg = f"YAML syntax error: {problem}" + (f" ({context})" if context and context not in problem else "")
    return InputError(where, _one_line(msg))


def _scan_nodes(root: yaml.Node) -> list[InputError]:
    """Walk the composed node graph (aliases followed, iteratively) and
    collect: duplicate keys, non-scalar keys, unsafe tags, recursive aliases,
    more than :data:`MAX_YAML_VALUES` values."""
    errors: list[tuple[int, InputError]] = []  # (line, error): reported in file order
    count = 0
    on_path: set[int] = set()
    stack: list[tuple[bool, yaml.Node, str]] = [(True, root, "")]
    while stack:
        enter, node, path = stack.pop()
        if not enter:
            on_path.discard(id(node))
            continue
        line = node.start_mark.line + 1
        if id(node) in on_path:
            errors.append((line, InputError(path or "config", f"recursive YAML alias: the value at line {line} contains itself")))
            continue
        count += 1
        if count > MAX_YAML_VALUES:
            return [InputError("config", f"more than {MAX_YAML_VALUES} values once YAML aliases (*name) are expanded; "
                                         "configs are limited to that")]
        if node.tag not in _SAFE_TAGS:
            errors.append((line, InputError(
                path or "config",
                f"unsupported YAML tag {_clip(_short_tag(node.tag))} (line {line}); only plain data is read: mappings, lists, "
                "numbers, strings, true/false, null")))
            continue
        if isinstance(node, yaml.ScalarNode):
            continue
        on_path.add(id(node))
        stack.append((False, node, path))
        if isinstance(node, yaml.SequenceNode):
            for i, child in reversed(list(enumerate(node.value))):
                stack.append((True, child, _join(path, i)))
        elif isinstance(node, yaml.MappingNode):
            seen: dict[tuple[str, str], int] = {}
            children = []
            for key_node, value_node in node.value:
                kline = key_node.start_mark.line + 1
                if key_node.tag == "tag:yaml.org,2002:merge":
                    children.append((value_node, path))
                    continue
                if not isinstance(key_node, yaml.ScalarNode):
                    errors.append((kline, InputError(
                        path or "config",
                        f"a key at line {kline} is a {'list' if isinstance(key_node, yaml.SequenceNode) else 'mapping'}; "
                        "keys must be plain names")))
                    continue
                k = (key_node.tag, key_node.value)
                child_path = _join(path, key_node.value)
                if k in seen:
                    errors.append((kline, InputError(
                        child_path,
                        f"duplicate key '{_clip(key_node.value)}' (lines {seen[k]} and {kline}); "
                        "YAML would silently keep only the last")))
                else:
                    seen[k] = kline
                children.append((value_node, child_path))
            for child, cpath in reversed(children):
                stack.append((True, child, cpath))
    return [e for _, e in sorted(errors, key=lambda le: le[0])]


# --------------------------------------------------------------------------
# validation helpers


class _Checker:
    """Collects validation errors; each helper returns a value or None."""

    def __init__(self) -> None:
        self.errors: list[InputError] = []

    def error(self, field: str, message: str) -> None:
        self.errors.append(InputError(field, _one_line(message)))

    def keys(self, path: str, mapping: Any, allowed: set[str], required: set[str] = frozenset()) -> bool:
        if not isinstance(mapping, dict):
            keys = ", ".join(sorted(required or allowed))
            self.error(path or "config", f"must be a mapping (with keys {keys}), got {_describe(mapping)}")
            return False
        for k in mapping:
            if k not in allowed:
                hint = difflib.get_close_matches(str(k), sorted(allowed), n=1)
                extra = f"did you mean '{hint[0]}'?" if hint else f"allowed: {', '.join(sorted(allowed))}"
                self.error(_join(path, k), f"unknown key; {extra}")
        for k in sorted(required):
            if k not in mapping:
                self.error(_join(path, k), "missing (required)")
        return True

    def number(self, path: str, value: Any, *, positive: bool = False, nonneg: bool = False,
               limit: str | None = None, unit: str = "") -> float | None:
        """A finite real number (``int`` or ``float``, not ``bool``); with
        ``limit`` (a key of :data:`LIMITS`) its magnitude must lie in range
        (zero allowed unless ``positive``)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            hint = ""
            if isinstance(value, str):
                try:
                    float(value)
                    hint = " (a number in quotes is text; remove the quotes)"
                except ValueError:
                    pass
            self.error(path, f"must be a number, got {_describe(value)}{hint}")
            return None
        try:
            v = float(value)
        except OverflowError:
            self.error(path, f"must be finite, got an integer with {len(str(abs(value)))} digits")
            return None
        if not math.isfinite(v):
            self.error(path, f"must be finite, got {value}")
            return None
        if positive and v <= 0:
            self.error(path, f"must be positive, got {value}")
            return None
        if nonneg and v < 0:
            self.error(path, f"must not be negative, got {value}")
            return None
        if limit is not None:
            lo, hi = LIMITS[limit]
            u = f" {unit}" if unit else ""
            if abs(v) > hi:
                self.error(path, f"must be at most {hi:g}{u} in magnitude, got {value}")
                return None
            if positive and v < lo:
                self.error(path, f"must be at least {lo:g}{u}, got {value}")
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
        if len(value) > 100:
            self.error(path, f"must list one [x, y, z] point per wire (at most {MAX_WIRES}), got {len(value)} items")
            return None
        out = [self.vector(_join(path, i), v, **kw) for i, v in enumerate(value)]
        if any(o is None for o in out):
            return None
        return np.asarray(out, dtype=float)


def _key(key: Any) -> str:
    """A config key as it appears in a dotted path: one short line."""
    s = str(key)
    if len(s) > 40 or not s.isprintable() or s == "" or any(c in s for c in " .:'\"\t"):
        return _clip(repr(s))  # quoted, so that the dotted path stays unambiguous and on one line
    return s


def _join(path: str, key: Any) -> str:
    k = _key(key)
    return f"{path}.{k}" if path else k


def _clip(s: str, n: int = 60) -> str:
    s = _one_line(str(s))
    return s if len(s) <= n else s[: n - 3] + "..."


def _one_line(s: str) -> str:
    return " ".join(str(s).split("\n")).replace("\r", " ")


def _describe(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, (dict, list, tuple)):
        return f"a {type(value).__name__} of {len(value)} item(s)"
    return f"{type(value).__name__} {_clip(repr(value))}"


def check_inertia_tensor(I: np.ndarray, path: str, chk: _Checker) -> bool:
    """Symmetric, positive definite, principal moments obey the triangle
    inequality (kg m^2, any axes).  Problems go to ``chk`` under ``path``."""
    scale = float(np.max(np.abs(I))) or 1.0
    if not _check_symmetric(I, path, chk):
        return False
    ev = np.linalg.eigvalsh(I)
    if ev[0] <= 1e-12 * scale:
        chk.error(path, f"inertia tensor must be positive definite; principal moments are {_fmt(ev)} kg m^2")
        return False
    # the allowance for rounded values (TRIANGLE_SLACK) is the one invert's admissible set uses
    if not obeys_triangle(ev):
        chk.error(
            path,
            f"principal moments {_fmt(ev)} kg m^2 break the triangle inequality I1 + I2 >= I3 "
            "(no real mass distribution has them)",
        )
        return False
    return True


def _fmt(a: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.6g}" for x in np.atleast_1d(a)) + "]"


# --------------------------------------------------------------------------
# the scene


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

    anchors = attachments = lengths = None
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
    )
    if warn:
        for w in plausibility_warnings(scene):
            log.warning(w)
    return scene


INERTIA_NAMES = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2), "Ixy": (0, 1), "Ixz": (0, 2), "Iyz": (1, 2)}


def null_components(cfg: Any) -> list[str]:
    """Inertia components the config marks unknown with ``null`` (a config
    mapping or a :class:`Scene` built from one), e.g. ``tensor: [[215, 0, 0],
    [0, 52.08, 0], [0, 0, null]]`` or ``principal: [1, 2, null]``: ``Izz``."""
    cfg = getattr(cfg, "config", cfg)
    try:
        spec = cfg["body"]["inertia"]
    except (KeyError, TypeError):
        return []
    out = []
    if not isinstance(spec, dict):
        return out
    if isinstance(spec.get("principal"), (list, tuple)):
        out = [n for n, (i, j) in INERTIA_NAMES.items() if i == j and i < len(spec["principal"])
               and spec["principal"][i] is None]
    rows = spec.get("tensor")
    if isinstance(rows, (list, tuple)) and len(rows) == 3 and all(isinstance(r, (list, tuple)) and len(r) == 3
                                                                  for r in rows):
        out = [n for n, (i, j) in INERTIA_NAMES.items() if rows[i][j] is None or rows[j][i] is None]
    return out


def _inertia(spec: Any, chk: _Checker, unknown: tuple | None = None) -> np.ndarray | None:
    if not chk.keys("body.inertia", spec, INERTIA_KEYS):
        return None
    nulls = null_components({"body": {"inertia": spec}})
    if nulls:
        if unknown is None:
            chk.error("body.inertia", f"{', '.join(nulls)} is null (unknown): only `bifilar invert` accepts an unknown "
                                      "component (it solves for it); give its value")
            return None
        return _inertia_with_nulls(spec, nulls, chk)
    present = [k for k in ("tensor", "principal") if k in spec]
    if len(present) != 1:
        chk.error("body.inertia", "give exactly one of 'tensor' (3x3) or 'principal' ([I1, I2, I3]), "
                                  f"got {' and '.join(present) or 'neither'}")
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
    if unknown and set(unknown) & set(INERTIA_NAMES):
        # the components solved for are starting guesses: only the tensor's shape is checked here
        return I if _check_symmetric(I, path, chk) else None
    return I if check_inertia_tensor(I, path, chk) else None


def _check_symmetric(I: np.ndarray, path: str, chk: _Checker) -> bool:
    scale = float(np.max(np.abs(I))) or 1.0
    if np.max(np.abs(I - I.T)) > 1e-9 * scale:
        i, j = np.unravel_index(int(np.argmax(np.abs(I - I.T))), I.shape)
        chk.error(path, f"inertia tensor must be symmetric; row {i}, column {j} is {I[i, j]:.6g} but "
                        f"row {j}, column {i} is {I[j, i]:.6g}")
        return False
    return True


def _inertia_with_nulls(spec: dict, nulls: list, chk: _Checker) -> np.ndarray | None:
    """The tensor with placeholders for the null components (diagonal: the
    mean of the known moments, products: 0); the known moments must be
    positive numbers, the known products numbers."""
    key = "principal" if "principal" in spec else "tensor"
    path = f"body.inertia.{key}"
    if key == "principal" and len(spec[key]) != 3:
        chk.error(path, f"must be a list of 3 numbers (or null for an unknown one), got {_describe(spec[key])}")
        return None
    unknown_at = {INERTIA_NAMES[n] for n in nulls} | {INERTIA_NAMES[n][::-1] for n in nulls}
    I = np.zeros((3, 3))
    ok = True
    for i in range(3):
        for j in range(3):
            if (i, j) in unknown_at or (key == "principal" and i != j):
                continue
            v = spec[key][i] if key == "principal" else spec[key][i][j]
            x = chk.number(f"{path}.{i}" if key == "principal" else f"{path}.{i}.{j}", v, positive=(i == j))
            ok = ok and x is not None
            I[i, j] = x if x is not None else 0.0
    if not ok:
        return None
    known = [I[i, i] for i in range(3) if (i, i) not in unknown_at]
    for i in range(3):
        if (i, i) in unknown_at:
            I[i, i] = float(np.mean(known)) if known else 1.0
    return I if _check_symmetric(I, path, chk) else None


def _check_gyration(mass: float, I: np.ndarray, path: str, chk: _Checker) -> None:
    """Radius of gyration sqrt(I/m) within :data:`LIMITS` (mass and inertia in consistent units)."""
    lo, hi = LIMITS["gyration"]
    ev = np.linalg.eigvalsh(I)
    k_min, k_max = math.sqrt(max(ev[0], 0.0) / mass), math.sqrt(ev[-1] / mass)
    if k_max > hi or k_min < lo:
        k = k_max if k_max > hi else k_min
        chk.error(path, f"radius of gyration sqrt(I/m) = {k:.3g} m is outside {lo:g} .. {hi:g} m "
                        f"(principal moments {_fmt(ev)} kg m^2, mass {mass:g} kg): are the units kg and m?")


def _body_from_parts(spec: Any, chk: _Checker):
    from . import parts as P  # local import: parts are optional

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
        return np.max(np.atleast_2d(d) @ pts.T, axis=-1)

    return support


def _check_geometry(a: np.ndarray, p: np.ndarray, L: np.ndarray, chk: _Checker) -> None:
    """Necessary conditions for a suspension (m, anchors world frame,
    attachments body frame): distinct points, attachments not all on one
    line, scales within :data:`SCALE_RATIO`, every pair of wires able to
    reach.  The rest-pose solver decides the rest (and the joint reach)."""
    n = len(L)
    span = max(float(np.ptp(a, axis=0).max()), float(np.ptp(p, axis=0).max()), float(np.max(L)))
    tiny = 1e-9 * span  # points closer than this are the same point to the solvers
    if np.max(L) > SCALE_RATIO * np.min(L):
        i, j = int(np.argmax(L)), int(np.argmin(L))
        chk.error("rig.lengths", f"wire {i + 1} ({L[i]:g} m) is more than {SCALE_RATIO:g} times longer than wire "
                                 f"{j + 1} ({L[j]:g} m); check the units")
        return
    for key, pts in (("anchors", a), ("attachments", p)):
        size = float(np.ptp(pts, axis=0).max())
        if size > SCALE_RATIO * np.max(L):
            chk.error(f"rig.{key}", f"span {size:g} m, more than {SCALE_RATIO:g} times the longest wire "
                                    f"({np.max(L):g} m); check the units")
            return
    for i in range(n):
        for j in range(i + 1, n):
            da = float(np.linalg.norm(a[i] - a[j]))
            dp = float(np.linalg.norm(p[i] - p[j]))
            if da <= tiny:
                chk.error(f"rig.anchors.{j}", f"coincides with rig.anchors.{i} ({_fmt(a[j])}); "
                                              "each wire needs its own anchor")
            if dp <= tiny:
                chk.error(f"rig.attachments.{j}", f"coincides with rig.attachments.{i} ({_fmt(p[j])}); "
                                                  "each wire needs its own attachment point")
            reach = dp + L[i] + L[j]
            if da > reach * (1 + 1e-12):
                chk.error(
                    "rig.lengths",
                    f"wires {i + 1} and {j + 1} cannot reach: anchors {i + 1} and {j + 1} are {da:.6g} m apart but "
                    f"attachments {dp:.6g} m apart plus wires {L[i]:.6g} + {L[j]:.6g} m only span {reach:.6g} m; "
                    f"lengthen them by {da - reach:.3g} m in total or move the anchors closer",
                )
            reach = da + L[i] + L[j]
            if dp > reach * (1 + 1e-12):
                chk.error(
                    "rig.lengths",
                    f"wires {i + 1} and {j + 1} cannot reach: attachments {i + 1} and {j + 1} are {dp:.6g} m apart but "
                    f"anchors {da:.6g} m apart plus wires {L[i]:.6g} + {L[j]:.6g} m only span {reach:.6g} m; "
                    f"lengthen them by {dp - reach:.3g} m in total or move the attachments closer",
                )
    if n >= 3:
        # all attachments on one line: nothing resists a rotation about it (anchors on a line are fine)
        c = p - p.mean(axis=0)
        sv = np.linalg.svd(c, compute_uv=False)
        if sv[1] <= 1e-9 * max(sv[0], tiny):
            chk.error("rig.attachments", f"all {n} attachments lie on one line: the body could spin freely "
                                         "about it; move one off the line")


# --------------------------------------------------------------------------
# plausibility (warnings only)

PLAUSIBLE = {
    "max_length": 1000.0,  # m: no hall is higher; a 5 km wire is a units slip
    "max_mass": 1e5,  # kg: 100 t is beyond any pendulum rig
    "gravity": (1.0, 30.0),  # m/s^2: the Moon (1.62) .. well above Jupiter (24.8)
    "mm_length": 100.0,  # m: every wire longer than this ...
    "mm_span": 10.0,  # m: ... while anchors and attachments span less: lengths in mm?
    "gyration_shape": 2.0,  # k / extent, body shape known: sqrt(3) is the geometric limit
    "gyration_attachments": 30.0,  # k / attachment spread (either way) when only attachments are known
    "gyration_for_mass": 10.0,  # m: largest k for 1 kg, scaled by (m / 1 kg)^(1/3); a whole config in mm
    "attachments_beyond_shape": 10.0,  # attachment reach / the known shape's reach: the rig in cm or mm?
}
"""Thresholds of :func:`plausibility_warnings` (SI units)."""


def plausibility_warnings(scene: Scene) -> list[str]:
    """Valid but implausible values of a scene, one message each (they
    usually mean a units slip).  Empty for a sensible rig.

    * every wire longer than 100 m while anchors and attachments each span
      less than 10 m: lengths in millimetres (the thesis's 500 m wires with
      anchors 505 m apart are consistent and do not warn); otherwise a wire
      longer than 1000 m;
    * a body heavier than 100 t;
    * gravity outside 1 .. 30 m/s^2 (e.g. 981: cm/s^2);
    * a radius of gyration k = sqrt(I_max / m) inconsistent with the body's
      size h (its farthest extent from the CoM along a body axis): k > 2 h
      when the shape is known (bounding box or parts; every mass point lies
      within sqrt(3) h, so k <= sqrt(3) h), k > 30 h or k < h / 30 when only
      the attachment points are known (inertia in kg cm^2 or g mm^2);
    * a radius of gyration too large for the mass, k > 10 m (m / 1 kg)^(1/3)
      (21.5 m for 10 kg, 46 m for 100 kg): a config written wholly in
      millimetres (lengths, points and inertia in kg mm^2, all consistent, so
      no other rule sees it) has k 1000 times the real one.  The body's size
      and inertia, not the wire length, carry the rule: long wires on a small
      body are legitimate (the thesis's 500 m wires on a 100 kg plate with
      k = 1.6 m).  Checked only when the shape rule above is quiet (one
      warning per slip);
    * an attachment point farther from the CoM than 10 times the known shape
      (bounding box or parts) reaches along a body axis: the rig in cm or mm
      beside a body in SI.
    """
    out = []
    L = scene.lengths
    span_a = float(np.ptp(scene.anchors, axis=0).max())
    span_p = float(np.ptp(scene.attachments, axis=0).max())
    if np.min(L) > PLAUSIBLE["mm_length"] and max(span_a, span_p) < PLAUSIBLE["mm_span"]:
        out.append(f"rig.lengths: every wire is longer than {PLAUSIBLE['mm_length']:g} m while the anchors and "
                   f"attachments span less than {PLAUSIBLE['mm_span']:g} m; are the lengths in millimetres?")
    elif np.max(L) > PLAUSIBLE["max_length"]:
        i = int(np.argmax(L))
        out.append(f"rig.lengths.{i} = {L[i]:g} m is implausibly long for a pendulum rig; are the lengths in millimetres?")
    if scene.mass > PLAUSIBLE["max_mass"]:
        out.append(f"body.mass = {scene.mass:g} kg is implausibly large for a pendulum rig; is it in grams?")
    glo, ghi = PLAUSIBLE["gravity"]
    if not glo <= scene.gravity <= ghi:
        out.append(f"gravity = {scene.gravity:g} m/s^2 is implausible (Earth: 9.81); is it in other units?")
    ev = np.linalg.eigvalsh(scene.inertia)
    k = math.sqrt(ev[-1] / scene.mass)
    d = np.eye(3)
    bad = False
    size = float(np.max(scene.body_support(np.vstack([d, -d]))))  # farthest extent from the CoM along a body axis
    if size > 0:
        if scene.support_source == "attachments":
            r = PLAUSIBLE["gyration_attachments"]
            bad = k > r * size or k < size / r
        else:
            bad = k > PLAUSIBLE["gyration_shape"] * size
        if bad:
            out.append(f"body: radius of gyration sqrt(I/m) = {k:.3g} m does not fit a body reaching {size:.3g} m "
                       f"from its centre of mass ({scene.support_source}); are the inertia and mass in kg m^2 and kg?")
    if scene.support is not None:
        reach = float(np.max(np.asarray(scene.support(np.vstack([d, -d])), dtype=float)))  # the shape alone
        att = float(np.max(np.abs(scene.attachments)))
        if att > PLAUSIBLE["attachments_beyond_shape"] * reach:
            src = "body.bounding_box" if scene.support_source == "bounding_box" else "body.parts"
            out.append(f"rig.attachments reach {att:.3g} m from the centre of mass along a body axis, but the body "
                       f"({src}) only {reach:.3g} m; are the rig's coordinates in other units (cm, mm)?")
    k_max = PLAUSIBLE["gyration_for_mass"] * scene.mass ** (1.0 / 3.0)
    if not bad and k > k_max:
        out.append(f"body: radius of gyration sqrt(I/m) = {k:.3g} m is implausibly large for a {scene.mass:.3g} kg body "
                   f"(above {k_max:.3g} m); is the whole config in millimetres (lengths in m, inertia in kg m^2)?")
    return out


def load_scene(path: str | os.PathLike, *, warn: bool = True, unknown: tuple | None = None) -> Scene:
    """Read and validate a config file; see :func:`read_yaml` and :func:`scene_from_dict`."""
    cfg = read_yaml(path)
    return scene_from_dict(cfg, source=str(path), warn=warn, unknown=unknown)
