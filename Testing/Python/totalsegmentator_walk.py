"""Real data and real motion: the TotalSegmentator scan prepared with the automatic skeleton and the
CT body, driven by the CMU walk. The clip drives every joint of the rig (the vertebrae share the
clip's lower and upper back), both femurs swing forward and back, the pelvis and spine follow, the
body stays one piece, and every bone stays rigid in every frame written (Dice >= 0.95 with its
rigidly moved rest bone). The same walk rescaled to centimetres in this test, with root motion, gives
the same poses moved by the clip's root displacement in millimetres, on grids bounded to the body;
the MotionBuilder-named clip drives the same joints."""
import os
import re
import shutil
import sys

import numpy as np
from scipy import ndimage

from bvh_oracle import Clip, write_scaled
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


def drives_every_joint(stdout, what):
    m = re.search(r"the clip drives (\d+) of (\d+) joints", stdout)
    check(m is not None and m.group(1) == m.group(2) and "warning" not in stdout,
          f"{what} drives every joint of the rig ({m.group(0) if m else 'no report'}), no warning", failures)


drives_every_joint(out, "the CMU walk (3dsMax names)")


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
    # The body (posed CT above -500 HU) stays one piece: no part thicker than a voxel breaks off. The
    # scan has a one-voxel layer over the back (a sheet or clothing), apart from the skin by an air gap; a sheet
    # that thin cannot keep its connectivity through resampling, so one voxel of opening removes it.
    ct = Image(f"{work}/walk/frames/image_{f:05d}.nii.gz")
    comp, n = ndimage.label(ndimage.binary_opening(ct.a > -500))
    sizes = np.bincount(comp.ravel())[1:]
    pieces.append(int((sizes >= 27).sum()))
print("worst Dice per bone:", {k: round(v, 3) for k, v in per_bone.items()})
check(max(pieces) == 1, f"the body stays one piece in every frame (pieces of 27+ voxels: {pieces})", failures)
check(worst[0] >= 0.95, f"every bone rigid in every frame: worst Dice {worst[0]:.3f} ({worst[1]})", failures)
for name, a in femur_ant.items():
    swing = np.degrees(np.arcsin(np.clip(max(a), -1, 1))) - np.degrees(np.arcsin(np.clip(min(a), -1, 1)))
    check(swing > 20, f"{name}: the femur swings forward and back through {swing:.0f} deg", failures)

# The walk in centimetres, with root motion: units inferred; every node moved by one translation, the
# clip's root displacement in mm, from the pose without root motion; each grid bounded to the body.
walk = os.path.join(SHARED, "mocap", "cmu_131_01_walk.bvh")
cm_walk = os.path.join(work, "walk_cm.bvh")
write_scaled(walk, cm_walk, 25.4 / 0.45 / 10)
_, cm_out, _ = run("animate", "--case", f"{work}/case", "--bvh", cm_walk, "--frames", "500:600:80", "--volumes",
                   "--out", f"{work}/walk_cm")
print(cm_out)
check("BVH units: centimetres (leg length 80.1 units), 10.00 mm per unit" in cm_out, "clip in centimetres: units said",
      failures)
clip = Clip(cm_walk)
root0 = clip.pose(0)[0][1]
shift_error, worst_ratio, old_rule, body_kept = 0.0, 0.0, 0.0, 1.0
for f in (500, 580):
    a = Mesh(f"{work}/walk/frames/mesh_{f:05d}.vtu").points
    b = Mesh(f"{work}/walk_cm/frames/mesh_{f:05d}.vtu").points
    expected = 10.0 * (clip.pose(f)[0][1] - root0)
    shift_error = max(shift_error, np.abs(b - a - expected).max())
    labels = Image(f"{work}/walk_cm/frames/labels_{f:05d}.nii.gz")
    ijk = ((b - rest.origin) @ rest.direction) / rest.spacing
    box = np.prod(np.ceil(ijk.max(0)) - np.floor(ijk.min(0)) + 9)
    worst_ratio = max(worst_ratio, np.prod(labels.dims) / box)
    lo, hi = np.minimum(np.floor(ijk.min(0)), 0) - 2, np.maximum(np.ceil(ijk.max(0)), np.array(rest.dims) - 1) + 2
    old_rule = max(old_rule, np.prod(hi - lo + 1))
    body_kept = min(body_kept, np.count_nonzero(labels.a) / np.count_nonzero(rest.a))
check(shift_error < 0.01, f"centimetres with root motion = the same poses moved by the root's displacement "
      f"(worst {shift_error:.2g} mm)", failures)
check(worst_ratio <= 2.0 and body_kept > 0.9, f"posed grids bounded to the body ({worst_ratio:.2f}x its box; the rest "
      f"extent and the body, the old rule: {old_rule / 1e6:.1f} M voxels), holding it ({body_kept:.3f} of the rest "
      f"labels)", failures)

# The MotionBuilder conversion (LeftUpLeg, LowerBack, ...) drives the same joints.
_, mb_out, _ = run("animate", "--case", f"{work}/case", "--bvh", os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh"),
                   "--frames", "0:75:15", "--no-root-motion", "--out", f"{work}/short")
print(mb_out)
drives_every_joint(mb_out, "the CMU clip in MotionBuilder names")
ant = []
for f in range(0, 75, 15):
    posed_pts = Mesh(f"{work}/short/frames/mesh_{f:05d}.vtu").points
    j = names.index("left_hip")
    G, _ = kabsch(rest_pts[fixed == j], posed_pts[fixed == j])
    ant.append(-(G[:3, :3] @ np.array([0, 0, -1.0]))[1])
swing = np.degrees(np.arcsin(np.clip(max(ant), -1, 1))) - np.degrees(np.arcsin(np.clip(min(ant), -1, 1)))
check(swing > 20, f"MotionBuilder clip: the left femur swings through {swing:.0f} deg", failures)
print(f"{11 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
