"""Input checks shared by the public functions: clear ValueErrors naming the parameter.

Numbers are real numbers: booleans, strings (even "1.5") and complex numbers are refused,
never converted. Magnitudes are bounded so that the solvers' arithmetic stays in normal
float64 (it ends near 1e308 and 1e-308): every number has |x| <= HUGE, a positive link
length is at least TINY, and a positive size given as a parameter (tol, damping, clamp,
stall_tol, ...) is 0 where allowed or at least SMALLEST. The Jacobian transpose's step size
multiplies six lengths (<JJ^T e, JJ^T e>), so an arm of size s works like one of size 1 only
while s^6 is a normal number: measured, jt / pinv / dls / ccd give the same statuses at
s = 1e-45 .. 1e45 as at s = 1 and fail beyond about 1e+-50; HUGE and TINY keep a margin.
"""
import math
import numbers

import numpy as np

HUGE = 1e40  # the largest magnitude accepted for any number (coordinates, lengths, tol, ...)
TINY = 1e-40  # the shortest positive link length accepted
SMALLEST = 1e-100  # the smallest positive size accepted (tol, damping, ...; never subnormal)


def _describe(x):
    shape = getattr(x, "shape", None)
    return f"shape {tuple(shape)}" if shape is not None else repr(x)


def numeric(x, name, what="an array of numbers"):
    """x as a float64 numpy array, refusing booleans, strings, complex and other objects."""
    if x is None or isinstance(x, (str, bytes)):
        raise ValueError(f"{name}: expected {what}, got {x!r:.80}")
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError):  # ragged lists
        raise ValueError(f"{name}: expected {what}, got {x!r:.80}") from None
    if raw.dtype.kind == "b":
        raise ValueError(f"{name}: expected {what}, got booleans {x!r:.80}")
    if raw.dtype.kind == "c":
        raise ValueError(f"{name}: expected real numbers, got complex {x!r:.80}")
    if raw.dtype.kind not in "iuf":  # strings, None, objects
        raise ValueError(f"{name}: expected {what}, got {x!r:.80}")
    return raw.astype(np.float64)


def as_array(x, name, shape=None, ndim=None):
    """x as a finite float64 numpy array (|x| <= HUGE); `shape` may use None for any length."""
    arr = numeric(x, name)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim} dimension(s), got {_describe(arr)}")
    if shape is not None:
        ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
        if not ok:
            want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + \
                ("," if len(shape) == 1 else "") + ")"
            raise ValueError(f"{name}: expected shape {want}, got {_describe(arr)}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite numbers, got NaN or inf")
    if arr.size and np.max(np.abs(arr)) > HUGE:
        raise ValueError(f"{name}: expected numbers of magnitude at most {HUGE:g}, "
                         f"got {np.max(np.abs(arr)):.3g}")
    return arr


def as_number(x, name, minimum=None, strict=False, allow_none=False):
    """x as a finite float, optionally bounded below (strictly when `strict`).

    |x| <= HUGE; a bound minimum >= 0 (a size) also asks for x = 0 or x >= SMALLEST.
    """
    if x is None and allow_none:
        return None
    if isinstance(x, (bool, np.bool_)):
        raise ValueError(f"{name}: expected a real number, got {x!r}")
    if not isinstance(x, numbers.Real):  # numpy / JAX scalars; refuses strings and complex
        x = numeric(x, name, "a real number")
        if x.ndim != 0:
            raise ValueError(f"{name}: expected a single number, got {_describe(x)}")
    value = float(x)
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value}")
    if minimum is not None and (value < minimum or (strict and value == minimum)):
        relation = ">" if strict else ">="
        raise ValueError(f"{name}: expected a number {relation} {minimum}, got {value}")
    if abs(value) > HUGE:
        raise ValueError(f"{name}: expected a number of magnitude at most {HUGE:g}, got {value:g}")
    if minimum is not None and minimum >= 0 and 0 < value < SMALLEST:
        raise ValueError(f"{name}: expected {'' if strict else '0 or '}a number >= {SMALLEST:g}, "
                         f"got {value:g}")
    return value


def as_count(x, name, minimum=1):
    """x as an int >= minimum."""
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)):
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {x!r:.80}")
    if x < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {x}")
    return int(x)


def round_finite(x, decimals):
    """x rounded to `decimals` places, for printing. np.round(x, d) multiplies by 10^d first,
    so 1e305 prints as inf; a float64 beyond 2^52 is a whole number already and is kept."""
    x = np.asarray(x, dtype=np.float64)
    small = np.abs(x) < 1e15
    return np.where(small, np.round(np.where(small, x, 0.0), decimals), x)
