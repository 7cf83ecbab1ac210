#include "posed_writes.h"

#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

#include <set>
#include <stdexcept>
#include <vector>

#include "vtkReposeDicomSegWriter.h"
#include "vtkReposeDicomSeriesWriter.h"
#include "vtkReposeSlicerSegmentationWriter.h"

#include "atomic_outputs.h"
#include "checked_write.h"
#include "label_table.h"
#include "repose_pipeline.h"

namespace repose {

void writeLabelTables(Pipeline& pipeline, AtomicOutputs& out, const std::string& base) {
  if (pipeline.labelTableTsv().empty()) return;
  const LabelTable table = parseLabelTable(pipeline.labelTableTsv(), "the case's label table");
  writeTextFile(out.stage(base + ".tsv"), labelTableToTsv(table));
  writeTextFile(out.stage(base + ".ctbl"), labelTableToSlicerColorTable(table));
}

namespace {

struct Segment {
  int value;
  std::string name;
  double rgb[3];
  bool bone;
};

/// A segment per label: each label the case's table names (not the background), then each value of
/// `labels` it does not name, as "label_<value>" in grey.
std::vector<Segment> labelSegments(Pipeline& pipeline, vtkImageData* labels) {
  const LabelTable table = pipeline.labelTableTsv().empty()
                               ? LabelTable{}
                               : parseLabelTable(pipeline.labelTableTsv(), "the case's label table");
  std::vector<Segment> segments;
  std::set<int> named;
  for (const LabelInfo& l : table.labels) {
    if (l.value == 0 || l.kind == LabelKind::Background) continue;
    const auto rgba = displayColour(l);
    segments.push_back({l.value, l.name, {rgba[0] / 255.0, rgba[1] / 255.0, rgba[2] / 255.0}, l.kind == LabelKind::Bone});
    named.insert(l.value);
  }
  vtkDataArray* values = labels->GetPointData()->GetScalars();
  std::set<int> present;
  for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i) present.insert(int(values->GetTuple1(i)));
  for (int v : present)
    if (v != 0 && !named.count(v)) segments.push_back({v, "label_" + std::to_string(v), {0.8, 0.8, 0.8}, false});
  return segments;
}

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

void writeLabelVolume(Pipeline& pipeline, vtkImageData* labels, const std::string& path) {
  if (!endsWith(path, ".seg.nrrd")) return writeLabelImage(labels, path);
  const QuietStderr quiet;
  vtkNew<vtkReposeSlicerSegmentationWriter> writer;
  for (const Segment& s : labelSegments(pipeline, labels))
    writer->AddSegment(s.value, s.name.c_str(), s.rgb[0], s.rgb[1], s.rgb[2]);
  writer->SetFileName(path.c_str());
  writer->SetDescription("labels");
  writer->SetInputData(labels);
  if (!writer->Write()) throw std::runtime_error(writer->GetLastError());
}

void writePosed(Pipeline& pipeline, AtomicOutputs& out, const std::string& labelsExt, const std::string& imageExt) {
  writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
  writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
  writeLabelVolume(pipeline, pipeline.posedLabels(), out.stage("posed_labels" + labelsExt));
  writeLabelTables(pipeline, out, "posed_labels");
  if (vtkImageData* image = pipeline.posedImage()) writeImage(image, out.stage("posed_image" + imageExt));
}

void writePosedDicom(Pipeline& pipeline, AtomicOutputs& out) {
  writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
  writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
  // The labels take the posed CT's patient, study and frame of reference (a new study when the CT
  // was no DICOM, or when there is no CT), so that a viewer overlays one on the other.
  vtkNew<vtkImageData> reference;
  vtkImageData* image = pipeline.posedImage();
  if (image) {
    vtkReposeDicomSeriesWriter::AssignNewStudy(image);
    reference->GetFieldData()->ShallowCopy(image->GetFieldData());
  } else {
    vtkReposeDicomSeriesWriter::AssignNewStudy(reference);
  }
  vtkNew<vtkImageData> labels;
  labels->ShallowCopy(pipeline.posedLabels());
  labels->GetFieldData()->ShallowCopy(reference->GetFieldData());
  vtkNew<vtkReposeDicomSegWriter> seg;
  seg->SetInputData(labels);
  seg->SetFileName(out.stage("posed_labels.dcm").c_str());
  seg->SetSeriesDescription("Reposed labels (Repose)");
  for (const Segment& s : labelSegments(pipeline, labels))
    seg->AddSegment(s.value, s.name.c_str(), s.rgb[0], s.rgb[1], s.rgb[2], s.bone);
  if (!seg->Write()) throw std::runtime_error(seg->GetLastError());
  writeLabelTables(pipeline, out, "posed_labels");
  if (image) writeImage(image, out.stage("posed_image/"));
}

}  // namespace repose
