"""Measured periods and the measurements YAML file of ``bifilar invert
--measurements``: the measurement, hanging and measurement-set records and
the file reader (the parsers of command-line specs, timed trials and
recorded signals it shares with the CLI are in
:mod:`bifilar.estimation.period_specs`).

SI units: periods and times in s, amplitudes in the unit of the mode's
dominant coordinate (rad for rotations, m for swings), as for
``bifilar simulate --amplitude``.

Measurements file (YAML)
------------------------
One hanging::

    config: thesis_lin1_torsion.yaml   # path relative to this file, or an inline config mapping
    solve_for: [Izz]                   # optional; inertia components and/or com.x, com.y, com.z
    method: auto                       # optional: auto, small-angle, thesis, linear, nonlinear
    monte_carlo: 200                   # optional: number of Monte Carlo draws (0 = off)
    seed: 1                            # optional
    rig: shared                        # optional: shared (default) or separate (several hangings,
                                       # bifilar.estimation.rig: entries equal in their configs measured once)
    uncertainty:                       # optional overrides (units: see uncertainty.UNCERTAINTY_KEYS)
      length: 0.001
    measurements:
      - mode: torsion                  # mode label or 1-based index
        period: 2.6823 +- 0.0004       # s; or period: 2.6823 with std: 0.0004
        amplitude: 0.0393              # optional, rad or m (+- sigma allowed)
      - mode: swing-y
        cycles: 10                     # timed trials: N cycles in each total time
        times: [29.55, 29.57, 29.56]   # s
        time_std: 0.05                 # optional, s per trial (default: the trials' scatter)
      - mode: pitch
        signal: pitch.csv              # a recording (CSV with t/time, or .mat)
        column: angle                  # optional, as for ``bifilar period``
        sample_rate: 240               # optional, Hz
        quantity: angle                # angle | rate | other (amplitude from the fit if angle/rate)
        scale: 0.0174533               # optional: multiplies the signal to rad (or m)
        model: auto                    # viscous | quadratic | two_mode | three_mode | auto

Several hangings (the body re-hung in other orientations)::

    hangings:
      - name: flat
        config: flat.yaml
        measurements: [...]
      - name: on-edge
        config: edge.yaml
        rotation: {axis: [1, 0, 0], angle_deg: 90}
        measurements: [...]

``rotation`` maps components in the reference body frame (the first
hanging's) to this hanging's body frame: ``v_h = R v_ref``, so the inertia
tensor in the hanging's frame is ``R I_ref R^T``.  It is a 3x3 matrix, the
word ``identity``, ``{axis: [x, y, z], angle_deg: a}`` (or ``angle`` in rad),
``{rotvec_deg: [...]}`` / ``{rotvec: [...]}``, or a list of elementary
rotations about the fixed axes applied in order, e.g. ``[{x: 90}, {z: 45}]``
(degrees).  The inertia of every hanging's config after the first is
ignored: it follows from the reference inertia and the rotation.  The body
mass and gravity must agree with the first hanging's (refused otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigErrors, InputError
from .sensitivity import INERTIA_COMPONENTS
from .period_specs import (MIN_RELATIVE_SIGMA, check_assumed_sigma, check_period_sigma, parse_times, parse_uncertainty_overrides,
                           parse_value_sigma, period_from_signal, period_from_trials)
from .uncertainty import default_uncertainty

#: the rungs of the ladder of estimators, simplest first (see invert.py)
METHODS = ("small-angle", "thesis", "linear", "nonlinear")
METHOD_NAMES = ("auto",) + METHODS
COM_UNKNOWNS = ("com.x", "com.y", "com.z")
#: what --solve-for accepts: inertia components (body axes) and the CoM position
SOLVABLE = INERTIA_COMPONENTS + COM_UNKNOWNS
#: cycles simulated by the nonlinear method when a measurement does not say
DEFAULT_CYCLES = 10
#: the nonlinear method simulates at most this many cycles per measurement
MAX_SIM_CYCLES = 20


@dataclass
class Measurement:
    """One measured period of one mode of one hanging.

    label : mode label or 1-based index (as given).
    period : s, the undamped period the model must reproduce (a signal's
        damped period divided by ``1/sqrt(1 - zeta^2)``).
    std : s, its standard uncertainty.
    source : ``period``, ``timed`` or ``signal``.
    field : the command-line option or file field it came from (for errors).
    amplitude, amplitude_std : rad or m (None when unknown).
    cycles : cycles timed (length of the nonlinear simulation).
    observed_period : s, before the damping correction.
    damping_ratio : from a signal fit (None otherwise).
    """

    label: str
    period: float
    std: float
    source: str
    field: str
    hanging: int = 0
    amplitude: float | None = None
    amplitude_std: float | None = None
    cycles: float = DEFAULT_CYCLES
    observed_period: float | None = None
    damping_ratio: float | None = None
    std_given: bool = True
    details: dict = field(default_factory=dict)
    fit: Any = field(default=None, repr=False)
    signal: Any = field(default=None, repr=False)  # (t, y) of a recording, for plots
    #: a recording's second mode, started by its release, that the nonlinear model is released with
    #: (:class:`~bifilar.estimation.signal_swing.Secondary`; set by invert), or None
    secondary: Any = field(default=None, repr=False)
    #: the other modes a recording's release may have started unseen, each at the stated bound
    #: (:class:`~bifilar.estimation.signal_swing.Hidden`, their shifts set by the nonlinear solve; set by invert)
    hidden: list = field(default_factory=list, repr=False)

    @property
    def dof(self) -> float:
        """Degrees of freedom of ``std``: ``n - 1`` for a period from ``n >=
        2`` timed trials whose std is the trials' own (their scatter, or the
        reaction-time floor standing in for it; :func:`period_from_trials`),
        a recording whose std is the spread of its re-quantised copies (their
        number, with the damping term as normal: ``details["dof"]``);
        infinite (``math.inf``) otherwise: a stated ``time_std``, one trial,
        a ``--period`` with its sigma, any other fitted recording."""
        nu = self.details.get("dof") if self.source in ("timed", "signal") else None
        return float(nu) if nu is not None else math.inf

    @property
    def fundamental(self) -> bool:
        """Whether the period and amplitude are a fitted record's: its
        fundamental's period and amplitude (the other oscillations fitted
        with it), which the nonlinear model must then reproduce
        (:func:`~bifilar.estimation.solve.amplitude_factor`); a period timed
        between crossings, and a stated release amplitude, otherwise."""
        return self.source == "signal"

    def state_amplitude(self, amplitude: float | None, amplitude_std: float | None = None) -> None:
        """Set the amplitude a user states (rad or m, the mode's dominant
        coordinate; None: unknown) and its std.  For a recording it is the
        amplitude at the start of the fit window: the release, when the
        record holds it (a leading rest is left out).  A decaying record's
        fitted period refers to a smaller amplitude, ``details["decay"]``
        times that one (:func:`~bifilar.estimation.signal_result.period_amplitude`),
        which is what the model is run at; the std scales with it."""
        d = self.details.get("decay") if self.source == "signal" else None
        if amplitude is None or d is None:
            self.amplitude, self.amplitude_std = amplitude, amplitude_std
            if self.source == "signal" and amplitude is not None:
                self.details["amplitude_source"] = "given"
            return
        self.amplitude = amplitude * d
        self.amplitude_std = None if amplitude_std is None else amplitude_std * d
        self.details["amplitude_source"] = (f"given at the record's start ({amplitude:.6g}), times its decay "
                                            f"{d:.4g}: the amplitude the fitted period refers to")

    def to_json(self) -> dict:
        d = {"mode": self.label, "hanging": self.hanging, "source": self.source, "period": self.period,
             "std": self.std, "std_given": self.std_given, "amplitude": self.amplitude,
             "amplitude_std": self.amplitude_std, "cycles": self.cycles}
        if self.observed_period is not None:
            d["observed_period"] = self.observed_period
        if self.damping_ratio is not None:
            d["damping_ratio"] = self.damping_ratio
        d.update(self.details)
        if self.source == "timed" and d["cycles"] != self.cycles:  # a stopwatch's trials span more cycles than the model simulates
            d["cycles_timed"], d["cycles"] = d["cycles"], self.cycles
        if self.secondary is not None:
            d["secondary"] = self.secondary.to_json()
        if self.hidden:
            d["hidden_second_modes"] = [h.to_json() for h in self.hidden]
        return d


@dataclass
class Hanging:
    """One way of hanging the body: its scene and the rotation ``R`` from
    the reference body frame to this scene's body frame (``v_h = R v_ref``)."""

    name: str
    scene: Any
    rotation: np.ndarray
    source: str = ""


@dataclass
class MeasurementSet:
    """Everything ``bifilar invert`` needs besides the options."""

    hangings: list
    measurements: list
    solve_for: list | None = None
    method: str = "auto"
    uncertainty: dict = field(default_factory=dict)
    monte_carlo: int = 0
    seed: int | None = None
    source: str = ""
    notes: list = field(default_factory=list)
    #: how the hangings' wire lengths, anchors and attachments were measured:
    #: ``shared`` (entries equal in several configs measured once) or ``separate``
    #: (:mod:`bifilar.estimation.rig`)
    rig: str = "shared"



def signal_measurement(label: str, path, fld: str, *, amplitude=None, amplitude_std=None, hanging: int = 0,
                       **kw) -> Measurement:
    """A :class:`Measurement` from a recording (see :func:`period_from_signal`)."""
    r = period_from_signal(path, fld=fld, **kw)
    fit = r["fit"]
    meta = {k: v for k, v in r["meta"].items() if k in ("path", "column", "n_samples", "sample_rate", "duration",
                                                         "time_source", "time_base", "warnings")}
    meta["path"] = str(meta.get("path", path))
    det = {"signal": meta, "fit": {"model": fit.model, "period": fit.period, "std": fit.std,
                                    "damping_ratio": fit.damping_ratio, "r_squared": fit.r_squared,
                                    "window": [fit.t0, fit.t1], "notes": list(fit.notes)},
           "amplitude_source": "fit (the amplitude the fitted period refers to)" if r["amplitude"] is not None else None,
           "decay": r["decay"], "quantity": kw.get("quantity", "other")}
    for key in ("time_base_warning", "start_warning"):
        if r.get(key):
            det[key] = r[key]
    std = r["std"]
    if r.get("dof") is not None:
        det["dof"] = r["dof"]
    if std < MIN_RELATIVE_SIGMA * r["period"]:  # a noise-free record: below what the model's period resolves
        std = MIN_RELATIVE_SIGMA * r["period"]
        det["std_floor"] = (f"the fitted std {r['std']:.3g} s is below {MIN_RELATIVE_SIGMA:g} of the period, "
                            f"which the model does not resolve; {std:.3g} s is used")
        det.pop("dof", None)  # the floor is a stated sigma
    m = Measurement(label, r["period"], std, "signal", fld, hanging=hanging, amplitude=r["amplitude"],
                    cycles=min(r["cycles"], MAX_SIM_CYCLES), observed_period=r["observed_period"],
                    damping_ratio=r["damping_ratio"], std_given=True, details=det, fit=fit, signal=(r["t"], r["y"]))
    if amplitude is not None:
        m.state_amplitude(amplitude, amplitude_std)
    return m


# ---------------------------------------------------------------------------
# rotations
# ---------------------------------------------------------------------------

def parse_rotation(spec: Any, fld: str) -> np.ndarray:
    """A rotation spec (module docstring) -> proper orthogonal 3x3 matrix."""
    from ..rotations import rotvec_to_matrix

    if spec is None or (isinstance(spec, str) and spec.strip().lower() == "identity"):
        return np.eye(3)
    if isinstance(spec, dict):
        keys = set(spec)
        if "axis" in keys:
            extra = keys - {"axis", "angle_deg", "angle"}
            if extra or len(keys & {"angle_deg", "angle"}) != 1:
                raise InputError(fld, "axis-angle form is {axis: [x, y, z], angle_deg: A} (or angle: A in rad)")
            ax = _vec3(spec["axis"], f"{fld}.axis")
            nrm = np.linalg.norm(ax)
            if nrm == 0:
                raise InputError(f"{fld}.axis", "must not be zero")
            ang = _num(spec.get("angle_deg", spec.get("angle")), f"{fld}.angle")
            ang = math.radians(ang) if "angle_deg" in spec else ang
            return rotvec_to_matrix(ax / nrm * ang)
        if keys == {"rotvec_deg"}:
            return rotvec_to_matrix(np.radians(_vec3(spec["rotvec_deg"], f"{fld}.rotvec_deg")))
        if keys == {"rotvec"}:
            return rotvec_to_matrix(_vec3(spec["rotvec"], f"{fld}.rotvec"))
        raise InputError(fld, f"unknown rotation form {sorted(keys)}; use axis/angle_deg, rotvec_deg, a matrix or a list")
    if isinstance(spec, (list, tuple)) and spec and all(isinstance(e, dict) for e in spec):
        R = np.eye(3)
        for i, e in enumerate(spec):
            if len(e) != 1 or next(iter(e)) not in ("x", "y", "z"):
                raise InputError(f"{fld}.{i}", "each elementary rotation is {x: DEG}, {y: DEG} or {z: DEG}")
            (axn, deg), = e.items()
            v = np.zeros(3)
            v["xyz".index(axn)] = math.radians(_num(deg, f"{fld}.{i}.{axn}"))
            R = rotvec_to_matrix(v) @ R
        return R
    if isinstance(spec, (list, tuple)) and len(spec) == 3:
        try:
            R = np.array(spec, dtype=float)
        except (TypeError, ValueError):
            raise InputError(fld, "a rotation matrix must be 3 rows of 3 numbers") from None
        if R.shape != (3, 3) or not np.all(np.isfinite(R)):
            raise InputError(fld, "a rotation matrix must be 3 rows of 3 finite numbers")
        err = float(np.max(np.abs(R @ R.T - np.eye(3))))
        if err > 1e-6 or np.linalg.det(R) < 0:
            raise InputError(fld, f"not a rotation (R R^T - 1 = {err:.2g}, det {np.linalg.det(R):.3g}); "
                                  "give a proper orthogonal matrix")
        U, _, Vt = np.linalg.svd(R)
        return U @ Vt
    raise InputError(fld, "a rotation is 'identity', a 3x3 matrix, {axis, angle_deg}, {rotvec_deg} or a list like [{x: 90}]")


def _num(v, fld) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise InputError(fld, f"must be a finite number, got {v!r}")
    return float(v)


def _vec3(v, fld) -> np.ndarray:
    if not isinstance(v, (list, tuple)) or len(v) != 3:
        raise InputError(fld, f"must be a list of 3 numbers, got {v!r}")
    return np.array([_num(x, f"{fld}.{i}") for i, x in enumerate(v)])


# ---------------------------------------------------------------------------
# the measurements file
# ---------------------------------------------------------------------------

_TOP = {"name", "description", "config", "measurements", "hangings", "solve_for", "method", "monte_carlo",
        "seed", "uncertainty", "rig"}
_HANG = {"name", "config", "rotation", "measurements", "description"}
_MEAS = {"mode", "period", "std", "cycles", "times", "time_std", "signal", "column", "sample_rate", "quantity",
         "scale", "model", "t_start", "t_stop", "trim", "amplitude", "amplitude_std", "note"}


def config_uncertainty(path) -> dict:
    """The ``uncertainty:`` block of the scene config at ``path`` (the block
    ``sweep`` and ``plan`` budget and ``--write-config`` writes), checked as
    ``--uncertainty`` is: {key: value} in the units of
    :data:`~bifilar.estimation.uncertainty.UNCERTAINTY_KEYS` (``timing`` s:
    a period given without ``+-SIGMA``; ``length``/``position``/``com`` m;
    ``mass``/``gravity``/``amplitude`` relative); {} without a block.  Bad
    values exit 2 naming ``uncertainty.KEY``."""
    from ..config import read_yaml

    doc = read_yaml(path)
    block = doc.get("uncertainty") if isinstance(doc, dict) else None
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise InputError("uncertainty", "must be a mapping like {timing: 0.001, length: 0.001}")
    return parse_uncertainty_overrides(block, "uncertainty")


def load_measurements(path, config_override: str | None = None, unknown: tuple = (),
                      overrides: dict | None = None) -> MeasurementSet:
    """Read and validate a measurements file (module docstring); every
    problem is reported at once (:class:`~bifilar.errors.ConfigErrors`),
    fields named by their dotted path in the file.

    ``config_override``: a config path given on the command line, used when
    the file names none (a single-hanging file).  ``unknown``: components
    solved for (from the command line; the file's ``solve_for`` adds to
    them), whose config values are starting guesses only.  ``overrides``:
    the command line's ``--uncertainty`` values, above the file's block: a
    period without ``+-`` gets their ``timing``, timed trials their
    ``trial_time`` floor (the file's ``uncertainty`` keeps only the file's
    block; the caller merges the flags into it)."""
    from ..config import read_yaml

    p = Path(path)
    try:
        doc = read_yaml(p)
    except ConfigErrors as exc:
        raise ConfigErrors([InputError(f"--measurements {e.field}", e.message) for e in exc.errors]) from None
    except InputError as exc:
        raise InputError("--measurements", exc.message) from None
    errs: list[InputError] = []
    if not isinstance(doc, dict):
        raise InputError("--measurements", f"{p} must be a YAML mapping (see docs/invert.md)")
    for k in doc:
        if k not in _TOP:
            errs.append(InputError(str(k), f"unknown key; expected one of {', '.join(sorted(_TOP))}"))
    base = p.parent
    unc = {}
    if "uncertainty" in doc:
        try:
            if not isinstance(doc["uncertainty"], dict):
                raise InputError("uncertainty", "must be a mapping like {length: 0.001}")
            unc = parse_uncertainty_overrides(doc["uncertainty"], "uncertainty")
        except InputError as exc:
            errs.append(exc)
    ms = MeasurementSet([], [], source=str(p), uncertainty=unc)
    overrides = dict(overrides or {})
    src = {k: "--uncertainty" if k in overrides else f"uncertainty.{k}" for k in {**unc, **overrides}}
    unc = {**unc, **overrides}  # what the measurements below use
    if "method" in doc:
        if doc["method"] not in METHOD_NAMES:
            errs.append(InputError("method", f"must be one of {', '.join(METHOD_NAMES)}, got {doc['method']!r}"))
        else:
            ms.method = doc["method"]
    if "rig" in doc:
        from .rig import RIG_MODELS

        if doc["rig"] not in RIG_MODELS:
            errs.append(InputError("rig", f"must be one of {', '.join(RIG_MODELS)}, got {doc['rig']!r}"))
        else:
            ms.rig = doc["rig"]
    if "monte_carlo" in doc:
        v = doc["monte_carlo"]
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            errs.append(InputError("monte_carlo", f"must be a non-negative integer, got {v!r}"))
        else:
            ms.monte_carlo = v
    if "seed" in doc:
        v = doc["seed"]
        if isinstance(v, bool) or not isinstance(v, int):
            errs.append(InputError("seed", f"must be an integer, got {v!r}"))
        else:
            ms.seed = v
    if "solve_for" in doc:
        sf = doc["solve_for"]
        sf = [sf] if isinstance(sf, str) else sf
        if not isinstance(sf, list) or not sf:
            errs.append(InputError("solve_for", "must be a component or a list of them"))
        else:
            bad = [s for s in sf if s not in SOLVABLE]
            if bad:
                errs.append(InputError("solve_for", f"unknown {bad}; choose from {', '.join(SOLVABLE)}"))
            else:
                ms.solve_for = list(dict.fromkeys(sf))
    if "hangings" in doc:
        if "measurements" in doc or "config" in doc:
            errs.append(InputError("hangings", "give either config + measurements or hangings, not both"))
        if config_override is not None:
            errs.append(InputError("CONFIG", "the measurements file defines hangings with their own configs; "
                                             "drop CONFIG from the command line"))
        hs = doc["hangings"]
        if not isinstance(hs, list) or not hs:
            errs.append(InputError("hangings", "must be a non-empty list"))
            hs = []
        for i, h in enumerate(hs):
            fh = f"hangings.{i}"
            if not isinstance(h, dict):
                errs.append(InputError(fh, "must be a mapping with config and measurements"))
                continue
            for k in h:
                if k not in _HANG:
                    errs.append(InputError(f"{fh}.{k}", f"unknown key; expected one of {', '.join(sorted(_HANG))}"))
            _hanging(ms, h.get("config"), h.get("rotation"), h.get("name") or f"hanging {i + 1}",
                     h.get("measurements"), fh, base, errs, unc, src=src, unknown=tuple(unknown) + tuple(ms.solve_for or ()))
    else:
        cfg = doc.get("config")
        if cfg is None:
            cfg = config_override
            if cfg is None:
                errs.append(InputError("config", "missing: name the scene config (or give CONFIG on the command line)"))
        elif config_override is not None:
            errs.append(InputError("config", "the file names a config and so does the command line; give one"))
        if cfg is not None:
            _hanging(ms, cfg, None, doc.get("name") or "reference", doc.get("measurements", []), "", base, errs, unc, src=src,
                     cli_config=config_override is not None and doc.get("config") is None,
                     unknown=tuple(unknown) + tuple(ms.solve_for or ()))
    if errs:
        raise ConfigErrors(errs)
    return ms


def _hanging(ms: MeasurementSet, cfg, rot, name, meas, fh: str, base: Path, errs: list, unc: dict,
             cli_config: bool = False, unknown: tuple = (), src: dict | None = None) -> None:
    from ..config import load_scene, scene_from_dict

    pre = f"{fh}." if fh else ""
    scene = None
    try:
        if isinstance(cfg, dict):
            scene = scene_from_dict(cfg, source=f"{ms.source}:{pre}config", unknown=unknown)
        elif isinstance(cfg, str):
            cp = Path(cfg) if (cli_config or Path(cfg).is_absolute()) else base / cfg
            scene = load_scene(cp, unknown=unknown)
        else:
            errs.append(InputError(f"{pre}config", "must be a config file path or an inline config mapping"))
    except ConfigErrors as exc:
        errs.extend(InputError(f"{pre}config.{e.field}", e.message) for e in exc.errors)
    except InputError as exc:
        errs.append(InputError(f"{pre}config", exc.message))
    try:
        R = parse_rotation(rot, f"{pre}rotation")
    except InputError as exc:
        errs.append(exc)
        R = np.eye(3)
    h_index = len(ms.hangings)
    if scene is not None and ms.hangings:
        errs.extend(_same_body(ms.hangings[0], scene, f"{pre}config"))
    if scene is not None:
        ms.hangings.append(Hanging(str(name), scene, R, str(cfg) if isinstance(cfg, str) else "inline"))
    if meas is None:
        meas = []
    if not isinstance(meas, list):
        errs.append(InputError(f"{pre}measurements", "must be a list of measurements"))
        return
    if not meas:
        errs.append(InputError(f"{pre}measurements", "no measurements given"))
    for j, m in enumerate(meas):
        fm = f"{pre}measurements.{j}"
        try:
            mm = _measurement(m, fm, base, unc, src)
            mm.hanging = h_index
            ms.measurements.append(mm)
        except ConfigErrors as exc:
            errs.extend(exc.errors)
        except InputError as exc:
            errs.append(exc)


#: relative difference below which two hangings' masses (or gravities) are the same number
SAME_BODY_RTOL = 1e-9


def _same_body(ref: Hanging, scene, fld: str) -> list[InputError]:
    """Refusals of a hanging whose config gives another body mass (kg) or
    gravity (m/s^2) than the reference hanging ``ref``: every hanging is
    the same body on the same planet, and the joint fit uses each hanging's
    own values, so a typo in one config would bias the estimate silently.
    Equal within :data:`SAME_BODY_RTOL` (relative)."""
    out = []
    for key, what, unit, a, b in (("body.mass", "body mass", "kg", ref.scene.mass, scene.mass),
                                  ("gravity", "gravity", "m/s^2", ref.scene.gravity, scene.gravity)):
        if abs(a - b) > SAME_BODY_RTOL * max(abs(a), abs(b)):
            out.append(InputError(f"{fld}.{key}", f"{what} {b:.10g} {unit} differs from {a:.10g} {unit} of the "
                                  f"reference hanging '{ref.name}': every hanging is the same body on the same rig "
                                  "site; give the same value in each config"))
    return out


#: the keys that only one way of giving a measurement reads (the others: mode, amplitude, amplitude_std, note,
#: cycles); given with another way they would be ignored, e.g. ``time_std`` beside a ``period`` left the period
#: at the default 1 ms std however large the stated one (audit16)
_KIND_KEYS = {"period": {"std"}, "times": {"time_std"},
              "signal": {"column", "sample_rate", "quantity", "scale", "model", "t_start", "t_stop", "trim"}}


def _refuse_other_kinds_keys(m: dict, fm: str, kind: str) -> None:
    """Refuse (exit 2, naming the key) a key of measurement ``m`` that only
    another way of giving a measurement (``period``, ``times``, ``signal``)
    reads, instead of ignoring it silently."""
    for other, keys in _KIND_KEYS.items():
        for k in sorted(keys & set(m)) if other != kind else ():
            hint = {"std": "a stopwatch's trial std is time_std", "time_std": "a period's std is std (or period: T +- s)"}
            extra = f"; {hint[k]}" if k in hint and kind in ("period", "times") else ""
            raise InputError(f"{fm}.{k}", f"applies to a measurement given by {other} only; this one gives {kind}, "
                             f"which would ignore it{extra}")


def _measurement(m: Any, fm: str, base: Path, unc: dict, src: dict | None = None) -> Measurement:
    if not isinstance(m, dict):
        raise InputError(fm, "must be a mapping with mode and one of period, times, signal")
    bad = [InputError(f"{fm}.{k}", f"unknown key; expected one of {', '.join(sorted(_MEAS))}") for k in m if k not in _MEAS]
    if bad:
        raise ConfigErrors(bad)
    if "mode" not in m:
        raise InputError(f"{fm}.mode", "missing: the mode label (torsion, swing-x, ...) or its 1-based index")
    label = str(m["mode"])
    kinds = [k for k in ("period", "times", "signal") if k in m]
    if len(kinds) != 1:
        raise InputError(fm, "give exactly one of period, times (with cycles) or signal")
    _refuse_other_kinds_keys(m, fm, kinds[0])
    amp = amp_s = None
    if "amplitude" in m:
        amp, amp_s = parse_value_sigma(m["amplitude"], f"{fm}.amplitude", "AMPLITUDE")
        if amp < 0:
            raise InputError(f"{fm}.amplitude", "must not be negative")
    if "amplitude_std" in m:
        amp_s = _num(m["amplitude_std"], f"{fm}.amplitude_std")
    cycles = m.get("cycles")
    if cycles is not None:
        cycles = _num(cycles, f"{fm}.cycles")
        if cycles <= 0:
            raise InputError(f"{fm}.cycles", "must be positive")
    kind = kinds[0]
    if kind == "period":
        T, s = parse_value_sigma(m["period"], f"{fm}.period", "SECONDS")
        if "std" in m:
            if s is not None:
                raise InputError(f"{fm}.std", "given twice (also after +- in period)")
            s = _num(m["std"], f"{fm}.std")
        if T <= 0:
            raise InputError(f"{fm}.period", f"must be positive, got {T:g}")
        if s is not None and s <= 0:
            raise InputError(f"{fm}.std", "must be positive")
        check_period_sigma(T, s, f"{fm}.period")
        given = s is not None
        if not given:  # the assumed timing, checked as a stated one, naming where it came from
            s = default_uncertainty(unc)["timing"]
            if "timing" in (src or {}):  # stated (not the built-in default, whose misfit the inversion names)
                check_assumed_sigma(T, s, f"{fm}.period", src["timing"])
        return Measurement(label, T, s, "period", f"{fm}.period", amplitude=amp, amplitude_std=amp_s,
                           cycles=min(cycles or DEFAULT_CYCLES, MAX_SIM_CYCLES), std_given=given)
    if kind == "times":
        if cycles is None:
            raise InputError(f"{fm}.cycles", "missing: how many cycles each time covers")
        times = parse_times(m["times"], f"{fm}.times")
        ts = _num(m["time_std"], f"{fm}.time_std") if "time_std" in m else None
        T, s, det = period_from_trials(cycles, times, ts, unc)
        if ts is not None or "trial_time" in (src or {}):
            check_assumed_sigma(T, s, f"{fm}.times", f"{fm}.time_std" if ts is not None else src["trial_time"])
        return Measurement(label, T, s, "timed", f"{fm}.times", amplitude=amp, amplitude_std=amp_s,
                           cycles=min(cycles, MAX_SIM_CYCLES), std_given=True, details=det)
    sig = m["signal"]
    if not isinstance(sig, str):
        raise InputError(f"{fm}.signal", "must be a file path")
    sp = Path(sig) if Path(sig).is_absolute() else base / sig
    kw = {k: m[k] for k in ("column", "sample_rate", "t_start", "t_stop", "trim") if k in m}
    if "column" in kw:
        kw["column"] = str(kw["column"])
    return signal_measurement(label, sp, f"{fm}.signal", amplitude=amp, amplitude_std=amp_s,
                              model=m.get("model", "auto"), quantity=m.get("quantity", "other"),
                              scale=m.get("scale"), **kw)
