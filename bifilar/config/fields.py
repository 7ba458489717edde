"""The schema of a config and the checks of its fields: allowed keys, hard
limits (:data:`LIMITS`), numbers and points (:class:`_Checker`, which
collects every problem, one line each, under its dotted path) and the rig's
geometry.  Part of :mod:`bifilar.config`.
"""

from __future__ import annotations

import difflib
import math
import re
from typing import Any

import numpy as np

from ..errors import InputError

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
RIG_KEYS = {"anchors", "attachments", "lengths", "attachments_frame", "stiffness"}


#: plain scalars YAML 1.1 reads as numbers other than the decimal ones they look like: base 60
#: (``1:30`` is 90, ``12:30`` 750) and a leading zero (``010`` is octal 8).  The config reader
#: (:mod:`.yaml_safe`) reads them as text, as YAML 1.2 reads the first: a number field then refuses
#: them naming the field, a name or a note keeps what was written.
_YAML11_SURPRISE = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?|0[0-7_]+)$")


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
            if isinstance(value, bool):  # YAML 1.1 reads yes/no, on/off, true/false as booleans
                self.error(path, f"must be a number, got a YAML boolean ({value!r}: yes/no, on/off and true/false "
                                 "are read so); write the number")
                return None
            if isinstance(value, str) and _YAML11_SURPRISE.match(value):
                hint = (" (YAML 1.1 reads it as a number in base 60 or, with its leading zero, octal; "
                        "write the number in plain decimal digits)")
            elif isinstance(value, str):
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
        return _stack([self.number(_join(path, i), v, **kw) for i, v in enumerate(value)])

    def vectors(self, path: str, value: Any, **kw: Any) -> np.ndarray | None:
        if not isinstance(value, (list, tuple)) or len(value) == 0:
            self.error(path, f"must be a non-empty list of [x, y, z] points, got {_describe(value)}")
            return None
        if len(value) > 100:
            self.error(path, f"must list one [x, y, z] point per wire (at most {MAX_WIRES}), got {len(value)} items")
            return None
        return _stack([self.vector(_join(path, i), v, **kw) for i, v in enumerate(value)])


def _stack(items: list) -> np.ndarray | None:
    """The checked items as one float array, or None when one failed its check."""
    return None if any(o is None for o in items) else np.asarray(items, dtype=float)


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


def _fmt(a: np.ndarray) -> str:
    return "[" + ", ".join(f"{x:.6g}" for x in np.atleast_1d(a)) + "]"


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
            for far, d_far, near, d_near in (("anchors", da, "attachments", dp), ("attachments", dp, "anchors", da)):
                reach = d_near + L[i] + L[j]
                if d_far > reach * (1 + 1e-12):
                    chk.error(
                        "rig.lengths",
                        f"wires {i + 1} and {j + 1} cannot reach: {far} {i + 1} and {j + 1} are {d_far:.6g} m apart "
                        f"but {near} {d_near:.6g} m apart plus wires {L[i]:.6g} + {L[j]:.6g} m only span {reach:.6g} "
                        f"m; lengthen them by {d_far - reach:.3g} m in total or move the {far} closer",
                    )
    if n >= 3:
        # all attachments on one line: nothing resists a rotation about it (anchors on a line are fine)
        c = p - p.mean(axis=0)
        sv = np.linalg.svd(c, compute_uv=False)
        if sv[1] <= 1e-9 * max(sv[0], tiny):
            chk.error("rig.attachments", f"all {n} attachments lie on one line: the body could spin freely "
                                         "about it; move one off the line")
