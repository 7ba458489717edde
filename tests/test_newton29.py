"""The batched rest-pose Newton's pass compiled as C (bifilar.analysis.newton_kernel):
numpy's numbers bit for bit, and numpy's pass whenever the C one cannot be had or declines.

Every check compares the compiled pass with the numpy pass of
:func:`bifilar.analysis.batch_rest._newton_batch` (``native=False``: numpy's
einsum, LAPACK solve and elementwise arithmetic, the reference), never with
numbers the code under test produced before.  The native tests skip where no
C compiler exists.  Session 29 (newton29)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from bifilar.analysis import batch_rest as br
from bifilar.analysis import newton_kernel as nwk
from bifilar.models import native_kernel as nk

from test_native_kernel import CONFIGS, _fresh, needs_cc


@pytest.fixture
def kernel(monkeypatch, tmp_path_factory):
    """This module's process state emptied, the suite's kept cache, ``BIFILAR_NATIVE=sync``; the loaded
    library (its ``nstep``, ``jacobians``, ``hessians``; checked for 2 wires)."""
    import os
    _fresh(monkeypatch, os.environ["BIFILAR_CACHE_DIR"])
    monkeypatch.setattr(nwk, "_lib", [])
    monkeypatch.setattr(nwk, "_checked", {})
    f = nwk._kernel(2)
    assert f is not None, "the Newton library did not build, load or agree"
    return f


def _bits(x) -> np.ndarray:
    return np.asarray(x, float).view(np.int64)


def _arrays(rng, B: int, n: int):
    """B random n-wire rigs (a ring of anchors over a turned ring of attachments, the CoM above or below the
    attachments, lengths within 3 % of taut at the untwisted pose: some slack, some turned far, some never
    converging), stacked as _newton_batch takes them (SI)."""
    r_att = rng.uniform(0.2, 0.6, (B, 1))
    r_anc = r_att * rng.uniform(0.5, 1.6, (B, 1))
    h = rng.uniform(-0.2, 0.3, (B, 1))
    drop = rng.uniform(0.5, 2.5, (B, 1))
    ang = rng.uniform(0, 2 * np.pi, (B, 1)) + np.arange(n) * 2 * np.pi / n + rng.uniform(-0.4, 0.4, (B, n))
    p = np.stack([r_att * np.cos(ang), r_att * np.sin(ang), np.broadcast_to(h, (B, n))], -1)
    tw = rng.uniform(-0.5, 0.5, (B, 1))
    a = np.stack([r_anc * np.cos(ang + tw), r_anc * np.sin(ang + tw), h + drop + rng.uniform(-0.1, 0.1, (B, n))], -1)
    L = np.linalg.norm(a - p, axis=-1) * rng.uniform(0.97, 1.03, (B, n))
    return a, p, L, rng.uniform(1, 50, B), np.full(B, 9.81)


def _both(f, a, p, L, m, g):
    """(numpy's (com, R, lam, res), the compiled pass's, what each compiled pass returned)."""
    ran: list = []

    def counted(*args):
        k = f(*args)
        ran.append(k)
        return k
    ref = br._newton_batch(a, p, L, m, g, *br.newton_start(a, p, L, m, g), native=False)
    got = br._newton_batch(a, p, L, m, g, *br.newton_start(a, p, L, m, g), native=counted)
    return ref, got, ran


@needs_cc
def test_compiled_pass_equals_numpy_pass_bit_for_bit_on_random_rigs(kernel):
    """~1200 random rigs of 2-5 wires in batches of 1-36: every scene's CoM, attitude, multipliers and
    residual the same bits (numpy's order of each einsum's sum, the same LAPACK dgesv on the same
    column-major matrix), the compiled pass stepping in the passes (a declined pass is the next test's)."""
    rng = np.random.default_rng(29)
    stepped = 0
    for _ in range(100):
        n, B = int(rng.integers(2, 6)), int(rng.choice([1, 2, 5, 17, 36]))
        ref, got, ran = _both(kernel.nstep, *_arrays(rng, B, n))
        for x, y in zip(ref, got):
            assert np.array_equal(_bits(x), _bits(y))
        stepped += sum(k > 0 for k in ran)
    assert stepped > 300


@needs_cc
def test_sigma_point_batches_of_the_configs_equal_bit_for_bit(kernel, monkeypatch):
    """A sweep point's whole JSON (the honest sigma's rest poses of every sigma point among it) of the
    Solar Boat and the KTH trifilar: the same bytes with the compiled pass and without it (BIFILAR_NATIVE=0
    keeps numpy's pass, and odeint's Python kernel)."""
    from bifilar.config import read_yaml
    from bifilar.jsonable import to_jsonable
    from bifilar.studies import sweep as sw

    used: list = []
    real = nwk.pass_for

    def spy(*args):
        r = real(*args)
        used.append(r is not None)
        return r
    monkeypatch.setattr(nwk, "pass_for", spy)
    for name, params in (("solar_boat.yaml", {"spacing": 3.0}), ("trifilar_kth.yaml", {})):
        cfg = read_yaml(CONFIGS / name)
        st = sw.resolve_settings(cfg)
        out = {}
        for mode in ("sync", "0"):
            monkeypatch.setenv("BIFILAR_NATIVE", mode)
            pt = sw.evaluate_point(cfg, str(CONFIGS / name), params, st)
            out[mode] = json.dumps(to_jsonable(pt), sort_keys=True)
        assert out["sync"] == out["0"]
    assert any(used) and not all(used)


@needs_cc
def test_a_declined_pass_is_numpys_and_the_loop_goes_on(kernel):
    """A compiled pass that declines every other call (as on a singular matrix or a non-finite number):
    numpy takes those passes, the compiled one the others, the same bits."""
    rng = np.random.default_rng(3)
    calls = [0]

    def flaky(*args):
        calls[0] += 1
        return -2 if calls[0] % 2 else kernel.nstep(*args)
    for n in (2, 3, 4):
        ref, got, ran = _both(flaky, *_arrays(rng, 9, n))
        assert -2 in ran and any(k > 0 for k in ran)
        for x, y in zip(ref, got):
            assert np.array_equal(_bits(x), _bits(y))


@needs_cc
def test_jacobians_and_hessians_equal_numpys_bit_for_bit(kernel):
    """batch_rest._jacobian and _hessian by the library (what _accepted, modes_batch and newton_start call)
    against _jacobian_numpy and _hessian_numpy on random rigs at random poses, batches of 1-36; an array
    that is not plain float64 (a transposed view, complex) gets None: numpy's."""
    from bifilar.rotations import rotvec_to_matrix

    rng = np.random.default_rng(2929)
    for _ in range(60):
        n, B = int(rng.integers(2, 6)), int(rng.choice([1, 2, 7, 36]))
        a, p, L, m, g = _arrays(rng, B, n)
        com = rng.normal(size=(B, 3))
        R = np.ascontiguousarray(rotvec_to_matrix(rng.normal(size=(B, 3))))
        lam = rng.normal(size=(B, n))
        ref, got = br._jacobian_numpy(a, p, com, R), nwk.jacobians(a, p, com, R)
        ref += (br._hessian_numpy(ref[0], ref[1], lam),)
        got += (nwk.hessians(got[0], got[1], lam),)
        for x, y in zip(ref, got):
            assert np.array_equal(_bits(x), _bits(y))
    assert nwk.hessians(ref[0], ref[1], np.asfortranarray(lam) if B > 1 else lam + 0j) is None
    assert nwk.jacobians(a, p, com, np.swapaxes(R, 1, 2)) is None


@needs_cc
def test_load_check_refuses_a_library_that_differs_or_never_steps(kernel):
    """_agrees: the real library passes on 2-5 wires; one whose CoM step is off by an ulp, one that
    declines every pass (it would prove nothing), or one whose Hessian is off by an ulp, is refused."""
    from types import SimpleNamespace

    for n in (2, 3, 4, 5):
        assert nwk._agrees(kernel, n)

    def off_by_an_ulp(*args):
        k = kernel.nstep(*args)
        if k > 0:
            com = np.ctypeslib.as_array((np.ctypeslib.ctypes.c_double * 3).from_address(args[8]))
            com[0] = np.nextafter(com[0], np.inf)
        return k

    def hessian_off(B, n, d, w, lam, H):
        r = kernel.hessians(B, n, d, w, lam, H)
        h = np.ctypeslib.as_array((np.ctypeslib.ctypes.c_double * 36).from_address(H))
        h[7] = np.nextafter(h[7], np.inf)
        return r
    lib = dict(nstep=kernel.nstep, jacobians=kernel.jacobians, hessians=kernel.hessians)
    assert nwk._agrees(SimpleNamespace(**lib), 3)
    assert not nwk._agrees(SimpleNamespace(**{**lib, "nstep": off_by_an_ulp}), 3)
    assert not nwk._agrees(SimpleNamespace(**{**lib, "nstep": lambda *args: -2}), 3)
    assert not nwk._agrees(SimpleNamespace(**{**lib, "hessians": hessian_off}), 3)


def test_numpy_pass_without_a_compiler_or_when_off(monkeypatch, tmp_path, capfd):
    """No compiler (a CC that does not exist), or BIFILAR_NATIVE=0: no compiled pass, nothing printed,
    and rest_poses answers all the same (the numpy pass)."""
    from test_native_kernel import _scene

    for env in ({"CC": str(tmp_path / "no-such-cc"), "BIFILAR_NATIVE": "sync"}, {"BIFILAR_NATIVE": "0"}):
        _fresh(monkeypatch, tmp_path)
        monkeypatch.setattr(nwk, "_lib", [])
        monkeypatch.setattr(nwk, "_checked", {})
        for k, v in env.items():
            monkeypatch.setenv(k, v)
        a, p, L, m, g = nwk.check_batch(2)
        assert nwk.pass_for(np.ones(8, bool), a, p, L, m * g, L.max(axis=1), *br.newton_start(a, p, L, m, g),
                            np.zeros(8)) is None
        s = _scene("solar_boat", {"spacing": 3.0})
        assert br.rest_poses([s])[0].kkt_residual < 1e-9
    assert capfd.readouterr() == ("", "")
    assert not list(tmp_path.glob("newton_*.so"))
