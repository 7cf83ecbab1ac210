#include "scan_preparation.h"

#include <stdexcept>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include "atomic_outputs.h"
#include "label_table_choice.h"
#include "repose_pipeline.h"
#include "vtkReposeAutoRig.h"

namespace repose {

RigResult rigLabels(vtkImageData* labels, const std::string& labelsName, const std::string& labelTablePath,
                    double maxGapMm, const std::string& labelTableOption) {
  const LabelTableChoice table = chooseLabelTable(labelsName, labelTablePath, labelTableOption);
  requireTableFits(labels, labelsName, table);
  auto rig = vtkSmartPointer<vtkReposeAutoRig>::New();
  rig->SetInputData(labels);
  rig->SetLabelTableTSV(table.text.c_str());
  rig->SetLabelTableName(table.origin.c_str());  // the report's "label table:" line
  rig->CheckLabelTableOff();  // checked above, with the file names
  rig->SetMaxGapMm(maxGapMm);
  const std::string what = "automatic skeleton of " + labelsName;
  updateOrThrow(rig, what);
  RigResult r;
  r.labels = vtkSmartPointer<vtkImageData>::New();
  r.labels->ShallowCopy(rig->GetOutput());
  r.skeletonJson = rig->GetSkeletonJSON();
  r.report = rig->GetReport();
  r.tableTsv = rig->GetOutputLabelTableTSV();
  if (rig->GetNumberOfJoints() < 2)
    throw std::runtime_error(labelsName + ": the automatic skeleton found " + std::to_string(rig->GetNumberOfJoints()) +
                             " joint(s) with the label table " + (table.path.empty() ? "of TotalSegmentator" : table.path) +
                             "; name the bones with " + labelTableOption + " or write skeleton.json by hand");
  vtkDataArray* a = labels->GetPointData()->GetScalars();
  vtkDataArray* b = r.labels->GetPointData()->GetScalars();
  for (vtkIdType i = 0, n = a->GetNumberOfTuples(); i < n && !r.relabelled; ++i)
    r.relabelled = a->GetTuple1(i) != b->GetTuple1(i);
  return r;
}

ScanForPreparation readScanForPreparation(const ScanSource& source,
                                          const std::function<void(const std::string&)>& stage) {
  auto tell = [&](const std::string& text) {
    if (stage) stage(text);
  };
  ScanForPreparation scan;
  scan.labels = readLabelVolume(source.labelsPath);
  if (source.skeletonPath == "auto") {
    tell("finding the skeleton from the bone labels");
    RigResult r = rigLabels(scan.labels, source.labelsPath, source.labelTablePath, source.maxGapMm, source.labelTableOption);
    scan.labels = r.labels;
    scan.skeletonJson = r.skeletonJson;
    scan.skeletonName = "automatic skeleton";
    scan.tableTsv = r.tableTsv;
    scan.rigReport = r.report;
  } else {
    scan.skeletonJson = readTextFile(source.skeletonPath);
    scan.skeletonName = source.skeletonPath;
    scan.tableTsv = caseLabelTable(scan.labels, source.labelsPath, source.labelTablePath, source.labelTableOption);
  }
  if (!source.imagePath.empty()) {
    tell("reading " + source.imagePath);
    scan.image = readIntensityImage(source.imagePath, source.seriesUid);
    checkSameGrid(scan.labels, source.labelsPath, scan.image, source.imagePath);
  }
  return scan;
}

}  // namespace repose
