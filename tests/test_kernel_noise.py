"""Rounding-level parameters are exact zeros for the compiled kernel
(``kernel_values._denoised``, perf14, session 20): the KTH trifilar's inertia,
summed from three rotated beams, carries products of inertia of ~1e-17 of
its moments and an attachment coordinate of 3e-18 m; with them its kernel
took the general-axes path (~25 % more operations a call).  Dropped, the
right-hand side still matches the naive formulation to its 3e-14; a stated
product of inertia or coordinate, however small beside rounding, is kept;
and a scene's values in a batch are those of its own kernel.
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from bifilar.config import load_scene
from bifilar.models import maximal as mx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_work_precision import naive_rhs_factory  # noqa: E402

KTH = load_scene(ROOT / "configs" / "trifilar_kth.yaml")


def _states(scene, k: int, seed: int) -> np.ndarray:
    """k states near the hanging pose, off the wires by ~2 % of a length."""
    rng = np.random.default_rng(seed)
    L = float(np.min(scene.lengths))
    r = np.mean(scene.anchors, axis=0) - [0.0, 0.0, 0.8 * L] + rng.normal(0.0, 0.02 * L, (k, 3))
    q = rng.normal(size=(k, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.concatenate([r, q, rng.normal(0.0, 0.3, (k, 3)), rng.normal(0.0, 0.5, (k, 3))], axis=1)


def _agrees(scene, P, seed: int) -> float:
    naive = naive_rhs_factory(scene)
    Y = _states(scene, 30, seed)
    ref = np.array([naive(0.0, y) for y in Y])
    f = mx.compiled_kernel(P, signature="odeint")
    got = np.array([f(y, 0.0).copy() for y in Y])
    return float(np.max(np.abs(got - ref) / np.max(np.abs(ref), axis=1, keepdims=True)))


def test_kth_trifilar_carries_rounding_noise_that_the_kernel_drops():
    I = np.asarray(KTH.inertia)
    off = np.abs(I[~np.eye(3, dtype=bool)])
    assert 0 < np.max(off) < 1e-15 * np.max(np.diag(I))  # the config's noise (the premise of the test)
    src = mx.kernel_source(mx.params_from_scenes(KTH), signature="odeint")
    # principal axes: Euler's coefficients, no product of inertia, no general mass matrix term
    assert "Ex*wy*wz" in src
    for name in ("Ixy", "Iyz", "Nxy", "Nyz", "Mxy", "Myz", "py0"):
        assert name not in src, name
    assert _agrees(KTH, mx.params_from_scenes(KTH), 3) < 3e-14


def test_a_stated_small_product_of_inertia_and_coordinate_are_kept():
    I = np.array(KTH.inertia, float)
    I[0, 1] = I[1, 0] = 1e-9 * I[2, 2]  # tiny, but a million times rounding: a stated figure
    att = np.array(KTH.attachments, float)
    att[0, 2] = 1e-12  # m
    sc = replace(KTH, inertia=I, attachments=att)
    P = mx.params_from_scenes(sc)
    src = mx.kernel_source(P, signature="odeint")
    assert "Ixy" in src and "pz0" in src
    assert _agrees(sc, P, 4) < 3e-14


def test_a_scene_in_a_batch_gets_the_values_of_its_own_kernel():
    """The noise is dropped scene by scene: in a batch beside a scene with
    stated products of inertia (so the batch kernel keeps those terms), the
    KTH scene's derivatives are its own kernel's."""
    I = np.array(KTH.inertia, float)
    I[0, 1] = I[1, 0] = 0.02 * I[2, 2]
    other = replace(KTH, inertia=I)
    Pb = mx.params_from_scenes([KTH, other])
    vals = mx._param_values(Pb)
    assert vals["Ixy"][0] == 0.0 and vals["Ixy"][1] != 0.0
    Y = _states(KTH, 8, 5)
    own = mx.compiled_kernel(mx.params_from_scenes(KTH))
    kb = mx.compiled_kernel(Pb)
    for y in Y:
        batch = np.array(kb(*[np.array([c, c]) for c in y.tolist()]))[:, 0]
        np.testing.assert_allclose(batch, own(*y.tolist()), rtol=1e-15, atol=1e-15 * np.max(np.abs(batch)))


def test_one_scene_values_are_the_batch_values():
    """The one-scene parameter values (Python floats, ``_one_scene_values``)
    are the batch code's for that scene: every shipped config, alone and
    with stated products of inertia or rounding noise added."""
    import glob

    from bifilar.config import read_yaml, scene_from_dict

    rng = np.random.default_rng(11)
    scenes = []
    for path in sorted(glob.glob(str(ROOT / "configs" / "*.yaml"))):
        try:
            scenes.append(scene_from_dict(read_yaml(path), warn=False))
        except Exception:  # noqa: BLE001 - measurement files are not scenes
            continue
    more = []
    for sc in scenes:
        I = np.array(sc.inertia, float)
        A = rng.normal(size=(3, 3)) * np.max(np.diag(I))
        more.append(replace(sc, inertia=I + 0.02 * (A + A.T)))
        more.append(replace(sc, inertia=I + 1e-17 * (A + A.T),
                            attachments=np.array(sc.attachments) + rng.normal(0.0, 1e-18, np.shape(sc.attachments))))
    assert len(scenes) >= 8
    for sc in scenes + more:
        one = mx._param_values(mx.params_from_scenes(sc))
        batch = mx._param_values(mx.params_from_scenes([sc, sc]))
        assert set(one) == set(batch)
        for k, v in one.items():
            assert type(v) is float, k
            np.testing.assert_allclose(v, batch[k][0], rtol=1e-15, atol=0.0, err_msg=k)
