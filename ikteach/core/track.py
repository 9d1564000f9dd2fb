"""Following moving targets: one IK step per time step (Buss's demo protocol).

At each time step the targets move, then the method takes ONE step from the current theta
(no iterating to convergence). Reported per step: the sum over end effectors of the
distance to its target after the step, and the joint motion.
"""
import dataclasses
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_array, as_number
from .jitter import jitter
from .limits import cap_step
from .methods import require_traceable
from .pinv import DEFAULT_RCOND
from .sdls import GAMMA_MAX
from .solve import (Settings, check_method_target, default_damping, linearize, resolve_method,
                    with_extras)
from .tasks import task_for
from .._runtime import jit as runtime_jit


@dataclasses.dataclass(frozen=True)
class TrackResult:
    """theta (T+1, n) from the start; error (T,) = sum_k |t_k - x_k| after each step."""
    theta: np.ndarray
    error: np.ndarray

    @property
    def mean_error(self):
        return float(np.mean(self.error))

    @property
    def jitter(self):
        """ik.jitter of the joint path: the mean of sum_j |theta_j(t+1) - 2 theta_j(t) + theta_j(t-1)|."""
        return jitter(self.theta)


def clamp_blocks(e, block, d_max):
    """Clamp each effector's error |e_k| to at most D_max (Buss's per-effector clamp; d_max a
    number or one per effector)."""
    parts = e.reshape(-1, block)
    norm = jnp.linalg.norm(parts, axis=1, keepdims=True)
    d_max = jnp.reshape(d_max, (-1, 1))
    scale = jnp.where(norm > d_max, d_max / jnp.where(norm > 0, norm, 1.0), 1.0)
    return (parts * scale).reshape(-1)


CHUNK = 128  # time steps per compiled scan: paths of any length reuse one program


@partial(runtime_jit.jit, static_argnames=("method",))
def _track(method, task, arm, targets, start, settings, d_max, grow):
    """CHUNK (or fewer) steps from start = (theta, each effector's clamp); returns the last
    (theta, clamps) and every step's theta and error."""
    block = getattr(task, "block_size", None)

    def step(carry, target):
        theta, clamps = carry
        e, linearized = linearize(task, arm, target, theta)  # e and J from one walk
        before = jnp.linalg.norm(e.reshape(-1, block or e.shape[0]), axis=1)
        e = clamp_blocks(e, block or e.shape[0], clamps)
        delta = cap_step(method.delta(linearized, arm, target, theta, e, settings),
                         settings.max_step)
        new = jnp.clip(theta + delta, settings.lower, settings.upper)  # joint limits
        theta = jnp.where(jnp.all(jnp.isfinite(new)), new, theta)  # never NaN: keep the last finite
        e_after = task.error(arm, target, theta)
        after = jnp.linalg.norm(e_after.reshape(-1, block or e_after.shape[0]), axis=1)
        # Buss's growing clamp: D_max plus how much farther from its target the step left it
        clamps = jnp.where(grow, d_max + jnp.maximum(after - before, 0.0), d_max)
        return (theta, clamps), (theta, jnp.sum(after))

    return jax.lax.scan(step, start, targets)


def _track_chunks(method, task, arm, targets, theta0, settings, d_max, grow=False):
    """Run the path CHUNK steps at a time, the last chunk padded by repeating the last target
    (its extra steps are dropped), so every path length runs the same compiled program."""
    steps = targets.shape[0]
    padded = np.concatenate([targets, np.repeat(targets[-1:], -steps % CHUNK, axis=0)])
    effectors = int(np.prod(targets.shape[1:])) // getattr(task, "block_size", int(np.prod(targets.shape[1:])))
    first_clamp = jnp.full(effectors, jnp.inf if grow else d_max)  # Buss: the first step unclamped
    carry, thetas, errors = (jnp.asarray(theta0), first_clamp), [np.asarray(theta0)[None]], []
    for first in range(0, padded.shape[0], CHUNK):
        carry, (chunk_thetas, chunk_errors) = _track(method, task, arm, padded[first: first + CHUNK],
                                                     carry, settings, d_max, jnp.asarray(grow))
        thetas.append(np.asarray(chunk_thetas))
        errors.append(np.asarray(chunk_errors))
    return np.concatenate(thetas)[: steps + 1], np.concatenate(errors)[:steps]


def track(arm, targets, theta0=None, method="dls", damping=None, rcond=DEFAULT_RCOND,
          clamp=None, max_step=None, gamma_max=GAMMA_MAX, joint_limits=None, limit_mode=None,
          levels=None, rest_pose=None, rest_gain=None, clamp_growth=False):
    """Follow targets[0], targets[1], ... with one step of `method` each (Buss's protocol).

    targets  (T, *target shape): one target (or one per end effector) per time step, T >= 1
             (an empty path raises a ValueError). Numbers are checked as in ik.solve.
    damping  DLS's lambda (default L / 6, as in ik.solve).
    clamp    D_max: each end effector's error is clamped to at most D_max before the step.
    clamp_growth  Buss's demo code (UpdatedSClampValue): effector k's clamp is D_max plus how
             much farther from its target the last step left it (0 if nearer), and the first
             step is unclamped. Needs clamp.
    max_step cap on any joint's change per step (radians).
    joint_limits, limit_mode, levels, rest_pose, rest_gain: as in ik.solve.
    """
    method = resolve_method(method)
    targets = as_array(targets, "targets")
    if targets.ndim < 2:
        raise ValueError(f"targets: expected one target per time step, got shape {targets.shape}")
    if targets.shape[0] == 0:
        raise ValueError(f"targets: expected at least one time step, got none (shape {targets.shape})")
    task = task_for(arm, targets.shape[1:], "targets")
    if hasattr(task, "check_target"):  # pose targets: rigid transforms only
        task.check_target(targets, "targets")
    check_method_target(method, task, arm, "targets")
    theta0 = np.zeros(arm.n_joints) if theta0 is None else as_array(theta0, "theta0", shape=(arm.n_joints,))
    settings = Settings(
        tol=0.0, damping=as_number(default_damping(task, arm) if damping is None else damping,
                                   "damping", minimum=0),
        rcond=as_number(rcond, "rcond", minimum=0), clamp=np.inf,
        max_step=np.inf if max_step is None else as_number(max_step, "max_step", minimum=0, strict=True),
        stall_tol=0.0, gamma_max=as_number(gamma_max, "gamma_max", minimum=0, strict=True))
    first = jnp.asarray(targets[:1])  # with_extras looks at the first target only: one shape
    method, settings, theta0 = with_extras(method, task, arm, first, jnp.asarray(theta0),
                                           settings, levels, rest_pose, rest_gain, joint_limits,
                                           limit_mode, batch=True)
    require_traceable(method, task, arm, first[0], theta0, settings)  # track compiles the step
    d_max = np.inf if clamp is None else as_number(clamp, "clamp", minimum=0, strict=True)
    if clamp_growth not in (True, False):
        raise ValueError(f"clamp_growth: expected True or False, got {clamp_growth!r:.80}")
    if clamp_growth and clamp is None:
        raise ValueError("clamp_growth: grows the clamp D_max; give clamp= too")
    thetas, errors = _track_chunks(method, task, arm, np.asarray(targets), theta0, settings,
                                   jnp.asarray(d_max), bool(clamp_growth))
    return TrackResult(thetas, errors)
