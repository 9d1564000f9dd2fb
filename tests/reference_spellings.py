"""The reference rule's students (issue 35), graded in tests/test_grade.py's class: every
spelling of "use ikteach's own answer" that the grader can stop scores nothing, because the
sandbox of the graded exercise holds that answer only as a stub (grading/reference.py); the
answers a notebook carries in itself (a marshalled blob, source typed in) are reported in
grades.csv's `copied` column and the feedback, for the instructor; a lookup table of the
instant check's cases meets hidden cases. Without bubblewrap the class is graded with
--no-sandbox (the copy of ikteach is then what PYTHONPATH points at)."""
import base64
import inspect
import marshal
from pathlib import Path

import nbformat

from ikteach.core import pinv
from ikteach.course import check

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = ROOT / "instructor" / "solutions"

RELOAD = '''\
import importlib
import ikteach.core.pinv as _pinv_module


def pinv_step(J, e, rcond):
    return np.asarray(importlib.reload(_pinv_module).pinv_step(J, e, rcond))
'''
SUBPROCESS = '''\
import json, subprocess, sys
_SERVER = ("import json, sys, numpy as np, ikteach as ik\\n"
           "for line in sys.stdin:\\n"
           "    J, e = json.loads(line)\\n"
           "    print(json.dumps(np.asarray(ik.jt_step(np.array(J), np.array(e))).tolist()), flush=True)\\n")
_child = []


def jt_step(J, e):
    """Answered by a fresh Python that imports ikteach, over a pipe."""
    if not _child:
        _child.append(subprocess.Popen([sys.executable, "-c", _SERVER], stdin=subprocess.PIPE,
                                       stdout=subprocess.PIPE, text=True))
    _child[0].stdin.write(json.dumps([np.asarray(J).tolist(), np.asarray(e).tolist()]) + "\\n")
    _child[0].stdin.flush()
    return np.array(json.loads(_child[0].stdout.readline()))
'''
EXEC_SOURCE = '''\
import ikteach.core.priority as _library
_scope = {"__name__": "ikteach.core.priority"}
_run = exec(compile(open(_library.__file__).read(), "<cell 3>", "exec"), _scope)
priority_step = _scope["priority_step"]
'''
SELFCHECK = '''\
import importlib
_selfcheck = importlib.import_module("ikteach.course.grading.selfcheck")
_run = exec(_selfcheck.good_answer(), globals())
'''
MARSHAL_AT_RUN_TIME = '''\
import marshal, types
import ikteach.core.pinv as _library
_f = types.FunctionType(marshal.loads(marshal.dumps(_library.pinv_step.__wrapped__.__code__)),
                        vars(_library))


def pinv_step(J, e, rcond):
    return np.asarray(_f(J, e, rcond))
'''
MARSHAL_BLOB = '''\
import base64, marshal, types
import jax.numpy as jnp
_f = types.FunctionType(marshal.loads(base64.b64decode("{blob}")), {{"jnp": jnp}})


def pinv_step(J, e, rcond):
    return np.asarray(_f(J, e, rcond))
'''
IMPORT_INSIDE = '''\
def jt_step(J, e):
    from ikteach.core.jt import jt_step as step
    return np.asarray(step(J, e))
'''
ATTRIBUTE_CHAIN = '''\
def stalled(delta_theta, lengths, fraction):
    return bool(ik.core.stop_rules.joint_steps(np.asarray(delta_theta)) < fraction * sum(lengths))


def stop_rule_step(step, lengths, fraction):
    def wrapped(J, e):
        delta = np.asarray(step(J, e))
        if stalled(delta, lengths, fraction):
            raise ik.StopSolve("stalled")
        return delta
    return wrapped
'''
METHOD_OBJECT = '''\
def dls_step(J, e, damping):
    return np.asarray(ik.DLS(damping=damping).step(np.asarray(J), np.asarray(e)))


def dls_step_normal(J, e, damping):
    method = ik.core.methods.METHODS["dls"](damping=damping)
    return np.asarray(method.step(np.asarray(J), np.asarray(e)))
'''
METHOD_OBJECT_ONE = '''\
def dls_step(J, e, damping):
    return np.asarray(ik.DLS(damping).step(J, e))


def dls_step_normal(J, e, damping):
    return np.linalg.solve(J.T @ J + damping**2 * np.eye(J.shape[1]), J.T @ e)
'''
LECTURE_PARTS = '''\
def priority_step(J1, e1, J2, e2, damping):
    N1 = np.asarray(ik.null_projector(J1))
    first = np.asarray(ik.damped_pinv(J1, damping)) @ e1
    return first + N1 @ (np.asarray(ik.damped_pinv(J2 @ N1, damping)) @ (e2 - J2 @ first))
'''
HONEST_JT = '''\
def jt_step(J, e):
    g = J.T @ e
    v = J @ g
    return np.zeros(J.shape[1]) if v @ v == 0 else (e @ v / (v @ v)) * g
'''


def fingerprint_stall():
    """0.4 MB crafted against the copied report, in a cell after an honest jt_step's: deeply
    nested lambdas, many functions, big constants (reference.py bounds the work on it)."""
    nested = "_f{i} = " + "lambda x: x * 3 - x ** 2 + (" * 60 + "1" + ")" * 60 + "\n"
    many = "def _g{i}(x):\n    return x * {i} + x ** 2 - abs(x) / 7 - max(x, {i}) * 3\n"
    big = "_t{i} = " + repr(tuple(range(300))) + "\n"
    parts, i = [], 0
    while sum(map(len, parts)) < 400_000:
        parts += [nested.format(i=i), many.format(i=i), big.format(i=i)]
        i += 1
    return "".join(parts)


LOOKUP = '''\
_TABLE = {table!r}


def planar_jacobian(lengths, theta):
    key = repr((list(lengths), [float(t) for t in theta]))
    return np.array(_TABLE.get(key, np.zeros((2, len(lengths))).tolist()))
'''


FORGE_FINGERPRINTS = ("import ikteach.course.grading.reference as _reference\n"
                      "_reference.fingerprints = lambda codes: {}\n")


def by_hand():
    """ikteach's pinv_step typed into the notebook, names changed: plagiarism, reported."""
    source = "".join(line for line in inspect.getsource(pinv.pinv_step.__wrapped__)
                     .splitlines(keepends=True) if not line.startswith("@"))  # no decorator
    return ("import numpy as jnp\n\n\n" + source.replace("sigma", "s").replace("rcond=DEFAULT_RCOND", "rcond"))


def lookup_table():
    table = {}
    for case in check.ex01_jacobian._jacobian_cases():
        lengths, theta = case.args
        key = repr((list(lengths), [float(t) for t in theta]))
        table[key] = check.ex01_jacobian._jacobian_reference(lengths, theta).tolist()
    return LOOKUP.format(table=table)


def marshal_blob():
    """Made at home with the student's own ikteach (the same Python as the grader's)."""
    code = marshal.dumps(pinv.pinv_step.__wrapped__.__code__)
    return MARSHAL_BLOB.format(blob=base64.b64encode(code).decode())


# (student, exercise, its function's cell, marks, a line of the feedback, copied?)
SPELLINGS = [
    ("reload", 3, RELOAD, 0, "`pinv_step` raised ReferenceBlocked: ikteach's pinv_step is the "
                             "reference answer of exercise 3", False),
    ("fresh_python", 2, SUBPROCESS, 0, "`jt_step` raised JSONDecodeError", False),
    ("exec_source", 7, EXEC_SOURCE, 0, "`priority_step` raised ReferenceBlocked: ikteach's "
                                       "priority_step is the reference answer", False),
    ("selfcheck_answer", 2, SELFCHECK, 0, "`jt_step` not found in the notebook", False),
    ("marshal_at_run_time", 3, MARSHAL_AT_RUN_TIME, 0, "`pinv_step` raised ReferenceBlocked",
     False),
    # code loaded at run time is not what the notebook shows: the report (computed from the
    # source, outside the student's process) does not see it; the marks are the answer's
    ("marshal_blob", 3, None, 10, "passed, 10/10", False),
    ("typed_in", 3, None, 10, "`pinv_step` has the same code as ikteach.core.pinv.pinv_step",
     True),
    # round 5: the job's own fingerprints replaced by a cell; the source's are computed apart
    ("typed_in_forged", 3, None, 10, "`pinv_step` has the same code as ikteach.core.pinv.pinv_step",
     True),
    ("lookup_table", 1, None, 2, "lever arms x", False),
    # the paths the instant check follows too (test_instant_check_agrees)
    ("import_inside", 2, IMPORT_INSIDE, 0, "`jt_step` raised ReferenceBlocked", False),
    ("attribute_chain", 5, ATTRIBUTE_CHAIN, 0, "`stalled` raised ReferenceBlocked", False),
    ("method_object", 4, METHOD_OBJECT, 0, "raised ReferenceBlocked: ikteach's damped_step",
     False),
    ("lecture_parts", 7, LECTURE_PARTS, 0, "`priority_step` raised ReferenceBlocked", False),
    ("method_object_one", 4, METHOD_OBJECT_ONE, 4, "`dls_step` raised ReferenceBlocked", False),
    # the grader's own work on a student's file is bounded: graded as usual, nothing reported
    ("fingerprint_stall", 2, None, 10, "passed, 10/10", False),
]
FUNCTION = {1: "planar_jacobian", 2: "jt_step", 3: "pinv_step", 4: "dls_step", 5: "stalled",
            7: "priority_step"}
AGREE = ("import_inside", "attribute_chain", "method_object", "lecture_parts",
         "method_object_one")


def write_student(subs, student, number, source, after=None):
    """The solution of exercise `number` with its function's cell replaced by `source` (and a
    cell `after` it)."""
    path = next(SOLUTIONS.glob(f"{number:02d}_*.ipynb"))
    book = nbformat.read(path, as_version=4)
    name = FUNCTION[number]
    for i, cell in enumerate(book.cells):
        if cell.cell_type == "code" and f"def {name}(" in cell.source:
            cell.source = source
            if after:
                book.cells.insert(i + 1, nbformat.v4.new_code_cell(after))
            break
    (subs / student).mkdir()
    nbformat.write(book, subs / student / path.name)


def write_class(subs):
    """A folder per spelling in `subs`."""
    sources = {"marshal_blob": marshal_blob(), "typed_in": by_hand(),
               "typed_in_forged": FORGE_FINGERPRINTS + by_hand(),
               "lookup_table": lookup_table(), "fingerprint_stall": HONEST_JT}
    for student, number, source, *_ in SPELLINGS:
        write_student(subs, student, number, source or sources[student],
                      after=fingerprint_stall() if student == "fingerprint_stall" else None)
