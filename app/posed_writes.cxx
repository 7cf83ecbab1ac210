#include "posed_writes.h"

#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>

#include <set>
#include <stdexcept>

#include "vtkReposeDicomSegWriter.h"
#include "vtkReposeDicomSeriesWriter.h"

#include "atomic_outputs.h"
#include "label_table.h"
#include "repose_pipeline.h"

namespace repose {

void writeLabelTables(Pipeline& pipeline, AtomicOutputs& out, const std::string& base) {
  if (pipeline.labelTableTsv().empty()) return;
  const LabelTable table = parseLabelTable(pipeline.labelTableTsv(), "the case's label table");
  writeTextFile(out.stage(base + ".tsv"), labelTableToTsv(table));
  writeTextFile(out.stage(base + ".ctbl"), labelTableToSlicerColorTable(table));
}

void writePosed(Pipeline& pipeline, AtomicOutputs& out, const std::string& labelsExt, const std::string& imageExt) {
  writeMesh(pipeline.posedMesh(), out.stage("posed_mesh.vtu"));
  writeSurfaces(pipeline.posedSurfaces(), out.stage("posed_surfaces.vtp"));
  writeLabelImage(pipeline.posedLabels(), out.stage("posed_labels" + labelsExt));
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
  const LabelTable table = pipeline.labelTableTsv().empty()
                               ? LabelTable{}
                               : parseLabelTable(pipeline.labelTableTsv(), "the case's label table");
  vtkNew<vtkReposeDicomSegWriter> seg;
  seg->SetInputData(labels);
  seg->SetFileName(out.stage("posed_labels.dcm").c_str());
  seg->SetSeriesDescription("Reposed labels (Repose)");
  std::set<int> named;
  for (const LabelInfo& l : table.labels) {
    if (l.value == 0 || l.kind == LabelKind::Background) continue;
    const auto rgba = displayColour(l);
    seg->AddSegment(l.value, l.name.c_str(), rgba[0] / 255.0, rgba[1] / 255.0, rgba[2] / 255.0, l.kind == LabelKind::Bone);
    named.insert(l.value);
  }
  vtkDataArray* values = labels->GetPointData()->GetScalars();
  std::set<int> present;
  for (vtkIdType i = 0; i < values->GetNumberOfTuples(); ++i) present.insert(int(values->GetTuple1(i)));
  for (int v : present)  // labels the table does not name still get a segment
    if (v != 0 && !named.count(v)) seg->AddSegment(v, ("label_" + std::to_string(v)).c_str(), 0.8, 0.8, 0.8, false);
  if (!seg->Write()) throw std::runtime_error(seg->GetLastError());
  writeLabelTables(pipeline, out, "posed_labels");
  if (image) writeImage(image, out.stage("posed_image/"));
}

}  // namespace repose
