"""A real skin surface (Human.vtp, no bones) with synthetic bones placed in its legs by the test:
`repose voxelize` -> `repose prepare` -> `repose pose` (left knee flexed): the tibia moves rigidly as
the skeleton says, the femur stays, and the skin follows near the knee but not far from it."""
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersCore import vtkCleanPolyData
from vtkmodules.vtkFiltersSources import vtkCylinderSource
from vtkmodules.vtkCommonTransforms import vtkTransform
from vtkmodules.vtkFiltersGeneral import vtkTransformPolyDataFilter
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLPolyDataWriter
from vtkmodules.vtkIOGeometry import vtkSTLWriter

from repose_testing import SHARED, TEMP, Image, bone_transforms, check, kabsch, load_json, rigid_bone_dice, run

work = os.path.join(TEMP, "voxelize_human")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
UNIT = 10.0  # Human.vtp is in centimetres: 1.67 m tall
human = os.path.join(SHARED, "meshes", "Human.vtp")
r = vtkXMLPolyDataReader()
r.SetFileName(human)
r.Update()
P = vtk_to_numpy(r.GetOutput().GetPoints().GetData()).astype(float) * UNIT


def leg_centre(z, side):
    """Centre (mm) of a leg's cross-section at height z (mm); side +1 left (+x in LPS), -1 right."""
    near = P[(np.abs(P[:, 2] - z) < 15) & (side * P[:, 0] > 25)]
    return 0.5 * (near.min(0) + near.max(0))


def capsule(a, b, radius, path):
    """Closed cylinder from a to b (mm), written as STL (a triangle soup) in Human.vtp's unit (cm)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    length = np.linalg.norm(b - a)
    cyl = vtkCylinderSource()
    cyl.SetRadius(radius)
    cyl.SetHeight(length)
    cyl.SetResolution(24)
    cyl.CappingOn()
    clean = vtkCleanPolyData()  # weld the caps to the tube
    clean.SetInputConnection(cyl.GetOutputPort())
    t = vtkTransform()  # cylinder axis +y -> b - a, centred at the midpoint
    t.PostMultiply()
    axis = (b - a) / length
    rot = np.cross([0, 1, 0], axis)
    angle = np.degrees(np.arccos(np.clip(axis[1], -1, 1)))
    if np.linalg.norm(rot) > 1e-9:
        t.RotateWXYZ(angle, *rot)
    t.Translate(*(0.5 * (a + b)))
    t.Scale(1 / UNIT, 1 / UNIT, 1 / UNIT)
    tf = vtkTransformPolyDataFilter()
    tf.SetInputConnection(clean.GetOutputPort())
    tf.SetTransform(t)
    tri = vtkTriangleFilter()
    tri.SetInputConnection(tf.GetOutputPort())
    w = vtkSTLWriter()
    w.SetFileName(path)
    w.SetInputConnection(tri.GetOutputPort())
    w.Write()


# Bones (mm): a pelvis across the hips, femurs hip -> knee, tibias knee -> ankle, in both legs.
hipZ, kneeZ, ankleZ = -130.0, -390.0, -690.0
args = ["voxelize", "--skin", human, "--unit-mm", UNIT, "--voxel", 8, "--out", f"{work}/vox/labels.nii.gz"]
joints = []
# The pelvis lies above the crotch (z = 0), across the hips.
pelvisL, pelvisR = leg_centre(hipZ, 1) * [0.7, 1, 0] + [0, 0, 60], leg_centre(hipZ, -1) * [0.7, 1, 0] + [0, 0, 60]
capsule(pelvisR, pelvisL, 25, f"{work}/pelvis.stl")
args += ["--bone", f"pelvis={work}/pelvis.stl"]
for side, name in ((1, "left"), (-1, "right")):
    hip, knee, ankle = leg_centre(hipZ, side), leg_centre(kneeZ, side), leg_centre(ankleZ, side)
    capsule(hip + (knee - hip) * 0.1, knee - (knee - hip) * 0.07, 22, f"{work}/femur_{name}.stl")
    capsule(knee + (ankle - knee) * 0.07, ankle, 16, f"{work}/tibia_{name}.stl")
    args += ["--bone", f"femur_{name}={work}/femur_{name}.stl", "--bone", f"tibia_{name}={work}/tibia_{name}.stl"]
    joints.append((name, hip, knee))
code, out, err = run(*args)
print(out)
names = {}
with open(f"{work}/vox/labels.tsv") as f:
    next(f)
    for line in f:
        v, n, k = line.split()
        names[n] = int(v)
check(all(n in names for n in ("pelvis", "femur_left", "tibia_left", "femur_right", "tibia_right")),
      "every bone has a label", failures)
check("outside the skin" not in out, "the bones lie inside the skin", failures)
rest = Image(f"{work}/vox/labels.nii.gz")
for n in ("pelvis", "femur_left", "tibia_left"):
    check((rest.a == names[n]).sum() > 100, f"{n} has voxels", failures)

skeleton = {"joints": [{"name": "pelvis", "parent": None, "center": list(0.5 * (pelvisL + pelvisR)),
                        "labels": [names["pelvis"]]}]}
for name, hip, knee in joints:
    skeleton["joints"].append({"name": f"{name}_hip", "parent": "pelvis", "center": list(hip),
                               "labels": [names[f"femur_{name}"]]})
    skeleton["joints"].append({"name": f"{name}_knee", "parent": f"{name}_hip", "center": list(knee),
                               "labels": [names[f"tibia_{name}"]]})
import json
with open(f"{work}/skeleton.json", "w") as f:
    json.dump(skeleton, f)
pose = {"rotations": {"left_knee": {"axis": [1, 0, 0], "degrees": 50}}, "translation": [0, 0, 0]}
with open(f"{work}/pose.json", "w") as f:
    json.dump(pose, f)
code, out, err = run("prepare", "--labels", f"{work}/vox/labels.nii.gz", "--skeleton", f"{work}/skeleton.json",
                     "--mesh-spacing", 12, "--out", f"{work}/case")
print(out)
code, out, err = run("pose", "--case", f"{work}/case", "--pose", f"{work}/pose.json", "--out", f"{work}/posed")
print(out)

G = bone_transforms(load_json(f"{work}/case/skeleton.json"), pose)
posed = Image(f"{work}/posed/posed_labels.nii.gz")
for n, joint in (("tibia_left", "left_knee"), ("femur_left", "left_hip"), ("tibia_right", "right_knee")):
    d = rigid_bone_dice(rest, posed, [names[n]], G[joint])
    check(d >= 0.9, f"{n} moved rigidly with {joint}: Dice {d:.3f} >= 0.9", failures)


def surfaces(path):
    rd = vtkXMLPolyDataReader()
    rd.SetFileName(path)
    rd.Update()
    s = rd.GetOutput()
    pts = vtk_to_numpy(s.GetPoints().GetData()).astype(float)
    cells = vtk_to_numpy(s.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    label = vtk_to_numpy(s.GetCellData().GetArray("Label"))
    return pts, cells, label


rp, rc, rl = surfaces(f"{work}/case/surfaces.vtp")
pp, pc, pl = surfaces(f"{work}/posed/posed_surfaces.vtp")
check(rp.shape == pp.shape, "posed surfaces keep the rest surfaces' points", failures)
tib = np.unique(rc[rl == names["tibia_left"]])
Gk, res = kabsch(rp[tib], pp[tib])
shift = np.linalg.norm(pp[tib] - rp[tib], axis=1).max()
check(res < 2.0 and np.abs(Gk[:3, :3] - G["left_knee"][:3, :3]).max() < 0.01,
      f"tibia_left surface moved rigidly by the knee's rotation (Kabsch residual {res:.2f} mm, moved up to "
      f"{shift:.0f} mm)", failures)
skin = np.unique(rc[~np.isin(rl, list(names.values()))])  # the skin's cells are not a bone's
move = np.linalg.norm(pp[skin] - rp[skin], axis=1)
z = rp[skin][:, 2]
lknee = joints[0][2]
near = np.linalg.norm(rp[skin] - lknee, axis=1) < 150
far = z > 0  # the upper body, far from the left knee
print(f"skin: max move near the knee {move[near].max():.1f} mm, above the hips {move[far].max():.3f} mm")
check(move[near].max() > 30, "the skin follows the knee", failures)
check(move[far].max() < 0.5, "the skin far from the knee stays", failures)
total = 14
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
