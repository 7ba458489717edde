"""Monte Carlo of the inertia-from-tensions std and 95 % interval (dev tool,
docs/design.md "Inertia from tensions: the std on short records").

For each rig, record length and load-cell noise (white, or AR(1) with
coefficient rho per sample, sd 0.5 % of the mean tension per wire,
independent between wires -- the generators of tests/test_coverage_tensions.py),
N noisy copies of the model's exact tensions are fitted for the excited
component.  Reported per cell:

* ``rms/sd``: the RMS of the printed stds over the exact sd of the
  estimate (the estimate is linear in the tension noise: its variance is
  ``sum_i sd_i^2 w_i^T C w_i`` with ``w_i`` the estimate's response to wire
  i's tension at each sample and ``C`` the noise's autocorrelation matrix,
  no Monte Carlo error);
* ``mean/sd``: the mean printed std over the same (Jensen: below rms/sd by
  ~1 / (4 dof));
* ``emp/sd``: the Monte Carlo sd of the estimates over the exact sd (a check
  of the exact one, +- 1 / sqrt(2 N));
* ``cover``: the fraction of 95 % intervals holding the config's inertia
  (Monte Carlo sd sqrt(0.95 0.05 / N) = 0.49 % at N = 2000).

Lengths: the first 101, 201, 501, 2001 samples of one 40-period run at 50
samples a period (one load cell sampled at one rate, recorded for longer).
Each cell has its own seed (the two bifilars' noise maps to the same
standardised torque noise, so one seed would repeat their numbers).

    python scripts/tension_std_coverage.py --draws 2000 > table.txt
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.linalg import toeplitz
from scipy.signal import lfilter

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's bifilar, not an installed copy

from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene
from bifilar.estimation.from_tensions import euler_design, inertia_from_tensions, wire_torque_body
from bifilar.models import maximal as mx
from bifilar.rotations import quat_to_matrix

IDX = {"Ixx": (0, 0), "Iyy": (1, 1), "Izz": (2, 2)}
RIGS = {"torsion": ("thesis_lin1_torsion.yaml", "torsion", "Izz"),
        "pitch": ("thesis_lin2_pitch.yaml", "pitch", "Iyy"),
        "trifilar": ("trifilar_kth.yaml", "torsion", "Izz")}
SPP = 50


@lru_cache(maxsize=None)
def _run(rig: str):
    config, mode, comp = RIGS[rig]
    scene = load_scene(f"configs/{config}")
    rest = rest_pose(scene)
    res = simulate(scene, mode, 0.05, 40, rest=rest, modes=linear_modes(scene, rest), rtol=1e-11,
                   samples_per_period=SPP)
    _, alpha, _, _ = mx.solve_dynamics(res.y, mx.params_from_scenes(scene), stabilise=False)
    return scene, comp, res.t, res.y[:, 0:3], quat_to_matrix(res.y[:, 3:7]), res.y[:, 10:13], alpha, res.tensions


def motion(rig: str, length: int):
    """The first ``length + 1`` samples of a 40-period run (2001 samples)."""
    scene, comp, *arrays = _run(rig)
    return (scene, comp, *(a[:length + 1] for a in arrays))


def exact_sd(scene, comp, com, R, omega, alpha, T, sd, rho):
    """sd (kg m^2) of the least-squares estimate of ``comp`` alone under the noise model."""
    A = euler_design(omega, alpha, (comp,)).reshape(-1, 1)
    L = np.linalg.pinv(A)  # (1, 3k)
    k, n = T.shape
    C = toeplitz(rho ** np.arange(k)) if rho else np.eye(k)
    var = 0.0
    for i in range(n):
        unit = np.zeros_like(T)
        unit[:, i] = 1.0
        J = wire_torque_body(scene, com, R, unit)  # (k, 3) torque per newton on wire i
        w = (L.reshape(k, 3) * J).sum(axis=1)  # (k,) response to wire i's tension at each sample
        var += sd[i] ** 2 * float(w @ C @ w)
    return math.sqrt(var)


def noise(rng, shape, sd, rho):
    e = rng.standard_normal(shape) * sd * math.sqrt(1 - rho ** 2)
    if rho:
        e[0] /= math.sqrt(1 - rho ** 2)  # stationary start
        e = lfilter([1.0], [1.0, -rho], e, axis=0)
    return e


def cell(rig, length, rho, draws, seed):
    scene, comp, t, com, R, omega, alpha, T = motion(rig, length)
    truth = scene.inertia[IDX[comp]]
    sd = 0.005 * T.mean(axis=0)
    sd_true = exact_sd(scene, comp, com, R, omega, alpha, T, sd, rho)
    rng = np.random.default_rng(seed)
    err, std, dof, hit = [], [], [], 0
    for _ in range(draws):
        est = inertia_from_tensions(scene, t, com, R, omega, T + noise(rng, T.shape, sd, rho), alpha=alpha,
                                    components=(comp,))
        err.append(est.values[comp] - truth)
        std.append(est.std[comp])
        dof.append(est.dof[comp])
        lo, hi = est.interval95(comp)
        hit += lo <= truth <= hi
    std = np.array(std)
    return dict(rig=rig, k=len(t), rho=rho, rms=math.sqrt(np.mean(std ** 2)) / sd_true,
                mean=float(np.mean(std)) / sd_true, emp=float(np.std(err, ddof=1)) / sd_true,
                bias=float(np.mean(err)) / sd_true, cover=hit / draws, dof=float(np.mean(dof)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=2000)
    ap.add_argument("--lengths", default="100,200,500,2000")
    ap.add_argument("--cases", default="torsion:0,torsion:0.8,pitch:0,pitch:0.5,trifilar:0,trifilar:0.5")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    print(f"draws {a.draws}: coverage MC sd {math.sqrt(0.05 * 0.95 / a.draws):.4f}")
    print("rig        rho   k     rms/sd mean/sd emp/sd bias/sd cover  dof")
    for c, case in enumerate(a.cases.split(",")):
        rig, rho = case.split(":")
        for n, length in enumerate(map(int, a.lengths.split(","))):
            t0 = time.process_time()
            r = cell(rig, length, float(rho), a.draws, (a.seed, c, n))
            print(f"{r['rig']:10s} {r['rho']:.1f} {r['k']:5d}  {r['rms']:.3f}  {r['mean']:.3f}  {r['emp']:.3f}"
                  f"  {r['bias']:+.3f}  {r['cover']:.4f} {r['dof']:6.1f}   ({time.process_time() - t0:.0f} s)",
                  flush=True)


if __name__ == "__main__":
    sys.exit(main())
