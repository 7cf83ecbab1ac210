"""Real anatomy: the Visible Human male's and female's pelvis and leg bones (surface meshes as an atlas
ships them: femurs with holes, hip bones in three overlapping parts), filled into a 3 mm label volume
here with VTK's stencil, then rigged under their file names (hip_left, femur_left, patella_left,
tibia_left, fibula_left, sacrum, coccyx). On both bodies: the pelvis, both hips (sphere fits to the
femoral heads) and both knees; each patella rides with its femur and each fibula with its tibia (the
same on every body); the hip bones' many loose pieces (the stencil of overlapping parts) all stay
with their hip bone, none with the femoral head they touch."""
import json
import os
import sys
import time

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkFiltersCore import vtkCleanPolyData, vtkTriangleFilter
from vtkmodules.vtkImagingStencil import vtkImageStencilToImage, vtkPolyDataToImageStencil
from vtkmodules.vtkIOPLY import vtkPLYReader

from repose import vtkReposeAutoRig
from repose_testing import SHARED, check

NAMES = ["sacrum", "coccyx", "hip_left", "hip_right", "femur_left", "femur_right", "patella_left",
         "patella_right", "tibia_left", "tibia_right", "fibula_left", "fibula_right"]
H = 3.0  # mm
failures = []


def voxelize(folder):
    """Label volume (value = index in NAMES + 1, later names over earlier ones) as vtkImageData."""
    polys = {}
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for n in NAMES:
        r = vtkPLYReader()
        r.SetFileName(os.path.join(folder, n + ".ply"))
        c = vtkCleanPolyData()
        c.SetInputConnection(r.GetOutputPort())
        t = vtkTriangleFilter()
        t.SetInputConnection(c.GetOutputPort())
        t.Update()
        polys[n] = t.GetOutput()
        b = np.array(polys[n].GetBounds())
        lo, hi = np.minimum(lo, b[0::2]), np.maximum(hi, b[1::2])
    lo, hi = lo - 10, hi + 10
    dims = (np.ceil((hi - lo) / H) + 1).astype(int)
    labels = np.zeros(dims[::-1], np.int32)
    for value, n in enumerate(NAMES, 1):
        s = vtkPolyDataToImageStencil()
        s.SetInputData(polys[n])
        s.SetOutputOrigin(*lo)
        s.SetOutputSpacing(H, H, H)
        s.SetOutputWholeExtent(0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1)
        im = vtkImageStencilToImage()
        im.SetInputConnection(s.GetOutputPort())
        im.SetInsideValue(1)
        im.SetOutsideValue(0)
        im.Update()
        labels[vtk_to_numpy(im.GetOutput().GetPointData().GetScalars()).reshape(dims[::-1]) > 0] = value
    img = vtkImageData()
    img.SetDimensions(*dims)
    img.SetOrigin(*lo)
    img.SetSpacing(H, H, H)
    img.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True, array_type=6))  # VTK_INT
    return img, labels


for subject in ("male", "female"):
    t = time.perf_counter()
    img, labels = voxelize(os.path.join(SHARED, "visible_human", subject))
    print(f"{subject}: {img.GetDimensions()} voxels filled in {time.perf_counter() - t:.1f} s")
    rig = vtkReposeAutoRig()
    rig.SetInputData(img)
    rig.SetLabelTableTSV("".join(f"{v}\t{n}\n" for v, n in enumerate(NAMES, 1)))
    rig.SetLabelTableName(f"Visible Human {subject} file names")
    rig.Update()
    report = rig.GetReport()
    print(f"autoRig {rig.GetSeconds():.2f} s")
    print("\n".join(report.splitlines()[:40]))
    joints = {j["name"]: j for j in json.loads(rig.GetSkeletonJSON())["joints"]}
    value = {n: v for v, n in enumerate(NAMES, 1)}
    parents = {n: j["parent"] for n, j in joints.items()}
    check(parents == {"pelvis": None, "left_hip": "pelvis", "right_hip": "pelvis", "left_knee": "left_hip",
                      "right_knee": "right_hip"}, f"{subject}: pelvis, hips and knees ({parents})", failures)
    for side in ("left", "right"):
        hip, knee = joints.get(f"{side}_hip", {}), joints.get(f"{side}_knee", {})
        check(sorted(hip.get("labels", [])) == sorted([value[f"femur_{side}"], value[f"patella_{side}"]]),
              f"{subject}: the {side} patella rides with its femur", failures)
        check(sorted(knee.get("labels", [])) == sorted([value[f"tibia_{side}"], value[f"fibula_{side}"]]),
              f"{subject}: the {side} fibula moves with its tibia", failures)
        line = next((l for l in report.splitlines() if l.strip().startswith(f"{side}_hip ")), "")
        fit = line.split("radius ")[-1].split(" mm")[0] if "sphere fit" in line else "nan"
        check("sphere fit" in line and 18 <= float(fit) <= 28,
              f"{subject}: {side} hip centre by a sphere fit to the femoral head: '{line.strip()}'", failures)
        if hip and knee:
            femur = np.argwhere(labels == value[f"femur_{side}"])[:, 0] * H + img.GetOrigin()[2]
            tibia = np.argwhere(labels == value[f"tibia_{side}"])[:, 0] * H + img.GetOrigin()[2]
            z = knee["center"][2]
            check(tibia.max() - 10 <= z <= femur.min() + 10,
                  f"{subject}: {side} knee centre z {z:.0f} between the tibial plateau ({tibia.max():.0f}) "
                  f"and the femoral condyles ({femur.min():.0f})", failures)
    out = vtk_to_numpy(rig.GetOutput().GetPointData().GetScalars()).reshape(labels.shape)
    for n in ("hip_left", "hip_right", "femur_left", "femur_right"):
        check(np.all(out[labels == value[n]] == value[n]), f"{subject}: every {n} voxel stays under {n}", failures)
    check(rig.GetNumberOfReassignedFragments() > 100 and rig.GetUnassignedFragmentVoxels() == 0,
          f"{subject}: {rig.GetNumberOfReassignedFragments()} loose pieces ({rig.GetReassignedFragmentVoxels()} "
          "voxels) placed, none left over", failures)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
