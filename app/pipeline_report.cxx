#include "pipeline_report.h"

#include <iomanip>
#include <iostream>
#include <stdexcept>

#include "deformation_stats.h"
#include "label_table.h"
#include "repose_pipeline.h"

namespace repose {

void printTimings(const Pipeline& pipeline, std::size_t from) {
  const auto& t = pipeline.timings();
  for (std::size_t i = from; i < t.size(); ++i)
    std::cout << "  " << std::left << std::setw(16) << t[i].stage << std::right << std::fixed
              << std::setprecision(3) << std::setw(9) << t[i].seconds << " s\n";
  std::cout.unsetf(std::ios::floatfield);
}

PoseQuality poseQualityOf(Pipeline& pipeline, const DeformationStats& stats) {
  LabelTable table;
  try {
    if (!pipeline.labelTableTsv().empty()) table = parseLabelTable(pipeline.labelTableTsv());
  } catch (const std::invalid_argument&) {
    // A table that does not parse only costs the names (loadCase checked it).
  }
  return poseQuality(stats, table, {}, pipeline.posedLabelStats());
}

}  // namespace repose
