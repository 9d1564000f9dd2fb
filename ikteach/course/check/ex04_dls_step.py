"""Exercise 4: both DLS forms against ik.dls_step, and against each other.

Parts: each form 4, the two forms agree 2.
"""
import numpy as np

from ...core.dls import dls_step as _ref_dls
from .verdicts import (_Case, _Part, _as_array, _call, _check_callable, _close, _evaluate,
                       _fmt, _matrix_text, _mismatch, _rng, _shape_message)

NUMBER = 4
CHECK_NAME = "dls_step"
TITLE = "damped least squares"
FUNCTIONS = ('dls_step', 'dls_step_normal')
# ikteach's own answer to this exercise: blocked (raises) while a student's code is graded
REFERENCES = ("ikteach.core.dls:dls_step",
              "ikteach.core.dls:dls_step_normal",
              "ikteach.core.dls:dls_step_small",  # what ik.DLS runs on 2-3 rows
              "ikteach.core.priority:damped_pinv",
)

HAND = [(np.array([[0.0, 0.0], [3.0, 2.0]]), np.array([1.0, 0.5]), 0.5, "singular J"),
        (np.zeros((2, 3)), np.array([1.0, -1.0]), 0.3, "zero J"),
        (np.eye(2), np.array([1.0, 2.0]), 0.5, "")]


def _hidden_hand(rng):
    """HAND's kinds with other numbers: a straight arm's J, J = 0, a scaled identity."""
    a, b, c = rng.uniform(0.5, 3.0, 3).round(3)
    lams = rng.uniform(0.1, 0.9, 3).round(3)
    return [(np.array([[0.0, 0.0], [a, b]]), rng.normal(size=2).round(3), lams[0], "singular J"),
            (np.zeros((2, int(rng.integers(3, 5)))), rng.normal(size=2).round(3), lams[1],
             "zero J"),
            (c * np.eye(2), rng.normal(size=2).round(3), lams[2], "")]


def _dls_cases(seed=None):
    rng = _rng(seed, 4)
    cases = []
    hand = HAND if seed is None else _hidden_hand(rng)
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


def _dls_parts(fns, names, seed=None):
    cases = _dls_cases(seed)
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


def verdict(dls_step, dls_step_normal, seed=None):
    """Verdict for exercise 4 without printing (`seed`: the grader's hidden cases)."""
    names = list(FUNCTIONS)
    return _evaluate(NUMBER, TITLE, names,
                     _dls_parts([dls_step, dls_step_normal], names, seed))
