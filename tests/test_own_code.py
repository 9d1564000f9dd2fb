"""Marks only for the student's own code: the sandbox's copy of ikteach holds the graded
exercise's reference functions only as stubs (grading/reference.py), checked here in a fresh
Python that imports the copy, as the sandbox's processes do; which graded names are not
functions written in the notebook (grading/own_code.py); and the fingerprints that report
copied code."""
import base64
import inspect
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
from ikteach.course.grading.extract import code_cells
from cells_as_python import python_source

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


def same_code(name, what, count):
    return (f"`{name}` has the same code as {what}: all its {count} compiled operations in the "
            "same order, names ignored (code written independently from the same formula can "
            "match too: read both)")


def operations(fn):
    return reference.fingerprint(reference._python_function(fn).__code__)[1]


TEXTBOOK_PINV = """\
def pinv_step(J, e, rcond):
    \"\"\"Golub & Van Loan: J+ e = sum over kept sigma_i of (u_i . e / sigma_i) v_i.\"\"\"
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    step = np.zeros(J.shape[1])
    for i in range(len(s)):
        if s[i] > 0 and s[i] >= rcond * s[0]:
            step += (U[:, i] @ e) / s[i] * Vt[i]
    return step
"""


def test_copied_code_is_reported_with_how_much_matched_and_what_is_not_seen():
    """What the guide says (docs/lecturers.md): a copy with names changed is reported with the
    number of operations that matched and the warning that independent code can match; a
    textbook implementation written from the formula is not the same code; a copy with its
    statements reordered (or rewritten, or split into helpers) is not seen."""
    import inspect
    from ikteach.core import pinv
    source = inspect.getsource(pinv.pinv_step.__wrapped__)
    renamed = (source.replace("pinv_step", "my_step").replace("sigma", "s").replace("jnp", "np")
               .replace('"""', '"""Mine. ', 1))
    found = reference.fingerprints([compile(renamed, "<cell 4>", "exec")])
    count = operations(pinv.pinv_step)
    assert reference.copied(found, known(3)) == [
        same_code("my_step", "ikteach.core.pinv.pinv_step", count)]
    blob = marshal.loads(marshal.dumps(pinv.pinv_step.__wrapped__.__code__))
    assert reference.copied(reference.fingerprints([blob]), known(3))
    textbook = reference.fingerprints([compile(TEXTBOOK_PINV, "<cell 3>", "exec")])
    assert reference.copied(textbook, known(3)) == []
    lines = renamed.splitlines()
    keep = next(i for i, line in enumerate(lines) if "keep = " in line)
    lines[keep], lines[keep - 1] = lines[keep - 1], lines[keep]  # two statements swapped
    reordered = "\n".join(lines).replace("keep = s >= rcond * s[0]", "keep = rcond * s[0] <= s")
    assert reordered != renamed
    found = reference.fingerprints([compile(reordered, "<cell 4>", "exec")])
    assert reference.copied(found, known(3)) == []  # the guide: reordering is not seen
    good = reference.fingerprints([compile(selfcheck.GOOD, "<cell 2>", "exec")])
    assert reference.copied(good, known(2)) == [  # the self-check's answer: ikteach's own
        same_code("jt_step", "ikteach.core.jt.jt_step", operations(ik_jt().jt_step)),
        same_code("optimal_alpha", "ikteach.core.jt.optimal_alpha",
                  operations(ik_jt().optimal_alpha))]
    for number in sorted(check.EXERCISES):  # the instructor's solutions: their own code
        path = next((ROOT / "instructor" / "solutions").glob(f"{number:02d}_*.ipynb"))
        cells = code_cells(json.loads(path.read_text()))
        found = reference.fingerprints([compile(python_source(c), f"<cell {n}>", "exec")
                                        for n, c in cells])
        assert reference.copied(found, known(number)) == [], number


def ik_jt():
    from ikteach.core import jt
    return jt


def test_fingerprints_are_bounded_whatever_the_cell():
    """A cell crafted against the fingerprint (deeply nested lambdas, huge constants, very
    many functions) costs bounded work: each code object is read once, at most MAX_CODES of
    them, long ones skipped, constants shown only when small; cells over the size bound are
    not compiled at all."""
    nested = "f = " + "lambda: (" * 150 + "1" + ")" * 150 + "\n"
    many = "".join(f"def g{i}(x):\n    return x * {i} + x ** 2 - (x, {i})[0] + abs(x) / 7"
                   f" - max(x, {i}) * 3\n" for i in range(2000))
    huge = "def h():\n    return " + repr(tuple(range(5000))) + " + (" + "10**400" + ",)\n"
    code = compile(nested + many + huge, "<cell 1>", "exec")
    seen = list(reference._codes(code))
    assert len(seen) == reference.MAX_CODES
    found = reference.fingerprints([code])
    assert 0 < len(found) <= reference.MAX_CODES
    assert all(len(k) <= 64 and len(v) <= 80 for k, v in found.items())  # what the worker sends
    assert reference.source_fingerprints([(1, nested + many)], max_chars=1000) == {}
    assert reference.source_fingerprints([(1, "def ok(:\n")]) == {}  # not Python: skipped


def test_the_report_reads_the_cells_source_not_the_students_process():
    """`copied` compares the code the cells' source defines, compiled in a job of its own
    (round 5: a cell can replace whatever its own process computes): a copy typed in is
    reported; a blob loaded at run time is code the notebook does not show, and is not."""
    from ikteach.core import pinv
    typed = "".join(line for line in inspect.getsource(pinv.pinv_step.__wrapped__)
                    .splitlines(keepends=True) if not line.startswith("@"))
    found = reference.source_fingerprints([(3, "import jax.numpy as jnp\n" + typed)])
    assert reference.copied(found, known(3)) == [
        same_code("pinv_step", "ikteach.core.pinv.pinv_step", operations(pinv.pinv_step))]
    blob = base64.b64encode(marshal.dumps(pinv.pinv_step.__wrapped__.__code__)).decode()
    loaded = textwrap.dedent(f"""
        import base64, marshal, types
        import jax.numpy as jnp
        _f = types.FunctionType(marshal.loads(base64.b64decode("{blob}")), {{"jnp": jnp}})
        def pinv_step(J, e, rcond):
            return _f(J, e, rcond)
        """)
    assert reference.copied(reference.source_fingerprints([(3, loaded)]), known(3)) == []


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
