"""Input checks shared by the public functions: clear ValueErrors naming the parameter."""
import math

import numpy as np


def _describe(x):
    shape = getattr(x, "shape", None)
    return f"shape {tuple(shape)}" if shape is not None else repr(x)


def as_array(x, name, shape=None, ndim=None):
    """x as a finite float64 numpy array; `shape` may use None for any length."""
    if x is None:
        raise ValueError(f"{name}: expected an array of numbers, got None")
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected an array of numbers, got {x!r:.80}") from None
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim} dimension(s), got {_describe(arr)}")
    if shape is not None:
        ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
        if not ok:
            want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name}: expected shape {want}, got {_describe(arr)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite numbers, got NaN or inf")
    return arr


def as_number(x, name, minimum=None, strict=False, allow_none=False):
    """x as a finite float, optionally bounded below (strictly when `strict`)."""
    if x is None and allow_none:
        return None
    try:
        value = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {x!r:.80}") from None
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value}")
    if minimum is not None and (value < minimum or (strict and value == minimum)):
        relation = ">" if strict else ">="
        raise ValueError(f"{name}: expected a number {relation} {minimum}, got {value}")
    return value


def as_count(x, name, minimum=1):
    """x as an int >= minimum."""
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)):
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {x!r:.80}")
    if x < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {x}")
    return int(x)
