"""repose pose --mesh on the tiny phantom: meshes of any kind (a triangulated sphere as OBJ, a polyline
catheter path as VTP, a small sphere as PLY) are posed with the body and written as
posed_<name> in their own format with the same points and cells; vertices inside a bone move
rigidly with it; the binding is cached in CASE/bindings and reused; --format vdb writes OpenVDB
files; bad mesh input fails with one line, a non-zero exit and no output."""
import os
import re
import shutil
import sys

import numpy as np
from scipy import ndimage
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOGeometry import vtkOBJReader, vtkOBJWriter
from vtkmodules.vtkIOPLY import vtkPLYReader, vtkPLYWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLPolyDataWriter

from repose_testing import SHARED, TEMP, TESTING, TINY, Image, bone_transforms, load_json, run
from repose_testing import check as _check

checks = []


def check(cond, message, failures):
    checks.append(message)
    _check(cond, message, failures)


failures = []
work = os.path.join(TEMP, "pose_mesh")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
# A copy of the fixture's case: pose --mesh writes its binding cache into CASE/bindings.
case = os.path.join(work, "case")
shutil.copytree(f"{TINY}/case", case)
pose_path = os.path.join(TESTING, "Data", "tiny_pose.json")
skeleton = load_json(f"{case}/skeleton.json")
G = bone_transforms(skeleton, load_json(pose_path))["left_hip"]  # moves the left femur (label 24)

# Points inside the left femur, a voxel away from its surface (their tets have only bone nodes).
rest = Image(f"{TINY}/phantom/labels.nii.gz")
femur = ndimage.binary_erosion(rest.a == 24, iterations=1)
centres = rest.centres()[femur]
assert len(centres) > 20, "the tiny phantom's femur is too thin for this test"
axis = centres[np.argsort(centres[:, 2])]
path_points = axis[np.linspace(0, len(axis) - 1, 12).astype(int)]  # catheter path along the femur
femur_centre = centres[np.argmin(np.linalg.norm(centres - centres.mean(0), axis=1))]


def sphere(centre, radius, resolution):
    s = vtkSphereSource()
    s.SetCenter(*centre)
    s.SetRadius(radius)
    s.SetThetaResolution(resolution)
    s.SetPhiResolution(resolution)
    s.Update()
    return s.GetOutput()


def write(writer, mesh, path):
    writer.SetFileName(path)
    writer.SetInputData(mesh)
    assert writer.Write() == 1, path


def read(reader, path):
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def points(mesh):
    return vtk_to_numpy(mesh.GetPoints().GetData()).astype(float)


# 1. A sphere around the torso, partly outside the body (OBJ).
torso = np.array(skeleton["joints"][1]["center"], float)
write(vtkOBJWriter(), sphere(torso, 120.0, 24), f"{work}/organ.obj")
# 2. A polyline through the femur with point data (VTP).
line = vtkPolyData()
pts = vtkPoints()
pts.SetData(numpy_to_vtk(path_points, deep=True))
line.SetPoints(pts)
cells = vtkCellArray()
cells.InsertNextCell(len(path_points))
for i in range(len(path_points)):
    cells.InsertCellPoint(i)
line.SetLines(cells)
arc = numpy_to_vtk(np.arange(len(path_points), dtype=np.float32), deep=True)
arc.SetName("arc")
line.GetPointData().AddArray(arc)
write(vtkXMLPolyDataWriter(), line, f"{work}/catheter.vtp")
# 3. A small sphere inside the femur (PLY).
write(vtkPLYWriter(), sphere(femur_centre, 0.5 * float(rest.spacing.min()), 8), f"{work}/bead.ply")

inputs = [f"{work}/organ.obj", f"{work}/catheter.vtp", f"{work}/bead.ply"]
mesh_args = [a for p in inputs for a in ("--mesh", p)]
_, text, _ = run("pose", "--case", case, "--pose", pose_path, *mesh_args, "--out", f"{work}/out1")
print(text)
bindings = os.path.join(case, "bindings")
cache = sorted(os.listdir(bindings)) if os.path.isdir(bindings) else []
check(len(cache) == 3 and all(c.endswith(".bin") for c in cache), f"one cached binding per mesh: {cache}", failures)
check(len(re.findall(r": \d+ vertices, \d+ outside the body .* bound in", text)) == 3, "each mesh is bound", failures)
m = re.search(r"mesh \S*organ\.obj: (\d+) vertices, (\d+) outside", text)
check(m is not None and 0 < int(m.group(2)) < int(m.group(1)), "part of the large sphere lies outside the body", failures)

readers = {"organ.obj": vtkOBJReader, "catheter.vtp": vtkXMLPolyDataReader, "bead.ply": vtkPLYReader}
posed = {}
for name, reader in readers.items():
    out_path = f"{work}/out1/posed_{name}"
    check(os.path.isfile(out_path), f"posed_{name} written", failures)
    if not os.path.isfile(out_path):
        continue
    a, b = read(reader(), f"{work}/{name}"), read(reader(), out_path)
    posed[name] = (a, b)
    check(a.GetNumberOfPoints() == b.GetNumberOfPoints() and a.GetNumberOfCells() == b.GetNumberOfCells() and
          a.GetNumberOfLines() == b.GetNumberOfLines() and a.GetNumberOfPolys() == b.GetNumberOfPolys(),
          f"{name}: same points ({b.GetNumberOfPoints()}) and cells ({b.GetNumberOfCells()})", failures)
    check(np.abs(points(a) - points(b)).max() > 1.0 or name == "organ.obj", f"{name}: moved", failures)

if "catheter.vtp" in posed:
    a, b = posed["catheter.vtp"]
    arc_out = b.GetPointData().GetArray("arc")
    check(arc_out is not None and np.array_equal(vtk_to_numpy(arc_out), np.arange(len(path_points))),
          "the polyline keeps its point data", failures)
for name in ("catheter.vtp", "bead.ply"):
    if name in posed:
        a, b = posed[name]
        expected = points(a) @ G[:3, :3].T + G[:3, 3]
        err = np.abs(points(b) - expected).max()
        moved = np.linalg.norm(points(b) - points(a), axis=1).max()
        # The bead's vertices reach within a few mm of the femur's surface, where a tet may have one
        # soft-tissue node: rigid to a few hundredths of a millimetre, for a motion of centimetres.
        check(err < 0.05 and moved > 10, f"{name}: vertices in the femur move rigidly with it (max error {err:.1e} mm, "
              f"moved up to {moved:.0f} mm)", failures)

# Second run: the cached bindings are read, not rewritten.
mtimes = {c: os.stat(os.path.join(bindings, c)).st_mtime_ns for c in cache}
_, text2, _ = run("pose", "--case", case, "--pose", pose_path, *mesh_args, "--out", f"{work}/out2")
check(text2.count("binding read from the cache") == 3, "the second run reads every binding from the cache", failures)
check(mtimes == {c: os.stat(os.path.join(bindings, c)).st_mtime_ns for c in cache}, "cache files untouched", failures)
same = all(np.array_equal(points(read(r(), f"{work}/out1/posed_{n}")), points(read(r(), f"{work}/out2/posed_{n}")))
           for n, r in readers.items())
check(same, "cached and fresh bindings pose identically", failures)
# A changed mesh is bound again.
write(vtkPLYWriter(), sphere(femur_centre, 0.4 * float(rest.spacing.min()), 8), f"{work}/bead.ply")
_, text3, _ = run("pose", "--case", case, "--pose", pose_path, "--mesh", f"{work}/bead.ply", "--out", f"{work}/out3")
check("binding read from the cache" not in text3 and len(os.listdir(bindings)) == 4, "a changed mesh is bound again",
      failures)

# --format vdb: OpenVDB files (their contents are checked by the C++ test test_vdb_volume_writer).
_, text4, _ = run("pose", "--case", case, "--pose", pose_path, "--format", "vdb", "--out", f"{work}/vdb")
print(text4)
vdb = f"{work}/vdb/posed_labels.vdb"
ok = os.path.isfile(vdb) and not os.path.exists(f"{work}/vdb/posed_labels.nii.gz")
if ok:
    data = open(vdb, "rb").read()
    ok = data[:4] == b" BDV" and b"labels" in data and b"label_24" in data  # OpenVDB magic, grid names
check(ok, "--format vdb writes posed_labels.vdb with the 'labels' and per-label grids", failures)
check(os.path.isfile(f"{work}/vdb/posed_mesh.vtu"), "--format vdb still writes the posed mesh", failures)

# animate --mesh: one posed series per mesh in the .pvd.
bvh = os.path.join(SHARED, "mocap", "cmu_131_01_walk.bvh")
run("animate", "--case", case, "--bvh", bvh, "--frames", "500:520:10", "--mesh", f"{work}/catheter.vtp",
    "--out", f"{work}/anim")
pvd = open(f"{work}/anim/animation.pvd").read()
frames = [f"{work}/anim/frames/catheter_{f:05d}.vtp" for f in (500, 510)]
check(all(os.path.isfile(f) for f in frames) and pvd.count('part="2" file="frames/catheter_') == 2,
      "animate --mesh writes the mesh's series into animation.pvd", failures)

# Bad input: one line naming the file, non-zero exit, no output.
for bad, why in ((f"{work}/missing.obj", "no such file"), (f"{work}/organ.xyz", "unknown mesh format")):
    if why == "unknown mesh format":
        shutil.copy(f"{work}/organ.obj", bad)
    out_dir = f"{work}/bad"
    code, out, err = run("pose", "--case", case, "--pose", pose_path, "--mesh", bad, "--out", out_dir, check=False)
    lines = err.strip().splitlines()
    check(code != 0 and len(lines) == 1 and lines[0].startswith("repose: error:") and bad in lines[0] and why in lines[0],
          f"{os.path.basename(bad)}: {err.strip()}", failures)
    check(not os.path.exists(out_dir), "no output after the error", failures)

# A mesh named as one of Repose's own outputs (the case's surfaces.vtp) would replace the posed surfaces.
shutil.copy(f"{case}/surfaces.vtp", f"{work}/surfaces.vtp")
for command in (["pose", "--pose", pose_path], ["animate", "--bvh", bvh, "--frames", "500:501"]):
    out_dir = f"{work}/own_name"
    code, out, err = run(command[0], "--case", case, *command[1:], "--mesh", f"{work}/surfaces.vtp", "--out", out_dir,
                         check=False)
    lines = err.strip().splitlines()
    check(code == 2 and len(lines) == 1 and "surfaces.vtp" in lines[0] and "posed_surfaces" in lines[0]
          and not os.path.exists(out_dir), f"{command[0]} --mesh surfaces.vtp is refused: {err.strip()}", failures)

print(f"{len(checks) - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
