"""The multi-hanging plan at a study's recommended (``sweep``) or planned
(``plan``) point: the plan, the warning a deferred mode-separation guard
gives, and the measurements file ``invert --measurements`` reads.

Units as :mod:`bifilar.studies.hangings` gives them: periods s, sigmas
kg m^2 (m for a CoM coordinate), the separation relative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: the multi-hanging plan's sigmas are linear (no second-order check, :mod:`bifilar.studies.hangings`): a caution
#: where the point's own sigma of a component the plan predicts is more than this factor above its linear one
#: (the 10 % by which the sweep's input-factor bound decides a term matters, README "sweep")
LINEAR_CAUTION = 1.1


def linear_caution(point: dict, plan_doc: dict, what: str) -> str | None:
    """One line (``what``: e.g. ``the recommended point``) where the
    multi-hanging plan ``plan_doc`` (its ``accuracy``, relative sigmas)
    predicts a component whose own sigma at ``point`` (a full sweep point:
    its ``shares`` give the ``second_order`` part of the variance, the
    part no input's linear term makes) exceeds its linear sigma by more
    than :data:`LINEAR_CAUTION`: the plan's sigmas are linear, so its
    figures can be as optimistic (c04, a 30 g part with its CoM 5 mm below
    the attachments: Izz +- 25.1 % at the point, 3.34 % linear, and the
    plan's 3.34 %; docs/design.md, "rank26, session 26").  The component
    with the largest factor is named; None where none exceeds it."""
    worst = None
    for c, e in (point.get("components") or {}).items():
        s, rel = (e.get("shares") or {}).get("second_order"), e.get("rel_sigma")
        if c not in (plan_doc.get("accuracy") or {}) or not s or rel is None or not math.isfinite(rel):
            continue
        lin = rel * math.sqrt(max(1.0 - s, 0.0))
        f = rel / lin if lin > 0 else math.inf
        if f > LINEAR_CAUTION and (worst is None or f > worst[1]):
            worst = (c, f, rel, lin, s)
    if worst is None:
        return None
    c, f, rel, lin, s = worst
    # all of the variance second order: no linear sigma to compare with, so no factor ("infx") is printed
    versus = (f"against +- {100 * lin:.3g} % linear ({f:.3g}x)" if math.isfinite(f)
              else "where the linear terms give none")
    return (f"{what}: the multi-hanging plan's sigmas are linear (no second-order check), but here second-order "
            f"terms (inputs whose effect is not linear over their uncertainty, e.g. a shallow CoM) make "
            f"{100 * s:.3g} % of {c}'s variance in the planned hanging: +- {100 * rel:.3g} % {versus}; "
            f"the plan's figures can be as optimistic")


@dataclass
class PointHangings:
    """The multi-hanging plan ``plan`` (a :class:`~bifilar.studies.hangings.HangingPlan`)
    at a study's point, ``document`` its JSON (``multi_hanging``), the
    ``warnings`` it gives (one line each, no ``warning:`` prefix), the
    constraints ``cons`` it was made under, the base config's path
    ``source`` and the command ``who`` that made it (``bifilar sweep``)."""

    plan: object
    document: dict
    warnings: list[str]
    cons: object
    source: str
    who: str

    def measurements_file(self, name: str) -> tuple[dict, list[str], list[str]]:
        """(document, notes, header) of the plan's measurements file, to be
        written as ``name`` (its header says how to use it): the document
        :func:`~bifilar.studies.hangings.measurements_document` gives, the
        notes on periods that could not be run over invert's cycles (warn
        them: they are also in the header) and the header's lines."""
        from .hangings import measurements_document

        ms = self.cons.min_separation
        sep = ([f"time these modes only: each is at least {100 * ms:g} % (--min-separation) from "
                "every other mode of its hanging"] if ms else [])
        notes: list = []  # periods that could not be run over invert's cycles: said, and kept in the file
        mdoc = measurements_document(self.plan, notes=notes)
        header = [f"measurements planned by {self.who} for {self.source}", *sep,
                  "the periods are the PLANNED ones (the config's inertia): replace them with the "
                  "measured periods", *notes, f"then: bifilar invert --measurements {name}"]
        return mdoc, notes, header


def hangings_at_point(cfg: dict, source: str, params: dict, settings, cons, reaction, sensor, who: str,
                      deferred: dict | None = None, point: dict | None = None) -> PointHangings:
    """The multi-hanging plan at the point ``params`` ({name: value, SI})
    of the base config ``cfg`` (read from ``source``) for
    ``settings.components`` under the constraints ``cons``
    (:func:`~bifilar.studies.hangings.plan_hangings`; ``reaction`` s, a
    stopwatch trial's std; ``sensor`` (noise, rate Hz) or None); ``who``
    the command (``bifilar plan`` names its point the planned one, else the
    recommended one).  ``deferred``: the point (dict), when the search left
    ``--min-separation`` to this plan (``separation_guard``
    ``multi_hanging``): a plan that cannot meet it is refused
    (:class:`~bifilar.errors.InputError`, :func:`~bifilar.studies.hangings.check_separated`),
    and the warning names the point's own modes not to time.  ``point``:
    the point (dict) the plan is made at, for :func:`linear_caution`."""
    from .hangings import check_separated, close_modes_warning, plan_hangings

    hp = plan_hangings(cfg, source, params, settings, list(settings.components), cons.min_separation, reaction, sensor)
    warnings = []
    what = "the planned point" if who == "bifilar plan" else "the recommended point"
    if deferred is not None:
        check_separated(hp)
        warnings = [close_modes_warning(deferred, cons.min_separation, what)]
    doc = hp.to_json()
    if point is not None and (w := linear_caution(point, doc, what)) is not None:
        warnings.append(w)
    return PointHangings(hp, doc, warnings, cons, source, who)
