"""repose pose reports the pose's quality: on the tiny phantom a mild pose prints its figures and no
warning; a knee and hip bent past their range fold tets, and pose warns with the count that the posed
mesh shows (tets of non-positive volume), saying what to try."""
import json
import os
import re
import sys

import numpy as np

from repose_testing import TEMP, TESTING, TINY, Mesh, check, run

failures = []
work = os.path.join(TEMP, "pose_quality")
os.makedirs(work, exist_ok=True)

_, out, err = run("pose", "--case", f"{TINY}/case", "--pose", os.path.join(TESTING, "Data", "tiny_pose.json"),
                  "--out", f"{work}/mild")
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
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
