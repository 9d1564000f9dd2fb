"""The instant check and the grader agree (issue 40): each kind of attempt seen in the exercise
feedback gets the same marks from the check cell (the instant cases) as from the grader's
hidden cases under every draw, and its message names the actual mistake. (Calls of ikteach's
own answer: test_check.py for the instant check, test_reference_rule.py for the grader.)"""
import numpy as np
import pytest

import ikteach as ik
from ikteach.course import check


def jacobian(lengths, theta):
    p = np.asarray(ik.joint_positions(ik.planar_chain(lengths), theta))
    d = p[-1] - p[:-1]
    return np.stack([-d[:, 1], d[:, 0]])


def row_0_sign_slip(lengths, theta):
    J = jacobian(lengths, theta)
    return np.stack([-J[0], J[1]])


def pinv_cut(cutoff=None, guard=True):
    def pinv_step(J, e, rcond):
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = s >= (rcond if cutoff is None else cutoff) * s.max()
        if guard:
            keep &= s > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            return Vt.T @ (np.where(keep, 1 / np.where(keep, s, 1), 0) * (U.T @ e))
    return pinv_step


def dls_m(J, e, damping):
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(J.shape[0]), e)


def dls_n(J, e, damping):
    return np.linalg.solve(J.T @ J + damping**2 * np.eye(J.shape[1]), J.T @ e)


def rule(size, scaled=True):
    def stalled(delta_theta, lengths, fraction):
        return bool(size(np.asarray(delta_theta)) < fraction * (np.sum(lengths) if scaled else 1))
    return stalled


def wrapping(stalled):
    def stop_rule_step(step, lengths, fraction):
        def wrapped(J, e):
            delta = np.asarray(step(J, e))
            if stalled(delta, lengths, fraction):
                raise ik.StopSolve("stalled")
            return delta
        return wrapped
    return stop_rule_step


def sum_abs(d):
    return np.abs(d).sum()


# (exercise, functions, marks, words of the message)
ATTEMPTS = {
    "ex 1 right": (1, [jacobian], 10, "passed"),
    "ex 1 a sign slip in row 0 only": (1, [row_0_sign_slip], 2, "row 0 has the wrong sign"),
    "ex 3 right": (3, [pinv_cut()], 10, "passed"),
    "ex 3 a fixed cut-off of 1e-3": (3, [pinv_cut(1e-3)], 7, "ignores `rcond`"),
    "ex 3 no guard for sigma_max = 0": (3, [pinv_cut(guard=False)], 8, "no guard for sigma_max"),
    "ex 4 both forms": (4, [dls_m, dls_n], 10, "passed"),
    "ex 4 the n x n form twice": (4, [dls_n, dls_n], 8, "the m x m solve"),
    "ex 4 without damping": (4, [lambda J, e, d: np.linalg.pinv(J) @ e] * 2, 2,
                             "the damping is missing"),
    "ex 5 right": (5, [rule(sum_abs), wrapping(rule(sum_abs))], 10, "passed"),
    "ex 5 a threshold without the link lengths": (
        5, [rule(sum_abs, scaled=False), wrapping(rule(sum_abs, scaled=False))], 0,
        "proportional to the link lengths"),
    "ex 5 a 2-norm instead of the sum": (
        5, [rule(np.linalg.norm), wrapping(rule(np.linalg.norm))], 0, "not their 2-norm"),
}


@pytest.mark.parametrize("attempt", sorted(ATTEMPTS))
def test_the_check_cell_and_the_grader_give_the_same_marks(attempt):
    number, functions, marks, words = ATTEMPTS[attempt]
    module = check.EXERCISES[number]
    instant = getattr(check, f"{module.CHECK_NAME}_verdict")(*functions)
    assert instant.score == marks and words in instant.message, instant.message
    namespace = dict(zip(module.FUNCTIONS, functions))
    for seed in (1, 2, 3, 2**40 + 11):
        hidden = check.grade(number, namespace, seed=seed)
        assert hidden.score == marks and words in hidden.message, (seed, hidden.message)
