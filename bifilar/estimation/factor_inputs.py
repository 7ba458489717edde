"""The amplitude factor's dependence on the measured inputs: ``dr/dx``
of a stated amplitude's law for every budgeted input (wire lengths,
anchors, attachments, the CoM, the mass, gravity), by one forward-difference
run per input or, where one holds, an exact route without a run (gravity
only scales time; moving every anchor moves the whole motion; a CoM shift
moves every attachment; ``r`` depends on ``m`` and ``I`` only through
``I/m`` and is unchanged when every length scales by ``s`` and ``I`` by
``s^2``).  Used by :func:`~bifilar.estimation.budget._budget` (the
inputs' terms with the full gain) and, through the law's ``dr_dx``, by the
Monte Carlo (:class:`~bifilar.estimation.montecarlo.FactorDraw`).  Split
from :mod:`bifilar.estimation.budget`; SI units, input keys as
:func:`~bifilar.estimation.budget.input_columns`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .budget import _key_hanging, _perturbed_scene
from .problem import Problem
from .sensitivity import input_value, mac_matches, n_modes


def _factor_routes(pb: Problem, h: int, keys: list) -> tuple[list, dict]:
    """:func:`factor_routes` of hanging ``h`` of ``pb`` (its keys carry the
    hanging's name where there are several)."""
    pre = f"{pb.models[h].hanging.name}:" if len(pb.models) > 1 else ""
    scene = pb.models[h].hanging.scene
    return factor_routes(scene.n_wires, keys, pre, stiff=getattr(scene, "stiffness", None) is not None)


def factor_routes(n_wires: int, keys: list, pre: str = "", stiff: bool = False) -> tuple[list, dict]:
    """How ``dr/dx`` of each input ``keys`` of a hanging with ``n_wires``
    wires (keys prefixed ``pre``) is got: (keys run with the input stepped,
    {key: why derived}).  Derived exactly, without a run: ``gravity`` (``r`` is a
    ratio of periods and ``g`` only scales time: 0); the last wire's anchor
    coordinates (moving every anchor by ``d`` moves the rest pose and the
    motion by ``d``: minus the sum over the other anchors); ``com.*`` (a
    CoM shift ``v``, reference frame, moves every attachment by ``-R v``:
    minus the attachments' derivatives through ``R``); the ``mass`` (``r``
    depends on ``m`` and ``I`` only through ``I/m``, and scaling every
    length by ``s`` and ``I`` by ``s^2`` leaves ``r`` unchanged, a
    translation amplitude scaled with them: ``2 m dr/dm = sum_j x_j
    dr/dx_j + A dr/dA``, the sum over every wire length, anchor and
    attachment coordinate (body frame at the CoM), ``A dr/dA`` only where
    the mode's dominant coordinate is a translation).  Each where the
    inputs it needs are among ``keys`` (the same uncertainty for every
    wire: all or none), else run.  :func:`derive_factor_routes` fills them in.

    ``stiff`` (the hanging states ``rig.stiffness``): ``r`` then depends on
    ``m``, ``g`` and EA also through the strain ``m g / EA`` of the loaded
    wires, so ``gravity`` is ``-dr/ds / g`` and the ``mass`` gets
    ``-dr/ds / m`` beside the scaling identity (``s`` the ``stiffness``
    factor): derived only where ``stiffness`` is among ``keys``, else run."""
    nw = n_wires
    have = set(keys)
    att = [f"{pre}attachment.{i + 1}.{a}" for i in range(nw) for a in "xyz"]
    geom = ([f"{pre}length.{i + 1}" for i in range(nw)] + [f"{pre}anchor.{i + 1}.{a}" for i in range(nw) for a in "xyz"]
            + att)
    derived = {}
    ea = not stiff or "stiffness" in have  # the strain's share is known (no EA, or EA's own derivative run)
    for key in keys:
        if key == "gravity" and ea:
            derived[key] = "gravity"
        elif key.startswith(f"{pre}anchor.{nw}.") and all(f"{pre}anchor.{i + 1}.{key[-1]}" in have
                                                             for i in range(nw - 1)):
            derived[key] = "translation"
        elif key.startswith("com.") and have.issuperset(att):
            derived[key] = "com"
        elif key == "mass" and ea and have.issuperset(geom):
            derived[key] = "scaling"
    return [k for k in keys if k not in derived], derived


def derive_factor_routes(dx: dict, derived: dict, scene, R, pre: str = "", translation_slope: float = 0.0) -> None:
    """Fill ``dx`` {key: dr/dx} in for the inputs ``derived`` {key: why}
    (:func:`factor_routes`) from the measured ones in ``dx``: ``scene`` the
    hanging's scene (its ``mass`` and input values), ``R`` its body frame
    in the reference one (a CoM shift is given there), ``pre`` its keys'
    prefix, ``translation_slope`` ``A dr/dA`` where the mode's dominant
    coordinate is a translation, else 0 (the scaling identity's term)."""
    nw = scene.n_wires
    for key, why in derived.items():
        if why == "translation":
            dx[key] = -sum(dx[f"{pre}anchor.{i + 1}.{key[-1]}"] for i in range(nw - 1))
        elif why == "gravity":  # g only scales time, and where EA is stated moves the strain m g / EA
            dx[key] = -dx["stiffness"] / scene.gravity if getattr(scene, "stiffness", None) is not None else 0.0
    for key, why in derived.items():
        if why == "com":
            a = "xyz".index(key[-1])
            dx[key] = -sum(R[b, a] * dx[f"{pre}attachment.{i + 1}.{'xyz'[b]}"] for i in range(nw) for b in range(3))
        elif why == "scaling":
            s = sum(input_value(scene, x.split(":", 1)[-1]) * v for x, v in dx.items()
                    if x.split(":", 1)[-1].split(".")[0] in ("length", "anchor", "attachment"))
            dx[key] = (s + translation_slope) / (2.0 * scene.mass)
            if getattr(scene, "stiffness", None) is not None:  # and the strain m g / EA
                dx[key] -= dx["stiffness"] / scene.mass


@dataclass
class SteppedFactors:
    """One scene's stepped runs for ``dr/dx`` (:func:`stepped_factor_runs`):
    the scene, its rest pose and modes, the mode indices ``idx`` run at
    ``amplitude`` (times each mode's normalised shape) for ``cycles``
    periods, and ``steps`` [(key, step d in SI, the scene with the input
    moved by d)].  Filled in: ``r0`` {mode index: the factor of the scene's
    own run in the same call}, ``dr_dx`` {mode index: {key: d r / d x}}
    ``failed`` {mode index: [keys whose stepped scene cannot hang,
    lost the mode or whose run failed]} and ``T_lin`` (the runs' linear
    periods); a mode whose own run fails has no
    ``r0`` and every key failed."""

    scene: Any
    rest: Any
    modes: Any
    idx: list
    amplitude: float
    cycles: float
    steps: list
    r0: dict = field(default_factory=dict)
    dr_dx: dict = field(default_factory=dict)
    failed: dict = field(default_factory=dict)
    #: {mode index: {key or None (the scene's own run): the run's linear period, s}}
    T_lin: dict = field(default_factory=dict)


def stepped_factor_runs(groups: list, rtol: float) -> None:
    """Forward differences of the amplitude factor ``r = T(A) / T_lin`` in
    each stepped input of every :class:`SteppedFactors` of ``groups``: the
    stepped scenes' rest poses (from the scene's) and modes batched, each
    mode found again by MAC, and all the groups' runs (each mode's own run
    first, then the stepped ones) in one
    :func:`~bifilar.analysis.batch.simulate_batch` call at ``rtol`` (the
    difference taken between runs of one engine).  Fills the groups in."""
    from ..analysis.batch import modes_batch, rest_poses, simulate_batch
    from .montecarlo import _modes_or_none

    jobs = []  # (group, mode index, key, step, scene, rest, modes, the mode's index there); key None: own run
    for g in groups:
        for k in g.idx:
            jobs.append((g, k, None, 0.0, g.scene, g.rest, g.modes, k))
        stepped = g.steps
        rs = rest_poses([s for _, _, s in stepped], g.rest, errors="return") if stepped else []
        good = [q for q, r in enumerate(rs) if not isinstance(r, BaseException)]
        mss = _modes_or_none(modes_batch, [stepped[q][2] for q in good], [rs[q] for q in good]) if good else []
        kept = [(q, ms) for q, ms in zip(good, mss) if ms is not None and n_modes(ms) == n_modes(g.modes)]
        cols = mac_matches(g.modes, [ms for _, ms in kept]) if kept else []
        for (q, ms), col in zip(kept, cols):
            key, d, s = stepped[q]
            for k in g.idx:
                jobs.append((g, k, key, d, s, rs[q], ms, int(col[k])))
        ran = {q for q, _ in kept}
        g.failed = {k: [stepped[q][0] for q in range(len(stepped)) if q not in ran] for k in g.idx}
        g.dr_dx = {k: {} for k in g.idx}
    if not jobs:
        return
    runs = simulate_batch([j[4] for j in jobs], mode=[j[7] + 1 for j in jobs], amplitude=[j[0].amplitude for j in jobs],
                          periods=[j[0].cycles for j in jobs], rtol=rtol, rests=[j[5] for j in jobs],
                          modes=[j[6] for j in jobs], errors="return", health=False)
    for j, run in zip(jobs, runs):
        if j[2] is None and not run.error and run.period:
            j[0].r0[j[1]] = run.period / run.linear_period
            j[0].T_lin.setdefault(j[1], {})[None] = run.linear_period
    for j, run in zip(jobs, runs):
        g, k, key = j[0], j[1], j[2]
        if key is None:
            continue
        if k in g.r0 and not run.error and run.period:
            g.dr_dx[k][key] = (run.period / run.linear_period - g.r0[k]) / j[3]
            g.T_lin.setdefault(k, {})[key] = run.linear_period
        else:
            g.failed[k].append(key)


def stated_laws(pb: Problem, laws):
    """(k, measurement, law) of each measurement of ``pb`` with a stated
    amplitude whose law ``laws[k]`` has its ``dr_dp`` (the factor's
    derivatives are measured for these)."""
    for k, m in enumerate(pb.measurements):
        law = laws[k] if laws is not None else None
        if law is not None and law.dr_dp is not None and m.amplitude:
            yield k, m, law


def factor_input_derivatives(pb: Problem, laws, keys: list, sigmas: dict, scenes, rests, modes, matches,
                             rtol: float = 1e-10) -> None:
    """Set ``laws[k].dr_dx`` {input key: d r_k / d x, per SI unit} for each
    measurement ``k`` with a stated amplitude's law (``dr_dp`` set): the
    amplitude factor's derivative in every budgeted input ``keys`` with a
    non-zero uncertainty ``sigmas`` that moves ``k``'s hanging (keys as
    :func:`input_columns`'s).  Forward differences, each input stepped as
    :func:`~bifilar.estimation.uncertainty.robust_sensitivity` steps it but
    by :data:`~bifilar.estimation.solve.FACTOR_STEP` of its scale (a length
    or position: of the longest wire), each stepped scene and the estimate's
    own run at the stated amplitude for ``m.cycles`` periods at ``rtol``,
    all in one :func:`~bifilar.analysis.batch.simulate_batch` call (the
    estimate's factor from that call, so that the difference is taken
    between runs of one engine); the inputs with an exact route are derived
    instead (:func:`_factor_routes`).  ``scenes`` .. ``matches``: per
    hanging at the estimate (:func:`input_columns`).  A stepped scene that
    cannot hang, whose mode is lost or whose run fails leaves its input at
    0 and in ``laws[k].dr_dx_failed`` (the factor taken to depend on it as
    on the unknowns, the budget before session 10)."""
    from .solve import FACTOR_STEP
    from .uncertainty import _step

    multi = len(pb.models) > 1
    plans = {}
    for k, m, _ in stated_laws(pb, laws):
        h = m.hanging
        mine = [key for key in keys if sigmas.get(key, 0) > 0 and h in _key_hanging(pb, key)]
        run, derived = _factor_routes(pb, h, mine)
        stepped = []
        for key in run:
            name = key.split(":", 1)[1] if multi and ":" in key else key
            d = _step(scenes[h], name, FACTOR_STEP)
            stepped.append((key, d, _perturbed_scene(pb, h, scenes[h], [(key, d)])))
        j = int(matches[h][pb.mode_index[k]])
        plans[k] = (mine, derived, j, SteppedFactors(scenes[h], rests[h], modes[h], [j], m.amplitude, m.cycles, stepped))
    if not plans:
        return
    stepped_factor_runs([p[3] for p in plans.values()], rtol)
    for k, (mine, derived, j, g) in plans.items():
        law = laws[k]
        law.dr_dx_derived = dict(derived)
        law.dr_dx_failed = list(g.failed[j])
        if j not in g.r0:
            law.dr_dx_failed = list(mine)
            law.dr_dx = {key: 0.0 for key in mine}
            continue
        dx = {key: 0.0 for key in mine}
        dx.update(g.dr_dx[j])
        h = pb.measurements[k].hanging
        md = modes[h].modes[j]
        derive_factor_routes(dx, derived, scenes[h], pb.models[h].R,
                             f"{pb.models[h].hanging.name}:" if multi else "",
                             law.amplitude * law.slope() if md.dominant < 3 else 0.0)
        law.dr_dx = dx
