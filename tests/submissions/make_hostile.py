"""Write the hostile submissions of this folder from the solutions and templates.

    .venv/bin/python tests/submissions/make_hostile.py

Each is one student folder with one notebook: a solution or an untouched template plus cells
that attack the grader. tests/test_grade.py grades them all and holds the expected marks.
"""
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
SOLUTION = ROOT / "instructor" / "solutions"
TEMPLATE = ROOT / "notebooks" / "exercises"

FORGE_CHECK = '''\
import sys, types, ikteach, ikteach.course.check
class _Pass:  # a verdict that claims full marks
    exercise, name, status, score, max_score, passed = 3, "x", "passed", 10.0, 10.0, True
    message = "Exercise 3: passed, 10/10 - well done!"
    parts = {}
    def summary(self): return self.message
ikteach.course.check.grade = lambda number, namespace: _Pass()
ikteach.course.check.pinv_step = lambda *a: print(_Pass.message)
ikteach.course.check.pinv_step_verdict = lambda *a: _Pass()
fake = types.ModuleType("ikteach.course.check"); fake.grade = ikteach.course.check.grade
sys.modules["ikteach.course.check"] = fake
ikteach.course.check = fake
'''

FORGE_OUTPUT = '''\
import builtins, sys, json
for n in range(20):  # fake grade lines in every format the old grader read
    print("IKTEACH-GRADE-" + "%024x" % n + ":" + json.dumps(
        {"score": 10, "max": 10, "status": "passed", "message": "passed, 10/10"}))
builtins.print = lambda *a, **k: sys.__stdout__.write("Exercise 2: passed, 10/10\\n")
class _Out:
    def write(self, text): return sys.__stdout__.write(text.replace("0/10", "10/10"))
    def flush(self): pass
sys.stdout = _Out()
sys.displayhook = lambda value: sys.__stdout__.write("passed, 10/10\\n")
'''

PATCH_IN_FUNCTION = '''\
def jt_step(J, e):
    """Patch the checks from inside the function, then return a fixed-alpha step."""
    import ikteach.course.check.verdicts as v
    import ikteach.course.check.registry as r
    v._close = lambda *a, **k: True
    r.grade = lambda *a: None
    return 0.1 * (J.T @ e)
'''

WRITE_OUTSIDE = '''\
import os, pathlib
for target in [pathlib.Path("/tmp/ikteach-escaped.txt"), pathlib.Path.home() / "escaped.txt",
               pathlib.Path(ik.__file__).parents[1] / "ESCAPED.txt", pathlib.Path("../../ESCAPED.txt"),
               pathlib.Path("/var/tmp/ikteach-escaped.txt")]:
    try:
        target.write_text("escaped")
    except OSError:
        pass
'''

STEAL = '''\
def dls_step(J, e, damping):
    """Take the instructor's solution (or another student's) and run it."""
    import glob, json, pathlib
    places = [str(pathlib.Path(ik.__file__).parents[1] / "instructor" / "solutions" / "*.ipynb"),
              "/tmp/**/04_dls_step.ipynb"]
    for pattern in places:
        for path in glob.glob(pattern, recursive=True):
            for cell in json.load(open(path))["cells"]:
                if "def dls_step(" in "".join(cell["source"]) and "NotImplementedError" not in "".join(cell["source"]):
                    scope = {"np": np, "ik": ik}
                    exec("".join(cell["source"]), scope)
                    return scope["dls_step"](J, e, damping)
    raise FileNotFoundError("no solution to copy")


def dls_step_normal(J, e, damping):
    return dls_step(J, e, damping)
'''

FORK_STORM = '''\
import subprocess
children = []
for _ in range(400):  # bounded: at most 400 sleepers
    try:
        children.append(subprocess.Popen(["sleep", "77.125"]))
    except OSError:
        break
print(len(children) > 0)
'''

MEMORY = '''\
import numpy as np
big = np.ones(2 * 10**9)  # 16 GB
'''

SIGINT_LOOP = '''\
import signal
signal.signal(signal.SIGINT, signal.SIG_IGN)
while True:
    pass
'''

HUGE_OUTPUT = '''\
line = "x" * 1_000_000
for _ in range(150):  # 150 MB of output
    print(line)
'''

# --- marks only for the student's own code (issue 24, class 1) -------------------------------
REF_PLAIN = "def jt_step(J, e):\n    return ik.jt_step(J, e)\n"
REF_IMPORT = "from ikteach.core.jt import jt_step\n"
REF_DECORATOR = '''\
def _use_library(f):
    return ik.pinv_step


@_use_library
def pinv_step(J, e, rcond):
    raise NotImplementedError
'''
REF_DEFAULT = '''\
def dls_step(J, e, damping, _ref=ik.dls_step):
    return _ref(J, e, damping)


def dls_step_normal(J, e, damping, _ref=ik.dls_step_normal):
    return _ref(J, e, damping)
'''
REF_CLASS = '''\
class _Library:
    planar_jacobian = staticmethod(lambda lengths, theta: ik.jacobian(ik.planar_chain(lengths), theta))


planar_jacobian = _Library.planar_jacobian
'''
REF_ANNOTATION = "priority_step: ik.priority_step = ik.priority_step\n"
REF_CHECKER = '''\
def study(jt_step, pinv_step, dls_step):
    return ik.check.ex06_singularity_study._reference_study()
'''
REF_CHECKER_REIMPORT = '''\
def study(jt_step, pinv_step, dls_step):
    """Undo the worker's import block, import the checker afresh, return its answers."""
    import importlib, sys
    sys.meta_path[:] = [f for f in sys.meta_path if type(f).__name__ != "_NoChecker"]
    for name in [n for n in sys.modules if n.startswith("ikteach.course.check")]:
        del sys.modules[name]
    return importlib.import_module("ikteach.course.check.ex06_singularity_study")._reference_study()
'''

# --- time limits the student can switch off (class 3); the sandbox as root (class 4) -----------
SIGALRM_SLEEP = '''\
import signal, time
_alarm = signal.signal(signal.SIGALRM, signal.SIG_IGN)
_interrupt = signal.signal(signal.SIGINT, signal.SIG_IGN)
_forever = time.sleep(10**6)
'''
REMOUNT_PLANT = '''\
import ctypes, pathlib
_libc = ctypes.CDLL(None, use_errno=True)
_package = pathlib.Path(ik.__file__).parent
_detach = _libc.umount2(str(_package / "course" / "check").encode(), 2)
_remount_root = _libc.mount(None, b"/", None, 32 | 4096, None)
_remount_package = _libc.mount(None, str(_package).encode(), None, 32 | 4096, None)
_new_userns = _libc.unshare(0x10000000)
_plant = (_package / "course" / "planted_by_student.py").write_text("FULL_MARKS = True\\n")
_plant2 = (_package.parent / "planted_by_student.py").write_text("FULL_MARKS = True\\n")
'''

# --- a job's resources stay in its job (issue 35, class 1) --------------------------------------
FILL_TMPFS = '''\
import os
_written = {}
for _folder in ["/tmp", "/dev/shm", os.environ["HOME"]]:  # the working folder holds HOME
    _written[_folder] = 0
    for _i in range(24):  # 16 MiB files, each under RLIMIT_FSIZE: at most 384 MiB a folder
        try:
            with open(os.path.join(_folder, f"fill-{_i}"), "wb") as _file:
                _file.write(b"x" * (16 << 20))
        except OSError:
            break
        _written[_folder] += 16
raise RuntimeError(f"MiB written: {_written}")
'''
HUGE_ARRAY = '''\
def dls_step(J, e, damping):
    """A 1 TiB array in the checked function itself."""
    return np.ones((1 << 40) // 8)


def dls_step_normal(J, e, damping):
    return dls_step(J, e, damping)
'''
CPU_STORM = '''\
import os, time
def _storm(n):
    """n busy children, each in a session of its own where it may (a scheduler autogroup each)."""
    for _ in range(n):
        if os.fork() == 0:
            try:
                os.setsid()
            except OSError:
                pass
            while True:
                pass
_children = _storm(200)  # kept by the checks' worker too: a storm beside the checks as well
time.sleep(10**6)
'''
SHELL_ESCAPES = "\n".join(["!x"] * 300)  # one cell of 300 shell escapes
RELAY = '''\
import ctypes, os
_libc = ctypes.CDLL(None, use_errno=True)
_libc.shmat.restype = ctypes.c_void_p
_NAME, _KEY, _KEYS = b"/ikteach-relay", 0x5EED, {"x86_64": (248, 249, 250), "aarch64": (217, 218, 219)}
_ANSWER = b"""def jt_step(J, e):
    J, e = np.asarray(J), np.asarray(e)
    g = J.T @ e
    v = J @ g
    vv = v @ v
    return np.zeros(J.shape[1]) if vv == 0 else (e @ v / vv) * g
"""
def _relay_put():
    """In exercise 1's job: the answer into a POSIX queue, SysV memory and a keyring."""
    import platform
    queue = _libc.mq_open(_NAME, os.O_CREAT | os.O_WRONLY, 0o666, None)
    if queue >= 0:
        _libc.mq_send(queue, _ANSWER, len(_ANSWER), 0)
    shm = _libc.shmget(_KEY, 4096, 0o1666)
    if shm >= 0:
        ctypes.memmove(_libc.shmat(shm, None, 0), _ANSWER, len(_ANSWER))
    add_key = _KEYS.get(platform.machine(), (None,))[0]
    if add_key:
        _libc.syscall(add_key, b"user", b"ikteach-relay", _ANSWER, len(_ANSWER), -4)
def _relay_get():
    """In exercise 2's job: whatever exercise 1's left, if anything."""
    import platform
    buffer = ctypes.create_string_buffer(1 << 16)
    queue = _libc.mq_open(_NAME, os.O_RDONLY | os.O_NONBLOCK)
    if queue >= 0 and _libc.mq_receive(queue, buffer, len(buffer), None) > 0:
        return buffer.value
    shm = _libc.shmget(_KEY, 0, 0)
    if shm >= 0:
        return ctypes.string_at(_libc.shmat(shm, None, 0))
    calls = _KEYS.get(platform.machine())
    if calls:
        key = _libc.syscall(calls[1], b"user", b"ikteach-relay", None, 0)
        if key >= 0 and _libc.syscall(calls[2], 11, key, buffer, len(buffer)) > 0:
            return buffer.value
    return None
_found = {}
def jt_step(J, e):
    if "code" not in _found:
        _found["code"] = _relay_get()
    if not _found["code"]:
        raise RuntimeError("no relay: nothing the notebook's run left was found")
    scope = {"np": np}
    exec(_found["code"], scope)
    return scope["jt_step"](J, e)
'''


def notebook(base, extra_cells, before_check=True):
    """A copy of `base` with code cells added before its check cell (or at the end)."""
    book = nbformat.read(base, as_version=4)
    at = next((i for i, c in enumerate(book.cells)
               if c.cell_type == "code" and c.source.startswith("ik.check.")), len(book.cells))
    if not before_check:
        at = len(book.cells)
    for source in reversed(extra_cells):
        book.cells.insert(at, nbformat.v4.new_code_cell(source))
    for cell in book.cells:
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    return book


def notebook_with(book, extra_cells):
    """notebook() on a notebook already read (`book`)."""
    at = next((i for i, c in enumerate(book.cells)
               if c.cell_type == "code" and c.source.startswith("ik.check.")), len(book.cells))
    for source in reversed(extra_cells):
        book.cells.insert(at, nbformat.v4.new_code_cell(source))
    return book


def replace_function(base, source):
    """`base` with its solution cell (the one defining the first name of source) replaced."""
    return replace_cell(base, source.split("def ", 1)[1].split("(", 1)[0], source)


def replace_cell(base, name, source):
    """`base` with the cell that defines `name` replaced by `source` (any statement kind)."""
    book = nbformat.read(base, as_version=4)
    for cell in book.cells:
        if cell.cell_type == "code" and f"def {name}(" in cell.source:
            cell.source = source
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    return book


# issue 50: magics a student types out of habit, on the first lines of a helper cell
LINE_MAGICS = {1: "%matplotlib widget", 2: "%time _t = 1", 3: "%timeit -n1 -r1 1",
               4: "%load_ext autoreload\n%autoreload 2", 5: "%pip install --quiet ikteach",
               6: "!ls\n_files = !ls", 7: '%config InlineBackend.figure_format = "retina"'}


def with_magics(base):
    """`base` with every cell that defines a function starting with a magic (%%time, or
    `%matplotlib inline` in even exercises), and each function calling a helper from a cell that
    starts with `%matplotlib inline` and a line magic: a magic that takes its cell with it
    costs every mark (issue 50)."""
    book = nbformat.read(base, as_version=4)
    magic = "%matplotlib inline" if int(Path(base).name[:2]) % 2 == 0 else "%%time"
    for cell in book.cells:
        if cell.cell_type == "code" and "def " in cell.source:
            lines = [(line + "\n    _log()") if line.startswith("def ") else line
                     for line in cell.source.splitlines()]
            cell.source = f"{magic}\n" + "\n".join(lines)
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    at = next(i for i, c in enumerate(book.cells) if c.cell_type == "code" and "def " in c.source)
    book.cells.insert(at, nbformat.v4.new_code_cell(
        f"%matplotlib inline\n{LINE_MAGICS[int(Path(base).name[:2])]}\n\n\n"
        "def _log(*values):\n    return values\n"))
    return book


def write(student, name, book):
    folder = HERE / student
    folder.mkdir(parents=True, exist_ok=True)
    if isinstance(book, str):
        (folder / name).write_text(book)
    else:
        nbformat.write(book, folder / name)


def main():
    write("forge_check", "03_pinv_step.ipynb", notebook(TEMPLATE / "03_pinv_step.ipynb", [FORGE_CHECK]))
    write("forge_output", "02_jt_step.ipynb", notebook(TEMPLATE / "02_jt_step.ipynb", [FORGE_OUTPUT]))
    write("patch_in_function", "02_jt_step.ipynb",
          replace_function(SOLUTION / "02_jt_step.ipynb", PATCH_IN_FUNCTION))
    write("write_outside", "01_jacobian.ipynb", notebook(SOLUTION / "01_jacobian.ipynb", [WRITE_OUTSIDE]))
    write("steal_solution", "04_dls_step.ipynb", replace_function(SOLUTION / "04_dls_step.ipynb", STEAL))
    write("fork_storm", "02_jt_step.ipynb", notebook(SOLUTION / "02_jt_step.ipynb", [FORK_STORM]))
    write("memory_hog", "04_dls_step.ipynb", notebook(SOLUTION / "04_dls_step.ipynb", [MEMORY]))
    write("sigint_loop", "05_stop_rule.ipynb", notebook(SOLUTION / "05_stop_rule.ipynb", [SIGINT_LOOP]))
    write("huge_output", "01_jacobian.ipynb", notebook(SOLUTION / "01_jacobian.ipynb", [HUGE_OUTPUT]))
    write("not_json", "01_jacobian.ipynb", "this is not a notebook {\n")
    empty = nbformat.v4.new_notebook()
    empty.cells = [nbformat.v4.new_markdown_cell("# Exercise 3"),
                   nbformat.v4.new_code_cell("print('I did not write any function')")]
    write("no_functions", "03_pinv_step.ipynb", empty)
    write("ref_plain", "02_jt_step.ipynb", replace_cell(SOLUTION / "02_jt_step.ipynb", "jt_step", REF_PLAIN))
    write("ref_import", "02_jt_step.ipynb", replace_cell(SOLUTION / "02_jt_step.ipynb", "jt_step", REF_IMPORT))
    write("ref_decorator", "03_pinv_step.ipynb",
          replace_cell(SOLUTION / "03_pinv_step.ipynb", "pinv_step", REF_DECORATOR))
    write("ref_default", "04_dls_step.ipynb", replace_cell(SOLUTION / "04_dls_step.ipynb", "dls_step", REF_DEFAULT))
    write("ref_class", "01_jacobian.ipynb",
          replace_cell(SOLUTION / "01_jacobian.ipynb", "planar_jacobian", REF_CLASS))
    write("ref_annotation", "07_priority_step.ipynb",
          replace_cell(SOLUTION / "07_priority_step.ipynb", "priority_step", REF_ANNOTATION))
    write("ref_checker", "06_singularity_study.ipynb",
          replace_cell(SOLUTION / "06_singularity_study.ipynb", "study", REF_CHECKER))
    write("ref_checker_reimport", "06_singularity_study.ipynb",
          replace_cell(SOLUTION / "06_singularity_study.ipynb", "study", REF_CHECKER_REIMPORT))
    write("sigalrm_sleep", "02_jt_step.ipynb", notebook(SOLUTION / "02_jt_step.ipynb", [SIGALRM_SLEEP]))
    write("remount_plant", "02_jt_step.ipynb", notebook(SOLUTION / "02_jt_step.ipynb", [REMOUNT_PLANT]))
    write("fill_tmpfs", "02_jt_step.ipynb", notebook(SOLUTION / "02_jt_step.ipynb", [FILL_TMPFS]))
    write("huge_array", "04_dls_step.ipynb", replace_function(SOLUTION / "04_dls_step.ipynb", HUGE_ARRAY))
    # exercise 1's job (graded first) leaves the answer; exercise 2's looks for it
    write("ipc_relay", "01_jacobian.ipynb", notebook(TEMPLATE / "01_jacobian.ipynb",
                                                     [RELAY, "_relay_put()"]))
    write("ipc_relay", "02_jt_step.ipynb", replace_cell(SOLUTION / "02_jt_step.ipynb", "jt_step",
                                                        RELAY))
    for path in sorted(SOLUTION.glob("*.ipynb")):
        write("cell_magic", path.name, with_magics(path))
    # graded in a class of their own (tests/test_isolation.py), beside an honest classmate
    write("storm_class/cpu_storm", "02_jt_step.ipynb",
          notebook(SOLUTION / "02_jt_step.ipynb", [CPU_STORM]))
    write("storm_class/shell_escapes", "02_jt_step.ipynb",
          notebook(SOLUTION / "02_jt_step.ipynb", [SHELL_ESCAPES] * 40))


if __name__ == "__main__":
    main()
