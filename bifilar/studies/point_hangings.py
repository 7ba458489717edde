"""The multi-hanging plan at a study's recommended (``sweep``) or planned
(``plan``) point: the plan, the warning a deferred mode-separation guard
gives, and the measurements file ``invert --measurements`` reads.

Units as :mod:`bifilar.studies.hangings` gives them: periods s, sigmas
kg m^2 (m for a CoM coordinate), the separation relative.
"""

from __future__ import annotations

from dataclasses import dataclass


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
                      deferred: dict | None = None) -> PointHangings:
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
    and the warning names the point's own modes not to time."""
    from .hangings import check_separated, close_modes_warning, plan_hangings

    hp = plan_hangings(cfg, source, params, settings, list(settings.components), cons.min_separation, reaction, sensor)
    warnings = []
    if deferred is not None:
        check_separated(hp)
        warnings = [close_modes_warning(deferred, cons.min_separation,
                                        "the planned point" if who == "bifilar plan" else "the recommended point")]
    return PointHangings(hp, hp.to_json(), warnings, cons, source, who)
