"""Checks the tiny phantom's prepared case and posed outputs against invariants and a rigid oracle:
weights are a partition of unity in [0,1]; bone nodes move rigidly; every bone of the posed volume
matches its rigidly moved rest bone (Dice >= 0.95); the body keeps its volume under DQS (5 %);
the posed body encloses no background the rest body did not."""
import os
import sys

import numpy as np
from scipy import ndimage

from repose_testing import (TESTING, TINY, Image, Mesh, bone_transforms, check, load_json, rigid_bone_dice)

failures = []
skeleton = load_json(f"{TINY}/case/skeleton.json")
pose = load_json(os.path.join(TESTING, "Data", "tiny_pose.json"))
G = bone_transforms(skeleton, pose)
names = [j["name"] for j in skeleton["joints"]]


rest_mesh = Mesh(f"{TINY}/case/mesh.vtu")
W = rest_mesh.point_array("Weights").astype(float)
B = rest_mesh.point_array("BoneIds").astype(int)
fixed = rest_mesh.point_array("FixedBone").astype(int)
check(np.abs(W.sum(1) - 1).max() <= 1e-6, f"weights sum to 1 (max error {np.abs(W.sum(1) - 1).max():.2e})", failures)
check(W.min() >= 0 and W.max() <= 1, f"weights in [0,1] (min {W.min():.3g}, max {W.max():.3g})", failures)
for j in range(len(names)):
    check((fixed == j).any(), f"bone {names[j]} has fixed nodes ({(fixed == j).sum()})", failures)
fx = fixed >= 0
top = B[np.arange(len(B)), W.argmax(1)]
check(np.all(top[fx] == fixed[fx]) and np.all(W.max(1)[fx] > 1 - 1e-6), "fixed nodes carry weight 1 for their bone", failures)

rest_pts = rest_mesh.points
for method in ("dqs", "lbs"):
    posed_pts = Mesh(f"{TINY}/posed_{method}/posed_mesh.vtu").points
    err = 0.0
    for j, n in enumerate(names):
        sel = fixed == j
        moved = rest_pts[sel] @ G[n][:3, :3].T + G[n][:3, 3]
        err = max(err, np.abs(moved - posed_pts[sel]).max(initial=0))
    check(err < 1e-3, f"{method}: bone nodes move rigidly (max deviation {err:.2e} mm)", failures)

rest = Image(f"{TINY}/phantom/labels.nii.gz")
for method in ("dqs", "lbs"):
    posed = Image(f"{TINY}/posed_{method}/posed_labels.nii.gz")
    check(np.allclose(posed.spacing, rest.spacing) and np.allclose(posed.direction, rest.direction),
          f"{method}: posed grid keeps spacing and direction", failures)
    worst = 1.0
    for j in skeleton["joints"]:
        d = rigid_bone_dice(rest, posed, j["labels"], G[j["name"]])
        worst = min(worst, d)
        if method == "dqs":
            check(d >= 0.95, f"{method}: bone {j['name']} Dice with its rigidly moved rest bone {d:.3f}", failures)
    print(f"{method}: worst bone Dice {worst:.3f}")
    ratio = (posed.a != 0).sum() / (rest.a != 0).sum()
    if method == "dqs":
        check(abs(ratio - 1) <= 0.05, f"{method}: body volume ratio {ratio:.4f} within 5 %", failures)
    else:
        print(f"{method}: body volume ratio {ratio:.4f}")

    def enclosed_background(a):
        comp, n = ndimage.label(a == 0)
        border = set(np.unique(np.concatenate([comp[0].ravel(), comp[-1].ravel(), comp[:, 0].ravel(),
                                                comp[:, -1].ravel(), comp[:, :, 0].ravel(), comp[:, :, -1].ravel()])))
        inner = [c for c in range(1, n + 1) if c not in border]
        return np.isin(comp, inner).sum()

    er, ep = enclosed_background(rest.a), enclosed_background(posed.a)
    check(ep <= er, f"{method}: enclosed background voxels posed {ep} <= rest {er} (no holes)", failures)

print(f"{0 if failures else 1} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
