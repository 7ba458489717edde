"""Session 27 (runs27): a sweep point's runs with less Python around odeint,
every shortcut against the path it replaces, bit for bit (docs/design.md,
"runs27, session 27"):

* the runs' crossings up to each run's end, sorted and scaled in one pass
  (``batch_lsoda._close``) against the run-by-run loop it replaced;
* a run's figures from Python floats (``batch._run_group``'s per-run loop:
  ``tolist`` once, each scene's ceiling once) on a batch of distinct scenes
  against each scene run alone;
* the body's support function taking the directions into each part frame
  once per distinct rotation (``parts.support``) against part by part;
* the lowest point's fold of runs of one body without ``np.isin``
  (``LowestPoint.fold``) against each run's own fold;
* a scene's float parameters (and so its compiled kernels) shared by the
  calls of one point (``batch._scene_params``) against fresh ones, and not
  kept past the scene.

The degree-7 roots written out (``integrators._root_unit_scalar``) are held
by tests/test_run_cost.py's roots test (floats against the vectorised
iteration), ``maximal._zero_set``'s reordered test by
tests/test_point_cost.py's (against the old function).
"""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pytest

import bifilar.analysis.batch as batch
import bifilar.models.maximal as mx
from bifilar import parts as P
from bifilar.analysis.batch import simulate_batch
from bifilar.analysis.batch_health import LowestPoint
from bifilar.analysis.batch_lsoda import _close
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import read_yaml, scene_from_dict
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS


def _scene(name, params=None):
    cfg, _ = apply_params(read_yaml(CONFIGS / f"{name}.yaml"), params or {}, name)
    return scene_from_dict(cfg, name, warn=False)


class _Obs:
    def __init__(self, Bn):
        self.t_final, self.y_final, self.cross = np.zeros(Bn), np.zeros((Bn, 13)), [[] for _ in range(Bn)]


def _close_run_by_run(obs, tt, y_last, stop_tau, T_ref, pers, status, cross_cols, cross_t):
    """``_close`` as it was before session 27 (a run at a time)."""
    obs.t_final[:] = np.minimum(tt[-1], stop_tau) * T_ref
    obs.y_final[:] = y_last
    cols = np.concatenate(cross_cols) if cross_cols else np.zeros(0, int)
    tcs = np.concatenate(cross_t) if cross_t else np.zeros(0)
    for b in range(len(T_ref)):
        sel = tcs[cols == b]
        obs.cross[b] = list(np.sort(sel[sel <= stop_tau[b] + 1e-12]) * T_ref[b])
        if stop_tau[b] < pers[b] - 1e-12 and status[b] == 0:
            status[b] = 1


def test_crossings_closed_in_one_pass_equal_run_by_run():
    rng = np.random.default_rng(27)
    for trial in range(60):
        Bn = int(rng.integers(1, 7))
        nwin = int(rng.integers(0, 4))
        cols, ts = [], []
        for w in range(nwin):  # windows: each sorted by run then time, as sampled_crossings gives them
            k = int(rng.integers(0, 12))
            c = rng.integers(0, Bn, size=k)
            t = w * 4.0 + rng.uniform(0, 4.0, size=k)
            if k and trial % 5 == 0:
                t[0] = np.nan  # (no crossing time is NaN; dropped either way)
            if k > 1 and trial % 7 == 0:
                t[1] = t[0]  # a tie
            o = np.lexsort((t, c))
            cols.append(c[o])
            ts.append(t[o])
        if trial % 3 == 0 and nwin > 1:  # windows out of order too
            cols, ts = cols[::-1], ts[::-1]
        pers = rng.uniform(2.0, 4.0 * max(nwin, 1), size=Bn)
        stop_tau = np.where(rng.random(Bn) < 0.3, pers * rng.uniform(0.2, 1.0, size=Bn), pers)
        if trial % 2 == 0:  # crossings just past run 0's end: one within _close's 1e-12 slack, one beyond it
            cols.append(np.array([0, 0]))
            ts.append(stop_tau[0] + np.array([5e-13, 3e-12]))
        T_ref = rng.uniform(0.5, 3.0, size=Bn)
        tt = np.linspace(0.0, float(np.max(pers)), 9)
        y = rng.normal(size=(Bn, 13))
        a, b = _Obs(Bn), _Obs(Bn)
        sa, sb = np.zeros(Bn, int), np.zeros(Bn, int)
        sa[-1] = sb[-1] = -1  # a failed run keeps its status
        _close(a, tt, y, stop_tau, T_ref, pers, sa, list(cols), list(ts))
        _close_run_by_run(b, tt, y, stop_tau, T_ref, pers, sb, list(cols), list(ts))
        assert np.array_equal(sa, sb)
        assert np.array_equal(a.t_final, b.t_final) and np.array_equal(a.y_final, b.y_final)
        for x, ref in zip(a.cross, b.cross):
            x = np.asarray(x)
            assert x.dtype == float and np.array_equal(x.view(np.int64), np.array(ref, float).view(np.int64))


def _figures(r):
    """Every figure of a run, as text (NaN equal to NaN; floats by their repr: their bits)."""
    def b(x):
        return None if x is None else np.asarray(x).tobytes()
    return repr((r.period, r.period_std, b(r.crossings), b(r.tension_min), b(r.tension_max), r.slack, r.depth_max,
                 r.lowest_z_min, r.max_constraint_violation, r.energy_drift, r.energy_drift_resolution, r.period_error,
                 r.nfev, r.nsteps, r.warnings, r.t_final, b(r.y_final), r.linear_period, r.amplitude, r.rtol, r.mode,
                 r.coordinate_name, r.error))


def test_run_figures_from_floats_across_distinct_scenes_equal_each_scene_alone():
    """``independent=True`` runs every scene through one vectorised engine
    whose figures do not depend on the batch: a batch of three scenes with
    different ceilings, rest CoMs and modes gives each scene's figures as
    that scene alone, so the per-run loop reads each run's own row (a
    ceiling, a CoM, a float) -- and its types are JSON's (float, int)."""
    scenes = [_scene("thesis_plate_rest"), _scene("thesis_plate_rest", {"length": 3.0}),
              _scene("trifilar_kth")]
    scenes[1] = scenes[1].__class__(**{**{k: getattr(scenes[1], k) for k in scenes[1].__dataclass_fields__},
                                       "anchors": np.asarray(scenes[1].anchors) + [0.0, 0.0, 0.7]})
    rests = [rest_pose(s) for s in scenes]
    mss = [linear_modes(s, r) for s, r in zip(scenes, rests)]
    labels = [[m.label for m in ms.modes if m.period][k] for ms, k in zip(mss, (0, 2, 1))]
    assert len({s.ceiling_z for s in scenes}) == 3 and len({r.com.tobytes() for r in rests}) == 3
    amps = [0.05, 0.02, 0.08]
    runs = simulate_batch(scenes, mode=labels, amplitude=amps, periods=2.0, rtol=1e-8, rests=rests, modes=mss,
                          independent=True)
    for j, (s, r, ms, lab, a) in enumerate(zip(scenes, rests, mss, labels, amps)):
        alone = simulate_batch([s], mode=lab, amplitude=a, periods=2.0, rtol=1e-8, rests=[r], modes=[ms],
                               independent=True)[0]
        assert _figures(runs[j]) == _figures(alone)
        assert runs[j].depth_max == s.ceiling_z - runs[j].lowest_z_min
        for f in ("period", "max_constraint_violation", "energy_drift", "depth_max", "lowest_z_min", "t_final",
                  "linear_period", "amplitude", "rtol"):
            assert type(getattr(runs[j], f)) is float, f
        assert type(runs[j].nfev) is int and type(runs[j].nsteps) is int
    # the shipped point path too: its law runs (several scenes, no health) as each run alone
    boat = _scene("solar_boat")
    rest = rest_pose(boat)
    ms = linear_modes(boat, rest)
    lab = [m.label for m in ms.modes if m.period][:2]
    heavier = boat.__class__(**{**{k: getattr(boat, k) for k in boat.__dataclass_fields__},
                                "inertia": np.asarray(boat.inertia) * 1.001})
    mh = linear_modes(heavier, rest)
    runs = simulate_batch([boat, heavier, boat], mode=[lab[0], lab[0], lab[1]], amplitude=[0.05, 0.05, 0.025],
                          periods=2.0, rtol=1e-8, rests=[rest] * 3, modes=[ms, mh, ms], health=False)
    for r, s, m, lb, a in zip(runs, [boat, heavier, boat], [ms, mh, ms], [lab[0], lab[0], lab[1]], [0.05, 0.05, 0.025]):
        alone = simulate_batch([s], mode=lb, amplitude=a, periods=2.0, rtol=1e-8, rests=[rest], modes=[m],
                               health=False)[0]
        assert _figures(r) == _figures(alone) and r.period is not None


def _support_part_by_part(parts, D):
    """``parts.support`` as it was before session 27 (each part's frame its own)."""
    best = np.full(D.shape[0], -np.inf)
    for p in parts:
        h = D @ p.position_array + p.geometry.local_support(D @ p.rotation_matrix)
        best = np.maximum(best, h)
    return best


def test_support_with_shared_part_frames_equals_part_by_part():
    cfg = read_yaml(CONFIGS / "solar_boat.yaml")
    boat = [P.part_from_dict(spec) for spec in cfg["body"]["parts"]]
    assert len({p.rotation for p in boat}) < len(boat)  # parts that share a frame
    rng = np.random.default_rng(5)
    # two parts in one tilted frame, far out (each the extreme part in many directions)
    extra = [P.part_from_dict({"name": "tilted", "shape": "box", "mass": 1.0, "size": [3.0, 2.0, 0.5],
                               "position": [6.0, -4.0, -5.0], "rotation": [0.3, -0.2, 0.5]}),
             P.part_from_dict({"name": "tilted too", "shape": "solid_cylinder", "mass": 1.0, "radius": 1.0,
                               "length": 4.0, "position": [-6.0, 4.0, 5.0], "rotation": [0.3, -0.2, 0.5]})]
    for parts in (boat, boat + extra, extra, boat[:1]):
        for k in (1, 7, 579):
            D = rng.normal(size=(k, 3))
            D[0] = [0.0, -0.0, -1.0]  # signed zeros
            assert np.array_equal(P.support(parts, D), _support_part_by_part(parts, D))
        assert P.support(parts, np.array([0.0, 0.0, -1.0])) == _support_part_by_part(parts, np.array([[0.0, 0.0, -1.0]]))[0]


def test_lowest_point_of_runs_of_one_body_without_isin_equals_each_run_alone():
    rng = np.random.default_rng(8)
    boat = _scene("solar_boat")
    plate = _scene("thesis_plate_rest")
    com = np.array([0.1, -0.2, -4.0])
    for scenes in ([boat] * 3, [boat, boat, plate], [plate, boat]):
        Bn = len(scenes)
        low = LowestPoint(scenes, np.tile(com, (Bn, 1)))
        assert [g[2] for g in low.groups] == ([True] if len({id(s) for s in scenes}) == 1 else [False] * 2)
        kb = 50
        q = rng.normal(size=(kb * Bn, 4)) * [1.0, 0.05, 0.05, 0.05] + [1.0, 0.0, 0.0, 0.0]
        z = rng.normal(size=kb * Bn) * 1e-3 - 4.0
        idx = np.tile(np.arange(Bn), kb)
        low.add(idx, z, q)
        got = low.z
        for b, s in enumerate(scenes):
            own = LowestPoint([s], com[None, :])
            own.add(np.zeros(kb, int), z[idx == b], q[idx == b])
            assert got[b].tobytes() == own.z[0].tobytes()


def test_a_scenes_parameters_shared_by_a_points_calls_and_not_kept_past_it(monkeypatch):
    """The point's own runs and then its amplitude laws' runs of the same
    scene (one call each, as ``point_amplitude._runs_at`` makes them): the
    second call builds no parameter values for that scene; every figure as
    with fresh parameters; a new scene object (the next point) shares
    nothing; the entry goes with the scene."""
    boat = _scene("solar_boat")
    rest = rest_pose(boat)
    ms = linear_modes(boat, rest)
    lab = [m.label for m in ms.modes if m.period][:2]
    builds = []
    real = mx._param_values

    def counted(Pr):
        builds.append(1)
        return real(Pr)

    monkeypatch.setattr(mx, "_param_values", counted)
    n0 = len(batch._SCENE_PARAMS)
    own = simulate_batch([boat] * 2, mode=lab, amplitude=0.05, periods=2.0, rtol=1e-8, rests=[rest] * 2, modes=[ms] * 2)
    assert len(builds) == 1
    heavier = boat.__class__(**{**{k: getattr(boat, k) for k in boat.__dataclass_fields__},
                                "inertia": np.asarray(boat.inertia) * 1.001})
    mh = linear_modes(heavier, rest)
    law = simulate_batch([boat, heavier], mode=[lab[0]] * 2, amplitude=[0.03, 0.05], periods=2.0, rtol=1e-8,
                         rests=[rest] * 2, modes=[ms, mh], health=False)
    assert len(builds) == 2  # the heavier scene's only
    batch._SCENE_PARAMS.clear()  # fresh parameters: the same figures
    builds.clear()
    own2 = simulate_batch([boat] * 2, mode=lab, amplitude=0.05, periods=2.0, rtol=1e-8, rests=[rest] * 2,
                          modes=[ms] * 2)
    batch._SCENE_PARAMS.clear()
    law2 = simulate_batch([boat, heavier], mode=[lab[0]] * 2, amplitude=[0.03, 0.05], periods=2.0, rtol=1e-8,
                          rests=[rest] * 2, modes=[ms, mh], health=False)
    assert len(builds) == 3
    assert [_figures(r) for r in own + law] == [_figures(r) for r in own2 + law2]
    # another scene object (a point builds its scene anew), the same values: nothing shared
    builds.clear()
    again = _scene("solar_boat")
    simulate_batch([again] * 2, mode=lab, amplitude=0.05, periods=2.0, rtol=1e-8, rests=[rest] * 2, modes=[ms] * 2)
    assert len(builds) == 1
    keys = set(batch._SCENE_PARAMS)
    assert id(again) in keys and id(boat) in keys
    # an entry under an id that is now another scene's (an id reused) is not taken
    builds.clear()
    third = _scene("solar_boat")
    batch._SCENE_PARAMS[id(third)] = (weakref.ref(boat), {np.asarray(rest.com, float).tobytes(): "stale"})
    simulate_batch([third] * 2, mode=lab, amplitude=0.05, periods=2.0, rtol=1e-8, rests=[rest] * 2, modes=[ms] * 2)
    assert len(builds) == 1 and batch._SCENE_PARAMS[id(third)][0]() is third
    del boat, again, third, heavier, own, law, own2, law2
    gc.collect()
    assert len(batch._SCENE_PARAMS) <= n0


def _trimmed_complete_numpy(run, end, periods):
    """``point_amplitude._trimmed_complete`` as it was before session 27 (numpy calls)."""
    from bifilar.studies.point_amplitude import LAW_SAMPLES

    if run.error or not run.period or not run.linear_period or len(run.crossings) < 2:
        return False
    tau = np.asarray(run.crossings, float) / run.linear_period
    cyc = np.diff(tau)
    if not (tau[-1] <= end - 6 / LAW_SAMPLES and cyc.min() > 0 and cyc.max() <= 1.1 * cyc.min()):
        return False
    return bool(tau[-1] + 0.75 * cyc.min() > periods)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's inf - inf and all-NaN minima in the cases
def test_trimmed_law_run_check_on_floats_equals_numpys():
    """The law runs' completeness check on Python floats against numpy's,
    on cycles at and about each of its thresholds (the end's 6 samples,
    10 % irregular, the next crossing at 0.75 of a cycle past ``periods``),
    non-positive and NaN cycles, too few crossings."""
    from types import SimpleNamespace

    from bifilar.studies.point_amplitude import LAW_SAMPLES, _trimmed_complete

    rng = np.random.default_rng(3)
    periods = 3.0
    cases = 0
    for trial in range(3000):
        T = float(rng.uniform(0.5, 3.0))
        k = int(rng.integers(0, 5))
        cyc = rng.uniform(0.9, 1.12, size=max(k - 1, 0))
        if trial % 11 == 0 and len(cyc):
            cyc[0] = [0.0, -0.1, np.nan, np.inf][trial % 4]
        t0 = float(rng.uniform(0.1, 0.5))
        tau = t0 + np.concatenate([[0.0], np.cumsum(cyc)])[:k]
        if trial % 5 == 0 and k >= 2:  # the last crossing exactly at a threshold
            tau[-1] = periods - 0.75 * np.nanmin(np.diff(tau)) if trial % 2 else tau[-1]
        end = float(tau[-1] + 6 / LAW_SAMPLES + rng.choice([-1e-12, 0.0, 1e-12, 0.05])) if k else periods
        run = SimpleNamespace(error=None if trial % 97 else "failed", period=T if trial % 89 else None,
                              linear_period=T, crossings=tau * T)
        ref = _trimmed_complete_numpy(run, end, periods)
        got = _trimmed_complete(run, end, periods)
        assert got == ref and type(got) is bool
        cases += got
    assert 100 < cases < 2900  # both answers reached


def test_joint_runs_with_a_non_finite_run_fall_back_to_run_by_run(monkeypatch):
    """``_lsoda_joint`` checks every run's samples for NaN or inf once,
    after the integrations: a run whose odeint samples are not finite still
    sends the point's runs back to one by one (before anything is
    recorded), where that run fails with LSODA's message and the others
    give their figures as without it."""
    import scipy.integrate as si

    boat = _scene("solar_boat")
    rest = rest_pose(boat)
    ms = linear_modes(boat, rest)
    lab = [m.label for m in ms.modes if m.period][:3]
    kw = dict(mode=lab, amplitude=0.05, periods=2.0, rtol=1e-8, rests=[rest] * 3, modes=[ms] * 3)
    clean = simulate_batch([boat] * 3, **kw)
    real = si.odeint
    calls = []

    def poisoned(f, y0, t, **k):  # the second mode's run: a NaN at its last sample
        Y, info = real(f, y0, t, **k)
        calls.append(len(t))
        if abs(float(t[-1]) - 2.0 * clean[1].linear_period) < 1e-9 * clean[1].linear_period:
            Y = Y.copy()
            Y[-1, 5] = np.nan
        return Y, info

    monkeypatch.setattr(si, "odeint", poisoned)
    runs = simulate_batch([boat] * 3, **kw)
    assert len(calls) == 6  # three joint, then three alone
    assert any("not finite" in w for w in runs[1].warnings), runs[1].warnings
    assert _figures(runs[0]) == _figures(clean[0]) and _figures(runs[2]) == _figures(clean[2])


def test_given_starts_taken_whole_or_by_the_runs_that_run():
    """``simulate_batch(..., starts=)`` takes the given start poses as they
    are when every run runs, in order, and only the rows of the runs that
    run otherwise (a bad mode in the middle, ``errors="return"``): either
    way each run's figures are those of the runs solving their own starts."""
    from bifilar.analysis.simulate import checked_start_poses

    boat = _scene("solar_boat")
    rest = rest_pose(boat)
    ms = linear_modes(boat, rest)
    modes = [m for m in ms.modes if m.period][:3]
    sp = checked_start_poses(boat, rest, modes, 0.05)
    labels = [m.label for m in modes]
    kw = dict(amplitude=0.05, periods=1.5, rtol=1e-8, rests=[rest] * 3, modes=[ms] * 3, errors="return")
    for lab in (labels, [labels[0], "no such mode", labels[2]]):
        own = simulate_batch([boat] * 3, mode=lab, **kw)
        given = simulate_batch([boat] * 3, mode=lab, starts=sp, **kw)
        assert [_figures(r) for r in own] == [_figures(r) for r in given]
        assert (own[1].error is None) == (lab is labels)
