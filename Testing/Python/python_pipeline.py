"""The pipeline built in vtkpython from the `repose` package: phantom -> mesher -> weights ->
skinning -> posed volume and surfaces. Changing the pose re-runs only the posing filters."""
import json
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkIntArray, vtkPoints
from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkUnstructuredGrid

from repose import vtkReposeCorotationalRelax, vtkReposePosedVolume, vtkReposeSurfaceDeformer

from repose_testing import check, tiny_pipeline

failures = []
tiny = tiny_pipeline()
phantom, mesher, weights, skinning, surfaces, binding = (tiny.phantom, tiny.mesher, tiny.weights, tiny.skinning,
                                                         tiny.surfaces, tiny.binding)
skeleton = tiny.skeleton
names = [j["name"] for j in json.loads(skeleton)["joints"]]

volume = vtkReposePosedVolume()
volume.SetInputConnection(0, phantom.GetOutputPort())
volume.SetInputConnection(1, weights.GetOutputPort())
volume.SetInputConnection(2, skinning.GetOutputPort())
volume.SetInterpolationToNearest()
deformer = vtkReposeSurfaceDeformer()
deformer.SetInputConnection(0, binding.GetOutputPort())
deformer.SetInputConnection(1, skinning.GetOutputPort())

skinning.SetPoseJSON(json.dumps({"rotations": {}}))
volume.Update()
deformer.Update()
rest_labels = vtk_to_numpy(phantom.GetOutput().GetPointData().GetScalars())
identity = vtk_to_numpy(volume.GetOutput().GetPointData().GetScalars())
mesh = weights.GetOutput()
check(mesh.GetNumberOfCells() > 1000, f"tet mesh: {mesh.GetNumberOfPoints()} nodes, {mesh.GetNumberOfCells()} tets", failures)
W = vtk_to_numpy(mesh.GetPointData().GetArray("Weights"))
check(np.abs(W.sum(1) - 1).max() < 1e-5 and W.min() >= 0, "weights: partition of unity, non-negative", failures)
ratio = (identity != 0).sum() / (rest_labels != 0).sum()
check(abs(ratio - 1) < 0.02, f"identity pose keeps the body volume (ratio {ratio:.4f})", failures)
rest_pts = vtk_to_numpy(deformer.GetOutput().GetPoints().GetData()).copy()
surf_rest = vtk_to_numpy(surfaces.GetOutput().GetPoints().GetData())
err = np.abs(rest_pts - surf_rest).max()
check(err < 0.02, f"identity pose leaves the surfaces in place (max {err:.2e} mm)", failures)

mesher_time = mesher.GetMTime()
mesh_out_time = mesher.GetOutput().GetMTime()
weights_out_time = weights.GetOutput().GetMTime()
skinning.SetPoseJSON(json.dumps({"rotations": {"left_knee": {"axis": [1, 0, 0], "degrees": 60}}}))
volume.Update()
deformer.Update()
check(mesher.GetOutput().GetMTime() == mesh_out_time and weights.GetOutput().GetMTime() == weights_out_time,
      "a new pose does not re-run meshing or weights", failures)
moved = np.linalg.norm(vtk_to_numpy(deformer.GetOutput().GetPoints().GetData()) - rest_pts, axis=1)
check(moved.max() > 20 and np.median(moved) < 1e-3, f"knee flexion moves part of the surfaces (max {moved.max():.1f} mm)", failures)
posed = vtk_to_numpy(volume.GetOutput().GetPointData().GetScalars()).copy()
check(volume.GetOutput().GetNumberOfPoints() >= len(rest_labels), "posed grid holds the posed body", failures)
# The tet field alone, without the rigid-bone pass, already carries the bones almost rigidly: the
# pass only corrects a thin layer of boundary voxels.
volume.RigidBonesOff()
volume.Update()
tet_only = vtk_to_numpy(volume.GetOutput().GetPointData().GetScalars())
tibia = 26  # TibiaLeft, moved by the knee flexion
a, b = tet_only == tibia, posed == tibia
d = 2 * (a & b).sum() / (a.sum() + b.sum())
check(d >= 0.95, f"tibia from the tet field alone vs with rigid bones: Dice {d:.3f}", failures)

# The FEM relaxation can be stopped: Cancel() (from any thread: a GUI's button) stops the running or
# next execution, which leaves no output; the next execution runs normally.
relax = vtkReposeCorotationalRelax()
relax.SetInputConnection(0, skinning.GetOutputPort())
relax.SetInputConnection(1, weights.GetOutputPort())
relax.SetSkeletonJSON(skeleton)
relax.Cancel()
relax.Update()
check(relax.GetCancelled() and relax.GetOutput().GetNumberOfPoints() == 0,
      "Cancel() stops the relaxation and leaves no output", failures)
relax.Modified()
relax.Update()
relaxed = relax.GetOutput().GetNumberOfPoints()
check(not relax.GetCancelled() and relaxed == mesh.GetNumberOfPoints() and relax.GetNewtonIterations() > 0,
      f"the next execution runs normally ({relax.GetNewtonIterations()} Newton iterations)", failures)
# In a script the solve runs on the caller's thread: a ProgressEvent observer sees where it is (the
# text) and may cancel it there.
seen = []


def on_progress(caller, _event):
    text = caller.GetProgressText()
    if text:  # the solver's reports (the executive's own, at the start and the end, carry no text)
        seen.append(text)
        if len(seen) == 2:
            caller.Cancel()


tag = relax.AddObserver("ProgressEvent", on_progress)
relax.Modified()
relax.Update()
check(relax.GetCancelled() and seen == ["FEM set-up", "relaxing the strained region"],
      f"a progress observer sees {seen} and cancels at the second report", failures)
# With the strained region not taken first, Newton starts on the whole mesh.
seen.clear()
relax.SetStrainedRegionThreshold(0)
relax.Update()
relax.RemoveObserver(tag)
check(relax.GetCancelled() and seen == ["FEM set-up", "Newton step 1"],
      f"without the strained region first, a progress observer sees {seen}", failures)

# Bones pushed past each other across one free layer (a 10 x 2 x 2 bar of Kuhn cubes; bone 0: x <= 4,
# bone 1: x >= 6, moved by -2.5): the layer's middle node must lie beyond bone 0's face (x > 4) and
# before bone 1's (x < 3.5). The filter reports it pinched, 0.25 short of room, and starts no
# fold-free continuation, which could not end.


def bar(points):
    grid = vtkUnstructuredGrid()
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(points, deep=True))
    grid.SetPoints(pts)
    for tet in tets:
        grid.InsertNextCell(VTK_TETRA, 4, [int(v) for v in tet])
    return grid


size = (11, 3, 3)
node_id = lambda i, j, k: (k * size[1] + j) * size[0] + i
rest_points = np.array([(i, j, k) for k in range(size[2]) for j in range(size[1]) for i in range(size[0])], float)
tets = []
for k in range(size[2] - 1):
    for j in range(size[1] - 1):
        for i in range(size[0] - 1):
            for order in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
                corner, tet = [i, j, k], [node_id(i, j, k)]
                for axis in order:
                    corner[axis] += 1
                    tet.append(node_id(*corner))
                a, b, c, d = rest_points[tet]
                if np.dot(b - a, np.cross(c - a, d - a)) < 0:  # odd orders: turn positive
                    tet[2], tet[3] = tet[3], tet[2]
                tets.append(tet)
fixed_bone = np.where(rest_points[:, 0] <= 4, 0, np.where(rest_points[:, 0] >= 6, 1, -1))
rest_bar = bar(rest_points)
fixed_array = vtkIntArray()
fixed_array.SetName("FixedBone")
for b in fixed_bone:
    fixed_array.InsertNextValue(int(b))
rest_bar.GetPointData().AddArray(fixed_array)
posed_points = rest_points.copy()
posed_points[fixed_bone == 1, 0] -= 2.5
pinch = vtkReposeCorotationalRelax()
pinch.SetInputData(0, bar(posed_points))
pinch.SetInputData(1, rest_bar)
pinch.Update()
check(pinch.GetInvertedAfter() > 0 and pinch.GetPinchedNodes() == 1 and abs(pinch.GetPinchedShortfall() - 0.25) < 1e-9
      and pinch.GetContinuationSteps() == 0,
      f"bones pushed past each other: {pinch.GetInvertedAfter()} tets left inverted, {pinch.GetPinchedNodes()} node "
      f"pinched {pinch.GetPinchedShortfall():.3g} short of room, {pinch.GetContinuationSteps()} continuation steps",
      failures)
print(f"{12 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
