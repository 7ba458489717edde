"""The scene: a rigid body and the rig of wires that holds it.

Frames: world frame z up, gravity along -z (m).  Body frame with origin at
the body's centre of mass (CoM); the body's inertia tensor and attachment
points are given in it.  A :class:`Scene` is immutable and validated: build
it with :func:`bifilar.config.load_scene` or :func:`bifilar.config.scene_from_dict`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any, Callable, Optional

import numpy as np

from .rowwise import row_max


@dataclass(frozen=True)
class Scene:
    """A validated body-and-rig description, SI units.

    Attributes
    ----------
    name : str
    gravity : float
        Gravitational acceleration, m/s^2, acting along world -z.
    mass : float
        Body mass, kg.
    inertia : ndarray (3, 3)
        Inertia tensor about the CoM in body axes, kg m^2.
    anchors : ndarray (n, 3)
        Ceiling points, world frame, m.
    attachments : ndarray (n, 3)
        Body attachment points, body frame (origin at the CoM), m.
    lengths : ndarray (n,)
        Wire lengths, m.
    support : callable or None
        ``support(d) -> h``: for unit direction(s) ``d`` (k, 3) in body axes,
        the largest ``x . d`` over all points ``x`` of the body (body frame,
        m).  Used for the clearance (lowest point of the body).  ``None``
        means only the attachment points and the CoM are known (the CoM
        lies in the convex hull of the body's mass, so the body reaches at
        least as far as it in every direction).
    support_source : str
        Where ``support`` comes from: ``parts``, ``bounding_box`` or ``attachments``.
    config : dict
        The (normalised) config mapping the scene was built from; studies
        edit it by dotted path and rebuild.
    stiffness : ndarray (n,) or None
        The wires' axial stiffness EA, N (``rig.stiffness``); None: rigid
        wires.  Used by the rest pose of 4 or 5 wires (elastic statics,
        :mod:`bifilar.analysis.elastic_rest`).
    """

    name: str
    gravity: float
    mass: float
    inertia: np.ndarray
    anchors: np.ndarray
    attachments: np.ndarray
    lengths: np.ndarray
    support: Optional[Callable[[np.ndarray], np.ndarray]] = None
    support_source: str = "attachments"
    config: dict = field(default_factory=dict, compare=False, repr=False)
    parts_com: Optional[np.ndarray] = None  # CoM in the parts' build frame, if built from parts
    stiffness: Optional[np.ndarray] = None  # wires' axial stiffness EA (n,), N (rig.stiffness); None: rigid wires

    @property
    def n_wires(self) -> int:
        return int(self.lengths.shape[0])

    @property
    def dof(self) -> int:
        """Degrees of freedom of the body on taut inextensible wires (6 - n)."""
        return 6 - self.n_wires

    @property
    def ceiling_z(self) -> float:
        """Height of the highest anchor, m (world z)."""
        return float(np.max(self.anchors[:, 2]))

    def body_support(self, directions: np.ndarray) -> np.ndarray:
        """Support function of the body in body axes, m (see class docstring).

        At least the attachment points and the CoM (the body frame's origin,
        inside the convex hull of the body's mass: a body whose CoM hangs
        below its attachments reaches at least that low); those alone when
        no shape is known.
        """
        d = np.atleast_2d(np.asarray(directions, dtype=float))
        h_att = np.maximum(row_max(d @ self.attachments.T), 0.0)
        if self.support is None:
            return h_att
        return np.maximum(np.asarray(self.support(d), dtype=float), h_att)

    def with_changes(self, **kw: Any) -> "Scene":
        """This scene with some fields changed (:func:`scene_with`)."""
        return scene_with(self, **kw)



#: the fields of :class:`Scene`, in order (for :func:`scene_with`)
_SCENE_FIELDS = tuple(f.name for f in fields(Scene))
_SCENE_FIELD_SET = frozenset(_SCENE_FIELDS)


def scene_with(scene: Scene, **changes) -> Scene:
    """``dataclasses.replace(scene, **changes)`` for the many perturbed
    scenes of a sweep point (sigma points, finite differences, inertia
    steps): the same fields, set directly instead of through the frozen
    class's ``__init__`` (a fifth of the cost).  A subclass, or a name that
    is no field, goes to ``replace`` (its error)."""
    if type(scene) is not Scene or not changes.keys() <= _SCENE_FIELD_SET:
        return replace(scene, **changes)
    new = object.__new__(Scene)
    d, old = new.__dict__, scene.__dict__
    for name in _SCENE_FIELDS:
        d[name] = changes[name] if name in changes else old[name]
    return new


def lowest_point_z(scene: Scene, com: np.ndarray, R: np.ndarray) -> np.ndarray:
    """World z of the lowest point of the body, m.

    Parameters
    ----------
    com : (..., 3) CoM position(s), world frame, m.
    R : (..., 3, 3) rotation(s) body -> world.
    """
    return _reach_z(scene, com, R, -1.0)


def highest_point_z(scene: Scene, com: np.ndarray, R: np.ndarray) -> np.ndarray:
    """World z of the highest point of the body, m (arguments as
    :func:`lowest_point_z`)."""
    return _reach_z(scene, com, R, 1.0)


def _reach_z(scene: Scene, com, R, sign: float) -> np.ndarray:
    """World z of the body's farthest point along ``sign`` x world z, m."""
    com = np.asarray(com, float)
    R = np.asarray(R, float)
    along = sign * R[..., 2, :]  # world (sign) z expressed in body axes (rows of R^T)
    flat = along.reshape(-1, 3)
    h = scene.body_support(flat).reshape(along.shape[:-1])
    return com[..., 2] + sign * h


#: Relative allowance of the triangle inequality of the principal moments,
#: ``I1 + I2 >= (1 - TRIANGLE_SLACK) I3``, for values rounded to 5 significant
#: digits (each off by up to 5e-5 of itself, so ``I1 + I2 - I3`` by up to
#: ~1e-4 of I3): a thin plate sits exactly on the limit, and the README's
#: [208.33, 52.08, 260.42] is one.  The one rule of what a real body is: the
#: config loader accepts exactly the tensors `invert` calls admissible
#: (:func:`obeys_triangle`; ``bifilar.estimation.problem.admissible`` and
#: ``admissible_interval``).
TRIANGLE_SLACK = 1e-4
#: eigenvalues of a computed tensor are good to ~1e-16 of the largest: a
#: tensor on the limit (an estimate clamped to it) passes whatever its last bits
_TRIANGLE_ROUNDING = 1e-12


def obeys_triangle(principal: np.ndarray) -> bool:
    """The principal moments (kg m^2, ascending) obey the triangle
    inequality ``I1 + I2 >= I3`` within :data:`TRIANGLE_SLACK`."""
    ev = np.asarray(principal, float)
    return bool(ev[0] + ev[1] >= ev[2] * (1.0 - TRIANGLE_SLACK - _TRIANGLE_ROUNDING))
