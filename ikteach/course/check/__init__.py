"""Instant feedback for the exercises: ``ik.check.<name>(student_function)`` prints one verdict.

Each check runs the student's function on hand-picked cases (singular ones included) and on
seeded random ones, compares with the module's own reference (ik.jacobian, ik.jt_step,
ik.pinv_step, ik.dls_step, ik.solve), and prints either "passed" or what is wrong, with the
smallest failing case. Whatever the student's code does (raises, returns NaN, float32 or the
wrong type, loops forever) becomes a message, never a traceback from ikteach. Every exercise is
worth POINTS, split into parts; ``<name>_verdict(...)`` returns the Verdict without printing,
``grade(number, namespace, seed)`` is what the grader calls: the check cell's cases, in every
draw, and as many again drawn from the seed (the same kinds, other numbers).

Layout: ``verdicts.py`` (running student code under a time limit, cases, comparisons, scoring
by parts, the Verdict), one module per exercise, ``registry.py`` (the exercise list; grade()).
To add exercise N, write ``exNN_<topic>.py`` as the others are (nothing else: ik.check.<name>,
the grader's exercise numbers and grades.csv's columns derive from the files): NUMBER,
CHECK_NAME (ik.check.<CHECK_NAME>), TITLE, FUNCTIONS (the names the template defines, in call
order), REFERENCES ("ikteach.core.x:fn": ikteach's own answer, stubbed in the grader's sandbox:
grading/reference.py) and verdict(*functions, seed=None): its cases from an @_in_every_draw
cases(seed) (None: the check cell's; a seed: its own on top), its parts [_Part(name, points,
run), ...] (points summing to POINTS; run() returns None or the smallest failing case's
message) handed to _evaluate(NUMBER, TITLE, list(FUNCTIONS), parts). Student code is called
only through verdicts._answers or _call (time limit, errors as messages).
"""
from . import registry, verdicts
from .registry import EXERCISES, NUMBERS, grade
from .verdicts import POINTS, Verdict

__all__ = ["grade", "EXERCISES", "NUMBERS", "POINTS", "Verdict", "registry", "verdicts"]
for _module in registry.MODULES:  # ik.check.<name> and ik.check.<name>_verdict, per exercise
    globals()[_module.CHECK_NAME] = registry.instant_check(_module)
    globals()[f"{_module.CHECK_NAME}_verdict"] = registry.instant_verdict(_module)
    __all__ += [_module.CHECK_NAME, f"{_module.CHECK_NAME}_verdict"]
