"""How much to shorten a slack wire: the advice of a
:class:`~bifilar.errors.SlackWireError`, checked by solving the changed rig
(:func:`~bifilar.analysis.equilibrium.rest_pose`) before it is printed.
Lengths in m, tensions in N, world frame z up."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import ConvergenceError, InputError, SlackWireError
from ..scene import Scene
from .equilibrium import _NO_ADVICE, _polish, _wires_dependent, constraint_jacobian, rest_pose

#: the advised shortening of a slack wire gives it this fraction of an equal
#: share of the weight, ``m g / n``, at rest: shortening it by just its slack
#: leaves it straight but without load (0.03 N on a 5-wire rig, slack at
#: t = 0 of the next `simulate`)
ADVISED_SHARE = 0.25

#: the advice is given as an amount only if, with the printed lengths, every
#: wire carries at least this fraction of ``m g / n`` at rest (else it is
#: given as a lower bound)
ADVICE_FLOOR_SHARE = 0.125

NO_AMOUNT = ("; no amount was found that loads it without taking the load off another wire (on 4 or more wires "
             "the tensions can change by thousands of N per mm of a length, and then the wires' stretch shares the "
             "load): check it with `bifilar modes` after the change")


def slack_advice(scene: Scene, idx, gap, com, R, plain: str, heads: list) -> str:
    """The message advising how much to shorten the slack wires ``idx``
    (0-based; ``gap`` (m) the shortening that makes each just straight in
    the pose ``com`` (m, world), ``R`` (body -> world)) so that each carries
    :data:`ADVISED_SHARE` of ``m g / n`` at rest.  The amount is given when
    the rest pose of the rig with the printed lengths (to 0.1 mm, finer where
    the rig needs it) gives every wire at least :data:`ADVICE_FLOOR_SHARE`
    of ``m g / n``; else ``plain`` (the lower bound: by the gap alone a wire
    carries no load) with the reason no amount was found.  ``heads``: each
    wire's opening words (what is wrong with it), as in ``plain``.

    Newton's method on the shortenings over the equilibrium with every wire
    taut (multipliers free in sign, so the tensions are smooth in the
    lengths), continued from ``com``, ``R``, with finite-difference slopes;
    then one :func:`rest_pose` of the changed rig as the check.  ~10 ms."""
    n, W = scene.n_wires, scene.mass * scene.gravity
    target, floor = ADVISED_SHARE * W / n, ADVICE_FLOOR_SHARE * W / n
    L = np.asarray(scene.lengths, float)
    s0 = np.asarray(gap, float)
    m = len(idx)
    state = [np.asarray(com, float).copy(), np.asarray(R, float).copy(), None]

    def taut(s, keep=False):
        """Tensions (n,) N of the all-taut equilibrium with wires idx shortened by s (m), or None."""
        Ls = _shortened(L, idx, s)
        if np.any(Ls <= 0):
            return None
        sc = replace(scene, lengths=Ls)
        c, Rr, lam, kkt = _polish(sc, state[0].copy(), state[1].copy(), None if state[2] is None else state[2].copy())
        if not kkt < 1e-9:
            return None
        if keep:
            state[:] = [c, Rr, lam]
        return lam * np.linalg.norm(constraint_jacobian(sc, c, Rr)[0], axis=1)

    h = 1e-7 * float(np.max(L))
    s = s0.copy()
    T = taut(s, keep=True)
    if T is not None and _wires_dependent(replace(scene, lengths=_shortened(L, idx, s)), state[0], state[1]):
        return _dependent_advice(scene, idx, s0, floor, heads) or plain + NO_AMOUNT
    J = np.full((m, m), np.nan)
    for _ in range(20):
        if T is None:
            return plain + NO_AMOUNT
        miss = target - T[idx]
        if np.all(np.abs(miss) <= 0.01 * target):
            break
        for j in range(m):
            Tj = taut(s + h * np.eye(m)[j])
            if Tj is None:
                return plain + NO_AMOUNT
            J[:, j] = (Tj[idx] - T[idx]) / h
        try:
            step = np.linalg.solve(J, miss)
        except np.linalg.LinAlgError:
            return plain + NO_AMOUNT
        s = s + step
        T = taut(s, keep=True)
    else:
        return plain + NO_AMOUNT
    others = [j for j in range(n) if j not in idx and T[j] < floor]
    if others:
        ws = ", ".join(str(j + 1) for j in others)
        return (plain + f"; but no single amount gives every wire load: shortening {'it' if m == 1 else 'them'} "
                f"until {'it carries' if m == 1 else 'each carries'} {target:.3g} N ({ADVISED_SHARE:g} of m g / n) "
                f"leaves wire {ws} with {', '.join(format(T[j], '.3g') for j in others)} N (below "
                f"{ADVICE_FLOOR_SHARE:g} of m g / n): change the other wires or the anchors too")
    checked = _printed_lengths(scene, idx, s, lambda Tr: np.min(Tr) >= floor and np.all(Tr[idx] >= 0.5 * target))
    if checked is None:
        return plain + NO_AMOUNT
    Ls, Tr, res = checked
    digits = int(round(-math.log10(res)))
    # (with two or more slack wires one may need lengthening once the other is shortened)
    parts = [f"{heads[k]}: {'shorten' if L[i] >= Ls[i] else 'lengthen'} it by {abs(L[i] - Ls[i]) * 1000:.{max(digits - 3, 0)}f} "
             f"mm, to {Ls[i]:.{digits}f} m, so that it carries {Tr[i]:.3g} N at rest" for k, i in enumerate(idx)]
    slope = float(np.max(np.abs(np.diag(J)))) * 1e-3  # N per mm of a slack wire's own length (NaN: not sampled)
    fine = f"; a slack wire's tension changes by ~{slope:.3g} N per mm of its length" if np.isfinite(slope) else ""
    if res < 1e-4:
        fine += f", so cut {'it' if m == 1 else 'them'} to {res * 1000:g} mm"
    return ("; ".join(parts) + f" (the aim: {target:.3g} N, {ADVISED_SHARE:g} of m g / n = {W / n:.3g} N; checked: "
            f"every wire then carries at least {np.min(Tr):.3g} N{fine}; shortened by its slack alone a wire is "
            "straight but carries no load)")


def _shortened(L: np.ndarray, idx, s) -> np.ndarray:
    """Lengths ``L`` (m) with wires ``idx`` shortened by ``s`` (m)."""
    Ls = np.array(L, float)
    Ls[idx] -= s
    return Ls


def _printed_lengths(scene: Scene, idx, s, accept):
    """The lengths of wires ``idx`` shortened by ``s`` (m) as printed, to
    0.1 mm, else 0.01 mm, else 1 um: the first whose rig's rest pose has
    tensions ``T`` with ``accept(T)``, as (lengths (n,) m, T (n,) N,
    resolution m); None if none has."""
    L = np.asarray(scene.lengths, float)
    token = _NO_ADVICE.set(True)
    try:
        for res in (1e-4, 1e-5, 1e-6):
            Ls = L.copy()
            Ls[idx] = np.round((L[idx] - s) / res) * res
            try:
                T = rest_pose(replace(scene, lengths=Ls)).tensions
            except (InputError, ConvergenceError):
                continue
            if accept(T):
                return Ls, T, res
        return None
    finally:
        _NO_ADVICE.reset(token)


def _dependent_advice(scene: Scene, idx, s0, floor, heads: list) -> str | None:
    """Advice for slack wires ``idx`` that, shortened by their slack ``s0``
    (m), make the wires dependent (parallel vertical wires: a table's legs):
    no shortening past that loads them without slackening another, so the
    advice is that length, if its rig hangs with the model's split (least squares of T_i / L_i)
    giving every wire at least ``floor`` N; else None."""
    checked = _printed_lengths(scene, idx, s0, lambda T: np.min(T) >= floor)
    if checked is None:
        return None
    Ls, T, res = checked
    more = Ls.copy()
    more[idx] -= 10 * res
    token = _NO_ADVICE.set(True)
    try:
        rest_pose(replace(scene, lengths=more))
        shorter = ""
    except SlackWireError:  # (which wire can hinge on rounding: a CoM on a diagonal of a table)
        shorter = f"; {10 * res * 1000:g} mm shorter leaves another wire slack"
    except (InputError, ConvergenceError):
        shorter = ""
    finally:
        _NO_ADVICE.reset(token)
    digits = int(round(-math.log10(res)))
    parts = [f"{heads[k]}: shorten it by {'exactly that much' if s0[k] > 0 else 'nothing'}, to {Ls[i]:.{digits}f} m"
             for k, i in enumerate(idx)]
    return ("; ".join(parts) + f": then the {scene.n_wires} wires are dependent (like a table's legs: their tensions "
            f"are statically indeterminate, set by the wires' stretch and a fraction of a mm of length); the "
            f"model's split (least squares of T_i / L_i) gives every wire at least {np.min(T):.3g} N{shorter}")
