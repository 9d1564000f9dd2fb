"""Instant feedback for the exercises: ``ik.check.<name>(student_function)`` prints one verdict.

Each check runs the student's function on hand-picked cases (singular ones included) and on
seeded random ones, compares with the module's own reference (ik.jacobian, ik.jt_step,
ik.pinv_step, ik.dls_step, ik.solve), and prints either "passed" or what is wrong, with the
smallest failing case. Whatever the student's code does (raises, returns NaN or the wrong
type, loops forever) becomes a message, never a traceback from ikteach.

Every exercise is worth POINTS, split into parts; ``verdict(name, *functions)`` returns the
score without printing (the grader uses it).
"""
import contextlib
import dataclasses
import functools
import os
import signal
import sys
import threading
import traceback
import warnings

import numpy as np

from .chain import planar_chain
from .dls import dls_step as _ref_dls
from .jacobian import jacobian as _ref_jacobian
from .jt import jt_step as _ref_jt
from .pinv import pinv_step as _ref_pinv
from .solve import StopSolve
from .solve import solve as _solve

POINTS = 10
TIME_LIMIT = 5.0    # seconds for one call of a student function
SOLVE_LIMIT = 30.0  # seconds for a whole ik.solve run with a student step function
SEED = 2024
_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))


# --- running student code safely -------------------------------------------------------------

class _TimeLimit(BaseException):
    """Raised inside student code when its time is up (BaseException: `except Exception` in
    the student's code does not swallow it)."""


class _NotYet(Exception):
    """The student's function still raises NotImplementedError."""


class _Fail(Exception):
    """A student function could not be run on a case; the message says why."""


class _Abort(_Fail):
    """Stop the whole check (endless loop: trying more cases would only cost time)."""


@contextlib.contextmanager
def _time_limit(seconds):
    """SIGALRM-based limit in the main thread (the kernel's); elsewhere no limit."""
    if (threading.current_thread() is not threading.main_thread()
            or not hasattr(signal, "setitimer")):
        yield
        return

    def _handler(signum, frame):
        raise _TimeLimit()

    previous = signal.signal(signal.SIGALRM, _handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _student_line(exc):
    """' (line N: code)' of the innermost frame in the student's own code, if any."""
    library = (_PACKAGE_DIR, sys.prefix, sys.base_prefix, os.path.dirname(os.__file__))
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        if not frame.filename.startswith(library) and not frame.filename.startswith("<frozen"):
            code = f": {frame.line.strip()}" if frame.line else ""
            return f" (line {frame.lineno}{code})"
    return ""


def _call(fn, name, case, *args, limit=None):
    """fn(*args) under a time limit; student errors become _NotYet/_Fail/_Abort."""
    limit = TIME_LIMIT if limit is None else limit
    try:
        with _time_limit(limit), np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # NaN is reported by the check
            return fn(*args)
    except _TimeLimit:
        raise _Abort(f"`{name}` did not return within {limit:g} s on {case} - an endless loop?"
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
    """The student's return value as a float array, or a _Fail saying what came back."""
    if value is None:
        raise _Fail(f"`{name}` returned None on {case} - did you forget `return`?")
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise _Fail(f"`{name}` returned {type(value).__name__} {value!r:.60} on {case}; "
                    f"expected an array of numbers") from None
    return arr


# --- cases and comparisons -------------------------------------------------------------------

def _fmt(x):
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 0:
        return f"{float(arr):.4g}"
    with np.printoptions(precision=4, suppress=True, floatmode="maxprec", linewidth=200):
        return np.array2string(arr, separator=", ").replace("\n", "")


@dataclasses.dataclass
class _Case:
    args: tuple
    text: str       # how the case is shown to the student
    size: int = 0   # smaller cases are reported first
    tag: str = ""   # which part of the check uses it

    def __str__(self):
        return self.text


def _close(a, b, rtol=1e-6, atol=1e-9):
    return a.shape == b.shape and bool(np.all(np.isfinite(a))) and np.allclose(a, b, rtol, atol)


def _mismatch(got, want, case, what="the step"):
    label = f"expected {what}:"
    width = max(len(label), len("your result:"))
    return (f"\n  smallest failing case: {case}\n  {label:<{width}} {_fmt(want)}"
            f"\n  {'your result:':<{width}} {_fmt(got)}")


def _shape_message(name, got, want, case, hint=""):
    return (f"wrong shape: `{name}` returned shape {got.shape}, expected {want.shape}"
            f"{hint}.\n  smallest failing case: {case}")


def _random_matrix(rng, m, n, cond_max=1e3):
    """A random m x n matrix with singular values in [1, 10] (well conditioned)."""
    U, _ = np.linalg.qr(rng.normal(size=(m, m)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    k = min(m, n)
    S = np.zeros((m, n))
    S[np.arange(k), np.arange(k)] = rng.uniform(1.0, 10.0, size=k)
    return U @ S @ V.T


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

    def summary(self):
        """One line, for the grader's feedback file."""
        return self.message.splitlines()[0]

    def __str__(self):
        return self.message


class _Part:
    def __init__(self, name, points, run):
        self.name, self.points, self.run = name, points, run


def _evaluate(number, name, function_names, parts):
    """Run every part; the first failure (smallest case) becomes the message."""
    results, first_failure, not_yet = {}, None, set()
    for part in parts:
        try:
            problem = part.run()
        except _NotYet as exc:
            not_yet.add(str(exc))
            problem = f"`{exc}` is not yet implemented (it raises NotImplementedError)."
        except _Abort as exc:
            results[part.name] = False
            first_failure = first_failure or str(exc)
            for rest in parts[parts.index(part) + 1:]:
                results[rest.name] = False
            break
        except _Fail as exc:
            problem = str(exc)
        results[part.name] = problem is None
        if problem is not None and first_failure is None:
            first_failure = problem
    score = float(sum(p.points for p in parts if results.get(p.name)))
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
    marks = "  ".join(f"{p.name} {'ok' if results.get(p.name) else 'x'}" for p in parts)
    return Verdict(number, name, "failed", score, total,
                   f"{title}: {score:g}/{total:g} - {first_failure}\n  parts: {marks}", results)


def _report(verdict):
    print(verdict.message)


def _check_callable(fn, name):
    if not callable(fn):
        raise _Fail(f"expected your function `{name}`, got {type(fn).__name__} {fn!r:.40}")


# --- exercise 1: the geometric Jacobian of a planar chain ---------------------------------------

def _jacobian_cases():
    rng = np.random.default_rng(SEED)
    cases = []
    hand = [([1.0], [0.0], "regular"), ([1.0, 1.0], [0.0, 0.0], "singular"),
            ([1.0, 1.0], [0.0, np.pi], "singular"), ([1.0, 2.0], [0.3, 0.5], "regular"),
            ([1.0, 1.0, 1.0], [0.0, 0.0, 0.0], "singular")]
    for lengths, theta, tag in hand:
        cases.append((lengths, theta, tag))
    for _ in range(12):
        n = int(rng.integers(1, 6))
        cases.append((rng.uniform(0.5, 1.5, n).round(3).tolist(),
                      rng.uniform(-np.pi, np.pi, n).round(3).tolist(), "regular"))
    out = []
    for k, (lengths, theta, tag) in enumerate(cases):
        text = f"lengths = {_fmt(lengths)}, theta = {_fmt(theta)}"
        out.append(_Case((lengths, theta), text, size=len(lengths) * 100 + k, tag=tag))
    return sorted(out, key=lambda c: c.size)


def _jacobian_reference(lengths, theta):
    return np.asarray(_ref_jacobian(planar_chain(lengths), np.asarray(theta, dtype=float)))


def _diagnose_jacobian(got, want, case):
    if not np.all(np.isfinite(got)):
        return f"your Jacobian contains NaN or inf.{_mismatch(got, want, case, 'J')}"
    if _close(got, -want):
        return ("wrong sign: your Jacobian is -1 x the expected one. Column i is "
                "w_i x (p_e - p_i) = z x (p_e - p_i) = (-(y_e - y_i), x_e - x_i)."
                + _mismatch(got, want, case, "J"))
    if _close(got, want[:, ::-1]):
        return ("the columns are in reverse order: column i belongs to joint i (joint 0 "
                "at the base)." + _mismatch(got, want, case, "J"))
    if _close(got, want[::-1]):
        return "rows swapped: row 0 is dx, row 1 is dy." + _mismatch(got, want, case, "J")
    return ("wrong values: column i should be z x (p_e - p_i), p_i the position of joint i "
            "(p_0 = the base), p_e the end effector." + _mismatch(got, want, case, "J"))


def _jacobian_parts(fn, name):
    cases = _jacobian_cases()
    cache = {}

    def result(case):
        if id(case) not in cache:
            lengths, theta = case.args
            cache[id(case)] = _as_array(_call(fn, name, case, list(lengths), np.array(theta)),
                                        name, case)
        return cache[id(case)]

    def shape():
        for case in cases:
            got, want = result(case), _jacobian_reference(*case.args)
            if got.shape != want.shape:
                hint = (" - one row per coordinate (x, y), one column per joint: transposed?"
                        if got.shape == want.T.shape else " - (2, number of joints)")
                return _shape_message(name, got, want, case, hint)

    def values(tag):
        def run():
            for case in (c for c in cases if c.tag == tag):
                got, want = result(case), _jacobian_reference(*case.args)
                if got.shape != want.shape:
                    return _shape_message(name, got, want, case)
                if not _close(got, want):
                    prefix = "at a singular configuration (arm straight or folded): " \
                        if tag == "singular" else ""
                    return prefix + _diagnose_jacobian(got, want, case)
        return run

    return [_Part("shape", 2, shape), _Part("values", 6, values("regular")),
            _Part("singular", 2, values("singular"))]


def jacobian_verdict(planar_jacobian):
    """Verdict for exercise 1 without printing."""
    name = "planar_jacobian"
    return _evaluate(1, "the geometric Jacobian", [name], _guarded(planar_jacobian, name,
                                                                   _jacobian_parts))


def jacobian(planar_jacobian):
    """Exercise 1: check planar_jacobian(lengths, theta) -> J (2, n), column i = z x (p_e - p_i)."""
    _report(jacobian_verdict(planar_jacobian))


def _guarded(fn, name, make_parts):
    """Parts for fn, or one failing part when fn is not a function."""
    if not callable(fn):
        def bad():
            raise _Fail(f"expected your function `{name}`, got {type(fn).__name__}")
        return [_Part("function", POINTS, bad)]
    return make_parts(fn, name)


# --- exercise 2: the Jacobian-transpose step with the optimal alpha -----------------------------

def _step_cases(shapes_seed, count=12, extra=()):
    rng = np.random.default_rng(shapes_seed)
    out = list(extra)
    for k in range(count):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 6))
        J = rng.normal(size=(m, n)).round(3)
        e = rng.normal(size=m).round(3)
        out.append(_Case((J, e), _matrix_text(J, e), size=m * n * 100 + 50 + k, tag="regular"))
    return sorted(out, key=lambda c: c.size)


def _jt_cases():
    hand = []
    for k, (J, e, tag) in enumerate([
            (np.eye(2), np.array([1.0, 0.0]), "regular"),
            (np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]), np.array([1.0, 1.0]), "regular"),
            (np.array([[1.0, 2.0], [0.5, -1.0]]), np.zeros(2), "zero"),
            (np.array([[1.0, 1.0], [0.0, 0.0]]), np.array([0.0, 1.0]), "zero"),
            (np.zeros((2, 3)), np.array([0.5, -0.5]), "zero")]):
        hand.append(_Case((J, e), _matrix_text(J, e), size=J.size * 100 + k, tag=tag))
    return _step_cases(SEED + 2, extra=hand)


def _jt_parts(fn, name):
    cases = _jt_cases()
    cache = {}

    def result(case):
        if id(case) not in cache:
            J, e = case.args
            cache[id(case)] = _as_array(_call(fn, name, case, J.copy(), e.copy()), name, case)
        return cache[id(case)]

    def coefficient(case):
        """(c, along) with got = c J^T e when `along`."""
        J, e = case.args
        got, g = result(case), J.T @ e
        if got.shape != g.shape:
            raise _Fail(_shape_message(name, got, g, case, " - one entry per joint"))
        if not np.all(np.isfinite(got)):
            raise _Fail(f"your step contains NaN or inf.{_mismatch(got, _ref(case), case)}")
        c = float(got @ g / (g @ g))
        return c, np.allclose(got, c * g, rtol=1e-6, atol=1e-9)

    def _ref(case):
        return np.asarray(_ref_jt(*case.args))

    regular = [c for c in cases if c.tag == "regular"]

    def direction():
        for case in regular:
            c, along = coefficient(case)
            if not along:
                return ("your step does not point along J^T e: the Jacobian-transpose step is "
                        "delta_theta = alpha J^T e." + _mismatch(result(case), _ref(case), case))
            if c < 0:
                return ("wrong sign: the step must go along +J^T e (downhill on 1/2 |e|^2), "
                        "with alpha > 0." + _mismatch(result(case), _ref(case), case))

    def alpha():
        found = []
        for case in regular:
            c, along = coefficient(case)
            if not along:
                return "your step is not alpha J^T e, so alpha cannot be checked yet."
            J, e = case.args
            v = J @ (J.T @ e)
            found.append((case, c, float(e @ v / (v @ v))))
        wrong = [(case, c, a) for case, c, a in found if not np.isclose(c, a, rtol=1e-6)]
        if not wrong:
            return None
        case, c, a = wrong[0]
        cs = np.array([f[1] for f in found])
        ratios = np.array([f[1] / f[2] for f in found])
        detail = (f"\n  smallest failing case: {case}\n  expected alpha: {a:.6g}"
                  f"\n  your alpha:     {c:.6g}")
        if np.allclose(cs, cs[0], rtol=1e-6):
            return (f"alpha looks fixed: it is {cs[0]:.6g} in every case. Use Buss's optimal "
                    "alpha = <e, J J^T e> / <J J^T e, J J^T e>, which changes with J and e."
                    + detail)
        if np.allclose(ratios, ratios[0], rtol=1e-6):
            return (f"alpha is off by a factor of {ratios[0]:.4g} in every case: "
                    "alpha = <e, J J^T e> / <J J^T e, J J^T e>." + detail)
        if np.allclose(cs * np.array([f[2] for f in found]), 1.0, rtol=1e-6):
            return "alpha is upside down (1/alpha): alpha = <e, v> / <v, v>, v = J J^T e." + detail
        return "wrong alpha: alpha = <e, J J^T e> / <J J^T e, J J^T e>." + detail

    def zero():
        for case in (c for c in cases if c.tag == "zero"):
            got, want = result(case), _ref(case)
            if got.shape != want.shape:
                return _shape_message(name, got, want, case, " - one entry per joint")
            if not np.all(np.isfinite(got)):
                return ("NaN where J J^T e = 0 (e = 0, or e orthogonal to every column of J): "
                        "alpha = 0/0 there. Return a zero step in that case."
                        + _mismatch(got, want, case))
            if not _close(got, want):
                return ("where J J^T e = 0 the step must be zero." + _mismatch(got, want, case))

    return [_Part("direction", 4, direction), _Part("alpha", 4, alpha), _Part("zero", 2, zero)]


def jt_step_verdict(jt_step):
    """Verdict for exercise 2 without printing."""
    return _evaluate(2, "the Jacobian-transpose step", ["jt_step"],
                     _guarded(jt_step, "jt_step", _jt_parts))


def jt_step(jt_step):
    """Exercise 2: check jt_step(J, e) -> alpha J^T e with Buss's optimal alpha."""
    _report(jt_step_verdict(jt_step))


# --- exercise 3: the pseudoinverse step through the SVD, with a cut-off -------------------------

def _pinv_cases():
    rng = np.random.default_rng(SEED + 3)
    cases = []
    for k in range(10):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 6))
        J = _random_matrix(rng, m, n).round(4)
        e = rng.normal(size=m).round(3)
        cases.append(_Case((J, e, 1e-6), _matrix_text(J, e, ", rcond = 1e-06"),
                           size=m * n * 100 + 50 + k, tag="regular"))
    singular = [
        (np.array([[0.0, 0.0], [3.0, 2.0]]), np.array([1.0, 0.5]), 1e-6),  # straight 2-link arm
        (np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([1.0, -1.0]), 1e-6),
        (_with_singular_values(rng, [1.0, 1e-9], 2, 3).round(12), np.array([0.3, 0.4]), 1e-6),
        (_with_singular_values(rng, [100.0, 1e-5], 2, 2), np.array([1.0, 1.0]), 1e-6),
        (_with_singular_values(rng, [1e-3, 1e-8], 2, 3), np.array([0.2, -0.1]), 1e-4),
    ]
    for k, (J, e, rcond) in enumerate(singular):
        s = np.linalg.svd(J, compute_uv=False)
        cases.append(_Case((J, e, rcond), _matrix_text(J, e, f", rcond = {rcond:g}")
                           + f" (singular values {_fmt(s)})", size=J.size * 100 + k,
                           tag="cutoff"))
    return sorted(cases, key=lambda c: c.size)


def _pinv_variant(J, e, cut):
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    keep = cut(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    return Vt.T @ (inv * (U.T @ e))


def _pinv_parts(fn, name):
    cases = _pinv_cases()

    def run(tag):
        def check():
            results = {}
            for case in (c for c in cases if c.tag == tag):
                J, e, rcond = case.args
                results[id(case)] = _as_array(_call(fn, name, case, J.copy(), e.copy(), rcond),
                                              name, case)
            absolute = all(_close(results[id(c)], _pinv_variant(*c.args[:2], lambda s, r=c.args[2]:
                                                                 s >= r))
                           for c in cases if c.tag == tag)
            for case in (c for c in cases if c.tag == tag):
                J, e, rcond = case.args
                got = results[id(case)]
                want = np.asarray(_ref_pinv(J, e, rcond))
                if got.shape != want.shape:
                    hint = (" - one entry per joint: delta_theta = V Sigma^+ U^T e"
                            if got.shape == e.shape else "")
                    return _shape_message(name, got, want, case, hint)
                if _close(got, want):
                    continue
                if not np.all(np.isfinite(got)):
                    return ("NaN or inf at a singular J: 1/sigma for a tiny or zero sigma. "
                            "Drop 1/sigma_i (use 0) for sigma_i < rcond * sigma_max."
                            + _mismatch(got, want, case))
                if _close(got, -want):
                    return "wrong sign: delta_theta = +J^+ e." + _mismatch(got, want, case)
                if absolute and tag == "cutoff":
                    return ("the cut-off must be relative: drop sigma_i < rcond * sigma_max "
                            "(the largest singular value), not sigma_i < rcond."
                            + _mismatch(got, want, case))
                if _close(got, _pinv_variant(J, e, lambda s: s > 0), rtol=1e-4):
                    return ("no cut-off: 1/sigma_i must be dropped for sigma_i < rcond * "
                            f"sigma_max; here your step is {np.linalg.norm(got):.3g} long."
                            + _mismatch(got, want, case))
                if _close(got, _pinv_variant(J, e, lambda s: s >= rcond)):
                    return ("the cut-off must be relative: drop sigma_i < rcond * sigma_max "
                            "(the largest singular value), not sigma_i < rcond."
                            + _mismatch(got, want, case))
                return ("wrong values: delta_theta = sum_i (u_i . e / sigma_i) v_i over the "
                        "sigma_i kept by the cut-off." + _mismatch(got, want, case))
        return check

    return [_Part("regular", 5, run("regular")), _Part("cut-off", 5, run("cutoff"))]


def pinv_step_verdict(pinv_step):
    """Verdict for exercise 3 without printing."""
    return _evaluate(3, "the pseudoinverse step", ["pinv_step"],
                     _guarded(pinv_step, "pinv_step", _pinv_parts))


def pinv_step(pinv_step):
    """Exercise 3: check pinv_step(J, e, rcond) -> J^+ e by the SVD with a relative cut-off."""
    _report(pinv_step_verdict(pinv_step))


# --- exercise 4: damped least squares, both forms ------------------------------------------------

def _dls_cases():
    rng = np.random.default_rng(SEED + 4)
    cases = []
    hand = [(np.array([[0.0, 0.0], [3.0, 2.0]]), np.array([1.0, 0.5]), 0.5, "singular J"),
            (np.zeros((2, 3)), np.array([1.0, -1.0]), 0.3, "zero J"),
            (np.eye(2), np.array([1.0, 2.0]), 0.5, "")]
    for k, (J, e, lam, note) in enumerate(hand):
        cases.append(_Case((J, e, lam), _matrix_text(J, e, f", damping = {lam:g}")
                           + (f" ({note})" if note else ""), size=J.size * 100 + k))
    for k in range(12):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 7))
        J = rng.normal(size=(m, n)).round(3)
        e = rng.normal(size=m).round(3)
        lam = float(rng.choice([rng.uniform(0.05, 0.8), rng.uniform(1.3, 3.0)]).round(3))
        cases.append(_Case((J, e, lam), _matrix_text(J, e, f", damping = {lam:g}"),
                           size=m * n * 100 + 50 + k))
    return sorted(cases, key=lambda c: c.size)


def _dls_parts(fns, names):
    cases = _dls_cases()
    cache = {}

    def result(which, case):
        key = (which, id(case))
        if key not in cache:
            J, e, lam = case.args
            got = _call(fns[which], names[which], case, J.copy(), e.copy(), lam)
            cache[key] = _as_array(got, names[which], case)
        return cache[key]

    def form(which):
        name = names[which]

        def check():
            _check_callable(fns[which], name)
            for case in cases:
                J, e, lam = case.args
                got, want = result(which, case), np.asarray(_ref_dls(J, e, lam))
                if got.shape != want.shape:
                    return _shape_message(name, got, want, case, " - one entry per joint")
                if _close(got, want):
                    continue
                if not np.all(np.isfinite(got)):
                    return ("NaN or inf near a singularity: with damping > 0, J J^T + "
                            "lambda^2 I is always invertible - no pseudoinverse needed."
                            + _mismatch(got, want, case))
                if _close(got, np.asarray(_ref_dls(J, e, np.sqrt(lam)))):
                    return (f"missing square on lambda: `{name}` adds lambda I, the damping "
                            "term is lambda^2 I (from lambda^2 |delta_theta|^2)."
                            + _mismatch(got, want, case))
                if _close(got, -want):
                    return "wrong sign." + _mismatch(got, want, case)
                formula = ("J^T (J J^T + lambda^2 I)^-1 e" if which == 0
                           else "(J^T J + lambda^2 I)^-1 J^T e")
                return f"wrong values: `{name}` should compute {formula}." + _mismatch(
                    got, want, case)
        return check

    def agree():
        for which in (0, 1):
            _check_callable(fns[which], names[which])
        for case in cases:
            a, b = result(0, case), result(1, case)
            if a.shape != b.shape or not _close(a, b, rtol=1e-6, atol=1e-9):
                return (f"your two forms disagree: `{names[0]}` and `{names[1]}` should give the "
                        "same step, (J^T J + lambda^2 I)^-1 J^T = J^T (J J^T + lambda^2 I)^-1."
                        f"\n  smallest failing case: {case}\n  {names[0]}: {_fmt(a)}"
                        f"\n  {names[1]}: {_fmt(b)}")

    return [_Part(names[0], 4, form(0)), _Part(names[1], 4, form(1)), _Part("agree", 2, agree)]


def dls_step_verdict(dls_step, dls_step_normal):
    """Verdict for exercise 4 without printing."""
    names = ["dls_step", "dls_step_normal"]
    return _evaluate(4, "damped least squares", names,
                     _dls_parts([dls_step, dls_step_normal], names))


def dls_step(dls_step, dls_step_normal):
    """Exercise 4: check both DLS forms against ik.dls_step, and against each other."""
    _report(dls_step_verdict(dls_step, dls_step_normal))


# --- exercise 5: the out-of-reach stop rule through ik.solve's step-function hook --------------

STOP_ARM = [1.0, 1.0, 1.0]
STOP_TARGET = [4.0, 0.5]      # out of reach: the arm is 3 long
STOP_THETA0 = [0.3, 0.2, 0.1]
STOP_FRACTION = 1e-3
STOP_MAX_ITER = 300
STOP_DAMPING = 1.0            # enough damping for DLS to settle (exercise 6: less jitters)


def _stalled_reference(delta_theta, lengths, fraction):
    """The report's rule: stop when sum |delta_theta_i| < fraction * (total link length)."""
    return float(np.sum(np.abs(delta_theta))) < fraction * float(np.sum(lengths))


def _stop_cases():
    rng = np.random.default_rng(SEED + 5)
    hand = [([0.1, -0.1], [1.0, 1.0], 1e-3), ([2e-3, 0.0, 0.0], [1.0, 1.0, 1.0], 1e-3),
            ([1e-3, 1e-3, 1e-3], [1.0, 1.0, 1.0], 1e-3), ([0.05, 0.05], [10.0, 20.0], 1e-3),
            ([-1e-3, 5e-4], [2.0, 1.0], 1e-3), ([0.5], [1.0], 1e-3)]
    for _ in range(10):
        n = int(rng.integers(1, 6))
        lengths = rng.uniform(0.3, 3.0, n).round(3)
        fraction = float(rng.choice([1e-3, 1e-2, 1e-4]))
        size = fraction * lengths.sum() * float(rng.choice([0.4, 2.5]))
        w = rng.dirichlet(np.ones(n)) * size * rng.choice([-1.0, 1.0], n)
        hand.append((w.tolist(), lengths.tolist(), fraction))
    cases = [_Case((np.array(d), list(L), f),
                   f"delta_theta = {_fmt(d)}, lengths = {_fmt(L)}, fraction = {f:g}",
                   size=len(d) * 100 + k) for k, (d, L, f) in enumerate(hand)]
    return sorted(cases, key=lambda c: c.size)


def _as_bool(value, name, case):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    arr = np.asarray(value) if value is not None else None
    if arr is not None and arr.shape == () and arr.dtype.kind in "biuf":
        return bool(arr)
    raise _Fail(f"`{name}` returned {type(value).__name__} {value!r:.60} on {case}; "
                "expected True or False")


def _stop_parts(stalled, stop_rule_step):
    names = ("stalled", "stop_rule_step")

    def rule():
        _check_callable(stalled, names[0])
        for case in _stop_cases():
            d, lengths, fraction = case.args
            got = _as_bool(_call(stalled, names[0], case, d.copy(), list(lengths), fraction),
                           names[0], case)
            want = _stalled_reference(d, lengths, fraction)
            if got == want:
                continue
            detail = (f"\n  smallest failing case: {case}\n  threshold: "
                      f"{fraction * sum(lengths):.4g}, sum |delta_theta_i| = "
                      f"{np.abs(d).sum():.4g}\n  expected {want}, you returned {got}")
            if got == (abs(float(np.sum(d))) < fraction * sum(lengths)) or \
                    got == (float(np.sum(d)) < fraction * sum(lengths)):
                return ("use absolute values: sum |delta_theta_i| - joints turning opposite "
                        "ways do not cancel." + detail)
            if got == (np.abs(d).sum() < fraction):
                return ("the threshold must be proportional to the link lengths: "
                        "fraction * (sum of the lengths), not just the fraction." + detail)
            if got == (np.abs(d).max() < fraction * sum(lengths)):
                return "sum the joint steps (sum |delta_theta_i|), not their largest." + detail
            if got == (not want):
                return ("inverted: return True when the step is small (the arm has stopped "
                        "moving: stop), False otherwise." + detail)
            return "stop when sum |delta_theta_i| < fraction * (sum of lengths)." + detail

    def base_step(J, e):
        return _ref_dls(J, e, STOP_DAMPING)

    def reference_step(J, e):
        delta = np.asarray(base_step(J, e))
        if _stalled_reference(delta, STOP_ARM, STOP_FRACTION):
            raise StopSolve("out of reach")
        return delta

    def run_solve(step, name):
        case = (f"ik.solve(ik.planar_chain({STOP_ARM}), target={STOP_TARGET}, "
                f"theta0={STOP_THETA0}, method=your step, stall_tol=0)")
        arm = planar_chain(STOP_ARM)

        def go():
            return _solve(arm, np.array(STOP_TARGET), np.array(STOP_THETA0), method=step,
                          stall_tol=0.0, max_iter=STOP_MAX_ITER)
        try:
            return _call(go, name, case, limit=SOLVE_LIMIT), case
        except _Fail as exc:
            raise type(exc)(str(exc).replace(f" on {case}", f" inside {case}")) from None

    def solve_part():
        _check_callable(stop_rule_step, names[1])
        case = (f"stop_rule_step(step, lengths={STOP_ARM}, fraction={STOP_FRACTION:g}) with "
                f"step = DLS (damping {STOP_DAMPING:g})")
        step = _call(stop_rule_step, names[1], case, base_step, list(STOP_ARM), STOP_FRACTION)
        if not callable(step):
            return (f"`{names[1]}` must return a step function step(J, e) -> delta_theta; "
                    f"it returned {type(step).__name__}.")
        got, text = run_solve(step, names[1])
        want, _ = run_solve(reference_step, "reference")
        detail = (f"\n  case: {text}, target out of reach\n  expected: stalled after "
                  f"{want.iterations} iterations\n  yours:    {got.status} after "
                  f"{got.iterations} iterations")
        if got.status == "stalled" and abs(got.iterations - want.iterations) <= 1:
            return None
        if got.status == "max_iter":
            return ("the solve never stopped: when the rule fires, raise ik.StopSolve from "
                    "your step function (ik.solve then ends \"stalled\")." + detail)
        return "the stop rule did not end the solve where it should." + detail

    return [_Part("rule", 5, rule), _Part("solve", 5, solve_part)]


def stop_rule_verdict(stalled, stop_rule_step):
    """Verdict for exercise 5 without printing."""
    return _evaluate(5, "the out-of-reach stop rule", ["stalled", "stop_rule_step"],
                     _stop_parts(stalled, stop_rule_step))


def stop_rule(stalled, stop_rule_step):
    """Exercise 5: check stalled(delta_theta, lengths, fraction) and stop_rule_step(...)."""
    _report(stop_rule_verdict(stalled, stop_rule_step))


# --- exercise 6: a singularity study, answered in code ------------------------------------------

STUDY_ARM = [1.0, 1.0, 1.0]
STUDY_THETA0 = [0.3, 0.2, 0.1]
STUDY_REACHABLE = [1.5, 1.0]
STUDY_UNREACHABLE = [4.0, 0.5]
STUDY_LAMBDAS = [0.2, 0.5, 0.7, 1.0]
STUDY_MAX_ITER = 500
BLOW_UP = 10.0  # radians: "the joint angles blow up" when some |theta_i| exceeds this
METHOD_NAMES = ("jt", "pinv", "dls")


@functools.lru_cache(maxsize=1)
def _reference_study():
    """The answers, from ik.solve with the module's own steps (the same runs as the exercise)."""
    arm, theta0 = planar_chain(STUDY_ARM), np.array(STUDY_THETA0)
    options = {"jt": {}, "pinv": {"rcond": 1e-6}, "dls": {"damping": 0.5}}
    iterations = {m: _solve(arm, np.array(STUDY_REACHABLE), theta0, method=m,
                            max_iter=STUDY_MAX_ITER, **options[m]).iterations
                  for m in METHOD_NAMES}
    options["pinv"] = {"rcond": 0.0}
    largest = {m: float(np.abs(_solve(arm, np.array(STUDY_UNREACHABLE), theta0, method=m,
                                      max_iter=STUDY_MAX_ITER, **options[m]).trace.theta).max())
               for m in METHOD_NAMES}
    smallest = next((lam for lam in STUDY_LAMBDAS
                     if _solve(arm, np.array(STUDY_UNREACHABLE), theta0, method="dls",
                               damping=lam, max_iter=STUDY_MAX_ITER).status == "stalled"), None)
    return {"iterations": iterations,
            "fewest_iterations": min(iterations, key=iterations.get),
            "blows_up": [m for m in METHOD_NAMES if largest[m] > BLOW_UP],
            "smallest_lambda": smallest}


_QUESTIONS = {
    "iterations": (3, "iterations on the reachable target: a dict {'jt': ..., 'pinv': ..., "
                      "'dls': ...} of res.iterations"),
    "fewest_iterations": (2, "the method that needs the fewest iterations on the reachable "
                             "target"),
    "blows_up": (2, "the list of methods whose joint angles blow up (some |theta_i| > "
                    f"{BLOW_UP:g} rad) on the out-of-reach target"),
    "smallest_lambda": (3, "the smallest damping in LAMBDAS for which DLS stops \"stalled\" on "
                           "the out-of-reach target instead of jittering until max_iter"),
}


def _same_answer(got, want):
    if isinstance(want, dict):
        return isinstance(got, dict) and set(got) == set(want) and all(
            _same_answer(got[k], want[k]) for k in want)
    if isinstance(want, list):
        try:
            return sorted(str(g) for g in got) == sorted(want)
        except TypeError:
            return False
    if isinstance(want, str):
        return isinstance(got, str) and got.strip().lower() == want
    try:
        return got is not None and np.isclose(float(got), float(want))
    except (TypeError, ValueError):
        return False


def _study_parts(study):
    name = "study"
    state = {}

    def answers():
        if "answers" not in state:
            _check_callable(study, name)
            case = "study(ik.jt_step, ik.pinv_step, ik.dls_step)"
            got = _call(study, name, case, _ref_jt, _ref_pinv, _ref_dls, limit=4 * SOLVE_LIMIT)
            if not isinstance(got, dict):
                raise _Fail(f"`{name}` must return a dict of answers, it returned "
                            f"{type(got).__name__}.")
            state["answers"] = got
            state["reference"] = _reference_study()
        return state["answers"], state["reference"]

    def question(key):
        points, meaning = _QUESTIONS[key]

        def check():
            got, want = answers()
            if key not in got:
                return f"the answer '{key}' is missing ({meaning})."
            if not _same_answer(got[key], want[key]):
                return (f"'{key}' is not right: you answered {got[key]!r:.80}. It should be "
                        f"{meaning} - run the solves and read it off the results.")
        return _Part(key, points, check)

    return [question(key) for key in _QUESTIONS]


def singularity_study_verdict(study):
    """Verdict for exercise 6 without printing."""
    return _evaluate(6, "a singularity study", ["study"], _study_parts(study))


def singularity_study(study):
    """Exercise 6: check study(jt_step, pinv_step, dls_step) -> dict of answers, by value."""
    _report(singularity_study_verdict(study))


# --- exercise 7: the two-level priority step (a secondary task in the primary's null space) -----

def _ref_priority(J1, e1, J2, e2, lam):
    from .priority import priority_step as reference  # one source: the module's own step
    return np.asarray(reference(J1, e1, J2, e2, lam))


def _damped(A, lam):
    """A^T (A A^T + lambda^2 I)^-1, or the plain pseudoinverse when lambda = 0 (variants)."""
    if lam == 0:
        return np.linalg.pinv(A)
    return A.T @ np.linalg.solve(A @ A.T + lam**2 * np.eye(A.shape[0]), np.eye(A.shape[0]))


def _priority_variants(J1, e1, J2, e2, lam):
    """Common wrong steps, each with what it gets wrong."""
    n = J1.shape[1]
    first = _damped(J1, lam) @ e1
    N1 = np.eye(n) - np.linalg.pinv(J1) @ J1
    N2 = np.eye(n) - np.linalg.pinv(J2) @ J2  # J2 N2 = 0: the same as ignoring the secondary
    rest = e2 - J2 @ first
    yield (first + _damped(J2, lam) @ rest,
           "the secondary step is not projected: J2+ (e2 - J2 J1+ e1) also moves the primary. "
           "Solve it in the null space of J1: N1 (J2 N1)+ (...) with N1 = I - J1+ J1.")
    yield (first + N1 @ (_damped(J2, lam) @ rest),
           "you project the secondary's own step, N1 J2+ (...); use (J2 N1)+ so the secondary "
           "is solved with the freedom that is left, not solved first and cut afterwards.")
    yield (first + N2 @ (_damped(J2 @ N2, lam) @ rest),
           "your step ignores the secondary task. Projector built from J2? J2 N2 = 0, so nothing "
           "is left; the null space that protects the primary is J1's, N1 = I - J1+ J1.")
    yield (first + N1 @ (_damped(J2 @ N1, lam) @ e2),
           "the secondary's error must be what is left after the primary step: e2 - J2 J1+ e1, "
           "not e2 (the primary step moves the secondary too).")
    yield (first + N1 @ (_damped(J2 @ N1, lam) @ (J2 @ first - e2)),
           "wrong sign: the secondary's remaining error is e2 - J2 J1+ e1.")
    yield (np.linalg.pinv(J1) @ e1 + N1 @ (_damped(J2 @ N1, lam) @ (e2 - J2 @ np.linalg.pinv(J1) @ e1)),
           "missing damping on J1+: use the damped J1^T (J1 J1^T + lambda^2 I)^-1 (it stays "
           "bounded where J1 is singular).")
    yield (first + N1 @ (np.linalg.pinv(J2 @ N1) @ rest),
           "missing damping on (J2 N1)+: use the damped form there too.")


def _priority_cases():
    rng = np.random.default_rng(SEED + 7)
    cases = []
    hand = [
        (np.array([[1.0, 0.0]]), np.array([1.0]), np.array([[0.0, 1.0]]), np.array([2.0]), 0.1,
         "independent tasks"),
        (np.array([[1.0, 0.0, 0.0]]), np.array([0.5]), np.array([[1.0, 1.0, 0.0]]), np.array([2.0]),
         0.1, "partial conflict"),
        (np.array([[1.0, 1.0, 0.0]]), np.array([1.0]), np.array([[1.0, 1.0, 0.0]]), np.array([-1.0]),
         0.2, "full conflict: J2 = J1"),
    ]
    for k, (J1, e1, J2, e2, lam, note) in enumerate(hand):
        cases.append(_Case((J1, e1, J2, e2, lam), _priority_text(J1, e1, J2, e2, lam, note),
                           size=J1.size * 100 + k, tag="regular"))
    singular = [
        (np.zeros((2, 3)), np.array([1.0, -1.0]), np.array([[1.0, 0.0, 1.0]]), np.array([1.0]), 0.3,
         "singular: J1 = 0"),
        (np.array([[1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]), np.array([1.0, 0.5]),
         np.array([[0.0, 1.0, 1.0]]), np.array([0.5]), 0.2, "singular: rank-1 J1"),
    ]
    for k, (J1, e1, J2, e2, lam, note) in enumerate(singular):
        cases.append(_Case((J1, e1, J2, e2, lam), _priority_text(J1, e1, J2, e2, lam, note),
                           size=J1.size * 100 + k, tag="singular"))
    for k in range(10):
        n = int(rng.integers(3, 7))
        m1, m2 = int(rng.integers(1, 3)), int(rng.integers(1, 3))
        J1, J2 = rng.normal(size=(m1, n)).round(3), rng.normal(size=(m2, n)).round(3)
        e1, e2 = rng.normal(size=m1).round(3), rng.normal(size=m2).round(3)
        lam = round(float(rng.uniform(0.05, 0.8)), 3)
        cases.append(_Case((J1, e1, J2, e2, lam), _priority_text(J1, e1, J2, e2, lam),
                           size=n * (m1 + m2) * 100 + 50 + k, tag="regular"))
    return sorted(cases, key=lambda c: c.size)


def _priority_text(J1, e1, J2, e2, lam, note=""):
    return (f"J1 = {_fmt(J1)}, e1 = {_fmt(e1)}, J2 = {_fmt(J2)}, e2 = {_fmt(e2)}, "
            f"damping = {lam:g}" + (f" ({note})" if note else ""))


def _priority_parts(fn, name):
    cases = _priority_cases()
    cache = {}

    def result(case):
        if id(case) not in cache:
            J1, e1, J2, e2, lam = case.args
            got = _call(fn, name, case, J1.copy(), e1.copy(), J2.copy(), e2.copy(), lam)
            cache[id(case)] = _as_array(got, name, case)
        return cache[id(case)]

    def diagnose(got, want, case):
        if got.shape != want.shape:
            return _shape_message(name, got, want, case, " - one entry per joint")
        if not np.all(np.isfinite(got)):
            return ("NaN or inf where J1 (or J2 N1) is singular: use damped pseudoinverses, "
                    "A^T (A A^T + lambda^2 I)^-1, which never divide by zero." + _mismatch(got, want, case))
        for variant, why in _priority_variants(*case.args):
            if _close(got, variant):
                return why + _mismatch(got, want, case)
        J1, e1, _, _, lam = case.args
        if not np.allclose(J1 @ got, J1 @ (_damped(J1, lam) @ e1), rtol=1e-6, atol=1e-8):
            return ("the primary task is disturbed: J1 delta_theta should equal J1 J1+ e1 "
                    "(the secondary may move only in J1's null space)." + _mismatch(got, want, case))
        return (f"wrong values: `{name}` should compute J1+ e1 + N1 (J2 N1)+ (e2 - J2 J1+ e1)."
                + _mismatch(got, want, case))

    def against_reference(tag):
        def check():
            _check_callable(fn, name)
            for case in (c for c in cases if c.tag == tag):
                got, want = result(case), _ref_priority(*case.args)
                if not _close(got, want, rtol=1e-6, atol=1e-8):
                    return diagnose(got, want, case)
        return check

    def primary_kept():
        """J1 delta = J1 J1+ e1: the secondary adds nothing the primary sees (first order)."""
        _check_callable(fn, name)
        for case in cases:
            J1, e1, J2, e2, lam = case.args
            got = result(case)
            kept = (got.shape == (J1.shape[1],) and np.all(np.isfinite(got))
                    and np.allclose(J1 @ got, J1 @ (_damped(J1, lam) @ e1), rtol=1e-6, atol=1e-8))
            if not kept:
                return diagnose(got, _ref_priority(*case.args), case)

    return [_Part("primary kept", 3, primary_kept), _Part("secondary", 4, against_reference("regular")),
            _Part("singular", 3, against_reference("singular"))]


def priority_step_verdict(priority_step):
    """Verdict for exercise 7 without printing."""
    return _evaluate(7, "the priority step", ["priority_step"],
                     _priority_parts(priority_step, "priority_step"))


def priority_step(priority_step):
    """Exercise 7: check priority_step(J1, e1, J2, e2, damping) against ik.priority_step."""
    _report(priority_step_verdict(priority_step))


# --- the exercise list, for the grader -----------------------------------------------------------

EXERCISES = {
    1: ("jacobian", ("planar_jacobian",), jacobian_verdict),
    2: ("jt_step", ("jt_step",), jt_step_verdict),
    3: ("pinv_step", ("pinv_step",), pinv_step_verdict),
    4: ("dls_step", ("dls_step", "dls_step_normal"), dls_step_verdict),
    5: ("stop_rule", ("stalled", "stop_rule_step"), stop_rule_verdict),
    6: ("singularity_study", ("study",), singularity_study_verdict),
    7: ("priority_step", ("priority_step",), priority_step_verdict),
}


def grade(number, namespace):
    """The verdict for exercise `number`, taking the student's functions from `namespace`
    (a notebook's globals). Missing functions fail with a message; nothing is printed."""
    if number not in EXERCISES:
        raise ValueError(f"number: expected one of {sorted(EXERCISES)}, got {number!r}")
    check_name, names, make = EXERCISES[number]
    missing = [n for n in names if not callable(namespace.get(n))]
    if missing:
        parts = [_Part("functions", POINTS, lambda: (
            f"{', '.join('`' + n + '`' for n in missing)} not found in the notebook: keep the "
            "function names of the template."))]
        return _evaluate(number, check_name, list(names), parts)
    return make(*(namespace[n] for n in names))
