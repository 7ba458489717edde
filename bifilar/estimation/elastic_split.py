"""Four or five elastic wires (``rig.stiffness``): what the measured inputs'
stated uncertainties do to the rig the experimenter writes down.  SI units
(N, m, kg), world frame; poses as (com m, R body -> world).

On such a rig the split of the weight between the wires is set by the
wires' lengths to within their stretch (EA / L: 16.7 N a mm of length on
1.2 m wires of EA 20 kN, against ~5 N a wire), and the modes the model
gives depend on how many wire directions it holds
(:func:`~bifilar.analysis.equilibrium.constraint_rank`: since session 26
a direction whose stretch stiffness is at least
:data:`~bifilar.analysis.stretch_held.STRETCH_HOLD` times its geometric
one; the others carry their springs).  Neither is a derivative the
one-input-at-a-time budget sees: a drawn config leaves a wire slack
(refused), or the model of it holds one direction more or fewer.  Measured
in closed loops (docs/design.md "elastic25, session 25"): a 2 kg plate on
four 1.2 m wires, 1 mm stds, EA 20 kN: 73 % slack; EA 2 kN: under the
eigenvalue rule of before session 26 (1e-6 of the largest eigenvalue of
``G M^-1 G^T``, which a millimetre's splay crossed) 22 % of drawn configs
held a fourth direction and the answered scattered 26x the sigma; under the
stretch rule no drawn config changes the count (its directions are 300x
stiffer by stretch than by geometry, or 1e-2x and less: docs/design.md
"elastic26, session 26").

:func:`drawn_rig_risks` estimates both probabilities from fixed-seed
normal draws of every budgeted input: the rest pose and the tensions
linear in the inputs (forward differences of the elastic rest pose, one
per input), the held-direction count evaluated at each drawn geometry,
that pose and those tensions (~0.15 s of CPU on four wires); the slack's
tail from each wire's tension plane at its most probable slack config
(+65 ms: EA's stated 10 % scales the lengths' warp, so the linear spread
put c07's tail at 0.083 % where the drawn configs' exact rests leave 0.130 %
slack, docs/design.md "elastic26b, session 26").  Checked against a hand
model of the tensions, the exact rests of drawn configs
(tests/test_sweep_audit24.py, tests/test_elastic26b.py) and closed loops
(design.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..analysis.stretch_held import STRETCH_HOLD
from ..errors import BifilarError
from ..rotations import matrix_to_rotvec
from .sensitivity import input_sigma, perturb

#: normal draws of the inputs (fixed seed: the same figures on every run); a
#: probability's binomial std is at most 0.5 / sqrt(DRAWS) = 0.008
DRAWS = 4000
#: draws of the tensions alone (n normal deviates each, the tensions' covariance factored): p_slack's
#: binomial std at most 0.5 / sqrt(SLACK_DRAWS) = 0.0016
SLACK_DRAWS = 100_000
#: a drawn config counts as near a change of the held directions where a
#: direction's stretch over geometric stiffness lies between this fraction
#: and its inverse of the rule's factor (a splay's stretch stiffness grows
#: as its square: a factor 10 is the splay's factor 3.2; a direction held
#: at 10-100x is off by up to a tenth .. a hundredth of its coupling)
HELD_MARGIN = 0.1
#: the sigma is not given where a drawn config leaves a wire slack this
#: often or more (the answered experiments are then a selection by the
#: lengths' errors, which the sigma does not describe)
SLACK_MAX = 0.05
#: a wire's tension plane for ``p_slack`` is taken at this share of the way to its linear slack point
#: (:func:`_slack_planes`; its tension there 10 % of its rest's, so the differences do not cross the slack)
DESIGN_SHARE = 0.9
#: a wire whose linear slack probability is below this keeps its linear plane (no rest solved for it): a
#: fattened tail moved c07's 3.4 stds to 3.2 (p x 1.7), far from lifting 1e-6 to the 1e-3 that matters
PLANE_SKIP = 1e-6
#: ``invert`` notes the slack's probability (its std kept) from this one on (100,000 draws: 1e-3 is 100 of
#: them, its binomial std 3 %)
SLACK_NOTE = 1e-3
#: where no drawn config crosses the held-direction rule but some come near it (``p_held`` 0, ``p_near`` > 0), a
#: component is refused only where the near hold's bias of it (its mode's period with the wires' springs against
#: the model's, :func:`near_hold_biases`) exceeds this share of its sigma: a bias of 0.1 sigma moves a 95 %
#: interval's coverage to 94.89 % (0.11 points) and a closed loop's sd / sigma by 0.5 %, far inside the 200-draw
#: chi^2 band (0.902..1.098); the 4-wire twin's torsion 2.5e-14 of its period, its swings 7.6e-5 (docs/design.md
#: "twin26, session 26")
COUPLING_SHARE = 0.1


@dataclass(frozen=True)
class DrawnRigRisks:
    """What :func:`drawn_rig_risks` found (probabilities over the drawn configs).

    p_slack: a wire slack at the drawn config's rest (a tension below 0 N;
    each wire's tension a plane in the inputs tangent near its most
    probable slack config, :func:`_slack_planes`); p_held: the model holds another number of
    wire directions at the drawn config than at the config's; p_near: a
    direction of the drawn config within a factor 1 / :data:`HELD_MARGIN`
    of the rule either way, or p_held (a superset of p_held's); p_model: slack or held; tension_sd (n,) N: each wire's
    tension's std from the inputs; tensions (n,) N at rest; held: the
    config's held directions (-1 where ``failed``)."""

    p_slack: float
    p_held: float
    p_near: float
    p_model: float
    tension_sd: np.ndarray
    tensions: np.ndarray
    held: int
    #: why the draws could not be made (a neighbour's rest pose not found), else None: then no figure above
    #: is known (NaN) and :func:`sigma_refusal` refuses the sigma, as where the draws are risky
    failed: str | None = None


def _inputs(scene, unc: dict) -> tuple[list, np.ndarray]:
    """The budgeted inputs with a nonzero std and their stds (SI)."""
    from .sensitivity import measured_inputs, stiff_inputs

    names = measured_inputs(scene) + stiff_inputs(scene, unc) + ["gravity"]
    sd = np.array([input_sigma(scene, n, unc) for n in names], float)
    keep = sd > 0
    return [n for n, k in zip(names, keep) if k], sd[keep]


def _stretch(scene, R, G, w, tensions):
    """The stretch and geometric stiffnesses (mu, kappa) of
    :func:`~bifilar.analysis.stretch_held.stretch_directions` of an elastic
    ``scene`` at pose(s) with attitude(s) ``R`` (..., 3, 3), Jacobian(s)
    ``G`` (..., n, 6), lever arms ``w`` (..., n, 3) m and wire tensions
    (..., n) N (a wire at or below 0 N has no spring)."""
    from ..analysis.stretch_held import stretch_directions

    d = G[..., :3]
    L = np.asarray(scene.lengths, float)
    taut = tensions > 0
    k = np.broadcast_to(np.asarray(scene.stiffness, float), L.shape) / L * taut
    M = np.zeros(np.shape(R)[:-2] + (6, 6))
    M[..., :3, :3] = scene.mass * np.eye(3)
    M[..., 3:, 3:] = R @ np.asarray(scene.inertia, float) @ np.swapaxes(R, -1, -2)
    return stretch_directions(k, np.where(taut, tensions, 0.0) / np.linalg.norm(d, axis=-1), d, w, G, M)[:2]


def _held(mu, kappa, margin: float = 1.0) -> np.ndarray:
    """The model's held-direction count(s) of :func:`_stretch`'s stiffnesses
    (:func:`~bifilar.analysis.stretch_held.held_mask`, its factor scaled by ``margin``)."""
    from ..analysis.stretch_held import held_mask

    return held_mask(mu, kappa, margin).sum(-1)


def _gradients(scene, rest, names: list, sd: np.ndarray, checked: bool = True):
    """The rest pose's com (k, 3) m, rotation vector (k, 3) rad (world) and
    tensions (k, n) N per standard deviation of each input ``names`` (stds
    ``sd``, SI) about ``rest`` (the rest pose of ``scene``, or a (com, R,
    tensions) tuple): forward differences at 1e-6 of each input's std, one
    elastic rest each (``checked``: the rest pose's checks, else the elastic
    equilibrium alone, a third of the CPU)."""
    from ..analysis.elastic_rest import elastic_rest
    from ..analysis.equilibrium import rest_pose

    c0, R0, T0 = (rest.com, rest.R, rest.tensions) if checked else rest
    dc, dth, dT = (np.zeros((len(names), 3)), np.zeros((len(names), 3)), np.zeros((len(names), scene.n_wires)))
    for j, (name, s) in enumerate(zip(names, sd)):
        h = 1e-6 * s
        moved = perturb(scene, name, h)
        if checked:
            rp = rest_pose(moved, guess=rest, local_only=True)
            c, R, T = rp.com, rp.R, rp.tensions
        else:
            c, R, T = elastic_rest(moved, moved.stiffness, c0, R0)[:3]
        dc[j] = (c - c0) / h * s
        dth[j] = matrix_to_rotvec(R @ R0.T) / h * s
        dT[j] = (T - T0) / h * s
    return dc, dth, dT


def _slack_planes(scene, rest, names: list, sd: np.ndarray, dT: np.ndarray):
    """Each wire's tension as a plane in the inputs' standard normal
    deviates ``z``, ``mean_i + z . grad[:, i]`` N, tangent near that wire's
    most probable slack config (the first-order reliability method's design
    point): (mean (n,) N, grad (k, n) N).  The tensions are not linear in
    the inputs: their error grows with the deviation (a tension's gradient
    moves with the points; c07 at EA 2 kN, 1 mm stds: exact rests minus the
    linear tensions scatter 0.06 N within one std, 0.3 N at 3), which
    fattens the slack tail -- 65 of 50,000 drawn configs' exact rests slack
    against 41 linear (docs/design.md "elastic26b, session 26").  The plane of
    wire ``i`` touches the tension at :data:`DESIGN_SHARE` of the way to the
    linear slack point along its gradient (at the point itself it crosses
    the slack's kink), where its rest's differences are taken again; a wire
    whose linear slack probability is below :data:`PLANE_SKIP` keeps its
    linear plane (``rest.tensions``, ``dT``).  One rest and ``k`` more per
    wire re-planed (the elastic equilibrium alone: +65 ms on four wires)."""
    from ..analysis.elastic_rest import elastic_rest

    mean, grad = np.array(rest.tensions, float), np.array(dT, float)
    for i in range(scene.n_wires):
        gg = float(dT[:, i] @ dT[:, i])
        if gg == 0.0 or 0.5 * math.erfc(mean[i] / math.sqrt(2.0 * gg)) < PLANE_SKIP:
            continue
        zp = -DESIGN_SHARE * mean[i] * dT[:, i] / gg
        moved = scene
        for name, zj, s in zip(names, zp, sd):
            moved = perturb(moved, name, zj * s)
        pose = elastic_rest(moved, moved.stiffness, rest.com, rest.R)[:3]
        if np.any(pose[2] <= 0.0):  # another wire slack there too (not met): the linear plane, the kink not differenced
            continue
        grad[:, i] = _gradients(moved, pose, names, sd, checked=False)[2][:, i]
        mean[i] = pose[2][i] - grad[:, i] @ zp
    return mean, grad


def drawn_rig_risks(scene, rest, unc: dict, draws: int = DRAWS, seed: int = 0) -> DrawnRigRisks:
    """:class:`DrawnRigRisks` of ``scene`` (elastic, more than three wires)
    at its rest pose ``rest``, for configs drawn with the stated standard
    uncertainties ``unc`` (as :func:`~bifilar.estimation.sensitivity.input_sigma`
    reads them): ``draws`` normal draws (``seed``) of every input, the rest
    pose (com, rotation vector) and tensions moved linearly (forward
    differences at 1e-6 of each input's std), the drawn anchors,
    attachments and CoM exact; ``p_slack`` from :data:`SLACK_DRAWS` draws of
    the tensions' planes of :func:`_slack_planes`.  Raises :class:`~bifilar.errors.BifilarError`
    where a neighbour's rest pose is not found."""
    from ..analysis.derivatives import input_directions
    from ..analysis.equilibrium import constraint_jacobian

    names, sd = _inputs(scene, unc)
    dc, dth, dT = _gradients(scene, rest, names, sd)
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((draws, len(names)))
    slack = np.any(rest.tensions + z @ dT < 0, axis=1)
    # where the linear draws leave a wire slack twice the refusal's share or more (4000 draws: 10 binomial stds
    # above it) the sigma is refused whatever the tail: the linear planes stand (EA 20 kN: 0.738, exact 0.737)
    if np.mean(slack) < 2 * SLACK_MAX:
        mean, grad = _slack_planes(scene, rest, names, sd, dT)
    else:
        mean, grad = np.asarray(rest.tensions, float), dT
    ev, V = np.linalg.eigh(grad.T @ grad)  # the planes' covariance (n, n), N^2
    u = rng.standard_normal((SLACK_DRAWS, len(ev)))
    p_slack = float(np.mean(np.any(mean + (u * np.sqrt(np.maximum(ev, 0.0))) @ V.T < 0, axis=1)))
    geo = [j for j, n in enumerate(names) if n != "stiffness"]  # EA's factor moves no point
    dirs = input_directions(scene, [names[j] for j in geo])
    A = scene.anchors + np.einsum("dj,jnk->dnk", z[:, geo] * sd[geo], dirs["anchors"])
    P = scene.attachments + np.einsum("dj,jnk->dnk", z[:, geo] * sd[geo], dirs["attachments"])
    # the drawn poses to first order, as the tensions: com + dc, R = (1 + [th]x) R0 (th ~ mrad)
    th = z @ dth
    w0 = P @ rest.R.T
    w = w0 + np.cross(th[:, None, :], w0)
    d = (rest.com + z @ dc)[:, None, :] + w - A
    G = np.concatenate([d, np.cross(w, d)], axis=2)  # (draws, n, 6): constraint_jacobian's [d, w x d]
    Rs = rest.R + np.cross(th[:, None, :], rest.R.T).transpose(0, 2, 1)  # (1 + [th]x) R0, column by column
    _, w_0, G0 = constraint_jacobian(scene, rest.com, rest.R)
    held0 = int(_held(*_stretch(scene, rest.R, G0, w_0, np.asarray(rest.tensions, float))))
    # near a change: a direction of the drawn config within a factor 1 / HELD_MARGIN of the rule either way
    # (the counts at the rule's factor scaled by HELD_MARGIN and by its inverse differ): held rigidly there, it
    # is off by up to about its geometric over its stretch stiffness (1.5 % of a leaning rig's torsion at 15x)
    mu, kappa = _stretch(scene, Rs, G, w, rest.tensions + z @ dT)
    # (a draw with a wire slack has that wire's spring gone, so another count: counted as slack only)
    held = (_held(mu, kappa) != held0) & ~slack
    near = held | ~slack & (_held(mu, kappa, HELD_MARGIN) != _held(mu, kappa, 1.0 / HELD_MARGIN))
    # slack or held: the slack's finer figure where none is held (the only case a sigma is given)
    p_model = float((slack | held).mean()) if held.any() else p_slack
    return DrawnRigRisks(p_slack, float(held.mean()), float(near.mean()), p_model,
                         np.sqrt(np.sum(dT ** 2, axis=0)), np.asarray(rest.tensions, float), held0)


def risks_or_none(scene, rest, unc: dict) -> DrawnRigRisks | None:
    """:func:`drawn_rig_risks` where ``scene`` has more than three elastic
    wires, else None.  Where the draws cannot be made (a neighbour's rest
    pose not found), risks whose ``failed`` says why, every figure NaN: the
    sigma is then refused too (before, the point's own figures stood,
    unchecked: the lower bounds the draws exist to catch)."""
    from ..models.maximal import MAX_ELIMINATION_WIRES

    if scene.stiffness is None or scene.n_wires <= MAX_ELIMINATION_WIRES:
        return None
    try:
        return drawn_rig_risks(scene, rest, unc)
    except (BifilarError, np.linalg.LinAlgError) as exc:
        nan = float("nan")
        return DrawnRigRisks(nan, nan, nan, nan, np.full(scene.n_wires, nan), np.asarray(rest.tensions, float), -1,
                             failed=str(exc).splitlines()[0] if str(exc) else type(exc).__name__)


_RULE = (f"it holds a direction rigidly where the wires' stretch resists it at least {STRETCH_HOLD:g} times as stiffly "
         "as the tensions' turning does, and carries the stretch of the others as springs")
_WHERE = ("a mode appears or goes and the other periods move by up to about a tenth of that direction's share "
          "(1.5 % of a torsion period on a leaning four-wire rig)")


def sigma_refusal(risks: DrawnRigRisks) -> str | None:
    """Why no sigma can be given for the rig of ``risks``, or None where it
    can (no drawn config holding another number of directions, fewer than
    :data:`SLACK_MAX` slack; drawn configs only near the rule leave it to each
    component, :func:`per_mode` and :func:`near_hold_refusal`)."""
    if risks.failed is not None:
        return ("the uncertainty cannot be given on these four or five elastic wires: the configs the measured "
                "inputs' stated uncertainties allow could not be drawn (" + risks.failed + "), so whether they "
                "leave a wire slack or change the wire directions the model holds is not known (either puts the "
                "answer off by tens of sigma): state the lengths and points to a fraction of a millimetre (their "
                "uncertainty block), or hang the body on three wires")
    parts = []
    if risks.p_near > 0 and risks.p_held > 0:  # near only (p_held 0): each component's own, near_hold_refusal
        parts.append(
            f"in {100 * risks.p_held:.3g} % of the configs the measured inputs' stated uncertainties allow "
            f"(and within a factor {1 / HELD_MARGIN:g} of it in {100 * risks.p_near:.3g} %), the model holds another "
            f"number of the elastic wires' directions than the {risks.held} it holds here ({_RULE}), so {_WHERE}")
    if risks.p_slack >= SLACK_MAX:
        i = int(np.argmax(risks.tension_sd / np.maximum(risks.tensions, 1e-300)))
        parts.append(
            f"the inputs' stated uncertainties spread each wire's tension by up to {risks.tension_sd[i]:.3g} N "
            f"(wire {i + 1}, which carries {risks.tensions[i]:.3g} N: the split of elastic wires is set by their "
            f"lengths to within their stretch), so {100 * risks.p_slack:.3g} % of the configs leave a wire slack")
    if not parts:
        return None
    stiffer = ", stiffer wires (the stretch's share grows with EA)" if risks.p_near > 0 else ""
    return ("the uncertainty cannot be given on these four or five elastic wires: " + "; and ".join(parts)
            + ": state the lengths and points to a fraction of a millimetre (their uncertainty block)" + stiffer
            + ", or hang the body on three wires")


def combined_refusal(p_limit, p_model: float) -> float:
    """The probability that ``invert`` refuses a drawn config: at the
    physical limit (``p_limit``, None: 0) or a drawn config the model cannot
    answer for (``p_model``), taken as independent."""
    p = 0.0 if p_limit is None or not math.isfinite(p_limit) else float(p_limit)
    return 1.0 - (1.0 - p) * (1.0 - float(p_model))


def slack_note(risks: DrawnRigRisks) -> str | None:
    """``invert``'s note where a kept std's rig leaves a wire slack in some
    drawn configs (at least :data:`SLACK_NOTE` of them, fewer than
    :data:`SLACK_MAX`), else None."""
    if not SLACK_NOTE <= risks.p_slack < SLACK_MAX:
        return None
    return (f"the measured inputs' stated uncertainties leave a wire slack in {100 * risks.p_slack:.3g} % of the "
            "configs they allow (the split of elastic wires is set by their lengths to within their stretch): "
            "this answer takes every wire as taut, as the config's are; a wire that hangs slack on the rig is a "
            "rig this config does not describe (the std, the budget's over all configs, held for the answered "
            "ones in closed loops at 2 % slack: docs/design.md \"elastic25, session 25\")")


def hangings_check(hangings, unc: dict, near: dict) -> tuple[str | None, list]:
    """``invert``'s check of its hangings ``(name, scene, rest pose)``
    (SI, world frame; stated uncertainties ``unc``), the sweep point's rule
    (:func:`risks_or_none`, :func:`sigma_refusal`) on each that has four or
    five elastic wires: (why no std can be given, None where every hanging
    keeps it; notes, :func:`slack_note`).  The reason is the sweep's words,
    prefixed by the hanging's name where there are several.  Before session
    25 ``invert`` printed a std 1.034x the sweep's sigma where the answers
    scattered 26x (docs/design.md "inv25").  ``near``: a dict that gets
    {hanging's index: its risks} where :func:`per_mode` leaves the std to
    each unknown (:func:`near_hold_refusal`, the caller's: it needs the
    answer's gain), as the sweep's point does for each component; required,
    so that no caller can take such a hanging's std unchecked."""
    hangings = list(hangings)
    notes = []
    for h, (name, scene, rest) in enumerate(hangings):
        risks = risks_or_none(scene, rest, unc)
        if risks is None:
            continue
        if per_mode(risks):
            near[h] = risks
        where = f"hanging '{name}': " if len(hangings) > 1 else ""
        refusal = sigma_refusal(risks)
        if refusal is not None:
            return where + refusal, []
        note = slack_note(risks)
        if note is not None:
            notes.append(where + note)
    return None, notes


def point_risks(res: dict, scene, rest, unc: dict):
    """(risks, refusal) of a sweep or plan point ``res`` (its dict, to which
    ``drawn_rig`` is added: ``p_slack``, ``p_held``, ``p_near``,
    ``tension_sd`` N, ``held_directions``) on four or five elastic wires
    (:func:`risks_or_none`; rest pose ``rest``, stated uncertainties
    ``unc``), else (None, None); ``refusal`` (:func:`sigma_refusal`) the
    reason its sigmas are not given, or None.  Before session 25 those
    sigmas were printed, 18-26x too small in closed loops (docs/design.md
    "elastic25")."""
    risks = risks_or_none(scene, rest, unc)
    if risks is None:
        return None, None
    res["drawn_rig"] = {"p_slack": risks.p_slack, "p_held": risks.p_held, "p_near": risks.p_near,
                        "tension_sd": risks.tension_sd, "held_directions": risks.held}
    if risks.failed is not None:
        res["drawn_rig"] = {"failed": risks.failed}
    return risks, sigma_refusal(risks)


def per_mode(risks: DrawnRigRisks | None) -> bool:
    """Whether the drawn configs of ``risks`` leave the sigma to each
    component (:func:`near_hold_refusal`): some come within a factor
    1 / :data:`HELD_MARGIN` of the held-direction rule, none crosses it, and
    :func:`sigma_refusal` refuses none for another reason."""
    return (risks is not None and risks.failed is None and risks.p_held == 0 and risks.p_near > 0
            and risks.p_slack < SLACK_MAX)


def near_hold_biases(scene, rest, modes) -> np.ndarray:
    """Each mode of ``modes`` (the model's linear modes about the elastic
    rest pose ``rest`` of ``scene``), its period's bias from the directions
    the model holds rigidly: the body on the wires' springs (every direction
    soft, :func:`~bifilar.analysis.elastic_rest.elastic_period_ratios`)
    less the model's period, s (NaN for a neutral mode).  The measured
    period is the springs'; the model's answer from it is off by the
    period's derivative times this."""
    from ..analysis.elastic_rest import elastic_period_ratios

    modes = list(getattr(modes, "modes", modes))
    T = np.array([m.period if m.period else np.nan for m in modes], float)
    return (elastic_period_ratios(scene, rest, modes) - 1.0) * T


def near_hold_refusal(risks: DrawnRigRisks, component: str, bias: float, sigma: float) -> str | None:
    """Why ``component``'s sigma (kg m^2, or m for a CoM coordinate) cannot
    be given on a rig whose drawn configs come near the held-direction rule
    (:func:`per_mode`), or None where it can: the bias ``bias`` (same unit)
    the near hold puts in the answer (its modes' :func:`near_hold_biases`
    through the answer's derivative in their periods) is at most
    :data:`COUPLING_SHARE` of ``sigma``."""
    if abs(bias) <= COUPLING_SHARE * sigma:
        return None
    return ("the uncertainty cannot be given on these four or five elastic wires: in "
            f"{100 * risks.p_near:.3g} % of the configs the measured inputs' stated uncertainties allow, the model "
            f"comes within a factor {1 / HELD_MARGIN:g} of holding another number of the elastic wires' directions "
            f"than the {risks.held} it holds here (none of the configs drawn crossed it; {_RULE}), and its rigid "
            f"hold moves {component} by {abs(bias):.3g} against the wires' springs, "
            f"{abs(bias) / sigma if sigma > 0 else math.inf:.3g} of its sigma (more than {COUPLING_SHARE:g}): "
            "state the lengths and points to a fraction of a millimetre (their uncertainty block), stiffer wires "
            "(the stretch's share grows with EA), or hang the body on three wires")


def component_refusals(risks: DrawnRigRisks | None, scene, rest, modes, chosen: dict, budgets: dict) -> dict:
    """The sweep or plan point's :func:`near_hold_refusal` of each component
    ``chosen`` ({component: index of its mode in ``modes``, the point's
    linear modes about ``rest``}; ``budgets`` {component:
    :class:`~bifilar.estimation.sensitivity.Budget`}, its ``dI_dT`` kg m^2/s
    and ``value_sigma`` kg m^2): {component: why its sigma is not given}
    for those refused, {} where :func:`per_mode` does not apply."""
    if not per_mode(risks) or not chosen:
        return {}
    bias = near_hold_biases(scene, rest, modes)
    out = {}
    for comp, k in chosen.items():
        b = budgets[comp]
        text = near_hold_refusal(risks, comp, float(bias[k] * b.dI_dT), b.value_sigma)
        if text is not None:
            out[comp] = text
    return out
