"""Instant feedback for the exercises: ``ik.check.<name>(student_function)`` prints one verdict.

Each check runs the student's function on hand-picked cases (singular ones included) and on
seeded random ones, compares with the module's own reference (ik.jacobian, ik.jt_step,
ik.pinv_step, ik.dls_step, ik.solve), and prints either "passed" or what is wrong, with the
smallest failing case. Whatever the student's code does (raises, returns NaN or the wrong
type, loops forever) becomes a message, never a traceback from ikteach. Every exercise is
worth POINTS, split into parts; ``<name>_verdict(...)`` returns the Verdict without printing,
``grade(number, namespace)`` is what the grader calls.

Layout: ``verdicts.py`` (running student code under a time limit, cases, comparisons, scoring
by parts, the Verdict), one module per exercise (``ex01_jacobian.py`` ...), ``registry.py``
(number -> module, grade()).

To add exercise N: write ``exNN_<topic>.py`` with
    NUMBER = N; CHECK_NAME = "<name>" (so ik.check.<name>); TITLE = "..."
    FUNCTIONS = ("student_fn", ...)        # the names the template defines, in call order
    REFERENCES = ("ikteach.core.x:fn", ...)  # ikteach's own answer: blocked while grading
    def verdict(*functions) -> Verdict     # build [_Part(name, points, run), ...] (points sum
                                           # to POINTS; run() returns None or the message of
                                           # the smallest failing case) and return
                                           # _evaluate(NUMBER, TITLE, list(FUNCTIONS), parts)
    def check(*functions): _report(verdict(*functions))
call student code only through verdicts._call (time limit, errors as messages), add the module
to MODULES in registry.py and two alias lines below. The grader then grades NN_*.ipynb.
"""
from . import registry, verdicts
from .ex01_jacobian import check as jacobian, verdict as jacobian_verdict
from .ex02_jt_step import check as jt_step, verdict as jt_step_verdict
from .ex03_pinv_step import check as pinv_step, verdict as pinv_step_verdict
from .ex04_dls_step import check as dls_step, verdict as dls_step_verdict
from .ex05_stop_rule import check as stop_rule, verdict as stop_rule_verdict
from .ex06_singularity_study import check as singularity_study
from .ex06_singularity_study import verdict as singularity_study_verdict
from .ex07_priority_step import check as priority_step
from .ex07_priority_step import verdict as priority_step_verdict
from .registry import EXERCISES, grade
from .verdicts import POINTS, Verdict

__all__ = ["jacobian", "jt_step", "pinv_step", "dls_step", "stop_rule", "singularity_study",
           "priority_step", "priority_step_verdict",
           "jacobian_verdict", "jt_step_verdict", "pinv_step_verdict", "dls_step_verdict",
           "stop_rule_verdict", "singularity_study_verdict", "grade", "EXERCISES", "POINTS",
           "Verdict", "registry", "verdicts"]
