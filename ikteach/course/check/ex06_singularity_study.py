"""Exercise 6: study(jt_step, pinv_step, dls_step) -> a dict of answers, checked by value.

Parts: iterations 3, fewest_iterations 2, blows_up 2, smallest_lambda 3. The notebook's
written answer to "why" is not marked by the checker: the grader copies it into the feedback
file for the instructor to read.
"""
import functools

import numpy as np

from ...core.chain import planar_chain
from ...core.dls import dls_step as _ref_dls
from ...core.jt import jt_step as _ref_jt
from ...core.pinv import pinv_step as _ref_pinv
from ...core.solve import solve as _solve
from .verdicts import SOLVE_LIMIT, _call, _evaluate, _Fail, _Part

NUMBER = 6
CHECK_NAME = "singularity_study"
TITLE = "a singularity study"
FUNCTIONS = ('study',)
REFERENCES = ()  # ikteach's answers, stubbed when graded

STUDY_ARM = [1.0, 1.0, 1.0]
STUDY_THETA0 = [0.3, 0.2, 0.1]
STUDY_REACHABLE = [1.5, 1.0]
STUDY_UNREACHABLE = [4.0, 0.5]
STUDY_LAMBDAS = [0.2, 0.5, 0.7, 1.0]
STUDY_MAX_ITER = 500
BLOW_UP = 10.0  # radians: "the joint angles blow up" when some |theta_i| exceeds this
METHOD_NAMES = ("jt", "pinv", "dls")


@functools.lru_cache(maxsize=1)
def _reference_study():
    """The answers, from ik.solve with the module's own steps (the same runs as the exercise)."""
    arm, theta0 = planar_chain(STUDY_ARM), np.array(STUDY_THETA0)
    options = {"jt": {}, "pinv": {"rcond": 1e-6}, "dls": {"damping": 0.5}}
    iterations = {m: _solve(arm, np.array(STUDY_REACHABLE), theta0, method=m,
                            max_iter=STUDY_MAX_ITER, **options[m]).iterations
                  for m in METHOD_NAMES}
    options["pinv"] = {"rcond": 0.0}
    largest = {m: float(np.abs(_solve(arm, np.array(STUDY_UNREACHABLE), theta0, method=m,
                                      max_iter=STUDY_MAX_ITER, **options[m]).trace.theta).max())
               for m in METHOD_NAMES}
    smallest = next((lam for lam in STUDY_LAMBDAS
                     if _solve(arm, np.array(STUDY_UNREACHABLE), theta0, method="dls",
                               damping=lam, max_iter=STUDY_MAX_ITER).status == "stalled"), None)
    return {"iterations": iterations,
            "fewest_iterations": min(iterations, key=iterations.get),
            "blows_up": [m for m in METHOD_NAMES if largest[m] > BLOW_UP],
            "smallest_lambda": smallest}


_QUESTIONS = {
    "iterations": (3, "iterations on the reachable target: a dict {'jt': ..., 'pinv': ..., "
                      "'dls': ...} of res.iterations"),
    "fewest_iterations": (2, "the method that needs the fewest iterations on the reachable "
                             "target"),
    "blows_up": (2, "the list of methods whose joint angles blow up (some |theta_i| > "
                    f"{BLOW_UP:g} rad) on the out-of-reach target"),
    "smallest_lambda": (3, "the smallest damping in LAMBDAS for which DLS stops \"stalled\" on "
                           "the out-of-reach target instead of jittering until max_iter"),
}


def _same_answer(got, want):
    if isinstance(want, dict):
        return isinstance(got, dict) and set(got) == set(want) and all(
            _same_answer(got[k], want[k]) for k in want)
    if isinstance(want, list):
        try:
            return sorted(str(g) for g in got) == sorted(want)
        except TypeError:
            return False
    if isinstance(want, str):
        return isinstance(got, str) and got.strip().lower() == want
    try:
        return got is not None and np.isclose(float(got), float(want))
    except (TypeError, ValueError):
        return False


def verdict(study, seed=None):
    """Verdict for exercise 6 without printing. `seed` is not used: the study's answers are
    values read off the notebook's own runs (fixed arm and targets), so there are no hidden
    cases - the instructor reads the code and the written answer."""
    name, state = FUNCTIONS[0], {}

    def answers():
        if "answers" not in state:
            case = "study(ik.jt_step, ik.pinv_step, ik.dls_step)"
            got = _call(study, name, case, _ref_jt, _ref_pinv, _ref_dls, limit=4 * SOLVE_LIMIT)
            if not isinstance(got, dict):
                raise _Fail(f"`{name}` must return a dict of answers, it returned "
                            f"{type(got).__name__}.")
            state["answers"] = got
        return state["answers"], _reference_study()  # computed once (lru_cache)

    def question(key):
        points, meaning = _QUESTIONS[key]

        def check():
            got, want = answers()
            if key not in got:
                return f"the answer '{key}' is missing ({meaning})."
            if not _same_answer(got[key], want[key]):
                return (f"'{key}' is not right: you answered {got[key]!r:.80}. It should be "
                        f"{meaning} - run the solves and read it off the results.")
        return _Part(key, points, check)

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS), [question(key) for key in _QUESTIONS])
