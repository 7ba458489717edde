"""Valid but implausible configs (a units slip, usually): warnings only.
Part of :mod:`bifilar.config`.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene import Scene

PLAUSIBLE = {
    "max_length": 1000.0,  # m: no hall is higher; a 5 km wire is a units slip
    "max_mass": 1e5,  # kg: 100 t is beyond any pendulum rig
    "gravity": (1.0, 30.0),  # m/s^2: the Moon (1.62) .. well above Jupiter (24.8)
    "mm_length": 100.0,  # m: every wire longer than this ...
    "mm_span": 10.0,  # m: ... while anchors and attachments span less: lengths in mm?
    "cm_length": 20.0,  # m: every wire longer than this ...
    "cm_span": 2.0,  # m: ... while anchors and attachments span less: lengths in cm?
    "gyration_shape": 2.0,  # k / extent, body shape known: sqrt(3) is the geometric limit
    "gyration_attachments": 30.0,  # k / attachment spread (either way) when only attachments are known
    "gyration_for_mass": 10.0,  # m: largest k for 1 kg, scaled by (m / 1 kg)^(1/3); a whole config in mm
    "attachments_beyond_shape": 10.0,  # attachment reach / the known shape's reach: the rig in cm or mm?
    "stretch": 1e-3,  # m: a wire stretched by more than a length's default uncertainty at its share of the weight
}
"""Thresholds of :func:`plausibility_warnings` (SI units)."""


def plausibility_warnings(scene: Scene) -> list[str]:
    """Valid but implausible values of a scene, one message each (they
    usually mean a units slip).  Empty for a sensible rig.

    * every wire longer than 100 m while anchors and attachments each span
      less than 10 m: lengths in millimetres (the thesis's 500 m wires with
      anchors 505 m apart are consistent and do not warn); every wire longer
      than 20 m while they span less than 2 m: lengths in centimetres (a
      drone's 0.8 m wires entered as 80; audit19); otherwise a wire longer
      than 1000 m;
    * a body heavier than 100 t;
    * gravity outside 1 .. 30 m/s^2 (e.g. 981: cm/s^2);
    * a radius of gyration k = sqrt(I_max / m) inconsistent with the body's
      size h (its farthest extent from the CoM along a body axis): k > 2 h
      when the shape is known (bounding box or parts; every mass point lies
      within sqrt(3) h, so k <= sqrt(3) h), k > 30 h or k < h / 30 when only
      the attachment points are known (inertia in kg cm^2 or g mm^2);
    * a radius of gyration too large for the mass, k > 10 m (m / 1 kg)^(1/3)
      (21.5 m for 10 kg, 46 m for 100 kg): a config written wholly in
      millimetres (lengths, points and inertia in kg mm^2, all consistent, so
      no other rule sees it) has k 1000 times the real one.  The body's size
      and inertia, not the wire length, carry the rule: long wires on a small
      body are legitimate (the thesis's 500 m wires on a 100 kg plate with
      k = 1.6 m).  Checked only when the shape rule above is quiet (one
      warning per slip);
    * an attachment point farther from the CoM than 10 times the known shape
      (bounding box or parts) reaches along a body axis: the rig in cm or mm
      beside a body in SI.
    """
    out = []
    L = scene.lengths
    span_a = float(np.ptp(scene.anchors, axis=0).max())
    span_p = float(np.ptp(scene.attachments, axis=0).max())
    if np.min(L) > PLAUSIBLE["mm_length"] and max(span_a, span_p) < PLAUSIBLE["mm_span"]:
        out.append(f"rig.lengths: every wire is longer than {PLAUSIBLE['mm_length']:g} m while the anchors and "
                   f"attachments span less than {PLAUSIBLE['mm_span']:g} m; are the lengths in millimetres?")
    elif np.min(L) > PLAUSIBLE["cm_length"] and max(span_a, span_p) < PLAUSIBLE["cm_span"]:
        out.append(f"rig.lengths: every wire is longer than {PLAUSIBLE['cm_length']:g} m while the anchors and "
                   f"attachments span less than {PLAUSIBLE['cm_span']:g} m; are the lengths in centimetres?")
    elif np.max(L) > PLAUSIBLE["max_length"]:
        i = int(np.argmax(L))
        out.append(f"rig.lengths.{i} = {L[i]:g} m is implausibly long for a pendulum rig; are the lengths in millimetres?")
    if scene.mass > PLAUSIBLE["max_mass"]:
        out.append(f"body.mass = {scene.mass:g} kg is implausibly large for a pendulum rig; is it in grams?")
    glo, ghi = PLAUSIBLE["gravity"]
    if not glo <= scene.gravity <= ghi:
        out.append(f"gravity = {scene.gravity:g} m/s^2 is implausible (Earth: 9.81); is it in other units?")
    ev = np.linalg.eigvalsh(scene.inertia)
    k = math.sqrt(ev[-1] / scene.mass)
    d = np.eye(3)
    bad = False
    size = float(np.max(scene.body_support(np.vstack([d, -d]))))  # farthest extent from the CoM along a body axis
    if size > 0:
        if scene.support_source == "attachments":
            r = PLAUSIBLE["gyration_attachments"]
            bad = k > r * size or k < size / r
        else:
            bad = k > PLAUSIBLE["gyration_shape"] * size
        if bad:
            out.append(f"body: radius of gyration sqrt(I/m) = {k:.3g} m does not fit a body reaching {size:.3g} m "
                       f"from its centre of mass ({scene.support_source}); are the inertia and mass in kg m^2 and kg?")
    if scene.support is not None:
        reach = float(np.max(np.asarray(scene.support(np.vstack([d, -d])), dtype=float)))  # the shape alone
        att = float(np.max(np.abs(scene.attachments)))
        if att > PLAUSIBLE["attachments_beyond_shape"] * reach:
            src = "body.bounding_box" if scene.support_source == "bounding_box" else "body.parts"
            out.append(f"rig.attachments reach {att:.3g} m from the centre of mass along a body axis, but the body "
                       f"({src}) only {reach:.3g} m; are the rig's coordinates in other units (cm, mm)?")
    k_max = PLAUSIBLE["gyration_for_mass"] * scene.mass ** (1.0 / 3.0)
    if not bad and k > k_max:
        out.append(f"body: radius of gyration sqrt(I/m) = {k:.3g} m is implausibly large for a {scene.mass:.3g} kg body "
                   f"(above {k_max:.3g} m); is the whole config in millimetres (lengths in m, inertia in kg m^2)?")
    w = stretch_warning(scene)
    if w is not None:
        out.append(w)
    return out


def stretch_warning(scene: Scene) -> str | None:
    """The warning for a stated ``rig.stiffness`` (EA, N) that stretches a
    wire, at an equal share of the weight ``m g / n``, by more than
    ``PLAUSIBLE["stretch"]`` (1 mm, a length's default uncertainty), or
    None.  Since session 17 the model carries the stretch on every wire
    count (``rig.lengths`` the unloaded lengths; the rest pose, the modes
    and the runs on the loaded wires, docs/design.md "stretch, session
    17"); EA's own uncertainty is budgeted since session 18 (``invert``'s
    and a sweep point's ``stiffness`` term, default 10 %): the warning says
    how far a 10 % error in EA moves the loaded lengths and the periods.  (Session 16's warning, that 2 and 3 wires
    ignored EA and 4 and 5 wires ran on unstretched wires, is void.)"""
    if scene.stiffness is None:
        return None
    share = scene.mass * scene.gravity / scene.n_wires
    dl = share * np.asarray(scene.lengths, float) / np.asarray(scene.stiffness, float)  # m
    i = int(np.argmax(dl))
    if not dl[i] > PLAUSIBLE["stretch"]:
        return None
    strain = dl[i] / scene.lengths[i]
    return (f"rig.stiffness: at an equal share of the weight ({share:.4g} N) wire {i + 1} stretches by "
            f"{1e3 * dl[i]:.3g} mm (strain {strain:.2g}), more than a length's {1e3 * PLAUSIBLE['stretch']:g} mm "
            "default uncertainty; rig.lengths are read as the unloaded lengths and the model hangs the body on the "
            "loaded wires, and EA's uncertainty is budgeted (uncertainty key stiffness, default 0.1): a 10 % error in "
            f"it moves each loaded length by {0.1e3 * dl[i]:.2g} mm and the periods by ~{0.1 * strain / 2:.2g} of "
            "themselves")
