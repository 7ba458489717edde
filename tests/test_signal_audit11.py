"""Signal audit, session 11 (docs/design.md, "End-to-end audit, session 11
(signals)"): records real labs produce that the earlier audits did not
write.  The truths are closed forms (a damped cosine), independent of the
fit under test.
"""

from __future__ import annotations

import math

import json

import numpy as np
import pytest

from bifilar.estimation.signal import fit_period

T_TRUE, ZETA, A, FS = 2.0, 0.0025, 0.1, 60.0


def _hand_release(seed, hold=1.5, cycles=30):
    """The experimenter twists the body to the release angle over ``hold``
    seconds (the recording already running), then lets go: a smooth ramp
    from rest to ``A``, then the free decay from ``A`` at rest.  Noise
    0.1 % of ``A``."""
    w_n = 2 * math.pi / T_TRUE / math.sqrt(1 - ZETA**2)  # the damped period is T_TRUE
    sg = ZETA * w_n
    wd = 2 * math.pi / T_TRUE
    t = np.arange(0.0, hold + cycles * T_TRUE, 1 / FS)
    tau = t - hold
    free = A * np.exp(-sg * tau) * (np.cos(wd * tau) + sg / wd * np.sin(wd * tau))  # released at rest
    ramp = A * (t / hold) ** 2
    y = np.where(t < hold, ramp, free)
    return t, y + 1e-3 * A * np.random.default_rng(seed).standard_normal(t.size)


def test_a_hand_release_transient_is_not_the_period():
    """The ramp before the release, fitted by ``auto`` as a second "mode"
    (damping ratio ~0.6, gone within a cycle), was larger at t0 than the
    oscillation and reported as the period: 2.77 +- 0.49 s on a 2.025 s
    torsion (the nonlinear quadcopter of the audit; ``invert`` then gave
    Izz 0.0250 +- 0.0091 for 0.022, exit 0).  The dominant mode is now the
    one with the larger RMS amplitude over the record.  The true period
    must lie within 3 of its stds, and that std must be one of a clean
    30-cycle record (well under 0.1 % of the period), over 3 noise draws."""
    for seed in range(3):
        t, y = _hand_release(seed)
        fit = fit_period(t, y, "auto")
        assert fit.std < 1e-3 * T_TRUE, (seed, fit.model, fit.period, fit.std)
        assert abs(fit.period - T_TRUE) < 3 * fit.std, (seed, fit.model, fit.period, fit.std)


# --------------------------------------------------------------------------- a slender boom at its triangle limit

BOOM = """name: slender boom hung along its length
gravity: 9.81
body:
  mass: 5.0
  inertia: {principal: [0.004, 3.75, 3.75]}
rig:
  anchors: [[-0.3, 0.0, 1.5], [0.3, 0.0, 1.5]]
  attachments: [[-0.3, 0.0, 0.03], [0.3, 0.0, 0.03]]
  lengths: [1.5, 1.5]
"""
EXACT = ["--uncertainty", "length=0", "--uncertainty", "position=0", "--uncertainty", "mass=0",
         "--uncertainty", "com=0"]


def _invert_boom(tmp_path, period):
    from click.testing import CliRunner

    from bifilar.cli import main

    cfg = tmp_path / "boom.yaml"
    cfg.write_text(BOOM)
    r = CliRunner().invoke(main, ["invert", str(cfg), "--period", f"torsion={period}+-0.00015", "--amplitude", "0.2",
                                  *EXACT, "--json"])
    return r


def test_an_edge_answer_counts_the_stated_amplitudes_uncertainty(tmp_path):
    """A slender boom (Ixx 0.004, Iyy = Izz = 3.75 kg m^2) has Izz within
    0.004 of both triangle limits, so a torsion period a little short puts
    it beyond the lower one.  Released at 0.2 rad, the amplitude's default
    10 % moves the model period by ~3.2e-3 s (the budget's std of Izz,
    3.4e-3 kg m^2, is nearly all of it), 20 times a camera record's timing
    std (1.5e-4 s).  The model period at the limit is 7.1044 s; a period
    3.4e-3 s short of it (about one combined sigma) was refused ("no
    physical Izz gives a period of ..."; the audit's camera records of the
    boom released 1-3 amplitude stds off their stated value with inputs
    exact: 33 of 100 refused) because the edge check counted timing and the
    inputs, not the amplitude.  Now it is answered at the limit; a period
    10.4e-3 s short (3.2 combined sigma) is still refused."""
    r = _invert_boom(tmp_path, 7.1010)
    assert r.exit_code == 0, r.output
    izz = json.loads(r.stdout)["inertia"]["Izz"]
    assert izz["value"] == pytest.approx(3.746, abs=1e-3)  # the lower triangle limit (with its margin)
    assert izz["interval_clipped"] == "triangle"
    r = _invert_boom(tmp_path, 7.0940)
    assert r.exit_code == 2, r.output
    assert "no physical Izz" in r.output


# --------------------------------------------------------------------------- a noisy decaying chirp


def _chirp(seed, noise, T0=2.0, kappa=1.2e-3, Q=200.0, cycles=30, fs=200.0):
    """A free decay whose frequency follows its amplitude, ``omega = W0 (1 -
    kappa (A / A0)^2)`` (a torsion released at ~0.1 rad), white noise
    ``noise`` times the release amplitude; returns t, y and the true period
    at amplitude ``a`` (in units of the release)."""
    w0 = 2 * math.pi / T0
    g = w0 / (2 * Q)
    t = np.arange(0.0, cycles * T0, 1 / fs) + np.random.default_rng(seed).uniform(0, 1 / fs)
    a = np.exp(-g * t)
    ph = w0 * t - w0 * kappa * (1 - np.exp(-2 * g * t)) / (2 * g)  # the phase, integrated exactly
    y = a * np.cos(ph + 0.3) + noise * np.random.default_rng(seed + 100).standard_normal(t.size)
    return t, y, lambda amp: 2 * math.pi / (w0 * (1 - kappa * amp ** 2))


def test_a_noisy_chirps_amplitude_law_is_judged_by_its_frequency_shift():
    """The law's shift was judged by ``beta`` alone, whose std the ``A^4``
    term inflates many times (``u`` and ``u^2`` are nearly collinear over a
    record decaying to u ~ 0.4): at 1 % noise the audit's quadcopter gyro
    record had beta -0.0020 +- 0.0015 rad/s, "not resolved", and kept the
    halves' std, 35 times the period's error (z sd 0.028 over 100 draws).
    Judged by the frequency shift over the record the law is resolved; its
    period at ``amplitude_period`` must lie within 3 of its stds of the
    truth and that std must be under a fifth of the halves' (8 draws)."""
    zs = []
    for seed in range(8):
        t, y, truth = _chirp(seed, 0.01)
        fit = fit_period(t, y, "viscous")
        law = fit.amplitude_law or {}
        assert law.get("used"), (seed, law.get("reason"))
        assert fit.std < 0.2 * law["without_law"]["std"], (seed, fit.std, law["without_law"]["std"])
        zs.append((fit.period - truth(fit.modes[0]["reference_amplitude"])) / fit.std)
    assert np.max(np.abs(zs)) < 3, zs


# --------------------------------------------------------------------------- a record in degrees


def drone_torsion_in_degrees(tmp_path, amplitude_deg: float):
    """(config path, scene, record path): the drone's torsion released at
    ``amplitude_deg`` degrees and recorded in degrees (Q = 200, 30 linear
    periods at 60 Hz, noise 1e-3 of the amplitude, seed 3)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import load_scene

    from conftest import CONFIGS

    cfg = CONFIGS / "drone_parallel.yaml"
    s = load_scene(cfg, warn=False)
    T = linear_modes(s, rest_pose(s)).get("torsion").period
    t = np.arange(0.0, 30 * T, 1 / 60.0)
    sg = (2 * math.pi / T) / 400.0  # Q = 200
    deg = amplitude_deg * np.exp(-sg * t) * np.cos(2 * math.pi * t / T) \
        + 1e-3 * amplitude_deg * np.random.default_rng(3).standard_normal(t.size)
    rec = tmp_path / "torsion_deg.csv"
    np.savetxt(rec, np.c_[t, deg], delimiter=",", header="t,angle_deg", comments="", fmt="%.10g")
    return cfg, s, rec


def test_a_record_in_degrees_read_as_radians_is_refused(tmp_path):
    """The drone's torsion released at 1.5 degrees, recorded in degrees, and
    given with ``--signal-quantity angle`` but no ``--signal-scale``: the
    fitted amplitude, 1.5 "rad", made the amplitude factor ~3300 times too
    large (the audit's quadcopter at 1.7 degrees: Izz 0.0171 +- 0.0009 for
    0.022, exit 0).  The record's halves differ by what its true amplitude
    allows (here nothing: a linear decay), the model at 1.5 rad would change
    the period by a tenth of a second between them: refused, exit 2, one
    line naming --signal and --signal-scale.  With the scale the same
    record is answered within its std of the truth."""
    from click.testing import CliRunner

    from bifilar.cli import main

    cfg, s, rec = drone_torsion_in_degrees(tmp_path, 1.5)
    r = CliRunner().invoke(main, ["invert", str(cfg), "--signal", f"torsion={rec}", "--signal-quantity", "angle",
                                  "--json"])
    assert r.exit_code == 2, r.output
    assert r.stdout == "" and "--signal" in r.output and "--signal-scale" in r.output, r.output
    r = CliRunner().invoke(main, ["invert", str(cfg), "--signal", f"torsion={rec}", "--signal-quantity", "angle",
                                  "--signal-scale", "0.0174533", "--json"])
    assert r.exit_code == 0, r.output
    izz = json.loads(r.stdout)["inertia"]["Izz"]
    truth = float(np.asarray(s.inertia)[2, 2])
    assert abs(izz["value"] - truth) < 3 * izz["std"], (izz, truth)


def test_a_time_column_in_ms_named_plain_time_is_refused_naming_the_unit(tmp_path):
    """A CSV whose time column is named ``time`` but holds ms: ``period``
    warns of a unit slip, ``invert --signal`` refused it as an alias at a
    sample rate of 0.06 Hz ("record at 2.5 x 0.978 = 2.45 Hz or faster"),
    the wrong cause.  Now: exit 2, one line naming the ms reading and the
    mode it then matches."""
    from click.testing import CliRunner

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.cli import main
    from bifilar.config import load_scene

    from conftest import CONFIGS

    cfg = CONFIGS / "drone_parallel.yaml"
    s = load_scene(cfg, warn=False)
    T = linear_modes(s, rest_pose(s)).get("torsion").period
    t = np.arange(0.0, 30 * T, 1 / 60.0)
    y = 0.05 * np.cos(2 * math.pi * t / T) + 1e-4 * np.random.default_rng(1).standard_normal(t.size)
    rec = tmp_path / "torsion.csv"
    np.savetxt(rec, np.c_[1000 * t, y], delimiter=",", header="time,angle", comments="", fmt="%.10g")
    r = CliRunner().invoke(main, ["invert", str(cfg), "--signal", f"torsion={rec}", "--json"])
    assert r.exit_code == 2 and r.stdout == "", r.output
    line = r.output.strip()
    assert "\n" not in line and "read in ms" in line and "'torsion'" in line and "t_ms" in line, line


# --------------------------------------------------------------------------- a record in deg/s


@pytest.mark.parametrize("quantity", ["rate", "angle"])
def test_a_record_beyond_any_reachable_start_is_refused_naming_the_signal(tmp_path, quantity):
    """The drone's torsion released at 5 degrees, recorded in degrees (or
    deg/s) and read as rad (rad/s): the fitted amplitude, 5 deg * 0.81 (the
    decay to the fitted period's reference) = 4.05 "rad", is beyond pi, which
    no start of a rotation reaches.  The start check refused it naming
    ``--amplitude``, an option the user never gave (auditsig11, found not
    fixed); the refusal names ``--signal`` and ``--signal-scale``, in one
    line, exit 2, nothing on stdout."""
    from click.testing import CliRunner

    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.cli import main
    from bifilar.config import load_scene

    from conftest import CONFIGS

    cfg = CONFIGS / "drone_parallel.yaml"
    s = load_scene(cfg, warn=False)
    T = linear_modes(s, rest_pose(s)).get("torsion").period
    t = np.arange(0.0, 30 * T, 1 / 60.0)
    w, sg = 2 * math.pi / T, (2 * math.pi / T) / 400.0  # Q = 200
    env = 5.0 * np.exp(-sg * t)
    y = env * np.cos(w * t) if quantity == "angle" else -w * env * np.sin(w * t)
    rec = tmp_path / f"torsion_{quantity}_deg.csv"
    np.savetxt(rec, np.c_[t, y], delimiter=",", header="t,value", comments="", fmt="%.10g")
    r = CliRunner().invoke(main, ["invert", str(cfg), "--signal", f"torsion={rec}", "--signal-quantity", quantity,
                                  "--json"])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and lines[0].startswith("error: --signal:"), r.output
    assert "--signal-scale" in lines[0] and "--amplitude" not in lines[0], r.output

