"""Local polynomial fits at a record's own time stamps: derivatives of an
unevenly sampled (jittered) record, and their noise gains.

An evenly sampled record is differentiated by Savitzky-Golay filters
(local quartic least-squares fits over 9 samples,
:func:`~bifilar.estimation.motion_record.derivatives`); a record whose time
stamps jitter took quintic interpolating splines until session 20, which
pass the poses' noise with a gain that depends on the jitter and left the
inertia from tensions uncorrected for it (tensrec2: with 0.5 mrad of
attitude noise and +-0.3 of a step of jitter Izz came out at 1.5 % of its
value).  Here each sample gets the same local quartic fit over its 9
nearest samples (the window shifted inwards at the record's ends, as
``savgol_filter``'s ``mode="interp"``), solved at the actual times, so that
the fits' weights -- hence the noise each derivative carries -- are known
sample by sample.

Units: ``t`` s; the weights of the d-th derivative in s^-d.
"""

from __future__ import annotations

import numpy as np

WINDOW, ORDER = 9, 4
"""The local fits' length (samples) and polynomial degree (as the evenly
sampled filters of :mod:`~bifilar.estimation.motion_record`)."""


def local_weights(t: np.ndarray, window: int = WINDOW, order: int = ORDER) -> tuple[np.ndarray, np.ndarray]:
    """(start (k,) int, weights (k, 3, window)): sample ``i``'s fit uses
    samples ``start[i] .. start[i] + window - 1`` (centred on ``i`` where
    the record allows), and its value, first and second derivative at
    ``t[i]`` are ``weights[i, d] @ x[start[i]:start[i] + window]`` (units of
    ``x`` per s^d).  ``t`` (k,) s, strictly increasing, ``k >= window``."""
    t = np.asarray(t, float)
    k, half = len(t), window // 2
    start = np.clip(np.arange(k) - half, 0, k - window)
    idx = start[:, None] + np.arange(window)
    h = float(np.median(np.diff(t)))
    tau = (t[idx] - t[:, None]) / h  # (k, window), dimensionless local time
    V = tau[..., None] ** np.arange(order + 1)  # (k, window, order + 1)
    P = np.linalg.pinv(V)  # (k, order + 1, window): the fit's coefficients per sample
    W = np.stack([P[:, 0], P[:, 1] / h, 2.0 * P[:, 2] / h ** 2], axis=1)
    return start, W


def apply(start: np.ndarray, W: np.ndarray, x: np.ndarray, deriv: int) -> np.ndarray:
    """(k, ...) the ``deriv``-th derivative (0, 1 or 2) of samples ``x`` (k,
    ...) from :func:`local_weights`' ``(start, W)``."""
    idx = start[:, None] + np.arange(W.shape[2])
    return np.einsum("kw,kw...->k...", W[:, deriv], np.asarray(x, float)[idx])


def derivatives(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and second time derivatives (units of ``x`` per s, per s^2) of
    samples ``x`` (k, m) at the times ``t`` (k,) s, by local quartic fits at
    the actual times (:func:`local_weights`)."""
    start, W = local_weights(t)
    return apply(start, W, x, 1), apply(start, W, x, 2)


def centre_weight(start: np.ndarray, W: np.ndarray) -> np.ndarray:
    """(k,) each sample's own weight in its smoothed value (the hat
    matrix's diagonal ``c_0``): the residual ``x - S x`` of white noise of
    variance ``s^2`` has the variance ``s^2 (1 - c_0)``."""
    k = len(start)
    return W[np.arange(k), 0, np.arange(k) - start]


def second_derivative_gain(W: np.ndarray) -> np.ndarray:
    """(k,) s^-4: the sum of the squared weights of each sample's second
    derivative (white noise of variance ``s^2`` in ``x`` leaves ``s^2``
    times this in the second derivative)."""
    return np.sum(W[:, 2] ** 2, axis=1)


def second_derivative_error(t: np.ndarray, start: np.ndarray, W: np.ndarray, freq: float) -> np.ndarray:
    """(k,) the relative error ``|H_i(w) / (-w^2) - 1|`` of each sample's
    second derivative of a sinusoid of angular frequency ``freq`` (rad/s),
    ``H_i(w) = sum_j W_i2j exp(i w (t_j - t_i))`` the fit's response at
    the actual times (its odd part is nonzero where the window is not
    symmetric about the sample)."""
    idx = start[:, None] + np.arange(W.shape[2])
    H = np.sum(W[:, 2] * np.exp(1j * freq * (t[idx] - t[:, None])), axis=1)
    return np.abs(H / -freq ** 2 - 1.0)
