"""The grader's self-check before it grades anyone: a known-good answer of exercise 2 (a
notebook built here: no instructor folder needed) must get full marks through the same sandbox
and job as every student, and a wrapper of ikteach's own jt_step none; otherwise the grader
cannot grade on this machine (its Python or packages not visible in the sandbox, a backend that
fails, a reference that still answers) and stops before writing a CSV of wrong zeros. The
known-good answer is ikteach's own jt.py as a cell (good_answer), while the sandbox's copy holds
those functions only as stubs (grading/reference.py): so the self-check also shows that code
typed into a cell is graded while the library's own functions answer nothing.
"""
import ast
import importlib
import inspect

from .report import RERUN

EXERCISE = 2
SETUP = "import numpy as np\nimport ikteach as ik\n"


def good_answer():
    """The module holding exercise 2's first reference, as a cell: its imports, constants and
    functions, without decorators (no jit: plain code, as a student writes it)."""
    from ..check import EXERCISES

    module = importlib.import_module(EXERCISES[EXERCISE].REFERENCES[0].split(":")[0])
    kept = []
    for node in ast.parse(inspect.getsource(module)).body:
        if isinstance(node, ast.FunctionDef):
            node.decorator_list = []
        if isinstance(node, (ast.Import, ast.Assign, ast.FunctionDef)) or (
                isinstance(node, ast.ImportFrom) and node.level == 0):
            kept.append(node)
    return ast.unparse(ast.Module(kept, [])) + "\n"


GOOD = good_answer()
WRAPPER = "def jt_step(J, e):\n    return ik.jt_step(J, e)\n"


class SelfCheckFailed(RuntimeError):
    """The grader cannot grade on this machine; the message says why."""


def book(source):
    code = [{"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None,
             "source": text} for text in (SETUP, source)]
    return {"cells": code, "metadata": {"ikteach": {"exercise": EXERCISE}}, "nbformat": 4,
            "nbformat_minor": 5}


def run(grade_book, sandbox, timeout, grade_timeout):
    """Raise SelfCheckFailed unless the known answers get their known marks."""
    for name, source, expected in (("a correct jt_step", GOOD, 10.0),
                                   ("a wrapper of ik.jt_step", WRAPPER, 0.0)):
        result = grade_book("self-check.ipynb", book(source), timeout, grade_timeout, sandbox)
        notes = [n for n in result["notes"] if n != RERUN]
        # the known-good answer's cells run without errors or notes (the runner works)
        if result["score"] != expected or result["exercise"] != EXERCISE or (expected and notes):
            details = "; ".join([result["message"]] + result["notes"])[:1500]
            raise SelfCheckFailed(
                f"the grader's self-check failed: {name} (exercise 2) got "
                f"{result['score']:g}/10 (expected {expected:g}/10, without notes) in this sandbox "
                f"({sandbox.backend}), so the grader cannot grade here and graded no one.\n"
                f"  what it said: {details}\n  (a Python or package folder the sandbox "
                "does not show, a broken install, or a failing backend)")
