"""--out onto inputs: an output folder that is or lies inside an input folder (a case), or whose
outputs would replace an input file (directly, through a symbolic link, through an output folder such
as frames/ that is replaced whole), is refused before any work: exit 1, one line naming --out and the
input, nothing printed on stdout (no stage ran), no file added or changed anywhere. Writing beside
inputs in their folder stays allowed when none would be replaced."""
import os
import shutil
import sys

from repose_testing import SHARED, TEMP, TESTING, TINY, check, check_failed_cleanly, file_hashes, run

work = os.path.join(TEMP, "outputs_onto_inputs")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []

phantom, case = f"{work}/phantom", f"{work}/case"
shutil.copytree(f"{TINY}/phantom", phantom)
shutil.copytree(f"{TINY}/case", case)
shutil.copy(os.path.join(TESTING, "Data", "tiny_pose.json"), f"{work}/pose.json")
os.makedirs(f"{work}/clip/frames")
shutil.copy(os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh"), f"{work}/clip/frames/walk.bvh")
os.symlink("phantom", f"{work}/phantom_link")
os.symlink("case", f"{work}/case_link")
shutil.copy(f"{phantom}/labels.nii.gz", f"{work}/reference.nii.gz")
os.makedirs(f"{work}/rigged")
shutil.copy(f"{phantom}/labels.nii.gz", f"{work}/rigged/labels_rigged.nii.gz")
skin = f"{TINY}/case/surfaces.vtp"  # any closed surface will do: the run must stop before reading it

labels, skeleton = f"{phantom}/labels.nii.gz", f"{phantom}/skeleton.json"
prepare = ["prepare", "--labels", labels, "--skeleton", skeleton, "--out"]
voxelize = ["voxelize", "--skin", skin, "--reference", f"{work}/reference.nii.gz"]
# (arguments, the input the message must name)
refused = [
    (prepare + [phantom], labels),                                # the folder of its inputs
    (prepare + [f"{phantom}/../phantom/."], labels),              # the same, spelt differently
    (prepare + [f"{work}/phantom_link"], labels),                 # the same, through a symbolic link
    (voxelize + ["--out", f"{work}/reference.nii.gz"], f"{work}/reference.nii.gz"),
    (voxelize + ["--voxel", "4", "--out", f"{work}/v/labels.nii.gz", "--skeleton-out", f"{work}/reference.nii.gz"],
     f"{work}/reference.nii.gz"),
    (["pose", "--case", case, "--pose", f"{work}/pose.json", "--out", case], case),
    (["pose", "--case", case, "--pose", f"{work}/pose.json", "--out", f"{case}/posed"], case),
    (["pose", "--case", case, "--pose", f"{work}/pose.json", "--out", f"{work}/case_link"], case),
    (["animate", "--case", case, "--bvh", f"{work}/clip/frames/walk.bvh", "--out", case], case),
    (["animate", "--case", case, "--bvh", f"{work}/clip/frames/walk.bvh", "--out", f"{work}/clip"],
     f"{work}/clip/frames/walk.bvh"),                             # frames/ is replaced whole
    (["rig", "--labels", labels, "--out", labels], labels),
    (["rig", "--labels", f"{work}/rigged/labels_rigged.nii.gz", "--out", f"{work}/rigged/skeleton.json"],
     f"{work}/rigged/labels_rigged.nii.gz"),
]


def listing():
    return sorted(os.path.join(d, n) for d, ds, fs in os.walk(work) for n in ds + fs)


before, files = file_hashes(work), listing()
for args, named in refused:
    what = " ".join(a.replace(work + "/", "") for a in args)
    result = run(*args, check=False)
    check_failed_cleanly(result, "choose another --out", [], failures, what)
    line = result[2].strip()
    out = args[args.index("--skeleton-out") + 1] if "--skeleton-out" in args else args[args.index("--out") + 1]
    check(named in line and (out in line or os.path.dirname(out) in line), f"{what}: names --out and {named}", failures)
    check(result[1] == "", f"{what}: refused before any work (stdout {result[1][:60]!r})", failures)
check(listing() == files, "no file added or removed", failures)
check(file_hashes(work) == before, "inputs byte-identical", failures)

# Beside its inputs, replacing none: allowed.
code, _, err = run("pose", "--case", case, "--pose", f"{work}/pose.json", "--out", work, check=False)
check(code == 0 and os.path.isfile(f"{work}/posed_mesh.vtu"), f"pose beside its pose.json is allowed ({err.strip()})",
      failures)
check(all(file_hashes(work)[p] == h for p, h in before.items()), "inputs byte-identical after the allowed run",
      failures)
total = 3 * len(refused) + 4
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
