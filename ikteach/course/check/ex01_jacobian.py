"""Exercise 1: planar_jacobian(lengths, theta) -> J (2, n), column i = z x (p_e - p_i).

Parts: shape 2, lever arms 4 (every column right up to its sign), sign 2, singular
configurations 2 - so a sign slip keeps the lever arms' marks, a wrong lever arm does not.
"""
import numpy as np

from ...core.chain import planar_chain
from ...core.jacobian import jacobian as _ref_jacobian
from .verdicts import (_answers, _Case, _close, _evaluate, _Fail, _fmt, _in_every_draw,
                       _mismatch, _Part, _rng, _shape_message)

NUMBER = 1
CHECK_NAME = "jacobian"
TITLE = "the geometric Jacobian"
FUNCTIONS = ("planar_jacobian",)
REFERENCES = ("ikteach.core.jacobian:jacobian",  # ikteach's answers, stubbed when graded
              "ikteach.core.jacobian:jacobian_from_frames",
              "ikteach.core.jacobian:jacobian_autodiff",
              "ikteach.core.jacobian:jacobian_fd",
              "ikteach.core.tree:tree_jacobian",
              "ikteach.core.tree:tree_jacobian_from_frames",
              "ikteach.core.tree:tree_jacobian_autodiff",
)


# the singular arms point off the x axis (base angle != 0): lying along x, row 0 of J is zero
# there and a slip in row 0 alone would pass them (the hidden cases draw the base angle)
HAND = [([1.0], [0.0], "regular"), ([1.0, 1.0], [0.5, 0.0], "singular"),
        ([1.0, 1.0], [-0.4, np.pi], "singular"), ([1.0, 2.0], [0.3, 0.5], "regular"),
        ([1.0, 1.0, 1.0], [1.2, 0.0, 0.0], "singular")]


def _hidden_hand(rng):
    """HAND turned: the base angle drawn, the lengths scaled by a power of 2 (the joint angles
    that make an arm straight or folded kept)."""
    return [((np.array(L) * 2.0 ** float(rng.choice([-1, 1]))).tolist(),
             [round(float(rng.uniform(-np.pi, np.pi)), 3)] + t[1:], tag) for L, t, tag in HAND]


@_in_every_draw
def _jacobian_cases(seed=None):
    rng = _rng(seed, 0)
    cases = list(HAND if seed is None else _hidden_hand(rng))
    for _ in range(12):
        n = int(rng.integers(1, 6))
        cases.append((rng.uniform(0.5, 1.5, n).round(3).tolist(),
                      rng.uniform(-np.pi, np.pi, n).round(3).tolist(), "regular"))
    return [_Case((lengths, np.array(theta)), f"lengths = {_fmt(lengths)}, theta = {_fmt(theta)}",
                  size=len(lengths) * 100 + k, tag=tag)
            for k, (lengths, theta, tag) in enumerate(cases)]


def _jacobian_reference(lengths, theta):
    return np.asarray(_ref_jacobian(planar_chain(lengths), np.asarray(theta, dtype=float)))


def _diagnose_jacobian(got, want, case):
    detail = _mismatch(got, want, case, "J")
    if not np.all(np.isfinite(got)):
        return "your Jacobian contains NaN or inf." + detail
    if _close(got, -want):
        return ("wrong sign: your Jacobian is -1 x the expected one. Column i is "
                "z_i x (p_e - p_i) = z x (p_e - p_i) = (-(y_e - y_i), x_e - x_i)." + detail)
    for row, other, what in ((0, 1, "row 0 (x) is -(y_e - y_i)"), (1, 0, "row 1 (y) is x_e - x_i")):
        if _close(got[row], -want[row], scale=np.abs(want).max()) and _close(
                got[other], want[other], scale=np.abs(want).max()):
            return (f"row {row} has the wrong sign (the other row is right): z x (p_e - p_i) = "
                    f"(-(y_e - y_i), x_e - x_i), so {what}." + detail)
    if _close(got, want[:, ::-1]):
        return ("the columns are in reverse order: column i belongs to joint i (J[:, 0] is "
                "joint 1, at the base)." + detail)
    if _close(got, want[::-1]):
        return "rows swapped: row 0 is dx, row 1 is dy." + detail
    return ("wrong values: column i should be z x (p_e - p_i), p_i the position of joint i "
            "(p_1 = the base = row 0 of ik.joint_positions), p_e the end effector." + detail)


def _columns_up_to_sign(got, want):
    """Every column equals the expected one or its negative (lever arm right, sign aside)."""
    scale = np.abs(want).max(initial=0.0)  # the case's, not each column's: as in _close
    return got.shape == want.shape and bool(np.all(np.isfinite(got))) and all(
        _close(g, w, scale=scale) or _close(g, -w, scale=scale) for g, w in zip(got.T, want.T))


def verdict(planar_jacobian, seed=None):
    """Verdict for exercise 1 without printing (`seed`: the grader's hidden cases)."""
    name, cases = FUNCTIONS[0], _jacobian_cases(seed)
    result = _answers(planar_jacobian, name)

    def compared(tag):
        """(case, got, want) of the cases with `tag`, shapes checked first."""
        for case in (c for c in cases if c.tag == tag):
            got, want = result(case), case.want(_jacobian_reference)
            if got.shape != want.shape:
                raise _Fail(_shape_message(name, got, want, case))
            yield case, got, want

    def shape():
        for case in cases:
            got, want = result(case), case.want(_jacobian_reference)
            if got.shape != want.shape:
                hint = (" - one row per coordinate (x, y), one column per joint: transposed?"
                        if got.shape == want.T.shape else " - (2, number of joints)")
                return _shape_message(name, got, want, case, hint)

    def lever_arms():
        for case, got, want in compared("regular"):
            if not _columns_up_to_sign(got, want):
                return _diagnose_jacobian(got, want, case)

    def sign():
        for case, got, want in compared("regular"):
            if not _close(got, want):
                return _diagnose_jacobian(got, want, case)

    def singular():
        for case, got, want in compared("singular"):
            if not _close(got, want):
                return ("at a singular configuration (arm straight or folded): "
                        + _diagnose_jacobian(got, want, case))

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), [
        _Part("shape", 2, shape), _Part("lever arms", 4, lever_arms), _Part("sign", 2, sign),
        _Part("singular", 2, singular)])
