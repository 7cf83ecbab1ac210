#!/usr/bin/python3
"""Binding arbitrary meshes to a prepared case (repose pose --mesh), and dense vs sparse (OpenVDB)
posed volumes.

usage: /usr/bin/python3 scripts/benchmark_binding.py [--case CASE_DIR] [--size medium] [--points 1300000]
       [--repose build/bin/repose] [--work DIR]
Without --case, the built-in phantom of --size is made and prepared first (medium: ~2.7 M tets).
Meshes bound: random points in the body's bounding box (a point cloud, .vtp vertices), the body's
outer isosurface (a skin-like triangle mesh, .vtp) and a fine sphere inside the torso (.ply). Each is
posed twice through the CLI, as a user runs it: the first run binds (and caches the binding in
CASE/bindings), the second reads the cache. Prints two Markdown tables."""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonCore import VTK_ID_TYPE, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOPLY import vtkPLYWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The built Python package, unless PYTHONPATH already names one.
sys.path.append(os.path.join(root, "build", "lib", "python3", "dist-packages"))
POSE = os.path.join(root, "Testing", "Data", "tiny_pose.json")


def run(cmd):
    p = subprocess.run(list(map(str, cmd)), capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def write_vtp(mesh, path):
    w = vtkXMLPolyDataWriter()
    w.SetFileName(path)
    w.SetInputData(mesh)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    assert w.Write() == 1


def point_cloud(points):
    pd = vtkPolyData()
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=np.float32), deep=True))
    pd.SetPoints(pts)
    verts = vtkCellArray()
    n = len(points)
    verts.SetData(numpy_to_vtk(np.arange(n + 1, dtype=np.int64), deep=True, array_type=VTK_ID_TYPE),
                  numpy_to_vtk(np.arange(n, dtype=np.int64), deep=True, array_type=VTK_ID_TYPE))
    pd.SetVerts(verts)
    return pd


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--case")
    ap.add_argument("--size", default="medium")
    ap.add_argument("--points", type=int, default=1300000)
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="repose-binding-")
    os.makedirs(work, exist_ok=True)
    case = a.case
    if not case:
        print(f"preparing the {a.size} phantom in {work} ...", file=sys.stderr)
        run([a.repose, "phantom", "--size", a.size, "--out", f"{work}/phantom"])
        run([a.repose, "prepare", "--labels", f"{work}/phantom/labels.nii.gz", "--skeleton",
             f"{work}/phantom/skeleton.json", "--out", f"{work}/case"])
        case = f"{work}/case"
    manifest = json.load(open(os.path.join(case, "manifest.json")))
    tets = manifest["tets"]
    shutil.rmtree(os.path.join(case, "bindings"), ignore_errors=True)

    sys.path.insert(0, os.path.join(root, "Testing", "Python"))
    os.environ.setdefault("REPOSE_EXE", a.repose)
    from repose import vtkReposeImageReader
    r = vtkReposeImageReader()
    r.SetFileName(os.path.join(case, manifest["labels"]))
    r.Update()
    labels = r.GetOutput()
    lo, hi = np.array(labels.GetBounds()[0::2]), np.array(labels.GetBounds()[1::2])

    meshes = []
    rng = np.random.default_rng(1)
    if a.points > 0:  # --points 0 skips this stress case (most points far outside the body)
        pts = lo + (hi - lo) * rng.random((a.points, 3))
        write_vtp(point_cloud(pts), f"{work}/random_points.vtp")
        meshes.append(("random points in the bounding box", f"{work}/random_points.vtp"))
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    body = vtkImageData()
    body.CopyStructure(labels)
    mask = (vtk_to_numpy(labels.GetPointData().GetScalars()) != 0).astype(np.uint8)
    body.GetPointData().SetScalars(numpy_to_vtk(mask, deep=True))
    iso = vtkFlyingEdges3D()
    iso.SetInputData(body)
    iso.SetValue(0, 0.5)
    iso.ComputeNormalsOff()
    iso.Update()
    write_vtp(iso.GetOutput(), f"{work}/skin_isosurface.vtp")
    meshes.append(("body isosurface (skin-like)", f"{work}/skin_isosurface.vtp"))
    skeleton = json.load(open(os.path.join(case, "skeleton.json")))
    s = vtkSphereSource()
    s.SetCenter(*skeleton["joints"][1]["center"])
    s.SetRadius(60)
    s.SetThetaResolution(1000)
    s.SetPhiResolution(1000)
    w = vtkPLYWriter()
    w.SetInputConnection(s.GetOutputPort())
    w.SetFileName(f"{work}/sphere.ply")
    w.SetFileTypeToBinary()
    assert w.Write() == 1
    meshes.append(("fine sphere in the torso", f"{work}/sphere.ply"))

    line = re.compile(r"mesh (\S+): (\d+) vertices, (\d+) outside the body \(([0-9.]+) %\), (bound|binding read from the cache) in ([0-9.]+) s")
    posed = re.compile(r"mesh (\S+): posed in ([0-9.]+) ms")
    rows = []
    for title, path in meshes:
        res = {}
        for attempt in ("fresh", "cached"):
            out = run([a.repose, "pose", "--case", case, "--pose", POSE, "--mesh", path, "--format", "vdb",
                       "--out", f"{work}/out_{attempt}"])
            m, p = line.search(out), posed.search(out)
            res[attempt] = (int(m.group(2)), int(m.group(3)), float(m.group(6)), float(p.group(2)))
        n, outside, bind, pose_ms = res["fresh"]
        rows.append((title, n, tets, 100.0 * (n - outside) / n, bind, res["cached"][2], pose_ms))
        print(f"{title}: {rows[-1][1:]}", file=sys.stderr)
        vdb_line = re.search(r"vdb posed_labels\.vdb: .*", out).group(0)
        times = {m.group(1): float(m.group(2)) for m in re.finditer(r"^\s+(\S[^\n]*?)\s+([0-9.]+) s$", out, re.M)}
    print("| mesh | vertices | tets | inside % | bind s | cached s | pose ms |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for t, n, nt, inside, bind, cached, pose_ms in rows:
        print(f"| {t} | {n:,} | {nt:,} | {inside:.1f} | {bind:.2f} | {cached:.2f} | {pose_ms:.1f} |")
    m = re.search(r"(\d+) grid\(s\), (\d+) of (\d+) voxels active \(([0-9.]+) %\), ([0-9.]+) MB sparse vs ([0-9.]+) MB dense, "
                  r"built in ([0-9.]+) s, written in ([0-9.]+) s", vdb_line)
    print()
    print("| posed label volume | voxels | active % | dense MB | vdb MB (all grids) | dense resample s | dense->vdb s | vdb write s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    print(f"| {os.path.basename(case)} | {int(m.group(3)):,} | {float(m.group(4)):.1f} | {float(m.group(6)):.1f} | "
          f"{float(m.group(5)):.1f} ({m.group(1)} grids) | {times.get('posed labels', float('nan')):.2f} | "
          f"{float(m.group(7)):.2f} | {float(m.group(8)):.2f} |")


if __name__ == "__main__":
    main()
