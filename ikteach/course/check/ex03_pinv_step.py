"""Exercise 3: pinv_step(J, e, rcond) -> J^+ e by the SVD with a relative cut-off.

Parts: regular J, up to the sign 2; the sign 3 (so a sign slip costs what it costs in exercise
2); small sigma dropped (the cut-off at singular and ill-conditioned J, up to the sign) 3; the
guard for sigma_max = 0 (J = 0: nothing is kept) 2.
"""
import numpy as np

from ...core.pinv import pinv_step as _ref_pinv
from .verdicts import (_answers, _Case, _close, _evaluate, _Fail, _fmt, _in_every_draw,
                       _matrix_text, _mismatch, _Part, _random_matrix, _rng, _shape_message,
                       _turned_hand, _with_singular_values)

NUMBER = 3
CHECK_NAME = "pinv_step"
TITLE = "the pseudoinverse step"
FUNCTIONS = ('pinv_step',)
REFERENCES = ("ikteach.core.pinv:pinv_step",  # ikteach's answers, stubbed when graded
              "ikteach.core.pinv:pinv_two_rows",
              "ikteach.core.priority:damped_pinv")  # damping 0: J^+
FIXED_CUTOFFS = tuple(10.0 ** (-k / 4) for k in range(33))  # a step ignoring rcond
SWAP_HINT = ("\n  hint: J (m x n) = U Sigma V^T with U m x k and V n x k: U^T takes e (m entries) "
             "and V gives delta_theta (n entries), delta_theta = V Sigma^+ U^T e. U and V "
             "swapped? (np.linalg.svd returns U, sigma and V^T.)")
RELATIVE = ("the cut-off must be relative: drop sigma_i < rcond * sigma_max (the largest "
            "singular value), not sigma_i < rcond.")


def _singular_hand(rng):
    """The instant check's singular and ill-conditioned J: (J, e, rcond)."""
    return [
        (np.array([[0.0, 0.0], [3.0, 2.0]]), np.array([1.0, 0.5]), 1e-6),  # straight 2-link arm
        (np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([1.0, -1.0]), 1e-6),
        (_with_singular_values(rng, [1.0, 1e-9], 2, 3).round(12), np.array([0.3, 0.4]), 1e-6),
        (_with_singular_values(rng, [100.0, 1e-5], 2, 2), np.array([1.0, 1.0]), 1e-6),
        # a small J (sigma_max 5e-5): the cut-off is relative, the step is not zero (a guard
        # "sigma_max < 1e-4: zero step" loses the cut-off's marks here, in every draw)
        (_with_singular_values(rng, [5e-5, 5e-10], 2, 3), np.array([0.2, -0.1]), 1e-4),
        # sigma_min / sigma_max between 1e-5 and 0.1: rcond decides, on either side
        (_with_singular_values(rng, [1.0, 1e-3], 2, 3), np.array([0.5, -0.2]), 1e-6),
        (_with_singular_values(rng, [2.0, 0.06], 2, 2), np.array([0.3, 0.7]), 0.05),
        (_with_singular_values(rng, [1.0, 0.05, 1e-4], 3, 3), np.array([0.2, 0.1, -0.3]), 1e-2),
    ]


@_in_every_draw
def _pinv_cases(seed=None):
    rng = _rng(seed, 3)
    cases = []
    for k in range(10):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 6))
        J = _random_matrix(rng, m, n).round(4)
        e = rng.normal(size=m).round(3)
        cases.append(_Case((J, e, 1e-6), _matrix_text(J, e, ", rcond = 1e-06"),
                           size=m * n * 100 + 50 + k, tag="regular"))
    singular = _singular_hand(_rng(None, 30))  # the seed's own: the same turned
    if seed is not None:
        singular = _turned_hand(rng, singular)
    for k, (J, e, rcond) in enumerate(singular):
        s = np.linalg.svd(J, compute_uv=False)
        cases.append(_Case((J, e, rcond), _matrix_text(J, e, f", rcond = {rcond:g}")
                           + f" (singular values {_fmt(s)})", size=J.size * 100 + k,
                           tag="cutoff"))
    n = 3 if seed is None else int(rng.integers(3, 5))  # not square, as the instant check's
    J, e = np.zeros((2, n)), np.array([1.0, -0.5]) * (1 if seed is None else rng.normal())
    cases.append(_Case((J, e, 1e-6), _matrix_text(J, e, ", rcond = 1e-06") + " (J = 0: sigma_max = 0)",
                       size=J.size * 100, tag="zero"))
    return cases


def _pinv_variant(J, e, cut, swapped=False):
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    keep = cut(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    if swapped:
        return U @ (inv * (Vt @ e)) if U.shape[0] == Vt.shape[1] else None
    return Vt.T @ (inv * (U.T @ e))


def _relative(rcond):
    return lambda s: (s >= rcond * s.max()) & (s > 0)


def _fixed_cutoff(results):
    """The fixed relative cut-offs (a grid from 1 to 1e-8, 4 per decade) that give the
    student's step on every case of `results` ([(case, got)]), in words, or None. The cases
    cannot tell apart cut-offs between two of their singular value ratios: the message names
    the whole range, not one value of it."""
    fits = [c for c in FIXED_CUTOFFS
            if all(_close(np.abs(got), np.abs(_pinv_variant(*case.args[:2], _relative(c))))
                   for case, got in results)]
    if not fits:
        return None
    low, high = min(fits), max(fits)
    if low == high:
        return f"a fixed relative cut-off of {low:.2g}"
    return f"a fixed relative cut-off (any between {low:.2g} and {high:.2g} fits these cases)"


def _diagnose(got, want, case):
    """What is wrong with a step that is not J^+ e (nor -J^+ e)."""
    J, e, rcond = case.args
    detail = _mismatch(got, want, case)
    if not np.all(np.isfinite(got)):
        return ("NaN or inf at a singular J: 1/sigma for a tiny or zero sigma. "
                "Drop 1/sigma_i (use 0) for sigma_i < rcond * sigma_max." + detail)
    swapped = _pinv_variant(J, e, _relative(rcond), swapped=True)
    if swapped is not None and (_close(got, swapped) or _close(got, -swapped)):
        return ("U and V swapped: delta_theta = V Sigma^+ U^T e (np.linalg.svd returns U, "
                "sigma and V^T)." + detail)
    if not np.any(got) and np.linalg.norm(J, 2) < 1e-2:
        return ("your step is zero for a small J: the cut-off is relative, so J's largest "
                "singular values are kept however small (a guard at a fixed sigma_max?)." + detail)
    uncut = _pinv_variant(J, e, lambda s: s > 0)
    if _close(got, uncut, rtol=1e-4) and not _close(uncut, want, rtol=1e-4):
        return ("no cut-off: 1/sigma_i must be dropped for sigma_i < rcond * "
                f"sigma_max; here your step is {np.linalg.norm(got):.3g} long (np.linalg.pinv(J) "
                "keeps every sigma_i >= 1e-15 sigma_max)." + detail)
    if _close(got, _pinv_variant(J, e, lambda s: s >= rcond)):
        return RELATIVE + detail
    return ("wrong values: delta_theta = sum_i (u_i . e / sigma_i) v_i over the "
            "sigma_i kept by the cut-off." + detail)


def verdict(pinv_step, seed=None):
    """Verdict for exercise 3 without printing (`seed`: the grader's hidden cases)."""
    name, cases = FUNCTIONS[0], _pinv_cases(seed)
    answer = _answers(pinv_step, name)

    def result(case):
        try:
            return answer(case)
        except _Fail as exc:  # numpy's error for mismatched shapes: U and V swapped?
            shapes = ("mismatch in its core dimension", "not aligned", "shapes")
            if type(exc) is _Fail and any(word in str(exc) for word in shapes):
                raise _Fail(str(exc) + SWAP_HINT) from None
            raise

    def compared(tag, signed):
        """None, or the message of the first case of `tag` that fails (`signed`: the sign
        counts; otherwise -J^+ e passes too)."""
        for case in (c for c in cases if c.tag == tag):
            J, e, rcond = case.args
            got, want = result(case), case.want(_ref_pinv)
            if got.shape != want.shape:
                hint = (" - one entry per joint: delta_theta = V Sigma^+ U^T e"
                        if got.shape == e.shape else "")
                return _shape_message(name, got, want, case, hint)
            if _close(got, want) or (not signed and _close(got, -want)):
                continue
            if _close(got, -want):
                return "wrong sign: delta_theta = +J^+ e." + _mismatch(got, want, case)
            results = [(c, result(c)) for c in cases if c.tag == tag]
            if tag == "cutoff" and all(  # every case: sigma_i < rcond dropped
                    _close(np.abs(g), np.abs(_pinv_variant(*c.args[:2], lambda s, r=c.args[2]:
                                                            s >= r))) for c, g in results):
                return RELATIVE + _mismatch(got, want, case)
            fixed = _fixed_cutoff(results) if tag == "cutoff" else None
            if fixed is not None:
                return (f"your cut-off ignores `rcond`: on every case it drops what "
                        f"{fixed} drops; here rcond = {rcond:g}. Drop "
                        "sigma_i < rcond * sigma_max with the rcond passed in."
                        + _mismatch(got, want, case))
            if tag == "zero":
                return ("no guard for sigma_max = 0: for J = 0 every sigma_i is 0, so "
                        "rcond * sigma_max = 0 and `sigma_i >= rcond * sigma_max` keeps them "
                        "all - 1/0. Keep only sigma_i > 0 as well (the step is then zero)."
                        + _mismatch(got, want, case))
            return _diagnose(got, want, case)

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), [
        _Part("regular", 2, lambda: compared("regular", signed=False)),
        _Part("sign", 3, lambda: compared("regular", signed=True)),
        _Part("small sigma dropped", 3, lambda: compared("cutoff", signed=False)),
        _Part("sigma_max = 0 guard", 2, lambda: compared("zero", signed=False))])
