"""Kinematic chains of revolute joints: planar arms and spatial serial chains.

A chain of n revolute joints is stored as
  axes[i]    the unit axis of joint i, in the frame of its parent link,
  offsets[i] the link from joint i to joint i+1 (the end effector after the
             last joint), in the frame of joint i after it has turned,
  base       the position of joint 0,
  dim        2 for a planar arm (results keep x, y), 3 for a spatial chain.
"""
import dataclasses

import jax
import numpy as np

from ._validate import as_array


@dataclasses.dataclass(frozen=True)
class Chain:
    axes: np.ndarray
    offsets: np.ndarray
    base: np.ndarray
    dim: int = 3

    @property
    def n_joints(self):
        return self.axes.shape[0]

    def __repr__(self):
        kind = "planar" if self.dim == 2 else "spatial"
        return f"Chain({kind}, {self.n_joints} joints, reach {float(reach(self)):.4g})"


jax.tree_util.register_dataclass(
    Chain, data_fields=["axes", "offsets", "base"], meta_fields=["dim"]
)


def planar_chain(lengths, base=(0.0, 0.0)):
    """A planar arm: revolute joints about z, link i of length lengths[i] along x."""
    lengths = as_array(lengths, "lengths", ndim=1)
    if lengths.size == 0:
        raise ValueError("lengths: expected at least one link length, got none")
    if np.any(lengths <= 0):
        raise ValueError(f"lengths: expected positive link lengths, got {lengths.tolist()}")
    base = as_array(base, "base", shape=(2,))
    n = lengths.size
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    offsets = np.zeros((n, 3))
    offsets[:, 0] = lengths
    return Chain(axes, offsets, np.append(base, 0.0), dim=2)


def serial_chain(axes, offsets, base=(0.0, 0.0, 0.0)):
    """A spatial serial chain: joint axes (n, 3) in the parent frame, link offsets (n, 3)."""
    axes = as_array(axes, "axes", shape=(None, 3))
    if axes.shape[0] == 0:
        raise ValueError("axes: expected at least one joint axis, got none")
    offsets = as_array(offsets, "offsets", shape=(axes.shape[0], 3))
    norms = np.linalg.norm(axes, axis=1)
    if np.any(norms < 1e-12):
        raise ValueError("axes: expected non-zero joint axes, got a zero vector")
    base = as_array(base, "base", shape=(3,))
    return Chain(axes / norms[:, None], offsets, base, dim=3)


def reach(arm):
    """Outer reach: the sum of the link lengths, the radius of the largest sphere reached."""
    return np.linalg.norm(np.asarray(arm.offsets), axis=1).sum()
