"""What a solve method is: an object that owns its parameters and gives the loop its step.

A Jacobian method only writes step(J, e) -> delta_theta (e.g. ik.DLS: J^T (J J^T + lambda^2 I)^-1 e).
Other methods (CCD, FABRIK) write delta(problem, theta, e, J) themselves. Parameters are
fields: numbers are traced, so a new value (a new lambda) reuses the compiled loop.
"""
from ._pytree import pytree_dataclass, replace

method = pytree_dataclass  # @method(data=("damping",)) class DLS(JacobianMethod): ...


class JacobianMethod:
    """Base of the methods that turn (J, e) into a step."""
    uses_jacobian = True
    is_jax = True  # written with jax.numpy: compiled without a trial trace

    def step(self, J, e):
        raise NotImplementedError

    def delta(self, problem, theta, e, J, free=None):
        """The loop's step at theta (free: the joints a joint-limit pass left free)."""
        return self.step(J, e)

    def resolved(self, length_scale):
        """The method with defaults that are lengths filled in for an arm of this size."""
        return self


__all__ = ["JacobianMethod", "method", "replace"]
