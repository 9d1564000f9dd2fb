"""ik.check: the verdicts on right and wrong student functions (no kernels: direct calls)."""
import re

import numpy as np
import pytest

import ikteach as ik
from ikteach.course import check


def planar_jacobian(lengths, theta):
    p = np.asarray(ik.joint_positions(ik.planar_chain(lengths), theta))
    d = p[-1] - p[:-1]
    return np.stack([-d[:, 1], d[:, 0]])


def jt_step(J, e):
    g = J.T @ e
    v = J @ g
    return np.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g


def pinv_no_cutoff(J, e, rcond):
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    keep = s > 0
    inv = np.zeros_like(s)
    inv[keep] = 1 / s[keep]
    return Vt.T @ (inv * (U.T @ e))


def stalled(delta_theta, lengths, fraction):
    return bool(np.sum(np.abs(delta_theta)) < fraction * np.sum(lengths))


def stop_rule_step(step, lengths, fraction):
    def wrapped(J, e):
        delta = np.asarray(step(J, e))
        if stalled(delta, lengths, fraction):
            raise ik.StopSolve()
        return delta
    return wrapped


def wrong_lever_arm(lengths, theta):
    """Column i from the next joint's position (p_{i+1}) instead of p_i."""
    p = np.asarray(ik.joint_positions(ik.planar_chain(lengths), theta))
    d = p[-1] - p[1:]
    return np.stack([-d[:, 1], d[:, 0]])


def not_yet(*args):
    raise NotImplementedError


def test_correct_functions_pass():
    assert check.jacobian_verdict(planar_jacobian).score == 10
    assert check.jt_step_verdict(jt_step).passed
    # ikteach's own answers pass the checks themselves (ik.check.<name>_verdict gives them 0,
    # as the grader does: test_a_wrapper_of_ikteachs_answer_is_told_what_the_grader_gives)
    assert check.ex03_pinv_step.verdict(lambda J, e, r: np.asarray(ik.pinv_step(J, e, r))).passed
    assert check.ex04_dls_step.verdict(ik.dls_step, ik.dls_step_normal).passed


@pytest.mark.parametrize("wrong, score, words", [
    (lambda L, t: -planar_jacobian(L, t), 6, "wrong sign"),  # lever arms right: 6 of 10
    (lambda L, t: wrong_lever_arm(L, t), 2, "wrong values"),
    (lambda L, t: planar_jacobian(L, t).T, 0, "transposed"),
    (lambda L, t: planar_jacobian(L, t)[:, ::-1], 2, "reverse order"),
    (lambda L, t: None, 0, "forget `return`"),
    (lambda L, t: "J", 0, "expected an array of numbers"),
    (lambda L, t: 1 / 0, 0, "raised ZeroDivisionError"),
])
def test_jacobian_mistakes(wrong, score, words):
    verdict = check.jacobian_verdict(wrong)
    assert verdict.score == score and verdict.status == "failed"
    assert words in verdict.message


def test_the_smallest_failing_case_is_shown():
    message = check.jacobian_verdict(lambda L, t: -planar_jacobian(L, t)).message
    assert "smallest failing case: lengths = [1.], theta = [0.]" in message
    message = check.jacobian_verdict(lambda L, t: planar_jacobian(L, t)[:, ::-1]).message
    assert "smallest failing case: lengths = [1., 2.]" in message  # 1 joint cannot show it


@pytest.mark.parametrize("wrong, score, words", [
    (lambda J, e: 0.1 * (J.T @ e), 7, "alpha looks fixed: it is 0.1"),
    (lambda J, e: 2 * jt_step(J, e), 7, "off by a factor of 2"),
    (lambda J, e: -jt_step(J, e), 7, "wrong sign"),  # direction and alpha's size are right
])
def test_jt_mistakes(wrong, score, words):
    verdict = check.jt_step_verdict(wrong)
    assert (verdict.score, verdict.status) == (score, "failed")
    assert words in verdict.message


def test_jt_nan_at_zero_error_is_named():
    def naive(J, e):
        g = J.T @ e
        v = J @ g
        return (e @ v / (v @ v)) * g
    verdict = check.jt_step_verdict(naive)
    assert verdict.score == 8 and "NaN where J J^T e = 0" in verdict.message


def test_pinv_without_cutoff():
    verdict = check.pinv_step_verdict(pinv_no_cutoff)
    assert verdict.score == 7 and "no cut-off" in verdict.message  # J = 0 still gives 0
    plain = check.pinv_step_verdict(
        lambda J, e, r: np.linalg.svd(J, full_matrices=False)[2].T
        @ ((np.linalg.svd(J, full_matrices=False)[0].T @ e) / np.linalg.svd(J, compute_uv=False)))
    assert plain.score == 5 and "NaN or inf at a singular J" in plain.message


def test_pinv_without_a_guard_for_a_zero_jacobian():
    """sigma >= rcond * sigma_max keeps every sigma when J = 0 (0 >= 0): 1/0, NaN."""
    def unguarded(J, e, rcond):
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = s >= rcond * s[0]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(keep, 1 / s, 0)
        return Vt.T @ (inv * (U.T @ e))
    verdict = check.pinv_step_verdict(unguarded)
    assert verdict.score == 8 and "no guard for sigma_max = 0" in verdict.message
    assert verdict.parts == {"regular": True, "sign": True, "small sigma dropped": True,
                             "sigma_max = 0 guard": False}


def test_pinv_absolute_cutoff():
    def absolute(J, e, rcond):
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        inv = np.where(s >= rcond, 1 / np.where(s >= rcond, s, 1), 0)
        return Vt.T @ (inv * (U.T @ e))
    verdict = check.pinv_step_verdict(absolute)
    assert verdict.score == 7 and "must be relative" in verdict.message


def pinv_fixed_cutoff(cutoff):
    """A pinv_step that ignores rcond: a fixed relative cut-off (np.linalg.pinv's is 1e-15)."""
    def step(J, e, rcond):
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = (s >= cutoff * s.max(initial=0.0)) & (s > 0)
        return Vt.T @ (np.where(keep, 1 / np.where(keep, s, 1), 0) * (U.T @ e))
    return step


@pytest.mark.parametrize("seed", [None, 1, 2, 3])
@pytest.mark.parametrize("cutoff", [1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
def test_pinv_ignoring_rcond_loses_the_cutoff_points(seed, cutoff):
    """Cases with sigma_min / sigma_max between 1e-5 and 0.1 and rcond on either side: a
    fixed cut-off keeps what rcond drops or drops what it keeps - in the instant check and in
    every draw of the hidden cases."""
    verdict = check.pinv_step_verdict(pinv_fixed_cutoff(cutoff), seed=seed)
    assert verdict.score == 7 and not verdict.parts["small sigma dropped"], verdict.message
    assert "ignores `rcond`: on every case it drops what a fixed relative cut-off" \
        in verdict.message, verdict.message
    said = verdict.message.split("fixed relative cut-off")[1].split(" drops;")[0]
    low, high = (float(x) for x in re.findall(r"\d\.?\d*e-\d+|0\.\d+|\b1\b", said)[-2:]) \
        if "between" in said else (float(said.split("of ")[1]),) * 2
    assert low * 0.99 <= cutoff <= high * 1.01, (cutoff, said)  # the student's, not a neighbour


def test_np_linalg_pinv_is_told_it_has_no_cutoff():
    verdict = check.pinv_step_verdict(lambda J, e, rcond: np.linalg.pinv(J) @ e)
    assert verdict.score == 7 and "no cut-off" in verdict.message
    assert "np.linalg.pinv(J) keeps every sigma_i >= 1e-15 sigma_max" in verdict.message


def test_pinv_with_u_and_v_swapped_gets_a_hint_not_only_numpys_error():
    def swapped(J, e, rcond):
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        keep = (s >= rcond * s[0]) & (s > 0)
        return U @ (np.where(keep, 1 / np.where(keep, s, 1), 0) * (Vt @ e))
    verdict = check.pinv_step_verdict(swapped)
    assert verdict.score == 0, verdict.message
    assert "mismatch in its core dimension" in verdict.message  # what numpy said, and then
    assert "hint: J (m x n) = U Sigma V^T" in verdict.message and "U and V swapped?" in verdict.message
    square = check.ex03_pinv_step.verdict(
        lambda J, e, r: swapped(J, e, r) if J.shape[0] == J.shape[1]
        else np.asarray(ik.pinv_step(J, e, r)))
    assert square.score < 10 and "U and V swapped: delta_theta = V Sigma^+ U^T e" in square.message


@pytest.mark.parametrize("seed", [None, 5])
def test_a_sign_slip_costs_the_same_in_exercises_2_and_3(seed):
    jt = check.jt_step_verdict(lambda J, e: -jt_step(J, e), seed=seed)
    pinv = check.ex03_pinv_step.verdict(lambda J, e, r: -np.asarray(ik.pinv_step(J, e, r)),
                                        seed=seed)
    assert jt.score == pinv.score == 7, (jt.message, pinv.message)
    assert "wrong sign" in jt.message and "wrong sign" in pinv.message
    assert not jt.parts["sign"] and not pinv.parts["sign"]


def test_dls_lambda_not_squared_and_partial_credit():
    lam = lambda J, e, l: J.T @ np.linalg.solve(J @ J.T + l * np.eye(J.shape[0]), e)
    verdict = check.ex04_dls_step.verdict(lam, ik.dls_step_normal)
    assert verdict.score == 4 and "missing square on lambda" in verdict.message
    assert "your two forms disagree" not in verdict.message  # the first failure is shown
    assert verdict.parts == {"dls_step": False, "dls_step_normal": True, "both forms": False}


def dls_m(J, e, damping):
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(J.shape[0]), e)


def dls_n(J, e, damping):
    return np.linalg.solve(J.T @ J + damping**2 * np.eye(J.shape[1]), J.T @ e)


@pytest.mark.parametrize("seed", [None, 1, 2])
@pytest.mark.parametrize("forms, score, words", [
    ((dls_m, dls_n), 10, "passed"),
    ((dls_n, dls_n), 8, "`dls_step` is not J^T (J J^T + lambda^2 I)^-1 e, the m x m solve"),
    ((dls_m, dls_m), 8, "`dls_step_normal` is not (J^T J + lambda^2 I)^-1 J^T e"),
    ((lambda J, e, d: dls_m(J, e, 0.0), lambda J, e, d: dls_n(J, e, 0.0)), 0,
     "the damping is missing"),
    ((lambda J, e, d: np.linalg.pinv(J) @ e,) * 2, 2, "the damping is missing"),
])
def test_dls_forms_and_missing_damping_are_named(forms, score, words, seed):
    """Both forms are checked as forms (at damping 0 only one of them is defined), and a step
    without damping is told so, whatever its first failing case does (NaN, LinAlgError)."""
    verdict = check.ex04_dls_step.verdict(*forms, seed=seed)
    assert verdict.score == score and words in verdict.message, verdict.message


def test_not_implemented_is_not_an_error(capsys):
    check.jacobian(not_yet)
    out = capsys.readouterr().out
    assert "not yet implemented" in out and "Traceback" not in out
    assert check.dls_step_verdict(not_yet, not_yet).status == "not implemented"
    half = check.ex04_dls_step.verdict(ik.dls_step, not_yet)
    assert half.status == "failed" and half.score == 4
    assert check.singularity_study_verdict(not_yet).status == "not implemented"


def test_endless_loop_is_stopped(monkeypatch):
    monkeypatch.setattr(check.verdicts, "TIME_LIMIT", 0.3)

    def forever(J, e):
        while True:
            try:
                pass
            except Exception:  # student code that swallows errors does not swallow the limit
                pass
    verdict = check.jt_step_verdict(forever)
    assert verdict.score == 0 and "did not return within 0.3 s" in verdict.message


def test_messages_show_the_students_line_not_ikteach_internals():
    def broken(J, e):
        return J @ e  # wrong product
    message = check.jt_step_verdict(broken).message
    assert "raised ValueError" in message and "J @ e  # wrong product" in message
    assert "ikteach/" not in message and "Traceback" not in message


def test_stop_rule():
    assert check.stop_rule_verdict(stalled, stop_rule_step).passed
    signed = check.stop_rule_verdict(lambda d, L, f: np.sum(d) < f * np.sum(L), stop_rule_step)
    assert signed.score == 5 and "absolute values" in signed.message
    unscaled = check.stop_rule_verdict(lambda d, L, f: np.abs(d).sum() < f, stop_rule_step)
    assert "proportional to the link lengths" in unscaled.message
    for wrong_rule, words in [
            (lambda d, L, f: np.abs(d).sum() <= f * np.sum(L), "use a strict <"),
            (lambda d, L, f: np.abs(d).sum() < f * np.max(L), "not the longest link"),
            (lambda d, L, f: np.abs(d).max() < f * np.sum(L), "not their largest"),
            (lambda d, L, f: np.abs(d).sum() >= f * np.sum(L), "inverted")]:
        verdict = check.stop_rule_verdict(wrong_rule, stop_rule_step)
        assert verdict.score == 5 and words in verdict.message, verdict.message
    never_stops = check.stop_rule_verdict(stalled, lambda step, L, f: step)
    assert never_stops.score == 5 and "raise ik.StopSolve" in never_stops.message


def test_singularity_study_answers_checked_by_value():
    reference = check.ex06_singularity_study._reference_study()
    assert reference["blows_up"] == ["pinv"]
    right = check.singularity_study_verdict(lambda jt, pinv, dls: dict(reference))
    assert right.passed
    wrong = dict(reference, smallest_lambda=0.2, fewest_iterations="jt")
    verdict = check.singularity_study_verdict(lambda jt, pinv, dls: wrong)
    assert verdict.score == 5
    assert "'fewest_iterations' is not right" in verdict.message
    assert verdict.parts["smallest_lambda"] is False
    assert "must return a dict" in check.singularity_study_verdict(lambda *a: 3).message


def jacobian_from_ikteach(lengths, theta):
    return np.asarray(ik.jacobian(ik.planar_chain(lengths), theta))


@pytest.mark.parametrize("number, functions, reference", [
    (1, [jacobian_from_ikteach], "ikteach.core.jacobian.jacobian"),
    (1, [lambda L, t: ik.jacobian(ik.planar_chain(L), t)], "ikteach.core.jacobian.jacobian"),
    (2, [ik.jt_step], "ikteach.core.jt.jt_step"),
    (3, [lambda J, e, r: ik.pinv_step(J, e, r)], "ikteach.core.pinv.pinv_step"),
    (4, [ik.dls_step, lambda J, e, l: np.asarray(ik.dls_step_normal(J, e, l))],
     "ikteach.core.dls.dls_step"),
    (7, [lambda *a: ik.priority_step(*a)], "ikteach.core.priority.priority_step"),
])
def test_a_wrapper_of_ikteachs_answer_is_told_what_the_grader_gives(number, functions,
                                                                     reference, capsys):
    """The instant check says what the grader will: 0, because the grader's sandbox has
    ikteach's own answer only as a stub that raises (grading/reference.py)."""
    module = check.EXERCISES[number]
    assert module.verdict(*functions).passed  # right answers, but not the student's own
    verdict = getattr(check, f"{module.CHECK_NAME}_verdict")(*functions)
    assert verdict.score == 0 and f"calls ikteach's own answer to this exercise ({reference})" \
        in verdict.message, verdict.message
    assert "raised ReferenceBlocked: your code calls" in verdict.message
    assert "which raises ReferenceBlocked in the grader" in verdict.message
    getattr(check, module.CHECK_NAME)(*functions)
    assert capsys.readouterr().out.strip() == verdict.message


def jt_imported_inside(J, e):
    from ikteach.core.jt import jt_step as step  # a function-level import
    return np.asarray(step(J, e))


def jt_by_getattr(J, e):
    return np.asarray(getattr(ik, "jt_step")(J, e))


def dls_by_method_object(J, e, damping):
    return np.asarray(ik.DLS(damping=damping).step(J, e))  # runs damped_step, then dls_step_small


def dls_by_method_table(J, e, damping):
    return np.asarray(ik.core.methods.METHODS["dls"](damping=damping).step(J, e))


class MyDLS(ik.DLS):  # a student's subclass of the method object
    pass


def priority_from_lecture_parts(J1, e1, J2, e2, damping):
    N1 = np.asarray(ik.null_projector(J1))
    first = np.asarray(ik.damped_pinv(J1, damping)) @ e1
    return first + N1 @ (np.asarray(ik.damped_pinv(J2 @ N1, damping)) @ (e2 - J2 @ first))


@pytest.mark.parametrize("number, functions, reference, marks", [
    (2, [jt_imported_inside], "ikteach.core.jt.jt_step", 0),
    (2, [jt_by_getattr], "ikteach.core.jt.jt_step", 0),
    (5, [lambda d, L, f: bool(ik.core.stop_rules.joint_steps(d) < f * np.sum(L)),
         stop_rule_step], "ikteach.core.stop_rules.joint_steps", 5),  # an attribute chain;
    # the solve part's own stop_rule_step keeps its 5 (in the grader too: only `stalled` raises)
    (4, [dls_by_method_object, dls_by_method_table], "ikteach.core.dls.damped_step", 0),
    (4, [lambda J, e, d: np.asarray(MyDLS(damping=d).step(J, e)), ik.dls_step_normal],
     "ikteach.core.dls.damped_step", 0),
    (3, [lambda J, e, rcond: np.asarray(ik.damped_pinv(J, 0.0)) @ e],  # J^+ at damping 0
     "ikteach.core.priority.damped_pinv", 0),
    (7, [priority_from_lecture_parts], "ikteach.core.priority.damped_pinv, "
                                       "ikteach.core.priority.null_projector", 0),
])
def test_every_path_to_the_reference_is_refused_by_the_instant_check(number, functions,
                                                                      reference, marks):
    """Function-level imports, getattr with a name, attribute chains, method objects, the
    method table, a subclass, the lecture's parts of exercise 7: the grader's sandbox stubs
    every one of them (reference_spellings.py, graded in test_grade.py), so the instant check
    gives what it gives."""
    module = check.EXERCISES[number]
    verdict = getattr(check, f"{module.CHECK_NAME}_verdict")(*functions)
    assert verdict.score == marks and reference in verdict.message, verdict.message


def test_a_method_object_in_one_function_costs_that_function_only():
    """ik.DLS(damping).step in `dls_step` beside an own normal form: the grader's stub raises
    in `dls_step` only, so the check cell gives what the grader gives, 4 (issue 48)."""
    def dls_step_normal(J, e, damping):
        return np.linalg.solve(J.T @ J + damping**2 * np.eye(J.shape[1]), J.T @ e)
    verdict = check.dls_step_verdict(dls_by_method_object, dls_step_normal)
    assert verdict.score == 4 and verdict.parts["dls_step_normal"], verdict.message
    assert "`dls_step` raised ReferenceBlocked" in verdict.message


def test_other_ikteach_functions_are_fine_in_the_instant_check():
    assert check.jacobian_verdict(planar_jacobian).passed  # ik.joint_positions: allowed
    other = check.pinv_step_verdict(lambda J, e, r: -np.asarray(ik.dls_step(J, e, 0.0)))
    assert "own code" not in other.parts, other.message  # checked like any answer, not refused


def test_grade_finds_functions_in_a_namespace():
    assert check.grade(2, {"jt_step": jt_step}).passed
    missing = check.grade(2, {})
    assert missing.score == 0 and "`jt_step` not found" in missing.message
    with pytest.raises(ValueError, match="number"):
        check.grade(8, {})  # exercises 1-7


def test_stop_solve_hook_ends_the_solve_stalled():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    theta0 = np.array([0.3, 0.2, 0.1])
    step = stop_rule_step(lambda J, e: ik.dls_step(J, e, 1.0), [1, 1, 1], 1e-3)
    res = ik.solve(arm, np.array([4.0, 0.5]), theta0, method=step, stall_tol=0, max_iter=300)
    assert res.status == "stalled" and 0 < res.iterations < 300
    assert len(res.trace.error) == res.iterations + 1 and np.isfinite(res.error)
    assert res.error == pytest.approx(np.linalg.norm([4.0, 0.5] - np.asarray(ik.fk(arm, res.theta))))
    # the stop rule never overrides convergence (checked first, as in the built-in loop):
    # at the target the step is 0, the rule fires, and the solve still ends "converged"
    res = ik.solve(arm, np.asarray(ik.fk(arm, theta0)), theta0, method=step, stall_tol=0)
    assert (res.status, res.iterations) == ("converged", 0)


def test_feedback_prints_the_digits_that_differ():
    """A Jacobian 3e-6 too long: expected and yours differ in the sixth digit, and are printed
    to it (not identically to four), with a word on float32 (issue 48)."""
    verdict = check.jacobian_verdict(lambda L, t: planar_jacobian(L, t) * (1 + 3e-6))
    lines = {line.split(":")[0].strip(): line.split(":", 1)[1] for line in
             verdict.message.splitlines() if line.strip().startswith(("expected J", "your J"))}
    assert lines["expected J"].strip() != lines["your J"].strip(), verdict.message
    assert "1.000003" in lines["your J"] and "1.000003" not in lines["expected J"]
    assert "they agree to 6 digits only: is something computed in float32?" in verdict.message
