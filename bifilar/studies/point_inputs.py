"""A sweep point's stated amplitude: the amplitude factor's derivative in
the measured inputs, ``dr/dx``, as ``invert --amplitude A`` measures it
(:mod:`bifilar.estimation.factor_inputs`), where it can change the sigma.

``invert`` fits ``T_lin(I, x) r(A; I, x) = T``, so an input ``x`` moves
its estimate by ``-(r dT_lin/dx + T_lin dr/dx) / (g dT_lin/dI)`` per unit
(``g = r + T_lin dr/dI dI/dT``, :func:`~bifilar.studies.point_amplitude.stated_amplitude_budget`),
where the small-amplitude budget has ``-(dT_lin/dx) / (dT_lin/dI)``: the
same only if ``dr/dx = dr/dI (dT_lin/dx) / (dT_lin/dI)`` (the factor
depending on the input as on the unknown).  A point measures ``dr/dx``
(one stepped run per input without an exact route, its timed modes' in
one batched call) only for a mode where the inputs' factor terms could
change a component's sigma by more than :data:`FACTOR_INPUT_ENOUGH` of
it: a bound from :data:`FACTOR_INPUT_K` (an assumed bound on how far
``dr/dx`` departs from that, stated below) and the point's own figures, no
run.  SI units.
"""

from __future__ import annotations

import math

import numpy as np

from .settings import _IDX

#: assumed: an input's ``dr/dx`` differs from what the factor's dependence on the unknown gives it,
#: ``dr/dI (dT_lin/dx) / (dT_lin/dI)``, by at most ``K A^2 / L`` for a wire length, an anchor,
#: attachment or CoM coordinate (``L`` the longest wire, ``A`` the stated amplitude) and ``K A^2 /
#: m`` for the mass (``r - 1`` is of order ``A^2`` and a relative change of the geometry moves it
#: by a like fraction).  Measured (``invert``'s ``dr/dx`` and ``dr/dI``, 92 timed modes: the Solar
#: Boat at spacing 1-4 and length 2-5, the thesis plate at height 0.3 and the KTH trifilar, at 0.05
#: and 0.3 rad): at most 3.24 (the boat's pitch at spacing 1, length 5, CoM z; its torsion at
#: spacing 1, length 2: 3.20); the bound takes twice that
FACTOR_INPUT_K = 6.5
#: a mode's ``dr/dx`` is measured when the bound on what its inputs' factor terms change a
#: component's sigma exceeds this fraction of the sigma (below it the sigma keeps the
#: small-amplitude input terms and ``amplitude_budget.input_factor_bound`` states the bound, 5 to
#: 300 times the change measured at the default amplitude: the bound sums every input's worst
#: case)
FACTOR_INPUT_ENOUGH = 0.1


def _inputs(pre, comp: str, k: int, unc: dict):
    """[(input, its standard uncertainty, dT_k/dx)] of the point's budgeted
    inputs (non-zero uncertainty) and ``dT_k/dI`` of ``comp``."""
    from ..estimation.sensitivity import input_sigma

    sens = pre.sens
    out = []
    for j, name in enumerate(sens.names):
        if name in _IDX:
            continue
        s = input_sigma(pre.scene, name, unc)
        if s > 0:
            out.append((name, s, float(sens.jacobian[k, j])))
    return out, float(sens.column(comp)[k])


def _bound_scale(scene, name: str, rest=None) -> float:
    """``|dr/dx|`` per ``A^2`` over :data:`FACTOR_INPUT_K` (1/SI unit of the input): 0 for gravity
    (exact: ``r`` is a ratio of periods; where EA is stated it moves the strain ``m g / EA``: EA's
    over ``g``), ``1/m`` for the mass, the largest strain at ``rest`` for EA's factor (it moves the
    loaded lengths by that share of themselves per unit), else ``1/L`` (the longest wire)."""
    if name == "stiffness":
        return float(np.max(np.asarray(rest.tensions, float) / np.asarray(scene.stiffness, float)))
    if name == "gravity":
        stiff = getattr(scene, "stiffness", None) is not None
        return _bound_scale(scene, "stiffness", rest) / float(scene.gravity) if stiff else 0.0
    if name == "mass":
        return 1.0 / float(scene.mass)
    return 1.0 / float(np.max(scene.lengths))


def input_factor_bound(pre, comp: str, k: int, unc: dict, T_lin: float, g: float) -> float:
    """Upper bound (kg m^2) on how much ``comp``'s stated-amplitude sigma
    (mode ``k``, linear period ``T_lin``, gain ``g``) changes when each
    input's term takes the measured ``dr/dx`` instead of the unknown's
    ``dr/dI (dT/dx) / (dT/dI)``: each term moves by ``T_lin s_x (dr/dx -
    dr/dI (dT/dx) / (dT/dI)) / (g dT/dI)``, at most ``T_lin s_x K A^2 / (L
    |g dT/dI|)`` under :data:`FACTOR_INPUT_K`'s assumption, and the sigma by
    at most their root sum of squares (the triangle inequality)."""
    rows, dT_dI = _inputs(pre, comp, k, unc)
    a2 = FACTOR_INPUT_K * pre.amplitude ** 2
    return math.sqrt(sum((T_lin * s * a2 * _bound_scale(pre.scene, name, pre.rest) / (g * dT_dI)) ** 2
                         for name, s, _ in rows))


def input_factor_terms(pre, comp: str, k: int, unc: dict, T_lin: float, r: float, g: float, dr_dx: dict,
                       failed) -> dict:
    """{input: its contribution (kg m^2, signed) to ``comp``'s estimate
    with the factor's measured ``dr_dx`` {input: d r / d x}}: ``-(r dT/dx +
    T_lin dr/dx) s_x / (g dT/dI)``, ``invert``'s term
    (:func:`~bifilar.estimation.budget._with_factor_gain`).  The inputs in
    ``failed`` (no derivative measured) are left out (they keep the
    small-amplitude term)."""
    rows, dT_dI = _inputs(pre, comp, k, unc)
    return {name: -(r * dT_dx + T_lin * dr_dx[name]) * s / (g * dT_dI)
            for name, s, dT_dx in rows if name in dr_dx and name not in failed}


def measure_factor_inputs(pre, modes: dict, unc: dict, st) -> dict:
    """``dr/dx`` of the point's factor in every budgeted input for each
    timed mode of ``modes`` {mode index: ``A dr/dA`` of its law}: one
    forward-difference run per input without an exact route
    (:func:`~bifilar.estimation.factor_inputs.factor_routes`), stepped as
    ``invert`` steps it (:data:`~bifilar.estimation.solve.FACTOR_STEP` of
    its scale), every mode's own run and stepped runs in one call
    (:func:`~bifilar.estimation.factor_inputs.stepped_factor_runs`, the
    point's periods and rtol), the rest derived exactly.  Returns {mode
    index: ({input: dr/dx}, [inputs without a derivative])}; a mode whose
    own run fails: every input without one."""
    return measure_factor_inputs_many([(pre, modes)], unc, st)[0]


def measure_factor_inputs_many(items: list, unc: dict, st) -> list:
    """:func:`measure_factor_inputs` of several scenes ``items`` [(pre,
    modes)] (``pre``: ``scene``, ``sens`` (its ``names``), ``rest``,
    ``ms``, ``amplitude``), every scene's runs in one batched call; one
    result per item.  The scene's inputs are its own (body frame of the
    scene: a CoM shift in its axes)."""
    from ..estimation.factor_inputs import SteppedFactors, derive_factor_routes, factor_routes, stepped_factor_runs
    from ..estimation.sensitivity import input_sigma, perturb
    from ..estimation.solve import FACTOR_STEP
    from ..estimation.uncertainty import _step

    groups = []
    for pre, modes in items:
        scene = pre.scene
        names = [n for n in pre.sens.names if n not in _IDX and input_sigma(scene, n, unc) > 0]
        run, derived = factor_routes(scene.n_wires, names, stiff=scene.stiffness is not None)
        steps = []
        for name in run:
            d = _step(scene, name, FACTOR_STEP)
            steps.append((name, d, perturb(scene, name, d)))
        groups.append((names, derived, SteppedFactors(scene, pre.rest, pre.ms, sorted(modes), pre.amplitude,
                                                      st.periods, steps)))
    stepped_factor_runs([g for _, _, g in groups], st.rtol)
    results = []
    for (pre, modes), (names, derived, grp) in zip(items, groups):
        out = {}
        for k in grp.idx:
            if k not in grp.r0:
                out[k] = ({}, list(names))
                continue
            failed = list(grp.failed[k])
            dx = dict(grp.dr_dx[k])
            if failed:  # an exact route would use a missing derivative: those keep the small-amplitude term
                failed += list(derived)
            else:
                trans = modes[k] if pre.ms.modes[k].dominant < 3 else 0.0
                derive_factor_routes(dx, derived, pre.scene, np.eye(3), "", trans)
            out[k] = (dx, failed)
        results.append(out)
    return results
