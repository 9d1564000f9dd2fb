"""The exercise list: number -> its check module, and grade(number, namespace) for the grader."""
from . import (ex01_jacobian, ex02_jt_step, ex03_pinv_step, ex04_dls_step, ex05_stop_rule,
               ex06_singularity_study, ex07_priority_step)
from .verdicts import POINTS, _evaluate, _Part

MODULES = (ex01_jacobian, ex02_jt_step, ex03_pinv_step, ex04_dls_step, ex05_stop_rule,
           ex06_singularity_study, ex07_priority_step)
EXERCISES = {module.NUMBER: module for module in MODULES}


def grade(number, namespace, seed=None):
    """The verdict for exercise `number`, taking the student's functions from `namespace`
    (a dict: a notebook's globals, or the grader's proxies), on the hidden cases drawn from
    `seed` (None: the instant check's cases). Missing functions fail with a message; nothing
    is printed."""
    if number not in EXERCISES:
        raise ValueError(f"number: expected one of {sorted(EXERCISES)}, got {number!r}")
    module = EXERCISES[number]
    missing = [n for n in module.FUNCTIONS if not callable(namespace.get(n))]
    if missing:
        parts = [_Part("functions", POINTS, lambda: (
            f"{', '.join('`' + n + '`' for n in missing)} not found in the notebook: keep the "
            "function names of the template."))]
        return _evaluate(number, module.TITLE, list(module.FUNCTIONS), parts)
    return module.verdict(*(namespace[n] for n in module.FUNCTIONS), seed=seed)


def refuse(number, message):
    """A 0 verdict for exercise `number` that says why (the grader's, e.g. a graded function
    that is not the student's own code)."""
    module = EXERCISES[number]
    return _evaluate(number, module.TITLE, list(module.FUNCTIONS),
                     [_Part("own code", POINTS, lambda: message)])
