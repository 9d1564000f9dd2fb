"""The reference rule: what the grader guarantees about ikteach's own answers, and what it only
reports.

Guaranteed (with bubblewrap): while exercise N is graded, every process of its sandbox (the
fork server, the notebook's run, the checks' worker, anything they start) sees a COPY of
ikteach (sandbox_copy) in which exercise N's reference functions (its check module's
REFERENCES) have a body that raises ReferenceBlocked, and which holds no checker and no
self-check answer. A reload, an exec of ikteach's source file, a fresh interpreter, a pickle
by reference: all find the stub. The expected values are computed in the grader's own
process, outside the sandbox; only the student's outputs come back.

Reported, not prevented: a notebook that carries ikteach's code in itself (its source typed or
pasted in, a marshalled code object, an exec'd string). That is copying, which only a reader
can judge; fingerprint() makes it visible: a code object's hash that ignores names,
docstrings, file names and line numbers, compared with the references' and the self-check's
(copied()). The grader writes what matched into grades.csv and the feedback.
"""
import ast
import compileall
import dis
import hashlib
import importlib
import os
import py_compile
import shutil
import tempfile
import types
from pathlib import Path

# what no job imports: the checks (expected values, diagnoses), the grader, the self-check's
# answer, the bundles; left out of the sandbox's copy
LEFT_OUT = ("course/check", "course/grade.py", "course/grading/selfcheck.py",
            "course/grading/gradescope.py", "course/grading/autograder.py")
MIN_CODE_BYTES = 40  # smaller functions (a one-line wrapper) are too common to report


def _stub_body(qualname, exercise):
    label = (f"ikteach's {qualname} is the reference answer of exercise {exercise}; graded "
             "code must compute it itself")
    return ast.parse("from ikteach.course.grading.own_code import ReferenceBlocked\n"
                     f"raise ReferenceBlocked({label!r})\n").body


def stub_source(source, names, exercise):
    """`source` (a module's text) with the top-level functions `names` raising instead; their
    signatures and decorators stay, so every caller (jit, a method table) still works."""
    tree = ast.parse(source)
    found = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name in names:
            node.body = _stub_body(node.name, exercise)
            found.add(node.name)
    if found != set(names):
        raise ValueError(f"references: {sorted(set(names) - found)} are not top-level "
                         "functions of their module")
    return ast.unparse(tree) + "\n"


def sandbox_copy(package, dest, references=(), exercise=None, base=None):
    """The folder `dest` (made once: a finished copy is reused), a copy of ikteach's
    `package` without LEFT_OUT, its `references` ("ikteach.core.x:fn") stubbed, compiled.
    `base`: such a copy without stubs to start from (its compiled files are reused; those of
    the stubbed modules are removed and made again from the stubs)."""
    dest = Path(dest)
    if dest.is_dir():
        return dest
    staging = Path(tempfile.mkdtemp(prefix=".copy-", dir=dest.parent)) / "ikteach"
    if base is None:
        shutil.copytree(package, staging, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        for left_out in LEFT_OUT:
            path = staging / left_out
            if path.is_dir():
                shutil.rmtree(path)
                path.mkdir()  # an empty folder: the sandbox lays a tmpfs over it
            else:
                path.unlink(missing_ok=True)
        compileall.compile_dir(str(staging), quiet=2, ddir=str(package))
    else:
        shutil.copytree(base, staging)
    by_module = {}
    for ref in references:
        module, name = ref.split(":")
        by_module.setdefault(module, []).append(name)
    for module, names in by_module.items():
        path = staging.joinpath(*module.split(".")[1:]).with_suffix(".py")
        path.write_text(stub_source(path.read_text(encoding="utf-8"), names, exercise),
                        encoding="utf-8")
        for compiled in path.parent.glob(f"__pycache__/{path.stem}.*.pyc"):
            compiled.unlink()  # the reference's own code: not left as a file
        py_compile.compile(str(path), dfile=str(package.joinpath(*path.relative_to(staging).parts)))
    try:
        os.rename(staging, dest)
    except OSError:  # another grading process made it first
        shutil.rmtree(staging.parent, ignore_errors=True)
    return dest


# --- fingerprints: copied code, reported ---------------------------------------------------

def _operations(code):
    """What `code` does, instruction by instruction: the operations, their numbers and
    operators, not the names they load (nor how a call on a module is spelled: a cell that
    imports `np` itself compiles `np.f()` other than one that does not)."""
    for ins in dis.get_instructions(code):
        if ins.opname == "CACHE":
            continue
        name = "LOAD_ATTR" if ins.opname == "LOAD_METHOD" else ins.opname
        if name == "LOAD_CONST":
            const = ins.argval
            if isinstance(const, types.CodeType):
                yield f"code {fingerprint(const)}"
            elif isinstance(const, (int, float, complex, tuple)) and not isinstance(const, bool):
                yield f"const {const!r}"
            else:
                yield name
        elif name in ("BINARY_OP", "COMPARE_OP", "CALL", "PRECALL", "CALL_FUNCTION_EX"):
            yield f"{name} {ins.argrepr or ins.arg}"
        else:
            yield name


def fingerprint(code):
    """A hash of what `code` does (_operations), not of its names, docstring, file or line
    numbers: a copy with renamed variables matches."""
    return hashlib.sha256("\n".join(_operations(code)).encode()).hexdigest()[:24]


def _codes(code):
    yield code
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            yield from _codes(const)


def fingerprints(codes):
    """{hash: function name} of every function in `codes` and nested in them (big enough)."""
    return {fingerprint(c): c.co_name for code in codes for c in _codes(code)
            if c.co_name != "<module>" and len(c.co_code) >= MIN_CODE_BYTES}


def _python_function(obj):
    for _ in range(8):
        if isinstance(obj, types.FunctionType):
            return obj
        obj = getattr(obj, "__wrapped__", None)
    return None


def reference_fingerprints(references, extra_sources=()):
    """{hash: what it is} of ikteach's reference functions and of answers given as source."""
    out = {}
    for ref in references:
        module, name = ref.split(":")
        fn = _python_function(getattr(importlib.import_module(module), name))
        if fn is not None:
            out.update({h: f"{module}.{name}" for h in fingerprints([fn.__code__])})
    for label, source in extra_sources:
        out.update({h: label for h in fingerprints([compile(source, label, "exec")])})
    return out


def _reachable(roots, depth=4):
    """Every object `roots` lead to through what their code names: functions and their
    wrappers (jit, partial, bound methods, a callable's __call__), the globals and module
    attributes (ik.jacobian) their code names, their defaults and closures, classes' methods,
    containers' items. ikteach's own functions are reached, not entered."""
    seen = {}

    def visit(obj, left):
        if obj is None or id(obj) in seen or left < 0:
            return
        seen[id(obj)] = obj
        inner = [getattr(obj, a, None) for a in ("__wrapped__", "__func__", "func")]
        if isinstance(obj, type):
            inner += list(vars(obj).values())
        elif isinstance(obj, (list, tuple, dict)):
            inner += list(obj.values() if isinstance(obj, dict) else obj)[:100]
        elif isinstance(obj, types.FunctionType):
            if not str(obj.__module__).startswith("ikteach"):
                names = {n for code in _codes(obj.__code__) for n in code.co_names}
                values = [obj.__globals__.get(n) for n in names]
                inner += values + [vars(v).get(n) for v in values  # not a module's __getattr__
                                   if isinstance(v, types.ModuleType) for n in names]
                inner += list(obj.__defaults__ or ()) + [_content(c) for c in obj.__closure__ or ()]
        elif not isinstance(obj, types.ModuleType):
            inner.append(getattr(type(obj), "__call__", None))
        for value in inner:
            visit(value, left - 1)

    for root in roots:
        try:
            visit(root, depth)
        except Exception:  # noqa: BLE001 - a student's odd object: not entered
            continue
    return list(seen.values())


def _content(cell):
    try:
        return cell.cell_contents
    except ValueError:  # an empty cell
        return None


def held_code(namespace):
    """The code objects a namespace holds (in the worker, after the student's statements):
    its functions' and those they reach, and bare code objects (a marshalled blob)."""
    found = _reachable(list(namespace.values()))
    return ([o.__code__ for o in found if isinstance(o, types.FunctionType)]
            + [o for o in found if isinstance(o, types.CodeType)])


def reached(functions, references):
    """The references ("ikteach.core.x:fn") that `functions` reach by what their code names
    (for the instant check: in the grader's sandbox those are stubs that raise)."""
    targets = {}
    for ref in references:
        module, name = ref.split(":")
        obj = getattr(importlib.import_module(module), name)
        targets.update({id(obj): ref, id(_python_function(obj)): ref})
    return sorted({targets[id(o)] for o in _reachable(functions) if id(o) in targets})


def copied(found, references):
    """Lines for the instructor: which of the notebook's functions (`found`: {hash: name})
    have the same code as a reference (`references`: {hash: what})."""
    lines = sorted({f"`{name}` has the same code as {references[h]}"
                    for h, name in found.items() if h in references})
    return lines[:5]

