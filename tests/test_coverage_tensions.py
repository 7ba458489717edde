"""Inertia from tensions (``bifilar tensions``, thesis 7.2.2): the printed
std is the spread of the estimate over load-cell noise, and the 95 %
interval covers the config's inertia as often as it claims.

One simulated motion per rig (the model's exact tensions, angular velocity
and acceleration); N_DRAWS noisy copies of the tensions, noise sd 0.5 % of
the mean tension per wire, either white or first-order low-pass (AR(1)
with coefficient rho per sample: a load cell filtered and sampled fast),
independent between wires.  The truth is the config's inertia, the number
the motion was simulated from.

Two checks per scenario:

* the std is calibrated: the RMS of the printed stds over the draws is the
  empirical standard deviation of the errors within 3 / sqrt(2 N) (the
  relative std of a sample std from N draws) + 5 % (the lag window's
  truncation bias, measured 3 % at rho = 0.8).  Before the sandwich
  covariance the pooled white-noise std ``s^2 (A^T A)^-1`` was 8-55x too
  large in all four scenarios (ratios 22, 7.6, 55, 8.0): one ``s^2`` for
  all three torque rows, while a wire's tension noise moves the x and y
  torques far more than the z torque (and the pitch rig's y torque), so the
  quiet row's component got the noisy rows' variance; serial correlation,
  which alone would make the white std too small, was hidden under it.
* the interval ``value +- t(dof) std`` covers the truth 95 % of the time
  within the binomial band 3 sqrt(0.95 0.05 / N) (white noise), and at
  least that often for correlated noise (the effective dof is conservative
  there), never above 99.5 % (not an uninformative interval).

N_DRAWS = 400: band 3.3 % on the coverage, 10.6 % + 5 % on the std ratio.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest
from scipy.signal import lfilter

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.estimation.from_tensions import inertia_from_tensions
from bifilar.models import maximal as mx
from bifilar.rotations import quat_to_matrix

N_DRAWS = 400
P = 0.95
COV_BAND = 3 * math.sqrt(P * (1 - P) / N_DRAWS)
STD_BAND = 3 / math.sqrt(2 * N_DRAWS) + 0.05
IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2)}


@lru_cache(maxsize=None)
def _motion(config: str, mode: str):
    scene = load_scene(f"configs/{config}")
    rest = rest_pose(scene)
    res = simulate(scene, mode, 0.05, 4, rest=rest, modes=linear_modes(scene, rest), rtol=1e-11,
                   samples_per_period=200)
    _, alpha, _, _ = mx.solve_dynamics(res.y, mx.params_from_scenes(scene), stabilise=False)
    return scene, res.t, res.y[:, 0:3], quat_to_matrix(res.y[:, 3:7]), res.y[:, 10:13], alpha, res.tensions


@pytest.mark.parametrize("config,mode,comp,rho,seed", [
    ("thesis_lin1_torsion.yaml", "torsion", "Izz", 0.0, 1),
    ("thesis_lin1_torsion.yaml", "torsion", "Izz", 0.8, 2),
    ("thesis_lin2_pitch.yaml", "pitch", "Iyy", 0.0, 3),
    ("trifilar_kth.yaml", "torsion", "Izz", 0.5, 4),
])
def test_tension_inertia_std_and_interval_cover(config, mode, comp, rho, seed):
    scene, t, com, R, omega, alpha, T = _motion(config, mode)
    truth = scene.inertia[IDX[comp]]
    rng = np.random.default_rng(seed)
    sd = 0.005 * T.mean(axis=0)
    err, std, hit = [], [], 0
    for _ in range(N_DRAWS):
        e = rng.standard_normal(T.shape) * sd * math.sqrt(1 - rho ** 2)
        if rho:
            e[0] /= math.sqrt(1 - rho ** 2)  # stationary start
            e = lfilter([1.0], [1.0, -rho], e, axis=0)
        est = inertia_from_tensions(scene, t, com, R, omega, T + e, alpha=alpha, components=(comp,))
        assert comp not in est.poorly_excited
        err.append(est.values[comp] - truth)
        std.append(est.std[comp])
        lo, hi = est.interval95(comp)
        hit += lo <= truth <= hi
    ratio = math.sqrt(np.mean(np.square(std))) / float(np.std(err))
    cov = hit / N_DRAWS
    assert abs(ratio - 1) <= STD_BAND, f"printed std / actual spread = {ratio:.3f}"
    assert cov >= P - COV_BAND, f"coverage {cov:.3f}"
    assert cov <= (P + COV_BAND if rho == 0 else 0.995), f"coverage {cov:.3f}"
