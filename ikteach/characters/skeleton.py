"""A BVH skeleton as an IK tree: every rotation channel is one revolute joint.

A ball joint with channels "Zrotation Xrotation Yrotation" becomes three revolute joints at the
same point with axes z, x, y, chained in the channel order, so R = R_parent Rz(a) Rx(b) Ry(c),
BVH's own product (in the rest pose nothing is rotated, so the local axes are world axes).
The root's position channels are not joints: the tree is built around the root and
world point = root translation + tree point (the root's OFFSET is then ignored, as in bvhio). Angles are radians here, degrees in the file.
"""
import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from ..core._validate import as_array
from ..core.tree import tree, tree_fk
from .._runtime.jit import quick_jit

AXES = {"Xrotation": (1.0, 0.0, 0.0), "Yrotation": (0.0, 1.0, 0.0), "Zrotation": (0.0, 0.0, 1.0)}
ROTATIONS = ("Xrotation", "Yrotation", "Zrotation")
POSITIONS = ("Xposition", "Yposition", "Zposition")


@dataclasses.dataclass(frozen=True, eq=False)
class Skeleton:
    """The joints of a BVH hierarchy, listed parents first.

    names[j], parents[j] (-1 for the root), offsets[j] (from the parent joint, rest pose),
    channels[j] (channel names of joint j); an end site k hangs on joint end_parents[k]
    at end_offsets[k].
    """
    names: tuple
    parents: tuple
    offsets: np.ndarray
    channels: tuple
    end_parents: tuple
    end_offsets: np.ndarray

    @property
    def n_channels(self):
        return sum(len(c) for c in self.channels)

    def index(self, name):
        """The index of joint `name` (ValueError naming the joints there are)."""
        if name not in self.names:
            raise ValueError(f"joint: expected one of {list(self.names)}, got {name!r}")
        return self.names.index(name)

    def columns(self, name):
        """{channel name: column of the motion} for joint `name`."""
        j = self.index(name)
        start = sum(len(c) for c in self.channels[:j])
        return {c: start + i for i, c in enumerate(self.channels[j])}

    def rig(self, points=None):
        """The skeleton as an IK tree (ik.characters.skeleton.rig): rig.tree is an ik.core.tree.Tree with end effectors
        at the named points (default: every joint and end site)."""
        return rig(self, points)

    def __repr__(self):
        return f"Skeleton({len(self.names)} joints, {len(self.end_parents)} end sites, {self.n_channels} channels)"


@dataclasses.dataclass(frozen=True, eq=False)
class Rig:
    """A skeleton's IK tree and how its revolute joints map back to the skeleton.

    tree           the ik.core.tree.Tree (end effectors = the named points);
    points         names of the end effectors (joint names, or "<joint>_end" for an end site);
    joint_of[i]    the skeleton joint that revolute i belongs to;
    column_of[i]   the motion column (channel) of revolute i;
    root_columns   the motion columns of the root's X, Y, Z position (None if it has none).
    """
    skeleton: Skeleton
    tree: object
    points: tuple
    joint_of: tuple
    column_of: tuple
    root_columns: tuple

    @property
    def n_joints(self):
        return self.tree.n_joints

    def revolutes(self, name, channels=None):
        """Indices of the revolute joints of skeleton joint `name` (optionally only these channels)."""
        j = self.skeleton.index(name)
        names = self.skeleton.channels[j]
        cols = self.skeleton.columns(name)
        wanted = [c for c in names if c in AXES and (channels is None or c in channels)]
        return [self.column_of.index(cols[c]) for c in wanted]

    def bones(self):
        """Pairs (a, b) of point indices to draw as bones: each point to its nearest drawn ancestor."""
        sk = self.skeleton
        where = {name: k for k, name in enumerate(self.points)}
        pairs = []
        for k, name in enumerate(self.points):  # end sites and offset points hang on their joint
            if isinstance(name, tuple):
                j = sk.index(name[0])
            else:
                j = sk.parents[sk.index(name)] if name in sk.names else sk.index(name[:-4])
            while j >= 0 and sk.names[j] not in where:
                j = sk.parents[j]
            if j >= 0:
                pairs.append((where[sk.names[j]], k))
        return pairs


def _end_index(sk, name):
    j = sk.index(name[:-4])
    ends = [k for k, p in enumerate(sk.end_parents) if p == j]
    if not ends:
        raise ValueError(f"points: joint {name[:-4]!r} has no end site, so {name!r} does not exist")
    return ends[0]


def _point(skeleton, joints, ends, point):
    """(joint that carries the point, its rest position) for a point name (see rig)."""
    if isinstance(point, tuple) and len(point) == 2 and isinstance(point[0], str):
        j = skeleton.index(point[0])
        return j, joints[j] + as_array(point[1], f"points: offset of {point[0]!r}", shape=(3,))
    if not isinstance(point, str):
        raise ValueError(f"points: expected joint names or (joint, offset) pairs, got {point!r:.80}")
    if point.endswith("_end") and point not in skeleton.names:
        k = _end_index(skeleton, point)
        return skeleton.end_parents[k], ends[k]
    j = skeleton.index(point)
    return j, joints[j]


def rest_positions(skeleton):
    """World positions of the joints (n, 3) and end sites (k, 3) in the rest pose."""
    p = np.zeros((len(skeleton.names), 3))
    for j, parent in enumerate(skeleton.parents):
        p[j] = skeleton.offsets[j] + (p[parent] if parent >= 0 else 0.0)
    ends = np.array([p[j] for j in skeleton.end_parents]).reshape(-1, 3) + skeleton.end_offsets
    return p, ends


def all_points(skeleton):
    """Every joint's name and "<joint>_end" for each joint with an end site (for drawing)."""
    return tuple(skeleton.names) + tuple(f"{skeleton.names[j]}_end" for j in sorted(set(skeleton.end_parents)))


def rig(skeleton, points=None):
    """The IK tree of a skeleton, with end effectors at the named points (default: all_points).

    points: joint names (effector at the joint), "<joint>_end" (at its end site) or
            (joint, offset) pairs (a point fixed to the joint, offset in the rest pose, e.g. the eyes).
    """
    if not isinstance(skeleton, Skeleton):
        raise ValueError(f"skeleton: expected an ik.characters.bvh.Skeleton, got {type(skeleton).__name__}")
    points = all_points(skeleton) if points is None else tuple(points)
    if not points:
        raise ValueError("points: expected a non-empty list of joint names, got none")
    root_cols = skeleton.columns(skeleton.names[0])
    root_columns = tuple(root_cols[c] for c in POSITIONS) if all(c in root_cols for c in POSITIONS) else None
    joints, ends = rest_positions(skeleton)
    if root_columns:  # the root's position channels say where it is (its OFFSET is ignored)
        joints, ends = joints - skeleton.offsets[0], ends - skeleton.offsets[0]
    positions, axes, parents, joint_of, column_of = [], [], [], [], []
    last = {}  # skeleton joint -> its last revolute (or its nearest ancestor's)
    column = 0
    for j, chans in enumerate(skeleton.channels):
        if skeleton.parents[j] >= 0 and any(c in POSITIONS for c in chans):
            raise ValueError(f"skeleton: position channels on joint {skeleton.names[j]!r}; "
                             "only the root may translate")
        prev = last.get(skeleton.parents[j], -1)
        for c in chans:
            if c in AXES:
                positions.append(joints[j])
                axes.append(AXES[c])
                parents.append(prev)
                joint_of.append(j)
                column_of.append(column)
                prev = len(positions) - 1
            column += 1
        last[j] = prev
    if not positions:
        raise ValueError("skeleton: expected rotation channels, got none")
    effectors, effector_parents = [], []
    for name in points:
        j, at = _point(skeleton, joints, ends, name)
        effectors.append(at)
        effector_parents.append(max(last[j], 0))
    arm = tree(positions, axes, parents, effectors, effector_parents)
    return Rig(skeleton, arm, points, tuple(joint_of), tuple(column_of), root_columns)


def angles(rig, frames):
    """Motion rows (F, channels) -> root translation (F, 3) and joint angles theta (F, n) in radians."""
    frames = as_array(frames, "frames", shape=(None, rig.skeleton.n_channels))
    root = frames[:, list(rig.root_columns)] if rig.root_columns else np.zeros((len(frames), 3))
    return root, np.radians(frames[:, list(rig.column_of)])


def frames_from(rig, root, theta, like):
    """Motion rows with the root translation and angles (radians) written into a copy of `like`."""
    out = np.array(as_array(like, "like", shape=(None, rig.skeleton.n_channels)))
    theta = as_array(theta, "theta", shape=(len(out), rig.n_joints))
    out[:, list(rig.column_of)] = np.degrees(theta)
    if rig.root_columns:
        out[:, list(rig.root_columns)] = as_array(root, "root", shape=(len(out), 3))
    return out


@quick_jit
def _points(arm, root, theta):
    return root[:, None, :] + jax.vmap(lambda q: tree_fk(arm, q))(theta)


def world_points(rig, root, theta):
    """World positions of the rig's points in every frame: (F, m, 3)."""
    theta = jnp.atleast_2d(jnp.asarray(theta, dtype=float))
    root = jnp.broadcast_to(jnp.asarray(root, dtype=float), (theta.shape[0], 3))
    return np.asarray(_points(rig.tree, root, theta))
