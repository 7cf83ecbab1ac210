"""repose pose --relax on the tiny phantom: the corotational FEM solve keeps the bone nodes exactly at
their rigid (skinned) positions, converges (relative residual <= 1e-6), inverts no more tets than
skinning did, and moves the tissue's volume towards the rest volume compared with plain LBS."""
import os
import re
import shutil
import sys

import numpy as np

from repose_testing import TEMP, TESTING, TINY, Mesh, check, run

failures = []
out = os.path.join(TEMP, "relax")
shutil.rmtree(out, ignore_errors=True)
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
_, text, _ = run("pose", "--case", f"{TINY}/case", "--pose", pose, "--skinning", "lbs", "--relax", "--out", f"{out}/fem")
print(text)
m = re.search(r"(\d+) CG iterations, relative residual (\S+), inverted tets (\d+) -> (\d+)", text)
check(m is not None, "the relaxation reports CG iterations, residual and inverted tets", failures)
iterations, residual, before, after = int(m.group(1)), float(m.group(2)), int(m.group(3)), int(m.group(4))
check(residual <= 1e-6, f"CG converged: {iterations} iterations, relative residual {residual:.1e}", failures)
check(after <= before, f"inverted tets {before} after skinning -> {after} after relaxation", failures)


rest_mesh = Mesh(f"{TINY}/case/mesh.vtu")
rest, tets = rest_mesh.points, rest_mesh.tets
fixed = rest_mesh.point_array("FixedBone") >= 0
skinned = Mesh(f"{TINY}/posed_lbs/posed_mesh.vtu").points
relaxed = Mesh(f"{out}/fem/posed_mesh.vtu").points



def volume(p):
    q = p[tets]
    return np.einsum("ij,ij->i", q[:, 1] - q[:, 0], np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 0])).sum() / 6


moved = np.abs(relaxed[fixed] - skinned[fixed]).max()
check(moved < 1e-3, f"bone nodes stay at their rigid positions (max shift {moved:.1e} mm)", failures)
check(np.abs(relaxed[~fixed] - skinned[~fixed]).max() > 0.1, "the soft tissue moved", failures)
v0, vl, vf = volume(rest), volume(skinned), volume(relaxed)
print(f"mesh volume ratio: LBS {vl / v0:.5f}, LBS+FEM {vf / v0:.5f}")
check(abs(vf / v0 - 1) <= abs(vl / v0 - 1) + 1e-4, f"FEM keeps the volume at least as well as LBS "
      f"({vf / v0:.5f} vs {vl / v0:.5f})", failures)
# The fidelity report: one row per method, and its plot.
run("pose", "--case", f"{TINY}/case", "--pose", pose, "--compare", "lbs,dqs,dqs+fem", "--out", f"{out}/compare")
import csv
rows = list(csv.DictReader(open(f"{out}/compare/fidelity.csv")))
check([r["method"] for r in rows] == ["lbs", "dqs", "dqs+fem"] and os.path.getsize(f"{out}/compare/fidelity.png") > 1000,
      "fidelity.csv has a row per method and fidelity.png is drawn", failures)
by = {r["method"]: r for r in rows}
check(abs(float(by["lbs"]["body_volume_ratio"]) - vl / v0) < 1e-6,
      "fidelity.csv's LBS volume ratio matches the posed mesh", failures)
check(float(by["dqs+fem"]["mean_abs_detF_minus_1"]) < float(by["dqs"]["mean_abs_detF_minus_1"]),
      f"FEM lowers the mean |det F - 1| ({by['dqs']['mean_abs_detF_minus_1']} -> {by['dqs+fem']['mean_abs_detF_minus_1']})",
      failures)
print(f"{9 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
