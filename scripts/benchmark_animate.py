#!/usr/bin/python3
"""Motion capture on a prepared case: `repose animate` with the label volume per frame, for the CMU
clips of both conversions, the walk rescaled to centimetres (its units inferred) and the same clip
read at the CMU scale (the old default: the body travels 5.6 times too far).

usage: PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 scripts/benchmark_animate.py
       [--repose build/bin/repose] [--work DIR] [--data ../shared/data] [--no-totalsegmentator]
Prints a Markdown table per case: the clip's units as animate infers them, the joints it drives, the
posing time per frame (mesh, surfaces and label volume), the largest posed volume against the grid
the rest-extent-and-body rule made before, the knee flexion range and the head's pitch against the
trunk (where the skeleton has them), wall time and peak memory."""
import argparse
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.append(os.path.join(root, "build", "lib", "python3", "dist-packages"))
sys.path.append(os.path.join(root, "Testing", "Python"))
from benchmark import measured_subprocess  # noqa: E402
from bvh_oracle import write_scaled  # noqa: E402

CMU_MM = 25.4 / 0.45


def read_points(path):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    r = vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    m = r.GetOutput()
    fixed = m.GetPointData().GetArray("FixedBone")
    return vtk_to_numpy(m.GetPoints().GetData()).copy(), None if fixed is None else vtk_to_numpy(fixed).copy()


def rest_grid(case):
    from repose import vtkReposeImageReader
    r = vtkReposeImageReader()
    r.SetFileName(f"{case}/labels.nii.gz")
    r.Update()
    img = r.GetOutput()
    m = img.GetDirectionMatrix()
    direction = np.array([[m.GetElement(i, j) for j in range(3)] for i in range(3)])
    return np.array(img.GetOrigin()), np.array(img.GetSpacing()), direction, np.array(img.GetDimensions())


def rotation_of(rest, posed):
    """Kabsch rotation taking rest points onto posed points."""
    a, b = rest - rest.mean(0), posed - posed.mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1, 1, d]) @ u.T


def frame_figures(case, out, skeleton):
    """Largest grid by the old rule, knee flexion and head pitch ranges from the posed meshes."""
    origin, spacing, direction, dims = rest_grid(case)
    rest, fixed = read_points(f"{case}/mesh.vtu")
    index = {j["name"]: i for i, j in enumerate(skeleton["joints"])}
    centre = {j["name"]: np.array(j["center"]) for j in skeleton["joints"]}
    old, knee, head = 0.0, [], []
    for name in sorted(os.listdir(f"{out}/frames")):
        if not name.startswith("mesh_"):
            continue
        posed, _ = read_points(f"{out}/frames/{name}")
        ijk = ((posed - origin) @ direction) / spacing
        lo, hi = np.minimum(np.floor(ijk.min(0)), 0) - 2, np.maximum(np.ceil(ijk.max(0)), dims - 1) + 2
        old = max(old, np.prod(hi - lo + 1))
        rot = {n: rotation_of(rest[fixed == i], posed[fixed == i]) for n, i in index.items() if (fixed == i).sum() > 3}
        if {"left_hip", "left_knee", "left_ankle"} <= rot.keys():
            thigh = rot["left_hip"] @ (centre["left_knee"] - centre["left_hip"])
            shank = rot["left_knee"] @ (centre["left_ankle"] - centre["left_knee"])
            knee.append(np.degrees(np.arccos(thigh @ shank / np.linalg.norm(thigh) / np.linalg.norm(shank))))
        skull = "head" if "head" in rot else "neck"
        if skull in rot and "spine" in rot:
            up = (rot["spine"].T @ rot[skull]) @ np.array([0, 0, 1.0])
            head.append(np.degrees(np.arctan2(-up[1], up[2])))
    rng = lambda v: f"{min(v):.0f}..{max(v):.0f}" if v else "-"
    return old, rng(knee), rng(head)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--data", default=os.path.join(root, "..", "shared", "data"))
    ap.add_argument("--no-totalsegmentator", action="store_true")
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-animate-")
    os.makedirs(work, exist_ok=True)
    exe, data = args.repose, args.data
    walk, short = f"{data}/mocap/cmu_131_01_walk.bvh", f"{data}/mocap/cmu_short_75frames.bvh"
    walk_cm = f"{work}/cmu_131_01_walk_cm.bvh"
    write_scaled(walk, walk_cm, CMU_MM / 10)

    cases = [("tiny phantom", f"{work}/tiny")]
    measured_subprocess([exe, "phantom", "--size", "tiny", "--out", f"{work}/tiny_src"])
    measured_subprocess([exe, "prepare", "--labels", f"{work}/tiny_src/labels.nii.gz", "--skeleton",
                         f"{work}/tiny_src/skeleton.json", "--out", f"{work}/tiny"])
    if not args.no_totalsegmentator:
        ts = f"{data}/totalsegmentator"
        measured_subprocess([exe, "prepare", "--labels", f"{ts}/example_seg_fast_force_split.nii.gz", "--skeleton",
                             "auto", "--image", f"{ts}/example_ct.nii.gz", "--mesh-spacing", "4", "--out", f"{work}/ts"])
        cases.append(("TotalSegmentator CT", f"{work}/ts"))
    runs = [("131_01 walk (3dsMax names)", walk, "500:700:20", []),
            ("short clip (MotionBuilder names)", short, "0:75:8", []),
            ("131_01 walk in cm", walk_cm, "500:700:20", []),
            ("131_01 in cm read as CMU units", walk_cm, "500:700:20", ["--unit-mm", f"{CMU_MM:.4f}"])]
    import json
    for label, case in cases:
        skeleton = json.load(open(f"{case}/skeleton.json"))
        print(f"\n### {label}: {len(skeleton['joints'])} joints\n")
        print("| clip | units (inferred) | joints driven | frames | posing ms mean / worst | largest posed volume "
              "| old rule | knee flexion deg | head pitch deg | wall s | peak MiB |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for name, clip, frames, extra in runs:
            out = f"{work}/{os.path.basename(case)}_{len(os.listdir(work))}"
            stdout, seconds, mib = measured_subprocess([exe, "animate", "--case", case, "--bvh", clip, "--frames", frames,
                                                        "--volumes", "--out", out, *extra])
            units = re.search(r"BVH units: ([^(;\n]+)", stdout).group(1).strip()
            driven = re.search(r"drives (\d+ of \d+) joints", stdout).group(1)
            posing = re.search(r"\(posing ([0-9.]+) ms mean, ([0-9.]+) ms worst", stdout)
            volume = re.search(r"largest posed volume (.*) = ([0-9.]+) M voxels", stdout)
            count = len([f for f in os.listdir(f"{out}/frames") if f.startswith("mesh_")])
            old, knee, head = frame_figures(case, out, skeleton)
            print(f"| {name} | {units} | {driven} | {count} | {posing.group(1)} / {posing.group(2)} | "
                  f"{volume.group(1)} = {volume.group(2)} M | {old / 1e6:.1f} M | {knee} | {head} | {seconds:.1f} | "
                  f"{mib:.0f} |")


if __name__ == "__main__":
    main()
