"""What the user states beside the periods, applied to a measurement set:
the assumed timing uncertainty a period without its own std gets, and the
release amplitudes (``invert``'s ``--period``, ``--timed`` and
``--amplitude``; the same rules for any caller).

SI units: periods and their stds s, amplitudes rad or m (the mode's
dominant coordinate, times its normalised shape, as for ``simulate``).
"""

from __future__ import annotations

from ..errors import InputError
from . import period_specs as ps


def check_assumed_std(T: float, s: float, what: str, key: str, flags: dict, unc: dict) -> None:
    """Check the period std ``s`` (s) that the stated uncertainty ``key``
    (``timing``, ``trial_time``) gave the period ``T`` (s) of ``what`` (the
    option and its label, e.g. ``--period torsion``), naming where it was
    stated: ``--uncertainty`` (``key`` in ``flags``, the command line's
    overrides) or ``uncertainty.KEY`` (in ``unc``, the config's block
    merged with them); raises :class:`~bifilar.errors.InputError` as
    :func:`~bifilar.estimation.period_specs.check_assumed_sigma` does.  The
    built-in defaults are not checked here: for an absurd period the
    inversion's refusal (no physical inertia gives it, a unit slip?) says
    more."""
    if key in flags or key in unc:
        ps.check_assumed_sigma(T, s, what, "--uncertainty" if key in flags else f"uncertainty.{key}")


def apply_amplitudes(ms, amps: dict, fld: str = "--amplitude") -> None:
    """State the release amplitudes ``amps`` ({mode label or None (every
    mode): (A, std or None)}, as :func:`~bifilar.estimation.period_specs.parse_amplitudes`
    gives them; rad or m) on the measurements of ``ms`` (a
    :class:`~bifilar.estimation.measurements.MeasurementSet`), in place:
    a labelled amplitude replaces any the measurement has, one for every
    mode only fills those that have none.  A label no measurement has is
    refused (:class:`~bifilar.errors.InputError` naming ``fld``)."""
    labels = {m.label for m in ms.measurements}
    for lab in amps:
        if lab is not None and lab not in labels:
            raise InputError(fld, f"no measurement of mode '{lab}' (measured: {', '.join(sorted(labels))})")
    for m in ms.measurements:
        spec = amps.get(m.label, amps.get(None))
        if spec is not None and (m.amplitude is None or m.label in amps):
            m.state_amplitude(*spec)
