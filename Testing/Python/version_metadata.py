"""Every file Repose writes says which version wrote it, where its format has a place: NIfTI's descrip
("Repose 0.1.0 labels", "... image", "... displacement field"), NRRD and MetaImage key/value fields
(ReposeVersion), and VTK XML field data (a ReposeVersion string array in .vtu, .vtp and .vti, the case's
too). The version is the one `repose --version` prints. Each file is read back by a parser of its own
(gzip and the NIfTI layout, the text headers) or by VTK's XML readers."""
import gzip
import os
import shutil
import struct
import sys

from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader

from repose_testing import TEMP, TESTING, TINY, check, run

failures = []
work = os.path.join(TEMP, "version_metadata")
shutil.rmtree(work, ignore_errors=True)
version = run("--version")[1].split()[1]
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
common = ["pose", "--case", f"{TINY}/case", "--pose", pose]
# The phantom's labels stand in for a CT: the posed image is written as an image, not as labels.
os.makedirs(work)
shutil.copy(f"{TINY}/case/surfaces.vtp", f"{work}/organ.vtp")  # posed through the tet field: posed_organ.vtp
run(*common, "--image", f"{TINY}/phantom/labels.nii.gz", "--displacement-field", ".nii.gz",
    "--mesh", f"{work}/organ.vtp", "--out", f"{work}/nii.gz")
for fmt in ("nii", "nrrd", "mha", "mhd", "vti"):
    run(*common, "--format", fmt, "--out", f"{work}/{fmt}")


def nifti_descrip(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rb") as f:
        header = f.read(348)
    check(struct.unpack_from("<i", header, 0)[0] == 348, f"{os.path.basename(path)} is NIfTI-1", failures)
    return header[148:228].split(b"\0")[0].decode()


for name, what in (("nii.gz/posed_labels.nii.gz", "labels"), ("nii.gz/posed_image.nii.gz", "image"),
                   ("nii.gz/posed_displacement.nii.gz", "displacement field"), ("nii/posed_labels.nii", "labels")):
    descrip = nifti_descrip(f"{work}/{name}")
    check(descrip == f"Repose {version} {what}", f"{name}: descrip {descrip!r}", failures)


def text_header(path, separator):
    fields = {}
    with open(path, "rb") as f:
        for raw in f:
            line = raw.decode("latin-1").rstrip("\n")
            if not line or line.startswith("ElementDataFile"):
                break
            key, sep, value = line.partition(separator)
            if sep:
                fields[key.strip()] = value.strip()
    return fields


for name, separator in (("nrrd/posed_labels.nrrd", ":="), ("mha/posed_labels.mha", " = "),
                        ("mhd/posed_labels.mhd", " = ")):
    value = text_header(f"{work}/{name}", separator).get("ReposeVersion")
    check(value == version, f"{name}: ReposeVersion {value!r}", failures)


def xml_version(reader_type, path):
    reader = reader_type()
    reader.SetFileName(path)
    reader.Update()
    array = reader.GetOutput().GetFieldData().GetAbstractArray("ReposeVersion")
    return array.GetValue(0) if array is not None and array.GetNumberOfValues() == 1 else None


xml = [(vtkXMLUnstructuredGridReader, "nii.gz/posed_mesh.vtu"), (vtkXMLPolyDataReader, "nii.gz/posed_surfaces.vtp"),
       (vtkXMLPolyDataReader, "nii.gz/posed_organ.vtp"), (vtkXMLImageDataReader, "vti/posed_labels.vti")]
for reader_type, name in xml:
    value = xml_version(reader_type, f"{work}/{name}")
    check(value == version, f"{name}: field data ReposeVersion {value!r}", failures)
value = xml_version(vtkXMLUnstructuredGridReader, f"{TINY}/case/mesh.vtu")
check(value == version, f"the prepared case's mesh.vtu: field data ReposeVersion {value!r}", failures)
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
