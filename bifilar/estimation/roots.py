"""Every physical solution of the inversion, the measured mode identified at
the solution (the check that an answer reproduces its measurements is
:mod:`bifilar.estimation.fit_check`).

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
An answer must reproduce every measured period:
:mod:`bifilar.estimation.fit_check`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import BifilarError, ConvergenceError, InputError
from .crossing_partner import partner_hint, surface_hint
from .fit_check import (EDGE_Z, _input_columns, fit_statistics, input_fit_check, label_index, labelled_periods,
                        prior_fit_hint, unstated_amplitude_variance)
from .problem import _IDX, Problem, admissible, admissible_interval

#: grid points over the admissible interval of one unknown
N_GRID = 41


@dataclass
class Root:
    """One admissible solution ``p`` (unknowns, SI); ``edge`` when it lies on
    the boundary of the physical set (no exact solution inside it)."""

    p: np.ndarray
    edge: bool = False




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
        self.switches = None  # set by attainable()

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

    def edge_root(self, target: float, sigma: float, extra_var=None) -> float | None:
        """A closed end of the interval (triangle limit) where the labelled
        mode's period is within ``EDGE_Z`` sigma of ``target``, or, failing
        that, within the period's uncertainty with the measured inputs'
        counted (:func:`input_fit_check`: at most the 99.9 % quantile of
        chi-square with 1 degree of freedom, an input error that explains
        it checked with the full model), else None.  ``extra_var``: a
        callable giving the (1,) variance (s^2) of ``target`` from the
        stated amplitude's own uncertainty (the nonlinear method's target is
        the period over its amplitude factor), called only when timing
        alone does not reach the end; it widens ``sigma`` of both tests (a
        slender boom's torsion released at 0.2 rad: the amplitude's 10 %
        is 20 times a camera record's timing std, and honest experiments
        whose release was 1-2 of its stds off were refused).  A body on the limit (a
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
        ev = None
        if best is None and ends and extra_var is not None:
            ev = np.asarray(extra_var(), float)
            wide = math.sqrt(1.0 + float(ev[0]) / sigma ** 2)
            best = min(((abs(z) / wide, x) for z, x in ends if abs(z) / wide <= EDGE_Z), default=None)
        if best is None:
            best = min(((abs(z), x) for z, x in ends if input_fit_check(self.pb, np.array([x]), [z],
                                                                         extra_var=ev)[0]), default=None)
        return None if best is None else best[1]

    # -- the attainable range ---------------------------------------------
    def attainable(self) -> list[tuple[float, float]]:
        """Disjoint ranges (s) of the labelled mode's period over the
        admissible interval, ascending; gaps where the label jumps between
        modes (the switch located by bisection)."""
        xs, segs = self.xs, []
        self.switches = []  # (xa, xb, k before, k after, T before, T after): where the label jumps
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
                run_k = run[0]
                if np.isfinite(Ta):
                    run[1], run[2] = min(run[1], Ta), max(run[2], Ta)
                segs.append(run)
                run = [k, T, T]
                Tb = self.period(xb, k)
                self.switches.append((xa, xb, run_k, k, Ta, Tb))
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

    def range_message(self, target: float, exact: bool = False, partner=None) -> str:
        """Why no physical value gives the labelled mode the period
        ``target`` (s): the range (s) its period spans, its gaps where the
        label passes to another mode, and, for a ``target`` inside such a gap,
        the partner label (:func:`~bifilar.estimation.crossing_partner.partner_hint`; ``exact``: ``target`` is
        the measured period itself, so the partner reading's root is what
        ``invert`` answers; ``partner``: with an amplitude, the partner reading's answer,
        :func:`~bifilar.estimation.crossing_partner.amplitude_reading`)."""
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
        return msg + f" with {where}" + partner_hint(self, target, exact, partner)


def scalar_roots(pb: Problem, target: float | None = None, extra_var=None, partner=None) -> list[Root]:
    """Roots of one inertia unknown from one period (module docstring).
    Raises InputError naming the period's field, with the attainable range,
    when there is none.  ``extra_var``: as for :meth:`ScalarScan.edge_root`;
    ``partner``: as for :meth:`ScalarScan.range_message`."""
    m = pb.measurements[0]
    exact = target is None or float(target) == m.period
    target = m.period if target is None else float(target)
    scan = ScalarScan(pb)
    xs = scan.roots(target)
    if xs:
        return [Root(np.array([x])) for x in xs]
    x = scan.edge_root(target, m.std, extra_var)
    if x is not None:
        return [Root(np.array([x]), edge=True)]
    raise InputError(m.field, scan.range_message(target, exact, partner) + _triangle_hint(scan, target)
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


#: an unknown whose timing-only std at the best fit exceeds this fraction of its scale
#: (:meth:`~bifilar.estimation.problem.Problem.scales`: the largest moment, or 1 % of the longest
#: wire for a CoM coordinate) is named as barely determined in a refusal
LOOSE_UNKNOWN = 0.1


def loosely_determined(pb: Problem, p) -> list[tuple[str, float]]:
    """[(unknown, std)] of the unknowns the measured periods barely fix at
    ``p``: the linear least-squares std from the timing stds alone (kg m^2
    or m) above :data:`LOOSE_UNKNOWN` of the unknown's scale, largest
    first; [] where the Jacobian cannot be formed or inverted."""
    sig = np.array([m.std for m in pb.measurements], float)
    try:
        J = pb.jacobian(np.asarray(p, float)) / sig[:, None]
        std = np.sqrt(np.diag(np.linalg.pinv(J.T @ J)))
    except (BifilarError, np.linalg.LinAlgError, ValueError):
        return []
    sc = pb.scales()
    loose = [(n, float(s)) for n, s, c in zip(pb.unknowns, std, sc) if np.isfinite(s) and s > LOOSE_UNKNOWN * c]
    return sorted(loose, key=lambda x: -x[1] / sc[pb.unknowns.index(x[0])])


def _loose_hint(pb: Problem) -> str:
    """The refusal's advice: the unknowns the periods barely determine at
    the config's values (the starting guess ``pb.prior``; at a failed best
    fit the Jacobian is often near singular) first, then the periods and
    the config."""
    loose = loosely_determined(pb, pb.prior)
    if not loose:
        return "check the periods, their modes and the config, or solve for other components"
    unit = {n: ("m" if n.startswith("com.") else "kg m^2") for n, _ in loose}
    names = " and ".join(n for n, _ in loose)
    stds = ", ".join(f"{n} +-{s:.2g} {unit[n]}" for n, s in loose)
    return (f"the periods barely determine {names} (from the timing alone, at the config's values: {stds}), so the timing's and "
            "the inputs' errors move them far: measure them and solve for fewer components, or add modes or "
            "hangings that depend on them; else check the periods, their modes and the config")


def _sampled_slip(pb: Problem, k: int) -> str:
    """:func:`slip_hint` for measurement ``k`` when its period lies outside
    the range its mode spans over the start design, else ``""``."""
    col = _sampled_periods(pb)[k]
    T = pb.measurements[k].period
    if not col.size or col.min() <= T <= col.max():
        return ""
    return slip_hint(T, [(float(col.min()), float(col.max()))])


def multi_roots(pb: Problem, targets: np.ndarray | None = None, extra_var=None) -> tuple[list[Root], dict]:
    """Distinct admissible least-squares solutions that pass the fit check,
    from every start of :func:`start_design`; also the best failed fit
    (dict with ``p``, ``z``, ``chi2``, ``test``) for the refusal message.
    ``extra_var``: a callable giving the (K,) variance (s^2) of the targets
    from the stated amplitudes (:meth:`ScalarScan.edge_root`), counted in
    the misfits' check with the inputs."""
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
    amp_var = ev = None  # one set of simulations for every misfit
    for q in misfits:
        if any(np.max(np.abs(q["p"] - f) / sc) < 1e-6 for f in found):
            continue
        # as many periods as unknowns: only a point on the edge of the physical set may miss them (nothing
        # inside fits exactly); it must still be within their uncertainty with the inputs'
        if (K > P or admissible_margin(pb, q["p"]) < EDGE_MARGIN) and np.all(np.isfinite(q["z"])):
            amp_var = unstated_amplitude_variance(pb, q["p"]) if amp_var is None else amp_var
            if ev is None and extra_var is not None:
                ev = np.asarray(extra_var(), float)
            if K <= P and P > 1:
                _edge_in_full_metric(pb, q, targets, amp_var, ev)
            ok, q["chi2"], _, q["test"] = input_fit_check(pb, q["p"], q["z"], amp_var=amp_var, extra_var=ev)
            q["amp_var"], q["extra_var"] = amp_var, ev  # for the refusal's hint (prior_fit_hint)
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


def _edge_in_full_metric(pb: Problem, q: dict, targets, amp_var, extra_var) -> None:
    """Move the edge point ``q`` (a misfit of :func:`multi_roots`: ``p``, ``z``)
    of as many periods as unknowns (P >= 2) to the least squares along the
    edge in the metric of the periods' full covariance ``C`` (timing,
    measured inputs, amplitudes, stated priors:
    :func:`~bifilar.estimation.fit_check.period_covariance` at ``q``),
    where it finds a lower misfit there.  In the linearisation the periods
    map one to one onto the unknowns, so this is the projection of the
    unconstrained estimate onto the edge in the metric of its covariance, in
    which the position along the edge is independent of the component
    across it that put the estimate outside: the timing metric's projection
    is not, and where the inputs dominate the periods' spread it slid the
    answer along the edge (the thin plate's Izz from torsion and pitch at
    0.3 ms, 1000 draws: edge answers -0.65 std on average, 0.906 of their
    95 % intervals covering it, 58 refused; with it +0.02 std, 0.983, 6
    refused; docs/design.md, "trust23, session 23")."""
    from scipy.linalg import solve_triangular

    from .fit_check import period_covariance
    from .solve import _edge_minimum

    try:
        L = np.linalg.cholesky(period_covariance(pb, q["p"], None, amp_var, extra_var)[0])
    except np.linalg.LinAlgError:
        return
    W = solve_triangular(L, np.eye(len(L)), lower=True)

    def cost(p):
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                r = W @ (pb.linear_periods(p) - targets)
        except BifilarError:
            return math.inf, None
        return (float(r @ r) if np.all(np.isfinite(r)) else math.inf), r

    c0 = cost(q["p"])[0]
    if not math.isfinite(c0):
        return
    pe = _edge_minimum(pb, cost, q["p"], c0, pb.scales(), W=W)
    if pe is None:
        return
    sig = np.array([m.std for m in pb.measurements])
    z = (labelled_periods(pb, pe) - targets) / sig
    if np.all(np.isfinite(z)):
        q["p"], q["z"] = pe, z
        q["chi2"], q["test"] = fit_statistics(z, len(pb.unknowns))[1:]


def find_roots(pb: Problem, targets: np.ndarray | None = None, extra_var=None, partner=None) -> list[Root]:
    """Every admissible solution of the linear model for the measured
    periods (module docstring), ascending; raises InputError (no admissible
    tensor reproduces the periods: the message names the attainable range
    or the best fit) or ConvergenceError (the solver failed).  ``targets``:
    the periods (s) the linear model must reproduce (default: the measured
    ones; the measured ones divided by the amplitude factors for the
    nonlinear method).  ``extra_var``: a callable giving the (K,) variance
    (s^2) of the targets from the stated amplitudes' uncertainty, counted
    where a misfit or an edge is checked (:meth:`ScalarScan.edge_root`).
    ``partner``: the partner reading of a refusal whose period lies in an
    avoided crossing's gap (:func:`~bifilar.estimation.crossing_partner.partner_reading`;
    one period: :meth:`ScalarScan.range_message`, several:
    :func:`~bifilar.estimation.crossing_partner.surface_hint`)."""
    K, P = len(pb.measurements), len(pb.unknowns)
    if K == 1 and P == 1 and pb.unknowns[0] in _IDX:
        return scalar_roots(pb, None if targets is None else float(targets[0]), extra_var, partner)
    roots, best = multi_roots(pb, targets, extra_var)
    if roots:
        return roots
    if not best:
        raise ConvergenceError("the least-squares solver found no admissible tensor from any start point")
    z = best["z"]
    k = int(np.nanargmax(np.abs(np.where(np.isfinite(z), z, np.inf))))
    vals = ", ".join(f"{n} = {v:.6g}" for n, v in zip(pb.unknowns, best["p"]))
    # a mode that is neutral at the best fit has no period there (NaN): said so, not printed as "+nan"
    zs = ", ".join(f"{m.label} {zk:+.3g}" if np.isfinite(zk) else f"{m.label} none (no period there: a neutral mode)"
                   for m, zk in zip(pb.measurements, z))
    raise InputError(pb.measurements[k].field,
                     f"no physical tensor reproduces the measured periods: the best admissible fit ({vals}) "
                     f"leaves normalised residuals {zs} sigma, failing the fit check ({best['test']}); "
                     + prior_fit_hint(pb, best["p"], z, extra_var=best.get("extra_var"), amp_var=best.get("amp_var"))
                     + _loose_hint(pb) + _sampled_slip(pb, k)
                     + surface_hint(pb, best["p"], z, [m.period for m in pb.measurements] if targets is None
                                    else targets, partner))


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
