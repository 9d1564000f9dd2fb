"""Marks only for the student's own code (grading/own_code.py), in a fresh Python each time:
blocking changes ikteach's functions for good, as it does in the checks' worker."""
import subprocess
import sys
import textwrap

import pytest


def run(code):
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_a_blocked_reference_raises_by_every_way_to_it():
    out = run("""
        import functools, numpy as np, ikteach as ik
        from ikteach.core import jt, methods
        from ikteach.course.grading import own_code
        from_import = jt.jt_step
        default = lambda J, e, f=ik.jt_step: f(J, e)
        class Holder:
            step = staticmethod(ik.jt_step)
        print(own_code.block(["ikteach.core.jt:jt_step"], 2))
        J, e = np.eye(2), np.ones(2)
        for name, fn in [("ik", ik.jt_step), ("from import", from_import), ("default", default),
                         ("class", Holder.step), ("wrapped", ik.jt_step.__wrapped__),
                         ("jit again", __import__("jax").jit(ik.jt_step.__wrapped__)),
                         ("method table", lambda J, e: methods.METHODS["jt"]().step(J, e))]:
            try:
                fn(J, e)
                print(name, "answered")
            except own_code.ReferenceBlocked as exc:
                print(name, "blocked:", exc)
        print("pinv still works:", np.asarray(ik.pinv_step(J, e)).tolist())
        """)
    assert "['ikteach.core.jt.jt_step']" in out
    assert "answered" not in out and out.count("blocked: ikteach's jt_step is the reference "
                                               "answer of exercise 2") == 7, out
    assert "pinv still works: [1.0, 1.0]" in out


def test_the_checker_cannot_be_imported_after_block_checker():
    out = run("""
        import ikteach as ik
        from ikteach.course.grading import own_code
        import ikteach.course.grading.selfcheck
        ik.check  # loaded before, as in a kernel
        own_code.block_checker()
        for attempt in ("ik.check", "__import__('ikteach.course.check')",
                        "__import__('ikteach.course.check.ex06_singularity_study')",
                        "__import__('ikteach.course.grading.selfcheck').course.grading.selfcheck.GOOD"):
            try:
                eval(attempt)
                print(attempt, "imported")
            except (ImportError, AttributeError) as exc:
                print(attempt, "refused", type(exc).__name__)
        """)
    assert "imported" not in out and out.count("refused") == 4, out


DEFINITIONS = [
    ("def f(J, e):\n    return J.T @ e\n", True),
    ("f = lambda J, e: J.T @ e\n", True),
    ("import jax\n@jax.jit\ndef f(J, e):\n    return J.T @ e\n", True),
    ("import functools\n@functools.lru_cache\ndef f(J, e):\n    return 0\n", True),
    ("class C:\n    def __call__(self, J, e):\n        return 0\nf = C()\n", True),
    ("f = ik.jt_step\n", False),
    ("from ikteach.core.jt import jt_step as f\n", False),
    ("import functools\nf = functools.partial(ik.dls_step, damping=0.1)\n", False),
    ("import numpy as np\nf = np.linalg.pinv\n", False),
    ("def g(J, e):\n    return 0\nf = ik.jt_step\nf.__wrapped__ = g\n", False),
]


@pytest.fixture(scope="module")
def verdicts():
    """{definition: foreign(...)'s answer}, all in one fresh Python."""
    out = run(f"""
        import ikteach as ik
        from ikteach.course.grading import own_code
        for definition in {[d for d, _ in DEFINITIONS]!r}:
            scope = {{"ik": ik}}
            exec(compile(definition, "<cell 3>", "exec"), scope)
            print(repr(definition), "->", own_code.foreign(scope, ["f", "missing"]))
        """)
    return dict(line.split(" -> ", 1) for line in out.splitlines())


@pytest.mark.parametrize("definition, own", DEFINITIONS)
def test_only_functions_written_in_the_notebook_count_as_own(verdicts, definition, own):
    answer = verdicts[repr(definition)]
    assert (answer == "{}") == own, answer
    assert "missing" not in answer
