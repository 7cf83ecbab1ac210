"""Bad numbers and bad text in skeleton, pose, joint map and BVH files, and absurd options: each
refused early with one line naming the file (or the option), no output, inputs unchanged."""
import json
import os
import shutil
import sys

from repose_testing import SHARED, TEMP, TINY, check, expect_refusal, file_digests

work = os.path.join(TEMP, "bad_messages")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/in")
failures = []
case = f"{TINY}/case"
labels = f"{TINY}/phantom/labels.nii.gz"
skeleton = json.load(open(f"{TINY}/phantom/skeleton.json"))
bvh = open(os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh")).read()
head, motion = bvh[:bvh.index("MOTION")], bvh[bvh.index("MOTION"):].split("\n")


def put(name, text):
    path = f"{work}/in/{name}"
    with open(path, "w") as f:
        f.write(text if isinstance(text, str) else json.dumps(text))
    return path


def skeleton_with_labels(values):
    joints = [dict(j) for j in skeleton["joints"]]
    joints[-1]["labels"] = values
    return {"joints": joints}


def bvh_with(value, column):
    rows = list(motion)
    words = rows[3].split()  # the first frame (after MOTION, Frames:, Frame Time:)
    words[column] = value
    rows[3] = " ".join(words)
    return head + "\n".join(rows)


prepare = ["prepare", "--labels", labels, "--skeleton"]
animate = ["animate", "--case", case, "--frames", "0:2:1", "--bvh"]
cases = [
    ("skeleton joint naming label 0 (the background)", prepare, put("label0.json", skeleton_with_labels([0]))),
    ("skeleton joint naming a negative label", prepare, put("negative.json", skeleton_with_labels([-3]))),
    ("skeleton nested 100000 deep", prepare, put("deep_skeleton.json", "{" * 100000)),
    ("skeleton label 2^40", prepare, put("huge_label.json", skeleton_with_labels([2**40]))),
    ("pose nested 100000 deep", ["pose", "--case", case, "--pose"], put("deep_pose.json", "[" * 100000)),
    ("pose with a translation of 1e999", ["pose", "--case", case, "--pose"],
     put("inf_translation.json", '{"rotations": {}, "translation": [1e999, 0, 0]}')),
    ("pose with a translation of 1e300 mm", ["pose", "--case", case, "--pose"],
     put("far_translation.json", '{"rotations": {}, "translation": [1e300, 0, 0]}')),
    ("BVH root position 1e308", animate, put("far.bvh", bvh_with("1e308", 0))),
    ("BVH rotation 1e308 degrees", animate, put("spin.bvh", bvh_with("1e308", 5))),
    ("BVH value nan", animate, put("nan.bvh", bvh_with("nan", 4))),
    ("BVH value inf", animate, put("inf.bvh", bvh_with("-inf", 7))),
    ("joint map nested 100000 deep", ["animate", "--case", case, "--frames", "0:2:1", "--bvh",
                                      os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh"), "--map"],
     put("deep_map.json", "{" * 100000)),
]
before = file_digests(f"{work}/in")
for i, (what, args, path) in enumerate(cases):
    expect_refusal(what, args + [path], os.path.basename(path), f"{work}/out{i}", failures)
# An absurd option: the message gives the grid's size as a number, not an overflowed product.
line = expect_refusal("voxelize --voxel 1e-6", ["voxelize", "--skin", f"{case}/surfaces.vtp", "--voxel", "1e-6"],
                      "voxel", f"{work}/tiny_voxels.nii.gz", failures)
check("e+" in line and "18446744073709551615" not in line, f"the voxel count is printed as a float", failures)
check(file_digests(f"{work}/in") == before, "inputs unchanged", failures)
print(f"bad skeleton/pose/map/BVH inputs tried: {len(cases) + 1}")
print(f"{len(cases) + 3 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
