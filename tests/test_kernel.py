"""The compiled right-hand side of the maximal-coordinate model against an
independent formulation, and the period accuracy that ``simulate``'s
default engine (LSODA on that kernel) promises.

The reference right-hand side is ``naive_rhs_factory`` of
``scripts/bench_work_precision.py``: the same equations written the obvious
way (numpy 3-vectors, a loop over the wires, ``np.linalg.solve`` for the
multipliers, world-frame attachment velocities, multipliers in N/m), which
shares no code with the generated kernel (body-frame attachment velocities,
multipliers scaled by the mass, folded Baumgarte terms, zero terms dropped).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from bifilar.analysis import batch as bt
from bifilar.analysis.equilibrium import rest_pose
from bifilar.analysis.modes import linear_modes
from bifilar.analysis.simulate import simulate
from bifilar.config import load_scene, scene_from_dict
from bifilar.models import maximal as mx

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from bench_work_precision import naive_rhs_factory  # noqa: E402

CONFIGS = ["thesis_plate_rest.yaml", "solar_boat.yaml", "trifilar_kth.yaml", "drone_parallel.yaml"]


def _general(n: int) -> dict:
    """n wires with every parameter nonzero: a full inertia tensor, anchors
    and attachments off every axis (no term of the kernel is dropped)."""
    rng = np.random.default_rng(n)
    ang = 2 * np.pi * np.arange(n) / n + 0.3
    att = [[0.6 * np.cos(a), 0.4 * np.sin(a), 0.15 + 0.05 * k] for k, a in enumerate(ang)]
    anc = [[1.1 * np.cos(a) + 0.1, 0.9 * np.sin(a) - 0.05, 0.2 * k] for k, a in enumerate(ang)]
    A = rng.normal(size=(3, 3))
    inertia = (np.diag([2.0, 3.0, 4.0]) + 0.2 * (A + A.T)).tolist()
    return {"name": f"general {n}", "gravity": 9.81, "body": {"mass": 7.0, "inertia": {"tensor": inertia}},
            "rig": {"anchors": anc, "attachments": att, "lengths": [2.0 + 0.1 * k for k in range(n)]}}


def _scenes():
    out = [(c, load_scene(ROOT / "configs" / c)) for c in CONFIGS]
    out += [(f"general-{n}", scene_from_dict(_general(n), warn=False)) for n in (2, 3, 4)]
    return out


SCENES = _scenes()


def _random_states(scene, rng, k: int) -> np.ndarray:
    """k states near the hanging pose, off the wires by up to ~1 %, quaternions
    off unit length by ~1e-6 (what the integrator sees)."""
    L = float(np.min(scene.lengths))
    r = np.mean(scene.anchors, axis=0) - [0.0, 0.0, 0.8 * L] + rng.normal(0.0, 0.02 * L, (k, 3))
    q = rng.normal(size=(k, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= 1.0 + rng.normal(0.0, 1e-6, (k, 1))
    return np.concatenate([r, q, rng.normal(0.0, 0.3, (k, 3)), rng.normal(0.0, 0.5, (k, 3))], axis=1)


@pytest.mark.parametrize("name, scene", SCENES, ids=[s[0] for s in SCENES])
def test_kernel_agrees_with_the_naive_right_hand_side(name, scene):
    P = mx.params_from_scenes(scene)
    naive = naive_rhs_factory(scene)
    Y = _random_states(scene, np.random.default_rng(7), 40)
    ref = np.array([naive(0.0, y) for y in Y])
    scale = np.max(np.abs(ref), axis=1, keepdims=True)  # the largest component of each derivative
    floats = np.array([mx.compiled_kernel(P)(*y.tolist()) for y in Y])
    odeint_f = mx.compiled_kernel(P, signature="odeint")
    flat = np.array([odeint_f(y, 0.0).copy() for y in Y])  # the kernel owns (and reuses) its output array
    arrays = mx.rhs(0.0, Y, P)  # the batch path: the same source on numpy arrays
    for got in (floats, flat, arrays):
        assert np.max(np.abs(got - ref) / scale) < 3e-14


@pytest.mark.parametrize("name, scene", SCENES, ids=[s[0] for s in SCENES])
def test_kernel_multipliers_are_the_naive_ones(name, scene):
    """The extras (multipliers in N/m, constraint values) against the same
    equations solved with numpy, without stabilisation (the physical tensions)."""
    P = mx.params_from_scenes(scene)
    Y = _random_states(scene, np.random.default_rng(8), 20)
    m, g = scene.mass, scene.gravity
    N = np.linalg.inv(np.array(scene.inertia))
    I = np.array(scene.inertia)
    n = scene.n_wires
    for y in Y:
        r, q, v, w = y[:3], y[3:7], y[7:10], y[10:13]
        R = mx.quat_to_matrix(q / np.linalg.norm(q))
        ds, Js, b = [], [], []
        for i in range(n):
            p = np.array(scene.attachments[i])
            d = r + R @ p - np.array(scene.anchors[i])
            s = v + np.cross(R @ w, R @ p)
            J = np.cross(p, R.T @ d)
            b.append(-s @ s - (R.T @ d) @ np.cross(w, np.cross(w, p)) + g * d[2] - J @ N @ (-np.cross(w, I @ w)))
            ds.append(d)
            Js.append(J)
        A = np.array([[ds[i] @ ds[j] / m + Js[i] @ N @ Js[j] for j in range(n)] for i in range(n)])
        lam = np.linalg.solve(A, b)
        phi = [0.5 * (d @ d - L**2) for d, L in zip(ds, scene.lengths)]
        out = mx.compiled_kernel(P, stabilise=False, extras=True)(*y.tolist())
        np.testing.assert_allclose(out[13:13 + n], lam, rtol=1e-12, atol=1e-13 * np.max(np.abs(lam)))
        np.testing.assert_allclose(out[13 + n:], phi, rtol=1e-12, atol=1e-15)


def test_odeint_signature_is_refused_unless_known_and_for_one_scene():
    scene = SCENES[0][1]
    P = mx.params_from_scenes(scene)
    with pytest.raises(ValueError, match="signature"):
        mx.compiled_kernel(P, signature="fortran")
    with pytest.raises(ValueError, match="one scene"):
        mx.compiled_kernel(mx.params_from_scenes([scene, scene]), signature="odeint")


def test_default_engine_meets_the_period_criterion_of_the_benchmark():
    """scripts/bench_simulate_marginal.py's criterion: thesis plate, torsion,
    amplitude 0.05, 210 periods at rtol 1e-9 give the period within 1e-9 of
    a converged run from the same start (the project's DOP853 at rtol 1e-13,
    another integrator)."""
    scene = load_scene(ROOT / "configs" / "thesis_plate_rest.yaml")
    rest = rest_pose(scene)
    ms = linear_modes(scene, rest)
    ref = bt.run_one(scene, rest, ms.get("torsion"), 0.05, 210, 1e-13, method="dop853", health=False,
                     lowest_point=False).period
    got = simulate(scene, "torsion", 0.05, 210, rest=rest, modes=ms, rtol=1e-9, method="auto").period
    assert abs(got / ref - 1) < 1e-9


def test_tensions_of_a_long_record_are_those_of_each_state():
    """A record longer than ``CACHE_CHUNK`` is taken in chunks: every state
    keeps the tensions it has alone (float path)."""
    scene = SCENES[0][1]
    P = mx.params_from_scenes(scene)
    Y = _random_states(scene, np.random.default_rng(9), mx.CACHE_CHUNK + 37)
    T = mx.tensions(Y, P)
    assert T.shape == (len(Y), scene.n_wires)
    for k in (0, mx.CACHE_CHUNK - 1, mx.CACHE_CHUNK, len(Y) - 1):
        np.testing.assert_allclose(T[k], mx.tensions(Y[k], P), rtol=1e-14)


def test_chunked_kernel_gives_the_kernels_values():
    scene = SCENES[1][1]
    P = mx.params_from_scenes(scene)
    k = mx.compiled_kernel(P, extras=True)
    Y = np.ascontiguousarray(_random_states(scene, np.random.default_rng(10), 2 * 1000 + 3).T)
    whole = k(*Y)
    parts = mx.chunked(k, 1000)(*Y)
    assert len(parts) == len(whole)
    for a, b in zip(parts, whole):
        np.testing.assert_allclose(a, np.broadcast_to(b, a.shape), rtol=1e-15, atol=0)
    y0 = Y[:, 0].tolist()  # floats go through unchanged
    np.testing.assert_allclose(mx.chunked(k, 1000)(*y0), k(*y0), rtol=1e-15)
