"""A two-wire scene in the thesis's five Kane angles (thesis section 5.1).

Maps a scene of :mod:`bifilar.scene` and its rest pose onto the parameters and
rest angles of :mod:`bifilar.models.kane`: wire 1 is B -> C, wire 2 D -> A, the
world turned about the vertical so that A - B lies along n2.  Used by the
thesis's section 7.1 linearisation (:mod:`bifilar.estimation.ladder`) and the
five-angle runs.  SI units (m, kg, rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import NotApplicable
from ..scene import Scene

@dataclass
class KaneMapping:
    """A two-wire scene in the thesis's Kane coordinates.

    params : KaneParams (inertia in the ntilde frame).  theta0 : rest angles, rad.
    C : (3, 3) columns ntilde_1..3 in the scene's body components.
    yaw : (3, 3) world -> thesis earth frame (a rotation about z putting the
    anchors along n2).
    """

    params: object
    theta0: np.ndarray
    C: np.ndarray
    yaw: np.ndarray


def kane_mapping(scene: Scene, rest) -> KaneMapping:
    """Express a two-wire scene and its rest pose in the thesis's angles.

    Wire 1 is B -> C (anchor 1, attachment 1, length l), wire 2 D -> A.
    ntilde_3 = -CD/b'; ntilde_1 is the direction of the CoM offset from C
    perpendicular to CD (or, with the CoM on CD, the downward vertical at
    rest); ntilde_2 = ntilde_3 x ntilde_1.  Raises :class:`NotApplicable`.
    """
    from ..models import kane

    if scene.n_wires != 2:
        raise NotApplicable("the thesis's Kane model has two wires")
    A0, B0 = scene.anchors[1], scene.anchors[0]
    Lmax = float(np.max(scene.lengths))
    if abs(A0[2] - B0[2]) > 1e-9 * Lmax:
        raise NotApplicable("the thesis's Kane model needs both anchors at one height")
    u = A0 - B0
    b = float(np.linalg.norm(u))
    u = u / b
    ex = np.cross(u, [0.0, 0.0, 1.0])
    yaw = np.array([ex, u, [0.0, 0.0, 1.0]])  # rows: new axes in world components
    pC, pD = scene.attachments[0], scene.attachments[1]
    bp = float(np.linalg.norm(pD - pC))
    if bp <= 0:
        raise NotApplicable("the attachment points coincide")
    nt3 = -(pD - pC) / bp
    off = -pC  # CoM - C, body components
    along = float(off @ nt3)
    perp = off - along * nt3
    if np.linalg.norm(perp) > 1e-9 * max(bp, 1e-300):
        nt1 = perp / np.linalg.norm(perp)
    else:
        down = rest.R.T @ np.array([0.0, 0.0, -1.0])
        down = down - (down @ nt3) * nt3
        if np.linalg.norm(down) < 1e-9:
            raise NotApplicable("the attachment line is vertical at rest")
        nt1 = down / np.linalg.norm(down)
    nt2 = np.cross(nt3, nt1)
    C = np.column_stack([nt1, nt2, nt3])
    r = float(np.linalg.norm(off))
    lam = math.atan2(float(off @ nt1), -along) if r > 0 else 0.0
    p = kane.KaneParams(b=b, b_prime=bp, l=float(scene.lengths[0]), l_prime=float(scene.lengths[1]),
                        mass=scene.mass, inertia=C.T @ scene.inertia @ C, r=r, lam=lam, g=scene.gravity,
                        anchor_B=yaw @ B0)
    Rk = yaw @ rest.R @ C  # ntilde -> thesis earth
    BC = yaw @ (rest.com + rest.R @ pC - B0)
    CD = yaw @ (rest.R @ (pD - pC))
    th2 = math.acos(max(-1.0, min(1.0, -BC[2] / p.l)))
    th3 = math.atan2(BC[1], BC[0])
    th4 = math.atan2(CD[0], CD[1])
    th5 = math.asin(max(-1.0, min(1.0, CD[2] / bp)))
    th1 = math.atan2(Rk[2, 1], -Rk[2, 0])
    theta0 = np.array([th1, th2, th3, th4, th5])
    if abs(math.sin(th2)) < kane.SIN_THETA2_MIN:
        raise NotApplicable("vertical wires: the thesis's coordinates are singular at theta2 = 0 (its section 6.2)")
    com_k, R_k = kane.pose(theta0, p)
    if np.max(np.abs(com_k - yaw @ rest.com)) > 1e-7 * Lmax or np.max(np.abs(R_k - Rk)) > 1e-7:
        raise NotApplicable("the thesis's angles do not reproduce this rest pose")
    return KaneMapping(p, theta0, C, yaw)


def replace_params(p, **kw):
    """A copy of a frozen KaneParams with fields changed."""
    from ..models.kane import KaneParams

    d = {f: getattr(p, f) for f in ("b", "b_prime", "l", "l_prime", "mass", "inertia", "r", "lam", "g", "anchor_B")}
    d.update(kw)
    return KaneParams(**d)
