"""Whether a slack wire is the measured inputs' doing: the spread that the
config's stated uncertainties give the slack of the wires a
:class:`~bifilar.errors.SlackWireError` names, and the refusal's words when
the slack lies within it.

On four or five taut wires a wire's tension moves by tens of N per mm of a
length (the leaning table of docs/design.md, session 10's audit: 30-37 N
per mm, 6 N in two of its wires), so a config whose lengths and points are
off by their stated 1 mm hangs with a wire slack in the model although the
rig hangs on every wire: which wire goes slack is then decided by the
measurement errors, not by the rig.  The refusal stands (the model cannot
answer for a config that does not hang), but it says so.

SI units: lengths m, the slack ("gap") m, tensions N.
"""

from __future__ import annotations

import numpy as np

from ..errors import BifilarError, SlackWireError
from ..scene import Scene, scene_with
from .sensitivity import input_sigma, measured_inputs, perturb

#: a slack whose size is at most this many of its standard uncertainties is
#: put down to the measured inputs (a measurement error that large is not
#: unusual: 3 sigmas of a normal error are exceeded 0.3 % of the time)
WITHIN_Z = 3.0


def _without(scene: Scene, idx) -> Scene:
    """``scene`` without wires ``idx`` (0-based), each per-wire field cut
    alike (the stiffness too: an elastic rig's (n,) EA against n - 1 wires
    was an internal error, audit24)."""
    keep = [i for i in range(scene.n_wires) if i not in set(idx)]
    ea = None if scene.stiffness is None else np.asarray(scene.stiffness)[keep]
    return scene_with(scene, anchors=scene.anchors[keep], attachments=scene.attachments[keep],
                      lengths=scene.lengths[keep], stiffness=ea)


def slack_gaps(scene: Scene, idx, rest=None) -> tuple[np.ndarray, object]:
    """The slack (m, one per wire of ``idx``, 0-based) of wires ``idx`` of
    ``scene``: length minus the distance between the wire's anchor and
    attachment at the rest pose of the rig without those wires (its rest
    pose returned too; ``rest``: a nearby one, the start of its Newton)."""
    from ..analysis.equilibrium import rest_pose

    rp = rest_pose(_without(scene, idx), guess=rest, local_only=rest is not None)
    d = rp.com + scene.attachments[list(idx)] @ rp.R.T - scene.anchors[list(idx)]
    return scene.lengths[list(idx)] - np.linalg.norm(d, axis=1), rp


def slack_gap_sigmas(scene: Scene, idx, unc: dict) -> np.ndarray:
    """The standard uncertainty (m) of the slack of each of wires ``idx``
    (:func:`slack_gaps`) from the measured inputs' stated uncertainties
    ``unc`` (as :func:`~bifilar.estimation.sensitivity.input_sigma` reads
    them: every length, anchor and attachment coordinate, the CoM), to first
    order: forward differences of the slack, one rest pose of the rig
    without the slack wires per input (~30 for four wires, a few ms each).
    NaN where a changed rig does not hang."""
    gap0, rp0 = slack_gaps(scene, idx)
    h = 1e-7 * float(np.max(scene.lengths))
    var = np.zeros(len(idx))
    for name in measured_inputs(scene):
        s = input_sigma(scene, name, unc)
        if name == "mass" or s == 0:  # the mass scales every force alike: no change of the pose
            continue
        try:
            g, _ = slack_gaps(perturb(scene, name, h), idx, rest=rp0)
        except BifilarError:
            return np.full(len(idx), np.nan)
        var += ((g - gap0) / h * s) ** 2
    return np.sqrt(var)


def within_uncertainty(err: SlackWireError, scene: Scene, unc: dict, where: str) -> SlackWireError:
    """``err`` (a :class:`SlackWireError` of ``scene``), with the words that
    its slack lies within :data:`WITHIN_Z` standard uncertainties of what
    the measured inputs (``unc``, from ``where``: :func:`uncertainty_source`)
    give it, when it does; else ``err`` itself.  The
    advice of ``err`` (how much to shorten) is kept: it is an amount
    within that uncertainty."""
    from ..errors import StiffnessNeededError

    if isinstance(err, StiffnessNeededError):  # the refusal already says the stretch decides, not the lengths
        return err
    if not err.gaps or not all(g > 0 for g in err.gaps):
        return err
    idx = [w - 1 for w in err.wires]
    try:
        sig = slack_gap_sigmas(scene, idx, unc)
    except BifilarError:
        return err
    gaps = np.asarray(err.gaps, float)
    if not (np.all(np.isfinite(sig)) and np.all(gaps <= WITHIN_Z * sig)):
        return err
    each = "; ".join(f"wire {w}'s {g * 1000:.3g} mm against a standard uncertainty of {s * 1000:.3g} mm"
                     for w, g, s in zip(err.wires, gaps, sig))
    lengths = input_sigma(scene, "length.1", unc) * 1000
    pos = input_sigma(scene, "anchor.1.x", unc) * 1000
    com = input_sigma(scene, "com.x", unc) * 1000
    note = (f"; but the slack is within {WITHIN_Z:g} standard uncertainties of what the measured inputs give it "
            f"({each}, from the lengths' {lengths:.3g} mm, the points' {pos:.3g} mm and the CoM's {com:.3g} mm: "
            f"{where}): the measurement errors may decide which wire goes slack, and the rig itself may "
            "hang on every wire: measure the lengths and points again (to a fraction of a mm), or move the config's lengths within "
            "their uncertainty as advised; the model cannot answer for a config that does not hang")
    return SlackWireError(err.wires, err.message + note, gaps=err.gaps)  # (err's advice computed now)


def uncertainty_source(flags: dict, stated: dict) -> str:
    """Where the geometry's uncertainties (length, position, com) of an
    inversion come from, for :func:`within_uncertainty`'s words: the
    ``--uncertainty`` flags, the config's (or measurements file's)
    ``uncertainty`` block, or the defaults."""
    keys = ("length", "position", "com")
    if any(k in flags for k in keys):
        return "--uncertainty"
    if any(k in stated for k in keys):
        return "the config's uncertainty block"
    return "the defaults, which the config's uncertainty block can set"


def explain_slack(err: SlackWireError, scenes, unc: dict, where: str) -> SlackWireError:
    """:func:`within_uncertainty` for the scene among ``scenes`` (a
    measurement set's hangings) that raises ``err``: the first whose rest
    pose is refused with the same wires; ``err`` itself if none is."""
    from ..analysis.equilibrium import _NO_ADVICE, rest_pose

    for scene in scenes:
        token = _NO_ADVICE.set(True)
        try:
            rest_pose(scene)
        except SlackWireError as e:
            if e.wires == err.wires:
                return within_uncertainty(err, scene, unc, where)
        except BifilarError:
            continue
        finally:
            _NO_ADVICE.reset(token)
    return err


#: the geometry's keys of an ``uncertainty:`` block (the slack depends on no other input)
GEOMETRY_KEYS = ("length", "position", "com")


def states_geometry(block) -> bool:
    """Whether an ``uncertainty:`` block (a mapping, else False) states a
    geometry uncertainty (:data:`GEOMETRY_KEYS`): a config that does claims
    measured inputs, whose errors can decide a slack wire."""
    return isinstance(block, dict) and any(k in block for k in GEOMETRY_KEYS)


def explain_config_slack(err: SlackWireError, scene: Scene, path) -> SlackWireError:
    """:func:`within_uncertainty` for the config at ``path`` (its scene
    ``scene``) that a command without an inversion (``simulate``,
    ``tensions``, ``modes``) refuses for a slack wire at rest, from the
    config's own ``uncertainty:`` block where it states the geometry's
    (:data:`GEOMETRY_KEYS`; the others at their defaults, as ``invert``
    takes them): the same words as ``invert``'s refusal.  ``err`` itself
    where the block states none of them (the config then claims no
    measurement: a rig as designed, whose slack is its own) or does not
    parse (its checks belong to the commands that budget it)."""
    from .measurements import config_uncertainty
    from .uncertainty import default_uncertainty

    try:
        stated = config_uncertainty(path)
    except BifilarError:
        return err
    if not states_geometry(stated):
        return err
    return within_uncertainty(err, scene, default_uncertainty(stated), "the config's uncertainty block")


def config_rest_pose(scene: Scene, config):
    """The rest pose of ``scene`` (the config at path ``config``), for the
    commands without an inversion (``simulate``, ``tensions``, ``modes``):
    :func:`bifilar.analysis.equilibrium.rest_pose`, whose slack wire's
    refusal says, as ``invert``'s does, when the config's ``uncertainty:``
    block puts the slack within what its measured inputs give it
    (:func:`explain_config_slack`)."""
    from ..analysis.equilibrium import rest_pose

    try:
        return rest_pose(scene)
    except SlackWireError as e:
        raise explain_config_slack(e, scene, config) from None
