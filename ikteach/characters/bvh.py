"""BVH (Biovision hierarchy), the animation world's motion-capture format: read and write.

A BVH file has two parts:
  HIERARCHY  joints as nested blocks: ROOT/JOINT name { OFFSET x y z  CHANNELS k ... },
             a leaf ends in "End Site { OFFSET x y z }";
  MOTION     "Frames: F", "Frame Time: dt", then F rows of numbers, one per channel, in the
             order the channels appear in the hierarchy (rotations in degrees).
A joint's local rotation is the product of its rotation channels in the order listed,
e.g. "Zrotation Xrotation Yrotation" means R = Rz(a) Rx(b) Ry(c); the rest pose has every
rotation zero. ikteach.skeleton turns a Skeleton into an IK tree.
"""
import dataclasses
import os
from importlib import resources

import numpy as np

from ..core._validate import as_array
from .skeleton import POSITIONS, ROTATIONS, Skeleton  # noqa: F401  (ik.characters.bvh.Skeleton)


@dataclasses.dataclass(frozen=True, eq=False)
class Motion:
    """frames (F, channels): one row per frame, channels in hierarchy order; frame_time in s."""
    frames: np.ndarray
    frame_time: float

    def __len__(self):
        return len(self.frames)


def _tokens(text):
    for line_no, line in enumerate(text.splitlines(), 1):
        for word in line.split():
            yield line_no, word


class _Reader:
    def __init__(self, text, source):
        self.words = list(_tokens(text))
        self.i = 0
        self.source = source

    def error(self, expected):
        line, got = self.words[self.i] if self.i < len(self.words) else ("end", "end of file")
        return ValueError(f"path: {self.source} is not valid BVH: line {line}: expected {expected}, got {got!r}")

    def next(self, expected="a word"):
        if self.i >= len(self.words):
            raise self.error(expected)
        self.i += 1
        return self.words[self.i - 1][1]

    def expect(self, *words):
        if self.i >= len(self.words) or self.words[self.i][1].upper() not in words:
            raise self.error(" or ".join(words))
        return self.next()

    def number(self, what):
        try:
            return float(self.next(what))
        except ValueError:
            self.i -= 1
            raise self.error(what) from None

    def offset(self):
        self.expect("OFFSET")
        return [self.number("an offset number") for _ in range(3)]


def _read_joint(r, parent, out):
    """A ROOT/JOINT block (its keyword already read) and everything inside it."""
    j = len(out["names"])
    out["names"].append(r.next("a joint name"))
    out["parents"].append(parent)
    r.expect("{")
    out["offsets"].append(r.offset())
    r.expect("CHANNELS")
    count = r.number("a channel count")
    if count != int(count) or count < 0:
        raise r.error("a channel count")
    channels = tuple(r.next("a channel name") for _ in range(int(count)))
    for c in channels:
        if c not in ROTATIONS + POSITIONS:
            r.i -= 1
            raise r.error("a channel name like Zrotation or Xposition")
    out["channels"].append(channels)
    while r.expect("JOINT", "END", "}").upper() != "}":
        if r.words[r.i - 1][1].upper() == "JOINT":
            _read_joint(r, j, out)
        else:
            r.expect("SITE")
            r.expect("{")
            out["end_parents"].append(j)
            out["end_offsets"].append(r.offset())
            r.expect("}")


def parse(text, source="<text>"):
    """A BVH file's text -> (Skeleton, Motion). Errors name the line and what was expected."""
    r = _Reader(text, source)
    r.expect("HIERARCHY")
    r.expect("ROOT")
    out = {k: [] for k in ("names", "parents", "offsets", "channels", "end_parents", "end_offsets")}
    _read_joint(r, -1, out)
    if len(set(out["names"])) != len(out["names"]):
        raise ValueError(f"path: {source} is not valid BVH: joint names repeat")
    skeleton = Skeleton(tuple(out["names"]), tuple(out["parents"]), np.array(out["offsets"], float),
                        tuple(out["channels"]), tuple(out["end_parents"]),
                        np.array(out["end_offsets"], float).reshape(-1, 3))
    r.expect("MOTION")
    r.expect("FRAMES:")
    count = r.number("the frame count")
    r.expect("FRAME")
    r.expect("TIME:")
    frame_time = r.number("the frame time")
    if count != int(count) or count < 0 or not frame_time > 0:
        raise ValueError(f"path: {source} is not valid BVH: expected a whole number of frames "
                         f"and a positive frame time, got {count} and {frame_time}")
    values = [r.number("a channel value") for _ in range(int(count) * skeleton.n_channels)]
    if r.i != len(r.words):
        raise r.error(f"end of file after {int(count)} frames")
    frames = np.array(values, float).reshape(int(count), skeleton.n_channels)
    return skeleton, Motion(frames, frame_time)


def load(path):
    """Read a BVH file: returns (skeleton, motion)."""
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path: expected a file name, got {path!r:.80}")
    if not os.path.isfile(path):
        raise ValueError(f"path: no such file: {os.fspath(path)!r}")
    with open(path, encoding="utf-8") as f:
        return parse(f.read(), os.fspath(path))


def _num(x):
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def format_bvh(skeleton, motion):
    """The BVH text of a skeleton and its motion (6 decimals: save then load round-trips)."""
    frames = as_array(motion.frames, "motion.frames", shape=(None, skeleton.n_channels))
    lines = ["HIERARCHY"]

    def joint(j, depth):
        pad = "  " * depth
        lines.append(f"{pad}{'ROOT' if skeleton.parents[j] < 0 else 'JOINT'} {skeleton.names[j]}")
        lines.append(pad + "{")
        lines.append(f"{pad}  OFFSET {' '.join(_num(v) for v in skeleton.offsets[j])}")
        lines.append(f"{pad}  CHANNELS {len(skeleton.channels[j])} {' '.join(skeleton.channels[j])}".rstrip())
        for child, parent in enumerate(skeleton.parents):
            if parent == j:
                joint(child, depth + 1)
        for k, parent in enumerate(skeleton.end_parents):
            if parent == j:
                lines.extend([f"{pad}  End Site", f"{pad}  {{",
                              f"{pad}    OFFSET {' '.join(_num(v) for v in skeleton.end_offsets[k])}",
                              f"{pad}  }}"])
        lines.append(pad + "}")

    joint(0, 0)
    lines += ["MOTION", f"Frames: {len(frames)}", f"Frame Time: {_num(motion.frame_time)}"]
    lines += [" ".join(_num(v) for v in row) for row in frames]
    return "\n".join(lines) + "\n"


def save(path, skeleton, motion):
    """Write skeleton and motion as a BVH file; returns the path."""
    if not isinstance(skeleton, Skeleton):
        raise ValueError(f"skeleton: expected an ik.characters.bvh.Skeleton, got {type(skeleton).__name__}")
    if not isinstance(motion, Motion):
        raise ValueError(f"motion: expected an ik.characters.bvh.Motion, got {type(motion).__name__}")
    text = format_bvh(skeleton, motion)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def walk_path():
    """The path of the walk clip shipped with ikteach (generated by ikteach/walk.py)."""
    return str(resources.files("ikteach.characters") / "data" / "walk.bvh")
