"""Foot planting on the shipped walk clip (150 frames, 2 feet): time to clean the whole clip
with ik.characters.clip_ik.solve_clip after compiling (the goal: under 1 s), and the skate before/after.

    python benchmarks/footplant.py [--repeat 20]
"""
import argparse
import time

import numpy as np

from ikteach.characters import bvh, clip_ik, footplant, skeleton

LONG_LEGS = {"LeftLeg": 1.2, "RightLeg": 1.2, "LeftFoot": 1.1, "RightFoot": 1.1}  # as notebook 09


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    sk, motion = bvh.load(bvh.walk_path())
    start = time.perf_counter()
    clean = footplant.clean_clip(sk, motion, LONG_LEGS)    # compiles, then solves once
    first = time.perf_counter() - start
    active = sum((footplant.leg_joints(clean.rig, f) for f in ("LeftFoot", "RightFoot")), [])
    times = []
    for _ in range(args.repeat):
        start = time.perf_counter()
        clip_ik.solve_clip(clean.rig, clean.root, clean.theta_before, clean.all_targets, active)
        times.append(time.perf_counter() - start)
    p50, p95 = np.percentile(times, [50, 95])
    frames, feet = clean.contact.shape
    print(f"walk clip: {frames} frames, {feet} feet, {clean.rig.n_joints} revolute joints "
          f"({len(active)} turned), DLS, tol 1e-3 cm")
    print(f"iterations per frame: mean {clean.result.iterations.mean():.2f}, max {clean.result.iterations.max()}")
    print(f"{'':28}{'p50':>10}{'p95':>10}")
    print(f"{'whole clip (after compile)':28}{p50 * 1e3:>8.1f}ms{p95 * 1e3:>8.1f}ms")
    print(f"{'per frame':28}{p50 / frames * 1e6:>8.1f}us{p95 / frames * 1e6:>8.1f}us")
    print(f"first call (with compiling): {first:.2f} s;  under 1 s after compiling: {p95 < 1.0}")
    before, after = clean.skate_before, clean.skate_after
    print(f"skate (cm), left/right: before {before[0]:.2f}/{before[1]:.2f}, after {after[0]:.4f}/{after[1]:.4f}, "
          f"reduced by {100 * (1 - after.sum() / before.sum()):.4f} %")
    print(f"largest frame-to-frame joint change (rad): clip {footplant.largest_step(clean.theta_before):.3f}, "
          f"cleaned {footplant.largest_step(clean.theta_after):.3f}")


if __name__ == "__main__":
    main()
