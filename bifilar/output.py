"""Every file the package writes: atomic replacement, CSV tables, JSON-lines
journals, and the checks of output paths made before any work.

This module sits below the CLI (it imports only :mod:`bifilar.errors` and
:mod:`bifilar.interrupts`), so
the library (reports, sweeps, the Monte Carlo journal) and the commands
share one implementation of the promises in docs/errors.md:

* an output file is written to a temporary file in its directory and renamed
  onto its name, so it is either untouched or complete; an existing file is
  replaced only with ``--force``; an input file never;
* an output name must be a regular file or not exist: a device node, FIFO or
  socket (``/dev/null``, a named pipe) is refused (exit 2) rather than
  replaced by a regular file or written through;
* a read-only file (no write permission bit, or not writable by this user)
  is never replaced or appended to, not even with ``--force``: the mode is
  the user's own mark that the file is to be kept (docs/errors.md);
* a journal (a JSON-lines file the work appends to as it goes, so an
  interrupted run can resume) is never written through a symbolic link, is
  repaired when its last line was torn by the interruption, and is refused
  with one line naming ``--resume`` when it holds anything else.
"""

from __future__ import annotations

import json
import os
import stat
import tempfile
from pathlib import Path
from typing import Any, Callable

from .errors import InputError
from .interrupts import Terminated, is_terminated, raise_if_stop_requested  # noqa: F401 (re-exported)


# ---------------------------------------------------------------------------
# output paths


PLOT_SUFFIXES = frozenset({".png", ".pdf", ".svg", ".svgz", ".eps", ".ps", ".pgf", ".jpg", ".jpeg", ".tif", ".tiff",
                           ".webp", ".gif"})
"""File name endings matplotlib can draw to (``--plot`` names are checked before any work)."""


def _same_file(a: Path, b: Path) -> bool:
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
        return a.resolve() == b.resolve()
    except OSError:  # pragma: no cover - unreadable path components
        return False


def _check_distinct(p: Path, protected: list, option: str) -> None:
    for k, q in enumerate(protected):
        if q is None:
            continue
        if _same_file(p, Path(q)):
            if k == 0:
                raise InputError(option, f"refusing to write over the input file {q}")
            raise InputError(option, f"refusing to write over {q}, which another option of this command also names")


def _check_directory(p: Path, option: str) -> None:
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(option, f"directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(option, f"directory {parent} is not writable")


def _check_regular(p: Path, option: str) -> None:
    """Refuse an existing name that is not a regular file (after symlinks)."""
    try:
        st = os.stat(p)
    except OSError:
        return  # absent (or a dangling link, which the rename replaces)
    if stat.S_ISDIR(st.st_mode):
        raise InputError(option, f"{p} is a directory")
    if not stat.S_ISREG(st.st_mode):
        kind = ("a FIFO" if stat.S_ISFIFO(st.st_mode) else "a socket" if stat.S_ISSOCK(st.st_mode)
                else "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else "not a regular file")
        raise InputError(option, f"{p} is {kind}; outputs are written only to regular files")


def _check_writable(p: Path, option: str) -> None:
    """Refuse an existing file that is read-only: no write permission bit at
    all (``chmod a-w``; looked at directly because root's ``os.access``
    says yes to anything) or not writable by this user."""
    try:
        st = os.stat(p)
    except OSError:
        return  # absent: nothing to protect
    if stat.S_ISREG(st.st_mode) and (not st.st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH)
                                     or not os.access(p, os.W_OK)):
        raise InputError(option, f"{p} is read-only; it is never replaced, even with --force: make it writable "
                                 "(chmod u+w) or choose another name")


def check_output_path(path: str | None, force: bool, protected: list[str | None], option: str) -> Path | None:
    """Validate an output path before any work is done (exit 2 on problems).

    ``protected``: paths this command reads or writes through other options
    (by convention the input config first); the output may be none of them,
    whether or not they exist yet (symlinks and hard links included).  An
    existing file is only replaced with ``force``; a read-only file, a
    directory, device node, FIFO or socket never (even with ``force``).  For ``option == "--plot"``
    the name must end in an image format (:data:`PLOT_SUFFIXES`)."""
    if path is None:
        return None
    p = Path(path)
    if str(path).strip() == "":
        raise InputError(option, "must be a file name, got an empty string")
    _check_distinct(p, protected, option)
    _check_regular(p, option)
    if option == "--plot" and p.suffix.lower() not in PLOT_SUFFIXES:
        raise InputError(option, f"cannot tell the image format of {p.name!r}: end the name in .png, .pdf or .svg "
                                 f"(or {', '.join(s for s in sorted(PLOT_SUFFIXES) if s not in ('.png', '.pdf', '.svg'))})")
    _check_writable(p, option)
    if p.exists() and not force:
        raise InputError(option, f"{p} exists; choose another name or pass --force to replace it")
    _check_directory(p, option)
    return p


def check_journal_path(path: str | os.PathLike, protected: list, option: str, *, resume: bool) -> Path:
    """Validate a journal path before any work (exit 2 on problems).

    A journal is appended to in place, so besides the checks of
    :func:`check_output_path` it may not be a symbolic link (it would be
    written through), and its directory must be writable even when resuming.
    Whether an existing journal may be continued or replaced is the caller's
    rule (``--resume`` / ``--force``)."""
    p = Path(path)
    if str(path).strip() == "":
        raise InputError(option, "must be a file name, got an empty string")
    if p.is_symlink():
        raise InputError(option, f"the journal {p} is a symbolic link; a journal is never written through a link: "
                                 "remove it or choose another name")
    _check_distinct(p, protected, option)
    _check_regular(p, option)
    _check_writable(p, option)  # resumed (appended to) or started over (truncated): written either way
    _check_directory(p, option)
    if resume and p.exists() and not os.access(p, os.R_OK | os.W_OK):
        raise InputError(option, f"the journal {p} is not readable and writable")
    return p


# ---------------------------------------------------------------------------
# atomic files


def atomic_write(path: Path, write: Callable[[str], None]) -> None:
    """Call ``write(tmp_path)`` then rename the temporary file onto ``path``.

    The temporary file sits in the same directory (so the rename is atomic),
    is flushed to disk before the rename, and is removed if ``write`` fails
    or the run is interrupted: ``path`` is either untouched or complete.
    The new file gets the mode of the file it replaces, else the umask's.
    A ``path`` that exists and is not a regular file (a device, FIFO) or is
    read-only is refused with :class:`~bifilar.errors.InputError` (the CLI
    checked both before any work; this holds for the library's callers and
    for a file made read-only during the run)."""
    path = Path(path)
    _check_regular(path, str(path))
    _check_writable(path, str(path))
    directory = str(path.parent) if str(path.parent) else "."
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=directory)
    os.close(fd)
    try:
        write(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, _target_mode(path))
        raise_if_stop_requested()  # a Ctrl-C a finaliser swallowed must not let the file land
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _target_mode(path: Path) -> int:
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def write_yaml(path, doc: dict, comments: list[str]) -> None:
    """Write ``doc`` (a config or measurements file) as YAML, atomically, after
    ``#`` comment lines (``comments``, one line each)."""
    import yaml

    from .jsonable import to_jsonable

    text = "".join(f"# {c}\n" for c in comments) + yaml.safe_dump(to_jsonable(doc), sort_keys=False,
                                                                   default_flow_style=None, width=110)

    def w(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)

    atomic_write(path, w)


def write_csv(path: Path, header: list[str], rows) -> None:
    """A numeric table (header row, then rows of floats, 12 significant
    digits), written atomically."""
    import numpy as np

    def w(tmp: str) -> None:
        np.savetxt(tmp, np.asarray(rows, float), delimiter=",", header=",".join(header), comments="", fmt="%.12g")

    atomic_write(path, w)


def write_table_csv(path: Path, header: list[str], rows) -> None:
    """A mixed table (numbers, text, ``None`` as an empty cell; floats with
    12 significant digits), written atomically with the :mod:`csv` module."""
    import csv

    def cell(v: Any) -> str:
        if v is None:
            return ""
        if isinstance(v, float):
            return f"{v:.12g}"
        return str(v)

    def w(tmp: str) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            wr = csv.writer(fh)
            wr.writerow(header)
            for r in rows:
                wr.writerow([cell(v) for v in r])

    atomic_write(path, w)


# ---------------------------------------------------------------------------
# JSON-lines journals


class JournalError(InputError):
    """A journal that cannot be resumed (exit 2, naming ``--resume``)."""


def read_journal(path: Path, check_header: Callable[[Any], None], check_record: Callable[[Any], bool], *,
                 option: str = "--resume", repair: bool = True) -> tuple[dict, list]:
    """(header, records) of the JSON-lines journal ``path``.

    ``check_header(head)`` raises :class:`~bifilar.errors.InputError` when
    the first line is not this kind of journal (it receives any JSON value);
    ``check_record(rec)`` returns False for a line that is not a record of it.
    The last line, when it does not end in a newline, was torn by an
    interruption: it is ignored and, with ``repair``, cut off the file so the
    next record starts on a line of its own.  Any other line that is not
    valid UTF-8 JSON or not a record raises :class:`JournalError` naming
    ``option``, the file and the line number (never its content).  An empty
    journal gives ``({}, [])``.
    """
    path = Path(path)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    with os.fdopen(fd, "rb") as fh:
        data = fh.read()
    complete = data[: data.rfind(b"\n") + 1]
    if repair and len(complete) < len(data):
        _truncate(path, len(complete))
    lines = complete.split(b"\n")[:-1]
    if not lines:
        return {}, []

    def parse(k: int, raw: bytes):
        try:
            return json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            raise JournalError(option, f"{path} line {k + 1} is not JSON: the file is not a journal this command "
                                       "wrote, or it was damaged; move it away to start over") from None

    head = parse(0, lines[0])
    check_header(head)
    records = []
    for k, raw in enumerate(lines[1:], start=1):
        rec = parse(k, raw)
        if not check_record(rec):
            raise JournalError(option, f"{path} line {k + 1} is not a record of this journal; it was damaged or "
                                       "written by something else: move it away to start over")
        records.append(rec)
    return head, records


def _truncate(path: Path, size: int) -> None:
    fd = os.open(path, os.O_WRONLY | getattr(os, "O_NOFOLLOW", 0))
    try:
        os.ftruncate(fd, size)
        os.fsync(fd)
    finally:
        os.close(fd)


class JournalWriter:
    """Append JSON records, one a line, each flushed and synced to disk.

    ``header``: written as the first line when the journal is created
    (``append=False`` or no non-empty file yet); ``append=True`` continues
    an existing file (read it with :func:`read_journal` first, which repairs
    a torn last line).  The file is opened with ``O_NOFOLLOW``: a symbolic
    link is refused, never written through.  ``path=None``: a journal that
    writes nothing."""

    def __init__(self, path: Path | None, header: dict | None, *, append: bool):
        self.fh = None
        if path is None:
            return
        path = Path(path)
        new = not (append and path.exists() and path.stat().st_size > 0)
        flags = os.O_WRONLY | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | (os.O_TRUNC if new else os.O_APPEND)
        try:
            fd = os.open(path, flags, 0o666)
        except OSError:
            if path.is_symlink():
                raise InputError(str(path), "a journal is never written through a symbolic link") from None
            raise
        self.fh = os.fdopen(fd, "w", encoding="utf-8")
        if new and header is not None:
            self.add(header)

    def add(self, rec: Any) -> None:
        if self.fh is None:
            return
        self.fh.write(json.dumps(rec) + "\n")
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self) -> None:
        if self.fh is not None:
            self.fh.close()
            self.fh = None
