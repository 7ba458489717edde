"""The command line under faults and interruptions: exit status and one-line
messages, safe output files (atomic, never over the input, --force), slack
wires during the motion, and the real entry point in a subprocess
(tracebacks only with --debug, Ctrl-C and SIGTERM leave no partial file)."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import bifilar.analysis.equilibrium as eq
import bifilar.analysis.simulate as simmod
from bifilar.cli import main
from bifilar.cli.common import OptionChecker, atomic_write, check_output_path
from bifilar.errors import ConfigErrors, InputError
from conftest import TRIFILAR

ROOT = Path(__file__).resolve().parents[1]
PLATE = ROOT / "configs" / "thesis_plate_rest.yaml"
DRONE = ROOT / "configs" / "drone_parallel.yaml"
SLACK = ROOT / "tests" / "bad_configs" / "slack_fourth_wire.yaml"
G = 9.81


def run(*args, **kw):
    return CliRunner().invoke(main, [str(a) for a in args], **kw)


def lines(text: str) -> list[str]:
    return [ln for ln in text.splitlines() if ln.strip()]


def listing(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir())


# --------------------------------------------------------------------------- output files


def test_existing_output_is_replaced_only_with_force(tmp_path):
    out = tmp_path / "modes.csv"
    out.write_text("precious\n")
    res = run("modes", PLATE, "--out", out)
    assert res.exit_code == 2
    assert lines(res.stderr) == [f"error: --out: {out} exists; choose another name or pass --force to replace it"]
    assert out.read_text() == "precious\n"
    res = run("modes", PLATE, "--out", out, "--force")
    assert res.exit_code == 0, res.stderr
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    assert rows.shape == (4, 8)  # 2 wires: 4 modes; index, period, 6 shape components
    # independent content check: the side sway is the planar pendulum of length 5 cos 30 deg (thesis 6.1)
    T_sway = 2 * np.pi * np.sqrt(5 * np.cos(np.pi / 6) / G)
    assert np.nanmin(np.abs(rows[:, 1] - T_sway)) < 1e-9 * T_sway  # linear modes are exact to rounding
    assert listing(tmp_path) == ["modes.csv"]  # no temporary file left behind


def test_never_writes_over_the_input_config(tmp_path):
    cfg = tmp_path / "rig.yaml"
    cfg.write_bytes(PLATE.read_bytes())
    (tmp_path / "link.yaml").symlink_to(cfg)
    os.link(cfg, tmp_path / "hard.yaml")
    for target in ("rig.yaml", "link.yaml", "hard.yaml"):
        res = run("modes", cfg, "--out", tmp_path / target, "--force")
        assert res.exit_code == 2
        assert lines(res.stderr) == [f"error: --out: refusing to write over the input file {cfg}"]
    assert cfg.read_bytes() == PLATE.read_bytes()


def test_two_outputs_may_not_share_a_file(tmp_path):
    both = tmp_path / "run.csv"
    res = run("simulate", PLATE, "--periods", 1, "--out", both, "--plot", both)
    assert res.exit_code == 2
    assert lines(res.stderr) == [f"error: --plot: refusing to write over {both}, which another option of this "
                                 "command also names"]
    assert not both.exists()


def test_plot_name_must_have_an_image_format(tmp_path):
    # found by the fuzzer: a --plot named .csv used to fail after the whole run, inside matplotlib (exit 1)
    for name in ("run.csv", "run"):
        res = run("simulate", PLATE, "--periods", 1, "--plot", tmp_path / name)
        assert res.exit_code == 2
        assert lines(res.stderr)[0].startswith(f"error: --plot: cannot tell the image format of '{name}': end the "
                                               "name in .png, .pdf or .svg")
    assert listing(tmp_path) == []


def test_output_directory_problems_are_input_errors(tmp_path):
    res = run("modes", PLATE, "--out", tmp_path / "missing" / "x.csv")
    assert res.exit_code == 2 and lines(res.stderr) == [f"error: --out: directory {tmp_path / 'missing'} does not exist"]
    with pytest.raises(InputError, match="is a directory"):
        check_output_path(str(tmp_path), True, [], "--out")


def test_failing_run_leaves_no_file_and_keeps_the_old_one(tmp_path):
    out = tmp_path / "modes.csv"
    res = run("modes", SLACK, "--out", out)  # wire 3 slack at rest: exit 2 after the output check
    assert res.exit_code == 2 and "wire 3" in res.stderr
    assert listing(tmp_path) == []
    out.write_text("precious\n")
    before = out.stat().st_mtime_ns
    res = run("modes", SLACK, "--out", out, "--force")
    assert res.exit_code == 2
    assert out.read_text() == "precious\n" and out.stat().st_mtime_ns == before
    assert listing(tmp_path) == ["modes.csv"]


def _partial_then(exc):
    def savetxt(fname, *a, **k):
        Path(fname).write_text("index,period_s\n1,")  # half a file, then the fault
        raise exc

    return savetxt


@pytest.mark.parametrize("existing", [False, True])
def test_interrupt_while_writing_leaves_no_partial_file(tmp_path, monkeypatch, existing):
    out = tmp_path / "modes.csv"
    if existing:
        out.write_text("precious\n")
    monkeypatch.setattr(np, "savetxt", _partial_then(KeyboardInterrupt()))
    res = run("modes", PLATE, "--out", out, "--force")
    assert res.exit_code == 130
    assert lines(res.stderr) == ["interrupted"]
    assert listing(tmp_path) == (["modes.csv"] if existing else [])
    if existing:
        assert out.read_text() == "precious\n"


def test_disk_full_is_a_clean_error(tmp_path, monkeypatch):
    out = tmp_path / "modes.csv"
    monkeypatch.setattr(np, "savetxt", _partial_then(OSError(errno.ENOSPC, "No space left on device")))
    res = run("modes", PLATE, "--out", out)
    assert res.exit_code == 1
    assert lines(res.stderr) == ["error: OSError: No space left on device"]
    assert listing(tmp_path) == []


def test_atomic_write_modes(tmp_path):
    umask = os.umask(0o022)
    try:
        p = tmp_path / "a.txt"
        atomic_write(p, lambda tmp: Path(tmp).write_text("1"))
        assert (p.stat().st_mode & 0o777) == 0o644  # as a plain open() would create it (mkstemp gives 0600)
        os.chmod(p, 0o600)
        atomic_write(p, lambda tmp: Path(tmp).write_text("2"))
        assert (p.stat().st_mode & 0o777) == 0o600 and p.read_text() == "2"  # a replaced file keeps its mode
    finally:
        os.umask(umask)


# --------------------------------------------------------------------------- faults: exit 1, one line, no traceback


def test_integrator_failure_is_exit_1_with_its_reason(monkeypatch):
    """A right-hand side that turns NaN makes the real integrator give up
    (step size underflow): exit 1 and the integrator's reason."""
    real = simmod.solve_ivp

    def broken(fun, t_span, y0, **kw):
        return real(lambda t, y: fun(t, y) * (np.nan if t > 0.2 else 1.0), t_span, y0, **kw)

    monkeypatch.setattr(simmod, "solve_ivp", broken)
    res = run("simulate", PLATE, "--periods", 1, "--json", "--method", "DOP853")
    assert res.exit_code == 1
    assert lines(res.stderr) == ["error: IntegrationError: integrator DOP853 failed: Required step size is less than "
                                 "spacing between numbers."]
    assert res.stdout == ""


def test_default_integrator_failure_is_exit_1_with_its_reason(monkeypatch):
    """The default engine (LSODA through scipy.integrate.odeint): a right-hand side
    that turns NaN gives a non-finite solution, which is a failure, not a result."""
    import scipy.integrate

    real = scipy.integrate.odeint

    def broken(f, y0, t, *a, **kw):
        return real(lambda y, tau: np.asarray(f(y, tau)) * (np.nan if tau > 0.2 else 1.0), y0, t, *a, **kw)

    monkeypatch.setattr(scipy.integrate, "odeint", broken)
    res = run("simulate", PLATE, "--periods", 1, "--json")
    assert res.exit_code == 1
    assert lines(res.stderr) == ["error: IntegrationError: integrator LSODA failed: the solution is not finite "
                                 "(NaN or inf)"]
    assert res.stdout == ""


def test_rest_pose_non_convergence_is_exit_1(monkeypatch):
    real = eq._newton_kkt

    def stuck(*a, **k):
        com, R, lam, _ = real(*a, **k)
        return com, R, lam, 1e-3

    monkeypatch.setattr(eq, "_newton_kkt", stuck)
    res = run("modes", PLATE, "--json")
    assert res.exit_code == 1
    assert lines(res.stderr) == ["error: ConvergenceError: rest pose did not converge (KKT residual 1.00e-03)"]


def test_unexpected_error_is_one_line_and_debug_shows_it(monkeypatch):
    def boom(*a, **k):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr("bifilar.analysis.modes.linear_modes", boom)
    res = run("modes", PLATE)
    assert res.exit_code == 1
    assert lines(res.stderr) == ["error: internal error (ZeroDivisionError: float division by zero); "
                                 "rerun with --debug for a traceback"]
    res = run("--debug", "modes", PLATE)
    assert isinstance(res.exception, ZeroDivisionError)  # propagates: Python prints the traceback


def test_python_warnings_become_one_line(monkeypatch):
    def noisy(*a, **k):
        np.float64(1e308) * 10  # RuntimeWarning: overflow
        raise InputError("--mode", "stop here")

    monkeypatch.setattr("bifilar.analysis.modes.linear_modes", noisy)
    res = run("modes", PLATE)
    assert res.exit_code == 2
    assert lines(res.stderr) == ["warning: RuntimeWarning: overflow encountered in scalar multiply",
                                 "error: --mode: stop here"]


def test_option_checker_reports_every_problem():
    chk = OptionChecker()
    assert chk.positive("--periods", 10.0)
    assert not chk.positive("--periods", -1.0)
    assert not chk.in_range("--rtol", 0.5, 0, 1e-2, lo_open=True, hi_open=True)
    assert not chk.finite("--amplitude", float("nan"))
    assert not chk.choice("--method", "DOP835", ["DOP853", "RK45"])
    with pytest.raises(ConfigErrors) as e:
        chk.done()
    assert str(e.value).splitlines() == [
        "--periods: must be positive, got -1",
        "--rtol: must be in (0, 0.01), got 0.5",
        "--amplitude: must be finite, got nan",
        "--method: must be one of DOP853, RK45, got 'DOP835'; did you mean 'DOP853'?",
    ]


# --------------------------------------------------------------------------- slack during the motion


def test_wire_going_slack_during_the_motion_is_reported_and_stop_ends_the_run(tmp_path):
    """Trifilar (R = 1 m, L = 0.995 m) twisted by 1.035 rad, just short of the
    2 asin(L / 2R) = 1.0424 rad at which the wires would be horizontal: the
    table starts nearly at the ceiling on almost horizontal, barely loaded
    wires and, unbalanced by its test mass, drops and swings until wire 2,
    then 1, then 3 go slack mid-motion (the same instants with DOP853, RK45 and
    Radau at rtol 1e-9 .. 1e-12: physics, not integration error; from the
    start pose with the twist held at exactly 1.035 rad -- the solver before
    the start-pose fix let it drift to 1.03489 rad, a start from which wire 3
    stayed taut).  The sampled detection (continue) and the integrator's event
    (stop) are independent ways to find the first instant."""
    assert 1.035 < 2 * np.arcsin(0.995 / 2)
    cfg = tmp_path / "trifilar.yaml"
    cfg.write_text(TRIFILAR)
    args = ["simulate", cfg, "--mode", "torsion", "--amplitude", 1.035, "--periods", 3, "--rtol", 1e-9, "--json"]
    res = run(*args)
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    t_end = 3 * doc["linear_period"]
    slack = {s["wire"]: s["t"] for s in doc["slack"]}
    assert sorted(slack) == [1, 2, 3] and min(slack, key=slack.get) == 2
    assert all(0 < t < t_end for t in slack.values())  # mid-motion, not at the release
    assert max(doc["tension"]["min"]) < 0
    assert doc["max_constraint_violation"] < 1e-6  # a clean run: the slack is physics, not numerical drift
    warn = [ln for ln in lines(res.stderr) if ln.startswith("warning:")]
    assert any("WIRE 1 GOES SLACK" in w for w in warn) and any("WIRE 2 GOES SLACK" in w for w in warn)

    res = run(*args, "--on-slack", "stop")
    assert res.exit_code == 0, res.stderr
    stop = json.loads(res.stdout)
    msg = [w for w in stop["warnings"] if w.startswith("run stopped at t = ")]
    assert len(msg) == 1 and any("run stopped" in ln for ln in lines(res.stderr))
    t_stop = float(msg[0].split("t = ")[1].split(" s")[0])
    # the event finds the zero of the tension; the sampled check the first sample at or below zero, which is
    # at most one sample spacing later (200 samples over the run, the minimum of simulate's grid)
    t_first = min(slack.values())
    assert t_first - t_end / 200 <= t_stop <= t_first + 1e-3
    assert stop["cycles"] < doc["cycles"]


def test_stop_on_a_wire_slack_at_the_release():
    # the quadcopter on its parallel bifilar (wires 1.5 m) swung sideways by 1.48 m, inside the reach of the
    # swing (1.5 m: the wires horizontal, where the start poses end): on such nearly horizontal wires the
    # rigid-wire model can hold the body at the release only with wire 2 pushing (its tension at the start,
    # from the model's multipliers, is negative), so wire 2 is slack at t = 0 and `--on-slack stop` ends
    # the run at once.  (This test used the thesis plate twisted by 1.36 rad, a start beyond the reach of
    # its torsion, arccos(1/4) = 1.3181 rad; the old projection let the twist drift to 1.27 rad and ran.)
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.analysis.simulate import initial_state
    from bifilar.config import load_scene
    from bifilar.models import maximal as mx

    scene = load_scene(DRONE, warn=False)
    rest = rest_pose(scene)
    y0 = initial_state(scene, rest, linear_modes(scene, rest).get("swing-y"), 1.48)
    T0 = mx.tensions(y0, mx.params_from_scenes(scene))
    assert T0[0] > 0 > T0[1]
    args = ["simulate", DRONE, "--mode", "swing-y", "--amplitude", 1.48, "--periods", 2, "--rtol", 1e-9, "--json"]
    doc = json.loads(run(*args).stdout)
    assert {s["wire"]: s["t"] for s in doc["slack"]}[2] == 0.0
    stop = json.loads(run(*args, "--on-slack", "stop").stdout)
    assert any(w.startswith("run stopped at t = 0 s") for w in stop["warnings"])
    assert [(s["wire"], s["t"]) for s in stop["slack"]] == [(2, 0.0)]


def test_absurd_amplitude_is_an_input_error():
    # found by fuzzing: 1e300 used to end in an internal error (exit 1)
    res = run("simulate", PLATE, "--amplitude", 1e300, "--periods", 1)
    assert res.exit_code == 2 and lines(res.stderr)[-1].startswith("error: --amplitude: ")


def test_kane_on_vertical_wires_is_an_input_error(tmp_path):
    # found by fuzzing: KaneSingularityError used to exit 1 for a --model the rig cannot use
    cfg = tmp_path / "vertical.yaml"
    cfg.write_text("body: {mass: 2.0, inertia: {principal: [0.1, 0.1, 0.2]}}\n"
                   "rig: {anchors: [[0, -0.5, 0], [0, 0.5, 0]], attachments: [[0, -0.5, 0.1], [0, 0.5, 0.1]], "
                   "lengths: [1.5, 1.5]}\n")
    res = run("simulate", cfg, "--model", "kane", "--periods", 1)
    assert res.exit_code == 2 and lines(res.stderr)[-1].startswith("error: --model: ")


def test_absurd_rtol_is_an_input_error(monkeypatch):
    def must_not_run(*a, **k):
        raise AssertionError("the simulation started: --rtol was not validated first")

    monkeypatch.setattr(simmod, "simulate", must_not_run)
    res = run("simulate", PLATE, "--rtol", 1e-30, "--periods", 1)
    assert res.exit_code == 2 and lines(res.stderr)[-1].startswith("error: --rtol: ")


# --------------------------------------------------------------------------- the real entry point


def _python_m(*args, **kw):
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "COLUMNS": "120"}
    return subprocess.run([sys.executable, "-m", "bifilar", *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=120, **kw)


def test_entry_point_success_and_input_error_via_subprocess(tmp_path):
    ok = _python_m("modes", PLATE, "--json")
    assert ok.returncode == 0, ok.stderr
    doc = json.loads(ok.stdout)  # exactly one JSON document on stdout
    assert set(doc) >= {"equilibrium", "modes"}
    bad = _python_m("modes", SLACK)
    assert bad.returncode == 2
    assert lines(bad.stderr) == ["error: rig.lengths: wire 3 is slack at rest by 50 mm: shorten it by exactly that "
                                 "much, to 1.0000 m: then the 4 wires are dependent (like a table's legs: their "
                                 "tensions are statically indeterminate, set by the wires' stretch and a fraction of a "
                                 "mm of length); the model's split (least squares of T_i / L_i) gives every wire at "
                                 "least 1.96 N; 1 mm "
                                 "shorter leaves another wire slack"]
    assert bad.stdout == ""
    dbg = _python_m("--debug", "modes", SLACK)
    assert dbg.returncode == 1 and "Traceback (most recent call last)" in dbg.stderr
    assert "SlackWireError" in dbg.stderr


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and pty")
@pytest.mark.parametrize("sig, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")])
def test_signal_during_a_run_exits_cleanly(tmp_path, sig, code, word):
    """A long simulation is signalled once its progress bar shows (stderr on
    a pseudo-terminal, so the bar is drawn): a clean exit code, one word,
    no traceback, and no output or temporary file."""
    import pty
    import select

    out = tmp_path / "run.csv"
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "bifilar", "simulate", str(PLATE), "--periods", "1e4",
                             "--out", str(out)], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    seen = b""
    try:
        deadline = time.time() + 60
        while b"simulating" not in seen and time.time() < deadline:
            r, _, _ = select.select([master], [], [], 0.5)
            if r:
                seen += os.read(master, 4096)
        assert b"simulating" in seen, seen
        proc.send_signal(sig)
        # keep draining the terminal while waiting: a child blocked on a full
        # pty (its progress bar still drawing on a loaded machine) cannot exit
        deadline = time.time() + 60
        while proc.poll() is None and time.time() < deadline:
            r, _, _ = select.select([master], [], [], 0.2)
            if r:
                try:
                    seen += os.read(master, 4096)
                except OSError:
                    break
        proc.wait(timeout=5)
        while True:
            r, _, _ = select.select([master], [], [], 0.2)
            if not r:
                break
            try:
                chunk = os.read(master, 4096)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    text = seen.decode("utf-8", "replace")
    assert proc.returncode == code, text[-2000:]  # the terminal's tail says what the child did
    assert word in text and "Traceback" not in text
    assert listing(tmp_path) == []
