"""Monte Carlo check of an inversion with the full model: draws of every
input, period and amplitude from their assumed distributions, each
re-estimated (draw by draw, or all at once with the batched engine), and a
journaled, resumable variant.  SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import BifilarError
from .birge import timing_scale
from .measurements import COM_UNKNOWNS, MeasurementSet
from .problem import _IDX, Problem, build_problem, physical_interval
from .sensitivity import input_sigma, perturb
from .solve import solve_linear
from .uncertainty import MonteCarloSummary, summarise

if TYPE_CHECKING:
    from .invert import InversionResult


@dataclass
class FactorDraw(MeasurementSet):
    """A Monte Carlo draw whose amplitude factors follow the unknowns.

    Measurement ``k``'s ``period`` is the drawn period divided by the factor
    ``r_k(A_k; p_hat)`` at the drawn amplitude and the estimate; the draw's
    model period is ``T_lin,k(p) rho_k(p)`` with
    ``rho_k(p) = 1 + offset[k] + slope[k] @ (unit * p - p_ref)``
    (dimensionless), i.e. the drawn period is matched by ``T_lin,k(p)
    r_k(A_k; p, x)``, ``r`` linearised about ``p_ref`` = ``p_hat`` and the
    measured inputs as the budget linearises it.

    slope : (K, P) ``w(A_k) dr_k/dp / r_k(A_k; p_hat)`` per unit of each
        unknown (kg m^2 or m); ``dr/dp`` is the law's at the stated
        amplitude, ``w = (r(A) - 1) / (r(A0) - 1)`` carries it to the drawn
        one (:meth:`~bifilar.estimation.solve.AmplitudeLaw.release_weight`).
    offset : (K,) ``w(A_k) sum_j dr_k/dx_j dx_j / r_k(A_k; p_hat)``: the
        factor's change with the draw's input errors ``dx_j`` (the law's
        ``dr_dx``, measured by the budget, the mass's included), as it
        follows the unknowns through ``dr/dp``.
    unit : (P,) ones where the law has ``dr_dx``; without it (a law the
        budget did not reach) ``m_hat / m_draw`` for inertia unknowns, 1 for
        CoM shifts: the motion depends on the mass only through ``I / m``,
        so the factor at the draw's mass and ``p`` is the estimate-mass
        factor at ``p m_hat / m_draw`` where the unknowns are the only
        inertia the factor depends on.
    p_ref : (P,) the estimate ``p_hat``."""

    slope: np.ndarray | None = None
    unit: np.ndarray | None = None
    p_ref: np.ndarray | None = None
    offset: np.ndarray | None = None

    def factor(self, p) -> np.ndarray:
        """(K,) ``rho_k(p)`` at unknowns ``p`` (SI)."""
        off = 0.0 if self.offset is None else self.offset
        return 1.0 + off + self.slope @ (self.unit * np.asarray(p, float) - self.p_ref)


@dataclass
class _FactorProblem(Problem):
    """A draw's :class:`Problem` whose ``linear_periods`` are the model
    periods ``T_lin(p) rho(p)`` of its :class:`FactorDraw` (s), so that
    :func:`solve_linear` (root finding, Gauss-Newton with its Jacobian by
    differences of these periods) solves the drawn periods with the factor
    following the unknowns."""

    draw: FactorDraw | None = None

    @classmethod
    def of(cls, pb: Problem, draw: FactorDraw) -> _FactorProblem:
        return cls(**{f.name: getattr(pb, f.name) for f in fields(Problem)}, draw=draw)

    def linear_periods(self, p) -> np.ndarray:
        return super().linear_periods(p) * self.draw.factor(p)

def draw_monte_carlo(res: InversionResult, n: int, rng: np.random.Generator) -> list:
    """``n`` perturbed measurement sets for :func:`monte_carlo_check`: inputs,
    periods and amplitudes drawn from their assumed distributions (centred on
    the measured values; normal, except a period from ``n`` timed trials:
    ``T + std T_{n-1}``, Student's t with the trials' dof, whose spread is
    what the trials support and whose 2.5-97.5 % quantiles are the
    Student interval; for ``n <= 3`` it has no finite variance); a rig
    input or body point several hangings share (``pb.links``,
    :mod:`bifilar.estimation.rig`) is drawn once for all of them; the amplitude factor at the drawn amplitude is
    the mode's amplitude law ``r(A) = 1 + a A^2 + b A^4`` (nonlinear method;
    ``res.amplitude_laws``, :class:`~bifilar.estimation.solve.AmplitudeLaw`) and each drawn period is divided by it.
    Where the law has a derivative in the unknowns (a stated amplitude) the
    draw is a :class:`FactorDraw`: its factor follows the re-estimated
    unknowns through ``dr/dp`` (the full model's gain, as the budget's
    timing and amplitude terms), not held at the estimate's (a fixed factor
    gave the Solar Boat's torsion at 0.3 rad 0.90 of the budget's timing
    term), and the drawn inputs move it through the law's ``dr/dx``
    (:attr:`FactorDraw.offset`; gravity's is 0 exactly, it only scales
    time); other draws are plain linear-model problems.  Every input is perturbed,
    degenerate ones (no derivative) too: their finite-size effect is what the
    linear budget cannot see.  The components not solved for are drawn
    about their priors where their uncertainty is stated (``--uncertainty
    inertia=``, :mod:`~bifilar.estimation.prior_inertia`; the factor
    following them through its ``dr/dI_c``).  A draw that cannot even be built
    is ``None``.  Reproducible for a given generator state.

    Where the fit's periods scatter beyond their stated timing stds (the
    Birge factor ``B`` > 1, ``res.fit["birge_factor"]``,
    :mod:`~bifilar.estimation.birge`), each period is drawn with ``B``
    times its stated std, as the budget's timing terms are widened: the
    Monte Carlo then checks the interval the budget prints (the stated stds
    gave the Solar Boat's Izz from two torsion timings 0.2 % apart a spread
    0.37x the widened std, flagged as nonlinearity)."""
    pb = res.problem
    unc = pb.unc
    t_scale = timing_scale(res)
    solved_com = {x for x in pb.unknowns if x in COM_UNKNOWNS}
    links = pb.links  # which rig inputs the hangings share (drawn once)
    draws: list = []
    for _ in range(n):
        try:
            # shared inputs: mass (relative), gravity, CoM (reference frame)
            dm = rng.normal(0.0, unc["mass"])
            dg = rng.normal(0.0, unc.get("gravity", 0.0))
            dcom = np.array([0.0 if f"com.{a}" in solved_com else rng.normal(0.0, unc["com"]) for a in "xyz"])
            # the wires' EA: one relative factor for every hanging, drawn only where it is budgeted (a rig without
            # rig.stiffness draws the numbers it drew before)
            s_ea = max(input_sigma(hm.hanging.scene, "stiffness", unc) for hm in pb.models)
            dea = rng.normal(0.0, s_ea) if s_ea > 0 else 0.0
            hangs = []
            slope = np.zeros((len(pb.measurements), len(pb.unknowns)))
            offset = np.zeros(len(pb.measurements))
            drawn: dict = {}  # rig and attachment input key -> its error: one draw for every hanging sharing it

            def error(h, name, sd):
                e = 0.0
                for key, c in links.of(h, name):
                    if key not in drawn:
                        drawn[key] = rng.normal(0.0, sd)
                    e += c * drawn[key]
                return e

            dI, eI = _prior_errors(res, rng)
            for h, hm in enumerate(pb.models):
                s = hm.hanging.scene
                att = s.attachments - (hm.R @ dcom)[None, :]
                an = s.anchors.copy()
                L = s.lengths.copy()
                for i in range(s.n_wires):
                    L[i] += error(h, f"length.{i + 1}", unc["length"])
                    for a in range(3):
                        an[i, a] += error(h, f"anchor.{i + 1}.{'xyz'[a]}", unc["position"])
                        att[i, a] += error(h, f"attachment.{i + 1}.{'xyz'[a]}", unc["position"])
                s2 = replace(s, mass=s.mass * (1 + dm), gravity=s.gravity * (1 + dg), lengths=L, anchors=an,
                             attachments=att, inertia=s.inertia + hm.R @ dI @ hm.R.T)
                if dea:
                    s2 = perturb(s2, "stiffness", dea)
                hangs.append(replace(hm.hanging, scene=s2))
            # each input's error under its budget key (input_columns's keys: a shared rig input's once), for the
            # factor's dr/dx
            dx = {"mass": pb.models[0].hanging.scene.mass * dm, "gravity": pb.models[0].hanging.scene.gravity * dg,
                  **{f"com.{a}": dcom[q] for q, a in enumerate("xyz")}, **drawn}
            if dea:
                dx["stiffness"] = dea
            meas = []
            for k, m in enumerate(pb.measurements):
                # a period from n timed trials: its std is estimated with
                # nu = n - 1 dof, so the truth given the trials is T + std T_nu
                # (Student), not T + std z: normal draws under-cover as 1.96 did
                nu = m.dof
                T = m.period + t_scale * m.std * (rng.standard_t(nu) if math.isfinite(nu) else rng.normal())
                r = res.factors[k]
                if m.amplitude and res.method == "nonlinear":
                    sA = m.amplitude_std if m.amplitude_std is not None else unc["amplitude"] * abs(m.amplitude)
                    A = m.amplitude + rng.normal(0.0, sA)
                    law = res.amplitude_laws[k]
                    r = float(law.factor(A))
                    if law.dr_dp is not None:
                        w = law.release_weight((A / law.amplitude) ** 2)
                        slope[k] = w * law.dr_dp / r
                        offset[k] = w * sum(v * dx.get(key, 0.0) for key, v in (law.dr_dx or {}).items()) / r
                        if eI is not None:  # the factor's change with the drawn priors (prior_inertia's dr/dI_c)
                            offset[k] += w * float(res.prior_inertia.dr[k] @ eI) / r
                meas.append(replace(m, period=T / r))
            if np.any(slope):
                measured = all(law is None or law.dr_dp is None or law.dr_dx is not None for law in res.amplitude_laws)
                unit = np.array([1.0 if measured or x not in _IDX else 1.0 / (1.0 + dm) for x in pb.unknowns])
                draws.append(FactorDraw(hangs, meas, slope=slope, unit=unit, p_ref=np.asarray(res.values, float),
                                        offset=offset))
            else:
                draws.append(MeasurementSet(hangs, meas))
        except BifilarError:
            draws.append(None)
    return draws


def _prior_errors(res: InversionResult, rng: np.random.Generator):
    """One draw of the errors of the components not solved for with a
    stated uncertainty (``res.prior_inertia``, reference frame): (3, 3)
    symmetric tensor error (kg m^2) and (Q,) the errors per component, or
    (zeros, None) where none is stated (no random number drawn: the draws
    of a run without it are as before)."""
    pri = getattr(res, "prior_inertia", None)
    dI = np.zeros((3, 3))
    if pri is None or not np.any(pri.sigmas > 0):
        return dI, None
    e = np.array([rng.normal(0.0, sd) if sd > 0 else 0.0 for sd in pri.sigmas])
    for q, c in enumerate(pri.names):
        i, j = _IDX[c]
        dI[i, j] += e[q]
        if i != j:
            dI[j, i] += e[q]
    return dI, e


def _batch(res: InversionResult) -> bool:
    """:func:`batched_applies`, and no prior drawn (the batched solver holds
    the components not solved for at the estimate's priors)."""
    pri = getattr(res, "prior_inertia", None)
    return batched_applies(res.problem) and (pri is None or not np.any(pri.sigmas > 0))


def batched_applies(pb: Problem) -> bool:
    """Whether :func:`solve_draws_batched` handles draws of ``pb``: one
    hanging, one measured period, one unknown that is an inertia component."""
    return len(pb.models) == 1 and len(pb.measurements) == 1 and len(pb.unknowns) == 1 and pb.unknowns[0] in _IDX


def solve_draws_loop(res: InversionResult, draws: list, progress=None) -> np.ndarray:
    """(n, P) re-estimates of the unknowns, one :func:`solve_linear` of the
    full perturbed problem per draw (NaN rows: draws whose inversion failed);
    a :class:`FactorDraw`'s model periods ``T_lin(p) rho(p)``
    (:class:`_FactorProblem`).  Any problem shape; ~30 ms a draw."""
    pb = res.problem
    out = np.full((len(draws), len(pb.unknowns)), np.nan)
    for it, ms2 in enumerate(draws):
        if ms2 is not None:
            try:
                pb2 = build_problem(ms2, unc=None, like=pb)
                pb2.I_ref0 = pb.I_ref0
                if isinstance(ms2, FactorDraw):
                    pb2 = _FactorProblem.of(pb2, ms2)
                out[it] = solve_linear(pb2, p0=res.values)
            except BifilarError:
                pass
        if progress:
            progress(it + 1, len(draws))
    return out


def _mac_track(base_shapes: np.ndarray, base_M: np.ndarray, shapes: np.ndarray, k0: np.ndarray) -> np.ndarray:
    """Index of the mode of each draw matching mode ``k0[b]`` of the draw's
    base set: :func:`~bifilar.estimation.sensitivity.mac_match` (the MAC
    matrix of all modes, then the best one-to-one assignment, which keeps
    two near-degenerate modes apart where a row-wise argmax would swap
    them), with the MAC matrices of all draws computed at once.

    base_shapes, shapes : (B, K, 6) mode shapes; base_M : (B, 6, 6) mass
    matrices (world chart) of the base sets; k0 : (B,) ints."""
    from scipy.optimize import linear_sum_assignment

    MA = np.einsum("bij,bkj->bki", base_M, base_shapes)  # (B, K, 6)
    num = np.einsum("bki,bli->bkl", MA, shapes) ** 2
    da = np.einsum("bki,bki->bk", base_shapes, MA)
    db = np.einsum("bki,bij,bkj->bk", shapes, base_M, shapes)
    mac = num / np.maximum(da[:, :, None] * db[:, None, :], 1e-300)
    out = np.empty(len(k0), int)
    for q in range(len(k0)):
        _, col = linear_sum_assignment(-mac[q])
        out[q] = col[k0[q]]
    return out


def solve_draws_batched(res: InversionResult, draws: list, progress=None, rtol: float = 1e-12,
                        max_iter: int = 20) -> np.ndarray:
    """(n, 1) re-estimates, all draws solved in lockstep with the batched
    engine (:mod:`bifilar.analysis.batch`); NaN rows: failed draws.  Only for
    problems with :func:`batched_applies`.

    Each draw solves the same equation as :func:`solve_linear` does for it:
    ``T_lin(x) rho(x) = T_draw`` (s; ``rho`` = 1 but for a
    :class:`FactorDraw`) for the unknown inertia component ``x``
    (kg m^2, reference body axes) in its physical interval, the mode tracked
    as :func:`build_problem` and :class:`HangingModel` track it (MAC against
    the estimate's base modes, then against the draw's own modes at the
    prior).  The rest poses do not depend on the inertia, so they are found
    once (:func:`~bifilar.analysis.batch.rest_poses`, each from the start
    pose, as :func:`~bifilar.analysis.equilibrium.rest_pose`); every iteration then computes the modes of all unconverged
    draws in one :func:`~bifilar.analysis.batch.modes_batch` call and makes
    one secant step per draw on ``f = T^2 - T_draw^2`` (close to linear in an
    inertia), the first slope from a forward difference, steps limited and
    kept inside the interval as :func:`solve_scalar` does, until
    ``|f| <= 2 rtol T_draw^2`` (``|T - T_draw| <= rtol T_draw``).  A draw
    whose rest pose fails, whose mode has no period, or that has not
    converged after ``max_iter`` steps is dropped (NaN), as the loop drops
    draws that raise.  Where the measured mode nearly coincides with another
    one, the tracked period can jump (avoided crossing) with no root; the
    loop's Brent step then returns the jump's location, this path drops the
    draw (no inertia gives ``|T - T_draw| <= rtol T_draw``)."""
    from ..analysis.batch import modes_batch, rest_poses

    pb = res.problem
    if not batched_applies(pb):
        raise ValueError("solve_draws_batched needs one hanging, one period and one inertia unknown")
    hm = pb.models[0]
    name = pb.unknowns[0]
    i, j = _IDX[name]
    R = hm.R
    I0 = np.asarray(pb.I_ref0, float)
    I0w = R @ I0 @ R.T
    n = len(draws)
    out = np.full((n, 1), np.nan)
    ok = [b for b, d in enumerate(draws) if d is not None]
    scenes0 = [replace(draws[b].hangings[0].scene, inertia=I0w) for b in ok]
    targets = np.array([draws[b].measurements[0].period for b in ok], float)
    # each draw's factor rho(x) = 1 + o + g (u x - x_ref) (FactorDraw; g = 0: held)
    fd = [draws[b] if isinstance(draws[b], FactorDraw) else None for b in ok]
    f_slope = np.array([d.slope[0, 0] if d is not None else 0.0 for d in fd])
    f_unit = np.array([d.unit[0] if d is not None else 1.0 for d in fd])
    f_ref = np.array([d.p_ref[0] if d is not None else 0.0 for d in fd])
    f_off = np.array([d.offset[0] if d is not None and d.offset is not None else 0.0 for d in fd])
    rests = rest_poses(scenes0, hm.rest0, errors="return") if scenes0 else []
    keep = [q for q, r in enumerate(rests) if not isinstance(r, BaseException)]
    ok = [ok[q] for q in keep]
    scenes0 = [scenes0[q] for q in keep]
    rests = [rests[q] for q in keep]
    targets = targets[keep]
    f_slope, f_unit, f_ref, f_off = f_slope[keep], f_unit[keep], f_ref[keep], f_off[keep]
    follows = bool(np.any(f_slope))
    B = len(ok)
    if B == 0:
        if progress:
            progress(n, n)
        return out

    def shapes_of(mss):
        return np.array([[m.shape for m in ms.modes] for ms in mss])

    # the draws' own base modes (at the prior inertia) and the measured mode in them
    ms0 = _modes_or_none(modes_batch, scenes0, rests)
    alive = np.array([m is not None for m in ms0])
    nk = len(hm.modes0.modes)
    alive &= np.array([m is not None and len(m.modes) == nk for m in ms0])
    S0 = np.zeros((B, nk, 6))
    M0 = np.zeros((B, 6, 6))
    for b in np.nonzero(alive)[0]:
        S0[b] = shapes_of([ms0[b]])[0]
        M0[b] = ms0[b].mass_matrix
    Sbase = np.broadcast_to(np.array([m.shape for m in hm.modes0.modes]), (B, nk, 6))
    Mbase = np.broadcast_to(hm.modes0.mass_matrix, (B, 6, 6))
    k0 = _mac_track(Sbase, Mbase, S0, np.full(B, pb.mode_index[0]))

    def f_of(idx: np.ndarray, x: np.ndarray) -> np.ndarray:
        """(T rho)^2 - target^2 (s^2) of draws ``idx`` at component values ``x``."""
        if not len(idx):
            return np.zeros(0)
        I = np.broadcast_to(I0, (len(idx), 3, 3)).copy()
        I[:, i, j] = x
        I[:, j, i] = x
        Iw = R @ I @ R.T
        scs = [replace(scenes0[b], inertia=Iw[q]) for q, b in enumerate(idx)]
        mss = _modes_or_none(modes_batch, scs, [rests[b] for b in idx])
        T = np.full(len(idx), np.nan)
        good = [q for q, m in enumerate(mss) if m is not None and len(m.modes) == nk]
        if good:
            g = np.array(good)
            kk = _mac_track(S0[idx[g]], M0[idx[g]], shapes_of([mss[q] for q in good]), k0[idx[g]])
            for q, k in zip(good, kk):
                per = mss[q].modes[k].period
                T[q] = per if per else np.nan
        if follows:
            T = T * (1.0 + f_off[idx] + f_slope[idx] * (f_unit[idx] * x - f_ref[idx]))
        return T * T - targets[idx] ** 2

    lo, hi = physical_interval(I0, name)
    scale = float(pb.scales()[0])
    margin = 1e-9 * scale
    lo_m = lo + margin if math.isfinite(lo) else -math.inf
    hi_m = hi - margin if math.isfinite(hi) else math.inf
    x0 = float(res.values[0])
    if math.isfinite(lo_m) or math.isfinite(hi_m):
        x0 = min(max(x0, lo_m + margin), hi_m - margin)
    tol = 2 * rtol * targets ** 2
    h = 1e-6 * scale
    xh0 = x0 - h if x0 + h >= hi_m else x0 + h
    # first evaluation: x0 and x0 + h for every draw, in one batched call
    idx = np.nonzero(alive)[0]
    fb = f_of(np.concatenate([idx, idx]), np.concatenate([np.full(len(idx), x0), np.full(len(idx), xh0)]))
    x = np.full(B, x0)
    fx = np.full(B, np.nan)
    fx[idx] = fb[:len(idx)]
    d = np.full(B, np.nan)
    d[idx] = (fb[len(idx):] - fb[:len(idx)]) / (xh0 - x0)
    alive &= np.isfinite(fx)
    result = np.full(B, np.nan)
    done = alive & (np.abs(fx) <= tol)
    result[done] = x[done]
    active = alive & ~done
    xt = np.full(B, np.nan)  # trial points

    def newton(a):
        with np.errstate(all="ignore"):
            good = (d[a] != 0) & np.isfinite(d[a])
            xn = np.where(good, x[a] - fx[a] / np.where(good, d[a], 1.0), x[a] + np.where(fx[a] < 0, 10, -10) * scale)
            xn = np.clip(xn, x[a] - 100 * scale, x[a] + 100 * scale)
            xn = np.where(xn <= lo_m, x[a] - 0.9 * (x[a] - lo_m), xn)
            xn = np.where(xn >= hi_m, x[a] + 0.9 * (hi_m - x[a]), xn)
        return xn

    a = np.nonzero(active)[0]
    xt[a] = newton(a)
    for _ in range(max_iter):
        a = np.nonzero(active)[0]
        if not len(a):
            break
        if progress:
            progress(n - len(a), n)
        ft = f_of(a, xt[a])
        fin = np.isfinite(ft)
        conv = fin & (np.abs(ft) <= tol[a])
        result[a[conv]] = xt[a[conv]]
        active[a[conv]] = False
        # no period at the trial point: halve the step
        bad = a[~fin]
        xt[bad] = 0.5 * (x[bad] + xt[bad])
        # secant update where the trial point has a period but is not yet a root
        up = a[fin & ~conv]
        fu = ft[fin & ~conv]
        stalled = xt[up] == x[up]
        active[up[stalled]] = False
        up, fu = up[~stalled], fu[~stalled]
        d[up] = (fu - fx[up]) / (xt[up] - x[up])
        x[up], fx[up] = xt[up], fu
        xt[up] = newton(up)
    out[np.array(ok), 0] = result
    if progress:
        progress(n, n)
    return out


def _modes_or_none(modes_batch, scenes, rests) -> list:
    """modes_batch, or scene by scene with None for scenes whose modes fail."""
    try:
        return modes_batch(scenes, rests)
    except (np.linalg.LinAlgError, BifilarError):
        out = []
        for s, r in zip(scenes, rests):
            try:
                out.append(modes_batch([s], [r])[0])
            except (np.linalg.LinAlgError, BifilarError):
                out.append(None)
        return out


DRAW_SCHEME = 7
"""Version of how the draws are made, part of a journal's key (with the
rig model, ``shared`` or ``separate``): 7 draws the periods with the
timing stds the Birge factor widened (session 22), 6 lets the factor follow the drawn
inputs too, through the law's ``dr/dx`` (:attr:`FactorDraw.offset`,
session 10), 5 draws a rig input or body point several hangings share
once for all of them (session 10), 4 lets a
stated amplitude's factor follow the re-estimated unknowns through the
law's ``dr/dp`` (:class:`FactorDraw`, session 9), 3 draws the
amplitude factor from the mode's amplitude law and a recording's period
with the dof of its re-quantised copies (session 8), 2 the factor by the
quadratic rule and every recording normal, 2 and 3 a period from n timed
trials with Student's t (n - 1 dof), 1 drew it normal.
A journal of another scheme is refused on ``--resume`` instead of mixing
the two kinds of draws."""


def monte_carlo_journaled(res: InversionResult, n: int, journal, *, seed: int | None = None, resume: bool = False,
                          chunk: int = 100, progress=None, stop_after: int | None = None) -> MonteCarloSummary:
    """:func:`monte_carlo_check` in chunks of ``chunk`` draws, each appended to
    the JSON-lines file ``journal`` as it finishes, so an interrupted run keeps
    what it finished and ``resume=True`` continues it with identical results.

    Chunk c draws from its own generator, spawned from ``seed`` (stored in the
    journal's first line with a key of the problem), so the draws do not depend
    on which chunks ran in which session.  ``stop_after``: finish at most that
    many chunks in this call (tests simulate an interruption with it).
    """
    import hashlib
    import json
    from pathlib import Path

    from ..errors import InputError
    from ..output import JournalWriter, read_journal

    path = Path(journal)
    key = hashlib.sha256(json.dumps([list(res.names), [float(v) for v in res.values], [float(v) for v in res.std],
                                     int(n), int(chunk), res.method, DRAW_SCHEME, res.problem.rig], sort_keys=True).encode()).hexdigest()[:16]
    n_chunks = (n + chunk - 1) // chunk
    done: dict[int, np.ndarray] = {}
    if path.exists():
        if not resume:
            raise InputError("--journal", f"{path} exists; pass --resume to continue it or choose another name")

        def check_header(head) -> None:
            if not isinstance(head, dict) or head.get("kind") != "bifilar-monte-carlo" or type(head.get("seed")) is not int:
                raise InputError("--journal", f"{path} is not a bifilar Monte Carlo journal")
            if head.get("key") != key:
                raise InputError("--journal", f"{path} belongs to another problem or settings, or to another "
                                                 "version of bifilar's draws; it cannot be resumed here")

        def is_record(rec) -> bool:
            return (isinstance(rec, dict) and type(rec.get("chunk")) is int and 0 <= rec["chunk"] < n_chunks
                    and isinstance(rec.get("samples"), list)
                    and all(isinstance(row, list) and len(row) == len(res.names)
                            and all(v is None or type(v) in (int, float) for v in row) for row in rec["samples"]))

        head, records = read_journal(path, check_header, is_record)
        if not head:
            raise InputError("--journal", f"{path} is not a bifilar Monte Carlo journal")
        if seed is not None and seed != head["seed"]:
            raise InputError("--seed", f"differs from the journal's seed {head['seed']}")
        seed = int(head["seed"])
        for rec in records:
            done[int(rec["chunk"])] = np.array([[np.nan if v is None else v for v in row] for row in rec["samples"]],
                                               float).reshape(-1, len(res.names))
        writer = JournalWriter(path, None, append=True)
    else:
        if resume:
            raise InputError("--resume", f"no journal {path} to resume")
        if seed is None:
            seed = int(np.random.SeedSequence().entropy % 2**63)
        writer = JournalWriter(path, {"kind": "bifilar-monte-carlo", "key": key, "seed": seed, "n": n, "chunk": chunk},
                               append=False)
    sizes = [min(chunk, n - c * chunk) for c in range((n + chunk - 1) // chunk)]
    children = np.random.SeedSequence(seed).spawn(len(sizes))
    ran = 0
    try:
        for c, size in enumerate(sizes):
            if c in done:
                continue
            if stop_after is not None and ran >= stop_after:
                break
            draws = draw_monte_carlo(res, size, np.random.default_rng(children[c]))
            use_batch = _batch(res)
            est = solve_draws_batched(res, draws, None) if use_batch else solve_draws_loop(res, draws, None)
            done[c] = est
            writer.add({"chunk": c, "samples": [[None if not np.isfinite(v) else float(v) for v in row] for row in est]})
            ran += 1
            if progress:
                progress(sum(len(v) for v in done.values()), n)
    finally:
        writer.close()
    est = np.concatenate([done[c] for c in sorted(done)]) if done else np.zeros((0, len(res.names)))
    good = np.all(np.isfinite(est), axis=1)
    return summarise(list(res.problem.unknowns), est[good], res.std, sum(len(v) for v in done.values()),
                     timing_scale=timing_scale(res))


def monte_carlo_check(res: InversionResult, n: int, rng: np.random.Generator, progress=None,
                      batched: bool | None = None, near_pose: bool = False) -> MonteCarloSummary:
    """Re-estimate the unknowns ``n`` times with inputs, periods and
    amplitudes drawn from their assumed distributions (:func:`draw_monte_carlo`),
    each time solving the full (not linearised) model: the rest pose, modes
    and root finding / Gauss-Newton of the perturbed scene.

    One hanging, one period and one inertia unknown (the common case) go
    through the batched engine, all draws at once
    (:func:`solve_draws_batched`, 8-15x faster: docs/performance.md); anything else, or
    ``batched=False``, draw by draw (:func:`solve_draws_loop`).  Draws
    whose inversion fails are counted in ``failed``.  ``near_pose``: drop
    draws that do not hang near the estimate's rest pose (Newton from it
    fails: the body would hang visibly otherwise than the one measured; the
    targeted Monte Carlo of degenerate inputs, which skips the slow global
    search for them)."""
    draws = draw_monte_carlo(res, n, rng)
    if near_pose:
        from ..analysis.equilibrium import rest_pose

        for q, d in enumerate(draws):
            if d is None:
                continue
            try:
                for h, hm in zip(d.hangings, res.problem.models):
                    rest_pose(h.scene, guess=hm.rest0, local_only=True)
            except BifilarError:
                draws[q] = None
    use_batch = _batch(res) if batched is None else bool(batched)
    est = solve_draws_batched(res, draws, progress) if use_batch else solve_draws_loop(res, draws, progress)
    good = np.all(np.isfinite(est), axis=1)
    return summarise(list(res.problem.unknowns), est[good], res.std, n, timing_scale=timing_scale(res))
