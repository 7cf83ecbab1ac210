"""What other tools open: the posed labels' names and colours beside them (posed_labels.tsv, and
posed_labels.ctbl as 3D Slicer reads colour tables) for every label of the posed volume; `pose --format vti` writes the posed labels as VTK XML image data with the
direction matrix (read back by VTK's own reader: the same grid and voxels as the NIfTI output, and
the posed mesh's nodes fall on labelled voxels through that geometry); `animate --volumes --format vti`
lists each frame's label volume in animation.pvd beside its mesh and surfaces. Label volumes are
written in the smallest integer type that holds them (unsigned char up to 255 labels, unsigned short,
short; int otherwise), the case's own labels too, with every value kept."""
import gzip
import struct
import os
import shutil
import sys
import xml.etree.ElementTree as ET

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLImageDataReader

from vtkmodules.vtkCommonCore import VTK_UNSIGNED_CHAR
from vtkmodules.vtkCommonDataModel import vtkImageData

from repose import vtkReposeImageWriter
from repose_testing import SHARED, TEMP, TESTING, TINY, Image, Mesh, check, run

failures = []
work = os.path.join(TEMP, "vti_output")
shutil.rmtree(work, ignore_errors=True)
pose = os.path.join(TESTING, "Data", "tiny_pose.json")
run("pose", "--case", f"{TINY}/case", "--pose", pose, "--format", "vti", "--out", f"{work}/vti")
run("pose", "--case", f"{TINY}/case", "--pose", pose, "--out", f"{work}/nii")

reader = vtkXMLImageDataReader()
reader.SetFileName(f"{work}/vti/posed_labels.vti")
reader.Update()
vti = reader.GetOutput()
nii = Image(f"{work}/nii/posed_labels.nii.gz")
direction = np.array([[vti.GetDirectionMatrix().GetElement(r, c) for c in range(3)] for r in range(3)])
extent = vti.GetExtent()
# VTK's origin is that of index 0; the first voxel is at the extent's start.
first = np.array(vti.GetOrigin()) + direction @ (np.array(vti.GetSpacing()) * np.array(extent[::2]))
check(np.allclose(direction, nii.direction) and not np.allclose(direction, np.eye(3))
      and np.allclose(vti.GetSpacing(), nii.spacing) and np.allclose(first, nii.origin)
      and tuple(vti.GetDimensions()) == tuple(nii.dims),
      f"posed_labels.vti: grid {vti.GetDimensions()}, direction {direction.round(3).tolist()} as the NIfTI's", failures)
values = vtk_to_numpy(vti.GetPointData().GetScalars()).reshape(nii.a.shape)
check(np.array_equal(values, nii.a), f"the same {int((values != 0).sum())} labelled voxels as posed_labels.nii.gz", failures)
mesh = Mesh(f"{work}/vti/posed_mesh.vtu")
ijk = np.rint(np.linalg.solve(direction, (mesh.points - first).T).T / np.array(vti.GetSpacing())).astype(int)
inside = np.all((ijk >= 0) & (ijk < np.array(vti.GetDimensions())), axis=1)
on_body = (values[ijk[inside, 2], ijk[inside, 1], ijk[inside, 0]] != 0).mean()
check(inside.all() and on_body > 0.99,
      f"the posed mesh lines up with the .vti: {100 * on_body:.1f} % of its nodes on labelled voxels", failures)

# Names and colours travel: every label of the posed volume is in both tables, under the case's name.
case_names = {int(v): n for v, n, *_ in (l.split("\t") for l in open(f"{TINY}/case/labels.tsv").read().splitlines()[1:])}
tsv = {int(v): n for v, n, *_ in (l.split("\t") for l in open(f"{work}/nii/posed_labels.tsv").read().splitlines()[1:])}
ctbl = {int(f[0]): (f[1], [int(c) for c in f[2:6]]) for f in
        (l.split() for l in open(f"{work}/nii/posed_labels.ctbl").read().splitlines() if not l.startswith("#"))}
present = set(np.unique(nii.a).tolist()) - {0}
check(present <= set(tsv) and present <= set(ctbl) and all(tsv[v] == case_names[v] for v in present)
      and all(ctbl[v][0] == case_names[v].replace(" ", "_") and len(ctbl[v][1]) == 4 for v in present)
      and os.path.isfile(f"{work}/vti/posed_labels.ctbl"),
      f"posed_labels.tsv and .ctbl name all {len(present)} posed labels as the case does, with colours "
      f"(e.g. {sorted(present)[0]}: {ctbl[sorted(present)[0]]})", failures)

bvh = os.path.join(SHARED, "mocap", "cmu_short_75frames.bvh")
run("animate", "--case", f"{TINY}/case", "--bvh", bvh, "--frames", "0:75:37", "--volumes", "--format", ".vti",
    "--out", f"{work}/animate")
entries = [(float(e.get("timestep")), int(e.get("part")), e.get("file"))
           for e in ET.parse(f"{work}/animate/animation.pvd").getroot().iter("DataSet")]
volumes = [e for e in entries if e[2].endswith(".vti")]
check(len(volumes) == 3 and all(os.path.isfile(os.path.join(work, "animate", f)) for _, _, f in volumes)
      and len({t for t, _, _ in entries}) == 3 and len({p for _, p, _ in volumes}) == 1,
      f"animation.pvd lists each frame's label volume as a part of its time step: {[f for _, _, f in volumes]}", failures)
code, _, err = run("animate", "--case", f"{TINY}/case", "--bvh", bvh, "--format", "vti", "--out", f"{work}/none",
                   check=False)
check(code == 2 and "--format" in err and not os.path.exists(f"{work}/none"),
      f"--format without volumes is refused: {err.strip()}", failures)


def nifti_datatype(path):
    with gzip.open(path) as f:
        return struct.unpack_from("<h", f.read(352), 70)[0]


check(nifti_datatype(f"{work}/nii/posed_labels.nii.gz") == 2 and nifti_datatype(f"{TINY}/case/labels.nii.gz") == 2
      and vti.GetScalarType() == VTK_UNSIGNED_CHAR,
      "the tiny phantom's posed labels (NIfTI, .vti) and its case's labels are unsigned char", failures)
# The writer on its own: each range gets the smallest type that holds it, values unchanged.
for values, datatype in (([0, 7, 255], 2), ([0, 300, 65535], 512), ([-5, 0, 300], 4), ([0, 70000], 8)):
    image = vtkImageData()
    image.SetDimensions(len(values), 1, 1)
    image.GetPointData().SetScalars(numpy_to_vtk(np.array(values, np.int32), deep=True))
    writer = vtkReposeImageWriter()
    writer.SetFileName(f"{work}/range.nii.gz")
    writer.SmallestIntegerTypeOn()
    writer.SetInputData(image)
    ok = writer.Write() == 1
    back = Image(f"{work}/range.nii.gz").a.ravel()
    check(ok and nifti_datatype(f"{work}/range.nii.gz") == datatype and back.tolist() == values,
          f"labels {values} written as NIfTI datatype {nifti_datatype(f'{work}/range.nii.gz')} "
          f"(expected {datatype}), read back {back.tolist()}", failures)
print(f"{len(failures)} failed")
sys.exit(1 if failures else 0)
