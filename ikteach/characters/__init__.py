"""Characters: BVH skeletons and motion, rigs, the shipped walk, foot planting, clip IK, look-at.
Uses the core only."""
