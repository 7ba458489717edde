"""Rigid-body primitives and their composition (thesis section 3).

A body is modelled as a list of :class:`Part` objects, each a homogeneous
primitive (or a point mass) with a mass, a centre of mass and an orientation
in a common *build frame*.  :func:`composite` adds them up with the
parallel-axis theorem; :func:`support` gives the extent of the union of the
parts in any direction (e.g. the lowest point of a hanging body).

Units are SI throughout: kg, m, kg m^2, radians.

Frames
------
build frame
    The frame the body is described in (for the Solar Boat: x along the boat,
    bow +x; y to port; z up; origin on the deck plane at mid-length).  Every
    position, inertia tensor, axis and direction accepted or returned by this
    module is in build-frame components unless stated otherwise.
part frame
    Attached to one part, origin at the part's centre of mass.  Cylinders and
    beams have their symmetry axis along the part-frame z axis; a box has its
    edges ``size = [lx, ly, lz]`` along the part-frame x, y, z axes.
    ``Part.rotation`` is the 3x3 matrix ``R`` whose columns are the part-frame
    axes in build-frame components (``x_build = position + R @ x_part``).

Config format (one mapping per part, see :func:`part_from_dict`)::

    {name: hull, shape: hollow_cylinder, mass: 30.0, outer_radius: 0.25,
     inner_radius: 0.24, length: 5.6, position: [0, 0, -0.3], axis: [1, 0, 0]}

Orientation is given by ``axis: [x, y, z]`` (cylinders and beams: the
direction of the symmetry axis, normalised here) or by
``rotation: [rx, ry, rz]`` (a rotation vector in radians, part frame ->
build frame); by default the part axes are the build axes.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar, Union

import numpy as np

from .errors import InputError
from .rotations import rotvec_to_matrix

__all__ = [
    "PartError",
    "SHAPES",
    "SolidCylinder",
    "HollowCylinder",
    "Box",
    "SolidSphere",
    "HollowSphere",
    "SlenderBeam",
    "PointMass",
    "Part",
    "Composite",
    "solid_cylinder",
    "hollow_cylinder",
    "box",
    "solid_sphere",
    "hollow_sphere",
    "slender_beam",
    "point_mass",
    "part_from_dict",
    "parts_from_list",
    "part_inertia",
    "transform_part",
    "composite",
    "support",
    "axis_rotation",
]


# --------------------------------------------------------------------------
# errors


class PartError(InputError):
    """An invalid part description.

    Attributes
    ----------
    path : str
        Dotted path of the offending entry, e.g. ``"body.parts.2.radius"``
        (the same string is also available as ``field``, as for every
        :class:`~bifilar.errors.InputError`).
    message : str
        What is wrong and what was expected.

    ``str(err)`` is ``"<path>: <message>"``.
    """

    def __init__(self, path: str, message: str):
        self.path = path
        super().__init__(path, message)


# --------------------------------------------------------------------------
# geometries (shape and size only; mass and placement live in Part)
#
# Each geometry provides, in its own part frame with origin at the CoM:
#   unit_inertia() -> (3,) principal moments per kg of mass (m^2)
#   local_support(d) -> max over the shape's points u of u . d, d (k, 3)


@dataclass(frozen=True)
class SolidCylinder:
    """Homogeneous solid cylinder, symmetry axis along part z.

    ``radius`` and ``length`` in m."""

    radius: float
    length: float
    shape: ClassVar[str] = "solid_cylinder"
    axisymmetric: ClassVar[bool] = True

    def unit_inertia(self) -> np.ndarray:
        r2, l2 = self.radius**2, self.length**2
        t = (3.0 * r2 + l2) / 12.0
        return np.array([t, t, 0.5 * r2])

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return 0.5 * self.length * np.abs(d[:, 2]) + self.radius * np.hypot(d[:, 0], d[:, 1])


@dataclass(frozen=True)
class HollowCylinder:
    """Homogeneous thick-walled tube, symmetry axis along part z.

    ``outer_radius``, ``inner_radius`` (0 <= inner < outer) and ``length`` in m.
    """

    outer_radius: float
    inner_radius: float
    length: float
    shape: ClassVar[str] = "hollow_cylinder"
    axisymmetric: ClassVar[bool] = True

    def unit_inertia(self) -> np.ndarray:
        s = self.outer_radius**2 + self.inner_radius**2
        t = (3.0 * s + self.length**2) / 12.0
        return np.array([t, t, 0.5 * s])

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return 0.5 * self.length * np.abs(d[:, 2]) + self.outer_radius * np.hypot(d[:, 0], d[:, 1])


@dataclass(frozen=True)
class Box:
    """Homogeneous rectangular block (a plate is a thin box).

    ``size = (lx, ly, lz)``: edge lengths along the part axes, m."""

    size: tuple[float, float, float]
    shape: ClassVar[str] = "box"
    axisymmetric: ClassVar[bool] = False

    def unit_inertia(self) -> np.ndarray:
        lx2, ly2, lz2 = (s * s for s in self.size)
        return np.array([ly2 + lz2, lx2 + lz2, lx2 + ly2]) / 12.0

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return np.abs(d) @ (0.5 * np.asarray(self.size, dtype=float))


@dataclass(frozen=True)
class SolidSphere:
    """Homogeneous solid ball of ``radius`` m."""

    radius: float
    shape: ClassVar[str] = "solid_sphere"
    axisymmetric: ClassVar[bool] = False

    def unit_inertia(self) -> np.ndarray:
        return np.full(3, 0.4 * self.radius**2)

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return self.radius * np.linalg.norm(d, axis=1)


@dataclass(frozen=True)
class HollowSphere:
    """Homogeneous spherical shell, ``0 <= inner_radius <= outer_radius`` (m).

    ``inner_radius == outer_radius`` is the thin-shell limit (2/3 m R^2)."""

    outer_radius: float
    inner_radius: float
    shape: ClassVar[str] = "hollow_sphere"
    axisymmetric: ClassVar[bool] = False

    def unit_inertia(self) -> np.ndarray:
        # 2/5 (R^5 - r^5)/(R^3 - r^3) with the common factor (R - r) divided
        # out analytically: no 0/0 at the thin-shell limit r = R.
        R, r = self.outer_radius, self.inner_radius
        num = R**4 + R**3 * r + R**2 * r**2 + R * r**3 + r**4
        den = R**2 + R * r + r**2
        return np.full(3, 0.4 * num / den)

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return self.outer_radius * np.linalg.norm(d, axis=1)


@dataclass(frozen=True)
class SlenderBeam:
    """Thin rod of ``length`` m along part z (no cross-section)."""

    length: float
    shape: ClassVar[str] = "slender_beam"
    axisymmetric: ClassVar[bool] = True

    def unit_inertia(self) -> np.ndarray:
        t = self.length**2 / 12.0
        return np.array([t, t, 0.0])

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return 0.5 * self.length * np.abs(d[:, 2])


@dataclass(frozen=True)
class PointMass:
    """A point mass (no extent)."""

    shape: ClassVar[str] = "point_mass"
    axisymmetric: ClassVar[bool] = False

    def unit_inertia(self) -> np.ndarray:
        return np.zeros(3)

    def local_support(self, d: np.ndarray) -> np.ndarray:
        return np.zeros(d.shape[0])


Geometry = Union[SolidCylinder, HollowCylinder, Box, SolidSphere, HollowSphere, SlenderBeam, PointMass]


# --------------------------------------------------------------------------
# parts


def _as_tuple3(v) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=float).reshape(3)
    return (float(a[0]), float(a[1]), float(a[2]))


@dataclass(frozen=True)
class Part:
    """One rigid primitive placed in the build frame.

    Attributes
    ----------
    name : str
        Label (free text).
    mass : float
        kg, > 0.
    position : tuple of 3 floats
        Centre of mass in the build frame, m.
    rotation : 3x3 tuple of tuples
        ``R`` with the part-frame axes as columns, in build-frame components
        (part frame -> build frame).  For cylinders and beams the symmetry
        axis is the third column.
    geometry : one of the geometry dataclasses
        Shape and size (m).
    """

    name: str
    mass: float
    position: tuple[float, float, float]
    rotation: tuple[tuple[float, float, float], ...]
    geometry: Geometry

    @property
    def shape(self) -> str:
        """Shape name as used in configs (``"solid_cylinder"``, ...)."""
        return self.geometry.shape

    @property
    def position_array(self) -> np.ndarray:
        """Centre of mass, build frame, m, as a new (3,) array."""
        return np.array(self.position, dtype=float)

    @property
    def rotation_matrix(self) -> np.ndarray:
        """Part frame -> build frame rotation matrix, as a new (3, 3) array."""
        return np.array(self.rotation, dtype=float)

    @property
    def axis(self) -> np.ndarray:
        """Unit part-frame z axis in the build frame (the symmetry axis of a
        cylinder or beam), (3,)."""
        return self.rotation_matrix[:, 2]


def axis_rotation(axis) -> np.ndarray:
    """Rotation matrix (3, 3), part frame -> build frame, taking the part z
    axis onto ``axis`` (build-frame components, any non-zero length).

    It is the smallest such rotation (about ``e_z x axis``); for ``axis``
    along -z, a half turn about x.  Only its third column matters for
    axisymmetric parts.
    """
    a = np.asarray(axis, dtype=float).reshape(3)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n == 0.0:
        raise ValueError(f"axis must be a finite non-zero vector, got {a.tolist()}")
    a = a / n
    c = a[2]
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    # Rodrigues for the rotation e_z -> a:  R = I + [v]x + [v]x^2 / (1 + c)
    v = np.array([-a[1], a[0], 0.0])  # e_z x a
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    R = np.eye(3) + K + (K @ K) / (1.0 + c)
    R[:, 2] = a  # exact third column
    return R


# --------------------------------------------------------------------------
# validation helpers


def _join(path: str, key) -> str:
    return f"{path}.{key}" if path else str(key)


def _show(value) -> str:
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return repr(value)
    return str(value)


MAX_SIZE = 1e5
"""Largest part dimension or position coordinate, m (the 100 km of
``bifilar.config.LIMITS["length"]``): beyond it inertias overflow double
precision (1e200 m squared) long before a rig could be that large."""
MAX_ROTATION = 1e3
"""Largest rotation vector length, rad (about 160 turns): sin and cos of a
larger angle lose their digits, and of 1e308 overflow."""


def _bounded(x: float, path: str, limit: float, unit: str) -> float:
    """``x`` if ``|x| <= limit``, else a :class:`PartError` naming ``path``."""
    if abs(x) > limit:
        raise PartError(path, f"must be at most {limit:g} {unit} in magnitude, got {_show(x)}")
    return x


def _number(value, path: str, *, positive: bool = False, nonneg: bool = False) -> float:
    kind = "a positive number" if positive else ("a non-negative number" if nonneg else "a finite number")
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        hint = ""
        if isinstance(value, str):
            try:
                float(value)
                hint = " (a string: YAML 1.1 reads e.g. 1e-3 as text; write 1.0e-3)"
            except ValueError:
                pass
        raise PartError(path, f"must be {kind}, got {_show(value)}{hint}")
    x = float(value)
    if not math.isfinite(x):
        raise PartError(path, f"must be {kind}, got {_show(value)}")
    if positive and not x > 0.0:
        raise PartError(path, f"must be {kind}, got {_show(value)}")
    if nonneg and not x >= 0.0:
        raise PartError(path, f"must be {kind}, got {_show(value)}")
    return x


def _vector3(value, path: str) -> np.ndarray:
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, (Sequence, np.ndarray)):
        raise PartError(path, f"must be a list of 3 numbers [x, y, z], got {_show(value)}")
    items = list(np.asarray(value, dtype=object).reshape(-1)) if isinstance(value, np.ndarray) else list(value)
    if len(items) != 3:
        raise PartError(path, f"must be a list of 3 numbers [x, y, z], got {len(items)} item(s)")
    return np.array([_number(v, _join(path, i)) for i, v in enumerate(items)])


def _suggest(word, candidates: Iterable[str], aliases: Mapping[str, str] | None = None) -> str:
    if not isinstance(word, str):
        return ""
    pool = {c: c for c in candidates}
    if aliases:
        pool.update(aliases)
    hit = difflib.get_close_matches(word.lower(), list(pool), n=1, cutoff=0.6)
    return f"; did you mean '{pool[hit[0]]}'?" if hit else ""


# --------------------------------------------------------------------------
# shape table: required dimension keys, optional orientation keys

_DIMS: dict[str, tuple[str, ...]] = {
    "solid_cylinder": ("radius", "length"),
    "hollow_cylinder": ("outer_radius", "inner_radius", "length"),
    "box": ("size",),
    "solid_sphere": ("radius",),
    "hollow_sphere": ("outer_radius", "inner_radius"),
    "slender_beam": ("length",),
    "point_mass": (),
}
SHAPES: tuple[str, ...] = tuple(_DIMS)
_AXISYMMETRIC = {"solid_cylinder", "hollow_cylinder", "slender_beam"}
_COMMON = ("name", "shape", "mass", "position", "rotation")
# Words people naturally type for a shape -> the shape to suggest.
_SHAPE_ALIASES = {
    "cylinder": "solid_cylinder",
    "disc": "solid_cylinder",
    "disk": "solid_cylinder",
    "tube": "hollow_cylinder",
    "pipe": "hollow_cylinder",
    "plate": "box",
    "block": "box",
    "cuboid": "box",
    "sphere": "solid_sphere",
    "ball": "solid_sphere",
    "shell": "hollow_sphere",
    "beam": "slender_beam",
    "rod": "slender_beam",
    "point": "point_mass",
    "mass": "point_mass",
}


def _allowed_keys(shape: str) -> tuple[str, ...]:
    keys = _COMMON + _DIMS[shape]
    if shape in _AXISYMMETRIC:
        keys += ("axis",)
    return keys


def _build(fields: Mapping, path: str) -> Part:
    """Validate a part description (mapping) and build the Part."""
    if not isinstance(fields, Mapping):
        raise PartError(path, f"a part must be a mapping with keys shape, mass, ..., got {_show(fields)}")
    if "shape" not in fields:
        raise PartError(_join(path, "shape"), f"missing required key 'shape' (one of: {', '.join(SHAPES)})")
    shape = fields["shape"]
    if not isinstance(shape, str) or shape not in _DIMS:
        raise PartError(
            _join(path, "shape"),
            f"unknown shape {_show(shape)}{_suggest(shape, SHAPES, _SHAPE_ALIASES)} "
            f"(known shapes: {', '.join(SHAPES)})",
        )
    allowed = _allowed_keys(shape)
    for key in fields:
        if key not in allowed:
            msg = f"unknown key {_show(key)} for shape {shape}{_suggest(key, allowed)}"
            if key == "axis":
                msg += "; orient this shape with rotation: [rx, ry, rz] (rad)"
            raise PartError(_join(path, key), msg + f" (allowed: {', '.join(allowed)})")
    for key in ("mass",) + _DIMS[shape]:
        if key not in fields:
            raise PartError(_join(path, key), f"missing required key for shape {shape}")

    name = fields.get("name", shape)
    if not isinstance(name, str):
        raise PartError(_join(path, "name"), f"must be a string, got {_show(name)}")
    mass = _number(fields["mass"], _join(path, "mass"), positive=True)
    position = _vector3(fields.get("position", (0.0, 0.0, 0.0)), _join(path, "position"))
    for i, v in enumerate(position):
        _bounded(v, _join(_join(path, "position"), i), MAX_SIZE, "m")

    if "axis" in fields and "rotation" in fields:
        raise PartError(_join(path, "axis"), "give either axis or rotation, not both")
    if "axis" in fields:
        axis = _vector3(fields["axis"], _join(path, "axis"))
        n = float(np.linalg.norm(axis))
        if not n > 0.0 or not math.isfinite(n):
            raise PartError(_join(path, "axis"), f"must be a non-zero direction, got {axis.tolist()}")
        R = axis_rotation(axis)
    elif "rotation" in fields:
        rv = _vector3(fields["rotation"], _join(path, "rotation"))
        for i, v in enumerate(rv):
            _bounded(v, _join(_join(path, "rotation"), i), MAX_ROTATION, "rad")
        R = rotvec_to_matrix(rv)
    else:
        R = np.eye(3)

    def dim(key, **kw):
        return _bounded(_number(fields[key], _join(path, key), **kw), _join(path, key), MAX_SIZE, "m")

    if shape == "solid_cylinder":
        geom: Geometry = SolidCylinder(dim("radius", positive=True), dim("length", positive=True))
    elif shape == "hollow_cylinder":
        ro = dim("outer_radius", positive=True)
        ri = dim("inner_radius", nonneg=True)
        if not ri < ro:
            raise PartError(
                _join(path, "inner_radius"),
                f"must be less than outer_radius ({_show(ro)}), got {_show(fields['inner_radius'])}",
            )
        geom = HollowCylinder(ro, ri, dim("length", positive=True))
    elif shape == "box":
        size_path = _join(path, "size")
        _vector3(fields["size"], size_path)  # shape and finiteness
        size = tuple(_bounded(_number(v, _join(size_path, i), positive=True), _join(size_path, i), MAX_SIZE, "m")
                     for i, v in enumerate(fields["size"]))
        geom = Box(size)  # type: ignore[arg-type]
    elif shape == "solid_sphere":
        geom = SolidSphere(dim("radius", positive=True))
    elif shape == "hollow_sphere":
        ro = dim("outer_radius", positive=True)
        ri = dim("inner_radius", nonneg=True)
        if not ri <= ro:
            raise PartError(
                _join(path, "inner_radius"),
                f"must not exceed outer_radius ({_show(ro)}), got {_show(fields['inner_radius'])}",
            )
        geom = HollowSphere(ro, ri)
    elif shape == "slender_beam":
        geom = SlenderBeam(dim("length", positive=True))
    else:
        geom = PointMass()

    return Part(
        name=name,
        mass=mass,
        position=_as_tuple3(position),
        rotation=tuple(_as_tuple3(row) for row in R),
        geometry=geom,
    )


def _kw(shape, mass, position, axis, rotation, name, **dims) -> dict:
    d = {"shape": shape, "mass": mass, "position": position, "name": name if name is not None else shape}
    d.update(dims)
    if axis is not None:
        d["axis"] = axis
    if rotation is not None:
        d["rotation"] = rotation
    return d


# --------------------------------------------------------------------------
# constructors (validate like part_from_dict; error paths are argument names)


def solid_cylinder(mass, radius, length, position=(0.0, 0.0, 0.0), *, axis=None, rotation=None, name=None) -> Part:
    """Homogeneous solid cylinder.

    mass kg; radius, length m; position = centre of mass, build frame, m;
    axis = symmetry-axis direction in the build frame (default +z) or
    rotation = rotation vector, rad, part -> build frame.
    Raises :class:`PartError` on invalid input."""
    return _build(_kw("solid_cylinder", mass, position, axis, rotation, name, radius=radius, length=length), "")


def hollow_cylinder(
    mass, outer_radius, inner_radius, length, position=(0.0, 0.0, 0.0), *, axis=None, rotation=None, name=None
) -> Part:
    """Homogeneous thick-walled tube, 0 <= inner_radius < outer_radius (m).

    mass kg; length m; position = centre of mass, build frame, m; axis /
    rotation as for :func:`solid_cylinder`."""
    return _build(
        _kw(
            "hollow_cylinder",
            mass,
            position,
            axis,
            rotation,
            name,
            outer_radius=outer_radius,
            inner_radius=inner_radius,
            length=length,
        ),
        "",
    )


def box(mass, size, position=(0.0, 0.0, 0.0), *, rotation=None, name=None) -> Part:
    """Homogeneous rectangular block; size = [lx, ly, lz] edge lengths, m,
    along the part axes (a plate is a thin box).

    mass kg; position = centre, build frame, m; rotation = rotation vector,
    rad, part -> build frame (default: edges along the build axes)."""
    return _build(_kw("box", mass, position, None, rotation, name, size=size), "")


def solid_sphere(mass, radius, position=(0.0, 0.0, 0.0), *, name=None) -> Part:
    """Homogeneous ball: mass kg, radius m, centre ``position`` (build frame, m)."""
    return _build(_kw("solid_sphere", mass, position, None, None, name, radius=radius), "")


def hollow_sphere(mass, outer_radius, inner_radius, position=(0.0, 0.0, 0.0), *, name=None) -> Part:
    """Homogeneous spherical shell, 0 <= inner_radius <= outer_radius (m);
    equal radii give the thin shell (I = 2/3 m R^2).  mass kg; centre
    ``position`` in the build frame, m."""
    return _build(
        _kw("hollow_sphere", mass, position, None, None, name, outer_radius=outer_radius, inner_radius=inner_radius),
        "",
    )


def slender_beam(mass, length, position=(0.0, 0.0, 0.0), *, axis=None, rotation=None, name=None) -> Part:
    """Thin rod: I = m L^2/12 about any transverse axis through its middle,
    0 about its own axis.  mass kg, length m; position = middle of the rod,
    build frame, m; axis / rotation as for :func:`solid_cylinder`."""
    return _build(_kw("slender_beam", mass, position, axis, rotation, name, length=length), "")


def point_mass(mass, position=(0.0, 0.0, 0.0), *, name=None) -> Part:
    """Point mass of ``mass`` kg at ``position`` (build frame, m)."""
    return _build(_kw("point_mass", mass, position, None, None, name), "")


def part_from_dict(d: Mapping, path: str = "") -> Part:
    """Build a :class:`Part` from a config mapping.

    Keys: ``shape`` (one of :data:`SHAPES`), ``mass`` (kg, > 0), the shape's
    dimensions in m (``radius``, ``length``, ``outer_radius``,
    ``inner_radius``, ``size: [lx, ly, lz]``), optional ``name``,
    ``position: [x, y, z]`` (centre of mass, build frame, m; default origin),
    and optionally one of ``axis: [x, y, z]`` (cylinders and beams: symmetry
    axis direction in the build frame, any non-zero length) or
    ``rotation: [rx, ry, rz]`` (rotation vector, rad, part -> build frame).

    ``path`` is the dotted location of ``d`` in the config (e.g.
    ``"body.parts.2"``); every problem raises :class:`PartError` whose
    ``path`` names the exact offending entry (``"body.parts.2.radius"``).
    """
    return _build(d, path)


def parts_from_list(items, path: str = "body.parts") -> tuple[Part, ...]:
    """Build the parts of a config list (``body.parts``); item ``i`` gets the
    path ``f"{path}.{i}"``.  Raises :class:`PartError` for the first invalid
    item, or for an empty / non-list value (at ``path``)."""
    if isinstance(items, (str, bytes, Mapping)) or not isinstance(items, Sequence):
        raise PartError(path, f"must be a list of parts, got {_show(items)}")
    if len(items) == 0:
        raise PartError(path, "must contain at least one part")
    return tuple(_build(item, _join(path, i)) for i, item in enumerate(items))


# --------------------------------------------------------------------------
# mass properties


def part_inertia(part: Part) -> np.ndarray:
    """Inertia tensor (3, 3), kg m^2, of ``part`` about its own centre of
    mass, in build-frame axes: ``R diag(I_part) R^T``."""
    R = part.rotation_matrix
    I = (R * (part.mass * part.geometry.unit_inertia())) @ R.T
    return 0.5 * (I + I.T)


def transform_part(part: Part, rotation, translation=(0.0, 0.0, 0.0)) -> Part:
    """The same part moved rigidly: ``x -> Q x + t`` in the build frame.

    ``rotation`` is a 3x3 rotation matrix ``Q`` or a rotation vector (3,),
    rad; ``translation`` ``t`` in m.  Returns a new :class:`Part` with
    position ``Q p + t`` and orientation ``Q R``."""
    Q = np.asarray(rotation, dtype=float)
    if Q.shape == (3,):
        Q = rotvec_to_matrix(Q)
    if Q.shape != (3, 3) or not np.allclose(Q @ Q.T, np.eye(3), atol=1e-9) or np.linalg.det(Q) < 0:
        raise ValueError("rotation must be a proper rotation matrix (3, 3) or a rotation vector (3,)")
    p = Q @ part.position_array + np.asarray(translation, dtype=float).reshape(3)
    R = Q @ part.rotation_matrix
    return Part(part.name, part.mass, _as_tuple3(p), tuple(_as_tuple3(r) for r in R), part.geometry)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Composite:
    """Mass properties of a set of parts (arrays are read-only).

    Attributes
    ----------
    mass : float
        Total mass, kg.
    com : (3,) array
        Centre of mass, build frame, m.
    inertia : (3, 3) array
        Inertia tensor about ``com``, build-frame axes, kg m^2 (symmetric).
    principal_moments : (3,) array
        Eigenvalues of ``inertia``, ascending, kg m^2.
    principal_axes : (3, 3) array
        Matching unit eigenvectors as columns, build-frame components,
        forming a right-handed frame (det = +1); each of the first two
        columns has its largest-magnitude component positive.
        ``inertia == axes @ diag(moments) @ axes.T``.
    parts : tuple of Part
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    parts: tuple[Part, ...]

    def inertia_about(self, point) -> np.ndarray:
        """Inertia tensor (3, 3), kg m^2, about ``point`` (build frame, m),
        build-frame axes (parallel-axis theorem)."""
        r = np.asarray(point, dtype=float).reshape(3) - self.com
        return self.inertia + self.mass * (np.dot(r, r) * np.eye(3) - np.outer(r, r))


def composite(parts: Iterable[Part]) -> Composite:
    """Total mass (kg), centre of mass (build frame, m) and inertia tensor
    about that centre of mass (build axes, kg m^2) of ``parts``, by the
    parallel-axis theorem, plus its principal moments (ascending) and axes
    (columns, right-handed)."""
    parts = tuple([parts] if isinstance(parts, Part) else parts)
    if not parts:
        raise ValueError("composite() needs at least one part")
    m = np.array([p.mass for p in parts])
    c = np.array([p.position for p in parts])  # (n, 3)
    M = float(m.sum())
    com = (m @ c) / M
    r = c - com
    own = sum(part_inertia(p) for p in parts)
    shift = np.eye(3) * float(m @ np.einsum("ij,ij->i", r, r)) - np.einsum("i,ij,ik->jk", m, r, r)
    I = own + shift
    I = 0.5 * (I + I.T)
    w, V = np.linalg.eigh(I)
    for k in range(3):
        j = int(np.argmax(np.abs(V[:, k])))
        if V[j, k] < 0:
            V[:, k] = -V[:, k]
    if np.linalg.det(V) < 0:
        V[:, 2] = -V[:, 2]
    return Composite(
        mass=M,
        com=_readonly(com),
        inertia=_readonly(I),
        principal_moments=_readonly(w),
        principal_axes=_readonly(V),
        parts=parts,
    )


def support(parts, direction) -> Union[float, np.ndarray]:
    """Support function of the union of ``parts``: max over all their points
    ``x`` (build frame, m) of ``x . d``.

    ``direction``: (3,) or (k, 3), build-frame components; it need not be a
    unit vector (the result scales with ``|d|`` beyond the ``c . d`` term).
    Returns a float for (3,), a (k,) array for (k, 3); units m * |d|.
    Exact for every primitive (cylinder: ``c.d + L/2 |a.d| + r |d - (a.d) a|``;
    box: max over the vertices; sphere: ``c.d + R|d|``; beam: its end points;
    point: ``c.d``).  For the lowest point of a body, ``-support(parts, e_z)``
    is the smallest z.  ``parts`` may be one Part or an iterable of them.
    """
    parts = tuple([parts] if isinstance(parts, Part) else parts)
    if not parts:
        raise ValueError("support() needs at least one part")
    d = np.asarray(direction, dtype=float)
    single = d.ndim == 1
    D = np.atleast_2d(d)
    if D.ndim != 2 or D.shape[1] != 3:
        raise ValueError(f"direction must have shape (3,) or (k, 3), got {d.shape}")
    best = np.full(D.shape[0], -np.inf)
    frames: dict = {}  # rotation -> the directions in that part frame: once for the parts that share it
    for p in parts:
        local = frames.get(p.rotation)
        if local is None:
            local = frames[p.rotation] = D @ p.rotation_matrix  # rows: R^T d, part-frame components
        h = D @ p.position_array + p.geometry.local_support(local)
        best = np.maximum(best, h)
    return float(best[0]) if single else best
