"""`repose voxelize` round trip: the tiny phantom's own surfaces (extracted from its labels) voxelized
on the phantom's grid give back its bones (Dice >= 0.95 each) and its body; the VTK filter gives the
same volume as the CLI; the result feeds `repose prepare --skeleton auto`."""
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersGeneral import vtkDiscreteFlyingEdges3D
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

from repose_testing import TEMP, Image, check, dice, label_table, run

work = os.path.join(TEMP, "voxelize_phantom")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []

run("phantom", "--size", "tiny", "--out", f"{work}/phantom")
ph = Image(f"{work}/phantom/labels.nii.gz")
table = {}
with open(f"{work}/phantom/labels.tsv") as f:
    next(f)
    for line in f:
        value, name, kind = line.split()
        table[int(value)] = (name, kind)
bones = [v for v, (n, k) in table.items() if k == "bone" and (ph.a == v).any()]


def surface_of(mask, path):
    """Closed surface between the mask's voxels and the rest (half a voxel out), written as .vtp."""
    padded = np.pad(mask.astype(np.uint8), 1)  # so the surface closes at the image border
    img = vtkImageData()
    img.SetDimensions(padded.shape[2], padded.shape[1], padded.shape[0])
    img.SetSpacing(*ph.spacing)
    img.SetOrigin(*(ph.origin - ph.direction @ ph.spacing))
    m = img.GetDirectionMatrix()
    for r in range(3):
        for c in range(3):
            m.SetElement(r, c, ph.direction[r, c])
    img.GetPointData().SetScalars(numpy_to_vtk(padded.ravel(), deep=True))
    fe = vtkDiscreteFlyingEdges3D()
    fe.SetInputData(img)
    fe.SetValue(0, 1)
    fe.ComputeNormalsOff()
    fe.ComputeGradientsOff()
    tri = vtkTriangleFilter()
    tri.SetInputConnection(fe.GetOutputPort())
    tri.Update()
    out = tri.GetOutput()
    # vtkDiscreteFlyingEdges3D ignores the direction matrix: apply it (and the origin) to the points.
    pts = np.array([out.GetPoint(i) for i in range(out.GetNumberOfPoints())])
    o = img.GetOrigin()
    pts = (pts - o) @ ph.direction.T + o
    out.GetPoints().SetData(numpy_to_vtk(pts, deep=True))
    w = vtkXMLPolyDataWriter()
    w.SetFileName(path)
    w.SetInputData(out)
    w.Write()
    return out


surfaces = {"skin": surface_of(ph.a > 0, f"{work}/skin.vtp")}
args = ["voxelize", "--skin", f"{work}/skin.vtp", "--reference", f"{work}/phantom/labels.nii.gz",
        "--out", f"{work}/voxelized/labels.nii.gz"]
for v in bones:
    name = table[v][0]
    surfaces[name] = surface_of(ph.a == v, f"{work}/{name}.vtp")
    args += ["--bone", f"{name}={work}/{name}.vtp"]
code, out, err = run(*args)
print(out)
vox = Image(f"{work}/voxelized/labels.nii.gz")
check(vox.dims == ph.dims and np.allclose(vox.origin, ph.origin) and np.allclose(vox.spacing, ph.spacing),
      "the output is on the reference grid", failures)
names = label_table(f"{work}/voxelized/labels.tsv")
check(names.get("soft_tissue") == (1, "soft"), "label 1 is the skin's interior (soft)", failures)
body = dice(vox.a > 0, ph.a > 0)
check(body >= 0.99, f"body Dice {body:.4f} >= 0.99", failures)
worst = 1.0
for v in bones:
    name = table[v][0]
    value, kind = names[name]
    d = dice(vox.a == value, ph.a == v)
    worst = min(worst, d)
    print(f"  {name:14s} Dice {d:.4f}")
    check(d >= 0.95 and kind == "bone", f"{name}: Dice {d:.4f} >= 0.95, kind bone", failures)
print(f"worst bone Dice {worst:.4f} over {len(bones)} bones")

# The VTK filter on the same surfaces gives the same volume.
from repose import vtkReposeMeshVoxelizer
f = vtkReposeMeshVoxelizer()
ref = vtkImageData()
ref.SetDimensions(*ph.dims)
ref.SetSpacing(*ph.spacing)
ref.SetOrigin(*ph.origin)
ref.SetDirectionMatrix(*ph.direction.ravel())
f.SetReferenceImage(ref)
f.AddInputData(surfaces["skin"])
f.SetPartRole(0, vtkReposeMeshVoxelizer.Skin)
for i, v in enumerate(bones, start=1):
    f.AddInputData(surfaces[table[v][0]])
    f.SetPartName(i, table[v][0])
f.Update()
from vtkmodules.util.numpy_support import vtk_to_numpy
a = vtk_to_numpy(f.GetOutput().GetPointData().GetScalars()).reshape(vox.a.shape)
check(np.array_equal(a, vox.a), "vtkReposeMeshVoxelizer gives the CLI's volume", failures)
check(f.GetLabelTableTSV().splitlines()[3].split("\t")[1] == table[bones[0]][0], "the filter's label table", failures)

# The result feeds prepare as it is (automatic skeleton from the bone names).
code, out, err = run("prepare", "--labels", f"{work}/voxelized/labels.nii.gz", "--label-table",
                     f"{work}/voxelized/labels.tsv", "--skeleton", "auto", "--out", f"{work}/case")
check(os.path.isfile(f"{work}/case/mesh.vtu"), "prepare --skeleton auto accepts the voxelized labels", failures)

# --skeleton-out: the automatic rig on the voxelized bones (the phantom's names are known to it).
rigged = [f"{work}/rigged/labels.nii.gz" if a == f"{work}/voxelized/labels.nii.gz" else a for a in args]
code, out, err = run(*rigged, "--skeleton-out", f"{work}/rigged/skeleton.json")
import json
with open(f"{work}/rigged/skeleton.json") as f:
    joints = {j["name"] for j in json.load(f)["joints"]}
check({"left_hip", "left_knee", "right_shoulder", "right_elbow"} <= joints and len(joints) >= 12,
      f"--skeleton-out finds the joints ({len(joints)})", failures)

total = 7 + len(bones)
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
