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
Izz: 5.7 times the sigma).  Units SI.
"""

from __future__ import annotations

import math

from ..errors import BifilarError
from ..estimation.budget import DEFAULT_AMPLITUDE_RANGE_DEG
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
    ``unstated_note`` where it cannot be computed), with their ratio; and
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
    out["text"] = what
    return out
