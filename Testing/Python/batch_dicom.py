"""repose batch with a DICOM CT series as a subject's image: the TotalSegmentator CT written as a series,
one pose on one worker. The posed CT is written as a DICOM series (posed_image/) whose voxels equal
`repose pose --image FOLDER`'s and whose study is the input's; the labels, mesh and surfaces equal the
CLI's byte for byte; a rerun skips both tasks; a changed slice makes both run again."""
import json
import os
import shutil
import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

from repose import vtkReposeDicomSeriesWriter, vtkReposeImageReader
from repose_testing import EXE, SHARED, TEMP, TESTING, check, run

failures = []
work = os.path.join(TEMP, "batch_dicom")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
ts = os.path.join(SHARED, "totalsegmentator")


def read(path):
    r = vtkReposeImageReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput(), r.GetLastError()


ct, _ = read(os.path.join(ts, "example_ct.nii.gz"))
w = vtkReposeDicomSeriesWriter()
w.SetInputData(ct)
w.SetFileName(f"{work}/ct")
check(w.Write() == 1, f"the CT written as a DICOM series ({w.GetLastError()})", failures)
series = f"{work}/ct"
labels = os.path.join(ts, "example_seg_fast_force_split.nii.gz")
skeleton = os.path.join(TESTING, "Data", "totalsegmentator_skeleton.json")
pose = os.path.join(TESTING, "Data", "totalsegmentator_hip_flexion.json")
manifest = f"{work}/batch.json"
with open(manifest, "w") as f:
    json.dump({"settings": {"outputs": ["labels", "mesh", "surfaces", "image"]},
               "subjects": [{"name": "ts", "labels": labels, "image": series, "skeleton": skeleton,
                             "prepare": {"mesh_spacing": 6}, "poses": [{"name": "hip", "file": pose}]}]}, f)


def batch():
    p = subprocess.run([EXE, "batch", manifest, "--out", f"{work}/out", "--workers", "1"], capture_output=True,
                       text=True)
    print(p.stdout + p.stderr)
    return p


p = batch()
result = f"{work}/out/ts/poses/hip"
check(p.returncode == 0 and os.path.isdir(f"{result}/posed_image"),
      f"the batch poses a subject whose CT is a DICOM folder (exit {p.returncode})", failures)
run("pose", "--case", f"{work}/out/ts/case", "--pose", pose, "--image", series, "--out", f"{work}/cli")
batch_ct, err1 = read(f"{result}/posed_image")
cli_ct, err2 = read(f"{work}/cli/posed_image")
same = (not err1 and not err2 and
        np.array_equal(vtk_to_numpy(batch_ct.GetPointData().GetScalars()), vtk_to_numpy(cli_ct.GetPointData().GetScalars())))
study = lambda img: dict(img.GetFieldData().GetAbstractArray("DicomTags").GetValue(i).split("=", 1)
                         for i in range(img.GetFieldData().GetAbstractArray("DicomTags").GetNumberOfValues()))
rest, _ = read(series)
check(same and study(batch_ct)["0020|000d"] == study(rest)["0020|000d"],
      f"posed_image/ is a DICOM series, voxel for voxel the CLI's, in the input's study ({err1}{err2})", failures)
differ = [n for n in ("posed_mesh.vtu", "posed_surfaces.vtp", "posed_labels.nii.gz")
          if open(f"{result}/{n}", "rb").read() != open(f"{work}/cli/{n}", "rb").read()]
check(not differ, f"labels, mesh and surfaces equal the CLI's byte for byte (differ: {differ})", failures)

p = batch()
check(p.returncode == 0 and "2 tasks: 0 to run, 2 complete before" in p.stdout + p.stderr,
      "a rerun skips the preparation and the pose", failures)
slice_file = sorted(os.listdir(series))[10]
with open(f"{series}/{slice_file}", "ab") as f:
    f.write(b"\0\0")  # the series' hash changes: the task is not the same any more
p = batch()
check(p.returncode == 0 and "2 tasks: 2 to run, 0 complete before" in p.stdout + p.stderr,
      "a changed slice (the series' hash) makes the preparation and the pose run again", failures)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
