"""Session 26, perf26a: a sweep point's start poses and runs without work
repeated on known values; each shortcut against the path it replaces, bit for
bit (docs/performance.md, "Session 26, perf26a")."""

from __future__ import annotations

import numpy as np
import pytest

from bifilar.analysis import start_pose as spm
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.config import load_scene

from conftest import CONFIGS
from test_dependent_wires_messages import CORNERS, scene_of, vertical


def _bits(a) -> np.ndarray:
    return np.ascontiguousarray(a, float).view(np.int64)


def test_quat_to_matrix_stacked_equals_the_entry_by_entry_path(monkeypatch):
    # 9 .. 256 quaternions (a start-pose solve's 9-row batches and its 108-row Hessian poses) take the entries'
    # products from one outer product; against the entry-by-entry numpy path (_FEW = _STACKED = 0: all it was
    # for these sizes): the same bits over random, tiny, huge and nearly identity quaternions in every shape
    # it takes, and the same NaN / inf for zero or non-finite ones
    from bifilar import rotations
    from bifilar.rotations import quat_to_matrix

    def entry_by_entry(q):
        with monkeypatch.context() as m:
            m.setattr(rotations, "_FEW", 0)
            m.setattr(rotations, "_STACKED", 0)
            return quat_to_matrix(q)

    rng = np.random.default_rng(26)
    n = 0
    for shape in ((9, 4), (20, 4), (108, 4), (256, 4), (3, 5, 4)):
        for scale in (1e-150, 1e-3, 1.0, 1e3, 1e150):
            for _ in range(8):
                q = rng.normal(size=shape) * scale
                q[rng.uniform(size=shape[:-1]) < 0.3, 1:] *= 1e-9  # nearly identity rows
                got = quat_to_matrix(q)
                assert got.shape == shape[:-1] + (3, 3)
                assert np.array_equal(_bits(got), _bits(entry_by_entry(q)))
                n += 1
    with np.errstate(all="ignore"):
        bad = rng.normal(size=(12, 4))
        bad[0], bad[1, 0], bad[2, 3], bad[3, 1] = 0.0, np.nan, np.inf, -np.inf
        assert np.array_equal(quat_to_matrix(bad), entry_by_entry(bad), equal_nan=True)
    assert n == 200


def _cases():
    """(scenes, rests, modes, amplitudes) of start-pose batches: every mode with a period of rigs of two
    to four wires, at amplitudes that take one Newton step (0.05), several (0.3 .. 1.31 rad), the branch
    followed from rest and a refusal (the pitch plate past its reach), four dependent wires (a level
    table)."""
    out = []
    for name, amps in (("solar_boat", (0.05, 0.3)), ("thesis_lin2_pitch", (0.5, 1.31, 1.35)),
                       ("trifilar_kth", (0.9,)), ("drone_parallel", (0.5,))):
        sc = load_scene(CONFIGS / f"{name}.yaml", warn=False)
        out.append((sc, amps))
    out += [(scene_of(vertical(CORNERS, [1.0] * 4)), (0.01, 0.3))]
    cases = []
    for sc, amps in out:
        r = rest_pose(sc)
        mds = [m for m in linear_modes(sc, r).modes if m.period]
        for a in amps:
            cases.append((sc, r, mds, a))
    return cases


CASES = _cases()


def test_start_poses_from_kept_geometry_equal_computing_it_again(monkeypatch):
    # The closest-pose Newton takes each row's wires at its pose from where they were computed (the path onto
    # the wires, each step's return to them) and its first step's constraint Jacobian from its start;
    # edge_ratio takes the rest's wires from solve_start_poses and one SVD call for rest and start; the
    # residual of poses _solve gave is not computed again.  Against the path that computes each again
    # (_kkt and _closest without the known geometry, edge_ratio without the rest's): every field of the
    # StartPoses the same bits, the residual the residual at the poses (ties wires to 2-4 wires, one Newton
    # step and up to 13, a refusal, the branch from rest)
    real_kkt, real_closest, real_edge = spm._kkt, spm._closest, spm.edge_ratio
    kkts = []

    def counted_kkt(*a, **k):
        kkts.append(1)
        return real_kkt(*a, **k)

    def again():
        with monkeypatch.context() as m:
            m.setattr(spm, "_kkt", lambda rig, x0, x, mu, Winv, at=None: real_kkt(rig, x0, x, mu, Winv))
            m.setattr(spm, "_closest", lambda rig, x0, x, Winv, iters, at=None, geometry=None:
                      real_closest(rig, x0, x, Winv, iters, geometry=geometry))  # (geometry: start27's, passed on)
            m.setattr(spm, "edge_ratio", lambda rig, x, hold, at_rest=None: real_edge(rig, x, hold))
            return spm.start_poses([sc] * len(mds), [r] * len(mds), mds, a)

    monkeypatch.setattr(spm, "_kkt", counted_kkt)
    steps, refused = [], 0
    for sc, r, mds, a in CASES:
        kkts.clear()
        got = spm.start_poses([sc] * len(mds), [r] * len(mds), mds, a)
        steps.append(len(kkts))
        ref = again()
        for f in spm.StartPoses.__dataclass_fields__:
            assert np.array_equal(_bits(getattr(got, f)), _bits(getattr(ref, f))), (sc.name, a, f)
        refused += int(np.sum(~got.feasible))
        if sc.n_wires <= spm.MAX_ELIMINATION_WIRES:  # (more wires: a pose put onto the held lengths after)
            rig = spm._Rig([sc] * len(mds), [r] * len(mds))
            assert np.array_equal(_bits(got.residual), _bits(rig.residual(got.x)))
    assert min(steps) == 1 and max(steps) >= 10 and refused >= 1  # the cases reach every branch named above


@pytest.mark.parametrize("rows", [1, 9])
def test_edge_ratio_with_the_rest_given_equals_it_alone(rows):
    # one SVD call for the rest's and the starts' matrices: each matrix's singular values its own
    sc = load_scene(CONFIGS / "solar_boat.yaml", warn=False)
    r = rest_pose(sc)
    mds = [m for m in linear_modes(sc, r).modes if m.period]
    mds = (mds * 3)[:rows]
    rig = spm._Rig([sc] * rows, [r] * rows)
    hold = np.array([m.dominant for m in mds])
    x = np.array([0.3 * np.asarray(m.shape, float) for m in mds])
    z = np.zeros_like(x)
    d, w, _ = rig.wires(z)
    at_rest = [d, w, rig.jacobian(z, d, w)]
    assert np.array_equal(_bits(spm.edge_ratio(rig, x, hold, at_rest)), _bits(spm.edge_ratio(rig, x, hold)))


def test_measured_period_equals_numpy_std_and_diff():
    # a run's single-cycle std by numpy's _var ufunc calls (sample_std) and the cycles by np.diff's
    # subtraction: against np.diff and ndarray.std(ddof=1), bit for bit, over 2 .. 1000 crossings (numpy's
    # pairwise sums from 8 and 128 terms on), nearly equal cycles (a run's) and spread ones, 1e-9 .. 1e6 s
    from bifilar.analysis.simulate import measured_period, sample_std

    rng = np.random.default_rng(261)
    n = 0
    for k in list(range(2, 12)) + [17, 129, 1000]:
        for scale in (1e-9, 1.0, 1e6):
            for spread in (1e-9, 0.3):
                tc = np.cumsum(scale * (1.0 + spread * rng.normal(size=k)))
                per = np.diff(tc)
                period, std = measured_period(tc)
                assert period == float((tc[-1] - tc[0]) / (k - 1))
                assert std is None if k == 2 else std == float(per.std(ddof=1))
                if k > 2:
                    assert np.array_equal(_bits(sample_std(per)), _bits(per.std(ddof=1)))
                n += 1
    assert measured_period(list(tc[:4])) == measured_period(tc[:4]) and measured_period(tc[:1]) == (None, None)
    assert n == 78
