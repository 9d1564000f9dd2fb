"""The instant check and the grader agree, whatever the hidden seed (issues 40, 48): each kind
of attempt met in class gets the same marks from the check cell as from the grader's hidden
cases under 40 seeds, and its message names the actual mistake. The deciding cases are the
check cell's, in every draw (the seed only adds cases); float32 answers are refused alike; a
function that reaches ikteach's own answer loses what the grader's stub makes it lose.
(The grader's sandbox itself: reference_spellings.py, graded in test_grade.py; verdicts here
run in-process.)"""
import json
from pathlib import Path

import numpy as np
import pytest

import ikteach as ik
from ikteach.course import check
from ikteach.course.grading.cells import only_checks
from ikteach.course.grading.extract import code_cells
from cells_as_python import python_source

ROOT = Path(__file__).resolve().parents[1]
SEEDS = tuple(range(40))


def jacobian(lengths, theta, dtype=np.float64):
    angle = np.cumsum(theta)
    links = np.asarray(lengths)[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    p = np.vstack([np.zeros(2), np.cumsum(links, axis=0)]).astype(dtype)  # joints, then tip
    d = p[-1] - p[:-1]
    return np.stack([-d[:, 1], d[:, 0]])


def row_0_sign_slip(lengths, theta):
    J = jacobian(lengths, theta)
    return np.stack([-J[0], J[1]])


def jt(J, e, dtype=np.float64):
    J, e = np.asarray(J, dtype), np.asarray(e, dtype)
    g = J.T @ e
    v = J @ g
    return np.zeros_like(g) if v @ v == 0 else (e @ v / (v @ v)) * g


def pinv_cut(cutoff=None, guard=True, absolute=None, dtype=np.float64):
    def pinv_step(J, e, rcond):
        J, e = np.asarray(J, dtype), np.asarray(e, dtype)
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        if absolute is not None and s.max() < absolute:  # a guard at a fixed size
            return np.zeros(J.shape[1])
        keep = s >= (rcond if cutoff is None else cutoff) * s.max()
        if guard:
            keep &= s > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            return Vt.T @ (np.where(keep, 1 / np.where(keep, s, 1), 0) * (U.T @ e))
    return pinv_step


def dls_m(J, e, damping, dtype=np.float64):
    J, e = np.asarray(J, dtype), np.asarray(e, dtype)
    return J.T @ np.linalg.solve(J @ J.T + dtype(damping)**2 * np.eye(len(J), dtype=dtype), e)


def dls_n(J, e, damping, dtype=np.float64):
    J, e = np.asarray(J, dtype), np.asarray(e, dtype)
    return np.linalg.solve(J.T @ J + dtype(damping)**2 * np.eye(J.shape[1], dtype=dtype), J.T @ e)


def dls_method_object(J, e, damping):
    return np.asarray(ik.DLS(damping).step(J, e))  # ikteach's own answer: blocked when graded


def rule(size, scaled=True):
    def stalled(delta_theta, lengths, fraction):
        return bool(size(np.asarray(delta_theta)) < fraction * (np.sum(lengths) if scaled else 1))
    return stalled


def wrapping(stalled, dtype=None):
    def stop_rule_step(step, lengths, fraction):
        def wrapped(J, e):
            delta = np.asarray(step(J, e), dtype=dtype)
            if stalled(delta, lengths, fraction):
                raise ik.StopSolve("stalled")
            return delta
        return wrapped
    return stop_rule_step


def sum_abs(d):
    return np.abs(d).sum()


def damped(A, lam, cut):
    """V diag(sigma / (sigma^2 + lambda^2)) U^T; sigma <= cut * sigma_max dropped."""
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    keep = s > cut * max(s.max(initial=0.0), 1e-300)
    return Vt.T @ (np.where(keep, s / np.where(keep, s**2 + lam**2, 1.0), 0.0)[:, None] * U.T)


def priority(cut=1e-10, dtype=np.float64):
    """cut=0: no cut-off; float32: J1, e1, J2, e2 rounded first (the step comes back float64,
    its digits float32's)."""
    def priority_step(J1, e1, J2, e2, damping):
        J1, e1, J2, e2 = (np.asarray(a, dtype) for a in (J1, e1, J2, e2))
        first = damped(J1, damping, cut) @ e1
        N1 = np.eye(J1.shape[1]) - np.linalg.pinv(J1) @ J1
        return first + N1 @ damped(J2 @ N1, damping, cut) @ (e2 - J2 @ first)
    return priority_step


def not_projected(J1, e1, J2, e2, damping):
    first = damped(J1, damping, 1e-10) @ e1
    return first + damped(J2, damping, 1e-10) @ (e2 - J2 @ first)


def submission(student):
    """tests/submissions/<student>'s functions (the grading tests' wrong answers)."""
    namespace = {}
    path = next((ROOT / "tests" / "submissions" / student).glob("*.ipynb"))
    for cell, source in code_cells(json.loads(path.read_text())):
        if not only_checks(source):
            exec(compile(python_source(source), f"<cell {cell}>", "exec"), namespace)
    return namespace


F32 = np.float32
FLOAT32 = "returns float32; return float64"


def out64(fn):
    """fn computed in float32, its answer handed back as float64: judged by its digits."""
    return lambda *args: np.asarray(fn(*args), dtype=np.float64)

# (exercise, functions or a tests/submissions name, marks, words of the message)
ATTEMPTS = {
    "ex 1 right": (1, [jacobian], 10, "passed"),
    "ex 1 float32": (1, [lambda L, t: jacobian(L, t, F32)], 0, FLOAT32),
    "ex 1 float32 inside": (1, [out64(lambda L, t: jacobian(L, t, F32))], 10, "passed"),
    "ex 1 a sign slip in row 0 only": (1, [row_0_sign_slip], 2, "row 0 has the wrong sign"),
    "ex 1 sign_error": (1, "sign_error", 6, "wrong sign"),
    "ex 2 right": (2, [jt], 10, "passed"),
    "ex 2 float32": (2, [lambda J, e: jt(J, e, F32)], 0, FLOAT32),
    "ex 2 fixed_alpha": (2, "fixed_alpha", 7, "alpha looks fixed"),
    "ex 2 exception": (2, "exception", 0, "raised"),
    "ex 3 right": (3, [pinv_cut()], 10, "passed"),
    "ex 3 np.linalg.pinv(J, rcond)": (3, [lambda J, e, r: np.linalg.pinv(J, rcond=r) @ e], 10,
                                       "passed"),
    "ex 3 float32": (3, [pinv_cut(dtype=F32)], 0, FLOAT32),
    "ex 3 float32 inside": (3, [out64(pinv_cut(dtype=F32))], 7, "computed in float32?"),
    "ex 3 no_cutoff": (3, "no_cutoff", 7, "no cut-off"),
    "ex 3 np.linalg.pinv(J)": (3, [lambda J, e, r: np.linalg.pinv(J) @ e], 7, "no cut-off"),
    "ex 3 a fixed cut-off of 1e-3": (3, [pinv_cut(1e-3)], 7, "ignores `rcond`"),
    "ex 3 no guard for sigma_max = 0": (3, [pinv_cut(guard=False)], 8, "no guard for sigma_max"),
    "ex 3 a guard sigma_max < 1e-3": (3, [pinv_cut(absolute=1e-3)], 7, "zero for a small J"),
    "ex 4 both forms": (4, [dls_m, dls_n], 10, "passed"),
    "ex 4 float32": (4, [lambda J, e, d: dls_m(J, e, d, F32), lambda J, e, d: dls_n(J, e, d, F32)],
                     0, FLOAT32),
    "ex 4 float32 inside": (4, [out64(lambda J, e, d: dls_m(J, e, d, F32)),
                                out64(lambda J, e, d: dls_n(J, e, d, F32))], 0,
                            "computed in float32?"),
    "ex 4 a method object beside an own normal form": (
        4, [dls_method_object, dls_n], 4, "`dls_step` raised ReferenceBlocked"),
    "ex 4 the n x n form twice": (4, [dls_n, dls_n], 8, "the m x m solve"),
    "ex 4 without damping": (4, [lambda J, e, d: np.linalg.pinv(J) @ e] * 2, 2,
                             "the damping is missing"),
    "ex 4 lambda_not_squared": (4, "lambda_not_squared", 2, "missing square on lambda"),
    "ex 5 right": (5, [rule(sum_abs), wrapping(rule(sum_abs))], 10, "passed"),
    "ex 5 float32": (5, [rule(sum_abs), wrapping(rule(sum_abs), F32)], 5, FLOAT32),
    "ex 5 a threshold without the link lengths": (
        5, [rule(sum_abs, scaled=False), wrapping(rule(sum_abs, scaled=False))], 0,
        "proportional to the link lengths"),
    "ex 5 a 2-norm instead of the sum": (
        5, [rule(np.linalg.norm), wrapping(rule(np.linalg.norm))], 0, "not their 2-norm"),
    "ex 7 right": (7, [priority()], 10, "passed"),
    "ex 7 float32 inside": (7, [priority(dtype=F32)], 0, "J1 delta_theta:"),
    "ex 7 no cut-off": (7, [priority(cut=0.0)], 8, "at damping = 0"),
    "ex 7 not projected": (7, [not_projected], 0, "not projected"),
}


def graded(attempt):
    number, functions, marks, words = ATTEMPTS[attempt]
    module = check.EXERCISES[number]
    if isinstance(functions, str):
        functions = [submission(functions)[name] for name in module.FUNCTIONS]
    return getattr(check, f"{module.CHECK_NAME}_verdict"), functions, marks, words


@pytest.mark.parametrize("number", sorted({a[0] for a in ATTEMPTS.values()}))
def test_the_check_cell_and_every_draw_give_the_same_marks(number):
    """The check cell's verdict (seed None) and the grader's on 40 hidden draws: the same marks,
    the same kind of message (the grader's stub for ikteach's answer: the check cell's too)."""
    attempts = {name: graded(name) for name, a in ATTEMPTS.items() if a[0] == number}
    module = check.EXERCISES[number]
    for name, (verdict, functions, marks, words) in attempts.items():
        instant = verdict(*functions)
        assert instant.score == marks and words in instant.message, (name, instant.message)
    as_graded = {name: [check.registry._as_graded(fn, module.REFERENCES) for fn in a[1]]
                 for name, a in attempts.items()}  # what the check cell's verdict runs
    for seed in SEEDS:  # seed-major: one draw's expected values serve every attempt
        for name, (_, _, marks, words) in attempts.items():
            hidden = module.verdict(*as_graded[name], seed=seed)
            assert hidden.score == marks and words in hidden.message, (name, seed, hidden.message)
