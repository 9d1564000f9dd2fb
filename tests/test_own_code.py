"""Marks only for the student's own code: the sandbox's copy of ikteach holds the graded
exercise's reference functions only as stubs (grading/reference.py), checked here in a fresh
Python that imports the copy, as the sandbox's processes do; which graded names are not
functions written in the notebook (grading/own_code.py); and the fingerprints that report
copied code."""
import base64
import json
import marshal
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import ikteach
from ikteach.course import check
from ikteach.course.grading import reference, selfcheck
from ikteach.course.grading.extract import code_cells, python_source

PACKAGE = Path(ikteach.__file__).resolve().parent
ROOT = PACKAGE.parent


def run(code, path=None):
    env = dict(os.environ, PYTHONPATH=str(path) if path else os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, timeout=180, env=env, cwd="/")
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


@pytest.fixture(scope="module")
def copy_for_exercise_2(tmp_path_factory):
    folder = tmp_path_factory.mktemp("package")
    return reference.sandbox_copy(PACKAGE, folder / "ikteach", check.EXERCISES[2].REFERENCES, 2)


def test_the_copy_has_stubs_for_the_exercises_answers_whatever_the_spelling(copy_for_exercise_2):
    """ik.jt_step, its jit's __wrapped__, the solver's method table, a reload, an exec of the
    module's source file, a fresh interpreter and the self-check's answer: all find nothing."""
    out = run("""
        import importlib, subprocess, sys, numpy as np, jax, ikteach as ik
        from ikteach.core import jt
        from ikteach.course.grading.own_code import ReferenceBlocked
        J, e = np.eye(2), np.ones(2)
        source = {}
        exec(compile(open(jt.__file__).read(), "<cell 3>", "exec"), source)
        fresh = [sys.executable, "-c", "import numpy as np, ikteach as ik; ik.jt_step(np.eye(2), np.ones(2))"]
        for name, call in [("ik", lambda: ik.jt_step(J, e)),
                           ("wrapped", lambda: ik.jt_step.__wrapped__(J, e)),
                           ("jit again", lambda: jax.jit(jt.jt_step.__wrapped__)(J, e)),
                           ("alpha", lambda: ik.optimal_alpha(J, e)),
                           ("solve", lambda: ik.solve(ik.planar_chain([1.0, 1.0]), [1.0, 1.0], [0.1, 0.2], method="jt")),
                           ("reload", lambda: importlib.reload(jt).jt_step(J, e)),
                           ("exec source", lambda: source["jt_step"](J, e))]:
            try:
                call()
                print(name, "answered")
            except ReferenceBlocked as exc:
                print(name, "blocked:", exc)
        run = subprocess.run(fresh, capture_output=True, text=True)
        print("fresh interpreter", "blocked:" if "ReferenceBlocked" in run.stderr else "answered")
        for hidden in ("ikteach.course.grading.selfcheck", "ikteach.course.check.verdicts",
                       "ikteach.course.grade"):
            try:
                importlib.import_module(hidden)
                print(hidden, "answered")
            except ImportError:
                print(hidden, "blocked: absent")
        print("pinv still works:", np.asarray(ik.pinv_step(J, e)).tolist(), ik.__file__)
        """, copy_for_exercise_2.parent)
    assert "answered" not in out, out
    assert out.count("blocked: ikteach's jt_step is the reference answer of exercise 2") == 6
    assert "blocked: ikteach's optimal_alpha is the reference" in out
    assert "fresh interpreter blocked:" in out and out.count("blocked: absent") == 3
    assert f"pinv still works: [1.0, 1.0] {copy_for_exercise_2}" in out


def test_stubs_keep_signatures_and_decorators():
    source = "import jax\n@jax.jit\ndef f(x, y=2):\n    'doc'\n    return x + y\ndef g(x):\n    return x\n"
    stubbed = reference.stub_source(source, ["f"], 9)
    assert "@jax.jit\ndef f(x, y=2):" in stubbed and "return x + y" not in stubbed
    assert "raise ReferenceBlocked(\"ikteach's f is the reference answer of exercise 9" in stubbed
    assert "def g(x):\n    return x" in stubbed
    with pytest.raises(ValueError, match="not top-level functions"):
        reference.stub_source(source, ["h"], 9)


def known(number):
    return reference.reference_fingerprints(check.EXERCISES[number].REFERENCES)


def test_a_copy_of_the_references_code_is_reported_a_students_own_is_not():
    import inspect
    from ikteach.core import pinv
    source = inspect.getsource(pinv.pinv_step.__wrapped__)
    renamed = (source.replace("pinv_step", "my_step").replace("sigma", "s").replace("jnp", "np")
               .replace('"""', '"""Mine. ', 1))
    found = reference.fingerprints([compile(renamed, "<cell 4>", "exec")])
    assert reference.copied(found, known(3)) == [
        "`my_step` has the same code as ikteach.core.pinv.pinv_step"]
    blob = marshal.loads(marshal.dumps(pinv.pinv_step.__wrapped__.__code__))
    assert reference.copied(reference.fingerprints([blob]), known(3))
    good = reference.fingerprints([compile(selfcheck.GOOD, "<cell 2>", "exec")])
    assert reference.copied(good, known(2)) == [  # the self-check's answer: ikteach's own
        "`jt_step` has the same code as ikteach.core.jt.jt_step",
        "`optimal_alpha` has the same code as ikteach.core.jt.optimal_alpha"]
    for number in sorted(check.EXERCISES):  # the instructor's solutions: their own code
        path = next((ROOT / "instructor" / "solutions").glob(f"{number:02d}_*.ipynb"))
        cells = code_cells(json.loads(path.read_text()))
        found = reference.fingerprints([compile(python_source(c), f"<cell {n}>", "exec")
                                        for n, c in cells])
        assert reference.copied(found, known(number)) == [], number


def test_the_worker_reports_code_its_namespace_holds():
    from ikteach.core import pinv
    blob = base64.b64encode(marshal.dumps(pinv.pinv_step.__wrapped__.__code__)).decode()
    namespace = {}
    exec(compile(textwrap.dedent(f"""
        import base64, marshal, types
        import jax.numpy as jnp
        _f = types.FunctionType(marshal.loads(base64.b64decode("{blob}")), {{"jnp": jnp}})
        def pinv_step(J, e, rcond):
            return _f(J, e, rcond)
        """), "<cell 3>", "exec"), namespace)
    held = reference.fingerprints(reference.held_code(namespace))
    assert reference.copied(held, known(3)) == [
        "`pinv_step` has the same code as ikteach.core.pinv.pinv_step"]


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


def test_no_file_of_the_copy_holds_the_references_code(tmp_path):
    """Sources and compiled files alike (the copy is made from a compiled base copy): no code
    object in them is ikteach's jt_step or optimal_alpha; the checker's folder is empty."""
    (tmp_path / "base").mkdir()
    (tmp_path / "ex2").mkdir()
    base = reference.sandbox_copy(PACKAGE, tmp_path / "base" / "ikteach")
    copy = reference.sandbox_copy(PACKAGE, tmp_path / "ex2" / "ikteach",
                                  check.EXERCISES[2].REFERENCES, 2, base=base)
    codes = [compile(p.read_text(), str(p), "exec") for p in copy.rglob("*.py")]
    codes += [marshal.loads(p.read_bytes()[16:]) for p in copy.rglob("*.pyc")]
    assert len(codes) > 100 and list((copy / "course" / "check").iterdir()) == []
    assert reference.copied(reference.fingerprints(codes), known(2)) == []
    assert reference.copied(reference.fingerprints(
        [marshal.loads(p.read_bytes()[16:]) for p in base.rglob("jt.*.pyc")]), known(2))
