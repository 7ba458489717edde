"""The full model's slope over the estimate's own uncertainty (invert only).

The nonlinear rung's budget takes the model period's derivative in the
unknowns as the *local* one at the estimate, ``r dT_lin/dp + T_lin dr/dp``
(``dr/dp`` a forward difference at :data:`~bifilar.estimation.solve.FACTOR_STEP`
of the scale, :func:`~bifilar.estimation.solve.stated_amplitude_law`).
Where the timed motion exchanges energy with another mode (a swing near
twice a pitch's period released at 0.2 m: docs/design.md "Estimation
audit, session 17", row B3) the mean period over the timed cycles wiggles
in the unknown on a scale smaller than the estimate's std, and the local
slope is that of one stretch of the wiggle (0.35x .. 1.5x the average on
that row): the std it gives was 0.6x .. 2.4x the realised spread.

:func:`secant_check` measures the slope again as a secant over the
estimate's 95 % interval, +-:data:`SECANT_REACH` std (two runs of the stated-amplitude model per unknown and
measurement) and, where the two differ by more than
:data:`SECANT_DISAGREE`, keeps the smaller slope magnitude (the larger
std) and warns.  SI units; the unknowns in the reference body axes.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import BifilarError
from .amplitude_runs import _unchecked_factor
from .problem import admissible

#: the relative difference between the secant and the local full-model slope above which the period is taken
#: as not smooth in the unknown over its std (a smooth factor's secant over +-1 std differs from its local slope
#: by the slope's curvature only: 1e-4 .. 1e-2 on the torsions and pitch of audit17 rows B1/B2, -0.3 .. +1.0 % on
#: the 26 shipped configs' records over +-1.96 std.  Session 17 took 0.2; audit17 row B3 with default input stds
#: (docs/design.md "secant2, session 18") had 4 of 30 draws at -17.5 .. -19.8 %, left on the too-steep local slope,
#: two of them outside their interval (z +2.05, +2.07): at 0.1 they are checked, coverage 0.900 -> 0.967)
SECANT_DISAGREE = 0.1
#: the secant's half-width in the estimate's std: the 95 % interval's (the slope must hold over the interval the
#: answer states; on audit17 row B3 over +-1 std the secant differed from the local slope by -18 .. -24 %, at the
#: threshold, over +-1.96 std by -22 .. -47 %, while the smooth torsions of row B1 differ by 1e-5 at any reach)
SECANT_REACH = 1.96
#: a difference of the two slopes counts only where it moves the period over the reach by more than this share of
#: the measurement's timing std (a period that does not depend on an unknown has slopes of ~1e-14 s per kg m^2 either
#: way, 100 % apart: the example file's torsion in Ixx); a single unknown's 10 % always moves it by > 0.19 of it
SECANT_SIGNIFICANT = 0.1
#: an end of the reach outside the physical tensors is brought in to their edge, and where a run fails the reach is
#: halved, this many times; with less than 1/2**SECANT_HALVINGS of the interval's width left, a warning (the local
#: slope then stands unchecked)
SECANT_HALVINGS = 2


def secant_check(pb, p, r, laws, std, rtol: float = 1e-10, multi: bool = False,
                 ctx=None) -> tuple[list[str], bool]:
    """Compare each stated-amplitude measurement's local full-model slope
    ``dT/dp_j = r dT_lin/dp_j + T_lin dr/dp_j`` (s per unit of ``p_j``:
    kg m^2 or m) with the secant ``(T(p + h e_j) - T(p - h e_j)) / (2 h)``
    of the full model period ``T = T_lin r`` over ``h`` =
    :data:`SECANT_REACH` times the estimate's std (``std``, the first
    budget's; an end outside the physical tensors brought in to their edge,
    a reach whose run fails halved up to :data:`SECANT_HALVINGS` times, and
    with less than a quarter of the width left a warning that the slope
    stands unchecked: :func:`_checked_secant`).  Where they
    differ by more than
    :data:`SECANT_DISAGREE` of the local slope (and by more than
    :data:`SECANT_SIGNIFICANT` of the timing std over the reach) and the
    secant is the smaller in magnitude, ``laws[k].dr_dp[j]`` is set so that the full slope is the
    secant (the budget's gain, hence the timing and amplitude terms and the
    Monte Carlo's, then follow it); a larger secant leaves the law alone
    (the local slope already gives the larger std).  ``p`` the estimate,
    ``r`` (K,) its amplitude factors, ``laws`` the estimate's amplitude laws
    (only those with ``dr_dp``: a nonlinear run law), runs at ``rtol``.
    Pairs that cannot matter (twice the local slope over the reach moves the
    period by at most :data:`SECANT_SIGNIFICANT` of its timing std) are not
    run.  Where a measurement's period is found not smooth in an unknown,
    its inputs' slopes are checked the same way (:func:`input_secants`,
    ``ctx`` the budget's :class:`~bifilar.estimation.second_order.BudgetContext`;
    none where it is None).  Returns (one warning per (measurement, unknown)
    that disagrees or could not be checked, and one per measurement whose
    inputs' slopes were widened; whether a law was changed: the budget must
    be made again)."""
    p = np.asarray(p, float)
    std = np.asarray(std, float)
    if laws is None or not any(law is not None and law.dr_dp is not None for law in laws):
        return [], False
    T_lin = pb.linear_periods(p)
    J = pb.jacobian(p)
    out, changed, rough = [], False, []
    for k, law in enumerate(laws):
        if law is None or law.dr_dp is None:
            continue
        m = pb.measurements[k]
        lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
        for j, name in enumerate(pb.unknowns):
            s = float(std[j]) if j < std.size else math.nan
            if not math.isfinite(s) or s <= 0:
                continue
            h, loc = SECANT_REACH * s, float(r[k] * J[k, j] + T_lin[k] * law.dr_dp[j])
            if 2.0 * abs(loc) * h <= SECANT_SIGNIFICANT * m.std:
                continue  # no smaller secant could matter (|sec - loc| < 2 |loc|): no runs
            sec, a, b, why = _checked_secant(pb, k, p, j, h, rtol)
            if isinstance(sec, str):
                out.append(f"mode '{lab}': the slope of its period in {name} could not be checked over the "
                           f"estimate's 95 % interval nor over a quarter of it ({sec}): the std is from the local "
                           f"slope ({loc:.3g} s per unit), too small if the period wiggles in {name} (another mode "
                           "exchanging energy with it); time it at a smaller amplitude to be sure")
                continue
            if (abs(sec - loc) <= SECANT_DISAGREE * abs(loc)
                    or abs(sec - loc) * (a + b) / 2 <= SECANT_SIGNIFICANT * m.std):
                continue
            where = ("the estimate's 95 % interval" if why is None else
                     f"{0.0 - a / s:+.3g} .. {b / s:+.3g} std of the estimate (over the 95 % interval, {why})")
            used = "secant" if abs(sec) < abs(loc) else "local"
            if used == "secant":
                law.dr_dp = np.array(law.dr_dp, float)
                law.dr_dp[j] = (sec - r[k] * J[k, j]) / T_lin[k]
                changed = True
            out.append(f"mode '{lab}': the period is not smooth in {name} at this amplitude (--amplitude "
                       f"{m.amplitude:g}): its slope over {where} ({sec:.3g} s per unit) "
                       f"differs from the local one ({loc:.3g}) by {100 * abs(sec - loc) / abs(loc):.0f} % "
                       f"(another mode exchanging energy with it?); the std is from the {used} slope, the smaller; "
                       "time it at a smaller amplitude")
            if k not in rough:
                rough.append(k)
    if rough and ctx is not None:
        more = input_secants(pb, [laws[k] for k in rough], rough, ctx, rtol, multi)
        out += more
        changed = changed or bool(more)
    return out, changed


def input_secants(pb, laws, ks, ctx, rtol: float, multi: bool) -> list[str]:
    """The full model period's slope in each input of measurements ``ks``
    (``laws`` theirs, with ``dr_dx``) as a secant over the input's
    +-:data:`SECANT_REACH` std, ``(T(x + d) - T(x - d)) / (2 d)`` with
    ``T = T_lin r`` (two runs an input, all in one batch:
    :func:`~bifilar.estimation.factor_inputs.stepped_factor_runs`, the
    estimate's own run among them), against
    the budget's local one ``r dT_lin/dx + T_lin dr/dx`` (``dT_lin/dx`` the
    same two runs' secant: the linear period is smooth).  Only for the
    measurements whose period :func:`secant_check` found not smooth in an
    unknown: the same energy exchange makes ``dr/dx`` wiggle (audit17 row
    B3 with the inputs at their default stds: the CoM height's local full
    slope 0.22 .. 1.1 s per m about ~0.7; docs/design.md "secant2, session
    18").  Where the secant is larger in magnitude by more than
    :data:`SECANT_DISAGREE` and moves the period over the reach by more
    than :data:`SECANT_SIGNIFICANT` of the timing std, ``law.dr_dx[key]``
    is set so that the full slope is the secant (the larger, the input's
    term the larger); a smaller one leaves it.  ``ctx``: the budget's
    context (its scenes, rests, modes, mode matches and input stds at the
    estimate).  Returns one warning per measurement whose inputs changed."""
    from .factor_inputs import SteppedFactors, stepped_factor_runs
    from .second_order import _perturbed_scene

    plans = []
    for k, law in zip(ks, laws):
        m = pb.measurements[k]
        h = m.hanging
        keys = [key for key in (law.dr_dx or {}) if ctx.sigmas.get(key, 0) > 0]
        if not keys:
            continue
        j = int(ctx.match[h][pb.mode_index[k]])
        steps = [((key, sign), sign * SECANT_REACH * ctx.sigmas[key],
                  _perturbed_scene(pb, h, ctx.scenes[h], [(key, sign * SECANT_REACH * ctx.sigmas[key])]))
                 for key in keys for sign in (1.0, -1.0)]
        plans.append((k, law, keys, j, SteppedFactors(ctx.scenes[h], ctx.rests[h], ctx.modes[h], [j], m.amplitude,
                                                      m.cycles, steps)))
    if not plans:
        return []
    stepped_factor_runs([plan[4] for plan in plans], rtol)
    out = []
    for k, law, keys, j, g in plans:
        m = pb.measurements[k]
        if j not in g.r0:
            continue
        r0, T0, dx, T = g.r0[j], g.T_lin[j][None], g.dr_dx[j], g.T_lin[j]
        wider = []
        for key in keys:
            up, down = (key, 1.0), (key, -1.0)
            if up not in dx or down not in dx:
                continue  # a stepped scene that cannot hang or whose run failed: the local slope stands
            d = SECANT_REACH * ctx.sigmas[key]
            T_up, T_down = T[up], T[down]
            r_up, r_down = r0 + d * dx[up], r0 - d * dx[down]
            sec = (T_up * r_up - T_down * r_down) / (2.0 * d)
            lin = (T_up - T_down) / (2.0 * d)
            loc = r0 * lin + T0 * law.dr_dx[key]
            if abs(sec) > (1.0 + SECANT_DISAGREE) * abs(loc) and abs(sec - loc) * d > SECANT_SIGNIFICANT * m.std:
                law.dr_dx = dict(law.dr_dx)
                law.dr_dx[key] = (sec - r0 * lin) / T0
                wider.append(f"{key} {sec / loc:.2g}x" if loc else key)
        if wider:
            lab = f"{pb.models[m.hanging].hanging.name}:{m.label}" if multi else m.label
            out.append(f"mode '{lab}': its period is not smooth in the inputs either: the budget takes the slopes "
                       "over their 95 % intervals where larger than the local ones (" + ", ".join(wider) + ")")
    return out


def _checked_secant(pb, k: int, p: np.ndarray, j: int, h: float, rtol: float):
    """(secant or why not, a, b, why the reach was shortened or None): the
    full model period's secant (:func:`_secant`) over ``p_j - a .. p_j +
    b``, ``a``, ``b`` = ``h`` where the tensors there are physical; else
    each end brought in to the edge of the physical set (:func:`_physical_reach`:
    a flat body's estimate sits on it, the thesis plates' and the KTH
    table's torsion), and where a run fails both halved, up to
    :data:`SECANT_HALVINGS` times.  Not checked (the first item a phrase)
    where less than a quarter of the interval's width is left."""
    a, b = _physical_reach(pb, p, j, -1.0, h), _physical_reach(pb, p, j, 1.0, h)
    why = None if a == h and b == h else _UNPHYSICAL
    for _ in range(SECANT_HALVINGS + 1):
        if a + b < 2.0 * h / 2 ** SECANT_HALVINGS:
            break
        sec = _secant(pb, k, p, j, a, b, rtol)
        if not isinstance(sec, str):
            return sec, a, b, why
        why, a, b = sec, a / 2.0, b / 2.0
    return ("less than a quarter of it is a physical tensor" if why == _UNPHYSICAL else why), a, b, why


_UNPHYSICAL = "its end is no physical inertia tensor"


def _physical(pb, q: np.ndarray) -> bool:
    vals = pb.values(q)
    return all(admissible(model.inertia_ref(vals)) for model in pb.models)


def _physical_reach(pb, p: np.ndarray, j: int, sign: float, h: float) -> float:
    """The largest ``t`` in 0 .. ``h`` (to 1e-6 of ``h``) with every
    hanging's tensor at ``p + sign t e_j`` physical (:func:`admissible`:
    positive definite, the triangle inequality; a convex set, so along a
    line an interval and bisection finds its end); 0 where ``p`` itself is
    not.  No runs."""
    q = np.array(p, float)

    def ok(t: float) -> bool:
        q[j] = p[j] + sign * t
        return _physical(pb, q)

    if ok(h):
        return h
    if not ok(0.0):
        return 0.0
    lo, hi = 0.0, h
    while hi - lo > 1e-6 * h:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def _secant(pb, k: int, p: np.ndarray, j: int, a: float, b: float, rtol: float) -> float | str:
    """(T(p + b e_j) - T(p - a e_j)) / (a + b), s per unit of ``p_j``: the
    full model period ``T_lin r`` of measurement ``k`` (its amplitude runs,
    unchecked, at ``rtol``; an end at ``p`` itself run there too); where it
    cannot be had, why (a phrase): a run or a linear model fails, or the
    difference is not finite.  The ends must be physical tensors
    (:func:`_physical_reach`; a swing whose period barely moves with an
    inertia has a std reaching past zero, the thesis roll rig's swing-x in
    Ixx: its modes have no meaning there)."""
    T = []
    for t in (b, -a):
        q = np.array(p, float)
        q[j] += t
        try:
            T.append(float(pb.linear_periods(q)[k]) * _unchecked_factor(pb, k, q, rtol))
        except (BifilarError, np.linalg.LinAlgError):
            return "a run at its end failed"
    val = (T[0] - T[1]) / (a + b)
    return val if math.isfinite(val) else "the period at its ends is not finite"
