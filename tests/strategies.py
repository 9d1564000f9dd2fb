"""Hypothesis strategies for random chains, angles and Jacobians."""
import numpy as np
from hypothesis import strategies as st

import ikteach as ik

finite = dict(allow_nan=False, allow_infinity=False)
angles = st.floats(-np.pi, np.pi, **finite)


@st.composite
def planar_arms(draw, min_joints=1, max_joints=6):
    n = draw(st.integers(min_joints, max_joints))
    lengths = draw(st.lists(st.floats(0.1, 2.0, **finite), min_size=n, max_size=n))
    return ik.planar_chain(lengths)


@st.composite
def spatial_arms(draw, min_joints=1, max_joints=7):
    n = draw(st.integers(min_joints, max_joints))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    offsets = rng.uniform(-1.0, 1.0, size=(n, 3))
    return ik.serial_chain(axes, offsets)


def arm_and_angles(arms):
    return arms.flatmap(lambda arm: st.tuples(
        st.just(arm), st.lists(angles, min_size=arm.n_joints, max_size=arm.n_joints).map(np.array)))


@st.composite
def matrices(draw, max_rows=6, max_cols=10):
    m = draw(st.integers(1, max_rows))
    n = draw(st.integers(1, max_cols))
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    return rng.normal(size=(m, n)), rng.normal(size=m)


def _topology(n, m, seed):
    """Random parents (each joint hangs from an earlier one) and effector parents."""
    rng = np.random.default_rng(seed)
    parents = [-1] + [int(rng.integers(0, j)) for j in range(1, n)]
    return tuple(parents), tuple(rng.integers(0, n, size=m).tolist())


# A tree's shape is static (one compile each), so shapes come from a fixed pool of random ones,
# 1 to 8 joints and 1 to 3 effectors, plus a chain and a star; the geometry is free.
TREE_SHAPES = [_topology(n, m, seed) for seed, (n, m) in
               enumerate([(1, 1), (2, 2), (3, 1), (4, 3), (5, 2), (6, 3), (8, 1), (8, 3)])]
TREE_SHAPES += [(tuple(range(-1, 5)), (5, 2)), ((-1,) + (0,) * 5, (1, 3, 5))]


@st.composite
def random_trees(draw, shapes=TREE_SHAPES):
    parents, effector_parents = draw(st.sampled_from(shapes))
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    n, m = len(parents), len(effector_parents)
    return ik.tree(rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), list(parents),
                   rng.normal(size=(m, 3)), list(effector_parents))
