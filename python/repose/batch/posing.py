"""A prepared case posed through the Python-wrapped filters, wired and written as `repose pose` does
(app/repose_pipeline.cxx), so that one pose's files equal that command's byte for byte. The case is
loaded once per worker thread; a new pose re-runs only skinning, relaxation and resampling."""
import json
import os

from vtkmodules.util.misc import calldata_type
from vtkmodules.util.vtkConstants import VTK_INT, VTK_STRING
from vtkmodules.vtkCommonCore import vtkDataArray
from vtkmodules.vtkIOXML import (vtkXMLPolyDataReader, vtkXMLPolyDataWriter, vtkXMLUnstructuredGridReader,
                                 vtkXMLUnstructuredGridWriter)

from repose import (vtkReposeCorotationalRelax, vtkReposeDicomSeriesWriter, vtkReposeImageReader, vtkReposeImageWriter, vtkReposeLabelTable,
                    vtkReposePosedVolume, vtkReposeSkeletonPoses, vtkReposeSkinning, vtkReposeSurfaceDeformer, vtkReposeVersion)

from .checked_files import WriteFailure, check_written, failure_reason, write_text

IMAGE_EXTENSIONS = (".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd")


def image_extension(path, fallback=".nii.gz"):
    """"a/b/labels.nii.gz" -> ".nii.gz"; "/" for a folder (a DICOM series); `fallback` for none of the
    image formats."""
    if path and os.path.isdir(path):
        return "/"
    return next((e for e in IMAGE_EXTENSIONS if path and path.endswith(e)), fallback)


def update(algorithm, what):
    """Runs a filter; raises RuntimeError "`what` failed: <the filter's own message>" on failure."""
    errors = []

    @calldata_type(VTK_STRING)
    def on_error(_caller, _event, text):
        text = text or ""
        errors.append(" ".join(text[text.find("): ") + 3:].split()) if "): " in text else " ".join(text.split()))

    tag = algorithm.AddObserver("ErrorEvent", on_error)
    ok = algorithm.GetExecutive().Update()
    algorithm.RemoveObserver(tag)
    if not ok or errors:
        raise RuntimeError(f"{what} failed" + (f": {errors[-1]}" if errors else ""))


def read_image(path, what):
    if not os.path.exists(path):  # a file, or a folder holding a DICOM series
        raise RuntimeError(f"{path}: no such file")
    reader = vtkReposeImageReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetLastError():
        raise RuntimeError(reader.GetLastError())
    image = reader.GetOutput()
    scalars = image.GetPointData().GetScalars() if image else None
    if scalars is None or scalars.GetNumberOfComponents() != 1:
        raise RuntimeError(f"{path}: cannot read {what}")
    return image


def write_dicom_series(image, folder):
    """The posed CT of a DICOM input as a DICOM series (the input's patient and study, a new series)."""
    writer = vtkReposeDicomSeriesWriter()
    writer.SetFileName(folder)
    writer.SetSeriesDescription(f"Reposed (Repose {vtkReposeVersion.GetVersion()})")
    writer.SetInputData(image)
    if not writer.Write():
        raise RuntimeError(writer.GetLastError() or f"{folder}: cannot write the DICOM series")


def write_image(image, path, labels=False):
    """Writes an image as `repose` does: label volumes in the smallest integer type holding them."""
    writer = vtkReposeImageWriter()
    writer.SetFileName(path)
    writer.SetSmallestIntegerType(labels)
    writer.SetInputData(image)
    if not writer.Write():
        raise RuntimeError(writer.GetLastError() or f"{path}: cannot write image")


def forget_cached_ranges(data):
    """Drops the value ranges a writer cached in the arrays' information when it wrote them before: the
    XML writers write those keys out, so a second file of the same (shared) arrays would differ from
    the first, which is what `repose pose` writes."""
    keys = (vtkDataArray.L2_NORM_RANGE(), vtkDataArray.L2_NORM_FINITE_RANGE(), vtkDataArray.PER_COMPONENT(),
            vtkDataArray.PER_FINITE_COMPONENT())
    arrays = [data.GetPoints().GetData()] if data.GetPoints() else []
    for attributes in (data.GetPointData(), data.GetCellData(), data.GetFieldData()):
        arrays += [attributes.GetAbstractArray(i) for i in range(attributes.GetNumberOfArrays())]
    for array in arrays:
        if array is not None and array.HasInformation():
            for key in keys:
                array.GetInformation().Remove(key)


def write_xml(writer_type, data, path):
    forget_cached_ranges(data)
    stamped = type(data)()  # a shallow copy carrying the version, as `repose pose` writes it
    stamped.ShallowCopy(data)
    vtkReposeVersion.Stamp(stamped)
    writer = writer_type()
    writer.SetFileName(path)
    writer.SetInputData(stamped)
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()
    for source in (writer, writer.GetExecutive()):  # their multi-line texts: the failure is reported below
        source.AddObserver("ErrorEvent", lambda *_: None)
    if not writer.Write():
        raise WriteFailure(path, failure_reason(path))
    check_written(path)  # Write() reports success even when the disk took only part of the file


def read_xml(reader_type, path):
    reader = reader_type()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


class CasePoser:
    """One prepared case (CASE_DIR, as `repose prepare` writes it) and its posing filters."""

    def __init__(self, case_dir, image_path=None):
        manifest_path = os.path.join(case_dir, "manifest.json")
        try:
            with open(manifest_path) as f:
                manifest = json.load(f)
        except (OSError, ValueError) as e:
            raise RuntimeError(f"{manifest_path}: not a prepared case ({e})") from None
        if manifest.get("format") != "repose-case":
            raise RuntimeError(f"{manifest_path}: not a Repose case manifest")
        files = {k: os.path.join(case_dir, manifest.get(k, "")) for k in ("mesh", "surfaces", "skeleton", "labels")}
        for path in files.values():
            if not os.path.isfile(path):
                raise RuntimeError(f"{path}: missing from the case directory")
        self.rest_mesh = read_xml(vtkXMLUnstructuredGridReader, files["mesh"])
        for name in ("Weights", "BoneIds", "FixedBone"):
            if self.rest_mesh.GetNumberOfCells() == 0 or not self.rest_mesh.GetPointData().GetArray(name):
                raise RuntimeError(f"{files['mesh']}: not a weighted tet mesh (needs point data {name})")
        self.rest_surfaces = read_xml(vtkXMLPolyDataReader, files["surfaces"])
        if not self.rest_surfaces.GetPointData().GetArray("BoundTet"):
            raise RuntimeError(f"{files['surfaces']}: not bound surfaces (needs point data BoundTet)")
        with open(files["skeleton"]) as f:
            self.skeleton_json = f.read()
        self.rest_labels = read_image(files["labels"], "the label volume")
        if self.rest_labels.GetPointData().GetScalars().GetDataType() != VTK_INT:
            raise RuntimeError(f"{files['labels']}: the case's labels are not integers")
        self.rest_labels.GetPointData().GetScalars().SetName("Labels")
        self.labels_ext = image_extension(files["labels"])
        self.label_table = None  # the case's table (cases saved before it was kept have none)
        if manifest.get("labelTable"):
            table_path = os.path.join(case_dir, manifest["labelTable"])
            try:
                with open(table_path) as f:
                    text = f.read()
            except OSError as e:
                raise RuntimeError(f"{table_path}: cannot read the case's label table ({e.strerror})") from None
            self.label_table = vtkReposeLabelTable()
            if not self.label_table.SetTableText(text, table_path):
                raise RuntimeError(self.label_table.GetLastError())
        self.case_dir, self.image_path = case_dir, image_path
        self.poses = vtkReposeSkeletonPoses()
        self.poses.SetSkeletonJSON(self.skeleton_json)
        self.clips = {}
        self._connect()

    def _connect(self):
        self.skinning = vtkReposeSkinning()
        self.skinning.SetInputData(self.rest_mesh)
        self.skinning.SetSkeletonJSON(self.skeleton_json)
        self.skinning.SetPoseJSON('{"rotations": {}}')
        self.deformer = vtkReposeSurfaceDeformer()
        self.deformer.SetInputData(0, self.rest_surfaces)
        self.labels = vtkReposePosedVolume()
        self.labels.SetInputData(0, self.rest_labels)
        self.labels.SetInputData(1, self.rest_mesh)
        self.labels.SetInterpolationToNearest()
        self.labels.SetBackgroundValue(0)
        self.image = None
        if self.image_path:
            rest_image = read_image(self.image_path, "the image")
            self.image = vtkReposePosedVolume()
            self.image.SetInputData(0, rest_image)
            self.image.SetInputData(1, self.rest_mesh)
            self.image.SetInterpolationToLinear()
            self.image.SetBackgroundValue(rest_image.GetPointData().GetScalars().GetRange()[0])  # air outside
        self.relax_by_method = {}
        self.source = self.skinning

    def configure(self, skinning, relax):
        """Skinning "dqs" | "lbs"; relax None or the manifest's relax settings (see manifest.py)."""
        self.skinning.SetSkinningMethod(0 if skinning == "dqs" else 1)
        if relax:
            if skinning not in self.relax_by_method:
                f = vtkReposeCorotationalRelax()
                f.SetInputConnection(0, self.skinning.GetOutputPort())
                f.SetInputData(1, self.rest_mesh)
                f.SetSkeletonJSON(self.skeleton_json)
                self.relax_by_method[skinning] = (f, f.GetStrainedRegionThreshold())
            f, threshold = self.relax_by_method[skinning]
            f.ResetCancel()
            f.SetWarmStart(False)  # every pose from its skinned shape, as `repose pose`
            f.SetPoissonRatio(relax["poisson"])
            f.SetOuterIterations(int(relax["iterations"]))
            # The manifest's words are the filter's own (checked against them in manifest.py).
            f.SetModel(vtkReposeCorotationalRelax.GetWordValue("model", relax["model"]))
            f.SetVolumeRegions(vtkReposeCorotationalRelax.GetWordValue("volume", relax["volume"]))
            f.SetContinuation(vtkReposeCorotationalRelax.GetWordValue("continuation", relax["continuation"]))
            f.SetStrainedRegionThreshold(threshold if relax["strained_region"] == "first" else 0.0)
            self.source = f
        else:
            self.source = self.skinning
        port = self.source.GetOutputPort()
        self.deformer.SetInputConnection(1, port)
        self.labels.SetInputConnection(2, port)
        if self.image:
            self.image.SetInputConnection(2, port)

    def pose_text(self, pose_file=None, pose_text=None):
        """A pose.json's text, checked against the skeleton as `repose pose` checks it."""
        name = pose_file or "pose"
        if pose_text is None:
            with open(pose_file, encoding="utf-8", newline="") as f:
                pose_text = f.read()
        if not self.poses.CheckPoseJSON(pose_text, name):
            raise RuntimeError(self.poses.GetLastError())
        return pose_text

    def frame_text(self, bvh, joint_map, retarget, frame):
        """pose.json text of a BVH frame, retargeted as `repose animate` does."""
        key = (bvh, joint_map, tuple(sorted(retarget.items())))
        if key not in self.clips:
            clip = vtkReposeSkeletonPoses()
            clip.SetSkeletonJSON(self.skeleton_json)
            clip.SetJointMapFileName(joint_map or "")
            clip.SetRetargetMode(retarget["mode"])
            clip.SetReferenceFrame(retarget["reference_frame"])
            clip.SetTranslateRoot(retarget["root_motion"])
            clip.SetUnitScaleMm(retarget["unit_mm"])
            if not clip.LoadBVH(bvh):
                raise RuntimeError(clip.GetLastError())
            self.clips[key] = clip
        text = self.clips[key].GetFramePoseJSON(frame)
        if not text:
            raise RuntimeError(self.clips[key].GetLastError())
        return text

    def pose(self, pose_json, outputs):
        """Runs the posing filters for `outputs` (+ the labels, which the figures need); returns
        {"mesh", "surfaces", "labels", "image"} (absent ones None)."""
        self.skinning.SetPoseJSON(pose_json)
        update(self.skinning, "skinning")
        if self.source is not self.skinning:
            update(self.source, "FEM relaxation")
        result = {"mesh": self.source.GetOutput(), "surfaces": None, "labels": None, "image": None}
        if "surfaces" in outputs:
            update(self.deformer, "posed surfaces")
            result["surfaces"] = self.deformer.GetOutput()
        update(self.labels, "posed labels")
        result["labels"] = self.labels.GetOutput()
        if self.image and "image" in outputs:
            update(self.image, "posed image")
            result["image"] = self.image.GetOutput()
        return result

    def write(self, posed, outputs, labels_format, folder):
        """Writes the posed outputs under `repose pose`'s names; returns the file names."""
        image_ext = image_extension(self.image_path)
        files = []
        if "mesh" in outputs:
            files.append("posed_mesh.vtu")
            write_xml(vtkXMLUnstructuredGridWriter, posed["mesh"], os.path.join(folder, files[-1]))
        if "surfaces" in outputs:
            files.append("posed_surfaces.vtp")
            write_xml(vtkXMLPolyDataWriter, posed["surfaces"], os.path.join(folder, files[-1]))
        if "labels" in outputs:
            files.append("posed_labels" + (labels_format or self.labels_ext))
            write_image(posed["labels"], os.path.join(folder, files[-1]), labels=True)
            if self.label_table is not None:  # names and colours beside it, as `repose pose` writes them
                for name, text in (("posed_labels.tsv", self.label_table.GetTsv()),
                                   ("posed_labels.ctbl", self.label_table.GetSlicerColorTable())):
                    write_text(os.path.join(folder, name), text)
        if posed["image"] is not None and image_ext == "/":  # a DICOM CT series, as `repose pose` writes it
            files.append("posed_image")
            write_dicom_series(posed["image"], os.path.join(folder, files[-1]))
        elif posed["image"] is not None:
            files.append("posed_image" + image_ext)
            write_image(posed["image"], os.path.join(folder, files[-1]))
        # Companion files (.raw of .mhd/.nhdr) are results too.
        return sorted(os.listdir(folder))
