"""Shared CLI plumbing: error -> exit status, JSON/table output, safe files.

Exit status: 0 success, 2 invalid input (one line per problem on stderr,
naming the field), 1 anything else.  ``--json`` prints exactly one JSON
document on stdout; logs and progress bars go to stderr.  Output files are
written atomically (temporary file + rename) and never over an existing
file unless ``--force`` is given, and never over the input config.
"""

from __future__ import annotations

import contextlib
import functools
import io
import json
import logging
import math
import os
import sys
import warnings
from typing import Any, Callable

import click

from ..interrupts import raise_if_stop_requested, stop_handlers
from ..output import (PLOT_SUFFIXES, Terminated, atomic_write, check_journal_path,  # noqa: F401 (re-exported)
                      check_output_path, is_terminated, write_csv, write_table_csv)

log = logging.getLogger("bifilar")


class _StderrHandler(logging.StreamHandler):
    """Log handler writing to whatever ``sys.stderr`` is at the time of the
    record (click's test runner and pytest swap it)."""

    def __init__(self) -> None:
        super().__init__()

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:  # the stream is always the current sys.stderr
        pass


class _LowerLevelFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        return f"{record.levelname.lower()}: {_one_line(record.getMessage())}"


class _Collector(logging.Handler):
    """Keeps the one-line text of every warning the config layer logs while a
    command runs (:func:`handle_errors` installs it), for :func:`emit_json`."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(_one_line(record.getMessage()))


#: the collector of the running command (None outside :func:`handle_errors`)
_config_warnings: _Collector | None = None


def setup_logging(verbose: bool) -> None:
    """Send the package's log records (``bifilar.*``) to stderr as
    ``warning: ...`` lines; INFO too with ``verbose``.  Idempotent."""
    logger = logging.getLogger("bifilar")
    for h in list(logger.handlers):
        if isinstance(h, _StderrHandler):
            logger.removeHandler(h)
    handler = _StderrHandler()
    handler.setFormatter(_LowerLevelFormatter())
    logger.addHandler(handler)
    logger.setLevel(logging.INFO if verbose else logging.WARNING)


def _one_line(s: str) -> str:
    """Collapse a message onto one line (the CLI promises one line per problem)."""
    return " ".join(str(s).replace("\r", "\n").split("\n"))


def _forget_unhandled_interrupt() -> None:
    """Undo CPython's note that a KeyboardInterrupt went unhandled.

    A KeyboardInterrupt that leaves code run by ``exec``/``eval`` of a
    *string* (``dataclasses`` and ``namedtuple`` build their methods so, e.g.
    while a module is imported lazily mid-run) sets the interpreter's flag
    ``_Py_UnhandledKeyboardInterrupt`` even when the exception is caught
    later; at exit CPython then kills itself with SIGINT, and a caller sees
    status -2 instead of this command's 130 (about 1 Ctrl-C in 40 during a
    `simulate` on a loaded machine).  Every ``exec`` of a string resets the
    flag first, so an empty one clears it."""
    exec("pass", {})  # noqa: S102 - a constant string


def handle_errors(fn: Callable) -> Callable:
    """Decorator for commands: package errors -> one-line messages and exit codes.

    * :class:`~bifilar.errors.InputError` (and :class:`~bifilar.errors.ConfigErrors`,
      one line per problem): exit 2, ``error: <field>: <message>``;
    * any other :class:`~bifilar.errors.BifilarError`: exit 1,
      ``error: <ClassName>: <message>``;
    * any other exception: exit 1, ``error: internal error (...)``;
    * Ctrl-C: exit 130, SIGTERM: exit 143 (``interrupted`` / ``terminated``),
      after temporary output files are removed;
    * a closed stdout pipe (``| head``): exit 141 quietly.

    ``bifilar --debug CMD`` re-raises instead (a traceback, exit 1).
    """

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from ..errors import BifilarError, ConfigErrors, InputError

        ctx = click.get_current_context()
        debug = bool((ctx.obj or {}).get("debug"))
        global _config_warnings
        config_log = logging.getLogger("bifilar.config")
        collector, outer = _Collector(), _config_warnings
        config_log.addHandler(collector)
        _config_warnings = collector
        try:
            with stop_handlers(), warnings.catch_warnings(), _native_stdout_to_stderr():
                if not debug:
                    warnings.showwarning = _show_warning_one_line
                result = fn(*args, **kwargs)
                raise_if_stop_requested()  # a Ctrl-C a finaliser swallowed after the last progress step
                return result
        except (click.exceptions.Exit, click.exceptions.Abort, click.ClickException):
            raise
        except ConfigErrors as exc:
            if debug:
                raise
            for e in exc.errors:
                click.echo(f"error: {_one_line(str(e))}", err=True)
            ctx.exit(2)
        except InputError as exc:
            if debug:
                raise
            click.echo(f"error: {_one_line(str(exc))}", err=True)
            ctx.exit(2)
        except BifilarError as exc:
            if debug:
                raise
            click.echo(f"error: {type(exc).__name__}: {_one_line(str(exc))}", err=True)
            ctx.exit(1)
        except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (Terminated), possibly re-raised as SweepInterrupted
            _forget_unhandled_interrupt()
            if is_terminated(exc):
                click.echo("terminated", err=True)
                ctx.exit(143)
            click.echo("interrupted", err=True)
            ctx.exit(130)
        except BrokenPipeError:
            _silence_stdout()
            ctx.exit(141)
        except OSError as exc:  # disk full, permission denied while writing an output, ...
            if debug:
                raise
            where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
            click.echo(f"error: {type(exc).__name__}: {_one_line(exc.strerror or str(exc))}{where}", err=True)
            ctx.exit(1)
        except Exception as exc:  # noqa: BLE001 - last resort, never a traceback without --debug
            if debug:
                raise
            click.echo(f"error: internal error ({type(exc).__name__}: {_one_line(str(exc))}); "
                       "rerun with --debug for a traceback", err=True)
            ctx.exit(1)
        finally:
            config_log.removeHandler(collector)
            _config_warnings = outer

    return wrapper


@contextlib.contextmanager
def _native_stdout_to_stderr():
    """Keep stdout for the package's own output while a command runs.

    Compiled libraries write diagnostics straight to file descriptor 1
    (LAPACK's ``** On entry to DLASCL parameter number 4 had an illegal
    value`` for a signal around 1e200), which would corrupt a ``--json``
    document or a table.  Here fd 1 is pointed at stderr and ``sys.stdout``
    at a duplicate of the real stdout, restored afterwards.  Nothing is done
    when ``sys.stdout`` is not fd 1 (a test runner's capture)."""
    try:
        sys.stdout.flush()
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError, io.UnsupportedOperation):
        fd = None
    if fd != 1:
        yield
        return
    old = sys.stdout
    saved = os.dup(1)
    new = io.TextIOWrapper(io.FileIO(saved, "w", closefd=False), encoding=old.encoding, errors=old.errors,
                           line_buffering=old.line_buffering)
    os.dup2(2, 1)
    sys.stdout = new
    try:
        yield
    finally:
        try:
            new.flush()
        except (OSError, ValueError):  # a closed pipe: handled (exit 141) by the caller
            pass
        sys.stdout = old
        os.dup2(saved, 1)
        os.close(saved)


def _show_warning_one_line(message, category, filename, lineno, file=None, line=None) -> None:
    """Python warnings (numpy overflow, scipy) as one ``warning:`` line on stderr."""
    click.echo(f"warning: {category.__name__}: {_one_line(str(message))}", err=True)


def _silence_stdout() -> None:
    """After EPIPE: point stdout at /dev/null so the interpreter's final flush is quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        pass


MAX_SIM_PERIODS = 10_000
"""Most periods ``simulate`` and ``tensions`` integrate (~45 s and ~2 M
samples for the thesis plate; more would run for hours and fill memory)."""
from ..studies.study_inputs import MAX_SWEEP_PERIODS  # noqa: E402,F401 (re-exported; sweep's and plan's limit)
MAX_WORKERS = 1024
"""Largest ``--workers`` accepted; fewer processes start when there are fewer
points or CPUs (:func:`bifilar.studies.sweep.effective_workers`)."""


def check_workers(workers: int) -> None:
    """``--workers`` in 1 .. :data:`MAX_WORKERS` (exit 2 otherwise)."""
    from ..errors import InputError

    if not 1 <= workers <= MAX_WORKERS:
        raise InputError("--workers", f"must be in 1 .. {MAX_WORKERS}, got {workers} (at most one process per "
                                      "CPU and per point starts anyway)")


class OptionChecker:
    """Collect command-line option problems and report them all at once.

    Usage in a command (before any work)::

        chk = OptionChecker()
        chk.positive("--periods", periods)
        chk.in_range("--rtol", rtol, 0, 1e-2, lo_open=True, hi_open=True)
        chk.done()  # raises ConfigErrors (exit 2, one line per problem) if any failed

    Each check returns True when the value passed (so later checks that
    need a valid value can be skipped).
    """

    def __init__(self) -> None:
        self.errors: list = []

    def error(self, option: str, message: str) -> None:
        from ..errors import InputError

        self.errors.append(InputError(option, message))

    def finite(self, option: str, value: float | None) -> bool:
        if value is None:
            return True
        if not math.isfinite(value):
            self.error(option, f"must be finite, got {value}")
            return False
        return True

    def positive(self, option: str, value: float | None) -> bool:
        if value is None or not self.finite(option, value):
            return value is None
        if value <= 0:
            self.error(option, f"must be positive, got {value:g}")
            return False
        return True

    def in_range(self, option: str, value: float | None, lo: float, hi: float, *,
                 lo_open: bool = False, hi_open: bool = False) -> bool:
        if value is None or not self.finite(option, value):
            return value is None
        ok = (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
        if not ok:
            interval = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
            self.error(option, f"must be in {interval}, got {value:g}")
        return ok

    def choice(self, option: str, value: Any, choices) -> bool:
        if value is None or value in choices:
            return True
        import difflib

        hint = difflib.get_close_matches(str(value), [str(c) for c in choices], n=1)
        extra = f"; did you mean '{hint[0]}'?" if hint else ""
        self.error(option, f"must be one of {', '.join(map(str, choices))}, got {value!r}{extra}")
        return False

    def done(self) -> None:
        """Raise :class:`~bifilar.errors.ConfigErrors` with every problem, if any."""
        from ..errors import ConfigErrors

        if self.errors:
            raise ConfigErrors(self.errors)


def config_rest_pose(scene, config):
    """The rest pose of ``scene`` (the config at path ``config``); kept here
    for the commands that import it: :func:`bifilar.estimation.slack_cause.config_rest_pose`
    (imported when called, so that the CLI starts without it)."""
    from ..estimation.slack_cause import config_rest_pose as rest_of_config

    return rest_of_config(scene, config)


def warn_at_rest(scene, rest, modes, only: str | None = None) -> list[str]:
    """Log the rest pose's warnings to stderr (``warning: ...``), as
    ``modes``, ``simulate`` and ``tensions`` give them
    (:func:`bifilar.analysis.rest_warnings.rest_warnings`), and return them
    (one line each, no prefix) for the command's JSON ``warnings``."""
    from ..analysis.rest_warnings import rest_warnings

    ws = rest_warnings(scene, rest, modes, only=only)
    for w in ws:
        click.echo(f"warning: {w}", err=True)
    return ws


def emit_json(doc: Any) -> None:
    """Print exactly one JSON document on stdout (NaN/inf become null).

    The warnings the config layer logged while the command read its inputs
    (implausible values, a stated ``rig.stiffness`` the model does not carry
    through: :func:`bifilar.config.plausibility_warnings`) go to stderr as
    they arise; they are put at the head of the document's ``warnings`` list
    too (created if need be), so that a program reading the JSON sees every
    caveat of its answer, not only those of the computation."""
    from ..jsonable import to_jsonable

    if isinstance(doc, dict) and _config_warnings is not None and _config_warnings.messages:
        have = doc.get("warnings")
        have = list(have) if isinstance(have, (list, tuple)) else ([] if have is None else None)
        if have is not None:
            extra = [w for w in dict.fromkeys(_config_warnings.messages) if w not in have]
            if extra:
                doc = {**doc, "warnings": extra + have}

    click.echo(json.dumps(to_jsonable(doc), allow_nan=False))


def _console_class():
    from rich.console import Console

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            """A closed stdout (``| head``): rich would exit 1; raise so that
            :func:`handle_errors` ends quietly with 141."""
            self.quiet = True
            raise BrokenPipeError(32, "stdout closed")

    return _Console


def console():
    """A rich console on stdout.  Markup in the package's own strings only:
    pass every user string (names, labels, paths, messages) through :func:`esc`;
    emoji codes (``:smile:``) are never substituted.  A closed pipe ends the
    command with status 141 and no message."""
    return _console_class()(emoji=False)


def err_console():
    return _console_class()(stderr=True, emoji=False)


def esc(x: Any) -> str:
    """``str(x)`` with rich markup escaped, so a config name such as
    ``"rotor [v2]"`` or ``"frame [/b]"`` prints literally."""
    from rich.markup import escape

    return escape(str(x))


def progress_bar(description: str, enabled: bool = True):
    """A rich progress bar on stderr; a context manager yielding ``update(done, total)``.

    Drawn only when stderr is a terminal (a log file or a pipe gets nothing)."""
    import contextlib

    @contextlib.contextmanager
    def cm():
        if not enabled or not _stderr_is_terminal():
            yield lambda done, total: raise_if_stop_requested()
            return
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                      TimeElapsedColumn(), console=err_console(), transient=True) as prog:
            task = prog.add_task(description, total=1.0)

            def update(done: float, total: float) -> None:
                raise_if_stop_requested()  # a Ctrl-C swallowed by a finaliser stops the run here
                prog.update(task, completed=min(done / total, 1.0) if total else 1.0)

            yield update

    return cm()


def _stderr_is_terminal() -> bool:
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError):
        return False


def fmt(x: Any, digits: int = 6) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.{digits}g}"
    return str(x)
