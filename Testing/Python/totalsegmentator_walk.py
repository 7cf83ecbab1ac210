"""Real data and real motion: the TotalSegmentator scan prepared with the automatic skeleton and the
CT body, driven by the CMU walk. Both femurs swing forward and back, the pelvis and spine follow,
the body stays one piece, and every bone stays rigid in every frame written (Dice >= 0.95 with its
rigidly moved rest bone)."""
import os
import shutil
import sys

import numpy as np
from scipy import ndimage

from repose_testing import SHARED, TEMP, Image, Mesh, check, kabsch, load_json, rigid_bone_dice, run

failures = []
work = os.path.join(TEMP, "totalseg_walk")
shutil.rmtree(work, ignore_errors=True)
ts = os.path.join(SHARED, "totalsegmentator")
labels_path = os.path.join(ts, "example_seg_fast_force_split.nii.gz")
run("prepare", "--labels", labels_path, "--skeleton", "auto", "--image", os.path.join(ts, "example_ct.nii.gz"),
    "--mesh-spacing", "4", "--out", f"{work}/case")
skeleton = load_json(f"{work}/case/skeleton.json")
names = [j["name"] for j in skeleton["joints"]]
check({"pelvis", "left_hip", "right_hip", "spine"} <= set(names), f"automatic skeleton has hips and the lumbosacral joint: {names}", failures)
frames = "500:700:40"
code, out, _ = run("animate", "--case", f"{work}/case", "--bvh", os.path.join(SHARED, "mocap", "cmu_131_01_walk.bvh"),
                   "--frames", frames, "--volumes", "--image", os.path.join(ts, "example_ct.nii.gz"), "--no-root-motion",
                   "--out", f"{work}/walk")
print(out)


rest_mesh = Mesh(f"{work}/case/mesh.vtu")
rest_pts = rest_mesh.points
fixed = rest_mesh.point_array("FixedBone")
rest = Image(f"{work}/case/labels.nii.gz")

femur_ant = {"left_hip": [], "right_hip": []}
worst = (1.0, "")
per_bone = {}
pieces = []
start, stop, step = map(int, frames.split(":"))
for f in range(start, stop, step):
    posed_pts = Mesh(f"{work}/walk/frames/mesh_{f:05d}.vtu").points
    posed = Image(f"{work}/walk/frames/labels_{f:05d}.nii.gz")
    for j, joint in enumerate(skeleton["joints"]):
        G, _ = kabsch(rest_pts[fixed == j], posed_pts[fixed == j])
        d = rigid_bone_dice(rest, posed, joint["labels"], G)
        per_bone[joint["name"]] = min(per_bone.get(joint["name"], 1.0), d)
        if d < worst[0]:
            worst = (d, f"{joint['name']} in frame {f}")
        if joint["name"] in femur_ant:
            axis = G[:3, :3] @ np.array([0, 0, -1.0])  # the femur's rest direction is about inferior
            femur_ant[joint["name"]].append(-axis[1])
    # The body (posed CT above -500 HU) stays one piece: no part larger than a few voxels breaks off.
    ct = Image(f"{work}/walk/frames/image_{f:05d}.nii.gz")
    comp, n = ndimage.label(ct.a > -500)
    sizes = np.bincount(comp.ravel())[1:]
    pieces.append(int((sizes >= 27).sum()))
print("worst Dice per bone:", {k: round(v, 3) for k, v in per_bone.items()})
check(max(pieces) == 1, f"the body stays one piece in every frame (pieces of 27+ voxels: {pieces})", failures)
check(worst[0] >= 0.95, f"every bone rigid in every frame: worst Dice {worst[0]:.3f} ({worst[1]})", failures)
for name, a in femur_ant.items():
    swing = np.degrees(np.arcsin(np.clip(max(a), -1, 1))) - np.degrees(np.arcsin(np.clip(min(a), -1, 1)))
    check(swing > 20, f"{name}: the femur swings forward and back through {swing:.0f} deg", failures)
print(f"{5 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
