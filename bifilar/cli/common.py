"""Shared CLI plumbing: error -> exit status, JSON/table output, safe files.

Exit status: 0 success, 2 invalid input (one line per problem on stderr,
naming the field), 1 anything else.  ``--json`` prints exactly one JSON
document on stdout; logs and progress bars go to stderr.  Output files are
written atomically (temporary file + rename) and never over an existing
file unless ``--force`` is given, and never over the input config.
"""

from __future__ import annotations

import functools
import json
import logging
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable

import click

log = logging.getLogger("bifilar")


def setup_logging(verbose: bool) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, stream=sys.stderr,
                        format="%(levelname)s: %(message)s")


def handle_errors(fn: Callable) -> Callable:
    """Turn package errors into one-line messages and exit codes."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from ..errors import BifilarError, ConfigErrors, InputError

        ctx = click.get_current_context()
        debug = bool((ctx.obj or {}).get("debug"))
        try:
            return fn(*args, **kwargs)
        except (click.exceptions.Exit, click.exceptions.Abort, click.ClickException):
            raise
        except ConfigErrors as exc:
            if debug:
                raise
            for e in exc.errors:
                click.echo(f"error: {e}", err=True)
            ctx.exit(2)
        except InputError as exc:
            if debug:
                raise
            click.echo(f"error: {exc}", err=True)
            ctx.exit(2)
        except BifilarError as exc:
            if debug:
                raise
            click.echo(f"error: {type(exc).__name__}: {exc}", err=True)
            ctx.exit(1)
        except KeyboardInterrupt:
            click.echo("interrupted", err=True)
            ctx.exit(130)
        except Exception as exc:  # noqa: BLE001 - last resort, never a traceback without --debug
            if debug:
                raise
            click.echo(f"error: internal error ({type(exc).__name__}: {exc}); rerun with --debug for a traceback",
                       err=True)
            ctx.exit(1)

    return wrapper


def _clean(x: Any) -> Any:
    import numpy as np

    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, np.ndarray):
        return _clean(x.tolist())
    if isinstance(x, (np.floating,)):
        x = float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def emit_json(doc: Any) -> None:
    """Print exactly one JSON document on stdout (NaN/inf become null)."""
    click.echo(json.dumps(_clean(doc), allow_nan=False))


def console():
    from rich.console import Console

    return Console()


def err_console():
    from rich.console import Console

    return Console(stderr=True)


def check_output_path(path: str | None, force: bool, protected: list[str | None], option: str) -> Path | None:
    """Validate an output path before any work is done (exit 2 on problems)."""
    from ..errors import InputError

    if path is None:
        return None
    p = Path(path)
    for q in protected:
        if q is not None and Path(q).exists() and p.exists() and p.resolve() == Path(q).resolve():
            raise InputError(option, f"refusing to write over the input file {q}")
    if p.exists() and not force:
        raise InputError(option, f"{p} exists; choose another name or pass --force to replace it")
    if p.exists() and p.is_dir():
        raise InputError(option, f"{p} is a directory")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.exists():
        raise InputError(option, f"directory {parent} does not exist")
    return p


def atomic_write(path: Path, write: Callable[[str], None]) -> None:
    """Call ``write(tmp_path)`` then rename the temporary file onto ``path``."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=str(path.parent or "."))
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def write_csv(path: Path, header: list[str], rows) -> None:
    import numpy as np

    def w(tmp: str) -> None:
        np.savetxt(tmp, np.asarray(rows, float), delimiter=",", header=",".join(header), comments="", fmt="%.12g")

    atomic_write(path, w)


def progress_bar(description: str, enabled: bool = True):
    """A rich progress bar on stderr; a context manager yielding ``update(done, total)``."""
    import contextlib

    @contextlib.contextmanager
    def cm():
        if not enabled:
            yield lambda done, total: None
            return
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
                      TimeElapsedColumn(), console=err_console(), transient=True) as prog:
            task = prog.add_task(description, total=1.0)

            def update(done: float, total: float) -> None:
                prog.update(task, completed=min(done / total, 1.0) if total else 1.0)

            yield update

    return cm()


def fmt(x: Any, digits: int = 6) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.{digits}g}"
    return str(x)
