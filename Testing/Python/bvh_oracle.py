"""A small BVH reader and forward kinematics of its own, for the motion tests: the clip's joint
positions and rotations computed independently of the code under test, and a clip rewritten in
another length unit."""
import re

import numpy as np

# BVH axes (X left, Y up, Z forward) -> LPS (x left, y posterior, z superior).
BVH_TO_LPS = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])


def _axis_rotation(axis, degrees):
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    if axis == "X":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "Y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


class Clip:
    """Joints (name, parent, offset, channels, first column) and the frame rows of a BVH file."""

    def __init__(self, path):
        text = open(path).read()
        head, motion = text.split("MOTION", 1)
        self.joints, stack, end_site = [], [], False
        tokens = head.split()
        i, column = 0, 0
        while i < len(tokens):
            t = tokens[i]
            if t in ("ROOT", "JOINT"):
                self.joints.append({"name": tokens[i + 1], "parent": stack[-1] if stack else -1, "channels": [],
                                    "first": column, "offset": np.zeros(3)})
                i += 2
            elif t == "End":
                end_site = True
                i += 2
            elif t == "{":
                stack.append(None if end_site else len(self.joints) - 1)
                i += 1
            elif t == "}":
                if stack.pop() is None:
                    end_site = False
                i += 1
            elif t == "OFFSET":
                if not end_site:
                    self.joints[stack[-1]]["offset"] = np.array(list(map(float, tokens[i + 1:i + 4])))
                i += 4
            elif t == "CHANNELS":
                n = int(tokens[i + 1])
                self.joints[stack[-1]]["channels"] = tokens[i + 2:i + 2 + n]
                self.joints[stack[-1]]["first"] = column
                column += n
                i += 2 + n
            else:
                i += 1
        rows = motion.strip().splitlines()[2:]
        self.frames = np.array([list(map(float, r.split())) for r in rows if r.strip()])
        self.index = {j["name"]: k for k, j in enumerate(self.joints)}

    def pose(self, frame):
        """Global (rotation, position) per joint, in LPS (positions in BVH units)."""
        row, out = self.frames[frame], []
        for j in self.joints:
            t, r = j["offset"].copy(), np.eye(3)
            for k, c in enumerate(j["channels"]):
                v = row[j["first"] + k]
                if c.endswith("position"):
                    t["XYZ".index(c[0])] += v
                else:
                    r = r @ _axis_rotation(c[0], v)
            if j["parent"] >= 0:
                pr, pt = out[j["parent"]]
                r, t = pr @ r, pt + pr @ t
            out.append((r, t))
        return [(BVH_TO_LPS @ r @ BVH_TO_LPS.T, BVH_TO_LPS @ t) for r, t in out]


def write_scaled(src, dst, factor):
    """The clip of `src` with every length (OFFSETs, position channels) multiplied by factor."""
    head, motion = open(src).read().split("MOTION", 1)
    head = re.sub(r"OFFSET\s+(\S+)\s+(\S+)\s+(\S+)",
                  lambda m: "OFFSET " + " ".join(f"{float(v) * factor:.6f}" for v in m.groups()), head)
    clip = Clip(src)
    position = [j["first"] + k for j in clip.joints for k, c in enumerate(j["channels"]) if c.endswith("position")]
    lines = motion.strip().splitlines()
    rows = []
    for line in lines[2:]:
        values = line.split()
        for c in position:
            values[c] = f"{float(values[c]) * factor:.6f}"
        rows.append(" ".join(values))
    open(dst, "w").write(head + "MOTION\n" + "\n".join(lines[:2] + rows) + "\n")


def pitch(r):
    """Forward flexion (degrees) of rotation r about the left-right axis: where it takes superior."""
    up = r @ np.array([0, 0, 1.0])
    return np.degrees(np.arctan2(-up[1], up[2]))


def angle_between(u, v):
    return np.degrees(np.arccos(np.clip(u @ v / np.linalg.norm(u) / np.linalg.norm(v), -1, 1)))
