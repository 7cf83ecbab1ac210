"""The vtkRepose* filters fed bad data from Python: empty inputs, meshes without the arrays a filter needs
(a mesh without Weights/BoneIds, a surface without its binding), and arrays or meshes of mismatched
sizes. Each must report a VTK error (seen by an ErrorEvent observer), fail its update and leave its
output empty: no crash and no C++ exception escaping into Python. The good data comes from the tiny
phantom's pipeline."""
import json
import sys

from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPolyData, vtkUnstructuredGrid

from repose import (vtkReposeAutoRig, vtkReposeBodyMesher, vtkReposeBoneWeights, vtkReposeCorotationalRelax,
                    vtkReposeImageWriter, vtkReposeMeshVoxelizer, vtkReposePosedVolume, vtkReposeSkinning,
                    vtkReposeSurfaceBinding, vtkReposeSurfaceDeformer, vtkReposeSurfaceExtractor)

from repose_testing import TEMP, check, tiny_pipeline

failures = []
tiny = tiny_pipeline()
skeleton = tiny.skeleton
pose = json.dumps({"rotations": {"left_knee": {"axis": [1, 0, 0], "degrees": 40}}})
tiny.skinning.SetPoseJSON(pose)


def run(f):
    f.Update()
    return f.GetOutputDataObject(0)


labels, bare_mesh, mesh, posed = run(tiny.phantom), run(tiny.mesher), run(tiny.weights), run(tiny.skinning)
surface, bound = run(tiny.surfaces), run(tiny.binding)


def copy(data, drop=()):
    """A shallow copy of `data` without the named point arrays."""
    c = data.NewInstance()
    c.ShallowCopy(data)
    for name in drop:
        c.GetPointData().RemoveArray(name)
    return c


def short_array(data, name):
    """`data` with point array `name` cut to half its tuples (sizes that disagree with the points)."""
    c = copy(data)
    a = c.GetPointData().GetArray(name)
    half = a.NewInstance()
    half.DeepCopy(a)
    half.SetNumberOfTuples(a.GetNumberOfTuples() // 2)
    c.GetPointData().RemoveArray(name)
    c.GetPointData().AddArray(half)
    return c


def fewer_points(grid):
    """The mesh with half its points and every tet kept (node indices out of range)."""
    c = vtkUnstructuredGrid()
    c.DeepCopy(grid)
    c.GetPoints().SetNumberOfPoints(grid.GetNumberOfPoints() // 2)
    return c


def no_scalars(image):
    c = vtkImageData()
    c.CopyStructure(image)
    return c


def filter_with(cls, inputs, **settings):
    f = cls()
    for port, data in enumerate(inputs):
        f.SetInputData(port, data)
    for name, value in settings.items():
        getattr(f, "Set" + name)(value)
    return f


S = {"SkeletonJSON": skeleton}
cases = {
    # empty inputs
    "BodyMesher, empty image": filter_with(vtkReposeBodyMesher, [vtkImageData()], **S),
    "BoneWeights, empty mesh": filter_with(vtkReposeBoneWeights, [vtkUnstructuredGrid()], **S),
    "Skinning, empty mesh": filter_with(vtkReposeSkinning, [vtkUnstructuredGrid()], PoseJSON=pose, **S),
    "CorotationalRelax, empty meshes": filter_with(vtkReposeCorotationalRelax, [vtkUnstructuredGrid(),
                                                                                vtkUnstructuredGrid()], **S),
    "SurfaceExtractor, empty image": filter_with(vtkReposeSurfaceExtractor, [vtkImageData()], **S),
    "SurfaceBinding, empty inputs": filter_with(vtkReposeSurfaceBinding, [vtkPolyData(), vtkUnstructuredGrid()]),
    "SurfaceDeformer, empty inputs": filter_with(vtkReposeSurfaceDeformer, [vtkPolyData(), vtkUnstructuredGrid()]),
    "PosedVolume, empty inputs": filter_with(vtkReposePosedVolume, [vtkImageData(), vtkUnstructuredGrid(),
                                                                    vtkUnstructuredGrid()]),
    "MeshVoxelizer, empty surface": filter_with(vtkReposeMeshVoxelizer, [vtkPolyData()]),
    "AutoRig, empty image": filter_with(vtkReposeAutoRig, [vtkImageData()]),
    "ImageWriter, empty image": filter_with(vtkReposeImageWriter, [vtkImageData()],
                                            FileName=f"{TEMP}/filter_bad_input.nii.gz"),
    # required arrays missing
    "BodyMesher, image without scalars": filter_with(vtkReposeBodyMesher, [no_scalars(labels)], **S),
    "AutoRig, image without scalars": filter_with(vtkReposeAutoRig, [no_scalars(labels)]),
    "BoneWeights, mesh without FixedBone": filter_with(vtkReposeBoneWeights, [copy(bare_mesh, ["FixedBone"])], **S),
    "Skinning, mesh without Weights/BoneIds": filter_with(vtkReposeSkinning, [bare_mesh], PoseJSON=pose, **S),
    "Skinning, mesh without BoneIds": filter_with(vtkReposeSkinning, [copy(mesh, ["BoneIds"])], PoseJSON=pose, **S),
    "CorotationalRelax, rest mesh without FixedBone": filter_with(vtkReposeCorotationalRelax,
                                                                  [posed, copy(mesh, ["FixedBone"])], **S),
    "SurfaceDeformer, surface without its binding": filter_with(vtkReposeSurfaceDeformer, [surface, posed]),
    "PosedVolume, labels without scalars": filter_with(vtkReposePosedVolume, [no_scalars(labels), mesh, posed]),
    # sizes that disagree
    "Skinning, Weights shorter than the points": filter_with(vtkReposeSkinning, [short_array(mesh, "Weights")],
                                                             PoseJSON=pose, **S),
    "Skinning, BoneIds shorter than the points": filter_with(vtkReposeSkinning, [short_array(mesh, "BoneIds")],
                                                             PoseJSON=pose, **S),
    "CorotationalRelax, posed and rest of other sizes": filter_with(vtkReposeCorotationalRelax,
                                                                    [fewer_points(posed), mesh], **S),
    "SurfaceBinding, tets indexing missing points": filter_with(vtkReposeSurfaceBinding, [surface, fewer_points(mesh)]),
    "SurfaceDeformer, binding shorter than the points": filter_with(vtkReposeSurfaceDeformer,
                                                                    [short_array(bound, "BoundTet"), posed]),
    "SurfaceDeformer, posed mesh of fewer points": filter_with(vtkReposeSurfaceDeformer, [bound, fewer_points(posed)]),
    "PosedVolume, posed mesh of fewer points": filter_with(vtkReposePosedVolume, [labels, mesh, fewer_points(posed)]),
    "PosedVolume, rest mesh of fewer points": filter_with(vtkReposePosedVolume, [labels, fewer_points(mesh), posed]),
    "BoneWeights, FixedBone shorter than the points": filter_with(vtkReposeBoneWeights,
                                                                  [short_array(bare_mesh, "FixedBone")], **S),
    "CorotationalRelax, FixedBone shorter than the points": filter_with(
        vtkReposeCorotationalRelax, [posed, short_array(mesh, "FixedBone")], **S),
    "SurfaceDeformer, BoundWeights shorter than the points": filter_with(vtkReposeSurfaceDeformer,
                                                                         [short_array(bound, "BoundWeights"), posed]),
}


def empty(output):
    if output is None:
        return True
    if isinstance(output, vtkImageData):
        return output.GetNumberOfPoints() == 0 or output.GetPointData().GetScalars() is None
    return output.GetNumberOfPoints() == 0 and output.GetNumberOfCells() == 0


for what, f in cases.items():
    errors = []
    for source in (f, f.GetExecutive()):  # the executive reports the failed request: kept off stderr
        source.AddObserver("ErrorEvent", lambda caller, _e, errors=errors: errors.append(caller.GetClassName()))
    print(f"... {what}", flush=True)  # a crash shows where
    try:
        ok = f.Write() if isinstance(f, vtkReposeImageWriter) else f.GetExecutive().Update()
        raised = ""
    except Exception as e:  # noqa: BLE001 - an exception escaping the C++ code is a defect too
        ok, raised = 1, f"{type(e).__name__}: {e}"
    output = None if isinstance(f, vtkReposeImageWriter) else f.GetOutputDataObject(0)
    check(not raised and ok == 0 and f.GetClassName() in errors and empty(output),
          f"{what}: update {'failed' if ok == 0 else 'SUCCEEDED'}, errors from {sorted(set(errors))}, output "
          f"{'empty' if empty(output) else 'NOT empty'}{', raised ' + raised if raised else ''}", failures)
print(f"{len(cases)} bad inputs: {len(cases) - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
