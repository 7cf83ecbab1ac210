"""`repose voxelize` on the Visible Human male and female meshes as the atlas ships them: the skin,
sacrum, coccyx, hip bones (each three overlapping parts in one file), femurs (holes at the knee),
patellae, tibiae and fibulae at 4 mm. Every bone gets the label the automatic rig knows; each volume
is checked against a reference computed here with VTK and SciPy alone: the body against the skin's
mesh volume (within 0.5 %), each femur against its holes filled (within 10 %). Each hip bone is a
cortical shell about 1.2 mm thick around its cancellous interior: the shell volume the report gives
is checked against the union of its three parts rasterized one by one at 1 mm (within 15 %), and the
bone, solid by default, against that union's envelope (closed by a 1 mm ball, the holes it walls in
filled): within 3 % in volume, Dice >= 0.9 voxel by voxel, in one piece. The femurs are solid too
(Dice >= 0.9 against their holes filled by VTK), and no bone label walls in a voxel it lacks.
With --hollow-bones the shells are labelled as they come (the hips fall apart into pieces and fail
the Dice check) while the body keeps every voxel. `repose rig` finds the pelvis, both hips (sphere
fits) and both knees on each solid body with under 1 ml of loose bone pieces (the shells leave
more than 100). The VTK filter does as the CLI, HollowBones off and on. An open sheet cut from a
real bone is a one-line error naming the file, with nothing written."""
import json
import os
import shutil
import sys

import numpy as np
from scipy import ndimage
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPolyData
from vtkmodules.vtkFiltersCore import (vtkCleanPolyData, vtkMassProperties, vtkPolyDataConnectivityFilter,
                                       vtkPolyDataNormals, vtkTriangleFilter)
from vtkmodules.vtkFiltersSources import vtkCubeSource
from vtkmodules.vtkFiltersModeling import vtkFillHolesFilter
from vtkmodules.vtkImagingStencil import vtkImageStencil, vtkPolyDataToImageStencil
from vtkmodules.vtkIOPLY import vtkPLYReader, vtkPLYWriter

from repose_testing import SHARED, TEMP, Image, check, label_table, run

work = os.path.join(TEMP, "voxelize_visible_human")
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
BONES = ["sacrum", "coccyx", "hip_left", "hip_right", "femur_left", "femur_right", "patella_left", "patella_right",
         "tibia_left", "tibia_right", "fibula_left", "fibula_right"]
VOXEL = 4.0
RIG = {"pelvis": None, "left_hip": "pelvis", "right_hip": "pelvis", "left_knee": "left_hip", "right_knee": "right_hip"}


def read(path):
    r = vtkPLYReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def mesh_volume(mesh):
    m = vtkMassProperties()
    m.SetInputData(mesh)
    m.Update()
    return m.GetVolume()


def filled_mesh(mesh):
    """The mesh with its holes filled by VTK (vtkFillHolesFilter), normals made consistent."""
    clean = vtkCleanPolyData()
    clean.SetInputData(mesh)
    fill = vtkFillHolesFilter()
    fill.SetInputConnection(clean.GetOutputPort())
    fill.SetHoleSize(1e4)
    normals = vtkPolyDataNormals()
    normals.SetInputConnection(fill.GetOutputPort())
    normals.ConsistencyOn()
    normals.AutoOrientNormalsOn()
    normals.SplittingOff()
    normals.Update()
    return normals.GetOutput()


class Lattice:
    """A lattice of h mm around a mesh's box, 2 voxels of margin: origin, dims (x, y, z)."""

    def __init__(self, mesh, h=1.0):
        b = mesh.GetBounds()
        self.h = h
        self.dims = [int(np.ceil((b[2 * a + 1] - b[2 * a]) / h)) + 5 for a in range(3)]
        self.origin = [b[2 * a] - 2 * h for a in range(3)]

    def stencil(self, closed):
        """The closed mesh rasterized by vtkPolyDataToImageStencil: a boolean array [k, j, i]."""
        stencil = vtkPolyDataToImageStencil()
        stencil.SetInputData(closed)
        stencil.SetOutputOrigin(*self.origin)
        stencil.SetOutputSpacing(self.h, self.h, self.h)
        stencil.SetOutputWholeExtent(0, self.dims[0] - 1, 0, self.dims[1] - 1, 0, self.dims[2] - 1)
        stencil.Update()
        return stencil_mask(stencil.GetOutput(), self.dims)

    def sampled(self, mask, vox):
        """mask (on this lattice) at the voxel centres of the label volume vox (axis-aligned), the
        nearest sample; False beyond the lattice."""
        out = np.zeros(vox.a.shape, bool)
        index = [np.round((vox.origin[a] + np.arange(vox.dims[a]) * vox.spacing[a] - self.origin[a]) / self.h)
                 .astype(int) for a in range(3)]
        ok = [(index[a] >= 0) & (index[a] < self.dims[a]) for a in range(3)]
        out[np.ix_(ok[2], ok[1], ok[0])] = mask[np.ix_(index[2][ok[2]], index[1][ok[1]], index[0][ok[0]])]
        return out


def union_mask(mesh, lattice):
    """The closed parts stored apart in one file (connected through point ids), each rasterized
    alone on the lattice, then OR-ed: (parts, mask)."""
    conn = vtkPolyDataConnectivityFilter()
    conn.SetInputData(mesh)
    conn.SetExtractionModeToSpecifiedRegions()
    conn.Update()
    parts = conn.GetNumberOfExtractedRegions()
    union = np.zeros(lattice.dims[::-1], bool)
    for region in range(parts):
        conn.InitializeSpecifiedRegionList()
        conn.AddSpecifiedRegion(region)
        conn.Update()
        part = vtkPolyData()
        part.DeepCopy(conn.GetOutput())
        union |= lattice.stencil(part)
    return parts, union


def envelope(mask):
    """The mask with what it walls in: closed by a ball of one voxel (its thinnest walls sampled at
    1 mm leave gaps), the holes filled, then opened again."""
    ball = ndimage.generate_binary_structure(3, 1)
    closed = ndimage.binary_fill_holes(ndimage.binary_dilation(mask, ball))
    return ndimage.binary_erosion(closed, ball, border_value=0) | mask


def dice(a, b):
    return 2 * (a & b).sum() / (a.sum() + b.sum())


def walled_in(mask):
    """Voxels not in mask that it encloses (no face-connected path to the volume's border)."""
    box = np.pad(mask[ndimage.find_objects(mask.astype(np.uint8))[0]], 1) if mask.any() else mask
    return int((ndimage.binary_fill_holes(box) & ~box).sum())


def largest_piece_fraction(mask):
    pieces, n = ndimage.label(mask)
    return np.bincount(pieces.ravel())[1:].max() / mask.sum() if n else 0.0


def reported_ml(line, what):
    """The volume after 'shell N voxels, ' or 'solid N voxels, ' in a part's report line (ml)."""
    text = line.split(what + " ")[1].split(", ")[1].split(" ")
    return float(text[0]) * (1000 if text[1].startswith("L") else 1)


def stencil_mask(stencil, dims):
    """The stencil's voxels as a boolean array [k, j, i]."""
    img = vtkImageData()
    img.SetDimensions(*dims)
    img.SetOrigin(stencil.GetOrigin())
    img.SetSpacing(stencil.GetSpacing())
    img.AllocateScalars(3, 1)  # unsigned char
    vtk_to_numpy(img.GetPointData().GetScalars())[:] = 1
    cut = vtkImageStencil()
    cut.SetInputData(img)
    cut.SetStencilData(stencil)
    cut.SetBackgroundValue(0)
    cut.Update()
    return vtk_to_numpy(cut.GetOutput().GetPointData().GetScalars()).reshape(dims[::-1]) > 0


def voxelize(subject, *flags):
    """`repose voxelize` on a subject's skin and bones at VOXEL: (its report line by part name, the
    label volume, the label table)."""
    D = os.path.join(SHARED, "visible_human", subject)
    folder = os.path.join(work, subject + "".join(flags))
    args = ["voxelize", "--skin", f"{D}/skin.ply", "--voxel", VOXEL, "--out", f"{folder}/labels.nii.gz", *flags]
    for b in BONES:
        args += ["--bone", f"{b}={D}/{b}.ply"]
    code, out, err = run(*args)
    print(out)
    lines = {line.split()[1]: line for line in out.splitlines() if line.startswith("  ") and len(line.split()) > 2}
    return lines, Image(f"{folder}/labels.nii.gz"), label_table(f"{folder}/labels.tsv")


def rig(folder):
    """`repose rig` on a voxelized subject (its labels.tsv found beside the volume): (its joints'
    parents by name, the line on each hip, the ml of loose bone pieces it had to place)."""
    code, out, err = run("rig", "--labels", f"{folder}/labels.nii.gz", "--out", f"{folder}/skeleton.json")
    with open(f"{folder}/skeleton.json") as f:
        parents = {j["name"]: j["parent"] for j in json.load(f)["joints"]}
    hips = [line.strip() for line in out.splitlines() if line.strip().split(" ")[0] in ("left_hip", "right_hip")]
    loose = next(line for line in out.splitlines() if line.startswith("fragments: "))
    return parents, hips, int(loose.split("(")[1].split(" ")[0]) * ml


ml = VOXEL ** 3 / 1000.0
bodies, envelopes = {}, {}
for subject, skin_litres in (("female", 79.30), ("male", 96.22)):
    D = os.path.join(SHARED, "visible_human", subject)
    lines, vox, names = voxelize(subject)
    check(all(names.get(b, (0, ""))[1] == "bone" for b in BONES), f"{subject}: every bone labelled by its name", failures)

    def volume(name):
        return (vox.a == names[name][0]).sum() * ml

    bodies[subject] = (vox.a > 0).sum()
    body, skin = bodies[subject] * ml / 1000.0, mesh_volume(read(f"{D}/skin.ply")) / 1e6
    check(abs(skin - skin_litres) < 0.01 and abs(body / skin - 1) < 0.005,
          f"{subject}: body {body:.2f} L, skin mesh {skin:.2f} L: within 0.5 %", failures)
    walls = {b: walled_in(vox.a == names[b][0]) for b in BONES}
    check(not any(walls.values()), f"{subject}: voxels walled in by a bone label: "
          f"{ {b: n for b, n in walls.items() if n} or 'none'}", failures)
    for side in ("left", "right"):
        hip = read(f"{D}/hip_{side}.ply")
        lattice = Lattice(hip)
        parts, union = union_mask(hip, lattice)
        envelopes[subject, side] = lattice, envelope(union)
        shell, solid = union.sum() / 1000, envelopes[subject, side][1].sum() / 1000
        v, line = volume(f"hip_{side}"), lines.get(f"hip_{side}", "")
        reported = reported_ml(line, "shell")
        check(parts == 3 and abs(reported / shell - 1) < 0.15,
              f"{subject} hip_{side}: shell {reported:.1f} ml reported, its {parts} parts' union {shell:.1f} ml: "
              "within 15 %", failures)
        label = vox.a == names[f"hip_{side}"][0]
        pieces, overlap = largest_piece_fraction(label), dice(label, lattice.sampled(envelopes[subject, side][1], vox))
        check(abs(v / solid - 1) < 0.03 and abs(reported_ml(line, "solid") / solid - 1) < 0.03 and overlap >= 0.9
              and pieces > 0.95, f"{subject} hip_{side}: solid {v:.1f} ml labelled, the union's envelope {solid:.1f} "
              f"ml: within 3 %, Dice {overlap:.3f}, the largest piece {100 * pieces:.1f} % of it", failures)
        check("3 pieces" in line and "ml of hollow interior (" in line,
              f"{subject} hip_{side}: the report names its 3 pieces and the hollow filled", failures)
        femur = filled_mesh(read(f"{D}/femur_{side}.ply"))
        lattice = Lattice(femur)
        v, reference = volume(f"femur_{side}"), mesh_volume(femur) / 1000
        overlap = dice(vox.a == names[f"femur_{side}"][0], lattice.sampled(lattice.stencil(femur), vox))
        check(abs(v / reference - 1) < 0.10 and overlap >= 0.9, f"{subject} femur_{side}: {v:.1f} ml, holes filled "
              f"by VTK {reference:.1f} ml: within 10 %, Dice {overlap:.3f}", failures)
        check("3 hole(s) spanned" in lines.get(f"femur_{side}", ""),
              f"{subject} femur_{side}: the report names its holes", failures)
    for b in ("sacrum", "tibia_left", "patella_right", "fibula_left"):
        v, reference = volume(b), mesh_volume(read(f"{D}/{b}.ply")) / 1000
        check(abs(v / reference - 1) < 0.25, f"{subject} {b}: {v:.1f} ml, mesh {reference:.1f} ml", failures)
    parents, hips, loose = rig(os.path.join(work, subject))
    check(parents == RIG and all("sphere fit" in h for h in hips) and loose < 1,
          f"{subject}: repose rig finds {sorted(parents)}, {hips}, {loose:.1f} ml of loose bone pieces", failures)

# --hollow-bones: the hip bones as their shells come, in pieces, the body unchanged; the solid
# volume still reported.
lines, vox, names = voxelize("male", "--hollow-bones")
line, label = lines["hip_left"], vox.a == names["hip_left"][0]
v, pieces = label.sum() * ml, largest_piece_fraction(label)
lattice, solid = envelopes["male", "left"]
overlap = dice(label, lattice.sampled(solid, vox))
# (the label loses to the sacrum, given first, the few voxels where they overlap)
check("left open" in line and abs(v / reported_ml(line, "shell") - 1) < 0.03 and reported_ml(line, "solid") > 4 * v
      and pieces < 0.5 and overlap < 0.5, f"--hollow-bones: hip_left {v:.1f} ml labelled, as its shell, Dice "
      f"{overlap:.3f} with the envelope, the largest piece {100 * pieces:.1f} %; '{line.split(': ')[-1]}'", failures)
parents, hips, loose = rig(os.path.join(work, "male--hollow-bones"))
check(parents == RIG and loose > 100, f"--hollow-bones: repose rig finds the same joints but has {loose:.1f} ml of "
      "loose bone pieces to place", failures)
check((vox.a > 0).sum() == bodies["male"], f"--hollow-bones: the body {(vox.a > 0).sum()} voxels, solid bones "
      f"{bodies['male']}", failures)

# The VTK filter: solid by default, the shell with HollowBones on; a box around the hip as the skin.
from repose import vtkReposeMeshVoxelizer
hip = read(f"{D}/hip_left.ply")
b = hip.GetBounds()
box = vtkCubeSource()
box.SetBounds(b[0] - 8, b[1] + 8, b[2] - 8, b[3] + 8, b[4] - 8, b[5] + 8)
tri = vtkTriangleFilter()
tri.SetInputConnection(box.GetOutputPort())
for hollow, expected in ((False, reported_ml(line, "solid")), (True, reported_ml(line, "shell"))):
    f = vtkReposeMeshVoxelizer()
    f.SetVoxelSize(VOXEL)
    f.AddInputConnection(tri.GetOutputPort())
    f.AddInputData(hip)
    f.SetPartName(1, "hip_left")
    f.SetHollowBones(hollow)
    f.Update()
    v = (vtk_to_numpy(f.GetOutput().GetPointData().GetScalars()) == 2).sum() * VOXEL ** 3 / 1000
    said = ("left open " if hollow else "filled ") in f.GetReport()
    check(said and abs(v / expected - 1) < (0.1 if hollow else 0.03),
          f"vtkReposeMeshVoxelizer, HollowBones {hollow}: hip_left {v:.1f} ml, the CLI's "
          f"{'shell' if hollow else 'solid'} {expected:.1f} ml", failures)

# A hopeless surface: the femur's outer side alone (triangles facing +x), an open sheet.
femur = read(os.path.join(SHARED, "visible_human", "female", "femur_left.ply"))
normals = vtkPolyDataNormals()
normals.SetInputData(femur)
normals.ComputeCellNormalsOn()
normals.ComputePointNormalsOff()
normals.SplittingOff()
normals.ConsistencyOff()
normals.Update()
n = vtk_to_numpy(normals.GetOutput().GetCellData().GetNormals())
sheet = vtkPolyData()
sheet.DeepCopy(femur)
sheet.GetPolys().Initialize()
cells = vtk_to_numpy(femur.GetPolys().GetConnectivityArray()).reshape(-1, 3)
for c in cells[n[:, 0] > 0.3]:
    sheet.GetPolys().InsertNextCell(3, [int(x) for x in c])
w = vtkPLYWriter()
w.SetFileName(f"{work}/sheet.ply")
w.SetInputData(sheet)
w.Write()
target = f"{work}/bad/labels.nii.gz"
code, out, err = run("voxelize", "--skin", f"{D}/skin.ply", "--bone", f"femur_left={work}/sheet.ply", "--voxel", VOXEL,
                     "--out", target, check=False)
lines = err.strip().splitlines()
ok = code != 0 and len(lines) == 1 and "sheet.ply: the surface is not closed enough to have an inside" in lines[0]
check(ok and not os.path.exists(target), f"an open sheet: exit {code}, '{lines[0] if lines else ''}', no output",
      failures)

total = 2 * (3 + 10 + 5) + 6
print(f"{total - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
