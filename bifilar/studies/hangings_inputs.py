"""The multi-hanging plan's stated amplitude: the amplitude factor's
derivative in the measured inputs, ``dr/dx``, in the joint fit's budget,
as ``invert --measurements`` measures it, where it can change a sigma (a
sweep point's counterpart: :mod:`bifilar.studies.point_inputs`).

``invert`` fits ``T_lin(p, x) r(A; p, x) = T`` to every timed period, so
an input ``x`` (its standard uncertainty ``s_x``, its columns over the
periods ``X_x = r dT_lin/dx s_x``) moves the estimate by ``-Gf (X_x +
T_lin dr/dx s_x)``, ``Gf`` the gain of the full rows ``Jf = r dT_lin/dp +
T_lin dr/dp`` (:func:`~bifilar.estimation.budget._with_factor_gain`); the
plan without them keeps ``-G X_x``, ``G`` the gain of ``Jp = r
dT_lin/dp``.  The two agree where the factor depends on the input as on
the unknowns: ``dr/dx s_x = dr/dp u_x`` with ``u_x = G X_x`` (then ``X_x +
T_lin dr/dp u_x = Jf u_x + res_x``, ``res_x = X_x - Jp u_x``, the part of
the input's columns no unknown explains).  In general the term moves by
``d_x = Gf res_x + Gf T_lin e_x`` with ``e_x = dr/dx s_x - dr/dp u_x``
per period: the first part is known without a run, the second is bounded
as a point bounds it, ``|e_x| <= K A^2 s_x / L`` per period
(:data:`~bifilar.studies.point_inputs.FACTOR_INPUT_K`; the mass: ``/ m``),
so a component's sigma moves by at most ``sqrt(sum_x (|Gf res_x| + |Gf|
T_lin K A^2 s_x / L)^2)`` (the triangle inequality; an input measured once
for several hangings is one ``x``, its share per hanging's input carried
through :func:`~bifilar.studies.hangings._input_map` in absolute value).
The assumption is the point's, measured on rotation modes; a swing's
factor (a mode whose kinetic energy is mostly translation, :func:`is_swing`)
departs far more: ``|e| L / A^2`` (a single mode, invert's own ``dr/dx``)
up to 16 on the audit's unequal trifilar at spacing 0.3-0.45 (its swing-x,
the CoM height's term) and 51-794 at spacing 0.6 (swings coupled to the
rotations), so a plan that times a swing has no bound (``inf``; JSON
``null``) and measures ``dr/dx`` whenever an amplitude is stated.  Where the bound exceeds
:data:`~bifilar.studies.point_inputs.FACTOR_INPUT_ENOUGH` of a
component's sigma, the plan measures ``dr/dx`` of every timed mode (one
forward-difference run per input without an exact route, every hanging's
in one batched call, :func:`~bifilar.studies.point_inputs.measure_factor_inputs_many`)
and the inputs take ``invert``'s terms.  SI units; the unknowns in units of
each component's scale (as :func:`~bifilar.studies.hangings.plan_hangings`
evaluates them).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from ..errors import BifilarError
from .point_inputs import FACTOR_INPUT_ENOUGH, FACTOR_INPUT_K, _bound_scale, measure_factor_inputs_many


def is_swing(mode) -> bool:
    """Whether a :class:`~bifilar.analysis.modes.Mode`'s kinetic energy is
    mostly translation (a swing or bounce, as labelled; its shape's largest
    entry, which sets the amplitude's unit, may be a rotation)."""
    return int(np.argmax(mode.energy_share)) < 3


def row_order(chosen: list) -> list:
    """The chosen (hanging, mode) pairs in the order of the joint fit's
    rows: by hanging, each hanging's modes as chosen."""
    return [(hi, k) for hi in sorted({a for a, _ in chosen}) for a, k in chosen if a == hi]


def keyed(maps: list, rows: list, raw: dict, absolute: bool = False) -> np.ndarray:
    """(K, O_1 + .. + O_H + S) columns of the joint fit's inputs: each
    used hanging's own inputs (a block of its rows), then the shared ones,
    from ``raw`` {hanging index: (its rows, R) per raw input of
    :func:`~bifilar.studies.hangings._input_map`} and ``maps`` (per
    candidate hanging its ``_input_map``); ``absolute``: through the maps'
    absolute values (a bound)."""
    used = sorted({hi for hi, _ in rows})
    width = [maps[hi][1].shape[1] for hi in used]
    n_sh = maps[used[0]][2].shape[1] if used else 0
    out = np.zeros((len(rows), sum(width) + n_sh))
    r0, c0 = 0, 0
    for hi, w in zip(used, width):
        _, Mo, Ms = maps[hi]
        Mo, Ms = (np.abs(Mo), np.abs(Ms)) if absolute else (Mo, Ms)
        block = raw[hi]
        n = len(block)
        out[r0:r0 + n, c0:c0 + w] = block @ Mo
        out[r0:r0 + n, sum(width):] = block @ Ms
        r0, c0 = r0 + n, c0 + w
    return out


def _gain(J: np.ndarray) -> np.ndarray:
    return np.linalg.solve(J.T @ J, J.T)


def factor_bound(Jp: np.ndarray, Jf: np.ndarray, X: np.ndarray, Eb: np.ndarray) -> np.ndarray:
    """Per unknown, the bound (module docstring; the unknowns' units) on
    how far its sigma moves when the inputs' terms take the measured
    ``dr/dx``: ``Jp``, ``Jf`` (K, P) the fit's rows without and with the
    factor's ``dr/dp``, ``X`` (K, N) the inputs' columns (s), ``Eb`` (K,
    N) the bound on ``T_lin |e_x|`` per period and input (s)."""
    G, Gf = _gain(Jp), _gain(Jf)
    known = Gf @ (X - Jp @ (G @ X))
    return np.sqrt(np.sum((np.abs(known) + np.abs(Gf) @ Eb) ** 2, axis=1))


def joint_factor_inputs(hs: list, maps: list, chosen: list, amp: dict, unc: dict, st, Jp: np.ndarray,
                        Jf: np.ndarray, sigma: np.ndarray, runs: bool = True) -> tuple:
    """The inputs' columns of the joint fit at the stated amplitude, with
    the factor's ``dr/dx`` where it can matter (module docstring).
    ``hs``, ``maps``: the candidate hangings and their
    :func:`~bifilar.studies.hangings._input_map`; ``chosen`` (hanging,
    mode) pairs; ``amp`` :func:`~bifilar.studies.hangings._amplitude_terms`;
    ``Jp``, ``Jf`` the fit's rows in :func:`row_order`; ``sigma`` each
    unknown's sigma without the terms; ``runs`` False: the bound only.  Returns (the columns ``X + T_lin
    dr/dx s_x`` (K, N) s, or None when not measured; the bound relative to
    each sigma, 0 where measured; a note or None)."""
    rows = row_order(chosen)
    used = sorted({hi for hi, _ in rows})
    A = float(st.amplitude)

    def per_hanging(f):
        return {hi: np.array([f(hi, k) for a, k in rows if a == hi], float).reshape(-1, len(maps[hi][0]))
                for hi in used}

    r = {key: amp[key][0] for key in rows}
    T = {key: float(hs[key[0]].sens.periods[key[1]]) for key in rows}
    X = keyed(maps, rows, per_hanging(lambda hi, k: np.nan_to_num(
        np.array([hs[hi].sens.column(n)[k] for n in maps[hi][0]]), nan=0.0) * r[(hi, k)]))
    Eb = keyed(maps, rows, per_hanging(lambda hi, k: T[(hi, k)] * FACTOR_INPUT_K * A * A * np.array(
        [_bound_scale(hs[hi].scene, n) for n in maps[hi][0]])), absolute=True)
    from .hangings import gravity_column

    # g's shared column (stated only): r dT_lin/dg s_g, its dr/dg exactly 0 (no bound, no run)
    Xg = np.array([gravity_column(hs[hi], unc)[k] * r[(hi, k)] for hi, k in rows]).reshape(len(rows), -1)
    X, Eb = np.hstack([X, Xg]), np.hstack([Eb, np.zeros_like(Xg)])
    bound = factor_bound(Jp, Jf, X, Eb)
    rel = np.where(sigma > 0, bound / np.where(sigma > 0, sigma, 1.0), math.inf)
    if any(is_swing(hs[hi].sens.modes.modes[k]) for hi, k in rows):
        rel = np.full(len(rel), math.inf)  # a swing timed: no bound holds (module docstring)
    if not np.any(rel > FACTOR_INPUT_ENOUGH) or not runs:
        return None, rel, None
    items = [(SimpleNamespace(scene=hs[hi].scene, sens=hs[hi].sens, rest=hs[hi].sens.rest, ms=hs[hi].sens.modes,
                              amplitude=A), {k: amp[(a, k)][3] for a, k in rows if a == hi}) for hi in used]
    try:
        measured = dict(zip(used, measure_factor_inputs_many(items, unc, st)))
    except BifilarError:
        return None, rel, "the runs for dr/dx could not be made: the inputs' terms take the factor to depend on them as on the unknowns"
    failed = sorted({n for hi in used for dx, f in measured[hi].values() for n in f})
    if failed:
        return None, rel, ("no dr/dx measured for " + ", ".join(failed) + ": the inputs' terms take the factor "
                           "to depend on them as on the unknowns")
    F = keyed(maps, rows, per_hanging(lambda hi, k: T[(hi, k)] * np.array(
        [measured[hi][k][0].get(n, 0.0) for n in maps[hi][0]])))
    F = np.hstack([F, np.zeros_like(Xg)])
    return X + F, np.zeros_like(rel), None
