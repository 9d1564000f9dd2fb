"""The methods the solve loop takes, listed once: a method object (ik.DLS(damping=0.2)), its
name as shorthand ("dls"), or a user's step function step(J, e) -> delta_theta."""
import inspect
from typing import Callable

import jax
import jax.numpy as jnp

from .ccd import CCD
from .dls import DLS
from .fabrik import FABRIK
from .jt import JT
from .method import JacobianMethod, method
from .pinv import Pinv
from .sdls import SDLS

METHODS = {"jt": JT, "pinv": Pinv, "dls": DLS, "sdls": SDLS, "ccd": CCD, "fabrik": FABRIK}


@method(data=(), meta=("fn",))
class StepFunction(JacobianMethod):
    """A step function step(J, e) -> delta_theta given by the user."""
    fn: Callable
    is_jax = False  # numpy, float(), branches on values: tried before compiling

    def step(self, J, e):
        return check_step(self.fn(J, e))

    def delta(self, problem, theta, e, J, free=None):
        delta = self.step(J, e)
        if delta.shape != theta.shape:
            raise ValueError(f"method: the step function returned shape {delta.shape}, "
                             f"expected {theta.shape} (one entry per joint)")
        return delta.astype(theta.dtype)


def check_step(delta):
    """A step function's output as an array of real numbers, or a ValueError naming `method`."""
    what = "method: the step function must return an array delta_theta (one real number per joint)"
    if delta is None or isinstance(delta, (str, bytes)):
        raise ValueError(f"{what}, got {delta!r:.80}")
    if isinstance(delta, dict):
        raise ValueError(f"{what}, got a dict {delta!r:.80}")
    try:
        delta = jnp.asarray(delta)
    except TypeError:
        raise ValueError(f"{what}, got {type(delta).__name__} {delta!r:.80}") from None
    if jnp.iscomplexobj(delta):
        raise ValueError(f"{what}, got complex numbers (dtype {delta.dtype})")
    if delta.dtype == bool or not jnp.issubdtype(delta.dtype, jnp.number):
        raise ValueError(f"{what}, got dtype {delta.dtype}")
    return delta


def method_parameters(cls):
    """The parameters a method class owns (its fields), e.g. ("damping",) for DLS."""
    return tuple(getattr(cls, "__dataclass_fields__", {}))


def as_method(method, **parameters):
    """A method object from a name, an object, or a step function.

    With a name, each parameter given goes to the method if it owns it (damping reaches DLS;
    "jt" has none and ignores it, once ik.DLS has checked it), so one set of keywords serves a
    loop over method names."""
    if isinstance(method, str):
        if method not in METHODS:
            raise ValueError(f"method: expected one of {sorted(METHODS)}, a method object such "
                             f"as ik.DLS(damping=0.2), or a function step(J, e) -> delta_theta, "
                             f"got {method!r:.80}")
        cls = METHODS[method]
        given = {k: v for k, v in parameters.items() if v is not None}
        for name, value in given.items():  # one it does not own is still checked by its owner
            owner = next((c for c in METHODS.values() if name in method_parameters(c)), None)
            if owner is not None and owner is not cls:
                owner(**{name: value})
        return cls(**{k: v for k, v in given.items() if k in method_parameters(cls)})
    if any(v is not None for v in parameters.values()):
        name = next(k for k, v in parameters.items() if v is not None)
        raise ValueError(f"{name}: give it to the method object (e.g. ik.DLS(damping=...)), "
                         f"not beside method={method!r:.60}")
    if isinstance(method, type):
        raise ValueError(f"method: expected a method object such as {method.__name__}() (with "
                         f"its parameters), got the class {method.__name__} itself")
    if hasattr(method, "delta"):
        return method
    if callable(method):
        try:
            inspect.signature(method).bind(None, None)
        except TypeError:
            raise ValueError("method: a step function must accept two arguments (J, e)") from None
        except ValueError:
            pass  # builtins without a signature
        return StepFunction(method)
    raise ValueError(f"method: expected one of {sorted(METHODS)}, a method object or a "
                     f"function step(J, e) -> delta_theta, got {method!r:.80}")


def trace_failure(method, problem, theta0):
    """None when JAX can trace the method's step at theta0 (methods written in JAX say so:
    is_jax); else the error tracing a user's step function raised (a ValueError of ours is
    raised as it is)."""
    if method.is_jax:
        return None
    try:
        jax.eval_shape(lambda q: method.delta(problem, q, problem.error(q), problem.jacobian(q)),
                       theta0)
        return None
    except ValueError:
        raise
    except Exception as err:
        return err


def traceable(method, problem, theta0):
    """Can JAX trace the method's step here (pure jax.numpy), or must it run eagerly?"""
    return trace_failure(method, problem, theta0) is None


def require_traceable(method, problem, theta0, caller):
    """A ValueError naming `method` when `caller` (which compiles the step) cannot trace it."""
    err = trace_failure(method, problem, theta0)
    if err is not None:
        raise ValueError(f"method: {caller} compiles the step function (jax.jit, jax.vmap), so "
                         f"its step functions must use jax.numpy, not numpy or Python branches "
                         f"on values (ik.solve runs either kind); JAX said: "
                         f"{type(err).__name__}: {str(err).splitlines()[0]:.200}") from err


def check_method_target(method, problem, name="target"):
    """CCD and FABRIK move the end effector towards a point: position targets on chains."""
    if method.uses_jacobian:
        return
    kind = type(method).__name__.lower()
    if not hasattr(problem.arm, "offsets"):
        raise ValueError(f"method: {kind!r} works on chains (ik.planar_chain, ik.serial_chain) "
                         f"with position targets, got {type(problem.arm).__name__}")
    if type(problem.task).__name__ != "PositionTask":
        raise ValueError(f"method: {kind!r} works on chains with position targets ({name} of "
                         f"shape ({problem.arm.dim},)), got a 4x4 pose target; use 'jt', "
                         f"'pinv', 'dls' or 'sdls'")
