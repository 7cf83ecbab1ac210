"""Real whole bodies from surface meshes, end to end: the Visible Human female and male (skin, pelvis
and leg bones as an atlas ships them: femurs with holes, hip bones in overlapping parts) are voxelized
at 4 mm, prepared with the automatic skeleton under a tet budget, and posed with the left hip abducted
30 deg and flexed 90 deg (the female's thighs touch at rest). On both bodies:
- the automatic skeleton has the pelvis, both hips and both knees; the mesh keeps to its budget;
- the body keeps its volume (within 3 %), every bone matches its rigidly moved rest bone
  (Dice >= 0.95) and the posed body encloses no background the rest body did not;
- no tissue web between the thighs: the tets between them (within a quarter of the hips' distance
  of the midline, from 4 cm below the hips to the knees) stretched past three times their rest
  length hold less than 10 ml (a web is made of tets stretched tens of times); the tissue the hip's
  own 90 degree flexion stretches past 3x (the buttock and groin) stays under 100 ml.
On the female, `pose --relax` (the corotational FEM) too: its tets hold the body's volume within 1 %,
no tet is inverted that skinning left positive, the bone nodes stay where skinning put them, and the
quality line's inverted count is the mesh's."""
import json
import os
import re
import sys

import numpy as np
from scipy.spatial.transform import Rotation

from repose_testing import (SHARED, TEMP, Image, Mesh, bone_transforms, check, enclosed_background, load_json,
                            rigid_bone_dice, run, stretched_volume)

BONES = ["sacrum", "coccyx", "hip_left", "hip_right", "femur_left", "femur_right", "patella_left",
         "patella_right", "tibia_left", "tibia_right", "fibula_left", "fibula_right"]
MAX_TETS = 400000
failures = []

# Abduction first, then flexion, both about the body's axes (LPS: flexion about -x brings the leg forward,
# abduction of the left leg about -y takes it to the patient's left).
hip = Rotation.from_rotvec([-np.pi / 2, 0, 0]) * Rotation.from_rotvec([0, -np.pi / 6, 0])
axis = hip.as_rotvec()
pose = {"rotations": {"left_hip": {"axis": list(axis / np.linalg.norm(axis)),
                                   "degrees": float(np.degrees(np.linalg.norm(axis)))}}}

def signed_volumes(points, tets):
    q = points[tets]
    return np.einsum("ij,ij->i", q[:, 1] - q[:, 0], np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 0])) / 6


def check_relaxed(work):
    _, text, _ = run("pose", "--case", f"{work}/case", "--pose", f"{work}/pose.json", "--relax",
                     "--out", f"{work}/relaxed")
    print(text)
    rest = Mesh(f"{work}/case/mesh.vtu")
    skinned = Mesh(f"{work}/posed/posed_mesh.vtu").points.astype(float)
    relaxed = Mesh(f"{work}/relaxed/posed_mesh.vtu").points.astype(float)
    v0 = signed_volumes(rest.points.astype(float), rest.tets)
    vs, vr = signed_volumes(skinned, rest.tets), signed_volumes(relaxed, rest.tets)
    ratio = vr.sum() / v0.sum()
    check(abs(ratio - 1) <= 0.01, f"female relaxed: tet volume {ratio:.4f} of rest, within 1 %", failures)
    turned = int(((vr <= 0) & (vs > 0)).sum())
    check(turned == 0, f"female relaxed: {turned} tets inverted that skinning left positive "
          f"({int((vs <= 0).sum())} inverted skinned, {int((vr <= 0).sum())} relaxed)", failures)
    m = re.search(r"quality: body volume \S+ of rest, (\d+) inverted tets", text)
    check(m is not None and int(m.group(1)) == int((vr <= 0).sum()),
          f"female relaxed: the quality line's inverted count {m.group(1) if m else None} is the mesh's", failures)
    fixed = rest.point_array("FixedBone") >= 0
    shift = np.abs(relaxed[fixed] - skinned[fixed]).max()
    check(shift < 1e-3, f"female relaxed: bone nodes stay where skinning put them (max shift {shift:.1e} mm)",
          failures)


for subject in ("female", "male"):
    src = os.path.join(SHARED, "visible_human", subject)
    work = os.path.join(TEMP, "visible_human_pose", subject)
    bones = [a for b in BONES for a in ("--bone", f"{b}={src}/{b}.ply")]
    run("voxelize", "--skin", f"{src}/skin.ply", *bones, "--voxel", 4, "--out", f"{work}/labels.nii.gz")
    _, text, _ = run("prepare", "--labels", f"{work}/labels.nii.gz", "--skeleton", "auto", "--max-tets", MAX_TETS,
                     "--out", f"{work}/case")
    print(text)
    skeleton = load_json(f"{work}/case/skeleton.json")
    names = {j["name"] for j in skeleton["joints"]}
    check({"pelvis", "left_hip", "right_hip", "left_knee", "right_knee"} <= names,
          f"{subject}: the automatic skeleton has the pelvis, hips and knees: {sorted(names)}", failures)
    tets = int(re.search(r"tet mesh: \d+ nodes, (\d+) tets", text).group(1))
    check(tets <= 1.2 * MAX_TETS, f"{subject}: {tets} tets for a budget of {MAX_TETS}", failures)
    with open(f"{work}/pose.json", "w") as f:
        json.dump(pose, f)
    run("pose", "--case", f"{work}/case", "--pose", f"{work}/pose.json", "--out", f"{work}/posed")

    rest, posed = Image(f"{work}/case/labels.nii.gz"), Image(f"{work}/posed/posed_labels.nii.gz")
    ratio = (posed.a != 0).sum() / (rest.a != 0).sum()
    check(abs(ratio - 1) <= 0.03, f"{subject}: body volume ratio {ratio:.4f} within 3 %", failures)
    G = bone_transforms(skeleton, pose)
    worst = min((rigid_bone_dice(rest, posed, j["labels"], G[j["name"]]), j["name"]) for j in skeleton["joints"])
    check(worst[0] >= 0.95, f"{subject}: worst bone Dice {worst[0]:.3f} ({worst[1]}) >= 0.95", failures)
    er, ep = enclosed_background(rest.a), enclosed_background(posed.a)
    check(ep <= er, f"{subject}: enclosed background voxels posed {ep} <= rest {er} (no holes)", failures)
    J = {j["name"]: np.array(j["center"]) for j in skeleton["joints"]}
    mid, half = (J["left_hip"][0] + J["right_hip"][0]) / 2, abs(J["left_hip"][0] - J["right_hip"][0]) / 2

    def between_thighs(c):
        return (np.abs(c[:, 0] - mid) < 0.5 * half) & (c[:, 2] < J["left_hip"][2] - 40) & (c[:, 2] > J["left_knee"][2])

    web, smax = stretched_volume(f"{work}/case", f"{work}/posed", region=between_thighs)
    check(web < 10.0, f"{subject}: between the thighs {web:.2f} ml stretched past 3x (< 10 ml), largest {smax:.2f}",
          failures)
    hip, hmax = stretched_volume(f"{work}/case", f"{work}/posed")
    check(hip < 100.0, f"{subject}: the whole body {hip:.1f} ml stretched past 3x (< 100 ml), largest {hmax:.1f}",
          failures)

    if subject == "female":
        check_relaxed(work)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
