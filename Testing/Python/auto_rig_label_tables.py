"""The label table beside a label volume, read by `repose rig` and `repose prepare`:
- the phantom read back with its own labels.tsv: its 15 joints, with the names and parents of its
  skeleton.json, and the report says which table it read;
- the wrong table (TotalSegmentator's names, given or by default): a one-line error naming the table
  and what did not match, exit 1, nothing written;
- a 3D Slicer colour table beside the volume (NAME_ColorTable.ctbl) with other spellings of the bone
  names (Femur_L, "Right Tibia", LHumerus, ...): the same joint names;
- prepare keeps the table in the case (CASE/labels.tsv, manifest "labelTable"), colours included,
  for a discovered table and for the rig's; a case without it (an older case) still poses."""
import json
import os
import shutil
import sys

from repose_testing import SHARED, TEMP, check, load_json, run

failures = []
work = os.path.join(TEMP, "auto_rig_label_tables")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
run("phantom", "--size", "tiny", "--out", f"{work}/ph")
truth = {j["name"]: j["parent"] for j in load_json(f"{work}/ph/skeleton.json")["joints"]}


def joints_of(path):
    return {j["name"]: j["parent"] for j in load_json(path)["joints"]}


# ---- the phantom with its own table, found beside the volume
code, out, _ = run("rig", "--labels", f"{work}/ph/labels.nii.gz", "--out", f"{work}/rig/skeleton.json")
print(out)
check(out.startswith(f"label table: {work}/ph/labels.tsv (found beside {work}/ph/labels.nii.gz)"),
      "rig says it read labels.tsv beside the volume", failures)
got = joints_of(f"{work}/rig/skeleton.json")
check(got == truth, f"15 joints with the phantom's names and parents ({len(got)} found)", failures)

# ---- the wrong table: given, and by default (the volume alone)
ts_table = os.path.join(SHARED, "totalsegmentator", "labels_total_v2.tsv")
code, out, err = run("rig", "--labels", f"{work}/ph/labels.nii.gz", "--label-table", ts_table,
                     "--out", f"{work}/wrong/skeleton.json", check=False)
print(err)
check(code == 1 and err.count("\n") == 1 and err.startswith(f"repose: error: {ts_table}: does not fit ")
      and "11 of 11 bone labels lie where their names cannot be: sacrum (25) lies" in err,
      "the TotalSegmentator table on the phantom: one line naming the table and the misplaced bones", failures)
check(not os.path.exists(f"{work}/wrong"), "nothing written", failures)
os.makedirs(f"{work}/alone")
shutil.copy(f"{work}/ph/labels.nii.gz", f"{work}/alone/labels.nii.gz")
code, out, err = run("rig", "--labels", f"{work}/alone/labels.nii.gz", "--out", f"{work}/alone/skeleton.json",
                     check=False)
print(err)
check(code == 1 and err.startswith(f"repose: error: {work}/alone/labels.nii.gz: the built-in TotalSegmentator names "
                                   "do not fit it (no --label-table given, none found beside it)"),
      "no table beside the phantom: the built-in names are refused, saying why", failures)
check(not os.path.exists(f"{work}/alone/skeleton.json"), "no skeleton written", failures)

# ---- notes in NAME.txt beside the volume are not a table: skipped for the next one (labels.tsv)
os.makedirs(f"{work}/notes")
shutil.copy(f"{work}/ph/labels.nii.gz", f"{work}/notes/seg.nii.gz")
shutil.copy(f"{work}/ph/labels.tsv", f"{work}/notes/labels.tsv")
with open(f"{work}/notes/seg.txt", "w") as f:
    f.write("Phantom written by repose phantom, tiny size\n")
code, out, _ = run("rig", "--labels", f"{work}/notes/seg.nii.gz", "--out", f"{work}/notes/skeleton.json")
check(out.startswith(f"label table: ignoring {work}/notes/seg.txt") and
      f"label table: {work}/notes/labels.tsv (found beside" in out and joints_of(f"{work}/notes/skeleton.json") == truth,
      "notes in seg.txt are skipped, labels.tsv beside is read", failures)

# ---- a Slicer colour table beside the volume, in other spellings
spellings = {"skull": "Cranium", "spine": "Spine", "ribcage": "Rib_cage", "pelvis": "Pelvis",
             "femur_left": "Femur_L", "femur_right": "Femur_R", "tibia_left": "Left_Tibia",
             "tibia_right": "Right_Tibia", "foot_left": "LFoot", "foot_right": "RFoot",
             "humerus_left": "LHumerus", "humerus_right": "RHumerus", "forearm_left": "Forearm.L",
             "forearm_right": "Forearm.R", "hand_left": "Hand_left", "hand_right": "Hand_right"}
rows = [l.split("\t") for l in open(f"{work}/ph/labels.tsv").read().splitlines()[1:]]
os.makedirs(f"{work}/slicer")
shutil.copy(f"{work}/ph/labels.nii.gz", f"{work}/slicer/seg.nii.gz")
with open(f"{work}/slicer/seg_ColorTable.ctbl", "w") as f:
    f.write(f"# Color table file {work}/slicer/seg_ColorTable.ctbl\n# {len(rows) + 1} values\n0 Background 0 0 0 0\n")
    for value, name, _kind in rows:
        f.write(f"{value} {spellings.get(name, name)} {int(value) * 7 % 256} 100 {int(value) * 13 % 256} 255\n")
code, out, _ = run("rig", "--labels", f"{work}/slicer/seg.nii.gz", "--out", f"{work}/slicer/skeleton.json")
check(f"label table: {work}/slicer/seg_ColorTable.ctbl (found beside" in out, "rig reads the Slicer table beside seg.nii.gz",
      failures)
got = joints_of(f"{work}/slicer/skeleton.json")
check(got == truth, f"the same 15 joint names and parents whatever the table calls the bones ({sorted(got)})", failures)

# ---- prepare keeps the table in the case
run("prepare", "--labels", f"{work}/slicer/seg.nii.gz", "--skeleton", f"{work}/ph/skeleton.json",
    "--out", f"{work}/case_given")
case_rows = open(f"{work}/case_given/labels.tsv").read().splitlines()
check(case_rows[0] == "value\tname\tkind\tr\tg\tb\ta" and "24\tFemur_L\tbone\t168\t100\t56\t255" in case_rows,
      "a discovered Slicer table goes into the case with its names, kinds and colours", failures)
check(load_json(f"{work}/case_given/manifest.json").get("labelTable") == "labels.tsv",
      "manifest.json lists labelTable: labels.tsv", failures)
run("prepare", "--labels", f"{work}/ph/labels.nii.gz", "--skeleton", "auto", "--out", f"{work}/case_auto")
auto_rows = open(f"{work}/case_auto/labels.tsv").read().splitlines()
check(auto_rows == open(f"{work}/ph/labels.tsv").read().splitlines(),
      "prepare --skeleton auto keeps the rig's table (the phantom's, nothing split)", failures)
check(joints_of(f"{work}/case_auto/skeleton.json") == truth, "the auto case has the phantom's joints", failures)
# An older case: no labels.tsv, no labelTable in the manifest. It still loads and poses.
shutil.copytree(f"{work}/case_auto", f"{work}/case_old")
os.remove(f"{work}/case_old/labels.tsv")
manifest = load_json(f"{work}/case_old/manifest.json")
del manifest["labelTable"]
with open(f"{work}/case_old/manifest.json", "w") as f:
    json.dump(manifest, f)
with open(f"{work}/pose.json", "w") as f:
    json.dump({"rotations": {"left_knee": {"axis": [1, 0, 0], "degrees": 30}}}, f)
code, _, err = run("pose", "--case", f"{work}/case_old", "--pose", f"{work}/pose.json", "--out", f"{work}/posed_old",
                   check=False)
check(code == 0 and os.path.isfile(f"{work}/posed_old/posed_labels.nii.gz"),
      f"a case without a label table still poses ({err.strip()})", failures)
# A broken table in a case is named.
with open(f"{work}/case_auto/labels.tsv", "a") as f:
    f.write("24\tduplicate\n")
code, _, err = run("pose", "--case", f"{work}/case_auto", "--pose", f"{work}/pose.json", "--out", f"{work}/posed_bad",
                   check=False)
check(code == 1 and f"{work}/case_auto/labels.tsv line" in err and "duplicate label value 24" in err,
      f"a broken case table is an error naming it: {err.strip()}", failures)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
