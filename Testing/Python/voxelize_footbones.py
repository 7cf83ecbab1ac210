"""`repose voxelize --bones-split`: footbones.ply (26 separate bones in one file) split into its
connected pieces, each its own label inside a synthetic skin (a box around the bones), each piece's
voxels where the piece is; and bad input: a missing mesh, an open dish, too many voxels, a negative
marrow radius -> a one-line
error naming the file, a non-zero exit and no output."""
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkFiltersCore import vtkPolyDataConnectivityFilter, vtkTriangleFilter
from vtkmodules.vtkFiltersCore import vtkMassProperties
from vtkmodules.vtkFiltersSources import vtkCubeSource, vtkSphereSource
from vtkmodules.vtkIOGeometry import vtkOBJWriter
from vtkmodules.vtkIOPLY import vtkPLYReader
from vtkmodules.vtkIOGeometry import vtkSTLWriter

from repose_testing import SHARED, TEMP, Image, check, label_table, run

work = os.path.join(TEMP, "voxelize_footbones")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
feet = os.path.join(SHARED, "meshes", "footbones.ply")
UNIT = 20.0  # footbones.ply spans 11.3 units: 226 mm at 20 mm a unit

# Independent reference: VTK's connectivity filter, in file order of each piece's first cell.
r = vtkPLYReader()
r.SetFileName(feet)
r.Update()
conn = vtkPolyDataConnectivityFilter()
conn.SetInputData(r.GetOutput())
conn.SetExtractionModeToAllRegions()
conn.ColorRegionsOn()
conn.Update()
regions = conn.GetNumberOfExtractedRegions()
check(regions == 26, f"VTK finds 26 pieces in footbones.ply ({regions})", failures)
out = conn.GetOutput()
pts = vtk_to_numpy(out.GetPoints().GetData()).astype(float) * UNIT
cells = vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3)
region = vtk_to_numpy(out.GetPointData().GetArray("RegionId"))[cells[:, 0]]
order = []
for rid in region:  # regions in order of first appearance, as repose numbers the pieces
    if rid not in order:
        order.append(rid)

lo, hi = r.GetOutput().GetBounds()[0::2], r.GetOutput().GetBounds()[1::2]
cube = vtkCubeSource()
cube.SetBounds(lo[0] - 0.5, hi[0] + 0.5, lo[1] - 0.5, hi[1] + 0.5, lo[2] - 0.5, hi[2] + 0.5)
tri = vtkTriangleFilter()
tri.SetInputConnection(cube.GetOutputPort())
w = vtkSTLWriter()
w.SetFileName(f"{work}/skin.stl")
w.SetInputConnection(tri.GetOutputPort())
w.Write()

code, stdout, err = run("voxelize", "--skin", f"{work}/skin.stl", "--bones-split", f"foot={feet}", "--unit-mm", UNIT,
                        "--voxel", 0.8, "--out", f"{work}/vox/labels.nrrd")
print(stdout)
vox = Image(f"{work}/vox/labels.nrrd")
table = label_table(f"{work}/vox/labels.tsv")
bones = [n for n, (v, k) in table.items() if k == "bone"]
check(len(bones) == 26 and bones == [f"foot_{i}" for i in range(1, 27)], "26 bones foot_1 .. foot_26", failures)
check(table.get("soft_tissue", (0,))[0] == 1, "the box's inside is soft tissue", failures)
centres = vox.centres()
worst = 0.0
for i, rid in enumerate(order, start=1):
    v = table[f"foot_{i}"][0]
    mask = vox.a == v
    piece = pts[np.unique(cells[region == rid])]
    centroid_vox = centres[mask].mean(0) if mask.any() else np.full(3, np.inf)
    # The piece's voxels sit where the piece is: centroids within 1.5 voxels, inside its bounds.
    err_mm = np.linalg.norm(centroid_vox - 0.5 * (piece.min(0) + piece.max(0)))
    inside_bounds = mask.any() and np.all(centres[mask] >= piece.min(0) - 0.8) and np.all(centres[mask] <= piece.max(0) + 0.8)
    worst = max(worst, err_mm)
    if not (mask.sum() > 0 and inside_bounds):
        check(False, f"foot_{i}: {mask.sum()} voxels inside the piece's bounds", failures)
print(f"largest distance between a bone's voxel centroid and its piece's bounding-box centre: {worst:.2f} mm")
check(all((vox.a == table[f"foot_{i}"][0]).sum() > 0 for i in range(1, 27)), "every piece has voxels", failures)

# Volumes: each label against the piece's closed-surface volume (vtkMassProperties), within 25 %.
sub = vtkPolyDataConnectivityFilter()
sub.SetInputData(r.GetOutput())
sub.SetExtractionModeToSpecifiedRegions()
ratios = []
for i, rid in enumerate(order, start=1):
    sub.InitializeSpecifiedRegionList()
    sub.AddSpecifiedRegion(int(rid))
    sub.Update()
    mp = vtkMassProperties()
    mp.SetInputData(sub.GetOutput())
    mp.Update()
    ratios.append((vox.a == table[f"foot_{i}"][0]).sum() * 0.8 ** 3 / (mp.GetVolume() * UNIT ** 3))
print("voxel / mesh volume per bone: min %.3f max %.3f" % (min(ratios), max(ratios)))
check(0.75 < min(ratios) and max(ratios) < 1.25, "every bone's voxel volume within 25 % of its mesh volume", failures)

# Bad input: one line naming the file, non-zero exit, nothing written.
sphere = vtkSphereSource()
sphere.SetRadius(10)
sphere.SetThetaResolution(24)
sphere.SetPhiResolution(24)
sphere.SetStartPhi(110)  # a shallow dish, the bottom of a sphere: too open to have an inside
wobj = vtkOBJWriter()
wobj.SetFileName(f"{work}/bowl.obj")
wobj.SetInputConnection(sphere.GetOutputPort())
wobj.Write()
cases = [
    ("missing mesh", ["--skin", f"{work}/nothing.stl", "--voxel", 1], "nothing.stl"),
    ("open dish", ["--skin", f"{work}/bowl.obj", "--voxel", 1], "bowl.obj: the surface is not closed enough"),
    ("too many voxels", ["--skin", f"{work}/skin.stl", "--unit-mm", UNIT, "--voxel", 0.01], "skin.stl:"),
    ("bad bone option", ["--skin", f"{work}/skin.stl", "--voxel", 1, "--bone", "femur.stl"], "NAME=MESH"),
    ("negative marrow radius", ["--skin", f"{work}/skin.stl", "--voxel", 1, "--max-marrow-radius", -2],
     "--max-marrow-radius must not be negative"),
]
for what, args, expect in cases:
    target = f"{work}/bad/{what.replace(' ', '_')}.nii.gz"
    code, o, e = run("voxelize", *args, "--out", target, check=False)
    lines = e.strip().splitlines()
    ok = code != 0 and len(lines) == 1 and lines[0].startswith("repose: error:") and expect in lines[0]
    ok = ok and not os.path.exists(target) and not os.path.exists(target.replace(".nii.gz", ".tsv"))
    check(ok, f"{what}: exit {code}, '{lines[0] if lines else ''}', no output", failures)

total = 8 + len(cases)
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
