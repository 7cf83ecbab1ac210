#!/usr/bin/python3
"""Repose benchmark: per-stage time and peak memory on the built-in phantom and on scans of your own
(a whole body), with voxel, node and tet counts, and the per-pose costs (skinning the nodes, moving
the surfaces, pulling the posed volume, and pulling one axial slice of it as a viewer would).

usage: PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 scripts/benchmark.py [--sizes small,medium,large]
       [--scan NAME=LABELS[:SKELETON] ...] [--repose build/bin/repose] [--work DIR] [--poses N]
A scan is prepared as `repose prepare --labels LABELS --skeleton SKELETON` (default: auto) with the
default tet budget.
Prints a Markdown table. Preprocessing is timed through the CLI (as a user runs it), posing through
the Python-wrapped filters so that repeated poses reuse the loaded case as an interactive tool does."""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The built Python package, unless PYTHONPATH already names one.
sys.path.append(os.path.join(root, "build", "lib", "python3", "dist-packages"))


def run_measured(cmd):
    """Runs a command; returns (stdout, seconds, peak resident MiB) of that process alone."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = p.communicate()
    seconds = time.perf_counter() - t0
    # ru_maxrss of the children waited so far; each stage runs in its own measuring subprocess.
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{out}\n{err}")
    return out, seconds


def measured_subprocess(cmd):
    code = ("import resource, subprocess, sys, time\n"
            "t = time.perf_counter(); p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
            "dt = time.perf_counter() - t\n"
            "sys.stdout.write(p.stdout); sys.stderr.write(p.stderr)\n"
            "print('@@', dt, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
            "sys.exit(p.returncode)\n")
    out, _ = run_measured([sys.executable, "-c", code, *cmd])
    m = re.search(r"@@ (\S+) (\d+)", out)
    return out, float(m.group(1)), int(m.group(2)) / 1024.0


def stage_times(out):
    return {m.group(1): float(m.group(2)) for m in re.finditer(r"^\s+(\S[^\n]*?)\s+([0-9.]+) s$", out, re.M)}


def pose_costs(case, poses):
    """Loads a prepared case in the filters and times `poses` different poses."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
    from repose import (vtkReposeImageReader, vtkReposePosedVolume, vtkReposeSkinning,
                        vtkReposeSurfaceDeformer)
    mr = vtkXMLUnstructuredGridReader()
    mr.SetFileName(f"{case}/mesh.vtu")
    mr.Update()
    sr = vtkXMLPolyDataReader()
    sr.SetFileName(f"{case}/surfaces.vtp")
    sr.Update()
    lr = vtkReposeImageReader()
    lr.SetFileName(f"{case}/labels.nii.gz")
    lr.Update()
    skeleton = open(f"{case}/skeleton.json").read()
    joints = {j["name"] for j in json.loads(skeleton)["joints"]}
    sk = vtkReposeSkinning()
    sk.SetInputConnection(mr.GetOutputPort())
    sk.SetSkeletonJSON(skeleton)
    de = vtkReposeSurfaceDeformer()
    de.SetInputConnection(0, sr.GetOutputPort())
    de.SetInputConnection(1, sk.GetOutputPort())
    vo = vtkReposePosedVolume()
    vo.SetInputConnection(0, lr.GetOutputPort())
    vo.SetInputConnection(1, mr.GetOutputPort())
    vo.SetInputConnection(2, sk.GetOutputPort())
    vo.SetInterpolationToNearest()
    # One axial slice through the middle, as a viewer showing the posed labels would request it.
    vs = vtkReposePosedVolume()
    vs.SetInputConnection(0, lr.GetOutputPort())
    vs.SetInputConnection(1, mr.GetOutputPort())
    vs.SetInputConnection(2, sk.GetOutputPort())
    vs.SetInterpolationToNearest()
    vs.RestrictToSubExtentOn()
    skin, surf, vol, sl, voxels = [], [], [], [], 0
    for i in range(poses + 1):
        a = 10 + 50 * i / max(poses, 1)
        rotations = {"left_hip": {"axis": [1, 0, 0], "degrees": -a}, "left_knee": {"axis": [1, 0, 0], "degrees": a},
                     "right_shoulder": {"axis": [0, 1, 0], "degrees": a},
                     "right_elbow": {"axis": [1, 0, 0], "degrees": -a}}
        sk.SetPoseJSON(json.dumps({"rotations": {k: v for k, v in rotations.items() if k in joints}}))
        t = time.perf_counter(); sk.Update(); t1 = time.perf_counter()
        de.Update(); t2 = time.perf_counter()
        vo.Update(); t3 = time.perf_counter()
        e = list(vo.GetFullOutputExtent())
        e[4] = e[5] = e[5] // 2
        vs.SetOutputSubExtent(e)
        t4 = time.perf_counter(); vs.Update(); t5 = time.perf_counter()
        if i == 0:
            continue  # first pose pays one-off costs (weights conversion, binding cache)
        skin.append(t1 - t); surf.append(t2 - t1); vol.append(t3 - t2); sl.append(t5 - t4)
        voxels = vo.GetOutput().GetNumberOfPoints()
    med = lambda v: sorted(v)[len(v) // 2]
    return med(skin), med(surf), med(vol), med(sl), voxels, sr.GetOutput().GetNumberOfPoints()


def image_dims(path):
    from repose import vtkReposeImageReader
    r = vtkReposeImageReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput().GetDimensions()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="small,medium,large", help="phantom sizes (empty: none)")
    ap.add_argument("--scan", action="append", default=[], metavar="NAME=LABELS[:SKELETON]",
                    help="a label volume of your own, prepared with SKELETON (default: auto); repeatable")
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--poses", type=int, default=5)
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-bench-")
    rows = []
    cases = [(size, None) for size in args.sizes.split(",") if size]
    cases += [tuple(entry.split("=", 1)) for entry in args.scan]
    for name, scan in cases:
        d = os.path.join(work, name)
        if scan is None:
            out, _, _ = measured_subprocess([args.repose, "phantom", "--size", name, "--out", f"{d}/phantom"])
            labels, skeleton = f"{d}/phantom/labels.nii.gz", f"{d}/phantom/skeleton.json"
        else:
            labels, _, skeleton = scan.partition(":")
            skeleton = skeleton or "auto"
        out, t_prep, mem = measured_subprocess([args.repose, "prepare", "--labels", labels, "--skeleton", skeleton,
                                                "--out", f"{d}/case"])
        st = stage_times(out)
        m = re.search(r"tet mesh: (\d+) nodes, (\d+) tets", out)
        nodes, tets = int(m.group(1)), int(m.group(2))
        dims = image_dims(f"{d}/case/labels.nii.gz")
        voxels = dims[0] * dims[1] * dims[2]
        skin, surf, vol, sl, outvox, surfverts = pose_costs(f"{d}/case", args.poses)
        rows.append((name, "x".join(map(str, dims)), voxels, nodes, tets, surfverts, st.get("mesh", 0),
                     st.get("weights", 0), st.get("surfaces", 0), st.get("binding", 0), t_prep, mem, skin * 1e3,
                     surf * 1e3, vol * 1e3, outvox / vol / 1e6, sl * 1e3))
        print(f"{name}: done", file=sys.stderr)
    print("| case | voxels | nodes | tets | surface verts | mesh s | weights s | surfaces s | binding s |"
          " prepare total s | prepare peak MiB | skin nodes ms | move surfaces ms | posed labels ms | Mvox/s |"
          " posed slice ms |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} ({r[2] / 1e6:.1f} M) | {r[3]} | {r[4]} | {r[5]} | {r[6]:.1f} | {r[7]:.1f} | {r[8]:.1f} |"
              f" {r[9]:.1f} | {r[10]:.1f} | {r[11]:.0f} | {r[12]:.1f} | {r[13]:.1f} | {r[14]:.0f} | {r[15]:.0f} | {r[16]:.1f} |")


if __name__ == "__main__":
    main()
