"""The Jacobian J = dx/dtheta, three ways: geometric, automatic and finite differences."""
from functools import partial

import jax
import jax.numpy as jnp

from .kinematics import fk, joint_frames
from .._runtime.jit import quick_jit


@partial(quick_jit, static_argnames="full")
def jacobian(arm, theta, full=False):
    """Geometric Jacobian: column i is z_i x (p_e - p_i), z_i joint i's unit axis.

    Shape (d, n). With full=True the angular rows z_i are appended:
    (6, n) for a spatial chain, (3, n) for a planar arm (x, y and the angle about z).
    """
    positions, axes, _ = joint_frames(arm, theta)
    return jacobian_from_frames(arm, positions, axes, full)


def jacobian_from_frames(arm, positions, axes, full=False):
    """The geometric Jacobian from joint_frames' positions p_0..p_n and axes z_i."""
    linear = jnp.cross(axes, positions[-1] - positions[:-1]).T
    if not full:
        return linear[: arm.dim]
    if arm.dim == 2:
        return jnp.vstack([linear[:2], axes.T[2:]])
    return jnp.vstack([linear, axes.T])


@quick_jit
def jacobian_autodiff(arm, theta):
    """J = dF/dtheta by forward-mode automatic differentiation (jax.jacfwd of fk)."""
    return jax.jacfwd(lambda t: fk(arm, t))(jnp.asarray(theta, dtype=float))


@quick_jit
def jacobian_fd(arm, theta, h=1e-6):
    """J by central differences: column i = (F(theta + h e_i) - F(theta - h e_i)) / 2h."""
    theta = jnp.asarray(theta, dtype=float)
    steps = h * jnp.eye(theta.shape[0])
    columns = jax.vmap(lambda s: (fk(arm, theta + s) - fk(arm, theta - s)) / (2 * h))(steps)
    return columns.T
