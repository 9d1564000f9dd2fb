"""Foot planting: find when a foot is on the ground, measure how far it slides there, and
clean a clip with IK so that planted feet stay put.

1. contacts:  a foot is in contact in frames where it is low (height < `height`) and slow
   (horizontal speed < `speed`).
2. skate:     horizontal foot travel summed over consecutive contact frames, sum |dx_xz|.
3. targets:   in each contact interval the foot aims at one point, the mean of where it was;
   between contacts the correction (target - foot) is interpolated, so the targets glide.
4. clean:     frame by frame, the solve loop (DLS) moves only the hips, knees and ankle hinges
   to put the feet on their targets (ik.characters.clip_ik.solve_clip), warm-started from the previous
   frame. Each toe (the foot's end site) aims at its ankle's target plus the clip's own
   ankle-to-toe vector, so the foot keeps the clip's orientation instead of pitching as the
   knee bends; every target is lifted to stay on or above the floor.
"""
import dataclasses

import numpy as np

from ..core._validate import as_array, as_number
from .bvh import Motion, Skeleton
from .clip_ik import ClipResult, solve_clip
from .skeleton import rest_positions

UP = 1  # BVH's Y axis points up


def _horizontal(v):
    return np.delete(v, UP, axis=-1)


def contacts(positions, frame_time, height, speed):
    """contact[f] = foot low and slow at frame f: height < `height`, horizontal speed < `speed`.

    positions (F, 3) of one foot, or (F, k, 3) for k feet (then contact is (F, k)).
    Speed is the central difference of the horizontal position over 2 frame_time.
    """
    positions = as_array(positions, "positions")
    if positions.ndim not in (2, 3) or positions.shape[-1] != 3 or len(positions) < 2:
        raise ValueError(f"positions: expected shape (frames >= 2, 3) or (frames, feet, 3), "
                         f"got shape {positions.shape}")
    dt = as_number(frame_time, "frame_time", minimum=0, strict=True)
    height = as_number(height, "height")
    speed = as_number(speed, "speed", minimum=0, strict=True)
    velocity = np.gradient(_horizontal(positions), dt, axis=0)
    return (positions[..., UP] < height) & (np.linalg.norm(velocity, axis=-1) < speed)


def intervals(contact):
    """Runs of True in a boolean array (F,): [(first, last + 1), ...]."""
    c = np.concatenate([[False], np.asarray(contact, bool), [False]]).astype(int)
    edges = np.flatnonzero(np.diff(c))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def foot_skate(positions, contact):
    """Horizontal travel during contact: sum over frames f with contact at f and f+1 of
    |x_xz(f+1) - x_xz(f)|, for each foot (positions (F, k, 3), contact (F, k)) -> (k,)."""
    positions = as_array(positions, "positions", shape=(None, None, 3))
    contact = np.asarray(contact, bool)
    if contact.shape != positions.shape[:2]:
        raise ValueError(f"contact: expected shape {positions.shape[:2]} (frames, feet), got {contact.shape}")
    step = np.linalg.norm(np.diff(_horizontal(positions), axis=0), axis=-1)
    return (step * (contact[1:] & contact[:-1])).sum(axis=0)


def plant_targets(positions, contact):
    """Per frame and foot, where the foot should be (F, k, 3): in a contact interval the mean
    of its positions there; elsewhere the foot plus the correction interpolated between the
    neighbouring contacts (held constant before the first and after the last)."""
    positions = as_array(positions, "positions", shape=(None, None, 3))
    contact = np.asarray(contact, bool)
    frames = np.arange(len(positions))
    targets = positions.copy()
    for k in range(positions.shape[1]):
        fixed = np.zeros(len(positions), bool)
        for a, b in intervals(contact[:, k]):
            targets[a:b, k] = positions[a:b, k].mean(axis=0)
            fixed[a:b] = True
        if fixed.any():
            shift = targets[fixed, k] - positions[fixed, k]
            for axis in range(3):
                targets[~fixed, k, axis] += np.interp(frames[~fixed], frames[fixed], shift[:, axis])
    return targets


def retarget(skeleton, motion, scales):
    """A copy of the clip on a skeleton whose bones are scaled: scales {joint: factor} scales
    the offset from that joint's parent. The naive retarget: same joint angles, the root's
    height scaled by the ratio of hip heights (root above the lowest rest point), its path
    along the ground kept. Longer legs then take longer strides than the body travels: the
    planted feet skate."""
    if not isinstance(skeleton, Skeleton):
        raise ValueError(f"skeleton: expected an ik.characters.bvh.Skeleton, got {type(skeleton).__name__}")
    if not isinstance(scales, dict) or not scales:
        raise ValueError(f"scales: expected a dict {{joint name: factor}}, got {scales!r:.80}")
    offsets = skeleton.offsets.copy()
    for name, factor in scales.items():
        offsets[skeleton.index(name)] *= as_number(factor, f"scales[{name!r}]", minimum=0, strict=True)
    new = dataclasses.replace(skeleton, offsets=offsets)

    def hip_height(sk):
        joints, ends = rest_positions(sk)
        return joints[0, UP] - min(joints[:, UP].min(), ends[:, UP].min() if len(ends) else np.inf)

    frames = np.array(motion.frames)
    cols = skeleton.columns(skeleton.names[0])
    if "Yposition" in cols:
        frames[:, cols["Yposition"]] *= hip_height(new) / hip_height(skeleton)
    return new, Motion(frames, motion.frame_time)


def largest_step(theta):
    """The largest frame-to-frame change of any joint angle (radians): a pop shows up here."""
    return float(np.max(np.abs(np.diff(np.asarray(theta), axis=0))))


def leg_joints(rig, foot):
    """The revolute joints that place a foot: its hip (the foot's grandparent, all channels),
    its knee (the foot's parent, a hinge: Xrotation only) and its own hinge (Xrotation: the
    foot's pitch, which keeps the toe where it should be)."""
    sk = rig.skeleton
    knee = sk.parents[sk.index(foot)]
    hip = sk.parents[knee]
    if knee < 0 or hip < 0:
        raise ValueError(f"feet: {foot!r} needs a knee and a hip above it")
    return (rig.revolutes(sk.names[hip]) + rig.revolutes(sk.names[knee], ["Xrotation"])
            + rig.revolutes(foot, ["Xrotation"]))


def floor_lift(targets, floor):
    """Targets (F, k, p, 3) (frame, foot, the foot's points) moved up, per frame and foot, by
    just enough that none of the foot's points is below `floor` (their heights keep their
    differences, so a flat foot stays flat)."""
    targets = np.array(targets, float)
    floor = as_number(floor, "floor")
    lift = np.maximum(0.0, floor - targets[..., UP].min(axis=-1))
    targets[..., UP] += lift[..., None]
    return targets


@dataclasses.dataclass(frozen=True)
class Cleanup:
    """A retargeted clip before and after foot planting: positions of the feet (ankles) and
    toes (F, k, 3); targets (F, k, 3) are the ankles'."""
    rig: object
    root: np.ndarray
    contact: np.ndarray          # (F, k) detected on the original clip
    theta_before: np.ndarray
    theta_after: np.ndarray
    feet_before: np.ndarray
    feet_after: np.ndarray
    targets: np.ndarray
    result: ClipResult
    toes_before: np.ndarray = None
    toes_after: np.ndarray = None
    toe_targets: np.ndarray = None

    @property
    def all_targets(self):
        """What solve_clip was given: (F, 2k, 3), the ankles' targets then the toes'."""
        return np.concatenate([self.targets, self.toe_targets], axis=1)

    @property
    def skate_before(self):
        return foot_skate(self.feet_before, self.contact)

    @property
    def skate_after(self):
        return foot_skate(self.feet_after, self.contact)


def clean_clip(skeleton, motion, scales, feet=("LeftFoot", "RightFoot"), height=9.0, speed=15.0,
               floor=0.0, **solve_options):
    """The whole pipeline: contacts on the original clip, retarget with `scales` (the feet
    skate), plant targets (lifted onto `floor`, None: no floor), IK frame by frame on the hips,
    knees and ankle hinges, the toes (each foot's end site) keeping the clip's ankle-to-toe
    vector. Returns a Cleanup."""
    from .skeleton import angles, rig as make_rig, world_points

    original = make_rig(skeleton, feet)
    root, theta = angles(original, motion.frames)
    contact = contacts(world_points(original, root, theta), motion.frame_time, height, speed)
    new_skeleton, new_motion = retarget(skeleton, motion, scales)
    k = len(feet)
    rig = make_rig(new_skeleton, list(feet) + [f + "_end" for f in feet])
    root, theta = angles(rig, new_motion.frames)
    before = world_points(rig, root, theta)
    ankle = plant_targets(before[:, :k], contact)
    both = np.stack([ankle, ankle + before[:, k:] - before[:, :k]], axis=2)   # (F, k, 2, 3)
    if floor is not None:
        both = floor_lift(both, floor)
    targets = np.concatenate([both[:, :, 0], both[:, :, 1]], axis=1)
    active = sum((leg_joints(rig, f) for f in feet), [])
    result = solve_clip(rig, root, theta, targets, active, **solve_options)
    after = world_points(rig, root, result.theta)
    return Cleanup(rig, root, contact, theta, result.theta, before[:, :k], after[:, :k],
                   targets[:, :k], result, before[:, k:], after[:, k:], targets[:, k:])
