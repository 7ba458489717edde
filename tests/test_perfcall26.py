"""odeint's call into the compiled kernel through the C-extension callable
(bifilar.models.native_call): the ctypes f's numbers and the Python
kernel's, bit for bit, and the ctypes f whenever the extension cannot be
had, silently.

Every check compares the extension's callable with the ctypes ``f`` and
with the Python kernel (CPython's own float arithmetic on the same
statements), never with numbers the code under test produced before.  The
tests that need a built extension skip where there is no C compiler or no
Python.h.  The working tests use the suite's kept cache
(tests/conftest.py: one build per machine, not per run); the failing
builds use a fresh directory each."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from bifilar.config import read_yaml
from bifilar.models import maximal as mx
from bifilar.models import native_call as nc
from bifilar.models import native_kernel as nk

from conftest import CONFIGS, trapezoid
from test_native_kernel import _bits, _has_compiler, _scene
from test_native_kernel import _fresh as _fresh_kernel

KEPT = os.environ["BIFILAR_CACHE_DIR"]  # conftest's $TMPDIR/bifilar-tests-native-<uid>


_CALL_TYPE = nc._call_type


def _fresh(monkeypatch, cache, mode="sync"):
    """As test_native_kernel's, with the call extension's state emptied too and its type looked for."""
    _fresh_kernel(monkeypatch, cache, mode)
    monkeypatch.setattr(nc, "_call_type", _CALL_TYPE)
    monkeypatch.setattr(nc, "_call", [])


needs_ext = pytest.mark.skipif(not (_has_compiler() and nc._python_includes()),
                               reason="no C compiler or Python.h: the ctypes f runs")


def _is_ext(f) -> bool:
    return type(f).__module__ == "bifilar_kcall"


def _is_ctypes(f) -> bool:
    return getattr(f, "__code__", None) is not None and f.__code__.co_filename == nk.__file__


def _three_ways(P, ticks=None):
    """(extension callable, ctypes f, Python kernel) of ``P``'s odeint kernel, the first two on
    separate arrays."""
    f = mx.compiled_kernel(P, signature="odeint", ticks=ticks)
    assert _is_ext(f)
    (pat,) = [p for p in nk._patterns.values() if p.state == "ready"]
    vals, zero = P.__dict__["_kernels"]["values"]
    n = int(P.lengths.shape[-1])
    c = nk._ctypes_f(pat.func, [vals[p] for p in mx._param_names(n) if p not in zero], ticks)[0]
    return f, c, mx.compiled_kernel(P, signature="odeint", native=False, ticks=ticks)


@pytest.fixture
def ext(monkeypatch):
    _fresh(monkeypatch, KEPT)


@needs_ext
@pytest.mark.parametrize("scene", [lambda: _scene("solar_boat", {"spacing": 3.0}), lambda: _scene("trifilar_kth")],
                         ids=["boat", "trifilar"])
def test_callable_equals_ctypes_and_python_bit_for_bit(ext, scene):
    # 150 random states (unnormalised quaternions, rates up to ~30 rad/s): the callable's 13 derivatives
    # have the ctypes f's and the Python kernel's 64 bits, in one array it returns every call (as theirs).
    # States that are not one C-contiguous row of doubles (a list, a strided view, float32, a big-endian
    # array) go through the ctypes f's numpy conversion: the same bits (the Python kernel takes arrays
    # only).  Broken on purpose in _CALL_SOURCE: one element copied from the wrong place (ybuf[3] =
    # ybuf[4] after the memcpy) -> the load-time check refuses the extension (not _is_ext here); with
    # that check off too -> mismatches
    P = mx.params_from_scenes(scene())
    f, c, g = _three_ways(P)
    rng = np.random.default_rng(26)
    out = f(np.zeros(13), 0.0)
    for scale in (0.1, 1.0, 30.0):
        for y in rng.normal(size=(50, 13)) * scale:
            a = f(y, 0.0)
            assert a is out
            assert np.array_equal(_bits(a), _bits(c(y, 0.0))) and np.array_equal(_bits(a), _bits(g(y, 0.0)))
    y = rng.normal(size=26)
    for odd in (list(y[:13]), y[::2], y[:13].astype(np.float32), y[:13].astype(">f8")):
        assert np.array_equal(_bits(f(odd, 0.0)), _bits(c(odd, 0.0)))
        assert isinstance(odd, list) or np.array_equal(_bits(f(odd, 0.0)), _bits(g(odd, 0.0)))


@needs_ext
def test_ticks_called_as_the_ctypes_f_calls_them(ext):
    # the tick check (t >= at[0] -> tick(t)) before the state is read, the same calls with the same t; an
    # exception from the tick (a progress bar stopping the run) comes out of the call unchanged.  Broken on
    # purpose: Py_GE -> Py_GT in the check -> the call at t == at[0] is missed
    P = mx.params_from_scenes(trapezoid(l1=5.0, l2=5.3, h=0.5))
    seen = {}
    for way in range(2):
        at, calls = [0.5], []

        def tick(t, at=at, calls=calls):
            calls.append(t)
            at[0] = t + 0.25
            if t > 2.0:
                raise KeyboardInterrupt
        f = _three_ways(P, (at, tick))[way]
        assert _is_ext(f) == (way == 0)
        outs = []
        for t in (0.0, 0.5, 0.6, 0.75, 1.5, 1.6):
            outs.append(f(np.full(13, 0.1) + t, t).copy())
        with pytest.raises(KeyboardInterrupt):
            f(np.zeros(13), 2.5)
        seen[way] = (calls, np.array(outs))
    assert seen[0][0] == seen[1][0] == [0.5, 0.75, 1.5, 2.5]
    assert np.array_equal(_bits(seen[0][1]), _bits(seen[1][1]))


@needs_ext
def test_run_samples_and_point_json_equal_three_ways(ext, monkeypatch):
    # simulate's samples (with a progress callback: the ticks variant) and a whole Solar Boat sweep point's
    # JSON the same bits with the extension's callable, the ctypes f and the Python kernel; the callable is
    # what the extension runs used.  Broken on purpose: the load-time check off and the wrong element
    # copied -> the extension's trifilar run fails in LSODA (excess work)
    from bifilar.analysis.simulate import simulate
    from bifilar.studies import sweep as sw

    made = []
    real = nc.callable_f
    monkeypatch.setattr(nc, "callable_f", lambda *a: made.append(real(*a)) or made[-1])
    scene = _scene("trifilar_kth")
    cfg = read_yaml(CONFIGS / "solar_boat.yaml")
    st = sw.resolve_settings(cfg)
    runs = {}
    for way in ("extension", "ctypes", "python"):
        if way == "ctypes":
            monkeypatch.setattr(nc, "_call_type", lambda *a: None)
        if way == "python":
            monkeypatch.setenv("BIFILAR_NATIVE", "0")
        del made[:]
        ticks = []
        r = simulate(scene, 1, 0.05, 2.0, method="auto", rtol=1e-9, progress=lambda a, b: ticks.append(a))
        doc = sw.evaluate_point(cfg, "solar_boat", {"spacing": 3.0}, st)
        doc.pop("runtime_s", None)
        runs[way] = (r, ticks, json.dumps(doc, sort_keys=True), list(made))
    assert runs["extension"][3] and all(_is_ext(f) for f in runs["extension"][3])
    assert runs["ctypes"][3] and all(_is_ctypes(f) for f in runs["ctypes"][3])
    assert not runs["python"][3]
    (a, ta, ja, _), (b, tb, jb, _), (c, tc, jc, _) = runs.values()
    for other in (b, c):
        assert np.array_equal(_bits(a.y), _bits(other.y)) and np.array_equal(_bits(a.t), _bits(other.t))
    assert ta == tb == tc and len(ta) > 10
    assert '"valid": true' in ja and ja == jb == jc


def test_no_python_headers_gives_the_ctypes_f_silently(monkeypatch, tmp_path, capfd):
    # sysconfig's include directory without Python.h (no development headers): no extension build is tried,
    # the kernel still C through ctypes, the Python kernel's numbers, nothing printed.  Broken on purpose:
    # the Python.h check dropped (_python_includes giving sysconfig's directories as they are, the hash
    # stat-ing the directory) -> a build is tried ("built")
    import sysconfig

    if nk._compiler() is None:
        pytest.skip("no C compiler: the Python kernel runs (tests/test_native_kernel.py)")
    _fresh(monkeypatch, KEPT)
    paths = sysconfig.get_paths()
    monkeypatch.setattr(sysconfig, "get_paths", lambda *a, **k: {**paths, "include": str(tmp_path),
                                                                  "platinclude": str(tmp_path)})
    real = nk._build
    monkeypatch.setattr(nk, "_build", lambda pat, *a: pytest.fail("built") if pat.kind == "call" else real(pat, *a))
    P = mx.params_from_scenes(trapezoid())
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_ctypes(f)
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    assert capfd.readouterr() == ("", "")
    assert nc._call[0].state == "failed"


@needs_ext
def test_failed_build_gives_the_ctypes_f_and_is_not_retried(monkeypatch, tmp_path, capfd):
    # an extension source the compiler refuses: the ctypes f (the kernel still C), a kcall .failed marker, no
    # temporary left, nothing printed; a new process (fresh state) does not try again.  Broken on purpose:
    # the .failed check skipped in native_kernel._find -> "rebuilt"
    _fresh(monkeypatch, tmp_path)
    monkeypatch.setattr(nc, "_CALL_SOURCE", "#include <bifilar_no_such_header.h>\n" + nc._CALL_SOURCE)
    P = mx.params_from_scenes(trapezoid(l1=5.0, l2=5.3, h=0.5))
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_ctypes(f)
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    names = sorted(p.name for p in tmp_path.iterdir())
    assert [n.split("_")[0] + os.path.splitext(n)[1] for n in names] == ["kcall.failed", "kern.so"]
    assert capfd.readouterr() == ("", "")
    monkeypatch.setattr(nk, "_patterns", {})
    monkeypatch.setattr(nc, "_call", [])
    monkeypatch.setattr(nk, "_build", lambda pat, *a: pytest.fail("rebuilt") if pat.kind == "call" else None)
    assert _is_ctypes(mx.compiled_kernel(mx.params_from_scenes(trapezoid(l1=5.0, l2=5.3, h=0.5)),
                                         signature="odeint"))


@needs_ext
def test_disagreeing_extension_is_refused(monkeypatch, capfd):
    # an extension that copies one element of the state from the wrong place: built and loaded, refused by
    # the load-time check (two states against the ctypes f), the ctypes f used, nothing printed (built into
    # the kept cache under its own hash: one build per machine).  Broken on purpose: _call_agrees
    # comparing the callable with itself -> the wrong callable is used (not ctypes)
    _fresh(monkeypatch, KEPT)
    good = "memcpy(ybuf, b.buf, (size_t)b.len);"
    assert nc._CALL_SOURCE.count(good) == 1
    monkeypatch.setattr(nc, "_CALL_SOURCE", nc._CALL_SOURCE.replace(good, good + " ybuf[3] = ybuf[4];"))
    P = mx.params_from_scenes(trapezoid(l1=4.0, l2=4.6))
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_ctypes(f)
    assert nc._call[0].state == "failed" and nc._call[0].checked
    assert capfd.readouterr() == ("", "")


@needs_ext
def test_background_build_ctypes_first_then_the_callable(monkeypatch, tmp_path, capfd):
    # default mode, the kernel's library there (copied from the kept cache) and no extension: the ctypes f
    # at once and the extension's build started in the background; once it is published, the callable (the
    # build's child reaped), nothing printed
    import shutil

    scene = trapezoid(l1=4.0, l2=4.6)
    _fresh(monkeypatch, KEPT)
    mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint")
    (kern,) = nk._patterns.values()
    shutil.copy(kern.path, tmp_path)
    _fresh(monkeypatch, tmp_path, mode="async")
    assert _is_ctypes(mx.compiled_kernel(mx.params_from_scenes(scene), signature="odeint"))
    (call,) = nc._call
    assert call.state == "building" and call.proc is not None
    call.proc.wait(60)  # (a bound on a hung compiler, not a timing assertion)
    P = mx.params_from_scenes(scene)
    f = mx.compiled_kernel(P, signature="odeint")
    assert _is_ext(f) and call.proc is None and not nk._running
    y = np.linspace(-0.3, 0.4, 13)
    assert np.array_equal(_bits(f(y, 0.0)), _bits(mx.compiled_kernel(P, signature="odeint", native=False)(y, 0.0)))
    assert capfd.readouterr() == ("", "")
    assert sorted(p.name.split("_")[0] for p in tmp_path.iterdir()) == ["kcall", "kern"]
