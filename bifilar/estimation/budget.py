"""The uncertainty budget of an inversion at its estimate: period and input
sensitivities, the gain matrix and each input's contribution
(:func:`bifilar.estimation.uncertainty.propagate`).  SI units.
"""

from __future__ import annotations

import numpy as np

from .measurements import COM_UNKNOWNS
from .problem import Problem
from .sensitivity import input_sigma, measured_inputs
from .uncertainty import gain_matrix, propagate, robust_sensitivity

def _budget(pb: Problem, p_hat, r_hat, method, rungs, best, unc):
    """Linear budget at the estimate; returns (LinearBudget, degenerate inputs, T_lin at p_hat)."""
    K = len(pb.measurements)
    vals = pb.values(p_hat)
    T_lin = pb.linear_periods(p_hat)
    Jp = pb.jacobian(p_hat) * r_hat[:, None]
    sig = np.array([m.std for m in pb.measurements])
    multi = len(pb.models) > 1
    cols: dict[str, np.ndarray] = {}
    sigmas: dict[str, float] = {}
    degenerate: list[str] = []
    solved_com = {n for n in pb.unknowns if n in COM_UNKNOWNS}
    for h, hm in enumerate(pb.models):
        ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
        if not ks:
            continue
        scene = hm.scene(vals)
        rest, ms_h, match = hm.locate(scene)
        names = [n for n in measured_inputs(scene) if not n.startswith("com.")]
        names += list(COM_UNKNOWNS)
        sens, failed = robust_sensitivity(scene, rest, ms_h, names, scheme="forward")
        pre = f"{hm.hanging.name}:" if multi else ""
        degenerate += [pre + n for n in failed]
        for j, n in enumerate(sens.names):
            col = np.zeros(K)
            for k in ks:
                col[k] = sens.jacobian[match[pb.mode_index[k]], j] * r_hat[k]
            if n.startswith("com."):
                # shared: a CoM shift in the reference frame (com_h = R com_ref)
                ax = "xyz".index(n[-1])
                for a in range(3):
                    key = f"com.{'xyz'[a]}"
                    if key in solved_com:
                        continue
                    cols[key] = cols.get(key, np.zeros(K)) + col * hm.R[ax, a]
                    sigmas[key] = input_sigma(scene, key, unc)
            elif n in ("mass", "gravity"):
                cols[n] = cols.get(n, np.zeros(K)) + col
                sigmas[n] = input_sigma(scene, n, unc)
            else:
                cols[pre + n] = col
                sigmas[pre + n] = input_sigma(scene, n, unc)
    in_names = list(cols)
    Jx = np.column_stack([cols[n] for n in in_names]) if in_names else np.zeros((K, 0))
    in_sig = np.array([sigmas[n] for n in in_names])
    G = gain_matrix(Jp, sig)
    extra = {}
    for k, m in enumerate(pb.measurements):
        lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
        if method == "nonlinear" and m.amplitude:
            sA = m.amplitude_std if m.amplitude_std is not None else unc["amplitude"] * m.amplitude
            dT_dA = T_lin[k] * 2 * (r_hat[k] - 1) / m.amplitude
            extra[f"amplitude[{lab}]"] = -G[:, k] * dT_dA * sA
    if method != best and best in rungs and "p" in rungs[best]:
        extra["model bias"] = np.abs(np.asarray(p_hat) - rungs[best]["p"])
    tn = []
    for m in pb.measurements:
        lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
        tn.append(f"timing[{lab}]")
    budget = propagate(list(pb.unknowns), Jp, sig, Jx, in_names, in_sig, extra=extra, timing_names=tn)
    return budget, degenerate, T_lin
