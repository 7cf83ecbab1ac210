"""Outputs on a full disk: every command that writes (phantom, rig, voxelize, prepare, pose, animate)
runs under a file-size limit (RLIMIT_FSIZE, so that a write fails with EFBIG as it does with ENOSPC on a
full file system) that cuts one of its outputs short. Each must exit 1 with one line naming the final
file and the reason, leave no output (not even the folder it created, nor its temporary folder) and
leave its inputs byte-identical. Under a limit above every output's size the same run succeeds, so
the limit itself is not what fails. The tiny phantom's case comes from the tiny_case fixture."""
import os
import shutil
import sys

from vtkmodules.vtkFiltersCore import vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkCubeSource
from vtkmodules.vtkIOGeometry import vtkSTLWriter

from repose_testing import SHARED, TEMP, TESTING, TINY, check, check_failed_cleanly, file_hashes, run_file_size_limited

work = os.path.join(TEMP, "full_disk_outputs")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
KB, MB = 1024, 1024 * 1024

for name, side in (("skin", 60), ("bone", 20)):  # a box in a box: voxelize's smallest useful input
    cube = vtkCubeSource()
    cube.SetXLength(side)
    cube.SetYLength(side)
    cube.SetZLength(2 * side)
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(cube.GetOutputPort())
    w = vtkSTLWriter()
    w.SetFileName(f"{work}/{name}.stl")
    w.SetInputConnection(triangles.GetOutputPort())
    w.Write()

phantom, case = f"{TINY}/phantom", f"{TINY}/case"
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
bvh = os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh")
inputs = [phantom, case, pose, bvh, f"{work}/skin.stl", f"{work}/bone.stl"]
before = file_hashes(*inputs)

# (command, output folder, limit in bytes, the file the message must name)
runs = []
out = f"{work}/out/nested"  # two folders the run creates; both must go
runs += [(["phantom", "--size", "tiny", "--out", out], out, limit, f"{out}/labels.nii.gz") for limit in (0, 1 * KB)]
runs += [(["rig", "--labels", f"{phantom}/labels.nii.gz", "--out", f"{out}/skeleton.json"], out, 0,
          f"{out}/skeleton.json")]
runs += [(["voxelize", "--skin", f"{work}/skin.stl", "--bone", f"femur_left={work}/bone.stl", "--voxel", "2",
           "--out", f"{out}/labels.nii.gz"], out, limit, f"{out}/labels.nii.gz") for limit in (0, 100)]
# A raw volume's short write (a detached NRRD, not compressed): the header fits, the voxels do not.
runs += [(["voxelize", "--skin", f"{work}/skin.stl", "--bone", f"femur_left={work}/bone.stl", "--voxel", "2",
           "--out", f"{out}/labels.nhdr"], out, 4 * KB, f"{out}/labels.nhdr")]
runs += [(["prepare", "--labels", f"{phantom}/labels.nii.gz", "--skeleton", f"{phantom}/skeleton.json",
           "--out", out], out, 64 * KB, f"{out}/mesh.vtu")]
runs += [(["pose", "--case", case, "--pose", pose, "--out", out], out, limit, f"{out}/posed_mesh.vtu")
         for limit in (0, 100, 64 * KB, 1 * MB, 2 * MB)]  # the posed mesh is 2.3 MB: cut near its end
# The series' label table (frames/labels.tsv, a few hundred bytes) is written first, then the frames.
runs += [(["animate", "--case", case, "--bvh", bvh, "--frames", "0:3", "--volumes", "--out", out], out, limit,
          f"{out}/frames/{named}") for limit, named in ((0, "labels.tsv"), (1 * MB, "mesh_00000.vtu"))]

for args, folder, limit, named in runs:
    what = f"{args[0]} under a {limit} B file-size limit"
    result = run_file_size_limited(limit, *args)
    check_failed_cleanly(result, f"{named}: cannot write (file too large)", [f"{work}/out"], failures, what)

# The same runs with room for every output succeed: the failures above come from the limit.
for args, folder, limit, named in runs[::3]:
    code, _, err = run_file_size_limited(64 * MB, *args)
    check(code == 0 and os.path.isdir(folder) and not [n for n in os.listdir(folder) if n.startswith(".repose-tmp")],
          f"{args[0]} with room succeeds ({err.strip()})", failures)
    shutil.rmtree(f"{work}/out", ignore_errors=True)

check(file_hashes(*inputs) == before, "inputs byte-identical", failures)
total = 3 * len(runs) + len(runs[::3]) + 1
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
