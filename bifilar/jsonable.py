"""Plain JSON-able Python from numpy-laden results (one rule for the whole package)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def to_jsonable(x: Any) -> Any:
    """Dicts, lists, numbers and strings only: numpy arrays become lists, numpy
    scalars Python numbers, numpy booleans bools, and non-finite floats None
    (JSON has no NaN), so a value read back from a JSON file equals the value
    written."""
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
