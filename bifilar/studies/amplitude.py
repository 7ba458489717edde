"""What a recommended or planned point's sigmas assume about the release
amplitude, and what leaving it out of ``invert`` costs
(docs/design.md, "Closed-loop check of the planner").

The sweep's sigma of a component is the std ``bifilar invert --period
MODE=T+-s --amplitude A --solve-for C`` prints for the period ``T`` timed
at the sweep's amplitude ``A`` (its default 10 % relative uncertainty
budgeted: :func:`bifilar.studies.point_amplitude.stated_amplitude_budget`).  Told
nothing about the amplitude, ``invert`` budgets a release anywhere in 0 to
:data:`~bifilar.estimation.budget.DEFAULT_AMPLITUDE_RANGE_DEG` degrees
(a systematic term of its own) and prints a larger std: that std is
computed here, at the point's truth, for the advice (the Solar Boat's
Izz: 5.7 times the sigma).  That budget covers releases up to the range's
end only: where the planned amplitude lies beyond it (a rotation above 10
degrees), the period the body shows there is inverted as ``invert`` would
without ``--amplitude``, and the advice says how far that estimate is from
the truth and whether its 95 % interval holds it (a trifilar's torsion at
0.3 rad: 3 of its stds off, outside; docs/design.md, "Closed-loop audit of
the planner, session 11").  Units SI.
"""

from __future__ import annotations

import math

from ..errors import BifilarError
from ..estimation.budget import DEFAULT_AMPLITUDE_RANGE_DEG, default_amplitude_range
from ..estimation.uncertainty import DEFAULT_AMPLITUDE_REL


def amplitude_advice(base_cfg: dict, source: str, point: dict, settings) -> dict:
    """The amplitude advice of ``point`` (a valid sweep point dict): the
    amplitude its sigmas assume (``amplitude``, in the unit of ``invert
    --amplitude``: the mode's normalised shape, rad for a rotation),
    ``relative_std`` (invert's default), ``budgeted`` (False without a
    nonlinear run: the sigmas are then for a small amplitude, ``--amplitude
    0``), and per identifiable component with a sigma: the mode, the
    period to expect at that amplitude (s), the ``invert`` options that
    reproduce the sigma, the sigma (kg m^2) and ``std_unstated``, the std
    invert prints without ``--amplitude`` (kg m^2; None with
    ``unstated_note`` where it cannot be computed), with their ratio;
    ``unstated_beyond_range`` where the amplitude lies beyond the release
    range that std assumes (:func:`unstated_beyond_range`), else None; and
    ``text``, one plain sentence for the table."""
    from ..analysis.equilibrium import rest_pose
    from ..config import scene_from_dict
    from ..estimation.honest import honest_stds
    from .shorthands import apply_params

    A = float(point["amplitude"])
    comps = {c: e for c, e in point["components"].items()
             if e.get("identifiable") and e.get("sigma") is not None and math.isfinite(e["sigma"])}
    budgeted = bool(comps) and all((e.get("amplitude_budget") or {}).get("budgeted") for e in comps.values())
    out: dict = {"amplitude": A, "relative_std": DEFAULT_AMPLITUDE_REL, "budgeted": budgeted, "components": {}}
    scene = rest = None
    unc = dict(point.get("uncertainty") or settings.unc)
    for c, e in comps.items():
        T = e.get("nonlinear_period") if budgeted else None
        T = float(T) if T else float(e["period"])
        amp = A if budgeted else 0.0
        row = {"mode": e["mode"], "period": T, "sigma": e["sigma"],
               "invert_options": f"--period {e['mode']}={T:.6g}+-{unc['timing']:.3g} --amplitude {amp:g} --solve-for {c}",
               "std_unstated": None, "ratio_unstated": None}
        try:
            if scene is None:
                scene = scene_from_dict(apply_params(base_cfg, point["params"], source)[0], source, warn=False)
                rest = rest_pose(scene)
            sd = honest_stds(scene, [(c, e["mode"])], unc, unc["timing"], amplitude=None, rest=rest)[0]
            row.update(std_unstated=sd, ratio_unstated=sd / e["sigma"] if e["sigma"] else None)
            row["unstated_beyond_range"] = (unstated_beyond_range(scene, rest, c, e["mode"], e["value"], A, T, unc)
                                            if budgeted else None)
        except BifilarError as exc:
            row["unstated_note"] = f"not computed: {exc}"
        out["components"][c] = row
    ratios = [r["ratio_unstated"] for r in out["components"].values() if r["ratio_unstated"]]
    what = (f"the sigmas assume the period timed at amplitude {A:g} and that amplitude measured and given to "
            f"invert (--amplitude {A:g}; its {100 * DEFAULT_AMPLITUDE_REL:g} % uncertainty is in the sigma)"
            if budgeted else
            "the sigmas are for a small amplitude given to invert as --amplitude 0 (no nonlinear run here, so the "
            f"amplitude {A:g}'s own uncertainty is not in them: time at a small amplitude, or rerun with the "
            "nonlinear runs)")
    if ratios:
        lo, hi = f"{min(ratios):.2g}", f"{max(ratios):.2g}"
        what += (f"; without --amplitude invert assumes a release anywhere in 0-{DEFAULT_AMPLITUDE_RANGE_DEG:g} "
                 f"degrees and its std is {lo if lo == hi else lo + '-' + hi} times the sigma")
    beyond = {c: r["unstated_beyond_range"] for c, r in out["components"].items() if r.get("unstated_beyond_range")}
    if beyond:
        what += (f"; but a release at {A:g} lies beyond that range, and without --amplitude invert's estimate is off by "
                 + ", ".join(f"{c} {100 * b['error_rel']:+.2g} % ({b['error_in_std']:+.2g} of its std"
                             + ("" if b["interval_holds_truth"] else ", outside its 95 % interval") + ")"
                             for c, b in beyond.items())
                 + ": state the amplitude")
    out["text"] = what
    return out


def unstated_beyond_range(scene, rest, comp: str, mode: str, value: float, A: float, period: float,
                          unc: dict) -> dict | None:
    """What ``invert`` without ``--amplitude`` gives for ``comp`` (kg m^2)
    of ``scene`` when the period is timed at the amplitude ``A`` (the unit
    of ``--amplitude``), where ``A`` lies beyond the release range its
    unstated budget assumes (:func:`~bifilar.estimation.budget.default_amplitude_range`;
    None within it): ``period`` (s) is the one the body shows at ``A``,
    inverted with the truth's inputs and ``unc``.  Returns ``range_max``
    (the range's end), ``estimate``, ``std`` (kg m^2), ``error`` (estimate
    minus ``value``, kg m^2), ``error_rel`` (of ``value``),
    ``error_in_std`` and ``interval_holds_truth`` (``value`` inside the
    printed 95 % interval)."""
    import numpy as np

    from ..analysis.modes import linear_modes
    from ..estimation.invert import invert
    from ..estimation.measurements import Hanging, Measurement, MeasurementSet

    md = linear_modes(scene, rest).get(mode)
    A_max = default_amplitude_range(scene, md)
    if not abs(A) > A_max:
        return None
    ms = MeasurementSet([Hanging("reference", scene, np.eye(3))],
                        [Measurement(mode, float(period), float(unc["timing"]), "period", "--period")])
    ms.uncertainty = dict(unc)
    res = invert(ms, solve_for=[comp], ladder=False)
    est, sd = res.value(comp), res.sigma(comp)
    lo, hi = (float(x) for x in res.interval[0])
    err = est - float(value)
    return {"range_max": float(A_max), "estimate": float(est), "std": float(sd), "error": float(err),
            "error_rel": float(err / value) if value else None,
            "error_in_std": float(err / sd) if sd > 0 else None, "interval_holds_truth": bool(lo <= value <= hi)}
