"""Issue 13, output safety and interrupt/resume: outputs onto devices and
FIFOs, journals that are the input or a symbolic link, outputs that name the
same file, SIGTERM during sweeps and plans, torn and malformed journals."""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import time

import pytest
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.output import Terminated
from bifilar.studies import sweep as sw
from conftest import CONFIGS

PLATE = CONFIGS / "thesis_plate_rest.yaml"
SOLAR = CONFIGS / "solar_boat.yaml"
PITCH = CONFIGS / "thesis_lin2_pitch.yaml"
INVERT = ["invert", str(PITCH), "--period", "torsion=1.9053513+-0.001", "--json"]


def run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def err_lines(err: str) -> list[str]:
    return [ln for ln in err.splitlines() if ln.strip()]


# --------------------------------------------------------------------------- non-regular targets


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX FIFOs")
@pytest.mark.parametrize("cmd", [["modes", PLATE, "--out"], ["simulate", PLATE, "--periods", "1", "--plot"]])
def test_output_onto_a_fifo_is_refused_even_with_force(tmp_path, cmd):
    fifo = tmp_path / ("pipe.png" if "--plot" in cmd else "pipe.csv")
    os.mkfifo(fifo)
    code, out, err = run(cmd + [fifo, "--force"])
    assert code == 2, err
    assert err_lines(err) == [f"error: {cmd[-1]}: {fifo} is a FIFO; outputs are written only to regular files"]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)  # still the FIFO, not replaced by a regular file


def test_output_onto_a_device_is_refused_even_with_force(tmp_path):
    link = tmp_path / "null.csv"  # a symlink to /dev/null: the check looks through the link
    link.symlink_to(os.devnull)
    code, _, err = run(["modes", PLATE, "--out", link, "--force"])
    assert code == 2 and "is a device" in err
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode) and link.is_symlink()


# --------------------------------------------------------------------------- the sweep journal


def test_sweep_journal_may_not_be_the_input_config(tmp_path):
    cfg = tmp_path / "s.csv.partial.jsonl"  # the journal of --out s.csv
    text = SOLAR.read_text()
    cfg.write_text(text)
    for extra in ([], ["--force"], ["--resume"]):
        code, _, err = run(["sweep", cfg, "--param", "spacing=2.8:4.8:2", "--no-tensions",
                            "--out", tmp_path / "s.csv", *extra])
        assert code == 2 and err.startswith("error: --out: refusing to write over the input file"), err
        assert cfg.read_text() == text  # never truncated, used or deleted


def test_sweep_journal_is_never_a_symlink(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (tmp_path / "s.csv.partial.jsonl").symlink_to(victim)
    for extra in (["--force"], ["--resume"]):
        code, _, err = run(["sweep", SOLAR, "--param", "spacing=2.8:4.8:2", "--no-tensions",
                            "--out", tmp_path / "s.csv", *extra])
        assert code == 2 and "symbolic link" in err, err
        assert victim.read_text() == "keep me"


# --------------------------------------------------------------------------- invert's outputs


def test_invert_journal_and_plot_may_not_be_the_same_file(tmp_path, monkeypatch):
    from bifilar.estimation import invert as inv

    def must_not_run(*a, **k):
        raise AssertionError("the inversion ran before the outputs were checked")

    monkeypatch.setattr(inv, "invert", must_not_run)
    x = tmp_path / "x.png"
    code, _, err = run(INVERT + ["--monte-carlo", "10", "--journal", x, "--plot", x])
    assert code == 2 and err.startswith("error: --journal: refusing to write over"), err
    code, _, err = run(INVERT + ["--monte-carlo", "10", "--journal", PITCH])
    assert code == 2 and err.startswith("error: --journal: refusing to write over the input file"), err
    code, _, err = run(INVERT + ["--monte-carlo", "10", "--journal", tmp_path / "no" / "such" / "j.jsonl"])
    assert code == 2 and err.startswith("error: --journal: directory"), err
    assert not x.exists()


# --------------------------------------------------------------------------- SIGTERM -> 143


def _env():
    return {**os.environ, "PYTHONWARNINGS": "ignore", "COLUMNS": "120"}


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_sigterm_during_a_sweep_exits_143_and_keeps_the_journal(tmp_path):
    out = tmp_path / "s.csv"
    journal = tmp_path / "s.csv.partial.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "bifilar", "sweep", str(SOLAR), "--param", "spacing=2.8:4.8:60",
                             "--no-tensions", "--out", str(out)], stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env())
    try:
        deadline = time.time() + 90
        while time.time() < deadline and proc.poll() is None:
            if journal.exists() and len(journal.read_bytes().splitlines()) >= 2:  # header + one point
                break
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = err.decode()
    assert proc.returncode == 143, err
    assert err.rstrip().endswith("terminated") and "Traceback" not in err and "--resume" in err
    assert not out.exists() and journal.exists()


def _terminated_point(*args, **kwargs):  # module level: the worker processes unpickle it by name
    raise Terminated()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_terminated_plan_with_workers_exits_143(monkeypatch):
    """A worker's point ends in Terminated (as when the pool is signalled):
    the plan stops with 143 'terminated', not 130 'interrupted'.  The plan
    module binds ``evaluate_point`` when first imported: patched there too
    (and imported first), or a first import under the patch would keep
    ``_terminated_point`` for every later plan in this process."""
    from bifilar.studies import plan as pl

    monkeypatch.setattr(sw, "evaluate_point", _terminated_point)
    monkeypatch.setattr(pl, "evaluate_point", _terminated_point)
    code, out, err = run(["plan", SOLAR, "--param", "spacing=2.8:4.8", "--no-tensions", "--workers", "2"])
    assert code == 143 and err_lines(err)[-1] == "terminated" and out == "", err


# --------------------------------------------------------------------------- torn and malformed journals


def _sweep_setup():
    from bifilar.config import read_yaml

    cfg = read_yaml(SOLAR)
    st = sw.resolve_settings(cfg, tensions=False, amplitude=0.05)
    return cfg, st


def test_a_torn_journal_line_is_cut_before_the_next_record(tmp_path):
    from bifilar.studies.shorthands import parse_param

    cfg, st = _sweep_setup()
    grid = sw.build_grid([parse_param("spacing=2.8:4.0:4")])
    j = tmp_path / "j.jsonl"
    with pytest.raises(sw.SweepInterrupted):
        sw.run_sweep(cfg, "s", grid, st, journal=j, stop_after=2)
    with open(j, "ab") as fh:
        fh.write(b'{"key": "{\\"spacing\\": 3.6}", "point": {"va')  # torn by an interruption
    with pytest.raises(sw.SweepInterrupted):
        sw.run_sweep(cfg, "s", grid, st, journal=j, resume=True, stop_after=1)
    recs = [json.loads(line) for line in j.read_text().splitlines()]  # every line is whole JSON again
    assert len(recs) == 1 + 3
    full = sw.run_sweep(cfg, "s", grid, st)
    assert sw.run_sweep(cfg, "s", grid, st, journal=j, resume=True) == full


@pytest.mark.parametrize("body", [b"5\n", b"{}\n", b'{"key": 3, "point": {}}\n', b"\xff\xfe\x00binary\n"])
def test_a_malformed_sweep_journal_exits_2_naming_resume(tmp_path, body):
    from bifilar.config import read_yaml

    out = tmp_path / "s.csv"
    args = ["sweep", SOLAR, "--param", "spacing=2.8:4.8:2", "--no-tensions", "--out", out, "--resume"]
    cfg = read_yaml(SOLAR)
    st = sw.resolve_settings(cfg, tensions=False)
    head = json.dumps({"journal": "bifilar-sweep", "version": sw.JOURNAL_VERSION,
                       "fingerprint": sw.fingerprint(cfg, st)}).encode() + b"\n"
    (tmp_path / "s.csv.partial.jsonl").write_bytes(head + body)
    code, stdout, err = run(args)
    assert code == 2 and stdout == "" and err.startswith("error: --resume: "), err
    assert "binary" not in err  # the file is named, its content is not quoted


@pytest.mark.parametrize("text", [b"[1,2]\n", b"\x00\x01\x02\n"])
def test_a_sweep_journal_with_a_bad_header_exits_2(tmp_path, text):
    out = tmp_path / "s.csv"
    (tmp_path / "s.csv.partial.jsonl").write_bytes(text)
    code, _, err = run(["sweep", SOLAR, "--param", "spacing=2.8:4.8:2", "--no-tensions", "--out", out, "--resume"])
    assert code == 2 and err.startswith("error: --resume: "), err


@pytest.fixture(scope="module")
def monte_carlo_journal(tmp_path_factory):
    """(journal path, the invert arguments that wrote it, its header line): one run for the module (test
    economy, session 26: each case below ran this same invert, ~0.2 s of CPU).  Every case rewrites the
    whole file before resuming, so none sees another's; the path and arguments are the writing run's, so the
    header matches them and only the record under test is wrong."""
    j = tmp_path_factory.mktemp("mc") / "mc.jsonl"
    args = INVERT + ["--monte-carlo", "10", "--seed", "1", "--journal", str(j)]
    assert CliRunner().invoke(main, args).exit_code == 0
    return j, args, j.read_bytes().splitlines(keepends=True)[0]


@pytest.mark.parametrize("record", [b"5\n", b"{}\n", b'{"chunk": 0, "samples": [[1, 2, 3]]}\n', b"\xff\xfe\n"])
def test_a_malformed_monte_carlo_journal_exits_2(monte_carlo_journal, record):
    j, args, head = monte_carlo_journal
    r = CliRunner()
    j.write_bytes(head + record)
    res = r.invoke(main, args + ["--resume"])
    assert res.exit_code == 2 and res.stderr.startswith("error: --resume: "), res.stderr
    j.write_bytes(b"[1,2]\n")
    res = r.invoke(main, args + ["--resume"])
    assert res.exit_code == 2 and "not a bifilar Monte Carlo journal" in res.stderr, res.stderr


def test_a_torn_monte_carlo_journal_resumes_to_the_full_result(tmp_path):
    j = tmp_path / "mc.jsonl"
    r = CliRunner()
    args = INVERT + ["--monte-carlo", "150", "--seed", "3", "--journal", str(j)]
    full = r.invoke(main, args)
    assert full.exit_code == 0, full.stderr
    lines = j.read_bytes().splitlines(keepends=True)
    assert len(lines) == 3  # header + two chunks of at most 100
    j.write_bytes(lines[0] + lines[1] + lines[2][:25])  # the second chunk torn mid-line
    again = r.invoke(main, args + ["--resume"])
    assert again.exit_code == 0, again.stderr
    assert json.loads(again.stdout)["monte_carlo"] == json.loads(full.stdout)["monte_carlo"]
    assert [json.loads(x) for x in j.read_text().splitlines()] == [json.loads(x) for x in lines]


def test_a_sweep_journal_of_an_earlier_version_is_refused_not_mixed(tmp_path, monkeypatch):
    """A journal's points are only resumed by the code whose figures they hold:
    one written under an earlier JOURNAL_VERSION (session 8 changed every
    point's sigma: the amplitude law) is refused naming --resume, rather than
    finished with points of two kinds; the same journal under the current
    version resumes."""
    from bifilar.studies.shorthands import parse_param

    cfg, st = _sweep_setup()
    grid = sw.build_grid([parse_param("spacing=2.8:4.0:3")])
    j = tmp_path / "s.csv.partial.jsonl"
    monkeypatch.setattr(sw, "JOURNAL_VERSION", sw.JOURNAL_VERSION - 1)
    with pytest.raises(sw.SweepInterrupted):
        sw.run_sweep(cfg, "s", grid, st, journal=j, stop_after=1)
    monkeypatch.undo()
    with pytest.raises(sw.InputError) as e:
        sw.run_sweep(cfg, "s", grid, st, journal=j, resume=True)
    assert e.value.field == "--resume" and "another version" in str(e.value)
    j.unlink()
    with pytest.raises(sw.SweepInterrupted):
        sw.run_sweep(cfg, "s", grid, st, journal=j, stop_after=1)
    assert sw.run_sweep(cfg, "s", grid, st, journal=j, resume=True) == sw.run_sweep(cfg, "s", grid, st)


def test_a_monte_carlo_journal_of_an_earlier_draw_scheme_is_refused(tmp_path, monkeypatch):
    """Draws made by an earlier scheme (session 8: the amplitude law, the
    copies' dof) are not mixed with the current ones on --resume."""
    from bifilar.estimation import montecarlo

    j = tmp_path / "mc.jsonl"
    r = CliRunner()
    args = INVERT + ["--monte-carlo", "10", "--seed", "1", "--journal", str(j)]
    monkeypatch.setattr(montecarlo, "DRAW_SCHEME", montecarlo.DRAW_SCHEME - 1)
    assert r.invoke(main, args).exit_code == 0
    monkeypatch.undo()
    res = r.invoke(main, args + ["--resume"])
    assert res.exit_code == 2 and "another version" in res.stderr, res.stderr
    j.unlink()
    assert r.invoke(main, args).exit_code == 0
    assert r.invoke(main, args + ["--resume"]).exit_code == 0
