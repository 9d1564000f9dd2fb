"""Exercise 7: priority_step(J1, e1, J2, e2, damping) -> the secondary task in the primary's
null space, J1+ e1 + N1 (J2 N1)+ (e2 - J2 J1+ e1), with damped pseudoinverses.

Parts: the primary kept (J1 delta = J1 J1+ e1) 3, the secondary on regular cases 3, singular J1 2,
no damping (lambda = 0, J1 singular or not: the exact pseudoinverses, finite) 2.
"""
import numpy as np

from ...core.priority import priority_step as _ref_step
from .verdicts import (_answers, _Case, _close, _evaluate, _Fail, _fmt, _in_every_draw,
                       _mismatch, _Part, _rng, _shape_message, _turned)

NUMBER = 7
CHECK_NAME = "priority_step"
TITLE = "the priority step"
FUNCTIONS = ("priority_step",)
REFERENCES = ("ikteach.core.priority:priority_step",  # ikteach's answers, stubbed when graded
              "ikteach.core.priority:multilevel_step",
              "ikteach.core.priority:null_space_step",
              "ikteach.core.priority:damped_pinv",  # the parts the exercise asks for
              "ikteach.core.priority:null_projector",
)


_AT_ZERO = ("With damping = 0, A^T (A A^T + lambda^2 I)^-1 is A^T (A A^T)^-1, which does not exist "
            "where A (here J1) is singular. At lambda = 0 the step uses the exact pseudoinverse: "
            "write the damped one from the SVD, V diag(sigma_i / (sigma_i^2 + lambda^2)) U^T with "
            "sigma_i below a small cut-off (e.g. 1e-10 sigma_max) dropped; it equals "
            "A^T (A A^T + lambda^2 I)^-1 for lambda > 0 and np.linalg.pinv(A) at lambda = 0.")


def _damped(A, lam):
    """A^T (A A^T + lambda^2 I)^-1, or the plain pseudoinverse when lambda = 0 (variants)."""
    if lam == 0:
        return np.linalg.pinv(A)
    return A.T @ np.linalg.solve(A @ A.T + lam**2 * np.eye(A.shape[0]), np.eye(A.shape[0]))


_DAMPING_MISTAKES = (  # (pseudoinverse used for J1 and for J2 N1, what is wrong)
    (lambda A, lam: _damped(A, np.sqrt(lam)),
     "the damping term is lambda^2 I, not lambda I: each damped pseudoinverse is "
     "A^T (A A^T + lambda^2 I)^-1 (from lambda^2 |delta_theta|^2, as in exercise 4)."),
    (lambda A, lam: np.linalg.pinv(A),
     "no damping: your step uses exact pseudoinverses for damping > 0. Use the damped "
     "A^T (A A^T + lambda^2 I)^-1 for J1 and for J2 N1 (exercise 4)."),
)


def _priority_variants(J1, e1, J2, e2, lam):
    """Common wrong steps, each with what it gets wrong."""
    n = J1.shape[1]
    first = _damped(J1, lam) @ e1
    N1 = np.eye(n) - np.linalg.pinv(J1) @ J1
    N2 = np.eye(n) - np.linalg.pinv(J2) @ J2  # J2 N2 = 0: the same as ignoring the secondary
    rest = e2 - J2 @ first
    for damp, why in _DAMPING_MISTAKES:
        mine = damp(J1, lam) @ e1
        yield mine + N1 @ (damp(J2 @ N1, lam) @ (e2 - J2 @ mine)), why
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


def _primary_kept(got, J1, e1, lam):
    """J1 delta = J1 J1+ e1 (J1+ damped with lambda^2, or lambda: that slip is another part's):
    the secondary task moves nothing the primary sees."""
    if got.shape != (J1.shape[1],) or not np.all(np.isfinite(got)):
        return False
    # J1 delta's rounding is relative to |J1| |delta| (the secondary's part is large where
    # e1 is small), not to J1 J1+ e1
    scale = np.linalg.norm(J1, 2) * max(np.abs(got).max(initial=0.0), 1e-300)
    return any(_close(J1 @ got, J1 @ (_damped(J1, d) @ e1), rtol=1e-6, atol=1e-8, scale=scale)
               for d in (lam, np.sqrt(lam)))


# rank 1 in its rounded entries as the hidden ones (an SVD leaves its second sigma at
# rounding size, not 0): a cut-off too small for the arithmetic used fails here, in every draw
RANK1 = np.outer([1.0, 1.7], [0.9, 1.3, 0.0])
HAND = {
    "regular": [
        (np.array([[1.0, 0.0]]), np.array([1.0]), np.array([[0.0, 1.0]]), np.array([2.0]), 0.1,
         "independent tasks"),
        (np.array([[1.0, 0.0, 0.0]]), np.array([0.5]), np.array([[1.0, 1.0, 0.0]]), np.array([2.0]),
         0.1, "partial conflict"),
        (RANK1[:1] / 2, np.array([1.0]), RANK1[:1] / 2, np.array([-1.0]), 0.05,  # rounded
         "full conflict: J2 = J1")],                                             # as drawn
    "singular": [
        (np.zeros((2, 3)), np.array([1.0, -1.0]), np.array([[1.0, 0.0, 1.0]]), np.array([1.0]), 0.3,
         "singular: J1 = 0"),
        (RANK1, np.array([1.0, 0.5]), np.array([[0.0, 1.0, 1.0]]), np.array([0.5]), 0.2,
         "singular: rank-1 J1")],
    # damping 0: A^T (A A^T)^-1 exists for J1 of full row rank, not for a singular J1
    # (J2 N1 has full row rank in every one of these, so only J1 decides)
    "no damping": [
        (np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([0.5, -1.0]),
         np.array([[0.0, 1.0, 1.0]]), np.array([1.0]), 0.0, "no damping, J1 of full row rank"),
        (np.array([[1.0, 2.0, 0.0, -1.0], [0.0, 1.0, 1.0, 0.5]]), np.array([0.3, 0.2]),
         np.array([[1.0, 0.0, 1.0, 1.0]]), np.array([-0.4]), 0.0, "no damping, J1 of full row rank"),
        (np.zeros((2, 3)), np.array([1.0, -1.0]), np.array([[1.0, 0.0, 1.0]]), np.array([1.0]), 0.0,
         "no damping, singular: J1 = 0"),
        (RANK1, np.array([1.0, 0.5]), np.array([[0.0, 1.0, 1.0]]), np.array([0.5]), 0.0,
         "no damping, singular: rank-1 J1")],
}


def _hidden_hand(rng):
    """HAND turned (verdicts._turned: J1 and J2 share their columns), the same damping."""
    def turned(J1, e1, J2, e2, lam, note):
        (J1, J2), (e1, e2) = _turned(rng, [J1, J2], [e1, e2])
        return J1, e1, J2, e2, lam, note
    return {tag: [turned(*case) for case in cases] for tag, cases in HAND.items()}


@_in_every_draw
def _priority_cases(seed=None):
    rng = _rng(seed, 7)
    cases = []
    hand = HAND if seed is None else _hidden_hand(rng)
    for tag, offset in (("regular", 0), ("singular", 0), ("no damping", 10)):
        for k, (J1, e1, J2, e2, lam, note) in enumerate(hand[tag]):
            cases.append(_Case((J1, e1, J2, e2, lam), _priority_text(J1, e1, J2, e2, lam, note),
                               size=J1.size * 100 + offset + k, tag=tag))
    for k in range(10):
        n = int(rng.integers(3, 7))
        m1, m2 = int(rng.integers(1, 3)), int(rng.integers(1, 3))
        J1, J2 = rng.normal(size=(m1, n)).round(3), rng.normal(size=(m2, n)).round(3)
        e1, e2 = rng.normal(size=m1).round(3), rng.normal(size=m2).round(3)
        lam = round(float(rng.uniform(0.05, 0.8)), 3)
        cases.append(_Case((J1, e1, J2, e2, lam), _priority_text(J1, e1, J2, e2, lam),
                           size=n * (m1 + m2) * 100 + 50 + k, tag="regular"))
    return cases


def _priority_text(J1, e1, J2, e2, lam, note=""):
    return (f"J1 = {_fmt(J1)}, e1 = {_fmt(e1)}, J2 = {_fmt(J2)}, e2 = {_fmt(e2)}, "
            f"damping = {lam:g}" + (f" ({note})" if note else ""))


def verdict(priority_step, seed=None):
    """Verdict for exercise 7 without printing (`seed`: the grader's hidden cases)."""
    name, cases = FUNCTIONS[0], _priority_cases(seed)
    result = _answers(priority_step, name)

    def diagnose(got, want, case):
        if got.shape != want.shape:
            return _shape_message(name, got, want, case, " - one entry per joint")
        (J1, e1, _, _, lam), detail = case.args, _mismatch(got, want, case)
        if not np.all(np.isfinite(got)):
            if lam == 0:
                return ("your step is NaN or inf at damping = 0 where J1 is singular. "
                        + _AT_ZERO + detail)
            return ("NaN or inf where J1 (or J2 N1) is singular: use damped pseudoinverses, "
                    "A^T (A A^T + lambda^2 I)^-1, which stay finite for damping > 0 (A A^T + "
                    "lambda^2 I is then invertible)." + detail)
        for variant, why in _priority_variants(*case.args):
            if _close(got, variant) and not (lam == 0 and "damping" in why):
                return why + detail
        if not _primary_kept(got, J1, e1, lam):
            return ("the primary task is disturbed: J1 delta_theta should equal J1 J1+ e1 "
                    "(the secondary may move only in J1's null space)."
                    + _mismatch(J1 @ got, J1 @ want, case, "J1 delta_theta"))
        return (f"wrong values: `{name}` should compute J1+ e1 + N1 (J2 N1)+ (e2 - J2 J1+ e1)."
                + detail)

    def against_reference(tag):
        def check():
            for case in (c for c in cases if c.tag == tag):
                got, want = result(case), case.want(_ref_step)
                if not _close(got, want, rtol=1e-6, atol=1e-8):
                    return diagnose(got, want, case)
        return check

    def no_damping():
        """damping = 0: the exact pseudoinverses, finite whether J1 is singular or not."""
        for case in (c for c in cases if c.tag == "no damping"):
            try:
                got = result(case)
            except _Fail as exc:
                return f"at damping = 0 {exc}.\n  " + _AT_ZERO
            want = case.want(_ref_step)
            if not _close(got, want, rtol=1e-6, atol=1e-8):
                problem = diagnose(got, want, case)
                return problem if problem.startswith("your step is NaN") else "at damping = 0: " + problem

    def primary_kept():
        """J1 delta = J1 J1+ e1: the secondary adds nothing the primary sees (first order)."""
        for case in (c for c in cases if c.tag != "no damping"):
            J1, e1, _, _, lam = case.args
            if not _primary_kept(result(case), J1, e1, lam):
                return diagnose(result(case), case.want(_ref_step), case)

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), [
        _Part("primary kept", 3, primary_kept), _Part("secondary", 3, against_reference("regular")),
        _Part("singular", 2, against_reference("singular")), _Part("no damping", 2, no_damping)])
