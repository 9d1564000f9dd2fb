"""Forward kinematics: x = F(theta), by walking the chain from base to end effector."""
import jax.numpy as jnp


def skew(w):
    """The cross-product matrix [w]x, so that [w]x v = w x v."""
    return jnp.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rotation_about(axis, angle):
    """Rodrigues' formula: R = I + sin(t) [a]x + (1 - cos(t)) [a]x^2 for a unit axis a."""
    K = skew(axis)
    return jnp.eye(3) + jnp.sin(angle) * K + (1.0 - jnp.cos(angle)) * (K @ K)


def joint_frames(arm, theta):
    """World joint positions p_0..p_n (p_n the end effector), world axes w_0..w_{n-1}
    and the end effector's rotation R.

    p_{i+1} = p_i + R_i o_i,  R_i = R_{i-1} Rot(a_i, theta_i),  w_i = R_{i-1} a_i.
    """
    theta = jnp.asarray(theta)
    R = jnp.eye(3)
    p = jnp.asarray(arm.base)
    positions, axes = [p], []
    for i in range(arm.axes.shape[0]):
        axes.append(R @ arm.axes[i])
        R = R @ rotation_about(arm.axes[i], theta[i])
        p = p + R @ arm.offsets[i]
        positions.append(p)
    return jnp.stack(positions), jnp.stack(axes), R


def joint_positions(arm, theta):
    """Base, every joint and the end effector: shape (n + 1, d)."""
    return joint_frames(arm, theta)[0][:, : arm.dim]


def fk(arm, theta):
    """End-effector position x = F(theta): shape (d,)."""
    return joint_frames(arm, theta)[0][-1, : arm.dim]
