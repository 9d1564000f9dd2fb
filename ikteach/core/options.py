"""The settings ik.solve, ik.solve_batch and ik.track share: one object, checked once.

    ik.solve(arm, target, theta0, method=ik.DLS(damping=0.2), options=ik.Options(tol=1e-4))
    ik.solve(arm, target, theta0, method="dls", damping=0.2, tol=1e-4)       # the same

A method's own parameters (damping, rcond, gamma_max) belong to the method (methods.py).
"""
import numpy as np

from ._pytree import pytree_dataclass, replace
from ._validate import as_array, as_count, as_number, numeric
from .stop_rules import DEFAULT_STOP_RULE, check_rule

TOL_PER_LENGTH = 3000  # tol = L / 3000 (1e-3 for three unit links; L: the arm's size)
STALL_PER_TOL = 0.01  # stall_tol = tol / 100
DEFAULT_MAX_ITER = 1000
MAX_ITER_CAP = 10**6  # the largest max_iter accepted: a full trace of 12 joints is then 100 MB
LIMIT_MODES = ("clamp", "clamping_loop")


@pytree_dataclass(data=("tol", "max_iter", "clamp", "max_step", "stall_tol", "joint_limits",
                        "levels", "rest_pose", "rest_gain", "weights"),
                  meta=("stop_rule", "limit_mode"))
class Options:
    """tol       stop "converged" when ||e|| < tol (a length; default L / 3000).
    max_iter  stop "max_iter" after this many steps (at most MAX_ITER_CAP; None: the default).
    clamp     Buss's D_max: each end effector's error is clamped to at most D_max.
    max_step  cap on any joint's change per step, in radians.
    stall_tol stop when the last step's size < stall_tol (default tol / 100; 0: never).
    stop_rule the step's size: "motion" (||J delta_theta||, scale-free, the default) or
              "joint_steps" (the report's sum |delta_theta_i|); None: the default. See stop_rules.py.
    joint_limits  (lower, upper): numbers or per-joint arrays, +-inf for no limit.
    limit_mode    "clamping_loop" (default for Jacobian methods) or "clamp" (joint_limits.py).
    levels    priority of each target block, 0 first (levels.py); rest_pose, rest_gain: a last
              level pulling theta towards rest_pose (default gain 0.1).
    weights   for a 4x4 pose target: (position_weight, orientation_weight), default (1, 1).
    """
    tol: float = None
    max_iter: int = DEFAULT_MAX_ITER
    clamp: float = None
    max_step: float = None
    stall_tol: float = None
    stop_rule: str = DEFAULT_STOP_RULE
    joint_limits: tuple = None
    limit_mode: str = None
    levels: tuple = None
    rest_pose: object = None
    rest_gain: float = None
    weights: tuple = None

    def __post_init__(self):
        check = {
            "tol": lambda v: as_number(v, "tol", minimum=0, strict=True),
            "max_iter": check_max_iter,
            "clamp": lambda v: as_number(v, "clamp", minimum=0, strict=True),
            "max_step": lambda v: as_number(v, "max_step", minimum=0, strict=True),
            "stall_tol": lambda v: as_number(v, "stall_tol", minimum=0),
            "stop_rule": check_rule,
            "joint_limits": check_limits,
            "limit_mode": check_limit_mode,
            "rest_pose": lambda v: as_array(v, "rest_pose", ndim=1),
            "rest_gain": lambda v: as_number(v, "rest_gain", minimum=0, strict=True),
        }
        for name, default in (("max_iter", DEFAULT_MAX_ITER), ("stop_rule", DEFAULT_STOP_RULE)):
            if getattr(self, name) is None:  # None: the default, as for every other field
                object.__setattr__(self, name, default)
        for name, fix in check.items():
            if getattr(self, name) is not None:
                object.__setattr__(self, name, fix(getattr(self, name)))
        if self.rest_gain is not None and self.rest_pose is None:
            raise ValueError("rest_gain: the gain of the rest-pose level, so it needs rest_pose= "
                             "(the pose to drift back to)")
        if self.limit_mode is not None and self.joint_limits is None:
            raise ValueError(f"limit_mode: {self.limit_mode!r} says how to keep joint limits, "
                             f"so it needs joint_limits=(lower, upper)")

    def resolved(self, length_scale, n_joints):
        """The numbers the loop reads: defaults filled in for an arm of size L = length_scale,
        joint limits as two arrays of shape (n_joints,)."""
        tol = length_scale / TOL_PER_LENGTH if self.tol is None else self.tol
        stall_tol = STALL_PER_TOL * tol if self.stall_tol is None else self.stall_tol
        limits = (np.full(n_joints, -np.inf), np.full(n_joints, np.inf))
        if self.joint_limits is not None:
            limits = tuple(broadcast_limit(b, n_joints, name)
                           for b, name in zip(self.joint_limits, ("lower", "upper")))
        return replace(self, tol=tol, stall_tol=stall_tol, joint_limits=limits,
                       clamp=np.inf if self.clamp is None else self.clamp,
                       max_step=np.inf if self.max_step is None else self.max_step,
                       max_iter=np.int64(self.max_iter))


def check_max_iter(value):
    value = as_count(value, "max_iter", minimum=1)
    if value > MAX_ITER_CAP:
        raise ValueError(f"max_iter: expected at most {MAX_ITER_CAP:,} iterations (ik.solve keeps "
                         f"every iterate), got {value:,}")
    return value


def check_limit_mode(mode):
    if mode not in LIMIT_MODES:
        raise ValueError(f"limit_mode: expected one of {LIMIT_MODES}, got {mode!r:.80}")
    return mode


def check_limits(joint_limits):
    """(lower, upper): numbers or 1-D arrays, no NaN, lower <= upper where both are given."""
    try:
        lower, upper = joint_limits
    except (TypeError, ValueError):
        raise ValueError(f"joint_limits: expected a pair (lower, upper) of per-joint arrays, "
                         f"got {joint_limits!r:.80}") from None
    out = []
    for name, bound, bad in (("lower", lower, np.inf), ("upper", upper, -np.inf)):
        try:
            arr = numeric(bound, "joint_limits")
        except ValueError:
            raise ValueError(f"joint_limits: expected {name} as a number or one per joint, "
                             f"got {bound!r:.80}") from None
        if arr.ndim > 1:
            raise ValueError(f"joint_limits: expected {name} as a number or one per joint, "
                             f"got shape {arr.shape}")
        if np.any(np.isnan(arr)) or np.any(arr == bad):
            raise ValueError(f"joint_limits: {name} must be numbers (or {-bad} for no limit), "
                             f"got {arr.tolist()}")
        out.append(arr)
    try:
        lower, upper = np.broadcast_arrays(*map(np.atleast_1d, out))
    except ValueError:
        raise ValueError(f"joint_limits: expected lower and upper of the same length, got "
                         f"shapes {out[0].shape} and {out[1].shape}") from None
    if np.any(lower > upper):
        j = int(np.argmax(lower > upper))
        raise ValueError(f"joint_limits: expected lower <= upper, got lower[{j}] = {lower[j]} "
                         f"> upper[{j}] = {upper[j]}")
    return tuple(out)


def broadcast_limit(bound, n, name):
    try:
        return np.broadcast_to(bound, (n,)).astype(float)
    except ValueError:
        raise ValueError(f"joint_limits: expected {name} as a number or shape ({n},) "
                         f"(one per joint), got shape {np.shape(bound)}") from None
