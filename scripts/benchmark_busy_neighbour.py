#!/usr/bin/python3
"""Repose beside a busy neighbour: the posing stages (skinning the nodes, the posed labels) and the weights'
solve on a prepared case, with the machine as it is and then with one core kept busy by a spinning process,
on 1 and 2 threads; prints each stage's slowdown in wall time and in the process's CPU time. Losing a core
to a neighbour costs wall time; a runtime that spin-waits for its threads (an OpenMP barrier, a BLAS pool
yielding in a loop) also burns CPU while it waits, so its CPU time grows too.

usage: PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 scripts/benchmark_busy_neighbour.py
       [--size small] [--case DIR] [--threads 1,2] [--rounds 3] [--poses 5] [--repose build/bin/repose] [--work DIR]
The library's threads are vtkSMPTools' (TBB), counted by VTK_SMP_MAX_THREADS; CHOLMOD's BLAS by
OPENBLAS_NUM_THREADS: both are set to the thread count of each run. Each run is a process of its own, the
runs interleaved (idle, busy, idle, busy, ...) over the rounds and each figure the median over them.
Prints a Markdown table."""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
_package = os.path.join(root, "build", "lib", "python3", "dist-packages")
sys.path.append(_package)
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (os.environ.get("PYTHONPATH"), _package) if p)
STAGES = (("skin", "skin nodes", "ms", 1e3), ("vol", "posed labels", "ms", 1e3), ("weights", "weights solve", "s", 1.0))


def child(case, poses):
    """Times the stages in this process; prints one JSON line."""
    from benchmark import pose_costs
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from repose import vtkReposeBoneWeights
    costs = pose_costs(case, poses)
    mr = vtkXMLUnstructuredGridReader()
    mr.SetFileName(f"{case}/mesh.vtu")
    mr.Update()
    w = vtkReposeBoneWeights()
    w.SetInputData(mr.GetOutput())
    w.SetSkeletonJSON(open(f"{case}/skeleton.json").read())
    c = time.process_time()
    w.Update()
    c = time.process_time() - c
    print(json.dumps({"skin": costs["skin"], "vol": costs["vol"], "weights": w.GetFactorizationTime() + w.GetSolveTime(),
                      "skincpu": costs["skincpu"], "volcpu": costs["volcpu"], "weightscpu": c}))


def run(case, threads, busy, poses):
    env = dict(os.environ, VTK_SMP_MAX_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads),
               OMP_NUM_THREADS=str(threads))
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"]) if busy else None
    try:
        if spinner:
            time.sleep(0.2)  # the spinner is running before the stages start
        out = subprocess.run([sys.executable, __file__, "--child", case, "--poses", str(poses)], env=env,
                             capture_output=True, text=True)
    finally:
        if spinner:
            spinner.kill()
            spinner.wait()
    if out.returncode != 0:
        sys.exit(f"benchmark child failed:\n{out.stderr}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="small", help="phantom size prepared when --case is not given")
    ap.add_argument("--case", help="a prepared case directory (repose prepare --out)")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--poses", type=int, default=5)
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.child, args.poses)
    case = args.case
    if not case:
        work = args.work or tempfile.mkdtemp(prefix="repose-busy-")
        subprocess.run([args.repose, "phantom", "--size", args.size, "--out", f"{work}/phantom"], check=True,
                       capture_output=True)
        subprocess.run([args.repose, "prepare", "--labels", f"{work}/phantom/labels.nii.gz", "--skeleton",
                        f"{work}/phantom/skeleton.json", "--out", f"{work}/case"], check=True, capture_output=True)
        case = f"{work}/case"
    threads = [int(t) for t in args.threads.split(",")]
    load = os.getloadavg()[0]
    runs = {(t, busy): [] for t in threads for busy in (False, True)}
    for r in range(args.rounds):
        for t in threads:
            for busy in (False, True):
                runs[(t, busy)].append(run(case, t, busy, args.poses))
        print(f"round {r + 1} of {args.rounds} done", file=sys.stderr)
    med = lambda v: sorted(v)[len(v) // 2]
    print(f"load average before: {load:.1f} on {os.cpu_count()} cores\n")
    print("| stage | threads | time as is | one core busy | slowdown | CPU as is | one core busy | CPU ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for key, name, unit, scale in STAGES:
        for t in threads:
            idle, busy, idlecpu, busycpu = (med([x[k] for x in runs[(t, b)]]) * scale
                                            for k, b in ((key, False), (key, True), (key + "cpu", False),
                                                         (key + "cpu", True)))
            print(f"| {name} | {t} | {idle:.3g} {unit} | {busy:.3g} {unit} | {busy / idle:.2f} | {idlecpu:.3g} {unit} |"
                  f" {busycpu:.3g} {unit} | {busycpu / idlecpu:.2f} |")


if __name__ == "__main__":
    main()
