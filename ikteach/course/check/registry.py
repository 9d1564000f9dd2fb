"""The exercise list, kept once: the modules exNN_<topic>.py of this folder, in number order.
Everything else derives from it: EXERCISES (number -> module), NUMBERS (the exercises the
grader grades and reports), ik.check.<CHECK_NAME> and ik.check.<CHECK_NAME>_verdict (the
instant checks, check/__init__.py), grade(number, namespace) for the grader.
"""
import importlib
import pkgutil
import re
from pathlib import Path

from ..grading.reference import reached
from .verdicts import POINTS, _evaluate, _Part

MODULES = tuple(importlib.import_module(f"{__package__}.{name}") for name in sorted(
    info.name for info in pkgutil.iter_modules([str(Path(__file__).parent)])
    if re.fullmatch(r"ex\d\d_\w+", info.name)))
EXERCISES = {module.NUMBER: module for module in MODULES}
NUMBERS = tuple(sorted(EXERCISES))


def grade(number, namespace, seed=None):
    """The verdict for exercise `number`, taking the student's functions from `namespace`
    (a dict: a notebook's globals, or the grader's proxies), on the instant check's cases and
    the hidden ones drawn from `seed` (None: the instant check's only). Missing functions fail
    with a message; nothing is printed."""
    if number not in EXERCISES:
        raise ValueError(f"number: expected one of {sorted(EXERCISES)}, got {number!r}")
    module = EXERCISES[number]
    missing = [n for n in module.FUNCTIONS if not callable(namespace.get(n))]
    if missing:
        return refuse(number, f"{', '.join('`' + n + '`' for n in missing)} not found in the "
                      "notebook: keep the function names of the template.", part="functions")
    return module.verdict(*(namespace[n] for n in module.FUNCTIONS), seed=seed)


def refuse(number, message, part="own code"):
    """A 0 verdict for exercise `number` that says why in one failed `part` (the grader's,
    e.g. a graded function that is not the student's own code)."""
    module = EXERCISES[number]
    return _evaluate(number, module.TITLE, list(module.FUNCTIONS),
                     [_Part(part, POINTS, lambda: message)])


class ReferenceBlocked(Exception):
    """Raised in the check cell where the grader's sandbox will raise its own ReferenceBlocked
    (grading/own_code.py): by a graded function that reaches ikteach's own answer."""


def _as_graded(fn, references):
    """fn, or, when fn reaches one of `references`, a stand-in that raises as fn will in the
    grader's sandbox (where those functions are stubs that raise)."""
    used = reached([fn], references)
    if not used:
        return fn
    names = ", ".join(ref.replace(":", ".") for ref in used)

    def blocked(*args, **kwargs):
        raise ReferenceBlocked(
            f"your code calls ikteach's own answer to this exercise ({names}), which raises "
            "ReferenceBlocked in the grader: compute the answer in your own code (other ikteach "
            "functions are fine)")
    return blocked


def instant_verdict(module):
    """ik.check.<name>_verdict: the module's verdict in the student's notebook, a graded
    function that calls ikteach's own answer getting the marks the grader will give it."""
    def verdict(*functions, seed=None):
        graded = [_as_graded(fn, module.REFERENCES) for fn in functions]
        return module.verdict(*graded, seed=seed)

    verdict.__name__ = f"{module.CHECK_NAME}_verdict"
    verdict.__doc__ = f"{module.__doc__.splitlines()[0]}\n\nReturns the Verdict, prints nothing."
    return verdict


def instant_check(module):
    """ik.check.<name>: print the instant verdict."""
    verdict = instant_verdict(module)

    def check(*functions):
        print(verdict(*functions).message)

    check.__name__ = module.CHECK_NAME
    check.__doc__ = f"{module.__doc__.splitlines()[0]}\n\nPrints the verdict."
    return check
