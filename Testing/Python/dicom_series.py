"""DICOM CT series in and out. The TotalSegmentator CT written as a series (vtkReposeDicomSeriesWriter)
and read back from its folder (vtkReposeImageReader) is the same grid and the same Hounsfield units;
an oblique grid keeps its direction; a folder of two series needs a Series Instance UID, and with it
reads the one chosen; a missing slice is refused as such; a series derived from a DICOM one keeps its
patient and study with a new series UID; `prepare --image FOLDER` takes the series beside a NIfTI
label volume on the same grid, and `pose --image FOLDER` writes the posed CT as a derived DICOM series
(posed_image/: the input's study, a new series, DERIVED image type, a description saying how it was
made) with the same voxels as from the NIfTI CT. The posed labels written as a DICOM Segmentation (one
segment per label, named) on that CT read back onto its grid voxel for voxel; `pose --format dicom`
writes both in one study; `--series-uid` chooses a series in a folder of two."""
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonMath import vtkMatrix3x3

from repose import vtkReposeDicomSegReader, vtkReposeDicomSegWriter, vtkReposeDicomSeriesWriter, vtkReposeImageReader
from repose_testing import SHARED, TEMP, Image, check, run


def round_half_away(x):
    """The writer's rounding of HU to integers (std::lround: halves away from zero; numpy's round
    takes halves to even)."""
    x = np.asarray(x, dtype=float)
    return np.sign(x) * np.floor(np.abs(x) + 0.5)

failures = []
work = os.path.join(TEMP, "dicom_series")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
ct_path = os.path.join(SHARED, "totalsegmentator", "example_ct.nii.gz")


def read(path, uid=None):
    r = vtkReposeImageReader()
    r.SetFileName(path)
    if uid:
        r.SetSeriesUID(uid)
    r.Update()
    return r.GetOutput(), r.GetLastError()


def write(image, folder, description="test series"):
    w = vtkReposeDicomSeriesWriter()
    w.SetInputData(image)
    w.SetFileName(folder)
    w.SetSeriesDescription(description)
    ok = w.Write()
    return ok, w.GetLastError()


def grid(img):
    m = img.GetDirectionMatrix()
    d = np.array([[m.GetElement(r, c) for c in range(3)] for r in range(3)])
    e = img.GetExtent()
    first = np.array(img.GetOrigin()) + d @ (np.array(img.GetSpacing()) * np.array(e[::2]))
    return img.GetDimensions(), first, np.array(img.GetSpacing()), d


def voxels(img):
    return vtk_to_numpy(img.GetPointData().GetScalars()).astype(float)


def attribute(path, group, element):
    """An attribute's text in an implicit-VR little-endian file (the transfer syntax the writer uses)."""
    data = open(path, "rb").read()
    at = data.find(group.to_bytes(2, "little") + element.to_bytes(2, "little"), 132 + 12)
    n = int.from_bytes(data[at + 4:at + 8], "little")
    return data[at + 8:at + 8 + n].rstrip(b"\x00 ").decode()


def series_uid(path):
    return attribute(path, 0x0020, 0x000E)


def tags(img):
    a = img.GetFieldData().GetAbstractArray("DicomTags")
    return dict(a.GetValue(i).split("=", 1) for i in range(a.GetNumberOfValues())) if a else {}


ct, err = read(ct_path)
check(not err, f"the NIfTI CT reads ({err})", failures)
ok, err = write(ct, f"{work}/ct")
files = sorted(os.listdir(f"{work}/ct"))
check(ok and len(files) == ct.GetDimensions()[2], f"one DICOM file per slice: {len(files)} ({err})", failures)
back, err = read(f"{work}/ct")
check(not err, f"the series reads back from its folder ({err})", failures)
(d0, f0, s0, m0), (d1, f1, s1, m1) = grid(ct), grid(back)
check(d0 == d1 and np.abs(f0 - f1).max() < 1e-3 and np.abs(s0 - s1).max() < 1e-4 and np.abs(m0 - m1).max() < 1e-5,
      f"same grid: dims {d1}, first voxel off {np.abs(f0 - f1).max():.1e} mm, spacing {s1}", failures)
diff = np.abs(np.clip(round_half_away(voxels(ct)), -32768, 32767) - voxels(back)).max()
check(diff == 0, f"the same Hounsfield units, voxel for voxel (largest difference {diff})", failures)
check(back.GetScalarType() == 10, "a DICOM CT reads as float (rescale applied)", failures)

# An oblique grid (rows and columns turned 30 degrees about x) keeps its direction.
oblique = type(ct)()
oblique.DeepCopy(ct)
c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
m = vtkMatrix3x3()
for r, row in enumerate([[1, 0, 0], [0, c, -s], [0, s, c]]):
    for col, v in enumerate(row):
        m.SetElement(r, col, v)
oblique.SetDirectionMatrix(m)
write(oblique, f"{work}/oblique")
ob, err = read(f"{work}/oblique")
(_, fo, _, mo), (_, fb, _, mb) = grid(oblique), grid(ob)
check(not err and np.abs(mo - mb).max() < 1e-5 and np.abs(fo - fb).max() < 1e-3,
      f"an oblique series keeps its direction and place ({err})", failures)

# Two series in one folder: refused without a UID (both listed), read with one.
os.makedirs(f"{work}/two")
for name in files[:20]:
    shutil.copy(f"{work}/ct/{name}", f"{work}/two/a_{name}")
ok, err = write(ct, f"{work}/ct2")
for name in files[:20]:
    shutil.copy(f"{work}/ct2/{name}", f"{work}/two/b_{name}")
_, err = read(f"{work}/two")
check("2 DICOM series in this folder, choose one with --series-uid" in err and err.startswith(f"{work}/two: "),
      f"two series without a UID: {err}", failures)
uid = series_uid(f"{work}/ct2/{files[0]}")
one, err = read(f"{work}/two", uid)
check(not err and one.GetDimensions()[2] == 20 and series_uid(f"{work}/ct/{files[0]}") != uid,
      f"with --series-uid the chosen series: {one.GetDimensions()} ({err})", failures)
_, err = read(f"{work}/two", "1.2.3.4")
check("no single DICOM series 1.2.3.4" in err, f"an unknown UID is named: {err}", failures)

# A missing slice is an error that says so, and so is a folder without DICOM files.
shutil.copytree(f"{work}/ct", f"{work}/gap")
os.remove(f"{work}/gap/{files[len(files) // 2]}")
_, err = read(f"{work}/gap")
check("missing slice" in err, f"a missing slice is refused: {err}", failures)
os.makedirs(f"{work}/empty")
_, err = read(f"{work}/empty")
check("no DICOM series in this folder" in err, f"an empty folder: {err}", failures)

# Patient and study carried into a derived series, which gets its own series UID.
first_tags = tags(back)
derived_ok, err = write(back, f"{work}/derived", "reposed")
derived, _ = read(f"{work}/derived")
check(derived_ok and first_tags.get("0020|000d") and tags(derived).get("0020|000d") == first_tags["0020|000d"] and
      tags(derived).get("0010|0010") == first_tags.get("0010|0010") and
      series_uid(f"{work}/derived/{files[0]}") != series_uid(f"{work}/ct/{files[0]}"),
      f"the derived series keeps patient and study ({tags(derived).get('0010|0010')}), new series UID", failures)
ok, err = write(back, f"{work}/derived")
check(not ok and "exists already" in err, f"an existing folder is not written over: {err}", failures)

# The CLI: prepare with the series as --image beside the NIfTI labels on the same grid, then pose.
labels = os.path.join(SHARED, "totalsegmentator", "example_seg_fast_force_split.nii.gz")
code, out, err = run("prepare", "--labels", labels, "--image", f"{work}/ct", "--skeleton", "auto",
                     "--label-table", os.path.join(SHARED, "totalsegmentator", "labels_total_v2.tsv"),
                     "--max-tets", 60000, "--out", f"{work}/case", check=False)
check(code == 0, f"prepare --image takes a DICOM folder ({err.strip()})", failures)
code, _, err = run("prepare", "--labels", f"{work}/ct", "--skeleton", "auto", "--out", f"{work}/case_from_folder",
                   check=False)
check(code != 0 and "a folder; label volumes are read from files" in err and not os.path.exists(f"{work}/case_from_folder"),
      f"a DICOM folder given as the labels is refused: {err.strip()}", failures)
pose = f"{work}/pose.json"
with open(pose, "w") as f:
    f.write('{"rotations": {"left_hip": {"axis": [1, 0, 0], "degrees": -40}}}')
run("pose", "--case", f"{work}/case", "--pose", pose, "--image", f"{work}/ct", "--out", f"{work}/posed_dicom")
run("pose", "--case", f"{work}/case", "--pose", pose, "--image", ct_path, "--out", f"{work}/posed_nifti")
posed, err = read(f"{work}/posed_dicom/posed_image")
posed_files = sorted(os.listdir(f"{work}/posed_dicom/posed_image"))
reference = Image(f"{work}/posed_nifti/posed_image.nii.gz")
same, halves = None, None
if not err:
    # Equal after the writer's rounding; a voxel within 1e-3 HU of a half may round the other way (the
    # two CT inputs reach the same HU through float arithmetic in a different order).
    hu = reference.a.ravel().astype(float)
    off = np.abs(np.clip(round_half_away(hu), -32768, 32767) - voxels(posed))
    near_half = np.abs(np.abs(hu - np.trunc(hu)) - 0.5) < 1e-3
    same, halves = off[~near_half].max(), int((off[near_half] > 0).sum())
check(not err and posed.GetDimensions() == reference.dims and same == 0 and halves is not None
      and (off[near_half] <= 1).all(),
      f"pose --image FOLDER writes posed_image/ as a DICOM series, the same HU as from the NIfTI CT "
      f"(largest difference {same}; {halves} voxel(s) at a half rounded the other way) ({err})", failures)
description = attribute(f"{work}/posed_dicom/posed_image/{posed_files[0]}", 0x0008, 0x103E)
image_type = attribute(f"{work}/posed_dicom/posed_image/{posed_files[0]}", 0x0008, 0x0008)
check(description.startswith("Reposed (Repose ") and image_type.startswith("DERIVED\\SECONDARY") and
      tags(posed).get("0020|000d") == first_tags["0020|000d"] and
      series_uid(f"{work}/posed_dicom/posed_image/{posed_files[0]}") != series_uid(f"{work}/ct/{files[0]}"),
      f"the posed series: '{description}', {image_type}, the input's study, a new series UID", failures)

# The posed labels as a DICOM Segmentation on the posed CT (its patient, study and frame of reference),
# one segment per label with its name: read back onto the CT's grid, every voxel's label is the same.
posed_labels, _ = read(f"{work}/posed_nifti/posed_labels.nii.gz")
posed_labels.GetFieldData().ShallowCopy(posed.GetFieldData())
table = [line.split("\t") for line in open(f"{work}/posed_nifti/posed_labels.tsv").read().splitlines()[1:]]
seg_writer = vtkReposeDicomSegWriter()
seg_writer.SetInputData(posed_labels)
seg_writer.SetFileName(f"{work}/posed_labels.dcm")
seg_reader = vtkReposeDicomSegReader()
for value, name, kind in table:
    seg_writer.AddSegment(int(value), name, 0.9, 0.8, 0.7, kind == "bone")
    seg_reader.AddSegment(int(value), name)
ok = seg_writer.Write()
seg_reader.SetInputData(posed)
seg_reader.SetFileName(f"{work}/posed_labels.dcm")
seg_reader.Update()
names_array = seg_reader.GetOutput().GetFieldData().GetAbstractArray("SegmentNames")
names = [names_array.GetValue(i) for i in range(names_array.GetNumberOfValues())] if names_array else []
expected = vtk_to_numpy(posed_labels.GetPointData().GetScalars())
got = vtk_to_numpy(seg_reader.GetOutput().GetPointData().GetScalars()) if not seg_reader.GetLastError() else None
present = sorted(set(expected.tolist()) - {0})
check(ok and got is not None and np.array_equal(expected, got) and len(names) == len(present),
      f"posed labels as a DICOM SEG: {len(names)} segments ({', '.join(names[:3])}, ...), read back voxel for voxel "
      f"({seg_writer.GetLastError()}{seg_reader.GetLastError()})", failures)
data = open(f"{work}/posed_labels.dcm", "rb").read()
check(first_tags["0020|000d"].encode() in data and b"1.2.840.10008.5.1.4.1.1.66.4" in data,
      "the SEG is a Segmentation Storage object in the CT's study", failures)

# pose --format dicom from the NIfTI CT: posed_labels.dcm and posed_image/ in one new study and frame
# of reference; the SEG read onto the posed CT's grid is the NIfTI run's posed labels voxel for voxel.
run("pose", "--case", f"{work}/case", "--pose", pose, "--image", ct_path, "--format", "dicom",
    "--out", f"{work}/posed_format_dicom")
fd = f"{work}/posed_format_dicom"
fd_image, err = read(f"{fd}/posed_image")
seg_reader = vtkReposeDicomSegReader()
for value, name, kind in table:
    seg_reader.AddSegment(int(value), name)
seg_reader.SetInputData(fd_image)
seg_reader.SetFileName(f"{fd}/posed_labels.dcm")
seg_reader.Update()
got = vtk_to_numpy(seg_reader.GetOutput().GetPointData().GetScalars()) if not seg_reader.GetLastError() else None
fd_tags = tags(fd_image)
seg_bytes = open(f"{fd}/posed_labels.dcm", "rb").read()
check(not err and got is not None and np.array_equal(got, expected) and fd_tags.get("0020|000d") and
      fd_tags["0020|000d"].encode() in seg_bytes and fd_tags.get("0020|0052", "").encode() in seg_bytes and
      fd_tags["0020|000d"] != first_tags["0020|000d"] and os.path.exists(f"{fd}/posed_labels.tsv"),
      f"pose --format dicom: posed_labels.dcm on posed_image/ voxel for voxel, one study and frame of reference "
      f"({err}{seg_reader.GetLastError()})", failures)

# --series-uid on the command line: a folder with two whole series is refused without it, read with it.
os.makedirs(f"{work}/both")
for name in files:
    shutil.copy(f"{work}/ct/{name}", f"{work}/both/a_{name}")
    shutil.copy(f"{work}/ct2/{name}", f"{work}/both/b_{name}")
code, _, err = run("pose", "--case", f"{work}/case", "--pose", pose, "--image", f"{work}/both",
                   "--out", f"{work}/posed_both", check=False)
check(code != 0 and "choose one with --series-uid" in err and not os.path.exists(f"{work}/posed_both"),
      f"two series without --series-uid: {err.strip()}", failures)
run("pose", "--case", f"{work}/case", "--pose", pose, "--image", f"{work}/both", "--series-uid",
    series_uid(f"{work}/ct2/{files[0]}"), "--out", f"{work}/posed_both")
chosen, err = read(f"{work}/posed_both/posed_image")
check(not err and np.array_equal(voxels(chosen), voxels(posed)),
      f"with --series-uid the chosen series is posed, as from its own folder ({err})", failures)

print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
