"""The shared verdict machinery of ik.check: run student code safely, build cases, compare,
score by parts (_Part, _evaluate: how an exercise module uses them is in check/__init__.py),
and word the one verdict a student sees."""
import collections
import contextvars
import dataclasses
import functools
import os
import sys
import time
import traceback
import warnings

import numpy as np

from ...core.solve import StopSolve
from ..grading.time_limit import TimeLimit, time_limit

POINTS = 10
TIME_LIMIT = 5.0    # CPU seconds for one call of a student function
SOLVE_LIMIT = 30.0  # CPU seconds for a whole ik.solve run with a student step function
BUSY = 30           # wall seconds per CPU second of a limit before a call counts as held up
# the student's CPU seconds so far: this process's in a kernel (the grader sets its job's)
CPU_CLOCK = contextvars.ContextVar("CPU_CLOCK", default=time.process_time)
SEED = 2024
_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # ikteach/


# --- running student code safely -------------------------------------------------------------

class _NotYet(Exception):
    """The student's function still raises NotImplementedError."""


class _Fail(Exception):
    """A student function could not be run on a case; the message says why."""


class _Abort(_Fail):
    """Stop the whole check (endless loop: trying more cases would only cost time)."""


def _student_line(exc):
    """' (line N: code)' of the innermost frame in the student's own code, if any (an error
    raised in the grader's sandboxed worker carries it as `student_line`)."""
    if isinstance(getattr(exc, "student_line", None), str):
        return exc.student_line
    library = (_PACKAGE_DIR, sys.prefix, sys.base_prefix, os.path.dirname(os.__file__))
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        if not frame.filename.startswith(library) and not frame.filename.startswith("<frozen"):
            code = f": {frame.line.strip()}" if frame.line else ""
            return f" (line {frame.lineno}{code})"
    return ""


def _call(fn, name, case, *args, limit=None):
    """fn(*args) under a time limit (None: TIME_LIMIT, read at the call); student errors
    become _NotYet/_Fail/_Abort."""
    limit = TIME_LIMIT if limit is None else limit
    if not callable(fn):
        raise _Fail(f"expected your function `{name}`, got {type(fn).__name__} {fn!r:.40}")
    try:
        with time_limit(limit, BUSY, CPU_CLOCK.get()), np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # NaN is reported by the check
            return fn(*args)
    except TimeLimit as stop:
        used, waited = stop.args
        if used >= limit:
            raise _Abort(f"`{name}` did not return within {limit:g} s of CPU time on {case} - "
                         "an endless loop?") from None
        raise _Abort(f"`{name}` did not return within {waited:.0f} s on {case} but had only "
                     f"{used:.1f} s of CPU time: this machine is busy (or your code waits)"
                     ) from None
    except NotImplementedError:
        raise _NotYet(name) from None
    except StopSolve:
        raise
    except Exception as exc:  # the student's own error, reported without our traceback
        message = str(exc).splitlines()[0] if str(exc) else ""
        raise _Fail(f"`{name}` raised {type(exc).__name__}"
                    f"{': ' + message if message else ''}{_student_line(exc)} on {case}") from None


def _as_array(value, name, case):
    """The student's return value as a float64 array, or a _Fail saying what came back. The
    dtype policy (the same in the check cell and the grader): float64 answers only, since the
    checks compare to 1e-6 of a case's scale and float32 rounding (1e-7, more after an SVD
    near a singularity) would make a mark depend on the case drawn."""
    if value is None:
        raise _Fail(f"`{name}` returned None on {case} - did you forget `return`?")
    try:
        raw = np.asarray(value)
        arr = np.array(raw, dtype=np.float64)
    except (TypeError, ValueError):
        raise _Fail(f"`{name}` returned {type(value).__name__} {value!r:.60} on {case}; "
                    f"expected an array of numbers") from None
    if raw.dtype.kind == "f" and raw.dtype.itemsize < 8:
        raise _Fail(f"`{name}` returns {raw.dtype}; return float64 (the checks work to 1e-6 "
                    f"of the answer's size, which {raw.dtype} rounding does not always meet) "
                    f"on {case}")
    return arr


def _answers(fn, name):
    """answer(case): fn on copies of the case's arguments, as a float64 array (_as_array),
    computed once per case (several parts ask for it)."""
    cache = {}

    def answer(case):
        if id(case) not in cache:
            args = [a.copy() if hasattr(a, "copy") else a for a in case.args]
            cache[id(case)] = _as_array(_call(fn, name, case, *args), name, case)
        return cache[id(case)]
    return answer


# --- cases and comparisons -------------------------------------------------------------------

def _fmt(x, digits=4):
    arr = np.asarray(x, dtype=float) + 0.0  # -0.0 printed as 0.
    if arr.ndim == 0:
        return f"{float(arr):.{digits}g}"
    small = 0 < np.abs(arr).max(initial=0.0) < 1e-3  # a small J in e-notation, not as zeros
    with np.printoptions(precision=digits, suppress=not small, floatmode="maxprec",
                         linewidth=200):
        return np.array2string(arr, separator=", ").replace("\n", "")


@dataclasses.dataclass
class _Case:
    args: tuple
    text: str       # how the case is shown to the student
    size: int = 0   # smaller cases are reported first
    tag: str = ""   # which part of the check uses it
    memo: dict = dataclasses.field(default_factory=dict, repr=False)

    def __str__(self):
        return self.text

    def want(self, reference):
        """reference(*args) as a float array, computed once (a draw's cases are kept)."""
        if "want" not in self.memo:
            self.memo["want"] = np.asarray(reference(*self.args), dtype=float)
        return self.memo["want"]


def _close(a, b, rtol=1e-6, atol=1e-9, scale=None):
    """a equals b up to rtol of the case's scale (by default b's largest entry), not of each
    entry: an answer rounded to float32 (6e-8 of its size) passes on every draw, a small
    entry left by cancellation included."""
    if a.shape != b.shape or not np.all(np.isfinite(a)):
        return False
    size = float(np.max(np.abs(b), initial=0.0)) if scale is None else float(scale)
    return bool(np.all(np.abs(a - b) <= atol + rtol * size))


def _mismatch(got, want, case, what="the step"):
    label, yours = f"expected {what}:", "your result:" if what == "the step" else f"your {what}:"
    width = max(len(label), len(yours))
    gap = (np.max(np.abs(got - want), initial=0.0) / max(np.max(np.abs(want)), 1e-300)
           if np.shape(got) == np.shape(want) and np.size(want) else np.inf)
    hint = (f"\n  they agree to {-np.log10(gap):.0f} digits only: is something computed in "
            "float32?" if 1e-8 < gap < 1e-3 else "")  # float64 keeps about 16
    digits = next((d for d in range(4, 17) if _fmt(got, d) != _fmt(want, d)), 17)
    got, want = _fmt(got, digits), _fmt(want, digits)  # to the digits that differ
    return (f"\n  smallest failing case: {case}\n  {label:<{width}} {want}"
            f"\n  {yours:<{width}} {got}{hint}")


def _shape_message(name, got, want, case, hint=""):
    return (f"wrong shape: `{name}` returned shape {got.shape}, expected {want.shape}"
            f"{hint}.\n  smallest failing case: {case}")


def _in_every_draw(cases):
    """cases(seed) -> the check cell's cases (seed None) in every draw, the seed's own on top:
    the hidden seed only adds cases, so what decides a part is decided alike everywhere."""
    @functools.lru_cache(maxsize=8)  # one draw serves a whole class
    def drawn(seed=None):
        own = tuple(cases(seed))
        return tuple(sorted(own if seed is None else drawn(None) + own, key=lambda c: c.size))
    return functools.wraps(cases)(drawn)


def _turned(rng, Js, es):
    """A hand case's counterpart for the seed: each J (they share columns) with rows and
    columns reordered and flipped (signed permutations), each e with its J's rows, scaled by
    a power of 2 - exactly the same singular values, ranks, zeros and ties (the same kind, as
    hard), other numbers."""
    def signed(n):
        return np.eye(n)[rng.permutation(n)] * rng.choice([-1.0, 1.0], n)
    Q, scale = signed(Js[0].shape[1]), 2.0 ** float(rng.choice([-1, 1, 2]))
    Ps = [signed(len(J)) for J in Js]
    return ([P @ J @ Q + 0.0 for P, J in zip(Ps, Js)],
            [scale * (P @ e) + 0.0 for P, e in zip(Ps, es)])


def _turned_hand(rng, hand):
    """Hand cases (J, e, anything else...) turned one by one (_turned), the rest kept."""
    return [(*(x[0] for x in _turned(rng, [J], [e])), *rest) for J, e, *rest in hand]


def _rng(seed, offset):
    """The cases' random generator: seed None gives the instant check's (SEED + offset: what a
    student sees in the notebook), an int the grader's added cases (drawn at grading time)."""
    return np.random.default_rng(SEED + offset if seed is None else [int(seed), offset])


def _random_matrix(rng, m, n):
    """A random m x n matrix with singular values in [1, 10] (well conditioned)."""
    return _with_singular_values(rng, rng.uniform(1.0, 10.0, size=min(m, n)), m, n)


def _with_singular_values(rng, sigma, m, n):
    U, _ = np.linalg.qr(rng.normal(size=(m, m)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    S = np.zeros((m, n))
    S[np.arange(len(sigma)), np.arange(len(sigma))] = sigma
    return U @ S @ V.T


def _matrix_text(J, e, extra=""):
    return f"J = {_fmt(J)}, e = {_fmt(e)}{extra}"


# --- the verdict --------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Verdict:
    """What a check found: status "passed" | "failed" | "not implemented", score of POINTS."""
    exercise: int
    name: str
    status: str
    score: float
    max_score: float
    message: str
    parts: dict

    @property
    def passed(self):
        return self.status == "passed"

    def __str__(self):
        return self.message


_Part = collections.namedtuple("_Part", "name points run")  # run() -> None or the message


def _evaluate(number, name, function_names, parts):
    """Run every part; the first failure (smallest case) becomes the message."""
    results, first_failure, not_yet = dict.fromkeys((p.name for p in parts), False), None, set()
    for part in parts:
        try:
            problem = part.run()
        except _NotYet as exc:
            not_yet.add(str(exc))
            problem = f"`{exc}` is not yet implemented (it raises NotImplementedError)."
        except _Abort as exc:  # the parts left stay failed
            first_failure = first_failure or str(exc)
            break
        except _Fail as exc:
            problem = str(exc)
        results[part.name] = problem is None
        if problem is not None and first_failure is None:
            first_failure = problem
    score = float(sum(p.points for p in parts if results[p.name]))
    total = float(sum(p.points for p in parts))
    title = f"Exercise {number} ({name})"
    if not_yet and score == 0 and not_yet >= set(function_names):
        return Verdict(number, name, "not implemented", 0.0, total,
                       f"{title}: not yet implemented - fill in "
                       f"{', '.join('`' + f + '`' for f in function_names)}, run its cell, "
                       f"then run this check again.", results)
    if first_failure is None:
        return Verdict(number, name, "passed", score, total,
                       f"{title}: passed, {score:g}/{total:g} - well done!", results)
    marks = "  ".join(f"{p.name} {'ok' if results[p.name] else 'x'}" for p in parts)
    return Verdict(number, name, "failed", score, total,
                   f"{title}: {score:g}/{total:g} - {first_failure}\n  parts: {marks}", results)
