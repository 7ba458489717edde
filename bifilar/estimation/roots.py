"""Every physical solution of the inversion, the measured mode identified at
the solution, and the check that an answer reproduces its measurements.

Units: periods in s, inertia components in kg m^2 (reference body axes),
CoM shifts in m (see :mod:`bifilar.estimation.problem`).

Mode identity
-------------
A measured period belongs to the mode that carries the measured label (or
1-based index) *for the tensor being tried*, as the labeller of
:func:`bifilar.analysis.modes.linear_modes` names it (the coordinate with
the largest share of kinetic energy: what the experimenter sees move).  When
the unknown changes, two interacting modes can exchange character (an
avoided crossing): the periods of the modes sorted slowest first stay
continuous, but the label passes from one of them to the other.  A value is
a solution when the mode that carries the label *there* has the measured
period; a sign change of ``T - T_meas`` across the place where the label
jumps is not a solution.

One unknown inertia component, one period
-----------------------------------------
The admissible values form an interval, computed in closed form
(:func:`~bifilar.estimation.problem.admissible_interval`: positive definite
and triangle inequality with the other components as given).  The periods
of every mode (sorted slowest first, each a continuous function of the
unknown) are computed on a fixed grid over that interval (one batched call,
the rest pose reused: it does not depend on the inertia); every sign change
of ``T_k(x) - T_meas`` on the grid is refined with Brent's method and kept
when mode ``k`` carries the measured label at the root.  For a moment of
inertia (diagonal component) the mass matrix grows with ``x``, so every
sorted period is non-decreasing and each mode has at most one root: the grid
cannot miss one.  For a product of inertia the periods need not be
monotone, so a grid cell whose three samples turn back near the measured
period is searched for a pair of close roots.  The path depends only on the
grid and the signs of ``T - T_meas`` at fixed points, not on rounding noise.

Several unknowns or periods
---------------------------
Weighted Gauss-Newton (with the mode identity re-decided by label at every
iterate) kept inside the admissible set, started from the prior and from a
deterministic low-discrepancy design over the box of admissible intervals;
every distinct start point's solution that passes the fit check is a root.

The fit check
-------------
An answer must reproduce every measured period: with ``z_k = (T_model -
T_meas) / sigma_k``, ``max |z_k| <= FIT_Z`` when there are as many periods as
unknowns (the equations are solved exactly; ``FIT_Z`` = 0.1), and the
chi-square ``sum z_k^2`` below its ``1 - CHI2_P`` quantile with ``K - P``
degrees of freedom when there are more periods ``K`` than unknowns ``P``
(``CHI2_P`` = 0.001).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import BifilarError, ConvergenceError, InputError
from .problem import _IDX, Problem, admissible, admissible_interval

#: largest normalised residual |T_model - T_meas| / sigma of an exactly determined fit
FIT_Z = 0.1
#: an overdetermined fit is refused when P(chi2 >= observed) < CHI2_P
CHI2_P = 1e-3
#: a solution on the edge of the admissible set is accepted within this many sigma
EDGE_Z = 2.0
#: grid points over the admissible interval of one unknown
N_GRID = 41


@dataclass
class Root:
    """One admissible solution ``p`` (unknowns, SI); ``edge`` when it lies on
    the boundary of the physical set (no exact solution inside it)."""

    p: np.ndarray
    edge: bool = False


def label_index(ms, label: str) -> int | None:
    """Index into ``ms.modes`` of the mode carrying ``label`` (or 1-based index), else None."""
    try:
        m = ms.get(label)
    except KeyError:
        return None
    return ms.modes.index(m)


def fit_statistics(z: np.ndarray, P: int) -> tuple[bool, float, str]:
    """(passes, chi2, threshold description) of normalised residuals ``z``
    for ``P`` unknowns (module docstring)."""
    z = np.asarray(z, float)
    K = len(z)
    chi2 = float(z @ z) if np.all(np.isfinite(z)) else math.inf
    if K <= P:
        return bool(np.all(np.abs(z) <= FIT_Z)), chi2, f"|residual| <= {FIT_Z:g} sigma"
    lim = chi2_limit(K, P)
    return chi2 <= lim, chi2, f"chi2 <= {lim:.4g} ({K - P} degrees of freedom, p = {CHI2_P:g})"


def chi2_limit(K: int, P: int) -> float:
    """The ``1 - CHI2_P`` quantile of chi-square with ``K - P`` degrees of freedom."""
    from scipy.stats import chi2 as chi2_dist

    return float(chi2_dist.ppf(1 - CHI2_P, K - P))


def _input_columns(pb: Problem, p, r=None) -> tuple[list, np.ndarray, np.ndarray]:
    """(input keys, (K, n) period sensitivities to them (s per SI unit,
    times the amplitude factors ``r``, NaN set to 0: no derivative), (n,)
    their standard uncertainties) of the modes carrying the measured labels
    at the unknowns ``p`` (:func:`~bifilar.estimation.budget.input_columns`)."""
    from .budget import input_columns
    from .uncertainty import default_uncertainty

    K = len(pb.measurements)
    r = np.ones(K) if r is None else np.asarray(r, float)

    def rows(h, ms, match, k):
        return label_index(ms, pb.measurements[k].label)

    unc = pb.unc if pb.unc else default_uncertainty()
    cols, sigmas = input_columns(pb, pb.values(p), r, unc, rows=rows)[:2]
    keys = list(cols)
    J = np.column_stack([np.where(np.isfinite(cols[n]), cols[n], 0.0) for n in keys]) if keys else np.zeros((K, 0))
    return keys, J, np.array([sigmas[n] for n in keys])


def input_period_covariance(pb: Problem, p, r=None) -> np.ndarray:
    """(K, K) covariance (s^2) of the measured periods caused by the measured
    inputs (wire lengths, anchor and attachment coordinates, mass, gravity,
    CoM) at their standard uncertainties ``pb.unc``, linearised at the
    unknowns ``p``: ``J_x diag(s^2) J_x^T``, ``J_x`` the periods' input
    sensitivities (times the amplitude factors ``r``) of the modes carrying
    the measured labels at ``p``.  Inputs without a derivative (a knife
    edge) are left out."""
    _, J, s = _input_columns(pb, p, r)
    Js = J * s
    return Js @ Js.T


def inputs_explain(pb: Problem, p, res: np.ndarray, other_var: np.ndarray, lim: float) -> bool:
    """Whether measured inputs off within their stated uncertainty explain
    the residuals ``res`` (K,) s (measured minus model, at the unknowns
    ``p`` held fixed) with the full model, not only its linearisation.

    The likeliest input error given the residuals (the conditional mean,
    ``dx = S^2 J^T C^-1 res``, ``C = J S^2 J^T + diag(other_var)``: timing
    and release amplitudes in ``other_var``, s^2) is applied to the
    hanging's scene, its rest pose and modes found again, and the misfit
    ``|dx / s|^2 + sum (res - dT)^2 / other_var`` with the periods' true
    change ``dT`` must be at most ``lim``.  Linearly it is ``res^T C^-1
    res``; where the periods are not linear over the inputs' uncertainty
    (four dependent wires, where 1 mm of a length moves a period by
    seconds in the linearisation, or leaves a wire slack) the linear test
    would accept any period: this one does not."""
    from ..analysis.equilibrium import rest_pose
    from ..analysis.modes import linear_modes
    from .sensitivity import perturb

    res = np.asarray(res, float)
    keys, J, s = _input_columns(pb, p)
    keep = s > 0  # an exact input cannot be off
    keys, J, s = [n for n, k in zip(keys, keep) if k], J[:, keep], s[keep]
    if not keys:
        return False
    C = (J * s ** 2) @ J.T + np.diag(other_var)
    dx = s ** 2 * (J.T @ np.linalg.solve(C, res))
    vals = pb.values(p)
    dT = np.zeros(len(res))
    for h, hm in enumerate(pb.models):
        ks = [k for k, m in enumerate(pb.measurements) if m.hanging == h]
        if not ks:
            continue
        pre = f"{hm.hanging.name}:" if len(pb.models) > 1 else ""
        scene, d_com = hm.scene(vals), np.zeros(3)
        for key, d in zip(keys, dx):
            if key.startswith("com."):
                d_com["xyz".index(key[-1])] += d
            elif key in ("mass", "gravity"):
                scene = perturb(scene, key, d)
            elif key.startswith(pre) and ":" not in key[len(pre):]:
                scene = perturb(scene, key[len(pre):], d)
        for ax, d in zip("xyz", hm.R @ d_com):  # a CoM shift in the reference frame, seen in this hanging's
            scene = perturb(scene, f"com.{ax}", d)
        try:
            ms = linear_modes(scene, rest_pose(scene, guess=hm.rest0))
        except (BifilarError, np.linalg.LinAlgError):
            return False
        base = labelled_periods(pb, p)
        for k in ks:
            i = label_index(ms, pb.measurements[k].label)
            if i is None or not ms.modes[i].period:
                return False
            dT[k] = ms.modes[i].period - base[k]
    misfit = float(np.sum((dx / s) ** 2) + np.sum((res - dT) ** 2 / other_var))
    return misfit <= lim


def unstated_amplitude_variance(pb: Problem, p, rtol: float = 1e-10) -> np.ndarray:
    """(K,) second moment (s^2) of the lengthening of each period timed at an
    unstated release amplitude (``amplitude is None``; 0 for the others), as
    the budget assumes it (:func:`~bifilar.estimation.budget.amplitude_systematic`:
    amplitudes uniform in 0 .. A_max, ``T = T_lin (1 + (r_max - 1) u)``,
    ``u = (A / A_max)^2``, ``E[u^2] = 1/5``): ``(T_lin (r_max - 1))^2 / 5``.
    Different modes are released independently.  One short simulation per
    such measurement at ``p``."""
    from .budget import default_amplitude_range
    from .solve import amplitude_factor

    vals = pb.values(p)
    out = np.zeros(len(pb.measurements))
    for k, m in enumerate(pb.measurements):
        if m.amplitude is not None:
            continue
        hm = pb.models[m.hanging]
        _, ms, match = hm.locate(hm.scene(vals))
        mode = ms.modes[match[pb.mode_index[k]]]
        if not mode.period:
            continue
        A = default_amplitude_range(hm.scene(vals), mode)
        try:
            r_max, _ = amplitude_factor(hm, vals, pb.mode_index[k], A, 3, rtol)
        except BifilarError:
            continue
        out[k] = (mode.period * (r_max - 1)) ** 2 / 5
    return out


def input_fit_check(pb: Problem, p, z, r=None, extra_var=None, amp_var=None) -> tuple[bool, float, float, str]:
    """The fit check with the measured inputs' uncertainty counted: (passes,
    chi2 of the fit, distance of ``p`` from the fit, description).

    The periods' covariance is ``C = diag(sigma_T^2) + C_x`` (timing plus
    :func:`input_period_covariance`, the spread of periods timed at an
    unstated amplitude, :func:`unstated_amplitude_variance`, and
    ``extra_var`` (K,) s^2 on the diagonal; ``amp_var``: the former when
    computed already, it hardly depends on ``p``).  With ``C = L L^T``, ``res = z
    sigma_T`` the residuals at ``p`` and ``J_p`` the periods' Jacobian in the
    unknowns:

    * the data must fit the model: ``min_dp |L^-1 (res + J_p dp)|^2`` (the
      generalised least-squares residual; with ``C_x = 0`` it equals ``sum
      z^2`` at the weighted least-squares solution) at most its 99.9 %
      quantile with ``K - P`` degrees of freedom;
    * ``p`` must be the fit, not only near a tensor that fits: the step
      ``d = G res`` from ``p`` to the weighted least-squares solution (``G``
      the budget's gain matrix, timing weights) in the metric of that
      estimate's covariance ``G C G^T``, ``d^T (G C G^T)^-1 d``, at most
      its 99.9 % quantile with ``P`` degrees of freedom (0 at the solution;
      the truth passes 99.9 % of the time), so that a point on the edge of
      the physical set away from the fit is not accepted.

    An input error shifts every period it touches together (a wire 1 mm
    long lengthens each swing period of that hanging), which timing alone
    calls a misfit."""
    from scipy.linalg import solve_triangular
    from scipy.stats import chi2 as chi2_dist

    from .uncertainty import gain_matrix

    K, P = len(pb.measurements), len(pb.unknowns)
    r = np.ones(K) if r is None else np.asarray(r, float)
    sig = np.array([m.std for m in pb.measurements])
    res = np.asarray(z, float) * sig
    if K > P:
        lim_fit, lim_p = chi2_limit(K, P), float(chi2_dist.ppf(1 - CHI2_P, P))
        test = (f"with the input uncertainties: fit chi2 <= {lim_fit:.4g} ({K - P} degrees of freedom) and the "
                f"estimate's distance from the fit <= {lim_p:.4g} ({P} degrees of freedom), p = {CHI2_P:g}")
    else:
        # as many periods as unknowns, missed only by an answer on the edge of the physical set (no tensor
        # inside fits): every set of periods fits; the edge is accepted as with timing alone, within EDGE_Z
        # sigma (for P unknowns the same probability, 95.4 %)
        lim_fit = math.inf
        lim_p = float(chi2_dist.ppf(chi2_dist.cdf(EDGE_Z ** 2, 1), P))
        test = (f"with the input uncertainties: the edge's distance from the exact fit <= {lim_p:.4g} ({P} degrees "
                f"of freedom, {EDGE_Z:g} sigma)")
    if not np.all(np.isfinite(res)):
        return False, math.inf, math.inf, test
    amp_var = unstated_amplitude_variance(pb, p) if amp_var is None else amp_var
    C = np.diag(sig ** 2 + amp_var) + input_period_covariance(pb, p, r)
    if extra_var is not None:
        C += np.diag(np.asarray(extra_var, float))
    try:
        L = np.linalg.cholesky(C)
    except np.linalg.LinAlgError:  # sensitivities that overflow: no finite covariance to check against
        return False, math.inf, math.inf, test
    Jp = pb.jacobian(p) * r[:, None]
    with np.errstate(over="ignore", invalid="ignore"):  # a 1e300 s period: an infinite misfit, refused
        rw = solve_triangular(L, res, lower=True)
        Jw = solve_triangular(L, Jp, lower=True)
        e = rw - Jw @ np.linalg.lstsq(Jw, rw, rcond=None)[0]
        G = gain_matrix(Jp, sig)
        d = G @ res
        dist = float(d @ np.linalg.solve(G @ C @ G.T, d))
        chi2_fit = float(e @ e)
    ok = bool(chi2_fit <= lim_fit and dist <= lim_p)  # False for NaN
    if ok and K <= P:
        # no other tensor is fitted: the inputs alone must bridge the residual, checked with the full model
        other = sig ** 2 + amp_var + (0.0 if extra_var is None else np.asarray(extra_var, float))
        ok = inputs_explain(pb, p, -res, other, lim_p)
    return ok, chi2_fit, dist, test


def labelled_periods(pb: Problem, p) -> np.ndarray:
    """(K,) linear periods (s) of the modes carrying the measured labels at ``p`` (NaN: no such mode)."""
    vals = pb.values(p)
    out = np.full(len(pb.measurements), np.nan)
    cache = {}
    for k, m in enumerate(pb.measurements):
        h = m.hanging
        if h not in cache:
            hm = pb.models[h]
            cache[h] = hm.locate(hm.scene(vals))[1]
        i = label_index(cache[h], m.label)
        if i is not None and cache[h].modes[i].period:
            out[k] = cache[h].modes[i].period
    return out


def relabel(pb: Problem, p) -> bool:
    """Re-decide the measured modes by label at ``p``: every hanging's base
    modes become its modes at ``p`` and ``pb.mode_index`` the labelled ones.
    False when a label is missing at ``p`` (nothing changed then)."""
    vals = pb.values(p)
    new = {}
    for h, hm in enumerate(pb.models):
        if any(m.hanging == h for m in pb.measurements):
            new[h] = hm.locate(hm.scene(vals))[1]
    idx = []
    for m in pb.measurements:
        i = label_index(new[m.hanging], m.label)
        if i is None or not new[m.hanging].modes[i].period:
            return False
        idx.append(i)
    for h, ms in new.items():
        pb.models[h].modes0 = ms
    pb.mode_index = idx
    return True


# ---------------------------------------------------------------------------
# one inertia component, one period


class ScalarScan:
    """The periods of every mode of the measured hanging over a grid of the
    unknown inertia component's admissible interval (module docstring)."""

    def __init__(self, pb: Problem, n: int = N_GRID):
        self.pb = pb
        self.name = pb.unknowns[0]
        self.m = pb.measurements[0]
        self.hm = pb.models[self.m.hanging]
        lo, hi = admissible_interval(pb.I_ref0, self.name)
        if not lo <= hi:
            raise InputError("body.inertia", f"no value of {self.name} makes the inertia tensor physical (positive "
                                             "definite, triangle inequality) with the other components as given")
        self.lo, self.hi = lo, hi
        # the positive-definite ends are open (a singular tensor): stay inside
        I_lo = self.hm.inertia_ref({self.name: lo})
        I_hi = self.hm.inertia_ref({self.name: hi})
        w = hi - lo
        self.a = lo + 1e-7 * w if np.linalg.eigvalsh(I_lo)[0] <= 1e-12 * abs(np.trace(I_lo)) else lo
        self.b = hi - 1e-7 * w if np.linalg.eigvalsh(I_hi)[0] <= 1e-12 * abs(np.trace(I_hi)) else hi
        xs = np.linspace(self.a, self.b, n)
        x0 = float(pb.I_ref0[_IDX[self.name]])
        if self.a < x0 < self.b:
            xs = np.sort(np.append(xs, x0))
        self.xs = xs
        sets = self._modes(xs)
        self.nk = max((len(s.modes) for s in sets if s is not None), default=0)
        self.T = np.full((len(xs), self.nk), np.nan)
        self.lab = np.full(len(xs), -1)
        for q, s in enumerate(sets):
            if s is None:
                continue
            self.T[q, :len(s.modes)] = [md.period if md.period else np.nan for md in s.modes]
            i = label_index(s, self.m.label)
            self.lab[q] = -1 if i is None else i
        self.diagonal = _IDX[self.name][0] == _IDX[self.name][1]

    def _modes(self, xs) -> list:
        from ..analysis.batch import modes_batch
        from ..analysis.modes import linear_modes

        hm = self.hm
        scenes = [hm.scene({self.name: float(x)}) for x in xs]
        try:
            out = modes_batch(scenes, [hm.rest0] * len(scenes))
        except (np.linalg.LinAlgError, BifilarError):
            out = []
            for s in scenes:
                try:
                    out.append(linear_modes(s, hm.rest0))
                except (np.linalg.LinAlgError, BifilarError):
                    out.append(None)
        hm.evaluations += len(scenes)
        return out

    def at(self, x: float):
        """ModeSet at ``x`` (None when the modes cannot be computed)."""
        return self._modes([x])[0]

    def period(self, x: float, k: int) -> float:
        s = self.at(x)
        if s is None or k >= len(s.modes) or not s.modes[k].period:
            return math.nan
        return float(s.modes[k].period)

    # -- roots -----------------------------------------------------------
    def roots(self, target: float) -> list[float]:
        """Every admissible value at which the mode carrying the measured
        label has period ``target`` (s), ascending."""
        from scipy.optimize import brentq, minimize_scalar

        xs, out = self.xs, []
        scale = max(abs(self.b), abs(self.a), self.b - self.a)
        for k in range(self.nk):
            f = self.T[:, k] - target
            cands = []
            for q in range(len(xs)):
                if f[q] == 0:
                    cands.append(float(xs[q]))
            for q in range(len(xs) - 1):
                if np.isfinite(f[q]) and np.isfinite(f[q + 1]) and np.sign(f[q]) * np.sign(f[q + 1]) < 0:
                    cands.append(self._brent(k, target, xs[q], xs[q + 1], brentq, scale))
            if not self.diagonal:
                # a product of inertia: a period can turn back inside a cell
                for q in range(1, len(xs) - 1):
                    a, b, c = f[q - 1], f[q], f[q + 1]
                    if not (np.isfinite(a) and np.isfinite(b) and np.isfinite(c)) or np.sign(a) != np.sign(b) or np.sign(b) != np.sign(c):
                        continue
                    if (abs(b) < abs(a)) and (abs(b) < abs(c)):
                        sgn = 1.0 if b > 0 else -1.0
                        r = minimize_scalar(lambda x: sgn * (self.period(x, k) - target),
                                            bounds=(xs[q - 1], xs[q + 1]), method="bounded",
                                            options={"xatol": 1e-12 * scale})
                        if np.isfinite(r.fun) and r.fun < 0:
                            cands.append(self._brent(k, target, xs[q - 1], r.x, brentq, scale))
                            cands.append(self._brent(k, target, r.x, xs[q + 1], brentq, scale))
            for x in cands:
                if x is None:
                    continue
                s = self.at(x)
                if s is not None and label_index(s, self.m.label) == k:
                    out.append(x)
        out.sort()
        uniq = []
        for x in out:
            if not uniq or abs(x - uniq[-1]) > 1e-9 * scale:
                uniq.append(x)
        return uniq

    def _brent(self, k, target, a, b, brentq, scale):
        fa, fb = self.period(a, k) - target, self.period(b, k) - target
        if not (np.isfinite(fa) and np.isfinite(fb)):
            return None
        if fa == 0:
            return float(a)
        if fb == 0:
            return float(b)
        if np.sign(fa) == np.sign(fb):
            return None
        return float(brentq(lambda x: self.period(x, k) - target, a, b, xtol=1e-15 * scale,
                            rtol=4 * np.finfo(float).eps, maxiter=200))

    def edge_root(self, target: float, sigma: float) -> float | None:
        """A closed end of the interval (triangle limit) where the labelled
        mode's period is within ``EDGE_Z`` sigma of ``target``, or, failing
        that, within the period's uncertainty with the measured inputs'
        counted (:func:`input_fit_check`: at most the 99.9 % quantile of
        chi-square with 1 degree of freedom, an input error that explains
        it checked with the full model), else None.  A body on the limit (a
        thin disc, ``Izz = Ixx + Iyy``) has its measured period beyond the
        limit's in about half of all experiments; the inputs' errors (1 mm
        of a trifilar's 0.15 m radius: 0.7 % of the period) put it many
        timing sigma beyond, and timing alone refused 35 % of such honest
        experiments."""
        ends = []
        for x, closed in ((self.lo, self.a == self.lo), (self.hi, self.b == self.hi)):
            if not closed:
                continue
            s = self.at(x)
            i = label_index(s, self.m.label) if s is not None else None
            if i is None or not s.modes[i].period:
                continue
            ends.append(((s.modes[i].period - target) / sigma, x))
        best = min(((abs(z), x) for z, x in ends if abs(z) <= EDGE_Z), default=None)
        if best is None:
            best = min(((abs(z), x) for z, x in ends if input_fit_check(self.pb, np.array([x]), [z])[0]), default=None)
        return None if best is None else best[1]

    # -- the attainable range ---------------------------------------------
    def attainable(self) -> list[tuple[float, float]]:
        """Disjoint ranges (s) of the labelled mode's period over the
        admissible interval, ascending; gaps where the label jumps between
        modes (the switch located by bisection)."""
        xs, segs = self.xs, []
        run = None  # [k, Tmin, Tmax]
        for q in range(len(xs)):
            k = int(self.lab[q])
            T = self.T[q, k] if k >= 0 else math.nan
            if k < 0 or not np.isfinite(T):
                if run:
                    segs.append(run)
                run = None
                continue
            if run is not None and run[0] != k:
                # the label moves from mode run[0] to mode k inside (xs[q-1], xs[q])
                xa, xb = float(xs[q - 1]), float(xs[q])
                for _ in range(40):
                    xm = 0.5 * (xa + xb)
                    s = self.at(xm)
                    if s is not None and label_index(s, self.m.label) == run[0]:
                        xa = xm
                    else:
                        xb = xm
                Ta = self.period(xa, run[0])
                if np.isfinite(Ta):
                    run[1], run[2] = min(run[1], Ta), max(run[2], Ta)
                segs.append(run)
                run = [k, T, T]
                Tb = self.period(xb, k)
                if np.isfinite(Tb):
                    run[1], run[2] = min(T, Tb), max(T, Tb)
                continue
            if run is None:
                run = [k, T, T]
            run[1], run[2] = min(run[1], T), max(run[2], T)
        if run:
            segs.append(run)
        rng = sorted((s[1], s[2]) for s in segs)
        merged: list[list[float]] = []
        for a, b in rng:
            if merged and a <= merged[-1][1] * (1 + 1e-12):
                merged[-1][1] = max(merged[-1][1], b)
            else:
                merged.append([a, b])
        return [(a, b) for a, b in merged]

    def range_message(self, target: float) -> str:
        rng = self.attainable()
        what = f"the mode labelled '{self.m.label}'"
        where = (f"{self.name} anywhere in its physical range, {self.lo:.6g} to {self.hi:.6g} kg m^2 (positive "
                 "definite, triangle inequality, the rest of the tensor as given)")
        if not rng:
            return f"no physical {self.name} gives a period of {target:.9g} s: {what} has no period for {where}"
        msg = (f"no physical {self.name} gives a period of {target:.9g} s for {what}: its period can only range "
               f"over {rng[0][0]:.9g} s .. {rng[-1][1]:.9g} s")
        if len(rng) > 1:
            gaps = ", ".join(f"{a[1]:.9g} s .. {b[0]:.9g} s" for a, b in zip(rng, rng[1:]))
            msg += f" except {gaps} (the label passes to another mode there: two modes exchange character)"
        return msg + f" with {where}"


def scalar_roots(pb: Problem, target: float | None = None) -> list[Root]:
    """Roots of one inertia unknown from one period (module docstring).
    Raises InputError naming the period's field, with the attainable range,
    when there is none."""
    m = pb.measurements[0]
    target = m.period if target is None else float(target)
    scan = ScalarScan(pb)
    xs = scan.roots(target)
    if xs:
        return [Root(np.array([x])) for x in xs]
    x = scan.edge_root(target, m.std)
    if x is not None:
        return [Root(np.array([x]), edge=True)]
    raise InputError(m.field, scan.range_message(target) + _triangle_hint(scan, target)
                     + _input_hint(scan, target) + slip_hint(target, scan.attainable()))


#: a refusal says the measured inputs may be the cause when the period is
#: within this many times the inputs' combined 1-sigma shift (linearised)
#: of the nearest end of the attainable range (:func:`_input_hint`)
INPUT_HINT_Z = 3.0


def _input_size(key: str, s: float) -> str:
    """A measured input's standard uncertainty ``s`` (SI) in the unit a
    user writes it in: mm for lengths and positions, g for the mass."""
    if key == "mass":
        return f"{s * 1e3:.3g} g"
    if key == "gravity":
        return f"{s:.3g} m/s^2"
    return f"{s * 1e3:.3g} mm"


def _input_hint(scan: ScalarScan, target: float) -> str:
    """When the measured inputs, off by their stated uncertainties, move the
    attainable range's nearest end (s) by more than its distance to the
    unreachable ``target`` (s) -- within :data:`INPUT_HINT_Z` times the
    combined linear shift ``sqrt(sum (dT/dx_i s_i)^2)`` of the labelled
    mode's period at the grid point whose period is nearest ``target`` --
    say so and name the dominant input; else ``""``.  Linear only (the
    budget's input Jacobian): the range of a body whose CoM lies a few mm
    below the attachments can move further than this says."""
    T = np.array([scan.T[q, k] if k >= 0 else math.nan for q, k in enumerate(scan.lab)])
    if not np.any(np.isfinite(T)):
        return ""
    q = int(np.nanargmin(np.abs(T - target)))
    T_end, d = float(T[q]), abs(target - float(T[q]))
    try:
        keys, J, s = _input_columns(scan.pb, np.array([scan.xs[q]]))
    except (BifilarError, np.linalg.LinAlgError):
        return ""
    dT = np.abs(J[0]) * s
    tot = float(np.sqrt(np.sum(dT ** 2)))
    if not (tot > 0 and d <= INPUT_HINT_Z * tot):
        return ""
    j = int(np.argmax(dT))
    return (f"; the measured inputs may be the cause: their stated uncertainties move the period near "
            f"{T_end:.6g} s by {100 * tot / T_end:.2g} % (1 sigma, linearised), and {target:.6g} s is "
            f"{100 * d / T_end:.2g} % away; the largest: {keys[j]}, whose {_input_size(keys[j], s[j])} moves it "
            f"by {100 * dT[j] / T_end:.2g} %: check the inputs")


#: the largest number of cycles a period may be the total time of (a
#: stopwatch trial times 5-50 cycles), and the largest N of a 1/N alias
SLIP_MAX_CYCLES = 100
SLIP_MAX_ALIAS = 10
#: a slip is named only for a period at least this factor beyond the
#: reachable range (above its top, below its bottom).  Every slip named
#: changes a period by a factor of 2 or more (N >= 2 cycles or 1/N, 1000
#: for ms), but a range reaching down near zero (a thin disc's Izz -> 0)
#: holds ``target / 2`` for any period just past its top: there a period a
#: few % too long is far likelier the inputs (a CoM a few mm off moves the
#: range by 5-20 %, :func:`_input_hint`) or the mode than a slip
SLIP_MIN_FACTOR = 1.5


def _ns(ns: list[int]) -> str:
    return ", ".join(map(str, ns)) if len(ns) <= 4 else f"{ns[0]} to {ns[-1]}"


def _span(a: float, b: float) -> str:
    return f"{a:.6g} s" if f"{a:.6g}" == f"{b:.6g}" else f"{a:.6g} .. {b:.6g} s"


def slip_hint(target: float, ranges: list[tuple[float, float]]) -> str:
    """Name the input slips that would bring an unreachable period
    ``target`` (s) into the reachable ``ranges`` (s, ``[(lo, hi), ...]``):
    entered in ms (``target / 1000`` reachable), the total time of ``N``
    cycles entered as a period (``target / N``, ``2 <= N <=``
    :data:`SLIP_MAX_CYCLES`) or a shorter alias (``N target``, ``2 <= N <=``
    :data:`SLIP_MAX_ALIAS`: a half period between zero crossings, a
    harmonic).  Only slips that land inside a range are named, and only
    for a period clearly outside the ranges: a too long period (ms, cycles)
    at least :data:`SLIP_MIN_FACTOR` times their top, a too short one (an
    alias) at most their bottom over it; ``""`` otherwise (the message then
    stands as it is)."""
    def inside(x: float) -> bool:
        return any(a * (1 - 1e-9) <= x <= b * (1 + 1e-9) for a, b in ranges)

    if not ranges:
        return ""
    hints = []
    too_long = target >= SLIP_MIN_FACTOR * max(b for _, b in ranges)
    too_short = target <= min(a for a, _ in ranges) / SLIP_MIN_FACTOR
    if too_long and inside(target / 1000):
        hints.append(f"it is reachable as {target / 1000:.6g} s: was it entered in ms?")
    longer = [n for n in range(2, SLIP_MAX_CYCLES + 1) if too_long and inside(target / n)]
    if longer:  # both when the range spans three decades (a thin disc's Izz -> 0): neither excludes the other
        hints.append(f"it is {_ns(longer)} times a reachable period ({_span(target / longer[-1], target / longer[0])}"
                     "): is it the total time of that many cycles?")
    shorter = [n for n in range(2, SLIP_MAX_ALIAS + 1) if too_short and inside(target * n)]
    if shorter:
        half = " (N = 2: a half period, timed between successive zero crossings)" if shorter[0] == 2 else ""
        hints.append(f"it is 1/N of a reachable period for N = {_ns(shorter)} ({_span(target * shorter[0], target * shorter[-1])}"
                     f"): a shorter alias{half} or a harmonic?")
    return ("; likely slip: " + "; or ".join(hints)) if hints else ""


def _triangle_hint(scan: ScalarScan, target: float) -> str:
    """When a positive-definite tensor breaking only the triangle inequality
    would reproduce the period, say so (the fixed components are then the
    likely culprits)."""
    from .problem import physical_interval
    from .solve import solve_scalar

    pb, name = scan.pb, scan.name
    lo, hi = physical_interval(scan.hm.inertia_ref({name: 0.5 * (scan.lo + scan.hi)}), name)

    def T_of_x(x):
        s = scan.at(x)
        i = label_index(s, scan.m.label) if s is not None else None
        return s.modes[i].period if i is not None and s.modes[i].period else math.nan

    x0 = scan.b if target > np.nanmax(scan.T) else scan.a
    try:
        x = solve_scalar(T_of_x, target, x0, lo, hi, float(pb.scales()[0]), scan.m.field, name)
    except (BifilarError, ValueError, ArithmeticError):
        return ""
    if not abs(T_of_x(x) - target) <= 1e-6 * target:
        return ""
    others = ", ".join(f"{n} = {pb.I_ref0[ij]:.6g}" for n, ij in _IDX.items() if n != name and ij[0] == ij[1])
    return (f"; {name} = {x:.6g} kg m^2 would reproduce it but breaks the triangle inequality with the other "
            f"components as given ({others}): check them, or solve for them too")


# ---------------------------------------------------------------------------
# several unknowns or periods


def _halton(n: int, d: int) -> np.ndarray:
    """First ``n`` points (from index 1) of the Halton sequence in [0, 1]^d."""
    primes = [2, 3, 5, 7, 11, 13, 17, 19, 23]
    out = np.zeros((n, d))
    for j in range(d):
        b = primes[j % len(primes)]
        for i in range(n):
            f, r, k = 1.0, 0.0, i + 1
            while k:
                f /= b
                r += f * (k % b)
                k //= b
            out[i, j] = r
    return out


def start_design(pb: Problem, n_extra: int | None = None) -> list[np.ndarray]:
    """Deterministic start points: the prior, then a Halton design over the
    box of each unknown's admissible interval (others at the prior; CoM
    shifts within 5 % of the longest wire), kept when admissible."""
    P = len(pb.unknowns)
    p0 = pb.prior
    n_extra = 2 * P + 2 if n_extra is None else n_extra
    lo = np.empty(P)
    hi = np.empty(P)
    Lmax = max(float(np.max(hm.scene0.lengths)) for hm in pb.models)
    for j, n in enumerate(pb.unknowns):
        if n in _IDX:
            a, b = admissible_interval(pb.I_ref0, n)
            if not a <= b:
                a = b = p0[j]
        else:
            a, b = p0[j] - 0.05 * Lmax, p0[j] + 0.05 * Lmax
        w = b - a
        lo[j], hi[j] = a + 0.1 * w, b - 0.1 * w
    out = [p0]
    for u in _halton(n_extra, P):
        p = lo + u * (hi - lo)
        if admissible(pb.models[0].inertia_ref(pb.values(p))):
            out.append(p)
    return out


UNREACHABLE_FACTOR = 10.0
"""A measured period more than this factor outside the range its mode spans
over the start design is an input error (units, a typo), not a failed fit."""


def _refuse_unreachable(pb: Problem, targets: np.ndarray) -> None:
    """Raise an :class:`InputError` naming the measurement whose period (s)
    lies more than :data:`UNREACHABLE_FACTOR` outside the periods its mode
    takes over the admissible start design (a sample of the admissible set):
    a 1e300 s period makes every least-squares misfit overflow, which is bad
    input, not a solver failure."""
    for k, (m, col) in enumerate(zip(pb.measurements, _sampled_periods(pb))):
        if col.size and not col.min() / UNREACHABLE_FACTOR <= targets[k] <= col.max() * UNREACHABLE_FACTOR:
            raise InputError(m.field, f"no admissible inertia gives a period near {m.period:.6g} s for the "
                             f"mode labelled {m.label!r}: over {col.size} admissible tensors sampled its period "
                             f"ranges over {col.min():.6g} .. {col.max():.6g} s (check the units and the label)"
                             + slip_hint(m.period, [(float(col.min()), float(col.max()))]))


def _sampled_periods(pb: Problem) -> list[np.ndarray]:
    """Per measurement, the finite periods (s) its labelled mode takes over
    the admissible start design (:func:`start_design`)."""
    T = np.array([labelled_periods(pb, p) for p in start_design(pb)])  # (starts, K) s
    return [T[:, k][np.isfinite(T[:, k])] for k in range(T.shape[1])]


def _sampled_slip(pb: Problem, k: int) -> str:
    """:func:`slip_hint` for measurement ``k`` when its period lies outside
    the range its mode spans over the start design, else ``""``."""
    col = _sampled_periods(pb)[k]
    T = pb.measurements[k].period
    if not col.size or col.min() <= T <= col.max():
        return ""
    return slip_hint(T, [(float(col.min()), float(col.max()))])


def multi_roots(pb: Problem, targets: np.ndarray | None = None) -> tuple[list[Root], dict]:
    """Distinct admissible least-squares solutions that pass the fit check,
    from every start of :func:`start_design`; also the best failed fit
    (dict with ``p``, ``z``, ``chi2``, ``test``) for the refusal message."""
    from .solve import gauss_newton

    targets = np.array([m.period for m in pb.measurements]) if targets is None else np.asarray(targets, float)
    sig = np.array([m.std for m in pb.measurements])
    sc = pb.scales()
    P = len(pb.unknowns)
    found: list[np.ndarray] = []
    misfits: list[dict] = []
    best: dict = {}
    errors = []
    for p0 in start_design(pb):
        if any(np.max(np.abs(p0 - q) / sc) < 1e-9 for q in found):
            continue
        try:
            p = gauss_newton(pb, targets, p0, admissible_only=True, relabel=True, known=found)
        except InputError:
            raise
        except BifilarError as exc:
            errors.append(str(exc))
            continue
        if p is None:  # reached a known root
            continue
        z = (labelled_periods(pb, p) - targets) / sig
        ok, chi2, test = fit_statistics(z, P)
        if ok:
            if not any(np.max(np.abs(p - q) / sc) < 1e-6 for q in found):
                found.append(p)
        elif not any(np.max(np.abs(p - q["p"]) / sc) < 1e-6 for q in misfits):
            misfits.append({"p": p, "z": z, "chi2": chi2, "test": test})
    # a misfit by timing alone may still fit within the inputs' uncertainty:
    # an input error shifts the periods together (input_fit_check)
    from .solve import EDGE_MARGIN, admissible_margin

    K = len(sig)
    amp_var = None  # one set of simulations for every misfit
    for q in misfits:
        if any(np.max(np.abs(q["p"] - f) / sc) < 1e-6 for f in found):
            continue
        # as many periods as unknowns: only a point on the edge of the physical set may miss them (nothing
        # inside fits exactly); it must still be within their uncertainty with the inputs'
        if (K > P or admissible_margin(pb, q["p"]) < EDGE_MARGIN) and np.all(np.isfinite(q["z"])):
            amp_var = unstated_amplitude_variance(pb, q["p"]) if amp_var is None else amp_var
            ok, q["chi2"], _, q["test"] = input_fit_check(pb, q["p"], q["z"], amp_var=amp_var)
            if ok:
                found.append(q["p"])
                continue
        if not best or q["chi2"] < best["chi2"]:
            best = q
    if not found and not best and errors:
        _refuse_unreachable(pb, targets)
        raise ConvergenceError(f"the least-squares solver failed from every start point: {errors[0]}")
    # ascending, compared at 1e-9 of the scales so that last-bit noise cannot reorder them
    found.sort(key=lambda q: tuple(np.round(q / sc, 9)))
    return [Root(q, edge=admissible_margin(pb, q) < EDGE_MARGIN) for q in found], best


def find_roots(pb: Problem, targets: np.ndarray | None = None) -> list[Root]:
    """Every admissible solution of the linear model for the measured
    periods (module docstring), ascending; raises InputError (no admissible
    tensor reproduces the periods: the message names the attainable range
    or the best fit) or ConvergenceError (the solver failed).  ``targets``:
    the periods (s) the linear model must reproduce (default: the measured
    ones; the measured ones divided by the amplitude factors for the
    nonlinear method)."""
    K, P = len(pb.measurements), len(pb.unknowns)
    if K == 1 and P == 1 and pb.unknowns[0] in _IDX:
        return scalar_roots(pb, None if targets is None else float(targets[0]))
    roots, best = multi_roots(pb, targets)
    if roots:
        return roots
    if not best:
        raise ConvergenceError("the least-squares solver found no admissible tensor from any start point")
    z = best["z"]
    k = int(np.nanargmax(np.abs(np.where(np.isfinite(z), z, np.inf))))
    vals = ", ".join(f"{n} = {v:.6g}" for n, v in zip(pb.unknowns, best["p"]))
    zs = ", ".join(f"{m.label} {zk:+.3g}" for m, zk in zip(pb.measurements, z))
    raise InputError(pb.measurements[k].field,
                     f"no physical tensor reproduces the measured periods: the best admissible fit ({vals}) "
                     f"leaves normalised residuals {zs} sigma, failing the fit check ({best['test']}); check the "
                     "periods, their modes and the config, or solve for other components" + _sampled_slip(pb, k))


def separating_measurement(pbs: list, roots: list, sigma: float) -> dict | None:
    """The mode (of a hanging already in use) whose predicted linear periods
    differ most between the roots, relative to the timing uncertainty
    ``sigma`` (s): {hanging, mode, periods (s, per root), separation (in
    sigma)}; modes already measured in that hanging are skipped.  None when
    no unmeasured mode has a period at every root."""
    best = None
    for h in range(len(pbs[0].models)):
        measured = {m.label for m in pbs[0].measurements if m.hanging == h}
        sets = []
        for pb, r in zip(pbs, roots):
            hm = pb.models[h]
            sets.append(hm.locate(hm.scene(pb.values(r.p)))[1])
        for md in sets[0].modes:
            if md.label in measured:
                continue
            Ts = []
            for s in sets:
                i = label_index(s, md.label)
                Ts.append(s.modes[i].period if i is not None and s.modes[i].period else None)
            if any(t is None for t in Ts):
                continue
            sep = (max(Ts) - min(Ts)) / sigma
            if best is None or sep > best["separation"]:
                best = {"hanging": pbs[0].models[h].hanging.name, "mode": md.label, "periods": Ts,
                        "separation": float(sep)}
    return best
