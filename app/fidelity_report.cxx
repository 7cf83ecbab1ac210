#include "fidelity_report.h"

#include "atomic_outputs.h"
#include "cli_options.h"
#include "deformation_stats.h"
#include "fidelity_plot.h"
#include "repose_pipeline.h"

namespace repose {

std::vector<std::string> parseCompare(const Options& o) {
  std::vector<std::string> methods;
  if (!o.has("compare")) return methods;
  std::stringstream in(o.get("compare"));
  for (std::string m; std::getline(in, m, ',');) {
    if (m != "lbs" && m != "dqs" && m != "lbs+fem" && m != "dqs+fem")
      throw UsageError("--compare takes lbs, dqs, lbs+fem, dqs+fem (comma separated), not '" + m + "'");
    methods.push_back(m);
  }
  if (methods.empty()) throw UsageError("--compare needs at least one method");
  return methods;
}

void FidelityReport::addFrame(Pipeline& pipeline, int frame, const std::string& userMethod, bool userRelax, double nu,
                              int iterations) {
  for (const std::string& m : methods) {
    pipeline.setSkinningMethod(m.substr(0, 3));
    pipeline.setRelaxation(m.size() > 3, nu, iterations);
    const DeformationStats s = pipeline.posedStats();
    if (labels.empty())
      for (const auto& [label, ratio] : s.labelVolumeRatio) labels.push_back(label);
    rows << frame << "," << m << "," << s.volumeRatio << "," << s.invertedTets << "," << s.meanAbsDetFMinus1 << ","
         << s.maxAbsDetFMinus1;
    for (auto label : labels) {
      auto it = s.labelVolumeRatio.find(label);
      rows << "," << (it == s.labelVolumeRatio.end() ? 0.0 : it->second);
    }
    rows << "\n";
    series[m].push_back({double(frame), s.volumeRatio});
  }
  pipeline.setSkinningMethod(userMethod);
  pipeline.setRelaxation(userRelax, nu, iterations);
}

void FidelityReport::write(AtomicOutputs& out) const {
  std::ostringstream csv;
  csv << "frame,method,body_volume_ratio,inverted_tets,mean_abs_detF_minus_1,max_abs_detF_minus_1";
  for (auto label : labels) csv << ",label_" << label << "_volume_ratio";
  csv << "\n" << rows.str();
  writeTextFile(out.stage("fidelity.csv"), csv.str());
  plotVolumeRatios(series, out.stage("fidelity.png"));
}

}  // namespace repose
