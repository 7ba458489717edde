"""Issue 13, inputs that must exit 2 (or end quietly) and did not: names with
rich markup, overflowing numbers, sizes, native library output on stdout, a
closed pipe, internal field names and file content in messages."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main
from bifilar.errors import InputError
from bifilar.studies import sweep as sw
from bifilar.studies.shorthands import ParamSpec
from conftest import CONFIGS

PLATE = CONFIGS / "thesis_plate_rest.yaml"
PITCH = CONFIGS / "thesis_lin2_pitch.yaml"
CYLINDER = CONFIGS / "thesis_cylinder_6_4.yaml"


def run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def one_error(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    return lines[0]


def _env():
    return {**os.environ, "PYTHONWARNINGS": "ignore", "COLUMNS": "120", "PYTHONPATH": os.pathsep.join(sys.path)}


# --------------------------------------------------------------------------- names printed literally


@pytest.mark.parametrize("name", ["frame [/b]", "[link=https://example.org]x", "rotor [v2]", "drone :thumbs_up:"])
def test_config_names_with_markup_print_literally(tmp_path, name):
    cfg = yaml.safe_load(PITCH.read_text())
    cfg["name"] = name
    p = tmp_path / "named.yaml"
    p.write_text(yaml.safe_dump(cfg))
    for args in (["modes", p], ["invert", p, "--period", "torsion=1.9053513+-0.001", "--no-ladder"],
                 ["sweep", p, "--param", "length=[5.0]", "--no-tensions"]):  # a valid point: none exits 2
        code, out, err = run(args)
        assert code == 0, err
        assert name in out, out  # not interpreted as markup (nor as an emoji code), not dropped


def test_names_in_simulate_and_tensions_tables(tmp_path):
    cfg = yaml.safe_load(PITCH.read_text())
    cfg["name"] = "rotor [v2] [/b]"
    p = tmp_path / "named.yaml"
    p.write_text(yaml.safe_dump(cfg))
    for args in (["simulate", p, "--periods", "2"], ["tensions", p, "--periods", "2"]):
        code, out, err = run(args)
        assert code == 0 and "rotor [v2] [/b]" in out, err


# --------------------------------------------------------------------------- overflowing numbers


@pytest.mark.parametrize("part, field", [
    ({"shape": "solid_sphere", "mass": 1.0, "radius": 0.1, "position": [1e200, 0, 0]}, "body.parts.1.position.0"),
    ({"shape": "solid_sphere", "mass": 1.0, "radius": 1e308}, "body.parts.1.radius"),
    ({"shape": "box", "mass": 1.0, "size": [0.1, 1e300, 0.1]}, "body.parts.1.size.1"),
    ({"shape": "box", "mass": 1.0, "size": [0.1, 0.1, 0.1], "rotation": [1e308, 0, 0]}, "body.parts.1.rotation.0"),
])
def test_overflowing_part_numbers_exit_2_naming_the_field(tmp_path, part, field):
    cfg = yaml.safe_load(PLATE.read_text())
    cfg["body"] = {"parts": [{"shape": "box", "mass": 100.0, "size": [2.5, 5.0, 0.01]}, part]}
    p = tmp_path / "parts.yaml"
    p.write_text(yaml.safe_dump(cfg))
    code, out, err = run(["modes", p])
    assert code == 2 and out == ""
    assert one_error(err).startswith(f"error: {field}: must be at most "), err


def _signal(tmp_path, name, t, y, header="t,y"):
    p = tmp_path / name
    cols = [y] if t is None else [t, y]
    np.savetxt(p, np.column_stack(cols), delimiter=",", header=header, comments="")
    return p


@pytest.fixture
def decay():
    t = np.arange(0.0, 20.0, 0.01)
    return t, np.sin(2 * np.pi * t / 1.9) * np.exp(-0.01 * t)


def test_absurd_sample_rates_times_and_magnitudes_exit_2(tmp_path, decay):
    t, y = decay
    only_y = _signal(tmp_path, "y.csv", None, y, header="y")
    tiny_t = _signal(tmp_path, "tiny.csv", t * 1e-300, y)
    huge_y = _signal(tmp_path, "huge.csv", t, y * 1e200)
    cases = [(["period", only_y, "--sample-rate", "1e300"], "--sample-rate"),
             (["invert", PITCH, "--signal", f"torsion={only_y}", "--sample-rate", "1e300"], "--sample-rate"),
             (["period", tiny_t], "SIGNAL"),
             (["invert", PITCH, "--signal", f"torsion={tiny_t}"], "--signal"),
             (["period", huge_y], "signal")]  # the samples' field, as the reader names it (readers19)
    for args, field in cases:
        code, out, err = run(args)
        assert code == 2 and out == "" and one_error(err).startswith(f"error: {field}"), (args, err)


def test_bad_counts_exit_2(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    cases = [(["invert", PITCH, "--period", "torsion=1.9", "--monte-carlo", "10", "--seed", "-1"], "--seed"),
             (["sweep", PITCH, "--param", "length=1,2", "--workers", "99999999999"], "--workers"),
             (["plan", PITCH, "--param", "length=1:2", "--workers", "99999999999"], "--workers"),
             (["tensions", PITCH, "--motion", empty], "--motion"),
             (["simulate", PITCH, "--periods", "1e9"], "--periods"),
             (["tensions", PITCH, "--periods", "1e9"], "--periods"),
             (["sweep", PITCH, "--param", "length=1,2", "--periods", "1e9"], "--periods")]
    for args, field in cases:
        code, out, err = run(args)
        assert code == 2 and out == "" and one_error(err).startswith(f"error: {field}: "), (args, err)


def test_sweep_amplitude_beyond_reach_is_refused_as_simulate_refuses_it():
    """amplitude 4 (rad) x the torsion shape: `simulate` refuses it; a sweep
    point got an internal LinAlgError from a run started anyway."""
    code, _, err = run(["simulate", CYLINDER, "--mode", "torsion", "--amplitude", "4", "--periods", "1"])
    assert code == 2
    refusal = one_error(err).removeprefix("error: ")
    from bifilar.config import read_yaml

    cfg = read_yaml(CYLINDER)
    p = sw.evaluate_point(cfg, "c", {"amplitude": 4.0}, sw.resolve_settings(cfg, components=["Izz"]))
    assert not p["valid"] and p["error"] == refusal


def test_grid_size_does_not_wrap_around():
    """65536**4 = 2**64 wraps to 0 in np.prod(int64): the point limit must still hold."""
    specs = [ParamSpec(f"p{i}", tuple(float(v) for v in range(65536))) for i in range(4)]
    with pytest.raises(InputError) as e:
        sw.build_grid(specs)
    assert e.value.field == "--param" and str(2**64) in str(e.value)


def test_workers_never_exceed_points_or_cpus(monkeypatch):
    import concurrent.futures as cf

    started = []

    class Recorder:
        def __init__(self, max_workers=None, **kw):
            started.append(max_workers)
            raise RuntimeError("recorded")

    monkeypatch.setattr(cf, "ProcessPoolExecutor", Recorder)
    with pytest.raises(RuntimeError, match="recorded"):
        sw.run_sweep({}, "s", [{"a": 1.0}, {"a": 2.0}, {"a": 3.0}], sw.SweepSettings(("Izz",)), workers=1000)
    assert started == [min(3, os.cpu_count() or 1)]


# --------------------------------------------------------------------------- stdout stays clean


NATIVE = textwrap.dedent("""
    import os, click
    from bifilar.cli.common import emit_json, handle_errors

    @click.command()
    @handle_errors
    def cmd():
        os.write(1, b" ** On entry to DLASCL parameter number  4 had an illegal value\\n")  # as LAPACK does
        emit_json({"period": 1.9})

    cmd()
""")


def test_native_writes_to_stdout_go_to_stderr():
    r = subprocess.run([sys.executable, "-c", NATIVE], capture_output=True, text=True, env=_env(), timeout=60)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == {"period": 1.9}  # exactly one JSON document
    assert "DLASCL" in r.stderr


def test_a_closed_stdout_pipe_ends_quietly_with_141():
    proc = subprocess.Popen([sys.executable, "-m", "bifilar", "modes", str(PLATE)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=_env())
    proc.stdout.close()  # the reader is gone before anything is written (`| head -0`)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 141 and err == b"", err


# --------------------------------------------------------------------------- messages


def test_theta_errors_name_the_option():
    code, _, err = run(["simulate", PITCH, "--model", "kane", "--theta", "1e308,0,0,0", "--periods", "1"])
    assert code == 2 and one_error(err).startswith("error: --theta: "), err


def test_messages_never_quote_a_file_that_is_not_a_config(tmp_path):
    secret = tmp_path / "passwd"
    secret.write_text("root:x:0:0:SECRET-VALUE:/root:/bin/bash\ndaemon:x:1:1:SECRET-TOO:/usr/sbin\n")
    meas = tmp_path / "m.yaml"
    meas.write_text(f"config: {secret}\nmeasurements:\n  - {{mode: torsion, period: 1.9}}\n")
    for args in (["modes", secret], ["invert", "--measurements", meas], ["tensions", PITCH, "--motion", secret]):
        code, _, err = run(args)
        assert code == 2 and "SECRET" not in err and "root:x" not in err, (args, err)


def test_a_file_that_is_not_a_recording_is_named_never_quoted(tmp_path):
    # issue 13: `period /etc/passwd` and `invert --signal torsion=/etc/passwd` quoted the file's first line
    secret = "root:x:0:0:root:/root:/bin/bash"
    f = tmp_path / "passwd"
    f.write_text(secret + "\ndaemon:x:1:1:daemon:/usr/sbin\n")
    for args in (["period", f], ["invert", PITCH, "--signal", f"torsion={f}"], ["period", f, "--json"]):
        code, out, err = run(args)
        line = one_error(err)
        assert code == 2 and "passwd is not a recording" in line, err
        assert "root" not in err and "daemon" not in err and out == ""
    # a real header with numbers below is still read (and its column names may be listed); 20 Hz (10 cycles,
    # 400 samples: the fit is what this test paid for, 9.7 s of CPU at 100 Hz, 1.2 s here; session 15)
    g = tmp_path / "rec.csv"
    t = np.arange(0, 20, 0.05)
    g.write_text("t,angle (rad)\n" + "".join(f"{a:.3f},{0.05 * np.cos(2 * np.pi * a / 1.9):.6f}\n" for a in t))
    code, out, err = run(["period", g, "--json"])
    assert code == 0, err
    assert json.loads(out)["period"] == pytest.approx(1.9, rel=1e-4)


def test_timed_trial_label_with_markup_is_printed_literally():
    # the --timed table's title rendered the label as rich markup ('[b]x' printed as a bold 'x')
    code, out, err = run(["period", "--timed", "[b]x=10:15.20,15.21"])
    assert code == 0, err
    assert "[b]x: 2 trial(s)" in out
