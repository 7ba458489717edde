"""Session 27, start27: a sweep point's start poses and thesis rung without
work repeated on known values; each shortcut against the path it replaces,
bit for bit (docs/design.md, "start27, session 27")."""

from __future__ import annotations

import numpy as np

from bifilar.analysis import start_pose as spm

from test_perf26a import CASES, _bits


def test_start_poses_residual_and_edge_from_the_solvers_wires_equal_computing_them_again(monkeypatch):
    # _solve takes the residual from the wires each row was last put on (_to_wires' or _closest's geometry)
    # and edge_ratio the starts' wires from there (where the direct solve gave every start).  Against the
    # path that computes both again at the returned poses (_Rig.residual ignoring the wires handed to it,
    # edge_ratio given the rest's geometry alone): every field of the StartPoses the same bits, over
    # CASES (2-4 wires, one Newton step and up to 13, the branch from rest, a refusal, four dependent
    # wires), tables splayed by 1e-6 and 1e-5 m (their starts put onto the held lengths after the branch
    # from rest) and the Solar Boat point's nine rows (four scenes: 0.05 and 0.045, the laws'
    # stepped scenes)
    real_residual, real_edge = spm._Rig.residual, spm.edge_ratio
    given = []

    def again(scenes, rests, mds, amps):
        with monkeypatch.context() as m:
            m.setattr(spm._Rig, "residual", lambda self, x, d=None: real_residual(self, x))
            m.setattr(spm, "edge_ratio", lambda rig, x, hold, at_rest=None: real_edge(rig, x, hold, at_rest[:3]))
            return spm.start_poses(scenes, rests, mds, amps)

    def noted_edge(rig, x, hold, at_rest=None):
        given.append(at_rest[3] is not None)
        return real_edge(rig, x, hold, at_rest)

    monkeypatch.setattr(spm, "edge_ratio", noted_edge)
    batches = [([sc] * len(mds), [r] * len(mds), mds, a) for sc, r, mds, a in CASES]
    batches.append(_boat_point_rows())
    from test_nearfix import _torsion
    from test_restrank import _splayed

    for eps, amps in ((1e-6, [0.2, 0.01]), (1e-5, [0.4])):  # tables splayed by 1e-6 and 1e-5 m: their starts
        sc = _splayed(eps)  # put onto the held lengths after the solve (_onto_held: 2e-11 and 6e-9 rad moved)
        rest, tor = _torsion(sc)
        batches.append(([sc] * len(amps), [rest] * len(amps), [tor] * len(amps), np.array(amps)))
    for scenes, rests, mds, a in batches:
        got = spm.start_poses(scenes, rests, mds, a)
        ref = again(scenes, rests, mds, a)
        for f in spm.StartPoses.__dataclass_fields__:
            assert np.array_equal(_bits(getattr(got, f)), _bits(getattr(ref, f))), (scenes[0].name, a, f)
    # the shortcut taken in most batches; not where the branch from rest moved a start (the splayed tables
    # reach _onto_held only after it, so start_poses' own guard for that case is not reached here)
    assert sum(given) >= len(batches) - 4 and not all(given)  # (10 of 13 here)


def _boat_point_rows():
    """The Solar Boat sweep point's (spacing 3) start-pose rows as evaluate_point hands them to
    start_poses: the point's 3 modes at 0.05, its laws' runs at 0.045 and on 3 stepped scenes at 0.05."""
    from bifilar.analysis import start_states
    from bifilar.config import read_yaml
    from bifilar.studies import sweep as sw

    from conftest import CONFIGS

    path = CONFIGS / "solar_boat.yaml"
    cfg = read_yaml(path)
    seen = []
    real = start_states.start_poses

    def keep(scenes, rests, modes, amplitude):
        seen.append((list(scenes), list(rests), list(modes), np.array(amplitude, float)))
        return real(scenes, rests, modes, amplitude)

    start_states.start_poses = keep
    try:
        sw.evaluate_point(cfg, str(path), {"spacing": 3.0}, sw.resolve_settings(cfg))
    finally:
        start_states.start_poses = real
    (rows,) = seen
    assert len(rows[0]) == 9 and len({id(s) for s in rows[0]}) == 4
    return rows


def test_rig_weights_from_one_eigvalsh_call_equal_one_call_a_scene():
    # _Rig takes the distinct scenes' mean principal moments from one stacked eigvalsh call; against the
    # call a scene it replaces (np.linalg.eigvalsh(inertia).mean()): the same bits in W, over the boat
    # point's rows (4 distinct scenes of 9) and 300 batches of 1-12 scenes with random inertias from
    # 1e-6 to 1e6 kg m^2 (nearly singular and isotropic ones among them), scenes repeated in any order
    import dataclasses

    scenes, rests, _, _ = _boat_point_rows()
    rng = np.random.default_rng(27)
    batches = [(scenes, rests)]
    for _ in range(300):
        k = int(rng.integers(1, 13))
        distinct = []
        for j in range(int(rng.integers(1, k + 1))):
            A = rng.normal(size=(3, 3)) * 10.0 ** rng.uniform(-3, 3)
            inertia = A @ A.T + (np.eye(3) * abs(A).max() ** 2 if j % 3 == 0 else 1e-9 * abs(A).max() ** 2)
            distinct.append(dataclasses.replace(scenes[0], inertia=inertia))
        batches.append(([distinct[i] for i in rng.integers(0, len(distinct), size=k)], [rests[0]] * k))
    for scs, rs in batches:
        rig = spm._Rig(scs, rs)
        Ibar = np.array([np.linalg.eigvalsh(s.inertia).mean() for s in scs])
        assert np.array_equal(_bits(rig.W[:, 3:]), _bits(np.repeat(Ibar[:, None], 3, 1)))
        assert np.array_equal(_bits(rig.W[:, :3]), _bits(np.repeat(np.array([s.mass for s in scs])[:, None], 3, 1)))


def test_a_points_biases_with_one_matcher_and_one_scale_equal_one_a_component(monkeypatch):
    # _finish builds the MAC matcher of the point's modes once for its components' linear estimates, and
    # the ladder the thesis rung's scale (the largest principal moment) once; against the path that builds
    # each a component (linear_estimate without ``matched``, the scale forgotten before each thesis call):
    # every number of three points' JSON the same; one matcher a point, and each thesis solve given its own
    # point's scale, points evaluated one after another (fails with the matcher or the scale kept at module
    # level from the first point: 1 matcher built, the boat solved with the plate's scale)
    from bifilar.config import read_yaml
    from bifilar.estimation import invert as inv
    from bifilar.estimation import sensitivity
    from bifilar.jsonable import to_jsonable
    from bifilar.studies import point as pt
    from bifilar.studies import sweep as sw

    from conftest import CONFIGS

    pts = [("thesis_plate_rest.yaml", {"spacing": 3.0}), ("solar_boat.yaml", {"spacing": 3.0}),
           ("solar_boat.yaml", {"spacing": 1.0, "length": 2.0})]

    def run():
        out = []
        for name, params in pts:
            cfg = read_yaml(CONFIGS / name)
            r = to_jsonable(sw.evaluate_point(cfg, name, params, sw.resolve_settings(cfg)))
            r.pop("timing", None)
            out.append(r)
        return out

    built, scales = [], []
    real_matcher, real_estimate, real_thesis = sensitivity.period_matcher, pt.linear_estimate, pt._Ladder.thesis
    real_solve = inv.solve_scalar
    monkeypatch.setattr(sensitivity, "period_matcher", lambda ms: built.append(1) or real_matcher(ms))

    def noted_thesis(self, *a):
        scales.append([float(np.max(np.linalg.eigvalsh(self.scene.inertia)))])
        return real_thesis(self, *a)

    def noted_solve(T_of_x, target, x0, lo, hi, scale, *a, **k):
        scales[-1].append(scale)
        return real_solve(T_of_x, target, x0, lo, hi, scale, *a, **k)

    with monkeypatch.context() as m:
        m.setattr(pt._Ladder, "thesis", noted_thesis)
        m.setattr(inv, "solve_scalar", noted_solve)
        got = run()
    assert len(built) == 3  # one a point
    # each thesis solve given its own point's scale (the plate's 260.4, the boat's 317.3 kg m^2)
    assert len(scales) >= 7 and all(len(s) == 2 and s[0] == s[1] for s in scales)
    assert len({s[0] for s in scales}) == 2
    with monkeypatch.context() as m:
        m.setattr(pt, "linear_estimate", lambda *a, matched=None, **k: real_estimate(*a, **k))

        def thesis_alone(self, *a):
            self._scale = None
            return real_thesis(self, *a)

        m.setattr(pt._Ladder, "thesis", thesis_alone)
        built.clear()
        ref = run()
        assert len(built) >= 7  # one a component
    assert all(r["valid"] for r in got) and sum(len(r["components"]) for r in got) >= 7
    for g, r in zip(got, ref):
        assert _same(g, r)


def _same(a, b) -> bool:
    """Two JSON-like trees equal, floats bit for bit (NaN as NaN)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return isinstance(b, (list, tuple)) and len(a) == len(b) and all(_same(u, v) for u, v in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return np.array_equal(_bits(a), _bits(b))
    return a == b
