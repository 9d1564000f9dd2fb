"""The methods the solve loop can take: a name ("jt", "pinv", "dls", "sdls", "ccd", "fabrik")
or a user's step function step(J, e) -> delta_theta, each turned into an object whose
delta(task, arm, target, theta, e, settings) gives the loop's step."""
import dataclasses
import inspect
from typing import Callable

import jax
import jax.numpy as jnp

from .ccd import CCDMethod
from .chain import Chain
from .dls import dls_step
from .fabrik import FABRIKMethod
from .joint_limits import LimitedMethod
from .jt import jt_step
from .levels import PriorityMethod
from .limits import clamp_error
from .pinv import pinv_step, pinv_two_rows
from .sdls import SDLSMethod


def _jt(J, e, s):
    return jt_step(J, e)


def _pinv(J, e, s):
    if J.shape[0] == 2:  # planar position targets: the closed form, no SVD call
        return pinv_two_rows(J, e, s.rcond)
    return pinv_step(J, e, s.rcond)


def _dls(J, e, s):
    return dls_step(J, e, s.damping)


@dataclasses.dataclass(frozen=True)
class JacobianMethod:
    """A method that turns (J, clamped e) into a step: step(J, e, settings) -> delta_theta."""
    step: Callable

    def delta(self, task, arm, target, theta, e, settings):
        J = task.jacobian(arm, theta)
        return self.step(J, clamp_error(e, settings.clamp), settings)


@dataclasses.dataclass(frozen=True)
class UserStep:
    """A step function step(J, e) -> delta_theta given by the user."""
    fn: Callable

    def __call__(self, J, e, s):
        return check_step(self.fn(J, e))


def check_step(delta):
    """A step function's output as an array of real numbers, or a ValueError naming `method`."""
    what = "method: the step function must return an array delta_theta (one real number per joint)"
    if delta is None or isinstance(delta, (str, bytes)):
        raise ValueError(f"{what}, got {delta!r:.80}")
    try:
        delta = jnp.asarray(delta)
    except TypeError:
        raise ValueError(f"{what}, got {type(delta).__name__} {delta!r:.80}") from None
    if jnp.iscomplexobj(delta):
        raise ValueError(f"{what}, got complex numbers (dtype {delta.dtype})")
    if delta.dtype == bool or not jnp.issubdtype(delta.dtype, jnp.number):
        raise ValueError(f"{what}, got dtype {delta.dtype}")
    return delta


def require_traceable(method, task, arm, target, theta0, settings):
    """solve_batch runs the method under jax.jit and jax.vmap: a ValueError naming `method`
    when a user's step function cannot be traced (numpy calls, float(), branches on values)."""
    if built_in(method):
        return
    try:
        jax.eval_shape(lambda q: method.delta(task, arm, target, q, task.error(arm, target, q),
                                              settings), theta0)
    except ValueError:
        raise
    except Exception as err:
        raise ValueError(f"method: ik.solve_batch compiles the step function (jax.jit, jax.vmap), "
                         f"so batch step functions must use jax.numpy, not numpy or Python "
                         f"branches on values (ik.solve runs either kind); JAX said: "
                         f"{type(err).__name__}: {str(err).splitlines()[0]:.200}") from err


METHODS = {"jt": JacobianMethod(_jt), "pinv": JacobianMethod(_pinv), "dls": JacobianMethod(_dls)}
METHODS.update(sdls=SDLSMethod(), ccd=CCDMethod(), fabrik=FABRIKMethod())


_TRACEABLE = {}


def traceable(method, task, arm, target, theta0, settings):
    """Can JAX trace the method (pure jax.numpy), or does it need eager execution?

    Built-in methods are JAX code; a user's step is tried once per problem shape.
    """
    if built_in(method):
        return True
    key = (method, task, type(arm), arm.dim, target.shape, theta0.shape)
    if key not in _TRACEABLE:
        try:
            jax.eval_shape(lambda q: method.delta(task, arm, target, q, task.error(arm, target, q),
                                                  settings), theta0)
            _TRACEABLE[key] = True
        except Exception:
            _TRACEABLE[key] = False
    return _TRACEABLE[key]


def built_in(method):
    """Is the method ikteach's own JAX code: a built-in method, the priority step, or one of
    those within joint limits? (Only a user's step function needs trying.)"""
    if isinstance(method, LimitedMethod):
        return built_in(method.inner)
    return method in METHODS.values() or isinstance(method, PriorityMethod)


def resolve_method(method):
    """A method name or a step function step(J, e) -> the loop's step(J, e, settings)."""
    if isinstance(method, str):
        if method not in METHODS:
            raise ValueError(f"method: expected one of {sorted(METHODS)} or a function "
                             f"step(J, e) -> delta_theta, got {method!r}")
        return METHODS[method]
    if callable(method):
        try:
            inspect.signature(method).bind(None, None)
        except TypeError:
            raise ValueError("method: a step function must accept two arguments (J, e)") from None
        except ValueError:
            pass  # builtins without a signature
        return JacobianMethod(UserStep(method))
    raise ValueError(f"method: expected one of {sorted(METHODS)} or a function "
                     f"step(J, e) -> delta_theta, got {method!r:.80}")


def check_method_target(method, task, arm, name="target"):
    """CCD and FABRIK move the end effector towards a point: position targets on chains only."""
    kind = {CCDMethod: "ccd", FABRIKMethod: "fabrik"}.get(type(method))
    if kind is None or not isinstance(arm, Chain) or type(task).__name__ == "PositionTask":
        return  # (trees: the method's own check, ccd.require_chain, names them)
    raise ValueError(f"method: {kind!r} works on chains with position targets ({name} of shape "
                     f"({arm.dim},)), got a 4x4 pose target; use 'jt', 'pinv', 'dls' or 'sdls'")
