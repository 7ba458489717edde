"""Second audit of cases nobody here wrote (docs/errors.md): several
hangings of one body, unit slips in periods and timed totals, recordings
from other tools and rigs, and the plausibility of a recommended point.
Each case is checked against an independent calculation or the project's
rules (exit 2 with one line naming the field, warnings on stderr and in
the JSON document)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from bifilar.cli import main
from conftest import CONFIGS

TRIFILAR_RIG = {"anchors": [[0.0, 0.3, 0.0], [-0.259808, -0.15, 0.0], [0.259808, -0.15, 0.0]],
                "attachments": [[0.0, 0.3, 0.02], [-0.259808, -0.15, 0.02], [0.259808, -0.15, 0.02]],
                "lengths": [1.0, 1.0, 1.0]}


def run(args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def _two_hangings(tmp_path, mass2=4.0, gravity2=9.81):
    body = {"mass": 4.0, "inertia": {"principal": [0.25, 0.25, 0.35]}}
    doc = {"solve_for": ["Ixx", "Izz"], "hangings": [
        {"name": "z-up", "config": {"body": body, "rig": TRIFILAR_RIG},
         "measurements": [{"mode": "torsion", "cycles": 10, "times": [21.14, 21.15, 21.16]}]},
        {"name": "x-up", "config": {"gravity": gravity2, "body": {**body, "mass": mass2}, "rig": TRIFILAR_RIG},
         "rotation": {"axis": [0, 1, 0], "angle_deg": -90},
         "measurements": [{"mode": "torsion", "cycles": 10, "times": [18.30, 18.32, 18.31]}]}]}
    p = tmp_path / "hangings.yaml"
    p.write_text(yaml.safe_dump(doc))
    return p


# -- 1. hangings of one body agree on its mass and on gravity ----------------

def test_hangings_with_different_mass_are_refused_naming_both_values(tmp_path):
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, mass2=4.4), "--json"])
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith("error: hangings.1.config.body.mass:")
    assert "4.4 kg" in lines[0] and "4 kg" in lines[0]


def test_hangings_with_different_gravity_are_refused(tmp_path):
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, gravity2=9.70), "--json"])
    assert code == 2 and out == ""
    assert err.strip().startswith("error: hangings.1.config.gravity:") and "9.7 " in err and "9.81 " in err


def test_hangings_equal_to_rounding_are_accepted(tmp_path):
    """A mass equal to 1e-12 relative (e.g. summed from parts) is the same mass."""
    code, out, err = run(["invert", "--measurements", _two_hangings(tmp_path, mass2=4.0 * (1 + 1e-12)),
                          "--amplitude", "0", "--json"])
    assert code == 0, err
    assert set(json.loads(out)["inertia"]) == {"Ixx", "Izz"}


# -- 2. an implausible period warns about a unit slip ------------------------

SLOW = {"name": "wide disc on close vertical wires",  # torsion T = 2 pi (k/r) sqrt(h/g) ~ 127 s
        "body": {"mass": 10.0, "inertia": {"principal": [45.0, 45.0, 90.0]}},
        "rig": {"anchors": [[0.0, -0.15, 0.0], [0.0, 0.15, 0.0]],
                "attachments": [[0.0, -0.15, 0.05], [0.0, 0.15, 0.05]], "lengths": [10.0, 10.0]}}


def _slow(tmp_path):
    p = tmp_path / "slow.yaml"
    p.write_text(yaml.safe_dump(SLOW))
    return p


def test_implausibly_long_period_warns_about_a_unit_slip_but_runs(tmp_path):
    """110 s is reachable on this rig (the vertical bifilar's torsion
    2 pi sqrt(Izz h / (m g r^2)) gives 110 s for Izz = 67.6), so it is
    estimated, with a warning in the JSON and on stderr."""
    code, out, err = run(["invert", _slow(tmp_path), "--period", "torsion=110+-0.1", "--amplitude", "0", "--json"])
    assert code == 0, err
    doc = json.loads(out)
    slip = [w for w in doc["warnings"] if "unit slip" in w]
    assert len(slip) == 1 and slip[0].startswith("--period:") and "ms" in slip[0] and "0.11 s" in slip[0]
    assert "unit slip" in err
    m, g, r, h = 10.0, 9.81, 0.15, 10.0
    assert doc["inertia"]["Izz"]["value"] == pytest.approx(110**2 * m * g * r**2 / (4 * np.pi**2 * h), rel=2e-3)


def test_plausible_period_does_not_warn_about_units():
    code, out, err = run(["invert", CONFIGS / "thesis_plate_rest.yaml", "--period", "torsion=1.8+-0.001",
                          "--amplitude", "0", "--json"])
    assert code == 0, err
    assert not [w for w in json.loads(out)["warnings"] if "unit slip" in w] and "unit slip" not in err


def test_plausibility_rule_bounds():
    from bifilar.estimation.period_specs import PLAUSIBLE_PERIOD, implausible_period

    lo, hi = PLAUSIBLE_PERIOD
    assert implausible_period(lo, "torsion", "--period") is None
    assert implausible_period(hi, "torsion", "--period") is None
    assert "minutes" in implausible_period(lo / 2, "torsion", "--period")
    assert "ms" in implausible_period(hi * 2, "torsion", "--period")


# -- 9. timed totals typed in ms warn ------------------------------------------

def test_period_timed_totals_in_ms_warn():
    code, out, err = run(["period", "--timed", "torsion=10:15200,15210", "--json"])
    assert code == 0, err
    doc = json.loads(out)
    assert doc["period"] == pytest.approx(1520.5)
    (w,) = doc["warnings"]
    assert w.startswith("--timed:") and "ms" in w and "1.5205 s" in w
    assert err.strip() == f"warning: {w}"


def test_period_of_a_recording_with_its_time_column_in_ms_warns(tmp_path):
    # a damped 1.3 s oscillation whose time column was written in ms: the fit is right in the column's
    # unit (1300 "s"), and the warning names the ms reading (1.3 s) and where the time scale came from
    t = np.arange(0.0, 20.0, 0.01)
    y = np.exp(-0.05 * t) * np.sin(2 * np.pi * t / 1.3) + 0.01 * np.random.default_rng(1).normal(size=t.size)
    for scale, warns in ((1000.0, True), (1.0, False)):
        p = tmp_path / f"rec{scale:g}.csv"
        np.savetxt(p, np.c_[t * scale, y], delimiter=",", header="t,x", comments="")
        code, out, err = run(["period", p, "--json"])
        assert code == 0, err
        doc = json.loads(out)
        assert doc["period"] == pytest.approx(1.3 * scale, rel=1e-3)
        ws = [w for w in doc["signal"]["warnings"] if "unit slip" in w]
        if warns:
            (w,) = ws
            assert "in ms it would be 1.3" in w and "column 't'" in w and "cycles" not in w
            assert f"warning: {w}" in err
        else:
            assert ws == []


@pytest.mark.parametrize("header, scale, sep, comma", [
    ("time [ms],x", 1000.0, ",", False), ("t_ms,x", 1000.0, ",", False), ("Zeit;Winkel", 1.0, ";", True),
    ("temps (s),x", 1.0, ",", False)])
def test_time_columns_named_in_ms_or_another_language_are_read(tmp_path, header, scale, sep, comma):
    # the same 1.3 s recording: a time column whose name says ms is converted to s, a German or French
    # name is recognised as time; each gives the period of the plain 't,x' file (same samples)
    t = np.arange(0.0, 20.0, 0.01)
    y = np.exp(-0.05 * t) * np.sin(2 * np.pi * t / 1.3) + 0.01 * np.random.default_rng(1).normal(size=t.size)
    ref = tmp_path / "ref.csv"
    np.savetxt(ref, np.c_[t, y], delimiter=",", header="t,x", comments="", fmt="%.9g")
    p = tmp_path / "rec.csv"
    rows = [f"{a:.9g}{sep}{b:.9g}" for a, b in zip(t * scale, y)]
    p.write_text("\n".join([header] + [r.replace(".", ",") if comma else r for r in rows]) + "\n")
    (c0, o0, e0), (c1, o1, e1) = run(["period", ref, "--json"]), run(["period", p, "--json"])
    assert c0 == 0 and c1 == 0, e1
    d0, d1 = json.loads(o0), json.loads(o1)
    assert d1["period"] == pytest.approx(d0["period"], rel=1e-9) and d1["period"] == pytest.approx(1.3, rel=1e-3)
    assert not [w for w in d1["signal"]["warnings"] if "unit slip" in w]
    assert ("ms, converted to s" in d1["signal"]["time_source"]) == (scale != 1.0)


def test_period_timed_plausible_totals_do_not_warn():
    code, out, err = run(["period", "--timed", "torsion=10:15.20,15.21", "--json"])
    assert code == 0 and json.loads(out)["warnings"] == [] and err == ""


def test_invert_timed_totals_in_ms_warn_when_reachable(tmp_path):
    """The same rule as --period (one function): totals of 10 cycles
    typed as 1100 'seconds' give 110 s, which the slow rig reaches."""
    code, out, err = run(["invert", _slow(tmp_path), "--timed", "torsion=10:1100,1101", "--amplitude", "0", "--json"])
    assert code == 0, err
    slip = [w for w in json.loads(out)["warnings"] if "unit slip" in w]
    assert len(slip) == 1 and slip[0].startswith("--timed:") and "look like ms" in slip[0]


# -- 5. an unreachable period's refusal names the likely slip ------------------

PLATE = CONFIGS / "thesis_plate_rest.yaml"
# the plate's torsion period over its whole physical Izz range (the refusal's own range)
PLATE_TORSION = (1.47587681, 1.90535322)


@pytest.mark.parametrize("period, slip", [
    ("1523", "reachable as 1.523 s: was it entered in ms?"),            # 1.523 s in ms
    ("15.2", "8, 9, 10 times a reachable period"),                      # 15.2 / 8..10 = 1.9 .. 1.52
    ("0.8", "1/N of a reachable period for N = 2 (1.6 s)"),             # a half period
    ("2.5", None),                                                      # 1.25 s, 5 s, 2.5 ms: none reachable
    ("1e300", None),
])
def test_unreachable_period_names_only_a_slip_that_reaches_the_range(period, slip):
    code, out, err = run(["invert", PLATE, "--period", f"torsion={period}", "--json"])
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and err.startswith("error: --period: no physical Izz")
    if slip is None:
        assert "likely slip" not in err
    else:
        assert "likely slip" in err and slip in err


def test_slip_hint_only_names_slips_landing_in_the_range():
    from bifilar.estimation.roots import slip_hint

    rng = [PLATE_TORSION]
    assert slip_hint(1523.0, rng).count("ms") == 1 and "cycles" not in slip_hint(1523.0, rng)
    assert slip_hint(3.2, rng) == "; likely slip: it is 2 times a reachable period (1.6 s): is it the total time of " \
                                  "that many cycles?"
    assert slip_hint(1000.0, rng) == ""         # 1 s, 10 .. 11.1 s or 0.1 .. 0.2 ks: none inside
    assert slip_hint(1.0, [(1.5, 1.6), (3.5, 3.6)]) == ""   # gaps of the range count as unreachable
    assert "N = 2" not in slip_hint(0.3, rng) and "N = 5, 6" in slip_hint(0.3, rng)


def test_timed_totals_in_ms_refused_naming_ms_when_unreachable():
    """Item 9: totals of 10 cycles in ms give 1800 s, which no Izz reaches:
    the refusal (not merely a warning) names the slip."""
    code, out, err = run(["invert", PLATE, "--timed", "torsion=10:18000,18010", "--json"])
    assert code == 2 and out == ""
    assert err.startswith("error: --timed: no physical Izz") and "reachable as 1.8005 s" in err


def test_several_unknowns_refusal_names_the_ms_slip(tmp_path):
    """The fit-check refusal of several periods and unknowns: the pitch period
    typed in ms (1913.6 for 1.9136 s)."""
    doc = yaml.safe_load((CONFIGS / "measurements_example.yaml").read_text())
    doc["config"] = str(CONFIGS / doc["config"])
    doc["measurements"][1]["period"] = "1913.6 +- 0.5"
    p = tmp_path / "m.yaml"
    p.write_text(yaml.safe_dump(doc))
    code, out, err = run(["invert", "--measurements", p, "--json"])
    assert code == 2 and out == ""
    assert err.startswith("error: measurements.1.period:") and "reachable as 1.9136 s: was it entered in ms?" in err


def test_refuse_unreachable_names_the_slip():
    from bifilar.estimation.measurements import load_measurements
    from bifilar.estimation.problem import build_problem
    from bifilar.estimation.roots import _refuse_unreachable
    from bifilar.errors import InputError

    ms = load_measurements(CONFIGS / "measurements_example.yaml")
    pb = build_problem(ms, ms.solve_for, ms.uncertainty)
    targets = np.array([m.period for m in pb.measurements])
    ms_targets = targets.copy()
    ms_targets[1] *= 1000
    pb.measurements[1].period = ms_targets[1]
    with pytest.raises(InputError) as exc:
        _refuse_unreachable(pb, ms_targets)
    assert exc.value.field == "measurements.1.period" and "was it entered in ms?" in exc.value.message
    pb.measurements[1].period = 1e300
    with pytest.raises(InputError) as exc:
        _refuse_unreachable(pb, np.array([targets[0], 1e300, targets[2]]))
    assert "likely slip" not in exc.value.message


# -- 4. --solve-for a component no given period depends on -----------------

def test_solving_ixx_from_a_torsion_period_names_the_mode_that_measures_it():
    """The plate's torsion period is the same for every physical Ixx (its
    own range refusal printed 1.90535131 s .. 1.90535131 s), and at that very
    period the solver failed with an internal error (singular matrix)."""
    for period in ("1.9", "1.90535131+-0.001"):
        code, out, err = run(["invert", PLATE, "--period", f"torsion={period}", "--solve-for", "Ixx", "--json"])
        assert code == 2 and out == "", err
        (line,) = err.strip().splitlines()
        assert line.startswith("error: --solve-for: Ixx cannot be solved for: no measured period ('torsion')")
        assert "time mode 'swing-y'" in line


def test_swing_y_does_measure_ixx_as_the_refusal_says():
    """The mode the refusal names really measures Ixx: timing it, Ixx is
    solved (the plate's swing-y period at its own Ixx gives that Ixx back)."""
    from bifilar.analysis.equilibrium import rest_pose
    from bifilar.analysis.modes import linear_modes
    from bifilar.config import load_scene

    sc = load_scene(PLATE)
    T = linear_modes(sc, rest_pose(sc)).get("swing-y").period
    code, out, err = run(["invert", PLATE, "--period", f"swing-y={T!r}+-0.0001", "--solve-for", "Ixx",
                          "--amplitude", "0", "--json", "--no-ladder"])
    assert code == 0, err
    assert json.loads(out)["inertia"]["Ixx"]["value"] == pytest.approx(sc.inertia[0, 0], rel=1e-6)


def test_component_no_mode_of_the_hanging_measures_is_refused():
    code, out, err = run(["invert", PLATE, "--period", "torsion=1.9", "--period", "swing-x=4.17",
                          "--solve-for", "Iyy", "--solve-for", "Izz", "--json"])
    assert code == 2 and out == ""
    assert err.startswith("error: --solve-for: Iyy cannot be solved for") and "hang the body another way" in err


# -- 10. an irregularly sampled time column -----------------------------------

def _damped(t, T=1.7, zeta=0.002, phase=0.3):
    w = 2 * np.pi / T
    return np.exp(-zeta * w * t) * np.cos(w * t + phase)


def _write_csv(path, t, y, header="t,angle", delimiter=","):
    np.savetxt(path, np.c_[t, y], delimiter=delimiter, header=header, comments="", fmt="%.10g")
    return path


def test_exponential_sampling_intervals_are_accepted_and_fit_within_the_std():
    """Random (exponential, mean 10 ms) intervals between 3000 samples: no
    step is anywhere near 2 % of the record, but the samples 'covered only
    69 % of the span at the median step' and were refused.  The fit must
    recover the period with a calibrated std: z = (T - 1.7) / std over 12
    records has mean ~0 and spread ~1."""
    from bifilar.estimation.signal import fit_period

    z = []
    for seed in range(12):
        rng = np.random.default_rng(seed)
        t = np.cumsum(rng.exponential(0.01, 3000))
        fit = fit_period(t, _damped(t) + rng.normal(0, 0.01, t.size))
        z.append((fit.period - 1.7) / fit.std)
    z = np.array(z)
    assert np.all(np.abs(z) < 4)
    assert abs(z.mean()) < 3 / np.sqrt(z.size) and 0.4 < z.std() < 1.8


def test_exponential_sampling_through_the_cli(tmp_path):
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.exponential(0.01, 3000))
    p = _write_csv(tmp_path / "irregular.csv", t, _damped(t) + rng.normal(0, 0.01, t.size))
    code, out, err = run(["period", p, "--json"])
    assert code == 0, err
    doc = json.loads(out)
    assert abs(doc["period"] - 1.7) < 4 * doc["std"]


def test_one_huge_gap_is_still_refused_quickly(tmp_path):
    """Resampling 1e7 s at 10 ms would allocate 1e9 samples: the gap is
    refused by the O(n) check first (and at once)."""
    import time

    t = np.arange(0, 30, 0.01)
    t[1500:] += 1e7
    p = _write_csv(tmp_path / "gap.csv", t, np.cos(2 * np.pi * t / 1.7))
    t0 = time.perf_counter()
    code, out, err = run(["period", p, "--json"])
    assert time.perf_counter() - t0 < 2.0
    assert code == 2 and out == "" and err.startswith("error: time: gap of") and len(err.splitlines()) == 1


def test_bunched_samples_are_refused_without_a_huge_grid():
    from bifilar.estimation.signal_io import SignalError, check_time

    base = np.arange(0, 20, 0.05)
    t = np.sort(np.r_[base, base + 1e-6, base + 2e-6])  # a median step of 1 us over 20 s: 2e7 grid points
    with pytest.raises(SignalError) as e:
        check_time(t)
    assert e.value.field == "time" and "bunched" in e.value.message


# -- 7. a decimal-comma CSV from a European spreadsheet ---------------------------

def _recording(seed=3):
    rng = np.random.default_rng(seed)
    t = np.arange(0, 20, 0.01)
    return t, 0.05 * _damped(t, T=1.3, zeta=0.002) + rng.normal(0, 1e-4, t.size)


def _euro(path, t, y, header="t;angle", sep=";", fmt="{:.4f}{sep}{:.6f}"):
    lines = [header] + [fmt.format(a, b, sep=sep).replace(".", ",") for a, b in zip(t, y)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_decimal_comma_semicolon_csv_reads_as_the_same_numbers_with_points(tmp_path):
    t, y = _recording()
    euro = _euro(tmp_path / "euro.csv", t, y)
    plain = tmp_path / "plain.csv"
    plain.write_text("t,angle\n" + "".join(f"{a:.4f},{b:.6f}\n" for a, b in zip(t, y)))
    from bifilar.estimation.signal import read_signal

    te, ye, me = read_signal(euro)
    tp, yp, _ = read_signal(plain)
    assert me["decimal"] == "comma" and np.array_equal(te, tp) and np.array_equal(ye, yp)
    code, out, err = run(["period", euro, "--json"])
    assert code == 0, err
    doc = json.loads(out)
    assert doc["signal"]["decimal"] == "comma"
    assert abs(doc["period"] - 1.3) < 4 * doc["std"]


def test_decimal_comma_without_header_and_with_tabs(tmp_path):
    t, y = _recording()
    p = _euro(tmp_path / "tabs.txt", t, y, header="time\tangle", sep="\t")
    code, out, err = run(["period", p, "--json"])
    assert code == 0, err
    assert abs(json.loads(out)["period"] - 1.3) < 1e-3
    lines = p.read_text().splitlines()[1:]
    q = tmp_path / "noheader.csv"
    q.write_text("\n".join(ln.replace("\t", ";") for ln in lines) + "\n")
    code, out, err = run(["period", q, "--sample-rate", "100", "--column", "col2", "--json"])
    assert code == 0, err
    assert abs(json.loads(out)["period"] - 1.3) < 1e-3


@pytest.mark.parametrize("header, sep, fmt, fragment", [
    ("t,angle", ",", "{:.4f}{sep}{:.6f}", "decimal commas in a comma-separated table"),
    ("t;angle", ";", "{:.4f}{sep}1.{:.6f}", "has both a comma and a point"),     # 1.0,05 style thousands
])
def test_ambiguous_decimal_marks_are_refused_with_one_line(tmp_path, header, sep, fmt, fragment):
    t, y = _recording()
    p = _euro(tmp_path / "amb.csv", t, y, header=header, sep=sep, fmt=fmt)
    if "1." in fmt:  # put the point back into the second cell: '1.0,050204'
        p.write_text(p.read_text().replace(";1,", ";1."))
    code, out, err = run(["period", p, "--json"])
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and fragment in err and "amb.csv" in err


def test_mixed_decimal_marks_are_refused(tmp_path):
    t, y = _recording()
    text = "t;angle\n" + "".join(f"{a:.4f};{b:.6f}\n".replace(".", ",", 1) for a, b in zip(t, y))
    p = tmp_path / "mixed.csv"
    p.write_text(text)  # time '0,0100', angle '0.049681'
    code, out, err = run(["period", p, "--json"])
    assert code == 2 and "decimal comma" in err and "decimal point" in err


# -- 8. a refused recording names its columns -----------------------------------

def _table(path, header, row):
    t = np.arange(0, 20, 0.01)
    y = np.cos(2 * np.pi * t / 1.3)
    path.write_text(header + "\n" + "".join(row(a, b, i) for i, (a, b) in enumerate(zip(t, y))))
    return path


def _refused(args, field):
    code, out, err = run(args)
    assert code == 2 and out == "", err
    (line,) = err.strip().splitlines()
    assert line.startswith(f"error: {field}:")
    return line


def test_no_numeric_column_lists_the_columns(tmp_path):
    p = _table(tmp_path / "text.csv", "t,label,note", lambda a, b, i: f"{a:.4f},run1,ok\n")
    line = _refused(["period", p, "--json"], "signal")
    assert "no numeric column" in line and "columns found: t, label, note" in line


def test_a_text_column_given_lists_the_numeric_ones(tmp_path):
    p = _table(tmp_path / "mixed.csv", "t,label,angle", lambda a, b, i: f"{a:.4f},run1,{b:.6f}\n")
    line = _refused(["period", p, "--column", "label", "--json"], "--column")
    assert "'label'" in line and "numeric columns: t, angle" in line and "columns found: t, label, angle" in line
    line = _refused(["period", p, "--column", "angel", "--json"], "--column")
    assert "t, label, angle" in line


def test_default_column_skips_a_leading_text_column_and_says_so(tmp_path):
    p = _table(tmp_path / "mixed.csv", "t,label,angle", lambda a, b, i: f"{a:.4f},run1,{b:.6f}\n")
    code, out, err = run(["period", p, "--model", "viscous", "--json"])
    assert code == 0, err
    doc = json.loads(out)
    assert doc["signal"]["column"] == "angle" and abs(doc["period"] - 1.3) < 1e-6
    assert "'label' skipped" in err


def test_text_later_in_the_file_and_empty_column_list_the_columns(tmp_path):
    p = _table(tmp_path / "late.csv", "t,angle",
               lambda a, b, i: f"{a:.4f},{'oops' if i == 1500 else f'{b:.6f}'}\n")
    line = _refused(["period", p, "--json"], "signal")
    assert "'oops'" in line and "line 1502" in line and "columns found: t, angle" in line
    q = _table(tmp_path / "empty.csv", "t,angle,rate", lambda a, b, i: f"{a:.4f},,{b:.6f}\n")
    line = _refused(["period", q, "--json"], "signal")
    assert "NaN or missing" in line and "columns found: t, angle, rate" in line


# -- 3. a leading stretch at rest is left out of the period fit ---------------------

def _rest_then_decay(seed=0, t_rest=5.0, T=1.7, zeta=0.003, noise=0.002, duration=25.0, fs=100.0):
    rng = np.random.default_rng(seed)
    t = np.arange(0, duration, 1 / fs)
    w = 2 * np.pi / T
    tau = t - t_rest
    y = np.where(tau >= 0, np.exp(-zeta * w * tau) * np.sin(w * tau), 0.0)
    return t, y + rng.normal(0, noise, t.size)


def test_leading_rest_is_detected_and_the_fit_starts_at_the_onset():
    """5 s of noise, then a damped sinusoid from t = 5 s.  The reference is
    the same record cut at the true onset (an independent fit of the decay
    alone): the period must agree within its std and the std must not be
    inflated (it was x1600, the flat stretch fitted as part of the decay)."""
    from bifilar.estimation.signal import fit_period

    t, y = _rest_then_decay()
    fit = fit_period(t, y, model="viscous")
    ref = fit_period(t[t >= 5.0], y[t >= 5.0], model="viscous")
    rest = fit.oscillation["leading_rest"]
    assert abs(rest["onset"] - 5.0) < 1.7 / 10                       # onset within a tenth of a period
    assert 5.0 < fit.t0 == rest["t_start"] < 5.0 + 1.7                 # the fit starts after it, within a period
    assert abs(fit.period - 1.7) < 4 * fit.std
    assert fit.std < 2 * ref.std
    assert any(n.startswith("leading rest:") for n in fit.notes)


def test_leading_rest_through_the_cli_reports_the_start_used(tmp_path):
    t, y = _rest_then_decay(seed=1, t_rest=4.2)
    p = _write_csv(tmp_path / "rest.csv", t, y)
    code, out, err = run(["period", p, "--json"])
    assert code == 0, err
    doc = json.loads(out)
    rest = doc["oscillation"]["leading_rest"]
    assert abs(rest["onset"] - 4.2) < 0.17 and doc["t0"] == pytest.approx(rest["t_start"])
    assert abs(doc["period"] - 1.7) < 4 * doc["std"] and doc["std"] < 1e-4
    code, out, err = run(["period", p])
    assert code == 0 and "leading rest" in out and "fit starts at t =" in out


def test_a_record_that_starts_oscillating_is_fitted_whole():
    from bifilar.estimation.signal import fit_period

    t, y = _rest_then_decay(t_rest=0.0)
    fit = fit_period(t, y, model="viscous")
    assert "leading_rest" not in fit.oscillation and fit.t0 == t[0]
    t2, y2 = _rest_then_decay(t_rest=5.0)
    fixed = fit_period(t2, y2, model="viscous", t_start=2.0)  # an explicit window is the user's choice
    assert "leading_rest" not in fixed.oscillation and fixed.t0 >= 2.0


# -- 6. the point plan/sweep recommends gets the config plausibility checks -------

def test_sweep_recommended_point_gets_the_plausibility_warnings():
    """Attachments 30 m from the CoM of a plate whose bounding box reaches
    2.5 m: the config rule (more than 10x the body) calls that a rig in other
    units; the recommended point never went through it."""
    from bifilar.config import plausibility_warnings, scene_from_dict

    code, out, err = run(["sweep", PLATE, "--param", "spacing=60", "--param", "ceiling_spacing=65", "--zip", "--json",
                          "--sigma", "position=0", "--sigma", "com=0"])  # no derivative at the plate's knife edge
    assert code == 0, err
    doc = json.loads(out)
    # (the plate is flat: its Izz also sits on the physical limit, tests/test_planner_closed_loop.py; and at its
    # knife edge a product moves the torsion at second order, Izz - Iyz^2/Iyy: the priors' caution)
    (w,) = [w for w in doc["warnings"] if "physical limit" not in w and "not solved for" not in w]
    assert w.startswith("the recommended point: rig.attachments reach 30 m") and "2.5 m" in w
    assert f"warning: {w}" in err.splitlines()
    # the same words as the config loader gives for that rig written out
    cfg = yaml.safe_load(PLATE.read_text())
    cfg["rig"]["attachments"] = [[0.0, -30.0, 0.0], [0.0, 30.0, 0.0]]
    cfg["rig"]["anchors"] = [[0.0, -32.5, 0.0], [0.0, 32.5, 0.0]]
    assert w.split(": ", 1)[1] in plausibility_warnings(scene_from_dict(cfg, warn=False))


def test_plan_planned_point_gets_the_plausibility_warnings():
    code, out, err = run(["plan", PLATE, "--param", "spacing=54:60", "--param", "ceiling_spacing=59:65", "--zip",
                          "--json", "--sigma", "position=0", "--sigma", "com=0"])  # the knife edge's inputs exact
    assert code == 0, err
    doc = json.loads(out)
    ws = [w for w in doc["warnings"] if "physical limit" not in w and "not solved for" not in w]  # two others
    assert len(ws) == 1 and ws[0].startswith("the planned point: rig.attachments reach")
    assert "warning: the planned point:" in err


def test_a_plausible_recommended_point_does_not_warn():
    code, out, err = run(["sweep", PLATE, "--param", "spacing=4,5", "--json"])
    assert code == 0, err
    assert json.loads(out)["warnings"] == [] and "warning" not in err
