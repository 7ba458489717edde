"""Wire tensions from a motion, by the thesis's methods of section 7.2.

The default model gives the tensions directly (its multipliers).  These
functions recompute them the way the thesis does, from the CoM acceleration
and the wire directions only, so the two can be compared:

* :func:`symmetric_tension` -- F_t = m (g + a_z) / (2 cos theta2) (the
  thesis's F_t = (-m a3 - m g) / (2 cos theta2) with its sign convention),
  valid when the two wires are mirror images (symmetric torsion, rest);
* :func:`general_tensions` -- Newton's second law sum_i F_i u_i = m (a + g e_z)
  for n wires: 3 equations, n unknowns, solved in the least-squares sense
  (the thesis's overdetermined 3 x 2 system) with its residual reported;
  square for 3 wires; for 4 or 5 wires underdetermined: the minimum-norm
  solution balances the forces but is not the wire tensions.

Units: N, m, s; world frame, z up.  All functions are vectorised over time.
"""

from __future__ import annotations

import numpy as np

from ..scene import Scene


def wire_units(scene: Scene, com: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Unit vectors (k, n, 3) from each attachment point towards its anchor (world).

    com : (k, 3) CoM positions, m; R : (k, 3, 3) body -> world rotations.
    """
    att = com[:, None, :] + np.einsum("kij,nj->kni", R, scene.attachments)
    u = scene.anchors[None, :, :] - att
    return u / np.linalg.norm(u, axis=-1, keepdims=True)


def symmetric_tension(mass: float, gravity: float, accel_z: np.ndarray, units: np.ndarray) -> np.ndarray:
    """Thesis 7.2 symmetric formula: tension in one wire, N (k,).

    accel_z : (k,) vertical CoM acceleration, m/s^2; units : (k, n, 3) wire
    unit vectors (attachment -> anchor); theta2 is taken from wire 1
    (cos theta2 = its vertical component).
    """
    cos2 = units[:, 0, 2]
    return mass * (gravity + accel_z) / (2.0 * cos2)


def general_tensions(mass: float, gravity: float, accel: np.ndarray, units: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Thesis 7.2 general method: least-squares tensions (k, n) in N and the
    residual norm (k,) in N of  sum_i F_i u_i = m (a + g e_z).

    accel : (k, 3) CoM acceleration, m/s^2; units : (k, n, 3).
    """
    rhs = mass * (accel + np.array([0.0, 0.0, gravity]))
    A = np.swapaxes(units, -1, -2)  # (k, 3, n)
    # batched least squares through the pseudo-inverse of each 3 x n system
    pinv = np.linalg.pinv(A)  # (k, n, 3)
    F = np.einsum("kni,ki->kn", pinv, rhs)
    res = np.linalg.norm(np.einsum("kin,kn->ki", A, F) - rhs, axis=-1)
    return F, res


def general_tensions_noise(mass: float, units: np.ndarray, accel_cov: np.ndarray, gain=1.0) -> np.ndarray:
    """(k, n) N: the std of :func:`general_tensions` at each sample from a
    noise of covariance ``accel_cov`` (3, 3) (m/s^2)^2 times ``gain`` (a
    scalar or (k,), per sample) in each sample's CoM acceleration (world):
    ``mass sqrt(gain diag(P C P^T))``, ``P`` (n, 3) the sample's
    pseudo-inverse of the wire directions ``units`` (k, n, 3)."""
    P = np.linalg.pinv(np.swapaxes(units, -1, -2))  # (k, n, 3)
    var = np.einsum("kni,ij,knj->kn", P, np.asarray(accel_cov, float), P) * np.reshape(gain, (-1, 1))
    return mass * np.sqrt(np.maximum(var, 0.0))
