"""Exercise 4: both DLS forms against ik.dls_step, and against each other.

Parts: each form 4; both forms 2 (they agree, and each is its own form: at damping 0 the m x m
form is defined for a wide J, the n x n form for a tall one, where the other is singular).
"""
import numpy as np

from ...core.dls import dls_step as _ref_dls
from .verdicts import (_answers, _Case, _close, _evaluate, _Fail, _fmt, _in_every_draw,
                       _matrix_text, _mismatch, _Part, _random_matrix, _rng, _shape_message,
                       _turned_hand)

NUMBER = 4
CHECK_NAME = "dls_step"
TITLE = "damped least squares"
FUNCTIONS = ('dls_step', 'dls_step_normal')
REFERENCES = ("ikteach.core.dls:dls_step",  # ikteach's answers, stubbed when graded
              "ikteach.core.dls:dls_step_normal",
              "ikteach.core.dls:dls_step_small",  # what ik.DLS runs on 2-3 rows
              "ikteach.core.dls:damped_step",  # ik.DLS's choice between the two
              "ikteach.core.priority:damped_pinv",
)

HAND = [(np.array([[0.0, 0.0], [3.0, 2.0]]), np.array([1.0, 0.5]), 0.5, "singular J"),
        (np.zeros((2, 3)), np.array([1.0, -1.0]), 0.3, "zero J"),
        (np.eye(2), np.array([1.0, 2.0]), 0.5, ""),
        # the smallest damping drawn, where a form's own matrix is singular (J J^T for a tall J,
        # J^T J for a wide one): a form solved with too few digits fails here, in every draw
        (np.array([[-0.6, 0.1], [0.4, 1.6], [0.9, -0.1]]), np.array([0.7, -0.4, 0.2]), 0.05,
         "tall J, small damping"),
        (np.array([[-0.6, 0.4, 0.9], [0.1, 1.6, -0.1]]), np.array([0.7, -0.4]), 0.05,
         "wide J, small damping")]


@_in_every_draw
def _dls_cases(seed=None):
    rng = _rng(seed, 4)
    hand = HAND if seed is None else _turned_hand(rng, HAND)  # the same damping
    cases = [_Case((J, e, lam), _matrix_text(J, e, f", damping = {lam:g}")
                   + (f" ({note})" if note else ""), size=J.size * 100 + k)
             for k, (J, e, lam, note) in enumerate(hand)]
    for k in range(12):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 7))
        J = rng.normal(size=(m, n)).round(3)
        e = rng.normal(size=m).round(3)
        lam = float(rng.choice([rng.uniform(0.05, 0.8), rng.uniform(1.3, 3.0)]).round(3))
        cases.append(_Case((J, e, lam), _matrix_text(J, e, f", damping = {lam:g}"),
                           size=m * n * 100 + 50 + k))
    return cases


@_in_every_draw
def _form_cases(seed=None):
    """Damping 0, where only one form is defined: a wide J of full row rank (J J^T invertible,
    the n x n J^T J singular) for the m x m form, a tall J of full column rank for the n x n
    form. Each is then J^+ e."""
    rng = _rng(seed, 40)
    wide, tall = _random_matrix(rng, 2, 4).round(3), _random_matrix(rng, 4, 2).round(3)
    return [_Case((J, rng.normal(size=len(J)).round(3), 0.0), f"J = {_fmt(J)} ({what})")
            for J, what in ((wide, "wide, full row rank"), (tall, "tall, full column rank"))]


NO_DAMPING = ("the damping is missing: your step is the undamped J^+ e (the least-squares step, "
              "which blows up near a singularity). Damped least squares adds lambda^2 I: "
              "J^T (J J^T + lambda^2 I)^-1 e.")
FORMS = ("J^T (J J^T + lambda^2 I)^-1 e, the m x m solve", "(J^T J + lambda^2 I)^-1 J^T e, "
         "the n x n solve")


def verdict(dls_step, dls_step_normal, seed=None):
    """Verdict for exercise 4 without printing (`seed`: the grader's hidden cases)."""
    names, cases = list(FUNCTIONS), _dls_cases(seed)
    answers = [_answers(fn, name) for fn, name in zip([dls_step, dls_step_normal], names)]

    def undamped(which, answered):
        """Is the answer the undamped J^+ e wherever the undamped form is defined (J of full
        row rank for the m x m form, of full column rank for the n x n one), on cases where
        damping matters? (`answered`: [(case, answer)])"""
        found = [(case, got) for case, got in answered
                 if np.linalg.matrix_rank(case.args[0]) == case.args[0].shape[which]]
        plain = [np.linalg.pinv(c.args[0]) @ c.args[1] for c, _ in found]
        return bool(found) and all(_close(g, p) for (_, g), p in zip(found, plain)) and any(
            not _close(p, np.asarray(_ref_dls(*c.args))) for (c, _), p in zip(found, plain))

    def diagnose(which, got, want, case):
        name, detail = names[which], _mismatch(got, want, case)
        if not np.all(np.isfinite(got)):
            return ("NaN or inf near a singularity: with damping > 0, J J^T + "
                    "lambda^2 I is always invertible - no pseudoinverse needed." + detail)
        if _close(got, np.asarray(_ref_dls(*case.args[:2], np.sqrt(case.args[2])))):
            return (f"missing square on lambda: `{name}` adds lambda I, the damping "
                    "term is lambda^2 I (from lambda^2 |delta_theta|^2)." + detail)
        if _close(got, -want):
            return "wrong sign." + detail
        return f"wrong values: `{name}` should compute {FORMS[which]}." + detail

    def form(which):
        name = names[which]

        def check():
            first = None  # (case, got or None, error or None): the smallest failing case
            answered = []
            for case in cases:
                try:
                    got = answers[which](case)
                except _Fail as exc:
                    if type(exc) is not _Fail:
                        raise
                    first = first or (case, None, str(exc))
                    continue
                answered.append((case, got))
                want = case.want(_ref_dls)
                if got.shape != want.shape:
                    return _shape_message(name, got, want, case, " - one entry per joint")
                if not _close(got, want):
                    first = first or (case, got, None)
            if first is None:
                return None
            case, got, error = first
            if undamped(which, answered):
                return NO_DAMPING + (f"\n  smallest failing case: {case}\n  {error}" if error
                                     else _mismatch(got, case.want(_ref_dls), case))
            if error is not None:
                raise _Fail(error)
            return diagnose(which, got, case.want(_ref_dls), case)
        return check

    def both_forms():
        """The two agree, and each is its own form: at damping 0 only that form is defined."""
        for case in cases:
            a, b = answers[0](case), answers[1](case)
            if a.shape != b.shape or not _close(a, b):
                return (f"your two forms disagree: `{names[0]}` and `{names[1]}` should give the "
                        "same step, (J^T J + lambda^2 I)^-1 J^T = J^T (J J^T + lambda^2 I)^-1."
                        f"\n  smallest failing case: {case}\n  {names[0]}: {_fmt(a)}"
                        f"\n  {names[1]}: {_fmt(b)}")
        for k, case in enumerate(_form_cases(seed)):
            which, (J, e, _) = k % 2, case.args  # wide, tall, wide, tall
            want, other = np.linalg.pinv(J) @ e, ("J^T J", "J J^T")[which]
            try:
                got = answers[which](case)
                problem = None if _close(got, want) else f"your result: {_fmt(got)}"
            except _Fail as exc:
                if type(exc) is not _Fail:
                    raise
                problem = str(exc).split(" on J = ")[0]
            if problem is not None:
                return (f"`{names[which]}` is not {FORMS[which]}: at damping = 0 with {case}, "
                        f"that form is defined (J^+ e = {_fmt(want)}) while {other} is "
                        f"singular. {problem}. The same form written twice? Write each form "
                        "as the exercise asks.")

    return _evaluate(NUMBER, TITLE, names, [_Part(names[0], 4, form(0)),
                                            _Part(names[1], 4, form(1)),
                                            _Part("both forms", 2, both_forms)])
