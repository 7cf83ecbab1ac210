"""Fixture: the CLI builds the tiny phantom, prepares it and poses it with DQS and LBS."""
import os
import re
import shutil

from repose_testing import TESTING, TINY, run

shutil.rmtree(TINY, ignore_errors=True)
os.makedirs(TINY)
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
run("phantom", "--size", "tiny", "--out", f"{TINY}/phantom")
code, out, _ = run("prepare", "--labels", f"{TINY}/phantom/labels.nii.gz", "--skeleton",
                   f"{TINY}/phantom/skeleton.json", "--out", f"{TINY}/case")
print(out)
# TetGen says nothing while it runs: prepare tells its size before it starts.
assert re.search(r"prepare: TetGen: \d+ surface triangles and \d+ bone seeds into about \d+ k tets", out), out
for method in ("dqs", "lbs"):
    code, out, _ = run("pose", "--case", f"{TINY}/case", "--pose", pose, "--skinning", method,
                       "--out", f"{TINY}/posed_{method}")
    print(out)
for name in ("case/mesh.vtu", "case/surfaces.vtp", "case/manifest.json", "case/skeleton.json",
             "posed_dqs/posed_labels.nii.gz", "posed_dqs/posed_mesh.vtu", "posed_dqs/posed_surfaces.vtp"):
    assert os.path.isfile(os.path.join(TINY, name)), name
print("1 passed, 0 failed")
