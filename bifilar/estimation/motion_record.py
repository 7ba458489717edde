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
    """

    t: np.ndarray
    y: np.ndarray
    tensions: np.ndarray
    omega: np.ndarray
    accel: np.ndarray
    alpha: np.ndarray
    alt: tuple


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
    # noise; unevenly sampled records take quintic interpolating splines (as accurate, noisier)
    conj = q * np.array([1, -1, -1, -1])

    def rates(spline):
        qdot, qddot = derivatives(t, q, spline)
        # body axes; alpha is d/dt of omega: conj(qdot) qdot is a scalar for a unit q
        return 2 * quat_multiply(conj, qdot)[:, 1:], 2 * quat_multiply(conj, qddot)[:, 1:]

    omega, alpha = rates(False)
    vel, accel = derivatives(t, com, False)
    y = np.zeros((len(t), 13))
    y[:, 0:3], y[:, 3:7], y[:, 7:10], y[:, 10:13] = com, q, vel, omega
    return MotionRecord(t, y, T, omega, accel, alpha, rates(True))


def derivatives(t: np.ndarray, x: np.ndarray, spline: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """First and second time derivatives of samples ``x`` (k, m) at times ``t`` (k,), s: local quartic
    least-squares fits over 9 samples (Savitzky-Golay) when the sampling is even, else (or with
    ``spline``) quintic interpolating splines."""
    dt = np.diff(t)
    if not spline and np.ptp(dt) <= 1e-6 * np.median(dt):
        from scipy.signal import savgol_filter

        h = float(np.mean(dt))
        return (savgol_filter(x, 9, 4, deriv=1, delta=h, axis=0), savgol_filter(x, 9, 4, deriv=2, delta=h, axis=0))
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
