"""The phantom lying as real scans are taken (arms against the torso, hands against the thighs, the
thighs touching, welded in the voxels) is prepared and posed apart (both arms abducted, one hip
abducted, the other flexed). The parts must come apart cleanly:
- the body keeps its volume (within 2 %), every bone matches its rigidly moved rest bone (Dice >= 0.97,
  hands included) and the posed body encloses no background the rest body did not;
- no tissue web: the tets stretched past three times their rest length in some direction hold less
  than 25 ml of the body and none is stretched twelve times (a web between two parts that were
  welded is made of tets stretched tens of times; the joints' own deformation in this pose
  stretches a few ml, as on the phantom lying apart), shown to fail on the same phantom prepared
  without contact separation;
- each part keeps its own tissue: the thighs under the hands and beside each other keep their shape
  (body voxels near each femur's shaft, posed against the rest body moved rigidly with the femur).
"""
import json
import os
import sys

import numpy as np

from repose_testing import (TEMP, Image, bone_transforms, check, dice, enclosed_background, load_json,
                            rigid_bone_dice, run, stretched_volume)

failures = []
work = os.path.join(TEMP, "contact_phantom")
phantom = os.path.join(work, "phantom")
run("phantom", "--size", "small", "--rest-pose", "contact", "--out", phantom)
skeleton = load_json(f"{phantom}/skeleton.json")
joints = {j["name"]: j for j in skeleton["joints"]}

pose = {"rotations": {"left_shoulder": {"axis": [0, 1, 0], "degrees": -75},
                      "right_shoulder": {"axis": [0, 1, 0], "degrees": 75},
                      "left_hip": {"axis": [0, 1, 0], "degrees": -30},
                      "right_hip": {"axis": [1, 0, 0], "degrees": -45}},
        "translation": [0, 0, 0]}
pose_path = os.path.join(work, "apart.json")
with open(pose_path, "w") as f:
    json.dump(pose, f)
G = bone_transforms(skeleton, pose)


def prepare_and_pose(name, *extra):
    case, out = os.path.join(work, f"case_{name}"), os.path.join(work, f"posed_{name}")
    _, text, _ = run("prepare", "--labels", f"{phantom}/labels.nii.gz", "--skeleton", f"{phantom}/skeleton.json",
                     "--out", case, *extra)
    run("pose", "--case", case, "--pose", pose_path, "--out", out)
    return case, out, text


def shaft_dice(rest, posed, name, child, radius):
    """Dice of body voxels within `radius` mm of a long bone's axis (its middle 60 %), posed against
    the rest body moved rigidly with the bone."""
    a, b = np.array(joints[name]["center"]), np.array(joints[child]["center"])
    x = posed.centres()
    g = G[name]
    back = (x - g[:3, 3]) @ g[:3, :3]
    u = (back - a) @ (b - a) / np.dot(b - a, b - a)
    r = np.linalg.norm(back - a - u[..., None] * (b - a), axis=-1)
    region = (u > 0.2) & (u < 0.8) & (r < radius)
    expected = rest.nearest(back) != 0
    return dice((posed.a != 0) & region, expected & region)


case, out, text = prepare_and_pose("separated")
print(text)
for pair in ("left_shoulder | spine", "right_shoulder | spine", "left_hip | left_wrist", "left_hip | right_hip"):
    a, b = pair.split(" | ")
    found = f"contact {a} | {b}" in text or f"contact {b} | {a}" in text
    check(found, f"prepare reports the contact {pair}", failures)

rest, posed = Image(f"{phantom}/labels.nii.gz"), Image(f"{out}/posed_labels.nii.gz")
ratio = (posed.a != 0).sum() / (rest.a != 0).sum()
check(abs(ratio - 1) <= 0.02, f"body volume ratio {ratio:.4f} within 2 %", failures)
worst = min((rigid_bone_dice(rest, posed, j["labels"], G[j["name"]]), j["name"]) for j in skeleton["joints"])
check(worst[0] >= 0.97, f"worst bone Dice {worst[0]:.3f} ({worst[1]}) >= 0.97", failures)
er, ep = enclosed_background(rest.a), enclosed_background(posed.a)
check(ep <= er, f"enclosed background voxels posed {ep} <= rest {er} (no holes)", failures)
web, smax = stretched_volume(case, out)
check(web < 25.0 and smax < 12, f"tets stretched more than 3x: {web:.2f} ml (< 25 ml); largest stretch {smax:.2f} (< 12)",
      failures)
for side in ("left", "right"):
    d = shaft_dice(rest, posed, f"{side}_hip", f"{side}_knee", 58.0)
    check(d >= 0.97, f"{side} thigh keeps its tissue: Dice {d:.3f} >= 0.97", failures)

case0, out0, _ = prepare_and_pose("welded", "--contact-separation", "off")
web0, smax0 = stretched_volume(case0, out0)
posed0 = Image(f"{out0}/posed_labels.nii.gz")
ratio0 = (posed0.a != 0).sum() / (rest.a != 0).sum()
check(web0 > 500 and smax0 > 20,
      f"without separation the measure fails: {web0:.1f} ml stretched more than 3x (largest {smax0:.1f}), "
      f"body volume ratio {ratio0:.4f}", failures)

print(f"{0 if failures else 1} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
