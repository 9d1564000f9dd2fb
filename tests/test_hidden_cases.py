"""The grader's hidden cases: every draw holds the check cell's cases (the deciding ones) and
adds as many of the same kinds with numbers drawn from the seed at grading time; the instructor's
solutions keep full marks on them and a table of the check cell's answers earns nothing more.
(Marks per kind of attempt under 40 seeds: test_check_agreement.py.)"""
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
CASES = {1: "_jacobian_cases", 2: "_jt_cases", 3: "_pinv_cases", 4: "_dls_cases",
         5: "_stop_cases", 7: "_priority_cases"}
SEEDS = (1, 20261125, 2**62 + 7)


def cases(number, seed):
    return getattr(check.EXERCISES[number], CASES[number])(seed)


def kind(case):
    """What kind of case it is: its tag and the note in brackets (not the values)."""
    note = case.text.rsplit("(", 1)[-1] if case.text.endswith(")") else ""
    return case.tag, "" if "singular values" in note else note


def numbers(case):
    return tuple(np.asarray(a, dtype=float).round(12).tobytes() for a in case.args
                 if np.size(a) > 1 or float(np.asarray(a).ravel()[0]) not in (0.0, 1.0))


@pytest.mark.parametrize("number", sorted(CASES))
@pytest.mark.parametrize("seed", SEEDS)
def test_every_draw_holds_the_check_cells_cases_and_adds_its_own(number, seed):
    instant, hidden = cases(number, None), cases(number, seed)
    ids = {id(c) for c in instant}
    assert [c for c in hidden if id(c) in ids] == list(instant)  # the same cases, in order
    own = [c for c in hidden if id(c) not in ids]
    assert len(own) == len(instant) and sorted(map(kind, own)) == sorted(map(kind, instant))
    seen = {numbers(c) for c in instant}
    assert not [c.text for c in own if numbers(c) in seen]  # other numbers
    redrawn = getattr(check.EXERCISES[number], CASES[number]).__wrapped__(seed)
    assert [c.text for c in own] == [c.text for c in sorted(redrawn, key=lambda c: c.size)]


def test_hidden_singular_cases_are_singular():
    for seed in SEEDS:
        for case in (c for c in cases(1, seed) if c.tag == "singular"):
            lengths, theta = case.args
            J = check.ex01_jacobian._jacobian_reference(lengths, theta)
            assert np.linalg.matrix_rank(J, tol=1e-9) < min(J.shape)
        for case in (c for c in cases(7, seed) if "singular" in c.text):
            assert np.linalg.matrix_rank(case.args[0], tol=1e-9) < case.args[0].shape[0]
        zero = [c for c in cases(3, seed) if c.tag == "zero"]
        assert zero and all(not np.any(c.args[0]) for c in zero)


def solution(number):
    path = next((ROOT / "instructor" / "solutions").glob(f"{number:02d}_*.ipynb"))
    namespace = {}
    for cell, source in code_cells(json.loads(path.read_text())):
        if not only_checks(source):
            exec(compile(python_source(source), f"<cell {cell}>", "exec"), namespace)
    return namespace


@pytest.mark.parametrize("number", [1, 2, 3, 4, 5, 7])
def test_the_solutions_keep_full_marks_on_hidden_cases(number):
    namespace = solution(number)
    for seed in (None,) + SEEDS:
        verdict = check.grade(number, namespace, seed=seed)
        assert verdict.score == 10, (seed, verdict.message)


def test_a_table_of_the_instant_checks_answers_earns_nothing_but_the_shape_hidden():
    """Exercise 1 answered from a lookup table of the instant check's cases (which a student
    can read off ikteach's source): full marks there, nothing on the grader's cases."""
    table = {(tuple(c.args[0]), tuple(c.args[1])): check.ex01_jacobian._jacobian_reference(*c.args)
             for c in cases(1, None)}

    def memorised(lengths, theta):
        return table.get((tuple(lengths), tuple(np.asarray(theta).tolist())),
                         np.zeros((2, len(lengths))))

    assert check.jacobian_verdict(memorised).score == 10
    for seed in SEEDS:  # only the shape's 2 points: its zeros have the right shape
        verdict = check.jacobian_verdict(memorised, seed=seed)
        assert verdict.score == 2 and verdict.parts["shape"], verdict.message


def test_a_memorised_stop_count_earns_only_the_rule():
    """Exercise 5's solve part answered by counting to the instant check's iteration count:
    the returned step is also tried on the rule's own cases, so the count earns only the rule,
    in the instant check as on hidden cases (both verdicts agree)."""
    ex5 = check.ex05_stop_rule
    namespace = solution(5)
    step = namespace["stop_rule_step"](ex5._BASE_STEP, ex5.STOP_ARM, ex5.STOP_FRACTION)
    count = ik.solve(ik.planar_chain(ex5.STOP_ARM), np.array(ex5.STOP_TARGET),
                     np.array(ex5.STOP_THETA0), method=step, stall_tol=0,
                     max_iter=ex5.STOP_MAX_ITER).iterations

    def stop_rule_step(step, lengths, fraction):
        calls = []

        def counted(J, e):
            calls.append(1)
            if len(calls) > count:
                raise ik.StopSolve("memorised")
            return np.asarray(step(J, e))
        return counted

    stalled = namespace["stalled"]
    for seed in (None,) + SEEDS:
        verdict = check.stop_rule_verdict(stalled, stop_rule_step, seed=seed)
        assert verdict.score == 5 and verdict.parts["rule"], (seed, verdict.message)
