#!/usr/bin/python3
"""Repose batch benchmark: one manifest (the built-in phantom and the TotalSegmentator CT, N poses each)
run by `repose batch` on a local Dask cluster of 1, 2, ... workers: the whole batch (each subject
prepared, then posed) and the posing alone (the prepared cases kept, the poses run again).

usage: /usr/bin/python3 scripts/benchmark_batch.py [--repose build/bin/repose] [--workers 1,2] [--poses 4]
       [--size small] [--data ../shared/data] [--work DIR]
Prints a Markdown table. "posing span" runs from the first pose's start to the last pose's end (no
cluster start); poses per minute are counted over it. One worker runs the filters on every core, N
workers one task each on cores/N threads."""
import argparse
import csv
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Hip poses both skeletons have (the phantom's and the TotalSegmentator case's): flexion, abduction.
POSES = [{"left_hip": ([1, 0, 0], -45)}, {"right_hip": ([0, 1, 0], -15)},
         {"left_hip": ([1, 0, 0], -30), "right_hip": ([1, 0, 0], 20)}, {"right_hip": ([1, 0, 0], -60)},
         {"left_hip": ([0, 1, 0], 20)}, {"left_hip": ([0, 0, 1], 25), "right_hip": ([0, 0, 1], -25)}]


def run(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}")
    return time.perf_counter() - t0


def write_manifest(work, args):
    run([args.repose, "phantom", "--out", os.path.join(work, "phantom"), "--size", args.size])
    poses = []
    for i, rotations in enumerate(POSES[:args.poses]):
        poses.append(os.path.join(work, f"pose{i + 1}.json"))
        with open(poses[-1], "w") as f:
            json.dump({"rotations": {j: {"axis": a, "degrees": d} for j, (a, d) in rotations.items()}}, f)
    ts = os.path.join(args.data, "totalsegmentator")
    manifest = {"subjects": [
        {"name": f"phantom_{args.size}", "labels": "phantom/labels.nii.gz", "skeleton": "phantom/skeleton.json",
         "poses": poses},
        {"name": "totalsegmentator", "labels": os.path.join(ts, "example_seg_fast_force_split.nii.gz"),
         "image": os.path.join(ts, "example_ct.nii.gz"), "prepare": {"mesh_spacing": 6}, "poses": poses,
         "skeleton": os.path.join(root, "Testing", "Data", "totalsegmentator_skeleton.json")}]}
    path = os.path.join(work, "batch.json")
    with open(path, "w") as f:
        json.dump(manifest, f, indent=2)
    return path


def posing_figures(out):
    """(posing span in s, poses done, median seconds per pose task) from DIR/batch.csv."""
    with open(os.path.join(out, "batch.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r["kind"] == "pose" and r["ran"] == "this"]
    if not rows or any(r["status"] != "done" for r in rows):
        sys.exit(f"{out}/batch.csv: a pose failed or none ran")
    start = min(datetime.fromisoformat(r["started"]) for r in rows)
    end = max(datetime.fromisoformat(r["finished"]) for r in rows)
    return (end - start).total_seconds(), len(rows), statistics.median(float(r["seconds"]) for r in rows)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    p.add_argument("--workers", default="1,2")
    p.add_argument("--poses", type=int, default=4, choices=range(1, len(POSES) + 1))
    p.add_argument("--size", default="small", choices=("tiny", "small", "medium"))
    p.add_argument("--data", default=os.path.join(os.path.dirname(root), "shared", "data"))
    p.add_argument("--work")
    args = p.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="repose-benchmark-batch-")
    os.makedirs(work, exist_ok=True)
    manifest = write_manifest(work, args)
    print(f"2 subjects (phantom {args.size}, TotalSegmentator CT at 6 mm mesh spacing) x {args.poses} poses; "
          f"outputs labels, mesh, surfaces (+ CT); {os.cpu_count()} cores\n")
    print("| workers | whole batch (2 prepares + poses) | posing only, wall | posing span | poses per minute "
          "| median pose task |")
    print("|---|---|---|---|---|---|")
    for workers in (int(w) for w in args.workers.split(",")):
        out = os.path.join(work, f"out_{workers}")
        shutil.rmtree(out, ignore_errors=True)
        whole = run([args.repose, "batch", manifest, "--out", out, "--workers", str(workers)])
        for subject in os.listdir(out):
            shutil.rmtree(os.path.join(out, subject, "poses"), ignore_errors=True)
        posing = run([args.repose, "batch", manifest, "--out", out, "--workers", str(workers)])
        span, count, median = posing_figures(out)
        print(f"| {workers} | {whole:.1f} s | {posing:.1f} s | {span:.1f} s | {60 * count / span:.1f} "
              f"| {median:.2f} s |", flush=True)
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
