"""A recorded motion for the inertia from tensions (``bifilar tensions
--motion``): read the CSV, differentiate the poses, and say how far the
poses are from the rig's wire lengths.

Frames and units: time ``t`` s; the CoM ``com`` m in the world frame (the
config's); the attitude ``q`` (w, x, y, z) a unit quaternion body -> world;
``omega`` and ``alpha`` body axes, rad/s and rad/s^2; ``accel`` the CoM's
acceleration, world, m/s^2; tensions N, one column per wire.
"""

from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np

from ..scene import Scene


@dataclass(frozen=True)
class MotionRecord:
    """A motion record and its rates (see the module's docstring for frames and units).

    t : (k,) s.  y : (k, 13) the state as the models lay it out (com, q,
    CoM velocity, omega).  tensions : (k, n) N.  omega, alpha : (k, 3)
    body axes from local quartic fits (:func:`derivatives`).  accel : (k, 3)
    world.  alt : (omega, alpha) the same rates differentiated another way
    (quintic interpolating splines), whose difference is the rates'
    systematic error (:func:`~bifilar.estimation.from_tensions.record_std`).
    alpha_noise, alpha_noise_rse : :func:`alpha_noise`.  com_noise : (3, 3)
    m^2, :func:`com_noise` (None for a short record).
    """

    t: np.ndarray
    y: np.ndarray
    tensions: np.ndarray
    omega: np.ndarray
    accel: np.ndarray
    alpha: np.ndarray
    alt: tuple
    alpha_noise: np.ndarray | None = None
    alpha_noise_rse: float = 0.0
    com_noise: np.ndarray | None = None


def read_motion(path, n_wires: int) -> MotionRecord:
    """Read t, com, quaternion and ``n_wires`` tensions from the CSV at
    ``path`` (columns t, com_x..z, q_w..q_z, tension_1..n, as ``bifilar
    simulate --out`` writes them; other columns ignored) and derive the
    rates (:func:`derivatives`).  The quaternion is normalised.  Raises
    :class:`~bifilar.errors.InputError` naming ``--motion`` (and the column
    and file line) for an unreadable file, a missing column, a non-finite
    cell, fewer than 20 samples, a time that does not increase, a zero
    quaternion."""
    import os
    import warnings

    from ..errors import InputError
    from ..rotations import quat_multiply

    try:
        if os.path.getsize(path) == 0:
            raise InputError("--motion", f"{path} is empty; expected a CSV with a header row (t, com_x, ..., q_w, ...)")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numpy's "empty input" warnings: reported below as one error
            data = np.atleast_1d(np.genfromtxt(path, delimiter=",", names=True))
    except (OSError, ValueError, IndexError, TypeError) as exc:
        reason = getattr(exc, "strerror", None) or type(exc).__name__
        raise InputError("--motion", f"cannot read {path} as a CSV table with a header row ({reason})") from None
    names = data.dtype.names or ()
    need = ["t", "com_x", "com_y", "com_z", "q_w", "q_x", "q_y", "q_z"] + [f"tension_{i + 1}" for i in range(n_wires)]
    missing = [n for n in need if n not in names]
    if missing:
        raise InputError("--motion", f"missing columns {', '.join(missing)} (have {', '.join(names)})")
    if len(data) < 20:
        raise InputError("--motion", "fewer than 20 samples")
    for n in need:  # a blank cell or a word reads as nan: name the first one (file line, header = line 1)
        bad = np.flatnonzero(~np.isfinite(data[n]))
        if len(bad):
            raise InputError("--motion", f"column {n}, line {bad[0] + 2}: not a finite number "
                             f"({len(bad)} such value(s) in the column)")
    t = data["t"]
    if np.any(np.diff(t) <= 0):
        raise InputError("--motion", "time column t must increase strictly")
    com = np.c_[data["com_x"], data["com_y"], data["com_z"]]
    q = np.c_[data["q_w"], data["q_x"], data["q_y"], data["q_z"]]
    qn = np.linalg.norm(q, axis=1, keepdims=True)
    if np.any(qn < 1e-6):
        raise InputError("--motion", f"line {int(np.argmax(qn[:, 0] < 1e-6)) + 2}: the quaternion (q_w, q_x, q_y, q_z) "
                         "is zero; it must be a rotation (unit length)")
    q /= qn
    T = np.c_[tuple(data[f"tension_{i + 1}"] for i in range(n_wires))]
    # second differences were biased by ~(omega h)^2 / 3, 0.3 % at 64 samples per period, far beyond the
    # estimate's std; local quartic fits over 9 samples (Savitzky-Golay) err by ~1e-5 there and pass less
    # noise; unevenly sampled records take the same fits at their actual times (estimation/local_fits.py)
    conj = q * np.array([1, -1, -1, -1])

    def rates(spline):
        qdot, qddot = derivatives(t, q, spline)
        # body axes; alpha is d/dt of omega: conj(qdot) qdot is a scalar for a unit q
        return 2 * quat_multiply(conj, qdot)[:, 1:], 2 * quat_multiply(conj, qddot)[:, 1:]

    omega, alpha = rates(False)
    vel, accel = derivatives(t, com, False)
    y = np.zeros((len(t), 13))
    y[:, 0:3], y[:, 3:7], y[:, 7:10], y[:, 10:13] = com, q, vel, omega
    noise, rse = alpha_noise(t, q)
    return MotionRecord(t, y, T, omega, accel, alpha, rates(True), noise, rse, com_noise(t, com))


SG_WINDOW, SG_ORDER = 9, 4
"""The local fits' length (samples) and polynomial degree (:func:`derivatives`)."""


def alpha_noise(t: np.ndarray, q: np.ndarray) -> tuple[np.ndarray | None, float]:
    """((3, 3) (rad/s^2)^2, the covariance of the noise each sample of the
    body-axes angular acceleration from :func:`derivatives` carries, and the
    relative standard error of that estimate), or (None, 0) for a record
    of fewer than ``2 SG_WINDOW`` samples (``read_motion`` refuses fewer than
    20; from 18 on, 10 interior samples, the noise is estimated, session 20:
    a 26-sample record was left uncorrected and 22 % low).

    The attitude's noise is estimated from the record itself: the residual
    of the local fits' smoothing, ``q - S q``, in body axes as a small
    rotation ``2 vec(conj(q) (q - S q))`` (rad), has the covariance
    ``C_theta (1 - c_0)`` for white attitude noise ``C_theta`` (``c_0`` the
    smoother's centre weight: ``S`` is a local projection, so its row's
    squares sum to ``c_0``); a smooth motion leaves only the fits'
    truncation (~1e-5 of the motion at 64 samples a period), which
    counts as noise here and so errs on the safe side.  The second
    derivative's filter ``c_2`` then passes ``C_theta sum(c_2^2)`` (a
    small rotation ``d theta`` of the attitude is ``d q = q (0, d theta /
    2)``, and alpha is ``2 vec(conj(q) q'')``).  The record's first and last
    ``SG_WINDOW // 2`` samples, fitted off-centre, are left out.  The
    standard error: ``sqrt(2 / n_eff)``, ``n_eff`` the residuals' count
    times ``1 - c_0`` (the local projections' share of free residual
    directions) per axis.  Jittered time stamps (session 20): the fits at
    the actual times (:mod:`~bifilar.estimation.local_fits`), ``c_0`` and
    the gain sample by sample, ``C_theta = sum eps eps^T / sum(1 - c_0)``
    and the gain the interior samples' mean (the corrected normal
    equations need the noise summed over the samples)."""
    from scipy.signal import savgol_coeffs, savgol_filter

    from ..rotations import quat_multiply
    from .design_noise import variance_rse

    if len(t) < 2 * SG_WINDOW:
        return None, 0.0
    smooth, free = _smoothed(t, q)
    eps = 2 * quat_multiply(q * np.array([1, -1, -1, -1]), q - smooth)[:, 1:]
    c_theta = _residual_covariance(eps, free)
    return c_theta * _second_derivative_gain(t), variance_rse(float(np.sum(free[SG_WINDOW // 2:-(SG_WINDOW // 2)])))


def _smoothed(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the local fits' smoothed ``x`` (k, m), each sample's ``1 - c_0``
    (k,), the share of its white noise the residual ``x - S x`` keeps):
    Savitzky-Golay for evenly spaced ``t`` (s), else the fits at the actual
    times (:mod:`~bifilar.estimation.local_fits`)."""
    from scipy.signal import savgol_coeffs, savgol_filter

    if evenly_sampled(t):
        c0 = float(savgol_coeffs(SG_WINDOW, SG_ORDER)[SG_WINDOW // 2])
        return savgol_filter(x, SG_WINDOW, SG_ORDER, axis=0), np.full(len(t), 1.0 - c0)
    from .local_fits import apply, centre_weight, local_weights

    start, W = local_weights(t, SG_WINDOW, SG_ORDER)
    return apply(start, W, x, 0), 1.0 - centre_weight(start, W)


def _residual_covariance(eps: np.ndarray, free: np.ndarray) -> np.ndarray:
    """(m, m): the white noise's covariance per sample from the smoothing
    residuals ``eps`` (k, m) and their ``1 - c_0`` ``free`` (k,) of
    :func:`_smoothed`, over the interior samples (the first and last
    ``SG_WINDOW // 2``, fitted off centre, left out)."""
    half = SG_WINDOW // 2
    eps, free = eps[half:-half], free[half:-half]
    return eps.T @ eps / float(np.sum(free))


def com_noise(t: np.ndarray, com: np.ndarray) -> np.ndarray | None:
    """(3, 3) m^2: the covariance of the white noise each recorded CoM
    position (world, m) carries, estimated as :func:`alpha_noise` estimates
    the attitude's (the local fits' residuals, ``C (1 - c_0)``), or None for
    a record of fewer than ``2 SG_WINDOW`` samples.  A smooth motion leaves
    the fits' truncation (~1e-5 of the motion at 64 samples a period),
    which counts as noise (the safe side)."""
    if len(t) < 2 * SG_WINDOW:
        return None
    smooth, free = _smoothed(t, com)
    return _residual_covariance(com - smooth, free)


def general_tension_noise(rec: MotionRecord, mass: float, units: np.ndarray) -> np.ndarray | None:
    """(k, n) N: the std of each sample's general tensions
    (:func:`~bifilar.analysis.tensions.general_tensions`) from the record's
    CoM noise (:func:`com_noise`): the CoM acceleration's noise, covariance
    ``C_com`` times the second derivative's gain, through each sample's
    pseudo-inverse of the wire directions ``units`` (k, n, 3) times
    ``mass`` kg (the directions' own noise, ``C_com / L^2`` of the tension,
    is 1e-4 of it at 64 samples a period and left out).  None where the
    noise is not estimated (a record shorter than ``2 SG_WINDOW``)."""
    from ..analysis.tensions import general_tensions_noise

    if rec.com_noise is None:
        return None
    return general_tensions_noise(mass, units, rec.com_noise, _second_derivative_gains(rec.t))


def _second_derivative_gains(t: np.ndarray) -> np.ndarray:
    """(k,) s^-4: each sample's sum of squared second-derivative weights
    of :func:`derivatives` (the record's end samples, fitted off centre,
    6-24 times the centre's)."""
    from .local_fits import local_weights, second_derivative_gain

    if not evenly_sampled(t):
        return second_derivative_gain(local_weights(t, SG_WINDOW, SG_ORDER)[1])
    gains = np.full(len(t), _second_derivative_gain(t))
    half = SG_WINDOW // 2
    gains[:half] = second_derivative_gain(local_weights(t[:SG_WINDOW], SG_WINDOW, SG_ORDER)[1])[:half]
    gains[-half:] = second_derivative_gain(local_weights(t[-SG_WINDOW:], SG_WINDOW, SG_ORDER)[1])[-half:]
    return gains


GENERAL_NOISE_WARN = 0.01
"""The general tensions' noise std (:func:`general_tension_noise`, RMS over
the samples) above this fraction of a wire's mean tension is said in a
warning."""


def general_noise_warning(noise_std: np.ndarray, tensions: np.ndarray, com_std: float) -> str | None:
    """One line when some wire's general-tension noise ``noise_std`` (n,) N
    (RMS over the samples) exceeds :data:`GENERAL_NOISE_WARN` of its mean
    recorded tension (``tensions`` (k, n) N), else None; ``com_std`` m, the
    CoM's noise RMS per axis."""
    mean = np.abs(np.mean(tensions, axis=0))
    rel = noise_std / np.maximum(mean, 1e-300)
    worst = int(np.argmax(rel))
    if not rel[worst] > GENERAL_NOISE_WARN:
        return None
    return (f"--motion: the record's CoM noise ({com_std * 1e3:.2g} mm RMS per axis, estimated from the record) "
            f"passes into the differentiated CoM acceleration: the thesis's general tensions carry a noise of "
            f"{noise_std[worst]:.3g} N RMS on wire {worst + 1} ({rel[worst]:.1%} of its mean tension; general.noise_std "
            "per wire); record the CoM more finely or compare them with the load cells over a smoothed motion")


def evenly_sampled(t: np.ndarray) -> bool:
    """Whether the time stamps ``t`` (s) are evenly spaced (to 1e-6 of the
    median step): the record is then differentiated by fixed filters."""
    dt = np.diff(t)
    return bool(np.ptp(dt) <= 1e-6 * np.median(dt))


def _second_derivative_gain(t: np.ndarray) -> float:
    """s^-4: the sum of the squared weights of :func:`derivatives`' second
    derivative at a centred sample of the evenly spaced times ``t`` (s);
    for jittered times the mean of that sum over the interior samples
    (:func:`interior`; the local fits at the actual times,
    :mod:`~bifilar.estimation.local_fits`)."""
    from scipy.signal import savgol_coeffs

    if not evenly_sampled(t):
        from .local_fits import local_weights, second_derivative_gain

        half = SG_WINDOW // 2
        return float(np.mean(second_derivative_gain(local_weights(t, SG_WINDOW, SG_ORDER)[1])[half:-half]))
    h = float(np.mean(np.diff(t)))
    return float(np.sum(savgol_coeffs(SG_WINDOW, SG_ORDER, deriv=2, delta=h) ** 2))


def derivatives(t: np.ndarray, x: np.ndarray, spline: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """First and second time derivatives of samples ``x`` (k, m) at times ``t`` (k,), s: local quartic
    least-squares fits over 9 samples (Savitzky-Golay when the sampling is even, else the same fits at the
    actual times, :mod:`~bifilar.estimation.local_fits`), or with ``spline`` quintic interpolating splines."""
    if not spline and evenly_sampled(t):
        from scipy.signal import savgol_filter

        h = float(np.mean(np.diff(t)))
        return (savgol_filter(x, SG_WINDOW, SG_ORDER, deriv=1, delta=h, axis=0),
                savgol_filter(x, SG_WINDOW, SG_ORDER, deriv=2, delta=h, axis=0))
    if not spline:
        from .local_fits import derivatives as local_derivatives

        return local_derivatives(t, x)
    from scipy.interpolate import make_interp_spline

    s = make_interp_spline(t, x, k=5, axis=0)
    return s.derivative(1)(t), s.derivative(2)(t)


def hanging_lengths(scene: Scene, rest=None) -> tuple[np.ndarray, str]:
    """(the wires' lengths as they hang, m; the words naming them in a warning): ``rig.lengths``, or with
    ``rig.stiffness`` the loaded ones at the rest pose ``rest`` (required then;
    :func:`~bifilar.analysis.elastic_rest.loaded_scene`), named "loaded (rig.lengths stretched under
    rig.stiffness) " (session 18: the unloaded ones were compared at 1 %, which a strain above 1 % alone
    tripped)."""
    if scene.stiffness is None:
        return np.asarray(scene.lengths, float), ""
    from ..analysis.elastic_rest import loaded_scene

    if rest is None:
        raise ValueError("hanging_lengths: a scene with rig.stiffness needs its rest pose")
    return loaded_scene(scene, rest).lengths, "loaded (rig.lengths stretched under rig.stiffness) "


LENGTH_MISMATCH_WARN = 0.01
"""Relative distance of a record's poses from a wire's hanging length above
which :func:`length_mismatch` words a warning."""


def length_mismatch(scene: Scene, com: np.ndarray, R: np.ndarray, rest=None) -> tuple[float, str | None]:
    """(the largest distance, m, of the poses' anchor-to-attachment spans
    from the hanging lengths (:func:`hanging_lengths`) over every wire and
    sample; a one-line warning when some wire is off by more than
    :data:`LENGTH_MISMATCH_WARN` of its length, else None).  ``com`` (k, 3)
    m world, ``R`` (k, 3, 3) body -> world.  A record in another frame or of
    another rig gives wire directions, hence tensions and inertia, that are
    not this rig's."""
    lengths, which = hanging_lengths(scene, rest)
    span = np.linalg.norm(com[:, None, :] + np.einsum("kij,nj->kni", R, scene.attachments) - scene.anchors, axis=-1)
    off = np.max(np.abs(span - lengths), axis=0)
    worst = int(np.argmax(off / lengths))
    warning = None
    if off[worst] > LENGTH_MISMATCH_WARN * lengths[worst]:
        warning = (f"--motion: the recorded poses are up to {off[worst]:.3g} m off the {which}length of wire "
                   f"{worst + 1} ({off[worst] / lengths[worst]:.1%}): the record does not fit this config's "
                   "rig (another frame, units or rig?); the wire directions and all figures from them are suspect")
    return float(off.max()), warning


def interior(rec: MotionRecord) -> slice:
    """The samples of ``rec`` the inertia is fitted on: all but the first and
    last ``SG_WINDOW // 2`` of an evenly sampled record, whose local fits are
    evaluated off their centre (the second derivative's noise gain 6-24
    times the centre's, session 19: with 0.5 mrad of attitude noise those 8
    samples of 513 made the sandwich std range 0.02-0.16 for a spread of
    0.057 kg m^2), evenly sampled or not; all of a record too short for
    the noise's estimate (:func:`alpha_noise`)."""
    if rec.alpha_noise is None:
        return slice(0, len(rec.t))
    return slice(SG_WINDOW // 2, len(rec.t) - SG_WINDOW // 2)


def differentiation_error(rec: MotionRecord) -> float:
    """The relative error of the angular acceleration of :func:`derivatives`'
    local quartic fits at the record's dominant frequency (the ratio of the
    RMS angular acceleration, its noise's power removed, to the RMS angular
    velocity about its mean, rad/s): ``|H(w) / (-w^2) - 1|``, ``H`` the
    second-derivative filter's response, times :data:`DIFFERENTIATION_SAFETY`.
    A systematic error of the inertia of that relative size (alpha scales
    the design); for jittered time stamps the RMS over the interior samples
    of each one's fit's error at the actual times; 0 for a record too short
    for the noise's estimate.  It replaces (session 19) the
    difference between the quartic fits' and interpolating quintic
    splines' estimates, which on a noisy record measured the splines' noise
    (0.5 mrad of attitude noise: 83 % of Izz), not the fits' truncation."""
    from scipy.signal import savgol_coeffs

    if rec.alpha_noise is None:
        return 0.0
    sl = interior(rec)
    h = float(np.mean(np.diff(rec.t)))
    w, a = rec.omega[sl], rec.alpha[sl]
    power = max(float(np.mean(np.sum(a ** 2, axis=1))) - float(np.trace(rec.alpha_noise)), 0.0)
    spread = float(np.mean(np.sum((w - w.mean(axis=0)) ** 2, axis=1)))
    if spread <= 0 or power <= 0:
        return 0.0
    freq = math.sqrt(power / spread)
    if not evenly_sampled(rec.t):  # each sample's own fit at its actual times: the RMS of their errors
        from .local_fits import local_weights, second_derivative_error

        start, W = local_weights(rec.t, SG_WINDOW, SG_ORDER)
        err = second_derivative_error(rec.t, start, W, freq)[sl]
        return DIFFERENTIATION_SAFETY * float(np.sqrt(np.mean(err ** 2)))
    c2 = savgol_coeffs(SG_WINDOW, SG_ORDER, deriv=2, delta=h, use="dot")
    H = float(np.sum(c2 * np.cos(freq * h * (np.arange(SG_WINDOW) - SG_WINDOW // 2))))
    return DIFFERENTIATION_SAFETY * abs(H / -freq ** 2 - 1.0)


DIFFERENTIATION_SAFETY = 2.0
"""Factor on the filter's error at the dominant frequency in
:func:`differentiation_error`: a real pendulum's motion carries harmonics
and other modes, whose error grows as the frequency's fourth power (the
drone's 0.1 rad torsion record, ``simulate --out``, 64 samples a period:
Izz 3.6e-5 off, the dominant frequency's error 3.0e-5 of it)."""


@dataclass(frozen=True)
class RecordInertia:
    """The inertia from a recorded motion's tensions (kg m^2).

    est : the fit (:func:`~bifilar.estimation.from_tensions.inertia_from_tensions`).
    std, std_geometry, interval, dof : per component, as
    :func:`~bifilar.estimation.from_tensions.record_std` gives them (NaN /
    None for a component not determined).  std_differentiation : the
    differentiation's systematic part (:func:`differentiation_error`).
    dilution : per component, how far plain least squares would have pulled
    the value toward zero by the poses' noise (``1 - plain / corrected``; 0
    for a record too short for the noise's estimate, not corrected).  noise_undetermined :
    components whose design the poses' noise swamps
    (:data:`~bifilar.estimation.design_noise.DILUTION_MAX`).
    attitude_noise : the estimated attitude noise, rad RMS per axis (None
    where not estimated).  products_held : the products of inertia held
    for that noise (:data:`PRODUCT_NOISE_MAX`) which a plain fit without the
    hold would not find poorly excited (those are not excited), listed as
    held, not as poorly excited (a column the noise swamps is in
    ``noise_undetermined`` too, which the CLI names first).
    """

    est: object
    std: dict
    std_geometry: dict
    interval: dict
    dof: dict
    std_differentiation: dict
    dilution: dict
    noise_undetermined: list
    attitude_noise: float | None
    products_held: list = ()


def record_inertia(scene: Scene, rec: MotionRecord, components: tuple, geometry: dict) -> RecordInertia:
    """Inertia ``components`` of ``scene``'s body from the recorded motion
    ``rec`` and its tensions, on the interior samples (:func:`interior`),
    the least squares corrected for the noise of the differentiated
    attitude (:mod:`~bifilar.estimation.design_noise`), the config's
    geometry's std ``geometry`` (m, ``position`` / ``com`` overrides of the
    defaults) and the differentiation's systematic error
    (:func:`differentiation_error`) budgeted as
    :func:`~bifilar.estimation.from_tensions.record_std` does."""
    from ..rotations import quat_to_matrix
    from .design_noise import DILUTION_MAX, design_noise
    from dataclasses import replace

    from .from_tensions import (COMPONENTS, POORLY_EXCITED, component_scale, euler_design, inertia_from_tensions,
                                record_std)

    sl = interior(rec)
    y = rec.y[sl]
    args = (scene, rec.t[sl], y[:, 0:3], quat_to_matrix(y[:, 3:7]), rec.omega[sl], rec.tensions[sl])
    noise_rms = None
    if rec.alpha_noise is not None:
        noise_rms = math.sqrt(float(np.trace(rec.alpha_noise)) / (3 * _second_derivative_gain(rec.t)))
    hold = tuple(c for c in components if c in PRODUCTS and noise_rms is not None and noise_rms > PRODUCT_NOISE_MAX)
    est = inertia_from_tensions(*args, alpha=rec.alpha[sl], components=components, geometry=geometry,
                                alpha_noise=rec.alpha_noise, alpha_noise_rse=rec.alpha_noise_rse, hold=hold,
                                min_lag=MIN_LAG)
    e = differentiation_error(rec)
    diff = {c: e * abs(est.values[c]) for c in est.components}
    std, geo, interval, dof = record_std(est, differentiation=diff)
    # the rule of poorly_excited applied to the std with the differentiation's term (session 20: the CLI listed
    # such a component as poorly excited beside its printed value); not re-fitted: the term exceeds half the
    # scale only on records sampled a few times a period
    over = [c for c in est.components if std[c] > POORLY_EXCITED * component_scale(scene, c)]
    if over:
        nan = {c: math.nan for c in over}
        est = replace(est, std={**est.std, **nan}, poorly_excited=[c for c in est.components
                                                                   if c in est.poorly_excited or c in over])
        std, dof = {**std, **nan}, {**dof, **nan}
        geo = {**geo, **nan}
        interval = {**interval, **{c: [math.nan, math.nan] for c in over}}
    dilution, swamped = {c: 0.0 for c in components}, []
    if rec.alpha_noise is not None:
        plain = inertia_from_tensions(*args, alpha=rec.alpha[sl], components=components, geometry=geometry, hold=hold,
                                      min_lag=MIN_LAG)
        # only the components fitted (not held: a finite std) are said to be moved by the correction
        dilution = {c: (1 - plain.values[c] / est.values[c]) if est.values[c] and math.isfinite(est.std[c])
                    else 0.0 for c in components}
        A = euler_design(rec.omega[sl], rec.alpha[sl], components)
        power = np.sum(A ** 2, axis=(0, 1))
        S = np.diag(design_noise(rec.alpha_noise))
        # the noise is named only where a plain fit would have determined the component (a clean record's
        # barely moved axis, its "noise" the fits' truncation, keeps the not-excited reason and no warning)
        # a held product is judged as a plain fit without the hold judges it (session 23: held, it was "poorly
        # excited" in the plain fit whatever its motion, and the CLI printed every held product 'not excited')
        free = inertia_from_tensions(*args, alpha=rec.alpha[sl], components=components, geometry=geometry,
                                     min_lag=MIN_LAG) if hold else plain
        unexcited = [c for c in components if c in (free if c in hold else plain).poorly_excited]
        swamped = [c for j, c in enumerate(components) if c not in unexcited
                   and len(y) * S[COMPONENTS.index(c)] > DILUTION_MAX * max(power[j], 1e-300)]
        hold = tuple(c for c in hold if c not in unexcited)
    return RecordInertia(est, std, geo, interval, dof, diff, dilution, swamped, noise_rms, list(hold))


MIN_LAG = SG_WINDOW - 1
"""The least lag window (samples) of a record's sandwich std
(:func:`~bifilar.estimation.from_tensions._score_covariance`): the rates
are local fits over ``SG_WINDOW`` samples, so their noise (and the
scores') is correlated over ``SG_WINDOW - 1`` samples either way, which
the window chosen from the scores' own autocorrelation missed (3 samples
in 48 of 60 draws of the drone's torsion at a random phase with 1 mrad of
attitude noise: coverage 0.867, z sd 1.27; session 20)."""

PRODUCTS = ("Ixy", "Ixz", "Iyz")

PRODUCT_NOISE_MAX = 1e-6
"""rad RMS per axis: a record whose estimated attitude noise exceeds this
gives its products of inertia no value (:func:`record_inertia` holds them
at the config's values, :func:`product_noise_reason`).  The noise tilts
the recorded wire directions, so the wire torques about x and y carry it,
correlated with the same noise in the differentiated accelerations of the
products' columns, which :mod:`~bifilar.estimation.design_noise` does not
model (session 20, the drone's torsion solving Izz, Ixz, Iyz, 0.3 % load
cells, 30-40 draws: Iyz coverage 0.48 at 0.2 mrad, z up to 17; Izz beside
them 0.77 at 10 urad; at 1 urad 0.975 / 0.975 / 1.00, as on a clean
record, whose fits' truncation reads as ~7e-9 rad)."""


def product_noise_reason(fit: RecordInertia) -> str:
    """The ``reason`` of a product of inertia held for the record's attitude noise (:data:`PRODUCT_NOISE_MAX`)."""
    return (f"{product_noise_cause(fit)}: the product is held at the config's value because the noise tilts the "
            "recorded wire directions, and the torques it puts about x and y correlate with its noise in this "
            "product's accelerations, which the fit does not correct; record the attitude more finely (or filter "
            "it) to solve for the products")


def product_noise_cause(fit: RecordInertia) -> str:
    """The short cause (a table cell) of a product held for the record's
    attitude noise: the noise and :data:`PRODUCT_NOISE_MAX` in urad RMS per axis."""
    return f"held: attitude noise {_urad(fit.attitude_noise)} urad RMS above {_urad(PRODUCT_NOISE_MAX)} urad"


def _urad(rad: float) -> str:
    """``rad`` in urad, to 3 significant figures (no exponent below 1e7 urad)."""
    x = float(f"{rad * 1e6:.3g}")
    return f"{x:.0f}" if x >= 100 or x == int(x) else f"{x:g}"


DILUTION_WARN = 0.01
"""A correction for the poses' noise (``RecordInertia.dilution``) above this
fraction of a value is said in a warning."""


def pose_noise_warnings(fit: RecordInertia) -> list[str]:
    """One line when the attitude's noise moved a component by more than
    :data:`DILUTION_WARN` (the correction made, naming the cause), else none."""
    big = {c: d for c, d in fit.dilution.items() if c not in fit.noise_undetermined and abs(d) > DILUTION_WARN}
    if not big and not fit.noise_undetermined:
        return []
    what = ", ".join(f"{c} by {d:+.1%}" for c, d in big.items()) or "none corrected"
    return [f"--motion: the record's attitude noise ({fit.attitude_noise * 1e3:.2g} mrad RMS per axis, estimated from "
            f"the record) passes into the differentiated angular accelerations and pulls a plain fit toward zero; "
            f"corrected for it ({what}), the correction's uncertainty in the std"
            + (f"; {', '.join(fit.noise_undetermined)} not determined (the noise swamps the motion)"
               if fit.noise_undetermined else "")]


def pose_noise_reason(fit: RecordInertia) -> str:
    """The ``reason`` of a component the poses' noise leaves undetermined."""
    return (f"not determined: the record's attitude noise ({fit.attitude_noise * 1e3:.2g} mrad RMS per axis) puts more "
            "than half as much noise as motion into the differentiated angular accelerations about this axis, so "
            "neither a plain fit (pulled toward zero) nor its correction can be trusted; record the attitude more "
            "finely or excite this axis more")
