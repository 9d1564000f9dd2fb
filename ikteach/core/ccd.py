"""Cyclic coordinate descent: turn one joint at a time, last to first, to point the end
effector at the target (Wang & Chen 1991; Welman 1993)."""
import jax
import jax.numpy as jnp

from .chain import Chain
from .kinematics import joint_frames
from .method import method
from .._runtime.jit import quick_jit


def ccd_angle(z, p, x, t):
    """The turn about the unit axis z through p that brings x closest to t.

    With u, v the parts of x - p and t - p perpendicular to z:
    angle = atan2(z . (u x v), u . v)   (0 when u or v vanishes).
    """
    u = (x - p) - jnp.dot(x - p, z) * z
    v = (t - p) - jnp.dot(t - p, z) * z
    return jnp.arctan2(jnp.dot(z, jnp.cross(u, v)), jnp.dot(u, v))


def as_point3(arm, target):
    """A position target in 3-D (planar targets get z = 0)."""
    return jnp.concatenate([target, jnp.zeros(3 - arm.dim)]) if arm.dim == 2 else target


@quick_jit
def ccd_sweep(arm, target, theta):
    """One CCD iteration: for i = n-1, ..., 0, theta_i += ccd_angle(z_i, p_i, x_end, target)."""
    t = as_point3(arm, target)
    n = arm.n_joints

    def turn(k, q):
        i = n - 1 - k
        positions, axes, _ = joint_frames(arm, q)
        return q.at[i].add(ccd_angle(axes[i], positions[i], positions[-1], t))

    return jax.lax.fori_loop(0, n, turn, jnp.asarray(theta))


def require_chain(arm, name):
    if not isinstance(arm, Chain):
        raise ValueError(f"method: {name!r} works on chains (ik.planar_chain, ik.serial_chain) "
                         f"with position targets, got {type(arm).__name__}")


@method(data=())
class CCD:
    """CCD as a solve method: delta_theta = (theta after one sweep) - theta."""
    uses_jacobian = False
    is_jax = True

    def delta(self, problem, theta, e, J, free=None):
        return ccd_sweep(problem.arm, problem.target, theta) - theta

    def resolved(self, length_scale):
        return self
