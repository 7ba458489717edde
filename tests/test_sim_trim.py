"""``simulate``'s per-period work besides integrating, each shortcut
against the path it replaces (docs/performance.md, "Cost per simulated
period"):

* the record's tensions come from the health's kernel pass
  (``compiled_kernel(..., physical=True)``) instead of a second pass of
  :func:`bifilar.models.maximal.tensions`;
* the lowest point of a one-scene fold skips the gathers of a batch;
* the timed coordinate is the one component of ``relative_pose`` asked for.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from bifilar.analysis import batch_health as bh
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import relative_pose, simulate
from bifilar.config import load_scene, scene_from_dict
from bifilar.models import maximal as mx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from test_kernel import SCENES, _random_states  # noqa: E402


@pytest.mark.parametrize("name, scene", SCENES, ids=[s[0] for s in SCENES])
def test_physical_kernel_is_both_kernels_bit_for_bit(name, scene):
    """The stabilised kernel's outputs and the unstabilised kernel's
    multipliers, the same bits, from one kernel (2-4 wires: elimination and
    the minimum-norm solve), on arrays and on floats; and the same extras
    from the kernel that skips the derivatives."""
    P = mx.params_from_scenes(scene)
    n = scene.n_wires
    Y = _random_states(scene, np.random.default_rng(5), 40)
    both = mx.compiled_kernel(P, extras=True, physical=True)
    stab = mx.compiled_kernel(P, extras=True)
    phys = mx.compiled_kernel(P, stabilise=False, extras=True)
    a, s, u = both(*Y.T), stab(*Y.T), phys(*Y.T)
    assert len(a) == 13 + 3 * n
    for x, y in zip(a[:13 + 2 * n], s):
        np.testing.assert_array_equal(np.broadcast_to(x, (40,)), np.broadcast_to(y, (40,)))
    for x, y in zip(a[13 + 2 * n:], u[13:13 + n]):
        np.testing.assert_array_equal(x, y)
    f = both(*Y[3].tolist())
    assert list(f[13 + 2 * n:]) == list(phys(*Y[3].tolist())[13:13 + n])
    lean = mx.compiled_kernel(P, extras=True, physical=True, derivatives=False)(*Y.T)  # the samples' kernel
    assert len(lean) == len(a) and all(x is None for x in lean[:13])
    for x, y in zip(lean[13:], a[13:]):
        np.testing.assert_array_equal(np.broadcast_to(x, (40,)), np.broadcast_to(y, (40,)))
    with pytest.raises(ValueError):
        mx.compiled_kernel(P, stabilise=False, extras=True, physical=True)
    with pytest.raises(ValueError):
        mx.compiled_kernel(P, derivatives=False)


def _unloaded_trifilar():
    """Wire 1 carries 2.7 % of the weight; a 0.6 m swing unloads it (tests/test_batch.py)."""
    ang = np.radians([0, 120, 240])
    pts = np.c_[0.5 * np.cos(ang), 0.5 * np.sin(ang), np.zeros(3)]
    return scene_from_dict({"body": {"mass": 3.0, "inertia": {"principal": [0.3, 0.3, 0.4]}},
                            "rig": {"anchors": pts.tolist(), "attachments": (pts + [0.23, 0, 0.1]).tolist(),
                                    "lengths": [2.0] * 3}})


CASES = [("thesis_plate_rest.yaml", "torsion", 0.05, 12, "continue"),
         ("trifilar_kth.yaml", None, 0.3, 3, "continue"),
         (None, "swing-x", 0.6, 3, "stop"),  # a wire goes slack: the record stops there
         (None, "swing-x", 0.6, 3, "continue"),
         ("thesis_lin2_pitch.yaml", None, 0.6, 4, "continue")]


@pytest.mark.parametrize("cfg, mode, amp, periods, on_slack", CASES)
def test_simulate_record_is_what_the_replaced_passes_give(cfg, mode, amp, periods, on_slack):
    """simulate(method="auto")'s tensions at the samples against
    ``maximal.tensions`` of its states (the pass it replaces: absolute
    positions, so rounding apart), its extremes against the health's
    extremes and those tensions, and its timed coordinate against
    ``relative_pose``'s column; the slack warning and the record's length
    where a wire goes slack."""
    scene = load_scene(ROOT / "configs" / cfg) if cfg else _unloaded_trifilar()
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    mode = mode or ms.modes[-1].label
    r = simulate(scene, mode, amp, periods, rest=rest, modes=ms, rtol=1e-10, method="auto", on_slack=on_slack)
    P = mx.params_from_scenes(scene)
    T = mx.tensions(r.y, P)
    assert r.tensions.shape == T.shape == (len(r.t), scene.n_wires)
    np.testing.assert_allclose(r.tensions, T, rtol=0, atol=1e-13 * np.max(np.abs(T)))
    # the extremes: the health's (refined) and the samples'
    tol = 1e-13 * np.max(np.abs(T))
    assert np.all(r.tension_min <= T.min(axis=0) + tol) and np.all(r.tension_max >= T.max(axis=0) - tol)
    m = ms.get(mode)
    np.testing.assert_array_equal(r.coordinate, relative_pose(r.y, rest)[:, m.dominant])
    for k in range(6):  # every column alone, as the whole pose gives it
        np.testing.assert_array_equal(relative_pose(r.y, rest, k), relative_pose(r.y, rest)[:, k])
    if cfg is None:
        assert r.slack and min(r.tension_min) <= 0
        assert any(w.startswith("run stopped") for w in r.warnings) == (on_slack == "stop")


def test_simulate_tensions_break_if_the_stabilised_multipliers_were_used():
    """The test above can fail: the stabilised multipliers (the health's)
    differ from the physical ones by far more than its tolerance on a run
    that leaves the wires by ~1e-9 of their length."""
    scene = load_scene(ROOT / "configs" / "thesis_lin2_pitch.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    r = simulate(scene, ms.modes[-1].label, 0.6, 4, rest=rest, modes=ms, rtol=1e-10, method="auto")
    P = mx.params_from_scenes(scene)
    n = scene.n_wires
    out = mx.compiled_kernel(P, extras=True)(*r.y.T)
    lam, phi = np.array(out[13:13 + n]), np.array(out[13 + n:13 + 2 * n])
    T_stab = (-lam * np.sqrt(P.lengths[:, None] ** 2 + 2 * phi)).T
    assert np.max(np.abs(T_stab - r.tensions)) > 1e-11 * np.max(np.abs(r.tensions))


def test_one_scene_lowest_point_fold_is_the_batch_fold():
    """A one-scene LowestPoint (broadcast attachments, no gathers) gives the
    bits the general fold gives that scene among others."""
    s1 = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    s2 = load_scene(ROOT / "configs" / "solar_boat.yaml")
    rng = np.random.default_rng(3)
    k = 5000
    q = rng.normal(size=(k, 4))
    z = rng.normal(size=k)
    one = bh.LowestPoint([s1], np.zeros((1, 3)))
    many = bh.LowestPoint([s2, s1, s1], np.zeros((3, 3)))
    for part in np.array_split(np.arange(k), 3):  # several buffered chunks, concatenated by the fold
        one.add(np.zeros(len(part), int), z[part], q[part])
        many.add(np.ones(len(part), int), z[part], q[part])
        many.add(np.zeros(len(part), int), z[part][::-1], q[part][::-1])
    assert one.z[0] == many.z[1]
    assert np.isnan(many.z[2])
    nan = bh.LowestPoint([s1], np.zeros((1, 3)))
    nan.add([0, 0], [0.0, np.nan], q[:2])
    assert np.isnan(nan.z[0])  # a NaN state is not hidden by the one-scene minimum


def test_chunked_extras_are_the_whole_kernels_bits():
    """``chunked(..., first=13)``: the extras of a record in chunks (the
    rows of a constant output filled) are the whole kernel's, bit for bit;
    the derivatives are not gathered; a short record goes through whole."""
    scene = SCENES[-1][1]  # four wires: the minimum-norm multipliers too
    P = mx.params_from_scenes(scene)
    k = mx.compiled_kernel(P, extras=True, physical=True)
    Y = np.ascontiguousarray(_random_states(scene, np.random.default_rng(11), 2 * 700 + 5).T)
    whole = k(*Y)
    parts = mx.chunked(k, 700, first=13)(*Y)
    assert len(parts) == len(whole) and all(p is None for p in parts[:13])
    for a, b in zip(parts[13:], whole[13:]):
        np.testing.assert_array_equal(a, np.broadcast_to(b, a.shape))
    short = mx.chunked(k, 700, first=13)(*Y[:, :700])
    assert all(p is not None for p in short)
