"""Marks only for the student's own code: run in the checks' worker, before and after the
student's statements.

- block(references): every function ikteach has for this exercise's answer (the check module's
  REFERENCES, e.g. ikteach.core.jt:jt_step) gets a body that raises ReferenceBlocked: the
  function object itself is changed, so every way to it (ik.jt_step, `from ... import`,
  a default argument, a decorator, a class attribute, jax.jit's __wrapped__, a solver's method
  table) reaches the stub, and a wrapper of it gets nothing from it.
- block_checker(): the checker (ikteach.course.check: the instant checks and their reference
  answers; the grader's self-check, which holds a correct answer) cannot be imported in the worker; in the sandbox its folder is empty as well.
- foreign(namespace, names): which graded names are not functions written in the notebook
  (their code must come from a `<cell N>`), and why - for the feedback: the worker runs the
  student's code, so what holds is the blocked references (their code is gone from this
  process). Not caught: ikteach's source text copied into the notebook (by hand, or read from
  its file at run time) - plagiarism, for the instructor who reads the code.
"""
import functools
import importlib
import sys
import types

CELL = "<cell "
CHECKER = ("ikteach.course.check", "ikteach.course.grade",
           "ikteach.course.grading.selfcheck")  # the self-check holds a correct exercise 2


class ReferenceBlocked(BaseException):
    """Raised by a blocked ikteach function (BaseException: `except Exception` in the student's
    code does not turn it into a value)."""


def _stub_code(label):
    scope = {}
    exec(compile(f"def _blocked(*args, **kwargs):\n"
                 f"    raise __ikteach_blocked__({label!r})\n", "<ikteach: blocked>", "exec"),
         scope)
    return scope["_blocked"].__code__


def _python_function(obj):
    """The plain Python function behind obj (jax.jit, functools.wraps...), or None."""
    for _ in range(8):
        if isinstance(obj, types.FunctionType):
            return obj
        obj = getattr(obj, "__wrapped__", None)
    return None


def block(references, exercise):
    """Give every reference function of the exercise a raising body; returns their names."""
    names = []
    for ref in references:
        module_name, qualname = ref.split(":")
        module = importlib.import_module(module_name)
        fn = _python_function(functools.reduce(getattr, qualname.split("."), module))
        if fn is None or fn.__closure__:
            raise TypeError(f"cannot block {ref}: not a plain function")
        label = (f"ikteach's {qualname} is the reference answer of exercise {exercise}; graded "
                 "code must compute it itself")
        fn.__globals__["__ikteach_blocked__"] = ReferenceBlocked
        fn.__code__ = _stub_code(label)
        names.append(f"{module_name}.{qualname}")
    return names


class _NoChecker:
    """A meta path finder that refuses the checker's modules."""

    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.startswith(CHECKER):
            raise ModuleNotFoundError(f"{name} is not available while grading", name=name)
        return None


def block_checker():
    for name in [n for n in sys.modules if n.startswith(CHECKER)]:
        del sys.modules[name]
        parent, _, child = name.rpartition(".")
        package = sys.modules.get(parent)
        if package is not None:  # e.g. ikteach.course.grading's attribute selfcheck
            package.__dict__.pop(child, None)
    sys.meta_path.insert(0, _NoChecker())
    ikteach = sys.modules.get("ikteach")
    if ikteach is not None:
        ikteach.__dict__.pop("check", None)
        lazy = getattr(ikteach, "LAZY", None)
        if isinstance(lazy, dict):
            lazy.pop("check", None)


def _own(obj):
    """Is obj's code written in the notebook? (a function, a jit/decorated wrapper of one,
    a bound method or a callable instance of a class defined there)."""
    for _ in range(8):
        if isinstance(obj, types.MethodType):
            obj = obj.__func__
        if isinstance(obj, types.FunctionType):
            return obj.__code__.co_filename.startswith(CELL)
        if isinstance(obj, functools.partial):
            obj = obj.func
            continue
        if str(getattr(obj, "__module__", "")).startswith("ikteach"):
            return False  # ikteach's own (a jit wrapper), whatever its __wrapped__ says
        inner = getattr(obj, "__wrapped__", None)
        if inner is None:
            call = getattr(type(obj), "__call__", None)
            return (isinstance(call, types.FunctionType)
                    and call.__code__.co_filename.startswith(CELL))
        obj = inner
    return False


def _where(obj):
    module = getattr(obj, "__module__", None) or type(obj).__module__
    name = getattr(obj, "__qualname__", None) or type(obj).__qualname__
    return f"{module}.{name}"


def foreign(namespace, names):
    """{name: why} for graded names bound to code not written in the notebook."""
    out = {}
    for name in names:
        obj = namespace.get(name)
        if obj is None or not callable(obj) or _own(obj):
            continue  # missing or not callable: the check itself says so
        out[name] = (f"`{name}` is not a function written in your notebook: it is "
                     f"{_where(obj)[:120]}. Marks are only for your own code - define "
                     f"`def {name}(...)` in the notebook and compute the answer there.")
    return out
