"""The amplitude runs of the nonlinear inversion: the full model released
at a measurement's amplitude and simulated over its cycles, giving the
amplitude factor ``r = T_sim / T_lin`` of its mode
(:func:`amplitude_factor`, :func:`measured_factor`), with their guards: a
motion that is not regular (:func:`irregular_difference`) and a run whose
equations are too stiff to make (:data:`RUN_EVALUATIONS_PER_CYCLE`).
Moved out of :mod:`bifilar.estimation.solve` (which re-exports every name)
when it passed 800 lines; the laws and the fixed point stay there.
Units: periods s, amplitudes in the mode's dominant coordinate (rad or m),
inertia kg m^2."""

from __future__ import annotations

import copy
import functools
import io
import pickle
import types
from contextvars import ContextVar

import numpy as np

from ..analysis.run_accuracy import TIMING_SHARE
from ..errors import ConvergenceError, InputError
from .problem import HangingModel, Problem


#: budget of right-hand-side evaluations a simulated cycle of one amplitude
#: run (:func:`bifilar.analysis.simulate.simulate`'s ``max_evaluations``,
#: times the cycles, at least 10): the shipped configs' DOP853 runs take
#: 250-450 a cycle at rtol 1e-10 and 420-670 at the check's 1e-12 (plate,
#: Solar Boat, KTH trifilar, 6.4 cylinder), so 2e4 is 30x the costliest;
#: beyond it the body has a vanishing principal moment (the audit's plate at
#: the corner Ixx = 2.6e-8 of a barely determined fit: one 10-cycle run took
#: 18 s, the next over 2 min; docs/design.md "Estimation audit, session 13")
RUN_EVALUATIONS_PER_CYCLE = 2e4


def _stiff_message(scene, label: str) -> str:
    """The refusal of an amplitude run too stiff to make (a principal moment
    that vanishes against the others; units kg m^2)."""
    ev = np.linalg.eigvalsh(np.asarray(scene.inertia, float))
    return (f"the nonlinear model of mode '{label}' would run a body whose principal moments are "
            f"{', '.join(f'{v:.3g}' for v in ev)} kg m^2: a moment that vanishes against the others makes its "
            f"equations stiff beyond {RUN_EVALUATIONS_PER_CYCLE:.0e} evaluations a cycle, so the amplitude's effect "
            "cannot be simulated there; where the fit put it (the estimate at a corner of the physical set) the periods barely "
            "determine the components: add modes or hangings that time them, solve for fewer components, or "
            "give the amplitude as 0 to answer with the linear model")


#: the amplitude runs already made within the current :func:`per_call_runs` call
#: (pickled exact inputs -> (r, SimulationResult)); None outside one
_RUNS: ContextVar[dict | None] = ContextVar("bifilar_amplitude_runs", default=None)


def per_call_runs(f):
    """``f`` (``invert``) with an amplitude-run memo for the length of one call:
    :func:`amplitude_factor` with the same inputs, bit for bit (scene, rest
    pose, mode set, mode, amplitude, cycles, rtol, timing, read, second
    mode), is run once and its result handed out as a copy.  The budget, the
    fit check and the edge roots each ask for the unstated amplitude's law at
    the same estimate (test_invert_roots' thin plate 3 stds beyond its edge:
    14 runs of 4 distinct inputs), and the first fixed-point step may repeat
    the prior's run (docs/design.md "invfast, session 23").  The memo ends with the call
    (a nested call shares its caller's): nothing outlives it."""

    @functools.wraps(f)
    def g(*args, **kwargs):
        if _RUNS.get() is not None:
            return f(*args, **kwargs)
        token = _RUNS.set({})
        try:
            return f(*args, **kwargs)
        finally:
            _RUNS.reset(token)

    return g


def _remembered(key_parts: tuple, run):
    """``run()``'s result, made once per :func:`per_call_runs` call for the
    exact inputs ``key_parts`` (pickled, a function by its identity: equal
    bytes, equal inputs; inputs that cannot be pickled, or no call open: run
    every time).  Every caller,
    the first too, gets a deep copy of the stored result, so a caller that
    edits its result (a run's warnings) edits its own."""
    memo = _RUNS.get()
    if memo is None:
        return run()
    held: list = []
    buf = io.BytesIO()
    try:
        _KeyPickler(buf, held).dump(key_parts)
    except Exception:  # inputs pickle cannot write: no memo
        return run()
    key = buf.getvalue()
    if key not in memo:
        memo[key] = (run(), held)
    return copy.deepcopy(memo[key][0])


class _KeyPickler(pickle.Pickler):
    """Pickles a memo key; a function in it (a scene's ``support``, often a
    closure pickle cannot write) is written as its identity, and held in
    ``held`` (kept with the memo's entry, so no other object takes its id)."""

    def __init__(self, buf, held: list):
        super().__init__(buf, protocol=pickle.HIGHEST_PROTOCOL)
        self.held = held

    def persistent_id(self, obj):
        if isinstance(obj, (types.FunctionType, types.MethodType, functools.partial)):
            self.held.append(obj)
            return ("function", id(obj))
        return None


def amplitude_factor(hm: HangingModel, values: dict, mode_index: int, amplitude: float, cycles: float,
                     rtol: float = 1e-10, timing: float | None = None,
                     fundamental: bool = False, second: tuple | None = None):
    """r = T_sim / T_lin of base mode ``mode_index`` at ``values``, simulated
    from rest displaced by ``amplitude`` x the mode shape for ``cycles``
    linear periods.  Returns (r, SimulationResult).

    ``timing``: the standard uncertainty (s) of the measured period the
    factor serves.  Where given, a run whose single-cycle periods spread by
    enough to matter against it (:func:`~bifilar.analysis.run_accuracy.check_matters`:
    their span over a tenth of ``timing``) is run again from the same start
    at rtol / 100 (:func:`~bifilar.analysis.run_accuracy.check_period`; the
    result's ``period_check`` says what it found).  A beating run whose
    span is below that pays nothing (the example measurements: no second
    run; checking every beating run cost them 19 % more CPU for nothing).
    None: the period alone (the law runs of an unstated amplitude).

    ``fundamental`` (a fitted record's period, :attr:`Measurement.fundamental`):
    ``T_sim`` is the period of the mode's fundamental and ``amplitude`` the
    fundamental's amplitude, as the record's fit reports them
    (:func:`~bifilar.analysis.fundamental.mode_fundamental`), not the mean
    period between the run's first and last crossings at a release of
    ``amplitude``: on the damped trifilar the other modes the release
    excites put that one 3.6e-6 s (one std of the record) below the
    fundamental's, and the release's fundamental is 1.0003 times it
    (+8.6e-7 s); Izz's z had mean +0.59 over 12 noise draws, the record's
    own -0.13 (docs/invert.md, "Signal audit, session 10").  The run is
    released at ``amplitude`` and ``r`` carried from its fundamental's
    amplitude ``a`` to ``amplitude`` by the quadratic rule ``dr/dA = 2 (r -
    1) / a`` (the step is ~3e-4 of the amplitude: a quartic law's slope,
    up to 10 % off that rule, moves ``r`` by ~1e-8 of itself).

    ``second``: (base mode index, amplitude) of a second mode the release
    started (a recording's, :class:`~bifilar.estimation.signal_swing.Secondary`):
    the run starts with it moving too
    (:func:`~bifilar.analysis.simulate.two_mode_state`), as the record's body did."""
    scene = hm.scene(values)
    rest, ms, match = hm.locate(scene)
    k = int(match[mode_index])
    other = (int(match[second[0]]), second[1]) if second is not None and second[1] else None
    return _remembered((scene, rest, ms, k, amplitude, cycles, rtol, timing, fundamental, other),
                       lambda: _factor_run(scene, rest, ms, k, amplitude, cycles, rtol, timing, fundamental, other))


def _factor_run(scene, rest, ms, k: int, amplitude: float, cycles: float, rtol: float, timing: float | None,
                fundamental: bool, other: tuple | None):
    """:func:`amplitude_factor`'s run of mode ``k`` of the mode set ``ms``
    about ``rest`` (``scene``'s, as the hanging model located them), with
    ``other`` (index into ``ms``, amplitude) the second mode started (None:
    none); the other arguments as there."""
    from ..analysis.fundamental import mode_fundamental
    from ..analysis.run_accuracy import check_matters, check_period
    from ..analysis.simulate import simulate, two_mode_state

    y0 = t_end = None
    if other is not None:
        y0 = two_mode_state(scene, rest, ms.modes[k], amplitude, ms.modes[other[0]], other[1])
        t_end = cycles * ms.modes[k].period

    def run(method: str = "DOP853", rtol: float = rtol, atol=None):
        return simulate(scene, k + 1, amplitude, cycles, rest=rest, modes=ms, method=method, rtol=rtol, atol=atol,
                        check=False, y0=y0, t_end=t_end, bound=True,
                        max_evaluations=RUN_EVALUATIONS_PER_CYCLE * max(cycles, 10.0))

    try:
        sim = run()
    except InputError as e:
        if e.field != "--periods" or "stiff body" not in str(e):
            raise
        raise InputError("--solve-for", _stiff_message(scene, ms.modes[k].label)) from None
    if sim.period is None:
        raise ConvergenceError(f"the simulated {ms.modes[k].label} motion showed fewer than two crossings")
    if timing is not None and check_matters(sim, timing):
        check_period(sim, run, sim.method, None, timing)
        # invert says it once per measurement (irregular_difference), in its own terms
        sim.warnings = [w for w in sim.warnings if not w.startswith("the motion is not regular")]
    T_lin = ms.modes[k].period
    if not fundamental:
        return sim.period / T_lin, sim
    T_f, a_f = mode_fundamental(sim.t, sim.y, rest, ms, k, sim.period)
    r = T_f / T_lin
    return r + 2.0 * (r - 1.0) / a_f * (abs(amplitude) - a_f), sim


#: an amplitude run whose motion is not regular is refused where its check
#: run's difference exceeds this share of the measured period's std (below
#: it the difference joins the budget as ``integration[mode]``): the share
#: below which simulate's period error need not warn either
IRREGULAR_REFUSE_SHARE = TIMING_SHARE


def measurement_run(pb: Problem, k: int, p, rtol: float, amplitude: float | None = None, timing: float | None = None,
                    second: tuple | None | str = "recorded"):
    """(r, SimulationResult): :func:`amplitude_factor` of measurement ``k``'s
    mode at the unknowns ``p``, released at the measured amplitude (or
    ``amplitude``) over the measured cycles, read as the measurement is
    (its fundamental for a recording), with the second mode its release
    started (``m.secondary``; ``second="recorded"``), another (``second`` =
    (base mode index, amplitude)) or none (``second=None``); ``timing`` (s)
    as :func:`amplitude_factor` takes it (None: no check run).  The one place a measurement becomes a run:
    :func:`measured_factor`, :func:`_unchecked_factor` and the hidden modes'
    runs (:func:`bifilar.estimation.solve._hidden_shifts`) go through it."""
    m = pb.measurements[k]
    if isinstance(second, str):
        sec = getattr(m, "secondary", None)
        second = None if sec is None else (sec.index, sec.amplitude)
    return amplitude_factor(pb.models[m.hanging], pb.values(p), pb.mode_index[k],
                            m.amplitude if amplitude is None else amplitude, m.cycles, rtol, timing=timing,
                            fundamental=m.fundamental, second=second)


def measured_factor(pb: Problem, k: int, p, rtol: float = 1e-10, amplitude: float | None = None):
    """(r, SimulationResult, d) of measurement ``k``'s mode at the unknowns
    ``p``: :func:`amplitude_factor` at the measured amplitude (or
    ``amplitude``) over the measured cycles, checked against the period's
    std, and ``d`` (s) the check run's difference where the motion is not
    regular (:func:`irregular_difference`; 0 otherwise)."""
    r, sim = measurement_run(pb, k, p, rtol, amplitude, timing=pb.measurements[k].std)
    return r, sim, irregular_difference(pb, k, p, sim)


def _unchecked_factor(pb: Problem, k: int, p, rtol: float) -> float:
    """Measurement ``k``'s amplitude factor at the unknowns ``p`` at
    ``rtol``, as :func:`measured_factor` simulates it but without its check
    run (a tighter rerun of runs :func:`measured_factor` has checked:
    :func:`factor_step_rtol`)."""
    return measurement_run(pb, k, p, rtol)[0]


def irregular_difference(pb: Problem, k: int, p, sim) -> float:
    """The difference (s) between measurement ``k``'s amplitude run ``sim``
    (at the unknowns ``p``) and its check run where the check shows a motion
    that is not regular (:func:`~bifilar.analysis.run_accuracy.not_regular`,
    against the measured period's std); 0 for a regular or unchecked run.

    Raises :class:`InputError` on the measurement's field where that
    difference exceeds :data:`IRREGULAR_REFUSE_SHARE` of the period's std:
    the simulated mean period then depends on the integrator's rounding at a
    level the measurement resolves, the difference is only an estimate of
    that dependence (other starts as close move it further:
    docs/design.md, "A motion that is not regular"), and the amplitude law's
    slope and the factor's derivative in the unknowns are differences of
    the same irregular function, so neither the estimate nor its std can be
    given."""
    from ..analysis.run_accuracy import not_regular

    m = pb.measurements[k]
    if not not_regular(sim.period_check, sim.period, m.std):
        return 0.0
    d = float(sim.period_check["difference"])
    if d > IRREGULAR_REFUSE_SHARE * m.std:
        at = ", ".join(f"{n} = {v:.6g}" for n, v in zip(pb.unknowns, np.asarray(p, float)))
        raise InputError(m.field, (
            f"mode '{m.label}' released at {sim.amplitude:g} and simulated over {m.cycles:g} cycles ({at}) is not a "
            f"regular motion: its single-cycle periods spread by {sim.period_std:.1g} s and a second run from the "
            f"same start at rtol {sim.period_check['rtol']:g} differs by {d:.1g} s, more than "
            f"{IRREGULAR_REFUSE_SHARE:g} of the period's std {m.std:.1g} s, so the nonlinear model's period (and the "
            "estimate) depends on the integrator's rounding and cannot be given to the measurement's accuracy; "
            "time fewer cycles (--cycles with --period) or release at a smaller amplitude"))
    return d
