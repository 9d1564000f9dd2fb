"""ik.check.priority_step (exercise 7): the right step passes, each usual mistake is named."""
import numpy as np
import pytest

import ikteach as ik


def damped(A, lam):
    return A.T @ np.linalg.solve(A @ A.T + lam**2 * np.eye(A.shape[0]), np.eye(A.shape[0]))


def projector(A):
    return np.eye(A.shape[1]) - np.linalg.pinv(A) @ A


def correct(J1, e1, J2, e2, damping):
    first = damped(J1, damping) @ e1
    N1 = projector(J1)
    return first + N1 @ damped(J2 @ N1, damping) @ (e2 - J2 @ first)


def not_projected(J1, e1, J2, e2, damping):
    first = damped(J1, damping) @ e1
    return first + damped(J2, damping) @ (e2 - J2 @ first)


def projector_from_j2(J1, e1, J2, e2, damping):
    first = damped(J1, damping) @ e1
    N2 = projector(J2)
    return first + N2 @ damped(J2 @ N2, damping) @ (e2 - J2 @ first)


def undamped_inverse(J1, e1, J2, e2, damping):
    first = J1.T @ np.linalg.inv(J1 @ J1.T) @ e1  # singular J1 -> error or inf
    N1 = projector(J1)
    return first + N1 @ damped(J2 @ N1, damping) @ (e2 - J2 @ first)


def pinv_no_damping(J1, e1, J2, e2, damping):
    first = np.linalg.pinv(J1) @ e1
    N1 = projector(J1)
    return first + N1 @ damped(J2 @ N1, damping) @ (e2 - J2 @ first)


def forgot_primary_motion(J1, e1, J2, e2, damping):
    first = damped(J1, damping) @ e1
    N1 = projector(J1)
    return first + N1 @ damped(J2 @ N1, damping) @ e2


def projected_after(J1, e1, J2, e2, damping):
    first = damped(J1, damping) @ e1
    return first + projector(J1) @ damped(J2, damping) @ (e2 - J2 @ first)


def nan_at_singular(J1, e1, J2, e2, damping):
    """Right wherever J1 has full row rank; NaN where it is singular (an unguarded division)."""
    step = correct(J1, e1, J2, e2, damping)
    return step if np.linalg.matrix_rank(J1) == J1.shape[0] else step * np.nan


def primary_only(J1, e1, J2, e2, damping):
    return damped(J1, damping) @ e1


def not_yet(J1, e1, J2, e2, damping):
    raise NotImplementedError


def test_correct_step_gets_full_marks():
    verdict = ik.check.priority_step_verdict(correct)
    assert verdict.passed and verdict.score == 10, verdict.message


def test_module_step_gets_full_marks():
    verdict = ik.check.priority_step_verdict(lambda *a: np.asarray(ik.priority_step(*a)))
    assert verdict.passed and verdict.score == 10, verdict.message


@pytest.mark.parametrize("wrong, says", [
    (not_projected, "not projected"),
    (projector_from_j2, "Projector built from J2?"),
    (pinv_no_damping, "missing damping on J1+"),
    (undamped_inverse, "missing damping on J1+"),
    (forgot_primary_motion, "e2 - J2 J1+ e1, not e2"),
    (projected_after, "use (J2 N1)+"),
    (nan_at_singular, "NaN or inf"),
    (primary_only, "ignores the secondary task"),
    (projector_from_j2, "ignores the secondary task"),
])
def test_each_mistake_is_diagnosed(wrong, says):
    verdict = ik.check.priority_step_verdict(wrong)
    assert verdict.status == "failed" and verdict.score < 10
    assert says in verdict.message, verdict.message
    assert "smallest failing case" in verdict.message


def test_projector_from_j2_keeps_the_primary_points_only():
    """Graded by parts: the primary is untouched (3 points), the rest is wrong."""
    verdict = ik.check.priority_step_verdict(projector_from_j2)
    assert verdict.score == 3 and verdict.parts["primary kept"]


def test_not_implemented_and_not_a_function():
    assert ik.check.priority_step_verdict(not_yet).status == "not implemented"
    verdict = ik.check.priority_step_verdict(None)
    assert verdict.status == "failed" and "expected your function" in verdict.message


def test_registered_for_the_grader():
    namespace = {"priority_step": correct}
    assert ik.check.grade(7, namespace).score == 10
    assert ik.check.EXERCISES[7].FUNCTIONS == ("priority_step",)
