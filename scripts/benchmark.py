#!/usr/bin/python3
"""Repose benchmark: per-stage time and peak memory on the built-in phantom and on scans of your own
(a whole body), with voxel, node and tet counts, and the per-pose costs (skinning the nodes, moving
the surfaces, pulling the posed volume, and pulling one axial slice of it as a viewer would).

usage: PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 scripts/benchmark.py [--sizes small,medium,large]
       [--scan NAME=LABELS[:SKELETON] ...] [--repose build/bin/repose] [--work DIR] [--poses N]
       [--orderings N]
A scan is prepared as `repose prepare --labels LABELS --skeleton SKELETON` (default: auto) with the
default tet budget.
Prints a Markdown table. Preprocessing is timed through the CLI (as a user runs it), posing through
the Python-wrapped filters so that repeated poses reuse the loaded case as an interactive tool does.
The ratio columns set each posing stage against a plain peer measured in the same run by
repose_stage_peers (built beside the CLI): skinning and moving the surfaces against STREAM's triad over
the bytes each reads and writes once, the posed labels' CPU time against a one-thread gather of the rest
labels through the same pose's ready displacement field, and the posed labels' wall time (and the
gather's one-thread CPU) against their floor: the triad's time over the posed labels' bytes, written once.
The posed CT (trilinear float intensities; a stand-in on the labels' grid: the labels cast to float) is
set against a one-thread trilinear gather through the same field. The surfaces are also moved right
after the posed labels, as an app showing both does: that pass has
evicted their data from the caches.
--orderings N adds a second table: the weights' sparse Cholesky (analysis, factorization, solve of every
bone) with each fill-reducing ordering of vtkReposeBoneWeights, the fastest of N interleaved runs each."""
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


def peers_exe(repose):
    return os.path.join(os.path.dirname(repose), "repose_stage_peers")


def image_affines(image):
    """(index -> physical, physical -> index) of a vtkImageData, row-major 3x4 lists."""
    import numpy as np
    d = np.array([image.GetDirectionMatrix().GetElement(r, c) for r in range(3) for c in range(3)]).reshape(3, 3)
    m = d @ np.diag(image.GetSpacing())
    o = np.array(image.GetOrigin())
    inv = np.linalg.inv(m)
    return np.hstack([m, o[:, None]]).ravel().tolist(), np.hstack([inv, (-inv @ o)[:, None]]).ravel().tolist()


def gather_peer(exe, image, posed_field, work, repeats, linear=False):
    """CPU ms of a plain one-thread gather of `image` through the ready displacement field
    (repose_stage_peers gather), the output written once: nearest-neighbour labels, or with `linear` trilinear
    float intensities."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    rest = vtk_to_numpy(image.GetPointData().GetScalars())
    field = vtk_to_numpy(posed_field.GetPointData().GetArray("Displacement")).astype("float32")
    rest.tofile(f"{work}/rest_labels.raw")
    field.tofile(f"{work}/displacement.raw")
    _, rest_to_index = image_affines(image)
    posed_to_physical, _ = image_affines(posed_field)
    out = subprocess.run([exe, "gather", f"{work}/rest_labels.raw", "0" if linear else str(rest.dtype.itemsize),
                          *map(str, image.GetDimensions()), *map(repr, rest_to_index), f"{work}/displacement.raw",
                          *map(str, posed_field.GetDimensions()), *map(repr, posed_to_physical), str(repeats)],
                         capture_output=True, text=True, check=True).stdout
    return float(re.search(r"cpu_ms (\S+)", out).group(1))


def triad_peer(exe, nbytes, repeats=20):
    """Wall ms of STREAM's triad over `nbytes` on every hardware thread (repose_stage_peers triad)."""
    out = subprocess.run([exe, "triad", str(int(nbytes)), str(repeats)], capture_output=True, text=True,
                         check=True).stdout
    return float(re.search(r"triad ms (\S+)", out).group(1))


def array_bytes(*arrays):
    return sum(a.GetNumberOfValues() * a.GetDataTypeSize() for a in arrays)


def pose_costs(case, poses, repose=None, work=None):
    """Loads a prepared case in the filters and times `poses` different poses; with `repose` (the CLI, beside
    which repose_stage_peers is built) also the stages' peers, measured in the same run."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkCommonExecutionModel import vtkTrivialProducer
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

    def posed_volume(image_port, linear=False):
        v = vtkReposePosedVolume()
        for port, source in enumerate((image_port, mr.GetOutputPort(), sk.GetOutputPort())):
            v.SetInputConnection(port, source)
        v.SetInterpolation(v.Linear if linear else v.Nearest)
        return v

    vo = posed_volume(lr.GetOutputPort())
    # One axial slice through the middle, as a viewer showing the posed labels would request it.
    vs = posed_volume(lr.GetOutputPort())
    vs.RestrictToSubExtentOn()
    # Posed intensities (trilinear, float) of a stand-in CT on the labels' grid: the labels as float (built
    # by hand: VTK 9.1's vtkImageCast drops the direction matrix).
    ct = vtkTrivialProducer()
    ct_image = vtkImageData()
    ct_image.CopyStructure(lr.GetOutput())
    ct_image.GetPointData().SetScalars(numpy_to_vtk(vtk_to_numpy(lr.GetOutput().GetPointData().GetScalars())
                                                    .astype("float32"), deep=1))
    ct.SetOutput(ct_image)
    vc = posed_volume(ct.GetOutputPort(), linear=True)
    skin, surf, vol, sl, skincpu, volcpu, after, ctw, ctcpu, voxels = [], [], [], [], [], [], [], [], [], 0
    for i in range(poses + 1):
        a = 10 + 50 * i / max(poses, 1)
        rotations = {"left_hip": {"axis": [1, 0, 0], "degrees": -a}, "left_knee": {"axis": [1, 0, 0], "degrees": a},
                     "right_shoulder": {"axis": [0, 1, 0], "degrees": a},
                     "right_elbow": {"axis": [1, 0, 0], "degrees": -a}}
        sk.SetPoseJSON(json.dumps({"rotations": {k: v for k, v in rotations.items() if k in joints}}))
        c0 = time.process_time(); t = time.perf_counter(); sk.Update(); t1 = time.perf_counter(); c1 = time.process_time()
        de.Update(); t2 = time.perf_counter()
        c2 = time.process_time(); vo.Update(); t3 = time.perf_counter(); c3 = time.process_time()
        e = list(vo.GetFullOutputExtent())
        e[4] = e[5] = e[5] // 2
        vs.SetOutputSubExtent(e)
        t4 = time.perf_counter(); vs.Update(); t5 = time.perf_counter()
        # The surfaces moved again right after the posed volume, whose pass has evicted them from the caches.
        de.Modified(); t6 = time.perf_counter(); de.Update(); t7 = time.perf_counter()
        c8 = time.process_time(); t8 = time.perf_counter(); vc.Update(); t9 = time.perf_counter(); c9 = time.process_time()
        if i == 0:
            continue  # first pose pays one-off costs (weights conversion, binding cache)
        skin.append(t1 - t); surf.append(t2 - t1); vol.append(t3 - t2); sl.append(t5 - t4); after.append(t7 - t6)
        ctw.append(t9 - t8); ctcpu.append(c9 - c8)
        skincpu.append(c1 - c0); volcpu.append(c3 - c2)
        voxels = vo.GetOutput().GetNumberOfPoints()
    med = lambda v: sorted(v)[len(v) // 2]
    costs = dict(skin=med(skin), surf=med(surf), vol=med(vol), slice=med(sl), skincpu=med(skincpu), volcpu=med(volcpu),
                 surf_after_volume=med(after), ct=med(ctw), ctcpu=med(ctcpu), voxels=voxels,
                 surfverts=sr.GetOutput().GetNumberOfPoints())
    if repose:
        # The peers, on the last pose: the gather through that pose's displacement field, the triads over
        # the bytes each stage reads and writes once (rest nodes, weights, bone ids and posed nodes; the
        # surface's binding, the posed nodes and the moved points).
        fo = vtkReposePosedVolume()
        for port in range(3):
            fo.SetInputConnection(port, vo.GetInputConnection(port, 0))
        fo.OutputDisplacementOn()
        fo.Update()
        exe = peers_exe(repose)
        costs["gather"] = gather_peer(exe, lr.GetOutput(), fo.GetOutput(), work, poses) / 1e3
        costs["gather_ct"] = gather_peer(exe, ct_image, fo.GetOutput(), work, poses, linear=True) / 1e3
        rest, posed, surface = mr.GetOutput(), sk.GetOutput(), de.GetOutput()
        costs["skin_triad"] = triad_peer(exe, array_bytes(
            rest.GetPoints().GetData(), rest.GetPointData().GetArray("Weights"),
            rest.GetPointData().GetArray("BoneIds"), posed.GetPoints().GetData())) / 1e3
        costs["surf_triad"] = triad_peer(exe, array_bytes(
            sr.GetOutput().GetPointData().GetArray("BoundTet"), sr.GetOutput().GetPointData().GetArray("BoundWeights"),
            posed.GetPoints().GetData(), surface.GetPoints().GetData())) / 1e3
        # The posed labels' floor: their output written once, at the triad's bandwidth.
        costs["vol_floor"] = triad_peer(exe, array_bytes(vo.GetOutput().GetPointData().GetScalars())) / 1e3
    return costs


ORDERINGS = ("AUTOMATIC", "AMD", "METIS", "CHOLMOD_DEFAULT")


def ordering_costs(case, repeats):
    """Weights of a prepared case per ordering: {ordering: (analysis s, factorization s, solve s, used, GFlop,
    nnz(L), process CPU s of the whole filter)}, the fastest of `repeats` runs taken in turn (a change of load
    then touches every ordering alike; the fastest is the one least disturbed by it)."""
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from repose import vtkReposeBoneWeights
    mr = vtkXMLUnstructuredGridReader()
    mr.SetFileName(f"{case}/mesh.vtu")
    mr.Update()
    skeleton = open(f"{case}/skeleton.json").read()
    runs = {o: [] for o in ORDERINGS}
    for _ in range(repeats):
        for o in ORDERINGS:
            w = vtkReposeBoneWeights()
            w.SetInputData(mr.GetOutput())
            w.SetSkeletonJSON(skeleton)
            w.SetOrdering(getattr(vtkReposeBoneWeights, o))
            c = time.process_time()
            w.Update()
            c = time.process_time() - c
            runs[o].append((w.GetAnalysisTime(), w.GetFactorizationTime() - w.GetAnalysisTime(), w.GetSolveTime(),
                            w.GetOrderingName(), w.GetFactorizationFlops() / 1e9, w.GetFactorNonzeros(), c))
    return {o: min(v, key=lambda r: r[0] + r[1] + r[2]) for o, v in runs.items()}, w.GetNumberOfFreeNodes()


def print_orderings(rows):
    print("\n| case | free nodes | ordering | used | GFlop | nnz(L) M | analysis s | factorization s | solve s |"
          " total s | vs fastest | filter CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, costs, free in rows:
        fastest = min(sum(c[:3]) for c in costs.values())
        for o, (a, f, s, used, gflop, lnz, cpu) in costs.items():
            print(f"| {name} | {free} | {o.lower()} | {used} | {gflop:.1f} | {lnz / 1e6:.1f} | {a:.3f} | {f:.3f} |"
                  f" {s:.3f} | {a + f + s:.3f} | {(a + f + s) / fastest:.2f} | {cpu:.2f} |")


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
    ap.add_argument("--orderings", type=int, default=0, metavar="N",
                    help="also time the weights per fill-reducing ordering, fastest of N runs (0: not)")
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-bench-")
    rows, orderings = [], []
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
        c = pose_costs(f"{d}/case", args.poses, args.repose, d)
        rows.append((name, "x".join(map(str, dims)), voxels, nodes, tets, c["surfverts"], st.get("mesh", 0),
                     st.get("weights", 0), st.get("surfaces", 0), st.get("binding", 0), t_prep, mem, c["skin"] * 1e3,
                     c["surf"] * 1e3, c["vol"] * 1e3, c["voxels"] / c["vol"] / 1e6, c["slice"] * 1e3,
                     c["skin"] / c["skin_triad"], c["surf"] / c["surf_triad"], c["volcpu"] / c["gather"],
                     c["surf_after_volume"] * 1e3, c["vol"] / c["vol_floor"], c["gather"] / c["vol_floor"],
                     c["ct"] * 1e3, c["ctcpu"] / c["gather_ct"]))
        if args.orderings > 0:
            costs, free = ordering_costs(f"{d}/case", args.orderings)
            orderings.append((name, costs, free))
        print(f"{name}: done", file=sys.stderr)
    print("| case | voxels | nodes | tets | surface verts | mesh s | weights s | surfaces s | binding s |"
          " prepare total s | prepare peak MiB | skin nodes ms | move surfaces ms | posed labels ms | Mvox/s |"
          " posed slice ms | skin / triad | move / triad | posed labels CPU / gather CPU |"
          " move surfaces after posed labels ms | posed labels / floor | gather CPU / floor | posed CT ms |"
          " posed CT CPU / trilinear gather CPU |")
    print("|---" * 24 + "|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} ({r[2] / 1e6:.1f} M) | {r[3]} | {r[4]} | {r[5]} | {r[6]:.1f} | {r[7]:.1f} | {r[8]:.1f} |"
              f" {r[9]:.1f} | {r[10]:.1f} | {r[11]:.0f} | {r[12]:.1f} | {r[13]:.1f} | {r[14]:.0f} | {r[15]:.0f} | {r[16]:.1f} |"
              f" {r[17]:.1f} | {r[18]:.1f} | {r[19]:.1f} | {r[20]:.1f} | {r[21]:.1f} | {r[22]:.1f} |"
              f" {r[23]:.0f} | {r[24]:.1f} |")

    if orderings:
        print_orderings(orderings)


if __name__ == "__main__":
    main()
