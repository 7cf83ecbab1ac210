#!/usr/bin/python3
"""Surface meshes -> label volume (repose voxelize) on the Visible Human meshes as the atlas ships
them: skin, sacrum, coccyx, hip bones, femurs, patellae, tibiae, fibulae.

usage: /usr/bin/python3 scripts/benchmark_voxelize.py [--data ../shared/data/visible_human]
       [--subjects female male] [--voxels 3 2] [--repose build/bin/repose] [--work DIR]
Each case runs the CLI once under /usr/bin/time -v, as a user runs it. Prints two Markdown tables:
per case (grid, voxelizing time, wall and CPU time, peak memory) and per part (triangles, what was
repaired, voxel volume against the mesh's, the bone's solid volume with its hollows filled, seconds)."""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BONES = ["sacrum", "coccyx", "hip_left", "hip_right", "femur_left", "femur_right", "patella_left", "patella_right",
         "tibia_left", "tibia_right", "fibula_left", "fibula_right"]
PART = re.compile(r"^\s+\d+ (\S+) \((\w+), .*?\): (\d+) triangles, (.*): (?:shell )?(\d+) voxels, ([\d.]+ (?:ml|L)) "
                  r"\(the mesh encloses (?:about )?([\d.]+ (?:ml|L))\)(?:, solid \d+ voxels, ([\d.]+ (?:ml|L)))?; ([\d.]+) s$")


def timed(cmd):
    """Runs cmd under /usr/bin/time -v: (stdout, wall s, CPU s, peak MB)."""
    p = subprocess.run(["/usr/bin/time", "-v", *map(str, cmd)], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed:\n{p.stdout}\n{p.stderr}")

    def field(name):
        return re.search(rf"{name}: (.*)", p.stderr).group(1).strip()

    wall = 0.0
    for part in field(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\)").split(":"):
        wall = 60 * wall + float(part)
    cpu = float(field(r"User time \(seconds\)")) + float(field(r"System time \(seconds\)"))
    return p.stdout, wall, cpu, int(field(r"Maximum resident set size \(kbytes\)")) / 1024


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", default=os.path.join(root, "..", "shared", "data", "visible_human"))
    ap.add_argument("--subjects", nargs="+", default=["female", "male"])
    ap.add_argument("--voxels", nargs="+", type=float, default=[3.0, 2.0])
    ap.add_argument("--repose", default=os.path.join(root, "build", "bin", "repose"))
    ap.add_argument("--work")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="repose_voxelize_")
    cases, parts = [], []
    for subject in a.subjects:
        d = os.path.join(a.data, subject)
        for voxel in a.voxels:
            out = os.path.join(work, f"{subject}_{voxel:g}", "labels.nii.gz")
            cmd = [a.repose, "voxelize", "--skin", os.path.join(d, "skin.ply"), "--voxel", voxel, "--out", out]
            for b in BONES:
                cmd += ["--bone", f"{b}={os.path.join(d, b + '.ply')}"]
            stdout, wall, cpu, peak = timed(cmd)
            grid = re.search(r"grid (\d+x\d+x\d+) voxels", stdout).group(1)
            voxelizing = float(re.search(r"voxelizing ([\d.]+) s", stdout).group(1))
            skin = bones = 0.0
            for line in stdout.splitlines():
                m = PART.match(line)
                if not m:
                    continue
                name, role, triangles, repairs, _, volume, mesh, solid, seconds = m.groups()
                if role == "skin":
                    skin += float(seconds)
                else:
                    bones += float(seconds)
                if voxel == a.voxels[0]:
                    parts.append((subject, name, triangles, repairs, volume, mesh, solid or volume, seconds))
            cases.append((subject, voxel, grid, skin, bones, voxelizing, wall, cpu, peak))
    print(f"\nrepose voxelize, Visible Human skin + {len(BONES)} bones\n")
    print("| subject | voxel (mm) | grid | skin (s) | bones (s) | voxelizing (s) | wall (s) | CPU (s) | peak memory (MB) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for s, v, g, sk, bo, vz, w, c, p in cases:
        print(f"| {s} | {v:g} | {g} | {sk:.2f} | {bo:.2f} | {vz:.2f} | {w:.2f} | {c:.2f} | {p:.0f} |")
    print(f"\nper part at {a.voxels[0]:g} mm\n")
    print("| subject | part | triangles | repaired | voxel volume | mesh volume | solid volume | seconds |")
    print("|---|---|---|---|---|---|---|---|")
    for row in parts:
        print("| " + " | ".join(row) + " |")
    if not a.work:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
