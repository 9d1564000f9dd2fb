"""Planar arms by cumulative sums: the solver's fast path for chains with dim 2.

A planar chain turns every joint about z, so joint i's world angle is the running sum
phi_i = a_1 theta_1 + ... + a_i theta_i (a_i = +-1, the axis' z component), and
  p_{i+1} = p_i + Rot(phi_i) o_i,   column i of J = z x (p_e - p_i) = (-(y_e - y_i), x_e - x_i) a_i.
Same numbers as kinematics.joint_frames and jacobian.jacobian (tests/test_planar.py) with
a few adds and one sin/cos per joint instead of a 3 x 3 matrix product per joint.
"""
import jax.numpy as jnp


def planar_positions(arm, theta):
    """Base, joints and end effector (n + 1, 2) of a planar chain, by cumulative sums."""
    spin = jnp.asarray(arm.axes)[:, 2]
    phi = jnp.cumsum(spin * theta)
    c, s = jnp.cos(phi), jnp.sin(phi)
    ox, oy = jnp.asarray(arm.offsets)[:, 0], jnp.asarray(arm.offsets)[:, 1]
    links = jnp.stack([c * ox - s * oy, s * ox + c * oy], axis=1)
    base = jnp.asarray(arm.base)[:2]
    return jnp.concatenate([base[None], base + jnp.cumsum(links, axis=0)])


def planar_fk(arm, theta):
    """End-effector position (2,) of a planar chain."""
    return planar_positions(arm, theta)[-1]


def planar_jacobian(arm, theta):
    """The geometric Jacobian (2, n) of a planar chain: z x (p_e - p_i) per column."""
    p = planar_positions(arm, theta)
    r = p[-1] - p[:-1]
    spin = jnp.asarray(arm.axes)[:, 2]
    return jnp.stack([-r[:, 1] * spin, r[:, 0] * spin])

