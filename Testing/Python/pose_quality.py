"""repose pose reports the pose's quality: on the tiny phantom a mild pose prints its figures and no
warning; a knee and hip bent past their range fold tets, and pose warns with the count that the posed
mesh shows (tets of non-positive volume), saying what to try, and counts the posed voxels two bones'
rigid motions both claim as an independent count over the posed grid does."""
import json
import os
import re
import sys

import numpy as np

from repose_testing import TEMP, TESTING, TINY, Image, Mesh, bone_transforms, check, load_json, run

failures = []
work = os.path.join(TEMP, "pose_quality")
os.makedirs(work, exist_ok=True)

_, out, err = run("pose", "--case", f"{TINY}/case", "--pose", os.path.join(TESTING, "Data", "tiny_pose.json"),
                  "--out", f"{work}/mild")
mild_out = out
line = re.search(r"quality: body volume ([0-9.]+) of rest, (\d+) inverted tets, largest stretch ([0-9.]+)x", out)
check(line is not None, f"pose prints its quality: {out.splitlines()[1:2]}", failures)
check("warning" not in err, f"a mild pose warns of nothing: {err.strip()!r}", failures)

extreme = os.path.join(work, "extreme.json")
with open(extreme, "w") as f:
    json.dump({"rotations": {"left_hip": {"axis": [-1, 0, 0], "degrees": 120},
                             "left_knee": {"axis": [1, 0, 0], "degrees": 140}}}, f)
_, out, err = run("pose", "--case", f"{TINY}/case", "--pose", extreme, "--out", f"{work}/extreme")
rest, posed = Mesh(f"{TINY}/case/mesh.vtu"), Mesh(f"{work}/extreme/posed_mesh.vtu")
t, p = rest.tets, posed.points
det = np.einsum("ij,ij->i", np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), p[t[:, 3]] - p[t[:, 0]])
inverted = int((det <= 0).sum())
check(inverted > 0, f"the extreme pose folds tets: {inverted}", failures)
check(f"warning: {inverted} tets turned inside out" in err and "--relax" in err,
      f"pose warns of the {inverted} folded tets and what to try: {err.strip()!r}", failures)

# Voxels claimed by two bones, counted independently: each posed voxel centre taken back by every bone's
# forward-kinematics motion; claimed by a bone when the rest voxel there holds one of its labels.
collide = os.path.join(work, "collide.json")
with open(collide, "w") as f:
    json.dump({"rotations": {"left_knee": {"axis": [1, 0, 0], "degrees": 175}}}, f)  # the tibia into the femur
_, out, err = run("pose", "--case", f"{TINY}/case", "--pose", collide, "--out", f"{work}/collide")
skeleton, pose = load_json(f"{TINY}/case/skeleton.json"), load_json(collide)
G = bone_transforms(skeleton, pose)
rest_labels, posed_labels = Image(f"{TINY}/case/labels.nii.gz"), Image(f"{work}/collide/posed_labels.nii.gz")
x = posed_labels.centres()
claims = sum(np.isin(rest_labels.nearest((x - G[j["name"]][:3, 3]) @ G[j["name"]][:3, :3]), j["labels"]).astype(int)
             for j in skeleton["joints"])
expected = int((claims >= 2).sum())
reported = re.search(r"(\d+) voxels claimed by two bones", out)
check(reported is not None and expected > 0 and abs(int(reported.group(1)) - expected) <= max(2, 0.02 * expected),
      f"the knee bent to 175 deg: {reported.group(1) if reported else None} voxels claimed by two bones reported, "
      f"{expected} counted independently", failures)
check("warning: two bones overlap in" in err, f"and warned: {err.strip()!r}", failures)
mild = re.search(r"(\d+) voxels claimed by two bones", mild_out)
check(mild is not None and int(mild.group(1)) < expected,
      f"the mild pose: {mild.group(1) if mild else None} voxels claimed by two bones", failures)
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
