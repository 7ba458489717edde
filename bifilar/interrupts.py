"""Stopping a run: Ctrl-C (SIGINT) and SIGTERM as exceptions that cannot be lost.

Python turns a signal into an exception at the next bytecode the main thread
runs, wherever that is.  When that bytecode belongs to a finaliser (a
``__del__`` method, a generator closed by the garbage collector, a ``gc``
callback), the interpreter prints "Exception ignored in ..." and *drops*
the exception: the run goes on as if the user had not pressed Ctrl-C, and a
10 000-period simulation finished and exited 0 (seen as a failure of
``tests/test_cli.py::test_signal_during_a_run_exits_cleanly`` about once in
a hundred runs on a loaded machine).

So the command line's handlers (:func:`stop_handlers`) also *remember* the
request, and the places a run passes through regularly or before it commits
a result call :func:`raise_if_stop_requested`: the progress updates of every
long computation, and :func:`bifilar.output.atomic_write` before it renames
its file onto the user's name.  A stop swallowed by a finaliser is thus
raised again within one progress step, and never lets a file be written.

This module imports nothing from the package, so every layer may use it.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Iterator


class Terminated(KeyboardInterrupt):
    """SIGTERM turned into an exception so that ``finally`` blocks (temporary
    files of :func:`~bifilar.output.atomic_write`, journals) run; the CLI
    exits with status 143.

    A subclass of :class:`KeyboardInterrupt` so that code stopping early on
    Ctrl-C stops on SIGTERM too; code that re-raises an interruption under its
    own type must keep it recognisable (see :func:`is_terminated`)."""


def is_terminated(exc: BaseException) -> bool:
    """True if ``exc`` is, or was raised from / carries, a SIGTERM
    (:class:`Terminated`) rather than a Ctrl-C."""
    seen = 0
    while exc is not None and seen < 20:
        if isinstance(exc, Terminated) or getattr(exc, "terminated", False):
            return True
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return False


_requested: list[type[KeyboardInterrupt]] = []
"""The stops signalled since :func:`stop_handlers` was entered (their exception types)."""


def _on_signal(signum, frame) -> None:  # pragma: no cover - exercised through a subprocess
    exc = Terminated if signum == signal.SIGTERM else KeyboardInterrupt
    _requested.append(exc)
    raise exc()


def stop_requested() -> type[KeyboardInterrupt] | None:
    """The exception type of the last stop signalled and not yet cleared
    (:class:`KeyboardInterrupt` for Ctrl-C, :class:`Terminated` for SIGTERM),
    else ``None``."""
    return _requested[-1] if _requested else None


def raise_if_stop_requested() -> None:
    """Raise the signalled stop again (see the module's docstring); a no-op
    when none was signalled.  Cheap: call it as often as convenient."""
    if _requested:
        raise _requested[-1]()


@contextlib.contextmanager
def stop_handlers() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM raise :class:`KeyboardInterrupt` /
    :class:`Terminated` *and* are remembered (:func:`stop_requested`); the
    previous handlers are restored and the record cleared on leaving.  Only
    in the main thread (elsewhere a no-op: Python runs handlers there only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            old[sig] = signal.signal(sig, _on_signal)
        except (ValueError, OSError):  # pragma: no cover - exotic embedding
            pass
    _requested.clear()
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        _requested.clear()
