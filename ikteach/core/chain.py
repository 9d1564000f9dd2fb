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

from ._validate import HUGE, TINY, as_array


UNIT_TOL = 1e-9  # a joint axis counts as unit when | |axis| - 1 | <= UNIT_TOL


@dataclasses.dataclass(frozen=True)
class Chain:
    """A chain as described in the module docstring. Building one directly checks it (unit
    axes, matching shapes, link lengths 0 or within [TINY, HUGE] with a positive total, and
    for dim = 2 axes along z and links in the plane); planar_chain and serial_chain build
    valid ones. JAX rebuilds chains from their leaves without these checks (tracers)."""
    axes: np.ndarray
    offsets: np.ndarray
    base: np.ndarray
    dim: int = 3

    def __post_init__(self):
        if isinstance(self.dim, bool) or self.dim not in (2, 3):
            raise ValueError(f"dim: expected 2 (planar) or 3 (spatial), got {self.dim!r:.80}")
        axes = as_array(self.axes, "axes", shape=(None, 3))
        if axes.shape[0] == 0:
            raise ValueError("axes: expected at least one joint axis, got none")
        offsets = as_array(self.offsets, "offsets", shape=(axes.shape[0], 3))
        base = as_array(self.base, "base", shape=(3,))
        norms = np.linalg.norm(axes, axis=1)
        if np.any(np.abs(norms - 1.0) > UNIT_TOL):
            j = int(np.argmax(np.abs(norms - 1.0)))
            raise ValueError(f"axes: expected unit joint axes, got |axes[{j}]| = {norms[j]:.6g} "
                             f"(ik.serial_chain normalises them)")
        check_link_lengths(link_lengths(offsets), "offsets")
        if self.dim == 2 and (np.any(axes[:, :2] != 0) or np.any(offsets[:, 2] != 0)
                              or base[2] != 0):
            raise ValueError("dim: a planar chain (dim=2) needs axes along z and offsets and base "
                             "in the plane z = 0 (ik.planar_chain builds one)")
        for name, value in (("axes", axes), ("offsets", offsets), ("base", base)):
            object.__setattr__(self, name, value)

    @property
    def n_joints(self):
        return self.axes.shape[0]

    def __repr__(self):
        kind = "planar" if self.dim == 2 else "spatial"
        return f"Chain({kind}, {self.n_joints} joints, reach {float(reach(self)):.4g})"


def _unflatten(dim, leaves):
    """A Chain from its leaves without __post_init__: JAX rebuilds chains of tracers."""
    arm = object.__new__(Chain)
    for name, value in zip(("axes", "offsets", "base"), leaves):
        object.__setattr__(arm, name, value)
    object.__setattr__(arm, "dim", dim)
    return arm


jax.tree_util.register_pytree_with_keys(
    Chain,
    lambda arm: ((tuple((jax.tree_util.GetAttrKey(k), getattr(arm, k))
                        for k in ("axes", "offsets", "base"))), arm.dim),
    _unflatten,
    lambda arm: ((arm.axes, arm.offsets, arm.base), arm.dim),
)


def link_lengths(offsets):
    """|offsets[i]| without underflow (hypot scales: a 1e-170 link is 1e-170, not 0)."""
    return np.hypot(np.hypot(offsets[:, 0], offsets[:, 1]), offsets[:, 2])


def check_link_lengths(lengths, name):
    """Each link 0 (two joints at one point, e.g. a spherical wrist) or within [TINY, HUGE],
    and a positive total: the same rule for planar and spatial chains."""
    if np.any(lengths < 0):
        raise ValueError(f"{name}: expected link lengths >= 0, got {lengths.tolist()}")
    if np.any((lengths > 0) & (lengths < TINY)) or np.any(lengths > HUGE):
        raise ValueError(f"{name}: expected link lengths of 0 or within [{TINY:g}, {HUGE:g}], "
                         f"got {lengths.tolist()}")
    if lengths.sum() > HUGE:
        raise ValueError(f"{name}: expected a total link length of at most {HUGE:g}, "
                         f"got {lengths.sum():g}")
    if lengths.sum() == 0:
        raise ValueError(f"{name}: expected a positive total link length, got all links of "
                         f"length 0")


def planar_chain(lengths, base=(0.0, 0.0)):
    """A planar arm: revolute joints about z, link i of length lengths[i] along x.

    Lengths are >= 0 (a zero-length link puts two joints at one point), within [TINY, HUGE]
    when positive (ikteach/core/_validate.py), with a positive total.
    """
    lengths = as_array(lengths, "lengths", ndim=1)
    if lengths.size == 0:
        raise ValueError("lengths: expected at least one link length, got none")
    check_link_lengths(lengths, "lengths")
    base = as_array(base, "base", shape=(2,))
    n = lengths.size
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    offsets = np.zeros((n, 3))
    offsets[:, 0] = lengths
    return Chain(axes, offsets, np.append(base, 0.0), dim=2)


def serial_chain(axes, offsets, base=(0.0, 0.0, 0.0)):
    """A spatial serial chain: joint axes (n, 3) in the parent frame (normalised here), link
    offsets (n, 3). Link lengths |offsets[i]| follow planar_chain's rule (0 allowed)."""
    axes = as_array(axes, "axes", shape=(None, 3))
    if axes.shape[0] == 0:
        raise ValueError("axes: expected at least one joint axis, got none")
    offsets = as_array(offsets, "offsets", shape=(axes.shape[0], 3))
    norms = np.linalg.norm(axes, axis=1)
    if np.any(norms < TINY):
        raise ValueError("axes: expected non-zero joint axes, got a zero vector")
    base = as_array(base, "base", shape=(3,))
    return Chain(axes / norms[:, None], offsets, base, dim=3)


def reach(arm):
    """Outer reach: the sum of the link lengths, the radius of the largest sphere reached."""
    return np.linalg.norm(np.asarray(arm.offsets), axis=1).sum()
