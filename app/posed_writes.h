#pragma once
// The posed outputs of a pipeline staged into a command's output directory.
#include <string>

class vtkImageData;

namespace repose {

class AtomicOutputs;
class Pipeline;

/// The case's label table beside a label output: BASE.tsv (Repose's, with kinds) and BASE.ctbl
/// (3D Slicer's colour table), so names and colours travel with the volume. Nothing without a table.
void writeLabelTables(Pipeline& pipeline, AtomicOutputs& out, const std::string& base);

/// A label volume at `path`: a 3D Slicer segmentation when it ends ".seg.nrrd" (a segment per label,
/// named and coloured from the case's table), else as writeLabelImage writes it.
void writeLabelVolume(Pipeline& pipeline, vtkImageData* labels, const std::string& path);

/// posed_mesh.vtu, posed_surfaces.vtp, posed_labels<labelsExt> with its tables and, when the
/// pipeline has a rest image, posed_image<imageExt>.
void writePosed(Pipeline& pipeline, AtomicOutputs& out, const std::string& labelsExt, const std::string& imageExt);

/// The same with the volumes in DICOM: posed_labels.dcm (a DICOM Segmentation, a segment per label
/// named and coloured from the case's table) and, with a rest image, posed_image/ (a DICOM CT series),
/// in one study and frame of reference: the CT's when it was read from DICOM, else a new one.
void writePosedDicom(Pipeline& pipeline, AtomicOutputs& out);

}  // namespace repose
