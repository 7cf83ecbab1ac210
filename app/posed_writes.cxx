#include "posed_writes.h"

#include <vtkImageData.h>

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

}  // namespace repose
