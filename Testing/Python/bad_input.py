"""Bad input: a one-line error naming the file and the problem, a non-zero exit, no partial output,
inputs never modified."""
import hashlib
import json
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData

from repose_testing import TEMP, run, check

work = os.path.join(TEMP, "bad_input")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def write_image(path, array, spacing=(2.0, 2.0, 3.0), origin=(10.0, -5.0, 7.0)):
    from repose import vtkReposeImageWriter
    img = vtkImageData()
    img.SetDimensions(array.shape[2], array.shape[1], array.shape[0])
    img.SetSpacing(*spacing)
    img.SetOrigin(*origin)
    img.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(array).ravel(), deep=True))
    w = vtkReposeImageWriter()
    w.SetFileName(path)
    w.SetInputData(img)
    assert w.Write() == 1, path


def write_json(path, obj_or_text):
    with open(path, "w") as f:
        f.write(obj_or_text if isinstance(obj_or_text, str) else json.dumps(obj_or_text))


def digest(paths):
    h = hashlib.sha256()
    for p in sorted(paths):
        if os.path.isfile(p):
            with open(p, "rb") as f:
                h.update(f.read())
    return h.hexdigest()


# A small valid subject: two bones in a soft-tissue block.
labels = np.zeros((20, 12, 12), np.int32)
labels[2:18, 2:10, 2:10] = 1
labels[4:9, 5:7, 5:7] = 10
labels[11:16, 5:7, 5:7] = 11
L = f"{work}/labels.nii.gz"
write_image(L, labels)
S = f"{work}/skeleton.json"
skel = {"joints": [{"name": "root", "parent": None, "center": [21, 7, 31], "labels": [10]},
                   {"name": "knee", "parent": "root", "center": [21, 7, 37], "labels": [11]}]}
write_json(S, skel)

write_image(f"{work}/float_labels.nii.gz", labels.astype(np.float32) + 0.5)
write_image(f"{work}/empty.nii.gz", np.zeros_like(labels))
write_image(f"{work}/ct_other_grid.nii.gz", np.zeros((20, 12, 13), np.float32))
write_json(f"{work}/not_an_image.nii.gz", "this is not an image")
write_json(f"{work}/skel_absent_label.json", {"joints": [skel["joints"][0], dict(skel["joints"][1], labels=[99])]})
write_json(f"{work}/skel_no_voxels.json", {"joints": [skel["joints"][0], dict(skel["joints"][1], labels=[])]})
write_json(f"{work}/skel_unknown_parent.json", {"joints": [skel["joints"][0], dict(skel["joints"][1], parent="hip")]})
write_json(f"{work}/skel_cycle.json", {"joints": [dict(skel["joints"][0], parent="knee"), skel["joints"][1]]})
write_json(f"{work}/skel_broken.json", '{"joints": [')
write_json(f"{work}/pose_unknown_joint.json", {"rotations": {"elbow": {"axis": [1, 0, 0], "degrees": 10}}})
write_json(f"{work}/pose_inf.json", '{"rotations": {"knee": {"axis": [1, 0, 0], "degrees": 1e999}}}')
write_json(f"{work}/pose_nan.json", '{"rotations": {"knee": {"axis": [1, 0, 0], "degrees": NaN}}}')
write_json(f"{work}/pose_zero_axis.json", {"rotations": {"knee": {"axis": [0, 0, 0], "degrees": 30}}})
write_json(f"{work}/pose_ok.json", {"rotations": {"knee": {"axis": [1, 0, 0], "degrees": 30}}})
inputs = [os.path.join(work, f) for f in os.listdir(work)]
before = digest(inputs)

# A valid case to pose.
run("prepare", "--labels", L, "--skeleton", S, "--out", f"{work}/case")
case_files = sorted(os.listdir(f"{work}/case"))

cases = [
    ("missing labels file", ["prepare", "--labels", f"{work}/nope.nii.gz", "--skeleton", S], "nope.nii.gz"),
    ("unreadable labels file", ["prepare", "--labels", f"{work}/not_an_image.nii.gz", "--skeleton", S], "not_an_image.nii.gz"),
    ("non-integer label volume", ["prepare", "--labels", f"{work}/float_labels.nii.gz", "--skeleton", S], "float_labels.nii.gz"),
    ("empty label volume", ["prepare", "--labels", f"{work}/empty.nii.gz", "--skeleton", S], "empty.nii.gz"),
    ("skeleton names an absent label", ["prepare", "--labels", L, "--skeleton", f"{work}/skel_absent_label.json"], "skel_absent_label.json"),
    ("bone with no voxels", ["prepare", "--labels", L, "--skeleton", f"{work}/skel_no_voxels.json"], "skel_no_voxels.json"),
    ("unknown parent", ["prepare", "--labels", L, "--skeleton", f"{work}/skel_unknown_parent.json"], "skel_unknown_parent.json"),
    ("parent cycle", ["prepare", "--labels", L, "--skeleton", f"{work}/skel_cycle.json"], "skel_cycle.json"),
    ("malformed skeleton", ["prepare", "--labels", L, "--skeleton", f"{work}/skel_broken.json"], "skel_broken.json"),
    ("image on another grid", ["prepare", "--labels", L, "--skeleton", S, "--image", f"{work}/ct_other_grid.nii.gz"], "ct_other_grid.nii.gz"),
    ("pose names an unknown joint", ["pose", "--case", f"{work}/case", "--pose", f"{work}/pose_unknown_joint.json"], "pose_unknown_joint.json"),
    ("infinite angle in pose", ["pose", "--case", f"{work}/case", "--pose", f"{work}/pose_inf.json"], "pose_inf.json"),
    ("NaN in pose", ["pose", "--case", f"{work}/case", "--pose", f"{work}/pose_nan.json"], "pose_nan.json"),
    ("zero rotation axis", ["pose", "--case", f"{work}/case", "--pose", f"{work}/pose_zero_axis.json"], "pose_zero_axis.json"),
    ("missing case", ["pose", "--case", f"{work}/no_case", "--pose", f"{work}/pose_ok.json"], "no_case"),
    ("image on another grid when posing", ["pose", "--case", f"{work}/case", "--pose", f"{work}/pose_ok.json", "--image",
                                           f"{work}/ct_other_grid.nii.gz"], "ct_other_grid.nii.gz"),
]
for i, (what, args, name) in enumerate(cases):
    out = f"{work}/out{i}"
    code, stdout, stderr = run(*args, "--out", out, check=False)
    lines = [l for l in stderr.splitlines() if l.strip()]
    one_line = len(lines) == 1 and lines[0].startswith("repose: error:")
    names_file = bool(lines) and name in lines[0]
    no_output = not os.path.exists(out) or not [f for f in os.listdir(out)]
    check(code != 0 and one_line and names_file and no_output,
          f"{what}: exit {code}, {len(lines)} line(s) {'naming' if names_file else 'NOT naming'} {name}, "
          f"{'no' if no_output else 'PARTIAL'} output: {lines[0] if lines else ''}", failures)

code, _, stderr = run("pose", "--case", f"{work}/case", "--out", f"{work}/x", check=False)
check(code != 0 and "--pose" in stderr, "missing required option is reported", failures)
# Every --relax-* word is checked the same way: a usage error (exit 2) naming the option and its words.
relax_words = [("--relax-model", "fixed-corotated"), ("--relax-volume", "segments"),
               ("--relax-continuation", "if-inverted"), ("--relax-strained-region", "first")]
for option, word in relax_words:
    code, _, stderr = run("pose", "--case", f"{work}/case", "--pose", f"{work}/pose_ok.json", "--relax", option, "bogus",
                          "--out", f"{work}/relax_words", check=False)
    lines = stderr.strip().splitlines()
    check(code == 2 and len(lines) == 1 and option in lines[0] and word in lines[0]
          and not os.path.exists(f"{work}/relax_words"),
          f"{option} bogus: exit {code} (a usage error), '{lines[0] if lines else ''}'", failures)
code, _, stderr = run("frobnicate", check=False)
check(code != 0 and "frobnicate" in stderr, "unknown command is reported", failures)
check(digest(inputs) == before, "inputs unchanged", failures)
check(sorted(os.listdir(f"{work}/case")) == case_files, "case directory unchanged by failed poses", failures)
print(f"{len(cases) + len(relax_words) + 4 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
