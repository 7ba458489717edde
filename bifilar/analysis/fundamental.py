"""The fundamental of one mode in a simulated run: its period and amplitude
as a record's fit reports them.

A release along a mode shape also excites the rig's other modes a little
(the nonlinear terms: the damped trifilar of tests/test_chirp_coupled_swing.py
at 0.095 rad carries its swings at 0.48 Hz, ~1e-4 rad in the torsion's
dominant coordinate).  The mean period between the first and last upward
crossings of the dominant coordinate (:func:`~bifilar.analysis.simulate.measured_period`)
then holds the swing's value at the two ends: over 20 cycles it moved by
1e-5 s with the number of cycles (-3.6e-6 s at 20 cycles, one std of a
60 Hz record's period), where a fitted record's period is its fundamental's
(the other oscillations fitted with it, :mod:`bifilar.estimation.signal_law`),
and its amplitude the fundamental's, not the release's (here 1.0003 times
it).  :func:`mode_fundamental` gives that pair from a run.

Frames and units: states ``Y`` (k, 13) as :func:`~bifilar.analysis.simulate.simulate`
returns them (world frame, SI), times in s; the amplitude in the unit of
the mode's dominant coordinate (rad, or m for a translation).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConvergenceError
from .equilibrium import RestPose
from .modes import ModeSet
from .simulate import relative_pose

#: harmonics of the fundamental fitted with it (with a constant): a pendulum's
#: third is ~A^2/200 of the fundamental, the next below 1e-6 at 0.3 rad
HARMONICS = 3
#: Gauss-Newton steps on the frequency at most (from the crossings' period, 3-5 suffice)
MAX_STEPS = 30
#: the step below which the frequency has converged (relative)
STEP_TOL = 1e-14


def _design(t: np.ndarray, omega: float) -> np.ndarray:
    cols = [np.ones_like(t)]
    for k in range(1, HARMONICS + 1):
        cols += [np.cos(k * omega * t), np.sin(k * omega * t)]
    return np.stack(cols, axis=1)


def _lsq(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``y`` on the (full-rank) columns of
    ``X``, by the normal equations of the columns scaled to unit norm (the
    columns are near-orthogonal sines and the frequency's: condition ~10).
    A thousand-row QR or SVD (``numpy.linalg.lstsq``) went to LAPACK's
    threads and cost 5-12 ms CPU each on a shared machine, the normal
    equations 0.02 ms."""
    s = np.sqrt(np.einsum("ij,ij->j", X, X))
    Xs = X / s
    return np.linalg.solve(Xs.T @ Xs, Xs.T @ y) / s


def _fit_frequency(t: np.ndarray, y: np.ndarray, omega0: float) -> float:
    """The angular frequency (rad/s) of the periodic function (constant and
    :data:`HARMONICS` harmonics) nearest ``y(t)`` in least squares, by
    Gauss-Newton from ``omega0`` (the amplitudes' columns and the
    frequency's, the model's derivative in it)."""
    w = float(omega0)
    beta = _lsq(_design(t, w), y)
    for _ in range(MAX_STEPS):
        X = _design(t, w)
        dw = np.zeros_like(t)
        for k in range(1, HARMONICS + 1):
            dw += k * t * (beta[2 * k] * np.cos(k * w * t) - beta[2 * k - 1] * np.sin(k * w * t))
        step = _lsq(np.c_[X, dw], y - X @ beta)
        if not np.all(np.isfinite(step)) or abs(step[-1]) > 0.05 * w:
            break
        beta = beta + step[:-1]
        w += step[-1]
        if abs(step[-1]) <= STEP_TOL * w:
            return w
    raise ConvergenceError(f"the fundamental's frequency of a simulated run did not converge (from "
                           f"{2 * math.pi / omega0:.9g} s)")


def mode_fundamental(t: np.ndarray, Y: np.ndarray, rest: RestPose, modes: ModeSet, index: int,
                     period0: float) -> tuple[float, float]:
    """(period s, amplitude) of the fundamental of mode ``modes.modes[index]``
    in the run ``t`` (s), ``Y`` (k, 13), whose crossings gave ``period0`` (s,
    the start of the search).

    The period is fitted on the mode's own coordinate, the mass-weighted
    projection of the pose on its shape (``q_k = phi_k^T M d / phi_k^T M
    phi_k``): the linear modes are M-orthogonal, so the other modes leave
    it at first order, and with them the end effect the crossings'
    period had (on the trifilar at 0.095 rad: 1.6442396 +- 3e-7 s for 10-40
    cycles against crossings' 1.644227-1.644236 s; 80 cycles of the
    dominant coordinate fitted with its two other oscillations 1.6442393 s).
    The amplitude is the fundamental's in the dominant coordinate with the
    other modes' linear parts taken out (``d_dom - sum_j q_j phi_j,dom``), at
    that frequency: what a record's fit of that coordinate reports (there
    0.0954744 against 80 fitted cycles' 0.0954723 and the release 0.095445)."""
    d = relative_pose(Y, rest)
    shapes = np.stack([m.shape for m in modes.modes], axis=1)  # (6, n)
    Mphi = modes.mass_matrix @ shapes
    Q = (d @ Mphi) / np.einsum("in,in->n", shapes, Mphi)  # (k, n) modal coordinates
    dom = modes.modes[index].dominant
    omega = _fit_frequency(t, Q[:, index] * shapes[dom, index], 2 * math.pi / period0)
    others = [j for j in range(shapes.shape[1]) if j != index]
    y = d[:, dom] - Q[:, others] @ shapes[dom, others]
    beta = _lsq(_design(t, omega), y)
    return 2 * math.pi / omega, math.hypot(beta[1], beta[2])
