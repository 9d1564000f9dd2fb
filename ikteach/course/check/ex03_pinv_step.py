"""Exercise 3: pinv_step(J, e, rcond) -> J^+ e by the SVD with a relative cut-off.

Parts: regular J 5, the cut-off at singular J 3, J = 0 (sigma_max = 0: nothing is kept) 2.
"""
import numpy as np

from ...core.pinv import pinv_step as _ref_pinv
from .verdicts import (SEED, _Case, _Part, _as_array, _call, _close, _evaluate, _fmt, _guarded,
                       _matrix_text, _mismatch, _report, _shape_message, _random_matrix,
                       _with_singular_values)

NUMBER = 3
CHECK_NAME = "pinv_step"
TITLE = "the pseudoinverse step"
FUNCTIONS = ('pinv_step',)
# ikteach's own answer to this exercise: blocked (raises) while a student's code is graded
REFERENCES = ("ikteach.core.pinv:pinv_step", "ikteach.core.pinv:pinv_two_rows")

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
    J, e = np.zeros((2, 3)), np.array([1.0, -0.5])
    cases.append(_Case((J, e, 1e-6), _matrix_text(J, e, ", rcond = 1e-06") + " (J = 0: sigma_max = 0)",
                       size=J.size * 100, tag="zero"))
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

    def zero():
        for case in (c for c in cases if c.tag == "zero"):
            J, e, rcond = case.args
            got = _as_array(_call(fn, name, case, J.copy(), e.copy(), rcond), name, case)
            want = np.asarray(_ref_pinv(J, e, rcond))
            if got.shape != want.shape:
                return _shape_message(name, got, want, case, " - one entry per joint")
            if not _close(got, want):
                return ("no guard for sigma_max = 0: for J = 0 every sigma_i is 0, so "
                        "rcond * sigma_max = 0 and `sigma_i >= rcond * sigma_max` keeps them "
                        "all - 1/0. Keep only sigma_i > 0 as well (the step is then zero)."
                        + _mismatch(got, want, case))

    return [_Part("regular", 5, run("regular")), _Part("cut-off", 3, run("cutoff")),
            _Part("J = 0", 2, zero)]


def verdict(pinv_step):
    """Verdict for exercise 3 without printing."""
    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), _guarded(pinv_step, FUNCTIONS[0], _pinv_parts))


def check(pinv_step):
    """Exercise 3: check pinv_step(J, e, rcond) -> J^+ e by the SVD with a relative cut-off."""
    _report(verdict(pinv_step))
