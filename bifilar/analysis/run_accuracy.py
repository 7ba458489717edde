"""How far a run's figures can be trusted, and what it cannot time: the
integrator's tolerance floor (:data:`MIN_RTOL`), amplitudes too small to
time (:func:`small_amplitude_period`), the energy drift's rounding floor
(:func:`drift_resolution`), the bound on the period's numerical error
(:func:`period_accuracy`: a per-method constant times rtol, plus the energy
drift's part) held against the user's timing, and the second run that
checks that bound where the motion is not clean (:func:`check_period`;
:func:`check_matters` where a caller holds the period against a measured
one's std, :func:`not_regular` its verdict).
SI units (s, rad, m, J).  Split from :mod:`bifilar.analysis.simulate`,
which runs the motion and reports these figures.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import IntegrationError, InputError
from ..models import maximal as mx
from ..scene import Scene
from .equilibrium import RestPose


def below_resolution(drift: float, resolution: float) -> bool | None:
    """Whether a relative energy ``drift`` is no larger than its ``resolution``
    (:func:`drift_resolution`: a number that is rounding, not drift); None where either is undefined."""
    if not (np.isfinite(drift) and np.isfinite(resolution)):
        return None
    return bool(drift <= resolution)


MIN_RTOL = 100 * float(np.finfo(float).eps)
"""Smallest relative tolerance a run takes (2.2e-14): ODEPACK's LSODA (the
``auto`` method) refuses anything tighter ("Illegal input detected", exit 1
after NaN warnings), and :func:`scipy.integrate.solve_ivp` silently raises it
to this value while the report would state the tighter one."""


def check_rtol(rtol: float) -> None:
    """Refuse (:class:`InputError` on ``--rtol``) a relative tolerance below
    :data:`MIN_RTOL`, which no integrator here keeps."""
    if not rtol >= MIN_RTOL:
        raise InputError("--rtol", f"must be at least {MIN_RTOL:.3g} (100 x the double precision: the integrators "
                                   f"refuse a tighter tolerance or loosen it to that), got {rtol:g}")


MIN_TIMED_ANGLE = 1e-6
"""Smallest release amplitude, as a wire angle (rad: the amplitude of a
rotation-dominated mode, a translation's metres over the longest wire), from
which a run times a period: the integrator's tolerances stop shrinking with
the amplitude there (:func:`state_scale`) and the state's rounding follows, so
below it the crossings time the tolerance and the rounding, not the motion
(at 1e-9 rad the thesis cylinder's torsion came out 1e-7 off its period, at
1e-12 rad 3e-4, at 1e-300 rad 44 %, all with exit status 0).  The run itself
(its record, tensions, health) is still given."""


def _small_amplitude(amplitude, dominant: int, Lmax: float) -> tuple[str, float] | None:
    """(unit, least amplitude) when ``amplitude`` (None: an explicit start,
    not judged) is nonzero but below :data:`MIN_TIMED_ANGLE` as a wire angle
    (``dominant`` the timed coordinate's index in dx dy dz rx ry rz, ``Lmax``
    the longest wire, m), else None."""
    if amplitude is None or amplitude == 0 or not np.isfinite(amplitude):
        return None
    unit, least = ("rad", MIN_TIMED_ANGLE) if dominant >= 3 else ("m", MIN_TIMED_ANGLE * Lmax)
    return (unit, least) if abs(amplitude) < least else None


_SMALL_WHY = ("below {least:.3g} {unit} the simulated crossings follow the integrator's tolerance and the rounding "
              "of the state, not the motion")


def small_amplitude_period(amplitude, dominant: int, Lmax: float, linear_period) -> tuple[float, str] | None:
    """(period, warning) of a run released at an amplitude too small to time
    (:data:`MIN_TIMED_ANGLE`): the linear period (s), which such a motion has
    to ~A^2 (below 1e-12 of it), and why it is given instead of the crossings';
    None otherwise (and for a mode without a period)."""
    small = _small_amplitude(amplitude, dominant, Lmax)
    if small is None or not linear_period:
        return None
    why = _SMALL_WHY.format(least=small[1], unit=small[0])
    return float(linear_period), (f"amplitude {amplitude:g} {small[0]} is too small to time: {why}; the period "
                                  "given is the linear one, which such a motion has to within ~amplitude^2 "
                                  f"(give |amplitude| >= {small[1]:.3g} {small[0]} to time it)")


def untimed(amplitude: float | None, dominant: int = 3, Lmax: float = 1.0) -> bool:
    """True when a run released at ``amplitude`` (None: an explicit start,
    not judged) cannot be timed: amplitude 0 or below :data:`MIN_TIMED_ANGLE`
    as a wire angle.  Its oscillation energy (~A^2, at most 1e-12 of the
    rig's) is then zero or at the rounding of the energy bookkeeping, so the
    drift relative to it is undefined too (nan: 0.0 or 0.32 for the same
    run, depending on the BLAS kernel's last bits)."""
    return amplitude is not None and (amplitude == 0 or _small_amplitude(amplitude, dominant, Lmax) is not None)


DRIFT_FLOOR_ULPS = 20.0
"""Rounding floor of a run's absolute energy error, in units of eps m g D
(D: the farthest anchor from the rest CoM, the lever the wire constraints
round their positions on).  Measured (docs/design.md, "Simulate's health
at the edges"): at amplitudes 2e-6 and 1e-5 rad, where the tolerances' part
(~rtol, relative) is negligible, |E - E0| was 0.2-10 eps m g D over every
mode of the shipped configs, LSODA and DOP853, 3-300 periods (it grows
slowly with the run's length: x2 from 10 to 100 periods); 20 covers these
with a margin of 2."""


def drift_resolution(scene: Scene, rest: RestPose, y_start: np.ndarray) -> float:
    """Smallest relative energy drift a run released at ``y_start`` (13,),
    world frame, can tell from the rounding of its own energy bookkeeping:
    :data:`DRIFT_FLOOR_ULPS` eps m g D over the oscillation energy E0 - E_rest
    (J; kinetic plus m g (z - z_rest), taken as a difference so that it is not
    rounded itself).  The oscillation energy grows as A^2, the floor does not,
    so at tiny amplitudes the measured drift is this floor (1/A^2: 7e-6 at
    1e-5 rad on the thesis plate) and says nothing about the integration.
    nan when there is no oscillation energy."""
    y = np.asarray(y_start, float).copy()
    y[0:3] -= rest.com
    e_osc = float(mx.energy(y, mx.params_from_scenes(scene)))
    return drift_floor(scene.mass, scene.gravity, scene.anchors - rest.com, e_osc)


def drift_floor(mass: float, gravity: float, anchors_rel: np.ndarray, e_osc: float) -> float:
    """:func:`drift_resolution` from its parts: ``mass`` kg, ``gravity`` m/s^2,
    ``anchors_rel`` (n, 3) the anchors relative to the rest CoM (m, world
    frame), ``e_osc`` the oscillation energy E0 - E_rest (J); nan where that
    is zero or undefined."""
    e_osc = abs(float(e_osc))
    if not e_osc > 0:
        return float("nan")
    lever = float(np.max(np.linalg.norm(anchors_rel, axis=1)))
    return DRIFT_FLOOR_ULPS * np.finfo(float).eps * float(mass) * float(gravity) * lever / e_osc


PERIOD_ERROR_PER_RTOL = {"auto": 15.0, "LSODA": 8.0, "DOP853": 4.0, "RK45": 5.0, "RK23": 7.0, "Radau": 0.05,
                         "BDF": 10.0}
"""Bound on a run's relative period error per unit of ``rtol``, by method
(``auto``: the batched engine's LSODA, ``scipy.integrate.odeint``; the others
:func:`scipy.integrate.solve_ivp`'s).  Measured (docs/design.md, "Simulate's
health at the edges"): the period of every mode of the shipped configs at
0.001-0.3 rad (translations: times the longest wire), 3-100 periods, rtol
1e-4..1e-10 (RK23 and BDF: the plate, to 1e-8), against the same run at rtol
1e-12 with DOP853; the largest error over rtol was 6.6 (auto), 3.6 (LSODA),
1.7 (DOP853), 2.2 (RK45), 3.5 (RK23), 0.016 (Radau), 4.6 (BDF).  Each bound
is about twice that (three times for Radau).
The error is the integration's phase error, so it is relative and does not
grow with the number of periods."""


PERIOD_ERROR_PER_RTOL_KANE = {"DOP853": 8.0, "RK45": 30.0, "LSODA": 40.0}
"""The same for the thesis's kane model (``--model kane``), whose equations
the tolerances meet differently: every mode of the plate and the pitch rig
at 0.001 and 0.05 rad, rtol 1e-4, 1e-6, 1e-8, 1e-10, against the kane run at
1e-12; largest error over rtol 3.4 (DOP853, its default; 0.8 from 1e-6 on),
14 (RK45), 20 (LSODA).  Other methods get the largest bound."""


PERIOD_ERROR_FLOOR = 1e-12
"""Smallest relative period error claimed: the 1e-12 reference runs agree
with each other (LSODA against DOP853) to 1e-12, so nothing finer was checked."""


PERIOD_ERROR_WARN = 1e-8
"""Relative period error above which a run warns when the config states no
timing uncertainty (the fallback of :func:`period_warn_threshold`): a tenth
of the best timing the planner considers (a sensor record of 50 cycles at
1 kHz with 0.1 % noise: ~1e-7 of the period, :mod:`bifilar.studies.timing`);
a stopwatch's is 1e-3."""


TIMING_SHARE = 0.1
"""Share of the stated timing uncertainty a period's numerical error may reach
before a run warns: below a tenth of the period's std it adds under 0.5 % to
it in quadrature (sqrt(1 + 0.1^2) = 1.005), so it is negligible against what
the experiment can reach."""


def period_warn_threshold(period: float, timing: float | None = None) -> float:
    """Numerical period error (s) above which a run warns: :data:`TIMING_SHARE`
    of ``timing`` (s, the standard uncertainty of one measured period, the
    config's ``uncertainty.timing``) where one is stated and positive, else
    :data:`PERIOD_ERROR_WARN` of ``period`` (s)."""
    return TIMING_SHARE * float(timing) if _timing_stated(timing) else PERIOD_ERROR_WARN * period


def _timing_stated(timing: float | None) -> bool:
    """Whether ``timing`` (s) is a usable stated timing uncertainty (finite, positive)."""
    return timing is not None and math.isfinite(timing) and timing > 0


def period_accuracy(period: float | None, method: str, rtol: float, amplitude: float | None = None,
                    dominant: int = 3, Lmax: float = 1.0, model: str = "maximal",
                    timing: float | None = None, linear_period: float | None = None,
                    drift: float = float("nan"), crossing: float = 0.0) -> tuple[float, str | None]:
    """(error, warning) of a run's measured ``period`` (s): a bound on its
    numerical error, s (nan without a period), and a warning when the bound
    exceeds :func:`period_warn_threshold` (a tenth of ``timing``, s, the
    stated standard uncertainty of a measured period; without one
    :data:`PERIOD_ERROR_WARN` of the period), else None.

    The bound is the integrator's part, :data:`PERIOD_ERROR_PER_RTOL` [``method``]
    x ``rtol`` of the period (``model="kane"``: :data:`PERIOD_ERROR_PER_RTOL_KANE`),
    at least :data:`PERIOD_ERROR_FLOOR`, plus the energy drift's part
    (:func:`drift_period_error`: ``drift``, the run's relative energy drift,
    times the period's distance from ``linear_period``, s); for a release too
    small to time (``amplitude``, ``dominant``, ``Lmax`` as
    :func:`small_amplitude_period`), whose period is the linear one, the wire
    angle squared.  A method without a measured bound (a name not in the
    table) gets the largest one.  ``crossing`` (s): the part the crossings'
    interpolation between samples adds (:func:`crossing_period_error`, the
    ``auto`` engine's).  Where that part could not be estimated (``crossing``
    NaN: too few samples or crossings, :func:`crossing_period_error`) the
    error is not established: NaN (JSON null) and a warning naming
    ``--periods``, not the other parts alone."""
    if period is None:
        return float("nan"), None
    small = _small_amplitude(amplitude, dominant, Lmax)
    if small is not None:
        angle = abs(amplitude) / (1.0 if dominant >= 3 else Lmax)
        return max(angle**2, PERIOD_ERROR_FLOOR) * period, None
    if not np.isfinite(crossing):
        return float("nan"), ("the period's numerical error is not established: the error of locating its crossings "
                              "between the samples could not be estimated (fewer than 9 samples, or a crossing the "
                              "samples do not show); integrate more --periods, or --method DOP853 locates them on "
                              "its own steps")
    table = PERIOD_ERROR_PER_RTOL_KANE if model == "kane" else PERIOD_ERROR_PER_RTOL
    c = table.get(method, max(table.values()))
    err_int = max(c * rtol, PERIOD_ERROR_FLOOR) * period
    err_drift = drift_period_error(period, linear_period, drift)
    crossing = float(crossing)
    err = err_int + err_drift + crossing
    limit = period_warn_threshold(period, timing)
    if err <= limit:
        return err, None
    what = (f"a tenth of the config's timing uncertainty (uncertainty.timing {timing:g} s)" if _timing_stated(timing)
            else f"the {PERIOD_ERROR_WARN:g} a sensor's timing resolves")
    # both parts shrink about as rtol (the drift's not exactly: rerun to check)
    need = max(10.0 ** math.floor(math.log10(rtol * limit / err)), MIN_RTOL)
    reach = max(c * need, PERIOD_ERROR_FLOOR) * period + err_drift * need / rtol
    cure = (f"--rtol {need:g} brings it below" if reach <= limit else
            f"no --rtol brings it below (the floor is {PERIOD_ERROR_FLOOR:g} of the period)")
    if crossing > err_int and crossing > err_drift:
        return err, (f"the period's error may reach {err:.1g} s ({err / period:.1g} relative), most of it "
                     f"({crossing:.1g} s) from locating the crossings between the samples: the motion has "
                     f"harmonics too fast for them even at {MAX_SAMPLES_PER_PERIOD} samples per linear period; "
                     f"above {what}; --method DOP853 locates them on its own steps")
    if err_drift > err_int:
        return err, (f"the period's integration error may reach {err:.1g} s ({err / period:.1g} relative), most of "
                     f"it from the energy drift: {drift:.1e} of the oscillation energy moves the amplitude, and "
                     f"with it the period (the run's is {period - linear_period:+.1e} s from the linear one), by up "
                     f"to {err_drift:.1g} s, beside {c:g} x rtol {rtol:g} for {method}; above {what}; {cure}")
    return err, (f"the period's integration error may reach {err:.1g} s ({err / period:.1g} relative: {c:g} x rtol "
                 f"{rtol:g} for {method}), above {what}; {cure}")


CROSSING_SHARE = 0.1
"""Share of the error model's bound (:func:`period_accuracy`) the crossings'
interpolation between samples may reach (:func:`crossing_period_error`) before
the ``auto`` engine's run is taken again with :data:`SAMPLES_STEP` times the
samples per period."""

SAMPLES_STEP = 4
"""Factor on the samples per period of a run taken again for its crossings."""

MAX_SAMPLES_PER_PERIOD = 1024
"""Most samples per linear period a run is taken again with (the degree-7
interpolation's error falls as the 8th power of the spacing: from 64 to 1024
by 16^8 ~ 4e9)."""


CROSSING_ROWS = 12
"""Rows either side of a crossing's sample that :func:`crossing_period_error`
may read: it reads the crossing's pair one sample either way and the three
degree-7 stencils about it, at most 6 rows either side in the record's
middle and 8 at its ends, where the stencils are shifted inside the record
(tests/test_simulate_summary.py: 7 rows change the error there)."""


def crossing_rows(t: np.ndarray, crossings) -> list:
    """The slices of the samples ``t`` (s) that :func:`crossing_period_error`
    reads of the timed coordinate for these ``crossings`` (s): the first and
    the last crossing's, :data:`CROSSING_ROWS` either side (none where it
    reads none).  A caller that has not computed the coordinate at every
    sample computes it on these rows only (NaN elsewhere) and gets the same
    error, bit for bit (tests/test_simulate_summary.py)."""
    tc = np.asarray(crossings, float)
    t = np.asarray(t, float)
    if len(tc) < 2 or len(t) < 9:
        return []
    dt = float(t[1] - t[0])
    K = len(t)
    out = []
    for tx in (tc[0], tc[-1]):
        k0 = int(np.floor((tx - t[0]) / dt))
        out.append(slice(min(max(k0 - CROSSING_ROWS, 0), K), min(max(k0 + CROSSING_ROWS + 1, 0), K)))
    return out


def crossing_period_error(t: np.ndarray, c: np.ndarray, crossings) -> float:
    """The part of a mean period's error (s) that locating its crossings
    between uniform samples makes: the mean period is (last - first crossing)
    over the cycles between them, so its error is at most the two crossings'
    interpolation errors (:func:`~bifilar.integrators.crossing_interpolation_error`,
    on the samples ``t`` (s) of the timed coordinate ``c``) over the number of
    cycles.  0 with fewer than two crossings; NaN where either could not be
    estimated (too few samples, a crossing the samples do not show)."""
    from .. import integrators as itg

    tc = np.asarray(crossings, float)
    t = np.asarray(t, float)
    if len(tc) < 2:
        return 0.0
    if len(t) < 9:
        return float("nan")
    dt = float(t[1] - t[0])
    ks = []
    for tx in (tc[0], tc[-1]):
        k0 = int(np.floor((tx - t[0]) / dt))
        near = [k for k in (k0, k0 - 1, k0 + 1) if 0 <= k < len(c) - 1 and c[k] < 0 <= c[k + 1]]
        if not near:
            return float("nan")
        ks.append(near[0])
    e = itg.crossing_interpolation_error(c, np.array(ks), dt)
    return float(np.sum(e) / (len(tc) - 1))


def drift_period_error(period: float | None, linear_period: float | None, drift: float) -> float:
    """The part of a run's period error (s) that its energy drift makes:
    ``drift`` (max |E - E0| over the oscillation energy, which is ~A^2)
    times |``period`` - ``linear_period``| (s).  The period's distance from the
    linear one is the amplitude's effect on it, ~A^2 to leading order, so a
    relative change ``drift`` of the oscillation energy moves it by at most
    ``drift`` times itself: an integration that loses or gains energy times a
    motion of another amplitude than the one released.  Measured (docs/design.md, "The period's
    error against what the user needs"): at 0.3 rad over 100 periods the true
    error was 0.36-0.55 of this, and it exceeded the integrator's part alone.
    0 where either is undefined (no period, nan drift)."""
    if period is None or linear_period is None or not np.isfinite(drift):
        return 0.0
    return abs(float(period) - float(linear_period)) * float(drift)


IRREGULAR_SPREAD = 1e-6
"""Spread of a run's single-cycle periods (``period_std`` over the period) above
which :func:`simulate` checks its period's error with a second run
(:func:`check_period`) instead of trusting the error model, which was measured
on regular motions only.  Every mode of the shipped configs at 0.05 and 0.3 rad
(translations: times the longest wire) over 10 and 40 periods (docs/design.md,
"A motion that is not regular"): clean modes spread by at most 2e-8 of the
period, and the default runs (0.05, 10 periods) of all but the modes that beat
with another stay below 1e-6; beating (regular) spreads 1e-6 to 3e-3, the
irregular plate's swing-y at 1.5 m 7e-3.  The spread alone does not tell
beating from irregular; the check run does."""


CHECK_RTOL_RATIO = 100.0
"""The check run's tolerance is the run's rtol over this (its error model's
bound is then a hundredth of the run's, so the difference is the run's error
where the motion is regular), or, where that is below :data:`MIN_RTOL`, the
other engine (DOP853 against LSODA) at the same rtol."""


IRREGULAR_FACTOR = 2.0
"""The check run's difference over the run's error bound above which the
motion is reported as not regular.  On the survey of :data:`IRREGULAR_SPREAD`
the regular (beating) runs' differences were at most 0.31 of the bound, the
plate's swing-y at 1.5 m over 40 periods 75x (over 50: 2000x)."""


def needs_check(r) -> bool:
    """Whether run ``r`` (a :class:`SimulationResult`) spread its single-cycle
    periods by more than :data:`IRREGULAR_SPREAD` of its period: a motion that
    is not clean, whose period's error the error model may not bound."""
    return (r.period is not None and r.period_std is not None and np.isfinite(r.period_std)
            and r.period_std > IRREGULAR_SPREAD * r.period)


FAR_FROM_LINEAR = 0.2
"""Relative distance of a run's period from the linear one above which
:func:`simulate` checks its period's error with a second run (DOP853 at
rtol / :data:`CHECK_RTOL_RATIO`) whatever its single-cycle spread.  The
error model's drift term (:func:`drift_period_error`) takes the period's
distance from the linear one to grow as the oscillation energy; near an
unstable equilibrium (a torsion towards the wires' turn at pi) it grows as
``-ln(E_sep - E)``, far faster: audit18's trifilar plate at 3.0 / 3.1 rad
(T / T_lin 2.5 / 3.2) ran 12.5 / 101 x past its stated bound under LSODA at
rtol 1e-10, with a spread too small for :func:`needs_check` (docs/design.md,
"Estimation audit, session 18", H2).  Up to 2.0 rad (T / T_lin 1.33) the
bound held with 3-30x to spare; 0.2 puts the check well inside that."""


def far_from_linear(r) -> bool:
    """Whether run ``r``'s period lies more than :data:`FAR_FROM_LINEAR` of
    the linear period from it (both s; False where either is undefined)."""
    if r.period is None or r.linear_period is None or not r.linear_period:
        return False
    return bool(abs(float(r.period) - float(r.linear_period)) > FAR_FROM_LINEAR * float(r.linear_period))


def needs_period_check(r) -> bool:
    """Whether :func:`simulate` checks run ``r``'s period error with a second
    run: its single-cycle periods spread (:func:`needs_check`) or its period
    lies far from the linear one (:func:`far_from_linear`)."""
    return needs_check(r) or far_from_linear(r)


def not_regular(period_check: dict | None, period: float, timing: float | None = None) -> bool:
    """Whether a check run (``period_check`` as :func:`check_period` writes
    it: ``difference`` and ``model_bound``, s; None: no check ran) shows a
    motion that is not regular: a difference above :data:`IRREGULAR_FACTOR` x
    the model's bound, or above the bound and above
    :func:`period_warn_threshold` of ``period`` and ``timing`` (s)."""
    if period_check is None:
        return False
    diff, model = period_check["difference"], period_check["model_bound"]
    return bool(diff > IRREGULAR_FACTOR * model or (diff > model and diff > period_warn_threshold(period, timing)))


def lost_start_span(r) -> float:
    """Span (s) of run ``r``'s single-cycle periods (largest minus smallest
    interval between successive crossings; 0 under two cycles): the most its
    mean period can move where the motion loses its start, the mean of
    cycles that each lie within that span (a run from another start on the
    same energy shell spans the same periods)."""
    per = np.diff(np.asarray(r.crossings, float))
    return float(per.max() - per.min()) if per.size > 1 else 0.0


def check_matters(r, timing: float) -> bool:
    """Whether run ``r`` needs the check of :func:`check_period` for a
    caller that holds its period against ``timing`` (s, the standard
    uncertainty of the measured period it is compared with): its
    single-cycle periods spread (:func:`needs_check`) and their span
    (:func:`lost_start_span`, the most a lost start could move the mean)
    exceeds :data:`TIMING_SHARE` of ``timing``.  Below that, even a motion
    that is not regular moves the period by under a tenth of its std:
    nothing to check (a beating run of the example measurements, span
    4e-5 s against 5e-4 s, pays nothing)."""
    return needs_check(r) and lost_start_span(r) > TIMING_SHARE * float(timing)


def check_period(r, again, method: str, atol, timing: float | None = None) -> None:
    """Check the period's error bound of run ``r`` (:class:`SimulationResult`,
    updated in place) with a second run from the same start:
    ``again(method, rtol, atol) -> SimulationResult`` at rtol /
    :data:`CHECK_RTOL_RATIO` with ``method`` (the run's, as asked: ``auto``
    too) and ``atol`` (None: scaled, else over the same ratio), or with the
    other engine at the same rtol where that would be below :data:`MIN_RTOL`.

    ``r.period_error`` becomes max(the model's bound, the two periods'
    difference, s) and ``r.period_check`` says what was run.  A difference above
    :data:`IRREGULAR_FACTOR` x the bound (or above the bound and above
    :func:`period_warn_threshold` of ``timing``, s) means the motion is not
    regular: its mean period depends on the start and on the run length (energy
    passing between modes), so no tolerance-based bound holds; a warning says
    so.  For such a motion the difference is an estimate, not a bound: other
    starts as close move the mean period by as much or more.  A check run that
    fails leaves the model's bound and says it could not be checked."""
    model = float(r.period_error)
    if not np.isfinite(model):  # not established (period_accuracy said why): no bound to check
        return
    tight = r.rtol / CHECK_RTOL_RATIO
    if not needs_check(r) and far_from_linear(r):  # a regular motion whose error model may fail (FAR_FROM_LINEAR)
        _check_far_from_linear(r, again, model, max(tight, MIN_RTOL), atol)
        return
    if tight >= MIN_RTOL:
        how, args = f"rtol {tight:g}", (method, tight, None if atol is None else np.asarray(atol) / CHECK_RTOL_RATIO)
    else:
        other = "LSODA" if r.method == "DOP853" else "DOP853"
        how, args = f"{other} at the same rtol", (other, r.rtol, atol)
    spread = (f"its single-cycle periods spread by {r.period_std:.1g} s ({r.period_std / r.period:.1g} of the "
              "period)")
    try:
        chk = again(*args)
    except (InputError, IntegrationError) as exc:
        r.warnings.append(f"the motion may not be regular ({spread}) and the run checking its period's error "
                          f"({how}) failed ({exc}): the period's error bound is the error model's and may not hold")
        return
    if chk.period is None:
        r.warnings.append(f"the motion may not be regular ({spread}) and the run checking its period's error "
                          f"({how}) timed no period: the period's error bound is the error model's and may not hold")
        return
    diff = abs(float(r.period) - float(chk.period))
    r.period_check = {"method": chk.method, "rtol": float(chk.rtol), "period": float(chk.period),
                      "difference": diff, "model_bound": model}
    r.period_error = max(model, diff)
    if not_regular(r.period_check, r.period, timing):
        r.warnings.append(f"the motion is not regular: the mean period depends on the start and on the run length "
                          f"({spread}); a second run from the same start at {how} differs by {diff:.1g} s, "
                          f"{diff / model:.3g} x the integration error bound of {model:.1g} s, so the period's "
                          "error is at least that (period_error), and other starts as close can move it "
                          "further; time fewer periods or release at a smaller amplitude")


def _check_far_from_linear(r, again, model: float, rtol: float, atol) -> None:
    """:func:`check_period` for a run whose single-cycle periods agree but
    whose period lies far from the linear one (:func:`far_from_linear`): a
    second run from the same start with DOP853 at ``rtol`` (its error model
    held to 1.2x at audit18's 3.1 rad, where LSODA's missed 100x).  1.1 x its
    difference plus twice the check run's own bound joins ``r.period_error``
    (s), and where that exceeds the model's bound one warning says so; no
    verdict on the motion's regularity (its cycles agree)."""
    try:
        chk = again("DOP853", rtol, None if atol is None else np.asarray(atol) / CHECK_RTOL_RATIO)
    except (InputError, IntegrationError) as exc:
        r.warnings.append(f"the period lies {abs(r.period / r.linear_period - 1):.0%} from the linear one, where "
                          f"the error model may not hold, and the run checking it (DOP853 at rtol {rtol:g}) failed "
                          f"({exc}): the period's error bound is the error model's and may not hold")
        return
    if chk.period is None:
        r.warnings.append(f"the period lies {abs(r.period / r.linear_period - 1):.0%} from the linear one and the "
                          f"run checking its error (DOP853 at rtol {rtol:g}) timed no period: the period's error "
                          "bound is the error model's and may not hold")
        return
    diff = abs(float(r.period) - float(chk.period))
    own = float(chk.period_error) if chk.period_error is not None and np.isfinite(chk.period_error) else 0.0
    r.period_check = {"method": chk.method, "rtol": float(chk.rtol), "period": float(chk.period),
                      "difference": diff, "model_bound": model}
    # the check's own error: its bound twice (DOP853's model held to 1.2x there), and a tenth of the difference
    # (a run at a hundredth of the rtol errs by far less than a tenth of the run's error; at 3.1 rad the check
    # ran 2.2e-9 s off, 3e-4 of the 7.0e-6 s difference, past twice its own bound of 7e-10)
    bound = 1.1 * diff + 2.0 * own
    if bound > model:
        r.period_error = bound
        r.warnings.append(f"the period lies {abs(r.period / r.linear_period - 1):.0%} from the linear one, beyond "
                          f"what the integration error model was measured on: a second run from the same start "
                          f"(DOP853 at rtol {rtol:g}) differs by {diff:.1g} s, {diff / model:.3g} x its bound of "
                          f"{model:.1g} s, so the period's error is taken as {bound:.1g} s (period_error); a "
                          "tighter --rtol or --method DOP853 runs closer")
