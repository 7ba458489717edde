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
