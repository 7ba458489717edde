"""odeint's right-hand side compiled as C at run time: an optional accelerator.

:func:`~bifilar.models.maximal.compiled_kernel` with ``signature="odeint"``
(stabilised, no extras, up to ``MAX_ELIMINATION_WIRES`` wires: the kernels
``odeint`` integrates in ``simulate`` and in a sweep point's runs) hands its
statement list (:func:`~bifilar.models.maximal.kernel_statements`) here.
The same statements are rendered as one C function ``kern(y, o, p)``
(state y (13,) in the layout of the model, SI units, world frame with
body-axes angular velocity; derivatives o (13,); parameters p in the
order of the pattern's names), compiled by the system C compiler into a
shared library loaded through :mod:`ctypes` (standard library: no new
dependency) and called from a Python ``f(y, t)``, or, where Python's
headers let :mod:`.native_call` build its extension, from that
extension's callable (the same call without ctypes: ~0.1 us against ~1).

Bit for bit the Python kernel's numbers: the statements are the same IEEE
double operations (``+ - * /`` only, on names and float literals, checked
by :func:`c_source`) in the same order, and the compiler flags forbid
contraction into fused multiply-adds and fast-math (:data:`FLAGS`); each
library is also checked against the Python kernel on two states when it
is loaded, and refused (the Python kernel kept) on any difference.  The
C source depends on the pattern (wire count and zero set) only: every
value is a parameter.

Never slower, never visible: a library in the disk cache (:func:`cache_dir`,
file named from a hash of the source, compiler identity, flags and
platform) is loaded at once; an absent one is built in the background (a
``sh`` child in its own session compiles to a temporary name in the same
directory and renames it into place, so no partial file is ever seen
under the final name and an exit mid-build still publishes it) while the
Python kernel runs; later requests of the pattern switch to it once it is
published.  One build a pattern at a time across processes (a lock file;
a lock older than :data:`STALE_LOCK_S` is taken over).  No compiler, an
unwritable directory, a failed build (a ``.failed`` marker: not retried for
:data:`FAILED_RETRY_S`),
a library that does not load or disagrees: the Python kernel, a
debug-level log record (``bifilar.native``), nothing printed.

``BIFILAR_NATIVE``: ``0``/``off`` disables it; ``sync`` builds in the
foreground (benchmarks, tests); anything else (default) as above.
Imports of ``ctypes``, ``subprocess`` and ``hashlib`` happen on the
first request (a command that runs no odeint never pays them).
"""
from __future__ import annotations

import logging
import os
import re
import sys

log = logging.getLogger("bifilar.native")

ABI = "bifilar-native-1"
"""Part of every library's hash: a change of the C function's layout changes it."""

FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-w")
"""Compiler flags.  ``-ffp-contract=off``: no fused multiply-add (gcc's
default outside ISO mode is ``fast``, clang's ``on``: either changes
roundings); ``-std=c99`` also makes gcc's excess precision ``standard``
(irrelevant with x86-64's SSE2, which rounds every operation to double,
as CPython's floats do)."""

STALE_LOCK_S = 120.0
"""A build lock older than this (s) is a dead build's and is taken over."""

FAILED_RETRY_S = 86400.0
"""A failed build's ``.failed`` marker (s) is honoured this long, then the
build is tried again (a transient failure, e.g. a full disk or a build
killed mid-way, does not keep the pattern on Python for good; a compiler
that always fails costs one attempt a day)."""

SYNC_TIMEOUT_S = 120.0
"""Longest wait (s) for a foreground build (``BIFILAR_NATIVE=sync``)."""

_NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")
_EXPR = re.compile(r"^[A-Za-z_0-9.+\-*/() ]+$")
_NUMBER = re.compile(r"(?<![A-Za-z_0-9.])[0-9][0-9.]*")
_CALL = re.compile(r"[A-Za-z_0-9.)]\s*\(")  # a call (or an implicit product): not arithmetic
_STATE = ("rx", "ry", "rz", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")

_patterns: dict = {}  # hash -> _Pattern (this process)
_env: dict = {}  # the compiler, its identity, the cache directory (found once a process)


def mode() -> str:
    """``"off"``, ``"sync"`` or ``"async"`` from ``BIFILAR_NATIVE``."""
    v = os.environ.get("BIFILAR_NATIVE", "").strip().lower()
    return "off" if v in ("0", "off", "no", "false") else ("sync" if v == "sync" else "async")


def cache_dir() -> str:
    """``$BIFILAR_CACHE_DIR``, else ``$XDG_CACHE_HOME/bifilar``, else ``~/.cache/bifilar``."""
    d = os.environ.get("BIFILAR_CACHE_DIR")
    if d:
        return d
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "bifilar")


def c_source(lines: list, out: list, params: list) -> str:
    """The statements ``lines`` (``"name = expr"``), outputs ``out`` (13
    expressions) and parameter names ``params`` as the C function
    ``void kern(const double *y, double *o, const double *p)``: ``y`` the
    state (13,) and ``o`` its time derivative (13,) in the layout of
    :mod:`bifilar.models.maximal` (SI units, world frame, angular velocity
    in body axes), ``p`` the parameters' values (SI) in ``params``' order.
    ValueError for anything that is not names, float literals (with a
    point: no integer division) and ``+ - * /`` with parentheses (no
    call: ``sqrt`` or ``_min_norm`` would not be Python's)."""
    def check(expr: str) -> str:
        if not _EXPR.match(expr) or _CALL.search(expr) or any("." not in m for m in _NUMBER.findall(expr)):
            raise ValueError(f"not a plain arithmetic expression: {expr!r}")
        return expr

    body, seen = [], set(_STATE) | set(params)
    for ln in lines:
        tgt, sep, expr = ln.partition(" = ")
        if not sep or not _NAME.fullmatch(tgt):
            raise ValueError(f"not a single assignment: {ln!r}")
        body.append(f"  {'' if tgt in seen else 'double '}{tgt} = {check(expr)};")
        seen.add(tgt)
    if len(out) != len(_STATE):
        raise ValueError("the C kernel gives the 13 derivatives only")
    return ("void kern(const double *bifilar_y, double *bifilar_o, const double *bifilar_p) {\n"
            + "".join(f"  double {v} = bifilar_y[{i}];\n" for i, v in enumerate(_STATE))
            + "".join(f"  double {v} = bifilar_p[{i}];\n" for i, v in enumerate(params))
            + "\n".join(body) + "\n"
            + "".join(f"  bifilar_o[{i}] = {check(e)};\n" for i, e in enumerate(out)) + "}\n"
            + f"int kern_params(void) {{ return {len(params)}; }}\n")


def _compiler():
    """(argv of the C compiler, its identity) or None: ``$CC`` if set (only
    it), else sysconfig's CC, else ``cc`` or ``gcc`` on PATH.  The identity
    is the resolved binary's path, size and modification time (a compiler
    upgrade makes new libraries; no subprocess to ask its version)."""
    if "cc" not in _env:
        import shlex
        import shutil
        import sysconfig
        cands = [os.environ["CC"]] if os.environ.get("CC") else \
            [c for c in (sysconfig.get_config_var("CC"), "cc", "gcc") if c]
        _env["cc"] = None
        for c in cands:
            try:
                argv = shlex.split(c)
            except ValueError:
                continue
            exe = shutil.which(argv[0]) if argv else None
            if exe:
                real = os.path.realpath(exe)
                st = os.stat(real)
                _env["cc"] = ([exe] + argv[1:], f"{real}:{st.st_size}:{st.st_mtime_ns}:{' '.join(argv[1:])}")
                break
        _env["sh"] = shutil.which("sh")
    return _env["cc"]


class _Pattern:
    """One cached artefact in this process: a pattern's kernel library
    (``kind`` ``"kernel"``) or the call extension (``"call"``, compiled
    with the extra ``flags``; :mod:`.native_call`), loaded by ``open(pat)``.
    State ``ready`` (``func``: what ``open`` gave: the kernel's ctypes
    function, the extension's callable type), ``building`` (ours: ``proc``;
    another process's: ``proc`` None), ``failed``."""

    def __init__(self, path: str, kind: str = "kernel", state: str = "new"):
        self.path, self.state, self.func, self.proc, self.checked = path, state, None, None, False
        self.kind, self.flags, self.open = kind, (), _open_kernel


def odeint_kernel(key: tuple, statements, values: list, ticks=None, reference=None):
    """A C ``f(y, t)`` for odeint, or None (then the caller runs its Python kernel).

    ``f(y, t)``: ``y`` the state (13,) (SI units, world frame, angular
    velocity in body axes), ``t`` the time (s, unused but for ``ticks``);
    returns its time derivative (13,), the same bits as the Python kernel.

    ``key``: the pattern (wire count, zero set), ``statements()`` ->
    ``(lines, out, params)`` (called once a pattern and process),
    ``values()`` -> the parameters' values in the order of ``params``
    (floats, SI units; asked only when the library is there), ``ticks``: ``(at, tick)`` as the Python kernel's (the tick
    check runs in Python before the C call: the same calls and times),
    ``reference()`` -> the Python ``f(y, t)`` with the same values, the
    check a newly loaded library must pass bit for bit.  The returned
    function overwrites and returns the same array (13,) on every call, as
    the Python kernel does.  Never raises: any error is a debug record and
    None."""
    try:
        return _odeint_kernel(key, statements, values, ticks, reference)
    except Exception as exc:  # noqa: BLE001 - an accelerator: the Python kernel is always there
        log.debug("native kernel: %s: %s", type(exc).__name__, exc)
        _patterns[key] = _Pattern("", state="failed")
        return None


def _odeint_kernel(key, statements, values, ticks, reference):
    m = mode()
    if m == "off":
        return None
    pat = _patterns.get(key)
    if pat is None:
        pat = _patterns[key] = _start(key, statements, m)
    if pat.state == "building":
        _poll(pat)
    if pat.state != "ready":
        return None
    if not pat.checked:
        pat.checked = True
        if reference is None or not _agrees(pat.func, values(), reference):
            log.debug("native kernel %s disagrees with the Python kernel: not used", pat.path)
            pat.state, pat.func = "failed", None
            return None
    return _wrap(pat.func, values(), ticks)


def ready_pattern(slot: list, start):
    """The :class:`_Pattern` in ``slot`` (a list of one, filled by ``start()``
    on the first call of a process), polled while it builds; it where it
    is ready (loaded), else None."""
    if not slot:
        slot.append(start())
    pat = slot[0]
    if pat.state == "building":
        _poll(pat)
    return pat if pat.state == "ready" else None


def _start(key, statements, m: str) -> _Pattern:
    """Find the pattern's library: load it, or start (or wait for) its build."""
    cc = _compiler()
    if cc is None or _env.get("sh") is None:
        log.debug("native kernel: no C compiler (or sh) found")
        return _Pattern("", state="failed")
    import hashlib
    lines, out, params = statements()
    try:
        src = c_source(lines, out, params)
    except ValueError as exc:
        log.debug("native kernel: %s", exc)
        return _Pattern("", state="failed")
    ident = "\n".join([ABI, cc[1], " ".join(FLAGS), sys.platform, os.uname().machine, src])
    pat = _Pattern(os.path.join(cache_dir(), "kern_" + hashlib.sha256(ident.encode()).hexdigest()[:32] + ".so"))
    pat.src = src
    return _find(pat, cc[0], m)


def _find(pat: _Pattern, cc: list, m: str) -> _Pattern:
    """``pat`` loaded from the cache, or its build started (or waited for),
    or failed (a directory others can write to, a recent ``.failed``)."""
    d = os.path.dirname(pat.path)
    if not _private(d):
        log.debug("native kernel: %s is not this user's alone: not used", d)
        pat.state = "failed"
        return pat
    if _load(pat):
        return pat
    if _failed_recently(pat.path + ".failed"):
        log.debug("native kernel: %s failed to build before: not retried", pat.path)
        pat.state = "failed"
        return pat
    _build(pat, cc, m == "sync")
    return pat


def _failed_recently(marker: str) -> bool:
    """A ``.failed`` marker younger than :data:`FAILED_RETRY_S`; an older
    one is removed (the build is tried again)."""
    import time
    try:
        if time.time() - os.stat(marker).st_mtime < FAILED_RETRY_S:
            return True
        os.unlink(marker)
    except OSError:
        pass
    return False


def _private(d: str) -> bool:
    """``d`` is absent (it will be made 0700) or owned by this user and not
    writable by group or others: a library loaded from it is one of ours."""
    try:
        st = os.stat(d)
    except FileNotFoundError:
        return True
    except OSError:
        return False
    return st.st_uid == os.getuid() and not st.st_mode & 0o022


def _load(pat: _Pattern) -> bool:
    """Load the published file if there is one (ready); a file that does not
    load, or has the wrong layout, is removed (and rebuilt)."""
    if not os.path.exists(pat.path):
        return False
    try:
        func = pat.open(pat)
    except (OSError, AttributeError, ImportError) as exc:
        log.debug("native kernel %s unusable (%s): removed", pat.path, exc)
        try:
            os.unlink(pat.path)
        except OSError:
            pass
        return False
    pat.state, pat.func = "ready", func
    return True


def _open_kernel(pat: _Pattern):
    """The kernel library's ``kern`` as a ctypes function."""
    import ctypes
    lib = ctypes.CDLL(pat.path)
    if lib.kern_params() != pat.src.count("= bifilar_p["):
        raise OSError("parameter count differs")
    func = lib.kern
    func.restype = None
    return func


_SCRIPT = ('src=$1; tmp=$2; dst=$3; lock=$4; shift 4; '
           '"$@" -o "$tmp" "$src" && mv -f "$tmp" "$dst" || : > "$dst.failed"; '
           'rm -f "$tmp" "$src" "$lock"')


def _build(pat: _Pattern, cc: list, sync: bool) -> None:
    """Compile ``pat``'s source: take the lock (or wait for the process
    that holds it), write the source, and run the compile-and-rename
    script (:data:`_SCRIPT`) in a child of its own session, its output
    discarded; in the foreground if ``sync``."""
    import subprocess
    d = os.path.dirname(pat.path)
    lock = pat.path + ".lock"
    pat.state, pat.lock = "building", lock
    fd = src_path = None
    try:
        os.makedirs(d, mode=0o700, exist_ok=True)
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        except FileExistsError:
            import time
            if time.time() - os.stat(lock).st_mtime < STALE_LOCK_S:
                if sync:  # another process is building it: wait for it here
                    t_end = time.monotonic() + SYNC_TIMEOUT_S
                    while os.path.exists(lock) and time.monotonic() < t_end:
                        time.sleep(0.02)
                    _poll(pat)
                return  # proc None: another process's build, polled by the file
            os.unlink(lock)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        os.close(fd)
        tag = f"{os.getpid()}.{os.urandom(4).hex()}"
        src_path, tmp = f"{pat.path}.{tag}.c", f"{pat.path}.{tag}.tmp"
        with open(src_path, "w") as fh:
            fh.write(pat.src)
        argv = [_env["sh"], "-c", _SCRIPT, "sh", src_path, tmp, pat.path, lock, *cc, *FLAGS, *pat.flags]
        pat.owner = os.getpid()
        pat.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.DEVNULL, start_new_session=True, close_fds=True)
    except OSError as exc:
        log.debug("native kernel: cannot build in %s (%s)", d, exc)
        pat.state = "failed"
        if pat.proc is None and fd is not None:  # our lock, no child to remove it
            for leftover in (lock, src_path):
                try:
                    os.unlink(leftover)
                except (OSError, TypeError):
                    pass
        return
    _running.append(pat.proc)
    if sync:
        try:
            pat.proc.wait(SYNC_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            pass
    _poll(pat)


def _poll(pat: _Pattern) -> None:
    """Switch a building pattern to ready (published) or failed (its build
    ended without a library); reaps our build's child."""
    if pat.proc is not None and pat.owner != os.getpid():  # a forked worker (sweep's pool): the parent's child
        pat.proc = None
    if pat.proc is not None:
        if pat.proc.poll() is None:
            return
        _running.remove(pat.proc)
        pat.proc = None
    elif os.path.exists(pat.lock) and not os.path.exists(pat.path):
        return  # another process is still building it
    if not _load(pat):
        log.debug("native kernel %s: build failed", pat.path)
        pat.state = "failed"


_running: list = []


def _reap() -> None:
    """At exit: reap our finished builds; a running one is left to finish and
    publish (it is in its own session; not waited for: an exit is never
    delayed by a build)."""
    for p in list(_running):
        if p.poll() is not None:
            _running.remove(p)


import atexit  # noqa: E402 - registered with the module (imported only with the first odeint kernel)

atexit.register(_reap)


def _states():
    """The two states (13,) every load-time check compares at (SI units,
    unnormalised quaternions, large rates: every term of the kernel counts)."""
    import numpy as np
    return (np.array([0.01, -0.02, -0.9, 0.99, 0.05, -0.08, 0.1, 0.3, -0.2, 0.05, 0.7, -1.1, 2.3]),
            np.array([-0.03, 0.015, -1.4, 0.9, -0.2, 0.3, -0.1, -0.1, 0.4, -0.02, -2.0, 0.6, -0.9]))


def _agrees(func, values: list, reference) -> bool:
    """The library's derivatives equal ``reference``'s bit for bit at two states."""
    import numpy as np
    f, ref = _ctypes_f(func, values, None)[0], reference()
    return all(np.array_equal(f(y, 0.0).view(np.int64), np.array(ref(y, 0.0)).view(np.int64)) for y in _states())


def _ctypes_f(func, values: list, ticks):
    """``(f, plain, pv, out)``: ``f(y, t)`` calling ``func`` through ctypes
    with the parameters ``pv`` (the array of ``values``) into ``out`` (13,),
    which it returns; ``plain`` the same without the tick check (``f``
    itself where ``ticks`` is None).  The state is copied into a buffer
    whose pointer is converted once (the cheapest ctypes call measured:
    ~0.53 us against ~0.90 us with ``from_buffer(y)``)."""
    import ctypes

    import numpy as np
    pv = np.array(values, dtype=float).reshape(-1)
    ybuf, out = np.empty(13), np.empty(13)
    yp, op, pp = (ctypes.c_void_p(a.ctypes.data) for a in (ybuf, out, pv))

    def plain(y, t, func=func, ybuf=ybuf, yp=yp, op=op, pp=pp, out=out, keep=pv):
        ybuf[:] = y
        func(yp, op, pp)
        return out
    if ticks is None:
        return plain, plain, pv, out
    at, tick = ticks

    def f(y, t, func=func, ybuf=ybuf, yp=yp, op=op, pp=pp, out=out, keep=pv, at=at, tick=tick):
        if t >= at[0]:
            tick(t)
        ybuf[:] = y
        func(yp, op, pp)
        return out
    return f, plain, pv, out


def _wrap(func, values: list, ticks):
    """odeint's ``f(y, t)`` of the library function ``func`` with the
    parameters ``values`` (see :func:`odeint_kernel`): the call extension's
    callable (:mod:`.native_call`; ~0.1 us a call against ~1 us) where it
    is built, loaded and checked, else the ctypes ``f`` (:func:`_ctypes_f`).
    Both copy the state, call ``func`` and return the same array; the
    callable hands any state that is not one C-contiguous row of 13
    doubles to the ctypes ``f`` (numpy's conversion, the same numbers)."""
    f, plain, pv, out = _ctypes_f(func, values, ticks)
    from . import native_call
    return native_call.callable_f(func, f, plain, pv, out, ticks)


def _address(func) -> int:
    """The C function's address behind the ctypes function ``func``."""
    import ctypes
    return ctypes.cast(func, ctypes.c_void_p).value
