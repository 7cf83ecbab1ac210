"""Real data: the automatic skeleton of the TotalSegmentator scan.
1. The filter with the built-in class names: hips (femoral head centres) and the lumbosacral joint,
   rooted at the pelvis (hip bones + sacrum + S1); ribs ride with the thoracic vertebrae (never
   joints); the femurs are reported as cut by the field of view; the scan's 11 loose crumbs of bone
   label (17 voxels) each stay with their own bone, which lies within reach.
2. The same scan with both femurs under one label and both hip bones under another, and a slice of
   the right femur cut out: the femur label splits by side, the cut-off piece goes to the right femur,
   not to the label's first value (the left femur) nor to a joint of its own, and the hip label (one
   piece: the hip bones meet at the symphysis) stays whole in the pelvis.
3. `repose rig` on the labels alone, and `repose prepare --skeleton auto` with the CT: the case keeps
   the label table (labels.tsv, listed in manifest.json) and poses the left hip by its standard name."""
import json
import os
import shutil
import sys
import time

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData

from repose import vtkReposeAutoRig, vtkReposeImageReader
from repose_testing import SHARED, TEMP, Image, bone_transforms, check, load_json, rigid_bone_dice, run

failures = []
ts = os.path.join(SHARED, "totalsegmentator")
path = os.path.join(ts, "example_seg_fast_force_split.nii.gz")
ct_path = os.path.join(ts, "example_ct.nii.gz")
reader = vtkReposeImageReader()
reader.SetFileName(path)
reader.Update()
if reader.GetLastError():
    sys.exit(reader.GetLastError())
source = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars()).copy()


def rig_of(image, table=""):
    rig = vtkReposeAutoRig()
    rig.SetInputData(image)
    rig.SetLabelTableTSV(table)
    t = time.perf_counter()
    rig.Update()
    print(f"autoRig {rig.GetSeconds():.3f} s (filter {time.perf_counter() - t:.3f} s)")
    print(rig.GetReport())
    joints = {j["name"]: j for j in json.loads(rig.GetSkeletonJSON())["joints"]}
    out = vtk_to_numpy(rig.GetOutput().GetPointData().GetScalars())
    return rig, joints, out


# ---- 1. the scan as TotalSegmentator wrote it
rig, joints, out = rig_of(reader.GetOutput())
roots = [n for n, j in joints.items() if j["parent"] is None]
check(roots == ["pelvis"], f"the root is the pelvis (roots: {roots})", failures)
check(set(joints.get("pelvis", {}).get("labels", [])) >= {25, 26, 77, 78},
      "the pelvis joins sacrum, S1 and both hip bones", failures)
for name, expected in (("left_hip", (77, -141, 133.5)), ("right_hip", (-75, -142, 131.5))):
    j = joints.get(name)
    check(j is not None and j["parent"] == "pelvis", f"{name} found, child of the pelvis", failures)
    if j:
        err = np.linalg.norm(np.array(j["center"]) - expected)
        check(err <= 15, f"{name} centre {np.round(j['center'], 1)} is {err:.1f} mm from {expected}", failures)
spine = joints.get("spine")
check(spine is not None and spine["parent"] == "pelvis" and spine["labels"] == [27],
      "the lumbosacral joint: 'spine' rotates L5 (label 27) on the pelvis", failures)
if spine:
    c = np.array(spine["center"])
    check(abs(c[0]) < 20 and c[2] > 150, f"lumbosacral centre {np.round(c, 1)} near the midline, above the hips",
          failures)
chain = ["pelvis", "spine", "vertebra_L4", "vertebra_L3", "vertebra_L2", "vertebra_L1", "vertebra_T12", "vertebra_T11"]
check(all(joints.get(b, {}).get("parent") == a for a, b in zip(chain, chain[1:])),
      "the spine chains L5 -> T11 upward, each vertebra on the one below", failures)
check(sorted(joints) == sorted(chain + ["left_hip", "right_hip"]), f"10 joints, standard names: {sorted(joints)}",
      failures)
ribs = list(range(98, 104)) + list(range(110, 116))
riding = {r: n for n, j in joints.items() for r in j["labels"] if r in ribs}
check(sorted(riding) == ribs and set(riding.values()) <= {"vertebra_T11", "vertebra_T12"},
      f"all 12 ribs ride with T11/T12 (rib 12 with T12), none is a joint: {sorted(set(riding.values()))}", failures)
check(riding.get(103) == "vertebra_T12" and riding.get(115) == "vertebra_T12", "ribs 12 ride with T12", failures)

report = rig.GetReport()
for femur in ("femur_left", "femur_right"):
    line = next((l for l in report.splitlines() if l.strip().startswith(femur + " ")), "")
    check("cut by the field of view" in line, f"{femur} reported as cut by the field of view: '{line.strip()}'", failures)
check("missing bones" in report and "skull" in report, "missing bones (skull, ...) are reported", failures)
# The scan's crumbs: 11 pieces (17 voxels) of bone labels apart from their bone; each lies within
# reach of its own bone (a sacrum crumb touching S1 stays sacrum), so no voxel changes label.
check(rig.GetNumberOfReassignedFragments() == 11 and rig.GetReassignedFragmentVoxels() == 17
      and rig.GetUnassignedFragmentVoxels() == 0,
      f"11 fragments (17 voxels) given to bones, none left over ({rig.GetNumberOfReassignedFragments()}, "
      f"{rig.GetReassignedFragmentVoxels()}, {rig.GetUnassignedFragmentVoxels()})", failures)
check(np.array_equal(out, source), "each crumb stays with its own bone: the output labels equal the input", failures)

# ---- 2. both femurs in one label, both hip bones in another, a slice cut out of the right femur
img = Image(path)
right_femur = img.a == 76
ks = np.flatnonzero(right_femur.any(axis=(1, 2)))
counts = np.array([right_femur[k].sum() for k in ks])
cut = ks[np.searchsorted(np.cumsum(counts), 0.1 * counts.sum())]  # the slice below which 10 % lies
piece = right_femur.copy()
piece[cut:] = False
a = img.a.copy()
a[cut][right_femur[cut]] = 81  # gluteus_maximus_right: soft tissue
a[a == 76] = 75
a[a == 78] = 77
merged_img = vtkImageData()
merged_img.DeepCopy(reader.GetOutput())
merged_img.GetPointData().SetScalars(numpy_to_vtk(a.ravel().astype(np.int32), deep=True))
lines = open(os.path.join(ts, "labels_total_v2.tsv")).read().splitlines()
table = []
for line in lines:
    f = line.split("\t")
    if f[0] in ("76", "78"):
        continue
    table.append({"75": "75\tfemur", "77": "77\thip"}.get(f[0], line))
rig2, joints2, out2 = rig_of(merged_img, "\n".join(table) + "\n")
out2 = out2.reshape(img.a.shape)
names = {int(f[0]): f[1] for f in (l.split("\t") for l in rig2.GetOutputLabelTableTSV().splitlines()[1:])}
value = {n: v for v, n in names.items()}
check("femur_left" in value and "femur_right" in value,
      "the femur label splits by side into femur_left and femur_right", failures)
# The hip bones meet at the pubic symphysis: one piece across the midline, kept whole in the pelvis.
check(77 in joints2.get("pelvis", {}).get("labels", []) and "hip_left" not in value,
      "the hip label (one piece across the midline) stays whole, in the pelvis", failures)
check(sorted(joints2) == sorted(joints), f"the same 10 joints ({sorted(joints2)})", failures)
fr = value.get("femur_right")
check(piece.sum() > 20 and np.all(out2[piece] == fr),
      f"the {piece.sum()} voxels below the cut go to femur_right (label {fr}), not to a joint of their own", failures)
check(not np.any(out2[img.a == 76] == 75), "no voxel of the right femur keeps the left femur's value", failures)
check(joints2.get("right_hip", {}).get("labels") == [fr] and joints2.get("left_hip", {}).get("labels") == [75],
      "left_hip rotates femur_left (75), right_hip femur_right", failures)
for name in ("left_hip", "right_hip"):
    if name in joints and name in joints2:
        d = np.linalg.norm(np.array(joints[name]["center"]) - joints2[name]["center"])
        check(d < 1.0, f"{name} centre moves {d:.2f} mm with the merged labels", failures)
frag = next((l for l in rig2.GetReport().splitlines() if "-> femur_right" in l), "")
check("nearest femur on its side" in frag, f"the report says where the piece went: '{frag.strip()}'", failures)

# ---- 3. the CLI: rig (labels only) and prepare --skeleton auto with the CT
work = os.path.join(TEMP, "auto_rig_totalsegmentator")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
t = time.perf_counter()
code, stdout, _ = run("rig", "--labels", path, "--out", f"{work}/rig/skeleton.json")
print(stdout)
print(f"repose rig: {time.perf_counter() - t:.2f} s")
check(stdout.startswith("label table: built-in TotalSegmentator names"), "rig says which table it used", failures)
check(not os.path.exists(f"{work}/rig/labels_rigged.nii.gz"),
      "nothing relabelled: the skeleton refers to the scan's own labels", failures)
check(sorted(j["name"] for j in load_json(f"{work}/rig/skeleton.json")["joints"]) == sorted(joints),
      "the CLI finds the filter's joints", failures)
t = time.perf_counter()
run("prepare", "--labels", path, "--skeleton", "auto", "--image", ct_path, "--mesh-spacing", "6",
    "--out", f"{work}/case")
print(f"repose prepare --skeleton auto (6 mm mesh): {time.perf_counter() - t:.1f} s")
manifest = load_json(f"{work}/case/manifest.json")
check(manifest.get("labelTable") == "labels.tsv", "manifest.json lists labelTable: labels.tsv", failures)
case_table = open(f"{work}/case/labels.tsv").read().splitlines()
check(case_table[0] == "value\tname\tkind" and "75\tfemur_left\tbone" in case_table
      and "117\tcostal_cartilages\tsoft" in case_table, "the case keeps the TotalSegmentator names and kinds", failures)
case_labels = Image(f"{work}/case/labels.nii.gz")
check(np.array_equal(case_labels.a.ravel(), out), "the case's labels are the rig's relabelled labels", failures)
skeleton = load_json(f"{work}/case/skeleton.json")
pose = {"rotations": {"left_hip": {"axis": [1, 0, 0], "degrees": -45}}}
with open(f"{work}/pose.json", "w") as f:
    json.dump(pose, f)
run("pose", "--case", f"{work}/case", "--pose", f"{work}/pose.json", "--out", f"{work}/posed")
G = bone_transforms(skeleton, pose)
d = rigid_bone_dice(case_labels, Image(f"{work}/posed/posed_labels.nii.gz"), [75], G["left_hip"])
check(d >= 0.9, f"the auto-rigged case flexes the left hip: femur Dice {d:.3f} against its rigid motion", failures)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
