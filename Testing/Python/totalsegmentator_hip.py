"""Real data: the TotalSegmentator CT (no skin label: the body comes from CT > -500 HU) with a
hand-written skeleton, prepared and posed with a 45 deg left hip flexion. The femur moves rigidly,
the thigh's soft tissue follows it, the pelvis and the other femur stay. The displacement field written
beside the posed CT is the map it was pulled through: the rest CT warped by it here (trilinear, scipy)
and by ITK's own WarpImageFilter (Testing/Cxx/itk_warp_compare.cxx) gives the posed CT."""
import os
import subprocess
import shutil
import sys

import numpy as np
from scipy import ndimage

from repose_testing import (SHARED, TEMP, TESTING, Image, bone_transforms, check, load_json, read_mha,
                            rigid_bone_dice, run)

failures = []
work = os.path.join(TEMP, "totalseg")
shutil.rmtree(work, ignore_errors=True)
ts = os.path.join(SHARED, "totalsegmentator")
labels_path = os.path.join(ts, "example_seg_fast_force_split.nii.gz")
ct_path = os.path.join(ts, "example_ct.nii.gz")
skel_path = os.path.join(TESTING, "Data", "totalsegmentator_skeleton.json")
pose_path = os.path.join(TESTING, "Data", "totalsegmentator_hip_flexion.json")
code, out, _ = run("prepare", "--labels", labels_path, "--skeleton", skel_path, "--image", ct_path,
                   "--out", f"{work}/case")
print(out)
code, out, _ = run("pose", "--case", f"{work}/case", "--pose", pose_path, "--image", ct_path,
                   "--displacement-field", ".mha", "--out", f"{work}/posed")
print(out)

skeleton, pose = load_json(skel_path), load_json(pose_path)
G = bone_transforms(skeleton, pose)
rest, posed = Image(labels_path), Image(f"{work}/posed/posed_labels.nii.gz")
rest_ct, posed_ct = Image(ct_path), Image(f"{work}/posed/posed_image.nii.gz")
check(np.allclose(posed.direction, rest.direction) and np.allclose(posed.spacing, rest.spacing),
      "posed grid keeps the scan's spacing and direction", failures)

d = rigid_bone_dice(rest, posed, [75], G["left_hip"])
check(d >= 0.95, f"left femur moves rigidly: Dice {d:.3f}", failures)
for name, labels in (("pelvis", [25, 26, 77, 78]), ("right femur", [76])):
    d = rigid_bone_dice(rest, posed, labels, np.eye(4))
    check(d >= 0.95, f"{name} stays: Dice {d:.3f}", failures)

# The thigh follows: soft tissue (CT > -500 HU) surrounds the moved femur shaft in the posed CT, as
# it does at rest (99 % of the shell), where the shell's rest point lies inside the scan: the scan
# cuts the thigh off below, and the femur's cut end carries no tissue with it.
femur = posed.a == 75
shell = ndimage.binary_dilation(femur, iterations=3) & ~femur
g = G["left_hip"]
back = (posed.centres()[shell] - g[:3, 3]) @ g[:3, :3]
ijk = np.rint(((back - rest.origin) @ rest.direction) / rest.spacing)
in_scan = np.all((ijk >= 3) & (ijk < np.array(rest.dims) - 3), axis=1)
soft = posed_ct.a[shell][in_scan] > -500
frac = soft.mean()
check(frac >= 0.95, f"tissue around the posed femur: {100 * frac:.1f} % of a 9 mm shell is body (> -500 HU), "
      f"where it comes from inside the scan ({in_scan.sum()} of {shell.sum()} voxels)", failures)
# ...and the posed femur's CT values are bone (it was carried, not left behind).
bone_hu = np.median(posed_ct.a[femur])
check(bone_hu > 150, f"posed femur keeps bone intensities (median {bone_hu:.0f} HU)", failures)
# The femur really moved, to where the rigid motion takes it (anteriorly: LPS -y).
def centroid(img, mask):
    return img.centres()[mask].mean(0)
c_rest = centroid(rest, rest.a == 75)
expected = G["left_hip"][:3, :3] @ c_rest + G["left_hip"][:3, 3]
got = centroid(posed, femur)
check(np.linalg.norm(got - expected) < 3 and got[1] - c_rest[1] < -5,
      f"femur centroid moved {np.linalg.norm(got - c_rest):.1f} mm anteriorly, {np.linalg.norm(got - expected):.1f} mm "
      f"from the rigid expectation", failures)

# The displacement field: on the posed CT's grid; rest CT warped through it = posed CT.
field, header = read_mha(f"{work}/posed/posed_displacement.mha")
u = field.astype(float)
check(u.shape[:3] == posed_ct.a.shape and header["ElementSpacing"] == " ".join(f"{x:g}" for x in posed_ct.spacing),
      f"displacement field {header['DimSize']} x 3 floats on the posed CT's grid", failures)
mapped = np.any(u != 0, axis=-1)
rest_points = posed_ct.centres()[mapped] + u[mapped]
ijk = ((rest_points - rest_ct.origin) @ rest_ct.direction) / rest_ct.spacing
# Edge voxels replicated within half a voxel, as the posed CT was sampled; beyond it, the background.
inside = np.all((ijk > -0.5) & (ijk < np.array(rest_ct.dims) - 0.5), axis=1)
clamped = np.clip(ijk, 0, np.array(rest_ct.dims) - 1)
warped = ndimage.map_coordinates(rest_ct.a.astype(float), clamped[:, ::-1].T, order=1, mode="nearest")
diff = np.abs(warped - posed_ct.a[mapped])[inside]
body = posed_ct.a[mapped][inside] > -500
# A few voxels filled from their neighbours (pinholes between tets) take the mean of their rest points
# in the field and of their samples in the CT: they differ by the CT's curvature there.
check(mapped.sum() > 0.3 * (posed_ct.a > -500).sum() and np.percentile(diff, 99.9) < 0.1 and np.median(diff) < 0.01,
      f"rest CT warped by the field = posed CT over {inside.sum()} voxels: median {np.median(diff):.2g} HU, "
      f"99.9th percentile {np.percentile(diff, 99.9):.2g} HU, largest {diff.max():.0f} HU "
      f"({(diff > 1).sum()} voxels off by more than 1 HU)", failures)
# The same through ITK's WarpImageFilter (linear interpolation), ITK reading the field as written.
itk = subprocess.run([os.environ["REPOSE_ITK_WARP"], ct_path, f"{work}/posed/posed_displacement.mha",
                      f"{work}/posed/posed_image.nii.gz"], capture_output=True, text=True)
figures = dict(zip(*[iter(itk.stdout.split())] * 2)) if itk.returncode == 0 else {}
check(itk.returncode == 0 and int(figures["voxels"]) == int(mapped.sum()) and float(figures["median"]) < 0.01
      and float(figures["p999"]) < 0.1,
      f"rest CT warped by ITK's WarpImageFilter through the field = posed CT: {itk.stdout.strip()}{itk.stderr.strip()}",
      failures)
g = G["left_hip"]
in_femur = (posed.a[mapped] == 75)
expected_u = (posed_ct.centres()[mapped][in_femur] - g[:3, 3]) @ g[:3, :3] - posed_ct.centres()[mapped][in_femur]
err = np.linalg.norm(u[mapped][in_femur] - expected_u, axis=1)
check(np.median(err) < 1.0,
      f"inside the posed femur the field is the femur's rigid motion back: median {np.median(err):.2f} mm, "
      f"90th percentile {np.percentile(err, 90):.2f} mm", failures)
print(f"{9 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
