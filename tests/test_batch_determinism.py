"""A scene's results from the batched engine must not depend on which other
scenes share its batch: a sweep's figures have to be identical for any
``--workers`` count and for a resumed sweep (tests/test_sweep.py), so only
the parts of the engine that pass this test may be shared across the
points of a sweep (docs/performance.md, issue 14, "Sweep points and plan").

Bit-for-bit equality (``==``), not a tolerance: a last-bit difference would
show in the journal and in the ``--workers 1`` vs ``2`` comparison.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bifilar.analysis.batch import SMALL_BATCH, modes_batch, rest_poses, simulate_batch
from bifilar.analysis.equilibrium import rest_pose
from bifilar.config import read_yaml, scene_from_dict
from bifilar.estimation.sensitivity import perturb
from bifilar.studies.shorthands import apply_params

ROOT = Path(__file__).resolve().parents[1]
BOAT = ROOT / "configs" / "solar_boat.yaml"


@pytest.fixture(scope="module")
def scenes():
    """Solar Boat scenes of a sweep: several spacings and lengths, and the
    sigma-point-like neighbours of one of them (mass and gravity moved)."""
    cfg = read_yaml(BOAT)
    out = []
    for sp, L in [(3.0, 3.0), (1.0, 2.0), (4.0, 5.0), (2.0, 4.0)]:
        c, _ = apply_params(cfg, {"spacing": sp, "length": L}, str(BOAT))
        out.append(scene_from_dict(c, str(BOAT), warn=False))
    s0 = out[0]
    out += [perturb(s0, "mass", 0.01 * s0.mass), perturb(s0, "gravity", -2e-3), perturb(s0, "mass", -0.02 * s0.mass)]
    return out


def _rest_figures(r):
    return (r.com.tobytes(), r.R.tobytes(), r.q.tobytes(), r.tensions.tobytes(), r.wire_vectors.tobytes(),
            r.lowest_z, r.depth, r.kkt_residual)


def _mode_figures(ms):
    return tuple((m.label, m.period, m.omega2, m.shape.tobytes(), m.energy_share.tobytes(), m.dominant)
                 for m in ms.modes) + (ms.mass_matrix.tobytes(), ms.basis.tobytes())


def test_rest_poses_and_modes_do_not_depend_on_the_batch(scenes):
    """Scene 0 alone, first in a batch of all, and last in a reversed batch
    whose members start from other guesses: the same rest pose and modes
    to the bit (Newton stops each scene on its own residual; the stacked
    linear algebra works matrix by matrix)."""
    guess = rest_pose(scenes[0])
    others = [rest_pose(s) for s in scenes[1:4]]

    def run(sc, gs):
        rs = rest_poses(sc, gs)
        return rs, modes_batch(sc, rs)

    alone = run(scenes[:1], [guess])
    batch = run(scenes, [guess] + others + [guess] * 3)
    rev = run(scenes[::-1], ([guess] * 3 + others[::-1] + [guess]))
    for rs, ms, b in [(alone[0], alone[1], 0), (batch[0], batch[1], 0), (rev[0], rev[1], len(scenes) - 1)]:
        assert _rest_figures(rs[b]) == _rest_figures(alone[0][0])
        assert _mode_figures(ms[b]) == _mode_figures(alone[1][0])
    # and every scene of the batch equals its reversed-batch self
    for k in range(len(scenes)):
        assert _rest_figures(batch[0][k]) == _rest_figures(rev[0][len(scenes) - 1 - k])
        assert _mode_figures(batch[1][k]) == _mode_figures(rev[1][len(scenes) - 1 - k])
    # a batch result is a rest pose at all (not an equal wrong answer): KKT residual of Newton's tolerance
    assert all(r.kkt_residual < 1e-9 for r in batch[0])


def test_a_sweep_points_nonlinear_runs_do_not_depend_on_the_batch(scenes):
    """The sweep's nonlinear runs (a point's chosen modes, fewer than
    ``SMALL_BATCH`` runs: LSODA scene by scene) give a run the same
    figures alone and beside other runs."""
    sc = scenes[:3]
    rs = [rest_pose(s) for s in sc]
    ms = modes_batch(sc, rs)
    kw = dict(amplitude=0.05, periods=3.0, rtol=1e-8)

    def figures(run):
        return (run.period, run.crossings.tobytes(), run.tension_min.tobytes(), run.tension_max.tobytes(),
                run.depth_max, run.max_constraint_violation, run.energy_drift)

    alone = simulate_batch([sc[0]], mode="torsion", rests=rs[:1], modes=ms[:1], **kw)[0]
    labels = ["torsion", "swing-x", "torsion", "swing-y"]
    pick = [0, 0, 1, 2]
    assert len(pick) < SMALL_BATCH
    batch = simulate_batch([sc[i] for i in pick], mode=labels, rests=[rs[i] for i in pick],
                           modes=[ms[i] for i in pick], **kw)
    assert figures(batch[0]) == figures(alone)
    assert np.isfinite(alone.period) and abs(alone.period / ms[0].get("torsion").period - 1) < 1e-2


def _run_figures(run):
    return (run.period, run.crossings.tobytes(), run.tension_min.tobytes(), run.tension_max.tobytes(),
            run.depth_max, run.max_constraint_violation, run.energy_drift, run.lowest_z_min)


def test_independent_dop853_runs_are_the_same_alone_and_in_any_batch(scenes):
    """``simulate_batch(..., independent=True)``: a run alone (a batch of
    one, which the other paths give to the float engine), in a batch with
    other runs, and in another batch in reverse order, with a scene whose
    product of inertia is not zero (so the compiled right-hand side keeps
    terms the others drop): the same figures to the bit."""
    s0 = scenes[0]
    skew = perturb(s0, "Ixy", 0.02 * s0.inertia[0, 0])  # Ixy = 0 in the others
    sc = [s0, scenes[1], skew, scenes[4]]
    rs = [rest_pose(s) for s in sc]
    ms = modes_batch(sc, rs)
    kw = dict(amplitude=0.05, periods=3.0, rtol=1e-8, independent=True)

    def run(pick, labels):
        return simulate_batch([sc[i] for i in pick], mode=labels, rests=[rs[i] for i in pick],
                              modes=[ms[i] for i in pick], **kw)

    alone = run([0], ["torsion"])[0]
    a = run([0, 1, 2, 3], ["torsion", "torsion", "torsion", "swing-y"])
    b = run([3, 2, 2, 1, 0], ["swing-y", "roll", "torsion", "torsion", "torsion"])
    assert _run_figures(a[0]) == _run_figures(alone) == _run_figures(b[4])
    assert _run_figures(a[1]) == _run_figures(b[3])
    assert _run_figures(a[2]) == _run_figures(b[2])
    assert _run_figures(a[3]) == _run_figures(b[0])
    skew_alone = run([2], ["torsion"])[0]
    assert _run_figures(skew_alone) == _run_figures(a[2])
    assert "DOP853" in alone.method


def test_independent_runs_keep_the_sweeps_accuracy(scenes):
    """The batch-independent engine at a sweep's settings (rtol 1e-8, 3
    periods) against the engine a sweep point uses (LSODA scene by scene,
    tensions at 64 samples a period): periods within 5e-7 relative (each
    engine's own period error was measured at <= 1.1e-7 against rtol 1e-12
    runs, docs/performance.md), tension extremes and depth within 1e-5
    (measured <= 1e-6; extremes refined on the coarse steps alone were
    ~1e-4 off, which this would catch)."""
    sc = scenes[:3]
    rs = [rest_pose(s) for s in sc]
    ms = modes_batch(sc, rs)
    labels = ["torsion", "roll", "swing-y"]
    kw = dict(amplitude=0.05, periods=3.0, rtol=1e-8, rests=rs, modes=ms)
    dop = simulate_batch(sc, mode=labels, independent=True, **kw)
    per = simulate_batch(sc, mode=labels, **kw)  # 3 < SMALL_BATCH: LSODA scene by scene
    for d, p in zip(dop, per):
        assert "LSODA" in p.method and "DOP853" in d.method
        assert abs(d.period / p.period - 1) < 5e-7
        np.testing.assert_allclose(d.tension_max, p.tension_max, rtol=1e-5)
        np.testing.assert_allclose(d.tension_min, p.tension_min, rtol=1e-5)
        assert abs(d.depth_max / p.depth_max - 1) < 1e-5
        assert d.t is None and d.y is None  # the health's samples are not returned unless asked for
