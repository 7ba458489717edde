"""Reduced-order and analytic reference models.

Pure functions, SI units throughout (m, kg, s, rad, N, J).  These models are
the yardsticks against which the full 6-DOF wire model is checked:

1. **Symmetric torsion of a trapezoidal bifilar.**  Anchors at world points
   ``(0, +-b/2, 0)``, body attachment points at body points ``(0, +-b'/2, h)``
   relative to the centre of mass (CoM), both wires of length ``l``, body mass
   ``m`` and moment of inertia ``Izz`` about its vertical principal axis
   through the CoM.  The rig is symmetric under the half turn about the
   vertical axis through the CoM, so (for a body whose vertical axis is
   principal, ``Ixz = Iyz = 0``) pure yaw ``theta(t)`` together with the
   vertical CoM rise ``z(theta)`` is an *exact* invariant 1-DOF motion of the
   full system.  ``h`` does not enter: the CoM rises exactly as the
   attachment points do.  With

       rho(theta)^2 = (b/2)^2 + (b'/2)^2 - (b b'/2) cos(theta)
       z(theta)     = sqrt(l^2 - rho0^2) - sqrt(l^2 - rho(theta)^2)

   three models are provided:

   * ``"exact"``:    L = 1/2 (Izz + m z'^2) thetadot^2 - m g z,
   * ``"thesis"``:   thesis (5.2.13), parallel wires ``D = b = b'``, ``h = l``,
     vertical kinetic energy neglected,
   * ``"adjusted"``: thesis Sec. 6.2, inclined wires, ``L = 1/2 Izz thetadot^2
     - m g z`` (vertical kinetic energy neglected).

   Both thesis models share the exact potential but have a too-small inertia
   ``Izz < Izz + m z'^2``, so their period is too short; to leading order
   ``(T_thesis - T_exact)/T_exact = -alpha theta0^2/4`` with
   ``alpha = m c^2/(4 H0^2 Izz)``, ``c = b b'/2``, ``H0 = sqrt(l^2 - rho0^2)``
   (see :func:`torsion_vertical_ke_coefficient`).

2. **Side sway** (thesis Sec. 6.1) and the compound pendulum.
3. **Spherical pendulum** (thesis Sec. 4.5) in angles and in Cartesian form.
4. **Planar double pendulum** (thesis Sec. 6.3), point masses or a rigid
   second link.

Every model has an ``*_energy`` function.  State arrays follow the
``scipy.integrate.solve_ivp`` convention: components along the first axis,
so ``energy(sol.y, params)`` evaluates the whole trajectory at once, and the
right-hand sides accept ``y`` of shape ``(n,)`` or ``(n, k)`` (``vectorized``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from bifilar.errors import InputError

__all__ = [
    "TorsionParams",
    "torsion_rho2",
    "torsion_rho",
    "torsion_z",
    "torsion_dz",
    "torsion_d2z",
    "torsion_inertia",
    "torsion_exact_rhs",
    "torsion_lagrange_thesis_rhs",
    "torsion_adjusted_lagrange_rhs",
    "torsion_energy",
    "torsion_period",
    "torsion_linear_period",
    "torsion_vertical_ke_coefficient",
    "thesis_wire_projection",
    "small_angle_inertia",
    "small_angle_period",
    "side_sway_pivot_distance",
    "side_sway_period",
    "side_sway_double_pendulum_params",
    "compound_pendulum_rhs",
    "compound_pendulum_energy",
    "compound_pendulum_period",
    "SphericalPendulumParams",
    "spherical_pendulum_rhs",
    "spherical_pendulum_energy",
    "spherical_to_cartesian",
    "spherical_pendulum_cartesian_rhs",
    "spherical_pendulum_cartesian_energy",
    "spherical_pendulum_cartesian_constraint",
    "DoublePendulumParams",
    "thesis_double_pendulum_params",
    "double_pendulum_mass_matrix",
    "double_pendulum_rhs",
    "double_pendulum_energy",
    "double_pendulum_linear_matrices",
    "double_pendulum_normal_modes",
]

TORSION_MODELS = ("exact", "thesis", "adjusted")


# --------------------------------------------------------------------------
# 1. Symmetric torsion
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class TorsionParams:
    """Trapezoidal bifilar in symmetric torsion.

    Attributes
    ----------
    m : float
        Body mass, kg.
    Izz : float
        Body moment of inertia about the vertical principal axis through
        the CoM, kg m^2.
    l : float
        Length of each wire, m.
    b : float
        Anchor separation |AB| (ceiling), m.
    bp : float
        Attachment separation |CD| (body), b', m.
    g : float
        Gravitational acceleration, m/s^2 (default 9.81).

    Raises :class:`InputError` on non-positive values or if the wires
    cannot reach (|b - b'|/2 >= l).
    """

    m: float
    Izz: float
    l: float
    b: float
    bp: float
    g: float = 9.81

    def __post_init__(self) -> None:
        for name in ("m", "Izz", "l", "b", "bp", "g"):
            v = getattr(self, name)
            if not np.all(np.isfinite(v)) or np.any(np.asarray(v) <= 0):
                raise InputError(name, f"must be positive and finite, got {v!r}")
        if np.any(self.rho0 >= self.l):
            raise InputError("l", f"wire length {self.l} cannot span the horizontal offset |b - b'|/2 = {self.rho0}")

    @property
    def c(self) -> float:
        """``b b'/2`` (m^2): rho^2 = a - c cos(theta)."""
        return 0.5 * self.b * self.bp

    @property
    def rho0(self) -> float:
        """Horizontal anchor-to-attachment distance at rest, |b - b'|/2, m."""
        return 0.5 * abs(self.b - self.bp)

    @property
    def H0(self) -> float:
        """Vertical drop of a wire at rest, sqrt(l^2 - rho0^2), m."""
        return float(np.sqrt(self.l**2 - self.rho0**2))


def _torsion(params: TorsionParams | Mapping[str, Any]) -> TorsionParams:
    """Accept a (validated) TorsionParams or a mapping with its field names."""
    if isinstance(params, TorsionParams):
        return params
    if isinstance(params, Mapping):
        try:
            return TorsionParams(**params)
        except TypeError as exc:
            raise InputError("params", f"torsion parameters: {exc}") from None
    raise InputError("params", f"expected TorsionParams or a mapping, got {type(params).__name__}")


def torsion_rho2(theta, params) -> np.ndarray:
    """Squared horizontal anchor-to-attachment distance rho^2(theta), m^2.

    ``theta`` in rad (any array shape).  Written as rho0^2 + 2 c sin^2(theta/2)
    (c = b b'/2), which equals (b/2)^2 + (b'/2)^2 - (b b'/2) cos(theta)
    without cancellation at small theta.
    """
    p = _torsion(params)
    s = np.sin(0.5 * np.asarray(theta, dtype=float))
    return p.rho0**2 + 2.0 * p.c * s * s


def torsion_rho(theta, params) -> np.ndarray:
    """Horizontal anchor-to-attachment distance rho(theta), m (theta in rad)."""
    return np.sqrt(torsion_rho2(theta, params))


def _H(theta, p: TorsionParams) -> np.ndarray:
    """Vertical extent of a wire, sqrt(l^2 - rho^2), m."""
    H2 = p.l**2 - torsion_rho2(theta, p)
    if np.any(H2 <= 0):
        raise InputError("theta", "rotation so large that the wires would be horizontal (rho >= l)")
    return np.sqrt(H2)


def torsion_z(theta, params) -> np.ndarray:
    """CoM rise z(theta) = sqrt(l^2 - rho0^2) - sqrt(l^2 - rho^2), m.

    Evaluated as 2 c sin^2(theta/2) / (H0 + H(theta)) (no cancellation).
    """
    p = _torsion(params)
    theta = np.asarray(theta, dtype=float)
    s = np.sin(0.5 * theta)
    return 2.0 * p.c * s * s / (p.H0 + _H(theta, p))


def torsion_dz(theta, params) -> np.ndarray:
    """dz/dtheta = c sin(theta) / (2 H(theta)), m/rad."""
    p = _torsion(params)
    theta = np.asarray(theta, dtype=float)
    return p.c * np.sin(theta) / (2.0 * _H(theta, p))


def torsion_d2z(theta, params) -> np.ndarray:
    """d^2z/dtheta^2 = c cos/(2H) + c^2 sin^2/(4H^3), m/rad^2."""
    p = _torsion(params)
    theta = np.asarray(theta, dtype=float)
    H = _H(theta, p)
    s = np.sin(theta)
    return p.c * np.cos(theta) / (2.0 * H) + (p.c * s) ** 2 / (4.0 * H**3)


def _check_thesis_parallel(p: TorsionParams) -> None:
    if not np.allclose(p.b, p.bp, rtol=1e-12, atol=0.0):
        raise InputError(
            "bp",
            f"the thesis model (5.2.13) assumes parallel wires (b == b'), got b={p.b}, b'={p.bp}; "
            "use model='adjusted' for inclined wires",
        )


def _check_model(model: str) -> str:
    if model not in TORSION_MODELS:
        raise InputError("model", f"unknown torsion model {model!r}; expected one of {TORSION_MODELS}")
    return model


def torsion_inertia(theta, params, model: str = "exact") -> np.ndarray:
    """Generalised inertia M(theta) of the 1-DOF torsion model, kg m^2.

    ``exact``: Izz + m z'(theta)^2; ``thesis``/``adjusted``: Izz.
    """
    p = _torsion(params)
    model = _check_model(model)
    theta = np.asarray(theta, dtype=float)
    if model == "exact":
        return p.Izz + p.m * torsion_dz(theta, p) ** 2
    if model == "thesis":
        _check_thesis_parallel(p)
    return np.full_like(theta, p.Izz, dtype=float) if theta.ndim else np.float64(p.Izz)


def torsion_exact_rhs(t, y, params) -> np.ndarray:
    """Exact symmetric torsion, y = [theta (rad), thetadot (rad/s)].

    From L = 1/2 (Izz + m z'^2) thetadot^2 - m g z:

        (Izz + m z'^2) thetaddot + m z' z'' thetadot^2 + m g z' = 0.

    Returns [thetadot, thetaddot] (rad/s, rad/s^2); ``t`` (s) unused.
    """
    p = _torsion(params)
    th, thd = np.asarray(y, dtype=float)[:2]
    dz = torsion_dz(th, p)
    d2z = torsion_d2z(th, p)
    thdd = -p.m * dz * (d2z * thd * thd + p.g) / (p.Izz + p.m * dz * dz)
    return np.array([thd, thdd])


def torsion_lagrange_thesis_rhs(t, y, params) -> np.ndarray:
    """Thesis (5.2.13), parallel wires, vertical kinetic energy neglected.

    D = b = b' (raises :class:`InputError` if b != b'), h = l:

        thetaddot = -(m g D^2 / (4 h I)) sin(theta)
                    / sqrt(1 - 1/2 (D/h)^2 (1 - cos theta)).

    y = [theta (rad), thetadot (rad/s)]; returns [thetadot, thetaddot].
    """
    p = _torsion(params)
    _check_thesis_parallel(p)
    th, thd = np.asarray(y, dtype=float)[:2]
    D, h = p.bp, p.l
    root = np.sqrt(1.0 - 0.5 * (D / h) ** 2 * (1.0 - np.cos(th)))
    thdd = -(p.m * p.g * D**2 / (4.0 * h * p.Izz)) * np.sin(th) / root
    return np.array([thd, thdd])


def torsion_adjusted_lagrange_rhs(t, y, params) -> np.ndarray:
    """Thesis Sec. 6.2 "adjusted" model: inclined wires, L = 1/2 Izz thetadot^2 - m g z.

    thetaddot = -m g z'(theta) / Izz.  y = [theta (rad), thetadot (rad/s)].
    The thesis writes z through the wire inclination phi,
    z = l cos(phi0) - l cos(phi) with l sin(phi) from the law of cosines
    (:func:`thesis_wire_projection`); l sin(phi) == rho(theta), so z is the
    exact CoM rise used here.
    """
    p = _torsion(params)
    th, thd = np.asarray(y, dtype=float)[:2]
    return np.array([thd, -p.m * p.g * torsion_dz(th, p) / p.Izz])


def torsion_energy(y, params, model: str = "exact") -> np.ndarray:
    """Total energy of a torsion model, J (zero at rest).

    E = 1/2 M(theta) thetadot^2 + m g z(theta), M from :func:`torsion_inertia`.
    ``y`` = [theta, thetadot], shape (2,) or (2, k).
    """
    p = _torsion(params)
    th, thd = np.asarray(y, dtype=float)[:2]
    return 0.5 * torsion_inertia(th, p, model) * thd * thd + p.m * p.g * torsion_z(th, p)


def thesis_wire_projection(theta, D, l, phi0) -> np.ndarray:
    """The thesis's law-of-cosines expression for l sin(phi) (Sec. 6.2), m.

    l sin(phi) = sqrt(D^2 sin^2(theta/2) + l^2 sin^2(phi0)
                      - 2 D sin(theta/2) l sin(phi0) cos(pi - (pi - theta)/2)),

    with D = b' (m), l the wire length (m), phi0 the rest inclination of the
    wires from the vertical (rad; positive when they lean inwards, b > b',
    so l sin(phi0) = (b - b')/2).  It equals :func:`torsion_rho`.
    """
    theta = np.asarray(theta, dtype=float)
    s = np.sin(0.5 * theta)
    r0 = l * np.sin(phi0)
    return np.sqrt(D**2 * s**2 + r0**2 - 2.0 * D * s * r0 * np.cos(np.pi - 0.5 * (np.pi - theta)))


def torsion_linear_period(params) -> float:
    """Small-amplitude torsion period 2 pi sqrt(Izz / (m g z''(0))), s.

    z''(0) = c/(2 H0) = b b' / (4 sqrt(l^2 - ((b - b')/2)^2)).  The vertical
    kinetic energy is of higher order, so all three models share this period.
    For parallel wires z''(0) = D^2/(4h) and this equals
    :func:`small_angle_period` (thesis 5.2.17).
    """
    p = _torsion(params)
    return float(2.0 * np.pi * np.sqrt(p.Izz / (p.m * p.g * torsion_d2z(0.0, p))))


def torsion_vertical_ke_coefficient(params) -> float:
    """alpha = m z'(theta)^2 / (Izz theta^2) as theta -> 0, i.e. m c^2/(4 H0^2 Izz), 1/rad^2.

    The exact inertia is Izz (1 + alpha theta^2 + O(theta^4)); the models that
    neglect the vertical kinetic energy therefore have a period short by the
    relative amount alpha theta0^2 / 4 + O(theta0^4) at amplitude theta0.
    """
    p = _torsion(params)
    return float(p.m * p.c**2 / (4.0 * p.H0**2 * p.Izz))


def _torsion_period_scalar(p: TorsionParams, theta0: float, model: str, epsrel: float) -> float:
    if theta0 == 0.0:
        return torsion_linear_period(p)
    if not (0.0 < theta0 < np.pi):
        raise InputError("amplitude", f"torsion amplitude must lie in [0, pi) rad, got {theta0!r}")
    H0a = _H(theta0, p)  # also raises if the wires would go horizontal
    four_mgc = 4.0 * p.m * p.g * p.c

    # Energy integral T = 4 int_0^theta0 sqrt(M / (2 (V(theta0) - V(theta)))) dtheta
    # with theta = theta0 sin(phi).  Using
    #   V(theta0) - V(theta) = m g c (cos theta - cos theta0) / (H + H0a)
    #                        = 2 m g c sin(sigma) sin(delta/2) / (H + H0a),
    #   sigma = (theta0 + theta)/2, delta = theta0 - theta = theta0 cos^2(phi)/(1 + sin(phi)),
    # the factor theta0 cos(phi)/sqrt(sin(delta/2)) becomes
    #   sqrt(2 theta0 (1 + sin phi) / sinc(delta/2)),
    # so the integrand is smooth and free of 0/0 on the closed interval.
    def integrand(phi: float) -> float:
        sphi = np.sin(phi)
        th = theta0 * sphi
        delta = theta0 * np.cos(phi) ** 2 / (1.0 + sphi)
        sinc = np.sinc(0.5 * delta / np.pi)  # sin(delta/2)/(delta/2)
        sigma = 0.5 * (theta0 + th)
        M = float(torsion_inertia(th, p, model))
        H = float(_H(th, p))
        return np.sqrt(2.0 * theta0 * (1.0 + sphi) / sinc) * np.sqrt(M * (H + H0a) / (four_mgc * np.sin(sigma)))

    from scipy import integrate

    val, _err = integrate.quad(integrand, 0.0, 0.5 * np.pi, epsabs=0.0, epsrel=epsrel, limit=200)
    return float(4.0 * val)


def torsion_period(params, amplitude, model: str = "exact", epsrel: float = 1e-13):
    """Exact period (s) of the conservative torsion oscillation at amplitude theta0 (rad).

    Quadrature of the energy integral
    T = 4 int_0^theta0 sqrt(M(theta) / (2 (V(theta0) - V(theta)))) dtheta,
    V = m g z, M = Izz + m z'^2 (``model="exact"``) or Izz (``"thesis"``,
    ``"adjusted"``; ``"thesis"`` requires b == b').  The endpoint singularity
    is removed by theta = theta0 sin(phi); ``scipy.integrate.quad`` to
    relative tolerance ``epsrel``.  ``amplitude`` may be an array (result has
    its shape); amplitude 0 gives :func:`torsion_linear_period`.
    """
    p = _torsion(params)
    model = _check_model(model)
    if model == "thesis":
        _check_thesis_parallel(p)
    amp = np.asarray(amplitude, dtype=float)
    out = np.array([_torsion_period_scalar(p, float(a), model, epsrel) for a in np.abs(amp).ravel()])
    return float(out[0]) if amp.ndim == 0 else out.reshape(amp.shape)


def small_angle_inertia(m, g, D, h, T):
    """Thesis (5.2.18): I = m g D^2 T^2 / (16 pi^2 h), kg m^2.

    m in kg, g in m/s^2, D wire separation (m), h wire length (m), T the
    measured torsion period (s).  Parallel wires, small amplitude.  Vectorised.
    """
    return np.asarray(m) * np.asarray(g) * np.asarray(D) ** 2 * np.asarray(T) ** 2 / (16.0 * np.pi**2 * np.asarray(h))


def small_angle_period(m, g, D, h, I):
    """Inverse of (5.2.18), thesis (5.2.17): T = 4 pi sqrt(I h / (m g D^2)), s.

    Units as :func:`small_angle_inertia`; I in kg m^2.  Vectorised.
    """
    return 4.0 * np.pi * np.sqrt(np.asarray(I) * np.asarray(h) / (np.asarray(m) * np.asarray(g) * np.asarray(D) ** 2))


# --------------------------------------------------------------------------
# 2. Side sway and the compound pendulum
# --------------------------------------------------------------------------
def side_sway_pivot_distance(l, b, bp):
    """Distance d (m) from the anchor line AB to the attachment line CD at rest.

    d = sqrt(l^2 - ((b - b')/2)^2); l, b, b' in m.  Vectorised.
    """
    l, b, bp = (np.asarray(v, dtype=float) for v in (l, b, bp))
    return np.sqrt(l**2 - (0.5 * (b - bp)) ** 2)


def compound_pendulum_rhs(t, y, I_pivot, m, g, d) -> np.ndarray:
    """Compound pendulum I_pivot psiddot = -m g d sin(psi).

    y = [psi (rad, from the downward vertical), psidot (rad/s)];
    I_pivot in kg m^2 about the pivot, m in kg, g in m/s^2, d pivot-to-CoM in m.
    """
    psi, psid = np.asarray(y, dtype=float)[:2]
    return np.array([psid, -m * g * d * np.sin(psi) / I_pivot])


def compound_pendulum_energy(y, I_pivot, m, g, d) -> np.ndarray:
    """E = 1/2 I_pivot psidot^2 + m g d (1 - cos psi), J (zero at rest)."""
    psi, psid = np.asarray(y, dtype=float)[:2]
    return 0.5 * I_pivot * psid**2 + m * g * d * 2.0 * np.sin(0.5 * psi) ** 2


def compound_pendulum_period(I_pivot, m, g, d, amplitude=0.0):
    """Exact period (s) of a compound pendulum swinging with amplitude psi0 (rad).

    T = 4 sqrt(I_pivot / (m g d)) K(k), k = sin(psi0/2), K the complete
    elliptic integral of the first kind (``scipy.special.ellipk`` takes the
    parameter k^2).  I_pivot in kg m^2, m in kg, g in m/s^2, d in m;
    0 <= |psi0| < pi.  Vectorised.
    """
    amp = np.abs(np.asarray(amplitude, dtype=float))
    if np.any(amp >= np.pi):
        raise InputError("amplitude", "compound pendulum amplitude must be below pi rad")
    k = np.sin(0.5 * amp)
    from scipy import special

    T = 4.0 * np.sqrt(np.asarray(I_pivot) / (np.asarray(m) * np.asarray(g) * np.asarray(d))) * special.ellipk(k * k)
    return float(T) if np.ndim(T) == 0 else T


def side_sway_period(m, l, b, bp, amplitude=0.0, g=9.81, I_CD=0.0, roll_locked=False):
    """Side-sway period (s) of a trapezoidal bifilar whose CoM lies on CD (thesis Sec. 6.1).

    m body mass (kg), l wire length, b = |AB|, bp = b' = |CD| (m), amplitude
    the swing angle of the wire plane about AB (rad), g (m/s^2).

    With ideal wires (free to pivot at both ends) the body's roll psi about
    CD is cyclic when the CoM lies on CD: the CoM height depends on the swing
    angle only, and the kinetic energy is 1/2 m d^2 swingdot^2 + 1/2 I_CD psidot^2.
    So the swing is a *simple* pendulum of length d whatever I_CD, and the
    body keeps rolling at its initial roll rate (zero from rest): it
    translates on a circular arc without turning.  That is the default,
    ``I_pivot = m d^2``.

    ``roll_locked=True`` returns the compound-pendulum period with
    ``I_pivot = I_CD + m d^2`` (I_CD about the axis through the CoM parallel
    to AB, kg m^2): the rigid rotation of the whole trapezoid about AB.  That
    is an exact motion only if something (a hinge, a rigid frame) forces the
    body to turn with the wires; for a free wire suspension it is not.
    """
    d = side_sway_pivot_distance(l, b, bp)
    I_pivot = (I_CD if roll_locked else 0.0) + m * d**2
    return compound_pendulum_period(I_pivot, m, g, d, amplitude)


# --------------------------------------------------------------------------
# 3. Spherical pendulum
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class SphericalPendulumParams:
    """Point mass ``m`` (kg) on a massless rod of length ``l`` (m); gravity ``g`` (m/s^2)."""

    l: float
    g: float = 9.81
    m: float = 1.0


def spherical_pendulum_rhs(t, y, params: SphericalPendulumParams) -> np.ndarray:
    """Thesis (4.5.7) in first-order form, y = [theta, thetadot, phi, phidot].

    theta (rad) from the downward vertical, phi (rad) azimuth about the
    upward vertical; rates in rad/s:

        thetaddot = (l phidot^2 sin(theta) cos(theta) - g sin(theta)) / l
        phiddot   = -2 phidot cos(theta) thetadot / sin(theta)

    The chart is **singular at theta = 0 (and pi)**: phi is undefined there
    and phiddot divides by sin(theta).  A trajectory with nonzero angular
    momentum about the vertical never reaches theta = 0, but one through the
    lowest point (e.g. a planar swing, phidot = 0, past theta = 0) cannot be
    followed in these coordinates; use :func:`spherical_pendulum_cartesian_rhs`.
    """
    th, thd, ph, phd = np.asarray(y, dtype=float)[:4]
    s, c = np.sin(th), np.cos(th)
    thdd = (params.l * phd**2 * s * c - params.g * s) / params.l
    phdd = -2.0 * phd * c * thd / s
    return np.array([thd, thdd, phd, phdd])


def spherical_pendulum_energy(y, params: SphericalPendulumParams) -> np.ndarray:
    """E = 1/2 m l^2 (thetadot^2 + phidot^2 sin^2 theta) - m g l cos(theta), J.

    Zero potential at the pivot height; the rest energy is -m g l.
    """
    th, thd, _ph, phd = np.asarray(y, dtype=float)[:4]
    m, l, g = params.m, params.l, params.g
    return 0.5 * m * l**2 * (thd**2 + (phd * np.sin(th)) ** 2) - m * g * l * np.cos(th)


def spherical_to_cartesian(y, params: SphericalPendulumParams) -> np.ndarray:
    """Angle state [theta, thetadot, phi, phidot] -> Cartesian [x, y, z, vx, vy, vz].

    Pivot at the origin, z up: position l (sin th cos ph, sin th sin ph, -cos th) (m),
    velocity in m/s.
    """
    th, thd, ph, phd = np.asarray(y, dtype=float)[:4]
    l = params.l
    st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    pos = [l * st * cp, l * st * sp, -l * ct]
    vel = [
        l * (ct * cp * thd - st * sp * phd),
        l * (ct * sp * thd + st * cp * phd),
        l * st * thd,
    ]
    return np.array(pos + vel)


def spherical_pendulum_cartesian_rhs(t, y, params: SphericalPendulumParams, alpha: float = 5.0, beta: float = 5.0) -> np.ndarray:
    """Cartesian constrained spherical pendulum, y = [x, y, z, vx, vy, vz] (m, m/s).

    m a = m g_vec + lambda x with the constraint C = (|x|^2 - l^2)/2 = 0.
    The multiplier is eliminated at index 1 with Baumgarte stabilisation,
    Cddot + 2 alpha Cdot + beta^2 C = 0 (alpha, beta in 1/s), giving

        lambda/m = -(x.g_vec + |v|^2 + 2 alpha x.v + beta^2 C) / |x|^2.

    No chart singularity.  On the constraint manifold (C = Cdot = 0) the
    Baumgarte terms vanish and the solution is the exact one.
    """
    y = np.asarray(y, dtype=float)
    x, v = y[:3], y[3:6]
    gvec_z = -params.g
    xx = np.sum(x * x, axis=0)
    xv = np.sum(x * v, axis=0)
    vv = np.sum(v * v, axis=0)
    C = 0.5 * (xx - params.l**2)
    mu = -(x[2] * gvec_z + vv + 2.0 * alpha * xv + beta**2 * C) / xx
    a = mu * x
    a[2] = a[2] + gvec_z
    return np.concatenate([v, a])


def spherical_pendulum_cartesian_energy(y, params: SphericalPendulumParams) -> np.ndarray:
    """E = 1/2 m |v|^2 + m g z, J (same zero as :func:`spherical_pendulum_energy`)."""
    y = np.asarray(y, dtype=float)
    return 0.5 * params.m * np.sum(y[3:6] ** 2, axis=0) + params.m * params.g * y[2]


def spherical_pendulum_cartesian_constraint(y, params: SphericalPendulumParams) -> np.ndarray:
    """Constraint violation |x| - l, m."""
    y = np.asarray(y, dtype=float)
    return np.sqrt(np.sum(y[:3] ** 2, axis=0)) - params.l


# --------------------------------------------------------------------------
# 4. Planar double pendulum
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class DoublePendulumParams:
    """Planar double pendulum.

    Attributes
    ----------
    m1 : float
        Point mass at the joint, kg (may be 0 if I2 > 0).
    m2 : float
        Mass of the second link, kg.
    L1 : float
        Pivot-to-joint length (massless rod), m.
    L2 : float
        Joint-to-CoM distance of the second link, m.
    I2 : float
        Moment of inertia of the second link about its CoM, kg m^2
        (0 for a point mass on a massless rod).
    g : float
        Gravity, m/s^2.
    """

    m1: float
    m2: float
    L1: float
    L2: float
    I2: float = 0.0
    g: float = 9.81


def thesis_double_pendulum_params(theta2: float = np.pi / 6, l: float = 5.0, g: float = 9.81) -> DoublePendulumParams:
    """The thesis's Sec. 6.3 analogy: m1 = m2 = 5, L1 = l cos(theta2), L2 = 1/2, I2 = m2 L2^2."""
    return DoublePendulumParams(m1=5.0, m2=5.0, L1=l * np.cos(theta2), L2=0.5, I2=5.0 * 0.25, g=g)


def side_sway_double_pendulum_params(m, I_CD, l, b, bp, r, g=9.81) -> DoublePendulumParams:
    """Exact planar reduction of a symmetric trapezoidal bifilar's side sway.

    The mirror symmetry across the plane bisecting AB leaves an invariant
    subspace: the wire plane swings about AB (the midpoint of CD moves on a
    circle of radius d = :func:`side_sway_pivot_distance`) and the body
    rolls about CD.  With massless wires this is a double pendulum with a
    massless joint: m1 = 0, L1 = d, m2 = m (kg), L2 = r (CoM distance below
    CD, m), I2 = I_CD (kg m^2, about the axis through the CoM parallel to AB).
    (The thesis's m1 = m2 = 5 is an analogy, not this reduction.)
    """
    d = float(side_sway_pivot_distance(l, b, bp))
    return DoublePendulumParams(m1=0.0, m2=float(m), L1=d, L2=float(r), I2=float(I_CD), g=float(g))


def double_pendulum_mass_matrix(phi1, phi2, params: DoublePendulumParams) -> np.ndarray:
    """Mass matrix (kg m^2) of the double pendulum at angles phi1, phi2 (rad), shape (2, 2, ...)."""
    p = params
    c = np.cos(np.asarray(phi1, dtype=float) - np.asarray(phi2, dtype=float))
    M11 = (p.m1 + p.m2) * p.L1**2 * np.ones_like(c)
    M12 = p.m2 * p.L1 * p.L2 * c
    M22 = (p.m2 * p.L2**2 + p.I2) * np.ones_like(c)
    return np.array([[M11, M12], [M12, M22]])


def double_pendulum_rhs(t, y, params: DoublePendulumParams) -> np.ndarray:
    """Planar double pendulum, y = [phi1, phi2, phi1dot, phi2dot] (rad, rad/s).

    Angles from the downward vertical.  Lagrange's equations

        (m1+m2) L1^2 phi1'' + m2 L1 L2 cos(D) phi2'' + m2 L1 L2 sin(D) phi2'^2 + (m1+m2) g L1 sin(phi1) = 0
        m2 L1 L2 cos(D) phi1'' + (m2 L2^2 + I2) phi2'' - m2 L1 L2 sin(D) phi1'^2 + m2 g L2 sin(phi2) = 0

    with D = phi1 - phi2, solved by Cramer's rule.  The mass matrix is
    singular only if m1 = 0, I2 = 0 and the links are aligned.
    """
    p = params
    ph1, ph2, w1, w2 = np.asarray(y, dtype=float)[:4]
    D = ph1 - ph2
    sD, cD = np.sin(D), np.cos(D)
    M11 = (p.m1 + p.m2) * p.L1**2
    M12 = p.m2 * p.L1 * p.L2 * cD
    M22 = p.m2 * p.L2**2 + p.I2
    f1 = -p.m2 * p.L1 * p.L2 * sD * w2**2 - (p.m1 + p.m2) * p.g * p.L1 * np.sin(ph1)
    f2 = p.m2 * p.L1 * p.L2 * sD * w1**2 - p.m2 * p.g * p.L2 * np.sin(ph2)
    det = M11 * M22 - M12 * M12
    a1 = (M22 * f1 - M12 * f2) / det
    a2 = (M11 * f2 - M12 * f1) / det
    return np.array([w1, w2, a1, a2])


def double_pendulum_energy(y, params: DoublePendulumParams) -> np.ndarray:
    """E = 1/2 qdot^T M(q) qdot - (m1+m2) g L1 cos(phi1) - m2 g L2 cos(phi2), J.

    Zero potential at the pivot height; rest energy -(m1+m2) g L1 - m2 g L2.
    """
    p = params
    ph1, ph2, w1, w2 = np.asarray(y, dtype=float)[:4]
    cD = np.cos(ph1 - ph2)
    T = 0.5 * ((p.m1 + p.m2) * p.L1**2 * w1**2 + 2.0 * p.m2 * p.L1 * p.L2 * cD * w1 * w2 + (p.m2 * p.L2**2 + p.I2) * w2**2)
    V = -(p.m1 + p.m2) * p.g * p.L1 * np.cos(ph1) - p.m2 * p.g * p.L2 * np.cos(ph2)
    return T + V


def double_pendulum_linear_matrices(params: DoublePendulumParams) -> tuple[np.ndarray, np.ndarray]:
    """Mass (kg m^2) and stiffness (N m/rad) matrices linearised about the hanging rest."""
    p = params
    M = double_pendulum_mass_matrix(0.0, 0.0, p)
    K = np.diag([(p.m1 + p.m2) * p.g * p.L1, p.m2 * p.g * p.L2])
    return M, K


def double_pendulum_normal_modes(params: DoublePendulumParams) -> tuple[np.ndarray, np.ndarray]:
    """Angular frequencies (rad/s, ascending) and mode shapes (columns) of small oscillations.

    Solves K v = omega^2 M v with M, K from :func:`double_pendulum_linear_matrices`.
    """
    from scipy.linalg import eigh

    M, K = double_pendulum_linear_matrices(params)
    w2, V = eigh(K, M)
    return np.sqrt(w2), V
