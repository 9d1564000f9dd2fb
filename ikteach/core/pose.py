"""Pose targets for spatial chains: position and orientation of the end effector.

A pose is a 4x4 homogeneous transform T = [[R, p], [0, 1]]. The pose error stacks the
position error and the orientation error as an axis-angle vector:

    e = [ beta_p (p_t - p(theta)) ;  beta_o L log(R_t R(theta)^T) ]          (6,)

L is the arm's reach (the sum of its link lengths, ik.reach): an angle times a length is a
length, so every entry of e is a length and the solve's lengths (tol = L / 3000, damping
lambda = L / 6, stall_tol = tol / 100) mean the same at every unit. Scale the arm by s and
e, J and those lengths all scale by s: metres and millimetres give the same steps. With
the default weights, "converged" (||e|| < tol) means ||e_p||^2 + L^2 ||e_o||^2 < tol^2: a position
error below tol and an orientation error below tol / L radians (1/3000 rad with the default
tol), and more than both - each at 0.9 of its bound is not converged (0.9^2 + 0.9^2 > 1).

log(R_t R^T) is the rotation vector omega with R_t = exp([omega]x) R: the small rotation
that takes the current hand to the target, in world coordinates. Its derivative at
omega = 0 is the angular part of the geometric Jacobian (rows z_i, the joint axes), so the 6 x n
Jacobian [z_i x (p_e - p_i); z_i] (ik.jacobian(arm, theta, full=True)) drives it.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_array, as_number
from .chain import Chain, reach
from .jacobian import jacobian
from .kinematics import joint_frames, skew
from .._runtime.jit import quick_jit

# Below sin^2(angle) = SMALL the log uses its Taylor series; above cos(angle) = NEAR_PI
# the axis is read from the symmetric part of R. Both branches are exact to float64.
SMALL = 1e-6
NEAR_PI = -0.9


@quick_jit
def fk_pose(arm, theta):
    """Forward kinematics as a 4x4 homogeneous transform T = [[R, p], [0, 0, 0, 1]]."""
    positions, _, R = joint_frames(arm, theta)
    top = jnp.hstack([R, positions[-1][:, None]])
    return jnp.vstack([top, jnp.array([[0.0, 0.0, 0.0, 1.0]])])


@quick_jit
def rotation_exp(omega):
    """Rodrigues' formula for a rotation vector: exp([w]x) = I + sinc(t)[w]x + (1-cos t)/t^2 [w]x^2,
    t = |w|; the two coefficients use their Taylor series near t = 0 (finite gradient at 0)."""
    omega = jnp.asarray(omega)
    t2 = jnp.dot(omega, omega)
    small = t2 < SMALL
    t = jnp.sqrt(jnp.where(small, 1.0, t2))
    a = jnp.where(small, 1.0 - t2 / 6.0 + t2**2 / 120.0, jnp.sin(t) / t)
    b = jnp.where(small, 0.5 - t2 / 24.0 + t2**2 / 720.0, (1.0 - jnp.cos(t)) / t**2)
    K = skew(omega)
    return jnp.eye(3) + a * K + b * (K @ K)


@quick_jit
def rotation_log(R):
    """The rotation vector omega = angle * axis of a rotation matrix, angle in [0, pi].

    With c = (tr R - 1)/2 = cos(angle) and v = vee(R - R^T)/2 = sin(angle) axis:
      small angles  (|v|^2 < SMALL):  omega = v (1 + s/6 + 3 s^2/40),  s = |v|^2
                    (the series of arcsin(x)/x: exact to float64, gradient finite at R = I);
      general:      omega = atan2(|v|, c) v / |v|;
      near pi       (c < NEAR_PI): (R + R^T)/2 - c I = (1 - c) a a^T, so the axis a is
                    the largest column of that matrix over the root of its diagonal entry,
                    signed to agree with v; omega = atan2(|v|, c) a.
    Every branch is evaluated on safe inputs, so neither values nor gradients are NaN.
    """
    R = jnp.asarray(R)
    c = jnp.clip((jnp.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    v = 0.5 * jnp.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = jnp.dot(v, v)
    small = (s < SMALL) & (c > 0)
    near_pi = c < NEAR_PI
    s_safe = jnp.where(small | near_pi, 1.0, s)
    sin_t = jnp.sqrt(s_safe)
    angle = jnp.arctan2(sin_t, c)
    general = v * (angle / sin_t)
    series = v * (1.0 + s / 6.0 + 3.0 * s**2 / 40.0)
    # near pi: the axis from the symmetric part
    c_pi = jnp.where(near_pi, c, -1.0)
    A = (0.5 * (R + R.T) - c_pi * jnp.eye(3)) / (1.0 - c_pi)   # = a a^T
    k = jnp.argmax(jnp.diag(A))
    axis = A[:, k] / jnp.sqrt(jnp.maximum(A[k, k], 1e-300))
    axis = jnp.where(jnp.dot(axis, v) < 0, -axis, axis)
    angle_pi = jnp.arctan2(_norm_safe(v, near_pi), c_pi)
    return jnp.where(small, series, jnp.where(near_pi, angle_pi * axis, general))


def _norm_safe(v, use):
    """|v| where `use`, with a gradient that is finite at v = 0 (the where-trick)."""
    s = jnp.dot(v, v)
    return jnp.where(use & (s > 0), jnp.sqrt(jnp.where(use & (s > 0), s, 1.0)), 0.0)


def orientation_error(R_target, R):
    """Axis-angle orientation error log(R_t R^T) in world coordinates, shape (3,)."""
    return rotation_log(R_target @ R.T)


@dataclasses.dataclass(frozen=True)
class PoseTask:
    """Reach a 4x4 pose with a spatial chain.

    e = [beta_p (p_t - p); beta_o L log(R_t R^T)],  J = diag(beta_p I, beta_o L I) [z_i x (p_e - p_i); z_i],
    L the arm's reach (module doc: every row is then a length).
    The weights are the task's data (a pytree leaf each): traced, so new weights reuse the
    compiled loop (ik.solve(..., weights=(beta_p, beta_o)) makes a new task, not a program).
    """
    position_weight: float = 1.0
    orientation_weight: float = 1.0

    def accepts_arm(self, arm):
        return isinstance(arm, Chain) and arm.dim == 3

    def accepts(self, arm, target_shape):
        return self.accepts_arm(arm) and tuple(target_shape) == (4, 4)

    def target_shape(self, arm):
        return "(4, 4)"

    def check_target(self, target, name):
        check_pose(target, name)

    def error(self, arm, target, theta):
        positions, _, R = joint_frames(arm, theta)
        e_p = target[:3, 3] - positions[-1]
        e_o = orientation_error(target[:3, :3], R)
        return jnp.concatenate([self.position_weight * e_p, self.orientation_scale(arm) * e_o])

    def jacobian(self, arm, theta):
        J = jacobian(arm, theta, full=True)
        return jnp.vstack([self.position_weight * J[:3], self.orientation_scale(arm) * J[3:]])

    def orientation_scale(self, arm):
        """beta_o L: radians of orientation error to the length they count as in e."""
        return self.orientation_weight * arm_length(arm)

    def length_scale(self, arm):
        return float(reach(arm))

    def weighted(self, weights):
        """The same task with weights (beta_p, beta_o) on the position and orientation errors."""
        try:
            w_p, w_o = weights
        except (TypeError, ValueError):
            raise ValueError(f"weights: expected a pair (position_weight, orientation_weight), "
                             f"got {weights!r:.80}") from None
        w_p = as_number(w_p, "weights", minimum=0)
        w_o = as_number(w_o, "weights", minimum=0)
        if w_p == 0 and w_o == 0:
            raise ValueError("weights: expected at least one positive weight, got (0, 0)")
        return PoseTask(w_p, w_o)


jax.tree_util.register_dataclass(PoseTask, data_fields=["position_weight", "orientation_weight"],
                                 meta_fields=[])


def arm_length(arm):
    """The arm's reach L = sum_i |offsets[i]| (traceable: ik.reach for the loop's arm)."""
    return jnp.sum(jnp.linalg.norm(jnp.asarray(arm.offsets), axis=1))


RIGID_TOL = 1e-6  # largest |R^T R - I| entry and |bottom row - [0, 0, 0, 1]| accepted


def check_pose(T, name="target"):
    """A ValueError naming `name` unless every 4x4 in T (shape (..., 4, 4), numpy) is a rigid
    transform [[R, p], [0, 0, 0, 1]]: R^T R = I and det R = +1 (a rotation: no scale, shear
    or reflection), each to RIGID_TOL."""
    T = np.asarray(T, dtype=np.float64).reshape(-1, 4, 4)
    R = T[:, :3, :3]
    where = lambda k: f"{name}[{k}]" if T.shape[0] > 1 or name == "targets" else name
    bottom = np.abs(T[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1)
    if np.any(bottom > RIGID_TOL):
        k = int(np.argmax(bottom))
        raise ValueError(f"{where(k)}: expected a rigid transform with bottom row [0, 0, 0, 1], "
                         f"got {T[k, 3].tolist()}")
    off = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max(axis=(1, 2))
    if np.any(off > RIGID_TOL):
        k = int(np.argmax(off))
        raise ValueError(f"{where(k)}: expected a rotation in the top-left 3x3 (R^T R = I to "
                         f"{RIGID_TOL:g}), got R^T R off by {off[k]:.3g} (scaled or sheared)")
    det = np.linalg.det(R)
    if np.any(det < 0):
        k = int(np.argmax(det < 0))
        raise ValueError(f"{where(k)}: expected a rotation in the top-left 3x3, got a reflection "
                         f"(det R = {det[k]:.3g})")


def pose_errors(arm, theta, target):
    """(position error |p_t - p|, orientation error angle in radians) of theta for a 4x4 target.

    target must be a rigid transform (check_pose: a ValueError naming target otherwise)."""
    target = as_array(target, "target", shape=(4, 4))
    check_pose(target, "target")
    T = fk_pose(arm, theta)
    target = jnp.asarray(target)
    e_p = jnp.linalg.norm(target[:3, 3] - T[:3, 3])
    e_o = jnp.linalg.norm(orientation_error(target[:3, :3], T[:3, :3]))
    return float(e_p), float(e_o)


def make_pose(R, p):
    """The 4x4 transform [[R, p], [0, 1]] from a rotation matrix R (3, 3) and a position p (3,).

    Numbers given (not traced) are checked: a ValueError naming R or p for a wrong shape or
    non-finite entries. (Whether R is a rotation is ik.solve's check: check_pose.)"""
    if not any(isinstance(x, jax.core.Tracer) for x in (R, p)):
        R, p = as_array(R, "R", shape=(3, 3)), as_array(p, "p", shape=(3,))
    top = jnp.hstack([jnp.asarray(R, dtype=float), jnp.asarray(p, dtype=float)[:, None]])
    return jnp.vstack([top, jnp.array([[0.0, 0.0, 0.0, 1.0]])])

