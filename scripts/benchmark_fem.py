#!/usr/bin/python3
"""Repose FEM relaxation benchmark: time per pose, Newton and CG iterations, inverted tets, volume ratio
and peak memory of the corotational relaxation on the built-in phantoms, per linear solver.

usage: PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 scripts/benchmark_fem.py
       [--sizes small,medium] [--solvers block,twolevel,jacobi,ic,cholmod] [--models fixed,linear]
       [--volumes segments,tissues,body,none] [--guards barrier,penalty] [--continuations if-inverted,never,always]
       [--repose build/bin/repose] [--work DIR] [--angle DEG] [--warm DEG]
Each (size, model, solver) runs in its own process so that its peak resident memory is its own; the
"skin only" row is the same process without the relaxation (the memory the FEM adds is the difference).
--warm DEG adds, per row, the pose DEG degrees short of --angle solved first and the pose itself then
warm-started from its correction (vtkReposeCorotationalRelax::WarmStart, as animate does frame to
frame); the figures are those of the second solve.
Prints a Markdown table."""
import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The built Python package, unless PYTHONPATH already names one (children inherit it).
_package = os.path.join(root, "build", "lib", "python3", "dist-packages")
sys.path.append(_package)
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (os.environ.get("PYTHONPATH"), _package) if p)
SOLVERS = {"jacobi": 0, "ic": 1, "cholmod": 2, "block": 3, "twolevel": 4}
MODELS = {"linear": 0, "fixed": 1}
VOLUMES = {"none": 0, "body": 1, "segments": 2, "tissues": 3}
GUARDS = {"penalty": 0, "barrier": 1}
CONTINUATIONS = {"never": 0, "if-inverted": 1, "always": 2}
STRAINED = {"first": 1e-4, "off": 0.0}


def pose_json(angle):
    """A walking-like pose: one leg forward with the knee bent, the other back, the arms swinging."""
    a = angle
    return json.dumps({"rotations": {
        "left_hip": {"axis": [1, 0, 0], "degrees": -a}, "left_knee": {"axis": [1, 0, 0], "degrees": a},
        "right_hip": {"axis": [1, 0, 0], "degrees": 0.5 * a},
        "right_shoulder": {"axis": [0, 1, 0], "degrees": a}, "right_elbow": {"axis": [1, 0, 0], "degrees": -a}}})


def child(case, model, solver, angle, volume, barrier=1, continuation=1, warm=0.0, strained=1e-4):
    """Skins the case to the pose, then relaxes it (model/solver < 0: skinning only); prints one JSON line."""
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from repose import vtkReposeCorotationalRelax, vtkReposeSkinning
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    mr = vtkXMLUnstructuredGridReader()
    mr.SetFileName(f"{case}/mesh.vtu")
    mr.Update()
    rest = mr.GetOutput()
    sk = vtkReposeSkinning()
    sk.SetInputConnection(mr.GetOutputPort())
    sk.SetSkeletonJSON(open(f"{case}/skeleton.json").read())
    sk.SetPoseJSON(pose_json(angle - warm if warm > 0 else angle))
    sk.Update()
    result = {"nodes": rest.GetNumberOfPoints(), "tets": rest.GetNumberOfCells()}
    posed = sk.GetOutput()
    if model >= 0:
        fem = vtkReposeCorotationalRelax()
        fem.SetInputConnection(0, sk.GetOutputPort())
        fem.SetInputData(1, rest)
        fem.SetModel(model)
        fem.SetPreconditioner(solver)
        fem.SetVolumeRegions(volume)
        fem.SetInversionBarrier(bool(barrier))
        fem.SetContinuation(continuation)
        fem.SetStrainedRegionThreshold(strained)
        fem.SetSkeletonJSON(open(f"{case}/skeleton.json").read())
        fem.SetMaxIterations(20000)
        if warm > 0:  # the pose before, then the pose itself from its correction
            fem.WarmStartOn()
            t = time.perf_counter()
            fem.Update()
            result["previous_seconds"] = time.perf_counter() - t
            sk.SetPoseJSON(pose_json(angle))
        t = time.perf_counter()
        fem.Update()
        result.update(seconds=time.perf_counter() - t, cg=fem.GetCGIterations(), newton=fem.GetNewtonIterations(),
                      before=fem.GetInvertedBefore(), after=fem.GetInvertedAfter(),
                      rigid=fem.GetInvertedRigidAfter(), pinched=fem.GetPinchedNodes(), assembly=fem.GetLastAssemblyTime(),
                      solve=fem.GetLastSolveTime(), untangle=fem.GetLastUntangleTime(),
                      untangle_newton=fem.GetUntangleNewtonIterations(),
                      continuation=fem.GetContinuationSteps() if fem.GetContinuationUsed() else -fem.GetContinuationSteps(),
                      continuation_s=fem.GetLastContinuationTime(), warm_started=fem.GetWarmStarted(),
                      strained_nodes=fem.GetStrainedRegionNodes(), strained_newton=fem.GetStrainedRegionNewtonIterations(),
                      strained_s=fem.GetLastStrainedRegionTime())
        posed = fem.GetOutput()
    cells = vtk_to_numpy(rest.GetCells().GetConnectivityArray()).reshape(-1, 4)

    def volume(points):
        p = vtk_to_numpy(points.GetData()).astype(np.float64)[cells]
        return np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])).sum() / 6

    result["volume_ratio"] = volume(posed.GetPoints()) / volume(rest.GetPoints())
    result["peak_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print("@@" + json.dumps(result))


def run_child(case, model, solver, angle, volume=2, barrier=1, continuation=1, warm=0.0, strained=1e-4):
    p = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", case, str(model), str(solver), str(angle),
                        str(volume), str(barrier), str(continuation), str(warm), str(strained)],
                       capture_output=True, text=True)
    m = re.search(r"^@@(.*)$", p.stdout, re.M)
    if p.returncode != 0 or not m:
        return None, (p.stderr.strip().splitlines() or ["failed"])[-1]
    return json.loads(m.group(1)), ""


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), int(sys.argv[6]),
              int(sys.argv[7]), int(sys.argv[8]), float(sys.argv[9]), float(sys.argv[10]) if len(sys.argv) > 10 else 1e-4)
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="small,medium")
    ap.add_argument("--solvers", default="twolevel,block")
    ap.add_argument("--models", default="fixed")
    ap.add_argument("--volumes", default="segments", help="region volume terms of the fixed-corotated model")
    ap.add_argument("--guards", default="barrier", help="inversion guard of the fixed-corotated model: barrier, penalty")
    ap.add_argument("--continuations", default="if-inverted",
                    help="fold-free continuation of the fixed-corotated model: if-inverted, never, always")
    ap.add_argument("--strained", default="first",
                    help="the fixed-corotated model's strained region: first (relaxed on its own before the whole"
                         " mesh, the default), off; a comma list compares them")
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work", default=None, help="reuses <work>/<size>/case when it exists")
    ap.add_argument("--angle", type=float, default=45.0, help="hip/knee/shoulder/elbow angle of the pose (degrees)")
    ap.add_argument("--warm", type=float, default=0.0,
                    help="also solve the pose this many degrees short first and warm-start from it (0: off)")
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-bench-fem-")
    rows = []
    for size in args.sizes.split(","):
        d = os.path.join(work, size)
        case = f"{d}/case"
        if not os.path.isfile(f"{case}/mesh.vtu"):
            for cmd in ([args.repose, "phantom", "--size", size, "--out", f"{d}/phantom"],
                        [args.repose, "prepare", "--labels", f"{d}/phantom/labels.nii.gz",
                         "--skeleton", f"{d}/phantom/skeleton.json", "--out", case]):
                p = subprocess.run(cmd, capture_output=True, text=True)
                if p.returncode != 0:
                    sys.exit(f"{' '.join(cmd)} failed:\n{p.stdout}\n{p.stderr}")
        base, err = run_child(case, -1, -1, args.angle)
        if base is None:
            sys.exit(f"{size}: skinning failed: {err}")
        rows.append((size, "skin only", "", "", base, ""))
        for model in args.models.split(","):
            for guard in args.guards.split(",") if model == "fixed" else ["barrier"]:
                for continuation in args.continuations.split(",") if model == "fixed" and guard == "barrier" else ["never"]:
                    label = model if guard == "barrier" else f"{model} ({guard})"
                    if model == "fixed" and continuation != "if-inverted":
                        label += f", continuation {continuation}"
                    for volume in args.volumes.split(",") if model == "fixed" else ["none"]:
                        for strained in args.strained.split(",") if model == "fixed" else ["off"]:
                            if strained not in STRAINED:
                                sys.exit(f"--strained: {strained} is not one of {', '.join(STRAINED)}")
                            label_s = label + (", strained region not first" if model == "fixed" and strained == "off" else "")
                            for solver in args.solvers.split(","):
                                r, err = run_child(case, MODELS[model], SOLVERS[solver], args.angle, VOLUMES[volume],
                                                   GUARDS[guard], CONTINUATIONS[continuation], args.warm, STRAINED[strained])
                                if r and args.warm > 0:
                                    label_w = f"{label_s}, warm from {args.angle - args.warm:g} deg"
                                    label_w += "" if r["warm_started"] else " (not taken)"
                                    label_w += f" (that pose: {r['previous_seconds']:.1f} s)"
                                    rows.append((size, label_w, volume, solver, r, err))
                                    continue
                                rows.append((size, label_s, volume, solver, r or base, err))
                                print(f"{size} {label_s} {volume} {solver}: {'done' if r else err}", file=sys.stderr)
    print("| size | nodes | tets | model | regions | solver | FEM s / pose | strained region nodes (Newton its, s) | assembly s | solves s | untangle s (neighbourhood Newton its) |"
          " continuation steps (s) | Newton its | CG its | inverted before -> after (only bone nodes; pinched nodes) | volume ratio |"
          " peak MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for size, model, volume, solver, r, err in rows:
        if err:
            print(f"| {size} | {r['nodes']} | {r['tets']} | {model} | {volume} | {solver} | failed: {err} | | | | | | | | | | |")
        elif "seconds" not in r:
            print(f"| {size} | {r['nodes']} | {r['tets']} | {model} | | | | | | | | | | | | {r['volume_ratio']:.4f} |"
                  f" {r['peak_mib']:.0f} |")
        else:
            print(f"| {size} | {r['nodes']} | {r['tets']} | {model} | {volume} | {solver} | {r['seconds']:.2f} |"
                  f" {strained_cell(r)} | {r['assembly']:.2f} | {r['solve']:.2f} | {r['untangle']:.2f} ({r['untangle_newton']}) | {continuation_cell(r)} | {r['newton']} |"
                  f" {r['cg']} | {r['before']} -> {r['after']} ({r['rigid']}; {r['pinched']}) | {r['volume_ratio']:.4f} |"
                  f" {r['peak_mib']:.0f} |")


def strained_cell(r):
    """Unknowns, Newton steps and seconds of the strained region's own solve ("-": not run)."""
    if r.get("strained_nodes", 0) == 0:
        return "-"
    return f"{r['strained_nodes']} ({r['strained_newton']}, {r['strained_s']:.1f} s)"


def continuation_cell(r):
    """Steps and seconds of the fold-free continuation; "not kept" when the direct result stayed."""
    steps = r.get("continuation", 0)
    if steps == 0:
        return "-"
    return f"{abs(steps)} ({r['continuation_s']:.1f} s{'' if steps > 0 else ', not kept'})"


if __name__ == "__main__":
    main()
