"""Sweep parameters: value ranges, dotted config paths and named shorthands.

A sweep parameter is either

* a **dotted path** into the config mapping (``rig.attachments.0.0``,
  ``rig.lengths.1``, ``body.mass``, ``body.parts.2.position.2``,
  ``uncertainty.timing``): list items are addressed by 0-based index and the
  leaf must be an existing number (``uncertainty.KEY`` leaves may be new: a
  point's measurement uncertainty, units as ``--sigma``, not negative); or
* a **named shorthand** for the usual design questions (:data:`SHORTHANDS`).

Values are SI (m, kg, s, rad, N) except the ``*_deg`` rotations (degrees).
Shorthands edit the config the way an experimenter would change the rig and
are applied after every dotted path, in this order: ``length``,
``length_offset``, ``spacing``, ``ceiling_spacing``, ``height``,
``stiffness`` (every wire's EA, N), then the rotations in the order given.
``amplitude`` is not a config value: it sets the excitation amplitude of the
point.

Value specifications (:func:`parse_values`): ``START:STOP:NUM`` (linear,
both ends included), ``log:START:STOP:NUM`` (geometric), a list ``[0.5, 1, 2]``
or ``0.5,1,2``, or a single number.
"""

from __future__ import annotations

import copy
import json
import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError

#: shorthand name -> (unit, meaning)
SHORTHANDS: dict[str, tuple[str, str]] = {
    "spacing": ("m", "symmetric body-attachment spacing: distance between the two attachment points "
                     "(n >= 3 wires: twice their mean horizontal distance from their centroid), "
                     "scaled about the centroid in the body's horizontal plane"),
    "ceiling_spacing": ("m", "the same for the anchors (ceiling points), world frame"),
    "length": ("m", "mean wire length; every wire changes by the same amount (differences kept)"),
    "length_offset": ("m", "unequal wires: the last wire is this much longer than the first "
                           "(linear across the wires in between), mean length kept"),
    "height": ("m", "height of the attachment points above the centre of mass (mean over the "
                    "attachments, body z); all attachments move vertically together"),
    "amplitude": ("rad or m", "excitation amplitude: this times each mode's normalised shape"),
    "stiffness": ("N", "the wires' axial stiffness EA, one value for every wire (rig.stiffness; rig.lengths "
                       "are then the unloaded lengths)"),
    "rotate_x": ("rad", "rotate the body about the world x axis before hanging (inertia, shape and "
                        "attachments turn with it; parts-built bodies turn their parts)"),
    "rotate_y": ("rad", "the same about world y"),
    "rotate_z": ("rad", "the same about world z"),
    "rotate_x_deg": ("deg", "rotate_x in degrees"),
    "rotate_y_deg": ("deg", "rotate_y in degrees"),
    "rotate_z_deg": ("deg", "rotate_z in degrees"),
}

_ORDER = ("length", "length_offset", "spacing", "ceiling_spacing", "height")
_CREATABLE = ("uncertainty",)  # top-level blocks whose leaves may be new
MAX_POINTS = 100_000


@dataclass(frozen=True)
class ParamSpec:
    """One swept parameter: ``name`` (dotted path or shorthand) and its values."""

    name: str
    values: tuple[float, ...]


#: a number as a user types one on the command line: ASCII digits, an optional point and exponent.  Python's
#: float() and int() also take '1_0' (10) and other scripts' digits, a typo read as another value
_PLAIN_NUMBER = re.compile(r"\s*[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?\s*")
_PLAIN_COUNT = re.compile(r"\s*\+?[0-9]+\s*")


def _num(text: str, arg: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise InputError(arg, f"{what} {text!r} is not a number") from None
    if not math.isfinite(v):
        raise InputError(arg, f"{what} must be finite, got {text}")
    if not _PLAIN_NUMBER.fullmatch(text):
        raise InputError(arg, f"{what} {text!r} is not a plain decimal number (digits 0-9, e.g. 1.5 or 2e-3)")
    return v


def _count(text: str, arg: str) -> int:
    try:
        n = int(text)
        if not _PLAIN_COUNT.fullmatch(text):
            raise ValueError
    except ValueError:
        raise InputError(arg, f"the number of points {text!r} must be a whole number") from None
    if not 1 <= n <= MAX_POINTS:
        raise InputError(arg, f"the number of points must be 1..{MAX_POINTS}, got {n}")
    return n


def parse_values(spec: str, arg: str = "--param") -> np.ndarray:
    """Values of a sweep specification (see the module docstring).

    Raises :class:`InputError` naming ``arg`` for malformed input.
    """
    s = spec.strip()
    if not s:
        raise InputError(arg, "empty value list; give START:STOP:NUM, log:START:STOP:NUM or a list like 0.5,1,2")
    if s.lower().startswith("log:"):
        parts = s[4:].split(":")
        if len(parts) != 3:
            raise InputError(arg, f"log range {spec!r} must be log:START:STOP:NUM")
        a, b = (_num(p, arg, "log range end") for p in parts[:2])
        n = _count(parts[2], arg)
        if a <= 0 or b <= 0:
            raise InputError(arg, f"log range ends must be positive, got {a:g} and {b:g}")
        return np.geomspace(a, b, n)
    if ":" in s:
        parts = s.split(":")
        if len(parts) != 3:
            raise InputError(arg, f"range {spec!r} must be START:STOP:NUM (or log:START:STOP:NUM)")
        a, b = (_num(p, arg, "range end") for p in parts[:2])
        return np.linspace(a, b, _count(parts[2], arg))
    if s.startswith("["):
        try:
            items = json.loads(s)
        except json.JSONDecodeError:
            raise InputError(arg, f"list {spec!r} is not a list of numbers like [0.5, 1, 2]") from None
        if not isinstance(items, list) or not items:
            raise InputError(arg, f"list {spec!r} must be a non-empty list of numbers")
        vals = [_num(json.dumps(v) if not isinstance(v, str) else v, arg, "list item") for v in items]
    else:
        vals = [_num(p.strip(), arg, "value") for p in s.split(",")]
    if len(vals) > MAX_POINTS:
        raise InputError(arg, f"at most {MAX_POINTS} values")
    return np.asarray(vals, float)


def parse_param(text: str, arg: str = "--param") -> ParamSpec:
    """``NAME=SPEC`` -> :class:`ParamSpec` (name not yet checked against a config)."""
    if "=" not in text:
        raise InputError(arg, f"{text!r} must be NAME=VALUES, e.g. spacing=1:4:7 or rig.lengths.0=[2,3]")
    name, spec = text.split("=", 1)
    name = name.strip()
    if not name:
        raise InputError(arg, f"{text!r} has no parameter name before '='")
    return ParamSpec(name, tuple(float(v) for v in parse_values(spec, arg)))


def parse_bounds(text: str, arg: str = "--param") -> tuple[str, float, float]:
    """``NAME=LO:HI`` -> (name, lo, hi) for :mod:`bifilar.studies.plan`."""
    if "=" not in text:
        raise InputError(arg, f"{text!r} must be NAME=LO:HI, e.g. spacing=1:4.8")
    name, spec = (p.strip() for p in text.split("=", 1))
    parts = spec.split(":")
    if not name or len(parts) != 2:
        raise InputError(arg, f"{text!r} must be NAME=LO:HI, e.g. spacing=1:4.8")
    lo, hi = (_num(p, arg, "bound") for p in parts)
    if not lo < hi:
        raise InputError(arg, f"{name}: lower bound {lo:g} must be below the upper bound {hi:g}")
    return name, lo, hi


# --------------------------------------------------------------------------
# dotted paths


def _tokens(path: str) -> list[str]:
    toks = path.split(".")
    if any(t == "" for t in toks):
        raise InputError("--param", f"{path!r} is not a dotted path (empty component)")
    return toks


def _walk(cfg: Any, toks: list[str], path: str, create: bool):
    """Return (container, key) of the leaf at ``toks``."""
    node = cfg
    for depth, t in enumerate(toks):
        last = depth == len(toks) - 1
        where = ".".join(toks[:depth]) or "config"
        if isinstance(node, dict):
            key: Any = t
            if key not in node:
                if create:
                    if last:
                        return node, key
                    node[key] = {}
                else:
                    import difflib

                    hint = difflib.get_close_matches(t, [str(k) for k in node], n=1)
                    extra = f"; did you mean '{hint[0]}'?" if hint else f"; keys there: {', '.join(map(str, node)) or 'none'}"
                    raise InputError("--param", f"{path}: no key '{t}' in {where}{extra}")
        elif isinstance(node, list):
            if not re.fullmatch(r"\d+", t):
                raise InputError("--param", f"{path}: {where} is a list; address its items by 0-based index, not '{t}'")
            key = int(t)
            if key >= len(node):
                raise InputError("--param", f"{path}: index {key} out of range ({where} has {len(node)} items)")
        else:
            raise InputError("--param", f"{path}: {where} is a single value, it has no '{t}'")
        if last:
            return node, key
        node = node[key]
    raise InputError("--param", f"{path}: empty path")  # pragma: no cover - toks is never empty


def get_path(cfg: Any, path: str) -> Any:
    """The value at a dotted path of a config mapping."""
    node, key = _walk(cfg, _tokens(path), path, create=False)
    return node[key]


def set_path(cfg: dict, path: str, value: float) -> None:
    """Set a numeric leaf in place (the leaf must exist and be a number,
    except under ``uncertainty``, whose leaves may be new)."""
    toks = _tokens(path)
    create = toks[0] in _CREATABLE
    node, key = _walk(cfg, toks, path, create=create)
    if isinstance(node, dict) and key not in node:
        node[key] = float(value)
        return
    old = node[key]
    if isinstance(old, bool) or not isinstance(old, (int, float)):
        kind = "a list" if isinstance(old, list) else "a mapping" if isinstance(old, dict) else type(old).__name__
        raise InputError("--param", f"{path} is {kind}, not a number; address a single number (e.g. {path}.0)")
    node[key] = float(value)


#: shorthand -> (the config list it edits after every dotted path, the coordinates of each item it moves
#: (None: the item itself), how)
_MOVES = {"length": ("rig.lengths", None, "every wire shifted by the same amount"),
          "length_offset": ("rig.lengths", None, "the lengths replaced about their mean"),
          "spacing": ("rig.attachments", (0, 1), "scaled about their centroid"),
          "ceiling_spacing": ("rig.anchors", (0, 1), "scaled about their centroid"),
          "height": ("rig.attachments", (2,), "every attachment raised by the same amount")}


def overlap_warnings(names) -> list[str]:
    """One line per swept dotted path that a shorthand swept with it moves
    afterwards (:func:`apply_params` applies the shorthands after every
    dotted path): ``rig.lengths.0`` with ``length`` (every wire shifted to
    the mean) or ``length_offset`` (the lengths replaced), a horizontal
    ``rig.attachments.I.0``/``.1`` with ``spacing`` (scaled about the
    centroid), ``rig.attachments.I.2`` with ``height``, ``rig.anchors.I.0``/
    ``.1`` with ``ceiling_spacing``.  Such a point's ``params`` value of the
    path is the one before the shorthand, not the built rig's (audit17:
    ``--param length=1:2:2 --param rig.lengths.0=1.2:1.4:2`` labelled a
    point ``rig.lengths.0: 1.2`` whose wire 1 was 0.85 m); its ``lengths``
    and ``rig`` give the built one."""
    out = []
    for n in names:
        toks = n.split(".")
        for s in names:
            if s not in _MOVES or toks[:2] != _MOVES[s][0].split("."):
                continue
            _, coords, how = _MOVES[s]
            if coords is not None and not (len(toks) == 4 and toks[3].isdigit() and int(toks[3]) in coords):
                continue
            out.append(f"--param: {n} is set before {s}, which then moves it ({how}): "
                       f"a point's {n} is the value before that move, not the built rig's (read each point's "
                       "lengths and rig, or sweep one of the two)")
    return out


def is_shorthand(name: str) -> bool:
    return name in SHORTHANDS


def check_param(cfg: dict, name: str, values=()) -> None:
    """Raise :class:`InputError` (``--param``) if ``name`` cannot be swept on
    ``cfg`` or one of ``values`` is out of its range (``uncertainty.KEY``:
    a known key, values not negative; ``plan.*`` settings are options, not
    sweep parameters)."""
    head = name.split(".")
    if head[0] == "uncertainty":
        from ..estimation.sensitivity import PLANNER_UNCERTAINTY_KEYS, uncertainty_too_large

        if len(head) != 2 or head[1] not in PLANNER_UNCERTAINTY_KEYS:
            raise InputError("--param", f"{name}: use uncertainty.KEY with KEY one of "
                                        f"{', '.join(PLANNER_UNCERTAINTY_KEYS)}")
        bad = [v for v in values if v < 0]
        if bad:
            raise InputError("--param", f"{name}: a standard uncertainty must not be negative, got {bad[0]:g}")
        too_large = [uncertainty_too_large(head[1], v) for v in values]
        if any(too_large):
            raise InputError("--param", f"{name}: {next(t for t in too_large if t)}")
        return
    if head[0] == "plan":
        raise InputError("--param", f"{name}: the plan block holds options (target, constraints, amplitude), "
                                    "not sweep parameters; give them as options, or sweep the amplitude shorthand")
    if name in ("amplitude", "stiffness") and any(v <= 0 for v in values):
        raise InputError("--param", f"{name} must be positive, got {min(values):g}")
    if is_shorthand(name):
        rig = cfg.get("rig") if isinstance(cfg, dict) else None
        if name in ("spacing", "ceiling_spacing", "height") and not isinstance(rig, dict):
            raise InputError("--param", f"{name} needs a rig")
        return
    if "." not in name and name not in (cfg or {}):
        import difflib

        hint = difflib.get_close_matches(name, list(SHORTHANDS) + [str(k) for k in (cfg or {})], n=1)
        extra = f"; did you mean '{hint[0]}'?" if hint else ""
        raise InputError("--param", f"unknown parameter '{name}'{extra} (shorthands: {', '.join(SHORTHANDS)}; "
                                    "or a dotted config path like rig.lengths.0)")
    trial = copy.deepcopy(cfg)
    set_path(trial, name, 1.0)


# --------------------------------------------------------------------------
# shorthands


def _points(cfg: dict, key: str) -> np.ndarray:
    try:
        return np.asarray(cfg["rig"][key], float).reshape(-1, 3)
    except (KeyError, TypeError, ValueError):
        raise InputError(f"rig.{key}", "must be a list of [x, y, z] points to apply a spacing shorthand") from None


def _spacing(pts: np.ndarray) -> float:
    c = pts.mean(axis=0)
    if len(pts) == 2:
        return float(np.linalg.norm(pts[1, :2] - pts[0, :2]))
    return float(2 * np.mean(np.linalg.norm(pts[:, :2] - c[:2], axis=1)))


def _set_spacing(cfg: dict, key: str, value: float, name: str) -> None:
    pts = _points(cfg, key)
    cur = _spacing(pts)
    if cur <= 1e-12:
        raise InputError("--param", f"{name}: the {key} coincide horizontally; there is no spacing to scale")
    c = pts.mean(axis=0)
    new = pts.copy()
    new[:, :2] = c[:2] + (pts[:, :2] - c[:2]) * (value / cur)
    cfg["rig"][key] = new.tolist()


def _lengths(cfg: dict) -> np.ndarray:
    try:
        return np.asarray(cfg["rig"]["lengths"], float).reshape(-1)
    except (KeyError, TypeError, ValueError):
        raise InputError("rig.lengths", "must be a list of numbers to apply a length shorthand") from None


def _rotate_cfg(cfg: dict, R: np.ndarray, base_scene) -> None:
    """Turn the body by R (world axes = body axes before hanging)."""
    from ..parts import part_from_dict
    from ..rotations import matrix_to_rotvec

    body = cfg.get("body") or {}
    rig = cfg.get("rig") or {}
    if "attachments" in rig:
        rig["attachments"] = (_points(cfg, "attachments") @ R.T).tolist()
    if "parts" in body:
        new_parts = []
        for i, d in enumerate(body["parts"]):
            part = part_from_dict(d, f"body.parts.{i}")
            nd = {k: v for k, v in d.items() if k not in ("axis", "rotation")}
            nd["position"] = (R @ np.asarray(part.position, float)).tolist()
            nd["rotation"] = matrix_to_rotvec(R @ part.rotation_matrix).tolist()
            new_parts.append(nd)
        body["parts"] = new_parts
    elif base_scene is not None:
        body["inertia"] = {"tensor": (R @ base_scene.inertia @ R.T).tolist()}
    if isinstance(body.get("bounding_box"), dict):
        lo = np.asarray(body["bounding_box"]["min"], float)
        hi = np.asarray(body["bounding_box"]["max"], float)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) @ R.T
        body["bounding_box"] = {"min": corners.min(axis=0).tolist(), "max": corners.max(axis=0).tolist()}


def _scene(cfg: dict, source: str):
    from ..config import scene_from_dict

    return scene_from_dict(cfg, source)


def apply_params(base_cfg: dict, params: dict[str, float], source: str = "config") -> tuple[dict, float | None]:
    """Edited deep copy of ``base_cfg`` and the point's amplitude override.

    ``params`` maps parameter names to values (see the module docstring for
    units and order).  Raises :class:`~bifilar.errors.InputError` (or
    :class:`~bifilar.errors.ConfigErrors` when a shorthand needs the scene of
    an already invalid config).
    """
    cfg = copy.deepcopy(base_cfg)
    amplitude = None
    for name, v in params.items():
        if not is_shorthand(name):
            set_path(cfg, name, v)
    for name in _ORDER:
        if name not in params:
            continue
        v = float(params[name])
        if name == "length":
            L = _lengths(cfg)
            cfg["rig"]["lengths"] = (L - L.mean() + v).tolist()
        elif name == "length_offset":
            L = _lengths(cfg)
            n = len(L)
            frac = np.arange(n) / max(n - 1, 1) - 0.5 if n > 1 else np.zeros(1)
            cfg["rig"]["lengths"] = (L.mean() + v * frac).tolist()
        elif name in ("spacing", "ceiling_spacing"):
            _set_spacing(cfg, "attachments" if name == "spacing" else "anchors", v, name)
        elif name == "height":
            pts = _points(cfg, "attachments")
            com_z = 0.0
            if (cfg.get("rig") or {}).get("attachments_frame") == "parts":
                com_z = float(_scene(cfg, source).parts_com[2])
            pts[:, 2] += v - (pts[:, 2].mean() - com_z)
            cfg["rig"]["attachments"] = pts.tolist()
    if "stiffness" in params:
        v = float(params["stiffness"])
        if not isinstance(cfg.get("rig"), dict):
            raise InputError("--param", "stiffness needs a rig")
        cfg["rig"]["stiffness"] = v  # a bad value is the config's error (rig.stiffness), as a dotted path's
    rots = [(n, params[n]) for n in params if n.startswith("rotate_")]
    if rots:
        from ..rotations import rotvec_to_matrix

        R = np.eye(3)
        for name, v in rots:
            axis = np.eye(3)["xyz".index(name[7])]
            ang = math.radians(v) if name.endswith("_deg") else float(v)
            R = rotvec_to_matrix(ang * axis) @ R
        body = cfg.get("body") or {}
        base_scene = None if "parts" in body else _scene(cfg, source)
        _rotate_cfg(cfg, R, base_scene)
    if "amplitude" in params:
        amplitude = float(params["amplitude"])
    return cfg, amplitude


def base_value(cfg: dict, name: str, source: str = "config", amplitude: float | None = None) -> float | None:
    """The value a parameter has in the unedited config (None if undefined)."""
    try:
        if not is_shorthand(name):
            v = get_path(cfg, name)
            return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None
        if name == "amplitude":
            return amplitude
        if name == "stiffness":  # the config's one EA (a list of equal ones counts as one), else none
            ea = (cfg.get("rig") or {}).get("stiffness")
            ea = np.asarray(ea if ea is not None else [], float).reshape(-1)
            return float(ea[0]) if ea.size and np.all(ea == ea[0]) else None
        if name.startswith("rotate_"):
            return 0.0
        if name == "length":
            return float(_lengths(cfg).mean())
        if name == "length_offset":
            L = _lengths(cfg)
            return float(L[-1] - L[0])
        if name in ("spacing", "ceiling_spacing"):
            return _spacing(_points(cfg, "attachments" if name == "spacing" else "anchors"))
        if name == "height":
            pts = _points(cfg, "attachments")
            com_z = 0.0
            if (cfg.get("rig") or {}).get("attachments_frame") == "parts":
                com_z = float(_scene(cfg, source).parts_com[2])
            return float(pts[:, 2].mean() - com_z)
    except InputError:
        return None
    return None


def param_unit(name: str) -> str:
    """Unit of a parameter for labels ("" when unknown)."""
    if name in SHORTHANDS:
        return SHORTHANDS[name][0]
    head = name.split(".")
    if head[0] == "rig" and len(head) > 1 and head[1] in ("anchors", "attachments", "lengths"):
        return "m"
    if head[0] == "rig" and len(head) > 1 and head[1] == "stiffness":
        return "N"
    if name == "body.mass" or name.endswith(".mass"):
        return "kg"
    if name == "gravity":
        return "m/s^2"
    if head[0] == "body" and "inertia" in head:
        return "kg m^2"
    return ""
