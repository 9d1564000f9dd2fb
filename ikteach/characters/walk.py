"""The walk clip shipped as ikteach/characters/data/walk.bvh, made here (no motion-capture clip with a
licence that allows shipping it comes in a registry package we could find).

A deterministic, procedural walk in centimetres (Y up, Z forward, X to the character's left):
the hips move forward at a steady speed and bob; each foot is planted flat on the ground for
60 % of the gait cycle (the stance) and swings along an arc to its next footprint; the legs
reach their feet by the analytic two-link solution in the sagittal plane; arms swing against
the legs, the chest twists, the head counter-twists. Regenerate with `python -m ikteach.walk`.
"""
import numpy as np

from .bvh import Motion, Skeleton, save

ZXY = ("Zrotation", "Xrotation", "Yrotation")
ROOT = ("Xposition", "Yposition", "Zposition") + ZXY
THIGH, SHIN, ANKLE = 44.0, 43.0, 8.0     # cm; the ankle sits ANKLE above the ground
HIP_HEIGHT, BOB = 88.5, 1.5              # hips' mean height and bob
STRIDE, CYCLE, DUTY, LIFT = 100.0, 1.0, 0.6, 5.0   # cm per cycle, s, stance fraction, swing height
FRAME_TIME, FRAMES = 1 / 30, 150

# name, parent, offset (cm, rest pose: standing, arms down), end site offset or None
JOINTS = [
    ("Hips", None, (0, 0, 0), None),
    ("LeftUpLeg", "Hips", (9, 0, 0), None),
    ("LeftLeg", "LeftUpLeg", (0, -THIGH, 0), None),
    ("LeftFoot", "LeftLeg", (0, -SHIN, 0), (0, -ANKLE, 14)),
    ("RightUpLeg", "Hips", (-9, 0, 0), None),
    ("RightLeg", "RightUpLeg", (0, -THIGH, 0), None),
    ("RightFoot", "RightLeg", (0, -SHIN, 0), (0, -ANKLE, 14)),
    ("Spine", "Hips", (0, 8, 0), None),
    ("Chest", "Spine", (0, 18, 0), None),
    ("Neck", "Chest", (0, 22, 0), None),
    ("Head", "Neck", (0, 10, 0), (0, 16, 0)),
    ("LeftShoulder", "Chest", (6, 16, 0), None),
    ("LeftArm", "LeftShoulder", (12, 0, 0), None),
    ("LeftForeArm", "LeftArm", (0, -28, 0), None),
    ("LeftHand", "LeftForeArm", (0, -26, 0), (0, -16, 0)),
    ("RightShoulder", "Chest", (-6, 16, 0), None),
    ("RightArm", "RightShoulder", (-12, 0, 0), None),
    ("RightForeArm", "RightArm", (0, -28, 0), None),
    ("RightHand", "RightForeArm", (0, -26, 0), (0, -16, 0)),
]


def walk_skeleton():
    """The clip's skeleton: 19 joints, each a ZXY ball joint, the hips also translate."""
    names = tuple(j[0] for j in JOINTS)
    parents = tuple(-1 if p is None else names.index(p) for _, p, _, _ in JOINTS)
    ends = [(i, e) for i, (_, _, _, e) in enumerate(JOINTS) if e is not None]
    return Skeleton(names, parents, np.array([j[2] for j in JOINTS], float),
                    tuple(ROOT if p is None else ZXY for _, p, _, _ in JOINTS),
                    tuple(i for i, _ in ends), np.array([e for _, e in ends], float))


def two_link(dz, dy, l1=THIGH, l2=SHIN):
    """Hip and knee angles (radians, about x) that put the ankle at (dz, dy) from the hip.

    Rx(a) turns the downward thigh (0, -1, 0) to (0, -cos a, -sin a), so the ankle is at
    z = -l1 sin a - l2 sin(a + b), y = -l1 cos a - l2 cos(a + b); the law of cosines gives
    the knee b >= 0 (the shin bends backwards), then a = atan2(-dz, -dy) - atan2(l2 sin b, l1 + l2 cos b).
    """
    d2 = dz ** 2 + dy ** 2
    b = np.arccos(np.clip((d2 - l1 ** 2 - l2 ** 2) / (2 * l1 * l2), -1.0, 1.0))
    a = np.arctan2(-dz, -dy) - np.arctan2(l2 * np.sin(b), l1 + l2 * np.cos(b))
    return a, b


def foot_path(t, phase):
    """Ankle (z, height) at times t for a foot whose stance starts at cycle phase `phase`.

    Stance: the foot stays where it landed, STRIDE * DUTY / 2 ahead of where the hips were
    then; swing: it travels one STRIDE along a raised arc to the next footprint.
    """
    speed = STRIDE / CYCLE
    u = t / CYCLE - phase
    cycle, phi = np.floor(u), u - np.floor(u)
    plant = speed * (cycle + phase) * CYCLE + STRIDE * DUTY / 2
    s = np.clip((phi - DUTY) / (1 - DUTY), 0.0, 1.0)   # 0 during stance, 0..1 over the swing
    z = plant + STRIDE * (1 - np.cos(np.pi * s)) / 2
    y = ANKLE + LIFT * np.sin(np.pi * s)
    return z, y


def walk_motion(frames=FRAMES, frame_time=FRAME_TIME):
    """The motion rows (frames x 57 channels) of the walk, in degrees and centimetres."""
    sk = walk_skeleton()
    t = np.arange(frames) * frame_time
    out = np.zeros((frames, sk.n_channels))
    col = {}
    start = 0
    for name, chans in zip(sk.names, sk.channels):
        col[name] = {c: start + i for i, c in enumerate(chans)}
        start += len(chans)
    hip_z = STRIDE / CYCLE * t
    hip_y = HIP_HEIGHT - BOB * np.cos(4 * np.pi * (t / CYCLE - 0.05))
    out[:, col["Hips"]["Yposition"]], out[:, col["Hips"]["Zposition"]] = hip_y, hip_z
    swing = {}
    for side, phase in (("Left", 0.0), ("Right", 0.5)):
        z, y = foot_path(t, phase)
        a, b = two_link(z - hip_z, y - hip_y)
        out[:, col[side + "UpLeg"]["Xrotation"]] = np.degrees(a)
        out[:, col[side + "Leg"]["Xrotation"]] = np.degrees(b)
        out[:, col[side + "Foot"]["Xrotation"]] = -np.degrees(a + b)   # the foot stays flat
        swing[side] = a
    for side, other, sign in (("Left", "Right", 1), ("Right", "Left", -1)):
        out[:, col[side + "Arm"]["Xrotation"]] = -np.degrees(0.8 * swing[side])  # against the leg
        out[:, col[side + "Arm"]["Zrotation"]] = sign * 6.0                     # away from the body
        out[:, col[side + "ForeArm"]["Xrotation"]] = -15.0 - 10.0 * np.degrees(swing[other]) / 30.0
    twist = 0.25 * np.degrees(swing["Left"] - swing["Right"])
    out[:, col["Chest"]["Yrotation"]] = twist
    out[:, col["Neck"]["Yrotation"]] = -twist                                    # eyes ahead
    out[:, col["Spine"]["Xrotation"]] = -3.0                                     # lean a little forward
    out[:, col["Neck"]["Xrotation"]] = 3.0
    return Motion(np.round(out, 4), frame_time)


def main(path=None):
    from .bvh import walk_path

    path = path or walk_path()
    save(path, walk_skeleton(), walk_motion())
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
