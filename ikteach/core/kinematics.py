"""Forward kinematics: x = F(theta), by walking the chain from base to end effector."""
import jax
import jax.numpy as jnp
import numpy as np
from .._runtime.jit import quick_jit


def skew(omega):
    """The cross-product matrix [omega]x, so that [omega]x v = omega x v."""
    o = omega
    return jnp.array([[0.0, -o[2], o[1]], [o[2], 0.0, -o[0]], [-o[1], o[0], 0.0]])


def rotation_about(axis, angle):
    """Rodrigues' formula: R = I + sin(t) [a]x + (1 - cos(t)) [a]x^2 for a unit axis a."""
    K = skew(axis)
    return jnp.eye(3) + jnp.sin(angle) * K + (1.0 - jnp.cos(angle)) * (K @ K)


@quick_jit
def joint_frames(arm, theta):
    """World positions p_1..p_n of the joints and p_e of the end effector (rows 0..n: row i-1
    is p_i, p_1 the base), world axes z_1..z_n (row i-1 is z_i) and the end effector's rotation R.

    p_{i+1} = p_i + R_i o_i (p_{n+1} = p_e),  R_i = R_{i-1} Rot(a_i, theta_i),  z_i = R_{i-1} a_i,
    R_0 = I; a_i is joint i's axis in its parent link's frame, o_i link i's offset (arrays index from 0).
    """
    def link(carry, joint):
        R, p = carry
        axis, offset, angle = joint
        z = R @ axis              # joint axis in the world, before the joint turns
        R = R @ rotation_about(axis, angle)
        p = p + R @ offset        # the next joint (or the end effector)
        return (R, p), (p, z)

    theta = jnp.asarray(theta, dtype=float)
    if theta.shape != (arm.axes.shape[0],):
        raise ValueError(f"theta: expected shape ({arm.axes.shape[0]},), one angle per joint, "
                         f"got shape {theta.shape}")
    base = jnp.asarray(arm.base, dtype=float)
    joints = (jnp.asarray(arm.axes), jnp.asarray(arm.offsets), theta)
    (R, _), (positions, axes) = jax.lax.scan(link, (jnp.eye(3), base), joints)
    return jnp.vstack([base[None], positions]), axes, R


@quick_jit
def joint_positions(arm, theta):
    """Base, every joint and the end effector: shape (n + 1, d)."""
    return joint_frames(arm, theta)[0][:, : arm.dim]


@quick_jit
def fk(arm, theta):
    """End-effector position x = F(theta): shape (d,)."""
    return joint_frames(arm, theta)[0][-1, : arm.dim]


PATH_CHUNK = 128  # end_path works in blocks of this many rows: one compile per arm shape


@quick_jit
def _end_block(arm, thetas):
    return jax.vmap(lambda q: fk(arm, q))(thetas)


def end_path(arm, thetas):
    """End-effector positions F(theta_k) for each row of thetas (k, n): shape (k, d).

    Traces differ in length; padding them to whole blocks of PATH_CHUNK rows keeps one
    compiled shape, so a new length costs no compilation.
    """
    thetas = np.asarray(thetas, dtype=float)
    k = thetas.shape[0]
    rows = -(-max(k, 1) // PATH_CHUNK) * PATH_CHUNK
    padded = np.zeros((rows,) + thetas.shape[1:])
    padded[:k] = thetas
    blocks = [_end_block(arm, padded[i:i + PATH_CHUNK]) for i in range(0, rows, PATH_CHUNK)]
    return np.concatenate([np.asarray(b) for b in blocks])[:k]
