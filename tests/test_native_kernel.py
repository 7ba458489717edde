"""odeint's right-hand side compiled as C (bifilar.models.native_kernel):
the Python kernel's numbers bit for bit, and the Python kernel whenever
the C one cannot be had, silently.

Every check compares the C kernel with the Python kernel (an independent
evaluation of the same statements by CPython's float arithmetic), never
with numbers the code under test produced before.  The native-specific
tests skip where no C compiler exists.  Each test uses its own cache
directory and a fresh process state of the module (the tests that only
need a built library share the suite's kept cache, tests/conftest.py:
one build a pattern per machine; a library is named from a hash of its
source, compiler and flags, so a changed renderer or flag still builds
anew)."""
from __future__ import annotations

import json
import os
import time

import numpy as np
import pytest

from bifilar.config import read_yaml, scene_from_dict
from bifilar.models import maximal as mx
from bifilar.models import native_kernel as nk
from bifilar.studies.shorthands import apply_params

from conftest import CONFIGS, trapezoid


def _fresh(monkeypatch, cache, mode="sync"):
    """The module's process state emptied, its cache ``cache``, ``BIFILAR_NATIVE=mode``; the ctypes ``f``
    (the call extension, native_call, is tests/test_perfcall26.py's)."""
    from bifilar.models import native_call

    monkeypatch.setattr(native_call, "_call_type", lambda *a: None)
    monkeypatch.setattr(nk, "_patterns", {})
    monkeypatch.setattr(nk, "_env", {})
    monkeypatch.setattr(nk, "_running", [])
    monkeypatch.setenv("BIFILAR_CACHE_DIR", str(cache))
    monkeypatch.setenv("BIFILAR_NATIVE", mode)
    monkeypatch.delenv("CC", raising=False)


def _has_compiler() -> bool:
    saved = dict(nk._env)
    nk._env.clear()
    try:
        return nk._compiler() is not None
    finally:
        nk._env.clear()
        nk._env.update(saved)


needs_cc = pytest.mark.skipif(not _has_compiler(), reason="no C compiler on this machine: the Python kernel runs")


@pytest.fixture(scope="module")
def shared_cache():
    return os.environ["BIFILAR_CACHE_DIR"]  # conftest's $TMPDIR/bifilar-tests-native-<uid>


@pytest.fixture
def native(monkeypatch, shared_cache):
    _fresh(monkeypatch, shared_cache)


def _scene(name, params=None):
    cfg, _ = apply_params(read_yaml(CONFIGS / f"{name}.yaml"), params or {}, name)
    return scene_from_dict(cfg, name, warn=False)


def _is_native(f) -> bool:
    return f.__code__.co_filename == nk.__file__


def _bits(a) -> np.ndarray:
    return np.asarray(a, float).view(np.int64)


def _three_wire_general():
    """Three wires at unequal lengths and heights, products of inertia: the general-axes path."""
    return scene_from_dict({"body": {"mass": 3.2, "inertia": {"tensor": [[0.31, 0.02, -0.013],
                                                                        [0.02, 0.42, 0.007],
                                                                        [-0.013, 0.007, 0.55]]}},
                            "rig": {"anchors": [[0.4, 0.0, 0.0], [-0.2, 0.35, 0.02], [-0.21, -0.33, -0.01]],
                                    "attachments": [[0.3, 0.01, 0.05], [-0.15, 0.26, 0.04], [-0.16, -0.25, 0.06]],
                                    "lengths": [1.1, 1.17, 1.05]}}, "general", warn=False)


PATTERNS = {
    "Solar Boat (2 wires, symmetric zeros)": lambda: _scene("solar_boat", {"spacing": 3.0}),
    "KTH trifilar": lambda: _scene("trifilar_kth"),
    "3 wires, general inertia, unequal wires": _three_wire_general,
    "thesis plate, unequal wires (zero terms dropped)": lambda: trapezoid(l1=5.0, l2=5.3, h=0.5),
}


@needs_cc
@pytest.mark.parametrize("case", list(PATTERNS))
def test_c_kernel_equals_python_kernel_bit_for_bit(native, case):
    # 400 random states (unnormalised quaternions, large rates): every derivative's 64 bits equal; the
    # C kernel is the one returned (not the fallback).  Broken on purpose: '-' rendered as '+' in the
    # C text's first subtraction -> the load-time check refuses the library (not native); with that
    # check off -> mismatches here.  Without -ffp-contract=off and with -mfma: mismatches too (x86-64's
    # default target has no FMA, so the flag matters where CC or -march enables it)
    P = mx.params_from_scenes(PATTERNS[case]())
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_native(f)
    g = mx.compiled_kernel(P, signature="odeint", native=False)
    assert not _is_native(g)
    zero = P.__dict__["_kernels"]["values"][1]
    assert ("Ixy" in zero) == (case != "3 wires, general inertia, unequal wires")
    rng = np.random.default_rng(abs(hash(case)) % 2**32)
    for scale in (0.1, 1.0, 30.0):
        for y in rng.normal(size=(400 // 3, 13)) * scale:
            assert np.array_equal(_bits(f(y, 0.0)), _bits(g(y, 0.0)))


def test_c_renderer_takes_plain_arithmetic_only():
    # the renderer refuses what C would evaluate differently (integer division) or cannot (calls)
    lines, out, params = mx.kernel_statements(2, frozenset(), True, False)
    assert nk.c_source(lines, out, params).count("bifilar_o[") == 13
    with pytest.raises(ValueError):
        nk.c_source(["a = 1/2"], out, params)
    with pytest.raises(ValueError):
        nk.c_source(["a = sqrt(b)"], out, params)
    with pytest.raises(ValueError):
        nk.c_source(lines, out[:12], params)


@needs_cc
@pytest.mark.parametrize("name,params", [("trifilar_kth", {})])
def test_sweep_point_json_equal_with_native_on_and_off(native, monkeypatch, name, params):
    # the whole evaluate_point JSON (every figure its runs feed: periods, laws, sigmas, tensions) the same
    # text with the C kernel and with the Python kernel (the Solar Boat's point: test_perfcall26, three ways)
    from bifilar.studies import sweep as sw

    cfg = read_yaml(CONFIGS / f"{name}.yaml")
    st = sw.resolve_settings(cfg)
    mx.compiled_kernel(mx.params_from_scenes(_scene(name, params)), signature="odeint")  # built (sync)
    calls = []
    real = nk._wrap
    monkeypatch.setattr(nk, "_wrap", lambda *a: calls.append(1) or real(*a))
    on = json.dumps(sw.evaluate_point(cfg, name, params, st), sort_keys=True)
    assert calls  # the point's runs went through the C kernel
    monkeypatch.setenv("BIFILAR_NATIVE", "0")
    off = json.dumps(sw.evaluate_point(cfg, name, params, st), sort_keys=True)
    assert '"valid": true' in on
    assert on == off


@needs_cc
def test_simulate_samples_equal_and_ticks_kept(native, monkeypatch):
    # simulate's LSODA path with a progress callback (the ticks variant: the tick check in Python before
    # the C call): the same samples bit for bit and the same progress calls as the Python kernel
    from bifilar.analysis.simulate import simulate

    scene = _scene("trifilar_kth")
    runs = {}
    for mode in ("sync", "0"):
        monkeypatch.setenv("BIFILAR_NATIVE", mode)
        ticks = []
        r = simulate(scene, 1, 0.05, 4.0, method="auto", rtol=1e-9, progress=lambda a, b: ticks.append(a))
        runs[mode] = (r, ticks)
    (a, ta), (b, tb) = runs["sync"], runs["0"]
    assert np.array_equal(_bits(a.y), _bits(b.y)) and np.array_equal(_bits(a.t), _bits(b.t))
    assert ta == tb and len(ta) > 10


@needs_cc
def test_switching_kernels_mid_integration_changes_nothing(native):
    # a command switches to the C kernel when its background build is published, between runs or while
    # one is being integrated: a right-hand side alternating C / Python on every call integrates the same
    # trajectory bit for bit as the Python kernel alone (broken on purpose: the C kernel's output scaled
    # by (1 + 2^-52) -> differs)
    from scipy.integrate import odeint

    scene = _scene("solar_boat", {"spacing": 3.0})
    P = mx.params_from_scenes(scene)
    f = mx.compiled_kernel(P, signature="odeint")
    g = mx.compiled_kernel(P, signature="odeint", native=False)
    assert _is_native(f)
    k = [0]

    def alt(y, t):
        k[0] += 1
        return (f if k[0] % 2 else g)(y, t)

    y0 = np.array([0.0, 0.01, -5.0, 1.0, 0.0, 0.0, 0.02, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1])
    t = np.linspace(0.0, 3.0, 31)
    ya = odeint(alt, y0, t, rtol=1e-9, atol=1e-12, mxstep=20000)
    yb = odeint(g, y0, t, rtol=1e-9, atol=1e-12, mxstep=20000)
    assert k[0] > 50 and np.array_equal(_bits(ya), _bits(yb))


def test_no_compiler_gives_the_python_kernel_silently(monkeypatch, tmp_path, capfd):
    # CC naming a compiler that does not exist: the Python kernel, nothing printed, nothing written
    _fresh(monkeypatch, tmp_path / "c")
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    P = mx.params_from_scenes(trapezoid())
    f = mx.compiled_kernel(P, signature="odeint")
    assert not _is_native(f)
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    assert capfd.readouterr() == ("", "")
    assert not (tmp_path / "c").exists()


@needs_cc
def test_failed_build_is_marked_and_not_retried(monkeypatch, tmp_path, capfd):
    # a compiler that fails (`false`): the Python kernel, a .failed marker, no library, no temporary
    # left, nothing printed; a new process (fresh state) does not start the build again
    _fresh(monkeypatch, tmp_path)
    monkeypatch.setenv("CC", "false")
    P = mx.params_from_scenes(trapezoid())
    assert not _is_native(mx.compiled_kernel(P, signature="odeint"))
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".failed"]
    monkeypatch.setattr(nk, "_patterns", {})
    monkeypatch.setattr(nk, "_build", lambda *a: pytest.fail("rebuilt"))
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(trapezoid()), signature="odeint"))
    assert capfd.readouterr() == ("", "")
    # a marker older than FAILED_RETRY_S (a transient failure a day ago) is removed and the build tried again
    (marker,) = tmp_path.iterdir()
    old = marker.stat().st_mtime - nk.FAILED_RETRY_S - 1.0
    os.utime(marker, (old, old))
    tried = []
    monkeypatch.setattr(nk, "_patterns", {})
    monkeypatch.setattr(nk, "_build", lambda pat, *a: tried.append(pat.path))
    mx.compiled_kernel(mx.params_from_scenes(trapezoid()), signature="odeint")
    assert tried == [str(marker)[:-len(".failed")]] and not marker.exists()


@needs_cc
def test_corrupt_cached_library_is_replaced(monkeypatch, shared_cache, tmp_path, capfd):
    # a cached file under the library's name that is not a library (a fresh path: this process has not
    # loaded it): removed and built again; then the C kernel, the same numbers, no other file left
    _fresh(monkeypatch, shared_cache)
    scene = _scene("trifilar_kth")
    assert _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (pat,) = nk._patterns.values()
    so = tmp_path / os.path.basename(pat.path)
    so.write_bytes(b"\x7fELF not really")
    _fresh(monkeypatch, tmp_path)
    P = mx.params_from_scenes(scene)
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_native(f) and so.stat().st_size > 1000
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    assert capfd.readouterr() == ("", "")
    assert [p.name for p in tmp_path.iterdir()] == [so.name]


@needs_cc
def test_background_build_python_first_then_c(monkeypatch, tmp_path, capfd):
    # default mode: the first request returns the Python kernel at once and starts the build; a request
    # after the library is published returns the C kernel; the build's child is reaped, nothing printed
    _fresh(monkeypatch, tmp_path, mode="async")
    scene = trapezoid(l1=4.0, l2=4.6)
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (pat,) = nk._patterns.values()
    assert pat.state == "building" and pat.proc is not None
    pat.proc.wait(60)  # (a bound on a hung compiler, not a timing assertion)
    P = mx.params_from_scenes(scene)
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_native(f) and pat.proc is None and not nk._running
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    assert capfd.readouterr() == ("", "")
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".so"]


@needs_cc
def test_another_process_build_is_waited_for_and_a_stale_lock_taken_over(monkeypatch, shared_cache, tmp_path):
    # a fresh lock (another process building the pattern): no second build, the Python kernel until the
    # library appears under its name (here: copied in, the lock removed), then the C kernel; a lock older
    # than STALE_LOCK_S (a dead build's): taken over and built here
    import shutil

    scene = _scene("trifilar_kth")
    _fresh(monkeypatch, shared_cache)
    assert _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (built,) = [p.path for p in nk._patterns.values()]
    name = os.path.basename(built)
    lock = tmp_path / (name + ".lock")
    lock.touch()
    _fresh(monkeypatch, tmp_path, mode="async")
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (pat,) = nk._patterns.values()
    assert pat.state == "building" and pat.proc is None and not nk._running
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    shutil.copy(built, tmp_path / (name + ".part"))
    os.replace(tmp_path / (name + ".part"), tmp_path / name)
    lock.unlink()
    assert _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (tmp_path / name).unlink()
    lock.touch()
    os.utime(lock, (time.time() - nk.STALE_LOCK_S - 1,) * 2)
    _fresh(monkeypatch, tmp_path)
    assert _is_native(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test_cache_directory_others_can_write_is_not_used(monkeypatch, tmp_path):
    # a library from a directory another user could write to could be anyone's: not loaded, not built
    d = tmp_path / "shared"
    d.mkdir()
    d.chmod(0o777)
    _fresh(monkeypatch, d)
    monkeypatch.setattr(nk, "_build", lambda *a: pytest.fail("built in a shared directory"))
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(trapezoid()), signature="odeint"))
    assert not any(d.iterdir())


def test_disabled_by_environment(monkeypatch, tmp_path):
    _fresh(monkeypatch, tmp_path, mode="0")
    monkeypatch.setattr(nk, "_start", lambda *a: pytest.fail("looked for a library"))
    assert not _is_native(mx.compiled_kernel(mx.params_from_scenes(trapezoid()), signature="odeint"))
    assert not tmp_path.exists() or not any(tmp_path.iterdir())


def test_cache_dir_order(monkeypatch):
    monkeypatch.setenv("BIFILAR_CACHE_DIR", "/x/b")
    monkeypatch.setenv("XDG_CACHE_HOME", "/x/xdg")
    assert nk.cache_dir() == "/x/b"
    monkeypatch.delenv("BIFILAR_CACHE_DIR")
    assert nk.cache_dir() == os.path.join("/x/xdg", "bifilar")
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", "/x/home")
    assert nk.cache_dir() == os.path.join("/x/home", ".cache", "bifilar")
