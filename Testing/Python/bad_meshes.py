"""Damaged and hostile meshes: surface meshes read by voxelize and `pose --mesh` (STL, PLY, OBJ, VTP,
legacy VTK) and the tet mesh, surfaces and manifest of a prepared case. Each is refused before any
allocation sized by its claims, with one line naming the file, no output and the input unchanged."""
import gzip
import json
import os
import shutil
import struct
import sys

import numpy as np
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOGeometry import vtkOBJWriter, vtkSTLWriter
from vtkmodules.vtkIOLegacy import vtkPolyDataWriter
from vtkmodules.vtkIOPLY import vtkPLYWriter
from vtkmodules.vtkIOXML import (vtkXMLPolyDataReader, vtkXMLPolyDataWriter, vtkXMLUnstructuredGridReader,
                                 vtkXMLUnstructuredGridWriter)

from repose_testing import TEMP, TESTING, TINY, check, expect_refusal, file_digests, run

work = os.path.join(TEMP, "bad_meshes")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(f"{work}/in")
failures = []
pose = os.path.join(TESTING, "Data", "tiny_pose.json")

sphere = vtkSphereSource()
sphere.SetRadius(40)
sphere.SetThetaResolution(12)
sphere.SetPhiResolution(12)
sphere.Update()
skin = sphere.GetOutput()


def written(writer, name, mesh=skin, ascii=False):
    path = f"{work}/in/{name}"
    w = writer()
    w.SetFileName(path)
    w.SetInputData(mesh)
    if hasattr(w, "SetFileTypeToASCII"):
        w.SetFileTypeToASCII() if ascii else w.SetFileTypeToBinary()
    if ascii and hasattr(w, "SetDataModeToAscii"):
        w.SetDataModeToAscii()
    assert w.Write() == 1, path
    return path


def text_of(path):
    with open(path, "rb") as f:
        return f.read()


def put(name, data):
    path = f"{work}/in/{name}"
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())
    return path


stl = text_of(written(vtkSTLWriter, "good.stl"))
ascii_stl = text_of(written(vtkSTLWriter, "good_ascii.stl", ascii=True)).decode()
ply = text_of(written(vtkPLYWriter, "good.ply", ascii=True)).decode()
binary_ply = text_of(written(vtkPLYWriter, "good_binary.ply"))
obj = text_of(written(vtkOBJWriter, "good.obj")).decode()
vtp = text_of(written(vtkXMLPolyDataWriter, "good.vtp", ascii=True)).decode()
vtk = text_of(written(vtkPolyDataWriter, "good.vtk", ascii=True)).decode()
n_points = skin.GetNumberOfPoints()
nan_mesh = type(skin)()
nan_mesh.DeepCopy(skin)
nan_mesh.GetPoints().SetPoint(5, float("nan"), 0, 0)
far_index = type(skin)()
far_index.DeepCopy(skin)
far_index.GetPolys().GetConnectivityArray().SetValue(4, 10**9)
end_header = binary_ply.index(b"end_header\n") + len(b"end_header\n")

meshes = {
    "random bytes named .stl": put("random.stl", np.random.default_rng(2).bytes(5000)),
    "binary STL cut short": put("cut.stl", stl[:-20]),
    "binary STL missing a triangle": put("short.stl", stl[:-50]),
    "binary STL claiming 10^9 triangles": put("vast.stl", stl[:80] + struct.pack("<I", 10**9) + stl[84:]),
    "ASCII STL cut short": put("cut_ascii.stl", ascii_stl[:len(ascii_stl) // 2]),
    "ASCII STL with a damaged line": put("damaged_ascii.stl", ascii_stl.replace("vertex", "vertex\x00\xca", 1)),
    "ASCII STL with a NaN vertex": put("nan_ascii.stl", ascii_stl.replace("vertex ", "vertex nan ", 1)),
    "binary STL with a NaN vertex": written(vtkSTLWriter, "nan.stl", nan_mesh),
    "empty STL": put("empty.stl", b""),
    "PLY claiming 10^9 vertices": put("vast.ply", ply.replace(f"element vertex {n_points}", "element vertex 1000000000")),
    "binary PLY claiming 10^9 vertices": put("vast_binary.ply", binary_ply.replace(
        f"element vertex {n_points}".encode(), b"element vertex 1000000000")),
    "binary PLY cut short": put("cut_binary.ply", binary_ply[:end_header + (len(binary_ply) - end_header) // 2]),
    "PLY with a negative count": put("negative.ply", ply.replace(f"element vertex {n_points}", "element vertex -5")),
    "PLY with an unknown type": put("type.ply", ply.replace("property float x", "property quad x")),
    "PLY list longer than the file": put("list.ply", ply[:ply.rindex("\n3 ")] + "\n200 0 1 2\n"),
    "binary PLY face naming a missing vertex": put("face_binary.ply", binary_ply[:-4] + struct.pack("<i", 99999)),
    "PLY face naming a missing vertex": put("face.ply", ply[:ply.rindex("\n3 ")] + "\n3 0 1 99999\n"),
    "PLY with a NaN coordinate": written(vtkPLYWriter, "nan.ply", nan_mesh, ascii=True),
    "OBJ face beyond the vertices": put("face.obj", obj + f"f 1 2 {n_points + 1}\n"),
    "OBJ face index 0": put("zero.obj", obj + "f 0 1 2\n"),
    "OBJ negative index too far back": put("negative.obj", obj + f"f -1 -2 -{n_points + 5}\n"),
    "OBJ NaN coordinate": put("nan.obj", obj.replace("v ", "v nan ", 1)),
    "OBJ vertex with two coordinates": put("short_vertex.obj", "v 1 2\n" + obj),
    "OBJ face of two vertices": put("two.obj", obj + "f 1 2\n"),
    "VTP claiming 10^9 points": put("vast.vtp", vtp.replace(f'NumberOfPoints="{n_points}"', 'NumberOfPoints="1000000000"')),
    "VTP cell naming point 10^9": written(vtkXMLPolyDataWriter, "far.vtp", far_index),
    "VTP with a NaN point": written(vtkXMLPolyDataWriter, "nan.vtp", nan_mesh),
    "VTP cut short": put("cut.vtp", vtp[:len(vtp) // 2]),
    "random bytes named .vtp": put("random.vtp", np.random.default_rng(3).bytes(3000)),
    "legacy VTK claiming 10^9 points": put("vast.vtk", vtk.replace(f"POINTS {n_points}", "POINTS 1000000000")),
    "legacy VTK cell naming point 10^9": written(vtkPolyDataWriter, "far.vtk", far_index),
}
# The undamaged files are voxelized: the checks refuse damage, not formats.
for name in ("good.stl", "good_ascii.stl", "good.ply", "good_binary.ply", "good.obj", "good.vtp", "good.vtk"):
    rc, _, err = run("voxelize", "--skin", f"{work}/in/{name}", "--voxel", "8", "--out", f"{work}/{name}.nii.gz",
                     check=False)
    check(rc == 0 and os.path.isfile(f"{work}/{name}.nii.gz"), f"undamaged {name} is voxelized {err.strip()}", failures)

before = file_digests(f"{work}/in")
for i, (what, path) in enumerate(meshes.items()):
    expect_refusal(what, ["voxelize", "--skin", path, "--voxel", "8"], os.path.basename(path),
                   f"{work}/voxelized{i}.nii.gz", failures)
for what in ("PLY face naming a missing vertex", "OBJ face beyond the vertices", "binary STL cut short"):
    expect_refusal(f"pose --mesh: {what}", ["pose", "--case", f"{TINY}/case", "--pose", pose, "--mesh", meshes[what]],
                   os.path.basename(meshes[what]), f"{work}/posed_{len(what)}", failures)
check(file_digests(f"{work}/in") == before, "mesh inputs unchanged", failures)

# Damaged cases: each a copy of the tiny case with one file changed.
case = f"{TINY}/case"
manifest = json.load(open(f"{case}/manifest.json"))


def damaged_case(name, files):
    folder = f"{work}/cases/{name}"
    shutil.copytree(case, folder)
    for file, data in files.items():
        put(os.path.relpath(f"{folder}/{file}", f"{work}/in"), data)
    return folder


def with_manifest(**changes):
    return json.dumps({**manifest, **changes})


def rewritten(name, change):
    """The case's `name` (mesh.vtu or surfaces.vtp) read, changed by `change(mesh)` and written."""
    xml = {"mesh.vtu": (vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter),
           "surfaces.vtp": (vtkXMLPolyDataReader, vtkXMLPolyDataWriter)}[name]
    r = xml[0]()
    r.SetFileName(f"{case}/{name}")
    r.Update()
    mesh = r.GetOutput()
    change(mesh)
    path = f"{work}/{len(os.listdir(work))}_{name}"
    w = xml[1]()
    w.SetFileName(path)
    w.SetInputData(mesh)
    assert w.Write() == 1
    return text_of(path)


def tet_mesh(change):
    return rewritten("mesh.vtu", change)


mesh_vtu = text_of(f"{case}/mesh.vtu")
labels = text_of(f"{case}/labels.nii.gz")
moved = bytearray(gzip.decompress(labels))
struct.pack_into("<f", moved, 268, struct.unpack_from("<f", moved, 268)[0] + 5000)  # qoffset_x
struct.pack_into("<f", moved, 292, struct.unpack_from("<f", moved, 292)[0] + 5000)  # srow_x[3]
cases = {
    "case version 2": ({"manifest.json": with_manifest(version=2)}, "manifest.json"),
    "case version as text": ({"manifest.json": with_manifest(version="1")}, "manifest.json"),
    "node count not the mesh's": ({"manifest.json": with_manifest(nodes=manifest["nodes"] + 1)}, "manifest.json"),
    "mesh path leaving the case": ({"manifest.json": with_manifest(mesh="../case/mesh.vtu")}, "manifest.json"),
    "absolute labels path": ({"manifest.json": with_manifest(labels="/etc/hostname")}, "manifest.json"),
    "mesh path not a string": ({"manifest.json": with_manifest(mesh=5)}, "manifest.json"),
    "tet naming node 10^9": ({"mesh.vtu": tet_mesh(lambda m: m.GetCells().GetConnectivityArray().SetValue(7, 10**9))},
                             "mesh.vtu"),
    "tet node at NaN": ({"mesh.vtu": tet_mesh(lambda m: m.GetPoints().SetPoint(3, 0, float("nan"), 0))}, "mesh.vtu"),
    "bone id beyond the skeleton": ({"mesh.vtu": tet_mesh(lambda m: m.GetPointData().GetArray("BoneIds")
                                                          .SetComponent(11, 0, 99))}, "mesh.vtu"),
    "NaN weight": ({"mesh.vtu": tet_mesh(lambda m: m.GetPointData().GetArray("Weights")
                                         .SetComponent(2, 1, float("nan")))}, "mesh.vtu"),
    "mesh.vtu cut short": ({"mesh.vtu": mesh_vtu[:len(mesh_vtu) * 6 // 10]}, "mesh.vtu"),
    "mesh.vtu of random bytes": ({"mesh.vtu": np.random.default_rng(4).bytes(len(mesh_vtu))}, "mesh.vtu"),
    "surface bound to tet 10^9": ({"surfaces.vtp": rewritten("surfaces.vtp", lambda m: m.GetPointData().GetArray("BoundTet")
                                                                  .SetValue(5, 10**9))}, "surfaces.vtp"),
    "labels moved 5 m away from the mesh": ({"labels.nii.gz": gzip.compress(bytes(moved))}, "labels.nii.gz"),
    "labels cut short": ({"labels.nii.gz": labels[:len(labels) * 9 // 10]}, "labels.nii.gz"),
    "manifest nested 100000 deep": ({"manifest.json": "[" * 100000}, "manifest.json"),
}
for i, (what, (files, name)) in enumerate(cases.items()):
    folder = damaged_case(f"c{i}", files)
    before = file_digests(folder)
    expect_refusal(what, ["pose", "--case", folder, "--pose", pose], name, f"{work}/case_out{i}", failures)
    check(file_digests(folder) == before, f"{what}: case unchanged", failures)
print(f"bad meshes tried: {len(meshes) + 3}, damaged cases: {len(cases)}")
print(f"{len(meshes) + 7 + 4 + 2 * len(cases) - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
