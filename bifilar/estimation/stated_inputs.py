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


def measurement_set(config, measurements, solve_for=(), unc: dict | None = None, rig: str | None = None,
                    periods=(), timed=(), signals=(), amps: dict | None = None, cycles: float | None = None,
                    signal_options: dict | None = None):
    """The :class:`~bifilar.estimation.measurements.MeasurementSet` that
    ``invert`` inverts: the measurements file ``measurements`` (its config
    replaced by ``config`` where given), else the one hanging of the scene
    config ``config`` (path; its ``uncertainty:`` block below the
    overrides), with the unknowns ``solve_for`` (component names), the
    uncertainty overrides ``unc`` ({key: value}, as
    :func:`~bifilar.estimation.period_specs.parse_uncertainty_overrides`
    gives them), the rig model ``rig`` (``shared``, ``separate`` or None:
    the file's), and the measurements stated beside it: ``periods``
    [(label, T s, std s or None: the stated ``timing``)], ``timed``
    [(label, cycles, [total times s])], ``signals`` [(label, path)], read
    with ``signal_options`` (``column``, ``sample_rate`` Hz, ``model``,
    ``quantity``, ``scale``: :func:`~bifilar.estimation.measurements.signal_measurement`'s),
    and the release amplitudes ``amps`` (:func:`apply_amplitudes`).
    ``cycles``: the cycles a ``--period``'s amplitude run simulates
    (default :data:`~bifilar.estimation.measurements.DEFAULT_CYCLES`).
    Raises :class:`~bifilar.errors.InputError` naming the option when a
    std cannot be used or there is no measurement at all."""
    import numpy as np

    from . import measurements as mm

    unc = dict(unc or {})
    if measurements is not None:
        ms = mm.load_measurements(measurements, config_override=config, unknown=tuple(solve_for), overrides=unc)
    else:
        from ..config import load_scene

        scene = load_scene(config, unknown=tuple(solve_for))
        # the config's uncertainty block (what sweep/plan budgeted) below --uncertainty
        ms = mm.MeasurementSet([mm.Hanging("reference", scene, np.eye(3), str(config))], [], source=str(config),
                               uncertainty=mm.config_uncertainty(config))
    if rig is not None:
        ms.rig = rig
    ms.uncertainty = {**ms.uncertainty, **unc}
    for label, T, s in periods:
        given = s is not None
        if not given:  # the assumed timing: checked as a stated +-SIGMA is, naming where it came from
            s = mm.default_uncertainty(ms.uncertainty)["timing"]
            check_assumed_std(T, s, f"--period {label}", "timing", unc, ms.uncertainty)
        ms.measurements.append(mm.Measurement(label, T, s, "period", "--period",
                                              cycles=min(cycles or mm.DEFAULT_CYCLES, mm.MAX_SIM_CYCLES),
                                              std_given=given))
    for label, n, times in timed:
        T, s, det = ps.period_from_trials(n, times, None, ms.uncertainty)
        check_assumed_std(T, s, f"--timed {label}", "trial_time", unc, ms.uncertainty)
        ms.measurements.append(mm.Measurement(label, T, s, "timed", "--timed", cycles=min(n, mm.MAX_SIM_CYCLES),
                                              details=det))
    for label, path in signals:
        ms.measurements.append(mm.signal_measurement(label, path, "--signal", **(signal_options or {})))
    if not ms.measurements:
        raise InputError("--period", "no measurement: give --period, --timed or --signal (or --measurements FILE)")
    apply_amplitudes(ms, amps or {})
    return ms
