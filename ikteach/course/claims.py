"""One-line verdicts for the claims a lecture notebook makes: `claim(text, ok, **numbers)`
prints ``claim: TEXT (k=v, ...): True/False`` with each number rounded to 3 significant
digits, so nbval compares the line on any BLAS kernel, and returns ok."""
import math


def _fmt(v):
    if isinstance(v, bool) or isinstance(v, str):
        return str(v)
    if isinstance(v, int):
        return str(v)
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    if not math.isfinite(f):
        return str(f)  # inf, -inf, nan (int() of them raises)
    if f == int(f) and abs(f) < 1e15:
        return str(int(f))
    out = f"{f:.3g}"
    return "0" if out in ("-0", "0") else out


def claim(text, ok, **numbers):
    """Print the claim `text`, its `numbers` (3 significant digits) and whether it holds."""
    if not isinstance(text, str) or not text:
        raise ValueError(f"text: expected the claim as a non-empty string, got {text!r:.40}")
    ok = bool(ok)
    nums = ", ".join(f"{k}={_fmt(v)}" for k, v in numbers.items())
    print(f"claim: {text} ({nums}): {ok}" if nums else f"claim: {text}: {ok}")
    return ok
