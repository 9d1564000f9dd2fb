"""Exercise 2: jt_step(J, e) -> alpha J^T e with Buss's optimal alpha.

Parts: direction (along J^T e, either way) 2, sign 3, alpha 3 (its size), zero step where
J J^T e = 0 2.
"""
import numpy as np

from ...core.jt import jt_step as _ref_jt
from .verdicts import (_answers, _Case, _close, _evaluate, _Fail, _in_every_draw, _matrix_text,
                       _mismatch, _Part, _rng, _shape_message, _turned_hand)

NUMBER = 2
CHECK_NAME = "jt_step"
TITLE = "the Jacobian-transpose step"
FUNCTIONS = ('jt_step',)
REFERENCES = ("ikteach.core.jt:jt_step",  # ikteach's answers, stubbed when graded
              "ikteach.core.jt:optimal_alpha")

HAND = [(np.eye(2), np.array([1.0, 0.0]), "regular"),
        (np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]), np.array([1.0, 1.0]), "regular"),
        (np.array([[1.0, 2.0], [0.5, -1.0]]), np.zeros(2), "zero"),
        (np.array([[1.0, 1.0], [0.0, 0.0]]), np.array([0.0, 1.0]), "zero"),
        (np.zeros((2, 3)), np.array([0.5, -0.5]), "zero")]


@_in_every_draw
def _jt_cases(seed=None):
    rng = _rng(seed, 2)
    cases = [_Case((J, e), _matrix_text(J, e), size=J.size * 100 + k, tag=tag) for k, (J, e, tag)
             in enumerate(HAND if seed is None else _turned_hand(rng, HAND))]
    for k in range(12):
        m = int(rng.integers(2, 4))
        n = int(rng.integers(1, 6))
        J = rng.normal(size=(m, n)).round(3)
        e = rng.normal(size=m).round(3)
        cases.append(_Case((J, e), _matrix_text(J, e), size=m * n * 100 + 50 + k, tag="regular"))
    return cases


def verdict(jt_step, seed=None):
    """Verdict for exercise 2 without printing (`seed`: the grader's hidden cases)."""
    name, cases = FUNCTIONS[0], _jt_cases(seed)
    result = _answers(jt_step, name)

    def coefficient(case):
        """(c, along) with got = c J^T e when `along`."""
        J, e = case.args
        got, g = result(case), J.T @ e
        if got.shape != g.shape:
            raise _Fail(_shape_message(name, got, g, case, " - one entry per joint"))
        if not np.all(np.isfinite(got)):
            raise _Fail(f"your step contains NaN or inf.{_mismatch(got, case.want(_ref_jt), case)}")
        c = float(got @ g / (g @ g))
        return c, _close(got, c * g)

    regular = [c for c in cases if c.tag == "regular"]

    def direction():
        for case in regular:
            c, along = coefficient(case)
            if not along:
                return ("your step does not point along J^T e: the Jacobian-transpose step is "
                        "delta_theta = alpha J^T e."
                        + _mismatch(result(case), case.want(_ref_jt), case))

    def sign():
        for case in regular:
            c, along = coefficient(case)
            if not along:
                return "your step is not alpha J^T e, so its sign cannot be checked yet."
            if c < 0:
                return ("wrong sign: the step must go along +J^T e (downhill on 1/2 |e|^2), "
                        "with alpha > 0." + _mismatch(result(case), case.want(_ref_jt), case))

    def alpha():
        found = []
        for case in regular:
            c, along = coefficient(case)
            if not along:
                return "your step is not alpha J^T e, so alpha cannot be checked yet."
            J, e = case.args
            v = J @ (J.T @ e)
            found.append((case, abs(c), float(e @ v / (v @ v))))  # size: the sign is its own part
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
            got, want = result(case), case.want(_ref_jt)
            if got.shape != want.shape:
                return _shape_message(name, got, want, case, " - one entry per joint")
            if not np.all(np.isfinite(got)):
                return ("NaN where J J^T e = 0 (e = 0, or e orthogonal to every column of J): "
                        "alpha = 0/0 there. Return a zero step in that case."
                        + _mismatch(got, want, case))
            if not _close(got, want):
                return ("where J J^T e = 0 the step must be zero." + _mismatch(got, want, case))

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), [
        _Part("direction", 2, direction), _Part("sign", 3, sign), _Part("alpha", 3, alpha),
        _Part("zero", 2, zero)])
