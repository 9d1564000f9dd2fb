"""The grader's self-check before it grades anyone: a known-good answer of exercise 2 (a
notebook built here, so it needs no instructor folder) must get full marks through the same
sandbox, runner and worker as every student; a known wrapper of ikteach's own jt_step must
get none. Otherwise the grader cannot grade on this machine (its Python or packages not
visible in the sandbox, a backend that fails, a blocked reference that still answers) and
stops before writing a CSV of wrong zeros.
"""

SETUP = "import numpy as np\nimport ikteach as ik\n"
# written unlike a student's usual answer (einsum, a conditional expression), so that its
# fingerprint in grades.csv's `copied` column points at a copy of it, not at a common answer;
# the sandbox's copy of ikteach does not hold this file (grading/reference.py)
GOOD = '''\
def jt_step(J, e):
    J, e = np.asarray(J, dtype=float), np.asarray(e, dtype=float)
    grad = np.einsum("ij,i->j", J, e)
    moved = np.einsum("ij,j->i", J, grad)
    num, den = float(np.dot(e, moved)), float(np.dot(moved, moved))
    return grad * (num / den) if den > 0.0 else np.zeros_like(grad)
'''
WRAPPER = "def jt_step(J, e):\n    return ik.jt_step(J, e)\n"


class SelfCheckFailed(RuntimeError):
    """The grader cannot grade on this machine; the message says why."""


def book(source):
    code = [{"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None,
             "source": text} for text in (SETUP, source)]
    return {"cells": code, "metadata": {"ikteach": {"exercise": 2}}, "nbformat": 4,
            "nbformat_minor": 5}


def run(grade_book, sandbox, timeout, grade_timeout):
    """Raise SelfCheckFailed unless the known answers get their known marks."""
    for name, source, expected, cells in (("a correct jt_step", GOOD, 10.0, True),
                                          ("a wrapper of ik.jt_step", WRAPPER, 0.0, False)):
        result = grade_book("self-check.ipynb", book(source), timeout, grade_timeout, sandbox,
                            run_cells=cells)
        # the known-good answer also runs its cells: no errors, no notes (the runner works)
        if result["score"] != expected or result["exercise"] != 2 or (cells and result["notes"]):
            details = "; ".join([result["message"]] + result["notes"])[:1500]
            raise SelfCheckFailed(
                f"the grader's self-check failed: {name} (exercise 2) got "
                f"{result['score']:g}/10 (expected {expected:g}/10, without notes) in this sandbox "
                f"({sandbox.backend}), so the grader cannot grade here and graded no one.\n"
                f"  what it said: {details}\n  (a Python or package folder the sandbox "
                "does not show, a broken install, or a failing backend)")
