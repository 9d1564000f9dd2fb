"""FABRIK, forward and backward reaching IK (Aristidou & Lasenby 2011), on chains.

FABRIK works on joint positions p_0..p_n (p_n the end effector) and link lengths d_i:
  forward:  p_n <- t,     p_i <- p_{i+1} + d_i (p_i - p_{i+1}) / |p_i - p_{i+1}|,  i = n-1..0
  backward: p_0 <- base,  p_{i+1} <- p_i + d_i (p_{i+1} - p_i) / |p_{i+1} - p_i|,  i = 0..n-1
and, when |t - p_0| > sum d_i (out of reach), stretches the chain straight at t.
Our joints are hinges, so the new points are turned back into angles: each joint in turn,
base first, is turned (ccd_angle) to point its link at the new p_{i+1}. For a planar arm
this reproduces the points exactly; for a spatial hinge chain it is the nearest the hinges
allow, one joint at a time.

Why FABRIK does not converge on the UR5 (ik.core.robots.ur5): FABRIK moves each point freely
on a sphere around its neighbour, as if every joint were a ball joint. The UR5's hinges cannot
follow: its first link runs along its own hinge axis (no turn of joint 0 can aim it), and the
shoulder and wrist offsets lie across the next hinges, so each joint turns its link only as near
the new point as its axis allows, the end effector lands elsewhere, and the next pass starts
from other points. The passes never settle: on 20 reachable UR5 targets (starts 0.5 rad off)
FABRIK ran to max_iter every time with ||e|| at 6-40 % of the reach, while CCD, which turns
each hinge for the end effector itself, converged on all 20 (tests/test_ccd_fabrik.py). FABRIK
suits planar chains and ball-jointed ones; on an industrial arm use CCD or a Jacobian method.
"""
import jax
import jax.numpy as jnp

from .ccd import as_point3, ccd_angle
from .kinematics import joint_frames
from .method import method
from .._runtime.jit import quick_jit

EPS = 1e-12  # relative: two points closer than EPS times the link length count as one


def _toward(a, b, d):
    """The point at distance d from a in the direction of b (along +x when b and a are
    closer than EPS d, so that the link keeps its length even when two points coincide;
    relative to d, so an arm of 1e-13 works like one of 1)."""
    v = b - a
    n = jnp.linalg.norm(v)
    apart = n > EPS * d
    unit = jnp.where(apart, v / jnp.where(apart, n, 1.0), jnp.array([1.0, 0.0, 0.0]))
    return a + d * unit


def fabrik_forward(points, lengths, target):
    """Forward reaching: end effector onto the target, then each joint back along its link."""
    n = lengths.shape[0]

    def reach_back(k, points):  # i = n-1, ..., 0
        i = n - 1 - k
        return points.at[i].set(_toward(points[i + 1], points[i], lengths[i]))

    return jax.lax.fori_loop(0, n, reach_back, points.at[n].set(target))


def fabrik_backward(points, lengths, base):
    """Backward reaching: the root back onto the base, then each joint out along its link."""
    def reach_out(i, points):  # i = 0, ..., n-1
        return points.at[i + 1].set(_toward(points[i], points[i + 1], lengths[i]))

    return jax.lax.fori_loop(0, lengths.shape[0], reach_out, points.at[0].set(base))


def fabrik_stretch(points, lengths, target):
    """Out of reach: every link points straight at the target, p_{i+1} = p_i + d_i unit(t - p_i)."""
    def straighten(i, points):
        return points.at[i + 1].set(_toward(points[i], target, lengths[i]))

    return jax.lax.fori_loop(0, lengths.shape[0], straighten, points)


@quick_jit
def fabrik_pass(points, lengths, target):
    """One FABRIK iteration on the points (stretch when the target is out of reach)."""
    points, lengths, target = jnp.asarray(points), jnp.asarray(lengths), jnp.asarray(target)
    reachable = jnp.linalg.norm(target - points[0]) <= jnp.sum(lengths)
    inside = fabrik_backward(fabrik_forward(points, lengths, target), lengths, points[0])
    return jnp.where(reachable, inside, fabrik_stretch(points, lengths, target))


def angles_toward_points(arm, theta, points):
    """Turn joints 0..n-1 in order so that each link points at the new position points[i+1]."""
    def turn(i, q):
        positions, axes, _ = joint_frames(arm, q)
        return q.at[i].add(ccd_angle(axes[i], positions[i], positions[i + 1], points[i + 1]))

    return jax.lax.fori_loop(0, arm.n_joints, turn, jnp.asarray(theta))


@method(data=())
class FABRIK:
    """FABRIK as a solve method: one pass on the points, then back to angles."""
    uses_jacobian = False
    is_jax = True

    def delta(self, problem, theta, e, J, free=None):
        arm = problem.arm
        positions = joint_frames(arm, theta)[0]
        lengths = jnp.linalg.norm(jnp.asarray(arm.offsets), axis=1)
        points = fabrik_pass(positions, lengths, as_point3(arm, problem.target))
        return angles_toward_points(arm, theta, points) - theta

    def resolved(self, length_scale):
        return self
