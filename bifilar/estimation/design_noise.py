"""Errors in the variables of the inertia from tensions: the angular
accelerations of a recorded motion are differentiated from noisy poses, so
the design of Euler's equations (:func:`~bifilar.estimation.from_tensions.
euler_design`) carries noise, and plain least squares pull every estimate
toward zero by the ratio of that noise's power to the motion's (regression
dilution; audit 18, row T2: Izz 11 % low in every draw with 0.5 mrad of
attitude noise, docs/design.md "tensrec, session 19").

The correction is the classical one for a known error covariance: with
``A = A_0 + D`` (``D`` the design's noise, zero mean, per-sample covariance
``S``), ``E[A^T A] = A_0^T A_0 + k S``, so ``(A^T A - k S) x = A^T b``
is unbiased to first order where ``A^T A x = A^T b`` is not.  The noise
of alpha dominates the design's: the angular velocity's enters multiplied
by the velocity itself, ``(omega h) ||c_1|| / ||c_2||`` (~3 % at 64
samples a period) of alpha's, and the torques' (the noisy wire directions)
correlate with alpha's only through the filter's centre, ``(omega h)^2``
of the correction: both are left out.
"""

from __future__ import annotations

import math

import numpy as np

from ..config.inertia import INERTIA_NAMES as COMPONENT_INDEX

DILUTION_MAX = 0.5
"""A component whose column's noise power is more than this fraction of
the column's power (``k S_jj / |A_j|^2``) is not determined: the
correction would be as large as the motion's own signal, and its
first-order expansion (and the estimated noise it rests on) no longer
bounds the error."""


def design_noise(alpha_noise: np.ndarray) -> np.ndarray:
    """(6, 6) the per-sample covariance of the design's errors over
    :data:`~bifilar.estimation.from_tensions.COMPONENTS` (kg^-2 m^-4 N^2
    m^2 per kg^2 m^4, i.e. (rad/s^2)^2), from ``alpha_noise`` (3, 3), the
    covariance of the noise in each sample of the body-axes angular
    acceleration: component ``j``'s column is ``E_j alpha + omega x (E_j
    omega)`` (``E_j`` the symmetric unit matrix of component ``j``), so its
    noise is ``E_j d`` and ``S_jl = E[d^T E_j E_l d] = tr(E_j E_l C)``."""
    E = []
    for c in COMPONENT_INDEX:
        i, j = COMPONENT_INDEX[c]
        e = np.zeros((3, 3))
        e[i, j] = e[j, i] = 1.0
        E.append(e)
    C = np.asarray(alpha_noise, float)
    return np.array([[float(np.trace(a @ b @ C)) for b in E] for a in E])


def corrected_normal_equations(As: np.ndarray, b: np.ndarray, scale: np.ndarray, noise: np.ndarray,
                               comps: tuple, fixed: list, xf: np.ndarray, k: int):
    """(the corrected estimate (m,) in the scaled unknowns ``x scale``, the
    scaled per-sample noise covariance ``S_cc`` (m, m), each sample's score
    offset (m,)) of ``(As^T As - k S_cc) x = As^T b + k S_cf x_f``.

    ``As`` (3k, m) the design divided by its column ``scale``; ``b`` (3k,)
    N m the torques less the held components' ``x_f`` (kg m^2) times their
    noisy columns (whose noise, correlated with the solved columns', is
    the ``S_cf`` term); ``noise`` (6, 6) :func:`design_noise`; ``k``
    samples.  The offset makes each sample's score ``As_k^T r_k + S_cc x +
    S_cf x_f`` zero-mean at the truth and their sum zero at the estimate,
    as the sandwich's covariance of the scores assumes."""
    from .from_tensions import COMPONENTS

    ic = [COMPONENTS.index(c) for c in comps]
    S_cc = noise[np.ix_(ic, ic)] / np.outer(scale, scale)
    S_cf = (noise[np.ix_(ic, [COMPONENTS.index(c) for c in fixed])] @ xf) / scale if fixed else np.zeros(len(ic))
    N = As.T @ As - k * S_cc
    x = np.linalg.lstsq(N, As.T @ b + k * S_cf, rcond=None)[0]
    return x, S_cc, S_cc @ x + S_cf


def correction_std(x: np.ndarray, x_plain: np.ndarray, rse: float) -> np.ndarray:
    """(m,) kg m^2: the std of the dilution correction ``x - x_plain``
    (corrected and plain least-squares estimates, kg m^2) from the relative
    standard error ``rse`` of the noise estimate it scales with (to first
    order the correction is proportional to the noise's variance)."""
    return np.abs(np.asarray(x) - np.asarray(x_plain)) * float(rse)


def undetermined_by_noise(noise_power: np.ndarray, N: np.ndarray) -> np.ndarray:
    """(m,) bool: components the design's noise leaves undetermined, its
    power ``noise_power`` (m,) (``k S_jj`` scaled, the columns' own scaled
    power being 1) above :data:`DILUTION_MAX`, or all of them when the
    corrected normal matrix ``N`` (m, m) is not positive definite."""
    bad = np.asarray(noise_power) > DILUTION_MAX
    if not np.all(np.isfinite(N)) or np.linalg.eigvalsh((N + N.T) / 2).min() <= 0:
        bad[:] = True
    return bad


def variance_rse(n_eff: float) -> float:
    """Relative standard error of a variance estimated from ``n_eff``
    independent normal residuals: ``sqrt(2 / n_eff)``."""
    return math.sqrt(2.0 / max(n_eff, 1.0))
