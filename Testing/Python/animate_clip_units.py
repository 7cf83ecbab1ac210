"""The MotionBuilder-named CMU clip (LeftUpLeg, LeftArm, ...) on the tiny phantom, as it is and rescaled
to centimetres in this test: the units are inferred and said, both give the same poses and the same
posed volumes, and every volume stays bounded to the body even when the clip is read at the wrong
scale (the body then travels 5.6 times too far: the old default). A grid over --max-voxels, a limb
joint left undriven under --strict, and a map that drives only the root are one-line errors with no
output."""
import os
import shutil
import sys

import numpy as np

from bvh_oracle import Clip, write_scaled
from repose_testing import SHARED, TEMP, TINY, Image, Mesh, check, run

failures = []
work = os.path.join(TEMP, "animate_clip_units")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
clip = os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh")
cm_clip = os.path.join(work, "cmu_short_75frames_cm.bvh")
CMU_MM = 25.4 / 0.45
write_scaled(clip, cm_clip, CMU_MM / 10)
frames = range(0, 75, 15)
case = f"{TINY}/case"


def no_output(name):
    folder = os.path.join(work, name)
    return not os.path.exists(folder) or not os.listdir(folder)


def animate(bvh, out, *extra, check_exit=True):
    return run("animate", "--case", case, "--bvh", bvh, "--frames", "0:75:15", "--volumes", "--out",
               os.path.join(work, out), *extra, check=check_exit)


_, cmu_out, _ = animate(clip, "cmu")
_, cm_out, _ = animate(cm_clip, "cm")
_, wrong_out, _ = animate(cm_clip, "cm_as_cmu", "--unit-mm", f"{CMU_MM:.4f}")
print(cmu_out, cm_out, wrong_out, sep="\n")
check("BVH units: CMU units of 1/0.45 inch (leg length 13.2 units), 56.44 mm per unit" in cmu_out,
      "CMU clip: units inferred and said", failures)
check("BVH units: centimetres (leg length 74.5 units), 10.00 mm per unit; --unit-mm overrides" in cm_out,
      "clip in centimetres: units inferred and said", failures)
check("the clip drives 15 of 15 joints" in cmu_out and "warning" not in cmu_out,
      "MotionBuilder names drive every joint of the phantom, no warning", failures)

rest = Image(f"{case}/labels.nii.gz")


def body_box_voxels(points, margin):
    """Voxels of the posed nodes' box on the rest lattice, with a margin."""
    ijk = ((points - rest.origin) @ rest.direction) / rest.spacing
    return np.prod(np.ceil(ijk.max(0)) - np.floor(ijk.min(0)) + 1 + 2 * margin)


def old_rule_voxels(points):
    """The grid before: the rest extent and the posed nodes, plus 2 voxels."""
    ijk = ((points - rest.origin) @ rest.direction) / rest.spacing
    lo = np.minimum(np.floor(ijk.min(0)), 0) - 2
    hi = np.maximum(np.ceil(ijk.max(0)), np.array(rest.dims) - 1) + 2
    return np.prod(hi - lo + 1)


worst_mesh, worst_labels, worst_ratio, old_before = 0.0, 0, 0.0, 0.0
clip_oracle = Clip(clip)
for f in frames:
    a = Mesh(os.path.join(work, "cmu", "frames", f"mesh_{f:05d}.vtu")).points
    b = Mesh(os.path.join(work, "cm", "frames", f"mesh_{f:05d}.vtu")).points
    worst_mesh = max(worst_mesh, np.abs(a - b).max())
    la = Image(os.path.join(work, "cmu", "frames", f"labels_{f:05d}.nii.gz"))
    lb = Image(os.path.join(work, "cm", "frames", f"labels_{f:05d}.nii.gz"))
    same_grid = la.dims == lb.dims and np.allclose(la.origin, lb.origin, atol=1e-6)
    worst_labels = max(worst_labels, int((la.a != lb.a).sum()) if same_grid else la.a.size)
    # Read at the CMU scale the clip travels 5.64 times as far; its grid holds the body, not the walk.
    w = Mesh(os.path.join(work, "cm_as_cmu", "frames", f"mesh_{f:05d}.vtu")).points
    lw = Image(os.path.join(work, "cm_as_cmu", "frames", f"labels_{f:05d}.nii.gz"))
    worst_ratio = max(worst_ratio, np.prod(lw.dims) / body_box_voxels(w, 4))
    old_before = max(old_before, old_rule_voxels(w))
    edges = [lw.a[0], lw.a[-1], lw.a[:, 0], lw.a[:, -1], lw.a[:, :, 0], lw.a[:, :, -1]]
    check(all(e.max() == 0 for e in edges), f"frame {f}: the posed body lies inside its grid (no label on the border)",
          failures)
    check(np.count_nonzero(lw.a) > 0.9 * np.count_nonzero(rest.a),
          f"frame {f}: the bounded grid holds the body ({np.count_nonzero(lw.a)} of {np.count_nonzero(rest.a)} "
          f"rest voxels)", failures)
travel = np.linalg.norm(Mesh(os.path.join(work, "cm_as_cmu", "frames", "mesh_00060.vtu")).points.mean(0) -
                        Mesh(os.path.join(work, "cm_as_cmu", "frames", "mesh_00000.vtu")).points.mean(0))
check(worst_mesh < 1e-3, f"the clip in centimetres poses the mesh as the CMU clip does (worst {worst_mesh:.2g} mm)",
      failures)
# The rescaled file holds 6 decimals: a voxel centre on a tet face may fall either side.
check(worst_labels <= 1e-4 * np.count_nonzero(rest.a), f"and the same posed label volumes ({worst_labels} voxels "
      f"differ, of {np.count_nonzero(rest.a)})", failures)
check(worst_ratio <= 2.0, f"read at the wrong scale (travels {travel / 1000:.1f} m by frame 60) every grid stays within "
      f"2x the body's own box ({worst_ratio:.2f}x; the old rule's grid: {old_before / 1e6:.1f} M voxels)", failures)

# --max-voxels: a one-line error that says what to do, no output.
code, out, err = animate(cm_clip, "capped", "--unit-mm", f"{CMU_MM:.4f}", "--max-voxels", "100k", check_exit=False)
print(err)
check(code != 0 and err.startswith("repose: error:") and err.count("\n") == 1 and "--max-voxels" in err and
      "--no-root-motion" in err and no_output("capped"),
      "a grid over --max-voxels is a one-line error naming the remedies, with no output", failures)

# A map without the knees: a warning that names them; with --strict, an error.
knee_less = os.path.join(work, "no_knees.json")
open(knee_less, "w").write('{"Hips": "pelvis", "LeftUpLeg": "left_hip", "RightUpLeg": "right_hip", "LeftFoot": '
                           '"left_ankle", "RightFoot": "right_ankle", "LowerBack": "spine", "Head": "neck", '
                           '"LeftArm": "left_shoulder", "RightArm": "right_shoulder", "LeftForeArm": "left_elbow", '
                           '"RightForeArm": "right_elbow", "LeftHand": "left_wrist", "RightHand": "right_wrist"}')
code, out, _ = run("animate", "--case", case, "--bvh", clip, "--map", knee_less, "--frames", "0:1",
                   "--out", os.path.join(work, "warned"))
check(code == 0 and "warning: the clip drives none of the limb joints left_knee, right_knee" in out,
      "an undriven knee is named in a warning", failures)
code, _, err = run("animate", "--case", case, "--bvh", clip, "--map", knee_less, "--strict", "--frames", "0:1",
                   "--out", os.path.join(work, "strict"), check=False)
print(err)
check(code != 0 and err.count("\n") == 1 and "left_knee, right_knee" in err and "--strict" in err and
      no_output("strict"), "--strict makes it a one-line error, no output", failures)
root_only = os.path.join(work, "root_only.json")
open(root_only, "w").write('{"Hips": "pelvis"}')
code, _, err = run("animate", "--case", case, "--bvh", clip, "--map", root_only, "--frames", "0:1",
                   "--out", os.path.join(work, "root_only"), check=False)
print(err)
check(code != 0 and "drives no joint of the skeleton but its root" in err and no_output("root_only"), "a map that drives only the root is an error", failures)
print(f"{10 + 2 * len(frames) - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
