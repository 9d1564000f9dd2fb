"""The reference rule (docs/lecturers.md, "The reference rule"): what the grader guarantees
about ikteach's own answers, how the check cell applies the same rule, and what is only
reported.

Guaranteed (with bubblewrap): while exercise N is graded, every process of its sandbox (the
fork server, the notebook's run, the checks' worker, anything they start) sees a COPY of
ikteach (sandbox_copy) in which exercise N's reference functions (its check module's
REFERENCES) have a body that raises ReferenceBlocked, and which holds no checker and no
self-check answer. A reload, an exec of ikteach's source file, a fresh interpreter, a pickle
by reference, a method object that runs a reference: all find the stub. The expected values
are computed in the grader's own process, outside the sandbox; only the student's outputs
come back.

The check cell (reached()): the references a student's functions reach through what their
code names (globals, imports at any level, attribute chains, literal strings, defaults,
closures, classes, containers, and ikteach's own functions on the way) give the same 0.

Reported, not prevented: a notebook that carries ikteach's code in its cells (its source typed
or pasted in). That is copying, which only a reader can judge; fingerprint() makes an exact
copy visible: a code object's operations, names, docstrings, file names and line numbers
ignored, compared with the references' (copied(): what matched and how many operations), for
the cells' source compiled in a job where no student code has run (source_fingerprints).
Reordered, rewritten or split code, and code loaded at run time, is not seen. The work is
bounded whatever a file holds (MAX_CODES, MAX_CODE_BYTES, MAX_TOTAL_BYTES).
"""
import ast
import compileall
import dis
import hashlib
import importlib
import os
import py_compile
import shutil
import sys
import tempfile
import types
from pathlib import Path

# what no job imports: the checks (expected values, diagnoses), the grader, the self-check's
# answer, the bundles; left out of the sandbox's copy
LEFT_OUT = ("course/check", "course/grade.py", "course/grading/selfcheck.py",
            "course/grading/gradescope.py", "course/grading/autograder.py")


def stub_source(source, names, exercise):
    """`source` (a module's text) with the top-level functions `names` raising instead; their
    signatures and decorators stay, so every caller (jit, a method table) still works."""
    tree = ast.parse(source)
    found = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name in names:
            label = (f"ikteach's {node.name} is the reference answer of exercise {exercise}; "
                     "graded code must compute it itself")
            node.body = ast.parse("from ikteach.course.grading.own_code import ReferenceBlocked"
                                  f"\nraise ReferenceBlocked({label!r})\n").body
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
# Cheap by construction, whatever a student's file holds: each code object is read once (a
# nested one is a token, not entered again), at most MAX_CODES of them, none longer than
# MAX_CODE_BYTES (a reference is far shorter), and a constant is shown only when it is small.

MIN_OPERATIONS = 20      # shorter functions (a one-line wrapper) are too common to report
MAX_CODE_BYTES = 16384   # longer code cannot be a reference's (the longest is ~1 kB): skipped
MAX_CODES = 400          # code objects compared per notebook (the rest are not)
MAX_TOTAL_BYTES = 1 << 20  # compiled code read per notebook, in all
MAX_NAMES = 300          # names of one function followed (the instant check)
MAX_REACHED = 20000      # objects followed from a student's functions


def _constant(const):
    if isinstance(const, types.CodeType):
        return "code"  # compared on its own (fingerprints), not entered here
    if isinstance(const, bool) or not isinstance(const, (int, float, complex, tuple)):
        return None
    if isinstance(const, int) and const.bit_length() > 64:
        return "const big int"
    if isinstance(const, tuple) and (len(const) > 8 or not all(
            isinstance(c, (int, float, str, type(None))) and not (
                isinstance(c, int) and c.bit_length() > 64) for c in const)):
        return f"const tuple of {len(const)}"
    return f"const {const!r:.80}"


def _operations(code):
    """What `code` does, instruction by instruction: the operations, their numbers and
    operators, not the names they load (nor how a call on a module is spelled: a cell that
    imports `np` itself compiles `np.f()` other than one that does not)."""
    for ins in dis.get_instructions(code):
        if ins.opname == "CACHE":
            continue
        name = "LOAD_ATTR" if ins.opname == "LOAD_METHOD" else ins.opname
        if name == "LOAD_CONST":
            yield _constant(ins.argval) or name
        elif name in ("BINARY_OP", "COMPARE_OP", "CALL", "PRECALL", "CALL_FUNCTION_EX"):
            yield f"{name} {ins.argrepr or ins.arg}"
        else:
            yield name


def fingerprint(code):
    """(a hash of what `code` does (_operations), not of its names, docstring, file or line
    numbers: a copy with renamed variables matches; how many operations that is)."""
    operations = list(_operations(code))
    return hashlib.sha256("\n".join(operations).encode()).hexdigest()[:24], len(operations)


def _codes(code, limit=MAX_CODES):
    """`code` and the code nested in it, breadth first, at most `limit` (no recursion: a
    deeply nested cell costs no stack)."""
    queue, seen = [code], 0
    while queue and seen < limit:
        current = queue.pop(0)
        seen += 1
        yield current
        queue += [c for c in current.co_consts if isinstance(c, types.CodeType)]


def fingerprints(codes):
    """{hash: function name} of every function in `codes` and nested in them (at least
    MIN_OPERATIONS long, at most MAX_CODES of them in all)."""
    out, left, budget = {}, MAX_CODES, MAX_TOTAL_BYTES
    for code in codes:
        for c in _codes(code, left):
            left -= 1
            if c.co_name == "<module>" or len(c.co_code) > min(MAX_CODE_BYTES, budget):
                continue
            budget -= len(c.co_code)
            digest, count = fingerprint(c)
            if count >= MIN_OPERATIONS:
                out[f"{digest}:{count}"] = c.co_name[:80]
        if left <= 0:
            break
    return out


def source_fingerprints(cells, max_chars=200_000):
    """fingerprints() of a notebook's code cells ([(number, source)]) compiled here, cells
    longer than `max_chars` skipped (no reference is near that long; compiling a crafted
    megabyte would cost the grader memory and time outside any limit)."""
    from .extract import without_magics

    found = {}
    for number, source in cells:
        if len(source) > max_chars:
            continue
        try:
            found.update(fingerprints([compile(without_magics(source), f"<cell {number}>",
                                               "exec")]))
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            continue  # not Python: the worker's notes say so
    return found


def _python_function(obj):
    for _ in range(8):
        if isinstance(obj, types.FunctionType):
            return obj
        obj = getattr(obj, "__wrapped__", None)
    return None


def reference_fingerprints(references):
    """{hash: what it is} of ikteach's reference functions ("ikteach.core.x:fn")."""
    out = {}
    for ref in references:
        module, name = ref.split(":")
        fn = _python_function(getattr(importlib.import_module(module), name))
        if fn is not None:
            out.update({h: f"{module}.{name}" for h in fingerprints([fn.__code__])})
    return out


_LIBRARY = tuple({sys.prefix, sys.base_prefix, os.path.dirname(os.__file__)})
_IKTEACH = str(Path(__file__).resolve().parents[2])  # ikteach/


def _entered(fn):
    """Is the function `fn`'s code followed? The student's (a cell's, the notebook's) and
    ikteach's (a method object's step); never a library's (numpy's, JAX's: they do not call
    ikteach)."""
    module, file = str(getattr(fn, "__module__", "") or ""), fn.__code__.co_filename
    return (module == "ikteach" or module.startswith("ikteach.") or file.startswith(_IKTEACH)
            or not file.startswith(_LIBRARY))


def _named(fn):
    """What `fn`'s code names: the globals it loads, the modules it imports (at any level),
    and every attribute chain through them (`ik.core.stop_rules.joint_steps`); strings it
    holds count as names too (`getattr(ik, "jt_step")`, `import_module("ikteach.core.jt")`)."""
    names = []
    for code in _codes(fn.__code__, 50):
        names += code.co_names
        names += [c for c in code.co_consts if isinstance(c, str) and len(c) < 200]
    names = list(dict.fromkeys(names))[:MAX_NAMES]
    found = [fn.__globals__.get(n) for n in names]
    modules = [v for v in found if isinstance(v, types.ModuleType)]
    modules += [m for m in map(sys.modules.get, names) if m is not None]  # imported, read only
    for module in modules:  # grows while it is read: the chains
        if len(modules) > 50:
            break
        try:
            attributes = vars(module)
        except TypeError:
            continue
        for n in names:
            value = attributes.get(n)  # not getattr: no module __getattr__ runs
            if isinstance(value, types.ModuleType):
                if all(value is not m for m in modules):
                    modules.append(value)
            elif value is not None:
                found.append(value)
    return [v for v in found if not isinstance(v, types.ModuleType)]


def _inner(obj):
    inner = [getattr(obj, a, None) for a in ("__wrapped__", "__func__", "func")]
    if isinstance(obj, type):
        inner += list(vars(obj).values()) + [b for b in obj.__mro__[1:] if b is not object]
    elif isinstance(obj, (list, tuple, set, frozenset)):
        inner += list(obj)[:100]
    elif isinstance(obj, dict):
        inner += list(obj.values())[:100]
    elif isinstance(obj, types.FunctionType):
        if _entered(obj):
            inner += _named(obj)
            inner += list(obj.__defaults__ or ()) + list((obj.__kwdefaults__ or {}).values())
            inner += [_content(c) for c in obj.__closure__ or ()]
    elif not isinstance(obj, (types.ModuleType, types.CodeType)):
        inner += [getattr(type(obj), "__call__", None), type(obj)]
    return inner


def _reachable(roots, stop):
    """Every object `roots` lead to through what their code names: functions and their
    wrappers (jit, partial, bound methods, a callable's __call__), the globals, imports and
    attribute chains (ik.core.jt.jt_step) their code names, their defaults and closures,
    classes' methods and bases, an object's class, containers' items (_inner), at most
    MAX_REACHED; library code is never entered, nor the objects whose ids are in `stop`."""
    seen, queue = {}, list(roots)
    while queue and len(seen) < MAX_REACHED:
        obj = queue.pop()
        if obj is None or id(obj) in seen or isinstance(obj, (str, bytes, int, float)):
            continue
        seen[id(obj)] = obj
        if id(obj) in stop:
            continue
        try:
            queue += _inner(obj)
        except Exception:  # noqa: BLE001 - a student's odd object: not entered
            continue
    return list(seen.values())


def _content(cell):
    try:
        return cell.cell_contents
    except ValueError:  # an empty cell
        return None


def reached(functions, references):
    """The references ("ikteach.core.x:fn") that `functions` reach by what their code names,
    ikteach's own functions entered (a method object such as ik.DLS reaches the step it
    runs): the instant check's side of the reference rule (in the grader's sandbox those
    functions are stubs that raise, however they are reached)."""
    targets = {}
    for ref in references:
        module, name = ref.split(":")
        obj = getattr(importlib.import_module(module), name)
        targets.update({id(obj): ref, id(_python_function(obj)): ref})
    found = _reachable(functions, stop=frozenset(targets))
    return sorted({targets[id(o)] for o in found if id(o) in targets})


def copied(found, references):
    """Lines for the instructor: which of the notebook's functions (`found`: {hash: name})
    compile to the same operations as a reference (`references`: {hash: what}), and how many
    operations that is."""
    lines = sorted({f"`{name}` has the same code as {references[h]}: all its "
                    f"{h.rsplit(':', 1)[-1]} compiled operations in the same order, names "
                    "ignored (code written independently from the same formula can match "
                    "too: read both)"
                    for h, name in found.items() if h in references})
    return lines[:5]
