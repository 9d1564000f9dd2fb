"""Marks only for the student's own code, in the checks' worker: foreign(namespace, names) says
which graded names are not functions written in the notebook (code from a `<cell N>`), and why:
such a name gets 0. A cell can replace foreign(), as it can wrap anything in a one-line `def`:
what holds is that ikteach's answers are not in the worker at all, only stubs that raise
ReferenceBlocked (reference.py; tests/test_job.py forges foreign() and still gets 0)."""
import functools
import types

CELL = "<cell "


class ReferenceBlocked(BaseException):
    """Raised by a stubbed ikteach reference function in the sandbox (BaseException: `except
    Exception` in the student's code does not turn it into a value)."""


def fixed_step(J, e, delta):
    """A step function step(J, e) that returns `delta` whatever J and e: exercise 5's check
    wraps it in the student's stop rule (a partial of it crosses to the worker by name, and no
    JAX program is compiled for it)."""
    return [float(x) for x in delta]


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


def foreign(namespace, names):
    """{name: why} for graded names bound to code not written in the notebook."""
    out = {}
    for name in names:
        obj = namespace.get(name)
        if obj is None or not callable(obj) or _own(obj):
            continue  # missing or not callable: the check itself says so
        where = (f"{getattr(obj, '__module__', None) or type(obj).__module__}."
                 f"{getattr(obj, '__qualname__', None) or type(obj).__qualname__}")
        out[name] = (f"`{name}` is not a function written in your notebook: it is "
                     f"{where[:120]}. Marks are only for your own code - define "
                     f"`def {name}(...)` in the notebook and compute the answer there.")
    return out
