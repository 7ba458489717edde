"""Dropped frames put back: the time base of a record without its time column.

A record read at a stated sample rate (``--sample-rate``) whose camera
dropped frames has the nominal time base ``t_j = j dt`` where the frames'
own times are ``(j + N_j) dt``, ``N_j`` the frames dropped before sample
``j`` (a non-decreasing whole number).  The oscillation's phase at sample
``j`` is then ``theta_j = omega (j + N_j) dt + phi``: divided by one frame's
phase ``omega dt`` (at the TRUE ``omega``) it is a whole number plus a
constant.  :func:`recover_frames` searches ``omega`` for that lattice:

``R(omega) = | sum_j w_j exp(2 pi i theta_j / (omega dt)) |``

(``theta_j`` the unwrapped phase of the analytic signal of the record, its
one-cycle local mean removed; ``w_j`` the squared local amplitude,
normalised).  At the true ``omega`` every sample lies on the lattice and
``R`` is the noise's ``sum w_j exp(-2 pi^2 (sigma_y / (a_j omega dt))^2)``
(``R_pred``); at the fit's ``omega`` (short by the drops' share) the phases
spread over it and ``R`` is small.  The peak's width is about one frame
over the record (``1 / n`` in relative frequency), so the search steps by a
quarter of it over ``SEARCH_SPAN`` below the fit's frequency (dropped frames
only shorten the nominal period).  The phases at the peak, rounded, give
``N_j``; the record is then refitted on ``(j + N_j) dt``.

Accepted only where it explains the record (design.md "dropfix, session
17" measured each threshold on synthetic drops and on clean, beating,
chirping, quantised and real records): the peak ``R`` above
``MIN_LATTICE`` and above ``MIN_LATTICE_SHARE`` of ``R_pred`` (a beat or a
chirp leaves a lattice far weaker than its noise allows), the recovered
``N`` rising with few falls (``MAX_FALL_SHARE``), and the refit's residual
rms below ``MAX_RMS_RATIO`` of the nominal fit's (a beat the two-mode model
had explained fits worse on a "corrected" time base).  SI units: time s,
frequency Hz, phase rad.
"""

from __future__ import annotations

import math

import numpy as np

#: the search for the lattice: from this share below the fit's angular
#: frequency ... (6 % dropped frames; a camera dropping more is no clock)
SEARCH_SPAN = 0.06
#: ... to this share above it (the fit's own error)
SEARCH_ABOVE = 0.003
#: the lattice's strength needed: a record without a lattice (a beat, a
#: chirp, a drop record too noisy to show it) peaked at 0.04-0.10 in the
#: measurements (design.md), the resolved drop records at 0.12-0.93
MIN_LATTICE = 0.12
#: ... and this share of what the record's noise allows (isolated drops:
#: 0.5-0.95 of it, dense ones 0.31-0.5 (the analytic signal smears each
#: step over a few samples); chirps 0.20-0.30, beats 0.18-0.45, the KTH
#: records under 0.27)
MIN_LATTICE_SHARE = 0.25
#: the recovered count's curvature along the record, in standard errors of
#: a Poisson staircase (drops at a constant rate: -2.5 .. +0.6 measured),
#: above which it is a frequency drifting with the amplitude (a chirp:
#: +2.5 .. +9.7), not drops
MAX_CURVATURE_Z = 2.0
#: the recovered drop count may fall back (noise at a step) at most this
#: share of the times it rises
MAX_FALL_SHARE = 1.0 / 3.0
#: the refit on the recovered time base must leave at most this share of the
#: nominal fit's residual rms (drops: 0.07-0.80; a beat's false lattice
#: 1.1-11)
MAX_RMS_RATIO = 0.9
#: records longer than this are not searched (the search's cost grows as
#: the square of the length; a camera's record is far shorter)
MAX_SAMPLES = 12_000
#: fewer samples a cycle than this: not searched
MIN_SAMPLES_PER_CYCLE = 8


def _lattice(theta, wgt, omega, dt):
    return np.abs(np.exp(2j * np.pi * np.outer(1.0 / (np.atleast_1d(omega) * dt), theta)) @ wgt)


def recover_frames(t, y, frequency: float) -> dict | None:
    """The frames dropped from a uniformly sampled record ``(t`` in s, ``y``
    in any unit) of an oscillation fitted at ``frequency`` (Hz, on the
    nominal time base).

    Returns None when the record is not searched (under four cycles, under
    ``MIN_SAMPLES_PER_CYCLE`` samples a cycle, over ``MAX_SAMPLES``); else a
    dict: ``frequency`` (Hz, the lattice's), ``lattice`` (``R`` at the peak),
    ``lattice_at_fit`` (``R`` at ``frequency``), ``lattice_expected``
    (``R_pred``), ``dropped`` (frames, the recovered total), ``rises`` /
    ``falls`` (how often the recovered count steps up / down),
    ``curvature_z`` (:func:`_curvature_z`), ``t`` (s,
    the recovered time base ``(j + N_j) dt`` from ``t[0]``), ``edge``
    (samples at either end where the phase is not read: a drop there is
    not found), ``resolved`` (the lattice passes ``MIN_LATTICE``,
    ``MIN_LATTICE_SHARE``, ``MAX_FALL_SHARE`` and ``MAX_CURVATURE_Z``, at least one frame
    recovered; the refit's check is the caller's).
    """
    from scipy.ndimage import median_filter
    from scipy.signal import hilbert

    from .signal_timebase import detrended, uniform_cycles, white_noise

    u = uniform_cycles(t, y, frequency, MIN_SAMPLES_PER_CYCLE, MAX_SAMPLES)
    if u is None:
        return None
    t, y, dt, W = u
    n = y.size
    # the one-cycle local mean removed (an offset or a drift), then the analytic signal, its first and
    # last half cycle dropped (the transform's edge)
    k, yk = detrended(y, W)
    a = hilbert(yk)
    e = max(W // 2, 4)
    a, jj = a[e:-e], k[e:-e]
    theta = np.unwrap(np.angle(a))
    theta = theta - theta[0]
    amp = np.abs(a)
    wgt = amp ** 2
    if not np.sum(wgt) > 0:
        return None
    wgt = wgt / np.sum(wgt)
    omega_fit = 2.0 * np.pi * frequency
    h = omega_fit * dt
    # white noise sigma_y (third differences: the oscillation's own is A h^3, small) over the local amplitude
    sig_y = white_noise(y)
    with np.errstate(divide="ignore", over="ignore"):
        r_pred = float(np.sum(wgt * np.exp(-2.0 * np.pi ** 2 * (sig_y / np.maximum(amp, 1e-300) / h) ** 2)))
    m = int(4 * (SEARCH_SPAN + SEARCH_ABOVE) * jj.size) + 50
    omegas = omega_fit * (1.0 + np.linspace(-SEARCH_SPAN, SEARCH_ABOVE, m))
    R = np.concatenate([_lattice(theta, wgt, omegas[i:i + 64], dt) for i in range(0, m, 64)])
    i = int(np.argmax(R))
    omega = float(omegas[i])
    # the lattice's frame index of each sample, rounded: j + N_j (a median over a quarter cycle keeps a
    # noisy sample at a step from counting)
    r = theta / (omega * dt)
    off = np.angle(np.sum(wgt * np.exp(2j * np.pi * r))) / (2.0 * np.pi)
    N = np.round(r - off) - (jj - jj[0])
    N = median_filter(N, size=2 * (W // 4) + 1, mode="nearest")
    N = N - N[0]
    dN = np.diff(N)
    rises, falls = int(np.sum(dN > 0)), int(np.sum(dN < 0))
    Nfull = np.empty(n)
    Nfull[:jj[0]] = 0.0
    Nfull[jj[0]:jj[-1] + 1] = N
    Nfull[jj[-1] + 1:] = N[-1]
    Nfull = np.maximum.accumulate(Nfull)
    dropped = int(Nfull[-1])
    lat_fit = float(_lattice(theta, wgt, omega_fit, dt)[0])
    curv = _curvature_z(Nfull)
    resolved = bool(dropped >= 1 and R[i] >= MIN_LATTICE and R[i] >= MIN_LATTICE_SHARE * r_pred
                    and falls <= MAX_FALL_SHARE * rises and curv <= MAX_CURVATURE_Z)
    return {"frequency": omega / (2.0 * np.pi), "lattice": float(R[i]), "lattice_at_fit": lat_fit,
            "lattice_expected": r_pred, "dropped": dropped, "rises": rises, "falls": falls, "curvature_z": curv,
            "t": t[0] + (np.arange(n) + Nfull) * dt, "edge": int(max(jj[0], n - 1 - jj[-1])),
            "resolved": resolved}


def _curvature_z(N) -> float:
    """The quadratic coefficient of a least-squares fit of the drop count
    ``N`` (frames) over the record's share ``u`` in [0, 1], in standard
    errors of a staircase of ``N[-1]`` drops at a constant rate (a Poisson
    bridge: covariance ``D (min(u, v) - u v)``).  A drifting frequency
    bends ``N`` one way; random drops do not."""
    N = np.asarray(N, float)
    n = N.size
    u = (np.arange(n) + 0.5) / n
    P = np.linalg.pinv(np.column_stack([np.ones(n), u, u * u]))[2]
    D = max(float(N[-1] - N[0]), 1.0)
    m = min(n, 200)  # the weights lumped onto m points (the bridge's covariance is smooth)
    idx = np.linspace(0, n - 1, m).astype(int)
    Pm = np.add.reduceat(P, np.concatenate([[0], (idx[1:] + idx[:-1]) // 2]))
    uu = u[idx]
    var = D * float(Pm @ (np.minimum.outer(uu, uu) - np.outer(uu, uu)) @ Pm)
    return float(P @ N) / math.sqrt(var) if var > 0 else 0.0


def correction_std(period: float, n: int, dropped: int, edge: int, samples_per_cycle: int) -> float:
    """The recovered time base's own uncertainty in the refitted period (s).

    A frame dropped at the share ``u`` of a record of ``n`` samples biases a
    linear-phase fit by ``6 u (1 - u) / n`` of the period.  Not found: the
    drops within ``edge`` samples of either end (expected ``2 edge`` times
    the drop rate ``dropped / n``, each at ``u <= edge / n``, taken at the
    bound); misplaced: each found drop by up to the median filter's reach
    (a quarter cycle), at random.  Both in quadrature.
    """
    if n <= 0:
        return 0.0
    rate = dropped / n
    missed = 2.0 * edge * rate * 6.0 * (edge / n) / n
    placed = 6.0 * (samples_per_cycle / 4.0) * math.sqrt(max(dropped, 1)) / n ** 2
    return float(period * math.hypot(missed, placed))
