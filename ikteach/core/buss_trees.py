"""Buss's "Y" and "double Y" test trees and their moving targets.

Numbers copied from S. R. Buss's public IK demo code (Buss & Kim 2005, "Selectively damped
least squares for inverse kinematics"; demo program main file: BuildTreeYShape,
BuildTreeDoubleYShape, UpdateTargets; Jacobian.cpp for the method constants). Positions are
world positions in the rest pose; the demo's node order gives our joint and effector order.
The targets are sums of sines of the time T, updated once per time step T_STEP.

The method settings are the constants of Buss's Jacobian.cpp as shipped in bullet3
(examples/ThirdPartyLibs/BussIK): demo_methods(tree_name) gives them to ik.track. What is ours
and not his is said there.
"""
import numpy as np

from .sdls import GAMMA_MAX, sdls_step
from .tree import tree

T_STEP = 0.005        # Tstep = 0.0005 * SlowdownFactor (10) in the demo
UNIT1 = np.array([np.sqrt(14.0) / 8.0, 1.0 / 8.0, 7.0 / 8.0])   # the demo's "unit1" axis
X, Y, Z = np.eye(3)

# The demo's per-method settings (Jacobian.cpp): MaxAngleJtranspose, MaxAnglePseudoinverse,
# MaxAngleDLS (MaxAngleSDLS = 45 degrees = GAMMA_MAX), PseudoInverseThresholdFactor,
# DefaultDampingLambda (0.6 "optimal for the Y"; the two commented-out alternatives: 1.1 for the
# double Y, 0.7 for the double Y with distance clamping) and BaseMaxTargetDist.
MAX_STEP = {"jt": np.radians(30.0), "pinv": np.radians(5.0), "dls": np.radians(45.0)}
PINV_RCOND = 0.01
DAMPING = {"y": 0.6, "double_y": 1.1, "clamped": 0.7}
D_MAX = 0.4           # BaseMaxTargetDist


def sdls_demo(J, e):
    """Buss's demo SDLS (CalcDeltaThetasSDLS): soft rescales (ikteach/sdls.py, soft=True),
    gamma_max 45 degrees, 3 rows per end effector. A step function for ik.track."""
    return sdls_step(J, e, GAMMA_MAX, block=3, soft=True)


def demo_methods(tree_name):
    """ik.track's settings for each method of Buss's demo on "y" or "double_y".

    Everything is his, except: DLS + clamp on the Y uses the Y's 0.6 (his 0.7 is stated for the
    double Y only), and the growing clamp reads each effector's own previous distance (his
    UpdatedSClampValue reads entries i..i+2 of the stacked error for effector i, which are
    effector i's own only for i = 0). DLS + clamp is his optional variant: its lines are
    commented out in Jacobian.cpp. The course's own SDLS (method="sdls", the paper's hard
    ClampMaxAbs and a fixed clamp) is listed too, as "SDLS (paper)".
    """
    clamped = DAMPING["clamped"] if tree_name == "double_y" else DAMPING["y"]
    grow = dict(clamp=D_MAX, clamp_growth=True)
    return {
        "JT": dict(method="jt", max_step=MAX_STEP["jt"]),
        "pseudoinverse": dict(method="pinv", max_step=MAX_STEP["pinv"], rcond=PINV_RCOND),
        "DLS": dict(method="dls", max_step=MAX_STEP["dls"], damping=DAMPING[tree_name]),
        "DLS + clamp": dict(method="dls", max_step=MAX_STEP["dls"], damping=clamped, **grow),
        "SDLS": dict(method=sdls_demo, **grow),
        "SDLS (paper)": dict(method="sdls", clamp=D_MAX),
    }


def y_tree():
    """The "Y": 7 revolute joints, 2 end effectors (a trunk that forks into two arms)."""
    positions = [(0.0, -0.5, 0.0), (0.0, 0.4, 0.0), (0.0, 0.4, 0.0), (0.5, 1.0, 0.0),
                 (-0.5, 1.0, 0.0), (0.7, 1.3, 0.0), (-0.8, 1.5, 0.0)]
    axes = [Z, Z, Z, X, X, UNIT1, UNIT1]
    parents = [-1, 0, 0, 1, 2, 3, 4]
    effectors = [(0.7, 2.0, 0.0), (-0.8, 1.9, 0.0)]
    return tree(positions, axes, parents, effectors, [5, 6])


def y_targets(t):
    """Targets of the Y at time t: shape (len(t), 2, 3) (UpdateTargets, YSHAPE)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    s = np.sin
    return np.stack([
        np.stack([2.0 + 1.5 * s(6 * t), -0.5 + 1.7 + 0.2 * s(7 * t), 0.3 + 0.2 * s(8 * t)], -1),
        np.stack([-0.7 + 0.4 * s(4 * t), -0.5 + 1.3 + 0.3 * s(4 * t), -0.2 + 0.2 * s(3 * t)], -1),
    ], axis=1)


def _double_y_points():
    r, h = 1.0 / np.sqrt(2.0), np.sqrt(3.0) / 2.0
    y0 = -0.5 + 0.5 * r
    p = {0: (0.0, -1.5), 1: (0.0, -1.0), 2: (0.0, -0.5), 3: (0.5 * r, y0),
         4: (0.5 * r + 0.5 * h, y0 + 0.25), 5: (0.5 * r + h, y0 + 0.5), 6: (0.5 * r + 1.5 * h, y0 + 0.75),
         7: (0.5 * r + 0.5 * h, y0 + 0.5 * h), 8: (0.5 * r + h, y0 + h), 9: (0.5 * r + 1.5 * h, y0 + 1.5 * h),
         10: (-0.5 * r, y0), 11: (-0.5 * r - 0.5 * h, y0 + 0.5 * h), 12: (-0.5 * r - h, y0 + h),
         13: (-0.5 * r - 1.5 * h, y0 + 1.5 * h), 14: (-0.5 * r - 0.5 * h, y0 + 0.25),
         15: (-0.5 * r - h, y0 + 0.5), 16: (-0.5 * r - 1.5 * h, y0 + 0.75)}
    return {k: np.array([x, y, 0.0]) for k, (x, y) in p.items()}


def double_y_tree():
    """The "double Y": 25 revolute joints, 4 end effectors (each arm of the Y forks again)."""
    p = _double_y_points()
    # (point, axis, parent joint) in the demo's node order, effector nodes left out
    joints = [(0, UNIT1, -1), (1, X, 0), (1, Z, 1), (2, Z, 2), (2, Z, 2), (3, Y, 3), (3, Y, 3),
              (3, X, 5), (4, Z, 7), (5, X, 8), (5, Y, 9),            # joints 0-10
              (3, X, 6), (7, Z, 11), (8, X, 12), (8, Y, 13),           # joints 11-14
              (10, Y, 4), (10, X, 15), (10, Y, 4), (11, Z, 16), (12, X, 18), (12, Y, 19),  # 15-20
              (10, X, 17), (14, Z, 21), (15, X, 22), (15, Y, 23)]     # joints 21-24
    effectors = [(6, 10), (9, 14), (13, 20), (16, 24)]
    return tree([p[i] for i, _, _ in joints], [a for _, a, _ in joints], [q for _, _, q in joints],
                [p[i] for i, _ in effectors], [j for _, j in effectors])


def double_y_targets(t):
    """Targets of the double Y at time t: shape (len(t), 4, 3) (UpdateTargets, DBLYSHAPE)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    s = np.sin
    rows = [
        (2.0 + 3.0 * s(3 * t), -0.5 + 1.0 + 0.4 * s(7 * t), 0.3 + 1.4 * s(5 * t)),
        (0.5 + 0.8 * s(4 * t), -0.5 + 0.9 + 0.6 * s(4 * t), -0.2 + 2.0 * s(3 * t)),
        (-0.5 + 1.6 * s(6 * t), -0.5 + 1.1 + 0.4 * s(7 * t), 0.3 + 1.0 * s(8 * t)),
        (-1.6 + 1.6 * s(4 * t), -0.5 + 0.8 + 0.6 * s(4 * t), -0.2 + 0.6 * s(3 * t)),
    ]
    return np.stack([np.stack(r, -1) for r in rows], axis=1)


def times(steps, dt=T_STEP):
    """The demo's clock: T = dt, 2 dt, ..., steps dt (targets are updated before each step)."""
    return dt * np.arange(1, steps + 1)
