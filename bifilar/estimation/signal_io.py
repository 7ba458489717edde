"""Reading recorded signals and checking their time column.

SI units: time in s, sample rates in Hz; samples in the file's own unit
``[y]``.  Part of :mod:`bifilar.estimation.signal` (the public API imports
from there).

Memory is bounded by the number of samples: text tables are parsed by
:func:`numpy.loadtxt` (or, when that fails on missing cells, streamed line by
line into two float arrays), never held as a list of lines; the time column
is checked (strictly increasing, no gap longer than ``MAX_GAP_FRACTION`` of
the record, samples covering at least ``MIN_COVERAGE`` of the span, a
uniform grid at the median step at most ``MAX_GRID_FACTOR`` times the
samples) before anything is resampled on a uniform grid, so nothing is ever
allocated in proportion to the time span.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from bifilar.errors import InputError

#: fewer samples than this cannot define a period with an uncertainty
MIN_SAMPLES = 20
#: NaN / missing samples up to this fraction are dropped with a warning
MAX_NAN_FRACTION = 0.01
#: a time step longer than this fraction of the record (and than
#: ``GAP_MIN_STEPS`` median steps) is a gap that is refused
MAX_GAP_FRACTION = 0.02
GAP_MIN_STEPS = 3.0
#: the samples must cover at least this fraction of the span: the span less
#: the steps longer than ``GAP_MEAN_STEPS`` mean steps (gaps; random
#: sampling intervals, e.g. exponential ones, are not gaps: an exponential
#: step exceeds 10 means with probability 5e-5)
MIN_COVERAGE = 0.75
GAP_MEAN_STEPS = 10.0
#: the uniform grid at the median step may hold at most this many times the
#: samples (exponential intervals need 1.44x; bursts of near-coincident
#: samples would need arbitrarily many)
MAX_GRID_FACTOR = 4.0

#: names of a time column: t or time, also in other languages a spreadsheet
#: may use (de Zeit, nl/da tijd/tid, fr temps, es tiempo, it/pt tempo), with an
#: optional unit, s or ms ("time_s", "Zeit [ms]", "t (sec)")
_TIME_RE = re.compile(
    r"^(t|time|zeit|tijd|tid|temps|tiempo|tempo)"
    r"(?:[\s_]*[\(\[]\s*(s|sec|seconds|ms|msec|milliseconds)\s*[\)\]]|[\s_]+(s|sec|seconds|ms|msec|milliseconds))?$"
)
_MS_UNITS = {"ms", "msec", "milliseconds"}
_RATE_NAMES = {
    "actualrate", "samplerate", "sample_rate", "samplingrate", "sampling_rate",
    "fs", "srate", "rate", "samplefrequency", "sample_frequency", "fsample",
}
_MISSING = {"", "nan", "na", "n/a", "null", "none", "-nan"}


class SignalError(InputError):
    """A recorded signal cannot be read or analysed.

    ``str(err)`` is ``"field: message"``; ``field`` names the offending
    input: ``"path"`` (the file), ``"--column"``, ``"--sample-rate"``,
    ``"time"`` (the time vector) or ``"signal"`` (the samples themselves).
    """

    def __init__(self, field: str, message: str):
        super().__init__(field, message)


# ---------------------------------------------------------------------------
# readers
# ---------------------------------------------------------------------------

def _is_time_name(name: str) -> bool:
    return bool(_TIME_RE.match(str(name).strip().lower()))


def _time_scale(name: str) -> float:
    """Seconds per unit of a time column named ``name`` (1e-3 when its name
    gives ms, else 1: a time column is in seconds unless its name says ms)."""
    m = _TIME_RE.match(str(name).strip().lower())
    unit = (m.group(2) or m.group(3)) if m else None
    return 1e-3 if unit in _MS_UNITS else 1.0


def _time_column(name: str, values: np.ndarray, kind: str) -> tuple[np.ndarray, str]:
    """(t in s, time_source) from a time column or variable named ``name``."""
    scale = _time_scale(name)
    src = f"{kind} {name!r}" + (" (ms, converted to s)" if scale != 1.0 else "")
    return values * scale if scale != 1.0 else values, src


def _check_rate(sample_rate) -> float | None:
    if sample_rate is None:
        return None
    try:
        fs = float(sample_rate)
    except (TypeError, ValueError):
        raise SignalError("--sample-rate", f"not a number: {sample_rate!r}") from None
    if not math.isfinite(fs) or fs <= 0:
        raise SignalError("--sample-rate", f"must be a positive number of Hz, got {sample_rate!r}")
    return fs


def read_signal(path, column: str | None = None, sample_rate: float | None = None):
    """Read one recorded signal.

    Parameters
    ----------
    path : str or Path
        A text table (``.csv``, ``.tsv``, ``.txt``, ...; comma, tab,
        semicolon or whitespace separated, one header row, ``#`` comments
        skipped) or a MATLAB ``.mat`` file (v5/v7, read by
        :func:`scipy.io.loadmat`).
    column : str, optional
        Text: the signal column (default: the first column that is not the
        time column).  MAT: the variable (default: the first numeric 1-D
        array that is not time-like).
    sample_rate : float, optional
        Sample rate in Hz.  When given, ``t = arange(n) / sample_rate`` and a
        time column, if any, is ignored.  Otherwise text files need a time
        column named ``t`` or ``time`` (case-insensitive, seconds; ``time_s``
        and ``time (s)`` also accepted; ``time [ms]``, ``t_ms`` are read as ms
        and converted; ``Zeit``, ``tijd``, ``tid``, ``temps``, ``tiempo``,
        ``tempo`` as well) and MAT files a scalar variable named
        like ``ActualRate``, ``SampleRate`` or ``fs`` (Hz) or a time vector.

    Returns
    -------
    t : ndarray
        Sample times in s, strictly increasing.
    y : ndarray
        Samples, in the unit of the file.
    meta : dict
        ``path``, ``format``, ``column``, ``columns`` (all available),
        ``time_source``, ``sample_rate`` (Hz, nominal or median),
        ``sample_rate_source``, ``n_samples``, ``n_dropped``, ``duration``
        (s), ``warnings`` (list of str) and, for MAT files, ``fields``
        (the scalar and string variables, e.g. the trial description).

    Raises
    ------
    SignalError
        Missing or unreadable file (``path``), unknown column (``--column``,
        listing the available ones), no way to know the time
        (``--sample-rate``), non-numeric data, more than 1 % NaN or fewer than
        ``MIN_SAMPLES`` samples (``signal``), non-increasing time (``time``).
    """
    fs = _check_rate(sample_rate)
    p = Path(path)
    if not p.exists():
        raise SignalError("path", f"no such file: {p}")
    if p.is_dir():
        raise SignalError("path", f"is a directory, not a recording: {p}")
    if not p.is_file():
        raise SignalError("path", f"not a file: {p}")
    if p.suffix.lower() == ".mat":
        t, y, meta = _read_mat(p, column, fs)
    else:
        t, y, meta = _read_text(p, column, fs)
    return _finish(t, y, meta)


def _sniff_delimiter(line: str) -> str | None:
    if "," in line and ";" in line and "\t" not in line:
        # a ';' table whose commas are decimal commas (a European spreadsheet's row)
        cells = [c.strip().strip('"') for c in line.split(";")]
        if all(_COMMA_NUMBER.match(c) or "," not in c for c in cells):
            return ";"
    for d in ("\t", ",", ";"):
        if d in line:
            return d
    return None  # whitespace


def _is_number(s: str) -> bool:
    try:
        float(s)
        return True
    except ValueError:
        return s.strip().lower() in _MISSING - {""}


def _encoding(p: Path) -> str:
    """The text encoding of a table: UTF-16 where the file starts with its
    byte-order mark (a Windows "Unicode text" export), or without it where
    one byte of each pair is NUL and the other is not (ASCII text as
    UTF-16-LE/BE: the NULs are valid UTF-8, so it would decode and be refused
    as "not a header"), else UTF-8 (a UTF-8 BOM skipped)."""
    with open(p, "rb") as fh:
        head = fh.read(4096)
    if head[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return "utf-16"
    odd, even = head[1::2], head[0::2]
    if len(head) >= 8:
        if odd.count(0) > 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
            return "utf-16-le"
        if even.count(0) > 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
            return "utf-16-be"
    return "utf-8-sig"


def _header(p: Path):
    """First non-comment, non-blank line of a text table: (its 0-based line
    index, its text, the delimiter).  Reads only up to that line."""
    try:
        with open(p, encoding=_encoding(p)) as fh:
            for i, ln in enumerate(fh):
                if ln.strip() and not ln.lstrip().startswith("#"):
                    return i, ln.rstrip("\r\n"), _sniff_delimiter(ln)
    except UnicodeDecodeError:
        with open(p, "rb") as fh:
            head = fh.read(4096)
        if head[1::2].count(0) > 0.4 * len(head[1::2]) or head[0::2].count(0) > 0.4 * len(head[0::2]):
            raise SignalError("path", f"{p.name} looks like UTF-16 text without its byte-order mark; save it as "
                                      "UTF-8 (or UTF-16 with a BOM)") from None
        raise SignalError("path", f"{p.name} is not a text table in UTF-8 or UTF-16 (and not a .mat file)") from None
    raise SignalError("signal", f"{p.name} is empty")


def _has_interior_blank_line(p: Path, chunk: int = 1 << 22) -> bool:
    """True if a blank line lies between data rows (read in chunks: memory
    does not grow with the file)."""
    if _encoding(p).startswith("utf-16"):
        return True  # not scanned: the line-by-line parser reads it (blank lines its way)
    pat = re.compile(rb"\n[ \t\r]*\n(?=[ \t\r]*[^\s#])")
    tail = b""
    with open(p, "rb") as fh:
        while True:
            block = fh.read(chunk)
            if not block:
                return False
            buf = tail + block
            if pat.search(buf):
                return True
            tail = buf[-256:]


def _stream_columns(p: Path, start: int, split, cols: list[int], names: list[str], found: str = ""):
    """Parse the data rows (from 0-based line ``start``) of columns ``cols``
    one line at a time into float arrays; missing cells and blank lines
    between rows are NaN (so times derived from a sample rate stay right),
    trailing blank lines are ignored, anything else non-numeric is an error
    naming the line."""
    from array import array

    out = [array("d") for _ in cols]
    pending_blank = 0
    nan = float("nan")
    with open(p, encoding=_encoding(p)) as fh:
        for i, ln in enumerate(fh):
            if i < start or ln.lstrip().startswith("#"):
                continue
            if not ln.strip():
                pending_blank += 1
                continue
            if pending_blank:
                for a in out:
                    a.extend([nan] * pending_blank)
                pending_blank = 0
            row = split(ln.rstrip("\r\n"))
            for a, c, name in zip(out, cols, names):
                cell = row[c] if c < len(row) else ""
                try:
                    a.append(float(cell))
                except ValueError:
                    if cell.strip().lower() in _MISSING:
                        a.append(nan)
                    else:
                        raise SignalError("signal", f"non-numeric value {cell!r} in column {name!r} "
                                                    f"at line {i + 1} of {p.name}"
                                                    + (f"; {found}" if found else "")) from None
    return [np.frombuffer(a, dtype=float).copy() if len(a) else np.empty(0) for a in out]


def _comma_float(s: str) -> float:
    return float(s.replace(",", "."))


def _load_columns(p: Path, start: int, delim, cols: list[int], names: list[str], split, comma: bool = False,
                  found: str = ""):
    """Columns ``cols`` of the data rows as float arrays: :func:`numpy.loadtxt`
    (C parser, memory ~ 8 bytes per value) when the table is clean, else the
    line-by-line parser with its NaN rules and precise messages.  ``comma``:
    the numbers have a decimal comma (:func:`_decimal_comma`)."""
    if not _has_interior_blank_line(p):
        try:
            with open(p, encoding=_encoding(p)) as fh:
                a = np.loadtxt(fh, delimiter=delim, comments="#", skiprows=start, usecols=cols,
                               ndmin=2, dtype=float, quotechar='"', converters=_comma_float if comma else None)
            return [a[:, k].copy() for k in range(len(cols))]
        except (ValueError, IndexError):
            pass
    if comma:
        return _stream_columns(p, start, lambda ln: [c.replace(",", ".") for c in split(ln)], cols, names, found)
    return _stream_columns(p, start, split, cols, names, found)


#: a column name: letters, digits and a few signs, at most 64 characters
_NAME_CHARS = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-. ()[]/%+*^#'|°µ")


def _plausible_header(names: list[str]) -> bool:
    """Whether a first row reads as column names: at most 1000 of them, each
    1-64 characters from :data:`_NAME_CHARS`, at least one starting with a
    letter (a line of some other text file fails, so it is never quoted)."""
    if not 1 <= len(names) <= 1000:
        return False
    if not all(0 < len(n) <= 64 and set(n) <= _NAME_CHARS for n in names):
        return False
    return any(n[:1].isalpha() for n in names)


_COMMA_NUMBER = re.compile(r"^[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?$")
_POINT_NUMBER = re.compile(r"^[+-]?(\d+\.\d*|\.\d+)([eE][+-]?\d+)?$")
#: data rows looked at to tell a decimal comma from a decimal point
SNIFF_ROWS = 50


def _first_rows(p: Path, start: int, n: int = SNIFF_ROWS) -> list[str]:
    """Up to ``n`` data lines from 0-based line ``start`` (comments and blank
    lines skipped; reads only those lines)."""
    out: list[str] = []
    with open(p, encoding=_encoding(p)) as fh:
        for i, ln in enumerate(fh):
            if i < start or not ln.strip() or ln.lstrip().startswith("#"):
                continue
            out.append(ln.rstrip("\r\n"))
            if len(out) >= n:
                break
    return out


def _units_row(p: Path, start: int, split):
    """``(line index, cells)`` of a row of units right under the header (every
    cell text, no number, each at most 16 characters: ``s,rad``, ``[s],[deg]``)
    with a number row after it; else None."""
    rows: list[tuple[int, str]] = []
    with open(p, encoding=_encoding(p)) as fh:
        for i, ln in enumerate(fh):
            if i < start or not ln.strip() or ln.lstrip().startswith("#"):
                continue
            rows.append((i, ln.rstrip("\r\n")))
            if len(rows) == 2:
                break
    if len(rows) < 2:
        return None
    cells, nxt = split(rows[0][1]), split(rows[1][1])
    if not cells or any(not c or len(c) > 16 or _is_number(c) or _COMMA_NUMBER.match(c) for c in cells):
        return None
    if not any(_is_number(c) or _COMMA_NUMBER.match(c) for c in nxt):
        return None
    return rows[0][0], cells


def _decimal_comma(p: Path, rows: list[list[str]], delim, n_fields: int) -> bool:
    """Whether the cells of a text table's first data ``rows`` write numbers
    with a decimal comma (``1,234`` = 1.234, as European spreadsheets do with
    a ``;`` or tab separator).  Only when it is unambiguous: the separator
    is not a comma, and the cells hold comma numbers but no point numbers.
    Refused (``SignalError`` on ``signal``, one line naming the file): a
    comma-separated table whose rows have more fields than its header (decimal
    commas that split the numbers), cells mixing both marks (``1.234,5``:
    thousands separators) or commas in some cells and points in others."""
    cells = [c for r in rows for c in r if c]
    commas = [c for c in cells if _COMMA_NUMBER.match(c)]
    if delim == ",":
        widths = {len(r) for r in rows}
        if rows and min(widths) > n_fields:
            raise SignalError("signal", f"{p.name}: the rows have {min(widths)} or more comma-separated fields but "
                                        f"the header {n_fields}: decimal commas in a comma-separated table cannot "
                                        "be told apart from separators; export it with ';' as the separator or "
                                        "with decimal points")
        return False
    if not commas:
        return False
    both = [c for c in cells if "," in c and "." in c]
    if both:
        raise SignalError("signal", f"{p.name}: the number {both[0]!r} has both a comma and a point (a "
                                    "thousands separator?): the decimal mark is ambiguous; export the numbers "
                                    "without thousands separators")
    points = [c for c in cells if _POINT_NUMBER.match(c)]
    if points:
        raise SignalError("signal", f"{p.name}: some numbers have a decimal comma ({commas[0]!r}) and others a "
                                    f"decimal point ({points[0]!r}): the decimal mark is ambiguous; export the "
                                    "table with one decimal mark")
    return True


def _read_text(p: Path, column, fs):
    hline, first, delim = _header(p)

    def split(s: str) -> list[str]:
        cells = s.split(delim) if delim else s.split()
        cells = [c.strip().strip('"').strip("'").strip() for c in cells]
        while len(cells) > 1 and not cells[-1]:  # a trailing separator ('t,y,'): an empty last column
            cells.pop()
        return cells

    warnings_: list[str] = []
    header = split(first)
    numeric_header = all(_is_number(c) or _COMMA_NUMBER.match(c) for c in header)
    units = None if numeric_header else _units_row(p, hline + 1, split)
    if units is not None:  # a row of units under the header ('s,rad'): skipped, its time unit read
        hline, units = units
        warnings_.append(f"row {hline + 1} ({', '.join(units)}) read as the columns' units and skipped")
    sample = [split(r) for r in _first_rows(p, hline if numeric_header else hline + 1)]
    comma = _decimal_comma(p, sample, delim, len(header))
    if comma:
        header = [c.replace(",", ".") for c in header] if numeric_header else header
    if all(_is_number(c) for c in header):
        names = [f"col{i + 1}" for i in range(len(header))]
        start = hline
        warnings_.append(f"no header row; columns named {', '.join(names)}")
    else:
        names = header
        start = hline + 1
        if not _plausible_header(names):
            # not a recording (a password file, a log, prose): name the file and
            # the problem, never quote its content
            raise SignalError("signal", f"{p.name} is not a recording: its first row is not a header of column "
                                        "names (expected e.g. 't,x' with numbers below, or a .mat file)")
    time_idx = next((i for i, n in enumerate(names) if _is_time_name(n)), None)

    def numeric(i: int):
        """What column ``i`` holds in the first rows: numbers (True, also
        with a stray bad cell, which the reader then names with its line),
        only text (its first cell: a label or note column) or only missing
        cells (None)."""
        vals = [r[i] for r in sample if i < len(r) and r[i].strip().lower() not in _MISSING]
        if not vals:
            return None
        if any(_is_number(v.replace(",", ".") if comma else v) for v in vals):
            return True
        return vals[0]

    found = f"columns found: {', '.join(names)}"
    if column is None:
        cand = [i for i in range(len(names)) if i != time_idx]
        if not cand:
            raise SignalError("--column", f"{p.name} has only a time column ({names[time_idx]!r}); {found}")
        usable = [i for i in cand if numeric(i) in (True, None)]  # text columns (labels, notes) are skipped
        if not usable:
            raise SignalError("signal", f"{p.name} has no numeric column besides the time column (in its first "
                                        f"rows); {found}")
        col_idx = usable[0]
        if col_idx != cand[0]:
            skipped = ", ".join(repr(names[i]) for i in cand if i < col_idx)
            warnings_.append(f"column(s) {skipped} skipped: text in their first rows; using "
                             f"{names[col_idx]!r} (choose with --column)")
    else:
        col = str(column)
        col_idx = next((i for i, n in enumerate(names) if n == col), None)
        if col_idx is None:
            col_idx = next((i for i, n in enumerate(names) if n.lower() == col.lower()), None)
        if col_idx is None:
            raise SignalError("--column", f"no column {col!r} in {p.name}; available: {', '.join(names)}")
        if col_idx == time_idx and fs is None:
            raise SignalError("--column", f"{col!r} is the time column of {p.name}; "
                                          f"choose one of {', '.join(n for n in names if n != col)}")
        kind = numeric(col_idx)
        if isinstance(kind, str):
            nums = [names[i] for i in range(len(names)) if numeric(i) is True]
            raise SignalError("--column", f"column {names[col_idx]!r} of {p.name} is not numeric ({kind!r}); "
                                          f"numeric columns: {', '.join(nums) or 'none'} ({found})")
    time_name = names[time_idx] if time_idx is not None else None
    if units is not None and time_idx is not None and time_idx < len(units) and fs is None:
        u = units[time_idx].strip("[]() ").lower()
        if u not in ("s", "sec", "seconds", "ms", "msec", "milliseconds"):
            raise SignalError("time", f"the units row of {p.name} gives the time column {time_name!r} in "
                                      f"{units[time_idx]!r}: only s or ms are read; convert it to s")
        if u in _MS_UNITS and _time_scale(time_name) == 1.0:
            time_name = f"{time_name} [ms]"  # read as ms, converted
    if fs is None and time_idx is None:
        raise SignalError(
            "--sample-rate",
            f"{p.name} has no time column (named 't' or 'time'; columns: "
            f"{', '.join(names)}); give the sample rate in Hz")
    cols = [col_idx] if fs is not None else [col_idx, time_idx]
    arrays = _load_columns(p, start, delim, cols, [names[c] for c in cols], split, comma, found)
    y = arrays[0]
    meta: dict[str, Any] = {
        "path": str(p), "format": "text", "delimiter": delim or "whitespace",
        "decimal": "comma" if comma else "point",
        "column": names[col_idx], "columns": list(names), "warnings": warnings_,
    }
    if fs is not None:
        t = np.arange(len(y)) / fs
        meta.update(time_source="sample_rate", sample_rate=fs, sample_rate_source="argument")
        if time_idx is not None:
            warnings_.append(f"time column {names[time_idx]!r} ignored: sample_rate given")
    else:
        t, src = _time_column(time_name, arrays[1], "column")
        meta.update(time_source=src, sample_rate=None,
                    sample_rate_source=f"median step of column {names[time_idx]!r}")
    return t, y, meta


def _as_1d_numeric(v) -> np.ndarray | None:
    if isinstance(v, np.ndarray) and v.dtype.kind in "iuf" and v.size >= 2:
        s = np.squeeze(v)
        if s.ndim == 1:
            return s.astype(float)
    return None


def _read_mat(p: Path, column, fs):
    from scipy.io import loadmat

    try:
        m = loadmat(str(p))
    except NotImplementedError:
        raise SignalError("path", f"{p.name} is a MATLAB v7.3 (HDF5) file; save it with -v7") from None
    except Exception as exc:  # scipy raises several types for corrupt files
        raise SignalError("path", f"cannot read {p.name} as a MAT file ({exc})") from None
    vars_ = {k: v for k, v in m.items() if not k.startswith("__")}
    numeric = [k for k, v in vars_.items() if _as_1d_numeric(v) is not None]
    warnings_: list[str] = []
    fields: dict[str, Any] = {}
    for k, v in vars_.items():
        if isinstance(v, np.ndarray):
            if v.dtype.kind in "iuf" and v.size == 1:
                fields[k] = v.item()
            elif v.dtype.kind == "U" and v.size <= 1:
                fields[k] = str(v.item()) if v.size else ""

    if column is None:
        cand = [k for k in numeric if not _is_time_name(k)]
        if not cand:
            raise SignalError("--column", f"no numeric 1-D variable in {p.name}; variables: {', '.join(vars_)}")
        name = cand[0]
    else:
        name = column if column in vars_ else next(
            (k for k in vars_ if k.lower() == str(column).lower()), None)
        if name is None:
            raise SignalError("--column", f"no variable {column!r} in {p.name}; available: "
                                          f"{', '.join(numeric) or '(no numeric 1-D variable)'}"
                                          f" (all: {', '.join(vars_)})")
        if _as_1d_numeric(vars_[name]) is None:
            v = vars_[name]
            raise SignalError("--column", f"variable {name!r} of {p.name} is not a numeric 1-D array "
                                          f"(dtype {getattr(v, 'dtype', type(v))}, shape {getattr(v, 'shape', '?')}); "
                                          f"numeric 1-D variables: {', '.join(numeric) or 'none'}")
    y = _as_1d_numeric(vars_[name])
    if y.size < MIN_SAMPLES:  # the signal named before the time: a variable this short is not the recording
        raise SignalError("signal", f"variable {name!r} of {p.name} holds only {y.size} samples (need at least "
                                    f"{MIN_SAMPLES}): not the recording? choose it with --column (variables: "
                                    f"{', '.join(vars_)})")
    meta: dict[str, Any] = {"path": str(p), "format": "mat", "column": name,
                            "columns": list(numeric), "fields": fields, "warnings": warnings_}
    rate_var = next((k for k in vars_ if k.lower() in _RATE_NAMES and isinstance(vars_[k], np.ndarray)
                     and vars_[k].dtype.kind in "iuf" and vars_[k].size == 1), None)
    if fs is not None:
        t = np.arange(len(y)) / fs
        meta.update(time_source="sample_rate", sample_rate=fs, sample_rate_source="argument")
        if rate_var is not None and not np.isclose(float(vars_[rate_var].item()), fs):
            warnings_.append(f"sample_rate {fs:g} Hz given overrides {rate_var} = "
                             f"{float(vars_[rate_var].item()):g} Hz in the file")
        return t, y, meta
    if rate_var is not None:
        fsv = float(vars_[rate_var].item())
        if not math.isfinite(fsv) or fsv <= 0:
            raise SignalError("--sample-rate", f"{rate_var} = {fsv!r} in {p.name} is not a sample rate; give one")
        t = np.arange(len(y)) / fsv
        meta.update(time_source="sample_rate", sample_rate=fsv, sample_rate_source=f"variable {rate_var!r}")
        return t, y, meta
    tvar = next((k for k in numeric if _is_time_name(k) and _as_1d_numeric(vars_[k]).size == y.size), None)
    if tvar is not None:
        t, src = _time_column(tvar, _as_1d_numeric(vars_[tvar]), "variable")
        meta.update(time_source=src, sample_rate=None,
                    sample_rate_source=f"median step of variable {tvar!r}")
        return t, y, meta
    raise SignalError("--sample-rate", f"{p.name} has no sample-rate variable (ActualRate, SampleRate, fs) "
                                       f"and no time vector; give the sample rate in Hz")


def _finish(t: np.ndarray, y: np.ndarray, meta: dict):
    n = len(y)
    t0, y0 = t, y
    bad = ~np.isfinite(y) | ~np.isfinite(t)
    nb = int(bad.sum())
    meta["n_dropped"] = nb
    if nb:
        if nb > max(1, int(MAX_NAN_FRACTION * n)):
            raise SignalError("signal", f"{nb} of {n} samples of {meta['column']!r} are NaN or missing (or inf) "
                                        f"(more than {MAX_NAN_FRACTION:.0%}); clean the recording or choose "
                                        f"another column (columns found: {', '.join(map(str, meta['columns']))})")
        t, y = t[~bad], y[~bad]
        ninf = int(np.sum(np.isinf(y0) | np.isinf(t0)))
        what = " and ".join(w for w in ((f"{nb - ninf} NaN/missing" if nb > ninf else ""),
                                        (f"{ninf} infinite (inf)" if ninf else "")) if w)
        meta["warnings"].append(f"dropped {what} sample(s) of {n}")
    from .signal_wrap import unwrap_record
    y, wrapped = unwrap_record(y)
    if wrapped:
        meta["warnings"].append(wrapped)
    if len(y) < MIN_SAMPLES:
        raise SignalError("signal", f"only {len(y)} usable samples in {meta['column']!r}; "
                                    f"need at least {MIN_SAMPLES}")
    dt = check_time(t)
    if meta.get("sample_rate") is None:
        meta["sample_rate"] = float(1.0 / np.median(dt))
    meta["n_samples"] = int(len(y))
    meta["duration"] = float(t[-1] - t[0])
    return t, y, meta


def check_time(t) -> np.ndarray:
    """Check a time column (s) before anything is resampled; returns its steps.

    Refused (``SignalError`` on ``time``): a step that is not positive
    (time not strictly increasing); a single step longer than
    ``MAX_GAP_FRACTION`` of the record and than ``GAP_MIN_STEPS`` median
    steps (a gap the fit would have to bridge by interpolation); gaps
    (steps longer than ``GAP_MEAN_STEPS`` mean steps) leaving less than
    ``MIN_COVERAGE`` of the span covered (many gaps); a span whose uniform
    grid at the median step would hold more than ``MAX_GRID_FACTOR`` times
    the samples.  Irregular sampling is accepted: random intervals (a
    logger's jitter, exponential intervals) or a change of sample rate.
    The checks cost O(n) and allocate O(n), whatever the span.
    """
    dt = np.diff(t)
    bad = np.nonzero(~(dt > 0))[0]
    if bad.size:
        i = int(bad[0])
        raise SignalError("time", f"time is not strictly increasing at sample {i + 2} "
                                  f"(t = {t[i]:g} s then {t[i + 1]:g} s)")
    span = float(t[-1] - t[0])
    if not math.isfinite(span):
        raise SignalError("time", "the time span is not finite")
    i = int(np.argmax(dt))
    med = float(np.median(dt))
    if dt[i] > MAX_GAP_FRACTION * span and dt[i] > GAP_MIN_STEPS * med:
        raise SignalError("time", f"gap of {dt[i]:g} s between t = {t[i]:g} s and {t[i + 1]:g} s is "
                                  f"{dt[i] / span:.0%} of the record (more than {MAX_GAP_FRACTION:.0%}); "
                                  f"cut the record at the gap (--t-start/--t-stop) or fix the time column")
    long_ = dt > GAP_MEAN_STEPS * span / dt.size
    covered = 1.0 - float(np.sum(dt[long_])) / span
    if covered < MIN_COVERAGE:
        raise SignalError("time", f"the samples cover only {covered:.0%} of the {span:g} s span (less than "
                                  f"{MIN_COVERAGE:.0%}): {int(np.sum(long_))} gaps longer than "
                                  f"{GAP_MEAN_STEPS:g} mean steps; cut the record to a part without gaps "
                                  "(--t-start/--t-stop) or fix the time column")
    grid = span / med + 1
    if grid > MAX_GRID_FACTOR * t.size:
        raise SignalError("time", f"the samples are bunched: a uniform grid at their median step {med:g} s "
                                  f"would need {grid:.3g} samples over the {span:g} s span, more than "
                                  f"{MAX_GRID_FACTOR:g} x the {t.size} recorded; fix the time column or give "
                                  "--sample-rate")
    return dt


def _validate(t, y) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if t.shape != y.shape:
        raise SignalError("signal", f"t and y differ in length ({t.size} vs {y.size})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise SignalError("signal", "t and y must be finite (read_signal drops NaNs)")
    if t.size < MIN_SAMPLES:
        raise SignalError("signal", f"only {t.size} samples; need at least {MIN_SAMPLES}")
    check_time(t)
    return t, y


def _window(t, y, t_start, t_stop):
    lo = -np.inf if t_start is None else float(t_start)
    hi = np.inf if t_stop is None else float(t_stop)
    if lo >= hi:
        raise SignalError("--t-start", f"t_start = {lo:g} s is not before t_stop = {hi:g} s")
    m = (t >= lo) & (t <= hi)
    if m.sum() < MIN_SAMPLES:
        raise SignalError("--t-start" if t_start is not None else "--t-stop",
                          f"only {int(m.sum())} samples between {lo:g} s and {hi:g} s; "
                          f"need at least {MIN_SAMPLES}")
    return t[m], y[m]


