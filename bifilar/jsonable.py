"""Plain JSON-able Python from numpy-laden results (one rule for the whole package)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

_PLAIN = frozenset((str, int, bool, type(None)))
"""Exact types :func:`to_jsonable` hands back as they are (what the general
rule gives them: ``bool(x)`` of a bool is that bool; an int, a str and None
fall through every test)."""


def to_jsonable(x: Any) -> Any:
    """Dicts, lists, numbers and strings only: numpy arrays become lists, numpy
    scalars Python numbers, numpy booleans bools, and non-finite floats None
    (JSON has no NaN), so a value read back from a JSON file equals the value
    written.

    The exact types of a sweep point's ~350 values (float, dict, list, bool,
    str, None) are dispatched on ``type(x)`` first, each to what the general
    rule below gives it (a float is ``float(x)`` already); anything else
    (numpy types, subclasses, tuples) takes the general rule
    (tests/test_runs28.py: the same output, types and bits, as that rule
    alone)."""
    t = type(x)
    if t is float:
        return x if math.isfinite(x) else None
    if t is dict:
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if t is list:
        return [to_jsonable(v) for v in x]
    if t in _PLAIN:
        return x
    return _general(x)


def _general(x: Any) -> Any:
    """:func:`to_jsonable`'s rule for any type (its containers' items back
    through :func:`to_jsonable`)."""
    if isinstance(x, dict):
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, (float, np.floating)):
        x = float(x)
        return x if math.isfinite(x) else None
    return x
