"""Real data: the automatic skeleton of the TotalSegmentator scan (built-in class names, no label
table). The hips (femoral head centres) and the lumbosacral joint are found, rooted at the pelvis
(hip bones + sacrum + S1), and the femurs are reported as cut by the field of view."""
import json
import os
import sys
import time

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

from repose import vtkReposeAutoRig, vtkReposeImageReader

failures = []


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


path = os.path.join(os.environ["REPOSE_SHARED_DATA"], "totalsegmentator", "example_seg_fast_force_split.nii.gz")
reader = vtkReposeImageReader()
reader.SetFileName(path)
reader.Update()
if reader.GetLastError():
    sys.exit(reader.GetLastError())

rig = vtkReposeAutoRig()
rig.SetInputConnection(reader.GetOutputPort())
t = time.perf_counter()
rig.Update()
print(f"autoRig {rig.GetSeconds():.3f} s (filter {time.perf_counter() - t:.3f} s)")
print(rig.GetReport())
print(rig.GetSkeletonJSON())

joints = {j["name"]: j for j in json.loads(rig.GetSkeletonJSON())["joints"]}
roots = [n for n, j in joints.items() if j["parent"] is None]
check(roots == ["pelvis"], f"the root is the pelvis (roots: {roots})")
check(set(joints.get("pelvis", {}).get("labels", [])) >= {25, 26, 77, 78},
      "the pelvis joins sacrum, S1 and both hip bones")
for name, expected in (("left_hip", (77, -141, 133.5)), ("right_hip", (-75, -142, 131.5))):
    j = joints.get(name)
    check(j is not None and j["parent"] == "pelvis", f"{name} found, child of the pelvis")
    if j:
        err = np.linalg.norm(np.array(j["center"]) - expected)
        check(err <= 15, f"{name} centre {np.round(j['center'], 1)} is {err:.1f} mm from {expected}")
spine = joints.get("spine")
check(spine is not None and spine["parent"] == "pelvis" and spine["labels"] == [27],
      "the lumbosacral joint: 'spine' rotates L5 (label 27) on the pelvis")
if spine:
    # Between the L5 and S1 bodies: well above the hips, near the midline.
    c = np.array(spine["center"])
    check(abs(c[0]) < 20 and c[2] > 150, f"lumbosacral centre {np.round(c, 1)} near the midline, above the hips")
check(joints.get("vertebra_L4", {}).get("parent") == "spine", "L4 hangs on L5")

report = rig.GetReport()
for femur in ("femur_left", "femur_right"):
    line = next((l for l in report.splitlines() if l.strip().startswith(femur + " ")), "")
    check("cut by the field of view" in line, f"{femur} reported as cut by the field of view: '{line.strip()}'")
check("missing bones" in report and "skull" in report, "missing bones (skull, ...) are reported")

# Nothing to split here (one component per bone): the output labels equal the input.
a = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars())
b = vtk_to_numpy(rig.GetOutput().GetPointData().GetScalars())
check(a.shape == b.shape and np.array_equal(a, b), "output labels equal the input")

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
