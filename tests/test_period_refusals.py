"""`bifilar period` refuses what is not an oscillation (exit 2, one line
naming the reason), checks the time column before any resampling, and
reduces stopwatch trials with a reaction-time floor and Student t."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats

from bifilar.cli import main
from bifilar.estimation import period_specs as ps
from bifilar.estimation.signal import SignalError, check_time, fit_period

T_GRID = np.arange(0, 20, 0.01)  # 2000 samples, 100 Hz


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write(path, t, y):
    path.write_text("t,y\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t.tolist(), y.tolist())))
    return path


def signals():
    rng = np.random.default_rng(1)
    t = T_GRID
    spike = 0.01 * rng.standard_normal(t.size)
    spike[500] = 10.0
    return {
        "noise": (t, rng.standard_normal(t.size), "no significant spectral peak"),
        "spike": (t, spike, "no significant spectral peak"),
        # linear sweep 0.5 -> 20.5 Hz: power spread over the band, no peak
        "chirp": (t, np.cos(2 * np.pi * (0.5 * t + 0.5 * t ** 2)) + 0.01 * rng.standard_normal(t.size),
                  "no significant spectral peak"),
        # half a cycle of a 40 s oscillation
        "sub-cycle": (t, np.cos(2 * np.pi * t / 40) + 1e-3 * rng.standard_normal(t.size), "fewer than 2 cycles"),
    }


@pytest.mark.parametrize("case", ["noise", "spike", "chirp", "sub-cycle"])
def test_not_an_oscillation_is_refused(case):
    t, y, fragment = signals()[case]
    with pytest.raises(SignalError) as e:
        fit_period(t, y, model="auto")
    assert e.value.field == "signal" and fragment in str(e.value)


def test_noise_false_alarm_rate_is_the_stated_one():
    """The spectral-peak test refuses pure noise: over 200 white-noise
    records it may accept at most a few (false-alarm probability 1e-3 per
    record: expected 0.2; P(>= 3) < 1e-3)."""
    rng = np.random.default_rng(3)
    accepted = 0
    for _ in range(200):
        try:
            fit_period(T_GRID, rng.standard_normal(T_GRID.size), crossing_check=False, split_check=False)
            accepted += 1
        except SignalError:
            pass
    assert accepted <= 2


def test_a_fit_explaining_almost_nothing_is_refused():
    """A significant but tiny line in strong noise: the peak passes, but a
    fit with r^2 below 10 % is not a usable period."""
    rng = np.random.default_rng(4)
    t = np.arange(0, 200, 0.01)  # long record: a weak line is still significant
    y = 0.2 * np.cos(2 * np.pi * t / 1.3) + rng.standard_normal(t.size)
    with pytest.raises(SignalError) as e:
        fit_period(t, y)
    assert "explains only" in str(e.value)


@pytest.mark.parametrize("last,fragment", [(1e7, "gap of"), (1e12, "gap of")])
def test_huge_gap_refused_without_allocating_by_the_span(last, fragment):
    t = T_GRID.copy()
    t[-1] = last  # resampling at 10 ms over 1e12 s would need 1e14 samples
    with pytest.raises(SignalError) as e:
        fit_period(t, np.cos(2 * np.pi * T_GRID / 1.3))
    assert e.value.field == "time" and fragment in str(e.value)


def test_many_small_gaps_refused():
    # 30 steps of 0.31 s (30 samples removed each: 1.6 % of the record, under
    # the single-gap limit) leave 1 - 30 x 0.31 / 19.99 = 53 % of the span covered
    keep = np.ones(T_GRID.size, bool)
    for k in range(30):
        keep[60 * k + 20:60 * k + 50] = False
    with pytest.raises(SignalError) as e:
        check_time(T_GRID[keep])
    assert e.value.field == "time" and "cover only 53%" in str(e.value)


def test_a_change_of_sample_rate_is_not_a_gap():
    # dense first third, then every third sample: irregular sampling, no gap
    # (it was refused as covering ~2/3 of the span at the median step)
    t = np.r_[T_GRID[:600], T_GRID[600::3]]
    check_time(t)
    fit = fit_period(t, np.cos(2 * np.pi * t / 1.3) + np.random.default_rng(0).normal(0, 0.01, t.size))
    assert abs(fit.period - 1.3) < 4 * fit.std


def test_cli_refusals_exit_2_with_one_line(tmp_path):
    for case, (t, y, fragment) in signals().items():
        r = run("period", write(tmp_path / f"{case}.csv", t, y), "--json")
        assert r.exit_code == 2, (case, r.output)
        assert fragment in r.output and "Traceback" not in r.output
    t = T_GRID.copy()
    t[100] = t[99]
    r = run("period", write(tmp_path / "nonmono.csv", t, np.cos(t)), "--json")
    assert r.exit_code == 2 and "not strictly increasing" in r.output
    t = T_GRID.copy()
    t[-1] = 1e12
    r = run("period", write(tmp_path / "gap.csv", t, np.cos(2 * np.pi * T_GRID / 1.3)), "--json")
    assert r.exit_code == 2 and "gap of" in r.output


def test_cli_json_reports_choice_and_uncertainty_terms(tmp_path):
    rng = np.random.default_rng(2)
    t = T_GRID
    y = np.exp(-0.02 * t) * np.cos(2 * np.pi * t / 1.3) + 0.3 * np.cos(2 * np.pi * t / 2.1) \
        + 0.01 * rng.standard_normal(t.size)
    r = run("period", write(tmp_path / "two.csv", t, y), "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert {"period", "std", "damping_ratio"} <= set(doc)
    assert doc["model"] == "two_mode" and "lowest BIC" in doc["choice_reason"]
    assert doc["selection"]["ranking"][0].startswith("two_mode")
    u = doc["uncertainty"]
    assert u["total"] == doc["std"] and u["dominant"] in ("noise", "serial_correlation", "nonstationarity")
    assert abs(doc["period"] - 1.3) < 3 * doc["std"]
    assert "peaks" in doc["residual_check"]


# ---------------------------------------------------------------------------
# timed trials
# ---------------------------------------------------------------------------

def test_identical_trials_never_more_uncertain_than_near_identical():
    _, s_same, d_same = ps.period_from_trials(10, [15.20, 15.20])
    _, s_near, d_near = ps.period_from_trials(10, [15.20, 15.21])
    _, s_three, _ = ps.period_from_trials(10, [15.20, 15.20, 15.21])
    assert s_same <= s_near
    # both below the 0.1 s reaction floor: the floor sets the trial std
    assert d_same["trial_std"] == d_near["trial_std"] == 0.1
    # the example: 3 trials, 0.1 / sqrt(3) / 10 s, not the 0.33 ms of the scatter
    assert s_three == pytest.approx(0.1 / math.sqrt(3) / 10, rel=1e-12)


def test_student_t_interval_for_few_scattered_trials():
    times = [15.0, 15.4, 15.8]  # scatter 0.4 s > 0.1 s floor
    T, s, det = ps.period_from_trials(10, times)
    assert det["dof"] == 2
    k = stats.t.ppf(0.975, 2)  # 4.30, not 1.96
    assert det["coverage_factor"] == pytest.approx(k)
    assert det["interval95"] == pytest.approx([T - k * s, T + k * s])


def test_reaction_floor_overridable_from_the_cli():
    r = run("period", "--timed", "torsion=10:15.20,15.20,15.21", "--uncertainty", "trial_time=0.02", "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["timed"]["floor"] == 0.02
    assert doc["std"] == pytest.approx(0.02 / math.sqrt(3) / 10)


def test_target_gives_cycles_and_trials_that_reach_it():
    r = run("period", "--timed", "torsion=10:15.20,15.20,15.21", "--target", "0.1%", "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    goal = doc["target"]["target_std"]
    assert goal == pytest.approx(1e-3 * doc["period"])
    for o in doc["target"]["options"]:
        # the plan reaches the target, and one cycle fewer would not
        assert 0.1 / (math.sqrt(o["trials"]) * o["cycles"]) <= goal * (1 + 1e-12)
        if o["cycles"] > 1:
            assert 0.1 / (math.sqrt(o["trials"]) * (o["cycles"] - 1)) > goal
    r = run("period", "--timed", "torsion=10:15.2", "--target", "-1%")
    assert r.exit_code == 2 and "--target" in r.output


def test_invert_refuses_a_noise_recording(tmp_path):
    """invert --signal used to turn pure noise into an inertia."""
    from conftest import CONFIGS

    t, y, _ = signals()["noise"]
    r = run("invert", CONFIGS / "thesis_lin1_torsion.yaml", "--signal",
            f"torsion={write(tmp_path / 'noise.csv', t, y)}", "--json")
    assert r.exit_code == 2 and "no significant spectral peak" in r.output
