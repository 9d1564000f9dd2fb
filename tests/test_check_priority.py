"""ik.check.priority_step (exercise 7): the right step passes, each usual mistake is named."""
import numpy as np
import pytest

import ikteach as ik


def damped(A, lam):
    """V diag(sigma / (sigma^2 + lambda^2)) U^T, sigma ~ 0 dropped: finite at lambda = 0 too."""
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    keep = s > 1e-10 * max(s.max(initial=0.0), 1e-300)
    return Vt.T @ (np.where(keep, s / np.where(keep, s**2 + lam**2, 1.0), 0.0)[:, None] * U.T)


def literal_inverse(J1, e1, J2, e2, damping):
    """The formula as written, A^T (A A^T + lambda^2 I)^-1 with np.linalg.inv: right for
    damping > 0, LinAlgError at damping 0 where J1 is singular."""
    def inv_form(A):
        return A.T @ np.linalg.inv(A @ A.T + damping**2 * np.eye(A.shape[0]))
    first = inv_form(J1) @ e1
    N1 = projector(J1)
    return first + N1 @ inv_form(J2 @ N1) @ (e2 - J2 @ first)


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


def nan_at_zero_damping(J1, e1, J2, e2, damping):
    """Right for damping > 0; NaN at damping 0 where J1 is singular (1/sigma unguarded)."""
    step = correct(J1, e1, J2, e2, damping)
    singular = np.linalg.matrix_rank(J1) < J1.shape[0]
    return step * np.nan if damping == 0 and singular else step


def zero_when_undamped(J1, e1, J2, e2, damping):
    """Right for damping > 0; a zero step at damping 0 even where J1 has full row rank."""
    return correct(J1, e1, J2, e2, damping) if damping > 0 else np.zeros(J1.shape[1])


def primary_only(J1, e1, J2, e2, damping):
    return damped(J1, damping) @ e1


def not_yet(J1, e1, J2, e2, damping):
    raise NotImplementedError


def test_correct_step_gets_full_marks():
    verdict = ik.check.priority_step_verdict(correct)
    assert verdict.passed and verdict.score == 10, verdict.message


def test_module_step_gets_full_marks():
    verdict = ik.check.ex07_priority_step.verdict(lambda *a: np.asarray(ik.priority_step(*a)))
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


def lambda_not_squared(J1, e1, J2, e2, damping):
    """Both pseudoinverses damped with lambda I instead of lambda^2 I (exercise 4's slip)."""
    lam = np.sqrt(damping)
    first = damped(J1, lam) @ e1
    N1 = projector(J1)
    return first + N1 @ damped(J2 @ N1, lam) @ (e2 - J2 @ first)


def no_damping_at_all(J1, e1, J2, e2, damping):
    first = np.linalg.pinv(J1) @ e1
    N1 = projector(J1)
    return first + N1 @ np.linalg.pinv(J2 @ N1) @ (e2 - J2 @ first)


@pytest.mark.parametrize("seed", [None, 3])
@pytest.mark.parametrize("wrong, says, score", [
    (lambda_not_squared, "the damping term is lambda^2 I, not lambda I", 5),
    (no_damping_at_all, "no damping: your step uses exact pseudoinverses for damping > 0", 2),
])
def test_wrong_damping_is_named_not_a_disturbed_primary(wrong, says, score, seed):
    """lambda for lambda^2 keeps the primary (its own damping is wrong, not the projection);
    no damping at all blows up where J2 N1 is nearly singular, so it loses the primary too."""
    verdict = ik.check.priority_step_verdict(wrong, seed=seed)
    assert verdict.score == score and says in verdict.message, verdict.message
    assert "primary task is disturbed" not in verdict.message
    assert verdict.parts["no damping"]  # at damping 0 both are the exact step


def test_the_solution_form_is_finite_at_zero_damping():
    """The SVD form of `correct` is the solution's; at damping 0 it is the exact priority step."""
    J1, e1 = np.array([[1.0, 1.0, 0.0], [2.0, 2.0, 0.0]]), np.array([1.0, 0.5])
    J2, e2 = np.array([[0.0, 1.0, 1.0]]), np.array([0.5])
    step = correct(J1, e1, J2, e2, 0.0)
    assert np.all(np.isfinite(step))
    np.testing.assert_allclose(step, np.asarray(ik.priority_step(J1, e1, J2, e2, 0.0)), atol=1e-12)
    with pytest.raises(np.linalg.LinAlgError):
        literal_inverse(J1, e1, J2, e2, 0.0)


@pytest.mark.parametrize("wrong, says", [
    (literal_inverse, "at damping = 0 `priority_step` raised LinAlgError: Singular matrix"),
    (nan_at_zero_damping, "your step is NaN or inf at damping = 0 where J1 is singular"),
])
def test_undamped_singular_j1_loses_the_no_damping_points(wrong, says):
    """The formula as the text writes it, np.linalg.inv and all, is right for damping > 0 and
    loses exactly the no-damping part; the feedback says what it does there and what to do."""
    verdict = ik.check.priority_step_verdict(wrong)
    assert verdict.status == "failed" and verdict.score == 8, verdict.message
    assert not verdict.parts["no damping"] and all(v for k, v in verdict.parts.items() if k != "no damping")
    assert says in verdict.message, verdict.message
    assert "damping = 0 (no damping, singular: J1 = 0)" in verdict.message
    assert "np.linalg.pinv(A) at lambda = 0" in verdict.message


def test_zero_damping_is_tried_with_j1_of_full_row_rank_too():
    verdict = ik.check.priority_step_verdict(zero_when_undamped)
    assert verdict.score == 8 and not verdict.parts["no damping"], verdict.message
    assert verdict.message.split(" - ", 1)[1].startswith("at damping = 0: the primary task is disturbed")
    assert "(no damping, J1 of full row rank)" in verdict.message


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
