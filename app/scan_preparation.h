#pragma once
// A scan made ready for Pipeline::prepare, the same way from the command line and from the desktop
// application: the label volume read, its skeleton found from the bone labels (`auto`, with the label
// table given, else one beside the volume, else TotalSegmentator's names) or read from a
// skeleton.json, the label table the case keeps, and the CT read and checked against the labels' grid.
#include <functional>
#include <string>

#include <vtkSmartPointer.h>

class vtkImageData;

namespace repose {

/// The automatic skeleton of a label volume (`repose rig`, `prepare --skeleton auto`, the GUI).
struct RigResult {
  vtkSmartPointer<vtkImageData> labels;  // relabelled when a label held several bones or fragments moved
  std::string skeletonJson, report, tableTsv;
  bool relabelled = false;
};

/// Rigs `labels` with the label table chooseLabelTable(labelsName, labelTablePath) picks and the
/// largest bone gap maxGapMm. Throws std::runtime_error naming labelsName when the table does not fit
/// or fewer than 2 joints are found.
RigResult rigLabels(vtkImageData* labels, const std::string& labelsName, const std::string& labelTablePath,
                    double maxGapMm = 6.0, const std::string& labelTableOption = "--label-table");

struct ScanSource {
  std::string labelsPath;
  std::string skeletonPath = "auto";  ///< a skeleton.json, or "auto"
  std::string labelTablePath;         ///< "" = none given
  std::string imagePath;              ///< "" = no CT; a folder = a DICOM series
  std::string seriesUid;              ///< the series to read from a folder of several
  double maxGapMm = 6.0;              ///< for "auto"
  std::string labelTableOption = "--label-table";  ///< how the user gives a table, for messages
};

struct ScanForPreparation {
  vtkSmartPointer<vtkImageData> labels;  ///< relabelled by the rig where it split or moved labels
  vtkSmartPointer<vtkImageData> image;   ///< null without a CT
  std::string skeletonJson, skeletonName;
  std::string tableTsv;                  ///< the label table the case keeps ("" = label_<value> names)
  std::string rigReport;                 ///< the rig's lines ("" for a skeleton.json)
};

/// Reads and rigs a scan. `stage` (optional) is told before each long step. Throws std::exception
/// ("FILE: problem") on bad input.
ScanForPreparation readScanForPreparation(const ScanSource& source,
                                          const std::function<void(const std::string&)>& stage = {});

}  // namespace repose
