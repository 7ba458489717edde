"""A read-only output file is never replaced, not even with ``--force``
(docs/errors.md, "Output files"): every command's every output option is
refused with exit 2 and one line naming the option and the file, before any
work, and the file keeps its content and its mode."""

from __future__ import annotations

import os
import stat

import pytest
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.errors import InputError
from bifilar.output import atomic_write
from conftest import CONFIGS

PLATE = CONFIGS / "thesis_plate_rest.yaml"
SOLAR = CONFIGS / "solar_boat.yaml"
PITCH = CONFIGS / "thesis_lin2_pitch.yaml"
SWEEP = ["sweep", SOLAR, "--param", "spacing=2.8:4.8:2", "--no-tensions"]
PLAN = ["plan", SOLAR, "--param", "spacing=2.8:4.8", "--no-tensions"]
INVERT = ["invert", PITCH, "--period", "torsion=1.9053513+-0.001"]

# (command before the output option, option, file name); the file is made read-only and given with --force
CASES = [
    (["modes", PLATE], "--out", "o.csv"),
    (["simulate", PLATE, "--periods", "1"], "--out", "o.csv"),
    (["simulate", PLATE, "--periods", "1"], "--plot", "o.png"),
    (["tensions", PLATE, "--periods", "1"], "--out", "o.csv"),
    (["period", "SIGNAL"], "--plot", "o.png"),
    (INVERT, "--plot", "o.png"),
    (SWEEP, "--out", "o.csv"),
    (SWEEP, "--plot", "o.png"),
    (SWEEP, "--write-config", "o.yaml"),
    (SWEEP, "--write-measurements", "o.yaml"),
    (PLAN, "--write-config", "o.yaml"),
    (PLAN, "--write-measurements", "o.yaml"),
]


def run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def read_only(path, text="keep me\n"):
    path.write_text(text)
    path.chmod(0o444)
    return path


def assert_refused(code, err, option, path, text="keep me\n"):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert lines == [f"error: {option}: {path} is read-only; it is never replaced, even with --force: make it "
                     "writable (chmod u+w) or choose another name"], err
    assert path.read_text() == text
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o444


@pytest.mark.parametrize("cmd, option, name", CASES, ids=[f"{c[0]}{o}" for c, o, _ in CASES])
def test_force_does_not_replace_a_read_only_output(tmp_path, cmd, option, name):
    signal = tmp_path / "signal.csv"
    signal.write_text("t,y\n" + "".join(f"{0.01 * k},{(k % 50) - 25}\n" for k in range(500)))
    cmd = [signal if a == "SIGNAL" else a for a in cmd]
    target = read_only(tmp_path / name)
    for extra in (["--force"], []):  # without --force too: the message names the real obstacle
        code, out, err = run([*cmd, option, target, *extra])
        assert_refused(code, err, option, target)
        assert out == ""


def test_a_writable_output_is_still_replaced_with_force(tmp_path):
    """The control: the refusal is about the mode, not about existing files."""
    target = tmp_path / "o.csv"
    target.write_text("old\n")
    target.chmod(0o640)
    code, _, err = run(["modes", PLATE, "--out", target, "--force"])
    assert code == 0, err
    assert target.read_text().startswith("index,period_s")
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o640  # a replaced file keeps its permissions


def test_a_read_only_sweep_journal_is_neither_resumed_nor_restarted(tmp_path):
    journal = read_only(tmp_path / "s.csv.partial.jsonl")
    for extra in (["--resume"], ["--force"]):
        code, _, err = run([*SWEEP, "--out", tmp_path / "s.csv", *extra])
        assert_refused(code, err, "--out", journal)
    assert not (tmp_path / "s.csv").exists()


def test_a_read_only_monte_carlo_journal_is_not_resumed(tmp_path):
    journal = read_only(tmp_path / "mc.jsonl")
    code, _, err = run([*INVERT, "--monte-carlo", "20", "--journal", journal, "--resume"])
    assert_refused(code, err, "--journal", journal)


def test_atomic_write_refuses_a_read_only_file(tmp_path):
    """The library's own guard (a file made read-only after the CLI's check)."""
    target = read_only(tmp_path / "o.csv")
    with pytest.raises(InputError, match="read-only"):
        atomic_write(target, lambda tmp: open(tmp, "w").write("new\n"))
    assert target.read_text() == "keep me\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.csv"]  # no temporary file left behind
