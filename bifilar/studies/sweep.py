"""Compare suspension configurations: the sweep engine behind ``bifilar sweep``.

Every point of a sweep is a full scene: the base config is copied, edited by
dotted path or shorthand (:mod:`bifilar.studies.shorthands`) and validated by
:func:`bifilar.config.scene_from_dict` like any config.  An invalid point
(bad config, slack wire, unstable rest, solver failure) is kept with its
one-line reason and skipped, never a crash.

Figures per valid point (SI units; world frame z up; inertia components in
the body axes of the point's scene):

* ``periods``: linear period of every mode, s (``None`` for a neutral mode);
* per inertia component (default ``Ixx Iyy Izz``), estimated from its
  best-suited mode (:func:`~bifilar.estimation.sensitivity.best_mode_for`):
  the relative sensitivity of the estimate to the period
  ``(dI/I)/(dT/T)`` and to every measured input ``d ln I / d x`` (1/unit of
  x), the predicted standard uncertainty ``sigma`` (kg m^2) and
  ``rel_sigma`` for the stated measurement errors
  (:func:`~bifilar.studies.point.predicted_budget`, for the point's
  uncertainties: the settings', or a swept ``uncertainty.KEY``; the
  period timed at the point's amplitude and that amplitude stated to
  ``invert`` with its default 10 %, :func:`~bifilar.studies.point_amplitude.stated_amplitude_budget`,
  the small-amplitude figure in ``amplitude_budget``), the
  variance shares by kind, the modes its period depends on
  (``from_modes``: ``|d ln T / d ln I|`` per mode), the separation of its
  mode (relative distance to the nearest other period), and the relative bias of simple estimators against the full
  model at the prescribed amplitude: the small-angle formula (thesis
  5.2.18), the thesis's linearisation (§7.1), and the exact linear model
  (the amplitude error of linear theory);
* ``separation``: the mode-separation guard, the smallest relative gap
  between any timed mode and any other mode (close periods beat and spoil
  the timing);
* ``rig``: the rig to build: anchors (world), attachments (body frame),
  lengths, each wire's angle from the vertical at rest (deg);
* ``tension``: rest tension per wire, and peak and minimum tension per wire
  during the prescribed excitation of each chosen mode (nonlinear model,
  the chosen modes of a point in one call of the batched engine
  :func:`~bifilar.analysis.batch.simulate_batch`, a few periods at
  rtol 1e-8), with slack detection; ``depth``: depth of the lowest body
  point below the ceiling at rest and the largest during the excitation, m.

The biases: each estimator is fed the period the full model shows at the
amplitude (or, without the nonlinear runs, the linear period) and its
estimate compared with the config's value.  The small-angle formula and the
thesis's linearisation come from :mod:`bifilar.estimation.invert` (the
small-angle formula: two wires D = the attachment spacing, h = the mean
vertical drop of the wires at rest; n >= 3 wires its multifilar analogue;
torsion about the vertical only); the exact linear model is inverted here
(:func:`linear_estimate`).

A component that no mode's period depends on (``|d ln T / d ln I| < 1e-6``
for every mode, e.g. the pitch inertia of a body on two vertical wires: its
in-plane swing is a pure translation) is reported with ``identifiable:
false`` and an infinite (``null``) uncertainty; the ranking then uses the
components that are measurable, and :mod:`bifilar.studies.remedy` names
the cheapest change that makes the others measurable.

Each point's figures depend only on the base config, the point's parameters
and the evaluation settings (every rest pose is found afresh by the
deterministic search rather than continued from a neighbour, which would
make a point depend on the order of evaluation: it costs ~2 ms of the
~130 ms a point takes), so results are identical for any ``workers`` count
and for a resumed sweep.

The sweep is split by concern: :mod:`bifilar.studies.settings` (settings,
constraints, grid), :mod:`bifilar.studies.point` (one point's figures),
this module (many points: workers, journal, resume),
:mod:`bifilar.studies.ranking` (feasibility, ranking), :mod:`bifilar.studies.recommend` (recommendation) and
:mod:`bifilar.studies.sweep_output` (CSV and figures).  Their public names
are re-exported here.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from ..analysis.shared_batch import run_together
from ..errors import InputError
from .point import (IDENTIFIABLE_MIN, TURN_MAX, _Ladder, _nonlinear_runs, _one_line, _plain,  # noqa: F401
                    evaluate_point, evaluate_points, linear_estimate, point_sensitivity, predicted_budget, rig_of,
                    timed_separation)
from .ranking import (CONSTRAINT_FLAGS, binding_constraint, measurable_components, objective,  # noqa: F401
                      pareto_front, point_separation, violations, why_invalid)
from .recommend import assess, explain  # noqa: F401
from .settings import (_IDX, DEFAULT_MIN_SEPARATION, PLAN_KEYS, PRINCIPAL, Constraints,  # noqa: F401
                       SweepSettings, build_grid,
                       check_component, plan_block, resolve_constraints, resolve_settings, resolve_target,
                       resolve_uncertainty)
from .sweep_output import csv_rows, write_points_csv  # noqa: F401

JOURNAL_VERSION = 8  # 2: points carry rig, separation, uncertainty, from_modes; 3: physical limits, no sigma at a knife edge;
# 4: the sigma budgets the stated amplitude (amplitude_budget); 5: the amplitude law and the factor's derivative (session 8);
# 6: points carry their runs' health (runs: period_error, energy_drift_resolution, ...); 7: the inputs' factor terms
# (dr/dx) where they can matter, input_factor_bound (session 11); 8: the depth counts a shapeless body's CoM, points
# carry the dependent wires' tension range (tension.range, range_peak) and tension_range_caution (session 12)


# --------------------------------------------------------------------------
# many points: workers, journal, resume


class SweepInterrupted(KeyboardInterrupt):
    """The sweep stopped early (Ctrl-C or a point budget); finished points are
    in the journal.  ``done``: number of points finished."""

    def __init__(self, done: int, total: int):
        super().__init__(f"sweep interrupted after {done} of {total} points")
        self.done = done
        self.total = total


def point_warnings(base_cfg: dict, source: str, params: dict) -> list[str]:
    """The config plausibility warnings (:func:`bifilar.config.plausibility_warnings`:
    a rig in cm beside a body in m, kilometre wires, ...) of the point
    ``params`` of ``base_cfg``, for a recommended or planned point: the
    studies build their scenes with ``warn=False``, so a point the base
    config's checks never saw is checked here.  Those the base config
    gives word for word are left out (already said when it was loaded).
    Then the point's rig at rest (:func:`bifilar.analysis.clearance.clearance_warnings`:
    the body through the ceiling, crossing wires), which no command has
    checked for a point the config did not describe."""
    from ..analysis.clearance import clearance_warnings
    from ..config import plausibility_warnings, scene_from_dict
    from .shorthands import apply_params

    base = set(plausibility_warnings(scene_from_dict(base_cfg, source, warn=False)))
    cfg, _ = apply_params(base_cfg, params, source)
    scene = scene_from_dict(cfg, source, warn=False)
    return [w for w in plausibility_warnings(scene) if w not in base] + clearance_warnings(scene)


def prior_cautions(base_cfg: dict, source: str, point: dict) -> list[str]:
    """One line per component of a recommended or planned point whose
    estimate a :data:`~bifilar.estimation.prior_inertia.PLAUSIBLE_PRIOR_ERROR`
    error of the other components' priors would move by more than
    :data:`~bifilar.estimation.prior_inertia.WARN_SHIFT` of its predicted
    sigma (:func:`~bifilar.estimation.prior_inertia.planned_prior_shift`;
    a rig that couples them into the mode: tilted, off-centre), as
    ``invert`` warns; the predicted sigma takes them as exact."""
    from ..analysis.equilibrium import rest_pose
    from ..config import scene_from_dict
    from ..errors import BifilarError
    from ..estimation.prior_inertia import PLAUSIBLE_PRIOR_ERROR, WARN_SHIFT, planned_prior_shift
    from .shorthands import apply_params

    todo = {c: e for c, e in point.get("components", {}).items()
            if e.get("mode") and e.get("sigma") is not None and math.isfinite(e["sigma"]) and e["sigma"] > 0}
    if not todo:
        return []
    cfg, _ = apply_params(base_cfg, point["params"], source)
    scene = scene_from_dict(cfg, source, warn=False)
    try:
        rest = rest_pose(scene)
    except BifilarError:
        return []
    out = []
    for c, e in todo.items():
        try:
            shift, movers = planned_prior_shift(scene, rest, c, e["mode"])
        except (BifilarError, StopIteration, np.linalg.LinAlgError):
            continue
        if shift > WARN_SHIFT * e["sigma"]:
            it = "it" if len(movers) == 1 else "them"
            out.append(f"{c} from its {e['mode']} depends on the config's {', '.join(movers)} (not solved for), which "
                       f"invert takes as exact, as the predicted sigma does: a {100 * PLAUSIBLE_PRIOR_ERROR:g} % error "
                       f"in {it} would move "
                       f"{c} by {shift / e['sigma']:.2g} of its sigma; state how well they are known (invert's "
                       "--uncertainty inertia=REL) or solve for them (--component)")
    return out


def stretching_summary(points: list[dict]) -> str | None:
    """One warning for the points of a sweep or plan whose rig's dependent
    wires cannot follow a mode they run (``stretching_modes``, set by
    :func:`~bifilar.studies.point.evaluate_point`; each point's own warning
    says why), or None: their tensions, slack and amplitude terms come
    from rigid-wire runs that are not physical at any amplitude."""
    hit = [p for p in points if p.get("stretching_modes")]
    if not hit:
        return None
    labels = sorted({lb for p in hit for lb in p["stretching_modes"]})
    first = ", ".join(f"{k}={v:g}" for k, v in hit[0]["params"].items())
    return (f"at {len(hit)} of {len(points)} points ({first}{', ...' if len(hit) > 1 else ''}) the rig's dependent "
            f"wires cannot follow mode{'s' if len(labels) > 1 else ''} {', '.join(repr(lb) for lb in labels)} "
            "rigidly (each point's warnings say why): the nonlinear runs' tensions, slack wires and amplitude "
            "terms there are not physical at any amplitude; a real rig's wires stretch and keep the linear "
            "periods: leave the runs out (--no-tensions) and time at a small amplitude (invert --amplitude 0)")


def point_key(params: dict) -> str:
    """Canonical text of a point's parameters (exact floats)."""
    return json.dumps({k: float(v) for k, v in params.items()}, sort_keys=True)


def fingerprint(base_cfg: dict, settings: SweepSettings) -> str:
    """Hash of everything that determines a point's figures besides its parameters."""
    st = {k: v for k, v in settings.describe().items() if k != "rig"}  # (only the hangings plan depends on it)
    doc = json.dumps({"config": base_cfg, "settings": st, "version": JOURNAL_VERSION},
                     sort_keys=True, default=str)
    return hashlib.sha256(doc.encode()).hexdigest()[:16]


def journal_path(out: str | os.PathLike) -> Path:
    return Path(str(out) + ".partial.jsonl")


def read_journal(path: Path, fp: str) -> dict[str, dict]:
    """Finished points of an interrupted sweep, by :func:`point_key`.

    A torn last line (interrupted while writing) is cut off the file.  A
    journal written for another config or other settings, or holding lines
    that are not sweep records, is refused (:class:`~bifilar.errors.InputError`
    naming ``--resume``).
    """
    from ..output import read_journal as read_jsonl

    def check_header(head) -> None:
        if not isinstance(head, dict) or head.get("journal") != "bifilar-sweep":
            raise InputError("--resume", f"{path} is not a sweep journal")
        if head.get("fingerprint") != fp:
            raise InputError("--resume", f"{path} was written for another config or other settings "
                                         "(components, amplitude, uncertainties, tensions) or by another version of bifilar, "
                                         "whose points are not this one's; rerun with --force to start over")

    def is_record(rec) -> bool:
        return isinstance(rec, dict) and isinstance(rec.get("key"), str) and isinstance(rec.get("point"), dict)

    _, records = read_jsonl(path, check_header, is_record)
    return {rec["key"]: rec["point"] for rec in records}


def _journal_writer(path: Path | None, fp: str, append: bool):
    from ..output import JournalWriter

    return JournalWriter(path, {"journal": "bifilar-sweep", "version": JOURNAL_VERSION, "fingerprint": fp},
                         append=append)


def effective_workers(workers: int, points: int) -> int:
    """Processes a sweep of ``points`` points actually starts for ``--workers
    workers``: never more than the points, nor than the CPUs (``os.cpu_count``)."""
    return max(1, min(int(workers), int(points), os.cpu_count() or 1))


def _ignore_sigint() -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and keeps finished points


def _evaluate_chunk(base_cfg: dict, source: str, grid: list[dict], settings: SweepSettings,
                    screen: bool = False, on_done: Callable[[int, dict], None] | None = None) -> list[dict]:
    """:func:`evaluate_point` of each point of ``grid`` (a chunk of a sweep,
    or a worker's task), several together in
    :func:`~bifilar.analysis.shared_batch.run_together` (their shared
    batches: the same figures as each alone; a screen, which has no sigma
    points, or a lone point: one at a time).  ``on_done(n, point)`` as each
    point ``grid[n]`` finishes."""
    if screen or len(grid) == 1:
        out = []
        for n, p in enumerate(grid):
            out.append(evaluate_point(base_cfg, source, p, settings, screen=screen))
            if on_done is not None:
                on_done(n, out[-1])
        return out
    return run_together([partial(evaluate_point, base_cfg, source, p, settings) for p in grid], on_done=on_done)


#: points of a one-process sweep evaluated together, their sigma points and start poses each in one batch
#: (:func:`~bifilar.analysis.shared_batch.run_together`): the batch's fixed cost a point is ~1/16 of
#: one point's, and the progress and journal lag a chunk by at most this many points
SHARED_CHUNK = 16


def run_sweep(base_cfg: dict, source: str, grid: list[dict], settings: SweepSettings, *, workers: int = 1,
              journal: Path | None = None, resume: bool = False, progress: Callable[[int, int], None] | None = None,
              stop_after: int | None = None, screen: bool = False) -> list[dict]:
    """Evaluate every point of ``grid`` (list of {param: value}); returns the
    point dicts in grid order.

    workers : processes (``concurrent.futures.ProcessPoolExecutor``) when > 1,
        each task a chunk of points evaluated together (at most
        :data:`SHARED_CHUNK`, two chunks a worker at least; a screen one point).
    journal : append each finished point to this JSON-lines file; with
        ``resume`` the points already in it are reused (same params -> same
        result) instead of recomputed.
    stop_after : stop (raising :class:`SweepInterrupted`) after this many
        newly computed points: a reproducible stand-in for Ctrl-C.
    screen : the cheap points of a planner's search (``evaluate_point(..., screen=True)``;
        not for a journal, whose points are full); in one process, their
        nonlinear runs in one batch (:func:`~bifilar.studies.point.evaluate_points`).
    With one worker, the points are evaluated in chunks of :data:`SHARED_CHUNK`
    whose sigma points and runs' start poses are each solved in one batch
    (:func:`~bifilar.analysis.shared_batch.run_together`: each point's
    figures the same bits as evaluated alone; progress and the journal move
    as each point of a chunk finishes, after the chunk's shared batches).
    Raises :class:`SweepInterrupted` on Ctrl-C too; finished points are in the journal.
    """
    if screen and journal is not None:
        raise ValueError("screen points are not journaled")
    fp = fingerprint(base_cfg, settings)
    done: dict[str, dict] = {}
    if resume and journal is not None and journal.exists():
        done = read_journal(journal, fp)
    keys = [point_key(p) for p in grid]
    results: list[dict | None] = [done.get(k) for k in keys]
    todo = [i for i, r in enumerate(results) if r is None]
    total = len(grid)
    finished = total - len(todo)
    jr = _journal_writer(journal, fp, append=resume)
    new = 0
    if progress:
        progress(finished, total)

    def record(i: int, point: dict) -> None:
        nonlocal finished, new
        results[i] = point
        jr.add({"key": keys[i], "point": point})
        finished += 1
        new += 1
        if progress:
            progress(finished, total)

    try:
        if screen and workers <= 1 and stop_after is None:
            # a planner's screens: the nonlinear runs of all points in one batch
            for i, point in zip(todo, evaluate_points(base_cfg, source, [grid[i] for i in todo], settings,
                                                      screen=True)):
                record(i, point)
        elif workers <= 1 or len(todo) <= 1:
            j = 0
            while j < len(todo):
                if stop_after is not None and new >= stop_after:
                    raise SweepInterrupted(finished, total)
                # (a screen has no sigma points: one at a time)
                size = 1 if screen else SHARED_CHUNK if stop_after is None else min(SHARED_CHUNK, stop_after - new)
                chunk = todo[j:j + size]
                j += len(chunk)
                # a chunk's points together, their sigma points' rest poses and modes, and their runs' start
                # poses, each in one batch: each point's figures the same bits as alone
                _evaluate_chunk(base_cfg, source, [grid[i] for i in chunk], settings, screen,
                                on_done=lambda n, point, chunk=chunk: record(chunk[n], point))
        else:
            from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

            nw = effective_workers(workers, len(todo))
            # a worker's points in chunks sharing their batches, as in one process; two chunks a worker at least,
            # so that the last ones balance (a screen: one point a task)
            size = 1 if screen else max(1, min(SHARED_CHUNK, len(todo) // (2 * nw)))
            ex = ProcessPoolExecutor(max_workers=nw, initializer=_ignore_sigint)
            try:
                pending = {ex.submit(_evaluate_chunk, base_cfg, source, [grid[i] for i in todo[j:j + size]], settings,
                                     screen): todo[j:j + size] for j in range(0, len(todo), size)}
                while pending:
                    ready, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for f in ready:
                        chunk = pending.pop(f)
                        for i, point in zip(chunk, f.result()):
                            if stop_after is not None and new >= stop_after:
                                raise SweepInterrupted(finished, total)
                            record(i, point)
            finally:
                ex.shutdown(wait=True, cancel_futures=True)
    except SweepInterrupted:
        raise
    except KeyboardInterrupt:
        raise SweepInterrupted(finished, total) from None
    finally:
        jr.close()
    return results  # type: ignore[return-value]
